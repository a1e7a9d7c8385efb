// The scene's buffers, bound at the same bindings by every pass that reads the mesh.
#ifndef BOUNCE_SCENE_GLSL
#define BOUNCE_SCENE_GLSL
#include "types.glsl"
#include "bindings.glsl"
#include "common.glsl"

layout(set = 0, binding = B_FRAME) uniform FrameBlock { FrameUniforms frame; };
layout(std430, set = 0, binding = B_VERTICES) readonly buffer Vertices { Vertex vertices[]; };
layout(std430, set = 0, binding = B_TRI_MATERIAL) readonly buffer TriMaterials { uint tri_material[]; };
layout(std430, set = 0, binding = B_MATERIALS) readonly buffer Materials { Material materials[]; };
layout(std430, set = 0, binding = B_TEXTURES) readonly buffer Textures { TextureInfo textures[]; };
layout(std430, set = 0, binding = B_TEXELS) readonly buffer Texels { uint texels[]; };
layout(std430, set = 0, binding = B_LIGHTS) readonly buffer Lights { Light lights[]; };

#include "lightmap.glsl"

// Albedo of triangle `tri` at texture coordinate `uv`: Kd × the nearest map_Kd texel (sRGB-decoded),
// repeat wrap, v flipped (OBJ v = 0 is the bottom row of the image). The CPU reference does the same.
layout(constant_id = SPEC_TEXTURED) const bool TEXTURED = true;

vec3 albedo_at(uint tri, vec2 uv) {
    Material m = materials[tri_material[tri]];
    vec3 kd = m.kd_tex.rgb;
    // Specialised away for untextured scenes (the driver drops the fetch path).
    if (!TEXTURED || m.kd_tex.w < 0.0) return kd;
    TextureInfo t = textures[uint(m.kd_tex.w)];
    uint x = min(uint(floor(fract(uv.x) * float(t.width))), t.width - 1u);
    uint y = min(uint(floor(fract(1.0 - uv.y) * float(t.height))), t.height - 1u);
    uint p = texels[t.offset + y * t.width + x];
    vec3 c = vec3(float(p & 255u), float((p >> 8) & 255u), float((p >> 16) & 255u)) / 255.0;
    return kd * vec3(srgb_to_linear(c.r), srgb_to_linear(c.g), srgb_to_linear(c.b));
}

#endif
