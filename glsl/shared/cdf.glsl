// Sampling the two-level CDF built by cdf_reduce.comp (see crates/graph/src/passes/cdf_reduce.rs).
// The including shader declares, before including this file:
//   layout(std430, binding = B_IMPORTANCE) readonly buffer Importance { float importance[]; };
//   layout(std430, binding = B_CDF) readonly buffer Cdf { float cdf[]; };
#ifndef BOUNCE_CDF_GLSL
#define BOUNCE_CDF_GLSL

// Layout of the cdf buffer: a header, then one inclusive prefix per row (over row totals), then the
// inclusive prefix within each row.
const uint CDF_HEADER = 4u; // [0] total, [1] rows (uint bits), [2] row length (uint bits), [3] unused

float cdf_total() { return cdf[0]; }

// Sanitised importance: negative, NaN and infinite values count as 0, as in cdf_reduce.comp.
float cdf_mass(uint v) {
    float x = importance[v];
    return (x > 0.0 && x < 1e30) ? x : 0.0;
}

// The largest float below a positive x.
float cdf_below(float x) {
    return uintBitsToFloat(floatBitsToUint(x) - 1u);
}

// Draw a texel with probability mass(v) / total by inverse transform: u in [0, 1). Returns the texel and
// writes its discrete probability. The rows are searched first (the first row whose prefix exceeds
// u·total), then the texel within the row (the first whose in-row prefix exceeds the rest).
// Why this never returns a texel without mass: a zero weight leaves a float prefix unchanged
// (acc + 0 = acc), so "first prefix > t" can only stop where the prefix grew, i.e. at a texel with
// mass; and clamping each target just below its total (u → 1 and rounding could otherwise reach it)
// guarantees such a prefix exists. The probability the estimator divides by is the drawn texel's own
// weight over the total. Call only with cdf_total() > 0.
uint cdf_sample(float u, out float prob) {
    float total = cdf[0];
    uint rows = floatBitsToUint(cdf[1]);
    uint len = floatBitsToUint(cdf[2]);
    float target = min(u * total, cdf_below(total));
    uint lo = 0u, hi = rows - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (cdf[CDF_HEADER + mid] > target) hi = mid; else lo = mid + 1u;
    }
    uint r = lo;
    float before = r > 0u ? cdf[CDF_HEADER + r - 1u] : 0.0;
    uint base = CDF_HEADER + rows + r * len;
    float t = min(max(target - before, 0.0), cdf_below(cdf[base + len - 1u]));
    lo = 0u;
    hi = len - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (cdf[base + mid] > t) hi = mid; else lo = mid + 1u;
    }
    uint v = r * len + lo;
    prob = cdf_mass(v) / total;
    return v;
}

#endif
