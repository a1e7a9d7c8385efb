#version 460
// ris, temporal stage (dispatch W × H × R, while last frame's reservoirs and surface are kept): each
// finished reservoir of the initial stage combined with last frame's final reservoir at the pixel's
// previous pixel q (passes/reproject.rs; none where the surface was disoccluded). Generalized balance
// weights m_i(y) = c_i p̂_i(y) / (c_0 p̂_0(y) + c_1 p̂_1(y)), p̂_0 this pixel's target and p̂_1 the target
// the history's sample was drawn for: at last frame's surface at q (its point, normal and albedo) with
// last frame's VPLs (B_PREV_VPL_*), the history's confidence capped at --temporal-cap times M. A VPL
// keeps its identity (its texel) when a light moves and is re-evaluated where it now is in p̂_0; with
// this frame's VPLs in p̂_1 instead, a VPL that moved towards x would weigh its history sample as if it
// had been drawn for its new place, and its contribution weight (drawn for the old one) makes a firefly:
// Sibenik under a light orbit had 4× the error of no temporal reuse. With the view and the lights
// unchanged q is the pixel itself and p̂_1 = p̂_0 (up to the albedo's unorm8), so the weights are the
// confidences'. The learned visibility's factor (at this pixel's tile) is in the resampling's target p̂_0
// alone, which cancels from the estimate and so may depend on anything; the weights m_i take the targets
// without it: its counts hold the ray last frame's shade traced for the history's own sample, and weights
// that depended on the sample they weigh would not average to the integral.
#define RIS_LEARNED_READ
#include "shared/ris.glsl"

layout(std430, set = 0, binding = B_RIS_OUT) buffer RisOut { Reservoir res_out[]; };
layout(std430, set = 0, binding = B_RIS_HISTORY) readonly buffer RisHistory { Reservoir res_history[]; };
layout(set = 0, binding = B_MOTION) uniform sampler2D motion;
layout(set = 0, binding = B_PREV_POSITION) uniform sampler2D prev_position;
layout(set = 0, binding = B_PREV_SURFACE) uniform usampler2D prev_surface;
layout(set = 0, binding = B_PREV_VPL_POSITION) uniform sampler2DArray prev_vpl_position;
layout(set = 0, binding = B_PREV_VPL_NORMAL) uniform sampler2DArray prev_vpl_normal;
layout(set = 0, binding = B_PREV_VPL_FLUX) uniform sampler2DArray prev_vpl_flux;

// Last frame's target at (x, n, a) for VPL v: with last frame's VPL maps.
float prev_target_at(vec3 x, vec3 n, vec3 a, uint v) {
    ivec3 t = vpl_texel(v);
    vec4 p = texelFetch(prev_vpl_position, t, 0);
    return target_of(x, n, a, vpl_from(p, texelFetch(prev_vpl_normal, t, 0).xyz, texelFetch(prev_vpl_flux, t, 0).rgb));
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    uint layer = gl_GlobalInvocationID.z;
    if (any(greaterThanEqual(px, ivec2(frame.size.xy))) || layer >= ris.reservoirs) return;
    vec4 gp = texelFetch(g_position, px, 0);
    if (gp.w == 0.0) return; // the initial stage left an empty reservoir, with no history to combine
    vec4 mv = texelFetch(motion, px, 0);
    if (mv.z == 0.0) return; // disoccluded: the reservoir stays this frame's own
    ivec2 q = ivec2(mv.xy);
    vec3 x = gp.xyz, nx = texelFetch(g_normal, px, 0).xyz, ax = texelFetch(g_albedo, px, 0).rgb;
    uvec4 su = texelFetch(prev_surface, q, 0);
    vec3 xq = texelFetch(prev_position, q, 0).xyz, nq = uintBitsToFloat(su.xyz), aq = unpackUnorm4x8(su.w).rgb;
    uint idx = res_index(px, layer);
    Reservoir r = res_out[idx];
    float m = float(ris.candidates);
    Reservoir h = res_history[res_index(q, layer)];
    float ch = min(h.confidence, ris.history_cap * m);
    bool has0 = r.vpl != RIS_NONE && r.weight > 0.0, has1 = h.vpl != RIS_NONE && h.weight > 0.0;
    // Each sample's target here and at q without the learned factor, (p̂_0, p̂_1), for the weights; and its
    // target here with it, for the resampling (r.target is the initial stage's, with it).
    vec2 t0 = has0 ? vec2(r.target / learned_at(px, r.vpl).x, prev_target_at(xq, nq, aq, r.vpl)) : vec2(0.0);
    vec2 t1 = has1 ? vec2(target_at(x, nx, ax, h.vpl), prev_target_at(xq, nq, aq, h.vpl)) : vec2(0.0);
    float here1 = has1 ? t1.x * learned_at(px, h.vpl).x : 0.0;
    float d0 = m * t0.x + ch * t0.y, d1 = m * t1.x + ch * t1.y;
    float w0 = d0 > 0.0 ? m * t0.x / d0 * r.target * r.weight : 0.0;
    float w1 = d1 > 0.0 ? ch * t1.y / d1 * here1 * h.weight : 0.0;
    float sum = w0 + w1;
    if (w1 > 0.0 && ris_rand(px, 2u, layer) * sum < w1) {
        r.vpl = h.vpl;
        r.target = here1;
    }
    r.weight = r.target > 0.0 && sum > 0.0 ? sum / r.target : 0.0;
    r.confidence = m + ch;
    if (!(r.weight > 0.0)) r = empty_reservoir(r.confidence);
    res_out[idx] = r;
}
