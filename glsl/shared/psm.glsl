// Per-VPL paraboloid shadow maps (thesis ch. 6, `--visibility psm`): the map of VPL k is a single
// paraboloid face around the VPL's normal, centred at the VPL lifted off its surface, storing the
// distance to the first surface over `far` per texel (exactly: psm.frag).
// Include after scene.glsl and types (PsmView); the caller declares `psm_views` and, for the lookup,
// `psm_depth` (PSM_LOOKUP).
#ifndef BOUNCE_PSM_GLSL
#define BOUNCE_PSM_GLSL

// d in the frame of a map whose axis is n (unit): z along n; x, y a fixed tangent basis of n.
vec3 psm_to_local(vec3 d, vec3 n) {
    vec3 t1, t2;
    tangent_basis(n, t1, t2);
    return vec3(dot(d, t1), dot(d, t2), dot(d, n));
}

#ifdef PSM_LOOKUP
// 1 when x (unit normal nx) is the first surface map k sees in x's direction, within the bias; 0
// otherwise (or behind the VPL), with paraboloid_shadow_bias's depth bias (scene.glsl).
float psm_visible(uint k, vec3 x, vec3 nx) {
    PsmView w = psm_views[k];
    vec3 d = x - w.position_v.xyz;
    vec3 local = psm_to_local(d, w.normal_p.xyz);
    if (local.z <= 0.0) return 0.0;
    float dist = length(local);
    vec2 uv = paraboloid_project(local);
    int res = int(frame.maps.z);
    ivec2 texel = clamp(ivec2(floor((uv * 0.5 + 0.5) * float(res))), ivec2(0), ivec2(res - 1));
    float stored = texelFetch(psm_depth, ivec3(texel, int(k)), 0).r * frame.scene_max.w;
    float cos_theta = clamp(-dot(nx, d) / max(dist, 1e-30), 0.0, 1.0);
    return dist <= stored + paraboloid_shadow_bias(uv, res, dist, cos_theta) ? 1.0 : 0.0;
}
#endif

#endif
