#version 460
// ris, spatial stage (dispatch W × H × R): the reservoir (input 0, canonical) combined with k neighbours'
// of the same layer by pairwise MIS weights (Bitterli 2022; Lin et al. 2022), each neighbour i paired with
// the canonical input alone: with S = Σ_{i ≥ 1} c_i and a = c_0 / S,
//   m_i(y) = (c_i / S) p̂_i(y) / (p̂_i(y) + a p̂_0(y)),  m_0(y) = Σ_{i ≥ 1} (c_i / S) a p̂_0(y) / (p̂_i(y) + a p̂_0(y)),
// which sum to 1 wherever p̂_0 > 0 (unbiased as the generalized balance weights c_i p̂_i / Σ_j c_j p̂_j,
// and equal to them, c_i / Σ c, where the targets agree), for 3k + 1 target evaluations instead of
// (k + 1)². With ris.control == RIS_CONTROL_REUSE (the last pass) it also writes the control variate's
// U_g = Σ_i m_i(y_i) f_x(y_i) W_i,
// the mean of f_x(y) W over this resampling's choice given its inputs (passes/ris.rs). The learned
// visibility's factor (at this pixel's tile) is in the resampling's target p̂_x alone, which cancels from
// the estimate; the weights m_i take the targets without it (its counts hold the rays traced for the
// inputs' own samples: weights depending on the sample they weigh would not average to the integral).
// The control's g is f · s (s the learned guess at this pixel's tile) as in the initial stage.
#define RIS_LEARNED_READ
#include "shared/ris.glsl"

layout(std430, set = 0, binding = B_RIS_IN) readonly buffer RisIn { Reservoir res_in[]; };
layout(std430, set = 0, binding = B_RIS_OUT) buffer RisOut { Reservoir res_out[]; };
// (A stand-in of one vec4 is bound when the pass writes no U_g.)
layout(std430, set = 0, binding = B_RIS_UNSHADOWED) writeonly buffer RisUnshadowed { vec4 unshadowed[]; };

// Whether neighbour q may lend its reservoir to p: both see geometry, their normals within ~25° and their
// distances from the eye within 10 % (a deterministic function of the two G-buffer texels).
bool similar(vec4 gp, vec3 np, vec4 gq, vec3 nq) {
    if (gq.w == 0.0) return false;
    float dp = distance(gp.xyz, frame.eye.xyz), dq = distance(gq.xyz, frame.eye.xyz);
    return dot(np, nq) >= 0.9 && abs(dq - dp) <= 0.1 * dp;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    uint layer = gl_GlobalInvocationID.z;
    if (any(greaterThanEqual(px, ivec2(frame.size.xy))) || layer >= ris.reservoirs) return;
    uint idx = res_index(px, layer);
    Reservoir canonical = res_in[idx];
    vec4 gp = texelFetch(g_position, px, 0);
    if (gp.w == 0.0) {
        res_out[idx] = canonical;
        if (ris.control == RIS_CONTROL_REUSE) unshadowed[idx] = vec4(0.0);
        return;
    }
    // The inputs: 0 the pixel itself, then the accepted neighbours (at most RIS_MAX_NEIGHBORS).
    ivec2 q[RIS_MAX_NEIGHBORS + 1];
    vec3 xs[RIS_MAX_NEIGHBORS + 1], ns[RIS_MAX_NEIGHBORS + 1], albs[RIS_MAX_NEIGHBORS + 1];
    q[0] = px;
    xs[0] = gp.xyz;
    ns[0] = texelFetch(g_normal, px, 0).xyz;
    albs[0] = texelFetch(g_albedo, px, 0).rgb;
    uint n = 1u;
    uint tries = min(ris.neighbors, uint(RIS_MAX_NEIGHBORS));
    for (uint j = 0u; j < tries; j++) {
        // A point of the disc of radius `radius` (by the hash of pixel, seed, pass, layer and j).
        uint stream = 16u + ris.pass * 64u + j;
        float a = 2.0 * PI * ris_rand(px, stream, 2u * layer), rr = ris.radius * sqrt(ris_rand(px, stream, 2u * layer + 1u));
        ivec2 c = px + ivec2(round(rr * vec2(cos(a), sin(a))));
        if (c == px || any(lessThan(c, ivec2(0))) || any(greaterThanEqual(c, ivec2(frame.size.xy)))) continue;
        vec4 gq = texelFetch(g_position, c, 0);
        vec3 nq = texelFetch(g_normal, c, 0).xyz;
        if (!similar(gp, ns[0], gq, nq)) continue;
        q[n] = c;
        xs[n] = gq.xyz;
        ns[n] = nq;
        albs[n] = texelFetch(g_albedo, c, 0).rgb;
        n++;
    }
    Reservoir inputs[RIS_MAX_NEIGHBORS + 1];
    inputs[0] = canonical;
    float confidence = canonical.confidence;
    for (uint i = 1u; i < n; i++) {
        inputs[i] = res_in[res_index(q[i], layer)];
        confidence += inputs[i].confidence;
    }
    // Resample: input i's sample y_i weighs m_i(y_i) · p̂_x(y_i) · W_i, m_i the pairwise weights (above).
    Reservoir r = empty_reservoir(confidence);
    float sum = 0.0;
    vec3 ug = vec3(0.0);
    // The kept VPL's s / (p̂ / luminance(f)) (the initial stage's u.w): 1 without the learned visibility.
    float ratio = 1.0;
    // S, the neighbours' confidence, and a = c_0 / S, the canonical input's share in each pair.
    float s_n = confidence - canonical.confidence, a = s_n > 0.0 ? canonical.confidence / s_n : 0.0;
    for (uint i = 0u; i < n; i++) {
        Reservoir in_i = inputs[i];
        if (in_i.vpl == RIS_NONE || !(in_i.weight > 0.0)) continue;
        Vpl vpl = vpl_fetch(in_i.vpl);
        vec2 learned_here = learned_at(px, in_i.vpl);
        // p̂_0 without the learned factor (the weights') and with it (the resampling's).
        float p0 = target_of(xs[0], ns[0], albs[0], vpl), here = p0 * learned_here.x;
        float m = 0.0;
        if (n == 1u) {
            m = 1.0;
        } else if (i == 0u) {
            // m_0(y) = Σ_j (c_j / S) · a p̂_0(y) / (p̂_j(y) + a p̂_0(y)).
            for (uint j = 1u; j < n; j++) {
                float d = target_of(xs[j], ns[j], albs[j], vpl) + a * p0;
                m += d > 0.0 ? inputs[j].confidence / s_n * a * p0 / d : 0.0;
            }
        } else {
            // m_i(y) = (c_i / S) · p̂_i(y) / (p̂_i(y) + a p̂_0(y)).
            float own = target_of(xs[i], ns[i], albs[i], vpl), d = own + a * p0;
            m = d > 0.0 ? in_i.confidence / s_n * own / d : 0.0;
        }
        float w = m * here * in_i.weight;
        if (!(w > 0.0)) continue;
        sum += w;
        // m_i g_x(y_i) W_i = w_i f_x(y_i) s(y_i) / p̂_x(y_i), p̂_x = luminance(f_x) · max(V̂, δ).
        if (ris.control == RIS_CONTROL_REUSE) {
            ug += w / here * learned_here.y * vpl_unshadowed(xs[0], ns[0], albs[0], vpl, pc.clamp_d2);
        }
        if (ris_rand(px, 8u + ris.pass, layer * 16u + i) * sum < w) {
            r.vpl = in_i.vpl;
            r.target = here;
            ratio = learned_here.y / learned_here.x;
        }
    }
    r.weight = r.vpl != RIS_NONE ? sum / r.target : 0.0;
    if (!(r.weight > 0.0)) r = empty_reservoir(confidence);
    res_out[idx] = r;
    if (ris.control == RIS_CONTROL_REUSE) unshadowed[idx] = vec4(r.vpl != RIS_NONE ? ug : vec3(0.0), ratio);
}
