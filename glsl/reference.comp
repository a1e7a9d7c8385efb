#version 460
// reference: the exact one-bounce integrator of the scene contract, on the GPU. The primary hit is the
// G-buffer's (the contract's pixel-centre ray, rasterized exactly); x's bounce light is
//   L_ind(x) = ∫_A albedo(x)/π · L_direct(y → x) · G(x, y) · V(x, y) dA(y),  G = cos θ_x cos θ_y / |x − y|²,
// where L_direct(y → x) is y's direct light toward x (two-sided Lambertian: the normal flipped toward x,
// exact shadow rays; a light lights only the face of y's triangle on its side). Two strategies draw y (x
// stands for the lifted origin o below):
//  (a) cosine: a cosine-distributed direction at x, y its first hit (BVH);
//      p_cos(y) = cos θ_x/π · cos θ_y/|x − y|²                                   (area measure at y)
//  (b) light side: a light l with probability P(l) ∝ the luminance of its intensity, a uniform direction
//      from it, y its first hit, and a shadow ray x ↔ y;
//      p_light(y) = Σ_l P(l) · 1/(4π) · cos θ_(y,l)/|l − y|² · V(l, y)         (area measure at y)
//      (V(l, y) comes from the shadow rays L_direct(y → x) needs anyway; θ_y, θ_(y,l) are angles to the
//      geometric normal, the measure's own).
// The default estimator (MIS) takes one sample of each strategy per sample index k and combines them by the
// balance heuristic over n_cos = n_light = N: with f = albedo(x)/π · L_direct · G · V, each sample adds
// f/(p_cos + p_light) = albedo(x) · L_direct · p_cos/(p_cos + p_light) (· V(x, y) for (b)). The points are
// Owen-scrambled Sobol (shared/owen_sobol.glsl), one 2D set per strategy per pixel and seed, indexed by the
// global sample index k, so the image does not depend on how [0, N) is split into dispatches: each
// dispatch takes samples [first, last), and every sample is added to the running image in order k, so
// any chunking performs the same float operations. out_sum accumulates Σ L_k / N and out_sq Σ L_k² / N
// (the host's standard error). See crates/graph/src/passes/reference.rs.
#include "shared/scene.glsl"
#include "shared/bvh.glsl"
#include "shared/owen_sobol.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(push_constant) uniform Push { GatherPush pc; };
layout(set = 0, binding = B_GATHER_GPOSITION) uniform sampler2D g_position;
layout(set = 0, binding = B_GATHER_GNORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = B_GATHER_GALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = B_GATHER_DIRECT) uniform sampler2D direct_radiance;
layout(set = 0, binding = B_GATHER_OUT, rgba32f) uniform image2D out_sum;
layout(set = 0, binding = B_REF_SQ, rgba32f) uniform image2D out_sq;

// A ray's hit y: position, shading normal flipped toward x, unit geometric normal, albedo.
struct Hit {
    vec3 y;
    vec3 ns;
    vec3 ng;
    vec3 albedo;
    // The side of y's triangle x lies on: the sign of ng · (x − y).
    float x_side;
};

Hit hit_at(uint tri, vec2 bary, vec3 x) {
    Vertex v0 = vertices[3u * tri], v1 = vertices[3u * tri + 1u], v2 = vertices[3u * tri + 2u];
    float w0 = 1.0 - bary.x - bary.y;
    Hit h;
    h.y = w0 * v0.position_u.xyz + bary.x * v1.position_u.xyz + bary.y * v2.position_u.xyz;
    h.ng = triangle_normal(tri);
    h.ns = shading_normal(w0 * v0.normal_v.xyz + bary.x * v1.normal_v.xyz + bary.y * v2.normal_v.xyz, h.ng);
    if (dot(h.ns, x - h.y) < 0.0) h.ns = -h.ns;
    h.x_side = sign(dot(h.ng, x - h.y));
    vec2 uv = w0 * vec2(v0.position_u.w, v0.normal_v.w) + bary.x * vec2(v1.position_u.w, v1.normal_v.w)
            + bary.y * vec2(v2.position_u.w, v2.normal_v.w);
    h.albedo = albedo_at(tri, uv);
    return h;
}

// Light l's share P(l) of the light strategy's samples, times the sum over lights (see light_power).
float light_weight(uint l) {
    return luminance(lights[l].intensity.rgb);
}

const uint NO_LIGHT = 0xFFFFFFFFu;

// L_direct(y → x) (returned) and the light strategy's area density at y (`p_light`). The light `known`
// drew y (NO_LIGHT: none did), so it sees y by construction and needs no shadow ray. A light on the far
// side of y's surface adds nothing to L_direct but may still have drawn y (two-sided surfaces).
vec3 light_side(Hit h, uint known, float inv_power, out float p_light) {
    vec3 l_sum = vec3(0.0);
    p_light = 0.0;
    for (uint l = 0u; l < frame.size.z; l++) {
        vec3 lp = lights[l].position.xyz;
        vec3 to = lp - h.y;
        float d2 = dot(to, to);
        if (d2 <= 0.0) continue;
        float inv_d = inversesqrt(d2);
        float c = dot(h.ns, to) * inv_d;
        float p = light_weight(l) * inv_power / (4.0 * PI) * abs(dot(h.ng, to)) * inv_d / d2;
        if (c <= 0.0 && p <= 0.0) continue;
        // From y lifted toward the light's side of its surface, as a VPL toward its light: with y on its
        // surface the ray needs bvh_occluded's 1e-4 relative window, and a wall within it (a floor point at
        // the foot of a wall between it and the light) did not count: light leaked under walls.
        if (l != known && bvh_occluded_lifted(lifted_origin(h.y, dot(h.ng, to) >= 0.0 ? h.ng : -h.ng), lp)) continue;
        // Light reaches the face of y that x sees only from that face's side of the triangle: where a mesh's
        // shading normal tilts far from its face it can face a light behind the surface, whose shadow ray
        // (from the light's side) the surface itself does not block. The VPLs on that face are the light's
        // side's, and no VPL method lights x through it.
        bool same_face = dot(h.ng, to) * h.x_side > 0.0;
        if (c > 0.0 && same_face) l_sum += h.albedo / PI * lights[l].intensity.rgb * c / d2;
        p_light += p;
    }
    return l_sum;
}

// The balance heuristic's share of a sample at a point with densities p_cos and p_light (area measure).
float balance(float p_cos, float p_light) {
    float sum = p_cos + p_light;
    return sum > 0.0 ? p_cos / sum : 0.0;
}

// The sum of light_weight over the lights (the light strategy's normaliser).
float light_power() {
    float total = 0.0;
    for (uint l = 0u; l < frame.size.z; l++) total += light_weight(l);
    return total;
}

// The light whose share of [0, total) holds u · total.
uint pick_light(float u, float total) {
    float target = u * total, acc = 0.0;
    uint last = 0u;
    for (uint l = 0u; l < frame.size.z; l++) {
        float w = light_weight(l);
        if (w <= 0.0) continue;
        acc += w;
        last = l;
        if (target < acc) break;
    }
    return last;
}

// Strategy (b)'s sample k at the lifted origin o (normal n, albedo ax): see the header.
vec3 light_sample(vec3 o, vec3 x, vec3 n, vec3 ax, uint k, uint seed, float total) {
    uint l = pick_light(owen_sobol1(k, seed ^ 0x85EBCA6Bu), total);
    vec2 u = owen_sobol2(k, seed ^ 0x7F4A7C15u);
    float z = 1.0 - 2.0 * u.x, r = sqrt(max(1.0 - z * z, 0.0)), phi = 2.0 * PI * u.y;
    vec3 lp = lights[l].position.xyz;
    uint tri;
    vec2 bary;
    if (bvh_closest_walk(lp, vec3(r * cos(phi), r * sin(phi), z), 1e30, tri, bary) <= 0.0) return vec3(0.0);
    Hit h = hit_at(tri, bary, x);
    vec3 w = h.y - o;
    float r2 = dot(w, w);
    if (r2 <= 0.0) return vec3(0.0);
    w *= inversesqrt(r2);
    float cos_x = dot(n, w), cos_y = abs(dot(h.ng, w));
    if (cos_x <= 0.0 || cos_y <= 0.0) return vec3(0.0);
    // x ↔ y, both ends off their surfaces (y lifted toward x), as the exact gather's shadow rays.
    vec3 y_up = lifted_origin(h.y, dot(h.ng, w) < 0.0 ? h.ng : -h.ng);
    if (bvh_occluded_lifted(o, y_up)) return vec3(0.0);
    float p_light;
    vec3 ld = light_side(h, l, 1.0 / total, p_light);
    return ax * ld * balance(cos_x / PI * cos_y / r2, p_light);
}

// Strategy (a)'s sample k: a cosine direction at o, its first hit, weighted by the balance heuristic
// under MIS.
vec3 cosine_sample(vec3 o, vec3 x, vec3 n, vec3 ax, uint k, uint seed, float total) {
    vec2 u = owen_sobol2(k, seed ^ 0x9E3779B9u);
    vec3 d = cosine_direction(n, u.x, u.y);
    uint tri;
    vec2 bary;
    if (bvh_closest_walk(o, d, 1e30, tri, bary) <= 0.0) return vec3(0.0);
    Hit h = hit_at(tri, bary, x);
    float p_light;
    vec3 ld = light_side(h, NO_LIGHT, total > 0.0 ? 1.0 / total : 0.0, p_light);
    vec3 w = h.y - o;
    float r2 = dot(w, w);
    float p_cos = r2 > 0.0 ? dot(n, d) / PI * abs(dot(h.ng, d)) / r2 : 0.0;
    return ax * ld * balance(p_cos, p_light);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 gp = texelFetch(g_position, px, 0);
    vec3 sum = vec3(0.0), sq = vec3(0.0);
    if (pc.accumulate != 0u) {
        sum = imageLoad(out_sum, px).rgb;
        sq = imageLoad(out_sq, px).rgb;
    }
    if (pc.add_direct != 0u) sum += texelFetch(direct_radiance, px, 0).rgb;
    if (gp.w != 0.0) {
        vec3 x = gp.xyz;
        vec3 n = texelFetch(g_normal, px, 0).xyz;
        vec3 ax = texelFetch(g_albedo, px, 0).rgb;
        vec3 o = lifted_origin(x, n);
        uint seed = pcg_hash(uint(px.x) + 65536u * uint(px.y)) ^ pc.seed ^ 0x2545F491u;
        float inv_n = 1.0 / float(pc.samples);
        float total = light_power();
        for (uint k = pc.first; k < pc.last; k++) {
            vec3 value = cosine_sample(o, x, n, ax, k, seed, total);
            if (total > 0.0) value += light_sample(o, x, n, ax, k, seed, total);
            // Added one sample at a time, in order k: the same sums whatever the dispatches.
            sum += value * inv_n;
            sq += value * value * inv_n;
        }
    }
    imageStore(out_sum, px, vec4(sum, 1.0));
    imageStore(out_sq, px, vec4(sq, 1.0));
}
