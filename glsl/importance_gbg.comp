#version 460
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
// importance (gathering-based global CDF, thesis §7.3.4), two stages:
//   IMP_GBG_SCATTER (one invocation per pixel): R cosine-distributed rays from the gather point (a
//     stratified set per pixel), each marched through the voxel grid to its first occupied cell (the
//     exact variant: to the surface it really hits); that point P is projected into each light's DPRSM, and when that texel's VPL is the surface at P
//     (the light sees it: within 3 cells), the VPL's unshadowed contribution (luminance) is added to its
//     sum and its hit count raised.
//     Sums are u64 fixed point (atomic adds of integers commute: the result does not depend on thread
//     order, so a seed gives one image).
//   IMP_GBG_RESOLVE (one invocation per texel): average = sum / count; texels holding a VPL that no ray
//     reached (holes) take the median of the averages of their reached 3×3 neighbours (same face).
// See crates/graph/src/passes/importance.rs.
#include "shared/scene.glsl"
#define VOXEL_BITS_ACCESS readonly
#include "shared/voxel.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(push_constant) uniform Push { ImportancePush pc; };
layout(set = 0, binding = B_GATHER_GPOSITION) uniform sampler2D g_position;
layout(set = 0, binding = B_GATHER_GNORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = B_GATHER_GALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = B_VPL_POSITION) uniform sampler2DArray vpl_position;
layout(set = 0, binding = B_VPL_NORMAL) uniform sampler2DArray vpl_normal;
layout(set = 0, binding = B_VPL_FLUX) uniform sampler2DArray vpl_flux;
layout(std430, set = 0, binding = B_IMPORTANCE) writeonly buffer Importance { float importance[]; };
layout(std430, set = 0, binding = B_GBG_SUM) buffer Sums { uint64_t sums[]; };
layout(std430, set = 0, binding = B_GBG_COUNT) buffer Counts { uint counts[]; };

#include "shared/vpl.glsl"
#include "shared/gathering.glsl"
#include "shared/owen_sobol.glsl"
#ifdef EXACT_VISIBILITY
// importance_gbg.exact.comp (`--visibility exact`): each ray's first hit is the real surface it meets
// (the BVH), from x lifted off its surface,
// instead of the entry point of the first occupied cell 2 cells off the surface.
#include "shared/bvh.glsl"
#define FIRST_HIT_TRACE bvh_trace
bool first_hit(vec3 x, vec3 n, vec3 d, out vec3 hit) {
    uint tri;
    vec2 bary;
    vec3 o = lifted_origin(x, n);
    float t = FIRST_HIT_TRACE(o, d, 0.0, 1e30, false, tri, bary);
    hit = o + d * max(t, 0.0);
    return t > 0.0;
}
#else
bool first_hit(vec3 x, vec3 n, vec3 d, out vec3 hit) {
    return gathering_hit(x, n, d, hit);
}
#endif

void scatter(ivec2 px) {
    vec4 gp = texelFetch(g_position, px, 0);
    if (gp.w == 0.0) return;
    vec3 x = gp.xyz;
    vec3 n = texelFetch(g_normal, px, 0).xyz;
    vec3 a = texelFetch(g_albedo, px, 0).rgb;
    // The rays are the pixel's stratified set (shared/owen_sobol.glsl): R directions spread over the
    // hemisphere rather than clumped, so each pixel's few rays cover more of what it sees.
    uint seed = pcg_hash(uint(px.x) + 65536u * uint(px.y)) ^ pc.seed ^ 0x5bd1e995u;
    // Rays [first, first + regions) of the pixel's R (a dispatch's share under the loop limit).
    uint last = min(pc.samples, pc.first + pc.regions);
    for (uint r = pc.first; r < last; r++) {
        vec2 u = owen_sobol2(r, seed);
        vec3 d = cosine_direction(n, u.x, u.y);
        // One march per ray (2 cells off the surface, the march's rule), then each light's VPL there.
        vec3 p;
        if (!first_hit(x, n, d, p)) continue;
        for (uint l = 0u; l < frame.size.z; l++) {
            uint v = vpl_at_point(p, l);
            if (v == NO_VPL) continue;
            float c = luminance(vpl_unshadowed(x, n, a, vpl_fetch(v), pc.min_d2));
            if (!(c > 0.0)) continue;
            atomicAdd(sums[v], uint64_t(min(c * pc.fixed_scale, 4294967296.0)));
            atomicAdd(counts[v], 1u);
        }
    }
}

float average(uint v) {
    return float(sums[v]) / float(counts[v]) / pc.fixed_scale;
}

void resolve(uvec3 id) {
    uint res = frame.size.w;
    uint v = (id.z * res + id.y) * res + id.x;
    float w = 0.0;
    if (vpl_fetch(v).valid) {
        if (counts[v] > 0u) {
            w = average(v);
        } else {
            // A hole: the median of the reached neighbours (3×3, same face).
            float vals[8];
            int k = 0;
            for (int dy = -1; dy <= 1; dy++) {
                for (int dx = -1; dx <= 1; dx++) {
                    ivec2 q = ivec2(id.xy) + ivec2(dx, dy);
                    if ((dx == 0 && dy == 0) || any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(int(res))))) continue;
                    uint u = (id.z * res + uint(q.y)) * res + uint(q.x);
                    if (counts[u] == 0u) continue;
                    float a = average(u);
                    int j = k++;
                    while (j > 0 && vals[j - 1] > a) { vals[j] = vals[j - 1]; j--; }
                    vals[j] = a;
                }
            }
            if (k > 0) w = (k % 2 == 1) ? vals[k / 2] : 0.5 * (vals[k / 2 - 1] + vals[k / 2]);
        }
    }
    importance[pc.section * vpl_slots() + v] = w;
}

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (pc.mode == IMP_GBG_SCATTER) {
        if (id.x < frame.size.x && id.y < frame.size.y) scatter(ivec2(id.xy));
    } else {
        uint res = frame.size.w;
        if (id.x < res && id.y < res) resolve(id);
    }
}
