// `--visibility hybrid`: exact visibility, the BVH's answer bit for bit, found by a march through
// a grid of triangle lists. Include after voxel.glsl and bvh.glsl.
//
// hybrid_trace(o, d, tmin, tmax, any_hit, tri, bary) answers what bvh_trace(o, d, tmin, tmax, ...) answers.
// Structure (crates/graph/src/bvh/cells.rs): over the voxel grid's box, a grid of cells frame.cells.w voxels
// wide (about CELL_DENSITY cells per triangle: a coarse grid for a small scene, a fine one for a large); cell c lists the BVH triangles that come within CELL_MARGIN (1/64 of a cell) of it. The march (Amanatides–
// Woo in list-grid units along o + t·d, clipped to the grid box and to [tmin, tmax]) tests, in each cell it
// enters, that cell's triangles with bvh_hit_triangle: the same watertight test and the same ray as bvh_trace,
// so every triangle gives the same t.
// Why this is bvh_trace's answer: a hit of the exact test lies in a cell the march enters, up to the march's
// f32 rounding (~1e-4 cell), and every triangle within 1/64 cell of a cell is in its list. Any-hit: occluded
// iff some tested triangle has t in (tmin, tmax). Closest: a hit found before the march leaves a cell by more
// than HYBRID_STOP cells is the closest (every closer hit lies in this or an earlier cell, whose triangles are
// tested); otherwise the march goes on. No end skip, no thickening: cells only decide where to look, never
// what is hit, so the voxel march's biases (the 2-cell end skip, which leaks, and conservative cells, which
// darken junctions) are gone.
//
// Work bound (llvmpipe's per-invocation loop limit): at most ldims.x + ldims.y + ldims.z + 3 march steps (each
// crosses one grid plane) and HYBRID_MAX_TESTS triangle tests in all; a cell whose list would pass that budget
// hands the rest of the ray, from where it entered that cell, to one bvh_trace (at most
// max_iterations_per_ray): Renderer::vpls_per_dispatch adds the three.
#ifndef BOUNCE_HYBRID_GLSL
#define BOUNCE_HYBRID_GLSL

layout(std430, set = 0, binding = B_CELL_OFFSETS) readonly buffer CellOffsets { uint cell_offsets[]; };
layout(std430, set = 0, binding = B_CELL_TRIS) readonly buffer CellTris { uint cell_tris[]; };

// Distance (cells) by which the march's rounding may misplace a point: the closest-hit stop and the start of a
// BVH hand-over keep this much ray on the safe side. Far below CELL_MARGIN's 1/64, far above f32 rounding.
const float HYBRID_STOP = 1.0 / 256.0;


float hybrid_trace(vec3 o, vec3 d, float tmin, float tmax, bool any_hit, out uint tri, out vec2 bary) {
    tri = BVH_NO_TRI;
    bary = vec2(0.0);
    float dmax = max(abs(d.x), max(abs(d.y), abs(d.z)));
    if (!voxel_finite(o) || !voxel_finite(d) || !(dmax >= BVH_MIN_DIR) || isnan(tmin) || isnan(tmax) || !(tmax > tmin))
        return -1.0;
    // The list grid: the voxel grid's box in cells CELL_BRICK voxels wide.
    uvec3 du = frame.cells.xyz;
    ivec3 dims = ivec3(du);
    float inv = voxel_rcp(frame.voxel_origin.w * float(frame.cells.w));
    vec3 a = voxel_to_grid(o, inv);
    vec3 gd = d * inv;
    float len = length(gd);
    float stop = HYBRID_STOP / len;
    // The ray parameter from which one BVH traversal finishes the trace, or −1: the whole ray when the grid
    // cannot be stepped along it.
    float handover = (du.x == 0u || du.y == 0u || du.z == 0u || !(len > 0.0) || isinf(len)) ? tmin : -1.0;
    float t0 = tmin, t1 = tmax;
    vec3 invd;
    bvec3 moving;
    bool outside = false;
    vec3 dimsf = vec3(du);
    voxel_clip_axis(a.x, gd.x, dimsf.x, t0, t1, invd.x, moving.x, outside);
    voxel_clip_axis(a.y, gd.y, dimsf.y, t0, t1, invd.y, moving.y, outside);
    voxel_clip_axis(a.z, gd.z, dimsf.z, t0, t1, invd.z, moving.z, outside);
    BvhRay r = bvh_make_ray(o, d);
    bool found = false;
    float best_t = tmax;
    uint best_tri = BVH_NO_TRI;
    vec2 best_bary = vec2(0.0);
    if (handover < 0.0 && !outside && t0 <= t1) {
        precise vec3 start = a + gd * t0;
        ivec3 cell = ivec3(clamp(floor(start), vec3(0.0), dimsf - 1.0));
        ivec3 step = ivec3(gd.x > 0.0 ? 1 : -1, gd.y > 0.0 ? 1 : -1, gd.z > 0.0 ? 1 : -1);
        float enter = t0;
        uint tests = 0u;
        int max_steps = dims.x + dims.y + dims.z + 3;
        for (int n = 0; n < max_steps; n++) {
            uint c = uint(cell.x) + du.x * (uint(cell.y) + du.y * uint(cell.z));
            uint j = cell_offsets[c], jend = cell_offsets[c + 1u];
            if (jend > j) {
                if (jend - j > uint(HYBRID_MAX_TESTS) - tests) {
                    handover = max(enter - stop, tmin);
                    break;
                }
                tests += jend - j;
                for (; j < jend; j++) {
                    BvhTri tr = bvh_tri(cell_tris[j]);
                    float t;
                    vec2 b;
                    if (!bvh_hit_triangle(r, tr, t, b) || !(t > tmin)) continue;
                    bool take = any_hit ? t < tmax : (t < best_t || (t == best_t && (!found || tr.tri < best_tri)));
                    if (take) {
                        found = true;
                        best_t = t;
                        best_tri = tr.tri;
                        best_bary = b;
                        if (any_hit) break;
                    }
                }
                if (found && any_hit) break;
            }
            float tx = voxel_exit_t(cell.x, a.x, gd.x, invd.x, moving.x);
            float ty = voxel_exit_t(cell.y, a.y, gd.y, invd.y, moving.y);
            float tz = voxel_exit_t(cell.z, a.z, gd.z, invd.z, moving.z);
            float exit_t = tx;
            int m = 0;
            if (ty < exit_t) { exit_t = ty; m = 1; }
            if (tz < exit_t) { exit_t = tz; m = 2; }
            if (found && best_t < exit_t - stop) break;
            if (exit_t > t1) break;
            cell[m] += step[m];
            if (cell[m] < 0 || cell[m] >= dims[m]) break;
            enter = exit_t;
        }
    }
    if (handover >= 0.0 && !(found && any_hit)) {
        // One call site of bvh_trace (each inlined copy costs llvmpipe registers and time).
        uint t2;
        vec2 b2;
        float t = bvh_trace(o, d, handover, any_hit || !found ? tmax : best_t, any_hit, t2, b2);
        if (t >= 0.0 && (!found || t < best_t || (t == best_t && t2 < best_tri))) {
            found = true;
            best_t = t;
            best_tri = t2;
            best_bary = b2;
        }
    }
    if (!found) return -1.0;
    tri = best_tri;
    bary = best_bary;
    return best_t;
}

// Occlusion between two lifted points, as bvh_occluded_lifted.
bool hybrid_occluded_lifted(vec3 a, vec3 b) {
    uint tri;
    vec2 bary;
    return hybrid_trace(a, b - a, BVH_LIFTED_EPS, 1.0 - BVH_LIFTED_EPS, true, tri, bary) >= 0.0;
}

#endif
