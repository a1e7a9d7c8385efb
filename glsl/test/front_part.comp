#version 460
// Test kernel: Q_v⁺ of glsl/shared/patch.glsl. For each case (s0, s1, s2) it builds the patch whose cut is
// s0 + s1·a + s2·b ≥ 0 (receiver at the origin facing +z; c = (0, 0, s0), e1 = (1, 0, s1), e2 = (0, 1, s2))
// and writes front_part's share of the square, then front_point at the 32 × 32 cell centres of [0, 1)²:
// floats [q·2049] = frac, [q·2049 + 1 + 2i, + 2] = point i. tests/tests/vpl.rs checks them against the
// exactly clipped square. Bindings B_TEST_IN (in) and B_TEST_OUT (out) are test-only numbers.
#include "../shared/bindings.glsl"
#include "../shared/patch.glsl"

layout(local_size_x = WG_1D) in;

layout(std430, set = 0, binding = B_TEST_IN) readonly buffer Cases { vec4 cases[]; };
layout(std430, set = 0, binding = B_TEST_OUT) writeonly buffer Outputs { float outputs[]; };

void main() {
    uint q = gl_GlobalInvocationID.x;
    if (q >= uint(cases.length())) return;
    vec3 s = cases[q].xyz;
    Patch pt;
    pt.c = vec3(0.0, 0.0, s.x);
    pt.n = vec3(0.0, 0.0, 1.0);
    pt.e1 = vec3(1.0, 0.0, s.y);
    pt.e2 = vec3(0.0, 1.0, s.z);
    pt.area = length(cross(pt.e1, pt.e2));
    FrontPart f = front_part(pt, vec3(0.0), vec3(0.0, 0.0, 1.0));
    uint base = q * 2049u;
    outputs[base] = f.frac;
    for (uint i = 0u; i < 1024u; i++) {
        vec2 u = (vec2(float(i % 32u), float(i / 32u)) + 0.5) / 32.0;
        vec2 ab = front_point(f, u);
        outputs[base + 1u + 2u * i] = ab.x;
        outputs[base + 2u + 2u * i] = ab.y;
    }
}
