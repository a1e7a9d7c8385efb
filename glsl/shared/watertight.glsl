// Watertight ray–triangle intersection (Woop, Benthin and Wald 2013) in f32, shared by the BVH
// (shared/bvh.glsl), the light maps (dprsm.comp) and psm's maps (psm.frag). The ray is sheared so that it runs along +z
// from its origin; each vertex is mapped to that frame by a function of the vertex and the ray alone, and
// the three 2D edge functions are `precise` (no fused multiply-add), so two triangles that share an edge
// compute exactly opposite values for it: a ray can never slip between them, even through a shared vertex
// (Möller–Trumbore can: a light sealed in a box leaked through its edges in the DPRSM). Edges count as
// inside (an edge function of exactly 0 passes), so a ray through an edge hits one or both triangles.
// crates/graph/src/cpu_ref.rs mirrors this test on the CPU.
#ifndef BOUNCE_WATERTIGHT_GLSL
#define BOUNCE_WATERTIGHT_GLSL

struct WtRay {
    vec3 o;
    vec3 mx;    // the shear: a vertex p maps to (dot(p − o, mx), dot(p − o, my), dot(p − o, mz)),
    vec3 my;    // i.e. x = p[kx] − Sx·p[kz], y = p[ky] − Sy·p[kz], z = Sz·p[kz] (Woop et al.'s frame)
    vec3 mz;
};

WtRay wt_make_ray(vec3 o, vec3 d) {
    WtRay r;
    r.o = o;
    // kz: the dominant axis; kx, ky the next two, swapped when d[kz] < 0 to keep the winding.
    vec3 ad = abs(d);
    int kz = ad.x > ad.y ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    if (d[kz] < 0.0) {
        int s = kx;
        kx = ky;
        ky = s;
    }
    float sz = 1.0 / d[kz];
    float sx = d[kx] * sz;
    float sy = d[ky] * sz;
    r.mx = vec3(0.0);
    r.my = vec3(0.0);
    r.mz = vec3(0.0);
    r.mx[kx] = 1.0;
    r.mx[kz] = -sx;
    r.my[ky] = 1.0;
    r.my[kz] = -sy;
    r.mz[kz] = sz;
    return r;
}

// One sheared coordinate of a vertex: (p.x·m.x + p.y·m.y) + p.z·m.z, unfused and in this order. Two of the
// terms are exact (a factor 1 or 0), so this is p[k] − S·p[kz] rounded as written, and it depends on the vertex
// and the ray only: what makes shared edges watertight.
float wt_shear(vec3 p, vec3 m) {
    precise float a = p.x * m.x;
    precise float b = p.y * m.y;
    precise float c = p.z * m.z;
    precise float ab = a + b;
    precise float s = ab + c;
    return s;
}

// 2D edge function x1·y2 − y1·x2, unfused: swapping the two points negates it exactly.
float wt_edge(float x1, float y1, float x2, float y2) {
    precise float p = x1 * y2;
    precise float q = y1 * x2;
    precise float e = p - q;
    return e;
}

// Watertight ray–triangle test: true with t and the weights of v1, v2 when the ray's line
// crosses the closed triangle (t is not range-checked here).
bool wt_hit_triangle(WtRay r, vec3 v0, vec3 v1, vec3 v2, out float t, out vec2 bary) {
    t = -1.0;
    bary = vec2(0.0);
    precise vec3 a = v0 - r.o;
    precise vec3 b = v1 - r.o;
    precise vec3 c = v2 - r.o;
    float ax = wt_shear(a, r.mx), ay = wt_shear(a, r.my);
    float bx = wt_shear(b, r.mx), by = wt_shear(b, r.my);
    float cx = wt_shear(c, r.mx), cy = wt_shear(c, r.my);
    float u = wt_edge(cx, cy, bx, by); // weight of v0
    float v = wt_edge(ax, ay, cx, cy); // weight of v1
    float w = wt_edge(bx, by, ax, ay); // weight of v2
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) return false;
    float det = u + v + w;
    if (det == 0.0 || isnan(det) || isinf(det)) return false;
    float az = wt_shear(a, r.mz), bz = wt_shear(b, r.mz), cz = wt_shear(c, r.mz);
    float tt = (u * az + v * bz + w * cz) / det;
    if (isnan(tt) || isinf(tt)) return false;
    t = tt;
    bary = vec2(v, w) / det;
    return true;
}

// The watertight inside test with the distance from the triangle's plane, t = n·(v0 − o) / n·d: the
// sheared-frame t above loses up to ~3e-5 relative precision at grazing angles, the plane form keeps
// ~1e-6 (the paraboloid maps are compared with a CPU ray cast at 2e-5). Same hit/miss decisions as
// wt_hit_triangle, so still watertight.
bool wt_hit_triangle_plane_t(WtRay r, vec3 d, vec3 v0, vec3 v1, vec3 v2, out float t, out vec2 bary) {
    if (!wt_hit_triangle(r, v0, v1, v2, t, bary)) return false;
    vec3 n = cross(v1 - v0, v2 - v0);
    float nd = dot(n, d);
    if (nd != 0.0) t = dot(n, v0 - r.o) / nd;
    return !(isnan(t) || isinf(t));
}

#endif
