//! voxelize: the scene's binary occupancy grid, marched by the gather shaders for VPL visibility.
//!
//! Owns: the grid fitting ([`fit`], [`VoxelGridSpec`]), the grid buffer ([`create_grid_buffer`]) and the
//! GPU voxelization ([`Voxelize`], `glsl/voxelize.comp`). The march lives in `glsl/shared/voxel.glsl`; the
//! CPU twins of both are in `bounce-oracles` (`tests/oracles/src/cpu_voxel.rs`).
//!
//! **Grid.** Cubic cells of size `cell`, `dims` cells per axis, minimum corner `origin`. Grid units are
//! g = (p − origin) · rcp(cell) (`rcp` = `voxel_rcp`, a division-free reciprocal that every device computes
//! bit for bit alike), so cell (i, j, k) is the unit cube [i, i+1] × [j, j+1] × [k, k+1]. Cell
//! c = x + dims.x · (y + dims.y · z) is bit c % 32 of word c / 32 of a buffer of u32 (binding `B_VOXELS`).
//! `FrameUniforms.voxel_origin` = (origin, cell), `voxel_dims` = (dims, cells), from
//! [`VoxelGridSpec::uniforms_fields`]; the buffer and the uniforms must come from the same spec.
//!
//! **Voxelization (conservative).** Cell B is marked iff the closed triangle T overlaps B grown by
//! ε = [`VOXEL_EPS`] = 2⁻¹³ ≈ 1.2e-4 cell on every side:  T ∩ [i − ε, i + 1 + ε] × … ≠ ∅. The test is
//! Akenine-Möller's separating-axis test with its 13 axes (3 box normals, the triangle normal, 9 edge ×
//! box-axis cross products), each axis judged from all three vertex projections against the box radius
//! h · (|a.x| + |a.y| + |a.z|), h = ½ + ε. ε absorbs float rounding of the grid coordinates, so a surface
//! lying exactly on a cell face marks the cells on both sides. **Degenerate triangles** (zero area) are
//! not skipped: with a zero normal the remaining axes are exactly the separating axes of a segment (or a
//! point) against a box, so they mark the cells their segment or point touches, on CPU and GPU alike.
//!
//! **Dispatch.** Two graph passes: `voxelize_clear` (vkCmdFillBuffer 0, `TransferWrite`, so a grid kept
//! across scenes or sizes never keeps stale bits) then `voxelize`: ⌈triangles / 64⌉ × S groups of 64×1,
//! invocation (t, s) testing share s of the candidate cells of triangle t (its bounding box, grown by half
//! a cell and clamped to the grid) in one flat loop, setting bits with `atomicOr`. On a device without a
//! loop limit S = 1: one invocation per triangle. llvmpipe silently cuts an invocation's loops after 65535
//! iterations in total (`Gpu::loop_iteration_limit`), so there each share is at most half that many cells
//! and S = ⌈grid cells / share⌉ (the grid bounds any bounding box; shares past a small triangle's box
//! return at once). Cost ∝ Σ over triangles of their bounding-box cell counts: a scene-sized floor at 128
//! cells is ~130² × 2 cells, acceptable for a grid built once per scene.

use super::FrameInputs;
use crate::bindings::*;
use crate::gpu_scene::{scene_bindings, GpuScene};
use crate::graph::{Graph, Handle};
use crate::pipelines::Lazy;
use crate::shader_types::VoxelizePush;
use crate::shaders;
use anyhow::{bail, Context, Result};
use bounce_device::sync::Access;
use bounce_device::{Binding, Buffer, BufferDesc, Gpu};

/// Conservative margin of the voxelization, in cells (2⁻¹³; from `glsl/shared/bindings.glsl`).
pub use crate::bindings::VOXEL_EPS;
// The grid's geometry is the scene crate's (the CPU twins use it too).
pub use bounce_scene::grid::{fit, VoxelGridSpec, DEFAULT_VOXELS, MAX_CELLS, MAX_VOXELS, MIN_CELL_ULPS};

/// Whether this device can hold the grid of `spec` (bad input otherwise: lower --voxels).
pub fn check_grid(gpu: &Gpu, spec: &VoxelGridSpec) -> Result<()> {
    spec.validate()?;
    let bytes = grid_desc(spec).size;
    let max_range = gpu.limits().max_storage_buffer_range as u64;
    if bytes > max_range {
        bail!(
            "the voxel grid ({}×{}×{} cells, {bytes} bytes) exceeds the device limit maxStorageBufferRange \
             ({max_range} bytes); lower --voxels",
            spec.dims.x,
            spec.dims.y,
            spec.dims.z
        );
    }
    Ok(())
}

/// The occupancy buffer for `spec`: `words × 4` bytes, storage + transfer src/dst, device-local. Its
/// contents are undefined until the `voxelize` passes ran.
pub fn grid_desc(spec: &VoxelGridSpec) -> BufferDesc {
    BufferDesc::storage("voxels", spec.words() as u64 * 4)
}

/// A grid buffer for `spec` outside any graph (tests voxelize into one they keep).
pub fn create_grid_buffer(gpu: &Gpu, spec: &VoxelGridSpec) -> Result<Buffer> {
    check_grid(gpu, spec)?;
    Buffer::new(gpu, &grid_desc(spec)).context("creating the voxel grid buffer")
}

pub struct Voxelize {
    pipeline: Lazy<1>,
}

impl Voxelize {
    pub fn new(gpu: &Gpu) -> Result<Self> {
        let mut bindings = scene_bindings();
        bindings.push(Binding::storage_buffer(B_VOXELS));
        let push = std::mem::size_of::<VoxelizePush>() as u32;
        Ok(Voxelize { pipeline: Lazy::new(gpu, "voxelize", shaders::VOXELIZE_COMP, &bindings, push) })
    }

    /// A new grid for `spec`, cleared and voxelized with the grid of `f.uniforms` (see the module doc).
    pub fn add<'a>(&'a self, g: &mut Graph<'a>, f: FrameInputs<'a>, spec: &VoxelGridSpec) -> Result<Handle<Buffer>> {
        let mut grid = g.create_buffer(grid_desc(spec));
        self.add_scene(g, f.scene, f.uniforms, &mut grid)?;
        Ok(grid)
    }

    /// [`Voxelize::add`] from what it really reads: the grid depends on the scene and the uniforms' voxel
    /// fields only, not on the frame size, so it can be built without a frame.
    pub fn add_scene<'a>(
        &'a self,
        g: &mut Graph<'a>,
        scene: &'a GpuScene,
        uniforms: &'a Buffer,
        grid: &mut Handle<Buffer>,
    ) -> Result<()> {
        let pipeline = self.pipeline.pipeline()?;
        g.add_clear("voxelize_clear", &mut [&mut *grid]);
        let h = *grid;
        g.add_pass("voxelize").write(grid, Access::ComputeWrite).record(move |ctx| {
            let buffer = ctx.buffer(&h);
            let (per_invocation, shares) = shares(ctx.gpu.loop_iteration_limit, buffer.size / 4 * 32);
            let writes = scene.writes(uniforms).storage_buffer(B_VOXELS, buffer);
            // Batches of at most maxComputeWorkGroupCount[0] groups. atomicOr makes their order
            // irrelevant, but they write one buffer, so the graph serializes them (one batch is usual).
            let batch = ctx.gpu.limits().max_compute_work_group_count[0].min(65535) * WG_1D;
            let mut first = 0;
            while first < scene.triangle_count {
                if first > 0 {
                    ctx.serialize(&h);
                }
                let n = batch.min(scene.triangle_count - first);
                let push = VoxelizePush { cells_per_invocation: per_invocation, first_triangle: first };
                pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&push), [n, shares, 1], [WG_1D, 1, 1]);
                first += n;
            }
        });
        Ok(())
    }
}

/// (candidate cells per invocation, invocations per triangle) under a loop iteration `limit`, for a grid of
/// at most `cells` cells. Half the limit goes to the cell loop; the other half is headroom for the few
/// iterations of the rest of the shader, whatever the compiler leaves of them.
fn shares(limit: Option<u32>, cells: u64) -> (u32, u32) {
    match limit {
        None => (u32::MAX, 1),
        Some(limit) => {
            let per = (limit / 2).max(1);
            (per, cells.div_ceil(per as u64).clamp(1, u32::MAX as u64) as u32)
        }
    }
}
