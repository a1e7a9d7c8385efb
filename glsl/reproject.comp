#version 460
// reproject (dispatch W × H): motion from the G-buffer, and the surface kept for the next frame
// (crates/graph/src/passes/reproject.rs). A pixel's surface point x projects through last frame's
// view_proj to where last frame saw it; the pixel there is its previous pixel when last frame's surface
// at it is the same surface: a point within `plane` pixel footprints of x's plane and a normal within
// acos(`normal`) of x's (disocclusion by depth and normal). Also written: where x was (xy, in pixels) and
// which of the four pixels around it hold the same surface (w, a 4-bit mask: the denoiser's bilinear
// lookup of its history). The scene is static, so the world position
// is the motion: no motion vector is rasterized.
#include "shared/scene.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(push_constant) uniform Push { ReprojectPush pc; };

layout(set = 0, binding = B_GATHER_GPOSITION) uniform sampler2D g_position;
layout(set = 0, binding = B_GATHER_GNORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = B_GATHER_GALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = B_PREV_POSITION) uniform sampler2D prev_position;
layout(set = 0, binding = B_PREV_SURFACE) uniform usampler2D prev_surface;
layout(set = 0, binding = B_MOTION, rgba32f) uniform writeonly image2D motion;
layout(set = 0, binding = B_SURFACE_POSITION_OUT, rgba32f) uniform writeonly image2D surface_position;
layout(set = 0, binding = B_SURFACE_OUT, rgba32ui) uniform writeonly uimage2D surface;

// Whether last frame's surface at pixel q is the surface (x, n): within `plane` footprints of x's plane,
// its normal within acos(`normal`) of n.
bool same_surface(ivec2 q, vec3 x, vec3 n, float footprint) {
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(frame.size.xy)))) return false;
    vec4 pp = texelFetch(prev_position, q, 0);
    vec3 pn = uintBitsToFloat(texelFetch(prev_surface, q, 0).xyz);
    return pp.w != 0.0 && abs(dot(n, pp.xyz - x)) <= pc.plane * footprint && dot(n, pn) >= pc.normal;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, ivec2(frame.size.xy)))) return;
    vec4 gp = texelFetch(g_position, px, 0);
    vec3 n = texelFetch(g_normal, px, 0).xyz;
    vec3 a = texelFetch(g_albedo, px, 0).rgb;
    imageStore(surface_position, px, gp);
    imageStore(surface, px, uvec4(floatBitsToUint(n), packUnorm4x8(vec4(a, 0.0))));
    vec4 m = vec4(-1.0, -1.0, 0.0, 0.0);
    if (gp.w != 0.0 && pc.history != 0u) {
        vec4 clip = frame.prev_view_proj * vec4(gp.xyz, 1.0);
        if (clip.w > 0.0) {
            // Vulkan clip space: y down the image, as the G-buffer's rows. The motion is the difference of
            // x's two projections, added to the pixel's centre: their rounding cancels, and a still camera's
            // pixel maps onto itself exactly (by the projection alone it landed off the centre).
            vec4 now = frame.view_proj * vec4(gp.xyz, 1.0);
            vec2 at = vec2(px) + 0.5 + (clip.xy / clip.w - now.xy / now.w) * 0.5 * vec2(frame.size.xy);
            float footprint = frame.camera.x * distance(gp.xyz, frame.eye.xyz);
            m.xy = at;
            // The four pixels around `at` whose centres a bilinear lookup weighs (the denoiser's history);
            // the one `at` falls in, ⌊at⌋ (the previous pixel), is among them.
            ivec2 base;
            vec2 t;
            bilinear_footprint(at, base, t);
            uint taps = 0u;
            for (uint k = 0u; k < 4u; k++) {
                if (same_surface(base + ivec2(k & 1u, k >> 1u), gp.xyz, n, footprint)) taps |= 1u << k;
            }
            ivec2 o = ivec2(floor(at)) - base;
            m.z = float((taps >> uint(o.x + 2 * o.y)) & 1u);
            m.w = float(taps);
        }
    }
    imageStore(motion, px, m);
}
