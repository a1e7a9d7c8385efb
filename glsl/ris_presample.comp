#version 460
// ris, presample stage (dispatch RIS_POOL_TILE × T, --pool-tiles T > 0): the candidate pool, T tiles of
// RIS_POOL_TILE VPLs; tile j's entries are points 0 .. RIS_POOL_TILE − 1 of one stratified set of the
// source (draw_vpl, seeded by j and the frame), stored with their data and p_v, so a candidate costs three
// texel fetches and its target. RIS_UNIFORM_SOURCE (a specialisation): the uniform source's shortcut.
#include "shared/ris.glsl"

layout(constant_id = SPEC_RIS_UNIFORM_SOURCE) const bool RIS_UNIFORM_SOURCE = false;
// Entry e: texels 3e (position, v), 3e + 1 (normal, p_v; 0: no draw), 3e + 2 (flux, the VPL's patch area
// A_v; 0 for an empty texel).
layout(std430, set = 0, binding = B_RIS_POOL) writeonly buffer RisPool { vec4 pool_out[]; };

void main() {
    uint k = gl_GlobalInvocationID.x, tile = gl_GlobalInvocationID.y;
    if (k >= uint(RIS_POOL_TILE) || tile >= ris.pool_tiles) return;
    uint e = tile * uint(RIS_POOL_TILE) + k;
    vec4 a = vec4(0.0), b = vec4(0.0), c = vec4(0.0);
    if (cdf_total_at(0u) > 0.0) {
        float prob;
        uint seed = pcg_hash(tile ^ 0x6A09E667u) ^ pc.seed;
        uint v;
        if (RIS_UNIFORM_SOURCE) {
            // The uniform source: its mixture is the validity CDF alone (no method section, no defensive
            // share), whose faces go by Russian roulette whatever --face says (it chooses among a method
            // section's faces), so draw_vpl's mixture is that CDF's distribution. One search
            // (and its probability) instead of draw_vpl's two, with draw_vpl's stratified points.
            uint all_rows = faces() * face_rows();
            vec3 u = vec3(owen_sobol2(k, seed ^ 0xA54FF53Au), owen_sobol1(k, seed ^ 0x510E527Fu));
            v = cdf_sample_rows3_prob(0u, 0u, u, 0u, all_rows, prob);
        } else {
            v = draw_vpl(k, seed, prob);
        }
        if (prob > 0.0) {
            Vpl vpl = vpl_fetch(v);
            a = vec4(vpl.position, uintBitsToFloat(v));
            b = vec4(vpl.normal, prob);
            c = vec4(vpl.flux, vpl.area);
        }
    }
    pool_out[3u * e] = a;
    pool_out[3u * e + 1u] = b;
    pool_out[3u * e + 2u] = c;
}
