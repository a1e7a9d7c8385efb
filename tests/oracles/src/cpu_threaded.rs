//! CPU twin of the shadow rays' stackless walk (`bvh_any_hit` in `glsl/shared/bvh.glsl`) over the
//! renderer's threaded BVH records ([`bounce_scene::bvh::FlatBvh::threaded`]), in f64: the records it
//! reads and whether a triangle crosses the segment. With [`crate::cpu_segment::brute_force`] (every
//! triangle) it checks the layout's claim: a box's link skips only triangles inside that box, so the walk
//! misses no occluder. `march-length` reports its records per ray for BENCHMARKS.md.

use crate::cpu_segment::crosses;
use bounce_scene::bvh::{GpuBvhTri, GpuThreadRec, THREAD_TRI};
use glam::DVec3;

/// What one walk did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WalkCount {
    pub occluded: bool,
    /// Records read (boxes and triangles).
    pub records: u32,
    /// Of which triangles.
    pub tests: u32,
    /// The GPU walk's steps: a met box whose successor is a box (`pad2` ≠ 0) reads both in one step.
    /// Its test of the successor here is the exact box's, where the GPU's is the packed box around it,
    /// so the GPU may enter a few more subtrees than counted (same answer).
    pub steps: u32,
}

/// Whether the segment a → b meets box [lo, hi] at a parameter in [t.0, t.1] (slabs in f64, closed).
fn meets_box_within(lo: DVec3, hi: DVec3, a: DVec3, b: DVec3, t: (f64, f64)) -> bool {
    let d = b - a;
    let (mut t0, mut t1) = t;
    for k in 0..3 {
        if d[k] == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return false;
            }
            continue;
        }
        let (u, v) = ((lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]);
        t0 = t0.max(u.min(v));
        t1 = t1.min(u.max(v));
    }
    t0 <= t1
}

/// The walk over `records` for the segment a → b, occluders counted at parameters in (lo, hi).
pub fn walk(records: &[GpuThreadRec], a: DVec3, b: DVec3, lo: f64, hi: f64) -> WalkCount {
    walk_clipped(records, a, b, lo, hi, &[(0.0, 1.0)])
}

/// [`walk`] entering a box only where one of the parameter intervals `runs` of the segment meets it: the
/// same answer when every triangle that can cross the segment lies in a run (`march-length`'s question:
/// how many records skipping empty space would save).
pub fn walk_clipped(records: &[GpuThreadRec], a: DVec3, b: DVec3, lo: f64, hi: f64, runs: &[(f64, f64)]) -> WalkCount {
    let mut c = WalkCount::default();
    let mut i = 0;
    // The record that the step before read as its second box, if any.
    let mut second = usize::MAX;
    while i < records.len() {
        let r = &records[i];
        c.records += 1;
        if i != second {
            c.steps += 1;
        }
        if r.link == THREAD_TRI {
            c.tests += 1;
            let t = GpuBvhTri { v0: r.a, tri: 0, v1: r.b, pad1: 0, v2: r.c, pad2: 0 };
            if crosses(&t, a, b, lo, hi) {
                c.occluded = true;
                return c;
            }
            i += 1;
        } else {
            let (blo, bhi) = (DVec3::from(r.a.map(f64::from)), DVec3::from(r.b.map(f64::from)));
            let meets = runs.iter().any(|&t| meets_box_within(blo, bhi, a, b, t));
            if meets && i != second && r.pad2 != 0 {
                second = i + 1;
            }
            i = if meets { i + 1 } else { r.link as usize };
        }
    }
    c
}
