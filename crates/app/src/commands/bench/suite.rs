//! `bounce suite`: every method at equal time on every scene of a suite, against each scene's ground
//! truth, per scene and in aggregate.
//!
//! The suite is a folder of scene folders (`scripts/make-scenes.py --suite DIR` writes one, a family's
//! scenes named `<family>-<k>`) or scene files. For each scene it runs `bench`'s equal-time sweep (one
//! budget, `--time-limit` seconds of progressive frames per method and seed, every method paying for its
//! whole frames; or, with `--equal-count`, one frame of `--vpls` VPLs a pixel, the thesis's comparison)
//! against the path-traced ground truth, cached in `OUT/<scene>/`. At equal time without `--vpls`, ris
//! runs as `render --time-limit` runs it, with the per-view budget of `commands::ris_frame_budget` (2
//! reservoirs of 64 or 128 candidates, 3 picks, the gathered source where visibility blocks most of the
//! view): 16 reservoirs of 32 candidates, what it ran before, read 1.29× the error over the generated
//! suite's 50 scenes, 3.6× on its dark rooms (BENCHMARKS.md, "On scenes of every kind"). Each run k of a
//! scene renders with `bench`'s `run_seed(k)`, far from the other runs' frames. It writes:
//! - `suite.csv`: one row per scene, method and seed (frames, wall ms, relMSE, mean ratio, p99.9 |error|);
//! - `suite.md`: per method over the scenes, the geometric mean and the worst case of its relMSE over
//!   `uniform`'s (each the median over seeds), how many scenes it loses to `uniform`, the largest bias of
//!   its image mean (the mean over seeds of mean/truth − 1) and spread (its standard deviation over
//!   seeds), and its tail (p99.9 |error|) over `uniform`'s; then the same geometric mean per family, and
//!   every scene's ratios;
//! - `suite.png`: each method's ratios over `uniform`, sorted, against the share of scenes.

use super::{median, ris_budget, sweep, BenchPlan, Column, Reference, Sample};
use crate::cli::SuiteArgs;
use crate::error::{self, bad};
use anyhow::{Context, Result};
use bounce_device::Gpu;
use bounce_graph::frame::{Component, FrameSettings, Method, Renderer};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// VPLs per pixel per frame without --vpls.
const SUITE_VPLS: u32 = 16;

/// One measured budget: a scene, a method, a seed.
struct Row {
    scene: String,
    family: String,
    sample: Sample,
}

pub fn run(a: &SuiteArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    crate::output::check_folder(&a.out).map_err(bad)?;
    let scenes = scene_files(&a.scenes).map_err(bad)?;
    if !a.methods.contains(&Method::Uniform) || a.methods.iter().all(|m| *m == Method::Uniform) {
        return Err(bad(anyhow::anyhow!(
            "--methods must include uniform and another method: every method is measured against uniform"
        )));
    }
    if a.methods.contains(&Method::All) {
        return Err(bad(anyhow::anyhow!("`all` is not a method to sweep (the ground truth is path traced)")));
    }
    if a.seeds == 0 {
        return Err(bad(anyhow::anyhow!("--seeds must be at least 1")));
    }
    let mut base = FrameSettings { component: Component::Indirect, ..a.frame.settings(a.width, a.height) };
    // At equal time the path tracer's frames are `render --time-limit`'s.
    if a.frame.spp.is_none() && !a.equal_count {
        base.spp = crate::cli::TIME_LIMIT_SPP;
    }
    let per_view = a.vpls.is_none() && !a.equal_count;
    super::super::warn_unread_by_methods(&a.frame.given, &base, &a.methods, per_view, err)?;
    let gpu = Gpu::new(&a.frame.gpu_options()).map_err(error::device)?;
    let vpls = a.vpls.unwrap_or(SUITE_VPLS);
    for &method in &a.methods {
        FrameSettings { method, vpls, ..base.clone() }.validate(&gpu)?;
    }
    let mut rows = vec![];
    for (k, path) in scenes.iter().enumerate() {
        let name = scene_name(path);
        writeln!(err, "scene {}/{}: {name}", k + 1, scenes.len())?;
        let scene = super::super::load_scene(path, err)?;
        let mut renderer = Renderer::new(&gpu, &scene)?;
        // ris as `render --time-limit` runs it: its budget chosen for this scene's view.
        let ris_budget = (a.vpls.is_none() && !a.equal_count && a.methods.contains(&Method::Ris))
            .then(|| ris_budget(&a.frame, &mut renderer, &base, &gpu, err))
            .transpose()?;
        let plan = BenchPlan {
            methods: a.methods.clone(),
            columns: vec![Column { vpls, seconds: (!a.equal_count).then_some(a.time_limit) }],
            repeats: a.seeds,
            base: base.clone(),
            reference: Reference::Path { spp: a.reference_spp },
            ris_budget,
            scene_fingerprint: scene.fingerprint(),
        };
        plan.check(&mut renderer)?;
        for sample in sweep(&mut renderer, &plan, path, &a.out.join(&name), err)? {
            rows.push(Row { scene: name.clone(), family: family(&name), sample });
        }
    }
    super::super::check_validation(&gpu, a.frame.validation)?;
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let md = markdown(a, &rows, &gpu.name, &command);
    // The tables and the plot go in together (a plot that cannot be drawn leaves neither table).
    let tables = [
        crate::output::stage_text(&a.out.join("suite.csv"), &csv(&rows))?,
        crate::output::stage_text(&a.out.join("suite.md"), &md)?,
    ];
    let curves: Vec<(String, Vec<f64>)> = a
        .methods
        .iter()
        .filter(|m| **m != Method::Uniform)
        .map(|m| (m.name().to_string(), ratios(&rows, *m).into_values().collect()))
        .collect();
    crate::plot::sorted_ratios(&a.out.join("suite.png"), &curves, &format!("{} scenes", scenes.len()))?;
    tables.into_iter().try_for_each(crate::output::Staged::commit)?;
    writeln!(out, "{md}")?;
    writeln!(err, "wrote {}/suite.csv, suite.md, suite.png", a.out.display())?;
    Ok(())
}

/// The scene files: each argument that is a file, a scene folder's `scene.toml`, and every `*/scene.toml` of
/// each other folder (sorted).
fn scene_files(args: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let mut files = vec![];
    for a in args {
        if a.join("scene.toml").is_file() {
            // One generated scene's own folder.
            files.push(a.join("scene.toml"));
        } else if a.is_dir() {
            let mut found: Vec<PathBuf> = std::fs::read_dir(a)
                .with_context(|| format!("reading {}", a.display()))?
                .filter_map(|e| e.ok().map(|e| e.path().join("scene.toml")))
                .filter(|p| p.is_file())
                .collect();
            found.sort();
            anyhow::ensure!(!found.is_empty(), "{} holds no */scene.toml", a.display());
            files.extend(found);
        } else {
            anyhow::ensure!(a.is_file(), "{}: no such scene file or folder", a.display());
            files.push(a.clone());
        }
    }
    anyhow::ensure!(!files.is_empty(), "no scene given");
    // Each scene's outputs and caches go to OUT/NAME: two scenes of one name would share them.
    for (i, f) in files.iter().enumerate() {
        if let Some(g) = files[..i].iter().find(|g| scene_name(g) == scene_name(f)) {
            anyhow::bail!(
                "{} and {} are both named {}: their outputs would share a folder",
                g.display(),
                f.display(),
                scene_name(f)
            );
        }
    }
    Ok(files)
}

/// A scene's name: its folder's, or the file's stem when the file is not a folder's `scene.toml`.
fn scene_name(path: &Path) -> String {
    let named = |p: Option<&std::ffi::OsStr>| p.map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    match path.file_name().and_then(|n| n.to_str()) {
        Some("scene.toml") => named(path.parent().and_then(|p| p.file_name())),
        _ => named(path.file_stem()),
    }
}

/// The family of a generated scene, `<family>-<k>`: the name without its number (else the name).
fn family(name: &str) -> String {
    match name.rsplit_once('-') {
        Some((f, k)) if k.parse::<u32>().is_ok() => f.to_string(),
        _ => name.to_string(),
    }
}

/// The median over seeds of `f` for each scene (in scene order) and `method`.
fn per_scene(rows: &[Row], method: Method, f: impl Fn(&Sample) -> f64) -> BTreeMap<String, f64> {
    let mut by: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.sample.method == method) {
        by.entry(r.scene.clone()).or_default().push(f(&r.sample));
    }
    by.into_iter().map(|(k, v)| (k, median(v))).collect()
}

/// Each scene's median relMSE of `method` over `uniform`'s.
fn ratios(rows: &[Row], method: Method) -> BTreeMap<String, f64> {
    let uniform = per_scene(rows, Method::Uniform, |s| s.metrics.rel_mse);
    per_scene(rows, method, |s| s.metrics.rel_mse)
        .into_iter()
        .filter_map(|(k, v)| uniform.get(&k).and_then(|u| ratio(v, *u)).map(|r| (k, r)))
        .collect()
}

/// An error over `uniform`'s. None where both are exact (a view that no one-bounce light reaches, whose
/// truth and estimates are all 0): such a scene says nothing of the methods and is left out of the
/// aggregates (0 / 0 would rank as every method's worst, 1 would pull each geometric mean toward 1).
/// Any error over an exact `uniform` is infinitely worse.
fn ratio(v: f64, uniform: f64) -> Option<f64> {
    match (v == 0.0, uniform == 0.0) {
        (true, true) => None,
        (false, true) => Some(f64::INFINITY),
        _ => Some(v / uniform),
    }
}

/// The scenes no method has a ratio on: every error there exactly 0 (see [`ratio`]).
fn dark_scenes<'s>(scenes: &'s [String], ratios: &BTreeMap<&str, BTreeMap<String, f64>>) -> Vec<&'s str> {
    scenes.iter().filter(|s| ratios.values().all(|r| !r.contains_key(*s))).map(|s| s.as_str()).collect()
}

/// (mean, standard deviation) over seeds of the image mean over the truth's, for each scene.
fn means(rows: &[Row], method: Method) -> BTreeMap<String, (f64, f64)> {
    let mut by: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.sample.method == method) {
        by.entry(r.scene.clone()).or_default().push(r.sample.metrics.mean_ratio);
    }
    by.into_iter()
        .map(|(k, v)| {
            let n = v.len() as f64;
            let m = v.iter().sum::<f64>() / n;
            let var = if v.len() > 1 { v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0) } else { 0.0 };
            (k, (m, var.sqrt()))
        })
        .collect()
}

/// The geometric mean of the ratios present (NaN: undefined, left out). An infinite ratio (a method
/// with error where `uniform` has none, or with a non-finite image) makes it infinite, and a 0 (exact
/// where `uniform` is not) makes it 0: the headline never hides the scene that rules it.
fn geomean(v: impl IntoIterator<Item = f64>) -> f64 {
    let v: Vec<f64> = v.into_iter().filter(|x| !x.is_nan()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    // An infinite ratio rules over a 0 (whose logarithm would cancel it into NaN).
    if v.contains(&f64::INFINITY) {
        return f64::INFINITY;
    }
    (v.iter().map(|x| x.ln()).sum::<f64>() / v.len() as f64).exp()
}

/// The (scene, value) with the largest value.
fn worst(m: &BTreeMap<String, f64>) -> (String, f64) {
    // A NaN (a scene whose ratio is undefined) counts as the worst.
    let key = |v: f64| if v.is_nan() { f64::INFINITY } else { v };
    m.iter()
        .max_by(|a, b| key(*a.1).total_cmp(&key(*b.1)))
        .map_or((String::from("–"), f64::NAN), |(s, v)| (s.clone(), *v))
}

/// suite.md's title and the line that says how it was measured.
fn header(a: &SuiteArgs, scenes: usize, device: &str, command: &str) -> String {
    let vpls = a.vpls.unwrap_or(SUITE_VPLS);
    let budget = match (a.equal_count, a.vpls) {
        (true, _) => format!("one frame of {vpls} VPLs a pixel per method and seed (equal count)"),
        (false, Some(_)) => format!("{} s per method and seed (equal time), {vpls} VPLs a frame", a.time_limit),
        (false, None) => format!(
            "{} s per method and seed (equal time), {vpls} VPLs a frame (ris: its per-view budget, as `render \
             --time-limit`)",
            a.time_limit
        ),
    };
    format!(
        "# Suite: {scenes} scenes, {} seeds, {budget}, {}×{}\n\n`{command}` on {device}; relMSE against each \
         scene's path-traced ground truth ({} spp), the median over seeds; ratios are over `uniform`'s on \
         the same scene.{}\n\n",
        a.seeds,
        a.width,
        a.height,
        a.reference_spp,
        if a.frame.cdf_seed.is_some() {
            " The seeds share one VPL set and CDF (--cdf-seed): their spread is the pixels' numbers' alone."
        } else {
            ""
        }
    )
}

/// The largest of `v` (0 if empty), or NaN if any is: a scene whose spread is undefined (a black truth's
/// infinite mean ratio) shows as such, not as the others' largest.
fn largest(v: impl IntoIterator<Item = f64>) -> f64 {
    v.into_iter().fold(0.0, |a: f64, x| if x.is_nan() || a.is_nan() { f64::NAN } else { a.max(x) })
}

/// The time `m` took over uniform's (geomean over scenes of the medians over seeds): at equal time the
/// wall time of its frames (the budget to within half a frame), at equal count one frame's GPU time.
fn time_ratio(a: &SuiteArgs, rows: &[Row], m: Method) -> f64 {
    let time = |s: &Sample| if a.equal_count { s.gpu_ms } else { s.wall_ms };
    let uniform = per_scene(rows, Method::Uniform, time);
    geomean(per_scene(rows, m, time).iter().filter_map(|(k, v)| uniform.get(k).map(|u| v / u)))
}

fn markdown(a: &SuiteArgs, rows: &[Row], device: &str, command: &str) -> String {
    let scenes: Vec<String> = {
        let mut s: Vec<String> = rows.iter().map(|r| r.scene.clone()).collect();
        s.dedup();
        s
    };
    let mut md = header(a, scenes.len(), device, command);
    let time_name = if a.equal_count { "GPU ms / uniform" } else { "wall time / uniform" };
    md += &format!("| method | geomean relMSE / uniform | worst (scene) | scenes above uniform | largest |mean − truth| over seeds (scene) | largest spread of the mean over seeds | median p99.9 |error| / uniform | {time_name} |\n");
    md += "|---|---:|---|---:|---|---:|---:|---:|\n";
    let uniform_tail = per_scene(rows, Method::Uniform, |s| s.metrics.p999_abs);
    // Each method's per-scene ratios, computed once for the three tables.
    let all: BTreeMap<&str, BTreeMap<String, f64>> = a.methods.iter().map(|m| (m.name(), ratios(rows, *m))).collect();
    for &m in &a.methods {
        let r = &all[m.name()];
        let (ws, wv) = worst(r);
        let above = r.values().filter(|v| **v > 1.0).count();
        let mm = means(rows, m);
        let bias: BTreeMap<String, f64> = mm.iter().map(|(k, (m, _))| (k.clone(), (m - 1.0).abs())).collect();
        let (bs, bv) = worst(&bias);
        let spread = largest(mm.values().map(|(_, s)| *s));
        let tail = per_scene(rows, m, |s| s.metrics.p999_abs);
        let tail_ratio =
            median(tail.iter().filter_map(|(k, v)| uniform_tail.get(k).and_then(|u| ratio(*v, *u))).collect());
        let time_ratio = time_ratio(a, rows, m);
        // One seed has no spread to show.
        let spread = if a.seeds > 1 { format!("{:.2} %", 100.0 * spread) } else { "–".into() };
        md += &format!(
            "| {} | {:.3} | {:.3} ({ws}) | {above} of {} | {:.2} % ({bs}) | {spread} | {:.3} | {time_ratio:.2} |\n",
            m.name(),
            geomean(r.values().copied()),
            wv,
            r.len(),
            100.0 * bv,
            tail_ratio
        );
    }
    let dark = dark_scenes(&scenes, &all);
    if !dark.is_empty() {
        md += &format!(
            "\nLeft out of the ratios: {} (every method's error exactly 0: no one-bounce light in view).\n",
            dark.join(", ")
        );
    }
    let families: Vec<String> = {
        let mut f: Vec<String> = rows.iter().map(|r| r.family.clone()).collect();
        f.sort();
        f.dedup();
        f
    };
    md += "\n## Per family: geomean relMSE / uniform\n\n| family | ";
    md += &a.methods.iter().map(|m| m.name()).collect::<Vec<_>>().join(" | ");
    md += " |\n|---|";
    md += &"---:|".repeat(a.methods.len());
    md += "\n";
    for f in &families {
        md += &format!("| {f} |");
        for &m in &a.methods {
            let r = &all[m.name()];
            let g = geomean(r.iter().filter(|(k, _)| family(k) == *f).map(|(_, v)| *v));
            md += &format!(" {g:.3} |");
        }
        md += "\n";
    }
    md += "\n## Per scene: relMSE / uniform (uniform's own relMSE in its column)\n\n| scene | ";
    md += &a.methods.iter().map(|m| m.name()).collect::<Vec<_>>().join(" | ");
    md += " |\n|---|";
    md += &"---:|".repeat(a.methods.len());
    md += "\n";
    let uniform = per_scene(rows, Method::Uniform, |s| s.metrics.rel_mse);
    for s in &scenes {
        md += &format!("| {s} |");
        for &m in &a.methods {
            let v = if m == Method::Uniform { uniform.get(s).copied() } else { all[m.name()].get(s).copied() };
            md += &format!(" {} |", v.map_or("–".into(), |v| format!("{v:.3}")));
        }
        md += "\n";
    }
    md
}

fn csv(rows: &[Row]) -> String {
    let mut csv = String::from("scene,family,method,seed,frames,wall_ms,rel_mse,mean_ratio,p999_abs\n");
    for r in rows {
        let s = &r.sample;
        csv += &format!(
            "{},{},{},{},{},{:.3},{:.6e},{:.6},{:.6e}\n",
            r.scene,
            r.family,
            s.method.name(),
            s.seed,
            s.frames,
            s.wall_ms,
            s.metrics.rel_mse,
            s.metrics.mean_ratio,
            s.metrics.p999_abs
        );
    }
    csv
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn families_and_means() {
        assert_eq!(family("light-corner-3"), "light-corner");
        assert_eq!(family("cornell-box"), "cornell-box");
        assert!((geomean([2.0, 8.0]) - 4.0).abs() < 1e-12);
        assert!(geomean([]).is_nan());
        // An infinitely worse scene rules the headline; an undefined one is left out.
        assert_eq!(geomean([2.0, f64::INFINITY]), f64::INFINITY);
        assert_eq!(geomean([2.0, 0.0]), 0.0);
        assert_eq!(geomean([0.0, f64::INFINITY]), f64::INFINITY);
        assert!((geomean([2.0, f64::NAN, 8.0]) - 4.0).abs() < 1e-12);
        let m: BTreeMap<String, f64> = [("a".to_string(), 1.0), ("b".to_string(), 3.0)].into();
        assert_eq!(worst(&m), ("b".to_string(), 3.0));
        assert_eq!(scene_name(Path::new("x/boxes-1/scene.toml")), "boxes-1");
        assert_eq!(scene_name(Path::new("x/room.toml")), "room");
        // A dark view: every method exact, left out; an error where `uniform` is exact is the worst.
        assert_eq!(ratio(0.0, 0.0), None);
        assert_eq!(ratio(0.5, 0.0), Some(f64::INFINITY));
        assert_eq!(ratio(0.0, 0.5), Some(0.0));
        assert_eq!(ratio(0.25, 0.5), Some(0.5));
    }

    /// A scene whose truth and estimates are all 0 is left out of every method's ratios and named as dark;
    /// a lit scene's ratio is the relMSEs' quotient; a scene where only `uniform` is exact stays in (worst).
    #[test]
    fn a_dark_scene_is_left_out_of_the_ratios() {
        let row = |scene: &str, method: Method, test: f32, truth: f32| Row {
            scene: scene.into(),
            family: family(scene),
            sample: Sample {
                method,
                column: Column { vpls: 1, seconds: None },
                vpls: 1,
                seed: 1,
                frames: 1,
                gpu_ms: 0.0,
                wall_ms: 0.0,
                passes: BTreeMap::new(),
                metrics: crate::metrics::Metrics::of(&[[test; 3]], &[[truth; 3]]),
            },
        };
        let rows = [
            row("dark", Method::Uniform, 0.0, 0.0),
            row("dark", Method::Gbg, 0.0, 0.0),
            row("lit", Method::Uniform, 1.2, 1.0),
            row("lit", Method::Gbg, 1.1, 1.0),
            row("odd", Method::Uniform, 0.0, 0.0),
            row("odd", Method::Gbg, 0.5, 0.0),
        ];
        let gbg = ratios(&rows, Method::Gbg);
        assert_eq!(gbg.keys().collect::<Vec<_>>(), ["lit", "odd"]);
        assert!((gbg["lit"] - 0.25).abs() < 1e-9, "{gbg:?}");
        assert_eq!(gbg["odd"], f64::INFINITY);
        let all: BTreeMap<&str, BTreeMap<String, f64>> =
            [("uniform", ratios(&rows, Method::Uniform)), ("gbg", gbg)].into();
        let scenes = ["dark", "lit", "odd"].map(String::from);
        assert_eq!(dark_scenes(&scenes, &all), ["dark"]);
    }
}
