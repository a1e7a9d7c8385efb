#version 460
// Test kernel: cdf_sample (glsl/shared/cdf.glsl) for a batch of random numbers u, exactly as gather.comp
// calls it: the importance buffer at B_IMPORTANCE and the CDF at B_CDF, declared as cdf.glsl's header
// asks, then the include. One invocation per u (so no invocation comes near llvmpipe's loop limit: a
// draw is two binary searches, ⌈log2 rows⌉ + ⌈log2 row_length⌉ iterations). tests/tests/cdf.rs compares
// the results with the CPU mirror (crates/graph/src/cpu_cdf.rs). Test-only bindings: the u values at 28,
// the results at 29 (outside bindings.glsl's range). Dispatches cover [first, first + count) of the u
// values, so a large batch can be split over several dispatches.
#include "../shared/bindings.glsl"

layout(local_size_x = WG_1D) in;
layout(push_constant) uniform Push {
    uint first;
    uint count;
} pc;

layout(std430, set = 0, binding = B_IMPORTANCE) readonly buffer Importance { float importance[]; };
layout(std430, set = 0, binding = B_CDF) readonly buffer Cdf { float cdf[]; };
layout(std430, set = 0, binding = 28) readonly buffer Us { float us[]; };
// x: the texel drawn; y: the bits of its probability.
layout(std430, set = 0, binding = 29) writeonly buffer Draws { uvec2 draws[]; };

#include "../shared/cdf.glsl"

void main() {
    if (gl_GlobalInvocationID.x >= pc.count) return;
    uint i = pc.first + gl_GlobalInvocationID.x;
    float prob;
    uint v = cdf_sample(us[i], prob);
    draws[i] = uvec2(v, floatBitsToUint(prob));
}
