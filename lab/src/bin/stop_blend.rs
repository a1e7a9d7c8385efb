//! What the viewer shows when the view stops moving: the running mean of the still frames P_1..P_n with
//! the last real-time (denoised) frame D kept in it as w_n frames' worth, (Σ P_k + w_n D) / (n + w_n),
//! for prior weights w_n = W · max(0, 1 − (n − 1) / N0) (W = 0: the plain mean, as the viewer had it).
//! Prints each schedule's relMSE against the truth after n still frames, and the stop's jump: the
//! relMSE of the first still display against D. Rows `aWMAX`: a weight per pixel, present.comp's
//! `prior_weight` with its cap at WMAX (`a16`: the viewer's): one still frame's luminance variance v over
//! D's squared error e², both over 3 × 3 pixels (the frames' sample variance; e² = the pooled
//! (l_D − l_mean)² less v / n), from frame 2 on; STOP_PRIOR_FIRST at frame 1, where one frame gives no
//! variance; faded over STOP_PRIOR_FADE frames. The figures of BENCHMARKS.md, "Real time under motion".
//!
//!     cargo run --release -p bounce-lab --bin stop-blend PRIOR.exr FRAMES_DIR TRUTH.exr
//!
//! PRIOR.exr: the last frame of `bounce render … --method realtime --camera-path PATH --frames N
//! --out-dir DIR`; FRAMES_DIR: `bounce render …` of the still frames at the path's end (frame_0000.exr,
//! …; `--frames K --out-dir`, the method the viewer accumulates); TRUTH.exr: that view's ground truth; all
//! of one component (bench's truths: `--component indirect`).

use anyhow::{bail, Result};
use bounce::metrics::Metrics;
use bounce::output::read_exr;
use bounce_graph::bindings::{STOP_PRIOR_FADE, STOP_PRIOR_FIRST};
use std::path::Path;

/// The prior's weight in pixel i's mean after the still frames so far.
type Weight = Box<dyn Fn(&Still, usize) -> f64>;

/// A schedule of the prior's weight: a row's label (W, N0) and its weight.
struct Schedule {
    label: (String, String),
    weight: Weight,
}

/// What the weights may read after n still frames: n, and per pixel the luminance's sample variance
/// and D's squared deviation from the running mean, each pooled over 3 × 3 pixels.
struct Still {
    n: f64,
    variance: Vec<f64>,
    deviation: Vec<f64>,
}

/// One row's figures as the frames come.
#[derive(Default)]
struct Row {
    cells: String,
    total: f64,
    jump: f64,
    last_ratio: f64,
}

fn luminance(p: &[f32; 3]) -> f64 {
    0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
}

/// The mean of `vals` over the 3 × 3 pixels around each pixel of a `w` × `h` image (those inside it).
fn pooled(vals: &[f64], w: usize, h: usize) -> Vec<f64> {
    (0..vals.len())
        .map(|i| {
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            let (mut a, mut m) = (0.0, 0.0);
            for (dx, dy) in (-1..=1).flat_map(|dy| (-1..=1).map(move |dx| (dx, dy))) {
                let (xx, yy) = (x + dx, y + dy);
                if xx >= 0 && yy >= 0 && xx < w as i64 && yy < h as i64 {
                    a += vals[yy as usize * w + xx as usize];
                    m += 1.0;
                }
            }
            a / m
        })
        .collect()
}

fn schedules() -> Vec<Schedule> {
    let mut out = vec![];
    for w in [0.0f64, 0.5, 1.0, 1.5, 2.0, 4.0, 8.0] {
        for n0 in [16.0f64, 32.0, f64::INFINITY] {
            if w == 0.0 && n0 != f64::INFINITY {
                continue;
            }
            let weight = move |s: &Still, _: usize| w * (1.0 - (s.n - 1.0) / n0).max(0.0);
            out.push(Schedule { label: (w.to_string(), n0.to_string()), weight: Box::new(weight) });
        }
    }
    for cap in [4.0f64, 16.0, 64.0] {
        let weight = move |s: &Still, i: usize| {
            let fade = (1.0 - (s.n - 1.0) / STOP_PRIOR_FADE as f64).max(0.0);
            if s.n <= 1.0 {
                return STOP_PRIOR_FIRST as f64 * fade;
            }
            let e2 = (s.deviation[i] - s.variance[i] / s.n).max(1e-30);
            (s.variance[i] / e2).min(cap) * fade
        };
        out.push(Schedule { label: (format!("a{cap}"), STOP_PRIOR_FADE.to_string()), weight: Box::new(weight) });
    }
    out
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 3 {
        bail!("usage: stop-blend PRIOR.exr FRAMES_DIR TRUTH.exr");
    }
    let (prior, _) = read_exr(Path::new(&args[0]))?;
    let (truth, _) = read_exr(Path::new(&args[2]))?;
    let dir = Path::new(&args[1]);
    let mut frames = vec![];
    while let Ok((f, _)) = read_exr(&dir.join(format!("frame_{:04}.exr", frames.len()))) {
        frames.push(f.pixels);
    }
    if frames.is_empty() || prior.pixels.len() != truth.pixels.len() {
        bail!("no frames in {}, or the prior and the truth differ in size", dir.display());
    }
    let (w, h, np) = (truth.width as usize, truth.height as usize, truth.pixels.len());
    let shown = [1usize, 2, 4, 8, 16, 32, 64, 128].into_iter().filter(|&n| n <= frames.len()).collect::<Vec<_>>();
    let d = Metrics::of(&prior.pixels, &truth.pixels);
    println!("prior D: relMSE {:.5}, mean ratio {:.3}", d.rel_mse, d.mean_ratio);
    let schedules = schedules();
    let mut rows: Vec<Row> = schedules.iter().map(|_| Row::default()).collect();
    let (mut sum, mut s1, mut s2) = (vec![[0.0f64; 3]; np], vec![0.0f64; np], vec![0.0f64; np]);
    for (k, f) in frames.iter().enumerate() {
        let n = (k + 1) as f64;
        for i in 0..np {
            (0..3).for_each(|c| sum[i][c] += f[i][c] as f64);
            let l = luminance(&f[i]);
            (s1[i], s2[i]) = (s1[i] + l, s2[i] + l * l);
        }
        let variance: Vec<f64> =
            (0..np).map(|i| if k == 0 { 0.0 } else { ((s2[i] - s1[i] * s1[i] / n) / (n - 1.0)).max(0.0) }).collect();
        let deviation: Vec<f64> = (0..np).map(|i| (luminance(&prior.pixels[i]) - s1[i] / n).powi(2)).collect();
        let still = Still { n, variance: pooled(&variance, w, h), deviation: pooled(&deviation, w, h) };
        for (schedule, row) in schedules.iter().zip(&mut rows) {
            let display: Vec<[f32; 3]> = (0..np)
                .map(|i| {
                    let wn = (schedule.weight)(&still, i);
                    std::array::from_fn(|c| ((sum[i][c] + wn * prior.pixels[i][c] as f64) / (n + wn)) as f32)
                })
                .collect();
            let m = Metrics::of(&display, &truth.pixels);
            row.total += m.rel_mse;
            row.last_ratio = m.mean_ratio;
            if k == 0 {
                row.jump = Metrics::of(&display, &prior.pixels).rel_mse;
            }
            if shown.contains(&(k + 1)) {
                row.cells += &format!(" {:.5} |", m.rel_mse);
            }
        }
    }
    print!("| W | N0 | jump |");
    for n in &shown {
        print!(" n = {n} |");
    }
    println!(" mean over n ≤ {} | mean ratio at {} |", frames.len(), frames.len());
    for (schedule, row) in schedules.iter().zip(&rows) {
        let (wl, nl) = &schedule.label;
        let mean = row.total / frames.len() as f64;
        println!("| {wl} | {nl} | {:.5} |{} {mean:.5} | {:.4} |", row.jump, row.cells, row.last_ratio);
    }
    Ok(())
}
