#version 460
// end_balls: each shadow-ray end's empty half-ball (shared/end_balls.glsl): per G-buffer pixel, or with
// END_BALLS_VPLS per VPL texel, rgba = (the end's plane normal, the ball's radius), 0 where there is no end or
// no ball. See crates/graph/src/passes/end_balls.rs.
#define END_BALLS_PASS
#include "shared/scene.glsl"
#include "shared/bvh.glsl"
#include "shared/end_balls.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;

#ifdef END_BALLS_VPLS
layout(set = 0, binding = B_VPL_POSITION) uniform sampler2DArray vpl_position;
layout(set = 0, binding = B_END_BALL_OUT, rgba32f) uniform writeonly image2DArray out_ball;
#else
layout(set = 0, binding = B_GATHER_GPOSITION) uniform sampler2D g_position;
layout(set = 0, binding = B_GATHER_GNORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = B_END_BALL_OUT, rgba32f) uniform writeonly image2D out_ball;
#endif

// Scene triangle tri's unit face normal, turned to the side of `toward`.
vec3 face_normal(uint tri, vec3 toward) {
    vec3 n = triangle_normal(tri);
    return dot(n, toward) < 0.0 ? -n : n;
}

// The ball of end p on triangle tri, whose ray leaves toward `side`.
vec4 ball_at(vec3 p, uint tri, vec3 side) {
    if (tri == BVH_NO_TRI) return vec4(0.0);
    vec3 n = face_normal(tri, side);
    if (!(dot(n, n) > 0.0)) return vec4(0.0); // a zero-area triangle has no plane
    return vec4(n, end_ball_radius(p, n, END_BALL_MAX_RADIUS * frame.scene_min.w));
}

void main() {
    ivec3 id = ivec3(gl_GlobalInvocationID);
#ifdef END_BALLS_VPLS
    ivec3 size = imageSize(out_ball);
    if (any(greaterThanEqual(id, size))) return;
    vec4 vp = texelFetch(vpl_position, id, 0);
    vec4 ball = vec4(0.0);
    if (vp.w != 0.0) {
        // The VPL's triangle: the light's first hit toward it (the map's texel ray, which found it). Its
        // shadow rays leave toward the light's side.
        vec3 light = lights[uint(id.z) / lm_faces()].position.xyz;
        uint tri;
        vec2 bary;
        bvh_closest_walk(light, vp.xyz - light, 2.0, tri, bary);
        ball = ball_at(vp.xyz, tri, light - vp.xyz);
    }
    imageStore(out_ball, id, ball);
#else
    if (any(greaterThanEqual(id.xy, imageSize(out_ball)))) return;
    vec4 gp = texelFetch(g_position, id.xy, 0);
    vec4 gn = texelFetch(g_normal, id.xy, 0);
    // The G-buffer's triangle and its camera-facing shading normal, along which the ray's origin is lifted.
    vec4 ball = gp.w != 0.0 ? ball_at(gp.xyz, floatBitsToUint(gn.w), gn.xyz) : vec4(0.0);
    imageStore(out_ball, id.xy, ball);
#endif
}
