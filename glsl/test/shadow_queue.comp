#version 460
// Test kernel: the shadow-ray queue of glsl/shared/shadow_queue.glsl against one bvh_occluded_lifted call
// per ray. tests/tests/bvh.rs checks that the two answers agree bit for bit, and against the CPU reference.
// Bindings: the BVH, the queues at B_TEST_IN and the answers at B_TEST_OUT. An invocation traces its queue
// twice (queued, then one by one), so it loops at most 2 · SHADOW_QUEUE · max_iterations_occluded + 2 ·
// SHADOW_QUEUE + 4 times: the test keeps that under llvmpipe's 65535.
#include "../shared/bvh.glsl"
#include "../shared/shadow_queue.glsl"

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

void main() {
    uint q = gl_GlobalInvocationID.x;
    if (q >= uint(queues.length())) return;
    vec3 o = queues[q].o.xyz;
    uint n = min(queues[q].n.x, SHADOW_QUEUE);
    for (uint j = 0u; j < n; j++) shadow_queue_end[j] = queues[q].ends[j].xyz;
    Answer a;
    a.queued = shadow_queue_trace(o, n);
    a.single = 0u;
    for (uint j = 0u; j < n; j++)
        if (!bvh_occluded_lifted(o, queues[q].ends[j].xyz)) a.single |= 1u << j;
    a.pad = uvec2(0u);
    answers[q] = a;
}
