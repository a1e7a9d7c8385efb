#version 460
// Test kernel: voxel_visibility (glsl/shared/voxel.glsl) for a batch of segment pairs, exactly as a gather
// shader calls it. One invocation per pair; tests/tests/voxelize.rs compares the results with the CPU march
// (crates/graph/src/cpu_voxel.rs). Bindings: the scene's frame uniforms and B_VOXELS as in a real pass, the
// pairs at B_TEST_IN and the results at B_TEST_OUT (test-only numbers).
#include "../shared/scene.glsl"
#include "../shared/voxel.glsl"

layout(local_size_x = WG_1D) in;

struct Pair {
    vec4 x;  // xyz: surface point x
    vec4 nx; // xyz: its unit normal, facing y's side
    vec4 y;
    vec4 ny;
};
layout(std430, set = 0, binding = B_TEST_IN) readonly buffer Pairs { Pair pairs[]; };
layout(std430, set = 0, binding = B_TEST_OUT) writeonly buffer Results { float visibility[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(pairs.length())) return;
    Pair p = pairs[i];
    visibility[i] = voxel_visibility(p.x.xyz, p.nx.xyz, p.y.xyz, p.ny.xyz);
}
