//! `same-pixels A.exr B.exr`: exit 0 when the two EXRs have the same size and bit-identical pixels
//! (f32 bits, so −0 ≠ +0 and NaN payloads count), else print how many values differ, the first one and
//! the largest difference, and exit 1. `scripts/same-images.sh` uses it to show that a refactor renders
//! exactly what the commit before it rendered.

use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 2 {
        eprintln!("error: usage: same-pixels A.exr B.exr");
        return ExitCode::from(2);
    }
    let read = |p: &str| bounce::output::read_exr(Path::new(p)).map(|(img, _)| img);
    let (a, b) = match (read(&args[0]), read(&args[1])) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("error: {e:#}");
            return ExitCode::from(2);
        }
    };
    if (a.width, a.height) != (b.width, b.height) {
        println!("different sizes: {}x{} vs {}x{}", a.width, a.height, b.width, b.height);
        return ExitCode::from(1);
    }
    let (mut differing, mut first, mut largest) = (0usize, None, 0.0f64);
    for (k, (pa, pb)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        for c in 0..3 {
            if pa[c].to_bits() != pb[c].to_bits() {
                differing += 1;
                first.get_or_insert((k, c, pa[c], pb[c]));
                largest = largest.max((pa[c] as f64 - pb[c] as f64).abs());
            }
        }
    }
    match first {
        None => ExitCode::SUCCESS,
        Some((k, c, x, y)) => {
            let w = a.width as usize;
            println!(
                "{differing} values differ; first at pixel ({}, {}) channel {c}: {x:e} vs {y:e}; largest |diff| {largest:e}",
                k % w,
                k / w
            );
            ExitCode::from(1)
        }
    }
}
