// `--visibility` as the shaders see it (psm's shared set reads its maps instead: shared/psm.glsl).
#ifndef BOUNCE_VISIBILITY_GLSL
#define BOUNCE_VISIBILITY_GLSL
// Whether the segment between a pixel's point x and a VPL is open, for the frame's `--visibility`: the one
// answer every VPL pass asks (contribution_of in sampling.glsl; the gather's and ris's shade's queues
// trace the same rays from lifted_origin to shadow_end). Per pixel it is the voxel march (`voxel`), or
// with EXACT_VISIBILITY (the `*.exact.comp` variants, `exact`) a shadow ray against the real triangles
// (BVH) between points lifted off their surfaces (surface_lift in common.glsl): x along its normal, the
// VPL towards its light. Not the VPL along its normal: a VPL exactly on an edge of a closed box (a light at the
// box's centre puts texel rays exactly through its edges) lifted along one face's normal stays in the
// other face's plane, and its shadow rays left the box through that face (a sealed light leaked).
// Towards the light is always into the free space the light saw it from.
#if defined(EXACT_VISIBILITY) && defined(END_BALLS_READ)
// With the end balls read (mis.exact), x's ball for contribution_of's shadow ray: the caller sets it per
// pixel; 0 (no ball) leaves the VPL's ball alone to shorten the ray.
vec4 contribution_x_ball = vec4(0.0);
#endif
#ifdef EXACT_VISIBILITY
// The shadow ray's far end (its origin is lifted_origin, scene.glsl): VPL v lifted towards its light.
vec3 shadow_end(uint v, Vpl vpl) {
    vec3 light = lights[v / (lm_faces() * frame.size.w * frame.size.w)].position.xyz;
    return vpl.position + normalize(light - vpl.position) * surface_lift(vpl.position, frame.scene_min.w);
}
#endif

// Whether nothing lies between x (normal nx) and VPL v (its data `vpl`). The voxel march answers 0 or 1.
bool segment_open(vec3 x, vec3 nx, uint v, Vpl vpl) {
#ifdef EXACT_VISIBILITY
#ifdef END_BALLS_READ
    // bvh_occluded_lifted's ray, walked only between its ends' balls (the same answer).
    vec3 o = lifted_origin(x, nx), e = shadow_end(v, vpl);
    vec2 w = end_ball_window(o, e, x, contribution_x_ball, v, vpl.position);
    return !bvh_any_hit(o, e - o, w.x, w.y);
#else
    return !bvh_occluded_lifted(lifted_origin(x, nx), shadow_end(v, vpl));
#endif
#else
    return voxel_visibility(x, nx, vpl.position, vpl.normal) > 0.0;
#endif
}
#endif
