#version 460
// gather: one-bounce indirect radiance at each G-buffer pixel from VPLs, visibility by a voxel march.
//   L(x) = 1/N Σ_k albedo(x)/π · Φ_v · (cos θ_v / π) · cos θ_x / d² · V(x, v) / p_v
// GATHER_SAMPLE: N VPLs drawn from the mixture below (p_v its exact discrete probability).
// GATHER_ALL: every VPL of [first, last) with p_v = 1, N = 1, accumulated over dispatches: the converged
// VPL estimate. See crates/graph/src/passes/gather.rs for the sampling mixture.
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
#include "shared/vpl.glsl"

uint vpl_slots() { return 2u * frame.size.z * frame.size.w * frame.size.w; }
uint face_rows() { return frame.size.w; }
uint faces() { return 2u * frame.size.z; }

// Number of faces with weight in method section s (the faces FACE_UNIFORM chooses among).
uint live_faces(uint cb) {
    uint n = 0u;
    for (uint f = 0u; f < faces(); f++) {
        if (cdf_rows_total(cb, f * face_rows(), (f + 1u) * face_rows()) > 0.0) n++;
    }
    return n;
}

// Probability that method section s (CDF at cb) draws v, given its face choice (exact: see
// cdf_prob_rows).
float section_prob(uint cb, uint v, uint nlive) {
    uint all_rows = faces() * face_rows();
    if (pc.face_mode == FACE_RR) return cdf_prob_rows(cb, v, 0u, all_rows);
    uint f = v / (face_rows() * face_rows());
    if (!(cdf_rows_total(cb, f * face_rows(), (f + 1u) * face_rows()) > 0.0)) return 0.0;
    return cdf_prob_rows(cb, v, f * face_rows(), (f + 1u) * face_rows()) / float(nlive);
}

// The sampling mixture: with probability ε (or when no method section has weight) uniformly among the
// VPLs (section 0); otherwise a method section s chosen uniformly (local: the regions; else the one),
// whose face is chosen by its weight (Russian roulette, thesis alg. 9) or uniformly among the faces
// with weight, then the texel by the face's CDF. Returns v and its exact mixture probability
//   p_v = ε_eff · valid_v / #VPLs + (1 − ε_eff) · 1/S Σ_s P_s(v).
uint draw_vpl(inout uint rng, out float prob) {
    uint len = pc.cdf_len;
    uint n = vpl_slots();
    uint sections = pc.sections;
    float eps = pc.defensive;
    uint live = 0u;
    for (uint s = 1u; s <= sections; s++) live += cdf_total_at(s * len) > 0.0 ? 1u : 0u;
    if (live == 0u) eps = 1.0; // all-zero importance: uniform (the host warns)
    float u0 = rand01(rng), u1 = rand01(rng), u2 = rand01(rng);
    uint v;
    if (u0 < eps) {
        v = cdf_sample_rows(0u, 0u, u1, 0u, faces() * face_rows());
    } else {
        // A section uniformly among those with weight (a local region whose gather points all missed
        // has none).
        uint pick = min(uint(u1 * float(live)), live - 1u);
        uint s = 1u;
        for (uint k = 1u; k <= sections; k++) {
            if (cdf_total_at(k * len) > 0.0) {
                if (pick == 0u) { s = k; break; }
                pick--;
            }
        }
        uint cb = s * len;
        if (pc.face_mode == FACE_RR) {
            v = cdf_sample_rows(cb, s * n, u2, 0u, faces() * face_rows());
        } else {
            uint nlive = live_faces(cb);
            pick = min(uint(u2 * float(nlive)), nlive - 1u);
            float u3 = rand01(rng);
            uint f = 0u;
            for (uint k = 0u; k < faces(); k++) {
                if (cdf_rows_total(cb, k * face_rows(), (k + 1u) * face_rows()) > 0.0) {
                    if (pick == 0u) { f = k; break; }
                    pick--;
                }
            }
            v = cdf_sample_rows(cb, s * n, u3, f * face_rows(), (f + 1u) * face_rows());
        }
    }
    // The mixture probability of v.
    float method = 0.0;
    for (uint s = 1u; s <= sections; s++) {
        uint cb = s * len;
        if (!(cdf_total_at(cb) > 0.0)) continue;
        method += section_prob(cb, v, pc.face_mode == FACE_UNIFORM ? live_faces(cb) : 0u);
    }
    float uniform_p = cdf_prob_rows(0u, v, 0u, faces() * face_rows());
    prob = eps * uniform_p + (live > 0u ? (1.0 - eps) * method / float(live) : 0.0);
    return v;
}

vec3 contribution(vec3 x, vec3 nx, vec3 ax, uint v) {
    Vpl vpl = vpl_fetch(v);
    vec3 c = vpl_unshadowed(x, nx, ax, vpl, pc.clamp_d2);
    if (c == vec3(0.0)) return c;
    return c * voxel_visibility(x, nx, vpl.position, vpl.normal);
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
            for (uint v = pc.first; v < pc.last; v++) sum += contribution(x, nx, ax, v);
        } else if (cdf_total_at(0u) > 0.0) {
            // Samples [first, last) of N: each sample's random numbers depend on (pixel, seed, sample)
            // only, so splitting the samples over dispatches does not change the image.
            uint base = pcg_hash(uint(px.x) + 65536u * uint(px.y)) ^ pc.seed;
            for (uint k = pc.first; k < pc.last; k++) {
                uint rng = pcg_hash(base ^ pcg_hash(k + 0x9E3779B9u));
                float prob;
                uint v = draw_vpl(rng, prob);
                if (prob > 0.0) sum += contribution(x, nx, ax, v) / prob;
            }
            sum /= float(pc.samples);
        }
    }
    if (pc.add_direct != 0u) sum += texelFetch(direct_radiance, px, 0).rgb;
    if (pc.accumulate != 0u) sum += imageLoad(out_radiance, px).rgb;
    imageStore(out_radiance, px, vec4(sum, 1.0));
}
