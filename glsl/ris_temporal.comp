#version 460
// ris, temporal stage (dispatch W × H × R, only while last frame's reservoirs are kept: --temporal-cap > 0
// and the view unchanged): each finished reservoir of the initial stage combined with last frame's final
// reservoir at the same pixel and layer. The same G-buffer gives the same target, so the generalized
// balance weights reduce to the confidences, m_i = c_i / (c_0 + c_1), the history's capped at
// --temporal-cap times M.
#include "shared/ris.glsl"

layout(std430, set = 0, binding = B_RIS_OUT) buffer RisOut { Reservoir res_out[]; };
layout(std430, set = 0, binding = B_RIS_HISTORY) readonly buffer RisHistory { Reservoir res_history[]; };

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    uint layer = gl_GlobalInvocationID.z;
    if (any(greaterThanEqual(px, ivec2(frame.size.xy))) || layer >= ris.reservoirs) return;
    vec4 gp = texelFetch(g_position, px, 0);
    if (gp.w == 0.0) return; // the initial stage left an empty reservoir, with no history to combine
    vec3 x = gp.xyz, nx = texelFetch(g_normal, px, 0).xyz, ax = texelFetch(g_albedo, px, 0).rgb;
    uint idx = res_index(px, layer);
    Reservoir r = res_out[idx];
    float m = float(ris.candidates);
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
    if (!(r.weight > 0.0)) r = empty_reservoir(r.confidence);
    res_out[idx] = r;
}
