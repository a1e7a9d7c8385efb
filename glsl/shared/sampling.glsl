// The VPL sampling mixture of the CDF methods and the shadowed VPL contribution, shared by gather.comp,
// mis.comp and psm.comp. Include after cdf.glsl, vpl.glsl and voxel.glsl, with `pc` a GatherPush.
#ifndef BOUNCE_SAMPLING_GLSL
#define BOUNCE_SAMPLING_GLSL
#include "owen_sobol.glsl"


// Number of faces with weight in method section s (the faces FACE_UNIFORM chooses among).
uint live_faces(uint cb) {
    uint n = 0u;
    for (uint f = 0u; f < faces(); f++) {
        if (cdf_rows_total(cb, f * face_rows(), (f + 1u) * face_rows()) > 0.0) n++;
    }
    return n;
}

// Term t of the mixture's probability of drawing v: t = 0 is section 0 (every valid VPL, over all rows);
// t ≥ 1 is method section t, with its faces by Russian roulette (all rows) or uniformly among its faces
// with weight (v's face's rows, over their number). Exact: see cdf_prob_rows. One cdf_prob_rows call
// whatever t is: llvmpipe runs both sides of a branch, so two calls behind a branch cost two.
float term_prob(uint t, uint v) {
    uint cb = t * pc.cdf_len, fr = face_rows();
    bool per_face = t > 0u && pc.face_mode == FACE_UNIFORM;
    uint f = v / (fr * fr);
    uint r0 = per_face ? f * fr : 0u, r1 = per_face ? (f + 1u) * fr : faces() * fr;
    float p = cdf_prob_rows(cb, v, r0, r1);
    if (!per_face) return p;
    if (!(cdf_rows_total(cb, r0, r1) > 0.0)) return 0.0;
    return p / float(live_faces(cb));
}

// No term known to mixture_prob: it computes them all.
#define TERM_NONE 0xFFFFFFFFu

// draw_vpl's p_v of VPL v, given `live` method sections with weight and the effective defensive share eps:
//   p_v = ε · P_0(v) + (1 − ε)/live · Σ_{s live} P_s(v).
// Term `known` (TERM_NONE: none) is given as known_p, the bits term_prob(known, v) has: draw_vpl knows the
// term that drew v, and cdf_sample_rows3_prob gives its probability from the searches' own reads. The
// other terms are computed one per iteration of a loop, whose count is the same for every lane, so
// `uniform` (section 0 alone) computes none: a loop runs only while a lane needs it, where llvmpipe runs
// a branch's body under a mask whatever the lanes need. The method terms are summed in section order as
// before, the known one in its place, so p_v keeps its bits.
float mixture_prob(uint v, uint live, float eps, uint known, float known_p) {
    uint sections = pc.sections;
    float uniform_p = known_p, method = 0.0;
    bool known_summed = known == 0u || known > sections;
    uint others = known <= sections ? sections : sections + 1u;
    for (uint j = 0u; j < others; j++) {
        uint t = j < known ? j : j + 1u;
        if (!known_summed && t > known) {
            method += known_p;
            known_summed = true;
        }
        float p = term_prob(t, v);
        if (t == 0u) uniform_p = p;
        else if (cdf_total_at(t * pc.cdf_len) > 0.0) method += p;
    }
    if (!known_summed) method += known_p;
    return eps * uniform_p + (live > 0u ? (1.0 - eps) * method / float(live) : 0.0);
}

// draw_vpl's p_v of any VPL v: the probability that the sampling mixture draws it.
float source_prob(uint v) {
    uint live = 0u;
    for (uint s = 1u; s <= pc.sections; s++) live += cdf_total_at(s * pc.cdf_len) > 0.0 ? 1u : 0u;
    return mixture_prob(v, live, live == 0u ? 1.0 : pc.defensive, TERM_NONE, 0.0);
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
    // The term that draws (section 0, or method section s) and its rows. One cdf_sample_rows3_prob call
    // with the chosen term's arguments: llvmpipe runs both sides of a branch under masks (it leaves only a
    // loop that no lane needs), so a call on each side, and one per face mode, each paid their reads.
    uint cb = 0u, ib = 0u, known = 0u, r0 = 0u, r1 = faces() * face_rows(), nlive = 1u;
    vec3 ut = u;
    bool per_face = false, found = false;
    if (!(choice.x < eps)) {
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
        cb = s * len;
        ib = s * n;
        known = s;
        if (pc.face_mode == FACE_UNIFORM) {
            // The face uniformly among those with weight, then (row, texel) inside it.
            per_face = true;
            nlive = live_faces(cb);
            pick = min(uint(u.x * float(nlive)), nlive - 1u);
            uint f = 0u;
            for (uint j = 0u; j < faces(); j++) {
                if (cdf_rows_total(cb, j * face_rows(), (j + 1u) * face_rows()) > 0.0) {
                    if (pick == 0u) { f = j; found = true; break; } // term_prob's test for v's face
                    pick--;
                }
            }
            ut = u.yzx;
            r0 = f * face_rows();
            r1 = (f + 1u) * face_rows();
        }
    }
    float p;
    uint v = cdf_sample_rows3_prob(cb, ib, ut, r0, r1, p);
    float known_p = per_face ? (found ? p / float(nlive) : 0.0) : p; // term_prob(known, v)'s bits
    prob = mixture_prob(v, live, eps, known, known_p);
    return v;
}

#include "visibility.glsl"

// The shadowed contribution of VPL v (its data already fetched: ris's shade reads its flux too).
vec3 contribution_of(vec3 x, vec3 nx, vec3 ax, uint v, Vpl vpl) {
    vec3 c = vpl_unshadowed(x, nx, ax, vpl, pc.clamp_d2);
    if (c == vec3(0.0)) return c;
    return segment_open(x, nx, v, vpl) ? c : vec3(0.0);
}

vec3 contribution(vec3 x, vec3 nx, vec3 ax, uint v) {
    return contribution_of(x, nx, ax, v, vpl_fetch(v));
}

#endif
