// Math shared by every shader: sRGB decoding, the paraboloid (stereographic) mapping of the dual
// paraboloid maps, ray-triangle intersection.
#ifndef BOUNCE_COMMON_GLSL
#define BOUNCE_COMMON_GLSL

const float PI = 3.14159265358979323846;

float srgb_to_linear(float c) {
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

// Paraboloid face f (0: front, looking along +z; 1: back, along -z) works in a local frame that mirrors
// z for the back face, so both faces use the same projection.
vec3 to_face(vec3 d, uint face) {
    return face == 0u ? d : vec3(d.x, d.y, -d.z);
}

// Direction (any length, local.z >= 0) -> paraboloid coordinates (u, v) in the unit disk. This is
// Heidrich–Seidel's mapping (thesis eq. 6.6): (u, v) = (x, y) / (|d| + z), a stereographic projection.
vec2 paraboloid_project(vec3 local) {
    return local.xy / (length(local) + local.z);
}

// Inverse: unit direction of paraboloid coordinates (u, v), u² + v² <= 1.
vec3 paraboloid_direction(vec2 uv) {
    float r2 = dot(uv, uv);
    return vec3(2.0 * uv, 1.0 - r2) / (1.0 + r2);
}

// An orthonormal basis (t1, t2, n) around unit n: fixed for each n (the gathering rays, the reference's
// bounces, the MIS patches and the per-VPL shadow maps all use this one).
void tangent_basis(vec3 n, out vec3 t1, out vec3 t2) {
    t1 = normalize(abs(n.x) > 0.9 ? cross(vec3(0.0, 1.0, 0.0), n) : cross(vec3(1.0, 0.0, 0.0), n));
    t2 = cross(n, t1);
}

// A cosine-distributed direction around unit n, from two uniforms (Malley's method).
vec3 cosine_direction(vec3 n, float u1, float u2) {
    vec3 t1, t2;
    tangent_basis(n, t1, t2);
    float rad = sqrt(u1), phi = 2.0 * PI * u2;
    return t1 * (rad * cos(phi)) + t2 * (rad * sin(phi)) + n * sqrt(max(1.0 - u1, 0.0));
}

// How far to lift a ray's origin off the surface at x: 1e-5 of the scene diagonal, but never less than
// 2⁻¹⁸ of |x| (about 32 float ulps of x's largest coordinate), so that the lift survives rounding far
// from the origin.
float surface_lift(vec3 x, float diagonal) {
    vec3 a = abs(x);
    return max(1e-5 * diagonal, max(a.x, max(a.y, a.z)) * (1.0 / 262144.0));
}

// Möller–Trumbore with barycentrics: (t, b1, b2) with the hit at (1−b1−b2)·a + b1·b + b2·c, or
// t = −1 when missed.
vec3 ray_triangle_bary(vec3 org, vec3 dir, vec3 a, vec3 b, vec3 c) {
    vec3 e1 = b - a;
    vec3 e2 = c - a;
    vec3 p = cross(dir, e2);
    float det = dot(e1, p);
    if (abs(det) < 1e-20) return vec3(-1.0);
    float inv = 1.0 / det;
    vec3 s = org - a;
    float u = dot(s, p) * inv;
    if (u < 0.0 || u > 1.0) return vec3(-1.0);
    vec3 q = cross(s, e1);
    float v = dot(dir, q) * inv;
    if (v < 0.0 || u + v > 1.0) return vec3(-1.0);
    float t = dot(e2, q) * inv;
    return t > 0.0 ? vec3(t, u, v) : vec3(-1.0);
}

// n's direction for any finite n (0 for 0). Where |n|² is no normal float (a tiny triangle's edge cross
// product: 0 or a denormal, where normalize gives ±inf or NaN; or beyond the float range) n is first
// scaled by 2^±64, exactly (a division by a tiny component has no precision bound in Vulkan); elsewhere
// it is normalize(n).
vec3 unit_direction(vec3 n) {
    float l2 = dot(n, n);
    if (l2 > 1e-30 && l2 < 1e30) return normalize(n);
    vec3 s = n * (l2 <= 1e-30 ? 18446744073709551616.0 : 5.42101086242752217e-20);
    float s2 = dot(s, s);
    return s2 > 0.0 && !isinf(s2) ? normalize(s) : vec3(0.0);
}

// A surface point's shading normal: the vertex normals' interpolation, normalized, or `face` (the unit
// face normal) where they cancel (vertex normals facing apart, a point on their zero set: normalize
// gave NaN, which then lit every pixel that drew the VPL, or none).
vec3 shading_normal(vec3 interpolated, vec3 face) {
    float l2 = dot(interpolated, interpolated);
    return l2 > 1e-30 && !isinf(l2) ? normalize(interpolated) : face;
}

// The thesis's luminance (eq. 7.6): the scalar importance of an RGB contribution (also the
// reference's light-strategy weights).
const vec3 LUMINANCE_WEIGHTS = vec3(LUMINANCE_R, LUMINANCE_G, LUMINANCE_B);
float luminance(vec3 c) {
    return LUMINANCE_WEIGHTS.r * c.r + LUMINANCE_WEIGHTS.g * c.g + LUMINANCE_WEIGHTS.b * c.b;
}

// Illumination = radiance / albedo (per channel; a channel of albedo 0 reflects nothing, so its
// radiance is 0 and its illumination is left 0): the denoiser filters it, so that it never blurs texture
// detail, and ris's shade reports its estimate's variance in it.
vec3 demodulate(vec3 c, vec3 albedo) {
    return vec3(albedo.r > 0.0 ? c.r / albedo.r : 0.0, albedo.g > 0.0 ? c.g / albedo.g : 0.0,
                albedo.b > 0.0 ? c.b / albedo.b : 0.0);
}

// The bilinear footprint of a point `at` in pixels (centres at k + ½): its lower-left pixel `base` and the
// weights' fractions t, so that pixels base + (0|1, 0|1) weigh (1 − t or t) per axis. ⌊at⌋ is one of the
// four: base + (t ≥ ½).
void bilinear_footprint(vec2 at, out ivec2 base, out vec2 t) {
    vec2 f = at - 0.5;
    base = ivec2(floor(f));
    t = f - vec2(base);
}

// `s` interpolated bilinearly over the footprint (base, t) by texel fetches (every pixel in the image).
vec4 bilinear_fetch(sampler2D s, ivec2 base, vec2 t) {
    return mix(mix(texelFetch(s, base, 0), texelFetch(s, base + ivec2(1, 0), 0), t.x),
               mix(texelFetch(s, base + ivec2(0, 1), 0), texelFetch(s, base + 1, 0), t.x), t.y);
}

// a / b (b > 0) in f32 with one correction either way: llvmpipe divides integers lane by lane, floats
// for the whole vector. Exact while a / b < 2^21 and a + b < 2^32: the f32 quotient's relative error is
// a few ulps (the conversions' and GLSL's 2.5-ulp division), so it is within 1 of the true one.
uint udiv(uint a, uint b) {
    uint q = uint(float(a) / float(b));
    if (q * b > a) q--;
    else if (a - q * b >= b) q++;
    return q;
}

// PCG hash (Jarzynski & Olano 2020): a good 32-bit hash for per-pixel, per-sample random streams.
uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// A random stream: state advanced by hashing; rand01 returns [0, 1) with 24 bits.
float rand01(inout uint state) {
    state = pcg_hash(state);
    return float(state >> 8) * (1.0 / 16777216.0);
}

// Möller–Trumbore: distance t along unit `dir` from `org` to the triangle, or -1 when missed.
float ray_triangle(vec3 org, vec3 dir, vec3 a, vec3 b, vec3 c) {
    vec3 e1 = b - a;
    vec3 e2 = c - a;
    vec3 p = cross(dir, e2);
    float det = dot(e1, p);
    if (abs(det) < 1e-20) return -1.0;
    float inv = 1.0 / det;
    vec3 s = org - a;
    float u = dot(s, p) * inv;
    if (u < 0.0 || u > 1.0) return -1.0;
    vec3 q = cross(s, e1);
    float v = dot(dir, q) * inv;
    if (v < 0.0 || u + v > 1.0) return -1.0;
    float t = dot(e2, q) * inv;
    return t > 0.0 ? t : -1.0;
}

#endif
