// A VPL's unshadowed contribution to a gather point, shared by the gather and the importance passes.
// Include after scene.glsl and after declaring the three VPL samplers `vpl_position`, `vpl_normal`,
// `vpl_flux` (sampler2DArray).
#ifndef BOUNCE_VPL_GLSL
#define BOUNCE_VPL_GLSL

struct Vpl {
    vec3 position;
    vec3 normal;
    vec3 flux;
    float area; // A_v, the surface patch its texel sees (dprsm.comp); 0: no VPL
    bool valid;
};

// A VPL from its texels in the three maps (position: xyz, area; normal; flux).
Vpl vpl_from(vec4 p, vec3 normal, vec3 flux) {
    return Vpl(p.xyz, normal, flux, p.w, p.w != 0.0);
}

Vpl vpl_fetch_texel(ivec3 t) {
    return vpl_from(texelFetch(vpl_position, t, 0), texelFetch(vpl_normal, t, 0).xyz, texelFetch(vpl_flux, t, 0).rgb);
}

// Texel (column, row, layer) of VPL index v.
ivec3 vpl_texel(uint v) {
    uint res = frame.size.w;
    return ivec3(v % res, (v / res) % res, v / (res * res));
}

Vpl vpl_fetch(uint v) {
    return vpl_fetch_texel(vpl_texel(v));
}

// albedo(x)/π · Φ_v · (cos θ_v / π) · cos θ_x · k(d²), without visibility; 0 for a VPL behind x or facing
// away. The kernel (--vpl-kernel; crates/graph/src/passes/gather.rs says why):
//   point (frame.vpl.x = 0, the thesis's): k = 1 / max(d², min_d2), unbounded next to x;
//   patch (frame.vpl.x = s = 1/π): k = 1 / max(√(d⁴ + (s·A_v)²), min_d2), A_v the area of the surface
//     patch the VPL's texel sees. Next to x it tends to π/A_v, so the VPL gives at most its patch's
//     radiosity Φ_v/A_v (the irradiance of a disk of area A_v at its centre); where d² ≫ A_v it is the point
//     kernel to second order (relative difference (s·A_v)²/(2d⁴)), so the sum keeps the point VPLs' energy
//     and converges to the same one-bounce integral as the map's resolution grows.
// The kernel's denominator 1/k for squared distance d2 (> 0): d2, or √(d⁴ + a²) with a = s·A_v, written
// as m·√(1 + (n/m)²), m = max(d², a), n = min(d², a), so that nothing overflows or underflows at any scale.
float vpl_kernel_den(float d2, Vpl vpl, float min_d2) {
    float a = frame.vpl.x * vpl.area, m = max(d2, a), n = min(d2, a) / m;
    return max(a > 0.0 ? m * sqrt(1.0 + n * n) : d2, min_d2);
}

vec3 vpl_unshadowed(vec3 x, vec3 nx, vec3 ax, Vpl vpl, float min_d2) {
    if (!vpl.valid) return vec3(0.0);
    vec3 w = vpl.position - x;
    float d2 = dot(w, w);
    if (d2 <= 0.0) return vec3(0.0);
    w *= inversesqrt(d2);
    float cos_x = dot(nx, w);
    float cos_v = -dot(vpl.normal, w);
    if (cos_x <= 0.0 || cos_v <= 0.0) return vec3(0.0);
    return ax / PI * vpl.flux * (cos_v / PI) * cos_x / vpl_kernel_den(d2, vpl, min_d2);
}

// vpl_unshadowed(x, nx, ax, vpl, min_d2) = (ax ⊙ Φ_v) · G with this G (0 for no VPL, or one behind x or
// facing away): the geometry, kernel and 1/π², everything but the colours. The cosines stay unnormalized
// (cos θ_x cos θ_v = (n_x·w)(−n_v·w)/d², w = v − x), so there is no inverse square root: ris's candidate
// loops, where it is most of the time, split the contribution into G and the colours this way.
float vpl_unshadowed_geometry(vec3 x, vec3 nx, Vpl vpl, float min_d2) {
    vec3 w = vpl.position - x;
    float d2 = dot(w, w);
    float cx = dot(nx, w), cv = -dot(vpl.normal, w);
    float g = (cx * cv) / (PI * PI * d2 * vpl_kernel_den(d2, vpl, min_d2));
    return vpl.valid && d2 > 0.0 && cx > 0.0 && cv > 0.0 ? g : 0.0;
}

// luminance(vpl_unshadowed(x, nx, ax, vpl, min_d2)) with axl = ax · the luminance weights
// (vpl_luminance_albedo): the same value up to rounding.
float vpl_unshadowed_luminance(vec3 x, vec3 nx, vec3 axl, Vpl vpl, float min_d2) {
    return dot(axl, vpl.flux) * vpl_unshadowed_geometry(x, nx, vpl, min_d2);
}

vec3 vpl_luminance_albedo(vec3 ax) {
    return ax * LUMINANCE_WEIGHTS;
}

#endif
