//! What the measuring tools (`end-balls`, `ray-windows`) share about the parts of a shadow ray that need
//! no walk: an end's empty ball (`glsl/shared/end_balls.glsl`, in f64 and without the renderer's cap),
//! where the segment leaves it, and the nearest triangle in a set of directions from a point.

use bounce_graph::bvh::query::BvhView;
use bounce_graph::bvh::GpuBvhNode;
use bounce_oracles::cpu_end_balls::point_triangle_distance;
use glam::{DVec3, Vec3};

/// The parameter along a → b (from a's side) up to which the segment lies in the empty half-ball of
/// radius r around p (plane normal n): 0 unless both ends are more than `margin` above the plane.
pub fn ball_exit(a: DVec3, b: DVec3, p: DVec3, n: DVec3, r: f64, margin: f64) -> f64 {
    let (ha, hb) = (n.dot(a - p), n.dot(b - p));
    if ha <= margin || hb <= margin || r <= 0.0 {
        return 0.0;
    }
    let r = r * (1.0 - 1e-4);
    let d = b - a;
    let f = a - p;
    let (qa, qb, qc) = (d.dot(d), 2.0 * f.dot(d), f.dot(f) - r * r);
    if qc >= 0.0 {
        return 0.0;
    }
    let disc = qb * qb - 4.0 * qa * qc;
    ((-qb + disc.sqrt()) / (2.0 * qa)).clamp(0.0, 1.0)
}

/// Distance from p to the nearest triangle with a vertex more than tau above p's plane (normal n).
pub fn ball_radius(view: &BvhView, p: Vec3, n: Vec3, tau: f32) -> f64 {
    nearest_above(view, p.as_dvec3(), p.as_dvec3(), n.as_dvec3(), tau as f64, &|_, _| true)
}

/// Distance from `from` to the nearest triangle that has a vertex more than tau above the plane through
/// p with normal n and whose bounding sphere passes `meets(centre, radius)`. Boxes are pruned by their
/// bounding spheres too, so `meets` must be conservative: true for every sphere that holds a point of
/// the region it stands for (a triangle with a point there is then never pruned).
pub fn nearest_above(
    view: &BvhView,
    from: DVec3,
    p: DVec3,
    n: DVec3,
    tau: f64,
    meets: &dyn Fn(DVec3, f64) -> bool,
) -> f64 {
    let mut best = f64::INFINITY;
    let mut stack = vec![0u32];
    while let Some(i) = stack.pop() {
        let nd: GpuBvhNode = view.nodes[i as usize];
        let (lo, hi) = (Vec3::from(nd.lo).as_dvec3(), Vec3::from(nd.hi).as_dvec3());
        if (from.clamp(lo, hi) - from).length() >= best {
            continue;
        }
        // Highest point of the box above the plane.
        let top = DVec3::new(
            if n.x > 0.0 { hi.x } else { lo.x },
            if n.y > 0.0 { hi.y } else { lo.y },
            if n.z > 0.0 { hi.z } else { lo.z },
        );
        if n.dot(top - p) <= tau || !meets((lo + hi) * 0.5, (hi - lo).length() * 0.5) {
            continue;
        }
        if nd.is_leaf() {
            for k in nd.first..nd.first + nd.count {
                let v = view.tris[k as usize].positions().map(|v| v.as_dvec3());
                if v.iter().all(|&v| n.dot(v - p) <= tau) {
                    continue;
                }
                let c = (v[0] + v[1] + v[2]) / 3.0;
                if meets(c, v.iter().map(|&q| (q - c).length()).fold(0.0, f64::max)) {
                    best = best.min(point_triangle_distance(from, &v));
                }
            }
        } else {
            stack.push(nd.first);
            stack.push(nd.first + 1);
        }
    }
    best
}
