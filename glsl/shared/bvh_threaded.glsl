// The BVH's stackless walks over its threaded records: any-hit (shadow rays) and closest-hit. Included by
// shared/bvh.glsl, whose header is the contract of both; its structs, ray setup and box test are theirs.
#ifndef BOUNCE_BVH_THREADED_GLSL
#define BOUNCE_BVH_THREADED_GLSL
// Any-hit traversal for occlusion, stackless over the threaded records (FlatBvh::threaded in the scene crate's bvh/flat.rs):
// the tree's triangles and the boxes worth testing in depth-first preorder, a box's link skipping its subtree
// (a box that would cost more steps than it saves on average is left out, its subtree walked unconditionally:
// FlatBvh::box_records). Each step reads one record and tests it, a box or a triangle; a missed box jumps past
// its subtree. Same answer as bvh_trace's any-hit mode: whether a triangle of the tree crosses the ray with
// t ∈ (tmin, tmax) (only which triangle stops it may differ). The walk only moves forward, so it reads at most
// records ≤ nodes + triangles of them; at BVH_MAX_STEPS it gives up (not occluded, bvh_exhausted).
//
// Why this shape (measured in BENCHMARKS.md, "Exact shadow rays"): llvmpipe runs every branch of a loop body
// for all lanes of a SIMD vector under masks, and reads a storage buffer lane by lane when the index differs
// per lane. bvh_trace's body (a triangle, a node and its two children from storage buffers, a stack push)
// paid all of that every iteration; a step here is three texel fetches (one gather per vector each) and
// one record's tests. And BVH_THREAD_UNROLL steps share one loop iteration, so llvmpipe's loop limit counts a trace
// as at most ⌈min(BVH_MAX_STEPS, records + 1) / BVH_THREAD_UNROLL⌉ iterations
// (GpuBvh::max_iterations_occluded): more shadow rays fit in one dispatch.
//
// Record k is texels 3k (a.xyz, link), 3k + 1 (b.xyz, -) and 3k + 2 (c.xyz, pair) of a uvec4 texel buffer: a
// box (a = lo, b = hi, link = the first record after its subtree; pair ≠ 0 when record k + 1 is a box too: c
// holds that box packed into this one and pair is its link) or a triangle (its vertices, link =
// BVH_THREAD_TRI; its successor is the next record).
//
// Two boxes a step: a met box whose successor is packed tests that one too, and moves past both (to k + 2 if
// it is met, else past its subtree). The step reads the third texel anyway (llvmpipe runs the triangle's side
// of the branch under masks), so the second box costs a slab test and no read. Packed, axis j of the second
// box is [lo_j + q_j · s_j, hi_j − q'_j · s_j] with s = (hi − lo) · 2^-16 and 16-bit q, q' (low and high half
// of word j of c), all rounded as written (`precise`); crates/scene/src/bvh/quant.rs picks q, q' with the
// same f32 arithmetic so that this box holds the exact one. The slab test is then bvh_hit_box on a box
// around the same triangles, which never culls what the exact box would let through: the answers do not
// change, only the steps.
layout(set = 0, binding = B_BVH_THREADED) uniform usamplerBuffer bvh_threaded;

// The walk's records.
int bvh_thread_records() {
    return textureSize(bvh_threaded) / 3;
}

// Whether the box packed as q into box [lo, hi] (see above) meets (tmin, tmax).
bool bvh_hit_packed_box(BvhRay r, vec3 lo, vec3 hi, uvec3 q, float tmin, float tmax) {
    // Through int: a 16-bit value converts exactly either way, and a signed conversion is one instruction on
    // x86 (llvmpipe), an unsigned one several.
    precise vec3 s = (hi - lo) * (1.0 / 65536.0);
    precise vec3 plo = lo + vec3(ivec3(q & 0xffffu)) * s;
    precise vec3 phi = hi - vec3(ivec3(q >> 16u)) * s;
    float tnear;
    return bvh_hit_box(r, plo, phi, tmin, tmax, tnear);
}

// Where a box step goes from box record i ([lo, hi], link a.w, third texel c): past its subtree if the box
// is missed; else to the next record, or with a packed successor past that one too (met: into its subtree;
// missed: past it).
int bvh_box_next(BvhRay r, vec3 lo, vec3 hi, uvec4 a, uvec4 c, bool met, int i, float tmin, float tmax) {
    bool second = bvh_hit_packed_box(r, lo, hi, c.xyz, tmin, tmax);
    int after = c.w == 0u ? i + 1 : (second ? i + 2 : int(c.w));
    return met ? after : int(a.w);
}

// One step of the walk: read and test record i (and its packed successor), then move on (nothing once
// `done`). Written without branches: llvmpipe runs both sides of a branch under masks anyway, and then
// blends every variable either side writes; here each is chosen once.
void bvh_thread_step(BvhRay r, float tmin, float tmax, int end, inout int i, inout uint steps, inout bool done,
                     inout bool hit) {
    // A done walk reads its last record again (in range: i can be end) and keeps its state.
    int k = min(i, end - 1);
    uvec4 a = texelFetch(bvh_threaded, 3 * k);
    vec3 b = uintBitsToFloat(texelFetch(bvh_threaded, 3 * k + 1).xyz);
    uvec4 c = texelFetch(bvh_threaded, 3 * k + 2);
    bool tri = a.w == BVH_THREAD_TRI;
    float t;
    vec2 bary;
    bool crossed = wt_hit_triangle(r.w, uintBitsToFloat(a.xyz), b, uintBitsToFloat(c.xyz), t, bary) && t > tmin &&
                   t < tmax;
    float tnear;
    vec3 lo = uintBitsToFloat(a.xyz);
    int box_next = bvh_box_next(r, lo, b, a, c, bvh_hit_box(r, lo, b, tmin, tmax, tnear), k, tmin, tmax);
    int next = tri ? k + 1 : box_next;
    bool stop = tri && crossed;
    bool live = !done;
    i = live ? next : i;
    steps += live ? 1u : 0u;
    hit = hit || (live && stop);
    // Past the last record: nothing left to test (the walk never starts there: the tree has a record).
    done = done || stop || next >= end;
}

// BVH_THREAD_UNROLL (8) steps, written out: a loop would count in llvmpipe's limit. One loop iteration of
// every walk of the threaded records (bvh_any_hit, shared/shadow_queue.glsl).
void bvh_thread_steps(BvhRay r, float tmin, float tmax, int end, inout int i, inout uint steps, inout bool done,
                      inout bool hit) {
    bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
    bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
    bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
    bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
    bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
    bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
    bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
    bvh_thread_step(r, tmin, tmax, end, i, steps, done, hit);
}

bool bvh_any_hit(vec3 o, vec3 d, float tmin, float tmax) {
    bvh_steps = 0u;
    bvh_exhausted = false;
    if (!bvh_usable_ray(o, d, tmin, tmax))
        return false;
    BvhRay r = bvh_make_ray(o, d);
    int end = bvh_thread_records();
    int i = 0;
    bool hit = false;
    bool done = false;
    uint steps = 0u;
    for (uint k = 0u; k < uint(BVH_MAX_STEPS / BVH_THREAD_UNROLL) && !done; k++)
        bvh_thread_steps(r, tmin, tmax, end, i, steps, done, hit);
    bvh_steps = steps;
    bvh_exhausted = !done;
    return hit;
}

// One step of the closest-hit walk over the threaded records: a box is entered only if it meets
// (tmin, best) (a box starting beyond the closest hit so far is skipped with its subtree); a triangle
// replaces the closest hit under bvh_trace's rule (nearer, or as near with a lower triangle index).
void bvh_closest_step(BvhRay r, float tmin, int end, inout int i, inout uint steps, inout float best,
                      inout bool found, inout uint best_tri, inout vec2 best_bary) {
    // Without branches, as bvh_thread_step: a finished walk reads its last record again and keeps its state.
    bool live = i < end;
    int k = min(i, end - 1);
    uvec4 a = texelFetch(bvh_threaded, 3 * k);
    uvec4 b = texelFetch(bvh_threaded, 3 * k + 1);
    uvec4 c = texelFetch(bvh_threaded, 3 * k + 2);
    bool tri = a.w == BVH_THREAD_TRI;
    float t;
    vec2 bary;
    bool crossed = wt_hit_triangle(r.w, uintBitsToFloat(a.xyz), uintBitsToFloat(b.xyz), uintBitsToFloat(c.xyz), t,
                                   bary) && t > tmin;
    // bvh_trace's rule: nearer, or as near with a lower triangle index.
    bool take = live && tri && crossed && (t < best || (t == best && (!found || b.w < best_tri)));
    float tnear;
    vec3 lo = uintBitsToFloat(a.xyz), hi = uintBitsToFloat(b.xyz);
    int box_next = bvh_box_next(r, lo, hi, a, c, bvh_hit_box(r, lo, hi, tmin, best, tnear), k, tmin, best);
    i = live ? (tri ? k + 1 : box_next) : i;
    steps += live ? 1u : 0u;
    found = found || take;
    best = take ? t : best;
    best_tri = take ? b.w : best_tri;
    best_bary = take ? bary : best_bary;
}

// bvh_closest's answer (the tests check every query bit for bit) by the walk the shadow rays take over the
// threaded records. It reads every record whose box meets the ray before the closest hit found so far:
// more than the ordered stack traversal, which visits the nearer child first, but each step is three
// texel fetches and one test instead of a node, its two children and a stack push. Which wins depends
// on the rays (measured: BENCHMARKS.md, "The path tracer's frames"): the reference's first hits take it
// (4–29 % less time a frame), gbg's importance rays do not (25 % more).
float bvh_closest_walk(vec3 o, vec3 d, float tmax, out uint tri, out vec2 bary) {
    tri = BVH_NO_TRI;
    bary = vec2(0.0);
    bvh_steps = 0u;
    bvh_exhausted = false;
    if (!bvh_usable_ray(o, d, 0.0, tmax)) return -1.0;
    BvhRay r = bvh_make_ray(o, d);
    int end = bvh_thread_records();
    int i = 0;
    uint steps = 0u;
    float best = tmax;
    bool found = false;
    uint best_tri = BVH_NO_TRI;
    vec2 best_bary = vec2(0.0);
    for (uint k = 0u; k < uint(BVH_MAX_STEPS / BVH_THREAD_UNROLL) && i < end; k++) {
        bvh_closest_step(r, 0.0, end, i, steps, best, found, best_tri, best_bary);
        bvh_closest_step(r, 0.0, end, i, steps, best, found, best_tri, best_bary);
        bvh_closest_step(r, 0.0, end, i, steps, best, found, best_tri, best_bary);
        bvh_closest_step(r, 0.0, end, i, steps, best, found, best_tri, best_bary);
        bvh_closest_step(r, 0.0, end, i, steps, best, found, best_tri, best_bary);
        bvh_closest_step(r, 0.0, end, i, steps, best, found, best_tri, best_bary);
        bvh_closest_step(r, 0.0, end, i, steps, best, found, best_tri, best_bary);
        bvh_closest_step(r, 0.0, end, i, steps, best, found, best_tri, best_bary);
    }
    bvh_steps = steps;
    if (i < end) {
        bvh_exhausted = true;
        return -1.0;
    }
    if (!found) return -1.0;
    tri = best_tri;
    bary = best_bary;
    return best;
}

float bvh_closest(vec3 o, vec3 d, float tmax, out uint tri, out vec2 bary) {
    return bvh_trace(o, d, 0.0, tmax, false, tri, bary);
}

bool bvh_occluded(vec3 a, vec3 b) {
    return bvh_any_hit(a, b - a, BVH_SHADOW_EPS, 1.0 - BVH_SHADOW_EPS);
}

// Occlusion between two points already lifted off their surfaces (surface_lift, ~32 ulps of their
// coordinates): the segment's ends need no window of their own, only one against rounding, so it is
// BVH_LIFTED_EPS = 1e-6 of the segment instead of BVH_SHADOW_EPS. With the 1e-4 window, a wall within
// 0.01 % of the segment length of a lifted end did not count: a VPL in the corner of a closed box, lifted
// by 2e-5, saw out through the wall next to it from 0.9 away.
const float BVH_LIFTED_EPS = 1e-6;
bool bvh_occluded_lifted(vec3 a, vec3 b) {
    return bvh_any_hit(a, b - a, BVH_LIFTED_EPS, 1.0 - BVH_LIFTED_EPS);
}
#endif
