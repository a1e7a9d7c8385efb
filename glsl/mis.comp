#version 460
// mis: multiple importance sampling of two strategies for the VPL sum (thesis §7.4), balance heuristic:
//   gathering: n_g cosine-distributed rays from x (density q_g(ω) = cos θ_x / π per steradian); a ray's
//     first voxel hit, projected into each light's DPRSM, names a VPL v (see shared/gathering.glsl);
//   CDF: n_c VPLs drawn from the gbg CDF mixture (discrete probability P_v, see shared/sampling.glsl).
// One measure: a VPL drawn with probability P_v is, seen from x, a solid-angle density
//   q_c(v) = P_v · d² / (A_v · cos θ_v),   A_v = Δω_v · d_l² / cos α_v
// (A_v the area of its texel's surface patch, d_l the light–VPL distance, α_v the angle at the VPL
// between its normal and the light), i.e. P_v / Ω_v with Ω_v = A_v cos θ_v / d² the patch's solid angle
// from x; and gathering picks v with probability q_g · Ω_v. Balance heuristic weights
//   w_c = n_c q_c / (n_c q_c + n_g q_g),   w_g = n_g q_g / (n_c q_c + n_g q_g)   (w_c + w_g = 1 per v)
// and the estimate
//   L(x) = 1/n_c Σ_j w_c c(v_j) / P_{v_j} + 1/n_g Σ_k w_g c(v_k) / (q_g Ω_{v_k}),
// c(v) the shadowed VPL contribution (as in gather.comp). MIS_THESIS replaces the weights by the
// thesis's literal ones, p_g = cos θ sin θ / π (eq. 7.10) against p_c = P_v (eq. 7.11): densities of
// different measures, so they no longer add to 1 per v; kept to measure the difference.
// Push: GatherPush (first/last: items of this dispatch, the n_c CDF samples then the n_g rays; `mode`
// MIS_CONSISTENT or MIS_THESIS; `rays` n_g). Dispatch ⌈W/8⌉ × ⌈H/8⌉.
#include "shared/scene.glsl"
#include "shared/voxel.glsl"
#ifdef EXACT_VISIBILITY
#include "shared/bvh.glsl"
#endif

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(push_constant) uniform Push { GatherPush pc; };

layout(set = 0, binding = B_GATHER_GPOSITION) uniform sampler2D g_position;
layout(set = 0, binding = B_GATHER_GNORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = B_GATHER_GALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = B_VPL_POSITION) uniform sampler2DArray vpl_position;
layout(set = 0, binding = B_VPL_NORMAL) uniform sampler2DArray vpl_normal;
layout(set = 0, binding = B_VPL_FLUX) uniform sampler2DArray vpl_flux;
layout(std430, set = 0, binding = B_IMPORTANCE) readonly buffer Importance { float importance[]; };
layout(std430, set = 0, binding = B_CDF) readonly buffer Cdf { float cdf[]; };
layout(set = 0, binding = B_GATHER_DIRECT) uniform sampler2D direct_radiance;
layout(set = 0, binding = B_GATHER_OUT, rgba32f) uniform image2D out_radiance;

#include "shared/cdf.glsl"
#include "shared/vpl.glsl"
#include "shared/sampling.glsl"
#include "shared/gathering.glsl"

// Solid angle of VPL v's surface patch seen from x (0 when it faces away).
float patch_solid_angle(vec3 x, uint v, Vpl vpl) {
    uint res = frame.size.w;
    ivec3 t = ivec3(v % res, (v / res) % res, v / (res * res));
    vec4 nt = texelFetch(vpl_normal, t, 0);        // w: distance light–VPL
    float d_omega = texelFetch(vpl_flux, t, 0).w;   // Δω of the texel
    vec3 light = lights[uint(t.z) / 2u].position.xyz;
    float cos_a = dot(vpl.normal, normalize(light - vpl.position));
    vec3 w = vpl.position - x;
    float d2 = dot(w, w);
    float cos_v = -dot(vpl.normal, w * inversesqrt(max(d2, 1e-30)));
    if (cos_a <= 0.0 || cos_v <= 0.0 || d2 <= 0.0) return 0.0;
    float area = d_omega * nt.w * nt.w / cos_a;
    return area * cos_v / d2;
}

// Gathering cannot find VPLs closer than this: its rays start 2 cells off the surface and the first hit
// is known to a cell. Its density there is 0, so the CDF strategy must carry those VPLs alone (weight 1);
// giving gathering a share it can never sample would bias the sum low (by 11% in the Cornell box).
bool gathering_reaches(vec3 x, Vpl vpl) {
    return distance(x, vpl.position) > 4.0 * frame.voxel_origin.w;
}

// Balance-heuristic weight of the CDF strategy for v (the gathering weight is 1 − this in the consistent
// mode), and the gathering density at v's direction.
float weight_cdf(vec3 x, vec3 nx, uint v, Vpl vpl, float p_v, out float q_g, out float omega) {
    vec3 w = normalize(vpl.position - x);
    float cos_x = max(dot(nx, w), 0.0);
    q_g = gathering_reaches(x, vpl) ? cos_x / PI : 0.0;
    omega = patch_solid_angle(x, v, vpl);
    float n_c = float(pc.samples), n_g = float(max(pc.rays, 1u));
    if (pc.mode == MIS_THESIS) {
        float sin_x = sqrt(max(1.0 - cos_x * cos_x, 0.0));
        float p_g = gathering_reaches(x, vpl) ? cos_x * sin_x / PI : 0.0;
        return p_v / (p_v + p_g);
    }
    float q_c = omega > 0.0 ? p_v / omega : 1e30;
    return n_c * q_c / (n_c * q_c + n_g * q_g);
}

float weight_gathering(vec3 x, vec3 nx, uint v, Vpl vpl, float p_v, float q_g) {
    if (!gathering_reaches(x, vpl)) return 0.0;
    if (pc.mode == MIS_THESIS) {
        vec3 w = normalize(vpl.position - x);
        float cos_x = max(dot(nx, w), 0.0);
        float p_g = cos_x * sqrt(max(1.0 - cos_x * cos_x, 0.0)) / PI;
        return p_g / (p_v + p_g);
    }
    float omega = patch_solid_angle(x, v, vpl);
    float q_c = omega > 0.0 ? p_v / omega : 1e30;
    float n_c = float(pc.samples), n_g = float(max(pc.rays, 1u));
    return n_g * q_g / (n_c * q_c + n_g * q_g);
}

// The exact mixture probability of v under the CDF strategy (the same as draw_vpl's).
float cdf_strategy_prob(uint v) {
    uint len = pc.cdf_len;
    uint live = 0u;
    float method = 0.0;
    for (uint s = 1u; s <= pc.sections; s++) {
        uint cb = s * len;
        if (!(cdf_total_at(cb) > 0.0)) continue;
        live++;
        method += section_prob(cb, v, pc.face_mode == FACE_UNIFORM ? live_faces(cb) : 0u);
    }
    float eps = live == 0u ? 1.0 : pc.defensive;
    float uniform_p = cdf_prob_rows(0u, v, 0u, faces() * face_rows());
    return eps * uniform_p + (live > 0u ? (1.0 - eps) * method / float(live) : 0.0);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 gp = texelFetch(g_position, px, 0);
    vec3 sum = vec3(0.0);
    if (gp.w != 0.0 && cdf_total_at(0u) > 0.0) {
        vec3 x = gp.xyz;
        vec3 nx = texelFetch(g_normal, px, 0).xyz;
        vec3 ax = texelFetch(g_albedo, px, 0).rgb;
        uint base = pcg_hash(uint(px.x) + 65536u * uint(px.y)) ^ pc.seed;
        uint n_c = pc.samples, n_g = max(pc.rays, 1u);
        // Items [first, last) of n_c CDF samples followed by n_g gathering rays (so dispatches split
        // both under the loop iteration limit).
        for (uint k = pc.first; k < pc.last; k++) {
            if (k < n_c) {
                uint rng = pcg_hash(base ^ pcg_hash(k + 0x9E3779B9u));
                float p_v;
                uint v = draw_vpl(rng, p_v);
                if (!(p_v > 0.0)) continue;
                vec3 c = contribution(x, nx, ax, v);
                if (c == vec3(0.0)) continue;
                float q_g, omega;
                float w = weight_cdf(x, nx, v, vpl_fetch(v), p_v, q_g, omega);
                sum += w * c / p_v / float(n_c);
            } else {
                uint rng = pcg_hash(base ^ pcg_hash(k - n_c + 0x7F4A7C15u) ^ 0x68E31DA4u);
                vec3 d = cosine_direction(nx, rand01(rng), rand01(rng));
#ifdef EXACT_VISIBILITY
                // Exact gathering: the ray's first hit on the real triangles, then each light's VPL there.
                uint hit_tri;
                vec2 hit_bary;
                float lift = surface_lift(x, frame.scene_min.w);
                float th = bvh_closest(x + nx * lift, d, 1e30, hit_tri, hit_bary);
                vec3 hit_p = x + nx * lift + d * th;
#endif
                for (uint l = 0u; l < frame.size.z; l++) {
#ifdef EXACT_VISIBILITY
                    uint v = th > 0.0 ? vpl_at_point(hit_p, l) : NO_VPL;
#else
                    uint v = gathering_vpl(x, nx, d, l);
#endif
                    if (v == NO_VPL) continue;
                    Vpl vpl = vpl_fetch(v);
                    vec3 c = contribution(x, nx, ax, v);
                    if (c == vec3(0.0)) continue;
                    float q_g = max(dot(nx, normalize(vpl.position - x)), 0.0) / PI;
                    float omega = patch_solid_angle(x, v, vpl);
                    if (!(q_g > 0.0) || !(omega > 0.0)) continue;
                    float w = weight_gathering(x, nx, v, vpl, cdf_strategy_prob(v), q_g);
                    sum += w * c / (q_g * omega) / float(n_g);
                }
            }
        }
    }
    if (pc.add_direct != 0u) sum += texelFetch(direct_radiance, px, 0).rgb;
    if (pc.accumulate != 0u) sum += imageLoad(out_radiance, px).rgb;
    imageStore(out_radiance, px, vec4(sum, 1.0));
}
