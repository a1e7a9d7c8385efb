// Ray casting against the scene's BVH: closest hit and segment occlusion. Includes only bindings.glsl;
// crates/scene/src/bvh/ builds the buffers (the binned-SAH tree the CPU reference walks too)
// and documents the layout; tests/tests/bvh.rs checks every function here against that CPU reference.
//
// Buffers (read-only uvec4 texel buffers holding the std430 bytes of GpuBvhNode / GpuBvhTri / GpuThreadRec in
// crates/scene/src/bvh/flat.rs, 32, 48 and 48 bytes: two, three and three texels; read through bvh_node / bvh_tri / the walk):
//  * node i = { lo, first, hi, count }: the box [lo, hi] (f32, exact bounds of the f32 vertices). A leaf
//    (count > 0) holds the triangles first .. first + count; an interior node (count == 0) has the
//    children first and first + 1 (adjacent, so one visit reads both boxes). Node 0 is the root. The tree is at
//    most BVH_STACK_SIZE levels deep below the root (bvh.rs guarantees it), so the stack never overflows.
//  * triangle j = { v0, tri, v1, -, v2, - }: the three vertex positions of the scene triangle `tri` (vertices
//    3·tri .. 3·tri+3 of the scene), stored again in leaf order so a leaf is one contiguous run. Zero-area
//    triangles are left out (they are never hit, as in the CPU reference).
//  * the threaded records: the same tree for the stackless walks (bvh_any_hit and bvh_closest_walk,
//    below); a triangle record's b.w is its scene triangle.
//
// Functions (d need not be unit; t is in units of |d|, the hit is at o + t·d):
//  * float bvh_closest(o, d, tmax, out tri, out bary): the closest hit with t ∈ (0, tmax], or −1. `tri` is the
//    scene triangle, `bary` the weights of its vertices 1 and 2 (vertex 0 gets 1 − bary.x − bary.y). Ties at
//    exactly equal t go to the lower triangle index, as in cpu_ref's Bvh::intersect.
//  * bool bvh_occluded(a, b): whether a triangle crosses the segment a → b with segment parameter
//    t ∈ (BVH_SHADOW_EPS, 1 − BVH_SHADOW_EPS), both ends open: cpu_ref's Bvh::occluded rule with the same
//    relative epsilon SHADOW_EPS = 1e-4. Relative, so it scales with the segment: it keeps the endpoints' own
//    surfaces from occluding (a point computed on a triangle is within f32 rounding, ~1e-7 of its coordinates,
//    of the plane) while any occluder farther than 0.01 % of the segment length from both ends counts.
//  * bool bvh_occluded_lifted(a, b): the same with a window of BVH_LIFTED_EPS = 1e-6 at both ends, for ends
//    already lifted off their surfaces (the exact gather's shadow rays; see the function).
//    Both are bvh_any_hit(o, d, tmin, tmax): the stackless walk over the threaded records, with its own
//    iteration bound (see the function). shared/shadow_queue.glsl runs the same walk (bvh_thread_step) for
//    many rays back to back.
//  * float bvh_closest_walk(o, d, tmax, out tri, out bary): bvh_closest's answer by the threaded walk (see
//    the function for which callers it suits).
//  * float bvh_trace(o, d, tmin, tmax, any_hit, out tri, out bary): the stack traversal behind bvh_closest.
//    Closest mode accepts t ∈ (tmin, tmax]; any-hit mode t ∈ (tmin, tmax) and stops at the first such hit
//    (the same answer as bvh_any_hit, which the tests check).
// Non-finite input, a direction with no component of magnitude ≥ 1e-30, or tmax ≤ tmin gives "no hit" at once.
//
// Triangle test: watertight ray–triangle intersection (Woop, Benthin and Wald 2013) in f32. The ray is sheared
// so that it runs along +z from the origin; each vertex is mapped to that frame by a function of the vertex and
// the ray alone, and the three 2D edge functions are `precise` (no fused multiply-add), so two triangles that
// share an edge compute exactly opposite values for it: a ray can never slip between them, even through a
// shared vertex. Edges count as inside (an edge function of exactly 0 passes), so a ray through an edge hits
// one or both of its triangles (the CPU reference is edge-inclusive too). Box test: slabs with the far distance
// grown by BVH_BOX_GROW (8 ulps), so rounding never culls a box whose triangle the exact test would hit (flat
// boxes of axis-aligned walls included). A direction component below BVH_MIN_DIR counts as ±BVH_MIN_DIR there;
// a ray lying exactly in the plane of a flat box then sees it only at its origin, which loses nothing: such a
// box holds only triangles in that plane, which the ray could meet edge-on at most.
//
// Traversal and its iteration bound (bvh_trace; the threaded walks have their own, see bvh_any_hit). One loop; each iteration is exactly one of: test one triangle of the
// current leaf; visit one node (read its two children, test both boxes, descend into the nearer one and push the
// other with its entry distance); pop a node whose entry distance is beyond the closest hit so far (culled); or
// the final iteration that finds the stack empty. A node is visited or popped at most once and a triangle tested
// at most once per call, so a call takes at most min(BVH_MAX_STEPS, nodes + triangles + 1) iterations: what
// GpuBvh::max_iterations_per_ray() in bvh.rs returns. There is no other loop. llvmpipe silently stops every
// loop of an invocation after 65535 iterations in total (Gpu::loop_iteration_limit), so a shader that traces n
// rays per invocation must keep n · max_iterations_per_ray() plus its other loop iterations under that limit,
// and split its work over dispatches otherwise. If a call reaches BVH_MAX_STEPS (never on the scenes measured:
// see bvh.rs), it gives up and answers "no hit" (bvh_closest −1, bvh_occluded false) with bvh_exhausted = true;
// a stack overflow, impossible with buffers from bvh.rs, gives the same answer.
//
// After every call, bvh_steps holds the steps it used (bvh_trace: loop iterations; bvh_any_hit: records read)
// and bvh_exhausted whether it gave up.
#ifndef BOUNCE_BVH_GLSL
#define BOUNCE_BVH_GLSL

// Binding numbers, bounds and epsilons: glsl/shared/bindings.glsl (the single source, also for Rust).
#include "bindings.glsl"
#include "watertight.glsl"

// BVH_NO_TRI (bvh_tri of "no hit") and BVH_SHADOW_EPS (bvh_occluded's relative end epsilon): bindings.glsl.
// 1 + 2^-20: growth of a box's far distance (and of the culling distance) against rounding.
const float BVH_BOX_GROW = 1.0 + 1.0 / 1048576.0;
// Direction components smaller than this in magnitude are replaced by ±this in the box test's reciprocal, so
// 1/d stays finite and 0 · (1/d) never makes a NaN.
const float BVH_MIN_DIR = 1e-30;

struct BvhNode {
    vec3 lo;
    uint first;
    vec3 hi;
    uint count;
};

struct BvhTri {
    vec3 v0;
    uint tri;
    vec3 v1;
    uint pad1;
    vec3 v2;
    uint pad2;
};

// Both buffers are read as uvec4 texel buffers (a node is two texels, a triangle three, their std430 bytes):
// llvmpipe fetches a texel for all lanes of a vector at once, where a storage-buffer read with a different
// index per lane goes lane by lane (measured: BENCHMARKS.md, "Exact shadow rays").
layout(set = 0, binding = B_BVH_NODES) uniform usamplerBuffer bvh_nodes;
layout(set = 0, binding = B_BVH_TRIS) uniform usamplerBuffer bvh_tris;

BvhNode bvh_node(uint i) {
    uvec4 a = texelFetch(bvh_nodes, int(2u * i));
    uvec4 b = texelFetch(bvh_nodes, int(2u * i + 1u));
    return BvhNode(uintBitsToFloat(a.xyz), a.w, uintBitsToFloat(b.xyz), b.w);
}

BvhTri bvh_tri(uint j) {
    uvec4 a = texelFetch(bvh_tris, int(3u * j));
    vec3 b = uintBitsToFloat(texelFetch(bvh_tris, int(3u * j + 1u)).xyz);
    vec3 c = uintBitsToFloat(texelFetch(bvh_tris, int(3u * j + 2u)).xyz);
    return BvhTri(uintBitsToFloat(a.xyz), a.w, b, 0u, c, 0u);
}

// Loop iterations of the last bvh_* call, and whether it gave up (see the header).
uint bvh_steps = 0u;
bool bvh_exhausted = false;

// A ray prepared for the box and triangle tests: the watertight frame (shared/watertight.glsl) and 1/d.
struct BvhRay {
    WtRay w;
    vec3 inv_d; // 1 / d, with tiny components replaced by ±BVH_MIN_DIR
};

float bvh_reciprocal_dir(float c) {
    return 1.0 / (abs(c) < BVH_MIN_DIR ? (c < 0.0 ? -BVH_MIN_DIR : BVH_MIN_DIR) : c);
}

BvhRay bvh_make_ray(vec3 o, vec3 d) {
    BvhRay r;
    r.w = wt_make_ray(o, d);
    r.inv_d = vec3(bvh_reciprocal_dir(d.x), bvh_reciprocal_dir(d.y), bvh_reciprocal_dir(d.z));
    return r;
}

bool bvh_hit_triangle(BvhRay r, BvhTri tr, out float t, out vec2 bary) {
    return wt_hit_triangle(r.w, tr.v0, tr.v1, tr.v2, t, bary);
}

// min and max as a comparison and a select. The slab test's operands are never NaN (finite o, lo and hi, and
// 1/d finite by BVH_MIN_DIR), where these agree with min and max (a zero's sign aside, which no comparison
// sees). llvmpipe makes min and max NaN-safe, three instructions each; this is one on x86.
vec3 bvh_min(vec3 a, vec3 b) {
    return mix(b, a, lessThan(a, b));
}
vec3 bvh_max(vec3 a, vec3 b) {
    return mix(b, a, greaterThan(a, b));
}
float bvh_min(float a, float b) {
    return a < b ? a : b;
}
float bvh_max(float a, float b) {
    return a > b ? a : b;
}

// Slab test of box [lo, hi] against (tmin, tmax): whether they meet, and the entry distance.
bool bvh_hit_box(BvhRay r, vec3 lo, vec3 hi, float tmin, float tmax, out float tnear) {
    vec3 t0 = (lo - r.w.o) * r.inv_d;
    vec3 t1 = (hi - r.w.o) * r.inv_d;
    vec3 ts = bvh_min(t0, t1);
    vec3 tb = bvh_max(t0, t1);
    float near = bvh_max(bvh_max(ts.x, ts.y), bvh_max(ts.z, tmin));
    float far = bvh_min(bvh_min(tb.x, tb.y), tb.z) * BVH_BOX_GROW;
    far = bvh_min(far, tmax * BVH_BOX_GROW);
    tnear = near;
    return near <= far;
}

bool bvh_finite(vec3 v) {
    return !any(isnan(v)) && !any(isinf(v));
}

// What every trace asks of its input (see the header): finite o and d, a direction component of magnitude
// ≥ BVH_MIN_DIR, and tmin < tmax, neither NaN. Anything else is "no hit" at once.
bool bvh_usable_ray(vec3 o, vec3 d, float tmin, float tmax) {
    float dmax = max(abs(d.x), max(abs(d.y), abs(d.z)));
    return bvh_finite(o) && bvh_finite(d) && dmax >= BVH_MIN_DIR && !isnan(tmin) && !isnan(tmax) && tmax > tmin;
}

float bvh_trace(vec3 o, vec3 d, float tmin, float tmax, bool any_hit, out uint tri, out vec2 bary) {
    tri = BVH_NO_TRI;
    bary = vec2(0.0);
    bvh_steps = 0u;
    bvh_exhausted = false;
    if (!bvh_usable_ray(o, d, tmin, tmax))
        return -1.0;
    BvhRay r = bvh_make_ray(o, d);

    uint stack_node[BVH_STACK_SIZE];
    float stack_t[BVH_STACK_SIZE];
    int sp = 0;

    bool found = false;
    float best_t = tmax;
    uint best_tri = BVH_NO_TRI;
    vec2 best_bary = vec2(0.0);

    // The node to visit next (when `have`), and the triangles of the current leaf still to test.
    float troot;
    BvhNode root = bvh_node(0u);
    bool have = bvh_hit_box(r, root.lo, root.hi, tmin, tmax, troot);
    uint node = 0u;
    uint next_tri = 0u;
    uint end_tri = 0u;
    bool done = false;
    uint steps = 0u;
    for (; steps < uint(BVH_MAX_STEPS); steps++) {
        if (next_tri < end_tri) {
            BvhTri tr = bvh_tri(next_tri);
            next_tri++;
            float t;
            vec2 b;
            if (bvh_hit_triangle(r, tr, t, b) && t > tmin) {
                bool take;
                if (any_hit) {
                    take = t < tmax;
                } else {
                    take = t < best_t || (t == best_t && (!found || tr.tri < best_tri));
                }
                if (take) {
                    found = true;
                    best_t = t;
                    best_tri = tr.tri;
                    best_bary = b;
                    if (any_hit) {
                        steps++;
                        done = true;
                        break;
                    }
                }
            }
            continue;
        }
        if (!have) {
            if (sp == 0) {
                steps++;
                done = true;
                break;
            }
            sp--;
            // Culled: it starts beyond the closest hit found since it was pushed.
            if (stack_t[sp] > best_t * BVH_BOX_GROW) continue;
            node = stack_node[sp];
        }
        have = false;
        BvhNode n = bvh_node(node);
        if (n.count > 0u) {
            next_tri = n.first;
            end_tri = n.first + n.count;
            continue;
        }
        uint l = n.first;
        BvhNode cl = bvh_node(l);
        BvhNode cr = bvh_node(l + 1u);
        float tl, trr;
        bool hl = bvh_hit_box(r, cl.lo, cl.hi, tmin, best_t, tl);
        bool hr = bvh_hit_box(r, cr.lo, cr.hi, tmin, best_t, trr);
        if (hl && hr) {
            if (sp >= BVH_STACK_SIZE) break; // impossible with bvh.rs's buffers: give up (exhausted)
            bool left_first = tl <= trr;
            stack_node[sp] = left_first ? l + 1u : l;
            stack_t[sp] = left_first ? trr : tl;
            sp++;
            hr = !left_first;
            hl = left_first;
        }
        // Descend into the one child left to visit; a leaf's triangles start at once.
        if (hl || hr) {
            BvhNode c = hl ? cl : cr;
            if (c.count > 0u) {
                next_tri = c.first;
                end_tri = c.first + c.count;
            } else {
                node = hl ? l : l + 1u;
                have = true;
            }
        }
    }
    bvh_steps = steps;
    if (!done) {
        bvh_exhausted = true;
        return -1.0;
    }
    if (!found) return -1.0;
    tri = best_tri;
    bary = best_bary;
    return best_t;
}

// The threaded walks (bvh_any_hit, bvh_closest_walk, bvh_closest, bvh_occluded, bvh_occluded_lifted).
#include "bvh_threaded.glsl"

#endif
