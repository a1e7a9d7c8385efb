#version 460
// Test kernel: the shadow-ray queue of glsl/shared/shadow_queue.glsl against one bvh_occluded_lifted call
// per ray. tests/tests/bvh.rs
// checks that the two answers agree bit for bit, and against the CPU reference. Bindings: the BVH, the
// queues at B_TEST_IN and the answers at B_TEST_OUT. An invocation traces its queue twice (queued, then
// one by one), so it loops at most SHADOW_QUEUE · (M + 1) + M + SHADOW_QUEUE · M + 4 times
// (M = max_iterations_occluded): the test keeps that under llvmpipe's 65535.
#include "../shared/bvh.glsl"

layout(local_size_x = WG_1D) in;

struct Queue {
    vec4 o;                      // xyz: the rays' common origin
    uvec4 n;                     // x: rays queued (≤ SHADOW_QUEUE)
    vec4 ends[SHADOW_QUEUE];     // xyz: each ray's far end
};

struct Answer {
    uint queued; // shadow_queue_trace's bits: ray j not occluded
    uint single; // the same from bvh_occluded_lifted, one ray at a time
    uvec2 pad;
};

layout(std430, set = 0, binding = B_TEST_IN) readonly buffer Queues { Queue queues[]; };
layout(std430, set = 0, binding = B_TEST_OUT) writeonly buffer Answers { Answer answers[]; };

#include "../shared/shadow_queue.glsl"

void main() {
    uint q = gl_GlobalInvocationID.x;
    // One past the last queue runs with no rays.
    bool inside = q < uint(queues.length());
    uint at = inside ? q : 0u;
    vec3 o = queues[at].o.xyz;
    uint n = inside ? min(queues[at].n.x, SHADOW_QUEUE) : 0u;
    Answer a;
    for (uint j = 0u; j < n; j++) shadow_queue_end[j] = queues[at].ends[j].xyz;
    a.queued = shadow_queue_trace(o, n);
    if (!inside) return;
    a.single = 0u;
    for (uint j = 0u; j < n; j++)
        if (!bvh_occluded_lifted(o, queues[at].ends[j].xyz)) a.single |= 1u << j;
    a.pad = uvec2(0u);
    answers[q] = a;
}
