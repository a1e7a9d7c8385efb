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
// iterations, and at most HYBRID_MAX_TRACES traversals of at most max_iterations_per_ray each: once
// HYBRID_MAX_TRACES − 1 runs are traced, the last traversal covers everything from the next run to tmax.
#ifndef BOUNCE_HYBRID_GLSL
#define BOUNCE_HYBRID_GLSL

// Trace the parameter interval [lo, hi] ∩ (tmin, tmax) of the ray; < 0 when nothing is hit there.
float hybrid_trace_run(vec3 o, vec3 d, float lo, float hi, float tmin, float tmax, bool any_hit, out uint tri,
                       out vec2 bary) {
    float a = max(lo, tmin);
    float b = min(hi, tmax);
    tri = BVH_NO_TRI;
    bary = vec2(0.0);
    if (!(b > a)) return -1.0;
    return bvh_trace(o, d, a, b, any_hit, tri, bary);
}

float hybrid_trace(vec3 o, vec3 d, float tmin, float tmax, bool any_hit, out uint tri, out vec2 bary) {
    tri = BVH_NO_TRI;
    bary = vec2(0.0);
    uvec3 du = frame.voxel_dims.xyz;
    // No grid: nothing to skip.
    if (du.x == 0u || du.y == 0u || du.z == 0u) return bvh_trace(o, d, tmin, tmax, any_hit, tri, bary);
    if (!voxel_finite(o) || !voxel_finite(d) || isnan(tmin) || isnan(tmax) || !(tmax > tmin)) return -1.0;
    ivec3 dims = ivec3(du);
    vec3 dimsf = vec3(du);
    float inv = voxel_rcp(frame.voxel_origin.w);
    vec3 a = voxel_to_grid(o, inv);
    vec3 gd = d * inv;
    float len = length(gd);
    if (!(len > 0.0) || isinf(len)) return bvh_trace(o, d, tmin, tmax, any_hit, tri, bary);
    // Half a cell of ray parameter: the growth of each run's interval.
    float margin = 0.5 / len;

    float t0 = tmin;
    float t1 = tmax;
    vec3 invd;
    bvec3 moving;
    bool outside = false;
    voxel_clip_axis(a.x, gd.x, dimsf.x, t0, t1, invd.x, moving.x, outside);
    voxel_clip_axis(a.y, gd.y, dimsf.y, t0, t1, invd.y, moving.y, outside);
    voxel_clip_axis(a.z, gd.z, dimsf.z, t0, t1, invd.z, moving.z, outside);
    if (outside || t0 > t1) return -1.0;

    ivec3 cell = ivec3(clamp(floor(a + gd * t0), vec3(0.0), dimsf - 1.0));
    ivec3 step = ivec3(gd.x > 0.0 ? 1 : -1, gd.y > 0.0 ? 1 : -1, gd.z > 0.0 ? 1 : -1);
    int max_steps = dims.x + dims.y + dims.z + 3;
    // The open run: its entry parameter (< 0: none open). `enter` is where the march entered `cell`.
    float run = -1.0;
    float enter = t0;
    uint traces = 0u;
    for (int n = 0; n < max_steps; n++) {
        float tx = voxel_exit_t(cell.x, a.x, gd.x, invd.x, moving.x);
        float ty = voxel_exit_t(cell.y, a.y, gd.y, invd.y, moving.y);
        float tz = voxel_exit_t(cell.z, a.z, gd.z, invd.z, moving.z);
        float best = min(tx, min(ty, tz));
        int m = tx <= ty && tx <= tz ? 0 : (ty <= tz ? 1 : 2);
        bool last = best > t1;
        if (voxel_occupied(cell)) {
            if (run < 0.0) run = enter;
            if (traces + 1u == uint(HYBRID_MAX_TRACES)) {
                // The last traversal allowed: everything from this run on.
                return hybrid_trace_run(o, d, run - margin, tmax, tmin, tmax, any_hit, tri, bary);
            }
        } else if (run >= 0.0) {
            float t = hybrid_trace_run(o, d, run - margin, enter + margin, tmin, tmax, any_hit, tri, bary);
            if (t >= 0.0) return t;
            traces++;
            run = -1.0;
        }
        if (last) break;
        enter = best;
        cell[m] += step[m];
        if (cell[m] < 0 || cell[m] >= dims[m]) break;
    }
    // A run still open where the march left the grid or reached t1.
    if (run >= 0.0) return hybrid_trace_run(o, d, run - margin, t1 + margin, tmin, tmax, any_hit, tri, bary);
    return -1.0;
}

// Occlusion between two lifted points, as bvh_occluded_lifted.
bool hybrid_occluded_lifted(vec3 a, vec3 b) {
    uint tri;
    vec2 bary;
    return hybrid_trace(a, b - a, BVH_LIFTED_EPS, 1.0 - BVH_LIFTED_EPS, true, tri, bary) >= 0.0;
}

#endif
