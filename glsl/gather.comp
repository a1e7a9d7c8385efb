#version 460
// gather: one-bounce indirect radiance at each G-buffer pixel from VPLs, visibility by a voxel march.
//   L(x) = 1/N Σ_k albedo(x)/π · Φ_v · (cos θ_v / π) · cos θ_x / d² · V(x, v) / p_v
// GATHER_SAMPLE: N VPLs drawn from the mixture below (p_v its exact discrete probability).
// GATHER_ALL: every VPL of [first, last) with p_v = 1, N = 1, accumulated over dispatches: the converged
// VPL estimate. See crates/graph/src/passes/gather.rs for the sampling mixture.
#include "shared/scene.glsl"
#include "shared/voxel.glsl"
#if defined(EXACT_VISIBILITY) || defined(HYBRID_VISIBILITY)
#include "shared/bvh.glsl"
#endif
#ifdef HYBRID_VISIBILITY
#include "shared/hybrid.glsl"
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

#include "shared/cdf.glsl"
#include "shared/vpl.glsl"
#include "shared/sampling.glsl"

#ifdef PSM_VISIBILITY
// `--visibility psm` (gather.psm.comp): sample k is VPL k of the frame's shared set (psm.comp), for
// every pixel, with visibility from its paraboloid shadow map. PSM_EXACT (gather.psm_exact.comp): the
// same shared set with exact shadow rays, which isolates the maps' own error.
layout(std430, set = 0, binding = B_PSM_VIEWS) readonly buffer PsmViews { PsmView psm_views[]; };
#ifndef PSM_EXACT
#define PSM_LOOKUP
layout(set = 0, binding = B_PSM_DEPTH) uniform sampler2DArray psm_depth;
#endif
#include "shared/psm.glsl"
#endif

#if defined(EXACT_VISIBILITY) && !defined(HYBRID_VISIBILITY) && !defined(PSM_VISIBILITY)
// Exact shadow rays, traced from a queue. A SIMD vector of invocations (llvmpipe: 8 lanes) runs the walk's
// steps until its slowest lane is done, so a loop of one ray per sample waits at every sample for the
// vector's longest ray, and a lane whose sample needs no ray (a VPL behind x) idles through it. Instead
// each block of GATHER_QUEUE samples is drawn first, its rays' ends and weighted contributions kept in
// the queue (only those that need a ray), and then every lane walks its own queue: a lane whose ray is
// done takes its next one at the next group of BVH_THREAD_UNROLL steps, so the vector waits only at the
// end of a block, for the lane with the most steps in all. The answers and the order of the sums are
// those of a ray per sample: the image is the same, bit for bit.
#define GATHER_REFILL
const uint GATHER_QUEUE = 32u;
vec3 queue_weight[GATHER_QUEUE]; // c(x, v) / p_v, the unshadowed contribution
vec3 queue_end[GATHER_QUEUE];    // the VPL's end of the shadow ray (shadow_end)

// Queue VPL v, drawn with probability prob (1 for `all`: c / 1 is c exactly), if it gives x anything.
void enqueue(vec3 x, vec3 nx, vec3 ax, uint v, float prob, inout uint n) {
    Vpl vpl = vpl_fetch(v);
    vec3 c = vpl_unshadowed(x, nx, ax, vpl, pc.clamp_d2);
    if (c == vec3(0.0)) return;
    queue_weight[n] = c / prob;
    queue_end[n] = shadow_end(v, vpl);
    n++;
}

// sum += queue_weight[j] for each j < n whose shadow ray o → queue_end[j] is not occluded, in order:
// bvh_occluded_lifted's answer, with its step bound per ray.
void trace_queue(vec3 o, uint n, inout vec3 sum) {
    int end = textureSize(bvh_threaded) / 3;
    const float tmin = BVH_LIFTED_EPS, tmax = 1.0 - BVH_LIFTED_EPS;
    uint next = 0u;
    bool tracing = false;
    BvhRay r;
    vec3 w = vec3(0.0);
    int i = 0;
    uint steps = 0u;
    bool done = false, hit = false;
    while (tracing || next < n) {
        if (!tracing) {
            w = queue_weight[next];
            vec3 d = queue_end[next] - o;
            next++;
            if (!bvh_usable_ray(o, d, tmin, tmax)) {
                sum += w; // "no hit", as bvh_any_hit answers
                continue;
            }
            r = bvh_make_ray(o, d);
            i = 0;
            steps = 0u;
            done = false;
            hit = false;
            tracing = true;
        }
        bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
        bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
        bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
        bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
        bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
        bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
        bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
        bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
        // Exhausted after BVH_MAX_STEPS steps: "no hit", as bvh_any_hit answers.
        if (done || steps >= uint(BVH_MAX_STEPS)) {
            if (!hit) sum += w;
            tracing = false;
        }
    }
}
#endif

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 gp = texelFetch(g_position, px, 0);
    vec3 sum = vec3(0.0);
    if (gp.w != 0.0) {
        vec3 x = gp.xyz;
        vec3 nx = texelFetch(g_normal, px, 0).xyz;
        vec3 ax = texelFetch(g_albedo, px, 0).rgb;
#ifdef GATHER_REFILL
        bool sampled = pc.mode != GATHER_ALL;
        if (!sampled || cdf_total_at(0u) > 0.0) {
            uint seed = pcg_hash(uint(px.x) + 65536u * uint(px.y)) ^ pc.seed;
            vec3 o = shadow_origin(x, nx);
            for (uint base = pc.first; base < pc.last; base += GATHER_QUEUE) {
                // Two loops, not one with `sampled ? draw_vpl(…) : k`: llvmpipe runs both sides of a
                // branch under masks, so the `all` mode would pay for drawing every VPL.
                uint n = 0u, top = min(base + GATHER_QUEUE, pc.last);
                if (sampled) {
                    for (uint k = base; k < top; k++) {
                        float prob;
                        uint v = draw_vpl(k, seed, prob);
                        if (prob > 0.0) enqueue(x, nx, ax, v, prob, n);
                    }
                } else {
                    for (uint v = base; v < top; v++) enqueue(x, nx, ax, v, 1.0, n);
                }
                trace_queue(o, n, sum);
            }
            if (sampled) sum /= float(pc.samples);
        }
#else
        if (pc.mode == GATHER_ALL) {
            for (uint v = pc.first; v < pc.last; v++) sum += contribution(x, nx, ax, v);
        } else if (cdf_total_at(0u) > 0.0) {
            // Samples [first, last) of N: each sample's random numbers depend on (pixel, seed, sample)
            // only, so splitting the samples over dispatches does not change the image.
#ifdef PSM_VISIBILITY
            for (uint k = pc.first; k < pc.last; k++) {
                PsmView w = psm_views[k];
                float prob = w.normal_p.w;
                if (!(prob > 0.0)) continue;
                uint v = floatBitsToUint(w.position_v.w);
#ifdef PSM_EXACT
                sum += contribution(x, nx, ax, v) / prob;
#else
                vec3 c = vpl_unshadowed(x, nx, ax, vpl_fetch(v), pc.clamp_d2);
                if (c != vec3(0.0)) sum += c * psm_visible(k, x, nx) / prob;
#endif
            }
#else
            // Sample k is point k of the pixel's stratified set (draw_vpl): a seed per pixel decorrelates
            // neighbours, and progressive frames (seed, seed + 1, …) are independent scrambles.
            uint seed = pcg_hash(uint(px.x) + 65536u * uint(px.y)) ^ pc.seed;
            for (uint k = pc.first; k < pc.last; k++) {
                float prob;
                uint v = draw_vpl(k, seed, prob);
                if (prob > 0.0) sum += contribution(x, nx, ax, v) / prob;
            }
#endif
            sum /= float(pc.samples);
        }
#endif
    }
    if (pc.add_direct != 0u) sum += texelFetch(direct_radiance, px, 0).rgb;
    if (pc.accumulate != 0u) sum += imageLoad(out_radiance, px).rgb;
    imageStore(out_radiance, px, vec4(sum, 1.0));
}
