//! The render passes. One pass = one Rust file here + GLSL file(s) in `glsl/` with the same stem. Each
//! pass struct owns its pipeline; its `add` declares reads and writes on the graph and records.

pub mod cdf_reduce;
pub mod denoise;
pub mod direct;
pub mod dprsm;
pub mod end_balls;
pub mod gather;
pub mod gbuffer;
pub mod importance;
pub mod mis;
pub mod present;
pub mod psm;
pub mod reference;
pub mod reproject;
pub mod ris;
pub mod voxelize;

use crate::gpu_scene::GpuScene;
use anyhow::{Context, Result};
use bounce_device::{Buffer, Gpu};

/// Every pass of bounce, with its pipelines: created once per scene, immutable afterwards.
pub struct Passes {
    pub gbuffer: gbuffer::GBuffer,
    pub dprsm: dprsm::Dprsm,
    pub direct: direct::Direct,
    pub end_balls: end_balls::EndBalls,
    pub voxelize: voxelize::Voxelize,
    pub importance: importance::Importance,
    pub cdf_reduce: cdf_reduce::CdfReduce,
    pub gather: gather::Gather,
    /// The gather's recording with the MIS shaders.
    pub mis: gather::Gather,
    pub psm: psm::Psm,
    pub reference: reference::Reference,
    pub ris: ris::Ris,
    /// Motion from the G-buffer and the surface kept for the next frame (temporal reuse).
    pub reproject: reproject::Reproject,
    /// The real-time frame's display filter.
    pub denoise: denoise::Denoise,
    /// The viewer's running mean and tone mapping.
    pub present: present::Present,
}

impl Passes {
    /// `textured`: whether the scene has textures (untextured scenes get shader variants without
    /// texture fetches).
    pub fn new(gpu: &Gpu, textured: bool) -> Result<Passes> {
        Ok(Passes {
            gbuffer: gbuffer::GBuffer::new(gpu, textured).context("creating the gbuffer pass")?,
            dprsm: dprsm::Dprsm::new(gpu, textured).context("creating the dprsm pass")?,
            direct: direct::Direct::new(gpu).context("creating the direct pass")?,
            end_balls: end_balls::EndBalls::new(gpu).context("creating the end_balls pass")?,
            voxelize: voxelize::Voxelize::new(gpu).context("creating the voxelize pass")?,
            importance: importance::Importance::new(gpu).context("creating the importance pass")?,
            cdf_reduce: cdf_reduce::CdfReduce::new(gpu).context("creating the cdf_reduce pass")?,
            gather: gather::Gather::new(gpu).context("creating the gather pass")?,
            mis: mis::create(gpu).context("creating the mis pass")?,
            psm: psm::Psm::new(gpu).context("creating the psm pass")?,
            reference: reference::Reference::new(gpu, textured).context("creating the reference pass")?,
            ris: ris::Ris::new(gpu).context("creating the ris pass")?,
            reproject: reproject::Reproject::new(gpu).context("creating the reproject pass")?,
            denoise: denoise::Denoise::new(gpu).context("creating the denoise pass")?,
            present: present::Present::new(gpu).context("creating the present pass")?,
        })
    }
}

/// What every pass of a frame reads besides graph resources: the static scene and the frame uniforms.
#[derive(Clone, Copy)]
pub struct FrameInputs<'a> {
    pub scene: &'a GpuScene,
    pub uniforms: &'a Buffer,
    pub width: u32,
    pub height: u32,
    /// Resolution per face of the reflective DPRSM (the VPLs).
    pub dprsm_res: u32,
    /// Faces of each light's VPL map (`--light-map`: 2 dprsm, 1 rsm, 6 cube).
    pub vpl_faces: u32,
    /// Where in its texel each VPL's light ray passes, in texels, in layer 0 (`Keys::vpl_offset`).
    pub vpl_offset: [f32; 2],
    /// How the frame's VPL passes test visibility: each picks its shader variant by it.
    pub visibility: crate::frame::Visibility,
    /// The scene's BVH: the exact visibility's shadow rays and gbg's importance rays, the reference's
    /// paths and the end balls trace it.
    pub bvh: &'a crate::gpu_bvh::GpuBvh,
    /// Exact rays one invocation may trace in one dispatch under the device's loop limit (gbg's
    /// importance rays are split over dispatches by it).
    pub traces_per_dispatch: u32,
    /// VPLs one gather dispatch may evaluate per pixel, so that no invocation exceeds the driver's loop
    /// iteration limit (`Gpu::loop_iteration_limit`); `u32::MAX` where there is none.
    pub vpls_per_dispatch: u32,
}

use crate::bindings::*;
use crate::graph::{Handle, PassContext};
use bounce_device::{vk, Binding, DescriptorWrites, Image};

/// The G-buffer as the compute passes read it (sampled, at the `B_GATHER_G*` bindings).
pub fn gbuffer_bindings() -> [Binding; 3] {
    [
        Binding::sampled_image(B_GATHER_GPOSITION),
        Binding::sampled_image(B_GATHER_GNORMAL),
        Binding::sampled_image(B_GATHER_GALBEDO),
    ]
}

/// The reflective DPRSM's VPL images as the compute passes read them (sampled, `B_VPL_*`).
pub fn vpl_bindings() -> [Binding; 3] {
    [Binding::sampled_image(B_VPL_POSITION), Binding::sampled_image(B_VPL_NORMAL), Binding::sampled_image(B_VPL_FLUX)]
}

/// Writes for [`gbuffer_bindings`]: position, normal, albedo.
pub fn gbuffer_writes(
    w: DescriptorWrites,
    ctx: &PassContext,
    g: [&Handle<Image>; 3],
    s: vk::Sampler,
) -> DescriptorWrites {
    w.sampled_image(B_GATHER_GPOSITION, ctx.image(g[0]), s)
        .sampled_image(B_GATHER_GNORMAL, ctx.image(g[1]), s)
        .sampled_image(B_GATHER_GALBEDO, ctx.image(g[2]), s)
}

/// Writes for [`vpl_bindings`]: position, normal, flux.
pub fn vpl_writes(w: DescriptorWrites, ctx: &PassContext, v: [&Handle<Image>; 3], s: vk::Sampler) -> DescriptorWrites {
    w.sampled_image(B_VPL_POSITION, ctx.image(v[0]), s).sampled_image(B_VPL_NORMAL, ctx.image(v[1]), s).sampled_image(
        B_VPL_FLUX,
        ctx.image(v[2]),
        s,
    )
}

/// `[first, last)` split into dispatches of at most `chunk` items (lavapipe's loop limit): each
/// dispatch's `(first, last)`, in order. At least one, so an empty range still gets the dispatch that
/// writes the pass's output.
pub fn dispatch_ranges(first: u32, last: u32, chunk: u32) -> impl Iterator<Item = (u32, u32)> {
    let chunk = chunk.max(1);
    let mut next = Some(first);
    std::iter::from_fn(move || {
        let f = next?;
        let l = f.saturating_add(chunk).min(last).max(f);
        next = (l < last).then_some(l);
        Some((f, l))
    })
}

#[cfg(test)]
mod tests {
    use super::dispatch_ranges;

    #[test]
    fn dispatch_ranges_cover_the_range_once_in_order() {
        let all = |f, l, c| dispatch_ranges(f, l, c).collect::<Vec<_>>();
        assert_eq!(all(0, 10, 4), vec![(0, 4), (4, 8), (8, 10)]);
        assert_eq!(all(3, 5, 10), vec![(3, 5)]);
        assert_eq!(all(7, 7, 4), vec![(7, 7)]);
        assert_eq!(all(0, 3, 0), vec![(0, 1), (1, 2), (2, 3)]);
        assert_eq!(all(u32::MAX - 1, u32::MAX, u32::MAX), vec![(u32::MAX - 1, u32::MAX)]);
    }
}
