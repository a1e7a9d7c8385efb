//! The render passes. One pass = one Rust file here + GLSL file(s) in `glsl/` with the same stem. Each
//! pass struct owns its pipeline; its `add` declares reads and writes on the graph and records.

pub mod direct;
pub mod dprsm;
pub mod gbuffer;

use crate::gpu_scene::GpuScene;
use bounce_device::Buffer;

/// What every pass of a frame reads besides graph resources: the static scene and the frame uniforms.
#[derive(Clone, Copy)]
pub struct FrameInputs<'a> {
    pub scene: &'a GpuScene,
    pub uniforms: &'a Buffer,
    pub width: u32,
    pub height: u32,
    /// Paraboloid depth map resolution per face.
    pub shadow_res: u32,
}
