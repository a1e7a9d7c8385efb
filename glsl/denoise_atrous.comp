#version 460
// denoise, à-trous stage (dispatch W × H, DENOISE_ITERATIONS times, tap spacing 2^i): a 5 × 5 B3-spline
// kernel h over illumination and variance (Dammertz et al. 2010; SVGF, Schied et al. 2017), each tap
// weighted by the normals, the plane distance and the luminance against σ_l standard deviations of the
// variance; the variance filtered with the squared weights. The last iteration multiplies the
// illumination by the albedo again and adds the direct light. Two forms (passes/denoise.rs says why):
//
// - gather, the first DENOISE_GATHER_ITERATIONS iterations: the stops p's own (its plane, its 3 × 3-
//   blurred variance), and the output the intercept a of the weighted least-squares plane through the
//   taps, c(q) ≈ a + b · d_q (d_q the tap's offset in taps; a local linear regression), with a ridge of
//   DENOISE_RIDGE · Σw on b, clamped into the taps' range. Where the taps are balanced around p (Σ w d =
//   0) it is SVGF's weighted mean Σ w c / Σ w; where the stops cut the kernel on one side (a plane's edge,
//   a bright neighbour rejected) the mean is pulled toward the other side's values, and the fit follows
//   the slope instead. A noisy pixel still takes from its quiet neighbours without giving back, which is
//   what removes a lone hit.
// - exchange, the rest: c_p ← c_p + Σ_q w_pq (c_q − c_p) with w_pq = w_qp (h times symmetric stops: the
//   larger of the two plane distances, the luminance against the geometric mean of the two pixels'
//   standard deviations) and the weight that the stops reject left on c_p. Whatever q gives p, p gives q
//   in return: the light is moved, never lost.
#include "shared/denoise.glsl"

layout(set = 0, binding = B_DENOISE_IN) uniform sampler2D ping;
layout(set = 0, binding = B_GATHER_DIRECT) uniform sampler2D direct_radiance;
layout(set = 0, binding = B_DENOISE_OUT, rgba32f) uniform writeonly image2D out_color;

const float KERNEL[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);

// A plane fitted to weighted samples c at offsets d by least squares, c ≈ a + b · d: the sums of its
// normal equations [s0 s1ᵀ; s1 S2] [a; b] = [t0; T1] per channel (S2 as xx, xy, yy; T1 as tx, ty),
// and the samples' range. The gathers keep its intercept a (passes/denoise.rs says why).
struct PlaneFit {
    float s0;
    vec2 s1;
    vec3 s2;
    vec3 t0, tx, ty;
    vec3 lo, hi;
};

PlaneFit plane_fit(float w, vec3 c) {
    return PlaneFit(w, vec2(0.0), vec3(0.0), w * c, vec3(0.0), vec3(0.0), c, c);
}

void plane_add(inout PlaneFit f, vec2 d, float w, vec3 c) {
    f.s0 += w;
    f.s1 += w * d;
    f.s2 += w * vec3(d.x * d.x, d.x * d.y, d.y * d.y);
    f.t0 += w * c;
    f.tx += w * d.x * c;
    f.ty += w * d.y * c;
    if (w > 0.0) {
        f.lo = min(f.lo, c);
        f.hi = max(f.hi, c);
    }
}

// a = (t0 − k · T1) / (s0 − k · s1) with k = M⁻¹ s1, M = S2 + ridge · s0 · I (a fit over few or collinear
// samples stays near their mean; nearly degenerate, the mean itself), clamped into the samples' range.
vec3 plane_intercept(PlaneFit f, float ridge) {
    vec3 m = f.s2 + vec3(ridge * f.s0, 0.0, ridge * f.s0);
    float det = m.x * m.z - m.y * m.y;
    vec2 k = det > 0.0 ? vec2(m.z * f.s1.x - m.y * f.s1.y, m.x * f.s1.y - m.y * f.s1.x) / det : vec2(0.0);
    float den = f.s0 - dot(k, f.s1);
    if (!(den > 1e-3 * f.s0)) {
        k = vec2(0.0);
        den = f.s0;
    }
    return clamp((f.t0 - k.x * f.tx - k.y * f.ty) / den, f.lo, f.hi);
}

vec4 gather(ivec2 px, Surface p, vec4 c) {
    // The variance blurred by a 3 × 3 Gaussian: the luminance stop's scale.
    float var = 0.0, wsum = 0.0;
    for (int dy = -1; dy <= 1; dy++) {
        for (int dx = -1; dx <= 1; dx++) {
            ivec2 q = px + ivec2(dx, dy);
            if (!inside(q)) continue;
            float w = (dx == 0 ? 0.5 : 0.25) * (dy == 0 ? 0.5 : 0.25);
            var += w * texelFetch(ping, q, 0).a;
            wsum += w;
        }
    }
    float sd = sqrt(max(var / wsum, 0.0));
    float lp = luminance(c.rgb);
    // The variance is filtered as the weighted mean's, Σ w² σ² / (Σ w)² (the next stops' scale): the
    // intercept's own, Σ ℓ² σ² with ℓ_q = w_q (1 − k · d_q) / (s0 − k · s1), larger where the taps lie on
    // one side, cost lavapipe 1.5–2× this stage's time for 0.96× the flicker and less of a corner's light
    // kept (BENCHMARKS.md, "Things tried").
    float w0 = KERNEL[0] * KERNEL[0];
    PlaneFit fit = plane_fit(w0, c.rgb);
    float v = w0 * w0 * c.a;
    for (int dy = -2; dy <= 2; dy++) {
        for (int dx = -2; dx <= 2; dx++) {
            if (dx == 0 && dy == 0) continue;
            ivec2 q = px + ivec2(dx, dy) * int(pc.step);
            if (!inside(q)) continue;
            vec4 cq = texelFetch(ping, q, 0);
            float w = KERNEL[abs(dx)] * KERNEL[abs(dy)]
                * geometry_weight(p, surface_at(q), length(vec2(dx, dy)) * float(pc.step))
                * luminance_weight(lp, luminance(cq.rgb), sd);
            plane_add(fit, vec2(dx, dy), w, cq.rgb);
            v += w * w * cq.a;
        }
    }
    return vec4(plane_intercept(fit, DENOISE_RIDGE), v / (fit.s0 * fit.s0));
}

vec4 exchange(ivec2 px, Surface p, vec4 c) {
    float lp = luminance(c.rgb);
    vec3 sum_c = vec3(0.0);
    float sum_v = 0.0, sum_w = 0.0;
    for (int dy = -2; dy <= 2; dy++) {
        for (int dx = -2; dx <= 2; dx++) {
            if (dx == 0 && dy == 0) continue;
            ivec2 q = px + ivec2(dx, dy) * int(pc.step);
            if (!inside(q)) continue;
            vec4 cq = texelFetch(ping, q, 0);
            float w = KERNEL[abs(dx)] * KERNEL[abs(dy)]
                * geometry_weight_symmetric(p, surface_at(q), length(vec2(dx, dy)) * float(pc.step))
                * luminance_weight(lp, luminance(cq.rgb), sqrt(sqrt(max(c.a * cq.a, 0.0))));
            sum_c += w * cq.rgb;
            sum_v += w * w * cq.a;
            sum_w += w;
        }
    }
    // The taps' weights sum to 1 − h(0)² at most: what is left (≥ h(0)²) stays with p.
    float w0 = 1.0 - sum_w;
    return vec4(sum_c + w0 * c.rgb, sum_v + w0 * w0 * c.a);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 c = texelFetch(ping, px, 0);
    Surface p = surface_at(px);
    if (p.hit) c = pc.step < (1u << DENOISE_GATHER_ITERATIONS) ? gather(px, p, c) : exchange(px, p, c);
    if (pc.last != 0u) {
        vec3 radiance = c.rgb * texelFetch(g_albedo, px, 0).rgb;
        if (pc.add_direct != 0u) radiance += texelFetch(direct_radiance, px, 0).rgb;
        c = vec4(p.hit ? radiance : vec3(0.0), 1.0);
    }
    imageStore(out_color, px, c);
}
