#version 460
// Test kernel: the sampling functions of glsl/shared/cdf.glsl, called as gather.comp calls them: the
// importance buffer at B_IMPORTANCE and the CDF at B_CDF, declared as cdf.glsl's header asks, then the
// include. tests/tests/cdf.rs compares the results with the CPU twin (crates/graph/src/cpu_cdf.rs).
// Modes (pc.mode):
//   0: cdf_sample(u) over section 0               → (texel, bits of its probability)
//   1: cdf_sample_rows(cb, ib, u, r0, r1)          → (texel, bits of cdf_prob_rows(cb, texel, r0, r1))
//   2: texel i = invocation, no u                  → (i, bits of cdf_prob_rows(cb, i, r0, r1))
//   3: cdf_sample_rows3_prob as mode 1 draws        → (texel, bits of the probability the draw gives)
// One invocation per u (or texel): a draw is two binary searches, ⌈log2 rows⌉ + ⌈log2 row_length⌉
// iterations, far below llvmpipe's loop limit. Test-only bindings: the u values at B_TEST_IN, the results
// at B_TEST_OUT. A dispatch covers [first, first + count), so a large batch can be split over several
// dispatches.
#include "../shared/bindings.glsl"

layout(local_size_x = WG_1D) in;
layout(push_constant) uniform Push {
    uint first;
    uint count;
    uint mode;
    uint cb; // the section's first CDF float
    uint ib; // the section's first importance float
    uint r0; // rows [r0, r1) for modes 1 and 2
    uint r1;
    uint pad;
} pc;

layout(std430, set = 0, binding = B_IMPORTANCE) readonly buffer Importance { float importance[]; };
layout(set = 0, binding = B_CDF) uniform usamplerBuffer cdf_texels;
layout(std430, set = 0, binding = B_TEST_IN) readonly buffer Us { float us[]; };
layout(std430, set = 0, binding = B_TEST_OUT) writeonly buffer Results { uvec2 results[]; };

#include "../shared/cdf.glsl"

void main() {
    if (gl_GlobalInvocationID.x >= pc.count) return;
    uint i = pc.first + gl_GlobalInvocationID.x;
    uint v;
    float prob;
    if (pc.mode == 0u) {
        v = cdf_sample(us[i], prob);
    } else if (pc.mode == 1u) {
        v = cdf_sample_rows(pc.cb, pc.ib, us[i], pc.r0, pc.r1);
        prob = cdf_prob_rows(pc.cb, v, pc.r0, pc.r1);
    } else if (pc.mode == 3u) {
        v = cdf_sample_rows3_prob(pc.cb, pc.ib, cdf_uniforms(us[i]), pc.r0, pc.r1, prob);
    } else {
        v = i;
        prob = cdf_prob_rows(pc.cb, v, pc.r0, pc.r1);
    }
    results[i] = uvec2(v, floatBitsToUint(prob));
}
