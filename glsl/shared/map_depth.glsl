// The paraboloid maps' depths. psm's rasterized maps (psm.geom, psm.frag): the geometry shader emits a
// triangle's box at map_box_depth, the fragment shader writes map_texel_depth of its texel ray's hit, and
// declares depth_greater, so that a GPU may run the depth test before it: sound only while no fragment
// writes a depth below its box's. The light maps (dprsm.comp) place a VPL with map_texel_point against
// the same bound. glsl/test/map_depth.comp and the `dprsm` tests
// check the box against an f64 closest point on triangles from a millimetre to kilometres, slivers and
// a light next to a vertex, an edge or the interior of a huge one. (lavapipe tests depth after the
// shader, so its images could never show a violation.)
#ifndef BOUNCE_MAP_DEPTH_GLSL
#define BOUNCE_MAP_DEPTH_GLSL

// The distance from the viewpoint (the origin) to the nearest point of triangle abc (Ericson, Real-Time
// Collision Detection, 5.1.5): no texel ray hits the triangle nearer than this.
float distance_to_triangle(vec3 a, vec3 b, vec3 c) {
    vec3 ab = b - a, ac = c - a, ap = -a;
    float d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return length(a);
    vec3 bp = -b;
    float d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return length(b);
    float vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return length(a + ab * (d1 / (d1 - d3)));
    vec3 cp = -c;
    float d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return length(c);
    float vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return length(a + ac * (d2 / (d2 - d6)));
    float va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) return length(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
    float denom = 1.0 / (va + vb + vc);
    return length(a + ab * (vb * denom) + ac * (vc * denom));
}

// The distance from the origin to segment ab.
float distance_to_segment(vec3 a, vec3 b) {
    vec3 ab = b - a;
    float l2 = dot(ab, ab);
    float s = l2 > 0.0 ? clamp(-dot(a, ab) / l2, 0.0, 1.0) : 0.0;
    return length(a + ab * s);
}

// The box's depth: the nearest distance over `far`, lowered by a margin for rounding (relative 1e-4,
// absolute 1e-7 of `far`), in [0, 1]. On a sliver (a vertex within ~1e-6 of the size off the opposite
// edge) the face case of distance_to_triangle divides by a vanishing area and came out up to 1.1e-4 too
// far in the map_depth test (12 of its 1500 slivers at 1e-6 and 1e-7 put the box above the nearest point); the edges' distances stay exact there, and a sliver's nearest point is on an
// edge or within its width of one, so the bound takes the least of the four.
float map_box_depth(vec3 a, vec3 b, vec3 c, float far) {
    float edges = min(distance_to_segment(a, b), min(distance_to_segment(b, c), distance_to_segment(c, a)));
    return clamp(min(distance_to_triangle(a, b, c), edges) / far * (1.0 - 1e-4) - 1e-7, 0.0, 1.0);
}

// A texel's depth: its ray's hit distance t over `far` (1 beyond it), never below `box`, the depth the
// rasterizer gave the fragment (gl_FragCoord.z: the box's). That keeps depth_greater's promise by
// construction: the box is below the triangle's true nearest distance (the map_depth test checks it), so
// the max only lifts a texel whose t came out short, toward the truth. In the map_depth test it did on
// 733 of 1900 slivers, where the plane's normal is ill-conditioned (the plane form of
// wt_hit_triangle_plane_t came out short by up to 0.2 % with a vertex 1e-4 of the size off the opposite
// edge, by up to 88 % at 1e-6 and 1e-7; Woop's sheared t did no better), and once on a grazing ray next
// to a huge triangle's edge (0.28 %). Such a texel's VPL is placed by map_texel_point.
float map_texel_depth(float t, float far, float box) {
    return max(min(t / far, 1.0), box);
}

// A texel's hit point in the map's frame (the viewpoint at the origin; xyz) and its distance (w): dir · t,
// unless the triangle is a sliver (twice its area under 1e-3 of its longest edge squared: its plane's
// normal, and so the plane-form t, is ill-conditioned, and came out long as well as short: points up to
// 97 % of their distance off the triangle, behind the surface, in the map_depth test) or t came out short
// of the box (`box`, map_box_depth's), then the barycentric point of the watertight test's weights, a
// convex combination of the vertices, so on the triangle up to rounding. Other texels keep dir · t, the
// more precise at grazing angles.
vec4 map_texel_point(vec3 dir, float t, vec2 bary, vec3 a, vec3 b, vec3 c, float far, float box) {
    vec3 n = cross(b - a, c - a);
    float l2 = max(dot(b - a, b - a), max(dot(c - b, c - b), dot(a - c, a - c)));
    bool sliver = dot(n, n) < 1e-6 * l2 * l2;
    if (!sliver && min(t / far, 1.0) >= box) return vec4(dir * t, t);
    vec3 p = a * (1.0 - bary.x - bary.y) + b * bary.x + c * bary.y;
    return vec4(p, length(p));
}

#endif
