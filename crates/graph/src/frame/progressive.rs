//! Progressive rendering under a time budget (`bounce render --time-limit`, `bounce bench
//! --time-limits`): frame k renders with seed `seed + k` and is added to a running mean (f64 on the
//! host), until the budget would be exceeded. Every frame is an unbiased estimate of the same image (each
//! sampled method is unbiased for the VPL sum given any CDF, the reference for the one-bounce integral),
//! so the mean is too, and its variance falls as 1/frames. All frames share one CDF (the importance's
//! seed is `--cdf-seed`, else the first frame's seed), as the viewer's do: the importance and CDF are
//! built once and kept by the graph, and each later frame records only the gather.
//!
//! The reference is the exception ([`frame_settings`]): its frames keep the seed and continue the
//! pixel's Owen-scrambled Sobol sequence (frame k takes samples k · spp .. (k + 1) · spp), so their mean
//! is that of one stratified set of F · spp points, whose variance falls faster than 1/F. Each point is
//! still uniform, so the mean stays unbiased. Measured: BENCHMARKS.md, "The path tracer's frames".
//!
//! `all` and the direct component are the same every frame: they render one frame, whatever the budget.
//! `realtime`'s frames are averaged raw (its denoised output is biased by design); they reuse one
//! another's reservoirs, so they are correlated, and the mean's error falls slower than 1/frames.
//!
//! The budget counts the frames' wall time, not the start-up before them (device, pipelines, scene
//! upload). A frame is started only if it should end within the budget, judged by the last frame's time;
//! the first frame always runs, and so does a second while time is left (the first also built what the
//! others reuse, so only the second tells what a frame costs).

use super::renderer::{FrameOutput, Renderer};
use super::settings::{Component, FrameSettings, Method};
use anyhow::Result;
use std::time::{Duration, Instant};

/// The accumulated result of [`render_for`].
pub struct Progressive {
    /// The mean of the frames' radiance.
    pub radiance: Vec<[f32; 4]>,
    pub frames: u32,
    /// Wall time of the frames.
    pub wall: Duration,
    /// The last frame (its timings, warnings, size).
    pub last: FrameOutput,
    /// Sum of every frame's GPU time, if the device has timestamps.
    pub gpu_ms: Option<f64>,
}

/// Whether more than one frame can change the mean: `all` (every VPL) and the direct component are the
/// same every frame, so one frame is their converged result.
pub fn averages(s: &FrameSettings) -> bool {
    s.method != Method::All && s.component != Component::Direct
}

/// Frame `k` of a progressive render of `s`: the reference's frames continue one stratified sample
/// sequence (same seed, samples `k · spp ..`), until it would run past 2^32 points, where it moves on to
/// the next seed's; every other method's frames take seeds `s.seed + k`, one CDF between them.
pub fn frame_settings(s: &FrameSettings, k: u32) -> FrameSettings {
    if s.method == Method::Reference {
        let per_seed = ((u32::MAX - s.sample_offset) / s.spp.max(1)).max(1);
        return FrameSettings {
            seed: s.seed.wrapping_add((k / per_seed) as u64),
            sample_offset: s.sample_offset.wrapping_add((k % per_seed) * s.spp),
            ..s.clone()
        };
    }
    FrameSettings { seed: s.seed.wrapping_add(k as u64), cdf_seed: Some(s.cdf_seed.unwrap_or(s.seed)), ..s.clone() }
}

/// Render frames of `s` (seeds `s.seed`, `s.seed + 1`, …) until `budget`, and average them.
/// `progress(frames, elapsed)` is called after each frame.
pub fn render_for(
    r: &mut Renderer,
    s: &FrameSettings,
    budget: Duration,
    progress: &mut dyn FnMut(u32, Duration),
) -> Result<Progressive> {
    let t0 = Instant::now();
    let mut sum: Vec<[f64; 4]> = vec![];
    let (mut frames, mut gpu_ms) = (0u32, Some(0.0));
    let mut previous = Duration::ZERO;
    let last = loop {
        let frame_s = frame_settings(s, frames);
        let f = r.render(&frame_s)?;
        // `realtime`'s raw estimate, each frame unbiased, not its denoised output, which is not.
        let estimate = f.raw.as_ref().unwrap_or(&f.radiance);
        sum.resize(estimate.len(), [0.0; 4]);
        for (a, p) in sum.iter_mut().zip(estimate) {
            for c in 0..4 {
                a[c] += p[c] as f64;
            }
        }
        frames += 1;
        gpu_ms = gpu_ms.zip(f.gpu_ms()).map(|(a, b)| a + b);
        let elapsed = t0.elapsed();
        progress(frames, elapsed);
        // The next frame costs about what the last one did. The first also built what the others
        // reuse (voxel grid, maps, CDF), so it is no guide: a second frame runs whenever time is left.
        let this_frame = elapsed - previous;
        previous = elapsed;
        let next_ends_late = if frames == 1 { elapsed >= budget } else { elapsed + this_frame > budget };
        if next_ends_late || !averages(s) {
            break f;
        }
    };
    let n = frames as f64;
    let radiance =
        sum.iter().map(|a| [(a[0] / n) as f32, (a[1] / n) as f32, (a[2] / n) as f32, (a[3] / n) as f32]).collect();
    Ok(Progressive { radiance, frames, wall: t0.elapsed(), last, gpu_ms })
}
