#version 460
// gbuffer: pulls the flat triangle list from the vertex buffer; see crates/graph/src/passes/gbuffer.rs.
#include "shared/scene.glsl"

layout(location = 0) out vec3 o_position;
layout(location = 1) out vec3 o_normal;
layout(location = 2) out vec2 o_uv;

void main() {
    Vertex v = vertices[gl_VertexIndex];
    o_position = v.position_u.xyz;
    o_normal = v.normal_v.xyz;
    o_uv = vec2(v.position_u.w, v.normal_v.w);
    gl_Position = frame.view_proj * vec4(v.position_u.xyz, 1.0);
}
