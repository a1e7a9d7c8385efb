#version 460
// denoise, à-trous stage (dispatch W × H, DENOISE_ITERATIONS times, tap spacing 2^i): a 5 × 5 B3-spline
// kernel h over illumination and variance (Dammertz et al. 2010; SVGF, Schied et al. 2017), each tap
// weighted by the normals, the plane distance and the luminance against σ_l standard deviations of the
// variance; the variance filtered with the squared weights. The last iteration multiplies the
// illumination by the albedo again and adds the direct light. Two forms (passes/denoise.rs says why):
//
// - gather, the first DENOISE_GATHER_ITERATIONS iterations (SVGF's): c_p ← Σ_q w_pq c_q / Σ_q w_pq, the
//   stops p's own (its plane, its 3 × 3-blurred variance). A noisy pixel takes from its quiet neighbours
//   without giving back, which is what removes a lone hit; what it held is lost.
// - exchange, the rest: c_p ← c_p + Σ_q w_pq (c_q − c_p) with w_pq = w_qp (h times symmetric stops: the
//   larger of the two plane distances, the luminance against the geometric mean of the two pixels'
//   standard deviations) and the weight that the stops reject left on c_p. Whatever q gives p, p gives q
//   in return: the light is moved, never lost, so the wide taps keep a peak at a plane's edge.
#include "shared/denoise.glsl"

layout(set = 0, binding = B_DENOISE_IN) uniform sampler2D ping;
layout(set = 0, binding = B_GATHER_DIRECT) uniform sampler2D direct_radiance;
layout(set = 0, binding = B_DENOISE_OUT, rgba32f) uniform writeonly image2D out_color;

const float KERNEL[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);

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
    vec3 sum_c = c.rgb * (KERNEL[0] * KERNEL[0]);
    float sum_v = c.a * (KERNEL[0] * KERNEL[0]) * (KERNEL[0] * KERNEL[0]), sum_w = KERNEL[0] * KERNEL[0];
    for (int dy = -2; dy <= 2; dy++) {
        for (int dx = -2; dx <= 2; dx++) {
            if (dx == 0 && dy == 0) continue;
            ivec2 q = px + ivec2(dx, dy) * int(pc.step);
            if (!inside(q)) continue;
            vec4 cq = texelFetch(ping, q, 0);
            float w = KERNEL[abs(dx)] * KERNEL[abs(dy)]
                * geometry_weight(p, surface_at(q), length(vec2(dx, dy)) * float(pc.step))
                * luminance_weight(lp, luminance(cq.rgb), sd);
            sum_c += w * cq.rgb;
            sum_v += w * w * cq.a;
            sum_w += w;
        }
    }
    return vec4(sum_c / sum_w, sum_v / (sum_w * sum_w));
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
