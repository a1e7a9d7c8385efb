#version 460
// Test kernel: the light maps' depth bound (shared/map_depth.glsl). Per case, a triangle in the viewpoint's
// frame (a, b, c; a.w = far) and a point q on it (the CPU's f64 closest point to the origin): the box depth
// psm.geom would emit, the least texel depth t / far over rays from the origin through q, q's
// neighbours, the vertices, the edge midpoints and a 16 × 16 grid of the triangle (as psm.frag and dprsm.comp find t,
// before map_texel_depth lifts it to the box's), how many of those rays hit, and distance_to_triangle.
// vec4 [S k] = (box, least texel depth, hits, distance), [S k + 1].x the least distance of the hit points
// map_texel_point places (the VPLs'), over far, [S k + 2 + i] ray i's placed point (w 1; 0 for a miss),
// S = 2 + RAYS. tests/tests/dprsm.rs checks the box, the distance and the
// placed points against the f64 closest point, and counts the texels the lift moves.
#include "../shared/bindings.glsl"
#include "../shared/watertight.glsl"
#include "../shared/map_depth.glsl"

layout(local_size_x = WG_1D) in;

struct Case {
    vec4 a;
    vec4 b;
    vec4 c;
    vec4 q;
};
layout(std430, set = 0, binding = B_TEST_IN) readonly buffer Cases { Case cases[]; };
layout(std430, set = 0, binding = B_TEST_OUT) writeonly buffer Outputs { vec4 outputs[]; };

const uint GRID = 16u;
const uint RAYS = GRID * GRID + 6u + 9u;
const uint STRIDE = 2u + RAYS;

// Ray i's aim: the grid's cell centres folded into the triangle, the vertices, the edge midpoints, then q
// and q moved by a thousandth of each edge either way.
vec3 aim(uint i, vec3 a, vec3 b, vec3 c, vec3 q) {
    if (i < GRID * GRID) {
        vec2 uv = (vec2(float(i % GRID), float(i / GRID)) + 0.5) / float(GRID);
        if (uv.x + uv.y > 1.0) uv = 1.0 - uv;
        return a + (b - a) * uv.x + (c - a) * uv.y;
    }
    i -= GRID * GRID;
    if (i < 6u) {
        vec3 v[3] = vec3[3](a, b, c);
        return i < 3u ? v[i] : 0.5 * (v[i - 3u] + v[(i - 2u) % 3u]);
    }
    i -= 6u;
    vec3 e[4] = vec3[4](vec3(0.0), (b - a) * 1e-3, (c - a) * 1e-3, (c - b) * 1e-3);
    return i == 0u ? q : q + e[1u + (i - 1u) / 2u] * ((i % 2u) == 1u ? 1.0 : -1.0);
}

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= uint(cases.length())) return;
    vec3 a = cases[k].a.xyz, b = cases[k].b.xyz, c = cases[k].c.xyz, q = cases[k].q.xyz;
    float far = cases[k].a.w;
    float least = 2.0, placed = 2.0;
    uint hits = 0u;
    float box = map_box_depth(a, b, c, far);
    for (uint i = 0u; i < RAYS; i++) {
        vec3 dir = normalize(aim(i, a, b, c, q));
        float t;
        vec2 bary;
        // As psm.frag: the watertight test, then the hit distance along the unit direction.
        if (wt_hit_triangle_plane_t(wt_make_ray(vec3(0.0), dir), dir, a, b, c, t, bary) && t > 0.0) {
            hits++;
            least = min(least, min(t / far, 1.0));
            vec4 point = map_texel_point(dir, t, bary, a, b, c, far, box);
            placed = min(placed, point.w / far);
            outputs[STRIDE * k + 2u + i] = vec4(point.xyz, 1.0);
        } else {
            outputs[STRIDE * k + 2u + i] = vec4(0.0);
        }
    }
    outputs[STRIDE * k] = vec4(box, least, float(hits), distance_to_triangle(a, b, c));
    outputs[STRIDE * k + 1u] = vec4(placed, 0.0, 0.0, 0.0);
}
