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
// from voxel_rcp (an integer first guess and Newton steps: only ×, + and −). The CPU does the same f32
// operations in the same order, so both sides get the same bits, not merely close ones.
//
// Visibility march, voxel_visibility(x, nx, y, ny), 1 = visible, 0 = occluded:
//  * Endpoint rule. The march runs from a = g(x) + 2·nx to b = g(y) + 2·ny (grid units, i.e. an offset
//    of δ = VOXEL_OFFSET_CELLS = 2 cells along each unit normal). The caller orients nx towards y's side
//    and ny towards x's side (cos > 0 at both ends; otherwise the contribution is 0 anyway). Why 2 cells:
//    a cell is marked only when a surface comes within VOXEL_EPS of it, so every point of a marked cell
//    lies within one cell diagonal (√3 + ε < 2) of that surface; a point 2 cells off x's (locally flat)
//    surface is therefore in none of its cells, and the surface does not shadow x (it can only block where
//    the segment comes back within √3 cells of it, i.e. when y is itself that close to x's plane: a corner,
//    which the grid cannot resolve anyway). Any occluder more than ~2 cells from both endpoints, even one
//    cell thick, is found, because the march visits every cell the segment a→b passes through.
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

// VOXEL_EPS, VOXEL_OFFSET_CELLS, VOXEL_MIN_DIR and VOXEL_NEVER: bindings.glsl (shared with Rust).
const float VOXEL_HALF = 0.5 + VOXEL_EPS;

// 1/c for |c| in [2^-100, 2^100], relative error below 2^-23 (exact for powers of two), the same bits on every
// device (see the header): the classic integer first guess (≤ 12 % off) and four Newton steps in
// correction form r ← r + r·(1 − c·r), each squaring the relative error (12 % → 1.4 % → 2e-4 → 4e-8 →
// rounding). The correction form lets the last step reach the exact value where a plain r·(2 − c·r) would
// stall an ulp short. Unrolled: llvmpipe counts loop iterations against a per-invocation limit.
float voxel_rcp_step(float a, float r) {
    precise float ar = a * r;
    precise float e = 1.0 - ar;
    precise float re = r * e;
    precise float next = r + re;
    return next;
}

float voxel_rcp(float c) {
    float a = abs(c);
    float r = uintBitsToFloat(0x7EF311C3u - floatBitsToUint(a));
    r = voxel_rcp_step(a, r);
    r = voxel_rcp_step(a, r);
    r = voxel_rcp_step(a, r);
    r = voxel_rcp_step(a, r);
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

// Clip a + t·d (one axis) to [0, dim]: narrows [t0, t1]; `moving` and `invd` are set when the axis's
// component is large enough to step through planes; `outside` when a parallel segment lies outside the slab.
void voxel_clip_axis(float a, float d, float dim, inout float t0, inout float t1, out float invd, out bool moving,
                     inout bool outside) {
    invd = 0.0;
    moving = abs(d) >= VOXEL_MIN_DIR;
    if (!moving) {
        if (a < 0.0 || a > dim) outside = true;
        return;
    }
    invd = voxel_rcp(d);
    precise float na = 0.0 - a;
    precise float ta = na * invd;
    precise float nb = dim - a;
    precise float tb = nb * invd;
    t0 = max(t0, min(ta, tb));
    t1 = min(t1, max(ta, tb));
}

// Parameter where the segment leaves cell `cell` through this axis's next plane (never for a still axis).
float voxel_exit_t(int cell, float a, float d, float invd, bool moving) {
    if (!moving) return VOXEL_NEVER;
    precise float plane = float(cell + (d > 0.0 ? 1 : 0));
    precise float np = plane - a;
    precise float t = np * invd;
    return t;
}

// 1 when the segment from x to y (offset as the header says) crosses no occupied cell, else 0. Loop
// iterations per call (what llvmpipe's per-invocation limit counts): at most dims.x + dims.y + dims.z + 3,
// one per cell tested; everything else is unrolled.
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

    // Clip a + t·d, t ∈ [0, 1], to the grid box [0, dims].
    float t0 = 0.0;
    float t1 = 1.0;
    vec3 invd;
    bvec3 moving;
    bool outside = false;
    voxel_clip_axis(a.x, d.x, dimsf.x, t0, t1, invd.x, moving.x, outside);
    voxel_clip_axis(a.y, d.y, dimsf.y, t0, t1, invd.y, moving.y, outside);
    voxel_clip_axis(a.z, d.z, dimsf.z, t0, t1, invd.z, moving.z, outside);
    if (outside || t0 > t1) return 1.0;

    // The cell holding the clipped start (clamped: rounding may put it a hair outside the box).
    precise vec3 dt0 = d * t0;
    precise vec3 p = a + dt0;
    ivec3 cell = ivec3(clamp(floor(p), vec3(0.0), dimsf - 1.0));
    ivec3 step = ivec3(d.x > 0.0 ? 1 : -1, d.y > 0.0 ? 1 : -1, d.z > 0.0 ? 1 : -1);
    int max_steps = dims.x + dims.y + dims.z + 3;
    for (int n = 0; n < max_steps; n++) {
        if (voxel_occupied(cell)) return 0.0;
        // Step through the nearest exit plane (x before y before z on ties). The exits are recomputed
        // from a, not accumulated: no drift, and the same bits as the CPU.
        float tx = voxel_exit_t(cell.x, a.x, d.x, invd.x, moving.x);
        float ty = voxel_exit_t(cell.y, a.y, d.y, invd.y, moving.y);
        float tz = voxel_exit_t(cell.z, a.z, d.z, invd.z, moving.z);
        float best = tx;
        int m = 0;
        if (ty < best) {
            best = ty;
            m = 1;
        }
        if (tz < best) {
            best = tz;
            m = 2;
        }
        // Past the end (this also ends a segment that moves along no axis: best = VOXEL_NEVER).
        if (best > t1) break;
        cell[m] += step[m];
        if (cell[m] < 0 || cell[m] >= dims[m]) break;
    }
    return 1.0;
}

#endif
