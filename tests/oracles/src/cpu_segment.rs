//! Segment–triangle crossings in f64 (Möller–Trumbore), and [`brute_force`]: whether any triangle of a
//! scene crosses a segment. The ground truth the BVH walks' CPU twins are checked against.

use bounce_scene::bvh::GpuBvhTri;
use glam::DVec3;

/// The segment a → b is crossed by triangle `t` at a parameter in (lo, hi) (Möller–Trumbore, f64).
pub fn crosses(t: &GpuBvhTri, a: DVec3, b: DVec3, lo: f64, hi: f64) -> bool {
    let [v0, v1, v2] = t.positions().map(|p| p.as_dvec3());
    let d = b - a;
    let (e1, e2) = (v1 - v0, v2 - v0);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return false;
    }
    let s = a - v0;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    (0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && t > lo && t < hi
}

/// Whether any of `tris` crosses a → b in (lo, hi).
pub fn brute_force(tris: &[GpuBvhTri], a: DVec3, b: DVec3, lo: f64, hi: f64) -> bool {
    tris.iter().any(|t| crosses(t, a, b, lo, hi))
}
