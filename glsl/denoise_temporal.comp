#version 460
// denoise, temporal stage (dispatch W × H): the raw estimate's indirect illumination (radiance minus
// the direct light, demodulated by the albedo) blended into last frame's accumulation where the pixel's
// surface was (passes/reproject.rs; bilinear where the four pixels around that place held the same
// surface, else the pixel it fell in), and so is the estimate's variance (the raw image's alpha: ris's
// shade measures it over the pixel's reservoirs); the blend's weight of the new frame is max(α, 1 /
// history length), the history restarting where the surface was disoccluded.
// The history is first clamped into this frame's neighbourhood (mean ± DENOISE_CLAMP_SIGMAS standard
// deviations per channel): light that moved is not dragged along for 1 / α frames. And where the
// lighting changed by more than the noise can explain, the history counts less (a temporal gradient
// test, after A-SVGF's): over 5 × 5 pixels, this frame's mean luminance against the history's at the
// previous pixels, Δ, with the estimate's measured variance σ² (the raw image's alpha) giving the
// difference's noise s = √(σ̄² / 25 · (1 + α)) (the history's own noise about α of a frame's); the new
// frame's weight is raised to λ = max(0, (Δ − DENOISE_GRADIENT_SIGMAS · s) / Δ), the share of the change
// beyond the noise.
#include "shared/denoise.glsl"

layout(set = 0, binding = B_DENOISE_IN) uniform sampler2D raw;
layout(set = 0, binding = B_GATHER_DIRECT) uniform sampler2D direct_radiance;
layout(set = 0, binding = B_MOTION) uniform sampler2D motion;
layout(set = 0, binding = B_DENOISE_PREV_COLOR) uniform sampler2D prev_color;
layout(set = 0, binding = B_DENOISE_PREV_VARIANCE) uniform sampler2D prev_variance;
layout(set = 0, binding = B_DENOISE_COLOR_OUT, rgba32f) uniform writeonly image2D color_out;
layout(set = 0, binding = B_DENOISE_VARIANCE_OUT, r32f) uniform writeonly image2D variance_out;

// The longest history counted (the blend's weight stays at α beyond 1 / α frames anyway).
const float MAX_HISTORY = 255.0;

// The raw estimate's indirect light at p, demodulated by the albedo, clipped at 0. The control variate
// makes single estimates negative where the kept VPL is occluded, and clipping them adds light (where it
// learns visibility, 1–5 % of the image's mean); unclipped, the generated suite measured 0.99× the
// denoised error, the dark rooms 1.02× with that light lost (BENCHMARKS.md, "Things tried").
vec3 illumination(ivec2 p) {
    vec3 c = texelFetch(raw, p, 0).rgb;
    if (pc.add_direct != 0u) c -= texelFetch(direct_radiance, p, 0).rgb;
    return max(demodulate(c, texelFetch(g_albedo, p, 0).rgb), vec3(0.0));
}

// h clamped into this frame's 5 × 5 neighbourhood: its mean ± DENOISE_CLAMP_SIGMAS standard deviations,
// per channel.
vec3 clamp_to_neighbourhood(ivec2 px, vec3 h) {
    vec3 m1 = vec3(0.0), m2 = vec3(0.0);
    for (int dy = -2; dy <= 2; dy++) {
        for (int dx = -2; dx <= 2; dx++) {
            vec3 iq = illumination(clamp(px + ivec2(dx, dy), ivec2(0), ivec2(frame.size.xy) - 1));
            m1 += iq;
            m2 += iq * iq;
        }
    }
    m1 /= 25.0;
    vec3 sd = sqrt(max(m2 / 25.0 - m1 * m1, vec3(0.0)));
    return clamp(h, m1 - DENOISE_CLAMP_SIGMAS * sd, m1 + DENOISE_CLAMP_SIGMAS * sd);
}

// λ of the temporal gradient test (above) between this frame at px and the history at q, over the offsets
// whose pixels lie inside the image around both (n of them: at a border the mean's noise is that of n
// pixels, not of 25 with some repeated).
float gradient_weight(ivec2 px, ivec2 q) {
    float now = 0.0, before = 0.0, variance = 0.0, n = 0.0;
    ivec2 size = ivec2(frame.size.xy);
    for (int dy = -2; dy <= 2; dy++) {
        for (int dx = -2; dx <= 2; dx++) {
            ivec2 a = px + ivec2(dx, dy), b = q + ivec2(dx, dy);
            if (any(lessThan(min(a, b), ivec2(0))) || any(greaterThanEqual(max(a, b), size))) continue;
            now += luminance(illumination(a));
            variance += texelFetch(raw, a, 0).a;
            before += luminance(texelFetch(prev_color, b, 0).rgb);
            n += 1.0;
        }
    }
    // (n ≥ 1: px and q are inside the image.)
    float change = abs(now - before) / n, noise = sqrt(variance / (n * n) * (1.0 + pc.alpha));
    return change > 0.0 ? clamp((change - DENOISE_GRADIENT_SIGMAS * noise) / change, 0.0, 1.0) : 0.0;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec3 illum = illumination(px);
    float variance = texelFetch(raw, px, 0).a;
    float len = 1.0;
    vec4 mv = texelFetch(motion, px, 0);
    if (pc.history != 0u && mv.z != 0.0) {
        // Last frame's accumulation where the surface was: bilinear where all four pixels around it held the
        // same surface, else the pixel it fell in, q (which also anchors the gradient test). A bilinear
        // lookup renormalized over fewer pixels is a gather, which at a plane's edge would lose a bright
        // edge's light frame after frame (passes/denoise.rs).
        ivec2 q = ivec2(mv.xy);
        vec4 h = texelFetch(prev_color, q, 0);
        float hv = texelFetch(prev_variance, q, 0).r;
        if (uint(mv.w) == 15u) {
            ivec2 base;
            vec2 t;
            bilinear_footprint(mv.xy, base, t);
            h = bilinear_fetch(prev_color, base, t);
            hv = bilinear_fetch(prev_variance, base, t).r;
        }
        if (h.a > 0.0) {
            h.rgb = clamp_to_neighbourhood(px, h.rgb);
            len = min(h.a + 1.0, MAX_HISTORY);
            float a = max(max(pc.alpha, 1.0 / len), gradient_weight(px, q));
            illum = mix(h.rgb, illum, a);
            variance = mix(hv, variance, a);
        }
    }
    imageStore(color_out, px, vec4(illum, len));
    imageStore(variance_out, px, vec4(variance));
}
