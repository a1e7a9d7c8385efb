// Stratified sample points: the first two dimensions of the Sobol sequence, Owen-scrambled with a hash
// (Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4)), with the index shuffled by the same
// scramble ("padding": independent 2D sets for each pair of dimensions a sample needs).
//
// Why these: every aligned block of 2^m consecutive Sobol indices is a (0, m, 2)-net (one point in each
// of the 2^m elementary intervals of every shape), and Owen scrambling keeps that while making each point
// uniform on [0, 1)², so an estimate stays unbiased. The shuffle changes an index's bit i only through its
// bits above i, so the first 2^m shuffled indices are again one aligned block: every power-of-two prefix
// is stratified. A point depends only on (index, seed), so a frame split into chunks of samples draws the
// same points whatever the chunking, and pixels with different seeds are decorrelated.
#ifndef BOUNCE_OWEN_SOBOL_GLSL
#define BOUNCE_OWEN_SOBOL_GLSL

// Laine and Karras's hash: bit i of the result depends on bits 0..i of x (and the seed) only.
uint laine_karras_permutation(uint x, uint seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

// An Owen scramble of x read as a binary fraction (most significant bit first): each digit is flipped
// by a random function of the digits before it.
uint nested_uniform_scramble(uint x, uint seed) {
    return bitfieldReverse(laine_karras_permutation(bitfieldReverse(x), seed));
}

// Sobol dimensions 0 (van der Corput: the index's bits reversed) and 1 (primitive polynomial x + 1:
// direction numbers v_0 = 2^31, v_j = v_(j-1) ^ (v_(j-1) >> 1), so bit 31 − i of v_j is C(j, i) mod 2). By
// Lucas's theorem C(j, i) is odd exactly when i's bits are a subset of j's, so dimension 1, bits reversed, is
// at each bit i the XOR of the index's bits j ⊇ i: a superset transform, five shift-and-XOR steps. No loop:
// llvmpipe runs a loop as long as its slowest lane, and a scrambled index has ~32 significant bits (the
// loop over them cost the gather's sampling). tests/tests/reference.rs checks the points bit for bit
// against a CPU twin that loops over the direction numbers (bounce_oracles::cpu_sobol).
uvec2 sobol2(uint index) {
    uint w = index;
    w ^= (w >> 1) & 0x55555555u;
    w ^= (w >> 2) & 0x33333333u;
    w ^= (w >> 4) & 0x0F0F0F0Fu;
    w ^= (w >> 8) & 0x00FF00FFu;
    w ^= (w >> 16) & 0x0000FFFFu;
    return uvec2(bitfieldReverse(index), bitfieldReverse(w));
}

// Point `index` of the 2D set `seed`, in [0, 1)² with 24 bits per coordinate.
vec2 owen_sobol2(uint index, uint seed) {
    uint i = nested_uniform_scramble(index, pcg_hash(seed));
    uvec2 s = sobol2(i);
    s.x = nested_uniform_scramble(s.x, pcg_hash(seed ^ 0x68bc21ebu));
    s.y = nested_uniform_scramble(s.y, pcg_hash(seed ^ 0x02e5be93u));
    return vec2(s >> 8) * (1.0 / 16777216.0);
}

// Point `index` of the 1D set `seed` (scrambled van der Corput, shuffled), in [0, 1).
float owen_sobol1(uint index, uint seed) {
    uint i = nested_uniform_scramble(index, pcg_hash(seed));
    return float(nested_uniform_scramble(bitfieldReverse(i), pcg_hash(seed ^ 0x68bc21ebu)) >> 8) * (1.0 / 16777216.0);
}

#endif
