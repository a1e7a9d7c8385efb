// The VPL sampling mixture of the CDF methods and the shadowed VPL contribution, shared by gather.comp,
// mis.comp and psm.comp. Include after cdf.glsl, vpl.glsl and voxel.glsl, with `pc` a GatherPush.
#ifndef BOUNCE_SAMPLING_GLSL
#define BOUNCE_SAMPLING_GLSL
#include "owen_sobol.glsl"
#include "regions.glsl"
#include "near_window.glsl"


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

// The method sections a draw at one pixel chooses among, with their probabilities (summing to 1): the
// first `count` entries, those with weight.
struct SectionMix {
    uvec4 section;
    vec4 weight;
    uint count;
};

// `local` at pixel px (thesis §7.3.3 samples every region's CDF at every pixel: one mixture for the whole
// screen, in which each region's CDF is a noisier copy of the global one). Here a pixel blends the CDFs of
// the (up to) four regions whose centres surround it, with bilinear weights: the mixture varies
// continuously over the screen (no seam at a region border, the thesis's reason for mixing them all) and a
// pixel draws from the CDFs built from gather points near it. Regions without weight (their gather points
// all missed) drop out and the rest are renormalised; a pixel with none left samples uniformly. A function
// of the pixel and the CDF totals only, so the draw's probability is exact.
SectionMix region_mixture(ivec2 px) {
    uint side = uint(round(sqrt(float(pc.sections))));
    uvec4 region;
    vec4 weight;
    region_weights(vec2(px), vec2(frame.size.xy), side, region, weight);
    uvec4 section = 1u + region;
    // The entries with weight first, so that the draws' loops run over those only (with 2 × 2 regions
    // three pixels in four have one or two).
    SectionMix m = SectionMix(uvec4(0u), vec4(0.0), 0u);
    float sum = 0.0;
    for (uint j = 0u; j < 4u; j++) {
        if (weight[j] > 0.0 && cdf_total_at(section[j] * pc.cdf_len) > 0.0) {
            m.section[m.count] = section[j];
            m.weight[m.count] = weight[j];
            m.count++;
            sum += weight[j];
        }
    }
    if (sum > 0.0) m.weight /= sum;
    return m;
}

// The mixture of the pixel being shaded: mix_by_pixel when draws blend the regions around it (`local`
// with a pixel; set by mixture_at_pixel, once per pixel, in gather.comp, mis.comp and ris_initial.comp
// without the pool), else every live
// method section alike (also for the sets psm.comp and ris's pool share over the screen).
bool mix_by_pixel = false;
SectionMix mix_pixel = SectionMix(uvec4(0u), vec4(0.0), 0u);

void mixture_at_pixel(ivec2 px) {
    mix_by_pixel = pc.sections > 1u;
    if (mix_by_pixel) mix_pixel = region_mixture(px);
}

// The mixture's entries: the pixel's (entry j: section mix_pixel.section[j], weight
// mix_pixel.weight[j]) or the method sections (entry j: section j + 1, weight 1 if it has any, summed
// and then divided by the number that do). Loop bounds, not branches: llvmpipe runs a branch's body
// under a mask whatever the lanes need, but a loop only while a lane needs it, so the methods that mix
// no regions pay nothing for `local`'s.
uint pixel_entries() { return mix_by_pixel ? mix_pixel.count : 0u; }
uint shared_entries() { return mix_by_pixel ? 0u : pc.sections; }
uint entry_section(uint j) { return mix_by_pixel ? mix_pixel.section[j & 3u] : j + 1u; }
float entry_weight(uint j) {
    if (mix_by_pixel) return mix_pixel.weight[j & 3u]; // & 3: a lane masked off may ask for TERM_NONE
    return cdf_total_at((j + 1u) * pc.cdf_len) > 0.0 ? 1.0 : 0.0;
}

// The number of method sections with weight (0 with a pixel's mixture, which weighs its own).
uint live_sections() {
    uint live = 0u;
    for (uint s = 1u; s <= shared_entries(); s++) live += cdf_total_at(s * pc.cdf_len) > 0.0 ? 1u : 0u;
    return live;
}

// Whether the mixture has no method entry with weight (then draws are uniform: ε = 1).
bool mixture_empty(uint live) {
    return mix_by_pixel ? mix_pixel.count == 0u : live == 0u;
}

// draw_vpl's p_v of VPL v, given `live` method sections with weight and the effective defensive share eps:
//   p_v = ε · P_0(v) + (1 − ε) Σ_j w_j P_{s_j}(v) / W,
// over the mixture's entries j (section s_j, weight w_j; W = 1 for a pixel's, the live sections' number
// otherwise). Term `known` (0: section 0, 1 + j: entry j, TERM_NONE: none) is given as known_p, the bits
// term_prob has for it: draw_vpl knows the term that drew v, and cdf_sample_rows3_prob gives its
// probability from the searches' own reads. The other terms are computed one per iteration of a loop,
// whose count is the same for every lane, so `uniform` (section 0 alone) computes none. The entries are
// summed in order, the known one in its place, so draw_vpl and source_prob agree bit for bit.
float mixture_prob(uint v, uint live, float eps, uint known, float known_p) {
    uint entries = pixel_entries() + shared_entries();
    float uniform_p = known_p, method = 0.0;
    bool known_summed = known == 0u || known > entries;
    uint others = known <= entries ? entries : entries + 1u;
    for (uint i = 0u; i < others; i++) {
        uint t = i < known ? i : i + 1u;
        if (!known_summed && t > known) {
            method += entry_weight(known - 1u) * known_p;
            known_summed = true;
        }
        float p = term_prob(t == 0u ? 0u : entry_section(t - 1u), v);
        if (t == 0u) uniform_p = p;
        else method += entry_weight(t - 1u) * p;
    }
    if (!known_summed) method += entry_weight(known - 1u) * known_p;
    bool any = mix_by_pixel || live > 0u;
    return eps * uniform_p + (any ? (1.0 - eps) * method / (mix_by_pixel ? 1.0 : float(live)) : 0.0);
}

// The near share of the pixel being shaded (set by near_at_pixel, once per pixel, in gather.comp; mis,
// psm and ris never set it): η = pc.near_share where one of x's near windows is open, else 0; then draws come with
// probability η from x's window (shared/near_window.glsl) and 1 − η from the mixture above:
//   p_v = η · p_near(v) + (1 − η) · p_mix(v),
// exact, so the estimate stays unbiased; p_near puts α / K² on each texel of a window (an empty texel
// is a draw that gives nothing). The pixel's VPLs next to x, which a screen-wide CDF cannot know, are
// then drawn about η · N / K² times as often as uniformly: a concave edge's fireflies.
float near_eta = 0.0;
Near near_px;

void near_at_pixel(vec3 x) {
    near_eta = 0.0;
    if (pc.near_share > 0.0) { // (the same for every lane)
        near_px = near_windows(x, pc.near_radius);
        near_eta = near_px.open ? pc.near_share : 0.0;
    }
}

// A loop bound, not a branch (see pixel_entries): 1 where the pixel draws from its window.
uint near_draws() { return near_eta > 0.0 ? 1u : 0u; }

// η · p_near(v): the near strategy's part of p_v.
float near_part(uint v) {
    float p = 0.0;
    for (uint i = 0u; i < near_draws(); i++) p = near_eta * near_prob(near_px, v);
    return p;
}

// draw_vpl's p_v of any VPL v: the probability that the sampling mixture draws it.
float source_prob(uint v) {
    uint live = live_sections();
    float mix = mixture_prob(v, live, mixture_empty(live) ? 1.0 : pc.defensive, TERM_NONE, 0.0);
    return near_part(v) + (1.0 - near_eta) * mix;
}

// The sampling mixture: with probability ε (or when no method section has weight) uniformly among the
// VPLs (section 0); otherwise a method section s: the one, or for `local` a region by the pixel's
// bilinear weights (region_mixture; without a pixel, the regions uniformly), whose face is chosen by its
// weight (Russian roulette, thesis alg. 9) or uniformly among the faces with weight, then the texel by
// the face's CDF. Returns v and its exact mixture probability (mixture_prob).
// Sample k of the stratified set `seed` (shared/owen_sobol.glsl): three padded sets, each uniform per
// sample (so p_v is its exact probability and the estimate stays unbiased) and stratified over the
// samples k of one seed: (defensive, section) together, so the ε share and the sections each get their
// proportion of the samples; (face, row), the two coarse levels of the inversion, together; the texel
// alone. (face, row, texel) are the same three uniforms in either branch.
uint draw_vpl(uint k, uint seed, out float prob) {
    uint len = pc.cdf_len;
    uint n = vpl_slots();
    uint live = live_sections();
    float eps = mixture_empty(live) ? 1.0 : pc.defensive; // all-zero importance: uniform (the host warns)
    vec2 choice = owen_sobol2(k, seed ^ 0x3C6EF372u);
    vec2 face_row = owen_sobol2(k, seed ^ 0xA54FF53Au);
    float texel = owen_sobol1(k, seed ^ 0x510E527Fu);
    vec3 u = vec3(face_row, texel);
    // The near share first: choice.x < η draws from x's window, the rest is rescaled to [0, 1).
    bool near_draw = choice.x < near_eta;
    choice.x = near_draw ? 0.0 : (choice.x - near_eta) / (1.0 - near_eta);
    // The term that draws (section 0, or method section s) and its rows. One cdf_sample_rows3_prob call
    // with the chosen term's arguments: llvmpipe runs both sides of a branch under masks (it leaves only a
    // loop that no lane needs), so a call on each side, and one per face mode, each paid their reads.
    uint cb = 0u, ib = 0u, known = 0u, r0 = 0u, r1 = faces() * face_rows(), nlive = 1u;
    vec3 ut = u;
    bool per_face = false, found = false;
    if (!(choice.x < eps)) {
        // A pixel's entry by its weight: the first whose running sum exceeds choice.y, else the last
        // (rounding).
        uint e = pixel_entries() > 0u ? pixel_entries() - 1u : 0u;
        float acc = 0.0;
        for (uint j = 0u; j < pixel_entries(); j++) {
            acc += mix_pixel.weight[j];
            if (choice.y < acc) { e = j; break; }
        }
        // Or a section uniformly among those with weight (a local region whose gather points all
        // missed has none).
        uint pick = min(uint(choice.y * float(live)), live - 1u);
        for (uint j = 0u; j < shared_entries(); j++) {
            if (cdf_total_at((j + 1u) * len) > 0.0) {
                if (pick == 0u) { e = j; break; }
                pick--;
            }
        }
        uint s = entry_section(e);
        cb = s * len;
        ib = s * n;
        known = 1u + e;
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
    for (uint i = 0u; i < near_draws(); i++) {
        if (near_draw) {
            // A texel of a window: the window by the texel's uniform, the texel by (face, row)'s.
            float p_near;
            ivec3 t = near_texel(near_px, u.z, u.xy, p_near);
            uint res = frame.size.w;
            v = (uint(t.z) * res + uint(t.y)) * res + uint(t.x);
            known = TERM_NONE;
        }
    }
    prob = near_part(v) + (1.0 - near_eta) * mixture_prob(v, live, eps, known, known_p);
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
