#version 460
// mis: multiple importance sampling of two strategies for the VPL sum Σ_v c(v) (thesis §7.4), balance
// heuristic, both strategies' densities in one measure, and unbiased with respect to `all`.
//
// The one measure. A VPL v stands for a patch of surface: give it Q_v, its texel's footprint on its
// tangent plane (patch_of: a parallelogram around it, of area A_v ≈ Δω_v · d_l² / cos α_v, d_l the
// light–VPL distance, α_v the angle at the VPL). At pixel x only its part in front of x's tangent plane
// counts: Q_v⁺ = Q_v ∩ {y : (y − x)·n_x > 0}, of area A_v⁺ (front_part). Then, exactly,
//   Σ_v c(v) = Σ_v ∫_{Q_v⁺} F(v, y) dA(y),   F(v, y) = c(v) / A_v⁺,
// an integral over pairs (VPL, point of its patch) in area measure, which both strategies sample:
//   CDF: v from the gbg CDF mixture (probability P_v, shared/sampling.glsl), y uniform in Q_v⁺:
//        p_c(v, y) = P_v / A_v⁺   (at x, in solid angle: P_v · |y−x|² / (A_v⁺ · cos θ_y), the form the estimator is written in);
//   gathering: a cosine-distributed direction ω from x (cos θ_x / π per steradian); the ray's first hit
//        (voxel march, or the BVH with EXACT_VISIBILITY), projected into light l's DPRSM and refined
//        (gathering_texel), names a texel v = T_l(ω); y is where the ray from x meets v's tangent
//        plane, and the pair counts if y ∈ Q_v (then y ∈ Q_v⁺: the ray leaves x forwards):
//        p_g(v, y) = [T_l(ω_y) = v] · cos θ_x / π · |cos θ_y| / |y−x|²,   ω_y the direction x → y.
// p_g is exact, not a model: for a CDF sample the indicator is evaluated by running the same T_l on ω_y
// (one more march or BVH ray). So VPLs the gathering rays cannot reach (too close to x, behind the
// ray's 2-cell start, hidden behind a nearer surface) get p_g = 0 and are carried by the CDF alone.
// Why Q_v⁺ and the footprint (patch_of): a pair no gathering ray can make has weight 1 on the CDF side,
// c / (n_c P_v), and where gbg's CDF rates a VPL near x low that is a firefly. With the whole patch, a
// VPL next to a junction (a floor texel beside the wall x is on) had half its patch behind x's plane.
// Balance heuristic, n_c CDF samples and n_g rays, every sample of either strategy adds
//   F / (n_c p_c + n_g p_g) = c(v) / (n_c P_v + n_g A_v⁺ p_g(v, y)),
// an unbiased estimate of Σ_v c(v) (P_v > 0 for every VPL through the defensive share; F = 0 outside Q_v⁺).
// c(v) is the shadowed VPL contribution of gather.comp (visibility from x to the VPL itself).
//
// MIS_THESIS replaces the weights by the thesis's literal ones, p_g = cos θ sin θ / π (eq. 7.10) against
// p_c = P_v (eq. 7.11): densities of different measures, so they no longer add to 1 per sample;
// kept to measure the difference (each strategy then adds w_s · F / (n_s p_s)).
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
layout(set = 0, binding = B_CDF) uniform usamplerBuffer cdf_texels;
layout(set = 0, binding = B_GATHER_DIRECT) uniform sampler2D direct_radiance;
layout(set = 0, binding = B_GATHER_OUT, rgba32f) uniform image2D out_radiance;

#ifdef EXACT_VISIBILITY
// The shadow rays of contribution() skip their ends' empty balls (pc.end_balls; passes/end_balls.rs):
// the same answers.
#define END_BALLS_READ
#include "shared/end_balls.glsl"
#endif
#define CDF_SHAPE_FROM_FRAME
#include "shared/cdf.glsl"
#include "shared/vpl.glsl"
#include "shared/sampling.glsl"
#include "shared/gathering.glsl"
#include "shared/patch.glsl"

#ifdef PSM_VISIBILITY
// `--visibility psm` (mis.psm.comp): the n_c CDF samples are the frame's shared set (psm.comp: draws
// from the same mixture P_v, shared by all pixels) and see through their shadow maps; the gathering
// samples are per pixel and keep the voxel march. The estimate is then unbiased for the VPL sum with the
// blended visibility w_c·V_psm + w_g·V_voxel (both approximate the true one within their bias bands).
layout(std430, set = 0, binding = B_PSM_VIEWS) readonly buffer PsmViews { PsmView psm_views[]; };
#define PSM_LOOKUP
layout(set = 0, binding = B_PSM_DEPTH) uniform sampler2DArray psm_depth;
#include "shared/psm.glsl"
#endif

// Where the ray from o along d meets the plane through c with normal n (parameter t > 0), or false.
bool ray_plane(vec3 o, vec3 d, vec3 c, vec3 n, out vec3 p) {
    float t = dot(c - o, n) / dot(d, n);
    p = o + d * t;
    return t > 0.0 && !isinf(t) && !isnan(t);
}

// Q_v (shared/patch.glsl): the texel's footprint on the VPL's tangent plane, the parallelogram whose edges
// are where the light's rays through the texel's edge midpoints meet that plane.
Patch patch_of(uint v, Vpl vpl) {
    uint res = frame.size.w;
    ivec3 t = ivec3(v % res, (v / res) % res, v / (res * res));
    float d_l = texelFetch(vpl_normal, t, 0).w;
    float d_omega = texelFetch(vpl_flux, t, 0).w;
    uint l = uint(t.z) / lm_faces(), face = uint(t.z) % lm_faces();
    vec3 light = lights[l].position.xyz;
    Patch q;
    q.c = vpl.position;
    q.n = vpl.normal;
    // Any positive area keeps the estimator exact. The footprint makes T_l(ω_y) = v for nearly every y
    // in Q_v, so a CDF sample of a VPL near x is also covered by the gathering density (a square of the
    // same area, turned at random against the texel, left up to half of it to neighbouring texels: a
    // VPL 0.4 % of Conference's extent from x then got weight 1 at 0.16× the uniform probability, a
    // firefly of 380× the pixel). The area is capped where the old square's was (cos α ≥ 0.05), so a
    // grazing VPL's patch cannot grow without bound.
    float a_max = d_omega * d_l * d_l / 0.05;
    vec2 uv = (vec2(t.xy) + 0.5) / float(res) * 2.0 - 1.0;
    float h = 1.0 / float(res); // half a texel in map coordinates
    vec3 X, Y, Z;
    lm_axes(l, face, X, Y, Z);
    mat3 to_world = mat3(X, Y, Z);
    vec3 p0, p1, p2, p3;
    bool ok = ray_plane(light, to_world * lm_direction(uv + vec2(h, 0.0)), q.c, q.n, p0)
           && ray_plane(light, to_world * lm_direction(uv - vec2(h, 0.0)), q.c, q.n, p1)
           && ray_plane(light, to_world * lm_direction(uv + vec2(0.0, h)), q.c, q.n, p2)
           && ray_plane(light, to_world * lm_direction(uv - vec2(0.0, h)), q.c, q.n, p3);
    q.e1 = p0 - p1;
    q.e2 = p2 - p3;
    q.area = length(cross(q.e1, q.e2));
    if (!ok || !(q.area > 1e-30) || isinf(q.area)) {
        // No footprint (a texel edge's ray misses the plane): the square of the texel's area.
        vec3 t1, t2;
        tangent_basis(q.n, t1, t2);
        float cos_a = max(abs(dot(vpl.normal, normalize(light - vpl.position))), 0.05);
        float side = sqrt(max(d_omega * d_l * d_l / cos_a, 1e-30));
        q.e1 = t1 * side;
        q.e2 = t2 * side;
        q.area = side * side;
    } else if (q.area > a_max) {
        float s = sqrt(a_max / q.area);
        q.e1 *= s;
        q.e2 *= s;
        q.area = a_max;
    } else {
        // Centred where the ray through the texel's centre meets the plane, not on the VPL, which lies at
        // a random point of its texel (dprsm.rs): so Q_v is the texel's footprint, the set where
        // T_l(ω_y) = v, wherever the VPL sits in it. (Centred on the VPL it reached into the neighbours'
        // footprints, where p_g is 0: the second suite's mis relMSE over uniform's 0.52 against 0.15.)
        // The capped and the fallback patches stay on the VPL.
        vec3 centre;
        if (ray_plane(light, to_world * lm_direction(uv), vpl.position, q.n, centre)) q.c = centre;
    }
    return q;
}

// The first hit of the gathering ray from x along unit d: voxel march, or the BVH.
bool gathering_first_hit(vec3 x, vec3 nx, vec3 d, out vec3 hit) {
#ifdef EXACT_VISIBILITY
    uint tri;
    vec2 bary;
    vec3 o = lifted_origin(x, nx);
    float th = bvh_closest(o, d, 1e30, tri, bary);
    hit = o + d * max(th, 0.0);
    return th > 0.0;
#else
    return gathering_hit(x, nx, d, hit);
#endif
}


// T_l(ω): the texel of light l that the gathering ray from x along unit d names, or NO_VPL; the one
// map both strategies evaluate, so p_g is the density the rays really have. The first hit's texel,
// then twice the texel of the point where the ray meets the current texel's plane: a voxel hit is a
// cell's entry point, up to a cell before the surface, and seen from the light that is often the
// neighbouring texel, whose patch the ray then misses. Any fixed map keeps the estimate exact; this
// one makes y ∈ Q_v likely, so gathering samples are not wasted.
uint gathering_texel(vec3 x, vec3 nx, vec3 d, uint l, vec3 hit) {
    uint v = texel_at_point(hit, l);
    for (int i = 0; i < 2 && v != NO_VPL; i++) {
        Vpl vpl = vpl_fetch(v);
        vec3 y;
        if (!ray_plane(x, d, vpl.position, vpl.normal, y)) break;
        uint next = texel_at_point(y, l);
        if (next == NO_VPL) break;
        v = next;
    }
    return v;
}

// A · p_g(v, y) for y on Q_v (already known to lie in it), given T_l(ω_y) = v holds or not.
float area_times_gathering_density(vec3 x, vec3 nx, Patch q, float area, vec3 y) {
    vec3 w = y - x;
    float d2 = dot(w, w);
    if (!(d2 > 0.0)) return 0.0;
    w *= inversesqrt(d2);
    float cos_x = dot(nx, w);
    if (cos_x <= 0.0) return 0.0;
    return area * cos_x / PI * abs(dot(q.n, w)) / d2;
}

// The thesis's gathering "density" (eq. 7.10) in the direction of VPL v.
float thesis_p_g(vec3 x, vec3 nx, Vpl vpl) {
    float cos_x = max(dot(nx, normalize(vpl.position - x)), 0.0);
    return cos_x * sqrt(max(1.0 - cos_x * cos_x, 0.0)) / PI;
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
#ifdef END_BALLS_READ
        contribution_x_ball = end_ball_of_pixel(px);
#endif
        // Stratified per pixel (shared/owen_sobol.glsl): CDF sample k is point k of draw_vpl's sets and
        // of the patch set, gathering ray j point j of the ray set; the pixel's seed decorrelates
        // neighbours, and progressive frames (seed, seed + 1, …) are independent scrambles.
        uint seed = pcg_hash(uint(px.x) + 65536u * uint(px.y)) ^ pc.seed;
        mixture_at_pixel(px); // `local`: the regions around px (shared/sampling.glsl)
        float n_c = float(pc.samples), n_g = float(max(pc.rays, 1u));
        bool thesis = pc.mode == MIS_THESIS;
        // Items [first, last) of n_c CDF samples followed by n_g gathering rays (so dispatches split
        // both under the loop iteration limit).
        for (uint k = pc.first; k < pc.last; k++) {
            if (k < pc.samples) {
#ifdef PSM_VISIBILITY
                PsmView sv = psm_views[k];
                float p_v = sv.normal_p.w;
                if (!(p_v > 0.0)) continue;
                uint v = floatBitsToUint(sv.position_v.w);
                vec3 c = vpl_unshadowed(x, nx, ax, vpl_fetch(v), pc.clamp_d2) * psm_visible(k, x, nx);
#else
                float p_v;
                uint v = draw_vpl(k, seed, p_v);
                if (!(p_v > 0.0)) continue;
                vec3 c = contribution(x, nx, ax, v);
#endif
                if (c == vec3(0.0)) continue;
                Vpl vpl = vpl_fetch(v);
                if (thesis) {
                    float p_g = thesis_p_g(x, nx, vpl);
                    sum += p_v / (p_v + p_g) * c / (n_c * p_v);
                    continue;
                }
                Patch q = patch_of(v, vpl);
                // y uniform in Q_v⁺(x): F = c / A_v⁺ there, p_c = P_v / A_v⁺ (c > 0 puts v in front of x,
                // so A_v⁺ > 0).
                FrontPart f = front_part(q, x, nx);
                if (!(f.frac > 0.0)) {
                    sum += c / (n_c * p_v); // rounding only: then no gathering ray names v from x either
                    continue;
                }
                vec2 ab = front_point(f, owen_sobol2(k, seed ^ 0x9B05688Cu));
                vec3 y = q.c + ab.x * q.e1 + ab.y * q.e2;
                float ap_g = area_times_gathering_density(x, nx, q, f.frac * q.area, y);
                if (ap_g > 0.0) {
                    vec3 hit, d = normalize(y - x);
                    uint light = v / (lm_faces() * frame.size.w * frame.size.w);
                    bool reached = gathering_first_hit(x, nx, d, hit) && gathering_texel(x, nx, d, light, hit) == v;
                    if (!reached) ap_g = 0.0;
                }
                sum += c / (n_c * p_v + n_g * ap_g);
            } else {
                vec2 ud = owen_sobol2(k - pc.samples, seed ^ 0x1F83D9ABu);
                vec3 d = cosine_direction(nx, ud.x, ud.y);
                vec3 hit;
                if (!gathering_first_hit(x, nx, d, hit)) continue;
                // One ray, one pair (v, y) per light.
                for (uint l = 0u; l < frame.size.z; l++) {
                    uint v = gathering_texel(x, nx, d, l, hit);
                    if (v == NO_VPL) continue;
                    Vpl vpl = vpl_fetch(v);
                    Patch q = patch_of(v, vpl);
                    vec3 y;
                    if (!ray_plane(x, d, q.c, q.n, y)) continue;
                    vec2 ab = patch_coords(q, y);
                    if (!all(lessThanEqual(abs(ab), vec2(0.5)))) continue;
                    vec3 c = contribution(x, nx, ax, v);
                    if (c == vec3(0.0)) continue;
                    float ap_g = area_times_gathering_density(x, nx, q, front_part(q, x, nx).frac * q.area, y);
                    if (!(ap_g > 0.0)) continue;
                    float p_v = source_prob(v);
                    if (thesis) {
                        float p_g = thesis_p_g(x, nx, vpl);
                        sum += p_g / (p_v + p_g) * c / (n_g * ap_g);
                    } else {
                        sum += c / (n_c * p_v + n_g * ap_g);
                    }
                }
            }
        }
    }
    if (pc.add_direct != 0u) sum += texelFetch(direct_radiance, px, 0).rgb;
    if (pc.accumulate != 0u) sum += imageLoad(out_radiance, px).rgb;
    imageStore(out_radiance, px, vec4(sum, 1.0));
}
