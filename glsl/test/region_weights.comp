#version 460
// Test kernel: `local`'s region blend (glsl/shared/regions.glsl). Each case is (pixel x, pixel y,
// width | height << 16, side); it writes the four entries' regions and weights: floats [q·8 + j] =
// region j, [q·8 + 4 + j] = weight j. tests/tests/vpl.rs checks them against the bilinear weights
// computed on the CPU and checks that they are continuous over the screen.
#include "../shared/bindings.glsl"
#include "../shared/regions.glsl"

layout(local_size_x = WG_1D) in;

layout(std430, set = 0, binding = B_TEST_IN) readonly buffer Cases { uvec4 cases[]; };
layout(std430, set = 0, binding = B_TEST_OUT) writeonly buffer Outputs { float outputs[]; };

void main() {
    uint q = gl_GlobalInvocationID.x;
    if (q >= uint(cases.length())) return;
    uvec4 c = cases[q];
    vec2 size = vec2(float(c.z & 0xFFFFu), float(c.z >> 16));
    uvec4 region;
    vec4 weight;
    region_weights(vec2(c.xy), size, c.w, region, weight);
    for (uint j = 0u; j < 4u; j++) {
        outputs[q * 8u + j] = float(region[j]);
        outputs[q * 8u + 4u + j] = weight[j];
    }
}
