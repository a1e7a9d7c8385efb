#version 460
// gather: one-bounce indirect radiance at each G-buffer pixel from VPLs, visibility by a voxel march.
//   L(x) = 1/N Σ_k albedo(x)/π · Φ_v · (cos θ_v / π) · cos θ_x / d² · V(x, v) / p_v
// GATHER_SAMPLE: N VPLs drawn from the mixture below (p_v its exact discrete probability).
// GATHER_ALL: every VPL of [first, last) with p_v = 1, N = 1, accumulated over dispatches: the converged
// VPL estimate. See crates/graph/src/passes/gather.rs for the sampling mixture.
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

#define CDF_SHAPE_FROM_FRAME
#include "shared/cdf.glsl"
#include "shared/vpl.glsl"
#include "shared/sampling.glsl"

#ifdef PSM_VISIBILITY
// `--visibility psm` (gather.psm.comp): sample k is VPL k of the frame's shared set (psm.comp), for
// every pixel, with visibility from its paraboloid shadow map.
layout(std430, set = 0, binding = B_PSM_VIEWS) readonly buffer PsmViews { PsmView psm_views[]; };
#define PSM_LOOKUP
layout(set = 0, binding = B_PSM_DEPTH) uniform sampler2DArray psm_depth;
#include "shared/psm.glsl"
#endif

#ifdef EXACT_VISIBILITY
// Exact shadow rays from a queue (shared/shadow_queue.glsl): each block of SHADOW_QUEUE samples is drawn
// first, the rays it needs queued with their weighted contributions, and then traced by this invocation
// (shadow_queue_trace), which gives every ray bvh_occluded_lifted's answer.
#define GATHER_QUEUE
// The rays skip their ends' empty balls (pc.end_balls; passes/end_balls.rs): the same answers.
#define SHADOW_QUEUE_WINDOWS
#define END_BALLS_READ
#include "shared/end_balls.glsl"
vec3 ray_origin;   // x lifted (lifted_origin)
vec4 pixel_ball;   // x's ball (0: none)
#include "shared/shadow_queue.glsl"
vec3 queue_weight[SHADOW_QUEUE]; // c(x, v) / p_v, the unshadowed contribution

// Queue VPL v, drawn with probability prob (1 for `all`: c / 1 is c exactly), if it gives x anything.
void enqueue(vec3 x, vec3 nx, vec3 ax, uint v, float prob, inout uint n) {
    Vpl vpl = vpl_fetch(v);
    vec3 c = vpl_unshadowed(x, nx, ax, vpl, pc.clamp_d2);
    if (c == vec3(0.0)) return;
    queue_weight[n] = c / prob;
    vec3 e = shadow_end(v, vpl);
    shadow_queue_end[n] = e;
    shadow_queue_window[n] = end_ball_window(ray_origin, e, x, pixel_ball, v, vpl.position);
    n++;
}

// The gather with exact rays: blocks of SHADOW_QUEUE samples drawn, their rays traced, the visible ones
// summed in sample order (the sums of a ray per sample, bit for bit).
vec3 gather_queued(ivec2 px, bool inside) {
    bool sampled = pc.mode != GATHER_ALL;
    if (sampled && !(cdf_total_at(0u) > 0.0)) return vec3(0.0); // the same for every invocation
    ivec2 at = min(px, ivec2(frame.size.xy) - 1);
    vec4 gp = texelFetch(g_position, at, 0);
    bool shade = inside && gp.w != 0.0;
    if (!shade) return vec3(0.0);
    vec3 x = gp.xyz;
    vec3 nx = texelFetch(g_normal, at, 0).xyz;
    vec3 ax = texelFetch(g_albedo, at, 0).rgb;
    uint seed = pcg_hash(uint(px.x) + 65536u * uint(px.y)) ^ pc.seed;
    mixture_at_pixel(px);
    near_at_pixel(x);
    vec3 o = lifted_origin(x, nx);
    vec4 ball = end_ball_of_pixel(at);
    ray_origin = o;
    pixel_ball = ball;
    vec3 sum = vec3(0.0);
    for (uint base = pc.first; base < pc.last; base += SHADOW_QUEUE) {
        uint n = 0u, top = min(base + SHADOW_QUEUE, pc.last);
        if (shade) {
            // Two loops, not one with `sampled ? draw_vpl(…) : k`: llvmpipe runs both sides of a branch
            // under masks, so the `all` mode would pay for drawing every VPL.
            if (sampled) {
                for (uint k = base; k < top; k++) {
                    float prob;
                    uint v = draw_vpl(k, seed, prob);
                    if (prob > 0.0) enqueue(x, nx, ax, v, prob, n);
                }
            } else {
                for (uint v = base; v < top; v++) enqueue(x, nx, ax, v, 1.0, n);
            }
        }
        uint visible = shadow_queue_trace(o, n);
        for (uint j = 0u; j < n; j++)
            if ((visible & (1u << j)) != 0u) sum += queue_weight[j];
    }
    if (sampled) sum /= float(pc.samples);
    return sum;
}
#endif

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    bool inside = all(lessThan(px, ivec2(frame.size.xy)));
#ifdef GATHER_QUEUE
    vec3 sum = gather_queued(px, inside);
    if (!inside) return;
#else
    if (!inside) return;
    vec4 gp = texelFetch(g_position, px, 0);
    vec3 sum = vec3(0.0);
    if (gp.w != 0.0) {
        vec3 x = gp.xyz;
        vec3 nx = texelFetch(g_normal, px, 0).xyz;
        vec3 ax = texelFetch(g_albedo, px, 0).rgb;
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
                vec3 c = vpl_unshadowed(x, nx, ax, vpl_fetch(v), pc.clamp_d2);
                if (c != vec3(0.0)) sum += c * psm_visible(k, x, nx) / prob;
            }
#else
            // Sample k is point k of the pixel's stratified set (draw_vpl): a seed per pixel decorrelates
            // neighbours, and progressive frames (seed, seed + 1, …) are independent scrambles.
            uint seed = pcg_hash(uint(px.x) + 65536u * uint(px.y)) ^ pc.seed;
            mixture_at_pixel(px);
            near_at_pixel(x);
            for (uint k = pc.first; k < pc.last; k++) {
                float prob;
                uint v = draw_vpl(k, seed, prob);
                if (prob > 0.0) sum += contribution(x, nx, ax, v) / prob;
            }
#endif
            sum /= float(pc.samples);
        }
    }
#endif
    if (pc.add_direct != 0u) sum += texelFetch(direct_radiance, px, 0).rgb;
    if (pc.accumulate != 0u) sum += imageLoad(out_radiance, px).rgb;
    imageStore(out_radiance, px, vec4(sum, 1.0));
}
