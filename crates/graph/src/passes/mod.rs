//! The render passes. One pass = one Rust file here + GLSL file(s) in `glsl/` with the same stem. Each
//! pass struct owns its pipeline; its `add` declares reads and writes on the graph and records.

pub mod cdf_reduce;
pub mod direct;
pub mod dprsm;
pub mod gather;
pub mod gbuffer;
pub mod importance;
pub mod mis;
pub mod reference;
pub mod voxelize;

use crate::gpu_scene::GpuScene;
use bounce_device::Buffer;

/// What every pass of a frame reads besides graph resources: the static scene and the frame uniforms.
#[derive(Clone, Copy)]
pub struct FrameInputs<'a> {
    pub scene: &'a GpuScene,
    pub uniforms: &'a Buffer,
    pub width: u32,
    pub height: u32,
    /// Resolution per face of the paraboloid depth map that shadows direct light.
    pub shadow_res: u32,
    /// Resolution per face of the reflective DPRSM (the VPLs).
    pub dprsm_res: u32,
    /// The scene's BVH when the gather tests visibility with exact shadow rays (`--visibility exact`);
    /// `None`: the voxel march.
    pub bvh: Option<&'a crate::bvh::GpuBvh>,
    /// VPLs one gather dispatch may evaluate per pixel, so that no invocation exceeds the driver's loop
    /// iteration limit (`Gpu::loop_iteration_limit`); `u32::MAX` where there is none.
    pub vpls_per_dispatch: u32,
}
