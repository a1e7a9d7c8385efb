#version 460
// Test kernel: the reference's sample points (glsl/shared/owen_sobol.glsl). For each input pair (index,
// seed) it writes (owen_sobol2(index, seed), owen_sobol1(index, seed), 0), so tests/tests/reference.rs can
// check the stratification on the CPU. Bindings B_TEST_IN (in) and B_TEST_OUT (out) are test-only numbers.
#include "../shared/bindings.glsl"
#include "../shared/common.glsl"
#include "../shared/owen_sobol.glsl"

layout(local_size_x = WG_1D) in;

layout(std430, set = 0, binding = B_TEST_IN) readonly buffer Inputs { uvec2 inputs[]; };
layout(std430, set = 0, binding = B_TEST_OUT) writeonly buffer Outputs { vec4 outputs[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(inputs.length())) return;
    uvec2 q = inputs[i];
    outputs[i] = vec4(owen_sobol2(q.x, q.y), owen_sobol1(q.x, q.y), 0.0);
}
