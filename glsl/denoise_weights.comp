#version 460
// denoise, weight-sum stage (dispatch W × H, before each à-trous iteration): each pixel's total kernel
// weight W = Σ_q h(q − p) w(p, q) at this iteration's tap spacing, with the à-trous stage's symmetric edge
// stops; that stage normalizes each pair's weight by the larger of the two sums.
#include "shared/denoise.glsl"

layout(set = 0, binding = B_DENOISE_IN) uniform sampler2D ping;
layout(set = 0, binding = B_DENOISE_OUT, r32f) uniform writeonly image2D out_sum;

const float KERNEL[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 c = texelFetch(ping, px, 0);
    Surface p = surface_at(px);
    float sum = KERNEL[0] * KERNEL[0];
    if (p.hit) {
        float lp = luminance(c.rgb);
        for (int dy = -2; dy <= 2; dy++) {
            for (int dx = -2; dx <= 2; dx++) {
                if (dx == 0 && dy == 0) continue;
                ivec2 q = px + ivec2(dx, dy) * int(pc.step);
                if (!inside(q)) continue;
                vec4 cq = texelFetch(ping, q, 0);
                sum += KERNEL[abs(dx)] * KERNEL[abs(dy)]
                    * geometry_weight_symmetric(p, surface_at(q), length(vec2(dx, dy)) * float(pc.step))
                    * luminance_weight(lp, luminance(cq.rgb), sqrt(sqrt(max(c.a * cq.a, 0.0))));
            }
        }
    }
    imageStore(out_sum, px, vec4(sum));
}
