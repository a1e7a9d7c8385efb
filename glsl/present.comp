#version 460
// present: the running mean of the frames, Reinhard 2002 (global operator) and sRGB, into an 8-bit
// image. Three stages (PresentPush.stage), one dispatch each, serialized by the pass:
//   PRESENT_ACCUMULATE  per pixel: sum += radiance (or sum = radiance on reset), plus the kept prior
//                       times the change of its weight (prior_delta; a real-time frame is kept as
//                       the prior with keep_prior); per workgroup, the
//                       partial Σ ln(δ + L), the count of finite L ≥ 0, and max L of the mean image
//   PRESENT_TOTAL       one workgroup: the partials' totals → stats[groups] = (a / L̄_w, L_white, n, 0)
//   PRESENT_MAP         per pixel: L_d = L (1 + L / L_white²) / (1 + L) on the luminance, colour ratios
//                       kept, clamped to [0, 1], sRGB-encoded and rounded as crates/app/src/output.rs does
// See crates/graph/src/passes/present.rs.
#include "shared/types.glsl"
#include "shared/bindings.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(push_constant) uniform Push { PresentPush pc; };
layout(set = 0, binding = B_PRESENT_RADIANCE) uniform sampler2D radiance;
layout(set = 0, binding = B_PRESENT_SUM, rgba32f) uniform image2D sum_image;
layout(set = 0, binding = B_PRESENT_OUT, rgba8) uniform writeonly image2D out_image;
// Per workgroup of the per-pixel stages: (Σ ln(δ + L), n, max L, 0); element `groups`: the totals.
layout(std430, set = 0, binding = B_PRESENT_STATS) buffer Stats { vec4 stats[]; };
// The last real-time frame, which a still view's first frames after a move carry (passes/present.rs).
layout(set = 0, binding = B_PRESENT_PRIOR, rgba32f) uniform image2D prior_image;

const uint LANES = WG_2D * WG_2D;
shared vec4 partial[LANES];

float luminance(vec3 c) {
    return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
}

bool usable(float l) {
    return !isnan(l) && !isinf(l) && l >= 0.0;
}

// Tree reduction of `partial` over the workgroup: sums in x and y, maximum in z.
vec4 reduce(uint lane) {
    for (uint s = LANES / 2u; s > 0u; s >>= 1u) {
        barrier();
        if (lane < s) {
            vec4 a = partial[lane], b = partial[lane + s];
            partial[lane] = vec4(a.x + b.x, a.y + b.y, max(a.z, b.z), 0.0);
        }
    }
    barrier();
    return partial[0];
}

float srgb_byte(float c) {
    c = clamp(c, 0.0, 1.0);
    float s = c <= 0.0031308 ? c * 12.92 : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
    return clamp(floor(s * 255.0 + 0.5), 0.0, 255.0);
}

void main() {
    uint lane = gl_LocalInvocationIndex;
    ivec2 size = imageSize(sum_image);
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    bool inside = all(lessThan(px, size));
    uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    if (pc.stage == PRESENT_ACCUMULATE) {
        vec4 sum = vec4(0.0);
        if (inside) {
            vec4 l = texelFetch(radiance, px, 0);
            sum = pc.reset != 0u ? l : imageLoad(sum_image, px) + l;
            // (Read only when its weight changes: a prior never kept is not read.)
            if (pc.prior_delta != 0.0) sum += pc.prior_delta * imageLoad(prior_image, px);
            imageStore(sum_image, px, sum);
            if (pc.keep_prior != 0u) imageStore(prior_image, px, l);
        }
        float l = luminance(sum.rgb / pc.frames);
        partial[lane] = inside && usable(l) ? vec4(log(REINHARD_DELTA + l), 1.0, l, 0.0) : vec4(0.0);
        vec4 total = reduce(lane);
        if (lane == 0u) stats[group] = total;
    } else if (pc.stage == PRESENT_TOTAL) {
        vec4 acc = vec4(0.0);
        // Bounded by groups / LANES iterations (≈ 2000 at 4K), far under the loop limit.
        for (uint g = lane; g < pc.groups; g += LANES) {
            vec4 s = stats[g];
            acc = vec4(acc.x + s.x, acc.y + s.y, max(acc.z, s.z), 0.0);
        }
        partial[lane] = acc;
        vec4 total = reduce(lane);
        if (lane == 0u) {
            float scale = 0.0, white = 1.0;
            if (total.y > 0.0) {
                scale = pc.exposure * REINHARD_KEY / exp(total.x / total.y);
                white = max(total.z * scale, 1e-12);
            }
            stats[pc.groups] = vec4(scale, white, total.y, 0.0);
        }
    } else {
        if (!inside) return;
        vec3 mean = imageLoad(sum_image, px).rgb / pc.frames;
        vec4 t = stats[pc.groups];
        float lw = luminance(mean);
        vec3 c = vec3(0.0);
        if (usable(lw) && lw > 0.0 && t.z > 0.0) {
            float l = lw * t.x;
            float ld = l * (1.0 + l / (t.y * t.y)) / (1.0 + l);
            c = mean * (ld / lw);
        }
        vec3 b = vec3(srgb_byte(c.r), srgb_byte(c.g), srgb_byte(c.b)) / 255.0;
        imageStore(out_image, px, vec4(pc.swap_rb != 0u ? b.bgr : b, 1.0));
    }
}
