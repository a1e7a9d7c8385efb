//! `bounce bench SCENE --animate PATH [--camera-path CAMERA] --frames N`: temporal stability. The lights
//! move along `PATH` (`crate::light_path`: `orbit[:PERIOD]` or a keyframe file; `none`: they stay put)
//! and the camera along `CAMERA` (`crate::camera_path`), either or both; each method renders the N frames at a
//! fixed budget per frame (`--vpls`'s first value), once per `--temporal` mode (`fresh`: frame k takes
//! seed 1 + k, its CDF too; `coherent`: every frame seed 1, so each pixel's stratified points and the
//! importance's gather points stay put while the light moves). Every frame is compared with its own
//! ground truth (`--method reference` at `--reference-spp`, the lights at that frame, rendered once and
//! cached in the output folder under a name keyed by the scene, the settings and the path).
//!
//! Per method and mode it reports the mean over frames of relMSE (mean of (t − r)² / (r² + 0.01)) and of
//! the flicker, `metrics::flicker`: mean of ((t_k − t_{k−1}) − (r_k − r_{k−1}))² / (r_k² + 0.01) over
//! frames 1..N−1, the relMSE of the frame-to-frame differences, so noise that is the same in every
//! frame does not count and noise that changes does. It writes `bench.csv` (one row per frame, then the means per method and mode),
//! `bench.md` (the means, and the GPU time per frame) and `flicker.png` (both figures over the frames).
//! The frames after a method's first keep what the light does not change (voxels, G-buffer), as an
//! interactive session would; the GPU time is the mean over those frames.

use super::{BenchArgs, Reference};
use crate::camera_path::CameraPath;
use crate::cli::Temporal;
use crate::error::bad;
use crate::light_path::LightPath;
use crate::metrics::{flicker, Metrics};
use crate::output::{self, RgbImage};
use anyhow::{Context, Result};
use bounce_graph::frame::{Component, FrameSettings, Method, Renderer};
use bounce_graph::scene::Scene;
use std::io::Write;
use std::path::Path;

/// The scripted motion of an animated sweep: the lights' path (`--animate`; `none`: they stay put) and
/// the camera's (`--camera-path`), with what names them in the table and keys the ground truth's cache.
struct Motion {
    lights: Option<LightPath>,
    camera: Option<CameraPath>,
    label: String,
    /// The paths' own texts (a file's contents) key the cache, so an edited keyframe file renders anew.
    key: u64,
}

impl Motion {
    fn parse(a: &BenchArgs, scene: &Scene) -> Result<Motion> {
        let lights_arg = a.animate.as_deref().filter(|p| *p != "none");
        let lights = lights_arg.map(|p| LightPath::parse(p, scene)).transpose()?;
        let camera = a.camera_path.as_deref().map(|p| CameraPath::parse(p, scene)).transpose()?;
        let text = |p: Option<&str>| p.map(|p| std::fs::read_to_string(p).unwrap_or_default()).unwrap_or_default();
        let light_key = (a.animate.as_deref().unwrap_or("none"), text(lights_arg));
        // Without a camera path the key is the lights' alone, as caches made before camera paths were.
        let key = match a.camera_path.as_deref() {
            None => bounce_graph::graph::fingerprint(&light_key),
            Some(c) => bounce_graph::graph::fingerprint(&(light_key, c, text(Some(c)))),
        };
        let label = match (lights_arg, a.camera_path.as_deref()) {
            (Some(l), None) => l.to_string(),
            (None, Some(c)) => format!("camera {c}"),
            (Some(l), Some(c)) => format!("{l}, camera {c}"),
            (None, None) => "no motion".to_string(),
        };
        Ok(Motion { lights, camera, label, key })
    }

    /// Lights and camera where they are at frame `k`.
    fn apply(&self, r: &mut Renderer, k: u32) {
        if let Some(l) = &self.lights {
            l.apply(r, k);
        }
        if let Some(c) = &self.camera {
            c.apply(r, k);
        }
    }
}

/// One rendered frame of one method and mode.
struct FrameSample {
    method: Method,
    temporal: Temporal,
    frame: u32,
    gpu_ms: f64,
    /// The raw estimate's share of it (the denoiser's passes aside).
    raw_ms: f64,
    /// Shadow rays per pixel the frame traced (NaN where the method does not count them).
    rays: f64,
    /// Of the raw estimate.
    rel_mse: f64,
    /// None for the first frame (no previous frame).
    flicker: Option<f64>,
    /// Of the denoised output, where the method has one (`realtime`).
    denoised: Option<(f64, Option<f64>)>,
    /// The image's mean over the ground truth's: the raw estimate's, the denoised output's (a filter
    /// that drops a bright feature's light shows here, where relMSE barely does).
    mean_ratio: f64,
    denoised_mean_ratio: Option<f64>,
    /// The ground truth's image mean, and the raw and denoised images': the mean row's ratio is Σ image
    /// means over Σ truth means (a frame whose truth is nearly dark has a ratio of noise over nothing,
    /// and one whose truth is black an infinite one, which must not rule the run).
    truth_mean: f64,
    image_mean: f64,
    denoised_image_mean: Option<f64>,
}

/// The animated sweep: settings checked, references rendered or read, every method × mode rendered.
pub(super) fn run(
    a: &BenchArgs,
    scene: &Scene,
    r: &mut Renderer,
    base: &FrameSettings,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<()> {
    let motion = Motion::parse(a, scene)?;
    if a.frames < 2 || a.temporal.is_empty() || !a.time_limits.is_empty() {
        return Err(bad(anyhow::anyhow!(
            "--animate needs --frames ≥ 2 and at least one --temporal mode, and no --time-limits"
        )));
    }
    if a.reference != crate::cli::ReferenceArg::Path {
        return Err(bad(anyhow::anyhow!("--animate measures against the path-traced ground truth (--reference path)")));
    }
    let (vpls, reference) = (a.vpl_counts()[0], Reference::Path { spp: a.reference_spp });
    for &method in &a.methods {
        r.check(&FrameSettings { method, vpls, ..base.clone() })?;
    }
    r.check(&reference.settings(base))?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let truth = references(r, &motion, (reference, scene.fingerprint()), base, &a.scene, &a.out, a.frames, err)?;
    let mut samples = vec![];
    let bar = indicatif::ProgressBar::new((a.methods.len() * a.temporal.len()) as u64 * a.frames as u64);
    for &method in &a.methods {
        // Frame 0's time (bench.csv) is then its work, not the driver's first-use compilation.
        r.warm_up(&FrameSettings { method, vpls, ..base.clone() })?;
        for &temporal in &a.temporal {
            r.clear_frame_cache();
            // The raw estimate's frames and (realtime) the denoised output's.
            let mut previous: Option<(RgbImage, Option<RgbImage>)> = None;
            for k in 0..a.frames {
                motion.apply(r, k);
                let seed = temporal.seed(1, k, 0);
                // One VPL set for the run, as `render --frames` has it.
                let (cdf_seed, vpl_seed) = (Some(seed), Some(base.vpl_seed_or_derived()));
                let f = r.render(&FrameSettings { method, vpls, seed, cdf_seed, vpl_seed, ..base.clone() })?;
                let shown = RgbImage::from_rgba(f.width, f.height, &f.radiance);
                let (img, denoised) = match &f.raw {
                    Some(raw) => (RgbImage::from_rgba(f.width, f.height, raw), Some(shown)),
                    None => (shown, None),
                };
                let (t, t_prev) = (&truth[k as usize].pixels, k.checked_sub(1).map(|j| &truth[j as usize].pixels));
                let score = |now: &RgbImage, before: Option<&RgbImage>| {
                    let flick = before.zip(t_prev).map(|(p, tp)| flicker(&now.pixels, &p.pixels, t, tp));
                    let m = Metrics::of(&now.pixels, t);
                    (m.rel_mse, flick, m.mean_ratio)
                };
                let (rel_mse, flick, mean_ratio) = score(&img, previous.as_ref().map(|p| &p.0));
                let denoised_score = denoised.as_ref().map(|d| score(d, previous.as_ref().and_then(|p| p.1.as_ref())));
                samples.push(FrameSample {
                    method,
                    temporal,
                    frame: k,
                    gpu_ms: f.gpu_ms().unwrap_or(f64::NAN),
                    raw_ms: f.raw_gpu_ms().unwrap_or(f64::NAN),
                    rays: f.rays_per_pixel.unwrap_or(f64::NAN),
                    rel_mse,
                    flicker: flick,
                    denoised: denoised_score.map(|(r, f, _)| (r, f)),
                    mean_ratio,
                    denoised_mean_ratio: denoised_score.map(|d| d.2),
                    truth_mean: image_mean(t),
                    image_mean: image_mean(&img.pixels),
                    denoised_image_mean: denoised.as_ref().map(|d| image_mean(&d.pixels)),
                });
                previous = Some((img, denoised));
                bar.inc(1);
            }
        }
    }
    bar.finish_and_clear();
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let md = table(a, base, &samples, &r.gpu.name, &command, &motion.label);
    write_outputs(a, &samples, &md, base, &r.gpu.name)?;
    writeln!(out, "{md}")?;
    writeln!(err, "wrote {}/bench.csv, bench.md, flicker.png", a.out.display())?;
    Ok(())
}

/// The mean over pixels and channels.
fn image_mean(p: &[[f32; 3]]) -> f64 {
    p.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / (3 * p.len().max(1)) as f64
}

/// The ground truth of every frame, from the cache or rendered (lights at that frame, seed 1).
#[allow(clippy::too_many_arguments)]
fn references(
    r: &mut Renderer,
    motion: &Motion,
    (reference, fingerprint): (Reference, u64),
    base: &FrameSettings,
    scene: &Path,
    dir: &Path,
    frames: u32,
    err: &mut dyn Write,
) -> Result<Vec<RgbImage>> {
    let key = motion.key;
    let stem = reference.file_name(base, scene);
    let stem = stem.trim_end_matches(".exr");
    let s = reference.settings(base);
    let mut truth = vec![];
    for k in 0..frames {
        let file = dir.join(format!("{stem}-path{key:016x}-frame{k:04}.exr"));
        if let Ok(Some(img)) = super::cached_truth(&file, (base.width, base.height), fingerprint, err) {
            truth.push(img);
            continue;
        }
        writeln!(err, "reference: frame {k} into {}", file.display())?;
        motion.apply(r, k);
        let f = r.render(&s)?;
        let img = RgbImage::from_rgba(f.width, f.height, &f.radiance);
        let meta = [
            ("component", "indirect".into()),
            ("method", "reference".into()),
            ("frame", k.to_string()),
            super::fingerprint(fingerprint),
        ];
        output::write_exr(&file, &img, &meta)?;
        truth.push(img);
    }
    Ok(truth)
}

/// One row per method, mode and frame, then per method and mode a row with frame `mean`: the means
/// bench.md reports (GPU ms and flicker over frames 1.., relMSE over all frames).
fn csv(samples: &[FrameSample]) -> String {
    let mut csv = String::from(
        "method,temporal,frame,gpu_ms,rays_per_pixel,rel_mse,flicker,denoised_rel_mse,denoised_flicker,raw_gpu_ms,\
         mean_ratio,denoised_mean_ratio\n",
    );
    let mut modes: Vec<(&str, &str)> = vec![];
    for s in samples {
        let mode = (s.method.name(), s.temporal.name());
        if !modes.contains(&mode) {
            modes.push(mode);
        }
    }
    let e = |v: Option<f64>| v.map(|f| format!("{f:.6e}")).unwrap_or_default();
    for s in samples {
        let (dr, df) = s.denoised.map_or((None, None), |(r, f)| (Some(r), f));
        csv.push_str(&format!(
            "{},{},{},{:.4},{:.4},{:.6e},{},{},{},{:.4},{:.6},{}\n",
            s.method.name(),
            s.temporal.name(),
            s.frame,
            s.gpu_ms,
            s.rays,
            s.rel_mse,
            e(s.flicker),
            e(dr),
            e(df),
            s.raw_ms,
            s.mean_ratio,
            s.denoised_mean_ratio.map(|v| format!("{v:.6}")).unwrap_or_default(),
        ));
    }
    for (m, t) in modes {
        let of = || samples.iter().filter(move |s| s.method.name() == m && s.temporal.name() == t);
        let later = || of().filter(|s| s.frame > 0);
        // Absent (no denoised frames) is an empty field; an infinite error is printed as such.
        let present = |x: f64| (!x.is_nan()).then_some(x);
        csv.push_str(&format!(
            "{m},{t},mean,{:.4},{:.4},{:.6e},{:.6e},{},{},{:.4},{:.6},{}\n",
            mean(later().map(|s| s.gpu_ms)),
            mean(of().map(|s| s.rays)),
            mean(of().map(|s| s.rel_mse)),
            mean(later().filter_map(|s| s.flicker)),
            e(present(mean(of().filter_map(|s| s.denoised.map(|d| d.0))))),
            e(present(mean(later().filter_map(|s| s.denoised.and_then(|d| d.1))))),
            mean(later().map(|s| s.raw_ms)),
            weighted_ratio(of().map(|s| (Some(s.image_mean), s.truth_mean))),
            present(weighted_ratio(of().map(|s| (s.denoised_image_mean, s.truth_mean))))
                .map(|v| format!("{v:.6}"))
                .unwrap_or_default(),
        ));
    }
    csv
}

/// The frames' image means (where present) over their truths': Σ image means / Σ truth means (NaN where
/// no frame has one; a frame whose image mean is not finite makes it so).
fn weighted_ratio(v: impl Iterator<Item = (Option<f64>, f64)>) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (image, truth) in v {
        if let Some(m) = image {
            num += m;
            den += truth;
        }
    }
    if den > 0.0 {
        num / den
    } else {
        f64::NAN
    }
}

/// The mean of the values present: NaN is a value not measured (a GPU time without timestamps) and is
/// left out; an infinite error (a frame with a non-finite pixel, `Metrics::of`) makes the mean infinite.
fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = v.filter(|x| !x.is_nan()).collect();
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// The samples of one method and mode.
fn of(samples: &[FrameSample], m: Method, t: Temporal) -> impl Iterator<Item = &FrameSample> {
    samples.iter().filter(move |s| s.method == m && s.temporal == t)
}

fn table(a: &BenchArgs, b: &FrameSettings, samples: &[FrameSample], device: &str, command: &str, arg: &str) -> String {
    let mut md = format!(
        "# bounce bench --animate\n\n`{command}`\n\nDevice: {device}. {}×{}, indirect, DPRSM {}² per face, {} voxels, \
         {} VPLs per pixel per frame, {} frames of `{arg}`. Ground truth: `--method reference` at {} spp per frame. \
         relMSE: mean over every frame (frame 0 too, which reuses no history yet: the viewer shows it); flicker: mean over frames 1..{} of the relMSE of the frame-to-frame difference \
         against the ground truth's; GPU ms: mean over frames 1..{} (the light side and the gather; voxels and \
         G-buffer kept; frame 0 also builds them), raw: less the denoiser's passes (what the raw estimate costs, `--denoise off`); \
         rays: shadow rays per pixel per frame, counted (– where a method does not count them). \
         relMSE and flicker are of the raw estimate; `denoised`: of the displayed output where a method has a \
         denoiser (realtime); mean ratio: the image's mean over the ground truth's (raw, denoised; over the frames, \
         Σ image means / Σ truth means). Medians too: one firefly that lasts a few frames moves a mean a lot.\n\n\
         | method | temporal | GPU ms / frame | raw GPU ms | rays / px | relMSE | flicker | denoised relMSE | denoised flicker | \
         mean ratio | denoised mean ratio | median relMSE | median flicker |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        b.width,
        b.height,
        b.dprsm_res,
        b.voxels,
        a.vpl_counts()[0],
        a.frames,
        a.reference_spp,
        a.frames - 1,
        a.frames - 1,
    );
    for &m in &a.methods {
        for &t in &a.temporal {
            let later = || of(samples, m, t).filter(|s| s.frame > 0);
            let num = |x: f64, digits: usize| if x.is_nan() { "–".into() } else { format!("{x:.digits$}") };
            md.push_str(&format!(
                "| {} | {} | {:.2} | {:.2} | {} | {:.4} | {:.4} | {} | {} | {:.3} | {} | {:.4} | {:.4} |\n",
                m.name(),
                t.name(),
                mean(later().map(|s| s.gpu_ms)),
                mean(later().map(|s| s.raw_ms)),
                num(mean(of(samples, m, t).map(|s| s.rays)), 2),
                mean(of(samples, m, t).map(|s| s.rel_mse)),
                mean(later().filter_map(|s| s.flicker)),
                num(mean(of(samples, m, t).filter_map(|s| s.denoised.map(|d| d.0))), 4),
                num(mean(later().filter_map(|s| s.denoised.and_then(|d| d.1))), 4),
                weighted_ratio(of(samples, m, t).map(|s| (Some(s.image_mean), s.truth_mean))),
                num(weighted_ratio(of(samples, m, t).map(|s| (s.denoised_image_mean, s.truth_mean))), 3),
                super::median(of(samples, m, t).map(|s| s.rel_mse).collect()),
                super::median(later().filter_map(|s| s.flicker).collect()),
            ));
        }
    }
    md
}

/// bench.csv, bench.md and flicker.png, together: a plot that cannot be drawn leaves neither table.
fn write_outputs(a: &BenchArgs, samples: &[FrameSample], md: &str, base: &FrameSettings, device: &str) -> Result<()> {
    let tables = [
        output::stage_text(&a.out.join("bench.csv"), &csv(samples))?,
        output::stage_text(&a.out.join("bench.md"), md)?,
    ];
    plot(&a.out.join("flicker.png"), a, samples, base, device)?;
    tables.into_iter().try_for_each(output::Staged::commit)
}

fn plot(file: &Path, a: &BenchArgs, samples: &[FrameSample], b: &FrameSettings, device: &str) -> Result<()> {
    let mut rel = vec![];
    let mut flick = vec![];
    for &m in &a.methods {
        for &t in &a.temporal {
            let name = format!("{} ({})", m.name(), t.name());
            rel.push((name.clone(), of(samples, m, t).map(|s| (s.frame as f64, s.rel_mse)).collect()));
            flick.push((name.clone(), of(samples, m, t).filter_map(|s| Some((s.frame as f64, s.flicker?))).collect()));
            // The displayed output beside the raw estimate, where the method denoises.
            if of(samples, m, t).any(|s| s.denoised.is_some()) {
                let d = format!("{name}, denoised");
                rel.push((
                    d.clone(),
                    of(samples, m, t).filter_map(|s| Some((s.frame as f64, s.denoised?.0))).collect(),
                ));
                flick.push((d, of(samples, m, t).filter_map(|s| Some((s.frame as f64, s.denoised?.1?))).collect()));
            }
        }
    }
    let panels = [
        crate::plot::Panel { y: "relMSE against the ground truth (log)", series: &rel },
        crate::plot::Panel { y: "flicker (log)", series: &flick },
    ];
    let component = if b.component == Component::Indirect { "indirect" } else { "combined" };
    let title = format!("Per-frame error and flicker ({}×{}, {component}, {device})", b.width, b.height);
    crate::plot::over_frames(file, &panels, &title)
}
