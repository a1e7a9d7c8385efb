//! `bounce render`: one frame of a scene (or, with `--time-limit`, the mean of as many progressive frames
//! as fit in the time) to a linear float32 EXR (with the settings as metadata), an
//! optional tone-mapped PNG, and with `--timings` the per-pass GPU time table on stdout. Warnings and
//! the `wrote …` line go to stderr.

use crate::camera_path::CameraPath;
use crate::cli::{RenderArgs, RENDER_FALLBACK_SIZE};
use crate::error::{self, bad};
use crate::light_path::LightPath;
use crate::output::{self, RgbImage};
use anyhow::{Context, Result};
use bounce_device::Gpu;
use bounce_graph::frame::progressive::{render_for, Progressive};
use bounce_graph::frame::{Component, FrameOutput, FrameSettings, Method, Renderer};
use bounce_graph::passes::psm::{Psm, MAX_PSM_BYTES};
use std::io::Write;
use std::time::{Duration, Instant};

pub fn run(a: &RenderArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    check_animation_flags(a)?;
    check_destinations(a)?;
    let scene = super::load_scene(&a.scene, err)?;
    let path = a.animation.light_path.as_deref().map(|p| LightPath::parse(p, &scene)).transpose()?;
    let camera = a.animation.camera_path.as_deref().map(|p| CameraPath::parse(p, &scene)).transpose()?;
    let mut settings = a.picture.settings(&a.frame, &scene, RENDER_FALLBACK_SIZE);
    if a.time_limit.is_some() {
        time_limit_method(a, &mut settings, err)?;
    }
    let started = Instant::now();
    let gpu = Gpu::new(&a.frame.gpu_options()).map_err(error::device)?;
    let device_s = started.elapsed().as_secs_f64();
    // Before the renderer uploads the scene and builds its BVH (seconds on a large scene).
    settings.validate(&gpu)?;
    let mut renderer = Renderer::new(&gpu, &scene)?;
    let renderer_s = started.elapsed().as_secs_f64() - device_s;
    if a.time_limit.is_some() && a.picture.vpls.is_none() && settings.method == Method::Ris {
        writeln!(err, "{}", super::ris_frame_budget(&a.frame, &mut renderer, &mut settings)?)?;
        settings.validate(&gpu)?;
    }
    // On the settings the frames run (ris's budget may have chosen its source).
    super::warn_ignored_flags(&a.frame.given, &settings, a.time_limit.is_some(), err)?;
    renderer.check(&settings)?;
    if let Some(frames) = a.frames {
        animate(a, &mut renderer, &settings, (path.as_ref(), camera.as_ref()), frames, (out, err))?;
        return super::check_validation(&gpu, a.frame.validation);
    }
    note_single_frame(a, &settings, err)?;
    // The frame's GPU time (the EXR's `gpu_ms`, --timings) and --time-limit's budget are then the frames'
    // own work, not the driver's first-use compilation; that compilation is paid here or in the frame.
    let warm = Instant::now();
    renderer.warm_up(&settings)?;
    renderer.prepare(&settings)?;
    let startup = Startup { device_s, renderer_s, warm_up_s: warm.elapsed().as_secs_f64() };
    let t0 = Instant::now();
    let (frame, frames) = match a.time_limit {
        None => (one_frame(&mut renderer, &settings)?, None),
        Some(t) => {
            let p = progressive(&mut renderer, &settings, t)?;
            // The reference's standard error is the last frame's, not the mean's: not reported.
            let last = FrameOutput { radiance: p.radiance, stderr: None, ..p.last };
            let sets = p.sets.last().map_or(0, |j| j + 1);
            (last, Some((p.frames, sets, p.gpu_ms)))
        }
    };
    let wall = t0.elapsed().as_secs_f64();
    super::check_validation(&gpu, a.frame.validation)?;
    let img = RgbImage::from_rgba(frame.width, frame.height, &frame.radiance);
    let bad_px = report_frame(&frame, &img, &settings, err)?;
    let mut meta = metadata(a, &settings, &gpu.name, &frame, bad_px);
    if let (Some((n, sets, gpu_ms)), Some(t)) = (frames, a.time_limit) {
        meta.push(("time_limit_s", format!("{t:?}")));
        meta.push(("frames", n.to_string()));
        meta.push(("vpl_sets", sets.to_string()));
        meta.push(("wall_s", format!("{wall:.3}")));
        meta.push(("gpu_ms_total", gpu_ms.map(|m| format!("{m:.3}")).unwrap_or_else(|| "n/a".into())));
        let sets = if settings.method == Method::Reference { String::new() } else { format!(", {sets} VPL set(s)") };
        writeln!(err, "{n} frame(s) in {wall:.2} s (time limit {} s){sets}", crate::plot::tick(t))?;
    }
    output::write_exr_and_png(&a.out, a.png.as_deref(), &img, &meta)?;
    if a.timings {
        timings(out, &settings, &frame, (wall, a.time_limit.is_some()), &gpu.name)?;
        startup.report(out)?;
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

/// Where the images go, checked before the work that makes them (an animation writes to --out-dir).
fn check_destinations(a: &RenderArgs) -> Result<()> {
    if a.frames.is_none() {
        if a.png.as_deref().is_some_and(|p| output::same_destination(p, &a.out)) {
            return Err(bad(anyhow::anyhow!("--out and --png name the same file ({})", a.out.display())));
        }
        output::check_destination(&a.out, "exr").map_err(bad)?;
        if let Some(png) = &a.png {
            output::check_destination(png, "png").map_err(bad)?;
        }
    }
    if let Some(dir) = &a.out_dir {
        output::check_folder(dir).map_err(bad)?;
        // Each frame's files (a folder or a special file in one's place is found now, not at frame k).
        if dir.is_dir() {
            for k in 0..a.frames.unwrap_or(0) {
                let stem = frame_stem(dir, k);
                output::check_destination(&stem.with_extension("exr"), "exr").map_err(bad)?;
                output::check_destination(&stem.with_extension("png"), "png").map_err(bad)?;
            }
        }
    }
    Ok(())
}

/// The animation flags go together: --frames with --out-dir (or --timings alone: the frames timed
/// back to back, as a viewer renders them, and not written), --light-path only with --frames, and an
/// animation is not a time-limited mean.
fn check_animation_flags(a: &RenderArgs) -> Result<()> {
    let fail = |m: &str| Err(bad(anyhow::anyhow!("{m}")));
    match (a.frames, &a.out_dir) {
        (Some(0), _) => fail("--frames must be at least 1"),
        (Some(_), _) if a.time_limit.is_some() => fail("--time-limit and --frames do not go together"),
        (Some(_), None) if !a.timings => fail("--frames needs --out-dir (or --timings, to time the frames unwritten)"),
        (None, Some(_)) => fail("--out-dir needs --frames"),
        (None, None) if a.animation.moves() => fail("--light-path and --camera-path need --frames and --out-dir"),
        _ => Ok(()),
    }
}

/// One frame; `all`'s tiles and the path tracer's sample batches report their progress (a bar on a
/// terminal).
fn one_frame(renderer: &mut Renderer, settings: &FrameSettings) -> Result<FrameOutput> {
    let bar = indicatif::ProgressBar::new(0);
    let f = renderer.render_with_progress(settings, &mut |done, total| {
        bar.set_length(total);
        bar.set_position(done);
    })?;
    bar.finish_and_clear();
    Ok(f)
}

/// What the user should know of the frame, on `err`: its warnings, the reference's own error, pixels that
/// are not finite (returned: their count), and an image that is black.
fn report_frame(frame: &FrameOutput, img: &RgbImage, s: &FrameSettings, err: &mut dyn Write) -> Result<usize> {
    for w in &frame.warnings {
        writeln!(err, "warning: {w}")?;
    }
    if let Some(se) = frame.stderr {
        writeln!(err, "reference: {} spp, standard error of the mean {se:.3e} (RMS over pixels and channels)", s.spp)?;
    }
    let bad_px = img.non_finite_count();
    if bad_px > 0 {
        writeln!(err, "warning: {bad_px} pixel(s) are not finite")?;
    }
    if img.pixels.iter().all(|p| p.iter().all(|&c| c == 0.0)) {
        writeln!(
            err,
            "note: the image is black: no light reaches what the camera sees (is a light outside the geometry, or behind a wall?)"
        )?;
    }
    Ok(bad_px)
}

/// Where frame k's EXR and PNG go (the extension added).
fn frame_stem(dir: &std::path::Path, k: u32) -> std::path::PathBuf {
    dir.join(format!("frame_{k:04}"))
}

/// Frame k of the animation: the lights at `path`'s frame k, the camera at `camera`'s, the seed of the
/// seed schedule; an EXR and a PNG each.
/// `render --frames N --out-dir DIR`: N frames along the light and camera paths, each an EXR and a PNG;
/// with `--timings` the frames' per-pass GPU times on `out` ([`frame_timings`]). Without --out-dir
/// nothing is written: between frames the GPU then idles only for the readback, not for the encoding,
/// so its clocks stay up (written frames left an H200 idle long enough to halve them).
fn animate(
    a: &RenderArgs,
    r: &mut Renderer,
    s: &FrameSettings,
    (path, camera): (Option<&LightPath>, Option<&CameraPath>),
    frames: u32,
    (out, err): (&mut dyn Write, &mut dyn Write),
) -> Result<()> {
    let dir = a.out_dir.as_ref();
    let mut timed = vec![];
    // The frames' files, in place once every frame is written: a run that fails leaves none of its frames.
    let mut staged = vec![];
    if let Some(dir) = dir {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        output::remove_stale_temporaries(dir, "frame_")?;
    }
    let gpu_name = r.gpu.name.clone();
    // So that frame 0's `gpu_ms` is its work, as every later frame's is.
    r.warm_up(s)?;
    // One VPL set for the run (`FrameSettings::vpl_seed`): the maps change only where a light moves.
    let vpl_seed = s.vpl_seed_or_derived();
    for k in 0..frames {
        if let Some(p) = path {
            p.apply(r, k);
        }
        if let Some(c) = camera {
            c.apply(r, k);
        }
        // Every frame of a moving light or camera is a change; a static one accumulates nothing here either.
        let since_change = if a.animation.moves() { 0 } else { k };
        let fs = FrameSettings {
            seed: a.animation.temporal().seed(s.seed, k, since_change),
            vpl_seed: Some(vpl_seed),
            ..s.clone()
        };
        let f = r.render(&fs)?;
        if let Some(dir) = dir {
            let img = RgbImage::from_rgba(f.width, f.height, &f.radiance);
            let mut meta = metadata(a, &fs, &gpu_name, &f, img.non_finite_count());
            meta.push(("frame", k.to_string()));
            meta.push(("temporal", a.animation.temporal().name().to_string()));
            meta.push(("light_path", a.animation.light_path.clone().unwrap_or_else(|| "none".into())));
            meta.push(("camera_path", a.animation.camera_path.clone().unwrap_or_else(|| "none".into())));
            let stem = frame_stem(dir, k);
            staged.extend(output::stage_image(
                &stem.with_extension("exr"),
                Some(&stem.with_extension("png")),
                &img,
                &meta,
            )?);
        }
        timed.push(FrameOutput { radiance: vec![], raw: None, ..f });
    }
    staged.into_iter().try_for_each(output::Staged::commit)?;
    match dir {
        Some(dir) => writeln!(err, "wrote {frames} frame(s) to {} (frame_0000.exr/.png …)", dir.display())?,
        None => writeln!(err, "rendered {frames} frame(s), not written (no --out-dir)")?,
    }
    if a.timings {
        frame_timings(out, &timed, &gpu_name)?;
    }
    Ok(())
}

/// `render --frames N --timings`: per pass, the median over frames 1..N of its GPU ms in a frame (a pass
/// recorded several times, as the denoiser's à-trous iterations, summed), the frames' median total, and
/// the shadow rays per pixel where the method counts them. Frame 0 builds what the others keep, so it is
/// left out (with one frame, it is all there is).
fn frame_timings(out: &mut dyn Write, frames: &[FrameOutput], device: &str) -> Result<()> {
    let later = if frames.len() > 1 { &frames[1..] } else { frames };
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied()
    };
    let mut names: Vec<&str> = vec![];
    for t in later.iter().flat_map(|f| &f.timings) {
        if !names.contains(&t.name) {
            names.push(t.name);
        }
    }
    let cell = |m: Option<f64>| m.map(|m| format!("{m:10.3}")).unwrap_or_else(|| format!("{:>10}", "n/a"));
    writeln!(out, "{:<16} {:>10}   (median over frames 1..{} of {device})", "pass", "GPU ms", frames.len())?;
    for name in names {
        // `+ 0.0`: an empty f64 sum is −0.0, which printed as "-0.000" for a pass absent from most frames.
        let per_frame =
            later.iter().map(|f| f.timings.iter().filter(|t| t.name == name).filter_map(|t| t.ms).sum::<f64>() + 0.0);
        writeln!(out, "{name:<16} {}", cell(median(per_frame.collect())))?;
    }
    writeln!(out, "{:<16} {}", "total", cell(median(later.iter().filter_map(|f| f.gpu_ms()).collect())))?;
    if let Some(rays) = median(later.iter().filter_map(|f| f.rays_per_pixel).collect()) {
        // The bounce's rays, counted by the shade; the direct light's (one per pixel and light) are not.
        writeln!(out, "shadow rays per pixel {rays:.3} (the bounce's; the direct light adds one per light)")?;
    }
    Ok(())
}

/// `--time-limit`'s defaults: without --method the path tracer ([`crate::cli::TIME_LIMIT_METHOD`], said
/// on `err`), unless --vpls asks for VPLs (then ris, the VPL default); and the reference's frames of
/// [`crate::cli::TIME_LIMIT_SPP`] samples unless --spp is given.
fn time_limit_method(a: &RenderArgs, settings: &mut FrameSettings, err: &mut dyn Write) -> Result<()> {
    if a.picture.method.is_none() && a.picture.vpls.is_none() && settings.component != Component::Direct {
        settings.method = crate::cli::TIME_LIMIT_METHOD;
        writeln!(
            err,
            "method: {} (no --method or --vpls: the lowest error at equal time of every method measured, BENCHMARKS.md)",
            settings.method.name()
        )?;
    } else if a.picture.method.is_none() && a.picture.vpls.is_some() {
        // --vpls asks for VPLs: the VPL default, said as the path tracer's choice is.
        writeln!(err, "method: {} (--vpls without --method: the VPL methods' default)", settings.method.name())?;
    }
    if settings.method == Method::Reference && a.frame.spp.is_none() {
        settings.spp = crate::cli::TIME_LIMIT_SPP;
    }
    Ok(())
}

/// Frames of `s` for `seconds` of wall time, averaged, with a progress bar on stderr.
fn progressive(r: &mut Renderer, s: &FrameSettings, seconds: f64) -> Result<Progressive> {
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
    device: &str,
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
        ("vpl_kernel", format!("{:?}", s.vpl_kernel).to_lowercase()),
        ("visibility", format!("{:?}", s.visibility).to_lowercase()),
        ("spp", s.spp.to_string()),
        ("seed", s.seed.to_string()),
        ("device", device.to_string()),
        ("gpu_ms", frame.gpu_ms().map(|m| format!("{m:.3}")).unwrap_or_else(|| "n/a".into())),
        ("dprsm_res", s.dprsm_res.to_string()),
        ("light_map", s.light_map.name().to_string()),
        ("non_finite_pixels", non_finite.to_string()),
    ]
}

/// Under `--time-limit`, says when every frame would be the same (one frame is rendered).
fn note_single_frame(a: &RenderArgs, settings: &FrameSettings, err: &mut dyn Write) -> Result<()> {
    if a.time_limit.is_some() && !bounce_graph::frame::progressive::averages(settings) {
        writeln!(
            err,
            "note: this frame is the same for every seed (`all` or direct light): one frame, whatever the time limit"
        )?;
    }
    Ok(())
}

/// Where the time before the first frame went (`--timings`): the device (instance, device, allocator),
/// the renderer (scene upload, BVH, the pipelines every frame runs) and the warm-up (the
/// pipelines the frame needs, built on first use, and an untimed small frame).
struct Startup {
    device_s: f64,
    renderer_s: f64,
    warm_up_s: f64,
}

impl Startup {
    fn report(&self, out: &mut dyn Write) -> Result<()> {
        let total = self.device_s + self.renderer_s + self.warm_up_s;
        writeln!(
            out,
            "startup {total:.3} s: device {:.3} s, renderer {:.3} s, pipelines and warm-up frame {:.3} s",
            self.device_s, self.renderer_s, self.warm_up_s
        )?;
        Ok(())
    }
}

/// The `--timings` table on `out`: each pass's GPU time, the passes a cache skipped, the total, the
/// PSM memory where the frame has per-VPL shadow maps, and the wall time.
fn timings(
    out: &mut dyn Write,
    s: &FrameSettings,
    frame: &FrameOutput,
    (wall, progressive): (f64, bool),
    device: &str,
) -> Result<()> {
    let ms = |m: Option<f64>| m.map(|m| format!("{m:10.3}")).unwrap_or_else(|| format!("{:>10}", "n/a"));
    // Under --time-limit the table is the last progressive frame's (the wall time is the whole budget's).
    let which = if progressive { "   (the last frame's)" } else { "" };
    writeln!(out, "{:<16} {:>10}{which}", "pass", "GPU ms")?;
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
