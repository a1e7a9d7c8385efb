#version 460
// denoise, variance stage (dispatch W × H): the accumulated illumination and its luminance variance
// for the à-trous stages, σ² = E[l²] − E[l]² from the accumulated moments; where the history is
// shorter than 4 frames, both from the pixel's 7 × 7 neighbourhood instead (weighted by the geometric
// edge stops), the variance raised by 4 / length (SVGF: a young history's moments are too few).
#include "shared/denoise.glsl"

layout(set = 0, binding = B_DENOISE_IN) uniform sampler2D color;
layout(set = 0, binding = B_DENOISE_MOMENTS) uniform sampler2D moments;
layout(set = 0, binding = B_DENOISE_OUT, rgba32f) uniform writeonly image2D out_color;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 c = texelFetch(color, px, 0);
    vec2 m = texelFetch(moments, px, 0).xy;
    Surface p = surface_at(px);
    if (p.hit && c.a < 4.0) {
        vec3 sum_c = vec3(0.0);
        vec2 sum_m = vec2(0.0);
        float sum_w = 0.0;
        for (int dy = -3; dy <= 3; dy++) {
            for (int dx = -3; dx <= 3; dx++) {
                ivec2 q = px + ivec2(dx, dy);
                if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(frame.size.xy)))) continue;
                float w = (dx == 0 && dy == 0) ? 1.0 : geometry_weight(p, surface_at(q), length(vec2(dx, dy)));
                if (w == 0.0) continue;
                sum_c += w * texelFetch(color, q, 0).rgb;
                sum_m += w * texelFetch(moments, q, 0).xy;
                sum_w += w;
            }
        }
        c.rgb = sum_c / sum_w;
        m = sum_m / sum_w;
        imageStore(out_color, px, vec4(c.rgb, max(0.0, m.y - m.x * m.x) * 4.0 / c.a));
        return;
    }
    imageStore(out_color, px, vec4(c.rgb, max(0.0, m.y - m.x * m.x)));
}
