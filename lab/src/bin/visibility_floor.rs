//! The least error any estimator can reach that draws its shadow rays by the *unshadowed* contribution
//! (ris's and realtime's target without learned visibility), from two exhaustive VPL sums of one VPL set:
//! t, every VPL with its shadow ray (`--method all`), and F, every VPL unshadowed (the same with
//! `lab/unshadowed-all.patch`). One VPL drawn with probability f_v / F and weighed F / f_v
//! gives F · V(v): mean t, variance t (F − t), whatever reuse chose it, since the target knows nothing
//! of V. So k independent rays cannot go below relMSE = mean over pixels and channels of
//! t (F − t) / k / (t² + ε) (`bounce compare`'s ε, `metrics::REL_EPS`). Prints the visible share Σ t / Σ F, that floor
//! for 1, 2 and 64 rays, and each further image's relMSE against t (BENCHMARKS.md, "Real time under
//! motion").
//!
//!     cargo run --release -p bounce-lab --bin visibility-floor ALL.exr UNSHADOWED.exr [IMAGE.exr…]

use anyhow::{bail, Result};
use bounce::metrics::{Metrics, REL_EPS};
use bounce::output::read_exr;
use std::path::Path;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 {
        bail!("usage: visibility-floor ALL.exr UNSHADOWED.exr [IMAGE.exr…]");
    }
    let (t, _) = read_exr(Path::new(&args[0]))?;
    let (f, _) = read_exr(Path::new(&args[1]))?;
    if (t.width, t.height) != (f.width, f.height) {
        bail!("{} is {}×{}, {} is {}×{}", args[0], t.width, t.height, args[1], f.width, f.height);
    }
    let (mut floor, mut visible, mut unshadowed) = (0.0f64, 0.0f64, 0.0f64);
    for (a, b) in t.pixels.iter().zip(&f.pixels) {
        for c in 0..3 {
            let (t, f) = (a[c] as f64, b[c] as f64);
            // F ≥ t up to the sums' rounding.
            floor += t * (f - t).max(0.0) / (t * t + REL_EPS);
            (visible, unshadowed) = (visible + t, unshadowed + f);
        }
    }
    floor /= (3 * t.pixels.len()) as f64;
    println!(
        "visible share {:.3}; relMSE floor of unshadowed-target rays: 1 ray {:.6}, 2 rays {:.6}, 64 rays {:.7}",
        visible / unshadowed,
        floor,
        floor / 2.0,
        floor / 64.0
    );
    for p in &args[2..] {
        let (img, _) = read_exr(Path::new(p))?;
        if (img.width, img.height) != (t.width, t.height) {
            bail!("{p} is {}×{}, not {}×{}", img.width, img.height, t.width, t.height);
        }
        println!("{p}: relMSE against all {:.6}", Metrics::of(&img.pixels, &t.pixels).rel_mse);
    }
    Ok(())
}
