// Exact shadow rays from one origin, traced from a queue (the gather's and ris's shade, EXACT_VISIBILITY).
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
// queue reads shadow_queue_window.
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


#endif
