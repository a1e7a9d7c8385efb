//! `bounce compare`: the error metrics (`crate::metrics`) of a test EXR against a reference EXR, as a
//! table or JSON on stdout, and optionally the FLIP error map as a PNG.

use crate::cli::CompareArgs;
use crate::error::bad;
use crate::metrics::Metrics;
use crate::output;
use anyhow::Result;
use std::io::Write;

pub fn run(a: &CompareArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    if let Some(h) = &a.heatmap {
        output::check_destination(h, "png").map_err(bad)?;
    }
    let (t, _) = output::read_exr(&a.test).map_err(bad)?;
    let (r, _) = output::read_exr(&a.reference).map_err(bad)?;
    if (t.width, t.height) != (r.width, r.height) {
        return Err(bad(anyhow::anyhow!(
            "{} is {}x{} but {} is {}x{}",
            a.test.display(),
            t.width,
            t.height,
            a.reference.display(),
            r.width,
            r.height
        )));
    }
    // The test's non-finite pixels are counted (and make its errors infinite); the reference's would make
    // every error NaN: it is no reference.
    let bad_pixels = r.non_finite_count();
    if bad_pixels > 0 {
        return Err(bad(anyhow::anyhow!(
            "{} has {bad_pixels} non-finite pixels: not a reference",
            a.reference.display()
        )));
    }
    let m = Metrics::with_flip(&t, &r);
    if let Some(h) = &a.heatmap {
        let (_, map) = output::flip(&t, &r);
        output::write_png_bytes(h, t.width, t.height, map)?;
        writeln!(err, "wrote {}", h.display())?;
    }
    if a.json {
        writeln!(out, "{}", m.json())?;
    } else {
        writeln!(out, "{}", m.table())?;
    }
    Ok(())
}
