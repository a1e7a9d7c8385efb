#version 460
// ris: resampled importance sampling over the VPLs (Talbot et al. 2005), with spatial and temporal reuse
// (Bitterli et al. 2020; generalized RIS, Lin et al. 2022). crates/graph/src/passes/ris.rs states the
// estimator and why it is unbiased. The target is the unshadowed contribution's luminance at the pixel,
//   p̂_x(v) = luminance(albedo(x)/π · Φ_v · (cos θ_v / π) · cos θ_x · k(d²)) (k: the VPL kernel, shared/vpl.glsl),
// the source is the gather's mixture (draw_vpl, its exact probability p_v). Stages (one variant each):
// RIS_INITIAL (dispatch W × H × R / K): candidate set s streams candidates [first, last) of its M: v ~ p,
//   w = p̂(v)/p_v, v kept with probability w / Σw, independently by each of its K = RIS_PICKS picks
//   (layers s·K + j); after the M-th, each pick's W = Σw / (M p̂(y_j)), then (RIS_HISTORY) combined with
//   last frame's reservoir at the same pixel and layer.
// RIS_PRESAMPLE (RIS_POOL_TILE × T, --pool-tiles T > 0; RIS_UNIFORM_SOURCE: the uniform source's shortcut): the
//   candidate pool, T tiles of RIS_POOL_TILE VPLs; tile
//   j's entries are points 0 .. RIS_POOL_TILE − 1 of one stratified set of the source (draw_vpl, seeded by j
//   and the frame), stored with their data and p_v, so a candidate costs three texel fetches and its target.
// RIS_INITIAL with RIS_POOL: reservoir r's candidates are consecutive entries of one tile, from a start, both
//   chosen by a hash of (pixel, layer, frame); each is a draw of the source (its marginal law is p: ris.rs).
// RIS_NEAR (with RIS_POOL; ris.near_candidates > 0): the last ris.near_candidates of the M candidates come
//   from (2r + 1)² windows of light-map texels around where x projects into each light's map (a window
//   picked by its light's radiosity at x, then a texel uniformly; RIS_NEAR_MULTI: every light's): the VPLs next to x, whose kernel makes the target's tail and
//   which the pool almost never holds. Every candidate, of either strategy, is weighed with the balance
//   mixture q(v) = (M_pool p_source(v) + M_near p_near(v)) / M (multiple-importance RIS): unbiased, since
//   the pool's strategy reaches every VPL (ris.rs).
// RIS_SPATIAL (W × H × R): the reservoir combined with k neighbours' of the same layer, generalized
//   balance weights m_i(y) = c_i p̂_i(y) / Σ_j c_j p̂_j(y).
// RIS_SHADE (W × H): L = 1/R Σ_r f(y_r) V(y_r) W_r over the reservoirs [first, last), visibility as the
//   gather's (voxel, EXACT_VISIBILITY); with ris.control each term adds the
//   unshadowed control variate β (U_g − g(y_r) W_r), mean 0 given the reservoir's candidates (ris.rs).
#include "shared/scene.glsl"
#include "shared/voxel.glsl"
#ifdef EXACT_VISIBILITY
#include "shared/bvh.glsl"
#endif

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(push_constant) uniform Push {
    GatherPush pc;
    RisPush ris;
};

layout(set = 0, binding = B_GATHER_GPOSITION) uniform sampler2D g_position;
layout(set = 0, binding = B_GATHER_GNORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = B_GATHER_GALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = B_VPL_POSITION) uniform sampler2DArray vpl_position;
layout(set = 0, binding = B_VPL_NORMAL) uniform sampler2DArray vpl_normal;
layout(set = 0, binding = B_VPL_FLUX) uniform sampler2DArray vpl_flux;
layout(std430, set = 0, binding = B_IMPORTANCE) readonly buffer Importance { float importance[]; };
layout(set = 0, binding = B_CDF) uniform usamplerBuffer cdf_texels;
#ifdef RIS_SHADE
layout(set = 0, binding = B_GATHER_DIRECT) uniform sampler2D direct_radiance;
layout(set = 0, binding = B_GATHER_OUT, rgba32f) uniform image2D out_radiance;
layout(std430, set = 0, binding = B_RIS_IN) readonly buffer RisIn { Reservoir res_in[]; };
layout(std430, set = 0, binding = B_RIS_VIS) buffer RisVis { uint vis_counts[]; };
layout(std430, set = 0, binding = B_RIS_UNSHADOWED) readonly buffer RisUnshadowed { vec4 unshadowed[]; };
layout(std430, set = 0, binding = B_RIS_CV) buffer RisCv { uvec4 cv_counts[]; };
#else
#ifdef RIS_SPATIAL
layout(std430, set = 0, binding = B_RIS_IN) readonly buffer RisIn { Reservoir res_in[]; };
#endif
layout(std430, set = 0, binding = B_RIS_OUT) buffer RisOut { Reservoir res_out[]; };
#ifdef RIS_INITIAL
// K: picks per reservoir (RisPush::picks selects the pipeline specialised to it).
layout(constant_id = SPEC_RIS_PICKS) const uint RIS_PICKS = 1u;
layout(std430, set = 0, binding = B_RIS_HISTORY) readonly buffer RisHistory { Reservoir res_history[]; };
// The control variate's state (add_candidate): xyz the candidates' estimate U_g of the reservoir (while
// streaming, its sum before the albedo and 1/M), w the kept VPL's ratio s / (p̂ / luminance(f)).
layout(std430, set = 0, binding = B_RIS_UNSHADOWED) buffer RisUnshadowed { vec4 unshadowed[]; };
#endif
#ifdef RIS_POOL
layout(set = 0, binding = B_RIS_POOL) uniform usamplerBuffer pool_texels;
#endif
#ifdef RIS_LEARNED
// Read through the counts' texel view (a texel fetch gathers a vector's lanes at once).
layout(set = 0, binding = B_RIS_VIS) uniform usamplerBuffer vis_texels;
#endif
#ifdef RIS_PRESAMPLE
// Entry e: texels 3e (position, v), 3e + 1 (normal, p_v; 0: no draw), 3e + 2 (flux, the VPL's patch area
// A_v; 0 for an empty texel).
layout(std430, set = 0, binding = B_RIS_POOL) writeonly buffer RisPool { vec4 pool_out[]; };
#endif
#endif

#define CDF_SHAPE_FROM_FRAME
#include "shared/cdf.glsl"
#include "shared/vpl.glsl"
#include "shared/sampling.glsl"
#if defined(RIS_SHADE) && defined(EXACT_VISIBILITY)
// The shade's shadow rays from a queue (shared/shadow_queue.glsl): a block's rays are queued first, traced,
// and then the block's reservoirs are shaded in order with their answers.
#define SHADE_QUEUE
// The queue's rays skip their ends' empty balls (pc.end_balls; passes/end_balls.rs): the same answers.
#define SHADOW_QUEUE_WINDOWS
#define END_BALLS_READ
#include "shared/end_balls.glsl"
#include "shared/shadow_queue.glsl"
#endif

// Where reservoir `layer` of pixel q lives (layer-major: one layer is one image of reservoirs).
uint res_index(ivec2 q, uint layer) {
    return layer * frame.size.x * frame.size.y + uint(q.y) * frame.size.x + uint(q.x);
}

// A uniform in [0, 1) that depends on (pixel, frame seed, stream, index) only: reservoir choices, apart
// from the candidates' own stratified numbers.
float ris_rand(ivec2 q, uint stream, uint i) {
    uint h = pcg_hash(uint(q.x) + 65536u * uint(q.y)) ^ pcg_hash(pc.seed ^ 0x2545F491u);
    h = pcg_hash(h ^ pcg_hash(stream * 0x9E3779B9u + i));
    return float(h >> 8) * (1.0 / 16777216.0);
}

// The target p̂ of pixel geometry (x, n, a) for VPL v: the unshadowed contribution's luminance (a target
// may be anything positive wherever the integrand is; the shade tests the frame's real visibility).
// Deterministic per pixel, so the spatial weights evaluate the same p̂ at each neighbour.
// Split as p̂ = luminance(a ⊙ Φ_v) · target_geometry: the candidates' loop needs the geometric factor for
// the control variate's U_g too.
float target_geometry(vec3 x, vec3 n, Vpl vpl) {
    return vpl_unshadowed_geometry(x, n, vpl, pc.clamp_d2);
}

float target_of(vec3 x, vec3 n, vec3 a, Vpl vpl) {
    return dot(vpl_luminance_albedo(a), vpl.flux) * target_geometry(x, n, vpl);
}

float target_at(vec3 x, vec3 n, vec3 a, uint v) {
    return target_of(x, n, a, vpl_fetch(v));
}

// The learned visibility's counts for pixel q and VPL v: (visible, traced) at vis_counts[i], [i + 1] with
// i = vis_tile_base(q) + 2 · vis_cell_of(v), for q's screen tile (vis_tile pixels per side) and v's
// light-map cell (vis_cell texels per side). Split so a loop over candidates divides only once per pixel
// for the tile (llvmpipe divides integers lane by lane); only the learned variant computes cells.
uint vis_side() {
    return (frame.size.w + ris.vis_cell - 1u) / ris.vis_cell;
}

// The cell of texel (tx, ty) of light-map layer `layer`.
uint vis_cell_at(uint layer, uint tx, uint ty) {
    uint side = vis_side();
    return (layer * side + udiv(ty, ris.vis_cell)) * side + udiv(tx, ris.vis_cell);
}

// The quotients (a layer, a row) are far below 2^21, so udiv is exact.
uint vis_cell_of(uint v) {
    uint res = frame.size.w, face = res * res;
    uint layer = udiv(v, face), r = v - layer * face, ty = udiv(r, res);
    return vis_cell_at(layer, r - ty * res, ty);
}

uint vis_tile_base(ivec2 q) {
    uint tiles_x = (frame.size.x + ris.vis_tile - 1u) / ris.vis_tile;
    uint tile = (uint(q.y) / ris.vis_tile) * tiles_x + uint(q.x) / ris.vis_tile;
    uint side = vis_side();
    return 2u * tile * (lm_faces() * frame.size.z * side * side);
}

Reservoir empty_reservoir(float confidence) {
    return Reservoir(RIS_NONE, 0.0, confidence, 0.0);
}

#ifdef RIS_PRESAMPLE
void main() {
    uint k = gl_GlobalInvocationID.x, tile = gl_GlobalInvocationID.y;
    if (k >= uint(RIS_POOL_TILE) || tile >= ris.pool_tiles) return;
    uint e = tile * uint(RIS_POOL_TILE) + k;
    vec4 a = vec4(0.0), b = vec4(0.0), c = vec4(0.0);
    if (cdf_total_at(0u) > 0.0) {
        float prob;
        uint seed = pcg_hash(tile ^ 0x6A09E667u) ^ pc.seed;
#ifdef RIS_UNIFORM_SOURCE
        // The uniform source with faces by Russian roulette: its section and the defensive one are the same
        // CDF (importance = validity), so draw_vpl's mixture is that CDF's distribution. One search (and its
        // probability) instead of draw_vpl's two, with draw_vpl's stratified points.
        uint all_rows = faces() * face_rows();
        vec3 u = vec3(owen_sobol2(k, seed ^ 0xA54FF53Au), owen_sobol1(k, seed ^ 0x510E527Fu));
        uint v = cdf_sample_rows3_prob(0u, 0u, u, 0u, all_rows, prob);
#else
        uint v = draw_vpl(k, seed, prob);
#endif
        if (prob > 0.0) {
            Vpl vpl = vpl_fetch(v);
            a = vec4(vpl.position, uintBitsToFloat(v));
            b = vec4(vpl.normal, prob);
            c = vec4(vpl.flux, vpl.area);
        }
    }
    pool_out[3u * e] = a;
    pool_out[3u * e + 1u] = b;
    pool_out[3u * e + 2u] = c;
}
#endif

#ifdef RIS_INITIAL
// Where reservoir `layer` of pixel q reads the pool: the first entry of its tile (chosen by a hash of
// (pixel, layer, frame)) and its start in the tile. Once per reservoir, not per candidate: llvmpipe divides
// integers lane by lane, and the tile index is a remainder by a push constant.
uvec2 pool_window(ivec2 q, uint layer) {
    uint tile = uint(ris_rand(q, 3u, layer) * float(ris.pool_tiles)) % ris.pool_tiles;
    uint start = uint(ris_rand(q, 4u, layer) * float(RIS_POOL_TILE)) % uint(RIS_POOL_TILE);
    return uvec2(tile * uint(RIS_POOL_TILE), start);
}

// Candidate i of reservoir `layer` at pixel q and its probability: a draw of the source either way.
// `window` is pool_window(q, layer) (unused without the pool).
uint candidate(ivec2 q, uint layer, uint i, uint seed, uvec2 window, out float prob, out Vpl vpl, out uint cell) {
#ifdef RIS_POOL
    int e = int(window.x + (window.y + i) % uint(RIS_POOL_TILE));
    uvec4 a = texelFetch(pool_texels, 3 * e);
    vec4 b = uintBitsToFloat(texelFetch(pool_texels, 3 * e + 1));
    vec4 c = uintBitsToFloat(texelFetch(pool_texels, 3 * e + 2));
    prob = b.w;
    vpl = Vpl(uintBitsToFloat(a.xyz), b.xyz, c.rgb, c.w, c.w != 0.0);
#ifdef RIS_LEARNED
    // Integer divisions, lane by lane on llvmpipe: only the learned variant pays them.
    cell = vis_cell_of(a.w);
#else
    cell = 0u;
#endif
    return a.w;
#else
    uint v = draw_vpl(layer * ris.candidates + i, seed, prob);
    if (prob > 0.0) vpl = vpl_fetch(v);
    cell = 0u; // the learned visibility needs the pool
    return v;
#endif
}

// Streams candidate k (VPL v, its data, its probability under the candidates' law) into r: the target,
// w = p̂ / prob, and the reservoir's choice; and into u the control variate's g = f · s, s the control's
// visibility guess: u.xyz sums Φ_v · p̂(v) s(v) / (prob · luminance(a ⊙ Φ_v)), which the albedo and 1/M
// make U_g = 1/M Σ g(v)/prob; u.w is the kept VPL's s / (p̂ / luminance(f)), so that the shade's g(y) W is
// f(y)/luminance(f(y)) · p̂(y) W · u.w. s is 1 (the shade's β scales it), or with the learned
// visibility the tile's and cell's visible fraction so far, visible / (traced + 1).
// With RIS_PICKS = K > 1 the candidates feed K picks: pick 0 is the reservoir itself, picks 1 .. K − 1 are
// held in component j of these (the VPL, its p̂, its control ratio). Pick j decides with u_j = fract(u_0 +
// j / K), pick 0's uniform rotated by j / K: uniform and independent across candidates for each j, so each
// pick is on its own exactly a reservoir of the same M candidates (the same Σw and U_g). Jointly, two picks
// take the same candidate only where its running share w / Σw exceeds 1 / K (with independent numbers
// they did so by chance, and a repeated pick traces the same shadow ray again): 3–5 % lower error at
// equal time than independent numbers, and one hash per candidate instead of K.
struct Picks {
    uvec4 vpl;
    vec4 target;
    vec4 ratio;
};

void add_candidate(inout Reservoir r, inout vec4 u, inout Picks pk, ivec2 px, uint k, uint v, Vpl vpl, float prob,
                   uint cell, vec3 x, vec3 nx, vec3 ax, uint tile_base) {
    float g = target_geometry(x, nx, vpl);
    float ratio = 1.0;
#ifdef RIS_LEARNED
    // V̂ = (visible + 1) / (traced + 2) from earlier frames only (this frame's shade adds after every
    // initial dispatch), floored at δ_L > 0: a target that depends on the past, positive wherever
    // the unshadowed one is, so each frame stays unbiased (passes/ris.rs).
    uint vi = tile_base + 2u * cell;
    uint seen = texelFetch(vis_texels, int(vi)).r, traced = texelFetch(vis_texels, int(vi + 1u)).r;
    float learned = max(float(seen + 1u) / float(traced + 2u), ris.learned);
    g *= learned;
    ratio = float(seen) / (float(traced + 1u) * learned);
#endif
    float t = dot(vpl_luminance_albedo(ax), vpl.flux) * g;
    float inv = 1.0 / prob;
    float w = t * inv;
    if (!(w > 0.0)) return;
    r.weight += w;
    u.xyz += vpl.flux * (g * inv * ratio);
    float u0 = ris_rand(px, 1u, k);
    if (u0 * r.weight < w) {
        r.vpl = v;
        r.target = t;
        u.w = ratio;
    }
    if (RIS_PICKS > 1u) {
        for (uint j = 1u; j < RIS_PICKS; j++) {
            if (fract(u0 + float(j) / float(RIS_PICKS)) * r.weight < w) {
                pk.vpl[j] = v;
                pk.target[j] = t;
                pk.ratio[j] = ratio;
            }
        }
    }
}

#ifdef RIS_NEAR
// The near strategy: a K × K window of light-map texels around where the pixel's point x projects into
// the map of each light, drawn uniformly: the VPLs next to x, whose kernel makes the target's tail, are
// found there when the light sees x's surroundings. Light l's window opens only when the texel x
// projects to sees a point within the window's reach of x, r·√A (A its patch area): behind an occluder
// it would hold the occluder's lit side, which gives x nothing. A near candidate first picks an open
// window with probability α_l ∝ luminance(I_l) / d_l², d_l the distance from light l to x (the radiosity
// of its VPLs next to x), then a texel of it. Every light's map has VPLs next to x, so every light's
// window is offered: with one window per reservoir, a VPL of the other light's next to x was a rare pool
// draw with a huge weight (the clutter scene's fireflies). The first RIS_NEAR_LIGHTS lights get
// windows (the RIS_NEAR_MULTI variants, for scenes with more than one light; the others hold one
// window, and a one-light scene pays nothing for the mixture); the pool's candidates cover the rest.
// All of it is fixed before any candidate, so the estimate stays unbiased whichever windows open.
#ifdef RIS_NEAR_MULTI
#define NEAR_LIGHTS RIS_NEAR_LIGHTS
#else
#define NEAR_LIGHTS 1
#endif

struct NearWindow {
    bool open;
    uint layer;  // the window's light-map layer (light · faces + face)
    ivec2 lo;    // its lowest texel
    float alpha; // the probability a near candidate picks this window (0: closed)
};

struct Near {
    NearWindow w[NEAR_LIGHTS];
    uint n;     // windows computed (min(lights, NEAR_LIGHTS))
    bool open;  // any window open
    int size;   // K = min(2r + 1, res) texels a side
    float p;    // 1 / K²
};

NearWindow near_window_of(uint l, vec3 x, int size) {
    NearWindow w;
    // Defined even where lm_locate finds no face (the window then stays closed).
    uint face = 0u;
    vec2 uv = vec2(0.0);
    int res = int(frame.size.w);
    vec3 d = x - lights[l].position.xyz;
    w.open = lm_locate(d, l, face, uv) && all(lessThan(abs(uv), vec2(2.0)));
    ivec2 c = clamp(ivec2(floor((uv * 0.5 + 0.5) * float(res))), ivec2(0), ivec2(res - 1));
    w.lo = clamp(c - ivec2(size / 2), ivec2(0), ivec2(res - size));
    w.layer = l * lm_faces() + face;
    vec4 seen = texelFetch(vpl_position, ivec3(c, int(w.layer)), 0);
    vec3 dx = seen.xyz - x;
    float reach2 = float(ris.near_radius * ris.near_radius) * seen.w;
    w.open = w.open && seen.w > 0.0 && dot(dx, dx) <= reach2;
    w.alpha = w.open ? luminance(lights[l].intensity.rgb) / max(dot(d, d), 1e-30) : 0.0;
    return w;
}

// Loops run to the constant NEAR_LIGHTS and branch on l < n inside, so that they unroll and every
// window is read at a constant index (llvmpipe keeps a dynamically indexed array in memory and reads
// it lane by lane, which halved the frame rate), and the branch, the same for every lane, skips the
// lights beyond the scene's (a select would evaluate them).
Near near_windows(vec3 x) {
    Near nw;
    int res = int(frame.size.w);
    nw.size = min(2 * int(ris.near_radius) + 1, res);
    nw.p = 1.0 / float(nw.size * nw.size);
    nw.n = min(frame.size.z, uint(NEAR_LIGHTS));
    float total = 0.0;
    for (uint l = 0u; l < uint(NEAR_LIGHTS); l++) {
        nw.w[l] = NearWindow(false, 0u, ivec2(0), 0.0);
        if (l < nw.n) {
            nw.w[l] = near_window_of(l, x, nw.size);
            total += nw.w[l].alpha;
        }
    }
    nw.open = total > 0.0;
    for (uint l = 0u; l < uint(NEAR_LIGHTS); l++) {
        if (l < nw.n) nw.w[l].alpha = nw.open ? nw.w[l].alpha / total : 0.0;
    }
    return nw;
}

// The texel of near candidate k, a window by α then a texel of it uniformly, and its probability under
// the near strategy, α / K².
ivec3 near_texel(Near nw, ivec2 q, uint k, out float p_near) {
    ivec2 lo = nw.w[0].lo;
    uint layer = nw.w[0].layer;
    float alpha = nw.w[0].alpha;
#if NEAR_LIGHTS > 1
    if (nw.n > 1u) {
        // (The same for every lane.)
        float u = ris_rand(q, 5u, k), acc = 0.0;
        bool picked = false;
        for (uint j = 0u; j < uint(NEAR_LIGHTS); j++) {
            // The last open window takes what rounding leaves of u.
            if (j < nw.n && nw.w[j].alpha > 0.0 && !picked) {
                lo = nw.w[j].lo;
                layer = nw.w[j].layer;
                alpha = nw.w[j].alpha;
                acc += alpha;
                picked = u < acc;
            }
        }
    }
#endif
    p_near = alpha * nw.p;
    ivec2 o = min(ivec2(vec2(ris_rand(q, 6u, k), ris_rand(q, 7u, k)) * float(nw.size)), ivec2(nw.size - 1));
    return ivec3(lo + o, int(layer));
}

// The near strategy's probability of VPL v: α of its light's window / K² inside that window, else 0.
// v's layer belongs to one light, so at most one window can hold it: find that window by its layer's
// index range and keep its corner and α (selects), then divide once and test once.
float near_prob(Near nw, uint v) {
    uint res = frame.size.w, face_texels = res * res;
#if NEAR_LIGHTS > 1
    if (nw.n == 1u)
#endif
    {
        // One window (in the multi variants, a one-light scene: the same for every lane, so the loop
        // below is skipped).
        uint base = nw.w[0].layer * face_texels;
        if (!nw.w[0].open || v < base || v - base >= face_texels) return 0.0;
        uint r1 = v - base, ty1 = udiv(r1, res); // a row: far below udiv's exact range
        ivec2 o1 = ivec2(int(r1 - ty1 * res), int(ty1)) - nw.w[0].lo;
        return all(greaterThanEqual(o1, ivec2(0))) && all(lessThan(o1, ivec2(nw.size))) ? nw.w[0].alpha * nw.p : 0.0;
    }
#if NEAR_LIGHTS > 1
    uint r = 0u;
    ivec2 lo = ivec2(0);
    float alpha = 0.0;
    for (uint j = 0u; j < uint(NEAR_LIGHTS); j++) {
        if (j < nw.n) {
            uint base = nw.w[j].layer * face_texels;
            bool mine = nw.w[j].open && v >= base && v - base < face_texels;
            r = mine ? v - base : r;
            lo = mine ? nw.w[j].lo : lo;
            alpha = mine ? nw.w[j].alpha : alpha;
        }
    }
    uint ty = udiv(r, res);
    ivec2 o = ivec2(int(r - ty * res), int(ty)) - lo;
    return alpha > 0.0 && all(greaterThanEqual(o, ivec2(0))) && all(lessThan(o, ivec2(nw.size))) ? alpha * nw.p : 0.0;
#endif
}
#endif

// Finishes pick r of layer `layer` after its M candidates: W = Σw / (M p̂(y)), then (ris.history) combined
// with last frame's reservoir at the same pixel and layer.
Reservoir finish(Reservoir r, ivec2 px, uint layer, uint idx, vec3 x, vec3 nx, vec3 ax) {
    float m = float(ris.candidates);
    r.weight = r.target > 0.0 ? r.weight / (m * r.target) : 0.0;
    r.confidence = m;
    if (ris.history != 0u) {
        // Last frame's final reservoir at this pixel: the same G-buffer, so the same target, and the
        // generalized balance weights reduce to the confidences: m_i = c_i / (c_0 + c_1).
        Reservoir h = res_history[idx];
        float ch = min(h.confidence, ris.history_cap * m);
        float th = h.vpl != RIS_NONE && h.weight > 0.0 ? target_at(x, nx, ax, h.vpl) : 0.0;
        float total = m + ch;
        float w0 = m / total * r.target * r.weight;
        float w1 = ch / total * th * h.weight;
        float sum = w0 + w1;
        if (w1 > 0.0 && ris_rand(px, 2u, layer) * sum < w1) {
            r.vpl = h.vpl;
            r.target = th;
        }
        r.weight = r.target > 0.0 && sum > 0.0 ? sum / r.target : 0.0;
        r.confidence = total;
    }
    if (!(r.weight > 0.0)) r = empty_reservoir(r.confidence);
    return r;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    // Invocation z streams candidate set `stream` into its K = RIS_PICKS picks, layers stream · K + j.
    uint stream = gl_GlobalInvocationID.z;
    uint layer = stream * RIS_PICKS;
    if (any(greaterThanEqual(px, ivec2(frame.size.xy))) || layer >= ris.reservoirs) return;
    uint idx = res_index(px, layer);
    vec4 gp = texelFetch(g_position, px, 0);
    if (gp.w == 0.0) {
        for (uint j = 0u; j < RIS_PICKS; j++) {
            res_out[res_index(px, layer + j)] = empty_reservoir(0.0);
            if (ris.control != 0u) unshadowed[res_index(px, layer + j)] = vec4(0.0);
        }
        return;
    }
    vec3 x = gp.xyz, nx = texelFetch(g_normal, px, 0).xyz, ax = texelFetch(g_albedo, px, 0).rgb;
    // The streaming state: (y, Σw, p̂(y)), carried in the output between dispatches.
    Reservoir r = pc.first == 0u ? empty_reservoir(0.0) : res_out[idx];
    // The control variate's sums, carried between dispatches only when the shade uses them.
    // (A stand-in of one vec4 is bound when it is off.)
    vec4 u = vec4(0.0);
    if (pc.first != 0u && ris.control != 0u) u = unshadowed[idx];
    // The other picks' choices, carried in their own layers between dispatches.
    Picks pk = Picks(uvec4(RIS_NONE), vec4(0.0), vec4(0.0));
    if (pc.first != 0u) {
        for (uint j = 1u; j < RIS_PICKS; j++) {
            Reservoir q = res_out[res_index(px, layer + j)];
            pk.vpl[j] = q.vpl;
            pk.target[j] = q.target;
            if (ris.control != 0u) pk.ratio[j] = unshadowed[res_index(px, layer + j)].w;
        }
    }
    if (cdf_total_at(0u) > 0.0) {
        // Candidate i of stream s is point s·M + i of the pixel's stratified set, the gather's seed.
        uint seed = pcg_hash(uint(px.x) + 65536u * uint(px.y)) ^ pc.seed;
#ifdef RIS_LEARNED
        uint tile_base = vis_tile_base(px);
#else
        uint tile_base = 0u;
#endif
#ifdef RIS_POOL
        uvec2 window = pool_window(px, stream);
#else
        uvec2 window = uvec2(0u);
#endif
#ifdef RIS_NEAR
        Near near = near_windows(x);
        // Closed windows give their candidates to the pool.
        uint split = near.open ? ris.candidates - ris.near_candidates : ris.candidates;
        float m_all = float(ris.candidates), m_pool = float(split), m_near = m_all - m_pool;
        // The pool's candidates, then the window's (two loops: llvmpipe would run both bodies for each).
        for (uint i = pc.first; i < min(pc.last, split); i++) {
            float prob;
            Vpl vpl;
            uint cell;
            uint v = candidate(px, stream, i, seed, window, prob, vpl, cell);
            if (!(prob > 0.0)) continue;
            // The balance mixture of the two strategies (multiple-importance RIS): each candidate weighed
            // by m_all / (m_pool p_source + m_near p_near).
            prob = (m_pool * prob + m_near * near_prob(near, v)) / m_all;
            add_candidate(r, u, pk, px, stream * ris.candidates + i, v, vpl, prob, cell, x, nx, ax, tile_base);
        }
        if (near.open) {
            for (uint i = max(pc.first, split); i < pc.last; i++) {
                uint k = stream * ris.candidates + i;
                float p_near;
                ivec3 t = near_texel(near, px, k, p_near);
                uint res = frame.size.w;
                uint v = (uint(t.z) * res + uint(t.y)) * res + uint(t.x);
                Vpl vpl = vpl_fetch_texel(t);
                if (!vpl.valid) continue;
#ifdef RIS_UNIFORM_SOURCE
                // The uniform source with faces by Russian roulette draws a face by its count of VPLs, then
                // a VPL of it uniformly: 1 / (all VPLs) for each. Its CDF's prefixes are integers, exact in
                // f32, so this is the pool's cdf_prob_rows to rounding, without its divisions and loop.
                float p_source = 1.0 / cdf_total_at(0u);
#else
                float p_source = source_prob(v);
#endif
                float prob = (m_pool * p_source + m_near * p_near) / m_all;
#ifdef RIS_LEARNED
                uint cell = vis_cell_at(uint(t.z), uint(t.x), uint(t.y));
#else
                uint cell = 0u;
#endif
                add_candidate(r, u, pk, px, k, v, vpl, prob, cell, x, nx, ax, tile_base);
            }
        }
#else
        for (uint i = pc.first; i < pc.last; i++) {
            float prob;
            Vpl vpl;
            uint cell;
            uint v = candidate(px, stream, i, seed, window, prob, vpl, cell);
            if (!(prob > 0.0)) continue;
            add_candidate(r, u, pk, px, stream * ris.candidates + i, v, vpl, prob, cell, x, nx, ax, tile_base);
        }
#endif
    }
    if (pc.last < ris.candidates) {
        res_out[idx] = r;
        if (ris.control != 0u) unshadowed[idx] = u;
        for (uint j = 1u; j < RIS_PICKS; j++) {
            res_out[res_index(px, layer + j)] = Reservoir(pk.vpl[j], r.weight, 0.0, pk.target[j]);
            if (ris.control != 0u) unshadowed[res_index(px, layer + j)] = vec4(0.0, 0.0, 0.0, pk.ratio[j]);
        }
        return;
    }
    // Every pick shares the candidates' Σw and U_g; each has its own y, p̂(y) and ratio.
    vec3 ug = ax * u.xyz / float(ris.candidates);
    for (uint j = 1u; j < RIS_PICKS; j++) {
        uint idx_j = res_index(px, layer + j);
        if (ris.control != 0u) unshadowed[idx_j] = vec4(ug, pk.ratio[j]);
        Reservoir q = Reservoir(pk.vpl[j], r.weight, 0.0, pk.target[j]);
        res_out[idx_j] = finish(q, px, layer + j, idx_j, x, nx, ax);
    }
    if (ris.control != 0u) unshadowed[idx] = vec4(ug, u.w);
    res_out[idx] = finish(r, px, layer, idx, x, nx, ax);
}
#endif

#ifdef RIS_SPATIAL
// Whether neighbour q may lend its reservoir to p: both see geometry, their normals within ~25° and their
// distances from the eye within 10 % (a deterministic function of the two G-buffer texels).
bool similar(vec4 gp, vec3 np, vec4 gq, vec3 nq) {
    if (gq.w == 0.0) return false;
    float dp = distance(gp.xyz, frame.eye.xyz), dq = distance(gq.xyz, frame.eye.xyz);
    return dot(np, nq) >= 0.9 && abs(dq - dp) <= 0.1 * dp;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    uint layer = gl_GlobalInvocationID.z;
    if (any(greaterThanEqual(px, ivec2(frame.size.xy))) || layer >= ris.reservoirs) return;
    uint idx = res_index(px, layer);
    Reservoir canonical = res_in[idx];
    vec4 gp = texelFetch(g_position, px, 0);
    if (gp.w == 0.0) {
        res_out[idx] = canonical;
        return;
    }
    // The inputs: 0 the pixel itself, then the accepted neighbours (at most RIS_MAX_NEIGHBORS).
    ivec2 q[RIS_MAX_NEIGHBORS + 1];
    vec3 xs[RIS_MAX_NEIGHBORS + 1], ns[RIS_MAX_NEIGHBORS + 1], albs[RIS_MAX_NEIGHBORS + 1];
    q[0] = px;
    xs[0] = gp.xyz;
    ns[0] = texelFetch(g_normal, px, 0).xyz;
    albs[0] = texelFetch(g_albedo, px, 0).rgb;
    uint n = 1u;
    uint tries = min(ris.neighbors, uint(RIS_MAX_NEIGHBORS));
    for (uint j = 0u; j < tries; j++) {
        // A point of the disc of radius `radius` (by the hash of pixel, seed, pass, layer and j).
        uint stream = 16u + ris.pass * 64u + j;
        float a = 2.0 * PI * ris_rand(px, stream, 2u * layer), rr = ris.radius * sqrt(ris_rand(px, stream, 2u * layer + 1u));
        ivec2 c = px + ivec2(round(rr * vec2(cos(a), sin(a))));
        if (c == px || any(lessThan(c, ivec2(0))) || any(greaterThanEqual(c, ivec2(frame.size.xy)))) continue;
        vec4 gq = texelFetch(g_position, c, 0);
        vec3 nq = texelFetch(g_normal, c, 0).xyz;
        if (!similar(gp, ns[0], gq, nq)) continue;
        q[n] = c;
        xs[n] = gq.xyz;
        ns[n] = nq;
        albs[n] = texelFetch(g_albedo, c, 0).rgb;
        n++;
    }
    Reservoir inputs[RIS_MAX_NEIGHBORS + 1];
    inputs[0] = canonical;
    float confidence = canonical.confidence;
    for (uint i = 1u; i < n; i++) {
        inputs[i] = res_in[res_index(q[i], layer)];
        confidence += inputs[i].confidence;
    }
    // Resample: input i's sample y_i weighs m_i(y_i) · p̂_x(y_i) · W_i.
    Reservoir r = empty_reservoir(confidence);
    float sum = 0.0;
    for (uint i = 0u; i < n; i++) {
        Reservoir in_i = inputs[i];
        if (in_i.vpl == RIS_NONE || !(in_i.weight > 0.0)) continue;
        Vpl vpl = vpl_fetch(in_i.vpl);
        float num = 0.0, den = 0.0, here = 0.0;
        for (uint j = 0u; j < n; j++) {
            float t = vpl_unshadowed_luminance(xs[j], ns[j], vpl_luminance_albedo(albs[j]), vpl, pc.clamp_d2);
            den += inputs[j].confidence * t;
            if (j == i) num = inputs[j].confidence * t;
            if (j == 0u) here = t;
        }
        float w = den > 0.0 ? num / den * here * in_i.weight : 0.0;
        if (!(w > 0.0)) continue;
        sum += w;
        if (ris_rand(px, 8u + ris.pass, layer * 16u + i) * sum < w) {
            r.vpl = in_i.vpl;
            r.target = here;
        }
    }
    r.weight = r.vpl != RIS_NONE ? sum / r.target : 0.0;
    if (!(r.weight > 0.0)) r = empty_reservoir(confidence);
    res_out[idx] = r;
}
#endif

#ifdef RIS_SHADE
void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 gp = texelFetch(g_position, px, 0);
    vec3 sum = vec3(0.0);
    if (gp.w != 0.0) {
        vec3 x = gp.xyz, nx = texelFetch(g_normal, px, 0).xyz, ax = texelFetch(g_albedo, px, 0).rgb;
        uint pixel = uint(px.y) * frame.size.x + uint(px.x);
        // (Read only when on: a stand-in of one uvec4 is bound when off.)
        uvec4 state = uvec4(0u);
        if (ris.control != 0u) state = cv_counts[pixel];
        // counts: β's (visible, traced). siblings: the same for the candidate set in progress, added to
        // counts only at the next set's first pick: the picks' choices depend on one another given their
        // candidates (rotated uniforms), so a pick's β must not see its siblings' rays. Other sets' rays
        // are independent of this pick's choice given the pool, and count at once. Both are carried
        // across dispatches and frames, so a dispatch may end inside a set.
        uvec2 counts = state.xy, siblings = state.zw;
#ifdef SHADE_QUEUE
        vec3 o = shadow_origin(x, nx);
        vec4 pixel_ball = end_ball_of_pixel(px);
        for (uint base = pc.first; base < pc.last; base += SHADOW_QUEUE) {
            uint top = min(base + SHADOW_QUEUE, pc.last), n = 0u;
            for (uint layer = base; layer < top; layer++) {
                Reservoir r = res_in[res_index(px, layer)];
                if (!(r.vpl != RIS_NONE && r.weight > 0.0)) continue;
                Vpl vpl = vpl_fetch(r.vpl);
                if (vpl_unshadowed(x, nx, ax, vpl, pc.clamp_d2) != vec3(0.0)) {
                    vec3 e = shadow_end(r.vpl, vpl);
                    shadow_queue_end[n] = e;
                    shadow_queue_window[n++] = end_ball_window(o, e, x, pixel_ball, r.vpl, vpl.position);
                }
            }
            uint visible = shadow_queue_trace(o, n), ray = 0u;
#else
        {
            uint base = pc.first, top = pc.last;
#endif
            for (uint layer = base; layer < top; layer++) {
                if (layer % ris.picks == 0u) {
                    counts += siblings;
                    siblings = uvec2(0u);
                }
                uint idx = res_index(px, layer);
                Reservoir r = res_in[idx];
                // An empty reservoir had no candidate with w > 0, so its U_g is 0 too: it adds nothing.
                if (!(r.vpl != RIS_NONE && r.weight > 0.0)) continue;
                Vpl vpl = vpl_fetch(r.vpl);
#ifdef SHADE_QUEUE
                // contribution_of's value: the unshadowed contribution, or 0 where the block's queued ray (the
                // next one) was occluded.
                vec3 c = vpl_unshadowed(x, nx, ax, vpl, pc.clamp_d2);
                if (c != vec3(0.0) && (visible & (1u << ray++)) == 0u) c = vec3(0.0);
#else
                vec3 c = contribution_of(x, nx, ax, r.vpl, vpl);
#endif
                sum += c * r.weight;
                if (ris.control != 0u) {
                    // The control variate: + β (U_g − g(y) W), g = f p̂ / luminance(f), whose g(y) W is the
                    // kept VPL's colour ratio f / luminance(f) times p̂(y) W = Σw / M. Given the candidates,
                    // E[g(y) W] = U_g exactly, so the term has mean 0 for any β fixed without this
                    // reservoir's choice: here from this pixel's earlier shadow rays (earlier frames and
                    // earlier candidate sets of this frame), β = visible / (traced + 1), 0 until one got through: a
                    // pixel no ray reaches keeps its exact 0 instead of the control's zero-mean noise.
                    vec4 ug = unshadowed[idx];
                    float lum = dot(vpl_luminance_albedo(ax), vpl.flux);
                    vec3 gw = lum > 0.0 ? ax * vpl.flux * (r.target * r.weight * ug.w / lum) : vec3(0.0);
                    float beta = ris.learned > 0.0 ? 1.0 : float(counts.x) / float(counts.y + 1u);
                    sum += beta * (ug.xyz - gw);
                    siblings += uvec2(c != vec3(0.0) ? 1u : 0u, 1u);
                }
                if (ris.learned > 0.0) {
                    // A kept VPL has an unshadowed contribution (its target is positive): 0 means occluded.
                    uint vi = vis_tile_base(px) + 2u * vis_cell_of(r.vpl);
                    if (c != vec3(0.0)) atomicAdd(vis_counts[vi], 1u);
                    atomicAdd(vis_counts[vi + 1u], 1u);
                }
            }
        }
        sum /= float(ris.reservoirs);
        if (ris.control != 0u) cv_counts[pixel] = uvec4(counts, siblings);
    }
    if (pc.add_direct != 0u) sum += texelFetch(direct_radiance, px, 0).rgb;
    if (pc.accumulate != 0u) sum += imageLoad(out_radiance, px).rgb;
    imageStore(out_radiance, px, vec4(sum, 1.0));
}
#endif
