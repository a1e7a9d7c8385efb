//! The two-level CDF: `cdf_reduce` (`crates/graph/src/passes/cdf_reduce.rs`, `glsl/cdf_reduce.comp`) and
//! the sampling of `glsl/shared/cdf.glsl` (`cdf_sample`, `cdf_sample_rows`, `cdf_prob_rows`, run here
//! through the test kernel `glsl/test/cdf_sample.comp`), against the CPU twin
//! `tests/oracles/src/cpu_cdf.rs` and against the distribution they must produce.
//!
//! - **Reduce vs twin.** The real pass, run through a `Graph` as the frame runs it, equals the CPU twin
//!   bit for bit on integer weights (which are also checked against exact integer sums) for one row,
//!   many rows, empty rows, a single texel with weight at the very end, several sections, and the
//!   largest shape, 2 × 1024² texels. On float weights spanning six orders of magnitude it must agree
//!   within [`FLOAT_ULPS`]; NaN, ±∞, negative and ≥ 1e30 weights count as 0. All-zero weights give a
//!   total of 0 and no NaN.
//! - **Sampling vs twin.** u = 0, the largest float below 1, 1 itself, runs of zero-weight texels (never
//!   drawn), a single texel with weight, the in-row clamp (a rest equal to the row's total), prob =
//!   weight / total for `cdf_sample`; `cdf_sample_rows` on sections and row ranges (faces, one row)
//!   draws the twin's texel and `cdf_prob_rows` gives the twin's probability, which is 0 outside the
//!   range and on texels without weight and sums to 1 over the range. (That `cdf_prob_rows` is the
//!   actual distribution of the draws is checked on the CPU, exhaustively over the 2²⁴ values of u, in
//!   cpu_cdf's unit tests.)
//! - **Distribution.** Pearson's chi-square of the drawn texels against weight / total, at p = 0.001
//!   ([`chi2_critical`], Wilson–Hilferty), on 64 bins × 200,000 draws and on 2 × 1024² texels grouped
//!   into 256 index ranges and 256 column ranges × 2²¹ draws, and for one face of it alone
//!   (`cdf_sample_rows` on rows [1024, 2048)). The same draws against a uniform expectation must fail by
//!   far, so a sampler that ignores the weights cannot pass.
//!
//! The random numbers are `rand01` of a PCG hash of the draw's counter (fixed seed), at most 1 − 2⁻²⁴:
//! independent draws, so the χ² test applies (the gather's own points are stratified, 24 bits too). Each
//! kernel invocation makes one draw (two binary searches), far below llvmpipe's loop limit; cdf_reduce
//! loops at most max(rows, row_length) = 2048 times per invocation.

use bounce_device::sync::Access;
use bounce_device::{vk, Binding, Buffer, BufferDesc, ComputePipeline, DescriptorWrites, Gpu};
use bounce_graph::bindings::{B_CDF, B_IMPORTANCE, WG_1D};
use bounce_graph::graph::{Graph, Persistent};
use bounce_graph::passes::cdf_reduce::CdfReduce;
use bounce_oracles::cpu_cdf::{self, pcg_hash, rand01, sanitise};
use bounce_tests::Rng;
use bounce_tests::TestGpu;
use std::time::Instant;

/// Test-only bindings of `glsl/test/cdf_sample.comp`.
const T_US: u32 = bounce_graph::bindings::B_TEST_IN;
const T_RESULTS: u32 = bounce_graph::bindings::B_TEST_OUT;
/// The largest float below 1: the most `rand01` returns.
const U_MAX: f32 = 1.0 - 1.0 / 16777216.0;
/// Draws per dispatch of `cdf_sample.comp` (a large batch is split over several dispatches).
const PER_DISPATCH: u32 = 1 << 20;
/// The largest shape the renderer builds for one light: 2 faces × 1024 rows of 1024 texels.
const BIG: Shape = Shape { rows: 2048, len: 1024, sections: 1 };
/// How far (in units in the last place) the GPU's CDF of float weights may be from the twin's. Vulkan
/// requires float additions to be correctly rounded, and the shader and the twin add the same terms in
/// the same order, so a conforming device gives the same bits (lavapipe: 0 ulp, see the test). The
/// slack of 4 ulp (≈ 2.4e-7 relative) is for a driver that rounds an isolated step differently; a
/// wrong order, a skipped or doubled term of comparable size, or a sum over the wrong row is far outside.
const FLOAT_ULPS: u32 = 4;
/// How far the GPU's probability may be from the twin's: `cdf_sample`'s weight / total is one division,
/// for which Vulkan allows 2.5 ulp; `cdf_prob_rows` is Δ / range · mass / Δ, two divisions and a product
/// (2 · 2.5 + 0.5 ulp, rounded up).
const PROB_ULPS: u32 = 3;
const PROB_ROWS_ULPS: u32 = 6;

/// The gather's random numbers: draw `k` of stream `seed`, as `gather.comp` makes them.
fn us(seed: u32, n: u32) -> Vec<f32> {
    (0..n)
        .map(|k| {
            let mut s = pcg_hash(seed ^ pcg_hash(k.wrapping_add(0x9E37_79B9)));
            rand01(&mut s)
        })
        .collect()
}

/// The pipelines under test: the real cdf_reduce pass and the sampling kernel.
struct Kernels {
    reduce: CdfReduce,
    sample: ComputePipeline,
}

impl Kernels {
    fn new(gpu: &Gpu) -> Kernels {
        let bindings = [
            Binding::storage_buffer(B_IMPORTANCE),
            Binding::uniform_texel_buffer(B_CDF),
            Binding::storage_buffer(T_US),
            Binding::storage_buffer(T_RESULTS),
        ];
        let sample = ComputePipeline::new(
            gpu,
            "cdf_sample",
            &bounce_graph::spirv(bounce_graph::shaders::CDF_SAMPLE_COMP),
            &bindings,
            32,
            &[],
        )
        .unwrap();
        Kernels { reduce: CdfReduce::new(gpu).unwrap(), sample }
    }
}

/// What `cdf_sample.comp` computes (its `pc.mode`).
#[derive(Clone, Copy, Debug)]
enum Op {
    /// `cdf_sample(u)` over section 0: (texel, weight / total) per u.
    Sample,
    /// `cdf_sample_rows` on rows [r0, r1) of a section: (texel, `cdf_prob_rows` of it) per u.
    Rows { section: u32, r0: u32, r1: u32 },
    /// `cdf_prob_rows` of every texel of a section for rows [r0, r1): (texel, probability) per texel.
    Probs { section: u32, r0: u32, r1: u32 },
    /// `cdf_sample_rows3_prob`, as `Rows` draws: (texel, the probability the draw gives with it).
    Drawn { section: u32, r0: u32, r1: u32 },
}

/// The CDF's shape: `sections` arrays of `rows × len` weights.
#[derive(Clone, Copy, Debug)]
struct Shape {
    rows: u32,
    len: u32,
    sections: u32,
}

const fn shape(rows: u32, len: u32) -> Shape {
    Shape { rows, len, sections: 1 }
}

/// What one GPU run gives back.
struct Run {
    cdf: Vec<f32>,
    /// Per op: (texel, probability) per u (per texel for [`Op::Probs`]).
    results: Vec<Vec<(u32, f32)>>,
}

/// Uploads `weights`, runs cdf_reduce through a graph as the frame does, then each op of `ops` with its
/// u values as a pass of `cdf_sample.comp` after it (split into dispatches of [`PER_DISPATCH`]).
fn run(gpu: &Gpu, k: &Kernels, weights: &[f32], s: Shape, ops: &[(Op, &[f32])]) -> Run {
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let texels = s.rows * s.len;
    assert_eq!(weights.len(), (texels * s.sections) as usize);
    let imp = Persistent::ready(Buffer::with_data(gpu, "importance", storage, bytemuck::cast_slice(weights)).unwrap());
    let ubs: Vec<Persistent<Buffer>> = ops
        .iter()
        .map(|(_, us)| {
            Persistent::ready(Buffer::with_data(gpu, "cdf test u", storage, bytemuck::cast_slice(us)).unwrap())
        })
        .collect();
    let section_len = CdfReduce::section_len(s.rows, s.len) as u32;
    let mut g = Graph::new(gpu);
    let hi = g.import_buffer(&imp);
    let cdf = k.reduce.add(&mut g, &hi, s.rows, s.len, s.sections);
    g.export(&cdf);
    let mut outs = vec![];
    for ((op, us), ub) in ops.iter().zip(&ubs) {
        let (mode, section, r0, r1, n) = match *op {
            Op::Sample => (0u32, 0, 0, 0, us.len() as u32),
            Op::Rows { section, r0, r1 } => (1, section, r0, r1, us.len() as u32),
            Op::Probs { section, r0, r1 } => (2, section, r0, r1, texels),
            Op::Drawn { section, r0, r1 } => (3, section, r0, r1, us.len() as u32),
        };
        let push = [0, 0, mode, section * section_len, section * texels, r0, r1, 0u32];
        let hu = g.import_buffer(ub);
        let mut out = g.create_buffer(BufferDesc::storage("cdf test results", 8 * n as u64));
        let (ho, pipeline) = (out, &k.sample);
        g.add_pass("cdf_sample")
            .read(&hi, Access::ComputeRead)
            .read(&cdf, Access::ComputeRead)
            .read(&hu, Access::ComputeRead)
            .overwrite(&mut out, Access::ComputeWrite)
            .record(move |ctx| {
                let w = DescriptorWrites::new()
                    .storage_buffer(B_IMPORTANCE, ctx.buffer(&hi))
                    .texel_view(B_CDF, ctx.buffer(&cdf))
                    .storage_buffer(T_US, ctx.buffer(&hu))
                    .storage_buffer(T_RESULTS, ctx.buffer(&ho));
                let mut first = 0;
                while first < n {
                    let count = (n - first).min(PER_DISPATCH);
                    let mut p = push;
                    (p[0], p[1]) = (first, count);
                    pipeline.dispatch(ctx.cmd, &w, bytemuck::cast_slice(&p), [count, 1, 1], [WG_1D, 1, 1]);
                    first += count;
                }
            });
        g.export(&out);
        outs.push(out);
    }
    let done = g.execute().unwrap();
    let cdf: Vec<f32> = bytemuck::pod_collect_to_vec(&done.read_buffer(&cdf).unwrap());
    let results = outs
        .iter()
        .map(|o| {
            bytemuck::pod_collect_to_vec::<u8, [u32; 2]>(&done.read_buffer(o).unwrap())
                .into_iter()
                .map(|[v, p]| (v, f32::from_bits(p)))
                .collect()
        })
        .collect();
    Run { cdf, results }
}

/// Runs cdf_reduce alone and returns the CDF.
fn reduce_on_gpu(gpu: &Gpu, k: &Kernels, weights: &[f32], s: Shape) -> Vec<f32> {
    run(gpu, k, weights, s, &[]).cdf
}

/// Distance in units in the last place between two non-negative finite floats.
fn ulps(a: f32, b: f32) -> u32 {
    assert!(a >= 0.0 && b >= 0.0 && a.is_finite() && b.is_finite(), "{a} vs {b}");
    a.to_bits().abs_diff(b.to_bits())
}

/// The GPU's CDF equals the twin's, bit for bit (header included).
fn assert_bits_equal(what: &str, gpu: &[f32], cpu: &[f32]) {
    assert_eq!(gpu.len(), cpu.len(), "{what}: CDF length");
    if let Some(k) = (0..cpu.len()).find(|&k| gpu[k].to_bits() != cpu[k].to_bits()) {
        let n = (0..cpu.len()).filter(|&k| gpu[k].to_bits() != cpu[k].to_bits()).count();
        panic!("{what}: {n} floats differ, the first at {k}: GPU {} vs CPU {}", gpu[k], cpu[k]);
    }
}

/// Integer weights: the CDF must be exact, so the twin is also checked against integer sums (valid while
/// every partial sum stays below 2²⁴, which the callers keep).
fn assert_exact_integer_sums(what: &str, w: &[f32], rows: u32, len: u32, cdf: &[f32]) {
    let (rows, len) = (rows as usize, len as usize);
    // The prefix over row totals restarts at each face (every `len` rows); the total sums the faces.
    let (mut in_face, mut total) = (0u64, 0u64);
    for r in 0..rows {
        if r % len == 0 {
            total += in_face;
            in_face = 0;
        }
        let mut acc = 0u64;
        for i in 0..len {
            acc += sanitise(w[r * len + i]) as u64;
            assert_eq!(cdf[4 + rows + r * len + i] as u64, acc, "{what}: row {r} prefix at {i}");
        }
        in_face += acc;
        assert_eq!(cdf[4 + r] as u64, in_face, "{what}: in-face prefix over rows at {r}");
    }
    total += in_face;
    assert!(total < 1 << 24);
    assert_eq!(cdf[0] as u64, total, "{what}: total");
}

#[test]
fn reduce_equals_the_twin_bit_for_bit_on_integer_weights() {
    let gpu = TestGpu::new();
    let k = Kernels::new(&gpu);
    let mut rng = Rng(0x5EED_0001);
    let mut cases: Vec<(&str, Shape, Vec<f32>)> = vec![];
    let random = |rng: &mut Rng, n: u32, max: u32| (0..n).map(|_| rng.below(max + 1) as f32).collect::<Vec<_>>();
    cases.push(("one texel", shape(1, 1), vec![5.0]));
    cases.push(("one row", shape(1, 1000), random(&mut rng, 1000, 9)));
    cases.push(("many short rows", shape(300, 7), random(&mut rng, 2100, 9)));
    // Rows of zeros: the first, the last, and every third one in between.
    let mut w = random(&mut rng, 64 * 33, 9);
    for r in (0..64).filter(|r| r % 3 == 0 || *r == 63) {
        w[r * 33..(r + 1) * 33].fill(0.0);
    }
    cases.push(("zero rows", shape(64, 33), w));
    let mut w = vec![0.0; 50 * 40];
    *w.last_mut().unwrap() = 3.0;
    cases.push(("one texel at the very end", shape(50, 40), w));
    // Three sections, the middle one empty.
    let mut w = random(&mut rng, 3 * 20 * 30, 9);
    w[600..1200].fill(0.0);
    cases.push(("three sections", Shape { rows: 20, len: 30, sections: 3 }, w));
    // The full shape; weights 0..=7 keep the total (≈ 7.3e6) below 2²⁴, so every sum is exact.
    cases.push(("2 x 1024^2", BIG, random(&mut rng, BIG.rows * BIG.len, 7)));
    for (what, s, w) in &cases {
        let t = Instant::now();
        let got = reduce_on_gpu(&gpu, &k, w, *s);
        let want = cpu_cdf::reduce_sections(w, s.rows, s.len, s.sections);
        let (n, texels) = (cpu_cdf::section_len(s.rows, s.len), (s.rows * s.len) as usize);
        for sec in 0..s.sections as usize {
            let ws = &w[sec * texels..(sec + 1) * texels];
            assert_exact_integer_sums(what, ws, s.rows, s.len, &want[sec * n..(sec + 1) * n]);
        }
        assert_bits_equal(what, &got, &want);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        eprintln!("{what} ({} x {} x {}): bit-identical, total {}, {ms:.0} ms", s.sections, s.rows, s.len, want[0]);
    }
}

#[test]
fn reduce_matches_the_twin_on_float_weights_and_zeroes_bad_ones() {
    let gpu = TestGpu::new();
    let k = Kernels::new(&gpu);
    let mut rng = Rng(0x5EED_0002);
    for s in [shape(1, 4096), shape(97, 61), BIG] {
        let w = floats_and_bad_values(&mut rng, s.rows * s.len);
        let got = reduce_on_gpu(&gpu, &k, &w, s);
        let want = cpu_cdf::reduce(&w, s.rows, s.len);
        assert_eq!(got.len(), want.len());
        assert_eq!(got[1..4].iter().map(|x| x.to_bits()).collect::<Vec<_>>(), [s.rows, s.len, 0]);
        let worst = (0..want.len()).filter(|&i| !(1..4).contains(&i)).map(|i| ulps(got[i], want[i])).max().unwrap();
        let differing = (0..want.len()).filter(|&i| got[i].to_bits() != want[i].to_bits()).count();
        eprintln!("{} x {} floats: total {:e}, worst {worst} ulp, {differing} floats differ", s.rows, s.len, want[0]);
        assert!(worst <= FLOAT_ULPS, "{s:?}: {worst} ulp apart (allowed {FLOAT_ULPS})");
        // The bad values count as 0: the total equals the f64 sum of the good ones (to float32 rounding
        // of a sum of at most 2048 terms per level).
        let good: f64 = w.iter().filter(|x| **x > 0.0 && **x < 1e30).map(|x| *x as f64).sum();
        assert!(((got[0] as f64) - good).abs() <= 1e-4 * good, "{s:?}: total {} vs {good}", got[0]);
    }
}

/// Weights 10^[-3, 3) with a random mantissa; 1 in 16 is one of the values that must count as 0.
fn floats_and_bad_values(rng: &mut Rng, n: u32) -> Vec<f32> {
    let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -1.0, -1e-3, 1e30, 3e38, -0.0, 0.0];
    (0..n)
        .map(|_| {
            if rng.below(16) == 0 {
                bad[rng.below(bad.len() as u32) as usize]
            } else {
                10f32.powf(6.0 * rng.f32() - 3.0)
            }
        })
        .collect()
}

#[test]
fn all_zero_weights_give_a_zero_total_and_no_nan() {
    let gpu = TestGpu::new();
    let k = Kernels::new(&gpu);
    let junk = [0.0, -0.0, -2.0, f32::NAN, f32::NEG_INFINITY, f32::INFINITY, 1e30];
    for s in [shape(1, 1), shape(3, 5), shape(64, 64), Shape { rows: 4, len: 4, sections: 2 }] {
        let w: Vec<f32> = (0..s.rows * s.len * s.sections).map(|i| junk[i as usize % junk.len()]).collect();
        let got = reduce_on_gpu(&gpu, &k, &w, s);
        assert_bits_equal("all zero", &got, &cpu_cdf::reduce_sections(&w, s.rows, s.len, s.sections));
        // Every float but the shape words is +0: total 0, no NaN, no -0 from a -0 weight.
        let n = cpu_cdf::section_len(s.rows, s.len);
        assert!(got.iter().enumerate().all(|(i, x)| matches!(i % n, 1 | 2) || x.to_bits() == 0), "{s:?}");
    }
}

/// Checks what `op` gave on the GPU (`got`, one entry per u, or per texel for [`Op::Probs`]) against
/// the twin on `cpu` (the twin's CDF of `w`):
/// - draws: the twin's texel, a texel with weight, and the twin's probability: weight / total for
///   [`Op::Sample`] (within [`PROB_ULPS`]), `prob_rows` for [`Op::Rows`] (within [`PROB_ROWS_ULPS`]);
/// - [`Op::Probs`]: the twin's `prob_rows` per texel, 0 outside the rows and on texels without weight,
///   summing to 1 when the rows have weight.
fn check(what: &str, w: &[f32], s: Shape, cpu: &[f32], op: Op, us: &[f32], got: &[(u32, f32)]) {
    let texels = (s.rows * s.len) as usize;
    let (section, r0, r1) = match op {
        Op::Sample => (0, 0, s.rows),
        Op::Rows { section, r0, r1 } | Op::Probs { section, r0, r1 } | Op::Drawn { section, r0, r1 } => {
            (section, r0, r1)
        }
    };
    let cb = section as usize * cpu_cdf::section_len(s.rows, s.len);
    let ws = &w[section as usize * texels..][..texels];
    if let Op::Probs { .. } = op {
        assert_eq!(got.len(), texels);
        let mut sum = 0.0f64;
        for (v, &(gv, p)) in got.iter().enumerate() {
            let want = cpu_cdf::prob_rows(cpu, cb, v as u32, r0, r1);
            assert_eq!(gv as usize, v);
            assert!(ulps(p, want) <= PROB_ROWS_ULPS, "{what} {op:?}: texel {v}: GPU {p:e}, twin {want:e}");
            let inside = (r0 * s.len..r1 * s.len).contains(&(v as u32));
            if !inside || sanitise(ws[v]) == 0.0 {
                assert_eq!(p, 0.0, "{what} {op:?}: texel {v} cannot be drawn");
            }
            sum += p as f64;
        }
        if cpu_cdf::rows_total(cpu, cb, r0, r1) > 0.0 {
            assert!((sum - 1.0).abs() < 1e-5, "{what} {op:?}: the probabilities sum to {sum}");
        } else {
            assert_eq!(sum, 0.0);
        }
        return;
    }
    assert_eq!(got.len(), us.len());
    for (&u, &(v, p)) in us.iter().zip(got) {
        let (cv, cp, tol) = match op {
            Op::Sample => {
                let (cv, cp) = cpu_cdf::sample(cpu, w, u);
                (cv, cp, PROB_ULPS)
            }
            _ => {
                let cv = cpu_cdf::sample_rows(cpu, cb, u, r0, r1);
                (cv, cpu_cdf::prob_rows(cpu, cb, cv, r0, r1), PROB_ROWS_ULPS)
            }
        };
        assert_eq!(v, cv, "{what} {op:?}: u = {u:e} ({:#x}): GPU texel {v}, twin {cv}", u.to_bits());
        assert!((r0 * s.len..r1 * s.len).contains(&v), "{what} {op:?}: texel {v} outside the rows");
        assert!(
            sanitise(ws[v as usize]) > 0.0 && p > 0.0,
            "{what} {op:?}: u = {u:e} drew texel {v} of weight {}",
            ws[v as usize]
        );
        assert!(ulps(p, cp) <= tol, "{what} {op:?}: u = {u:e}: GPU prob {p:e}, twin {cp:e}");
    }
}

/// Runs `ops` on the GPU after cdf_reduce of `w`, checks the CDF (bit for bit) and every result against
/// the twin, and returns the results.
fn run_and_check(
    gpu: &Gpu,
    k: &Kernels,
    what: &str,
    w: &[f32],
    s: Shape,
    ops: &[(Op, &[f32])],
) -> Vec<Vec<(u32, f32)>> {
    let r = run(gpu, k, w, s, ops);
    let cpu = cpu_cdf::reduce_sections(w, s.rows, s.len, s.sections);
    assert_bits_equal(what, &r.cdf, &cpu);
    for ((op, us), got) in ops.iter().zip(&r.results) {
        check(what, w, s, &cpu, *op, us, got);
    }
    r.results
}

/// `cdf_sample` draws for `us`, checked against the twin.
fn draws_match_twin(gpu: &Gpu, k: &Kernels, what: &str, w: &[f32], s: Shape, us: &[f32]) -> Vec<(u32, f32)> {
    run_and_check(gpu, k, what, w, s, &[(Op::Sample, us)]).remove(0)
}

#[test]
fn sampling_edge_cases_match_the_twin() {
    let gpu = TestGpu::new();
    let k = Kernels::new(&gpu);
    let edges = [0.0, f32::from_bits(1), 1e-7, 0.5, U_MAX, 1.0];

    // The hand-computed case of cpu_cdf's unit tests: rows [1, 0, 3], [0, 0, 0], [2, 0, 0].
    let w = [1.0, 0.0, 3.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0];
    let us = [0.0, 0.1666, 0.1667, 0.6666, 0.6667, U_MAX, 1.0];
    let d = draws_match_twin(&gpu, &k, "3 x 3", &w, shape(3, 3), &us);
    // u picks the row (row 0 for u · 6 < 4, row 2 above); within row 0 the second uniform u2 picks
    // texel 0 for u2 · 4 < 1, else texel 2.
    let row0 = |u: f32| if cpu_cdf::second_uniform(u) * 4.0 < 1.0 { 0 } else { 2 };
    let want = [row0(0.0), row0(0.1666), row0(0.1667), row0(0.6666), 6, 6, 6];
    assert_eq!(d.iter().map(|x| x.0).collect::<Vec<_>>(), want);
    // cdf_sample's probability is the drawn texel's weight over the total, 6.
    assert_eq!(d.iter().map(|x| x.1).collect::<Vec<_>>(), want.map(|v| w[v as usize] / 6.0));

    // The in-row clamp (see cpu_cdf's unit test): at u = U_MAX the rest equals row 1's total; without the
    // clamp the search ends on texel 5, which has no weight.
    let (a, b) = (1.6768258e-3f32, 3.204143e-2f32);
    let w = [a, 0.0, 0.0, b, 0.0, 0.0];
    let d = draws_match_twin(&gpu, &k, "in-row clamp", &w, shape(2, 3), &[U_MAX]);
    assert_eq!(d[0].0, 3);

    // A single texel with weight: at the very start, in the middle, at the very end.
    for at in [0usize, 2000, 64 * 64 - 1] {
        let mut w = vec![0.0f32; 64 * 64];
        w[at] = 0.25;
        let u = us_and_edges(&edges, 1000, at as u32);
        let d = draws_match_twin(&gpu, &k, "single texel", &w, shape(64, 64), &u);
        assert!(d.iter().all(|&(v, p)| v as usize == at && p == 1.0), "single texel at {at}");
    }

    // Runs of zero-weight texels (whole rows, long in-row runs, isolated texels), bad values among them,
    // and float weights over six orders of magnitude.
    let mut rng = Rng(0x5EED_0003);
    let (rows, len) = (128u32, 96u32);
    let mut w = vec![0.0f32; (rows * len) as usize];
    for r in 0..rows as usize {
        if r % 5 == 0 || r < 3 || r + 2 >= rows as usize {
            continue; // empty rows, including the first and last ones
        }
        for i in 0..len as usize {
            let x = &mut w[r * len as usize + i];
            *x = match (i / 8 + r) % 4 {
                0 => 10f32.powf(6.0 * rng.f32() - 3.0),
                1 if i % 3 == 0 => 1.0,
                2 => [f32::NAN, -1.0, f32::INFINITY, 0.0][i % 4],
                _ => 0.0,
            };
        }
    }
    let u = us_and_edges(&edges, 20_000, 11);
    let d = draws_match_twin(&gpu, &k, "zero runs", &w, shape(rows, len), &u);
    let first = w.iter().position(|x| sanitise(*x) > 0.0).unwrap() as u32;
    let last = w.iter().rposition(|x| sanitise(*x) > 0.0).unwrap() as u32;
    // 128 rows of 96 are two faces (96 rows, then 32): u picks the face (the row and the texel inside come
    // from the derived uniforms): u = 0 the first face with weight, u → 1 the last.
    let face = |v: u32| v / len / len;
    assert_eq!(face(d[20_000].0), face(first), "u = 0 draws in the first face with weight");
    assert_eq!(face(d[20_000 + 4].0), face(last), "u = 1 − 2⁻²⁴ draws in the last face with weight");
    assert_eq!(face(d[20_000 + 5].0), face(last), "u = 1 (out of contract) is clamped to the last face with weight");
    // The same rows drawn with the probability the draw gives (both faces, so its face factor too).
    let ops: [(Op, &[f32]); 2] =
        [(Op::Rows { section: 0, r0: 0, r1: rows }, &u), (Op::Drawn { section: 0, r0: 0, r1: rows }, &u)];
    assert_eq!(drawn_equal_rows(&ops, &run_and_check(&gpu, &k, "zero runs, drawn", &w, shape(rows, len), &ops)), 1);
}

/// Checks that each [`Op::Drawn`] of `ops` gave what the [`Op::Rows`] just before it gave (the same rows
/// and u), bit for bit: the probability a draw returns with its texel (draw_vpl's known term) is
/// `cdf_prob_rows`'s. Returns the number of such pairs.
fn drawn_equal_rows(ops: &[(Op, &[f32])], results: &[Vec<(u32, f32)>]) -> usize {
    let mut pairs = 0;
    for (j, (op, _)) in ops.iter().enumerate() {
        let Op::Drawn { section, r0, r1 } = *op else { continue };
        let before = if j > 0 { Some(ops[j - 1].0) } else { None };
        assert!(
            matches!(before, Some(Op::Rows { section: s0, r0: a, r1: b }) if (s0, a, b) == (section, r0, r1)),
            "{op:?} must follow the Rows op of its rows"
        );
        assert_eq!(results[j].len(), results[j - 1].len());
        for (n, (&(v, p), &(vr, pr))) in results[j].iter().zip(&results[j - 1]).enumerate() {
            assert_eq!(v, vr, "{op:?}: draw {n}: texel {v}, cdf_sample_rows's {vr}");
            assert_eq!(p.to_bits(), pr.to_bits(), "{op:?}: draw {n} (texel {v}): its own {p:e}, cdf_prob_rows {pr:e}");
        }
        pairs += 1;
    }
    pairs
}

#[test]
fn sample_rows_and_prob_rows_match_the_twin_on_sections_and_faces() {
    let gpu = TestGpu::new();
    let k = Kernels::new(&gpu);
    // Three sections of two 64² faces (rows [0, 64) and [64, 128)), as the gather's method sections:
    // 0: faces of similar weight with zero runs; 1: face 0 a thousand times heavier; 2: face 0 empty,
    // face 1 floats over six orders of magnitude with bad values.
    let (res, s) = (64u32, Shape { rows: 128, len: 64, sections: 3 });
    let face_texels = (res * res) as usize;
    let mut rng = Rng(0x5EED_0004);
    let mut w = vec![];
    for (sec, heavy) in [(0, 1.0f32), (1, 1e3), (2, 0.0)] {
        if sec == 2 {
            w.resize(w.len() + face_texels, 0.0);
            w.extend(floats_and_bad_values(&mut rng, face_texels as u32));
            continue;
        }
        for v in 0..2 * face_texels {
            let (face, y, x) = (v / face_texels, (v / res as usize) % res as usize, v % res as usize);
            let zero = y % 16 == 3 || (x / 5) % 4 == 1;
            w.push(if zero { 0.0 } else { (0.5 + rng.f32()) * if face == 0 { heavy } else { 1.0 } });
        }
    }
    let edges = [0.0, U_MAX];
    let u = us_and_edges(&edges, 4096, 0xFACE);
    let cpu = cpu_cdf::reduce_sections(&w, s.rows, s.len, s.sections);
    let mut ops: Vec<(Op, &[f32])> = vec![];
    for section in 0..3 {
        // Both faces, each face, one row, and row 3 (empty in every section).
        for (r0, r1) in [(0, 128), (0, 64), (64, 128), (70, 71), (3, 4)] {
            // Draw only where the gather would (rows with weight); the probabilities everywhere.
            if cpu_cdf::rows_total(&cpu, section as usize * cpu_cdf::section_len(s.rows, s.len), r0, r1) > 0.0 {
                ops.push((Op::Rows { section, r0, r1 }, &u));
                ops.push((Op::Drawn { section, r0, r1 }, &u));
            }
            ops.push((Op::Probs { section, r0, r1 }, &[]));
        }
    }
    let t = Instant::now();
    let results = run_and_check(&gpu, &k, "sections", &w, s, &ops);
    // Section 2, face 0 is empty: every draw over all its rows lands on face 1.
    let (i, _) =
        ops.iter().enumerate().find(|(_, (op, _))| matches!(op, Op::Rows { section: 2, r0: 0, r1: 128 })).unwrap();
    assert!(results[i].iter().all(|&(v, _)| v >= res * res));
    assert!(drawn_equal_rows(&ops, &results) >= 10);
    eprintln!("{} ops on 3 sections: {:.2} s", ops.len(), t.elapsed().as_secs_f64());
}

/// `n` draws of stream `seed`, then the edge values.
fn us_and_edges(edges: &[f32], n: u32, seed: u32) -> Vec<f32> {
    let mut u = us(seed, n);
    u.extend_from_slice(edges);
    u
}

/// The chi-square critical value at upper tail `p = 0.001` for `df` degrees of freedom, by the
/// Wilson–Hilferty approximation: (χ²/df)^(1/3) is close to normal with mean 1 − 2/(9 df) and variance
/// 2/(9 df), so χ²_crit ≈ df · (1 − 2/(9 df) + z · √(2/(9 df)))³ with z = Φ⁻¹(0.999) = 3.090232. It is
/// slightly above the exact quantile, by less than 0.1 % for df ≥ 50 (df = 56: 94.54 vs 94.46; df = 255:
/// 330.55 vs 330.52), so the test is marginally more lenient than p = 0.001 says.
fn chi2_critical(df: usize) -> f64 {
    let z = 3.090_232_306_167_813;
    let k = df as f64;
    let c = 2.0 / (9.0 * k);
    k * (1.0 - c + z * c.sqrt()).powi(3)
}

/// Pearson's statistic of `observed` against `expected` (bins expected empty must be observed empty
/// and are left out); returns (statistic, degrees of freedom).
fn chi2(observed: &[u64], expected: &[f64]) -> (f64, usize) {
    let mut stat = 0.0;
    let mut bins = 0;
    for (b, (&o, &e)) in observed.iter().zip(expected).enumerate() {
        if e == 0.0 {
            assert_eq!(o, 0, "bin {b} has no weight but was drawn {o} times");
            continue;
        }
        assert!(e >= 5.0, "bin {b}: expected count {e} too small for the chi-square approximation");
        stat += (o as f64 - e).powi(2) / e;
        bins += 1;
    }
    (stat, bins - 1)
}

/// Checks the draws' histogram over `bins` (texel → bin by `bin_of`) against weight / total (the
/// weights of `w` with `bin_of` = Some) and against a uniform expectation over the bins with weight;
/// returns (statistic, df, critical, uniform statistic).
fn fit(w: &[f32], draws: &[(u32, f32)], bins: usize, bin_of: impl Fn(u32) -> Option<usize>) -> (f64, usize, f64, f64) {
    let mut mass = vec![0.0f64; bins];
    for (v, x) in w.iter().enumerate() {
        if let Some(b) = bin_of(v as u32) {
            mass[b] += sanitise(*x) as f64;
        }
    }
    let total: f64 = mass.iter().sum();
    let n = draws.len() as f64;
    let mut observed = vec![0u64; bins];
    for &(v, _) in draws {
        observed[bin_of(v).expect("a draw outside the binned texels")] += 1;
    }
    let expected: Vec<f64> = mass.iter().map(|m| n * m / total).collect();
    let (stat, df) = chi2(&observed, &expected);
    let live = mass.iter().filter(|m| **m > 0.0).count() as f64;
    let uniform: Vec<f64> = mass.iter().map(|m| if *m > 0.0 { n / live } else { 0.0 }).collect();
    let (uniform_stat, _) = chi2(&observed, &uniform);
    (stat, df, chi2_critical(df), uniform_stat)
}

fn assert_fit(what: &str, f: (f64, usize, f64, f64)) {
    let (stat, df, crit, uniform) = f;
    eprintln!("{what}: chi2 = {stat:.1}, df = {df}, critical (p = 0.001) = {crit:.1}; against uniform: {uniform:.3e}");
    assert!(stat < crit, "{what}: chi2 {stat:.1} ≥ {crit:.1} (df {df}): the draws do not follow weight / total");
    assert!(uniform > 100.0 * crit, "{what}: the weights are too flat to tell a sampler that ignores them");
}

#[test]
fn chi2_critical_values_match_tables() {
    // Exact upper 0.001 quantiles (the inverse of the regularised incomplete gamma function, by
    // bisection; df = 10 is the textbook 29.588) against the approximation: ≤ 0.1 % above for df ≥ 50.
    for (df, exact) in [(56, 94.461), (57, 95.751), (153, 212.797), (223, 293.996), (255, 330.520)] {
        let approx = chi2_critical(df);
        assert!(approx >= exact && approx / exact - 1.0 < 1e-3, "df {df}: {approx} vs {exact}");
    }
    assert!((chi2_critical(10) / 29.588 - 1.0).abs() < 0.01);
}

#[test]
fn draws_follow_weight_over_total_on_64_bins() {
    let gpu = TestGpu::new();
    let k = Kernels::new(&gpu);
    // 8 rows × 8: weights 0..10 × 0.37 (six bins with zero weight, one a whole-row start), and a NaN.
    let mut w: Vec<f32> = (0..64u32).map(|i| ((i * 7) % 11) as f32 * 0.37).collect();
    w[40] = f32::NAN;
    let t = Instant::now();
    let u = us(0xC0FFEE, 200_000);
    let d = draws_match_twin(&gpu, &k, "64 bins", &w, shape(8, 8), &u);
    assert_fit("64 bins, 200k draws", fit(&w, &d, 64, |v| Some(v as usize)));
    eprintln!("64 bins: {:.2} s", t.elapsed().as_secs_f64());
}

#[test]
fn draws_follow_weight_over_total_on_two_faces_of_1024_squared() {
    let gpu = TestGpu::new();
    let k = Kernels::new(&gpu);
    let (rows, len) = (BIG.rows, BIG.len);
    let t = Instant::now();
    // Two faces of 1024²: a smooth bump per face (different centres and widths) over a floor, with zero
    // runs: 8 whole rows out of every 64, a 40-texel gap out of every 96 of a row, and 1 texel in 7.
    let w: Vec<f32> = (0..rows * len)
        .map(|v| {
            let (face, y, x) = (v / (len * 1024), (v / len) % 1024, v % len);
            if y % 64 < 8 || x % 96 >= 56 || v % 7 == 3 {
                return 0.0;
            }
            let (cx, cy, s) = if face == 0 { (300.0, 700.0, 150.0) } else { (800.0, 200.0, 300.0) };
            let d2 = ((x as f32 - cx).powi(2) + (y as f32 - cy).powi(2)) / (s * s);
            0.02 + 5.0 * (-d2).exp()
        })
        .collect();
    let (u, u_face) = (us(0xB16_C0DE, 1 << 21), us(0xFACE_0001, 1 << 20));
    let ops = [(Op::Sample, &u[..]), (Op::Rows { section: 0, r0: 1024, r1: 2048 }, &u_face[..])];
    let r = run_and_check(&gpu, &k, "2 x 1024^2", &w, BIG, &ops);
    // 256 groups of 8 consecutive rows (one in 8 has no weight), and 256 groups of 4 columns.
    assert_fit("2 x 1024^2 by 8-row groups, 2^21 draws", fit(&w, &r[0], 256, |v| Some((v / (8 * len)) as usize)));
    assert_fit("2 x 1024^2 by 4-column groups, 2^21 draws", fit(&w, &r[0], 256, |v| Some(((v % len) / 4) as usize)));
    // Face 1 alone (cdf_sample_rows on rows [1024, 2048)): 256 groups of 4 rows.
    let face1 = |v: u32| (v >= 1024 * len).then(|| ((v - 1024 * len) / (4 * len)) as usize);
    assert_fit("face 1 by 4-row groups, 2^20 draws", fit(&w, &r[1], 256, face1));
    eprintln!("2 x 1024^2: {:.2} s", t.elapsed().as_secs_f64());
}
