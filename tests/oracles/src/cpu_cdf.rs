//! The CPU twin of the two-level CDF: [`reduce`] / [`reduce_sections`] mirror `glsl/cdf_reduce.comp`;
//! [`sample_rows`], [`prob_rows`] and [`sample`] mirror `cdf_sample_rows`, `cdf_prob_rows` and
//! `cdf_sample` of `glsl/shared/cdf.glsl`. Used by the tests (`tests/tests/cdf.rs`).
//!
//! **Why a twin and not an independent formula.** The GPU adds in float32, in a fixed order; the twin
//! does the same float32 operations in the same order (each row left to right, then the row totals top
//! to bottom), so its CDF equals the shader's bit for bit wherever the device rounds as IEEE 754 requires
//! (Vulkan: additions and multiplications correctly rounded). The sampling twin makes the same
//! comparisons, clamps and binary searches, so for the same `u` it returns the same texel. What a twin
//! cannot establish is that the method itself is right; that is checked separately: hand-computed cases
//! here, [`u_grid_counts`] (the exact distribution of the draws under the gather's 24-bit `u`) against
//! [`prob_rows`], and chi-square fits against weight / total on the GPU in `tests/tests/cdf.rs`.
//!
//! Layout (see `crates/graph/src/passes/cdf_reduce.rs`): sections one after the other, each
//! [`section_len`] floats: `[total, rows (u32 bits), row_length (u32 bits), 0]`, then the inclusive
//! prefix over row totals (`rows` floats), then each row's inclusive prefix (`rows × row_length`
//! floats). Weights are sanitised as in the shader: `x > 0 && x < 1e30 ? x : 0`, so negative, NaN and
//! infinite weights (and finite ones ≥ 1e30) count as 0.
//!
//! **Resolution.** A draw is one `u` with 24 bits mapped through float prefixes, so a texel's actual
//! probability is resolved only to about one u step (2⁻²⁴) plus one float step of the target
//! (ulp(end) / range, where `end` is the prefix at the range's last row): [`u_grid_counts`] and
//! [`prob_rows`] agree to within two such steps per texel (unit test below), not relatively. Texels
//! lighter than that are drawn with a quantised probability, or never.
//!
//! The stream of random numbers the CDF tests feed to the sampling is mirrored too ([`pcg_hash`],
//! [`rand01`] of `glsl/shared/common.glsl`): at most 1 − 2⁻²⁴, with 24 bits, as the gather's stratified
//! points (`glsl/shared/owen_sobol.glsl`).

/// Floats in the CDF header (`CDF_HEADER` of `glsl/shared/bindings.glsl`).
pub const HEADER: usize = bounce_scene::bindings::CDF_HEADER as usize;

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
    // Stage CDF_TOTALS: the row totals turned into their inclusive prefix, restarting at each face (every
    // `row_length` rows); the total is the sum of the face totals in face order.
    let (mut acc, mut total) = (0.0f32, 0.0f32);
    for r in 0..n_rows {
        if r % len == 0 {
            total += acc;
            acc = 0.0;
        }
        acc += cdf[HEADER + r];
        cdf[HEADER + r] = acc;
    }
    total += acc;
    cdf[0] = total;
    cdf[1] = f32::from_bits(rows);
    cdf[2] = f32::from_bits(row_length);
    cdf[3] = 0.0;
    cdf
}

/// Floats per CDF section (`CdfReduce::section_len`).
pub fn section_len(rows: u32, row_length: u32) -> usize {
    HEADER + rows as usize + rows as usize * row_length as usize
}

/// `cdf_reduce` over `sections` importance arrays of `rows × row_length` weights laid one after the
/// other: section s's CDF starts at float s · [`section_len`].
pub fn reduce_sections(importance: &[f32], rows: u32, row_length: u32, sections: u32) -> Vec<f32> {
    let texels = rows as usize * row_length as usize;
    assert!(texels > 0);
    assert_eq!(importance.len(), texels * sections as usize, "importance must hold sections × rows × row_length");
    importance.chunks_exact(texels).flat_map(|w| reduce(w, rows, row_length)).collect()
}

/// The total weight of the section at `cb` (`cdf_total_at`).
pub fn total_at(cdf: &[f32], cb: usize) -> f32 {
    cdf[cb]
}

/// The total weight of section 0 (`cdf_total`).
pub fn total(cdf: &[f32]) -> f32 {
    cdf[0]
}

/// `(rows, row_length)` from the header of the section at `cb`.
pub fn shape_at(cdf: &[f32], cb: usize) -> (u32, u32) {
    (cdf[cb + 1].to_bits(), cdf[cb + 2].to_bits())
}

/// `(rows, row_length)` of section 0.
pub fn shape(cdf: &[f32]) -> (u32, u32) {
    shape_at(cdf, 0)
}

/// `cdf_face_total`: the total of face f (its last row's in-face prefix).
pub fn face_total(cdf: &[f32], cb: usize, f: u32) -> f32 {
    let (rows, len) = shape_at(cdf, cb);
    cdf[cb + HEADER + ((f + 1) * len).min(rows) as usize - 1]
}

/// `cdf_row_start`: the in-face prefix before row r (0 at a face's first row).
pub fn row_start(cdf: &[f32], cb: usize, r: u32) -> f32 {
    let (_, len) = shape_at(cdf, cb);
    if r.is_multiple_of(len) {
        0.0
    } else {
        cdf[cb + HEADER + r as usize - 1]
    }
}

/// `cdf_rows_total`: the weight of rows [r0, r1), inside one face or over whole faces (summed in face
/// order).
pub fn rows_total(cdf: &[f32], cb: usize, r0: u32, r1: u32) -> f32 {
    let (_, len) = shape_at(cdf, cb);
    let (f0, f1) = (r0 / len, (r1 - 1) / len);
    if f0 == f1 {
        return cdf[cb + HEADER + r1 as usize - 1] - row_start(cdf, cb, r0);
    }
    (f0..=f1).fold(0.0f32, |t, f| t + face_total(cdf, cb, f))
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

/// The rows [a, b) of the face [`sample_rows3`] draws for `u` (the whole range when it lies in one face).
pub fn sample_face(cdf: &[f32], cb: usize, u: f32, r0: u32, r1: u32) -> (u32, u32) {
    let (rows, len) = shape_at(cdf, cb);
    assert!(r0 < r1 && r1 <= rows, "rows [{r0}, {r1}) of {rows}");
    let (f0, f1) = (r0 / len, (r1 - 1) / len);
    if f0 == f1 {
        return (r0, r1);
    }
    let t = rows_total(cdf, cb, r0, r1);
    let target = glsl_min(u * t, below(t));
    let mut cum = 0.0f32;
    let mut f = f1;
    for k in f0..=f1 {
        cum += face_total(cdf, cb, k);
        if cum > target {
            f = k;
            break;
        }
    }
    (f * len, ((f + 1) * len).min(rows))
}

/// The row inside rows [a, b) of one face that [`sample_rows3`] draws for `u`.
pub fn sample_row_in(cdf: &[f32], cb: usize, u: f32, a: u32, b: u32) -> u32 {
    let before0 = row_start(cdf, cb, a);
    let end = cdf[cb + HEADER + b as usize - 1];
    assert!(end - before0 > 0.0, "cdf_sample_rows is only called on rows with weight");
    let mut target = glsl_min(before0 + u * (end - before0), below(end));
    target = glsl_max(target, before0);
    let (mut lo, mut hi) = (a, b - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if cdf[cb + HEADER + mid as usize] > target {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    lo
}

/// The texel within row `r` that [`sample_rows3`] draws for `u`.
pub fn sample_in_row(cdf: &[f32], cb: usize, r: u32, u: f32) -> u32 {
    let (rows, len) = shape_at(cdf, cb);
    let base = cb + HEADER + (rows + r * len) as usize;
    let last = cdf[base + len as usize - 1];
    let t = glsl_min(u * last, below(last));
    let (mut lo, mut hi) = (0, len - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if cdf[base + mid as usize] > t {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    lo
}

/// `cdf_sample_rows3_prob(cb, ib, u, r0, r1, prob)`: the texel (index within the section) drawn among rows [r0, r1)
/// of the section at `cb` for the three uniforms `u` (face, row in face, texel in row). The shader's
/// `ib` is not read.
///
/// Panics when rows [r0, r1) have no weight: the gather only samples ranges whose total is > 0.
pub fn sample_rows3(cdf: &[f32], cb: usize, u: [f32; 3], r0: u32, r1: u32) -> u32 {
    let (_, len) = shape_at(cdf, cb);
    // One face: u[0] picks the row and u[1] the texel. Several: u[0] the face, u[1] the row, u[2] the texel.
    let multi = r0 / len != (r1 - 1) / len;
    let (a, b) = sample_face(cdf, cb, u[0], r0, r1);
    let (ur, ut) = if multi { (u[1], u[2]) } else { (u[0], u[1]) };
    let r = sample_row_in(cdf, cb, ur, a, b);
    r * len + sample_in_row(cdf, cb, r, ut)
}

/// `cdf_uniforms(u)`: the three uniforms the single-u entry points derive from one.
pub fn uniforms(u: f32) -> [f32; 3] {
    let h1 = pcg_hash(u.to_bits() ^ 0x9E37_79B9);
    let h2 = pcg_hash(h1 ^ 0x85EB_CA6B);
    [u, (h1 >> 8) as f32 * (1.0 / 16777216.0), (h2 >> 8) as f32 * (1.0 / 16777216.0)]
}

/// The second derived uniform (the texel's, inside one face).
pub fn second_uniform(u: f32) -> f32 {
    uniforms(u)[1]
}

/// `cdf_sample_rows(cb, ib, u, r0, r1)`: [`sample_rows3`] with the derived uniforms.
pub fn sample_rows(cdf: &[f32], cb: usize, u: f32, r0: u32, r1: u32) -> u32 {
    sample_rows3(cdf, cb, uniforms(u), r0, r1)
}

/// `cdf_prob_rows(cb, v, r0, r1)`: the probability the shader assigns to [`sample_rows3`] drawing texel
/// `v` among rows [r0, r1): (C_f − C_{f−1})/C · Δ_r/range · (p_i − p_{i−1})/P, from the floats (same
/// operations and order as the shader).
// `!(x > 0.0)` as in the shader: NaN counts as "no weight".
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn prob_rows(cdf: &[f32], cb: usize, v: u32, r0: u32, r1: u32) -> f32 {
    let (rows, len) = shape_at(cdf, cb);
    let (r, i) = (v / len, v % len);
    if r < r0 || r >= r1 {
        return 0.0;
    }
    let (f0, f1, f) = (r0 / len, (r1 - 1) / len, r / len);
    let (mut p_face, mut a, mut b) = (1.0f32, r0, r1);
    if f0 != f1 {
        let t = rows_total(cdf, cb, r0, r1);
        if !(t > 0.0) {
            return 0.0;
        }
        let (mut cum, mut before) = (0.0f32, 0.0f32);
        for k in f0..=f {
            before = cum;
            cum += face_total(cdf, cb, k);
        }
        p_face = (cum - before) / t;
        a = f * len;
        b = ((f + 1) * len).min(rows);
    }
    let range = cdf[cb + HEADER + b as usize - 1] - row_start(cdf, cb, a);
    let delta = cdf[cb + HEADER + r as usize] - row_start(cdf, cb, r);
    if !(range > 0.0) || !(delta > 0.0) {
        return 0.0;
    }
    let base = cb + HEADER + (rows + r * len) as usize;
    let last = cdf[base + len as usize - 1];
    if !(last > 0.0) {
        return 0.0;
    }
    let hi = cdf[base + i as usize];
    let lo = if i > 0 { cdf[base + i as usize - 1] } else { 0.0 };
    p_face * (delta / range) * (glsl_max(hi - lo, 0.0) / last)
}

/// `cdf_sample(u, prob)`: [`sample_rows`] over every row of section 0, and the texel's probability as
/// the shader gives it, its sanitised weight (read from `importance`) over the total.
///
/// Panics when the total is not positive: the gather only samples when `cdf_total() > 0`.
pub fn sample(cdf: &[f32], importance: &[f32], u: f32) -> (u32, f32) {
    let t0 = total(cdf);
    assert!(t0 > 0.0, "cdf_sample is only called with a positive total (got {t0})");
    let (rows, _) = shape(cdf);
    let v = sample_rows(cdf, 0, u, 0, rows);
    (v, sanitise(importance[v as usize]) / t0)
}

/// How many of the 2²⁴ values `k / 2²⁴` (what [`rand01`] can return) make `draw` give each index below
/// `n`. The draw is monotone in u, so each index's values form one run, found by binary search.
fn grid_counts(n: usize, draw: impl Fn(f32) -> u32) -> Vec<u32> {
    const N: u32 = 1 << 24;
    let mut counts = vec![0u32; n];
    let at = |k: u32| draw(k as f32 / N as f32);
    let mut k = 0u32;
    while k < N {
        let v = at(k);
        let (mut lo, mut hi) = (k, N - 1);
        while lo < hi {
            let mid = lo + (hi - lo).div_ceil(2);
            if at(mid) == v {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        counts[v as usize] += lo - k + 1;
        k = lo + 1;
    }
    counts
}

/// The exact distribution of [`sample_rows3`] (rows [r0, r1) of the section at `cb`) under three
/// independent 24-bit uniforms: per texel, P(face) · P(row | face) · P(texel | row), each counted over
/// the 2²⁴ values its uniform can take.
pub fn u_grid_probs(cdf: &[f32], cb: usize, r0: u32, r1: u32) -> Vec<f64> {
    const N: f64 = 16777216.0;
    let (rows, len) = shape_at(cdf, cb);
    let faces = rows.div_ceil(len) as usize;
    let face_counts = grid_counts(faces, |u| sample_face(cdf, cb, u, r0, r1).0 / len);
    let mut probs = vec![0.0f64; rows as usize * len as usize];
    for (f, &fc) in face_counts.iter().enumerate() {
        if fc == 0 {
            continue;
        }
        let (a, b) = sample_face(cdf, cb, 0.0, r0, r1);
        let (a, b) =
            if (r0 / len) == ((r1 - 1) / len) { (a, b) } else { (f as u32 * len, ((f as u32 + 1) * len).min(rows)) };
        let row_counts = grid_counts(rows as usize, |u| sample_row_in(cdf, cb, u, a, b));
        for (r, &rc) in row_counts.iter().enumerate() {
            if rc == 0 {
                continue;
            }
            let texel_counts = grid_counts(len as usize, |u| sample_in_row(cdf, cb, r as u32, u));
            for (i, &tc) in texel_counts.iter().enumerate() {
                probs[r * len as usize + i] = (fc as f64 / N) * (rc as f64 / N) * (tc as f64 / N);
            }
        }
    }
    probs
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
        // Rows: u · 6 against the row totals: row 0 (texels 0 and 2, weights 1 and 3) covers [0, 4), the
        // empty row 1 nothing, row 2 (texel 6) [4, 6). Within row 0 the second uniform u2 picks texel 0
        // for u2 · 4 < 1, else texel 2.
        let row0 = |u: f32| if second_uniform(u) * 4.0 < 1.0 { 0 } else { 2 };
        let cases = [
            (0.0, row0(0.0)),
            (0.3, row0(0.3)),
            (0.6666, row0(0.6666)), // 3.9996
            (0.6667, 6),            // 4.0002: past the empty row 1
            (U_MAX, 6),             // just below 6
            (1.0, 6),               // outside the contract; clamped below the total, still a texel with mass
        ];
        // Both texels of row 0 occur among the cases' neighbours (the test would not notice a texel
        // choice that ignored u2 otherwise).
        let seen: std::collections::BTreeSet<u32> = (0..64).map(|k| row0(k as f32 / 100.0)).collect();
        assert_eq!(seen.len(), 2);
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
    fn sample_rows_and_prob_rows_on_row_ranges() {
        let (w, cdf) = small();
        // Rows [0, 1): texel 0 for u2 · 4 < 1, texel 2 above; rows [1, 3): only texel 6 has weight.
        assert_eq!(sample_rows3(&cdf, 0, [0.5, 0.0, 0.0], 0, 1), 0);
        assert_eq!(sample_rows3(&cdf, 0, [0.5, 0.2499, 0.0], 0, 1), 0);
        assert_eq!(sample_rows3(&cdf, 0, [0.5, 0.2501, 0.0], 0, 1), 2);
        assert_eq!(sample_rows3(&cdf, 0, [0.5, U_MAX, 0.0], 0, 1), 2);
        // Over rows [0, 3) (totals 4, 0, 2): u picks row 0 below 4/6, row 2 above.
        assert_eq!(sample_rows3(&cdf, 0, [0.66, 0.9, 0.0], 0, 3), 2);
        assert_eq!(sample_rows3(&cdf, 0, [0.67, 0.0, 0.0], 0, 3), 6);
        for u in [0.0, 0.3, U_MAX, 1.0] {
            assert_eq!(sample_rows(&cdf, 0, u, 1, 3), 6);
            assert_eq!(sample_rows(&cdf, 0, u, 2, 3), 6);
        }
        assert_eq!(rows_total(&cdf, 0, 1, 2), 0.0);
        assert_eq!(rows_total(&cdf, 0, 0, 3), 6.0);
        let p = |v, r0, r1| prob_rows(&cdf, 0, v, r0, r1);
        assert_eq!([p(0, 0, 1), p(1, 0, 1), p(2, 0, 1), p(6, 0, 1)], [0.25, 0.0, 0.75, 0.0]);
        assert_eq!([p(0, 0, 3), p(2, 0, 3), p(6, 0, 3), p(3, 0, 3)], [1.0 / 6.0, 0.5, 2.0 / 6.0, 0.0]);
        assert_eq!([p(6, 1, 3), p(0, 1, 3), p(4, 1, 3), p(4, 1, 2)], [1.0, 0.0, 0.0, 0.0]);
        // Two sections: the second's CDF starts at section_len.
        let w2: Vec<f32> = w.iter().chain(&[0.0, 0.0, 0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 0.0]).copied().collect();
        let cdf2 = reduce_sections(&w2, 3, 3, 2);
        let cb = section_len(3, 3);
        assert_eq!(&cdf2[..cb], &cdf[..]);
        assert_eq!(total_at(&cdf2, cb), 5.0);
        assert_eq!(sample_rows3(&cdf2, cb, [0.7, 0.7, 0.0], 0, 3), 4);
        assert_eq!(prob_rows(&cdf2, cb, 4, 0, 3), 1.0);
    }

    /// Two 64² faces, face 0 `ratio` times heavier, with zero runs; a jitter so that prefixes round.
    fn two_faces(ratio: f32) -> (Vec<f32>, Vec<f32>) {
        let res = 64usize;
        let w: Vec<f32> = (0..2 * res * res)
            .map(|v| {
                let (face, y, x) = (v / (res * res), (v / res) % res, v % res);
                if y % 16 == 3 || (x / 5) % 4 == 1 {
                    return 0.0;
                }
                let jitter = 1.0 + (v.wrapping_mul(2654435761) % 1000) as f32 / 1000.0;
                jitter * if face == 0 { ratio } else { 1.0 }
            })
            .collect();
        let cdf = reduce(&w, 2 * res as u32, res as u32);
        (w, cdf)
    }

    #[test]
    fn prob_rows_is_the_u_grid_distribution_to_within_two_steps() {
        // prob_rows must give what sample_rows3 actually does under independent 24-bit uniforms, per
        // texel, to within the resolution of each level: 2⁻²⁴ (one uniform) plus a few ulps of its total.
        // With the prefix restarted per face, even a face 10⁵ times lighter than the other is resolved.
        for ratio in [1.0, 10.0, 1e3, 1e5] {
            let (w, cdf) = two_faces(ratio);
            for (r0, r1) in [(0, 64), (64, 128), (0, 128)] {
                let probs = u_grid_probs(&cdf, 0, r0, r1);
                assert!((probs.iter().sum::<f64>() - 1.0).abs() < 1e-6);
                let levels = if r0 / 64 == (r1 - 1) / 64 { 2.0 } else { 3.0 };
                let step = levels * (1.0 / 16777216.0 + 4.0 * f32::EPSILON as f64);
                let mut sum = 0.0f64;
                for (v, &q) in probs.iter().enumerate() {
                    let p = prob_rows(&cdf, 0, v as u32, r0, r1) as f64;
                    sum += p;
                    assert!(
                        // Each factor is off by at most one level's step, absolutely; factors are ≤ 1.
                        (q - p).abs() <= 2.0 * step,
                        "ratio {ratio}, rows [{r0}, {r1}), texel {v}: drawn {q:e}, prob_rows {p:e}"
                    );
                    if sanitise(w[v]) == 0.0 {
                        assert!(q == 0.0 && p == 0.0, "texel {v} has no weight");
                    }
                }
                assert!((sum - 1.0).abs() < 1e-5, "ratio {ratio}, rows [{r0}, {r1}): prob_rows sums to {sum}");
            }
        }
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
