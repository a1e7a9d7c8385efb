#version 460
// Test kernel: the normals of glsl/shared/common.glsl. Per case (a, b, c, interpolated), vec4 [2k] =
// unit_direction(cross(b − a, c − a)), the face normal as the light maps, the end balls and the
// reference make it, and [2k + 1] = shading_normal(interpolated, that face normal), as the G-buffer,
// the light maps and the reference make a surface's. tests/tests/stress.rs compares them with f64.
#include "../shared/bindings.glsl"
#include "../shared/common.glsl"

layout(local_size_x = WG_1D) in;

struct Case {
    vec4 a;
    vec4 b;
    vec4 c;
    vec4 interpolated;
};
layout(std430, set = 0, binding = B_TEST_IN) readonly buffer Cases { Case cases[]; };
layout(std430, set = 0, binding = B_TEST_OUT) writeonly buffer Outputs { vec4 outputs[]; };

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= uint(cases.length())) return;
    vec3 a = cases[k].a.xyz, b = cases[k].b.xyz, c = cases[k].c.xyz;
    vec3 face = unit_direction(cross(b - a, c - a));
    outputs[2u * k] = vec4(face, 0.0);
    outputs[2u * k + 1u] = vec4(shading_normal(cases[k].interpolated.xyz, face), 0.0);
}
