// `--visibility hybrid`: exact visibility (the BVH's answer, bit for bit) that traverses the BVH only where
// the voxel grid says a triangle may be. Include after voxel.glsl and bvh.glsl.
//
// hybrid_trace(o, d, tmin, tmax, any_hit, tri, bary) answers what bvh_trace(o, d, tmin, tmax, ...) answers.
// It marches the grid along o + t·d (Amanatides–Woo, no endpoint offset, the segment clipped to the grid
// box) and collects the *runs* of consecutive occupied cells; each run, as a parameter interval grown by
// half a cell on both sides, is traced against the real triangles with bvh_trace, in order along the ray.
// Why this is bvh_trace's answer: the voxelization is conservative (a cell is marked when a triangle comes
// within VOXEL_EPS of it), so every point where the ray meets a triangle lies in an occupied cell the march
// visits, inside one run's interval (the half-cell growth absorbs the rounding of the march's parameters
// against the world-space ray). The BVH is traced with the same o and d as bvh_trace, so every triangle
// gives the same t; an interval only narrows which t count. Any-hit: occluded iff some run holds a hit.
// Closest: the runs come in order of t, so the first run with a hit holds the closest one (a hit in an
// earlier interval would have been found there). Outside the grid box there is no geometry (the grid's
// margin, passes/voxelize.rs). Empty cells cost one bit test; the voxel march's biases (the 2-cell end skip,
// which leaks, and conservative cells, which darken junctions) are gone, because cells only decide where to
// look, never what is hit.
//
// Work bound (llvmpipe's per-invocation loop limit): the march takes at most dims.x + dims.y + dims.z + 3
// iterations in all, plus at most HYBRID_MAX_TRACES iterations of the loop over runs, and at most
// HYBRID_MAX_TRACES traversals of at most max_iterations_per_ray each: once HYBRID_MAX_TRACES − 1 runs are
// traced, the last traversal covers everything from the next occupied cell to tmax.
#ifndef BOUNCE_HYBRID_GLSL
#define BOUNCE_HYBRID_GLSL

// The march's state along the ray, in grid units: a + t·gd, t clipped to [t0, t1]; `cell` the current cell,
// entered at parameter `enter`; `n` the cells tested so far (bounded by dims.x + dims.y + dims.z + 3 over
// all calls, as voxel_visibility's march); `ended` once the march has left the grid or passed t1.
struct HybridMarch {
    vec3 a, gd, invd;
    bvec3 moving;
    float t1, enter;
    ivec3 cell, step;
    int n;
    bool ended;
};

// Advance to the end of the next run of occupied cells (to the end of the march when `to_end`): its
// interval [lo, hi] (hi is where the run was left, or t1), or false when no occupied cell is left.
bool hybrid_next_run(inout HybridMarch m, bool to_end, out float lo, out float hi) {
    ivec3 dims = ivec3(frame.voxel_dims.xyz);
    int max_steps = dims.x + dims.y + dims.z + 3;
    lo = -1.0;
    hi = m.t1;
    for (; !m.ended && m.n < max_steps; m.n++) {
        bool occupied = voxel_occupied(m.cell);
        if (occupied && lo < 0.0) lo = m.enter;
        if (!occupied && lo >= 0.0 && !to_end) {
            hi = m.enter;
            return true;
        }
        // Step through the nearest exit plane (x before y before z on ties), as voxel_visibility does.
        float tx = voxel_exit_t(m.cell.x, m.a.x, m.gd.x, m.invd.x, m.moving.x);
        float ty = voxel_exit_t(m.cell.y, m.a.y, m.gd.y, m.invd.y, m.moving.y);
        float tz = voxel_exit_t(m.cell.z, m.a.z, m.gd.z, m.invd.z, m.moving.z);
        float best = min(tx, min(ty, tz));
        int k = tx <= ty && tx <= tz ? 0 : (ty <= tz ? 1 : 2);
        m.enter = best;
        m.cell[k] += m.step[k];
        if (best > m.t1 || m.cell[k] < 0 || m.cell[k] >= dims[k]) m.ended = true;
    }
    m.ended = true;
    return lo >= 0.0;
}

float hybrid_trace(vec3 o, vec3 d, float tmin, float tmax, bool any_hit, out uint tri, out vec2 bary) {
    tri = BVH_NO_TRI;
    bary = vec2(0.0);
    if (!voxel_finite(o) || !voxel_finite(d) || isnan(tmin) || isnan(tmax) || !(tmax > tmin)) return -1.0;
    uvec3 du = frame.voxel_dims.xyz;
    float inv = voxel_rcp(frame.voxel_origin.w);
    HybridMarch m;
    m.a = voxel_to_grid(o, inv);
    m.gd = d * inv;
    float len = length(m.gd);
    // No grid, or a ray the grid cannot step along: one traversal of the whole interval.
    bool whole = du.x == 0u || du.y == 0u || du.z == 0u || !(len > 0.0) || isinf(len);
    // Half a cell of ray parameter: the growth of each run's interval.
    float margin = 0.5 / len;
    float t0 = tmin;
    m.t1 = tmax;
    bool outside = false;
    vec3 dimsf = vec3(du);
    voxel_clip_axis(m.a.x, m.gd.x, dimsf.x, t0, m.t1, m.invd.x, m.moving.x, outside);
    voxel_clip_axis(m.a.y, m.gd.y, dimsf.y, t0, m.t1, m.invd.y, m.moving.y, outside);
    voxel_clip_axis(m.a.z, m.gd.z, dimsf.z, t0, m.t1, m.invd.z, m.moving.z, outside);
    m.ended = outside || t0 > m.t1;
    if (!whole && m.ended) return -1.0;
    m.enter = t0;
    m.cell = ivec3(clamp(floor(m.a + m.gd * t0), vec3(0.0), max(dimsf - 1.0, vec3(0.0))));
    m.step = ivec3(m.gd.x > 0.0 ? 1 : -1, m.gd.y > 0.0 ? 1 : -1, m.gd.z > 0.0 ? 1 : -1);
    m.n = 0;
    // One traversal per run, the last one allowed covering every run left: one call site of bvh_trace
    // (each inlined copy of its loop and stack costs llvmpipe registers and time).
    for (uint k = 0u; k < uint(HYBRID_MAX_TRACES); k++) {
        float lo = tmin, hi = tmax;
        if (!whole) {
            bool last = k + 1u == uint(HYBRID_MAX_TRACES);
            if (!hybrid_next_run(m, last, lo, hi)) return -1.0;
            lo = max(lo - margin, tmin);
            hi = last || m.ended ? tmax : min(hi + margin, tmax);
        }
        float t = -1.0;
        if (hi > lo) t = bvh_trace(o, d, lo, hi, any_hit, tri, bary);
        if (t >= 0.0 || whole || m.ended) return t;
    }
    return -1.0;
}

// Occlusion between two lifted points, as bvh_occluded_lifted.
bool hybrid_occluded_lifted(vec3 a, vec3 b) {
    uint tri;
    vec2 bary;
    return hybrid_trace(a, b - a, BVH_LIFTED_EPS, 1.0 - BVH_LIFTED_EPS, true, tri, bary) >= 0.0;
}

#endif
