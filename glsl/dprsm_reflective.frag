#version 460
// dprsm (reflective): like dprsm.frag, the exact hit of each texel's ray (through the layer's random point
// in the texel, not its centre), plus the VPL it makes:
// world position, shading normal facing the light, and reflected flux
//   Φ_v = albedo(v) · I · Δω_v,   Δω_v = 4 / (1 + u² + v²)² · (2 / res)² (paraboloid faces)
// (the texel's solid angle seen from the light; the thesis's eqs. 7.1–7.3 leave it out, and without it
// the VPL sum does not converge to the one-bounce integral). With `--light-map rsm|cube` the faces are
// perspective and Δω_v is theirs (shared/lightmap.glsl). See crates/graph/src/passes/dprsm.rs. And the
// area of the surface patch the texel sees, A_v = Δω_v · d² / cos α (d the distance to the light, α
// between the triangle's face normal and the ray; cos α ≥ VPL_MIN_COS bounds a grazing patch), for the
// patch kernel of shared/vpl.glsl.
#include "shared/scene.glsl"
#include "shared/watertight.glsl"
#include "shared/map_depth.glsl"

// The map resolution per face.
layout(push_constant) uniform Push { ParaboloidPush pc; };

// Never nearer than the box's own depth (dprsm.geom's lower bound), so the depth test may run early.
layout(depth_greater) out float gl_FragDepth;

layout(location = 0) flat in vec3 i_a;
layout(location = 1) flat in vec3 i_b;
layout(location = 2) flat in vec3 i_c;
layout(location = 3) flat in uint i_tri;
layout(location = 4) flat in uint i_instance;

layout(location = 0) out vec4 o_position; // xyz world position, w = A_v > 0 (0 where empty: cleared)
layout(location = 1) out vec4 o_normal;   // xyz unit normal facing the light, w = distance to the light
layout(location = 2) out vec4 o_flux;     // rgb reflected flux (W), w = Δω (sr)

void main() {
    float res = float(pc.map_res);
    // The texel's ray passes at the frame's offset in it (dprsm.rs: a Cranley–Patterson rotation of the
    // texel grid, its own per layer), not at its centre.
    vec2 uv = (floor(gl_FragCoord.xy) + texel_offset(pc.offset, i_instance)) / res * 2.0 - 1.0;
    if (!lm_covers(uv)) discard;
    vec3 dir = lm_direction(uv);
    // Watertight, as in dprsm.frag: no texel ray slips between two triangles sharing an edge.
    float t;
    vec2 bary;
    if (!wt_hit_triangle_plane_t(wt_make_ray(vec3(0.0), dir), dir, i_a, i_b, i_c, t, bary) || !(t > 0.0)) discard;
    vec3 hit = vec3(t, bary);
    gl_FragDepth = map_texel_depth(t, frame.scene_max.w, gl_FragCoord.z);
    // On the triangle even where t came out short (slivers: shared/map_depth.glsl).
    vec4 point = map_texel_point(dir, t, bary, i_a, i_b, i_c, frame.scene_max.w, gl_FragCoord.z);
    t = point.w;

    uint face = i_instance % lm_faces(), li = i_instance / lm_faces();
    Light light = lights[li];
    vec3 world = light.position.xyz + lm_from_local(point.xyz, li, face);
    Vertex v0 = vertices[3u * i_tri], v1 = vertices[3u * i_tri + 1u], v2 = vertices[3u * i_tri + 2u];
    float w0 = 1.0 - hit.y - hit.z;
    vec3 n = normalize(w0 * v0.normal_v.xyz + hit.y * v1.normal_v.xyz + hit.z * v2.normal_v.xyz);
    if (dot(n, light.position.xyz - world) < 0.0) n = -n;
    vec2 tex = w0 * vec2(v0.position_u.w, v0.normal_v.w) + hit.y * vec2(v1.position_u.w, v1.normal_v.w)
             + hit.z * vec2(v2.position_u.w, v2.normal_v.w);
    float d_omega = lm_d_omega(uv, res);
    // The face normal, not the shading one: the patch is the triangle's. Floored so that the area stays a
    // positive normal float (w = 0 means "no VPL") at any scene scale.
    float cos_a = max(abs(dot(normalize(cross(i_b - i_a, i_c - i_a)), dir)), VPL_MIN_COS);
    o_position = vec4(world, max(d_omega * t * t / cos_a, 1e-30));
    o_normal = vec4(n, t);
    o_flux = vec4(albedo_at(i_tri, tex) * light.intensity.rgb * d_omega, d_omega);
}
