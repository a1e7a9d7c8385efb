#version 460
// denoise, à-trous stage (dispatch W × H, DENOISE_ITERATIONS times, tap spacing 2^i): a 5 × 5 B3-spline
// kernel over illumination and variance (Dammertz et al. 2010; SVGF, Schied et al. 2017), each tap
// weighted by the normals, the plane distance and the luminance against σ_l standard deviations of the
// pixel's 3 × 3-blurred variance; the variance filtered with the squared weights. The last iteration
// multiplies the illumination by the albedo again and adds the direct light.
#include "shared/denoise.glsl"

layout(set = 0, binding = B_DENOISE_IN) uniform sampler2D ping;
layout(set = 0, binding = B_GATHER_DIRECT) uniform sampler2D direct_radiance;
layout(set = 0, binding = B_DENOISE_OUT, rgba32f) uniform writeonly image2D out_color;

const float KERNEL[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 c = texelFetch(ping, px, 0);
    Surface p = surface_at(px);
    if (p.hit) {
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
        c = vec4(sum_c / sum_w, sum_v / (sum_w * sum_w));
    }
    if (pc.last != 0u) {
        vec3 radiance = c.rgb * texelFetch(g_albedo, px, 0).rgb;
        if (pc.add_direct != 0u) radiance += texelFetch(direct_radiance, px, 0).rgb;
        c = vec4(p.hit ? radiance : vec3(0.0), 1.0);
    }
    imageStore(out_color, px, c);
}
