#version 460
// direct: Σ_l albedo/π · I_l · max(0, cos θ_l) / d_l² · V(x, l), V from the paraboloid depth maps.
// See crates/graph/src/passes/direct.rs.
#include "shared/scene.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

layout(set = 0, binding = B_DIRECT_GPOSITION) uniform sampler2D g_position;
layout(set = 0, binding = B_DIRECT_GNORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = B_DIRECT_GALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = B_DIRECT_SHADOW) uniform sampler2DArray shadow_map;
layout(set = 0, binding = B_DIRECT_OUT, rgba32f) uniform writeonly image2D out_radiance;

// 1 when x (at distance d from light li, cos_theta between its normal and the light direction) is the
// nearest surface the light sees in that direction, within the bias; 0 otherwise.
float visibility(vec3 x, float d, float cos_theta, uint li) {
    vec3 local = x - lights[li].position.xyz;
    uint face = local.z >= 0.0 ? 0u : 1u;
    vec2 uv = paraboloid_project(to_face(local, face));
    int res = int(frame.maps.x);
    ivec2 texel = clamp(ivec2(floor((uv * 0.5 + 0.5) * float(res))), ivec2(0), ivec2(res - 1));
    float stored = texelFetch(shadow_map, ivec3(texel, int(li * 2u + face)), 0).r * frame.scene_max.w;
    return d <= stored + paraboloid_shadow_bias(uv, res, d, cos_theta) ? 1.0 : 0.0;
}

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
    for (uint li = 0u; li < frame.size.z; li++) {
        vec3 to_light = lights[li].position.xyz - x;
        float d2 = dot(to_light, to_light);
        float d = sqrt(d2);
        float cos_theta = dot(n, to_light / d);
        if (cos_theta <= 0.0 || d2 == 0.0) continue;
        radiance += albedo / PI * lights[li].intensity.rgb * cos_theta / d2 * visibility(x, d, cos_theta, li);
    }
    imageStore(out_radiance, px, vec4(radiance, 1.0));
}
