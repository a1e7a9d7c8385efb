#version 460
// denoise, à-trous stage (dispatch W × H, DENOISE_ITERATIONS times, tap spacing 2^i): a 5 × 5 B3-spline
// kernel over illumination and variance (Dammertz et al. 2010; SVGF, Schied et al. 2017), each tap
// weighted by the normals, the plane distance and the luminance against σ_l standard deviations of the
// pixel's 3 × 3-blurred variance; the variance filtered with the squared weights. The last iteration
// multiplies the illumination by the albedo again and adds the direct light.
#include "shared/denoise.glsl"

layout(set = 0, binding = B_DENOISE_IN) uniform sampler2D ping;
layout(set = 0, binding = B_GATHER_DIRECT) uniform sampler2D direct_radiance;
layout(set = 0, binding = B_DENOISE_VARIANCE) uniform sampler2D weight_sum;
layout(set = 0, binding = B_DENOISE_OUT, rgba32f) uniform writeonly image2D out_color;

const float KERNEL[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 c = texelFetch(ping, px, 0);
    Surface p = surface_at(px);
    if (p.hit) {
        float lp = luminance(c.rgb), wp = texelFetch(weight_sum, px, 0).r;
        vec3 sum_c = vec3(0.0);
        float sum_v = 0.0, sum_k = 0.0;
        for (int dy = -2; dy <= 2; dy++) {
            for (int dx = -2; dx <= 2; dx++) {
                if (dx == 0 && dy == 0) continue;
                ivec2 q = px + ivec2(dx, dy) * int(pc.step);
                if (!inside(q)) continue;
                vec4 cq = texelFetch(ping, q, 0);
                float k = KERNEL[abs(dx)] * KERNEL[abs(dy)]
                    * geometry_weight_symmetric(p, surface_at(q), length(vec2(dx, dy)) * float(pc.step))
                    * luminance_weight(lp, luminance(cq.rgb), sqrt(sqrt(max(c.a * cq.a, 0.0))))
                    / max(wp, texelFetch(weight_sum, q, 0).r);
                sum_c += k * cq.rgb;
                sum_v += k * k * cq.a;
                sum_k += k;
            }
        }
        float k0 = 1.0 - sum_k;
        c = vec4(sum_c + k0 * c.rgb, sum_v + k0 * k0 * c.a);
    }
    if (pc.last != 0u) {
        vec3 radiance = c.rgb * texelFetch(g_albedo, px, 0).rgb;
        if (pc.add_direct != 0u) radiance += texelFetch(direct_radiance, px, 0).rgb;
        c = vec4(p.hit ? radiance : vec3(0.0), 1.0);
    }
    imageStore(out_color, px, c);
}
