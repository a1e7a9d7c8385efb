//! What the viewer shows when the view stops moving: the running mean of the still frames P_1..P_n with
//! the last real-time (denoised) frame D kept in it as w_n frames' worth, (Σ P_k + w_n D) / (n + w_n),
//! for prior weights w_n = W · max(0, 1 − (n − 1) / N0) (W = 0: the plain mean, as the viewer had it).
//! Prints each schedule's relMSE against the truth after n still frames, and the stop's jump: the
//! relMSE of the first still display against D. The figures of BENCHMARKS.md, "Real time under motion".
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
    Ok(())
}
