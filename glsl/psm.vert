#version 460
// psm's maps: one instance per VPL of the shared set; the geometry shader does the paraboloid projection.
#include "shared/scene.glsl"

layout(location = 0) out vec3 o_world;
layout(location = 1) flat out uint o_instance;

void main() {
    o_world = vertices[gl_VertexIndex].position_u.xyz;
    o_instance = uint(gl_InstanceIndex);
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
