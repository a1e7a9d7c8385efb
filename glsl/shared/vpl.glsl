// A VPL's unshadowed contribution to a gather point, shared by the gather and the importance passes.
// Include after scene.glsl and after declaring the three VPL samplers `vpl_position`, `vpl_normal`,
// `vpl_flux` (sampler2DArray).
#ifndef BOUNCE_VPL_GLSL
#define BOUNCE_VPL_GLSL

struct Vpl {
    vec3 position;
    vec3 normal;
    vec3 flux;
    bool valid;
};

Vpl vpl_fetch(uint v) {
    uint res = frame.size.w;
    ivec3 t = ivec3(v % res, (v / res) % res, v / (res * res));
    Vpl o;
    vec4 p = texelFetch(vpl_position, t, 0);
    o.position = p.xyz;
    o.valid = p.w != 0.0;
    o.normal = texelFetch(vpl_normal, t, 0).xyz;
    o.flux = texelFetch(vpl_flux, t, 0).rgb;
    return o;
}

// albedo(x)/π · Φ_v · (cos θ_v / π) · cos θ_x / max(d², min_d2), without visibility; writes the unit
// direction x → v (for the march) and returns 0 for a VPL behind x or facing away.
vec3 vpl_unshadowed(vec3 x, vec3 nx, vec3 ax, Vpl vpl, float min_d2) {
    if (!vpl.valid) return vec3(0.0);
    vec3 w = vpl.position - x;
    float d2 = dot(w, w);
    if (d2 <= 0.0) return vec3(0.0);
    w *= inversesqrt(d2);
    float cos_x = dot(nx, w);
    float cos_v = -dot(vpl.normal, w);
    if (cos_x <= 0.0 || cos_v <= 0.0) return vec3(0.0);
    return ax / PI * vpl.flux * (cos_v / PI) * cos_x / max(d2, min_d2);
}

#endif
