#version 460
// importance: one non-negative weight per DPRSM texel (VPL) and CDF section, the input of cdf_reduce.
//   IMP_UNIFORM: 1 for every texel holding a VPL (section 0: the validity map; also the defensive part).
//   IMP_GLOBAL (Ritschel et al. 2011): each VPL's average unshadowed contribution (luminance) to S gather
//     points drawn uniformly over the image.
//   IMP_STRATIFIED (thesis §7.3.2): the same with the S gather points spread over the 4 screen quarters.
//   IMP_LOCAL (§7.3.3): one section per region (side × side grid), each from S gather points of its region.
// Dispatch: res × res × (layers · sections written). See crates/graph/src/passes/importance.rs.
#include "shared/scene.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(push_constant) uniform Push { ImportancePush pc; };
layout(set = 0, binding = B_GATHER_GPOSITION) uniform sampler2D g_position;
layout(set = 0, binding = B_GATHER_GNORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = B_GATHER_GALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = B_VPL_POSITION) uniform sampler2DArray vpl_position;
layout(set = 0, binding = B_VPL_NORMAL) uniform sampler2DArray vpl_normal;
layout(set = 0, binding = B_VPL_FLUX) uniform sampler2DArray vpl_flux;
layout(std430, set = 0, binding = B_IMPORTANCE) writeonly buffer Importance { float importance[]; };

#include "shared/vpl.glsl"

// Gather point k of the set for `region` (−1: the whole image; −2: stratified quarters): a pixel.
ivec2 gather_point(uint k, int region) {
    uvec2 size = frame.size.xy;
    uvec2 lo = uvec2(0u), hi = size;
    if (region == -2) {
        uint q = k % 4u;
        uvec2 half_size = max(size / 2u, uvec2(1u));
        lo = uvec2(q % 2u, q / 2u) * half_size;
        hi = min(lo + half_size + uvec2(q % 2u == 1u ? size.x % 2u : 0u, q / 2u == 1u ? size.y % 2u : 0u), size);
    } else if (region >= 0) {
        uint side = pc.regions;
        uvec2 cell = uvec2(uint(region) % side, uint(region) / side);
        lo = cell * size / side;
        hi = max((cell + 1u) * size / side, lo + 1u);
    }
    uint h = pcg_hash(pcg_hash(k * 2654435761u + uint(region + 7)) ^ pc.seed);
    uvec2 extent = hi - lo;
    return ivec2(lo + uvec2(h % extent.x, pcg_hash(h) % extent.y));
}

void main() {
    uvec3 id = gl_GlobalInvocationID;
    uint res = frame.size.w;
    if (id.x >= res || id.y >= res) return;
    uint layers = faces();
    uint layer = id.z % layers;
    uint section = pc.section + id.z / layers;
    uint v = (layer * res + id.y) * res + id.x;
    uint texels = layers * res * res;
    Vpl vpl = vpl_fetch(v);
    float w = 0.0;
    if (pc.mode == IMP_UNIFORM) {
        w = vpl.valid ? 1.0 : 0.0;
    } else if (vpl.valid) {
        int region = pc.mode == IMP_GLOBAL ? -1 : (pc.mode == IMP_STRATIFIED ? -2 : int(section - pc.section));
        float sum = 0.0;
        uint n = 0u;
        for (uint k = 0u; k < pc.samples; k++) {
            ivec2 px = gather_point(k, region);
            vec4 p = texelFetch(g_position, px, 0);
            if (p.w == 0.0) continue;
            n++;
            sum += luminance(vpl_unshadowed(p.xyz, texelFetch(g_normal, px, 0).xyz, texelFetch(g_albedo, px, 0).rgb, vpl, pc.min_d2));
        }
        w = n > 0u ? sum / float(n) : 0.0;
    }
    importance[section * texels + v] = w;
}
