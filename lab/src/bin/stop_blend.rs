//! What the viewer shows when the view stops moving: the running mean of the still frames P_1..P_n with
//! the last real-time (denoised) frame D kept in it as w_n frames' worth, (Σ P_k + w_n D) / (n + w_n),
//! for prior weights w_n = W · max(0, 1 − (n − 1) / N0) (W = 0: the plain mean, as the viewer had it).
//! Prints each schedule's relMSE against the truth after n still frames, and the stop's jump: the
//! relMSE of the first still display against D. Rows `aWMAX`: a weight per pixel, the present pass's
//! rule at WMAX = 16 (one still frame's luminance variance v over D's squared error e², both pooled over
//! 3 × 3 pixels: the frames' sample variance from frame 2 on, e² = the pooled (l_D − l_mean)² less v /
//! n; capped at WMAX, faded over 32 frames; the first frame takes W = 1, where one frame gives no
//! variance). The figures of BENCHMARKS.md, "Real time under motion".
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
use std::path::Path;

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
    let shown = [1usize, 2, 4, 8, 16, 32, 64, 128].into_iter().filter(|&n| n <= frames.len()).collect::<Vec<_>>();
    println!(
        "prior D: relMSE {:.5}, mean ratio {:.3}",
        Metrics::of(&prior.pixels, &truth.pixels).rel_mse,
        Metrics::of(&prior.pixels, &truth.pixels).mean_ratio
    );
    print!("| W | N0 | jump |");
    for n in &shown {
        print!(" n = {n} |");
    }
    println!(" mean over n ≤ {} | mean ratio at {} |", frames.len(), frames.len());
    for w in [0.0f64, 0.5, 1.0, 1.5, 2.0, 4.0, 8.0] {
        for n0 in [16.0f64, 32.0, f64::INFINITY] {
            if w == 0.0 && n0 != f64::INFINITY {
                continue;
            }
            let mut sum = vec![[0.0f64; 3]; truth.pixels.len()];
            let (mut row, mut total, mut jump, mut last_ratio) = (String::new(), 0.0, 0.0, 0.0);
            for (k, f) in frames.iter().enumerate() {
                let n = (k + 1) as f64;
                let wn = w * (1.0 - (n - 1.0) / n0).max(0.0);
                for (s, p) in sum.iter_mut().zip(f) {
                    for c in 0..3 {
                        s[c] += p[c] as f64;
                    }
                }
                let display: Vec<[f32; 3]> = sum
                    .iter()
                    .zip(&prior.pixels)
                    .map(|(s, d)| std::array::from_fn(|c| ((s[c] + wn * d[c] as f64) / (n + wn)) as f32))
                    .collect();
                let m = Metrics::of(&display, &truth.pixels);
                total += m.rel_mse;
                last_ratio = m.mean_ratio;
                if k == 0 {
                    jump = Metrics::of(&display, &prior.pixels).rel_mse;
                }
                if shown.contains(&(k + 1)) {
                    row += &format!(" {:.5} |", m.rel_mse);
                }
            }
            println!("| {w} | {n0} | {jump:.5} |{row} {:.5} | {last_ratio:.4} |", total / frames.len() as f64);
        }
    }

    // The weight per pixel (the module's `aWMAX` rows): w = v / e² from frame 2 on (the first frame's
    // neighbourhood variance misjudged it: light-wall-0 2.0× the plain mean's error at frame 1).
    let (w_img, h_img) = (truth.width as i64, truth.height as i64);
    let lum = |p: &[f32; 3]| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
    for wmax in [4.0f64, 16.0, 64.0] {
        let np = truth.pixels.len();
        let mut sum = vec![[0.0f64; 3]; np];
        let (mut s1, mut s2) = (vec![0.0f64; np], vec![0.0f64; np]);
        let (mut row, mut total, mut jump, mut last_ratio) = (String::new(), 0.0, 0.0, 0.0);
        for (k, f) in frames.iter().enumerate() {
            let n = (k + 1) as f64;
            for i in 0..np {
                for c in 0..3 {
                    sum[i][c] += f[i][c] as f64;
                }
                let l = lum(&f[i]);
                s1[i] += l;
                s2[i] += l * l;
            }
            let pool = |vals: &dyn Fn(usize) -> f64, i: usize| -> f64 {
                let (x, y) = ((i as i64) % w_img, (i as i64) / w_img);
                let (mut a, mut m) = (0.0, 0.0);
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let (xx, yy) = (x + dx, y + dy);
                        if xx >= 0 && yy >= 0 && xx < w_img && yy < h_img {
                            a += vals((yy * w_img + xx) as usize);
                            m += 1.0;
                        }
                    }
                }
                a / m
            };
            let var_frame: Vec<f64> = if k == 0 {
                let mean = |i: usize| s1[i];
                let sq = |i: usize| s1[i] * s1[i];
                (0..np).map(|i| (pool(&sq, i) - pool(&mean, i).powi(2)).max(0.0)).collect()
            } else {
                let v = |i: usize| ((s2[i] - s1[i] * s1[i] / n) / (n - 1.0)).max(0.0);
                (0..np).map(|i| pool(&v, i)).collect()
            };
            let dev = |i: usize| (lum(&prior.pixels[i]) - s1[i] / n).powi(2);
            let fade = (1.0 - (n - 1.0) / 32.0).max(0.0);
            let display: Vec<[f32; 3]> = (0..np)
                .map(|i| {
                    let e2 = (pool(&dev, i) - var_frame[i] / n).max(1e-12);
                    let wn = if k == 0 { 1.0 } else { (var_frame[i] / e2).min(wmax) * fade };
                    let d = &prior.pixels[i];
                    std::array::from_fn(|c| ((sum[i][c] + wn * d[c] as f64) / (n + wn)) as f32)
                })
                .collect();
            let m = Metrics::of(&display, &truth.pixels);
            total += m.rel_mse;
            last_ratio = m.mean_ratio;
            if k == 0 {
                jump = Metrics::of(&display, &prior.pixels).rel_mse;
            }
            if shown.contains(&(k + 1)) {
                row += &format!(" {:.5} |", m.rel_mse);
            }
        }
        println!("| a{wmax} | 32 | {jump:.5} |{row} {:.5} | {last_ratio:.4} |", total / frames.len() as f64);
    }
    Ok(())
}
