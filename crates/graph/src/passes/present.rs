//! present: the viewer's picture, made on the GPU: the running mean of the frames since the last change,
//! tone-mapped and sRGB-encoded into an 8-bit image that the swapchain copies (no readback per frame).
//!
//! Inputs: the frame's `radiance` (RGBA32F W×H). Kept: `present.sum` (RGBA32F W×H, a temporal image:
//! the sum of the frames since the last reset). Output: an RGBA8 UNORM W×H image the caller owns
//! ([`Present::ldr_image`], imported into the graph), sRGB-encoded bytes in the swapchain's channel
//! order. Transient: `present.stats`, one vec4 per workgroup plus one.
//!
//! Mapping (the thesis's, and `crates/app/src/output.rs`'s for PNGs): mean = sum / frames; Reinhard et
//! al. 2002's global operator with key a = 0.18 over the log-average luminance
//! L̄_w = exp(mean ln(δ + L_w)) (δ = 10⁻⁶; finite L_w ≥ 0 only), times `exposure`:
//! L = L_w · exposure · a / L̄_w, L_d = L (1 + L / L_white²) / (1 + L), L_white the largest L; the colour
//! is scaled by L_d / L_w, clamped to [0, 1] and sRGB-encoded, rounded as the PNG writer rounds. It
//! runs in f32 where the PNG writer runs in f64: equal within one 8-bit step (tested).
//!
//! Dispatches (serialized): ⌈W/8⌉ × ⌈H/8⌉ groups accumulate and reduce per workgroup; one group reduces
//! the partials (loops bounded by groups / 64); ⌈W/8⌉ × ⌈H/8⌉ groups map.

use crate::bindings::*;
use crate::graph::{Graph, Handle, Persistent};
use crate::pipelines::Lazy;
use crate::shader_types::PresentPush;
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{vk, Binding, BufferDesc, DescriptorWrites, Gpu, Image, ImageDesc, Sampler};

/// The 8-bit output's format: the same 32-bit size as the swapchain's UNORM formats, so a plain image
/// copy moves it.
pub const LDR_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

/// How one frame is presented.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PresentParams {
    /// Frames in the running mean, this one included (≥ 1).
    pub frames: u32,
    /// The sum restarts at this frame (camera, lights or settings changed).
    pub reset: bool,
    /// Multiplies Reinhard's scale (1: the PNG writer's mapping).
    pub exposure: f32,
    /// Write B, G, R: the swapchain is BGRA.
    pub swap_rb: bool,
}

pub struct Present {
    /// Built when the viewer first presents (`render` never does).
    pipeline: Lazy<1>,
    sampler: Sampler,
}

impl Present {
    pub fn new(gpu: &Gpu) -> Result<Self> {
        let bindings = [
            Binding::sampled_image(B_PRESENT_RADIANCE),
            Binding::storage_image(B_PRESENT_SUM),
            Binding::storage_image(B_PRESENT_OUT),
            Binding::storage_buffer(B_PRESENT_STATS),
        ];
        let push = std::mem::size_of::<PresentPush>() as u32;
        let pipeline = Lazy::new(gpu, "present", shaders::PRESENT_COMP, &bindings, push);
        Ok(Present { pipeline, sampler: Sampler::nearest(gpu)? })
    }

    /// An 8-bit output image of `width` × `height` for [`Present::add`], owned by the caller (the viewer
    /// keeps one per window size and copies it into the swapchain).
    pub fn ldr_image(gpu: &Gpu, width: u32, height: u32) -> Result<Persistent<Image>> {
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        Ok(Persistent::new(Image::new(gpu, &ImageDesc::new("present.ldr", width, height, LDR_FORMAT, usage))?))
    }

    /// Adds `radiance` to the running mean and maps the mean into `out`; returns the sum image (read it
    /// back, divided by `p.frames`, for a screenshot's linear mean).
    pub fn add<'a>(
        &'a self,
        g: &mut Graph<'a>,
        radiance: &Handle<Image>,
        out: &mut Handle<Image>,
        width: u32,
        height: u32,
        p: PresentParams,
    ) -> Result<Handle<Image>> {
        let pipeline = self.pipeline.pipeline()?;
        let desc = crate::frame::recipe::radiance_desc("present.sum", width, height);
        let kept = g.temporal_image("present.sum", desc, &());
        let mut sum = kept.handle;
        let groups = width.div_ceil(WG_2D) * height.div_ceil(WG_2D);
        let mut stats = g.create_buffer(BufferDesc::storage("present.stats", 16 * (groups as u64 + 1)));
        let push = PresentPush {
            frames: p.frames.max(1),
            // A new sum image holds nothing to add to.
            reset: (p.reset || kept.fresh) as u32,
            swap_rb: p.swap_rb as u32,
            exposure: p.exposure,
            groups,
            ..PresentPush::default()
        };
        let (radiance, o, s, st) = (*radiance, *out, sum, stats);
        g.add_pass("present")
            .read(&radiance, Access::ComputeRead)
            .write(&mut sum, Access::ComputeWrite)
            .overwrite(&mut stats, Access::ComputeWrite)
            .overwrite(out, Access::ComputeWrite)
            .record(move |ctx| {
                let writes = DescriptorWrites::new()
                    .sampled_image(B_PRESENT_RADIANCE, ctx.image(&radiance), self.sampler.raw)
                    .storage_image(B_PRESENT_SUM, ctx.image(&s))
                    .storage_image(B_PRESENT_OUT, ctx.image(&o))
                    .storage_buffer(B_PRESENT_STATS, ctx.buffer(&st));
                let grid = [width, height, 1];
                let wg = [WG_2D, WG_2D, 1];
                let accumulate = PresentPush { stage: PRESENT_ACCUMULATE, ..push };
                pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&accumulate), grid, wg);
                ctx.serialize(&st);
                let total = PresentPush { stage: PRESENT_TOTAL, ..push };
                pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&total), wg, wg);
                ctx.serialize(&st);
                ctx.serialize(&s);
                let map = PresentPush { stage: PRESENT_MAP, ..push };
                pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&map), grid, wg);
            });
        Ok(sum)
    }
}
