//! present: the viewer's picture, made on the GPU: the running mean of the frames since the last change,
//! tone-mapped and sRGB-encoded into an 8-bit image that the swapchain copies (no readback per frame).
//!
//! Inputs: the frame's `radiance` (RGBA32F W×H). Kept: `present.sum` (RGBA32F W×H, a temporal image:
//! the sum of the frames since the last reset), `present.prior` (the last real-time frame, made and
//! written by [`Prior::Keep`]) and `present.moments` (a stop's luminance moments, made at its reset).
//! Output: an RGBA8 UNORM W×H image the caller owns ([`Present::ldr_image`], imported into the graph), sRGB-encoded bytes in the
//! swapchain's channel order. Transient: `present.stats`, one vec4 per workgroup plus one, and
//! `present.mean` (a stop's mean).
//!
//! **A stop** ([`Prior::Use`]): when the camera or a light stops, the viewer's still frames start a new
//! mean, whose first frames can be far noisier than the denoised real-time frame shown while it moved
//! (in the two rooms one ris frame had 35× its error: the picture broke into noise the moment the view
//! stopped). So a still view's mean after a move carries that last real-time frame D (`present.prior`)
//! as w frames' worth, per pixel: mean = (Σ_{k ≤ n} P_k + w D) / (n + w), shown and read back from
//! `present.mean`. w = v / e², v one still frame's luminance variance and e² D's squared error, both
//! over the 3 × 3 pixels around it (from the frames' luminance mean and squared deviations in
//! `present.moments`, kept by Welford's update; e² = mean (l_D − l̄)² less v / n): the weight that
//! makes the blend's error least, at most `STOP_PRIOR_MAX`. At the first frame, where one frame shows no variance, w = `STOP_PRIOR_FIRST`.
//! It fades to 0 over `STOP_PRIOR_FADE` frames; from then on the picture is the plain unbiased mean.
//! Chosen over 22 views stopping after a camera walk (the generated suite's scenes 0 and 2, Sibenik and
//! the two rooms; BENCHMARKS.md, "Real time under motion"): the displayed error after 4 still frames
//! 0.61× the plain mean's (geomean; worst 0.91×), over the first 64 frames 0.80× (worst 1.00×); one
//! frame's worth everywhere: 0.76× and 0.86×. At the first frame 0.43× (worst 0.81×, light-wall-0);
//! w from that frame's neighbourhood variance there: worst 2.0×; W = 2: 0.38×, worst 1.11×.
//!
//! Mapping (the thesis's, and `crates/app/src/output.rs`'s for PNGs): mean = sum / frames; Reinhard et
//! al. 2002's global operator with key a = 0.18 over the log-average luminance
//! L̄_w = exp(mean ln(δ + L_w)) (δ = 10⁻⁶; finite L_w ≥ 0 only), times `exposure`:
//! L = L_w · exposure · a / L̄_w, L_d = L (1 + L / L_white²) / (1 + L), L_white the largest L; the colour
//! is scaled by L_d / L_w, clamped to [0, 1] and sRGB-encoded, rounded as the PNG writer rounds. It
//! runs in f32 where the PNG writer runs in f64: equal within one 8-bit step (tested).
//!
//! Dispatches (serialized): ⌈W/8⌉ × ⌈H/8⌉ groups accumulate and reduce per workgroup (during a stop,
//! another ⌈W/8⌉ × ⌈H/8⌉ weigh the prior and reduce); one group reduces the partials (loops bounded by
//! groups / 64); ⌈W/8⌉ × ⌈H/8⌉ groups map.

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

/// The last real-time frame's part in the running mean.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Prior {
    /// None.
    None,
    /// This frame (a real-time one, shown alone) is kept as the prior.
    Keep,
    /// The mean is a still view's after a move: it carries the kept prior (the module's "A stop"), from
    /// the mean's first frame (a reset) on, where a kept frame of this size wrote one.
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
    /// Whether this frame's mean may carry the kept prior (a stop's first `STOP_PRIOR_FADE` frames).
    pub fn carries_prior(&self) -> bool {
        self.prior == Prior::Use && (self.frames as f32) < 1.0 + STOP_PRIOR_FADE
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
            Binding::storage_image(B_PRESENT_MOMENTS),
            Binding::storage_image(B_PRESENT_MEAN),
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

    /// Adds `radiance` to the running mean and maps the mean into `out`; returns the image a screenshot
    /// reads back and what to divide it by for the linear mean the picture shows: the sum and its frames,
    /// or with [`Prior::Use`] the mean itself and 1.
    pub fn add<'a>(
        &'a self,
        g: &mut Graph<'a>,
        radiance: &Handle<Image>,
        out: &mut Handle<Image>,
        width: u32,
        height: u32,
        p: PresentParams,
    ) -> Result<(Handle<Image>, f32)> {
        let pipeline = self.pipeline.pipeline()?;
        let desc = |name| crate::frame::recipe::radiance_desc(name, width, height);
        let kept = g.temporal_image("present.sum", desc("present.sum"), &());
        let mut sum = kept.handle;
        // A new sum image holds nothing to add to.
        let reset = p.reset || kept.fresh;
        let (mut prior, mut moments, prior_mode) = stop_images(g, &p, reset, width, height);
        // The blended mean, only while a stop carries the prior (otherwise the sum stands in at its binding,
        // which nothing then reads through).
        let mut mean = (prior_mode == PRESENT_PRIOR_USE).then(|| g.create_image(desc("present.mean")));
        let groups = width.div_ceil(WG_2D) * height.div_ceil(WG_2D);
        let mut stats = g.create_buffer(BufferDesc::storage("present.stats", 16 * (groups as u64 + 1)));
        let push = PresentPush {
            frames: p.frames.max(1) as f32,
            reset: reset as u32,
            swap_rb: p.swap_rb as u32,
            exposure: p.exposure,
            groups,
            prior: prior_mode,
            ..PresentPush::default()
        };
        let (radiance, o, s, st) = (*radiance, *out, sum, stats);
        // Where the stop's images are not made, the sum stands in at their bindings (nothing reads or
        // writes them there).
        let (pr, mo, me) = (prior.unwrap_or(sum), moments.unwrap_or(sum), mean.unwrap_or(sum));
        let mut b = g.add_pass("present").read(&radiance, Access::ComputeRead).write(&mut sum, Access::ComputeWrite);
        for h in [prior.as_mut(), moments.as_mut()].into_iter().flatten() {
            b = b.write(h, Access::ComputeWrite);
        }
        if let Some(m) = mean.as_mut() {
            b = b.overwrite(m, Access::ComputeWrite);
        }
        b.overwrite(&mut stats, Access::ComputeWrite).overwrite(out, Access::ComputeWrite).record(move |ctx| {
            let writes = DescriptorWrites::new()
                .sampled_image(B_PRESENT_RADIANCE, ctx.image(&radiance), self.sampler.raw)
                .storage_image(B_PRESENT_SUM, ctx.image(&s))
                .storage_image(B_PRESENT_OUT, ctx.image(&o))
                .storage_buffer(B_PRESENT_STATS, ctx.buffer(&st))
                .storage_image(B_PRESENT_PRIOR, ctx.image(&pr))
                .storage_image(B_PRESENT_MOMENTS, ctx.image(&mo))
                .storage_image(B_PRESENT_MEAN, ctx.image(&me));
            let grid = [width, height, 1];
            let wg = [WG_2D, WG_2D, 1];
            let stage = |stage| PresentPush { stage, ..push };
            pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&stage(PRESENT_ACCUMULATE)), grid, wg);
            ctx.serialize(&s);
            if push.prior == PRESENT_PRIOR_USE {
                // The weights read the moments around each pixel.
                ctx.serialize(&mo);
                pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&stage(PRESENT_WEIGHT)), grid, wg);
                ctx.serialize(&me);
            }
            ctx.serialize(&st);
            pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&stage(PRESENT_TOTAL)), wg, wg);
            ctx.serialize(&st);
            pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&stage(PRESENT_MAP)), grid, wg);
        });
        Ok(match mean {
            Some(m) => (m, 1.0),
            None => (sum, push.frames),
        })
    }
}

/// The images of a stop (the module's "A stop") and the prior's mode for the shader. The last real-time
/// frame is made by the frame that keeps it and only found by a stop's, so a stop after a resize, say,
/// finds none rather than an image nothing wrote; its luminance moments are made at the stop's reset and
/// only found after.
fn stop_images<'a>(
    g: &mut Graph<'a>,
    p: &PresentParams,
    reset: bool,
    width: u32,
    height: u32,
) -> (Option<Handle<Image>>, Option<Handle<Image>>, u32) {
    let desc = |name| crate::frame::recipe::radiance_desc(name, width, height);
    let prior = match p.prior {
        Prior::Keep => Some(g.temporal_image("present.prior", desc("present.prior"), &()).handle),
        Prior::Use if p.carries_prior() => g.existing_temporal_image("present.prior", &desc("present.prior"), &()),
        _ => None,
    };
    let moments = match (p.prior, prior) {
        (Prior::Use, Some(_)) if reset => {
            Some(g.temporal_image("present.moments", desc("present.moments"), &()).handle)
        }
        (Prior::Use, Some(_)) => g.existing_temporal_image("present.moments", &desc("present.moments"), &()),
        _ => None,
    };
    let mode = match (p.prior, prior, moments) {
        (Prior::Keep, _, _) => PRESENT_PRIOR_KEEP,
        (Prior::Use, Some(_), Some(_)) => PRESENT_PRIOR_USE,
        _ => PRESENT_PRIOR_NONE,
    };
    (prior, moments, mode)
}
