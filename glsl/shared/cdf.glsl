// Sampling the two-level CDF built by cdf_reduce.comp (see crates/graph/src/passes/cdf_reduce.rs).
// The including shader declares, before including this file:
//   layout(std430, binding = B_IMPORTANCE) readonly buffer Importance { float importance[]; };
//   layout(binding = B_CDF) uniform usamplerBuffer cdf_texels;   (the cdf buffer's R32_UINT texel view: llvmpipe
//   fetches a texel for a whole SIMD vector at once, where a storage buffer is read lane by lane)
#ifndef BOUNCE_CDF_GLSL
#define BOUNCE_CDF_GLSL
#include "bindings.glsl"
#include "common.glsl"

// Element i of the cdf buffer.
float cdf_at(uint i) { return uintBitsToFloat(texelFetch(cdf_texels, int(i)).r); }

// Layout of the cdf buffer: a header (CDF_HEADER floats, bindings.glsl), then one inclusive prefix per row
// (over row totals), then the inclusive prefix within each row.

// A section's CDF starts at `cb` (= section · cdf_len) and its importance at `ib` (= section · texels).
float cdf_total_at(uint cb) { return cdf_at(cb); }
float cdf_total() { return cdf_at(0u); }

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

// The prefix over row totals restarts at each face, a run of `len` rows (cdf_reduce.comp).
// CDF_SHAPE_FROM_FRAME (defined by the renderer's shaders before the include, after scene.glsl): every
// section is over the frame's VPL slots, faces() · face_rows() rows of face_rows() texels
// (shared/lightmap.glsl; the shape the frame recipe gives cdf_reduce), so no search reads the header. On
// llvmpipe a texel fetch is a gather instruction even when every lane reads the same texel, and the
// header was read again by every helper below. Test kernels read the header.
#ifdef CDF_SHAPE_FROM_FRAME
uint cdf_len(uint cb) { return face_rows(); }
uint cdf_rows(uint cb) { return faces() * face_rows(); }
#else
uint cdf_len(uint cb) { return floatBitsToUint(cdf_at(cb + 2u)); }
uint cdf_rows(uint cb) { return floatBitsToUint(cdf_at(cb + 1u)); }
#endif

// Total of face f (its last row's prefix).
float cdf_face_total(uint cb, uint f) {
    return cdf_at(cb + CDF_HEADER + min((f + 1u) * cdf_len(cb), cdf_rows(cb)) - 1u);
}

// The in-face prefix before row r (0 at a face's first row).
float cdf_row_start(uint cb, uint r) {
    return r % cdf_len(cb) == 0u ? 0.0 : cdf_at(cb + CDF_HEADER + r - 1u);
}

// Total weight of rows [r0, r1): either inside one face, or whole faces (summed in face order).
float cdf_rows_total(uint cb, uint r0, uint r1) {
    uint len = cdf_len(cb);
    uint f0 = r0 / len, f1 = (r1 - 1u) / len;
    if (f0 == f1) return cdf_at(cb + CDF_HEADER + r1 - 1u) - cdf_row_start(cb, r0);
    float t = 0.0;
    for (uint f = f0; f <= f1; f++) t += cdf_face_total(cb, f);
    return t;
}

// The last step of cdf_prob_rows (and of cdf_sample_rows3_prob, which must give its bits): the face
// factor, times the row's share Δ_r of the face's range, times the texel's step of its row's prefix
// over the row's total. 0 where any of them has no weight.
float cdf_prob_of(float p_face, float range, float delta, float last, float hi, float lo) {
    if (!(range > 0.0) || !(delta > 0.0) || !(last > 0.0)) return 0.0;
    return p_face * (delta / range) * (max(hi - lo, 0.0) / last);
}

// Draw a texel among rows [r0, r1) of section (cb, ib) (inside one face, or whole faces) with
// probability mass(v) / total(rows), by inverse transform with one uniform per level: the face (when the
// range spans several) by the face totals, the row inside the face (the first whose in-face prefix
// exceeds the target), the texel inside the row (the first whose in-row prefix exceeds the uniform times
// the row's total). Inside one face u.x and u.y serve row and texel; over several faces u.x, u.y, u.z
// serve face, row and texel. One uniform per level: a single 24-bit u cannot resolve a texel whose
// share of the range is below 2⁻²⁴, and a face's rows, resolved against everything before them, lose
// the precision of the heavier faces (the prefix restarts per face for the same reason).
// Why this never returns a texel without mass: a zero weight leaves a float prefix unchanged
// (acc + 0 = acc), so "first prefix > t" can only stop where the prefix grew, i.e. at a texel with
// mass; and clamping each target just below its total (u → 1 and rounding could otherwise reach it)
// guarantees such a prefix exists. Call only when the rows' total is > 0. Returns the texel, and in prob
// the texel's cdf_prob_rows(cb, texel, r0, r1), bit for bit: computed by cdf_prob_of from the same floats
// (the face totals, summed in the same order, and the row range the search read; four more reads for the
// row's and the texel's own steps), which spares a caller the twenty-odd reads of a second descent.
uint cdf_sample_rows3_prob(uint cb, uint ib, vec3 u, uint r0, uint r1, out float prob) {
    uint rows = cdf_rows(cb), len = cdf_len(cb);
    uint f0 = r0 / len, f1 = (r1 - 1u) / len;
    uint a = r0, b = r1;
    // One face: u.x picks the row and u.y the texel. Several: u.x the face, u.y the row, u.z the texel.
    vec2 ur = u.xy;
    float p_face = 1.0;
    bool weighed = true; // cdf_prob_rows's early 0 when the faces' total is not > 0
    if (f0 != f1) {
        ur = u.yz;
        float t = cdf_rows_total(cb, r0, r1);
        float target = min(u.x * t, cdf_below(t));
        float cum = 0.0, before = 0.0;
        uint f = f1;
        for (uint k = f0; k <= f1; k++) {
            before = cum;
            cum += cdf_face_total(cb, k);
            if (cum > target) { f = k; break; }
        }
        // cdf_prob_rows's face factor: its loop stops at f with the same partial sums.
        weighed = t > 0.0;
        p_face = (cum - before) / t;
        a = f * len;
        b = min((f + 1u) * len, rows);
    }
    float before0 = cdf_row_start(cb, a);
    float end = cdf_at(cb + CDF_HEADER + b - 1u);
    float target = min(before0 + ur.x * (end - before0), cdf_below(end));
    target = max(target, before0);
    uint lo = a, hi = b - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (cdf_at(cb + CDF_HEADER + mid) > target) hi = mid; else lo = mid + 1u;
    }
    uint r = lo;
    uint base = cb + CDF_HEADER + rows + r * len;
    float last = cdf_at(base + len - 1u);
    float tt = min(ur.y * last, cdf_below(last));
    lo = 0u;
    hi = len - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (cdf_at(base + mid) > tt) hi = mid; else lo = mid + 1u;
    }
    float delta = cdf_at(cb + CDF_HEADER + r) - cdf_row_start(cb, r);
    float texel_hi = cdf_at(base + lo);
    float texel_lo = lo > 0u ? cdf_at(base + lo - 1u) : 0.0;
    prob = weighed ? cdf_prob_of(p_face, end - before0, delta, last, texel_hi, texel_lo) : 0.0;
    return r * len + lo;
}

// Two more uniforms derived from the first, for the single-u entry points used by tests.
vec3 cdf_uniforms(float u) {
    uint h1 = pcg_hash(floatBitsToUint(u) ^ 0x9E3779B9u);
    uint h2 = pcg_hash(h1 ^ 0x85EBCA6Bu);
    return vec3(u, float(h1 >> 8) * (1.0 / 16777216.0), float(h2 >> 8) * (1.0 / 16777216.0));
}

uint cdf_sample_rows(uint cb, uint ib, float u, uint r0, uint r1) {
    float prob;
    return cdf_sample_rows3_prob(cb, ib, cdf_uniforms(u), r0, r1, prob);
}

// The probability that cdf_sample_rows3_prob returns v, computed from the same floats the searches read
// (not from v's weight): the face f with probability (C_f − C_{f−1}) / C (C the running sum of face
// totals over the range, in the same order), the row r inside it with Δ_r / (face range), the texel with
// (p_i − p_{i−1}) / P (P the row's total). A weight too small to change its float prefix is never drawn
// and gets probability 0 here too. Exact for continuous uniforms; with 24-bit ones each factor is off by
// at most 2⁻²⁴ plus one ulp of its own total.
float cdf_prob_rows(uint cb, uint v, uint r0, uint r1) {
    uint rows = cdf_rows(cb), len = cdf_len(cb);
    uint r = v / len, i = v % len;
    if (r < r0 || r >= r1) return 0.0;
    uint f0 = r0 / len, f1 = (r1 - 1u) / len, f = r / len;
    float p_face = 1.0;
    uint a = r0, b = r1;
    if (f0 != f1) {
        float t = cdf_rows_total(cb, r0, r1);
        if (!(t > 0.0)) return 0.0;
        float cum = 0.0, before = 0.0;
        for (uint k = f0; k <= f; k++) {
            before = cum;
            cum += cdf_face_total(cb, k);
        }
        p_face = (cum - before) / t;
        a = f * len;
        b = min((f + 1u) * len, rows);
    }
    float range = cdf_at(cb + CDF_HEADER + b - 1u) - cdf_row_start(cb, a);
    float delta = cdf_at(cb + CDF_HEADER + r) - cdf_row_start(cb, r);
    uint base = cb + CDF_HEADER + rows + r * len;
    float last = cdf_at(base + len - 1u);
    float hi = cdf_at(base + i);
    float lo = i > 0u ? cdf_at(base + i - 1u) : 0.0;
    return cdf_prob_of(p_face, range, delta, last, hi, lo);
}

// The whole of section 0, with the texel's probability (its weight over the total).
uint cdf_sample(float u, out float prob) {
    uint rows = floatBitsToUint(cdf_at(1u));
    uint v = cdf_sample_rows(0u, 0u, u, 0u, rows);
    prob = cdf_mass(v) / cdf_at(0u);
    return v;
}

#endif
