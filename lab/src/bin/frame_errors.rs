//! The errors of an animation's frames against per-frame ground truths: `bench`'s relMSE and flicker
//! (`bounce::metrics`), the relMSE without the pixels whose truth is 0, and the energy-weighted forms
//! ΣΣ (t − r)² / ΣΣ r² of both, which no single dark pixel rules (a pixel of truth 0 next to a bright one
//! can hold nearly all of a frame's relMSE). The figures of BENCHMARKS.md, "Real time under motion".
//!
//!     cargo run --release -p bounce-lab --bin frame-errors FRAMES_DIR TRUTH_DIR [MATCH]
//!
//! FRAMES_DIR: `bounce render … --frames N --out-dir FRAMES_DIR` (frame_0000.exr, …), rendered with the
//! truths' component (bench's: `--component indirect`); TRUTH_DIR: a `bounce bench --animate … --out DIR`
//! folder, one reference-…-frameNNNN.exr a frame (MATCH, a substring of their names, picks one path's
//! where the folder holds several).

use anyhow::{bail, Context, Result};
use bounce::metrics::{flicker, Metrics, REL_EPS};
use bounce::output::read_exr;
use std::path::{Path, PathBuf};

/// A frame's pixels and its truth's.
type Pair = (Vec<[f32; 3]>, Vec<[f32; 3]>);

/// The one truth of frame `k` in `dir` whose name contains `matching`.
fn truth(dir: &Path, k: usize, matching: &str) -> Result<PathBuf> {
    let suffix = format!("frame{k:04}.exr");
    let found: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.ends_with(&suffix) && n.contains(matching))
        })
        .collect();
    match found.as_slice() {
        [one] => Ok(one.clone()),
        _ => bail!("{}: {} truths for frame {k} (give MATCH)", dir.display(), found.len()),
    }
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if !(2..=3).contains(&args.len()) {
        bail!("usage: frame-errors FRAMES_DIR TRUTH_DIR [MATCH]");
    }
    let (frames, truths) = (Path::new(&args[0]), Path::new(&args[1]));
    let matching = args.get(2).map_or("", String::as_str);
    let count = (0..).take_while(|k| frames.join(format!("frame_{k:04}.exr")).exists()).count();
    if count < 2 {
        bail!("{}: fewer than two frames", frames.display());
    }
    let (mut rel, mut rel_lit, mut flick) = (0.0, 0.0, 0.0);
    // Σ (t − r)², Σ r², Σ of the frame-to-frame differences' squared error, Σ t, Σ r.
    let (mut se, mut sr2, mut sf, mut st, mut sr) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut prev: Option<Pair> = None;
    for k in 0..count {
        let (t, _) = read_exr(&frames.join(format!("frame_{k:04}.exr")))?;
        let (r, _) = read_exr(&truth(truths, k, matching)?)?;
        if (t.width, t.height) != (r.width, r.height) {
            bail!("frame {k}: {}×{} against a truth of {}×{}", t.width, t.height, r.width, r.height);
        }
        rel += Metrics::of(&t.pixels, &r.pixels).rel_mse;
        let mut lit = 0.0;
        for (a, b) in t.pixels.iter().zip(&r.pixels) {
            for c in 0..3 {
                let (a, b) = (a[c] as f64, b[c] as f64);
                let e = (a - b) * (a - b);
                if b != 0.0 {
                    lit += e / (b * b + REL_EPS);
                }
                (se, sr2, st, sr) = (se + e, sr2 + b * b, st + a, sr + b);
            }
        }
        rel_lit += lit / (3 * r.pixels.len()) as f64;
        if let Some((pt, pr)) = &prev {
            flick += flicker(&t.pixels, pt, &r.pixels, pr);
            for (((a, pa), b), pb) in t.pixels.iter().zip(pt).zip(&r.pixels).zip(pr) {
                for c in 0..3 {
                    let d = (a[c] as f64 - pa[c] as f64) - (b[c] as f64 - pb[c] as f64);
                    sf += d * d;
                }
            }
        }
        prev = Some((t.pixels, r.pixels));
    }
    let n = count as f64;
    println!(
        "relMSE {:.6}  without truth-0 pixels {:.6}  energy-weighted {:.6}  flicker {:.6}  energy-weighted {:.6}  mean ratio {:.5}",
        rel / n,
        rel_lit / n,
        se / sr2,
        flick / (n - 1.0),
        sf / sr2,
        st / sr
    );
    Ok(())
}
