//! The voxel grid's geometry: cubic cells of size `cell`, `dims` cells per axis, minimum corner `origin`,
//! fitted around the scene's bounds ([`fit`]). The graph crate's `voxelize` pass fills it on the GPU
//! (its module doc states the voxelization); the tests' CPU twins read the same spec.

use anyhow::{bail, Result};
use glam::{UVec3, Vec3};

/// Default cells along the longest side of the scene (`--voxels`).
pub const DEFAULT_VOXELS: u32 = 128;
/// Most cells along the longest side that [`fit`] makes (1024³ bits = 128 MiB).
pub const MAX_VOXELS: u32 = 1024;
/// Smallest cell [`fit`] makes, relative to the largest |coordinate| of the bounds (at least 1): 2⁻²⁰.
pub const MIN_CELL_ULPS: f64 = 1.0 / (1u64 << 20) as f64;
/// Most cells a grid may have (1024³): the shaders index cells with a u32, and under llvmpipe's loop limit
/// the voxelize dispatch needs ⌈cells / 32767⌉ ≤ 65535 invocations per triangle in y.
pub const MAX_CELLS: u64 = 1 << 30;

/// A voxel grid: cubic cells of size `cell`, `dims` cells per axis, minimum corner `origin`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelGridSpec {
    pub origin: Vec3,
    pub cell: f32,
    pub dims: UVec3,
}

/// [`VoxelGridSpec::fit`].
pub fn fit(bounds_min: Vec3, bounds_max: Vec3, voxels_longest: u32) -> VoxelGridSpec {
    VoxelGridSpec::fit(bounds_min, bounds_max, voxels_longest)
}

impl VoxelGridSpec {
    /// The grid around the box [bounds_min, bounds_max] with `voxels_longest` cells (clamped to
    /// 1..=[`MAX_VOXELS`]) along its longest side.
    ///
    /// Each side gets a margin m = 1 cell + 10⁻³ · L (L = longest extent; no whole-cell margin when
    /// `voxels_longest` < 3, there is no room for one), so surfaces on the bounds are never on the grid's
    /// outer faces: cell = L · (1 + 2·10⁻³) / (N − 2), the longest axis has exactly N cells, the others
    /// ⌈(extent + 2m) / cell⌉ (≥ 1), and each axis is centred on the bounds. Computed in f64; rounding the
    /// corner to f32 can take up to half an f32 ulp of the coordinates (< 1/16 cell) off the margin.
    ///
    /// Never fails: non-finite or inverted bounds (an empty scene) become a point at the origin, and the
    /// cell is at least 2⁻²⁰ · max(1, |coordinate|) (8 f32 ulps of the coordinates), so a point, a flat or
    /// a one-triangle scene still gets a positive, finite cell that f32 can resolve at the bounds'
    /// magnitude (the grid is then larger than the bounds need, still centred on them).
    pub fn fit(bounds_min: Vec3, bounds_max: Vec3, voxels_longest: u32) -> VoxelGridSpec {
        let n = voxels_longest.clamp(1, MAX_VOXELS);
        let (mut lo, mut hi) = (bounds_min.as_dvec3(), bounds_max.as_dvec3());
        if !(lo.is_finite() && hi.is_finite()) || lo.cmpgt(hi).any() {
            lo = glam::DVec3::ZERO;
            hi = glam::DVec3::ZERO;
        }
        let extent = hi - lo;
        let longest = extent.max_element();
        let margin_cells = if n >= 3 { 1.0 } else { 0.0 };
        // At least 8 f32 ulps of the coordinates: the f32 corner and cell size then keep the margin.
        let magnitude = lo.abs().max(hi.abs()).max_element().max(1.0);
        let cell = (longest * (1.0 + 2e-3) / (n as f64 - 2.0 * margin_cells)).max(magnitude * MIN_CELL_ULPS);
        let margin = margin_cells * cell + 1e-3 * longest;
        let centre = (lo + hi) * 0.5;
        // The longest axis (the first of equals) gets exactly n cells; ceil() there could round up to n + 1.
        let long = (0..3).fold(0, |best, k| if extent[k] > extent[best] { k } else { best });
        let mut dims = UVec3::ONE;
        let mut origin = Vec3::ZERO;
        for k in 0..3 {
            let cells = if k == long { n } else { (((extent[k] + 2.0 * margin) / cell).ceil() as u32).clamp(1, n) };
            dims[k] = cells;
            origin[k] = (centre[k] - 0.5 * cells as f64 * cell) as f32;
        }
        VoxelGridSpec { origin, cell: cell as f32, dims }
    }

    /// Total cells.
    pub fn cells(&self) -> u64 {
        self.dims.x as u64 * self.dims.y as u64 * self.dims.z as u64
    }

    /// u32 words of the occupancy bits: ⌈cells / 32⌉.
    pub fn words(&self) -> u32 {
        self.cells().div_ceil(32).min(u32::MAX as u64) as u32
    }

    /// `(FrameUniforms.voxel_origin, FrameUniforms.voxel_dims)`: (origin, cell) and (dims, cells).
    pub fn uniforms_fields(&self) -> ([f32; 4], [u32; 4]) {
        let o = self.origin;
        let d = self.dims;
        ([o.x, o.y, o.z, self.cell], [d.x, d.y, d.z, self.cells().min(u32::MAX as u64) as u32])
    }

    /// The world-space box the grid covers.
    pub fn world_max(&self) -> Vec3 {
        self.origin + self.dims.as_vec3() * self.cell
    }

    /// Rejects grids the shaders cannot index or map (for hand-made specs; [`fit`] always passes).
    pub fn validate(&self) -> Result<()> {
        if self.dims.min_element() == 0 {
            bail!("voxel grid {} has an empty axis", self.dims);
        }
        if self.cells() > MAX_CELLS {
            bail!(
                "voxel grid {} has {} cells, more than the {} the shaders can index",
                self.dims,
                self.cells(),
                MAX_CELLS
            );
        }
        // voxel_rcp's first guess needs a normal float whose reciprocal is normal too.
        if !(self.cell.is_finite() && (1e-30..=1e30).contains(&self.cell)) {
            bail!("voxel cell size {} is not a positive size between 1e-30 and 1e30", self.cell);
        }
        if !self.origin.is_finite() {
            bail!("voxel grid origin {} is not finite", self.origin);
        }
        Ok(())
    }
}
