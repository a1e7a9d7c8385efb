#version 460
// present: the running mean of the frames, Reinhard 2002 (global operator) and sRGB, into an 8-bit
// image. Up to four stages (PresentPush.stage), one dispatch each, serialized by the pass:
//   PRESENT_ACCUMULATE  per pixel: sum += radiance (or sum = radiance on reset); a real-time frame is
//                       also kept as the prior (PRESENT_PRIOR_KEEP); with PRESENT_PRIOR_USE the moments
//                       (mean, Σ (l − mean)²) of the frames' luminance; without it, per workgroup, the partial
//                       Σ ln(δ + L), the count of finite L ≥ 0, and max L of the mean image
//   PRESENT_WEIGHT      (PRESENT_PRIOR_USE only) per pixel: the prior's weight w from the 3 × 3 moments
//                       and prior around it, the mean (sum + w D) / (n + w) into the mean image, and the
//                       partials of that mean
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
// The last real-time frame D, which a still view's first frames after a move carry (passes/present.rs);
// the frames' luminance moments (mean, Σ (l − mean)²) since the mean began; the mean shown while D is
// carried.
layout(set = 0, binding = B_PRESENT_PRIOR, rgba32f) uniform image2D prior_image;
layout(set = 0, binding = B_PRESENT_MOMENTS, rgba32f) uniform image2D moments_image;
layout(set = 0, binding = B_PRESENT_MEAN, rgba32f) uniform image2D mean_image;

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

// Per workgroup: the partial Σ ln(δ + L), the count of finite L ≥ 0 and max L of the mean's pixels.
void partials(uint lane, uint group, bool inside, vec3 mean) {
    float l = luminance(mean);
    partial[lane] = inside && usable(l) ? vec4(log(REINHARD_DELTA + l), 1.0, l, 0.0) : vec4(0.0);
    vec4 total = reduce(lane);
    if (lane == 0u) stats[group] = total;
}

// The prior D's weight, in frames, in pixel px's mean of n = pc.frames still frames: v / e², v one
// frame's luminance variance and e² D's squared error, both over the 3 × 3 pixels around px (the frames'
// sample variance; e² = mean (l_D − l̄)² less v / n, the running mean's own share), at most
// STOP_PRIOR_MAX; at the first frame, where one frame shows no variance, STOP_PRIOR_FIRST; fading to 0
// over STOP_PRIOR_FADE frames. (v / e² frames of D make the blend's error least where D's error is e².)
float prior_weight(ivec2 px, ivec2 size) {
    float n = pc.frames;
    float fade = max(1.0 - (n - 1.0) / STOP_PRIOR_FADE, 0.0);
    if (n <= 1.0) return STOP_PRIOR_FIRST * fade;
    float v = 0.0, dev = 0.0, count = 0.0;
    for (int dy = -1; dy <= 1; dy++) {
        for (int dx = -1; dx <= 1; dx++) {
            ivec2 q = px + ivec2(dx, dy);
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
            vec2 m = imageLoad(moments_image, q).xy;
            v += m.y / (n - 1.0);
            float d = luminance(imageLoad(prior_image, q).rgb) - m.x;
            dev += d * d;
            count += 1.0;
        }
    }
    v /= count;
    float e2 = max(dev / count - v / n, 1e-30);
    return min(v / e2, STOP_PRIOR_MAX) * fade;
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
            imageStore(sum_image, px, sum);
            if (pc.prior == PRESENT_PRIOR_KEEP) imageStore(prior_image, px, l);
            if (pc.prior == PRESENT_PRIOR_USE) {
                // Welford's running mean and sum of squared deviations (no cancellation in f32).
                float y = luminance(l.rgb);
                vec2 m = vec2(y, 0.0);
                if (pc.reset == 0u) {
                    m = imageLoad(moments_image, px).xy;
                    float d = y - m.x;
                    m.x += d / pc.frames;
                    m.y += d * (y - m.x);
                }
                imageStore(moments_image, px, vec4(m, 0.0, 0.0));
            }
        }
        // (With the prior the weight stage takes the partials of the mean it makes.)
        if (pc.prior == PRESENT_PRIOR_USE) return;
        partials(lane, group, inside, sum.rgb / pc.frames);
    } else if (pc.stage == PRESENT_WEIGHT) {
        vec3 mean = vec3(0.0);
        if (inside) {
            float w = prior_weight(px, size);
            mean = (imageLoad(sum_image, px).rgb + w * imageLoad(prior_image, px).rgb) / (pc.frames + w);
            imageStore(mean_image, px, vec4(mean, w));
        }
        partials(lane, group, inside, mean);
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
        vec3 mean = pc.prior == PRESENT_PRIOR_USE ? imageLoad(mean_image, px).rgb
                                                  : imageLoad(sum_image, px).rgb / pc.frames;
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
