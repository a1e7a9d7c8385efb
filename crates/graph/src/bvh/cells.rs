//! The triangle lists of `--visibility hybrid` (`glsl/shared/hybrid.glsl`): a uniform grid over the
//! voxel grid's box, each of its cells a whole number of voxel cells wide ([`CellLists::factor`]: about
//! CELL_DENSITY cells per triangle), listing the real triangles that touch it. A ray marches this grid
//! and tests, in each cell it enters, that cell's triangles; visibility is then the exact test's answer
//! (the BVH's, bit for bit), with no end skip and no thickening.
//!
//! Built once per scene and grid on the CPU, like the BVH it indexes: the lists hold indices into the
//! BVH's leaf-ordered triangle array ([`super::GpuBvhTri`]), so the shader tests them with the same
//! watertight test as `bvh_trace`.
//!
//! Layout (two storage buffers, bindings `B_CELL_OFFSETS`, `B_CELL_TRIS`), over the list grid of
//! ⌈dims / factor⌉ cells, cell c = x + ldims.x · (y + ldims.y · z): the triangles of cell c are
//! `tris[offsets[c] .. offsets[c + 1]]`, each an index into the BVH's triangle buffer. Dense offsets (one
//! word per cell) and short lists keep a march's reads within a few hundred kilobytes, which is what
//! decides its speed on a CPU device (an earlier layout with per-voxel lists in 4³ bricks read megabytes
//! and was 3× slower than the plain march).
//!
//! Membership is conservative: triangle T is in cell C's list when T meets C's box grown by
//! [`CELL_MARGIN`] of a list cell on every side (separating-axis test in f64). Why exactness follows: a
//! hit the exact test reports at parameter t lies in some cell the f32 march enters, or within the
//! march's rounding (≪ the margin) of one; that cell lists T, so the march tests T with the same ray and
//! gets the same t.

use super::gpu::GpuBvhTri;
use crate::bindings::{B_CELL_OFFSETS, B_CELL_TRIS, CELL_DENSITY};
use crate::passes::voxelize::VoxelGridSpec;
use anyhow::{Context, Result};
use bounce_device::{vk, Binding, Buffer, DescriptorWrites, Gpu};
use glam::{DVec3, UVec3};

/// How far (in list cells) a triangle may miss a cell and still be listed in it: far above the march's
/// rounding (f32 grid coordinates below 2¹⁰: ~10⁻⁴ cell), small enough to add few tests.
pub const CELL_MARGIN: f64 = 1.0 / 64.0;

/// The lists of one grid, on the CPU.
#[derive(Clone, Debug, Default)]
pub struct CellLists {
    pub offsets: Vec<u32>,
    pub tris: Vec<u32>,
    /// The list grid's cells per axis: ⌈voxel dims / factor⌉.
    pub dims: UVec3,
    /// Voxel cells per list cell ([`CellLists::factor`]).
    pub factor: u32,
}

/// Sizes of a build, for reports.
#[derive(Clone, Copy, Debug, Default)]
pub struct CellStats {
    pub cells: u32,
    pub occupied_cells: u32,
    pub entries: u32,
    pub max_list: u32,
}

impl CellLists {
    /// Voxel cells per list cell for `triangles` over the voxel grid `spec`: the smallest whole number
    /// that leaves at most CELL_DENSITY list cells per triangle (the classic uniform-grid density: a
    /// march through a coarser grid tests more triangles per cell, through a finer one steps more cells).
    pub fn factor(spec: &VoxelGridSpec, triangles: usize) -> u32 {
        let voxels = spec.dims.x as f64 * spec.dims.y as f64 * spec.dims.z as f64;
        let want = (CELL_DENSITY as f64 * triangles.max(1) as f64).max(1.0);
        ((voxels / want).cbrt().ceil() as u32).clamp(1, spec.dims.max_element().max(1))
    }

    /// The list grid over the voxel grid `spec`: the same box, cells `factor` voxels wide.
    pub fn list_grid(spec: &VoxelGridSpec, factor: u32) -> VoxelGridSpec {
        VoxelGridSpec {
            origin: spec.origin,
            cell: spec.cell * factor as f32,
            dims: (spec.dims + UVec3::splat(factor - 1)) / factor,
        }
    }

    /// The lists of `tris` (the BVH's triangle buffer) over the list grid of `spec`.
    pub fn build(tris: &[GpuBvhTri], spec: &VoxelGridSpec) -> CellLists {
        let factor = Self::factor(spec, tris.len());
        let grid = Self::list_grid(spec, factor);
        let dims = grid.dims;
        let origin = grid.origin.as_dvec3();
        let inv = 1.0 / grid.cell as f64;
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for (j, t) in tris.iter().enumerate() {
            let v = t.positions().map(|p| (p.as_dvec3() - origin) * inv);
            for_each_cell(&v, dims, |c| pairs.push((c.x + dims.x * (c.y + dims.y * c.z), j as u32)));
        }
        pairs.sort_unstable();
        let cells = (dims.x * dims.y * dims.z) as usize;
        let mut offsets = vec![0u32; cells + 1];
        for &(c, _) in &pairs {
            offsets[c as usize + 1] += 1;
        }
        for c in 0..cells {
            offsets[c + 1] += offsets[c];
        }
        CellLists { offsets, tris: pairs.iter().map(|p| p.1).collect(), dims, factor }
    }

    pub fn stats(&self) -> CellStats {
        let lens = self.offsets.windows(2).map(|w| w[1] - w[0]);
        CellStats {
            cells: self.offsets.len() as u32 - 1,
            occupied_cells: lens.clone().filter(|&n| n > 0).count() as u32,
            entries: self.tris.len() as u32,
            max_list: lens.max().unwrap_or(0),
        }
    }

    /// The triangles listed in list cell `c`.
    pub fn cell(&self, c: UVec3) -> &[u32] {
        let i = (c.x + self.dims.x * (c.y + self.dims.y * c.z)) as usize;
        &self.tris[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }
}

/// Calls `f` with every cell of the grid `dims` whose box, grown by [`CELL_MARGIN`], meets the triangle
/// `v` (grid units). The triangle's extent along its dominant normal axis is cut per column of cells,
/// so a large sloped triangle costs its area in cells, not its bounding box's volume. (Also the
/// membership rule of the `cell-bvhs` measuring tool's grid.)
pub fn for_each_cell(v: &[DVec3; 3], dims: UVec3, mut f: impl FnMut(UVec3)) {
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    if !v.iter().all(|p| p.is_finite()) || n.length_squared() == 0.0 {
        return;
    }
    let m = CELL_MARGIN;
    let lo = v[0].min(v[1]).min(v[2]) - DVec3::splat(m);
    let hi = v[0].max(v[1]).max(v[2]) + DVec3::splat(m);
    let top = dims.as_dvec3() - DVec3::ONE;
    let first = lo.floor().clamp(DVec3::ZERO, top);
    let last = hi.floor().clamp(DVec3::ZERO, top);
    if lo.cmpgt(dims.as_dvec3()).any() || hi.cmplt(DVec3::ZERO).any() {
        return;
    }
    // k: the dominant normal axis; (i, j) the other two.
    let a = n.abs();
    let k = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    let d = n.dot(v[0]);
    for ci in first[i] as u32..=last[i] as u32 {
        for cj in first[j] as u32..=last[j] as u32 {
            // The plane's k-range over the column's grown square, then the cells it spans.
            let mut zlo = f64::INFINITY;
            let mut zhi = f64::NEG_INFINITY;
            for (pi, pj) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                let xi = ci as f64 - m + pi * (1.0 + 2.0 * m);
                let xj = cj as f64 - m + pj * (1.0 + 2.0 * m);
                let z = (d - n[i] * xi - n[j] * xj) / n[k];
                zlo = zlo.min(z);
                zhi = zhi.max(z);
            }
            let z0 = (zlo - m).floor().max(first[k]) as i64;
            let z1 = (zhi + m).floor().min(last[k]) as i64;
            for ck in z0..=z1 {
                let mut c = UVec3::ZERO;
                c[i] = ci;
                c[j] = cj;
                c[k] = ck as u32;
                let centre = c.as_dvec3() + DVec3::splat(0.5);
                if tri_box_overlap(v, centre, 0.5 + m) {
                    f(c);
                }
            }
        }
    }
}

/// Separating-axis test of triangle `v` against the cube of half-size `h` around `c` (Akenine-Möller
/// 2001), in f64; touching counts as overlapping.
pub fn tri_box_overlap(v: &[DVec3; 3], c: DVec3, h: f64) -> bool {
    let p = [v[0] - c, v[1] - c, v[2] - c];
    let e = [p[1] - p[0], p[2] - p[1], p[0] - p[2]];
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    let separated = |axis: DVec3| {
        let r = h * (axis.x.abs() + axis.y.abs() + axis.z.abs());
        let s = [axis.dot(p[0]), axis.dot(p[1]), axis.dot(p[2])];
        let (lo, hi) = (s[0].min(s[1]).min(s[2]), s[0].max(s[1]).max(s[2]));
        lo > r || hi < -r
    };
    for a in axes {
        if separated(a) {
            return false;
        }
    }
    if separated(e[0].cross(e[1])) {
        return false;
    }
    for ed in e {
        for a in axes {
            let axis = ed.cross(a);
            if axis.length_squared() > 0.0 && separated(axis) {
                return false;
            }
        }
    }
    true
}

/// The lists on the GPU, for one voxel grid.
pub struct GpuCells {
    pub spec: VoxelGridSpec,
    pub offsets: Buffer,
    pub tris: Buffer,
    /// The list grid: cells per axis, voxel cells per list cell (FrameUniforms::cells).
    pub grid: [u32; 4],
}

impl GpuCells {
    pub fn upload(gpu: &Gpu, lists: &CellLists, spec: VoxelGridSpec) -> Result<GpuCells> {
        let max_range = gpu.limits().max_storage_buffer_range as u64;
        let up = |name: &str, data: &[u32]| {
            // An empty buffer cannot be bound: one unused word instead.
            let data = if data.is_empty() { &[0u32][..] } else { data };
            let bytes: &[u8] = bytemuck::cast_slice(data);
            anyhow::ensure!(
                bytes.len() as u64 <= max_range,
                "the {name} buffer ({} bytes) exceeds the device limit maxStorageBufferRange ({max_range} bytes); use fewer --voxels",
                bytes.len()
            );
            Buffer::with_data(gpu, name, vk::BufferUsageFlags::STORAGE_BUFFER, bytes)
                .with_context(|| format!("uploading {name}"))
        };
        Ok(GpuCells {
            spec,
            offsets: up("cell offsets", &lists.offsets)?,
            tris: up("cell triangles", &lists.tris)?,
            grid: [lists.dims.x, lists.dims.y, lists.dims.z, lists.factor],
        })
    }

    pub fn bindings() -> [Binding; 2] {
        [Binding::storage_buffer(B_CELL_OFFSETS), Binding::storage_buffer(B_CELL_TRIS)]
    }

    pub fn writes(&self, w: DescriptorWrites) -> DescriptorWrites {
        w.storage_buffer(B_CELL_OFFSETS, &self.offsets).storage_buffer(B_CELL_TRIS, &self.tris)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_overlap_test_agrees_with_sampling() {
        // A triangle crossing a cube's corner region, and one just outside a face.
        // The plane x + y + z = 2.8 cuts the corner (1, 1, 1) off the unit cube; x + y + z = 3.2 misses it.
        let t = [DVec3::new(1.8, 0.5, 0.5), DVec3::new(0.5, 1.8, 0.5), DVec3::new(0.5, 0.5, 1.8)];
        assert!(tri_box_overlap(&t, DVec3::splat(0.5), 0.5));
        let t = t.map(|v| v + DVec3::splat(0.4 / 3.0));
        assert!(!tri_box_overlap(&t, DVec3::splat(0.5), 0.5));
        assert!(tri_box_overlap(&t, DVec3::splat(0.5), 0.5 + 0.07));
        let far = [DVec3::new(1.02, 0.0, 0.0), DVec3::new(1.02, 1.0, 0.0), DVec3::new(1.02, 0.0, 1.0)];
        assert!(!tri_box_overlap(&far, DVec3::splat(0.5), 0.5));
        assert!(tri_box_overlap(&far, DVec3::splat(0.5), 0.5 + 1.0 / 32.0));
    }

    #[test]
    fn a_sloped_triangle_is_listed_in_every_cell_a_point_of_it_falls_in() {
        let v = [DVec3::new(0.3, 0.2, 0.1), DVec3::new(7.7, 1.1, 5.9), DVec3::new(2.2, 7.6, 3.3)];
        let mut cells = std::collections::HashSet::new();
        for_each_cell(&v, UVec3::splat(8), |c| {
            cells.insert(c);
        });
        for a in 0..=40 {
            for b in 0..=(40 - a) {
                let (u, w) = (a as f64 / 40.0, b as f64 / 40.0);
                let p = v[0] + (v[1] - v[0]) * u + (v[2] - v[0]) * w;
                assert!(cells.contains(&p.floor().as_uvec3().min(UVec3::splat(7))), "{p}");
            }
        }
        // Conservative, not the bounding box: an 8³ box would be 512 cells.
        assert!(cells.len() < 200, "{}", cells.len());
    }
}
