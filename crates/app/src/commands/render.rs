//! `bounce render`: one frame of a scene (or, with `--time-limit`, the mean of as many progressive frames
//! as fit in the time) to a linear float32 EXR (with the settings as metadata), an
//! optional tone-mapped PNG, and with `--timings` the per-pass GPU time table on stdout. Warnings and
//! the `wrote …` line go to stderr.

use crate::cli::{RenderArgs, RENDER_FALLBACK_SIZE};
use crate::error::{self, bad};
use crate::output::{self, RgbImage};
use anyhow::{Context, Result};
use bounce_device::Gpu;
use bounce_graph::frame::progressive::{render_for, Progressive};
use bounce_graph::frame::{Component, FrameOutput, FrameSettings, Renderer};
use bounce_graph::passes::psm::{Psm, MAX_PSM_BYTES};
use std::io::Write;
use std::time::{Duration, Instant};

pub fn run(a: &RenderArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    let scene = super::load_scene(&a.scene, err)?;
    let settings = a.picture.settings(&a.frame, &scene, RENDER_FALLBACK_SIZE);
    let gpu = Gpu::new(&a.frame.gpu_options()).map_err(error::device)?;
    settings.validate(&gpu)?;
    let mut renderer = Renderer::new(&gpu, &scene)?;
    renderer.check(&settings)?;
    if a.time_limit.is_some() && !bounce_graph::frame::progressive::averages(&settings) {
        writeln!(
            err,
            "note: this frame is the same for every seed (`all` or direct light): one frame, whatever the time limit"
        )?;
    }
    let t0 = Instant::now();
    let (frame, frames) = match a.time_limit {
        None => (renderer.render(&settings)?, None),
        Some(t) => {
            let p = progressive(&mut renderer, &settings, t)?;
            let last = FrameOutput { radiance: p.radiance, ..p.last };
            (last, Some((p.frames, p.gpu_ms)))
        }
    };
    let wall = t0.elapsed().as_secs_f64();
    for w in &frame.warnings {
        writeln!(err, "warning: {w}")?;
    }
    if let Some(se) = frame.stderr {
        writeln!(
            err,
            "reference: {} spp, standard error of the mean {se:.3e} (RMS over pixels and channels)",
            settings.spp
        )?;
    }
    super::check_validation(&gpu, a.frame.validation)?;
    let img = RgbImage::from_rgba(frame.width, frame.height, &frame.radiance);
    let bad_px = img.non_finite_count();
    if bad_px > 0 {
        writeln!(err, "warning: {bad_px} pixel(s) are not finite")?;
    }
    let mut meta = metadata(a, &settings, &gpu, &frame, bad_px);
    if let (Some((n, gpu_ms)), Some(t)) = (frames, a.time_limit) {
        meta.push(("time_limit_s", t.to_string()));
        meta.push(("frames", n.to_string()));
        meta.push(("wall_s", format!("{wall:.3}")));
        meta.push(("gpu_ms_total", gpu_ms.map(|m| format!("{m:.3}")).unwrap_or_else(|| "n/a".into())));
        writeln!(err, "{n} frame(s) in {wall:.2} s (time limit {t} s)")?;
    }
    output::write_exr(&a.out, &img, &meta)?;
    if let Some(p) = &a.png {
        output::write_png(p, &img)?;
    }
    if a.timings {
        timings(out, &settings, &frame, wall, &gpu.name)?;
    }
    writeln!(
        err,
        "wrote {}{}",
        a.out.display(),
        a.png.as_ref().map(|p| format!(" and {}", p.display())).unwrap_or_default()
    )
    .context("writing to stderr")?;
    Ok(())
}

/// Frames of `s` for `seconds` of wall time, averaged, with a progress bar on stderr.
fn progressive(r: &mut Renderer, s: &FrameSettings, seconds: f64) -> Result<Progressive> {
    if !(seconds.is_finite() && seconds > 0.0 && seconds <= 1e6) {
        return Err(bad(anyhow::anyhow!("--time-limit must be a positive number of seconds (got {seconds})")));
    }
    let bar = indicatif::ProgressBar::new((seconds * 10.0).ceil() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("render {bar:40} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let p = render_for(r, s, Duration::from_secs_f64(seconds), &mut |frames, elapsed| {
        bar.set_position((elapsed.as_secs_f64() * 10.0) as u64);
        bar.set_message(format!("{frames} frame(s), {:.1}/{seconds} s", elapsed.as_secs_f64()));
    })?;
    bar.finish_and_clear();
    Ok(p)
}

/// The EXR's `bounce.*` attributes: what was rendered, how, and on what.
fn metadata(
    a: &RenderArgs,
    s: &FrameSettings,
    gpu: &Gpu,
    frame: &FrameOutput,
    non_finite: usize,
) -> Vec<(&'static str, String)> {
    vec![
        ("scene", a.scene.display().to_string()),
        ("component", s.component.name().to_string()),
        ("method", if s.component == Component::Direct { "none".into() } else { s.method.name().to_string() }),
        ("vpls", s.vpls.to_string()),
        ("voxels", s.voxels.to_string()),
        ("clamp", s.clamp.to_string()),
        ("visibility", format!("{:?}", s.visibility).to_lowercase()),
        ("spp", s.spp.to_string()),
        ("seed", s.seed.to_string()),
        ("device", gpu.name.clone()),
        ("gpu_ms", frame.gpu_ms().map(|m| format!("{m:.3}")).unwrap_or_else(|| "n/a".into())),
        ("dprsm_res", s.dprsm_res.to_string()),
        ("light_map", s.light_map.name().to_string()),
        ("shadow_res", s.shadow_res.to_string()),
        ("non_finite_pixels", non_finite.to_string()),
    ]
}

/// The `--timings` table on `out`: each pass's GPU time, the passes a cache skipped, the total, the
/// PSM memory where the frame has per-VPL shadow maps, and the wall time.
fn timings(out: &mut dyn Write, s: &FrameSettings, frame: &FrameOutput, wall: f64, device: &str) -> Result<()> {
    let ms = |m: Option<f64>| m.map(|m| format!("{m:10.3}")).unwrap_or_else(|| format!("{:>10}", "n/a"));
    writeln!(out, "{:<16} {:>10}", "pass", "GPU ms")?;
    for t in &frame.timings {
        writeln!(out, "{:<16} {}", t.name, ms(t.ms))?;
    }
    for skipped in &frame.skipped {
        writeln!(out, "{skipped:<16} {:>10}", "skipped")?;
    }
    writeln!(out, "{:<16} {}", "total", ms(frame.gpu_ms()))?;
    if s.visibility.shared_set() && s.component != Component::Direct {
        let bytes = Psm::bytes(s.vpls, s.psm_res);
        writeln!(
            out,
            "psm maps: {} × {}² depth = {:.1} MiB (bound {} MiB)",
            s.vpls,
            s.psm_res,
            bytes as f64 / 1048576.0,
            MAX_PSM_BYTES >> 20
        )?;
    }
    writeln!(out, "wall {wall:.3} s on {device}")?;
    Ok(())
}
