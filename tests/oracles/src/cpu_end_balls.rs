//! The CPU twin of the end balls' radii (`crates/graph/src/passes/end_balls.rs`, `glsl/shared/end_balls.glsl`),
//! in f64 over every triangle: no BVH, no pruning, no cap, no lift subtracted (the test applies those).

use glam::DVec3;

/// `surface_lift` (glsl/shared/common.glsl) in f64.
pub fn lift(p: DVec3, diag: f64) -> f64 {
    (1e-5 * diag).max(p.abs().max_element() / 262144.0)
}

/// Distance from p to the nearest triangle with a vertex more than `tau` above the plane through p with
/// unit normal n (infinity when there is none).
pub fn radius(tris: &[[DVec3; 3]], p: DVec3, n: DVec3, tau: f64) -> f64 {
    tris.iter()
        .filter(|t| t.iter().any(|&v| n.dot(v - p) > tau))
        .map(|t| point_triangle_distance(p, t))
        .fold(f64::INFINITY, f64::min)
}

/// Distance from p to a triangle: the nearest of its interior (when p projects inside) and its edges.
pub fn point_triangle_distance(p: DVec3, t: &[DVec3; 3]) -> f64 {
    let [a, b, c] = *t;
    let n = (b - a).cross(c - a);
    let inside = [(a, b), (b, c), (c, a)].iter().all(|&(u, v)| (v - u).cross(p - u).dot(n) >= 0.0);
    if inside && n.length_squared() > 0.0 {
        return (p - a).dot(n).abs() / n.length();
    }
    [(a, b), (b, c), (c, a)]
        .iter()
        .map(|&(u, v)| {
            let e = v - u;
            let s = if e.length_squared() > 0.0 { ((p - u).dot(e) / e.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
            (p - (u + e * s)).length()
        })
        .fold(f64::INFINITY, f64::min)
}
