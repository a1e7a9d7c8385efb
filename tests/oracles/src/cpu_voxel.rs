//! The CPU twin of the voxel grid: the conservative voxelizer of `glsl/voxelize.comp` and the
//! Amanatides–Woo visibility march of `glsl/shared/voxel.glsl`, for the tests.
//!
//! Inputs: a [`VoxelGridSpec`] and world-space triangles (or a [`Scene`]); outputs: a [`CpuGrid`] holding
//! the same bit array the GPU writes (bit c % 32 of word c / 32, c = x + dims.x · (y + dims.y · z)), and
//! [`visible`] / [`march`] for segments between surface points. The rules (the ε = 2⁻¹³ cell margin, the
//! 13-axis separating-axis test, degenerate triangles marking the cells their segment or point touches,
//! the 2-cell endpoint offsets, grid clipping, the bounded DDA) are stated in `passes/voxelize.rs` and
//! `glsl/shared/voxel.glsl`.
//!
//! **Same bits as the GPU, not just close ones.** Every value that feeds a decision is computed with the
//! same f32 operations in the same order as the GLSL, which marks those temporaries `precise` (no fused
//! multiply-add, no reassociation). Rust never contracts a·b + c into an fma and its +, −, × are IEEE
//! round-to-nearest like Vulkan's; division is avoided on both sides ([`rcp`]), because Vulkan lets `/` be
//! 2.5 ulp off. That is why the arithmetic below is written component by component instead of with
//! glam's `dot`/`cross`.

use bounce_scene::bindings::{VOXEL_EPS, VOXEL_NEVER};
pub use bounce_scene::bindings::{VOXEL_MIN_DIR, VOXEL_OFFSET_CELLS};
use bounce_scene::grid::VoxelGridSpec;
use bounce_scene::scene::Scene;
use glam::{IVec3, Vec3};

/// Half size of a grown cell in grid units: ½ + ε (exact: ε is a power of two).
pub const VOXEL_HALF: f32 = 0.5 + VOXEL_EPS;

type V = [f32; 3];

fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `voxel_rcp` of `voxel.glsl`: 1/c with relative error below 2⁻²³ for |c| in [2⁻¹⁰⁰, 2¹⁰⁰] (exact for
/// powers of two), from the integer first guess 0x7EF311C3 − bits(|c|) (≤ 12 % off) and four Newton steps
/// in correction form r ← r + r · (1 − |c| · r). Only ×, + and −, so every device computes the same bits
/// (unlike `/`).
pub fn rcp(c: f32) -> f32 {
    let a = c.abs();
    let mut r = f32::from_bits(0x7EF3_11C3u32.wrapping_sub(a.to_bits()));
    for _ in 0..4 {
        let ar = a * r;
        let e = 1.0 - ar;
        let re = r * e;
        r += re;
    }
    if c < 0.0 {
        -r
    } else {
        r
    }
}

/// World position → grid units: (p − origin) · inv, inv = rcp(cell).
fn to_grid(spec: &VoxelGridSpec, p: Vec3, inv: f32) -> V {
    let o = spec.origin;
    [(p.x - o.x) * inv, (p.y - o.y) * inv, (p.z - o.z) * inv]
}

/// A voxel grid's occupancy bits on the CPU, in the GPU buffer's layout.
#[derive(Clone, Debug, PartialEq)]
pub struct CpuGrid {
    pub spec: VoxelGridSpec,
    /// `spec.words()` words.
    pub bits: Vec<u32>,
}

impl CpuGrid {
    pub fn empty(spec: VoxelGridSpec) -> CpuGrid {
        CpuGrid { spec, bits: vec![0; spec.words() as usize] }
    }

    /// Wrap bits read back from the GPU (little-endian bytes of the u32 words).
    pub fn from_bytes(spec: VoxelGridSpec, bytes: &[u8]) -> CpuGrid {
        let mut bits: Vec<u32> = bytes.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        bits.resize(spec.words() as usize, 0);
        CpuGrid { spec, bits }
    }

    /// Bit number of cell `c`, `None` outside the grid.
    pub fn index(&self, c: IVec3) -> Option<u32> {
        let d = self.spec.dims;
        if c.min_element() < 0 || c.x as u32 >= d.x || c.y as u32 >= d.y || c.z as u32 >= d.z {
            return None;
        }
        Some(c.x as u32 + d.x * (c.y as u32 + d.y * c.z as u32))
    }

    /// Whether cell `c` is marked (cells outside the grid are empty).
    pub fn occupied(&self, c: IVec3) -> bool {
        self.index(c).is_some_and(|i| self.bits[(i >> 5) as usize] & (1 << (i & 31)) != 0)
    }

    /// Mark cell `c` (ignored outside the grid).
    pub fn set(&mut self, c: IVec3) {
        if let Some(i) = self.index(c) {
            self.bits[(i >> 5) as usize] |= 1 << (i & 31);
        }
    }

    /// Marked cells.
    pub fn count(&self) -> u64 {
        self.bits.iter().map(|w| w.count_ones() as u64).sum()
    }

    /// Every marked cell, in bit order.
    pub fn cells(&self) -> Vec<IVec3> {
        let d = self.spec.dims;
        let mut out = vec![];
        for z in 0..d.z as i32 {
            for y in 0..d.y as i32 {
                for x in 0..d.x as i32 {
                    let c = IVec3::new(x, y, z);
                    if self.occupied(c) {
                        out.push(c);
                    }
                }
            }
        }
        out
    }
}

/// Per-triangle data of the separating-axis test (grid units), as `voxelize.comp` computes it.
struct TriAxes {
    g: [V; 3],
    e: [V; 3],
    /// Box radius on the axes X×e, Y×e, Z×e of each edge.
    r: [V; 3],
    n: V,
    rn: f32,
}

impl TriAxes {
    fn new(g: [V; 3]) -> TriAxes {
        let e = [sub(g[1], g[0]), sub(g[2], g[1]), sub(g[0], g[2])];
        let (e0, e1) = (e[0], e[1]);
        let n = [e0[1] * e1[2] - e0[2] * e1[1], e0[2] * e1[0] - e0[0] * e1[2], e0[0] * e1[1] - e0[1] * e1[0]];
        let r = e.map(|e| {
            let a = e.map(f32::abs);
            [VOXEL_HALF * (a[1] + a[2]), VOXEL_HALF * (a[0] + a[2]), VOXEL_HALF * (a[0] + a[1])]
        });
        let rn = VOXEL_HALF * ((n[0].abs() + n[1].abs()) + n[2].abs());
        TriAxes { g, e, r, n, rn }
    }

    /// The separating-axis test against cell `c` grown by ε.
    fn overlaps(&self, c: [i32; 3]) -> bool {
        let centre = [c[0] as f32 + 0.5, c[1] as f32 + 0.5, c[2] as f32 + 0.5];
        let v = self.g.map(|g| sub(g, centre));
        let [v0, v1, v2] = v;
        for k in 0..3 {
            if separated(v0[k], v1[k], v2[k], VOXEL_HALF) {
                return false;
            }
        }
        let n = self.n;
        let q = v.map(|v| (n[0] * v[0] + n[1] * v[1]) + n[2] * v[2]);
        if separated(q[0], q[1], q[2], self.rn) {
            return false;
        }
        for (e, r) in self.e.iter().zip(&self.r) {
            let a = v.map(|v| e[1] * v[2] - e[2] * v[1]);
            let b = v.map(|v| e[2] * v[0] - e[0] * v[2]);
            let c = v.map(|v| e[0] * v[1] - e[1] * v[0]);
            if separated(a[0], a[1], a[2], r[0])
                || separated(b[0], b[1], b[2], r[1])
                || separated(c[0], c[1], c[2], r[2])
            {
                return false;
            }
        }
        true
    }
}

/// Whether projections p0..p2 miss [−r, r].
fn separated(p0: f32, p1: f32, p2: f32, r: f32) -> bool {
    p0.min(p1).min(p2) > r || p0.max(p1).max(p2) < -r
}

/// Mark the cells of one world-space triangle, as one `voxelize.comp` invocation does.
pub fn voxelize_triangle(grid: &mut CpuGrid, tri: &[Vec3; 3]) {
    let spec = grid.spec;
    if spec.dims.min_element() == 0 {
        return;
    }
    let inv = rcp(spec.cell);
    let g = tri.map(|p| to_grid(&spec, p, inv));
    if g.iter().flatten().any(|v| !v.is_finite()) {
        return;
    }
    let axes = TriAxes::new(g);
    let dims = spec.dims.as_vec3().to_array();
    let mut lo = [0i32; 3];
    let mut hi = [0i32; 3];
    for k in 0..3 {
        let mn = g[0][k].min(g[1][k]).min(g[2][k]);
        let mx = g[0][k].max(g[1][k]).max(g[2][k]);
        lo[k] = (mn - 0.5).floor().clamp(0.0, dims[k] - 1.0) as i32;
        hi[k] = (mx + 0.5).floor().clamp(0.0, dims[k] - 1.0) as i32;
    }
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                if axes.overlaps([x, y, z]) {
                    grid.set(IVec3::new(x, y, z));
                }
            }
        }
    }
}

/// The grid of world-space triangles.
pub fn voxelize_triangles(spec: VoxelGridSpec, tris: &[[Vec3; 3]]) -> CpuGrid {
    let mut grid = CpuGrid::empty(spec);
    for t in tris {
        voxelize_triangle(&mut grid, t);
    }
    grid
}

/// The grid of a scene's triangles (the positions the GPU reads from the vertex buffer).
pub fn voxelize_scene(scene: &Scene, spec: VoxelGridSpec) -> CpuGrid {
    let tris: Vec<[Vec3; 3]> =
        scene.vertices.chunks_exact(3).map(|v| [v[0].position(), v[1].position(), v[2].position()]).collect();
    voxelize_triangles(spec, &tris)
}

/// The march of `voxel_visibility`: calls `visit` on every cell from x's end to y's end (see
/// `voxel.glsl` for the endpoint rule) until it returns true. Returns whether it did (false: the
/// segment was walked to its end, or there was no segment to walk).
pub fn march(spec: &VoxelGridSpec, x: Vec3, nx: Vec3, y: Vec3, ny: Vec3, mut visit: impl FnMut(IVec3) -> bool) -> bool {
    let du = spec.dims;
    if du.min_element() == 0 {
        return false;
    }
    let dims = [du.x as i32, du.y as i32, du.z as i32];
    let dimsf = du.as_vec3().to_array();
    let inv = rcp(spec.cell);
    let gx = to_grid(spec, x, inv);
    let gy = to_grid(spec, y, inv);
    let ox = (nx * VOXEL_OFFSET_CELLS).to_array();
    let oy = (ny * VOXEL_OFFSET_CELLS).to_array();
    let a = [gx[0] + ox[0], gx[1] + ox[1], gx[2] + ox[2]];
    let b = [gy[0] + oy[0], gy[1] + oy[1], gy[2] + oy[2]];
    if a.iter().chain(&b).any(|v| !v.is_finite()) {
        return false;
    }
    let d = sub(b, a);
    let s = sub(gy, gx);
    let along = (d[0] * s[0] + d[1] * s[1]) + d[2] * s[2];
    // `!(along > 0.0)` in the GLSL: NaN (an overflowed segment) is visible too.
    if along.is_nan() || along <= 0.0 {
        return false;
    }

    // Clip a + t·d, t ∈ [0, 1], to the grid box [0, dims] (voxel_clip_axis per axis).
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    let mut invd = [0.0f32; 3];
    let mut moving = [false; 3];
    let mut outside = false;
    for k in 0..3 {
        moving[k] = d[k].abs() >= VOXEL_MIN_DIR;
        if !moving[k] {
            outside |= a[k] < 0.0 || a[k] > dimsf[k];
            continue;
        }
        invd[k] = rcp(d[k]);
        let ta = (0.0 - a[k]) * invd[k];
        let tb = (dimsf[k] - a[k]) * invd[k];
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    if outside || t0 > t1 {
        return false;
    }

    let mut cell = [0i32; 3];
    for k in 0..3 {
        let p = a[k] + d[k] * t0;
        cell[k] = p.floor().clamp(0.0, dimsf[k] - 1.0) as i32;
    }
    let max_steps = dims[0] + dims[1] + dims[2] + 3;
    for _ in 0..max_steps {
        if visit(IVec3::from_array(cell)) {
            return true;
        }
        // voxel_exit_t per axis; the nearest wins, x before y before z on ties.
        let exit = |k: usize| {
            if !moving[k] {
                return VOXEL_NEVER;
            }
            let plane = (cell[k] + i32::from(d[k] > 0.0)) as f32;
            (plane - a[k]) * invd[k]
        };
        let (mut best, mut m) = (exit(0), 0);
        for k in 1..3 {
            let t = exit(k);
            if t < best {
                (best, m) = (t, k);
            }
        }
        // Past the end (this also ends a segment that moves along no axis: best = VOXEL_NEVER).
        if best > t1 {
            break;
        }
        cell[m] += if d[m] > 0.0 { 1 } else { -1 };
        if cell[m] < 0 || cell[m] >= dims[m] {
            break;
        }
    }
    false
}

/// `voxel_visibility` on the CPU: true when no marked cell lies on the march from x to y.
pub fn visible(grid: &CpuGrid, x: Vec3, nx: Vec3, y: Vec3, ny: Vec3) -> bool {
    !march(&grid.spec, x, nx, y, ny, |c| grid.occupied(c))
}
