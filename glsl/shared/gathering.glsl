// Gathering through the voxel grid: the first occupied cell along a ray, and the VPL a hit point
// corresponds to. Used by the gbg importance (thesis §7.3.4) and the MIS gathering strategy (§7.4).
// Include after voxel.glsl and vpl.glsl.
#ifndef BOUNCE_GATHERING_GLSL
#define BOUNCE_GATHERING_GLSL

const uint NO_VPL = 0xFFFFFFFFu;

// First occupied cell along o + t·d (grid units), t in (0, tmax]: its entry parameter, or −1.
float voxel_first_hit(vec3 o, vec3 d, float tmax) {
    ivec3 dims = ivec3(frame.voxel_dims.xyz);
    vec3 inv = vec3(abs(d.x) > 1e-12 ? 1.0 / d.x : 1e30, abs(d.y) > 1e-12 ? 1.0 / d.y : 1e30, abs(d.z) > 1e-12 ? 1.0 / d.z : 1e30);
    vec3 ta = (vec3(0.0) - o) * inv, tb = (vec3(dims) - o) * inv;
    float t0 = max(max(max(min(ta.x, tb.x), min(ta.y, tb.y)), min(ta.z, tb.z)), 0.0);
    float t1 = min(min(min(max(ta.x, tb.x), max(ta.y, tb.y)), max(ta.z, tb.z)), tmax);
    if (t0 > t1) return -1.0;
    ivec3 cell = ivec3(clamp(floor(o + d * t0), vec3(0.0), vec3(dims) - 1.0));
    ivec3 step = ivec3(sign(d));
    vec3 next = (vec3(cell) + max(vec3(step), vec3(0.0)) - o) * inv;
    vec3 delta = abs(inv);
    float t = t0;
    int max_steps = dims.x + dims.y + dims.z + 3;
    for (int n = 0; n < max_steps; n++) {
        if (voxel_occupied(cell)) return t;
        if (next.x <= next.y && next.x <= next.z) { t = next.x; next.x += delta.x; cell.x += step.x; }
        else if (next.y <= next.z) { t = next.y; next.y += delta.y; cell.y += step.y; }
        else { t = next.z; next.z += delta.z; cell.z += step.z; }
        if (t > t1 || any(lessThan(cell, ivec3(0))) || any(greaterThanEqual(cell, dims))) break;
    }
    return -1.0;
}

// The texel of light l's DPRSM that point p projects into, as a VPL index (NO_VPL when that texel holds
// no VPL). No test that the texel's VPL is near p: the MIS gathering strategy needs only a fixed,
// deterministic map from rays to texels (see mis.comp).
uint texel_at_point(vec3 p, uint l) {
    uint res = frame.size.w;
    uint face;
    vec2 uv;
    if (!lm_locate(p - lights[l].position.xyz, l, face, uv)) return NO_VPL;
    uvec2 texel = uvec2(clamp(ivec2(floor((uv * 0.5 + 0.5) * float(res))), ivec2(0), ivec2(int(res) - 1)));
    uint v = ((lm_faces() * l + face) * res + texel.y) * res + texel.x;
    return vpl_fetch(v).valid ? v : NO_VPL;
}

// The VPL of light l whose texel sees point p: p projected into the light's DPRSM, accepted when that
// texel's VPL lies within its own surface patch of p, plus 3 voxel cells (the light sees the surface
// the ray hit; the hit point of a voxel march is only known to a cell). NO_VPL otherwise. (gbg.)
uint vpl_at_point(vec3 p, uint l) {
    uint v = texel_at_point(p, l);
    if (v == NO_VPL) return NO_VPL;
    Vpl vpl = vpl_fetch(v);
    // The texel's surface patch reaches about √A_v from its VPL (A_v = Δω · d_l² / cos α, as in mis.comp):
    // accept hits within the patch, or within 3 cells when the hit is only known to a cell.
    uint res = frame.size.w;
    ivec3 t = ivec3(v % res, (v / res) % res, v / (res * res));
    float d_l = texelFetch(vpl_normal, t, 0).w;
    float cos_a = max(dot(vpl.normal, normalize(lights[l].position.xyz - vpl.position)), 1e-3);
    float patch_size = sqrt(texelFetch(vpl_flux, t, 0).w * d_l * d_l / cos_a);
    if (distance(vpl.position, p) > 3.0 * frame.voxel_origin.w + 2.0 * patch_size) return NO_VPL;
    return v;
}

// The first occupied voxel cell a ray from x (unit normal n) in direction d reaches: its entry point
// (world space), or false. The ray starts 2 cells off the surface, as the visibility march does.
bool gathering_hit(vec3 x, vec3 n, vec3 d, out vec3 hit) {
    float cell = frame.voxel_origin.w;
    vec3 o = (x - frame.voxel_origin.xyz) / cell + n * 2.0;
    float t = voxel_first_hit(o, d, 4.0 * float(frame.voxel_dims.x + frame.voxel_dims.y + frame.voxel_dims.z));
    hit = frame.voxel_origin.xyz + (o + d * max(t, 0.0)) * cell;
    return t >= 0.0;
}

#endif
