#version 460
// dprsm: the reflective light map by ray casting. Each texel's ray leaves the light through the layer's
// random point in the texel (not its centre) and finds its first surface through the BVH; the hit is the
// texel's VPL: world position, shading normal facing the light, and reflected flux
//   Φ_v = albedo(v) · I · Δω_v,   Δω_v = 4 / (1 + u² + v²)² · (2 / res)² (paraboloid faces)
// (the texel's solid angle seen from the light; the thesis's eqs. 7.1–7.3 leave it out, and without it
// the VPL sum does not converge to the one-bounce integral). With `--light-map rsm|cube` the faces are
// perspective and Δω_v is theirs (shared/lightmap.glsl). And the area of the surface patch the texel sees,
// A_v = Δω_v · d² / cos α (d the distance to the light, α between the triangle's face normal and the ray;
// cos α ≥ VPL_MIN_COS bounds a grazing patch), for the patch kernel of shared/vpl.glsl.
// See crates/graph/src/passes/dprsm.rs.
#include "shared/scene.glsl"
#include "shared/bvh.glsl"
#include "shared/map_depth.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

// The map resolution per face and layer 0's texel offset.
layout(push_constant) uniform Push { ParaboloidPush pc; };

layout(set = 0, binding = B_DPRSM_POSITION_OUT, rgba32f) uniform writeonly image2DArray o_position;
layout(set = 0, binding = B_DPRSM_NORMAL_OUT, rgba32f) uniform writeonly image2DArray o_normal;
layout(set = 0, binding = B_DPRSM_FLUX_OUT, rgba32f) uniform writeonly image2DArray o_flux;

// The texel's VPL; all zero where its ray leaves the scene (or the face).
void texel_vpl(ivec3 id, out vec4 position, out vec4 normal, out vec4 flux) {
    position = vec4(0.0);
    normal = vec4(0.0);
    flux = vec4(0.0);
    float res = float(pc.map_res);
    uint layer = uint(id.z);
    vec2 uv = (vec2(id.xy) + texel_offset(pc.offset, layer)) / res * 2.0 - 1.0;
    if (!lm_covers(uv)) return;
    uint face = layer % lm_faces(), li = layer / lm_faces();
    Light light = lights[li];
    vec3 dir = lm_direction(uv);
    float far = frame.scene_max.w;
    uint tri;
    vec2 bary;
    float t = bvh_closest_walk(light.position.xyz, lm_from_local(dir, li, face), far, tri, bary);
    if (!(t > 0.0)) return;
    // The hit again in the map's frame (the light at the origin), as the rasterized map computed it: t from
    // the triangle's plane, exact at grazing angles, and the point on the triangle where t came out short
    // (slivers: shared/map_depth.glsl). Where rounding in this frame misses the triangle that the world
    // frame's test crossed (a ray through an edge), the world frame's t and weights stand.
    Vertex v0 = vertices[3u * tri], v1 = vertices[3u * tri + 1u], v2 = vertices[3u * tri + 2u];
    vec3 a = lm_to_local(v0.position_u.xyz - light.position.xyz, li, face);
    vec3 b = lm_to_local(v1.position_u.xyz - light.position.xyz, li, face);
    vec3 c = lm_to_local(v2.position_u.xyz - light.position.xyz, li, face);
    float t_local;
    vec2 bary_local;
    if (wt_hit_triangle_plane_t(wt_make_ray(vec3(0.0), dir), dir, a, b, c, t_local, bary_local) && t_local > 0.0) {
        t = t_local;
        bary = bary_local;
    }
    vec4 point = map_texel_point(dir, t, bary, a, b, c, far, map_box_depth(a, b, c, far));
    t = point.w;
    vec3 world = light.position.xyz + lm_from_local(point.xyz, li, face);
    float w0 = 1.0 - bary.x - bary.y;
    vec3 n = shading_normal(w0 * v0.normal_v.xyz + bary.x * v1.normal_v.xyz + bary.y * v2.normal_v.xyz, vec3(0.0));
    if (n == vec3(0.0)) n = triangle_normal(tri); // vertex normals that cancel here
    if (dot(n, light.position.xyz - world) < 0.0) n = -n;
    vec2 tex = w0 * vec2(v0.position_u.w, v0.normal_v.w) + bary.x * vec2(v1.position_u.w, v1.normal_v.w)
             + bary.y * vec2(v2.position_u.w, v2.normal_v.w);
    float d_omega = lm_d_omega(uv, res);
    // The face normal, not the shading one: the patch is the triangle's. Floored so that the area stays a
    // positive normal float (w = 0 means "no VPL") at any scene scale.
    float cos_a = max(abs(dot(unit_direction(cross(b - a, c - a)), dir)), VPL_MIN_COS);
    position = vec4(world, max(d_omega * t * t / cos_a, 1e-30));
    normal = vec4(n, t);
    flux = vec4(albedo_at(tri, tex) * light.intensity.rgb * d_omega, d_omega);
}

void main() {
    ivec3 id = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(id.xy, ivec2(pc.map_res)))) return;
    vec4 position, normal, flux;
    texel_vpl(id, position, normal, flux);
    imageStore(o_position, id, position);
    imageStore(o_normal, id, normal);
    imageStore(o_flux, id, flux);
}
