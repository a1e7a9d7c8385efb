#version 460
// psm (select): the frame's shared VPL set for `--visibility psm`: sample k (k < N) draws one VPL from
// the method's CDF mixture exactly as a gather sample does (draw_vpl, shared/sampling.glsl): point k of
// one stratified set per seed (not per pixel), so every pixel uses the same N VPLs and the same N shadow maps
// (thesis Fig. 6.1). The gather then weights sample k by 1/(N p_k): unbiased for the VPL sum given the
// maps' visibility. Writes PsmView k (probability 0 when there is no VPL to draw). Dispatch ⌈N/64⌉.
#include "shared/scene.glsl"
#include "shared/voxel.glsl"

layout(local_size_x = WG_1D) in;
layout(push_constant) uniform Push { GatherPush pc; };

layout(set = 0, binding = B_VPL_POSITION) uniform sampler2DArray vpl_position;
layout(set = 0, binding = B_VPL_NORMAL) uniform sampler2DArray vpl_normal;
layout(set = 0, binding = B_VPL_FLUX) uniform sampler2DArray vpl_flux;
layout(std430, set = 0, binding = B_IMPORTANCE) readonly buffer Importance { float importance[]; };
layout(set = 0, binding = B_CDF) uniform usamplerBuffer cdf_texels;
layout(std430, set = 0, binding = B_PSM_VIEWS) writeonly buffer PsmViews { PsmView psm_views[]; };

#define CDF_SHAPE_FROM_FRAME
#include "shared/cdf.glsl"
#include "shared/vpl.glsl"
#include "shared/sampling.glsl"

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= pc.samples) return;
    PsmView w;
    w.position_v = vec4(0.0);
    w.normal_p = vec4(0.0, 0.0, 1.0, 0.0);
    if (cdf_total_at(0u) > 0.0) {
        float prob;
        uint v = draw_vpl(k, pcg_hash(pc.seed ^ 0x85EBCA6Bu), prob);
        Vpl vpl = vpl_fetch(v);
        if (prob > 0.0 && vpl.valid) {
            // Off its own surface, so that surface (z = −lift in the map's frame) falls outside the
            // hemisphere and cannot shadow what the VPL lights.
            vec3 c = vpl.position + vpl.normal * surface_lift(vpl.position, frame.scene_min.w);
            w.position_v = vec4(c, uintBitsToFloat(v));
            w.normal_p = vec4(vpl.normal, prob);
        }
    }
    psm_views[k] = w;
}
