#version 460
// voxelize: conservative binary voxelization, one invocation per triangle (per triangle and share of its
// cells where the driver limits loop iterations: llvmpipe). A cell is marked iff the closed
// triangle overlaps the cell's box grown by VOXEL_EPS on every side (Akenine-Möller's triangle–box
// separating-axis test, in grid units where cells are unit cubes). See crates/graph/src/passes/voxelize.rs;
// crates/graph/src/cpu_voxel.rs does exactly the same operations on the CPU.
#define VOXEL_BITS_ACCESS
#include "shared/scene.glsl"
#include "shared/voxel.glsl"

layout(local_size_x = WG_1D) in;

layout(push_constant) uniform Push { VoxelizePush pc; };

// Whether the projections p0..p2 of the (cell-centred) triangle onto an axis miss the box's projection
// [-r, r]. Sound for any axis, even an inaccurate one: separated projections prove disjointness.
bool separated(float p0, float p1, float p2, float r) {
    return min(min(p0, p1), p2) > r || max(max(p0, p1), p2) < -r;
}

// The three axes (unit axis) × e of edge e, with their box radii r = (r_X, r_Y, r_Z). Projections of v:
// X×e: e.y·v.z − e.z·v.y; Y×e: e.z·v.x − e.x·v.z; Z×e: e.x·v.y − e.y·v.x.
bool edge_separated(vec3 e, vec3 r, vec3 v0, vec3 v1, vec3 v2) {
    precise float a0 = e.y * v0.z - e.z * v0.y;
    precise float a1 = e.y * v1.z - e.z * v1.y;
    precise float a2 = e.y * v2.z - e.z * v2.y;
    if (separated(a0, a1, a2, r.x)) return true;
    precise float b0 = e.z * v0.x - e.x * v0.z;
    precise float b1 = e.z * v1.x - e.x * v1.z;
    precise float b2 = e.z * v2.x - e.x * v2.z;
    if (separated(b0, b1, b2, r.y)) return true;
    precise float c0 = e.x * v0.y - e.y * v0.x;
    precise float c1 = e.x * v1.y - e.y * v1.x;
    precise float c2 = e.x * v2.y - e.y * v2.x;
    return separated(c0, c1, c2, r.z);
}

// Triangle (grid units g0..g2; edges e0..e2, normal n, radii r0..r2 and rn) against cell c grown by ε:
// the 13 axes of Akenine-Möller's test.
bool overlaps(vec3 g0, vec3 g1, vec3 g2, vec3 e0, vec3 e1, vec3 e2, vec3 n, vec3 r0, vec3 r1, vec3 r2, float rn,
              ivec3 c) {
    precise vec3 centre = vec3(c) + 0.5;
    precise vec3 v0 = g0 - centre;
    precise vec3 v1 = g1 - centre;
    precise vec3 v2 = g2 - centre;
    // 3 box face normals.
    if (separated(v0.x, v1.x, v2.x, VOXEL_HALF)) return false;
    if (separated(v0.y, v1.y, v2.y, VOXEL_HALF)) return false;
    if (separated(v0.z, v1.z, v2.z, VOXEL_HALF)) return false;
    // The triangle's plane, as an axis with all three projections (see separated()).
    precise float q0 = (n.x * v0.x + n.y * v0.y) + n.z * v0.z;
    precise float q1 = (n.x * v1.x + n.y * v1.y) + n.z * v1.z;
    precise float q2 = (n.x * v2.x + n.y * v2.y) + n.z * v2.z;
    if (separated(q0, q1, q2, rn)) return false;
    // 9 edge cross products.
    return !edge_separated(e0, r0, v0, v1, v2) && !edge_separated(e1, r1, v0, v1, v2) &&
           !edge_separated(e2, r2, v0, v1, v2);
}

void main() {
    uint t = pc.first_triangle + gl_GlobalInvocationID.x;
    if (t >= uint(vertices.length()) / 3u) return;
    uvec3 du = frame.voxel_dims.xyz;
    if (du.x == 0u || du.y == 0u || du.z == 0u) return;
    float inv = voxel_rcp(frame.voxel_origin.w);
    vec3 g0 = voxel_to_grid(vertices[3u * t].position_u.xyz, inv);
    vec3 g1 = voxel_to_grid(vertices[3u * t + 1u].position_u.xyz, inv);
    vec3 g2 = voxel_to_grid(vertices[3u * t + 2u].position_u.xyz, inv);
    // A triangle with a non-finite vertex marks nothing (the scene loader never makes one).
    if (!voxel_finite(g0) || !voxel_finite(g1) || !voxel_finite(g2)) return;

    // Per-triangle axis data. A box of half size h projects onto axis v with radius h·(|v.x| + |v.y| + |v.z|);
    // for e: X×e = (0, −e.z, e.y), Y×e = (e.z, 0, −e.x), Z×e = (−e.y, e.x, 0).
    precise vec3 e0 = g1 - g0;
    precise vec3 e1 = g2 - g1;
    precise vec3 e2 = g0 - g2;
    precise vec3 n;
    precise float nx0 = e0.y * e1.z;
    precise float nx1 = e0.z * e1.y;
    n.x = nx0 - nx1;
    precise float ny0 = e0.z * e1.x;
    precise float ny1 = e0.x * e1.z;
    n.y = ny0 - ny1;
    precise float nz0 = e0.x * e1.y;
    precise float nz1 = e0.y * e1.x;
    n.z = nz0 - nz1;
    precise vec3 ae0 = abs(e0);
    precise vec3 ae1 = abs(e1);
    precise vec3 ae2 = abs(e2);
    precise vec3 r0 = VOXEL_HALF * vec3(ae0.y + ae0.z, ae0.x + ae0.z, ae0.x + ae0.y);
    precise vec3 r1 = VOXEL_HALF * vec3(ae1.y + ae1.z, ae1.x + ae1.z, ae1.x + ae1.y);
    precise vec3 r2 = VOXEL_HALF * vec3(ae2.y + ae2.z, ae2.x + ae2.z, ae2.x + ae2.y);
    precise float rn = VOXEL_HALF * ((abs(n.x) + abs(n.y)) + abs(n.z));

    // Candidate cells: every cell whose grown box can meet the bounding box. Cell i qualifies only if
    // i − ε ≤ max and i + 1 + ε ≥ min, and the only integer in (min − 1.5, min − 0.5] is floor(min − 0.5),
    // so [floor(min − 0.5), floor(max + 0.5)] holds every candidate (the SAT decides). Clamped to the grid
    // in float first: a huge triangle's bounds must not overflow an int.
    precise vec3 lo_f = floor(min(min(g0, g1), g2) - 0.5);
    precise vec3 hi_f = floor(max(max(g0, g1), g2) + 0.5);
    vec3 top = vec3(du) - 1.0;
    ivec3 lo = ivec3(clamp(lo_f, vec3(0.0), top));
    ivec3 hi = ivec3(clamp(hi_f, vec3(0.0), top));

    // This invocation's share of the candidates, in x-fastest order: [first, first + count).
    uvec3 span = uvec3(hi - lo) + 1u;
    uint total = span.x * span.y * span.z;
    uint first = gl_GlobalInvocationID.y * pc.cells_per_invocation;
    if (gl_GlobalInvocationID.y > 0u && pc.cells_per_invocation == 0xFFFFFFFFu) return;
    if (first >= total) return;
    uint count = min(total - first, pc.cells_per_invocation);
    uvec3 k = uvec3(first % span.x, (first / span.x) % span.y, first / (span.x * span.y));
    // One loop (llvmpipe counts iterations per invocation), walking x fastest.
    for (uint i = 0u; i < count; i++) {
        ivec3 c = lo + ivec3(k);
        if (overlaps(g0, g1, g2, e0, e1, e2, n, r0, r1, r2, rn, c)) {
            uint bit = voxel_index(uvec3(c));
            uint w = bit >> 5u;
            // The caller sizes the buffer from the same grid; the check keeps a mismatch in bounds.
            if (w < uint(voxel_bits.length())) atomicOr(voxel_bits[w], 1u << (bit & 31u));
        }
        k.x++;
        if (k.x == span.x) {
            k.x = 0u;
            k.y++;
            if (k.y == span.y) {
                k.y = 0u;
                k.z++;
            }
        }
    }
}
