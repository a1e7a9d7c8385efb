// Sampling the two-level CDF built by cdf_reduce.comp (see crates/graph/src/passes/cdf_reduce.rs).
// The including shader declares, before including this file:
//   layout(std430, binding = B_IMPORTANCE) readonly buffer Importance { float importance[]; };
//   layout(std430, binding = B_CDF) readonly buffer Cdf { float cdf[]; };
#ifndef BOUNCE_CDF_GLSL
#define BOUNCE_CDF_GLSL
#include "common.glsl"

// Layout of the cdf buffer: a header, then one inclusive prefix per row (over row totals), then the
// inclusive prefix within each row.
const uint CDF_HEADER = 4u; // [0] total, [1] rows (uint bits), [2] row length (uint bits), [3] unused

// A section's CDF starts at `cb` (= section · cdf_len) and its importance at `ib` (= section · texels).
float cdf_total_at(uint cb) { return cdf[cb]; }
float cdf_total() { return cdf[0]; }

// Sanitised importance: negative, NaN and infinite values count as 0, as in cdf_reduce.comp.
float cdf_mass_at(uint ib, uint v) {
    float x = importance[ib + v];
    return (x > 0.0 && x < 1e30) ? x : 0.0;
}
float cdf_mass(uint v) { return cdf_mass_at(0u, v); }

// The largest float below a positive x.
float cdf_below(float x) {
    return uintBitsToFloat(floatBitsToUint(x) - 1u);
}

// Inclusive prefix of the row totals up to row r − 1 (0 for r = 0).
float cdf_rows_before(uint cb, uint r) {
    return r == 0u ? 0.0 : cdf[cb + CDF_HEADER + r - 1u];
}

// Total weight of rows [r0, r1) (e.g. one paraboloid face).
float cdf_rows_total(uint cb, uint r0, uint r1) {
    return cdf_rows_before(cb, r1) - cdf_rows_before(cb, r0);
}

// Draw a texel among rows [r0, r1) of section (cb, ib) with probability mass(v) / total(rows), by
// inverse transform with two uniforms in [0, 1): u.x picks the row (the first whose prefix exceeds the
// target before0 + u.x·range), u.y the texel within it (the first whose in-row prefix exceeds u.y times
// the row's own total P). Two draws, not one split: a single 24-bit u cannot tell apart texels whose
// share of the whole range is below 2⁻²⁴ (at 2 × 1024² texels, most of them), while u.y resolves each
// texel against its row alone.
// Why this never returns a texel without mass: a zero weight leaves a float prefix unchanged
// (acc + 0 = acc), so "first prefix > t" can only stop where the prefix grew, i.e. at a texel with
// mass; and clamping each target just below its total (u → 1 and rounding could otherwise reach it)
// guarantees such a prefix exists. Call only when the rows' total is > 0. Returns the texel.
uint cdf_sample_rows2(uint cb, uint ib, vec2 u, uint r0, uint r1) {
    uint rows = floatBitsToUint(cdf[cb + 1u]);
    uint len = floatBitsToUint(cdf[cb + 2u]);
    float before0 = cdf_rows_before(cb, r0);
    float end = cdf_rows_before(cb, r1);
    float target = min(before0 + u.x * (end - before0), cdf_below(end));
    target = max(target, before0);
    uint lo = r0, hi = r1 - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (cdf[cb + CDF_HEADER + mid] > target) hi = mid; else lo = mid + 1u;
    }
    uint r = lo;
    uint base = cb + CDF_HEADER + rows + r * len;
    float last = cdf[base + len - 1u];
    float t = min(u.y * last, cdf_below(last));
    lo = 0u;
    hi = len - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (cdf[base + mid] > t) hi = mid; else lo = mid + 1u;
    }
    return r * len + lo;
}

// A second uniform derived from the first, for the single-u entry points used by tests.
float cdf_second_uniform(float u) {
    uint h = pcg_hash(floatBitsToUint(u) ^ 0x9E3779B9u);
    return float(h >> 8) * (1.0 / 16777216.0);
}

uint cdf_sample_rows(uint cb, uint ib, float u, uint r0, uint r1) {
    return cdf_sample_rows2(cb, ib, vec2(u, cdf_second_uniform(u)), r0, r1);
}

// The probability that cdf_sample_rows2 returns v, computed from the same float prefixes the searches
// read (not from v's weight): row r is chosen when the target falls in [R_{r−1}, R_r), i.e. with
// probability Δ/range (Δ = R_r − R_{r−1}, range = R_{r1−1} − R_{r0−1}), and texel i within it when
// u.y·P falls in [p_{i−1}, p_i), i.e. with probability (p_i − p_{i−1})/P. A weight too small to change
// its float prefix is never drawn and gets probability 0 here too. Exact for continuous uniforms; with
// 24-bit ones each factor is off by at most 2⁻²⁴ plus one ulp of its total (the row level: ulp(end)/range,
// which is coarse for the faces of a light under a much heavier one; README, Known issues).
float cdf_prob_rows(uint cb, uint v, uint r0, uint r1) {
    uint rows = floatBitsToUint(cdf[cb + 1u]);
    uint len = floatBitsToUint(cdf[cb + 2u]);
    uint r = v / len, i = v % len;
    if (r < r0 || r >= r1) return 0.0;
    float range = cdf_rows_before(cb, r1) - cdf_rows_before(cb, r0);
    float delta = cdf_rows_before(cb, r + 1u) - cdf_rows_before(cb, r);
    if (!(range > 0.0) || !(delta > 0.0)) return 0.0;
    uint base = cb + CDF_HEADER + rows + r * len;
    float last = cdf[base + len - 1u];
    if (!(last > 0.0)) return 0.0;
    float hi = cdf[base + i];
    float lo = i > 0u ? cdf[base + i - 1u] : 0.0;
    return delta / range * (max(hi - lo, 0.0) / last);
}

// The whole of section 0, with the texel's probability (its weight over the total).
uint cdf_sample(float u, out float prob) {
    uint rows = floatBitsToUint(cdf[1]);
    uint v = cdf_sample_rows(0u, 0u, u, 0u, rows);
    prob = cdf_mass(v) / cdf[0];
    return v;
}

#endif
