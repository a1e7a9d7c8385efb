#version 460
// denoise, variance stage (dispatch W × H): the accumulated illumination and the noise variance σ² that
// scales the à-trous stages' luminance stop. σ² is the raw estimate's own variance (ris's shade measures
// it over the pixel's reservoirs; the temporal stage averages it over the history): the noise alone, not
// the signal's variation, so a bright corner's gradient is not taken for noise and blurred away (SVGF's
// E[l²] − E[l]² over the frames, and over a 7 × 7 neighbourhood for a young history, counts both).
// Where the history is shorter than 4 frames, σ² is pooled over the 7 × 7 neighbourhood (weighted by the
// geometric edge stops) and the illumination is filtered there once: each neighbour weighted by the edge
// stops and by the luminance stop at the noise scale s = max(σ, σ² / m), m the neighbourhood's mean
// luminance. σ² / m is the size of one sample's contribution where the noise is sparse hits (a pixel's
// estimate is 0 or one large value: Var ≈ m · size), whose hits the stop must take for noise, not signal.
#include "shared/denoise.glsl"

layout(set = 0, binding = B_DENOISE_IN) uniform sampler2D color;
layout(set = 0, binding = B_DENOISE_VARIANCE) uniform sampler2D variance;
layout(set = 0, binding = B_DENOISE_OUT, rgba32f) uniform writeonly image2D out_color;

// The history length below which the neighbourhood stands in for the pixel (SVGF's 4 frames).
const float YOUNG = 4.0;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 c = texelFetch(color, px, 0);
    float var = texelFetch(variance, px, 0).r;
    Surface p = surface_at(px);
    if (p.hit && c.a < YOUNG) {
        // The neighbourhood's geometric weights, its pooled variance and its mean luminance.
        float w[49];
        float sum_v = 0.0, sum_l = 0.0, sum_w = 0.0;
        for (int dy = -3; dy <= 3; dy++) {
            for (int dx = -3; dx <= 3; dx++) {
                int k = (dy + 3) * 7 + dx + 3;
                ivec2 q = px + ivec2(dx, dy);
                w[k] = !inside(q) ? 0.0
                    : (dx == 0 && dy == 0) ? 1.0
                    : geometry_weight(p, surface_at(q), length(vec2(dx, dy)));
                if (w[k] == 0.0) continue;
                sum_v += w[k] * texelFetch(variance, q, 0).r;
                sum_l += w[k] * luminance(texelFetch(color, q, 0).rgb);
                sum_w += w[k];
            }
        }
        var = sum_v / sum_w;
        float m = sum_l / sum_w, sd = sqrt(var);
        if (m > 0.0) sd = max(sd, var / m);
        float lp = luminance(c.rgb);
        vec3 sum_c = vec3(0.0);
        float sum_cw = 0.0;
        for (int dy = -3; dy <= 3; dy++) {
            for (int dx = -3; dx <= 3; dx++) {
                int k = (dy + 3) * 7 + dx + 3;
                if (w[k] == 0.0) continue;
                vec3 cq = texelFetch(color, px + ivec2(dx, dy), 0).rgb;
                float wq = w[k] * luminance_weight(lp, luminance(cq), sd);
                sum_c += wq * cq;
                sum_cw += wq;
            }
        }
        c.rgb = sum_c / sum_cw;
        var = sd * sd;
    }
    imageStore(out_color, px, vec4(c.rgb, var));
}
