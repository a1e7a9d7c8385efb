// The VPL sampling mixture of the CDF methods and the shadowed VPL contribution, shared by gather.comp,
// mis.comp and psm.comp. Include after cdf.glsl, vpl.glsl and voxel.glsl, with `pc` a GatherPush.
#ifndef BOUNCE_SAMPLING_GLSL
#define BOUNCE_SAMPLING_GLSL
#include "owen_sobol.glsl"

uint vpl_slots() { return lm_faces() * frame.size.z * frame.size.w * frame.size.w; }
uint face_rows() { return frame.size.w; }
uint faces() { return lm_faces() * frame.size.z; }

// Number of faces with weight in method section s (the faces FACE_UNIFORM chooses among).
uint live_faces(uint cb) {
    uint n = 0u;
    for (uint f = 0u; f < faces(); f++) {
        if (cdf_rows_total(cb, f * face_rows(), (f + 1u) * face_rows()) > 0.0) n++;
    }
    return n;
}

// Probability that method section s (CDF at cb) draws v, given its face choice (exact: see
// cdf_prob_rows).
float section_prob(uint cb, uint v, uint nlive) {
    uint all_rows = faces() * face_rows();
    if (pc.face_mode == FACE_RR) return cdf_prob_rows(cb, v, 0u, all_rows);
    uint f = v / (face_rows() * face_rows());
    if (!(cdf_rows_total(cb, f * face_rows(), (f + 1u) * face_rows()) > 0.0)) return 0.0;
    return cdf_prob_rows(cb, v, f * face_rows(), (f + 1u) * face_rows()) / float(nlive);
}

// The mixture probability of VPL v (draw_vpl's p_v), given `live` method sections with weight and the
// effective defensive share eps.
float mixture_prob(uint v, uint live, float eps) {
    uint len = pc.cdf_len;
    float method = 0.0;
    for (uint s = 1u; s <= pc.sections; s++) {
        uint cb = s * len;
        if (!(cdf_total_at(cb) > 0.0)) continue;
        method += section_prob(cb, v, pc.face_mode == FACE_UNIFORM ? live_faces(cb) : 0u);
    }
    float uniform_p = cdf_prob_rows(0u, v, 0u, faces() * face_rows());
    return eps * uniform_p + (live > 0u ? (1.0 - eps) * method / float(live) : 0.0);
}

// draw_vpl's p_v of any VPL v: the probability that the sampling mixture draws it.
float source_prob(uint v) {
    uint live = 0u;
    for (uint s = 1u; s <= pc.sections; s++) live += cdf_total_at(s * pc.cdf_len) > 0.0 ? 1u : 0u;
    return mixture_prob(v, live, live == 0u ? 1.0 : pc.defensive);
}

// The sampling mixture: with probability ε (or when no method section has weight) uniformly among the
// VPLs (section 0); otherwise a method section s chosen uniformly (local: the regions; else the one),
// whose face is chosen by its weight (Russian roulette, thesis alg. 9) or uniformly among the faces
// with weight, then the texel by the face's CDF. Returns v and its exact mixture probability
//   p_v = ε_eff · valid_v / #VPLs + (1 − ε_eff) · 1/S Σ_s P_s(v).
// Sample k of the stratified set `seed` (shared/owen_sobol.glsl): three padded sets, each uniform per
// sample (so p_v is its exact probability and the estimate stays unbiased) and stratified over the
// samples k of one seed: (defensive, section) together, so the ε share and the sections each get their
// proportion of the samples; (face, row), the two coarse levels of the inversion, together; the texel
// alone. (face, row, texel) are the same three uniforms in either branch.
uint draw_vpl(uint k, uint seed, out float prob) {
    uint len = pc.cdf_len;
    uint n = vpl_slots();
    uint sections = pc.sections;
    float eps = pc.defensive;
    uint live = 0u;
    for (uint s = 1u; s <= sections; s++) live += cdf_total_at(s * len) > 0.0 ? 1u : 0u;
    if (live == 0u) eps = 1.0; // all-zero importance: uniform (the host warns)
    vec2 choice = owen_sobol2(k, seed ^ 0x3C6EF372u);
    vec2 face_row = owen_sobol2(k, seed ^ 0xA54FF53Au);
    float texel = owen_sobol1(k, seed ^ 0x510E527Fu);
    vec3 u = vec3(face_row, texel);
    uint v;
    if (choice.x < eps) {
        v = cdf_sample_rows3(0u, 0u, u, 0u, faces() * face_rows());
    } else {
        // A section uniformly among those with weight (a local region whose gather points all missed
        // has none).
        uint pick = min(uint(choice.y * float(live)), live - 1u);
        uint s = 1u;
        for (uint j = 1u; j <= sections; j++) {
            if (cdf_total_at(j * len) > 0.0) {
                if (pick == 0u) { s = j; break; }
                pick--;
            }
        }
        uint cb = s * len;
        if (pc.face_mode == FACE_RR) {
            v = cdf_sample_rows3(cb, s * n, u, 0u, faces() * face_rows());
        } else {
            // The face uniformly among those with weight, then (row, texel) inside it.
            uint nlive = live_faces(cb);
            pick = min(uint(u.x * float(nlive)), nlive - 1u);
            uint f = 0u;
            for (uint j = 0u; j < faces(); j++) {
                if (cdf_rows_total(cb, j * face_rows(), (j + 1u) * face_rows()) > 0.0) {
                    if (pick == 0u) { f = j; break; }
                    pick--;
                }
            }
            v = cdf_sample_rows3(cb, s * n, u.yzx, f * face_rows(), (f + 1u) * face_rows());
        }
    }
    prob = mixture_prob(v, live, eps);
    return v;
}

// The shadowed contribution. Visibility: the voxel march (`--visibility voxel`), or with EXACT_VISIBILITY defined (the
// `*.exact.comp` variants, `--visibility exact`) a shadow ray against the real triangles (BVH) between
// points lifted off their surfaces (surface_lift in common.glsl): x along its normal, the VPL towards
// its light. Not the VPL along its normal: a VPL exactly on an edge of a closed box (a light at the
// box's centre puts texel rays exactly through its edges) lifted along one face's normal stays in the
// other face's plane, and its shadow rays left the box through that face (a sealed light leaked).
// Towards the light is always into the free space the light saw it from. With HYBRID_VISIBILITY (the
// `*.hybrid.comp` variants, `--visibility hybrid`) the same shadow ray, traced only through the grid's
// occupied cells (shared/hybrid.glsl): the same answer.
// contribution_of takes VPL v's data already fetched (ris's shade reads its flux too).
#if defined(EXACT_VISIBILITY) && !defined(HYBRID_VISIBILITY) && defined(END_BALLS_READ)
// With the end balls read (mis.exact), x's ball for contribution_of's shadow ray: the caller sets it per
// pixel; 0 (no ball) leaves the VPL's ball alone to shorten the ray.
vec4 contribution_x_ball = vec4(0.0);
#endif
#if defined(EXACT_VISIBILITY) || defined(HYBRID_VISIBILITY)
// The shadow ray's ends: x lifted along its normal, and VPL v lifted towards its light.
vec3 shadow_origin(vec3 x, vec3 nx) {
    return x + nx * surface_lift(x, frame.scene_min.w);
}
vec3 shadow_end(uint v, Vpl vpl) {
    vec3 light = lights[v / (lm_faces() * frame.size.w * frame.size.w)].position.xyz;
    return vpl.position + normalize(light - vpl.position) * surface_lift(vpl.position, frame.scene_min.w);
}
#endif

vec3 contribution_of(vec3 x, vec3 nx, vec3 ax, uint v, Vpl vpl) {
    vec3 c = vpl_unshadowed(x, nx, ax, vpl, pc.clamp_d2);
    if (c == vec3(0.0)) return c;
#if defined(EXACT_VISIBILITY) || defined(HYBRID_VISIBILITY)
#ifdef HYBRID_VISIBILITY
    return hybrid_occluded_lifted(shadow_origin(x, nx), shadow_end(v, vpl)) ? vec3(0.0) : c;
#else
#ifdef END_BALLS_READ
    // bvh_occluded_lifted's ray, walked only between its ends' balls (the same answer).
    vec3 o = shadow_origin(x, nx), e = shadow_end(v, vpl);
    vec2 w = end_ball_window(o, e, x, contribution_x_ball, v, vpl.position);
    return bvh_any_hit(o, e - o, w.x, w.y) ? vec3(0.0) : c;
#else
    return bvh_occluded_lifted(shadow_origin(x, nx), shadow_end(v, vpl)) ? vec3(0.0) : c;
#endif
#endif
#else
    return c * voxel_visibility(x, nx, vpl.position, vpl.normal);
#endif
}

vec3 contribution(vec3 x, vec3 nx, vec3 ax, uint v) {
    return contribution_of(x, nx, ax, v, vpl_fetch(v));
}

#endif
