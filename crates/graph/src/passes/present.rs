//! present: the viewer's picture, made on the GPU: the running mean of the frames since the last change,
//! tone-mapped and sRGB-encoded into an 8-bit image that the swapchain copies (no readback per frame).
//!
//! Inputs: the frame's `radiance` (RGBA32F W×H). Kept: `present.sum` (RGBA32F W×H, a temporal image:
//! the sum of the frames since the last reset) and `present.prior` (the last real-time frame, kept by
//! [`Prior::Keep`]). Output: an RGBA8 UNORM W×H image the caller owns
//! ([`Present::ldr_image`], imported into the graph), sRGB-encoded bytes in the swapchain's channel
//! order. Transient: `present.stats`, one vec4 per workgroup plus one.
//!
//! **A stop** ([`Prior::Use`]): when the camera or a light stops, the viewer's still frames start a new
//! mean, whose first frames can be far noisier than the denoised real-time frame shown while it moved
//! (in the two rooms one ris frame had 35× its error: the picture broke into noise the moment the view
//! stopped). So a still view's mean after a move carries that last real-time frame D as w_n frames'
//! worth, mean_n = (Σ_{k ≤ n} P_k + w_n D) / (n + w_n), w_n = [`STOP_PRIOR_FRAMES`] · max(0, 1 − (n − 1)
//! / [`STOP_PRIOR_FADE`]): the first still picture is the mean of D and one still frame, and from frame
//! `STOP_PRIOR_FADE` + 1 on it is the plain unbiased mean again (the sum takes w_n − w_{n−1} of D each
//! frame, so their total is 0). The weights are one constant for every scene, chosen by the display's
//! error over the first 64 still frames of 22 views (the constants' comments). A weight by each pixel's
//! noise (D against the running mean's spread) would fit scenes whose denoised frame is much better or
//! much worse than one still frame; it is not built.
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

/// W: frames' worth of the last real-time frame in a still view's first mean after a move. Chosen over
/// 22 views stopping after a camera walk (the generated suite's scenes 0 and 2, Sibenik and the two
/// rooms; BENCHMARKS.md): the display's error at the first still frame 0.44× the plain mean's (geomean;
/// worst 1.18×, light-wall-0, whose denoised frame had 4× one still frame's error), over the first 64
/// frames 0.86× (worst 1.00×); W = 2: 0.40× but worst 1.79×; W = 0.5: 0.54×, worst 0.84×.
pub const STOP_PRIOR_FRAMES: f32 = 1.0;
/// Frames over which its weight fades to 0 (linearly; 16: 0.87× over the 64 frames, never fading 0.84×
/// but never the plain mean again).
pub const STOP_PRIOR_FADE: f32 = 32.0;

/// w_n: the last real-time frame's weight in the mean of a still view's first `n` frames after a move.
pub fn stop_prior_weight(n: u32) -> f32 {
    STOP_PRIOR_FRAMES * (1.0 - n.saturating_sub(1) as f32 / STOP_PRIOR_FADE).max(0.0)
}

/// The last real-time frame's part in the running mean.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Prior {
    /// None.
    None,
    /// This frame (a real-time one, shown alone) is kept as the prior.
    Keep,
    /// The mean is a still view's after a move: it carries the kept prior, [`stop_prior_weight`].
    Use,
}

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
    pub prior: Prior,
}

impl PresentParams {
    /// The prior's weight w_n in this frame's mean.
    pub fn prior_weight(&self) -> f32 {
        match self.prior {
            Prior::Use => stop_prior_weight(self.frames.max(1)),
            _ => 0.0,
        }
    }

    /// What the running mean divides its sum by: its frames and the prior's weight.
    pub fn weight(&self) -> f32 {
        self.frames.max(1) as f32 + self.prior_weight()
    }

    /// w_n − w_{n−1}: the prior's weight the sum takes at this frame (a new mean starts from 0).
    fn prior_delta(&self) -> f32 {
        let before = match (self.prior, self.reset) {
            (Prior::Use, false) => stop_prior_weight(self.frames.max(2) - 1),
            _ => 0.0,
        };
        self.prior_weight() - before
    }
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
            Binding::storage_image(B_PRESENT_PRIOR),
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
    /// back, divided by `p.weight()`, for a screenshot's linear mean: what the picture shows).
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
        let kept = g.temporal_image("present.sum", desc.clone(), &());
        let mut sum = kept.handle;
        let prior_kept = g.temporal_image("present.prior", desc, &());
        let mut prior = prior_kept.handle;
        // A prior never kept (a new image) holds nothing to carry.
        let p = if prior_kept.fresh && p.prior == Prior::Use { PresentParams { prior: Prior::None, ..p } } else { p };
        let groups = width.div_ceil(WG_2D) * height.div_ceil(WG_2D);
        let mut stats = g.create_buffer(BufferDesc::storage("present.stats", 16 * (groups as u64 + 1)));
        // A new sum image holds nothing to add to.
        let reset = p.reset || kept.fresh;
        let push = PresentPush {
            frames: p.weight(),
            reset: reset as u32,
            swap_rb: p.swap_rb as u32,
            exposure: p.exposure,
            groups,
            prior_delta: PresentParams { reset, ..p }.prior_delta(),
            keep_prior: (p.prior == Prior::Keep) as u32,
            ..PresentPush::default()
        };
        let (radiance, o, s, st, pr) = (*radiance, *out, sum, stats, prior);
        g.add_pass("present")
            .read(&radiance, Access::ComputeRead)
            .write(&mut sum, Access::ComputeWrite)
            .write(&mut prior, Access::ComputeWrite)
            .overwrite(&mut stats, Access::ComputeWrite)
            .overwrite(out, Access::ComputeWrite)
            .record(move |ctx| {
                let writes = DescriptorWrites::new()
                    .sampled_image(B_PRESENT_RADIANCE, ctx.image(&radiance), self.sampler.raw)
                    .storage_image(B_PRESENT_SUM, ctx.image(&s))
                    .storage_image(B_PRESENT_OUT, ctx.image(&o))
                    .storage_buffer(B_PRESENT_STATS, ctx.buffer(&st))
                    .storage_image(B_PRESENT_PRIOR, ctx.image(&pr));
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
