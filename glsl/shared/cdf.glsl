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

// Draw a texel with probability mass(v) / total by inverse transform: u in [0, 1). Returns the texel and
// writes its discrete probability. Rows are searched first (first row whose prefix exceeds u·total), then
// the texel within the row; a strict "exceeds" skips zero-mass entries, and a rounding slip onto a
// zero-mass texel at a row's end is walked back to the nearest texel with mass, whose probability is
// what the estimator divides by. Call only with cdf_total() > 0.
uint cdf_sample(float u, out float prob) {
    float total = cdf[0];
    uint rows = floatBitsToUint(cdf[1]);
    uint len = floatBitsToUint(cdf[2]);
    float target = u * total;
    uint lo = 0u, hi = rows - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (cdf[CDF_HEADER + mid] > target) hi = mid; else lo = mid + 1u;
    }
    uint r = lo;
    // Skip back over rows without mass (only reachable through rounding at u → 1).
    while (r > 0u && cdf[CDF_HEADER + r] - cdf[CDF_HEADER + r - 1u] <= 0.0) r--;
    float before = r > 0u ? cdf[CDF_HEADER + r - 1u] : 0.0;
    float t = target - before;
    uint base = CDF_HEADER + rows + r * len;
    lo = 0u;
    hi = len - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (cdf[base + mid] > t) hi = mid; else lo = mid + 1u;
    }
    uint v = r * len + lo;
    if (cdf_mass(v) <= 0.0) {
        uint k = lo;
        while (k > 0u && cdf_mass(r * len + k) <= 0.0) k--;
        if (cdf_mass(r * len + k) <= 0.0) {
            k = lo;
            while (k + 1u < len && cdf_mass(r * len + k) <= 0.0) k++;
        }
        v = r * len + k;
    }
    prob = cdf_mass(v) / total;
    return v;
}

#endif
