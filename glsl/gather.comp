#version 460
// gather: one-bounce indirect radiance at each G-buffer pixel from VPLs, visibility by a voxel march.
//   L(x) = 1/N Σ_k albedo(x)/π · Φ_v · (cos θ_v / π) · cos θ_x / d² · V(x, v) / p_v
// GATHER_SAMPLE: N VPLs drawn from the CDF (p_v its discrete probability). GATHER_ALL: every VPL of the
// tile [first, last) with p_v = 1, N = 1, accumulated over tiles: the converged VPL estimate.
// See crates/graph/src/passes/gather.rs.
#include "shared/scene.glsl"
#include "shared/voxel.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(push_constant) uniform Push { GatherPush pc; };

layout(set = 0, binding = B_GATHER_GPOSITION) uniform sampler2D g_position;
layout(set = 0, binding = B_GATHER_GNORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = B_GATHER_GALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = B_VPL_POSITION) uniform sampler2DArray vpl_position;
layout(set = 0, binding = B_VPL_NORMAL) uniform sampler2DArray vpl_normal;
layout(set = 0, binding = B_VPL_FLUX) uniform sampler2DArray vpl_flux;
layout(std430, set = 0, binding = B_IMPORTANCE) readonly buffer Importance { float importance[]; };
layout(std430, set = 0, binding = B_CDF) readonly buffer Cdf { float cdf[]; };
layout(set = 0, binding = B_GATHER_DIRECT) uniform sampler2D direct_radiance;
layout(set = 0, binding = B_GATHER_OUT, rgba32f) uniform image2D out_radiance;

#include "shared/cdf.glsl"

// Radiance at x (normal nx, albedo ax) from VPL v, before dividing by its probability.
vec3 vpl_contribution(vec3 x, vec3 nx, vec3 ax, uint v) {
    uint res = frame.size.w;
    ivec3 t = ivec3(v % res, (v / res) % res, v / (res * res));
    vec4 p = texelFetch(vpl_position, t, 0);
    if (p.w == 0.0) return vec3(0.0);
    vec3 ny = texelFetch(vpl_normal, t, 0).xyz;
    vec3 flux = texelFetch(vpl_flux, t, 0).rgb;
    vec3 w = p.xyz - x;
    float d2 = dot(w, w);
    if (d2 <= 0.0) return vec3(0.0);
    w *= inversesqrt(d2);
    float cos_x = dot(nx, w);
    float cos_v = -dot(ny, w);
    if (cos_x <= 0.0 || cos_v <= 0.0) return vec3(0.0);
    float vis = voxel_visibility(x, nx, p.xyz, ny);
    if (vis == 0.0) return vec3(0.0);
    return ax / PI * flux * (cos_v / PI) * cos_x / max(d2, pc.clamp_d2) * vis;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 gp = texelFetch(g_position, px, 0);
    vec3 sum = vec3(0.0);
    if (gp.w != 0.0) {
        vec3 x = gp.xyz;
        vec3 nx = texelFetch(g_normal, px, 0).xyz;
        vec3 ax = texelFetch(g_albedo, px, 0).rgb;
        if (pc.mode == GATHER_ALL) {
            for (uint v = pc.first; v < pc.last; v++) sum += vpl_contribution(x, nx, ax, v);
        } else if (cdf_total() > 0.0) {
            // Samples [first, last) of N: each sample's random number depends on (pixel, seed, sample)
            // only, so splitting the samples over dispatches does not change the image.
            uint base = pcg_hash(uint(px.x) + 65536u * uint(px.y)) ^ pc.seed;
            for (uint k = pc.first; k < pc.last; k++) {
                uint rng = pcg_hash(base ^ pcg_hash(k + 0x9E3779B9u));
                float prob;
                uint v = cdf_sample(rand01(rng), prob);
                sum += vpl_contribution(x, nx, ax, v) / prob;
            }
            sum /= float(pc.samples);
        }
    }
    if (pc.add_direct != 0u) sum += texelFetch(direct_radiance, px, 0).rgb;
    if (pc.accumulate != 0u) sum += imageLoad(out_radiance, px).rgb;
    imageStore(out_radiance, px, vec4(sum, 1.0));
}
