//! The CPU twin of the two-level CDF: [`reduce`] mirrors `glsl/cdf_reduce.comp` and [`sample`] mirrors
//! `cdf_sample` of `glsl/shared/cdf.glsl`, for the tests (`tests/tests/cdf.rs`).
//!
//! **Why a twin and not an independent formula.** The GPU adds in float32, in a fixed order; the twin
//! does the same float32 operations in the same order (each row left to right, then the row totals top
//! to bottom), so its CDF equals the shader's bit for bit wherever the device rounds as IEEE 754 requires
//! (Vulkan: additions and multiplications correctly rounded). The sampling twin makes the same
//! comparisons, clamps and binary searches, so for the same `u` it returns the same texel. What the twin
//! cannot establish is that the method itself is right; the tests check that separately (hand-computed
//! cases here, a chi-square fit against weight / total in `tests/tests/cdf.rs`).
//!
//! Layout (see `crates/graph/src/passes/cdf_reduce.rs`): `[total, rows (u32 bits), row_length (u32 bits),
//! 0]`, then the inclusive prefix over row totals (`rows` floats), then each row's inclusive prefix
//! (`rows × row_length` floats). Weights are sanitised as in the shader: `x > 0 && x < 1e30 ? x : 0`, so
//! negative, NaN and infinite weights (and finite ones ≥ 1e30) count as 0.
//!
//! The stream of random numbers the gather feeds to `cdf_sample` is mirrored too ([`pcg_hash`],
//! [`rand01`] of `glsl/shared/common.glsl`): at most 1 − 2⁻²⁴, with 24 bits.

/// Floats in the CDF header (as `cdf_reduce::CDF_HEADER` and `CDF_HEADER` in `cdf.glsl`).
pub const HEADER: usize = 4;

/// A weight as the CDF counts it: `x > 0 && x < 1e30 ? x : 0` (NaN, ±∞, negatives and ≥ 1e30 → 0).
pub fn sanitise(x: f32) -> f32 {
    if x > 0.0 && x < 1e30 {
        x
    } else {
        0.0
    }
}

/// The largest float below a positive `x` (`cdf_below`: the bits minus one).
pub fn below(x: f32) -> f32 {
    f32::from_bits(x.to_bits() - 1)
}

/// The CDF that `cdf_reduce` builds from `importance` (`rows × row_length` weights, row-major), in the
/// same layout and with the same float32 additions in the same order.
pub fn reduce(importance: &[f32], rows: u32, row_length: u32) -> Vec<f32> {
    let (n_rows, len) = (rows as usize, row_length as usize);
    assert_eq!(importance.len(), n_rows * len, "importance must hold rows × row_length weights");
    let mut cdf = vec![0.0f32; HEADER + n_rows + n_rows * len];
    // Stage CDF_ROWS: one row per invocation, each a running sum from the left.
    for r in 0..n_rows {
        let mut acc = 0.0f32;
        let base = HEADER + n_rows + r * len;
        for i in 0..len {
            acc += sanitise(importance[r * len + i]);
            cdf[base + i] = acc;
        }
        cdf[HEADER + r] = acc;
    }
    // Stage CDF_TOTALS: the row totals turned into their inclusive prefix, top to bottom.
    let mut acc = 0.0f32;
    for r in 0..n_rows {
        acc += cdf[HEADER + r];
        cdf[HEADER + r] = acc;
    }
    cdf[0] = acc;
    cdf[1] = f32::from_bits(rows);
    cdf[2] = f32::from_bits(row_length);
    cdf[3] = 0.0;
    cdf
}

/// The total weight (`cdf_total`).
pub fn total(cdf: &[f32]) -> f32 {
    cdf[0]
}

/// `(rows, row_length)` from the header.
pub fn shape(cdf: &[f32]) -> (u32, u32) {
    (cdf[1].to_bits(), cdf[2].to_bits())
}

/// GLSL `min(x, y)`: `y < x ? y : x`.
fn glsl_min(x: f32, y: f32) -> f32 {
    if y < x {
        y
    } else {
        x
    }
}

/// GLSL `max(x, y)`: `x < y ? y : x`.
fn glsl_max(x: f32, y: f32) -> f32 {
    if x < y {
        y
    } else {
        x
    }
}

/// `cdf_sample(u, prob)`: the texel drawn for `u` in [0, 1) and its probability `weight / total` (the
/// sanitised weight, read from `importance`, divided by the CDF's total). Same operations as the shader:
/// the target `u · total` clamped just below the total, the first row whose prefix exceeds it, the rest
/// clamped into [0, below(row total)], the first texel of that row whose in-row prefix exceeds the rest.
///
/// Panics when the total is not positive: the gather only samples when `cdf_total() > 0`.
pub fn sample(cdf: &[f32], importance: &[f32], u: f32) -> (u32, f32) {
    let t0 = total(cdf);
    assert!(t0 > 0.0, "cdf_sample is only called with a positive total (got {t0})");
    let (rows, len) = shape(cdf);
    let header = HEADER as u32;
    let at = |k: u32| cdf[k as usize];
    let target = glsl_min(u * t0, below(t0));
    let (mut lo, mut hi) = (0u32, rows - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if at(header + mid) > target {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    let r = lo;
    let before = if r > 0 { at(header + r - 1) } else { 0.0 };
    let base = header + rows + r * len;
    let t = glsl_min(glsl_max(target - before, 0.0), below(at(base + len - 1)));
    lo = 0;
    hi = len - 1;
    while lo < hi {
        let mid = (lo + hi) / 2;
        if at(base + mid) > t {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    let v = r * len + lo;
    (v, sanitise(importance[v as usize]) / t0)
}

/// `pcg_hash` of `glsl/shared/common.glsl` (the PCG RXS-M-XS output permutation of one LCG step).
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

/// `rand01` of `glsl/shared/common.glsl`: advances `state` by hashing and returns a float in [0, 1) with
/// 24 bits (so at most 1 − 2⁻²⁴, the largest float below 1).
pub fn rand01(state: &mut u32) -> f32 {
    *state = pcg_hash(*state);
    (*state >> 8) as f32 * (1.0 / 16777216.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The largest float below 1 (what `rand01` returns at most).
    const U_MAX: f32 = 1.0 - 1.0 / 16777216.0;

    /// The hand-computed case: rows [1, 0, 3], [0, 0, 0], [2, 0, 0].
    fn small() -> (Vec<f32>, Vec<f32>) {
        let w = vec![1.0, 0.0, 3.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0];
        let cdf = reduce(&w, 3, 3);
        (w, cdf)
    }

    #[test]
    fn reduce_lays_out_header_row_prefix_and_in_row_prefixes() {
        let (_, cdf) = small();
        assert_eq!(cdf.len(), 4 + 3 + 9);
        assert_eq!(cdf[0], 6.0);
        assert_eq!(shape(&cdf), (3, 3));
        assert_eq!(cdf[3], 0.0);
        assert_eq!(&cdf[4..7], &[4.0, 4.0, 6.0], "prefix over row totals 4, 0, 2");
        assert_eq!(&cdf[7..], &[1.0, 1.0, 4.0, 0.0, 0.0, 0.0, 2.0, 2.0, 2.0]);
    }

    #[test]
    fn sample_picks_the_hand_computed_texels() {
        let (w, cdf) = small();
        // u · 6 against the cumulative masses: texel 0 covers [0, 1), texel 2 [1, 4), texel 6 [4, 6).
        let cases = [
            (0.0, 0),
            (0.1666, 0), // 0.9996
            (0.1667, 2), // 1.0002
            (0.6666, 2), // 3.9996
            (0.6667, 6), // 4.0002: past the empty row 1
            (U_MAX, 6),  // just below 6
            (1.0, 6),    // outside the contract; clamped below the total, still a texel with mass
        ];
        for (u, want) in cases {
            let (v, p) = sample(&cdf, &w, u);
            assert_eq!(v, want, "u = {u}");
            assert_eq!(p, w[want as usize] / 6.0, "u = {u}");
        }
    }

    #[test]
    fn bad_weights_count_as_zero() {
        let w = [f32::NAN, -1.0, f32::INFINITY, 1e30, f32::NEG_INFINITY, 2.0, -0.0, 0.5];
        let cdf = reduce(&w, 2, 4);
        assert_eq!(cdf[0], 2.5);
        assert_eq!(&cdf[4..6], &[0.0, 2.5]);
        assert_eq!(&cdf[6..], &[0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 2.0, 2.5]);
        for k in 0..1000 {
            let (v, p) = sample(&cdf, &w, k as f32 / 1000.0);
            assert!(v == 5 || v == 7, "u = {k}/1000 drew texel {v}");
            assert!(p > 0.0);
        }
    }

    #[test]
    fn all_zero_weights_give_a_zero_total_and_finite_prefixes() {
        let cdf = reduce(&[0.0, f32::NAN, -3.0, 0.0, 0.0, 0.0], 2, 3);
        assert_eq!(cdf[0], 0.0);
        assert!(cdf.iter().enumerate().all(|(k, x)| k == 1 || k == 2 || *x == 0.0));
    }

    #[test]
    fn the_in_row_clamp_keeps_the_draw_off_trailing_zero_texels() {
        // Row totals a and b whose float sum exceeds a by more than b: the target just below the total
        // leaves a rest t = b, which no in-row prefix exceeds. Without the clamp below b the search would
        // end on the row's last texel, which has no weight.
        let (a, b) = (1.6768258e-3f32, 3.204143e-2f32);
        let w = [a, 0.0, 0.0, b, 0.0, 0.0];
        let cdf = reduce(&w, 2, 3);
        let target = U_MAX * cdf[0];
        assert_eq!(target, below(cdf[0]));
        assert!(target - cdf[4] >= b, "the case must reach the clamp");
        assert_eq!(sample(&cdf, &w, U_MAX), (3, b / cdf[0]));
    }

    #[test]
    fn zero_runs_are_never_drawn() {
        let mut w = vec![0.0f32; 16 * 16];
        for (k, x) in w.iter_mut().enumerate() {
            if k % 37 == 5 || k == 255 {
                *x = 1.0 + (k % 5) as f32;
            }
        }
        let cdf = reduce(&w, 16, 16);
        let mut state = 7u32;
        for _ in 0..20000 {
            let (v, p) = sample(&cdf, &w, rand01(&mut state));
            assert!(w[v as usize] > 0.0 && p > 0.0);
        }
        // u = 0 draws the first texel with mass, u just below 1 the last.
        assert_eq!(sample(&cdf, &w, 0.0).0, 5);
        assert_eq!(sample(&cdf, &w, U_MAX).0, 255);
    }

    #[test]
    fn pcg_matches_values_computed_independently() {
        // pcg_hash evaluated with Python's unbounded integers masked to 32 bits.
        assert_eq!([pcg_hash(0), pcg_hash(1), pcg_hash(12345)], [129708002, 2831084092, 4099845390]);
        let mut s = 0u32;
        assert_eq!(rand01(&mut s), (129708002u32 >> 8) as f32 / 16777216.0);
        assert_eq!(s, 129708002);
    }
}
