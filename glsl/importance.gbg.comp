#version 460
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
// importance (gathering-based global CDF, thesis §7.3.4), two stages:
//   IMP_GBG_SCATTER (one invocation per pixel): R cosine-distributed rays from the gather point, each
//     marched through the voxel grid to its first occupied cell; the entry point P is projected into
//     each light's DPRSM, and when that texel's VPL is the surface at P (the light sees it: within 3
//     cells), the VPL's unshadowed contribution (luminance) is added to its sum and its hit count raised.
//     Sums are u64 fixed point (atomic adds of integers commute: the result does not depend on thread
//     order, so a seed gives one image).
//   IMP_GBG_RESOLVE (one invocation per texel): average = sum / count; texels holding a VPL that no ray
//     reached (holes) take the median of the averages of their reached 3×3 neighbours (same face).
// See crates/graph/src/passes/importance.rs.
#include "shared/scene.glsl"
#define VOXEL_BITS_ACCESS readonly
#include "shared/voxel.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(push_constant) uniform Push { ImportancePush pc; };
layout(set = 0, binding = B_GATHER_GPOSITION) uniform sampler2D g_position;
layout(set = 0, binding = B_GATHER_GNORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = B_GATHER_GALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = B_VPL_POSITION) uniform sampler2DArray vpl_position;
layout(set = 0, binding = B_VPL_NORMAL) uniform sampler2DArray vpl_normal;
layout(set = 0, binding = B_VPL_FLUX) uniform sampler2DArray vpl_flux;
layout(std430, set = 0, binding = B_IMPORTANCE) writeonly buffer Importance { float importance[]; };
layout(std430, set = 0, binding = B_GBG_SUM) buffer Sums { uint64_t sums[]; };
layout(std430, set = 0, binding = B_GBG_COUNT) buffer Counts { uint counts[]; };

#include "shared/vpl.glsl"

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

void scatter(ivec2 px) {
    vec4 gp = texelFetch(g_position, px, 0);
    if (gp.w == 0.0) return;
    vec3 x = gp.xyz;
    vec3 n = texelFetch(g_normal, px, 0).xyz;
    vec3 a = texelFetch(g_albedo, px, 0).rgb;
    float cell = frame.voxel_origin.w;
    vec3 t1 = normalize(abs(n.x) > 0.9 ? cross(vec3(0.0, 1.0, 0.0), n) : cross(vec3(1.0, 0.0, 0.0), n));
    vec3 t2 = cross(n, t1);
    uint res = frame.size.w;
    uint rng = pcg_hash(pcg_hash(uint(px.x) + 65536u * uint(px.y)) ^ pc.seed ^ 0x5bd1e995u);
    for (uint r = 0u; r < pc.samples; r++) {
        float u1 = rand01(rng), u2 = rand01(rng);
        float rad = sqrt(u1), phi = 2.0 * PI * u2;
        vec3 d = t1 * (rad * cos(phi)) + t2 * (rad * sin(phi)) + n * sqrt(max(1.0 - u1, 0.0));
        // Start 2 cells off the surface (the march's rule), in grid units.
        vec3 o = (x - frame.voxel_origin.xyz) / cell + n * 2.0;
        float t = voxel_first_hit(o, d, 4.0 * float(frame.voxel_dims.x + frame.voxel_dims.y + frame.voxel_dims.z));
        if (t < 0.0) continue;
        vec3 p = frame.voxel_origin.xyz + (o + d * t) * cell;
        for (uint l = 0u; l < frame.size.z; l++) {
            vec3 local = p - lights[l].position.xyz;
            uint face = local.z >= 0.0 ? 0u : 1u;
            vec2 uv = paraboloid_project(to_face(local, face));
            uvec2 texel = uvec2(clamp(ivec2(floor((uv * 0.5 + 0.5) * float(res))), ivec2(0), ivec2(int(res) - 1)));
            uint v = ((2u * l + face) * res + texel.y) * res + texel.x;
            Vpl vpl = vpl_fetch(v);
            if (!vpl.valid || distance(vpl.position, p) > 3.0 * cell) continue;
            float c = luminance(vpl_unshadowed(x, n, a, vpl, pc.min_d2));
            if (!(c > 0.0)) continue;
            atomicAdd(sums[v], uint64_t(min(c * pc.fixed_scale, 4294967296.0)));
            atomicAdd(counts[v], 1u);
        }
    }
}

float average(uint v) {
    return float(sums[v]) / float(counts[v]) / pc.fixed_scale;
}

void resolve(uvec3 id) {
    uint res = frame.size.w;
    uint v = (id.z * res + id.y) * res + id.x;
    float w = 0.0;
    if (vpl_fetch(v).valid) {
        if (counts[v] > 0u) {
            w = average(v);
        } else {
            // A hole: the median of the reached neighbours (3×3, same face).
            float vals[8];
            int k = 0;
            for (int dy = -1; dy <= 1; dy++) {
                for (int dx = -1; dx <= 1; dx++) {
                    ivec2 q = ivec2(id.xy) + ivec2(dx, dy);
                    if ((dx == 0 && dy == 0) || any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(int(res))))) continue;
                    uint u = (id.z * res + uint(q.y)) * res + uint(q.x);
                    if (counts[u] == 0u) continue;
                    float a = average(u);
                    int j = k++;
                    while (j > 0 && vals[j - 1] > a) { vals[j] = vals[j - 1]; j--; }
                    vals[j] = a;
                }
            }
            if (k > 0) w = (k % 2 == 1) ? vals[k / 2] : 0.5 * (vals[k / 2 - 1] + vals[k / 2]);
        }
    }
    importance[pc.section * (2u * frame.size.z * res * res) + v] = w;
}

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (pc.mode == IMP_GBG_SCATTER) {
        if (id.x < frame.size.x && id.y < frame.size.y) scatter(ivec2(id.xy));
    } else {
        uint res = frame.size.w;
        if (id.x < res && id.y < res) resolve(id);
    }
}
