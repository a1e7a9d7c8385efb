#version 460
// direct: Σ_l albedo/π · I_l · max(0, cos θ_l) / d_l² · V(x, l), V by an exact shadow ray from x (lifted
// off its surface) to the light through the BVH. See crates/graph/src/passes/direct.rs.
#include "shared/scene.glsl"
#include "shared/bvh.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(set = 0, binding = B_DIRECT_GPOSITION) uniform sampler2D g_position;
layout(set = 0, binding = B_DIRECT_GNORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = B_DIRECT_GALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = B_DIRECT_OUT, rgba32f) uniform writeonly image2D out_radiance;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 p = texelFetch(g_position, px, 0);
    if (p.w == 0.0) {
        imageStore(out_radiance, px, vec4(0.0, 0.0, 0.0, 1.0));
        return;
    }
    vec3 x = p.xyz;
    vec3 n = texelFetch(g_normal, px, 0).xyz;
    vec3 albedo = texelFetch(g_albedo, px, 0).rgb;
    vec3 radiance = vec3(0.0);
    vec3 o = lifted_origin(x, n);
    for (uint li = 0u; li < frame.size.z; li++) {
        vec3 to_light = lights[li].position.xyz - x;
        float d2 = dot(to_light, to_light);
        float d = sqrt(d2);
        float cos_theta = dot(n, to_light / d);
        if (cos_theta <= 0.0 || d2 == 0.0) continue;
        radiance += albedo / PI * lights[li].intensity.rgb * cos_theta / d2
                  * (bvh_occluded_lifted(o, lights[li].position.xyz) ? 0.0 : 1.0);
    }
    imageStore(out_radiance, px, vec4(radiance, 1.0));
}
