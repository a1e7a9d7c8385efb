//! CPU twin of `--visibility hybrid`'s march (`glsl/shared/hybrid.glsl`) over the renderer's triangle
//! lists (`bounce_graph::bvh::cells`), in f64: which list cells a segment enters, which triangles it
//! tests, and whether one of them crosses it. With [`brute_force`] (every triangle of the scene) it
//! checks the lists' claim: no triangle a segment crosses is missing from the cells the march enters.
//! `march-length` reports its counts (cells and tests per march) for BENCHMARKS.md.

use bounce_graph::bvh::cells::CellLists;
use bounce_graph::bvh::GpuBvhTri;
use bounce_graph::passes::voxelize::VoxelGridSpec;
use glam::{DVec3, IVec3};

/// What one march did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MarchCount {
    pub occluded: bool,
    /// List cells entered.
    pub cells: u32,
    /// Triangle tests.
    pub tests: u32,
}

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

/// The march of a → b over the lists of `spec` (the voxel grid they were built for), testing each
/// entered cell's triangles for a crossing in (lo, hi). Stops at the first crossing, as any-hit does.
pub fn march(
    lists: &CellLists,
    spec: &VoxelGridSpec,
    tris: &[GpuBvhTri],
    a: DVec3,
    b: DVec3,
    lo: f64,
    hi: f64,
) -> MarchCount {
    let grid = CellLists::list_grid(spec, lists.factor);
    let inv = 1.0 / grid.cell as f64;
    let ga = (a - grid.origin.as_dvec3()) * inv;
    let gd = (b - a) * inv;
    let dims = grid.dims.as_dvec3();
    // Clip to the grid box.
    let (mut t0, mut t1) = (lo, hi);
    for k in 0..3 {
        if gd[k].abs() < 1e-300 {
            if ga[k] < 0.0 || ga[k] > dims[k] {
                return MarchCount::default();
            }
            continue;
        }
        let (ta, tb) = ((0.0 - ga[k]) / gd[k], (dims[k] - ga[k]) / gd[k]);
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    let mut count = MarchCount::default();
    if t0 > t1 {
        return count;
    }
    let top = grid.dims.as_ivec3() - IVec3::ONE;
    let mut cell = (ga + gd * t0).floor().as_ivec3().clamp(IVec3::ZERO, top);
    let step = IVec3::new(sign(gd.x), sign(gd.y), sign(gd.z));
    loop {
        count.cells += 1;
        for &j in lists.cell(cell.as_uvec3()) {
            count.tests += 1;
            if crosses(&tris[j as usize], a, b, lo, hi) {
                count.occluded = true;
                return count;
            }
        }
        let exit = |k: usize| {
            if gd[k].abs() < 1e-300 {
                f64::INFINITY
            } else {
                (cell[k] as f64 + if gd[k] > 0.0 { 1.0 } else { 0.0 } - ga[k]) / gd[k]
            }
        };
        let (tx, ty, tz) = (exit(0), exit(1), exit(2));
        let m = if tx <= ty && tx <= tz {
            0
        } else if ty <= tz {
            1
        } else {
            2
        };
        if [tx, ty, tz][m] > t1 {
            return count;
        }
        cell[m] += step[m];
        if cell[m] < 0 || cell[m] > top[m] {
            return count;
        }
    }
}

fn sign(x: f64) -> i32 {
    if x > 0.0 {
        1
    } else {
        -1
    }
}
