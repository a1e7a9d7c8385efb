//! Ray queries on the CPU over the flattened BVH's nodes and triangles ([`super::FlatBvh`]): closest hit and
//! segment occlusion in f32, for decisions the host makes from the scene's geometry (ris's automatic
//! learned visibility, the graph crate's `passes::ris::blocked_share`). An estimate needs no watertightness: the
//! triangle test is Möller–Trumbore, not the shaders' watertight one. The renderer's images never depend
//! on these answers, only which (unbiased) estimator a frame uses; `tests/tests/bvh.rs` checks them
//! against the f64 reference.

use super::{GpuBvhNode, GpuBvhTri};
use glam::Vec3;

/// A BVH's nodes and leaf-ordered triangles, as flattened for the GPU.
#[derive(Clone, Copy)]
pub struct BvhView<'a> {
    pub nodes: &'a [GpuBvhNode],
    pub tris: &'a [GpuBvhTri],
}

impl BvhView<'_> {
    /// The closest hit of o + t·d with t in (tmin, tmax): its t and its index in `tris`.
    pub fn closest(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Option<(f32, usize)> {
        self.walk(o, d, tmin, tmax, false)
    }

    /// Whether a triangle crosses the segment a → b away from its ends (t in (eps, 1 − eps)).
    pub fn occluded(&self, a: Vec3, b: Vec3, eps: f32) -> bool {
        self.walk(a, b - a, eps, 1.0 - eps, true).is_some()
    }

    fn walk(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32, any: bool) -> Option<(f32, usize)> {
        if self.nodes.is_empty() || !(o.is_finite() && d.is_finite()) || d == Vec3::ZERO {
            return None;
        }
        let inv = d.recip();
        let mut best: Option<(f32, usize)> = None;
        let mut far = tmax;
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            let n = self.nodes[i as usize];
            if !hits_box(Vec3::from(n.lo), Vec3::from(n.hi), o, inv, tmin, far) {
                continue;
            }
            if n.is_leaf() {
                for k in n.first as usize..(n.first + n.count) as usize {
                    let t = &self.tris[k];
                    if let Some(s) = hit_triangle(o, d, t.v0.into(), t.v1.into(), t.v2.into()) {
                        if s > tmin && s < far {
                            best = Some((s, k));
                            far = s;
                            if any {
                                return best;
                            }
                        }
                    }
                }
            } else {
                stack.push(n.first);
                stack.push(n.first + 1);
            }
        }
        best
    }
}

/// Slab test of [lo, hi] against the ray's (tmin, tmax); 1/d's infinities are fine (NaN where o lies on a
/// slab with d = 0 counts as a hit: an estimate may test a box too many).
fn hits_box(lo: Vec3, hi: Vec3, o: Vec3, inv: Vec3, tmin: f32, tmax: f32) -> bool {
    let (a, b) = ((lo - o) * inv, (hi - o) * inv);
    let (near, far) = (a.min(b), a.max(b));
    let t0 = near.max_element().max(tmin);
    let t1 = far.min_element().min(tmax);
    // NaN (o on a slab with d = 0) compares false: a hit.
    t0.partial_cmp(&t1) != Some(std::cmp::Ordering::Greater)
}

/// Möller–Trumbore: the ray parameter of the hit, if any.
fn hit_triangle(o: Vec3, d: Vec3, v0: Vec3, v1: Vec3, v2: Vec3) -> Option<f32> {
    let (e1, e2) = (v1 - v0, v2 - v0);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - v0;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(q) * inv)
}
