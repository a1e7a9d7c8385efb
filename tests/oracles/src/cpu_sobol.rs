//! The CPU twin of the stratified sample points (`glsl/shared/owen_sobol.glsl`): the first two Sobol
//! dimensions, Owen-scrambled by Laine and Karras's hash, with the index shuffled by the same scramble.
//! Dimension 1 is computed here from its definition, a loop over the direction numbers (v_0 = 2³¹,
//! v_j = v_(j−1) ^ (v_(j−1) >> 1)), not by the shader's loop-free transform, so the two can be compared
//! bit for bit.

use crate::cpu_cdf::pcg_hash;

fn laine_karras_permutation(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50b47c);
    x ^= x.wrapping_mul(0xb82f1e52);
    x ^= x.wrapping_mul(0xc7afe638);
    x ^= x.wrapping_mul(0x8d22f6e6);
    x
}

fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras_permutation(x.reverse_bits(), seed).reverse_bits()
}

/// Sobol dimensions 0 and 1 of `index`, from the direction numbers.
pub fn sobol2(index: u32) -> [u32; 2] {
    let (mut y, mut v, mut rest) = (0u32, 0x8000_0000u32, index);
    while rest != 0 {
        if rest & 1 != 0 {
            y ^= v;
        }
        rest >>= 1;
        v ^= v >> 1;
    }
    [index.reverse_bits(), y]
}

fn unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16777216.0)
}

/// `owen_sobol2(index, seed)`: point `index` of the 2D set `seed`.
pub fn owen_sobol2(index: u32, seed: u32) -> [f32; 2] {
    let i = nested_uniform_scramble(index, pcg_hash(seed));
    let [x, y] = sobol2(i);
    [
        unit(nested_uniform_scramble(x, pcg_hash(seed ^ 0x68bc21eb))),
        unit(nested_uniform_scramble(y, pcg_hash(seed ^ 0x02e5be93))),
    ]
}

/// `owen_sobol1(index, seed)`: point `index` of the 1D set `seed`.
pub fn owen_sobol1(index: u32, seed: u32) -> f32 {
    let i = nested_uniform_scramble(index, pcg_hash(seed));
    unit(nested_uniform_scramble(i.reverse_bits(), pcg_hash(seed ^ 0x68bc21eb)))
}
