#version 460
// reference: the exact one-bounce integrator of the scene contract, on the GPU. The primary hit is the
// G-buffer's (the contract's pixel-centre ray, rasterized exactly); then per sample a cosine-distributed
// bounce ray is traced against the real triangles (BVH) to its first hit y, whose direct light toward x
// (normal flipped toward x, exact shadow rays) is the incoming radiance:
//   L_ind(x) = ∫ albedo(x)/π · L_direct(y → x) cos θ dω ≈ albedo(x) · 1/N Σ_k L_direct(y_k → x)
// (the cosine pdf cancels the BRDF's 1/π and the cosine). Samples [first, last) of N per dispatch; the
// output accumulates Σ L_k / N and the second image Σ L_k² / N, from which the host reports the standard
// error. See crates/graph/src/passes/reference.rs.
#include "shared/scene.glsl"
#include "shared/bvh.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(push_constant) uniform Push { GatherPush pc; };
layout(set = 0, binding = B_GATHER_GPOSITION) uniform sampler2D g_position;
layout(set = 0, binding = B_GATHER_GNORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = B_GATHER_GALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = B_GATHER_DIRECT) uniform sampler2D direct_radiance;
layout(set = 0, binding = B_GATHER_OUT, rgba32f) uniform image2D out_sum;
layout(set = 0, binding = B_REF_SQ, rgba32f) uniform image2D out_sq;

// Direct radiance leaving y toward x (the contract's L_direct), exact visibility.
vec3 direct_at(vec3 y, vec3 ny, vec3 ay) {
    vec3 l_sum = vec3(0.0);
    for (uint l = 0u; l < frame.size.z; l++) {
        vec3 lp = lights[l].position.xyz;
        vec3 to = lp - y;
        float d2 = dot(to, to);
        if (d2 <= 0.0) continue;
        float c = dot(ny, to) * inversesqrt(d2);
        if (c <= 0.0 || bvh_occluded(y, lp)) continue;
        l_sum += ay / PI * lights[l].intensity.rgb * c / d2;
    }
    return l_sum;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 gp = texelFetch(g_position, px, 0);
    vec3 sum = vec3(0.0), sq = vec3(0.0);
    if (gp.w != 0.0) {
        vec3 x = gp.xyz;
        vec3 n = texelFetch(g_normal, px, 0).xyz;
        vec3 ax = texelFetch(g_albedo, px, 0).rgb;
        // Leave x's own triangle: a small offset along the normal (see surface_lift).
        vec3 o = x + n * surface_lift(x, frame.scene_min.w);
        uint base = pcg_hash(uint(px.x) + 65536u * uint(px.y)) ^ pc.seed ^ 0x2545F491u;
        for (uint k = pc.first; k < pc.last; k++) {
            uint rng = pcg_hash(base ^ pcg_hash(k + 0x9E3779B9u));
            float u1 = rand01(rng), u2 = rand01(rng);
            vec3 d = cosine_direction(n, u1, u2);
            uint tri;
            vec2 bary;
            float t = bvh_closest(o, d, 1e30, tri, bary);
            vec3 value = vec3(0.0);
            if (t > 0.0) {
                Vertex v0 = vertices[3u * tri], v1 = vertices[3u * tri + 1u], v2 = vertices[3u * tri + 2u];
                float w0 = 1.0 - bary.x - bary.y;
                vec3 y = w0 * v0.position_u.xyz + bary.x * v1.position_u.xyz + bary.y * v2.position_u.xyz;
                vec3 ny = normalize(w0 * v0.normal_v.xyz + bary.x * v1.normal_v.xyz + bary.y * v2.normal_v.xyz);
                if (dot(ny, x - y) < 0.0) ny = -ny;
                vec2 uv = w0 * vec2(v0.position_u.w, v0.normal_v.w) + bary.x * vec2(v1.position_u.w, v1.normal_v.w)
                        + bary.y * vec2(v2.position_u.w, v2.normal_v.w);
                value = ax * direct_at(y, ny, albedo_at(tri, uv));
            }
            sum += value;
            sq += value * value;
        }
        sum /= float(pc.samples);
        sq /= float(pc.samples);
    }
    if (pc.add_direct != 0u) sum += texelFetch(direct_radiance, px, 0).rgb;
    if (pc.accumulate != 0u) {
        sum += imageLoad(out_sum, px).rgb;
        sq += imageLoad(out_sq, px).rgb;
    }
    imageStore(out_sum, px, vec4(sum, 1.0));
    imageStore(out_sq, px, vec4(sq, 1.0));
}
