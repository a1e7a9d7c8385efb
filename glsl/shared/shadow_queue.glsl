// Exact shadow rays from one origin, traced from a queue (the gather's and ris's shade, EXACT_VISIBILITY),
// and the queue shared by a subgroup (shadow_pool_trace below: the gather's `--shadow-rays pool`).
// Include after bvh.glsl.
//
// Why a queue: llvmpipe runs a SIMD vector of invocations (8 lanes) in lockstep, so a loop of one shadow ray per
// sample waits at every sample for the vector's longest ray, and a lane whose sample needs no ray (a VPL behind
// x) idles through it. A caller instead puts up to SHADOW_QUEUE rays' far ends in the queue (only those that
// need a ray), and shadow_queue_trace walks them one after another per lane: a lane whose ray is done takes its
// next one at the next group of BVH_THREAD_UNROLL steps, so the vector waits only at the end of the queue, for
// the lane with the most steps in all. Each answer is bvh_occluded_lifted's, with its bound of BVH_MAX_STEPS
// records per ray (the same walk, step for step; with SHADOW_QUEUE_WINDOWS the same walk over a shorter part
// of the segment, which drops records and never an answer), so an image does not change, bit for bit; the
// loop runs at most GpuBvh::max_iterations_occluded iterations per ray, the bound the callers' dispatches are
// sized by.
#ifndef BOUNCE_SHADOW_QUEUE_GLSL
#define BOUNCE_SHADOW_QUEUE_GLSL

vec3 shadow_queue_end[SHADOW_QUEUE];
#ifdef SHADOW_QUEUE_WINDOWS
// With SHADOW_QUEUE_WINDOWS the caller also gives each ray the part of the segment to walk, (tmin, tmax)
// within (BVH_LIFTED_EPS, 1 − BVH_LIFTED_EPS): the gather and ris's shade leave out the rays' ends' empty
// balls (shared/end_balls.glsl), which changes no answer. An empty window is "not occluded" at once. The
// queue reads shadow_queue_window; the pool asks vec2 shadow_pool_window(key, owner, from, end), which the
// includer defines.
vec2 shadow_queue_window[SHADOW_QUEUE];
#endif

// Bit j set: the shadow ray o → shadow_queue_end[j] (j < n ≤ SHADOW_QUEUE) is not occluded.
uint shadow_queue_trace(vec3 o, uint n) {
    int end = bvh_thread_records();
    float tmin = BVH_LIFTED_EPS, tmax = 1.0 - BVH_LIFTED_EPS;
    uint visible = 0u, next = 0u, current = 0u, steps = 0u;
    bool tracing = false, done = false, hit = false;
    BvhRay r;
    int i = 0;
    while (tracing || next < n) {
        if (!tracing) {
            current = next++;
            vec3 d = shadow_queue_end[current] - o;
#ifdef SHADOW_QUEUE_WINDOWS
            tmin = shadow_queue_window[current].x;
            tmax = shadow_queue_window[current].y;
#endif
            if (!bvh_usable_ray(o, d, tmin, tmax)) {
                visible |= 1u << current; // "no hit", as bvh_any_hit answers
                continue;
            }
            r = bvh_make_ray(o, d);
            i = 0;
            steps = 0u;
            done = false;
            hit = false;
            tracing = true;
        }
        bvh_thread_steps(r, tmin, tmax, end, i, steps, done, hit);
        // Exhausted after BVH_MAX_STEPS records: "no hit", as bvh_any_hit answers.
        if (done || steps >= uint(BVH_MAX_STEPS)) {
            if (!hit) visible |= 1u << current;
            tracing = false;
        }
    }
    return visible;
}

#ifdef SHADOW_POOL_INVOCATIONS
// The queue shared by a subgroup (the gather's exact rays with `--shadow-rays pool`). Needs
// GL_KHR_shader_subgroup_ballot and _arithmetic, enabled by the includer, and before the include:
// SHADOW_POOL_INVOCATIONS (the workgroup's invocations) and vec3 shadow_pool_end(uint key), the far end of a
// queued ray from the caller's key. Shared memory: 8 · SHADOW_QUEUE + 20 bytes per invocation, plus what the
// includer keeps for shadow_pool_window (the gather: 32; POOL_SHARED_BYTES in passes/gather.rs checks the
// device's limit).
//
// Why: with a queue per invocation, a SIMD vector still waits at the end of every block for its lane with the
// most steps in all, and the lanes of a vector differ: on Sibenik and Conference the lanes were busy 72 % of
// the vector's iterations (88 % on the Cornell box). Here the rays of a subgroup's invocations form one pool:
// a lane whose ray is done takes the pool's next ray, whoever queued it, so the lanes stay busy until the
// pool is empty. The answers go back to the invocation that queued each ray (a bit per ray), and every answer
// is still bvh_occluded_lifted's: the same walk, step for step, whichever lane runs it.
//
// Loop bound: before the pool is empty every lane advances a ray by one iteration (or takes a ray that needs
// none), and a lane queues at most SHADOW_QUEUE rays, so a call loops at most
// SHADOW_QUEUE · (M + 1) + M iterations, M = GpuBvh::max_iterations_occluded (a ray's most): what the
// gather's dispatch sizing counts.
shared uvec2 shadow_pool[SHADOW_POOL_INVOCATIONS * SHADOW_QUEUE]; // (key, owner << 5 | slot)
shared vec3 shadow_pool_origin[SHADOW_POOL_INVOCATIONS];
shared uint shadow_pool_visible[SHADOW_POOL_INVOCATIONS];
uint shadow_pool_key[SHADOW_QUEUE]; // this invocation's queued rays (n of them): keys for shadow_pool_end

// Bit j set: this invocation's ray j (from o to shadow_pool_end(shadow_pool_key[j]), j < n) is not occluded.
// Every invocation of the subgroup calls it together, in subgroup-uniform control flow (n = 0 for one with
// nothing to trace).
uint shadow_pool_trace(vec3 o, uint n) {
    uint me = gl_LocalInvocationIndex;
    // The subgroup's part of the pool, its rays lane by lane (subgroups are gl_SubgroupSize invocations,
    // the last one possibly fewer, so the parts do not overlap).
    uint base = gl_SubgroupID * gl_SubgroupSize * SHADOW_QUEUE;
    uint first = base + subgroupExclusiveAdd(n);
    uint total = subgroupAdd(n);
    uint lanes = subgroupBallotBitCount(subgroupBallot(true));
    shadow_pool_origin[me] = o;
    shadow_pool_visible[me] = 0u;
    for (uint j = 0u; j < n; j++) shadow_pool[first + j] = uvec2(shadow_pool_key[j], (me << 5) | j);
    subgroupMemoryBarrierShared();
    subgroupBarrier();

    int end = bvh_thread_records();
    float tmin = BVH_LIFTED_EPS, tmax = 1.0 - BVH_LIFTED_EPS;
    uint taken = 0u, ticket = 0u, steps = 0u;
    bool tracing = false, done = true, hit = false;
    BvhRay r;
    int i = 0;
    while (true) {
        uvec4 need = subgroupBallot(!tracing);
        uint needing = subgroupBallotBitCount(need);
        if (needing == lanes && taken >= total) break; // nothing left to take, nothing being traced
        uint g = taken + subgroupBallotExclusiveBitCount(need);
        taken += needing;
        if (!tracing && g < total) {
            uvec2 e = shadow_pool[base + g];
            ticket = e.y;
            vec3 from = shadow_pool_origin[e.y >> 5];
            vec3 far_end = shadow_pool_end(e.x);
            vec3 d = far_end - from;
#ifdef SHADOW_QUEUE_WINDOWS
            vec2 window = shadow_pool_window(e.x, e.y >> 5, from, far_end);
            tmin = window.x;
            tmax = window.y;
#endif
            // The start of a walk, as in shadow_queue_trace. Written out twice on purpose: one function
            // with the ray as an inout parameter made the queue 3–6 % slower on lavapipe, where its
            // copies run at every loop iteration under masks.
            if (bvh_usable_ray(from, d, tmin, tmax)) {
                r = bvh_make_ray(from, d);
                i = 0;
                steps = 0u;
                done = false;
                hit = false;
                tracing = true;
            } else {
                atomicOr(shadow_pool_visible[e.y >> 5], 1u << (e.y & 31u)); // "no hit", as bvh_any_hit answers
            }
        }
        bvh_thread_steps(r, tmin, tmax, end, i, steps, done, hit);
        // Exhausted after BVH_MAX_STEPS records: "no hit", as bvh_any_hit answers.
        if (tracing && (done || steps >= uint(BVH_MAX_STEPS))) {
            if (!hit) atomicOr(shadow_pool_visible[ticket >> 5], 1u << (ticket & 31u));
            tracing = false;
            done = true;
        }
    }
    subgroupMemoryBarrierShared();
    subgroupBarrier();
    return shadow_pool_visible[me];
}
#endif

#endif
