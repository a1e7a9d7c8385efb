// A VPL's patch Q_v for mis (glsl/mis.comp): the parallelogram c + a·e1 + b·e2, |a|, |b| ≤ ½, in the
// VPL's tangent plane (normal n), of area |e1 × e2|; and its part in front of a receiver's tangent plane,
// Q_v⁺, with its area and a uniform point. Pure math, no bindings, so that a test kernel
// (glsl/test/front_part.comp) checks it against the exact clipped square on the CPU.
#ifndef BOUNCE_PATCH_GLSL
#define BOUNCE_PATCH_GLSL

// Q_v: centre c, unit normal n, edges e1 and e2, area |e1 × e2|.
struct Patch {
    vec3 c, n, e1, e2;
    float area;
};

// Coordinates (a, b) of a point y of Q_v's plane: y − c = a·e1 + b·e2.
vec2 patch_coords(Patch q, vec3 y) {
    vec3 r = y - q.c;
    float g11 = dot(q.e1, q.e1), g12 = dot(q.e1, q.e2), g22 = dot(q.e2, q.e2);
    float det = g11 * g22 - g12 * g12;
    vec2 rhs = vec2(dot(r, q.e1), dot(r, q.e2));
    return vec2(g22 * rhs.x - g12 * rhs.y, g11 * rhs.y - g12 * rhs.x) / det;
}

// The part of Q_v in front of x's tangent plane, Q_v⁺(x), in patch coordinates: the square [−½, ½]² cut
// by (y(a, b) − x) · n_x = s0 + s1·a + s2·b ≥ 0. No gathering ray from x reaches the rest of Q_v, so the
// estimator's patch at x is Q_v⁺. With the steeper slope p = |s_i| ≥ q = |s_j| and signs flipped
// (a' = sign(s_i)·coordinate i, b' likewise), Q_v⁺ is p·a' + q·b' ≥ −s0, and its cross-section along
// a' at b' has length ℓ(b') = clamp(½ + (s0 + q·b')/p, 0, 1): zero up to b0, a linear ramp to b1, then 1.
// So its area is closed-form, and a uniform point of it is b' by inverting ∫ℓ, then a' uniform in
// [½ − ℓ(b'), ½] (no arrays or loops: both cost lanes on lavapipe).
struct FrontPart {
    float s0, p, q, b0, b1, l0, ramp;
    float frac; // A_v⁺ / A_v
    bool swap;  // the steeper slope is e2's
    vec2 sgn;
};

FrontPart front_part(Patch pt, vec3 x, vec3 nx) {
    FrontPart f;
    float s1 = dot(pt.e1, nx), s2 = dot(pt.e2, nx);
    f.s0 = dot(pt.c - x, nx);
    f.swap = abs(s2) > abs(s1);
    f.sgn = vec2(s1 < 0.0 ? -1.0 : 1.0, s2 < 0.0 ? -1.0 : 1.0);
    // A slope of 0 made tiny: the breakpoints then land at ±∞ and clamp to the square's sides.
    f.p = max(max(abs(s1), abs(s2)), 1e-30);
    f.q = max(min(abs(s1), abs(s2)), 1e-30);
    f.b0 = clamp((-0.5 * f.p - f.s0) / f.q, -0.5, 0.5);
    f.b1 = clamp((0.5 * f.p - f.s0) / f.q, -0.5, 0.5);
    f.l0 = clamp(0.5 + (f.s0 + f.q * f.b0) / f.p, 0.0, 1.0);
    float w = f.b1 - f.b0;
    f.ramp = f.l0 * w + 0.5 * (f.q / f.p) * w * w;
    f.frac = f.ramp + (0.5 - f.b1);
    return f;
}

// A point uniform in Q_v⁺ (patch coordinates) from u uniform in [0, 1)².
vec2 front_point(FrontPart f, vec2 u) {
    float t = u.x * f.frac, b;
    if (t < f.ramp) {
        // ∫_{b0}^{b} ℓ = l0·Δ + (q/p)·Δ²/2 = t, solved without cancellation.
        b = f.b0 + 2.0 * t / max(f.l0 + sqrt(f.l0 * f.l0 + 2.0 * (f.q / f.p) * t), 1e-30);
    } else {
        b = min(f.b1 + (t - f.ramp), 0.5);
    }
    float len = clamp(0.5 + (f.s0 + f.q * b) / f.p, 0.0, 1.0);
    float a = 0.5 - len * u.y;
    return (f.swap ? vec2(b, a) : vec2(a, b)) * f.sgn;
}

#endif
