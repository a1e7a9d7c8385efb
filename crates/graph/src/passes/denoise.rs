//! denoise: the real-time frame's display filter, spatiotemporal variance-guided filtering (SVGF,
//! Schied et al. 2017) on the indirect light, its luminance stop scaled by the estimate's measured noise.
//! Three stages, one shader each over `glsl/shared/denoise.glsl`:
//!
//! - `denoise_temporal`: the raw estimate's indirect light, demodulated by the albedo, ĩ = (L − L_direct)
//!   / ρ, is blended into last frame's accumulation where the pixel's point was (`passes/reproject.rs`;
//!   restarted where the surface was disoccluded; looked up bilinearly where the four pixels around that
//!   place saw the same surface, else in the pixel it fell in): Ī ← (1 − a) clamp(Ī_prev) + a ĩ with
//!   a = max(α, 1 / n), n the history's length, and so is the estimate's variance σ²_f (the raw image's alpha: ris's shade
//!   measures it over the pixel's reservoirs, `glsl/ris_shade.comp`). The history is first clamped into
//!   this frame's 5 × 5 neighbourhood, mean ± `DENOISE_CLAMP_SIGMAS` standard deviations per channel (as
//!   temporal anti-aliasing clamps colours), so that light that moved is not dragged along; and a
//!   temporal gradient test (after A-SVGF, Schied et al. 2018) raises a to λ where the lighting changed:
//!   Δ, the change of the 5 × 5 mean luminance from the history's, against its noise s from the measured
//!   variance, λ = max(0, (Δ − `DENOISE_GRADIENT_SIGMAS` · s) / Δ). (A-SVGF re-shades last frame's
//!   samples for a noise-free Δ; here the noise is known instead.) The accumulation (rgb, n) and the
//!   variance are kept for the next frame (`denoise.color`, `denoise.variance`, histories keyed by the size).
//! - `denoise_variance`: σ² = the accumulated σ²_f; where n < 4, pooled over the 7 × 7 neighbourhood
//!   (weighted by the geometric edge stops), raised to the noise scale s = max(σ, σ² / m) (m the
//!   neighbourhood's mean luminance: where the noise is sparse hits, one hit's size), and the illumination
//!   filtered there once with the edge stops and the luminance stop at s.
//! - `denoise_atrous` × `DENOISE_ITERATIONS` (tap spacing 1, 2, 4, 8, 16): the 5 × 5 B3-spline kernel
//!   h(k) with edge stops w = h · max(0, n_p · n_q)^σ_n · exp(−|n_p · (x_q − x_p)| / (σ_z θ_px |x_p − eye|
//!   · |Δ|)) · exp(−|l_p − l_q| / (σ_l √(G₃ₓ₃ ∗ σ²)_p)); the variance is filtered with w². The plane
//!   distance in pixel footprints makes the depth stop scale-free. The first `DENOISE_GATHER_ITERATIONS`
//!   (four) gather: Ī_p ← a, the intercept of the plane a + b · d fitted to the taps by weighted least
//!   squares (d the tap's offset; a ridge `DENOISE_RIDGE` · Σ w on b; clamped into the taps' range),
//!   which is SVGF's Ī_p ← Σ w Ī_q / Σ w wherever Σ w d = 0; the last exchanges, Ī_p ← Ī_p + Σ w_pq
//!   (Ī_q − Ī_p), with symmetric stops (the larger plane distance; the luminance against √(σ_p σ_q)) and
//!   the rejected weight left on p. The last iteration writes ρ · Ī + L_direct.
//!
//! Why the measured variance and not SVGF's: SVGF's σ² = E[l²] − E[l]² over the frames (over the 7 × 7
//! neighbourhood for a young history) counts the signal's own variation as noise, so next to a bright
//! peak (a light in a corner) every pixel's stop accepts everything and the à-trous, a normalized
//! gather, averages the peak into its dim plane: the light-corner scenes' denoised images held 0.33–0.48
//! of the truth's mean. With the measured variance they held 0.55–0.75 (0.75–0.86 as built now, the
//! gathers fitting planes), and the generated suite's denoised error fell by a fifth to a quarter (and by as
//! much again with the gradient test) (BENCHMARKS.md, "Real time under motion").
//!
//! Why the gathers fit planes: a weighted mean is pulled toward the taps that the stops keep, and at a
//! plane's edge (or beside a neighbour the luminance stop rejects) those lie on one side: where the light
//! rises toward the edge, as next to a light in a corner, the edge pixel takes the dimmer inside's values
//! and the peak sinks, iteration by iteration. The intercept of a plane fitted to the same taps follows
//! the slope to the edge, and is the weighted mean itself where the taps are balanced (Dammertz's and
//! SVGF's filters are the zeroth-order case of this local regression). On the generated suite under motion
//! four fitting gathers then one exchange had 0.88× the denoised relMSE and 0.94× the flicker of two
//! gathers by weighted means then three exchanges, 0.91× and 0.94× on the scenes held out, and kept more
//! of the light next to a corner (the lowest image mean 0.68 → 0.75) (BENCHMARKS.md, "Real time under motion").
//!
//! Why the last iteration exchanges: a gather, fitted or not, loses light wherever the signal peaks at a
//! plane's edge. Its weights sum to 1 over each output pixel, not over each input pixel: a pixel on the
//! edge has fewer taps, so its own value counts for more in its own output and less in its neighbours',
//! which normalize by their larger sums (in 1-D, a B3 tap row cut at the edge passes on 0.87 of the edge
//! pixel's light). An exchange with symmetric weights is a doubly stochastic filter: it keeps every
//! constant and every sum, so it moves light along a plane and loses none. But it cannot take a lone hit
//! away from where it fell (a pixel gives back what it takes), which the gathers do: with weighted means,
//! all five exchanging kept 0.89 of a corner's light for 1.42× the flicker, two gathers then three
//! exchanges lowered both the error and the flicker of five gathers; with fitted planes, four then one
//! lowered both again (BENCHMARKS.md, "Real time under motion").
//!
//! Why the history is looked up bilinearly, and only where all four pixels saw the same surface: under a
//! moving camera a point falls between last frame's pixel centres, and the pixel it fell in holds the
//! accumulation up to half a pixel away, a shift that changes from frame to frame (a still camera loses
//! nothing: its points fall on the centres). Bilinearly, the generated suite's camera orbits had 0.83× the
//! denoised error and 0.85× the flicker, and no run more than 1.03×; renormalized over the pixels that
//! saw the surface where some did not, the lookup is a gather, which loses a bright edge's light frame
//! after frame (the light-corner runs 1.3–5× the error) (BENCHMARKS.md, "Real time under motion").
//!
//! Why a frame's variance, blended over the history, and not the accumulation's (which falls as 1 / n as
//! the history grows): the tighter stop keeps a corner's peak in a still view, but the filter serves
//! moving views, whose short histories it then leaves noisier: on the generated suite under motion 1.09×
//! the denoised error and 1.39× the flicker, and no σ_l buys back both (BENCHMARKS.md, "Things tried").
//!
//! Inputs: the raw radiance (direct light included when `add_direct`; its alpha the estimate's variance),
//! the direct light, the G-buffer, the frame's `Motion`. Output: the denoised radiance, RGBA32F. The raw
//! estimate is untouched (what the error of the estimator is measured on); the filter is biased by design
//! (it trades variance for blur and lag), so its output's error against the ground truth is reported
//! beside the raw one (`bounce bench --animate`). The history fed back is the unfiltered accumulation
//! (SVGF feeds back its first à-trous iteration's output, which blurs further with each frame).

use super::reproject::Motion;
use super::FrameInputs;
use crate::bindings::*;
use crate::graph::{Graph, Handle, PassBuilder};
use crate::passes::gbuffer::GBufferOut;
use crate::pipelines::Lazy;
use crate::shader_types::DenoisePush;
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{vk, Binding, Gpu, Image, ImageDesc, Sampler};

/// The filter's constants: SVGF's published α = 0.2 and σ_n = 128; σ_z = 1 footprint per pixel of offset;
/// σ_l = 2 standard deviations of the measured noise (SVGF's 4 is for its variance, which holds signal
/// too): chosen over the generated suite (σ_l 1.5 / 2 / 3 / 4: denoised relMSE over ris at 4's geomean
/// 0.171 / 0.173 / 0.189 / 0.207, worst 0.995 / 0.936 / 0.98 / 1.12; BENCHMARKS.md).
pub const DEFAULTS: DenoisePush =
    DenoisePush { history: 0, step: 1, last: 0, add_direct: 0, alpha: 0.2, sigma_l: 2.0, sigma_n: 128.0, sigma_z: 1.0 };

pub struct Denoise {
    temporal: Lazy<1>,
    variance: Lazy<1>,
    atrous: Lazy<1>,
    sampler: Sampler,
}

/// A stage's pass: it reads the G-buffer and `reads`.
fn stage<'g, 'a>(
    g: &'g mut Graph<'a>,
    name: &'static str,
    gb: &GBufferOut,
    reads: &[Handle<Image>],
) -> PassBuilder<'g, 'a> {
    let mut b = g.add_pass(name);
    for r in [gb.position, gb.normal, gb.albedo].iter().chain(reads) {
        b = b.read(r, Access::ComputeRead);
    }
    b
}

fn image(name: &str, w: u32, h: u32) -> ImageDesc {
    image_of(name, w, h, vk::Format::R32G32B32A32_SFLOAT)
}

fn image_of(name: &str, w: u32, h: u32, format: vk::Format) -> ImageDesc {
    ImageDesc::new(
        name,
        w,
        h,
        format,
        vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC,
    )
}

impl Denoise {
    pub fn new(gpu: &Gpu) -> Result<Self> {
        let with = |extra: &[Binding]| {
            let mut b = crate::gpu_scene::scene_bindings();
            b.extend(super::gbuffer_bindings());
            b.extend_from_slice(extra);
            b
        };
        let push = std::mem::size_of::<DenoisePush>() as u32;
        let sampled = Binding::sampled_image;
        let temporal = with(&[
            sampled(B_DENOISE_IN),
            sampled(B_GATHER_DIRECT),
            sampled(B_MOTION),
            sampled(B_DENOISE_PREV_COLOR),
            sampled(B_DENOISE_PREV_VARIANCE),
            Binding::storage_image(B_DENOISE_COLOR_OUT),
            Binding::storage_image(B_DENOISE_VARIANCE_OUT),
        ]);
        let variance =
            with(&[sampled(B_DENOISE_IN), sampled(B_DENOISE_VARIANCE), Binding::storage_image(B_DENOISE_OUT)]);
        let atrous = with(&[sampled(B_DENOISE_IN), sampled(B_GATHER_DIRECT), Binding::storage_image(B_DENOISE_OUT)]);
        Ok(Denoise {
            temporal: Lazy::new(gpu, "denoise_temporal", shaders::DENOISE_TEMPORAL_COMP, &temporal, push),
            variance: Lazy::new(gpu, "denoise_variance", shaders::DENOISE_VARIANCE_COMP, &variance, push),
            atrous: Lazy::new(gpu, "denoise_atrous", shaders::DENOISE_ATROUS_COMP, &atrous, push),
            sampler: Sampler::nearest(gpu)?,
        })
    }

    /// The denoised radiance of `raw` (which holds `direct` when it is given).
    pub fn add<'a>(
        &'a self,
        g: &mut Graph<'a>,
        f: FrameInputs<'a>,
        gb: &GBufferOut,
        m: &Motion,
        raw: Handle<Image>,
        direct: Option<Handle<Image>>,
    ) -> Result<Handle<Image>> {
        let (w, h) = (f.width, f.height);
        let (temporal, variance, atrous) =
            (self.temporal.pipeline()?, self.variance.pipeline()?, self.atrous.pipeline()?);
        let color = g.history_image("denoise.color", image("denoise.color", w, h), &(w, h));
        let variance_image = |name| image_of(name, w, h, vk::Format::R32_SFLOAT);
        let noise = g.history_image("denoise.variance", variance_image("denoise.variance"), &(w, h));
        let history = color.previous.is_some() && noise.previous.is_some();
        let (prev_color, prev_variance) = match (color.previous, noise.previous) {
            (Some(c), Some(v)) => (c, v),
            // Stand-ins the shader does not read (history = 0).
            _ => (
                g.create_image(image("denoise.color (none)", 1, 1)),
                g.create_image(image_of("denoise.variance (none)", 1, 1, vk::Format::R32_SFLOAT)),
            ),
        };
        // The direct light, or (never read) a stand-in.
        let direct_or = direct.unwrap_or_else(|| g.create_image(image("denoise.direct (none)", 1, 1)));
        let gb = *gb;
        let base = DenoisePush { add_direct: direct.is_some() as u32, ..DEFAULTS };
        let m = *m;
        let s = self.sampler.raw;
        let gbw = move |ctx: &crate::graph::PassContext| {
            super::gbuffer_writes(f.scene.writes(f.uniforms), ctx, [&gb.position, &gb.normal, &gb.albedo], s)
        };
        let size = [w, h, 1];
        let (mut acc, mut var) = (color.current, noise.current);
        let (ca, cv) = (acc, var);
        let push = DenoisePush { history: history as u32, ..base };
        stage(g, "denoise_temporal", &gb, &[raw, direct_or, m.motion, prev_color, prev_variance])
            .overwrite(&mut acc, Access::ComputeWrite)
            .overwrite(&mut var, Access::ComputeWrite)
            .record(move |ctx| {
                let writes = gbw(ctx)
                    .sampled_image(B_DENOISE_IN, ctx.image(&raw), s)
                    .sampled_image(B_GATHER_DIRECT, ctx.image(&direct_or), s)
                    .sampled_image(B_MOTION, ctx.image(&m.motion), s)
                    .sampled_image(B_DENOISE_PREV_COLOR, ctx.image(&prev_color), s)
                    .sampled_image(B_DENOISE_PREV_VARIANCE, ctx.image(&prev_variance), s)
                    .storage_image(B_DENOISE_COLOR_OUT, ctx.image(&ca))
                    .storage_image(B_DENOISE_VARIANCE_OUT, ctx.image(&cv));
                temporal.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&push), size, [WG_2D, WG_2D, 1]);
            });
        let mut ping = g.create_image(image("denoise.ping", w, h));
        let p = ping;
        stage(g, "denoise_variance", &gb, &[acc, var]).overwrite(&mut ping, Access::ComputeWrite).record(move |ctx| {
            let writes = gbw(ctx)
                .sampled_image(B_DENOISE_IN, ctx.image(&acc), s)
                .sampled_image(B_DENOISE_VARIANCE, ctx.image(&var), s)
                .storage_image(B_DENOISE_OUT, ctx.image(&p));
            variance.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&base), size, [WG_2D, WG_2D, 1]);
        });
        for i in 0..DENOISE_ITERATIONS {
            let last = i + 1 == DENOISE_ITERATIONS;
            let name = if last { "denoise.out" } else { "denoise.pong" };
            let mut next = g.create_image(image(name, w, h));
            let (src, dst) = (ping, next);
            let push = DenoisePush { step: 1 << i, last: last as u32, ..base };
            stage(g, "denoise_atrous", &gb, &[src, direct_or]).overwrite(&mut next, Access::ComputeWrite).record(
                move |ctx| {
                    let writes = gbw(ctx)
                        .sampled_image(B_DENOISE_IN, ctx.image(&src), s)
                        .sampled_image(B_GATHER_DIRECT, ctx.image(&direct_or), s)
                        .storage_image(B_DENOISE_OUT, ctx.image(&dst));
                    atrous.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&push), size, [WG_2D, WG_2D, 1]);
                },
            );
            ping = next;
        }
        Ok(ping)
    }
}
