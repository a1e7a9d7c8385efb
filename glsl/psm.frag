#version 460
// psm's per-VPL maps (depth only): exact per-texel depth. Each texel's centre direction is
// intersected with the (unclipped) triangle; the stored depth is that distance over `far`, so the map
// holds exactly what a ray cast from the viewpoint through the texel centre would hit.
#include "shared/scene.glsl"
#include "shared/watertight.glsl"
#include "shared/map_depth.glsl"

// The map resolution per face.
layout(push_constant) uniform Push { ParaboloidPush pc; };

// Never nearer than the box's own depth (psm.geom's lower bound), so the depth test may run early.
layout(depth_greater) out float gl_FragDepth;

layout(location = 0) flat in vec3 i_a;
layout(location = 1) flat in vec3 i_b;
layout(location = 2) flat in vec3 i_c;

void main() {
    vec2 uv = gl_FragCoord.xy / float(pc.map_res) * 2.0 - 1.0;
    if (dot(uv, uv) > 1.0) discard; // outside the map's one face: behind the VPL's surface, which it never lights
    // Watertight (shared/watertight.glsl), so a texel ray through an edge two triangles share hits one
    // of them: with Möller–Trumbore a few texel rays slipped out of a closed box around the light.
    vec3 dir = paraboloid_direction(uv);
    float t;
    vec2 bary;
    if (!wt_hit_triangle_plane_t(wt_make_ray(vec3(0.0), dir), dir, i_a, i_b, i_c, t, bary) || !(t > 0.0)) discard;
    // A sliver's t from the barycentric point, as the light maps place their VPLs (shared/map_depth.glsl).
    t = map_texel_point(dir, t, bary, i_a, i_b, i_c, frame.scene_max.w, gl_FragCoord.z).w;
    gl_FragDepth = map_texel_depth(t, frame.scene_max.w, gl_FragCoord.z);
}
