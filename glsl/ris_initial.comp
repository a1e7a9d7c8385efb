#version 460
// ris, initial stage (dispatch W × H × R / K): candidate set s streams candidates [first, last) of its M:
//   v ~ p, w = p̂(v)/p_v, v kept with probability w / Σw, independently by each of its K = RIS_PICKS picks
//   (layers s·K + j); after the M-th, each pick's W = Σw / (M p̂(y_j)) (ris_temporal.comp then
//   combines it with last frame's, when kept).
// RIS_POOL: reservoir r's candidates are consecutive entries of one tile of the presampled pool
//   (ris_presample.comp), from a start, both chosen by a hash of (pixel, layer, frame); each is a draw of
//   the source (its marginal law is p: ris.rs). RIS_LEARNED: the target weighs in the learned visibility.
// RIS_NEAR (a specialisation; with the pool, ris.near_candidates > 0): the last ris.near_candidates of the
//   M candidates come from (2r + 1)² windows of light-map texels around where x projects into each
//   light's map (shared/near_window.glsl): the VPLs next to x, whose kernel makes the target's tail and
//   which the pool almost never holds. Every candidate, of either strategy, is weighed with the balance
//   mixture q(v) = (M_pool p_source(v) + M_near p_near(v)) / M (multiple-importance RIS): unbiased, since
//   the pool's strategy reaches every VPL (ris.rs).
#include "shared/ris.glsl"

layout(constant_id = SPEC_RIS_NEAR) const bool RIS_NEAR = false;
layout(constant_id = SPEC_RIS_UNIFORM_SOURCE) const bool RIS_UNIFORM_SOURCE = false;
layout(std430, set = 0, binding = B_RIS_OUT) buffer RisOut { Reservoir res_out[]; };
// K: picks per reservoir (RisPush::picks selects the pipeline specialised to it).
layout(constant_id = SPEC_RIS_PICKS) const uint RIS_PICKS = 1u;
// The control variate's state (add_candidate): xyz the candidates' estimate U_g of the reservoir (while
// streaming, its sum before the albedo and 1/M), w the kept VPL's ratio s / (p̂ / luminance(f)).
layout(std430, set = 0, binding = B_RIS_UNSHADOWED) buffer RisUnshadowed { vec4 unshadowed[]; };
#ifdef RIS_POOL
layout(set = 0, binding = B_RIS_POOL) uniform usamplerBuffer pool_texels;
#endif
#ifdef RIS_LEARNED
// Read through the counts' texel view (a texel fetch gathers a vector's lanes at once).
layout(set = 0, binding = B_RIS_VIS) uniform usamplerBuffer vis_texels;
#endif

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

#include "shared/near_window.glsl"

// Finishes a pick after its M candidates: W = Σw / (M p̂(y)).
Reservoir finish(Reservoir r) {
    float m = float(ris.candidates);
    r.weight = r.target > 0.0 ? r.weight / (m * r.target) : 0.0;
    r.confidence = m;
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
            if (ris.control == RIS_CONTROL_CANDIDATES) unshadowed[res_index(px, layer + j)] = vec4(0.0);
        }
        return;
    }
    vec3 x = gp.xyz, nx = texelFetch(g_normal, px, 0).xyz, ax = texelFetch(g_albedo, px, 0).rgb;
    // The streaming state: (y, Σw, p̂(y)), carried in the output between dispatches.
    Reservoir r = pc.first == 0u ? empty_reservoir(0.0) : res_out[idx];
    // The control variate's sums, carried between dispatches only when the shade uses them.
    // (A stand-in of one vec4 is bound when it is off.)
    vec4 u = vec4(0.0);
    if (pc.first != 0u && ris.control == RIS_CONTROL_CANDIDATES) u = unshadowed[idx];
    // The other picks' choices, carried in their own layers between dispatches.
    Picks pk = Picks(uvec4(RIS_NONE), vec4(0.0), vec4(0.0));
    if (pc.first != 0u) {
        for (uint j = 1u; j < RIS_PICKS; j++) {
            Reservoir q = res_out[res_index(px, layer + j)];
            pk.vpl[j] = q.vpl;
            pk.target[j] = q.target;
            if (ris.control == RIS_CONTROL_CANDIDATES) pk.ratio[j] = unshadowed[res_index(px, layer + j)].w;
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
        // Drawn here, per pixel: `local`'s source is its mixture at px, as the gather's (the pool is
        // shared by the screen, so it draws every region alike).
        mixture_at_pixel(px);
#endif
        if (RIS_NEAR) {
        Near near = near_windows(x, ris.near_radius);
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
                ivec3 t = near_texel(near, ris_rand(px, 5u, k), vec2(ris_rand(px, 6u, k), ris_rand(px, 7u, k)), p_near);
                uint res = frame.size.w;
                uint v = (uint(t.z) * res + uint(t.y)) * res + uint(t.x);
                Vpl vpl = vpl_fetch_texel(t);
                if (!vpl.valid) continue;
                // The uniform source (the validity CDF alone) draws a face by its count of VPLs, then
                // a VPL of it uniformly: 1 / (all VPLs) for each. Its CDF's prefixes are integers, exact in
                // f32, so this is the pool's cdf_prob_rows to rounding, without its divisions and loop.
                float p_source = RIS_UNIFORM_SOURCE ? 1.0 / cdf_total_at(0u) : source_prob(v);
                float prob = (m_pool * p_source + m_near * p_near) / m_all;
#ifdef RIS_LEARNED
                uint cell = vis_cell_at(uint(t.z), uint(t.x), uint(t.y));
#else
                uint cell = 0u;
#endif
                add_candidate(r, u, pk, px, k, v, vpl, prob, cell, x, nx, ax, tile_base);
            }
        }
        } else {
        for (uint i = pc.first; i < pc.last; i++) {
            float prob;
            Vpl vpl;
            uint cell;
            uint v = candidate(px, stream, i, seed, window, prob, vpl, cell);
            if (!(prob > 0.0)) continue;
            add_candidate(r, u, pk, px, stream * ris.candidates + i, v, vpl, prob, cell, x, nx, ax, tile_base);
        }
        }
    }
    if (pc.last < ris.candidates) {
        res_out[idx] = r;
        if (ris.control == RIS_CONTROL_CANDIDATES) unshadowed[idx] = u;
        for (uint j = 1u; j < RIS_PICKS; j++) {
            res_out[res_index(px, layer + j)] = Reservoir(pk.vpl[j], r.weight, 0.0, pk.target[j]);
            if (ris.control == RIS_CONTROL_CANDIDATES) unshadowed[res_index(px, layer + j)] = vec4(0.0, 0.0, 0.0, pk.ratio[j]);
        }
        return;
    }
    // Every pick shares the candidates' Σw and U_g; each has its own y, p̂(y) and ratio.
    vec3 ug = ax * u.xyz / float(ris.candidates);
    for (uint j = 1u; j < RIS_PICKS; j++) {
        uint idx_j = res_index(px, layer + j);
        if (ris.control == RIS_CONTROL_CANDIDATES) unshadowed[idx_j] = vec4(ug, pk.ratio[j]);
        Reservoir q = Reservoir(pk.vpl[j], r.weight, 0.0, pk.target[j]);
        res_out[idx_j] = finish(q);
    }
    if (ris.control == RIS_CONTROL_CANDIDATES) unshadowed[idx] = vec4(ug, u.w);
    res_out[idx] = finish(r);
}
