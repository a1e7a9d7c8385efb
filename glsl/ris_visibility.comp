#version 460
// ris, visibility stage (dispatch W × H × R; `Method::Realtime`, after the temporal stage): each
// reservoir's sample tested by a shadow ray at its own pixel before it is reused (visibility reuse,
// Bitterli et al. 2020): an occluded sample is dropped (W = 0, the confidence kept), so the next frame's
// history and the neighbours lend samples that were visible where they were made. The reservoir is then
// a contribution weight for the target p̂ · V at this pixel; the spatial stage's balance weights keep
// evaluating p̂ without V at the other pixels, so a VPL visible here but hidden from a neighbour is
// weighted for that neighbour without being in its reservoir: a darkening, measured (BENCHMARKS.md,
// "Real time under motion"). One shadow ray per reservoir, counted with the shade's.
#include "shared/ris.glsl"

layout(std430, set = 0, binding = B_RIS_OUT) buffer RisOut { Reservoir res_out[]; };
layout(std430, set = 0, binding = B_RIS_RAYS) buffer RisRays { uint rays_traced; };

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    uint layer = gl_GlobalInvocationID.z;
    if (any(greaterThanEqual(px, ivec2(frame.size.xy))) || layer >= ris.reservoirs) return;
    vec4 gp = texelFetch(g_position, px, 0);
    if (gp.w == 0.0) return;
    uint idx = res_index(px, layer);
    Reservoir r = res_out[idx];
    if (!(r.vpl != RIS_NONE && r.weight > 0.0)) return;
    atomicAdd(rays_traced, 1u);
    if (!segment_open(gp.xyz, texelFetch(g_normal, px, 0).xyz, r.vpl, vpl_fetch(r.vpl))) {
        res_out[idx] = empty_reservoir(r.confidence);
    }
}
