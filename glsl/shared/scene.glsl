// The scene's buffers, bound at the same bindings by every pass that reads the mesh.
#ifndef BOUNCE_SCENE_GLSL
#define BOUNCE_SCENE_GLSL
#include "types.glsl"
#include "bindings.glsl"
#include "common.glsl"

layout(set = 0, binding = B_FRAME) uniform FrameBlock { FrameUniforms frame; };

// Where a ray leaving the surface at x on the side of nx starts: x lifted along nx (surface_lift), off its
// own triangle. Every traced ray from a surface point starts here: a pixel's shadow rays to VPLs and
// lights, its paths and gathering rays, and the reference's rays from its bounce points.
vec3 lifted_origin(vec3 x, vec3 nx) {
    return x + nx * surface_lift(x, frame.scene_min.w);
}

layout(std430, set = 0, binding = B_VERTICES) readonly buffer Vertices { Vertex vertices[]; };
layout(std430, set = 0, binding = B_TRI_MATERIAL) readonly buffer TriMaterials { uint tri_material[]; };
layout(std430, set = 0, binding = B_MATERIALS) readonly buffer Materials { Material materials[]; };
layout(std430, set = 0, binding = B_TEXTURES) readonly buffer Textures { TextureInfo textures[]; };
layout(std430, set = 0, binding = B_TEXELS) readonly buffer Texels { uint texels[]; };
layout(std430, set = 0, binding = B_LIGHTS) readonly buffer Lights { Light lights[]; };

// Triangle tri's unit face normal (its winding's side; 0 for a zero-area triangle), at any size
// (common.glsl's unit_direction).
vec3 triangle_normal(uint tri) {
    vec3 a = vertices[3u * tri].position_u.xyz;
    return unit_direction(cross(vertices[3u * tri + 1u].position_u.xyz - a, vertices[3u * tri + 2u].position_u.xyz - a));
}

#include "lightmap.glsl"

// The depth bias of a paraboloid shadow-map test (the per-VPL maps of `--visibility psm`): at
// map coordinates uv of a res² face, a point at distance d whose normal makes cos θ with the map's
// direction. The texel stores the depth along its centre direction, up to ~0.71 texel away from the
// point's; on a surface tilted by θ that changes the depth by ≈ d · Δangle · tan θ, the slope term. A
// texel's angular size is 2/(1+r²) · (2/res) radians. tan θ is capped: at grazing angles cos θ (and so
// the light) is tiny anyway. frame.shadow: x constant (world units), y slope scale (texels).
float paraboloid_shadow_bias(vec2 uv, int res, float d, float cos_theta) {
    float r2 = dot(uv, uv);
    float texel_angle = 2.0 / (1.0 + r2) * (2.0 / float(res));
    float tan_theta = min(sqrt(max(1.0 - cos_theta * cos_theta, 0.0)) / max(cos_theta, 1e-4), 50.0);
    return frame.shadow.x + frame.shadow.y * d * texel_angle * tan_theta;
}

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
