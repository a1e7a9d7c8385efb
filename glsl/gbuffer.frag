#version 460
// gbuffer: world position, camera-facing shading normal and albedo per pixel.
#include "shared/scene.glsl"

layout(location = 0) in vec3 i_position;
layout(location = 1) in vec3 i_normal;
layout(location = 2) in vec2 i_uv;

layout(location = 0) out vec4 o_position; // xyz world position, w = 1 where there is geometry (cleared to 0)
layout(location = 1) out vec4 o_normal;   // xyz unit normal facing the camera, w = triangle index (float bits)
layout(location = 2) out vec4 o_albedo;   // rgb albedo, w = 1

void main() {
    uint tri = uint(gl_PrimitiveID);
    // The face normal only where the vertex normals cancel (fetched then, not for every fragment).
    vec3 n = shading_normal(i_normal, vec3(0.0));
    if (n == vec3(0.0)) n = triangle_normal(tri);
    // Two-sided surfaces: the shading normal faces the incoming (camera) direction.
    if (dot(n, frame.eye.xyz - i_position) < 0.0) n = -n;
    o_position = vec4(i_position, 1.0);
    o_normal = vec4(n, uintBitsToFloat(tri));
    o_albedo = vec4(albedo_at(tri, i_uv), 1.0);
}
