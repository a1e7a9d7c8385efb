#version 460
// reproject (dispatch W × H): motion from the G-buffer, and the surface kept for the next frame
// (crates/graph/src/passes/reproject.rs). A pixel's surface point x projects through last frame's
// view_proj to where last frame saw it; the pixel there is its previous pixel when last frame's surface
// at it is the same surface: a point within `plane` pixel footprints of x's plane and a normal within
// acos(`normal`) of x's (disocclusion by depth and normal). The scene is static, so the world position
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
            // Vulkan clip space: y down the image, as the G-buffer's rows.
            vec2 at = (clip.xy / clip.w * 0.5 + 0.5) * vec2(frame.size.xy);
            ivec2 q = ivec2(floor(at));
            if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(frame.size.xy)))) {
                vec4 pp = texelFetch(prev_position, q, 0);
                vec3 pn = uintBitsToFloat(texelFetch(prev_surface, q, 0).xyz);
                float footprint = frame.camera.x * distance(gp.xyz, frame.eye.xyz);
                bool same = pp.w != 0.0 && abs(dot(n, pp.xyz - gp.xyz)) <= pc.plane * footprint
                    && dot(n, pn) >= pc.normal;
                if (same) m = vec4(vec2(q), 1.0, 0.0);
            }
        }
    }
    imageStore(motion, px, m);
}
