//! Is `--method realtime`'s raw estimate unbiased under motion, on any scene? Renders a moving run
//! (the scene's `camera-path.toml` or a camera orbit, or `--light-path orbit`) of F frames S times with seeds 1..=S (each run a new
//! renderer, so each its own reuse chain), on one VPL set, and compares the per-pixel mean over the runs
//! with `all` (the exhaustive VPL sum on the same set) frame by frame. Unbiased, the mean's error against
//! `all` is its variance alone: relMSE(mean) ≈ relMSE(one run) / S; a bias shows as relMSE(mean) staying
//! above that, and in the image mean's ratio. The indirect component, raw (`--denoise off`); errors are
//! Σ (m − a)² / Σ a² (no 0.01 floor: the test is of the mean, not of a picture).
//!
//! A light next to a wall makes the VPLs' 1/d² heavy-tailed: a few runs' rare large values then decide
//! a pixel's mean, and the mean's error reads above one run's / S without a bias (most means miss the
//! rare values). `clamp` (a fraction of the scene's diagonal, as the tests' 1 %) bounds 1/d² in both
//! `all` and realtime: the same integral, no tail.
//!
//!     cargo run --release -p bounce-lab --bin realtime-bias SCENE camera|light [runs] [frames] [size] [clamp]

use bounce::camera_path::CameraPath;
use bounce::light_path::LightPath;
use bounce_device::{Gpu, GpuOptions};
use bounce_graph::frame::{Component, FrameSettings, Method, Renderer};
use bounce_graph::scene::Scene;

/// The moving run: the camera's path or the lights', applied at frame k.
struct Motion {
    camera: Option<CameraPath>,
    lights: Option<LightPath>,
    label: String,
}

impl Motion {
    fn place(&self, r: &mut Renderer, k: u32) {
        if let Some(c) = &self.camera {
            c.apply(r, k);
        }
        if let Some(l) = &self.lights {
            l.apply(r, k);
        }
    }
}

/// Per frame: the runs' per-pixel sums, the sum of one run's squared errors, each run's image sum.
struct Sums {
    pixels: Vec<Vec<[f64; 3]>>,
    single: Vec<f64>,
    images: Vec<Vec<f64>>,
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: realtime-bias SCENE camera|light [runs] [frames] [size] [clamp]";
    let (path, motion) = match (args.first(), args.get(1)) {
        (Some(p), Some(m)) if m == "camera" || m == "light" => (p.clone(), m.clone()),
        _ => anyhow::bail!(usage),
    };
    let num = |i: usize, d: u32| args.get(i).map(|a| a.parse::<u32>()).transpose().map(|v| v.unwrap_or(d));
    let (runs, frames, size) = (num(2, 32)?, num(3, 8)?, num(4, 32)?);
    let clamp: f32 = args.get(5).map(|a| a.parse()).transpose()?.unwrap_or(0.0);
    let scene = Scene::load(std::path::Path::new(&path))?;
    let gpu = Gpu::new(&GpuOptions::default())?;
    let motion = motion_of(&path, &motion, &scene)?;
    let base = FrameSettings {
        width: size,
        height: size,
        component: Component::Indirect,
        dprsm_res: 64,
        vpl_seed: Some(1),
        cdf_seed: Some(1),
        denoise: false,
        clamp,
        ..FrameSettings::default()
    };
    // `all` per frame: what every run's frame k must average to.
    let mut r = Renderer::new(&gpu, &scene)?;
    let mut truth = vec![];
    for k in 0..frames {
        motion.place(&mut r, k);
        truth.push(r.render(&FrameSettings { method: Method::All, ..base.clone() })?.radiance);
    }
    let sums = run_all(&gpu, &scene, &motion, &base, &truth, runs)?;
    println!(
        "{} — {path}, {}, {size}², {frames} frames, {runs} runs (seeds 1..={runs}), indirect, raw, 64² maps, clamp {clamp}",
        gpu.name, motion.label
    );
    print_table(&sums, &truth, runs);
    Ok(())
}

/// The scene's own camera path where it has one (an orbit leaves a room such as the two rooms'), else an
/// orbit; or the lights' orbit.
fn motion_of(path: &str, motion: &str, scene: &Scene) -> anyhow::Result<Motion> {
    let own = std::path::Path::new(path).with_file_name("camera-path.toml");
    let walk = if own.is_file() { own.display().to_string() } else { "orbit".to_string() };
    Ok(match motion {
        "camera" => Motion {
            camera: Some(CameraPath::parse(&walk, scene)?),
            lights: None,
            label: format!("camera path {walk}"),
        },
        _ => Motion { camera: None, lights: Some(LightPath::parse("orbit", scene)?), label: "light orbit".into() },
    })
}

/// Runs 1..=runs (seeds), each with a renderer of its own (its own reuse chain), summed per frame.
fn run_all(
    gpu: &Gpu,
    scene: &Scene,
    motion: &Motion,
    base: &FrameSettings,
    truth: &[Vec<[f32; 4]>],
    runs: u32,
) -> anyhow::Result<Sums> {
    let (frames, pixels) = (truth.len(), truth[0].len());
    let mut sums =
        Sums { pixels: vec![vec![[0.0; 3]; pixels]; frames], single: vec![0.0; frames], images: vec![vec![]; frames] };
    for run in 1..=runs as u64 {
        let mut r = Renderer::new(gpu, scene)?;
        for (k, t) in truth.iter().enumerate() {
            motion.place(&mut r, k as u32);
            let f = r.render(&FrameSettings { method: Method::Realtime, seed: run, ..base.clone() })?;
            sums.images[k].push(f.radiance.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>());
            for (q, px) in f.radiance.iter().enumerate() {
                for c in 0..3 {
                    sums.pixels[k][q][c] += px[c] as f64;
                    sums.single[k] += (px[c] as f64 - t[q][c] as f64).powi(2);
                }
            }
        }
    }
    Ok(sums)
}

/// One row a frame and one for all of them: the image mean's ratio (± its standard error over runs), the
/// runs' mean's relMSE against `all` and one run's over the number of runs.
fn print_table(sums: &Sums, truth: &[Vec<[f32; 4]>], runs: u32) {
    println!("| frame | mean ratio (runs' mean / all) ± standard error | relMSE of the runs' mean | one run's relMSE / runs |");
    println!("|---:|---:|---:|---:|");
    let n = runs as f64;
    let (mut tot, mut tot_mean, mut tot_single, mut tot_t2) = ([0.0f64; 2], 0.0, 0.0, 0.0);
    for (k, t) in truth.iter().enumerate() {
        let (mut err, mut t2, mut means) = (0.0, 0.0, [0.0f64; 2]);
        for (q, a) in t.iter().enumerate() {
            for c in 0..3 {
                let (m, a) = (sums.pixels[k][q][c] / n, a[c] as f64);
                err += (m - a).powi(2);
                t2 += a * a;
                means[0] += m;
                means[1] += a;
            }
        }
        let (_, se) = bounce_tests::mean_and_stderr(&sums.images[k]);
        let single = sums.single[k] / n;
        println!(
            "| {k} | {:.4} ± {:.4} | {:.3e} | {:.3e} |",
            means[0] / means[1],
            se / means[1],
            err / t2,
            single / t2 / n
        );
        tot[0] += means[0];
        tot[1] += means[1];
        tot_mean += err;
        tot_single += single;
        tot_t2 += t2;
    }
    println!("| all | {:.4} | {:.3e} | {:.3e} |", tot[0] / tot[1], tot_mean / tot_t2, tot_single / tot_t2 / n);
}
