// The voxel grid: occupancy bits, the world → grid mapping, and the visibility march used by the gather
// shaders. Include after scene.glsl (it needs `frame`). crates/graph/src/cpu_voxel.rs is the CPU twin of
// everything here, operation for operation; tests/tests/voxelize.rs checks that both give the same bits.
//
// Grid: `frame.voxel_origin.xyz` is the world position of the grid's minimum corner, `.w` the cell size
// (cubic cells); `frame.voxel_dims.xyz` the cells per axis. Grid units: g = (p − origin) · voxel_rcp(cell),
// so cell (i, j, k) is the unit cube [i, i+1] × [j, j+1] × [k, k+1]. Cell c = x + dims.x · (y + dims.y · z)
// is bit (c % 32) of word (c / 32) of `voxel_bits`.
//
// Bit-identical CPU and GPU. Vulkan makes +, − and × correctly rounded but allows `/` 2.5 ulp, and a
// compiler may fuse a·b + c into one fma (a different rounding). So: every float temporary that feeds a
// decision is `precise` (SPIR-V NoContraction: no fusion, no reassociation), sums are written out in a
// fixed order (no dot()/cross() whose order is the driver's), and there is no division: reciprocals come
// from voxel_rcp (an integer first guess and Newton steps, i.e. only × and −). The CPU does the same f32
// operations in the same order, so both sides get the same bits, not merely close ones.
//
// Visibility march, voxel_visibility(x, nx, y, ny), 1 = visible, 0 = occluded:
//  * Endpoint rule. The march runs from a = g(x) + 2·nx to b = g(y) + 2·ny (grid units, i.e. an offset
//    of δ = VOXEL_OFFSET_CELLS = 2 cells along each unit normal). The caller orients nx towards y's side
//    and ny towards x's side (cos > 0 at both ends; otherwise the contribution is 0 anyway). Why 2 cells:
//    the conservative voxelization marks a cell when a surface comes within VOXEL_EPS of it, so a point
//    2 cells off a plane is farther than one cell diagonal (√3 < 2) from the plane's marked cells and a
//    surface never shadows itself; any occluder more than ~2 cells from both endpoints, even one cell
//    thick, is found, because the march visits every cell the segment a→b passes through.
//  * If the offset segment points backwards, dot(b − a, g(y) − g(x)) ≤ 0 (the endpoints are within about
//    4 cells of each other and the offsets crossed), the pair is visible: there is no room for an occluder
//    the grid can resolve.
//  * a→b is clipped to the grid box [0, dims] (slab test); outside the grid nothing is occupied. Every cell
//    the clipped segment enters, both end cells included, is tested (Amanatides–Woo 3D-DDA). Where the
//    segment crosses two planes at exactly the same parameter (it runs through a cell edge or corner), the
//    march steps x before y before z and so visits one of the cells that only touch the segment there.
//  * The loop is bounded by dims.x + dims.y + dims.z + 3 steps (a segment inside the box crosses at most
//    dims.x + dims.y + dims.z planes), so it cannot hang on any input. Non-finite inputs give 1.
#ifndef BOUNCE_VOXEL_GLSL
#define BOUNCE_VOXEL_GLSL
#include "scene.glsl"

// voxelize.comp defines VOXEL_BITS_ACCESS as nothing before including this file (it writes the bits).
#ifndef VOXEL_BITS_ACCESS
#define VOXEL_BITS_ACCESS readonly
#endif
layout(std430, set = 0, binding = B_VOXELS) VOXEL_BITS_ACCESS buffer Voxels { uint voxel_bits[]; };

// Conservative margin, in cells: a cell counts as touched when a triangle comes within VOXEL_EPS of its box
// (2^-13 ≈ 1.2e-4 cell, a power of two so that 0.5 + VOXEL_EPS is exact in both languages). It absorbs the
// rounding of the grid coordinates (~1e-7 cell), so a surface exactly on a cell face marks both cells.
const float VOXEL_EPS = 1.0 / 8192.0;
const float VOXEL_HALF = 0.5 + VOXEL_EPS;
// The endpoint offset of the march, in cells (see the header).
const float VOXEL_OFFSET_CELLS = 2.0;
// Direction components smaller than this (grid units, 2^-30) count as parallel to that axis's planes.
const float VOXEL_MIN_DIR = 1.0 / 1073741824.0;

// 1/c for |c| in [2^-100, 2^100], within ~2 ulp, computed identically on every device (see the header):
// the classic integer first guess (≤ 12 % off) and four Newton steps r ← r·(2 − c·r), each squaring
// the relative error (12 % → 1.4 % → 2e-4 → 4e-8 → rounding).
float voxel_rcp(float c) {
    float a = abs(c);
    precise float r = uintBitsToFloat(0x7EF311C3u - floatBitsToUint(a));
    for (int i = 0; i < 4; i++) {
        precise float ar = a * r;
        precise float corr = 2.0 - ar;
        r = r * corr;
    }
    return c < 0.0 ? -r : r;
}

bool voxel_finite(vec3 v) {
    return !any(isnan(v)) && !any(isinf(v));
}

// World position → grid units, with inv = voxel_rcp(cell size).
vec3 voxel_to_grid(vec3 p, float inv) {
    precise vec3 rel = p - frame.voxel_origin.xyz;
    precise vec3 g = rel * inv;
    return g;
}

// Bit number of cell c (inside the grid).
uint voxel_index(uvec3 c) {
    uvec3 dims = frame.voxel_dims.xyz;
    return c.x + dims.x * (c.y + dims.y * c.z);
}

// Whether cell c is marked. Cells outside the grid (or beyond the bound buffer) are empty.
bool voxel_occupied(ivec3 c) {
    uvec3 dims = frame.voxel_dims.xyz;
    if (any(lessThan(c, ivec3(0))) || any(greaterThanEqual(uvec3(c), dims))) return false;
    uint i = voxel_index(uvec3(c));
    uint w = i >> 5u;
    if (w >= uint(voxel_bits.length())) return false;
    return (voxel_bits[w] & (1u << (i & 31u))) != 0u;
}

// 1 when the segment from x to y (offset as the header says) crosses no occupied cell, else 0.
float voxel_visibility(vec3 x, vec3 nx, vec3 y, vec3 ny) {
    uvec3 du = frame.voxel_dims.xyz;
    if (du.x == 0u || du.y == 0u || du.z == 0u) return 1.0;
    ivec3 dims = ivec3(du);
    vec3 dimsf = vec3(du);
    float inv = voxel_rcp(frame.voxel_origin.w);
    vec3 gx = voxel_to_grid(x, inv);
    vec3 gy = voxel_to_grid(y, inv);
    precise vec3 ox = nx * VOXEL_OFFSET_CELLS;
    precise vec3 oy = ny * VOXEL_OFFSET_CELLS;
    precise vec3 a = gx + ox;
    precise vec3 b = gy + oy;
    if (!voxel_finite(a) || !voxel_finite(b)) return 1.0;
    precise vec3 d = b - a;
    precise vec3 s = gy - gx;
    precise float along = (d.x * s.x + d.y * s.y) + d.z * s.z;
    if (!(along > 0.0)) return 1.0;

    // Clip a + t·d, t ∈ [0, 1], to the grid box.
    float t0 = 0.0;
    float t1 = 1.0;
    vec3 invd = vec3(0.0);
    bvec3 moving = bvec3(false);
    for (int k = 0; k < 3; k++) {
        if (abs(d[k]) < VOXEL_MIN_DIR) {
            if (a[k] < 0.0 || a[k] > dimsf[k]) return 1.0;
        } else {
            moving[k] = true;
            invd[k] = voxel_rcp(d[k]);
            precise float na = 0.0 - a[k];
            precise float ta = na * invd[k];
            precise float nb = dimsf[k] - a[k];
            precise float tb = nb * invd[k];
            t0 = max(t0, min(ta, tb));
            t1 = min(t1, max(ta, tb));
        }
    }
    if (t0 > t1) return 1.0;

    // The cell holding the clipped start (clamped: rounding may put it a hair outside the box).
    precise vec3 dt0 = d * t0;
    precise vec3 p = a + dt0;
    ivec3 cell = ivec3(clamp(floor(p), vec3(0.0), dimsf - 1.0));
    int max_steps = dims.x + dims.y + dims.z + 3;
    for (int n = 0; n < max_steps; n++) {
        if (voxel_occupied(cell)) return 0.0;
        // The parameter where the segment leaves this cell through each axis's next plane; step through the
        // nearest (first axis on ties). Recomputed from a rather than accumulated: the same bits on both
        // sides and no drift.
        float best = 3.0e38;
        int m = -1;
        for (int k = 0; k < 3; k++) {
            if (!moving[k]) continue;
            precise float plane = float(cell[k] + (d[k] > 0.0 ? 1 : 0));
            precise float np = plane - a[k];
            precise float tk = np * invd[k];
            if (tk < best) {
                best = tk;
                m = k;
            }
        }
        if (m < 0 || best > t1) break;
        cell[m] += d[m] > 0.0 ? 1 : -1;
        if (cell[m] < 0 || cell[m] >= dims[m]) break;
    }
    return 1.0;
}

#endif
