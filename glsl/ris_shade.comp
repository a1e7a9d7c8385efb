#version 460
// ris, shade stage (dispatch W × H): L = 1/R Σ_r f(y_r) V(y_r) W_r over the reservoirs [first, last),
// visibility as the gather's (voxel, EXACT_VISIBILITY); with ris.control each term adds the unshadowed
// control variate β (U_g − g(y_r) W_r), mean 0 given the reservoir's candidates (ris.rs). The alpha
// channel holds the estimate's variance, from its R reservoirs' own estimates L_r (independent given the
// frame's inputs): with l_r the luminance of L_r demodulated by the albedo (the denoiser's signal),
// σ² = Σ_r (l_r − l̄)² / (R (R − 1)), the variance of their mean; 0 with one reservoir, or where one
// dispatch does not hold all R. The real-time frame's denoiser reads it, and its R = 2 reservoirs are
// split only where lavapipe's loop limit leaves fewer than 2 a dispatch (`vpls_per_dispatch`: a per-VPL
// bound over 32k iterations, thousands of lights); its luminance stop then sees no noise.
#include "shared/ris.glsl"

layout(set = 0, binding = B_GATHER_DIRECT) uniform sampler2D direct_radiance;
layout(set = 0, binding = B_GATHER_OUT, rgba32f) uniform image2D out_radiance;
layout(std430, set = 0, binding = B_RIS_IN) readonly buffer RisIn { Reservoir res_in[]; };
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
                    // The counts stop at RIS_VIS_COUNT_MAX rays (a tile's counts are kept across moves: hours
                    // of a 1080p view could wrap a uint, and (visible + 1) / (traced + 2) would pass 1). Any
                    // counts fixed before a choice keep the estimate unbiased.
                    if (atomicAdd(vis_counts[vi + 1u], 0u) < RIS_VIS_COUNT_MAX) {
                        if (c != vec3(0.0)) atomicAdd(vis_counts[vi], 1u);
                        atomicAdd(vis_counts[vi + 1u], 1u);
                    }
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
