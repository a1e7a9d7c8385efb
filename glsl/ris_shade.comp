#version 460
// ris, shade stage (dispatch W × H): L = 1/R Σ_r f(y_r) V(y_r) W_r over the reservoirs [first, last),
// visibility as the gather's (voxel, EXACT_VISIBILITY); with ris.control each term adds the unshadowed
// control variate β (U_g − g(y_r) W_r), mean 0 given the reservoir's candidates (ris.rs). The alpha
// channel holds the estimate's variance, from its R reservoirs' own estimates L_r (independent given the
// frame's inputs): with l_r the luminance of L_r demodulated by the albedo (the denoiser's signal),
// σ² = Σ_r (l_r − l̄)² / (R (R − 1)), the variance of their mean; 0 with one reservoir, or where one
// dispatch does not hold all R (then nothing reads it).
#include "shared/ris.glsl"

layout(set = 0, binding = B_GATHER_DIRECT) uniform sampler2D direct_radiance;
layout(set = 0, binding = B_GATHER_OUT, rgba32f) uniform image2D out_radiance;
#ifdef RIS_HISTORY
// The history variant rewrites each reservoir with its combination (the one kept for the next frame).
layout(std430, set = 0, binding = B_RIS_IN) buffer RisIn { Reservoir res_in[]; };
#else
layout(std430, set = 0, binding = B_RIS_IN) readonly buffer RisIn { Reservoir res_in[]; };
#endif
layout(std430, set = 0, binding = B_RIS_VIS) buffer RisVis { uint vis_counts[]; };
layout(std430, set = 0, binding = B_RIS_UNSHADOWED) readonly buffer RisUnshadowed { vec4 unshadowed[]; };
layout(std430, set = 0, binding = B_RIS_CV) buffer RisCv { uvec4 cv_counts[]; };
// The frame's shadow rays (visibility tests), counted: `bounce bench` reports them per pixel.
layout(std430, set = 0, binding = B_RIS_RAYS) buffer RisRays { uint rays_traced; };
#ifdef EXACT_VISIBILITY
// The shade's shadow rays from a queue (shared/shadow_queue.glsl): a block's rays are queued first, traced,
// and then the block's reservoirs are shaded in order with their answers.
#define SHADE_QUEUE
// The queue's rays skip their ends' empty balls (pc.end_balls; passes/end_balls.rs): the same answers.
#define SHADOW_QUEUE_WINDOWS
#define END_BALLS_READ
#include "shared/end_balls.glsl"
#include "shared/shadow_queue.glsl"
#endif

#ifdef RIS_HISTORY
// RIS_HISTORY: the temporal combination, here because its target knows visibility. Each of the pixel's
// reservoirs (this frame's, after the spatial passes: y_0, W_0, c_0) is combined with last frame's final
// one at the pixel's previous pixel q (y_1, W_1, c_1 capped at history_cap · c_0; none where the surface
// was disoccluded) for the target p̂ = p̂_u · V: the unshadowed target times the visibility that both
// samples' shadow rays (two a reservoir) test here. Balance weights m_i(y) = c_i p̂_i(y) / Σ_j c_j p̂_j(y)
// with p̂_0 = p̂_u here and p̂_1 = last frame's p̂ at q (its surface and VPLs), whose visibility is taken
// as this frame's (exact for a still view and lights, where q is the pixel itself; otherwise off only
// where a VPL's visibility from the point changed between the frames). The estimate is the
// combination's weight sum in colour, L = Σ_i m_i(y_i) f(y_i) V(y_i) W_i (plus the fresh reservoir's
// control variate scaled by its constant share c_0 / (c_0 + c_1): zero mean, unbiased), and the
// reservoir kept is y_i with probability ∝ w_i = m_i p̂(y_i) W_i, W = Σ w / p̂(y): a history of visible
// samples whose weight averages the frames' visibility tests, where a target blind to visibility
// leaves every frame one Bernoulli draw (BENCHMARKS.md, "Real time under motion").
layout(std430, set = 0, binding = B_RIS_HISTORY) readonly buffer RisHistory { Reservoir res_history[]; };
layout(set = 0, binding = B_MOTION) uniform sampler2D motion;
layout(set = 0, binding = B_PREV_POSITION) uniform sampler2D prev_position;
layout(set = 0, binding = B_PREV_SURFACE) uniform usampler2D prev_surface;
layout(set = 0, binding = B_PREV_VPL_POSITION) uniform sampler2DArray prev_vpl_position;
layout(set = 0, binding = B_PREV_VPL_NORMAL) uniform sampler2DArray prev_vpl_normal;
layout(set = 0, binding = B_PREV_VPL_FLUX) uniform sampler2DArray prev_vpl_flux;

// Last frame's unshadowed target at (x, n, a) for VPL v: with last frame's VPL maps.
float prev_target_at(vec3 x, vec3 n, vec3 a, uint v) {
    ivec3 t = vpl_texel(v);
    vec4 p = texelFetch(prev_vpl_position, t, 0);
    return target_of(x, n, a, vpl_from(p, texelFetch(prev_vpl_normal, t, 0).xyz, texelFetch(prev_vpl_flux, t, 0).rgb));
}

// Whether the shadow rays x → y_0 and x → y_1 are open (bits 0 and 1), traced only where `need` says (an
// unshadowed contribution).
uvec2 two_rays(ivec2 px, vec3 x, vec3 nx, bvec2 need, uvec2 v, Vpl a, Vpl b) {
    uvec2 open = uvec2(0u);
#ifdef EXACT_VISIBILITY
    vec3 o = lifted_origin(x, nx);
    vec4 pixel_ball = end_ball_of_pixel(px);
    uint n = 0u;
    if (need.x) {
        vec3 e = shadow_end(v.x, a);
        shadow_queue_end[n] = e;
        shadow_queue_window[n++] = end_ball_window(o, e, x, pixel_ball, v.x, a.position);
    }
    if (need.y) {
        vec3 e = shadow_end(v.y, b);
        shadow_queue_end[n] = e;
        shadow_queue_window[n++] = end_ball_window(o, e, x, pixel_ball, v.y, b.position);
    }
    uint visible = shadow_queue_trace(o, n);
    if (n > 0u) atomicAdd(rays_traced, n);
    if (need.x) open.x = visible & 1u;
    if (need.y) open.y = (visible >> (need.x ? 1u : 0u)) & 1u;
#else
    if (need.x) {
        atomicAdd(rays_traced, 1u);
        open.x = segment_open(x, nx, v.x, a) ? 1u : 0u;
    }
    if (need.y) {
        atomicAdd(rays_traced, 1u);
        open.y = segment_open(x, nx, v.y, b) ? 1u : 0u;
    }
#endif
    return open;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 gp = texelFetch(g_position, px, 0);
    vec3 sum = vec3(0.0);
    float variance = 0.0;
    if (gp.w != 0.0) {
        vec3 x = gp.xyz, nx = texelFetch(g_normal, px, 0).xyz, ax = texelFetch(g_albedo, px, 0).rgb;
        uint pixel = uint(px.y) * frame.size.x + uint(px.x);
        uvec4 state = uvec4(0u);
        if (ris.control != 0u) state = cv_counts[pixel];
        // β from earlier frames' fresh rays (this frame's are added after).
        float beta = ris.learned > 0.0 ? 1.0 : float(state.x) / float(state.y + 1u);
        uvec2 added = uvec2(0u);
        vec4 mv = texelFetch(motion, px, 0);
        bool kept = mv.z != 0.0;
        ivec2 q = ivec2(mv.xy);
        if (!kept && mv.w != 0.0) {
            // The pixel the point fell in saw another surface (a silhouette): the nearest of the four
            // around it that saw this one.
            ivec2 base;
            vec2 t;
            bilinear_footprint(mv.xy, base, t);
            uint taps = uint(mv.w);
            float best = 1e30;
            for (uint k = 0u; k < 4u; k++) {
                ivec2 c = base + ivec2(k & 1u, k >> 1u);
                vec2 d = vec2(c) + 0.5 - mv.xy;
                if ((taps & (1u << k)) != 0u && dot(d, d) < best) {
                    best = dot(d, d);
                    q = c;
                    kept = true;
                }
            }
        }
        vec3 xq = vec3(0.0), nq = vec3(0.0), aq = vec3(0.0);
        if (kept) {
            uvec4 su = texelFetch(prev_surface, q, 0);
            xq = texelFetch(prev_position, q, 0).xyz;
            nq = uintBitsToFloat(su.xyz);
            aq = unpackUnorm4x8(su.w).rgb;
        }
        for (uint layer = pc.first; layer < pc.last; layer++) {
            uint idx = res_index(px, layer);
            Reservoir r = res_in[idx];
            Reservoir h = kept ? res_history[res_index(q, layer)] : empty_reservoir(0.0);
            bool has0 = r.vpl != RIS_NONE && r.weight > 0.0, has1 = h.vpl != RIS_NONE && h.weight > 0.0;
            Vpl v0 = vpl_fetch(has0 ? r.vpl : 0u), v1 = vpl_fetch(has1 ? h.vpl : 0u);
            vec3 f0 = has0 ? vpl_unshadowed(x, nx, ax, v0, pc.clamp_d2) : vec3(0.0);
            vec3 f1 = has1 ? vpl_unshadowed(x, nx, ax, v1, pc.clamp_d2) : vec3(0.0);
            uvec2 open = two_rays(px, x, nx, bvec2(f0 != vec3(0.0), f1 != vec3(0.0)), uvec2(r.vpl, h.vpl), v0, v1);
            float c0 = r.confidence, c1 = kept ? min(h.confidence, ris.history_cap * c0) : 0.0;
            // p̂_u here and p̂_1 at q, for each sample.
            float t0 = has0 ? target_of(x, nx, ax, v0) : 0.0, t1 = has1 ? target_of(x, nx, ax, v1) : 0.0;
            float p0 = has0 && kept ? prev_target_at(xq, nq, aq, r.vpl) : 0.0;
            float p1 = has1 ? prev_target_at(xq, nq, aq, h.vpl) : 0.0;
            float k = uintBitsToFloat(ris.pad0);
            float s0 = p0 > 0.0 && t0 > 0.0 ? pow(min(p0 / t0, t0 / p0), k) * (k > 0.0 ? 1.0 : p0 / t0) : 0.0;
            float s1 = p1 > 0.0 && t1 > 0.0 ? pow(min(p1 / t1, t1 / p1), k) * (k > 0.0 ? 1.0 : p1 / t1) : 0.0;
            float m0 = has0 ? c0 / (c0 + c1 * s0) : 0.0, m1 = has1 && t1 > 0.0 ? c1 * s1 / (c0 + c1 * s1) : 0.0;
            vec3 e0 = open.x != 0u ? f0 * r.weight : vec3(0.0), e1 = open.y != 0u ? f1 * h.weight : vec3(0.0);
            // The fresh reservoir's own estimate, with its control variate (mean 0 given its inputs).
            vec3 fresh = e0;
            if (ris.control != 0u && has0) {
                vec4 ug = unshadowed[idx];
                float lum = dot(vpl_luminance_albedo(ax), v0.flux);
                vec3 gw = lum > 0.0 ? ax * v0.flux * (r.target * r.weight * ug.w / lum) : vec3(0.0);
                fresh += beta * (ug.xyz - gw);
                added += uvec2(open.x, f0 != vec3(0.0) ? 1u : 0u);
            }
            float share = c0 / (c0 + c1);
            sum += m0 * e0 + m1 * e1 + share * (fresh - e0);
            // The reservoir kept: target p̂_u · V.
            float w0 = open.x != 0u ? m0 * t0 * r.weight : 0.0, w1 = open.y != 0u ? m1 * t1 * h.weight : 0.0;
            Reservoir o = empty_reservoir(c0 + c1);
            if (w0 + w1 > 0.0) {
                bool take1 = ris_rand(px, 2u, layer) * (w0 + w1) < w1;
                o.vpl = take1 ? h.vpl : r.vpl;
                o.target = take1 ? t1 : t0;
                o.weight = (w0 + w1) / o.target;
            }
            res_in[idx] = o;
            // The estimate's variance: with a history, about share / 2 · (l_fresh − l_history)² (the sum is
            // about a running mean of fresh estimates at rate share); without, the fresh one's square.
            float lf = luminance(demodulate(fresh, ax)), lh = luminance(demodulate(e1, ax));
            variance += kept ? 0.5 * share * (lf - lh) * (lf - lh) : lf * lf;
            if (ris.learned > 0.0) {
                uint base = vis_tile_base(px);
                if (f0 != vec3(0.0)) {
                    uint vi = base + 2u * vis_cell_of(r.vpl);
                    atomicAdd(vis_counts[vi], open.x);
                    atomicAdd(vis_counts[vi + 1u], 1u);
                }
                if (f1 != vec3(0.0)) {
                    uint vi = base + 2u * vis_cell_of(h.vpl);
                    atomicAdd(vis_counts[vi], open.y);
                    atomicAdd(vis_counts[vi + 1u], 1u);
                }
            }
        }
        float n = float(ris.reservoirs);
        sum /= n;
        variance /= n * n;
        if (ris.control != 0u) cv_counts[pixel] = uvec4(state.xy + added, 0u, 0u);
    }
    if (pc.add_direct != 0u) sum += texelFetch(direct_radiance, px, 0).rgb;
    if (pc.accumulate != 0u) sum += imageLoad(out_radiance, px).rgb;
    imageStore(out_radiance, px, vec4(sum, variance));
}
#else

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 gp = texelFetch(g_position, px, 0);
    vec3 sum = vec3(0.0);
    // Σ l_r and Σ l_r² over the reservoirs (the variance in alpha).
    vec2 moments = vec2(0.0);
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
        vec3 o = lifted_origin(x, nx);
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
            if (n > 0u) atomicAdd(rays_traced, n);
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
                vec3 before = sum;
#ifdef SHADE_QUEUE
                // contribution_of's value: the unshadowed contribution, or 0 where the block's queued ray (the
                // next one) was occluded.
                vec3 c = vpl_unshadowed(x, nx, ax, vpl, pc.clamp_d2);
                if (c != vec3(0.0) && (visible & (1u << ray++)) == 0u) c = vec3(0.0);
#else
                // contribution_of, with its visibility test counted.
                vec3 c = vpl_unshadowed(x, nx, ax, vpl, pc.clamp_d2);
                if (c != vec3(0.0)) {
                    atomicAdd(rays_traced, 1u);
                    if (!segment_open(x, nx, r.vpl, vpl)) c = vec3(0.0);
                }
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
                // (An empty reservoir's l_r is 0: it adds nothing to either sum.)
                float l_r = luminance(demodulate(sum - before, ax));
                moments += vec2(l_r, l_r * l_r);
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
    float n = float(ris.reservoirs), variance = 0.0;
    if (pc.first == 0u && pc.last == ris.reservoirs && ris.reservoirs > 1u) {
        variance = max(moments.y - moments.x * moments.x / n, 0.0) / (n * (n - 1.0));
    }
    if (pc.add_direct != 0u) sum += texelFetch(direct_radiance, px, 0).rgb;
    if (pc.accumulate != 0u) sum += imageLoad(out_radiance, px).rgb;
    imageStore(out_radiance, px, vec4(sum, variance));
}
#endif
