#version 460
// Test kernel: voxel_rcp (glsl/shared/voxel.glsl) of every input float, so tests/tests/voxelize.rs can check
// that the GPU's reciprocal has the same bits as the CPU's (crates/graph/src/cpu_voxel.rs `rcp`). Bindings
// B_TEST_IN (in) and B_TEST_OUT (out) are test-only numbers.
#include "../shared/scene.glsl"
#include "../shared/voxel.glsl"

layout(local_size_x = WG_1D) in;

layout(std430, set = 0, binding = B_TEST_IN) readonly buffer Inputs { float inputs[]; };
layout(std430, set = 0, binding = B_TEST_OUT) writeonly buffer Outputs { float outputs[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(inputs.length())) return;
    outputs[i] = voxel_rcp(inputs[i]);
}
