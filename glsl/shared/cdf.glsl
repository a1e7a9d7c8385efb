// Sampling the two-level CDF built by cdf_reduce.comp (see crates/graph/src/passes/cdf_reduce.rs).
// The including shader declares, before including this file:
//   layout(std430, binding = B_IMPORTANCE) readonly buffer Importance { float importance[]; };
//   layout(std430, binding = B_CDF) readonly buffer Cdf { float cdf[]; };
#ifndef BOUNCE_CDF_GLSL
#define BOUNCE_CDF_GLSL

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
// inverse transform, u in [0, 1). The rows are searched first (the first row whose prefix exceeds the
// target), then the texel within the row (the first whose in-row prefix exceeds the rest).
// Why this never returns a texel without mass: a zero weight leaves a float prefix unchanged
// (acc + 0 = acc), so "first prefix > t" can only stop where the prefix grew, i.e. at a texel with
// mass; and clamping each target just below its total (u → 1 and rounding could otherwise reach it)
// guarantees such a prefix exists. Call only when the rows' total is > 0. Returns the texel.
uint cdf_sample_rows(uint cb, uint ib, float u, uint r0, uint r1) {
    uint rows = floatBitsToUint(cdf[cb + 1u]);
    uint len = floatBitsToUint(cdf[cb + 2u]);
    float before0 = cdf_rows_before(cb, r0);
    float end = cdf_rows_before(cb, r1);
    float target = min(before0 + u * (end - before0), cdf_below(end));
    target = max(target, before0);
    uint lo = r0, hi = r1 - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (cdf[cb + CDF_HEADER + mid] > target) hi = mid; else lo = mid + 1u;
    }
    uint r = lo;
    float before = cdf_rows_before(cb, r);
    uint base = cb + CDF_HEADER + rows + r * len;
    float t = min(max(target - before, 0.0), cdf_below(cdf[base + len - 1u]));
    lo = 0u;
    hi = len - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (cdf[base + mid] > t) hi = mid; else lo = mid + 1u;
    }
    return r * len + lo;
}

// The probability that cdf_sample_rows(cb, ib, u, r0, r1) returns v for u uniform in [0, 1), computed
// from the same float prefixes the search reads (not from v's weight): a weight too small to change
// its float prefix is never drawn and gets probability 0 here too, so an estimator dividing by this is
// unbiased with respect to what is actually sampled. Row r is chosen when the target falls in
// [R_{r−1}, R_r), i.e. with probability Δ/(R_{r1−1} − R_{r0−1}), Δ = R_r − R_{r−1}; within the row the
// offset t is uniform in [0, Δ) and clamped below the row's last prefix P (Δ and P can differ by the
// rounding of the row-total prefix), so texel i is drawn for t in [min(p_{i−1}, Δ), min(p_i, Δ)), and
// the last texel with weight also takes [P, Δ).
float cdf_prob_rows(uint cb, uint v, uint r0, uint r1) {
    uint rows = floatBitsToUint(cdf[cb + 1u]);
    uint len = floatBitsToUint(cdf[cb + 2u]);
    uint r = v / len, i = v % len;
    if (r < r0 || r >= r1) return 0.0;
    float range = cdf_rows_before(cb, r1) - cdf_rows_before(cb, r0);
    float delta = cdf_rows_before(cb, r + 1u) - cdf_rows_before(cb, r);
    if (!(range > 0.0) || !(delta > 0.0)) return 0.0;
    uint base = cb + CDF_HEADER + rows + r * len;
    float hi = cdf[base + i];
    float lo = i > 0u ? cdf[base + i - 1u] : 0.0;
    float last = cdf[base + len - 1u];
    float mass = min(hi, delta) - min(lo, delta);
    if (hi == last && lo < last) mass += max(delta - last, 0.0);
    return delta / range * max(mass, 0.0) / delta;
}

// The whole of section 0, with the texel's probability (its weight over the total).
uint cdf_sample(float u, out float prob) {
    uint rows = floatBitsToUint(cdf[1]);
    uint v = cdf_sample_rows(0u, 0u, u, 0u, rows);
    prob = cdf_mass(v) / cdf[0];
    return v;
}

#endif
