// The denoiser's shared part (glsl/denoise_<stage>.comp include it first; crates/graph/src/passes/
// denoise.rs states the filter): the push constants, the G-buffer and the edge stops.
#ifndef BOUNCE_DENOISE_GLSL
#define BOUNCE_DENOISE_GLSL
#include "scene.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(push_constant) uniform Push { DenoisePush pc; };

layout(set = 0, binding = B_GATHER_GPOSITION) uniform sampler2D g_position;
layout(set = 0, binding = B_GATHER_GNORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = B_GATHER_GALBEDO) uniform sampler2D g_albedo;

// Whether pixel q is in the image (the stages' neighbourhoods stop at its edges).
bool inside(ivec2 q) {
    return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(frame.size.xy)));
}

// A pixel's surface: point, normal, footprint (its width at that distance: θ_px · |x − eye|).
struct Surface {
    vec3 x;
    vec3 n;
    float footprint;
    bool hit;
};

Surface surface_at(ivec2 p) {
    vec4 gp = texelFetch(g_position, p, 0);
    Surface s;
    s.x = gp.xyz;
    s.n = texelFetch(g_normal, p, 0).xyz;
    s.footprint = frame.camera.x * distance(gp.xyz, frame.eye.xyz);
    s.hit = gp.w != 0.0;
    return s;
}

// The geometric edge stop between surfaces of normals n_p and n_q, `pixels` apart, the one `off`
// footprints off the other's plane: normals (cos^σ_n) and the distance against σ_z footprints per pixel
// of offset (scale-free).
float geometry_stop(vec3 np, vec3 nq, float off, float pixels) {
    float wn = pow(max(0.0, dot(np, nq)), pc.sigma_n);
    return off == 0.0 ? wn : wn * exp(-off / (pc.sigma_z * pixels));
}

// The stop between p's surface and q's, q's distance off p's tangent plane in p's footprints.
float geometry_weight(Surface p, Surface q, float pixels) {
    if (!q.hit) return 0.0;
    return geometry_stop(p.n, q.n, abs(dot(p.n, q.x - p.x)) / p.footprint, pixels);
}

// The same stop made symmetric (w(p, q) = w(q, p)): the larger of the two plane distances, each in its
// own pixel's footprints.
float geometry_weight_symmetric(Surface p, Surface q, float pixels) {
    if (!q.hit) return 0.0;
    vec3 d = q.x - p.x;
    return geometry_stop(p.n, q.n, max(abs(dot(p.n, d)) / p.footprint, abs(dot(q.n, d)) / q.footprint), pixels);
}

// The luminance edge stop: |l_p − l_q| against σ_l standard deviations of p's (filtered) variance; 1
// for equal values (also where the variance is 0), 0 for different ones there.
float luminance_weight(float lp, float lq, float sd) {
    float d = abs(lp - lq);
    return d == 0.0 ? 1.0 : exp(-d / (pc.sigma_l * sd));
}

#endif
