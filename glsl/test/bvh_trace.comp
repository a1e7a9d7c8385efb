#version 460
// Test kernel: the BVH traversal of glsl/shared/bvh.glsl, one invocation per query, exactly as a pass calls it.
// tests/tests/bvh.rs compares the results with the CPU reference (crates/graph/src/cpu_ref.rs). Bindings: the
// BVH at B_BVH_NODES / B_BVH_TRIS, the queries at B_TEST_IN and the results at B_TEST_OUT. Each invocation
// makes four traces (closest, occluded, the any-hit trace behind occluded again for its triangle, and the
// closest hit by the threaded walk), so it loops at most 3 · BVH_MAX_STEPS + BVH_MAX_STEPS / 8 + 4 = 51204
// < 65535 times.
#include "../shared/bvh.glsl"

layout(local_size_x = WG_1D) in;

struct Query {
    vec4 o; // xyz: ray origin, w: tmax
    vec4 d; // xyz: ray direction
    vec4 a; // xyz: segment start
    vec4 b; // xyz: segment end
};

struct Result {
    float t;        // bvh_closest
    uint tri;
    vec2 bary;
    uint occluded;  // bvh_occluded
    uint occ_tri;   // the triangle the any-hit trace of the segment stopped at (BVH_NO_TRI if none)
    float occ_t;
    uint steps;     // loop iterations of bvh_closest
    uint occ_steps; // loop iterations of bvh_occluded
    uint exhausted; // bit 0: bvh_closest gave up, bit 1: bvh_occluded did, bit 2: bvh_closest_walk did
    float walk_t;   // bvh_closest_walk: must equal bvh_closest's answer bit for bit
    uint walk_tri;
    vec2 walk_bary;
};

layout(std430, set = 0, binding = B_TEST_IN) readonly buffer Queries { Query queries[]; };
layout(std430, set = 0, binding = B_TEST_OUT) writeonly buffer Results { Result results[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(queries.length())) return;
    Query q = queries[i];
    Result r;
    r.t = bvh_closest(q.o.xyz, q.d.xyz, q.o.w, r.tri, r.bary);
    r.steps = bvh_steps;
    r.exhausted = bvh_exhausted ? 1u : 0u;
    r.occluded = bvh_occluded(q.a.xyz, q.b.xyz) ? 1u : 0u;
    r.occ_steps = bvh_steps;
    r.exhausted |= bvh_exhausted ? 2u : 0u;
    vec2 unused;
    r.occ_t = bvh_trace(q.a.xyz, q.b.xyz - q.a.xyz, BVH_SHADOW_EPS, 1.0 - BVH_SHADOW_EPS, true, r.occ_tri, unused);
    r.walk_t = bvh_closest_walk(q.o.xyz, q.d.xyz, q.o.w, r.walk_tri, r.walk_bary);
    r.exhausted |= bvh_exhausted ? 4u : 0u;
    results[i] = r;
}
