//! `bounce bench`: run time against error for every method and VPL count, or (with `--time-limits`) for
//! every method and wall-time budget: each budget's column is then an equal-time comparison, every
//! method averaging as many progressive frames (`--vpls`'s first value per frame; without --vpls ris takes
//! `render --time-limit`'s per-view budget, `commands::ris_frame_budget`) as fit in it.
//!
//! For each method × VPL count it renders `--repeats` full frames (runs 1..=K, each with its own seed far
//! from the others' frames: `run_seed`; the renderer's frame
//! cache is cleared before each) of the indirect component and records, per frame, the GPU time (sum
//! of pass timestamps) and each pass's time, the wall time of `Renderer::render`, and the error
//! against a reference image. The reference (`--reference`) is the path-traced ground truth or the
//! exhaustive VPL sum (`--method all`) on the same VPL set, rendered once and cached in the output
//! folder under a name keyed by the scene and the settings that change it. It writes:
//! - `bench.csv`: one row per frame (method, VPLs, seed, GPU ms, wall ms, RMSE, relMSE, mean ratio,
//!   p99 and p99.9 |error|, FLIP, then one column per pass);
//! - `bench.md`: the medians over repeats, shaped like the thesis's Tables 7.1 and 7.2 (methods in rows,
//!   VPL counts in columns, time and error per cell) and a per-pass time table (Fig. 7.19's breakdown);
//! - `time_vs_error.png`: median relMSE against median GPU time, log–log, one line per method (points at
//!   the VPL counts), so equal-time comparisons read off a vertical line.
//!
//! `realtime` is scored as `render` gives it: one frame denoised (unless `--denoise off`); at equal time
//! the mean of its raw frames (the denoised ones are not unbiased, and the denoiser does not run).
//!
//! With `--animate PATH --frames N` it measures temporal stability instead (per-frame relMSE and
//! flicker of a moving light's animation): see [`animation`].

mod animation;
pub mod suite;

use crate::cli::{BenchArgs, ReferenceArg};
use crate::error::{self, bad};
use crate::metrics::Metrics;
use crate::output::{self, RgbImage};
use anyhow::{Context, Result};
use bounce_device::Gpu;
use bounce_graph::frame::progressive::render_for;
use bounce_graph::frame::{Component, FrameOutput, FrameSettings, LightMap, Method, Renderer, Visibility, VplKernel};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;
use std::time::{Duration, Instant};

pub fn run(a: &BenchArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    output::check_folder(&a.out).map_err(bad)?;
    let scene = super::load_scene(&a.scene, err)?;
    let vpl_counts = a.vpl_counts();
    if a.methods.is_empty() || a.repeats == 0 {
        return Err(bad(anyhow::anyhow!("--methods and --repeats must not be empty or zero")));
    }
    if a.methods.contains(&Method::All) {
        return Err(bad(anyhow::anyhow!("`all` is the reference of `bounce bench`, not a method to sweep")));
    }
    let mut base = FrameSettings { component: Component::Indirect, ..a.frame.settings(a.width, a.height) };
    // At equal time the path tracer's frames are `render --time-limit`'s (a frame of the 256 default
    // samples overran a 0.5 s budget 2.7 times and was reported at 0.5 s).
    if a.frame.spp.is_none() && !a.time_limits.is_empty() {
        base.spp = crate::cli::TIME_LIMIT_SPP;
    }
    // Against `all` every run takes its VPL set (the VPLs' places in their texels: `vpl_seed`), so that the
    // error is the selection's alone; against the path-traced truth each seed draws its own.
    let base = match a.reference {
        ReferenceArg::All => FrameSettings { vpl_seed: Some(base.vpl_seed_or_derived()), ..base },
        ReferenceArg::Path => base,
    };
    let per_view = a.vpls.is_empty() && !a.time_limits.is_empty();
    super::warn_unread_by_methods(&a.frame.given, &base, &a.methods, per_view, err)?;
    let gpu = Gpu::new(&a.frame.gpu_options()).map_err(error::device)?;
    // Bad settings are one line at once, before the renderer builds its pipelines and uploads the scene;
    // the checks that need the renderer follow below.
    for &method in &a.methods {
        for &vpls in &vpl_counts {
            FrameSettings { method, vpls, ..base.clone() }.validate(&gpu)?;
        }
    }
    let mut renderer = Renderer::new(&gpu, &scene)?;
    if a.animate.is_some() || a.camera_path.is_some() {
        animation::run(a, &scene, &mut renderer, &base, out, err)?;
        return super::check_validation(&gpu, a.frame.validation);
    }
    let columns = match a.time_limits.is_empty() {
        true => vpl_counts.iter().map(|&vpls| Column { vpls, seconds: None }).collect(),
        false => a.time_limits.iter().map(|&t| Column { vpls: vpl_counts[0], seconds: Some(t) }).collect(),
    };
    // At equal time without --vpls, ris as `render --time-limit` runs it (as `suite` does).
    let ris_budget = (a.vpls.is_empty() && !a.time_limits.is_empty() && a.methods.contains(&Method::Ris))
        .then(|| ris_budget(&a.frame, &mut renderer, &base, &gpu, err))
        .transpose()?;
    let plan = BenchPlan {
        methods: a.methods.clone(),
        columns,
        repeats: a.repeats,
        base,
        reference: match a.reference {
            ReferenceArg::Path => Reference::Path { spp: a.reference_spp },
            ReferenceArg::All => Reference::All,
        },
        ris_budget,
        scene_fingerprint: scene.fingerprint(),
    };
    plan.check(&mut renderer)?;
    renderer.check(&plan.reference.settings(&plan.base))?;
    let samples = sweep(&mut renderer, &plan, &a.scene, &a.out, err)?;
    super::check_validation(&gpu, a.frame.validation)?;
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    write_outputs(&a.out, &plan, &samples, &gpu.name, &command)?;
    writeln!(out, "{}", std::fs::read_to_string(a.out.join("bench.md")).unwrap_or_default())?;
    writeln!(err, "wrote {}/bench.csv, bench.md, time_vs_error.png", a.out.display())?;
    Ok(())
}

/// One column of the sweep: a VPL count per frame, and for an equal-time sweep the wall-time budget.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Column {
    vpls: u32,
    seconds: Option<f64>,
}

impl Column {
    fn label(self) -> String {
        match self.seconds {
            Some(t) => format!("{t} s"),
            None => format!("{} VPLs", self.vpls),
        }
    }
}

/// One measured frame (or, in an equal-time sweep, one budget's progressive frames).
#[derive(Clone, Debug)]
struct Sample {
    method: Method,
    column: Column,
    /// VPLs a frame shaded per pixel (`FrameSettings::vpls_per_frame`): the column's, or ris's per-view
    /// budget's.
    vpls: u32,
    seed: u64,
    /// Frames averaged (1 without a time budget).
    frames: u32,
    gpu_ms: f64,
    wall_ms: f64,
    passes: BTreeMap<&'static str, f64>,
    metrics: Metrics,
}

/// What the errors are measured against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Reference {
    /// The path-traced one-bounce ground truth (`--method reference`) at `spp` samples per pixel.
    Path { spp: u32 },
    /// The exhaustive VPL sum on the same VPL set: isolates the selection error.
    All,
}

/// What `bench` sweeps, over which base settings, against which reference.
struct BenchPlan {
    methods: Vec<Method>,
    columns: Vec<Column>,
    repeats: u32,
    base: FrameSettings,
    reference: Reference,
    /// ris's settings in the equal-time columns where it takes `render --time-limit`'s per-view budget
    /// (without --vpls: [`ris_budget`]), in place of the base and the column's VPLs.
    ris_budget: Option<FrameSettings>,
    /// The scene's [`bounce_graph::scene::Scene::fingerprint`]: the cached reference is this scene's.
    scene_fingerprint: u64,
}

impl BenchPlan {
    /// What `method` renders in `column` (its runs' seeds aside).
    fn settings(&self, method: Method, column: Column) -> FrameSettings {
        match (&self.ris_budget, method, column.seconds) {
            (Some(ris), Method::Ris, Some(_)) => FrameSettings { component: Component::Indirect, ..ris.clone() },
            _ => FrameSettings { method, vpls: column.vpls, component: Component::Indirect, ..self.base.clone() },
        }
    }

    /// Every frame the sweep will render, checked before the first one renders.
    fn check(&self, r: &mut Renderer) -> Result<()> {
        for &method in &self.methods {
            for &c in &self.columns {
                r.check(&self.settings(method, c))?;
            }
        }
        Ok(())
    }
}

/// ris's settings over `base` under `render --time-limit`'s per-view budget for the renderer's view
/// (`super::ris_frame_budget`), said on `err`.
fn ris_budget(
    frame: &crate::cli::FrameArgs,
    r: &mut Renderer,
    base: &FrameSettings,
    gpu: &Gpu,
    err: &mut dyn Write,
) -> Result<FrameSettings> {
    let mut s = FrameSettings { method: Method::Ris, ..base.clone() };
    writeln!(err, "{}", super::ris_frame_budget(frame, r, &mut s)?)?;
    s.validate(gpu)?;
    Ok(s)
}

/// The median of the values present: NaN is a value not measured (a GPU time without timestamps) and is
/// left out; an infinite error (a frame with a non-finite pixel, `Metrics::of`) counts, as the largest.
fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| !x.is_nan());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The seed run `k` (1..=repeats) renders with. A progressive run's frame j takes the seed + j
/// (`progressive::frame_settings`), so runs seeded k and k + 1 would share all frames but one: the same
/// pixels' random numbers, the same presampled pool, the same texels drawn where the CDF is the same
/// (uniform's, whatever the VPL set), and four "seeds" were nearly one. Run k starts k · φ · 2⁶⁴ (φ the
/// golden ratio's fraction) instead, far from every other run's frames; its label stays k.
fn run_seed(k: u64) -> u64 {
    k.wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

/// The path-traced reference's seed, none of the runs' (`run_seed(1..=repeats)`): the reference method's progressive
/// frames continue their seed's sample sequence, so a run with the reference's seed would take its first
/// samples, and its error against it would read low.
const PATH_REFERENCE_SEED: u64 = 0xFFFF_FFF0;

impl Reference {
    /// The settings of the reference frame over the plan's base settings.
    fn settings(self, base: &FrameSettings) -> FrameSettings {
        let (method, spp, seed) = match self {
            Reference::Path { spp } => (Method::Reference, spp, PATH_REFERENCE_SEED),
            Reference::All => (Method::All, base.spp, base.seed),
        };
        FrameSettings { method, spp, seed, component: Component::Indirect, ..base.clone() }
    }

    /// What the plot's error axis says it is measured against.
    fn short(self) -> String {
        match self {
            Reference::Path { spp } => format!("the ground truth (path traced, {spp} spp)"),
            Reference::All => "`all` (selection error only)".to_string(),
        }
    }

    /// How the progress line and the cache file name it.
    fn kind(self) -> String {
        match self {
            Reference::Path { spp } => format!("path{spp}"),
            Reference::All => "all".to_string(),
        }
    }

    /// Its cache file's name: keyed by the scene and every setting the reference image depends on.
    /// The exhaustive sum also depends on the VPL map, the visibility and the VPL kernel; they appear in
    /// the name only when not the defaults of the runs that made the first caches (dprsm, voxel, point),
    /// so those caches keep their names and are never taken for another kernel.
    fn file_name(self, base: &FrameSettings, scene: &Path) -> String {
        let stem = scene.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let parent =
            scene.parent().and_then(|p| p.file_name()).map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let mut kind = self.kind();
        if self != Reference::All {
            kind += "-mis"; // caches of earlier runs, named without it, hold the cosine estimator
            kind += &format!("-seed{PATH_REFERENCE_SEED}"); // earlier caches used the runs' seed 1
        } else {
            match base.light_map {
                LightMap::Dprsm => {}
                LightMap::Rsm { fov_deg } => kind += &format!("-rsm{fov_deg}"),
                other => kind += &format!("-{}", other.name()),
            }
            if base.visibility != Visibility::Voxel {
                kind += &format!("-{:?}", base.visibility).to_lowercase();
            }
            if base.vpl_kernel != VplKernel::Point {
                kind += &format!("-{:?}", base.vpl_kernel).to_lowercase();
            }
            // The VPLs' places in their texels (earlier caches, without it, hold the texel centres' sum).
            kind += &format!("-vplseed{}", base.vpl_seed_or_derived());
        }
        let b = base;
        format!(
            "reference-{kind}-{parent}-{stem}-{}x{}-dprsm{}-vox{}-clamp{}.exr",
            b.width, b.height, b.dprsm_res, b.voxels, b.clamp
        )
    }
}

/// The cached reference for the plan's settings, rendering it when absent.
fn reference(r: &mut Renderer, plan: &BenchPlan, scene: &Path, dir: &Path, err: &mut dyn Write) -> Result<RgbImage> {
    let b = &plan.base;
    let name = plan.reference.file_name(b, scene);
    let path = dir.join(name);
    if let Some(img) = cached_truth(&path, (b.width, b.height), plan.scene_fingerprint, err)? {
        writeln!(err, "reference: {} (cached)", path.display())?;
        return Ok(img);
    }
    let s = plan.reference.settings(b);
    writeln!(err, "reference: rendering {} into {}", plan.reference.kind(), path.display())?;
    let bar = indicatif::ProgressBar::new(0);
    let f = r.render_with_progress(&s, &mut |done, total| {
        bar.set_length(total);
        bar.set_position(done);
    })?;
    bar.finish_and_clear();
    let img = RgbImage::from_rgba(f.width, f.height, &f.radiance);
    let meta =
        [("component", "indirect".into()), ("method", s.method.name().into()), fingerprint(plan.scene_fingerprint)];
    output::write_exr(&path, &img, &meta)?;
    Ok(img)
}

/// The metadata entry that ties a cached ground truth to its scene.
fn fingerprint(scene: u64) -> (&'static str, String) {
    ("scene_fingerprint", format!("{scene:016x}"))
}

/// The ground truth cached at `path`, if one of `size` is there and was made for the scene of
/// fingerprint `scene` (or before fingerprints were written: such a file has none and is taken as it
/// is). One made for another scene (the scene's files edited since) is said and left to be rendered anew.
fn cached_truth(path: &Path, size: (u32, u32), scene: u64, err: &mut dyn Write) -> Result<Option<RgbImage>> {
    if !path.exists() {
        return Ok(None);
    }
    let (img, meta) = output::read_exr(path)?;
    let (key, want) = fingerprint(scene);
    let made_for = meta.iter().find(|(k, _)| k.strip_prefix("bounce.") == Some(key)).map(|(_, v)| v.as_str());
    if made_for.is_some_and(|v| v != want) {
        writeln!(err, "reference: {} was made for another version of the scene", path.display())?;
        return Ok(None);
    }
    Ok(((img.width, img.height) == size).then_some(img))
}

/// Renders and measures every frame of the plan.
fn sweep(r: &mut Renderer, plan: &BenchPlan, scene: &Path, dir: &Path, err: &mut dyn Write) -> Result<Vec<Sample>> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let reference = reference(r, plan, scene, dir, err)?;
    let total = (plan.methods.len() * plan.columns.len()) as u64 * plan.repeats as u64;
    let bar = indicatif::ProgressBar::new(total);
    bar.set_style(
        indicatif::ProgressStyle::with_template("bench {bar:40} {pos}/{len} frames ({msg}), eta {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut samples = vec![];
    for &method in &plan.methods {
        // An untimed frame of the method first: the driver compiles there what it compiles at first use,
        // so no timed frame or budget pays for it (each still records its full frame: `measure` clears
        // the kept products).
        let first = plan.columns.first().copied().unwrap_or(Column { vpls: 1, seconds: None });
        r.warm_up(&plan.settings(method, first))?;
        for &column in &plan.columns {
            for seed in 1..=plan.repeats as u64 {
                bar.set_message(format!("{} {}", method.name(), column.label()));
                let s = FrameSettings { seed: run_seed(seed), ..plan.settings(method, column) };
                samples.push(Sample { seed, ..measure(r, &s, column, &reference)? });
                bar.inc(1);
            }
        }
    }
    bar.finish_and_clear();
    Ok(samples)
}

/// One frame of `s` (or its column's budget of progressive frames), timed and compared. Every method pays
/// for its full frame: the kept products are dropped first (a seed-independent CDF would otherwise be
/// reused); within a budget, the frames after the first reuse them, as `render --time-limit` does.
fn measure(r: &mut Renderer, s: &FrameSettings, column: Column, reference: &RgbImage) -> Result<Sample> {
    r.clear_frame_cache();
    r.prepare(s)?;
    let t0 = Instant::now();
    let (f, frames, gpu_ms) = match column.seconds {
        None => {
            let f = r.render(s)?;
            let gpu_ms = f.gpu_ms().unwrap_or(f64::NAN);
            (f, 1, gpu_ms)
        }
        Some(t) => {
            let p = render_for(r, s, Duration::from_secs_f64(t), &mut |_, _| {})?;
            let f = FrameOutput { radiance: p.radiance, ..p.last };
            // Per frame, as without a budget.
            (f, p.frames, p.gpu_ms.unwrap_or(f64::NAN) / p.frames as f64)
        }
    };
    let wall_ms = t0.elapsed().as_secs_f64() * 1e3;
    let img = RgbImage::from_rgba(f.width, f.height, &f.radiance);
    let mut passes = BTreeMap::new();
    for t in &f.timings {
        *passes.entry(t.name).or_insert(0.0) += t.ms.unwrap_or(f64::NAN);
    }
    let metrics = Metrics::with_flip(&img, reference);
    let vpls = s.vpls_per_frame();
    Ok(Sample { method: s.method, column, vpls, seed: s.seed, frames, gpu_ms, wall_ms, passes, metrics })
}

/// Write bench.csv, bench.md and time_vs_error.png (each through a temporary file).
fn write_outputs(dir: &Path, plan: &BenchPlan, samples: &[Sample], device: &str, command: &str) -> Result<()> {
    let pass_names: Vec<&str> = {
        let mut v: Vec<&str> = samples.iter().flat_map(|s| s.passes.keys().copied()).collect();
        v.sort();
        v.dedup();
        v
    };
    // The tables and the plot go in together (a plot that cannot be drawn leaves neither table).
    let md = error_table(plan, samples, device, command) + &pass_table(plan, samples, &pass_names);
    let tables = [
        output::stage_text(&dir.join("bench.csv"), &csv(samples, &pass_names))?,
        output::stage_text(&dir.join("bench.md"), &md)?,
    ];
    let series: Vec<(String, Vec<(f64, f64)>)> = plan
        .methods
        .iter()
        .map(|&m| {
            let points = plan.columns.iter().map(|&c| cell(samples, m, c)).map(|x| (x.time, x.rel_mse));
            (m.name().to_string(), points.collect())
        })
        .collect();
    let b = &plan.base;
    let equal_time = plan.columns.iter().any(|c| c.seconds.is_some());
    let axes = crate::plot::Axes {
        time: if equal_time { "wall time per budget (s, log)" } else { "GPU time per frame (ms, log)" },
        error: &format!("relMSE against {} (log)", plan.reference.short()),
    };
    crate::plot::time_vs_error(
        &dir.join("time_vs_error.png"),
        &series,
        &format!("{}×{}, {}", b.width, b.height, device),
        &axes,
    )?;
    tables.into_iter().try_for_each(output::Staged::commit)
}

/// One row per frame (per budget with `--time-limits`: `time_limit_s` and the `frames` averaged, `gpu_ms`
/// their mean, `wall_ms` their sum, the pass columns the last frame's), one column per pass.
fn csv(samples: &[Sample], pass_names: &[&str]) -> String {
    let mut csv = String::from(
        "method,vpls,seed,gpu_ms,wall_ms,rmse,rel_mse,mean_ratio,p99_abs,p999_abs,flip,time_limit_s,frames",
    );
    for p in pass_names {
        csv.push_str(&format!(",pass_{p}_ms"));
    }
    csv.push('\n');
    for s in samples {
        csv.push_str(&format!(
            "{},{},{},{:.4},{:.3},{:.6e},{:.6e},{:.6},{:.6e},{:.6e},{:.6},{},{}",
            s.method.name(),
            s.vpls,
            s.seed,
            s.gpu_ms,
            s.wall_ms,
            s.metrics.rmse,
            s.metrics.rel_mse,
            s.metrics.mean_ratio,
            s.metrics.p99_abs,
            s.metrics.p999_abs,
            s.metrics.flip.unwrap_or(f64::NAN),
            s.column.seconds.map(|t| t.to_string()).unwrap_or_default(),
            s.frames,
        ));
        // A pass the frame did not run (a product it kept) is empty, not 0 ms.
        for p in pass_names {
            csv.push_str(&s.passes.get(p).map_or(",".to_string(), |ms| format!(",{ms:.4}")));
        }
        csv.push('\n');
    }
    csv
}

/// The medians of one method in one column.
struct Cell {
    /// GPU ms per frame, or wall seconds for a time budget (the plot's x).
    time: f64,
    rel_mse: f64,
    /// The tail: p99.9 |error| (a firefly shows here before it moves the relMSE).
    tail: f64,
    flip: f64,
    frames: f64,
}

fn cell(samples: &[Sample], m: Method, c: Column) -> Cell {
    let sel: Vec<&Sample> = samples.iter().filter(|s| s.method == m && s.column == c).collect();
    let time = |s: &Sample| if c.seconds.is_some() { s.wall_ms / 1e3 } else { s.gpu_ms };
    Cell {
        time: median(sel.iter().map(|s| time(s)).collect()),
        rel_mse: median(sel.iter().map(|s| s.metrics.rel_mse).collect()),
        tail: median(sel.iter().map(|s| s.metrics.p999_abs).collect()),
        flip: median(sel.iter().map(|s| s.metrics.flip.unwrap_or(f64::NAN)).collect()),
        frames: median(sel.iter().map(|s| s.frames as f64).collect()),
    }
}

/// bench.md's heading and its first table: methods in rows, VPL counts in columns.
fn error_table(plan: &BenchPlan, samples: &[Sample], device: &str, command: &str) -> String {
    let b = &plan.base;
    let equal_time = plan.columns.iter().any(|c| c.seconds.is_some());
    let mut md = format!(
        "# bounce bench\n\n`{command}`\n\nDevice: {device}. {}×{}, indirect, DPRSM {}² per face, {} voxels, clamp {}, {:?} VPLs, {} repeat(s) \
         (runs 1..={}, each its own seed{}); medians over repeats. Reference: {}. {}\n\n## {}, p99.9 |error| and mean FLIP against the reference\n\n| method |",
        b.width,
        b.height,
        b.dprsm_res,
        b.voxels,
        b.clamp,
        b.vpl_kernel,
        plan.repeats,
        plan.repeats,
        if b.cdf_seed.is_some() { ", one VPL set and CDF between them (--cdf-seed): they differ in the pixels' numbers alone" } else { "" },
        match plan.reference {
            Reference::Path { spp } => format!("the path-traced ground truth (`--method reference`, {spp} spp)"),
            Reference::All => "the exhaustive VPL sum on the same VPL set (`--method all`)".to_string(),
        },
        if equal_time {
            "Each column is a wall-time budget: every method averages its progressive frames while half of the next fits (`wall s`: the time they took)."
        } else {
            "GPU time: the sum of the frame's pass timestamps."
        },
        if equal_time { "Frames averaged, relMSE" } else { "GPU time (ms), relMSE" },
    );
    // At equal time, each budget's frames and the wall time they took (the budget to within half a frame).
    let first = if equal_time { "frames | wall s" } else { "ms" };
    for c in &plan.columns {
        md.push_str(&format!(" {}: {first} | relMSE | p99.9 | FLIP |", c.label()));
    }
    md.push_str("\n|---|");
    for _ in &plan.columns {
        md.push_str(if equal_time { "---:|---:|---:|---:|---:|" } else { "---:|---:|---:|---:|" });
    }
    md.push('\n');
    for &m in &plan.methods {
        md.push_str(&format!("| {} |", m.name()));
        for &c in &plan.columns {
            let x = cell(samples, m, c);
            let first = if equal_time { format!("{:.1} | {:.2}", x.frames, x.time) } else { format!("{:.1}", x.time) };
            md.push_str(&format!(" {first} | {:.4} | {:.4} | {:.4} |", x.rel_mse, x.tail, x.flip));
        }
        md.push('\n');
    }
    md
}

/// bench.md's second table: each pass's median GPU time per method, at the largest VPL count.
fn pass_table(plan: &BenchPlan, samples: &[Sample], pass_names: &[&str]) -> String {
    let mut md = String::from(
        "\n## Per-pass GPU time (ms, median over runs; at equal time each run's last frame), in the last column\n\n| method |",
    );
    for p in pass_names {
        md.push_str(&format!(" {p} |"));
    }
    md.push_str("\n|---|");
    for _ in pass_names {
        md.push_str("---:|");
    }
    md.push('\n');
    let last = plan.columns.last().copied();
    for &m in &plan.methods {
        md.push_str(&format!("| {} |", m.name()));
        for p in pass_names {
            let v = median(
                samples
                    .iter()
                    .filter(|s| s.method == m && Some(s.column) == last)
                    .filter_map(|s| s.passes.get(p).copied())
                    .collect(),
            );
            md.push_str(&if v.is_finite() { format!(" {v:.2} |") } else { " – |".to_string() });
        }
        md.push('\n');
    }
    md
}
