//! The time-versus-error plot of `bounce bench`: log–log, one line per method, labelled axes with units
//! and a legend; for `bench --animate`, panels of per-frame figures (relMSE, flicker) over the
//! frames; for `suite`, each method's sorted ratios over `uniform` across the scenes. Text uses the embedded DejaVu Sans (assets/fonts), so no system font is needed.

use anyhow::{anyhow, Result};
use plotters::coord::combinators::BindKeyPoints;
use plotters::prelude::*;
use std::path::Path;

static FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");

fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // Registering a valid embedded font cannot fail but for a broken file, which is a build bug.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Runs `draw` on a white bitmap of `size` pixels written to a temporary PNG beside `path`, then renames it
/// into place, so a failed plot leaves no half-written file (the encoder picks the format from the
/// extension, so the temporary name ends in .png too).
fn png(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>) -> Result<()>,
) -> Result<()> {
    register_font();
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.{}.tmp.png", std::process::id()));
    let drawn = (|| {
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("plot: {e}"))?;
        draw(&root)?;
        root.present().map_err(|e| anyhow!("plot: {e}"))
    })();
    let done =
        drawn.and_then(|()| std::fs::rename(&tmp, path).map_err(|e| anyhow!("renaming into {}: {e}", path.display())));
    if done.is_err() {
        // No half-drawn temporary is left beside the outputs.
        let _ = std::fs::remove_file(&tmp);
    }
    done
}

/// What the two axes show (the error axis names what the error is measured against).
pub struct Axes<'a> {
    pub time: &'a str,
    pub error: &'a str,
}

/// A log-axis tick: three significant digits, no trailing zeros, so ticks stay short and distinct
/// (`0.25`, `3`, `120`, `1.5e4`) where a fixed `{:.3}` read "100.000" and overlapped.
pub fn tick(v: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return String::new();
    }
    if !(1e-3..1e4).contains(&v) {
        return format!("{v:.2e}").replace(".00e", "e").replace("0e", "e");
    }
    let digits = (2 - v.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Log-axis ticks at 1, 2 and 5 times the powers of ten inside [lo, hi], or at the decades alone when
/// the range spans more than three of them (so a narrow range still gets several labelled ticks).
pub fn key_points(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return vec![];
    }
    let steps: &[f64] = if (hi / lo).log10() > 3.0 { &[1.0] } else { &[1.0, 2.0, 5.0] };
    let mut v = vec![];
    let mut decade = 10f64.powf(lo.log10().floor());
    while decade <= hi {
        v.extend(steps.iter().map(|m| m * decade).filter(|x| (lo..=hi).contains(x)));
        decade *= 10.0;
    }
    v
}

/// `series`: (method, [(time, relMSE)]) in column order. Points with a non-positive or non-finite value
/// cannot go on log axes and are left out.
pub fn time_vs_error(path: &Path, series: &[(String, Vec<(f64, f64)>)], subtitle: &str, axes: &Axes) -> Result<()> {
    let pts: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|(_, v)| v.iter().copied())
        .filter(|(t, e)| *t > 0.0 && *e > 0.0 && t.is_finite() && e.is_finite())
        .collect();
    // With nothing to put on log axes (every error 0: a black scene) the axes are drawn empty, and say so.
    let (pts, empty) = if pts.is_empty() { (vec![(1.0, 1.0)], ", no positive error to plot") } else { (pts, "") };
    let (tmin, tmax) = pts.iter().fold((f64::MAX, f64::MIN), |(a, b), (t, _)| (a.min(*t), b.max(*t)));
    let (emin, emax) = pts.iter().fold((f64::MAX, f64::MIN), |(a, b), (_, e)| (a.min(*e), b.max(*e)));
    png(path, (900, 640), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(format!("Run time against error ({subtitle}{empty})"), ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(96)
            .build_cartesian_2d(
                (tmin / 1.5..tmax * 1.5).log_scale().with_key_points(key_points(tmin / 1.5, tmax * 1.5)),
                (emin / 1.5..emax * 1.5).log_scale().with_key_points(key_points(emin / 1.5, emax * 1.5)),
            )
            .map_err(|e| anyhow!("plot: {e}"))?;
        chart
            .configure_mesh()
            .x_desc(axes.time)
            .y_desc(axes.error)
            .x_labels(8)
            .y_labels(8)
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(|e| anyhow!("plot: {e}"))?;
        for (k, (name, v)) in series.iter().enumerate() {
            let color = Palette99::pick(k).to_rgba();
            let line: Vec<(f64, f64)> =
                v.iter().copied().filter(|(t, e)| *t > 0.0 && *e > 0.0 && t.is_finite() && e.is_finite()).collect();
            chart
                .draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))
                .map_err(|e| anyhow!("plot: {e}"))?
                .label(name.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3)));
            chart
                .draw_series(line.iter().map(|p| Circle::new(*p, 4, color.filled())))
                .map_err(|e| anyhow!("plot: {e}"))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 16))
            .draw()
            .map_err(|e| anyhow!("plot: {e}"))?;
        Ok(())
    })
}

/// The suite's plot (`bounce suite`): for each method its per-scene relMSE over `uniform`'s, sorted,
/// against the share of scenes (x from 0 to 1, y log), with the line y = 1 where a method ties `uniform`.
pub fn sorted_ratios(path: &Path, series: &[(String, Vec<f64>)], subtitle: &str) -> Result<()> {
    // With no finite positive ratio (every scene dark) the plot keeps its y = 1 line and axes.
    let all: Vec<f64> =
        series.iter().flat_map(|(_, v)| v.iter().copied()).filter(|v| v.is_finite() && *v > 0.0).collect();
    let lo = all.iter().copied().fold(1.0f64, f64::min) / 1.5;
    let hi = all.iter().copied().fold(1.0f64, f64::max) * 1.5;
    png(path, (900, 640), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(format!("relMSE over uniform's, per scene, sorted ({subtitle})"), ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(96)
            .build_cartesian_2d(0.0..1.0f64, (lo..hi).log_scale().with_key_points(key_points(lo, hi)))
            .map_err(|e| anyhow!("plot: {e}"))?;
        chart
            .configure_mesh()
            .x_desc("share of scenes")
            .y_desc("relMSE / uniform's (below 1: better than uniform)")
            .y_label_formatter(&|v| tick(*v))
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(|e| anyhow!("plot: {e}"))?;
        chart
            .draw_series(LineSeries::new(vec![(0.0, 1.0), (1.0, 1.0)], BLACK.mix(0.5).stroke_width(1)))
            .map_err(|e| anyhow!("plot: {e}"))?;
        for (k, (name, v)) in series.iter().enumerate() {
            let color = Palette99::pick(k).to_rgba();
            let mut v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite() && *x > 0.0).collect();
            v.sort_by(|a, b| a.total_cmp(b));
            let n = v.len().max(1) as f64;
            let line: Vec<(f64, f64)> = v.iter().enumerate().map(|(i, y)| ((i as f64 + 0.5) / n, *y)).collect();
            chart
                .draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))
                .map_err(|e| anyhow!("plot: {e}"))?
                .label(name.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3)));
            chart
                .draw_series(line.iter().map(|p| Circle::new(*p, 3, color.filled())))
                .map_err(|e| anyhow!("plot: {e}"))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 16))
            .draw()
            .map_err(|e| anyhow!("plot: {e}"))?;
        Ok(())
    })
}

/// One panel of [`over_frames`]: its y-axis label and its series, (name, [(frame, value)]).
pub struct Panel<'a> {
    pub y: &'a str,
    pub series: &'a [(String, Vec<(f64, f64)>)],
}

/// Panels stacked vertically, frame number on a linear x axis, the values on log y axes, one line per
/// series (the same colour in every panel).
pub fn over_frames(path: &Path, panels: &[Panel], title: &str) -> Result<()> {
    png(path, (900, 420 * panels.len().max(1) as u32), |root| {
        let root = root.titled(title, ("sans-serif", 22)).map_err(|e| anyhow!("plot: {e}"))?;
        for (area, panel) in root.split_evenly((panels.len().max(1), 1)).iter().zip(panels) {
            frame_panel(area, panel)?;
        }
        Ok(())
    })
}

fn frame_panel(area: &DrawingArea<BitMapBackend, plotters::coord::Shift>, panel: &Panel) -> Result<()> {
    let ok = |(f, v): &(f64, f64)| f.is_finite() && *v > 0.0 && v.is_finite();
    let pts: Vec<(f64, f64)> = panel.series.iter().flat_map(|(_, v)| v.iter().copied()).filter(ok).collect();
    // Nothing to put on a log axis (a black scene's errors, a still view's flicker): the axes, empty.
    let (pts, y_desc) = if pts.is_empty() {
        (vec![(0.0, 1.0)], format!("{} (none positive)", panel.y))
    } else {
        (pts, panel.y.to_string())
    };
    let (fmin, fmax) = pts.iter().fold((f64::MAX, f64::MIN), |(a, b), (f, _)| (a.min(*f), b.max(*f)));
    let (vmin, vmax) = pts.iter().fold((f64::MAX, f64::MIN), |(a, b), (_, v)| (a.min(*v), b.max(*v)));
    let mut chart = ChartBuilder::on(area)
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(96)
        .build_cartesian_2d(
            fmin - 0.5..fmax + 0.5,
            (vmin / 1.5..vmax * 1.5).log_scale().with_key_points(key_points(vmin / 1.5, vmax * 1.5)),
        )
        .map_err(|e| anyhow!("plot: {e}"))?;
    chart
        .configure_mesh()
        .x_desc("frame")
        .y_desc(y_desc)
        .y_labels(8)
        // Whole frames only, at most ten labels (fractional ticks rounded to repeated numbers).
        .x_labels(((fmax - fmin) as usize + 1).min(10))
        .x_label_formatter(&|v| if (v - v.round()).abs() < 1e-6 { format!("{v:.0}") } else { String::new() })
        .y_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", 15))
        .draw()
        .map_err(|e| anyhow!("plot: {e}"))?;
    for (k, (name, v)) in panel.series.iter().enumerate() {
        let color = Palette99::pick(k).to_rgba();
        let line: Vec<(f64, f64)> = v.iter().copied().filter(ok).collect();
        chart
            .draw_series(LineSeries::new(line, color.stroke_width(2)))
            .map_err(|e| anyhow!("plot: {e}"))?
            .label(name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(|e| anyhow!("plot: {e}"))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::tick;

    #[test]
    fn ticks_are_short_and_distinct() {
        assert_eq!(tick(100.0), "100");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(3.0), "3");
        assert_eq!(tick(12.5), "12.5");
        assert_eq!(tick(0.0043), "0.0043");
        assert_eq!(tick(1.5e4), "1.5e4");
        assert_eq!(tick(2e-5), "2e-5");
    }

    #[test]
    fn narrow_log_ranges_get_1_2_5_ticks_and_wide_ones_decades() {
        assert_eq!(super::key_points(0.3, 3.0), vec![0.5, 1.0, 2.0]);
        assert_eq!(super::key_points(1e-5, 1.0), vec![1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0]);
        assert!(super::key_points(0.0, 1.0).is_empty());
    }
}
