//! Image error metrics, as the project defines them (linear radiance, all pixels and channels):
//! RMSE; relMSE = mean of (t − r)² / (r² + 0.01); bias = mean(t) / mean(r); the 99th percentile of
//! |t − r|; and the count of non-finite test pixels (which never count as agreeing). For animations,
//! [`flicker`]: the relMSE of the frame-to-frame differences.

/// relMSE's ε in (t − r)² / (r² + ε), in radiance units: where the reference is dark, an absolute error.
pub const REL_EPS: f64 = 0.01;

#[derive(Clone, Debug, PartialEq)]
pub struct Metrics {
    pub rmse: f64,
    pub rel_mse: f64,
    /// mean(test) / mean(reference).
    pub mean_ratio: f64,
    pub p99_abs: f64,
    /// The tail: the 99.9th percentile of the per-pixel, per-channel |error| (fireflies show here first).
    pub p999_abs: f64,
    pub non_finite: usize,
    /// Mean FLIP of the tone-mapped pair, when computed (`with_flip`).
    pub flip: Option<f64>,
}

impl Metrics {
    pub fn of(test: &[[f32; 3]], reference: &[[f32; 3]]) -> Metrics {
        assert_eq!(test.len(), reference.len(), "images of different sizes");
        let (mut se, mut rel, mut st, mut sr) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let mut abs = Vec::with_capacity(test.len() * 3);
        let mut non_finite = 0;
        for (t, r) in test.iter().zip(reference) {
            if t.iter().any(|c| !c.is_finite()) {
                non_finite += 1;
            }
            for c in 0..3 {
                let (t, r) = (t[c] as f64, r[c] as f64);
                let t = if t.is_finite() { t } else { f64::INFINITY };
                se += (t - r) * (t - r);
                rel += (t - r) * (t - r) / (r * r + REL_EPS);
                st += t;
                sr += r;
                abs.push((t - r).abs());
            }
        }
        let n = abs.len().max(1) as f64;
        abs.sort_by(|a, b| a.total_cmp(b));
        let quantile = |q: f64| {
            abs.get(((abs.len() as f64 * q) as usize).min(abs.len().saturating_sub(1))).copied().unwrap_or(0.0)
        };
        let (p99, p999) = (quantile(0.99), quantile(0.999));
        Metrics {
            rmse: (se / n).sqrt(),
            rel_mse: rel / n,
            mean_ratio: if sr > 0.0 {
                st / sr
            } else if st == 0.0 {
                1.0
            } else {
                f64::INFINITY
            },
            p99_abs: p99,
            p999_abs: p999,
            non_finite,
            flip: None,
        }
    }

    /// The metrics plus mean FLIP (see `output::flip`).
    pub fn with_flip(test: &crate::output::RgbImage, reference: &crate::output::RgbImage) -> Metrics {
        let mut m = Metrics::of(&test.pixels, &reference.pixels);
        m.flip = Some(crate::output::flip(test, reference).0);
        m
    }

    pub fn table(&self) -> String {
        format!(
            "RMSE        {:.6e}\nrelMSE      {:.6e}\nmean ratio  {:.6}\np99 |err|   {:.6e}\np99.9 |err| {:.6e}\nmean FLIP   {}\nnon-finite  {}",
            self.rmse,
            self.rel_mse,
            self.mean_ratio,
            self.p99_abs,
            self.p999_abs,
            self.flip.map(|f| format!("{f:.6}")).unwrap_or_else(|| "n/a".into()),
            self.non_finite
        )
    }

    pub fn json(&self) -> String {
        format!(
            "{{\"rmse\": {}, \"rel_mse\": {}, \"mean_ratio\": {}, \"p99_abs\": {}, \"p999_abs\": {}, \"flip\": {}, \"non_finite\": {}}}",
            self.rmse,
            self.rel_mse,
            self.mean_ratio,
            self.p99_abs,
            self.p999_abs,
            self.flip.map(|f| f.to_string()).unwrap_or_else(|| "null".into()),
            self.non_finite
        )
    }
}

/// The flicker of frame k of an animation: the error of its frame-to-frame difference against the
/// ground truth's, mean over pixels and channels of ((t_k − t_{k−1}) − (r_k − r_{k−1}))² / (r_k² + 0.01)
/// (relMSE's normalisation). A constant error (a bias that does not change) does not flicker; fresh
/// noise every frame does. A non-finite test value gives infinity.
pub fn flicker(t: &[[f32; 3]], t_prev: &[[f32; 3]], r: &[[f32; 3]], r_prev: &[[f32; 3]]) -> f64 {
    assert!(t.len() == r.len() && t_prev.len() == r.len() && r_prev.len() == r.len(), "images of different sizes");
    let mut sum = 0.0f64;
    for i in 0..r.len() {
        for c in 0..3 {
            let dt = t[i][c] as f64 - t_prev[i][c] as f64;
            let dr = r[i][c] as f64 - r_prev[i][c] as f64;
            let e = if dt.is_finite() { dt - dr } else { f64::INFINITY };
            sum += e * e / ((r[i][c] as f64).powi(2) + REL_EPS);
        }
    }
    sum / (3 * r.len()).max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flicker_counts_changes_of_the_error_not_the_error() {
        let (r0, r1) = ([[1.0f32, 0.0, 0.5]], [[2.0f32, 0.0, 0.5]]);
        // A constant offset from the truth: no flicker, whatever its size.
        let (t0, t1) = ([[1.5f32, 0.3, 0.0]], [[2.5f32, 0.3, 0.0]]);
        assert_eq!(flicker(&t1, &t0, &r1, &r0), 0.0);
        // The error grows by 0.1 in the first channel and by 0.2 in the second:
        // (0.1² / (2² + 0.01) + 0.2² / (0 + 0.01)) / 3.
        let t1 = [[2.6f32, 0.5, 0.0]];
        let want = (0.01 / 4.01 + 0.04 / 0.01) / 3.0;
        assert!((flicker(&t1, &t0, &r1, &r0) - want).abs() < 1e-6, "{}", flicker(&t1, &t0, &r1, &r0));
    }

    #[test]
    fn hand_computed_case() {
        let r = [[1.0f32, 0.0, 0.0], [0.0, 0.0, 0.0]];
        let t = [[2.0f32, 0.0, 0.0], [0.0, 0.1, 0.0]];
        let m = Metrics::of(&t, &r);
        // squared errors: 1, 0.01 over 6 entries
        assert!((m.rmse - (1.01f64 / 6.0).sqrt()).abs() < 1e-9);
        // relMSE: 1/(1 + 0.01) + 0.01/0.01 = 0.990099 + 1, over 6
        assert!((m.rel_mse - (1.0 / 1.01 + 1.0) / 6.0).abs() < 1e-7);
        assert!((m.mean_ratio - 2.1).abs() < 1e-6);
        assert_eq!(m.non_finite, 0);
    }

    #[test]
    fn flip_is_zero_for_identical_images_and_grows_with_a_difference() {
        use crate::output::RgbImage;
        let px: Vec<[f32; 3]> =
            (0..64 * 64).map(|k| [((k % 64) as f32) / 64.0, 0.3, ((k / 64) as f32) / 64.0]).collect();
        let a = RgbImage { width: 64, height: 64, pixels: px.clone() };
        let mut b = a.clone();
        assert_eq!(Metrics::with_flip(&a, &a).flip, Some(0.0));
        for p in b.pixels.iter_mut().take(64 * 32) {
            p[1] = 2.0;
        }
        let f = Metrics::with_flip(&b, &a).flip.unwrap();
        assert!(f > 0.05, "FLIP {f}");
    }

    #[test]
    fn non_finite_pixels_are_counted_and_poison_the_error() {
        let r = [[1.0f32; 3]];
        let t = [[f32::NAN, 1.0, 1.0]];
        let m = Metrics::of(&t, &r);
        assert_eq!(m.non_finite, 1);
        assert!(!m.rmse.is_finite());
    }
}
