//! The two-level CDF: `cdf_reduce` (`crates/graph/src/passes/cdf_reduce.rs`, `glsl/cdf_reduce.comp`) and
//! `cdf_sample` (`glsl/shared/cdf.glsl`, run here through the test kernel `glsl/test/cdf_sample.comp`),
//! against the CPU twin `crates/graph/src/cpu_cdf.rs` and against the distribution they must produce.
//!
//! - **Reduce vs twin.** The real pass, run through a `Graph`, equals the CPU twin bit for bit on integer
//!   weights (which are also checked against exact integer sums) for one row, many rows, empty rows, a
//!   single texel with weight at the very end, and the largest shape, 2 × 1024² texels. On float weights
//!   spanning six orders of magnitude it must agree within 4 ulp (see [`FLOAT_ULPS`]); NaN, ±∞, negative
//!   and ≥ 1e30 weights count as 0. All-zero weights give a total of 0 and no NaN.
//! - **Sampling edge cases vs the twin.** u = 0, the largest float below 1, 1 itself, runs of zero-weight
//!   texels (never drawn), a single texel with weight, the in-row clamp (a rest equal to the row total),
//!   and prob = weight / total for every draw.
//! - **Distribution.** Pearson's chi-square of the drawn texels against weight / total, at p = 0.001
//!   ([`chi2_critical`], Wilson–Hilferty), on 64 bins × 200,000 draws and on 2 × 1024² texels grouped
//!   into 256 index ranges and 256 column ranges × 2²¹ draws. The same draws against a uniform
//!   expectation must fail by far, so a sampler that ignores the weights cannot pass.
//!
//! The random numbers are the gather's: `rand01` of a PCG hash of the draw's counter (fixed seed), at
//! most 1 − 2⁻²⁴. Each kernel invocation makes one draw (two binary searches), far below llvmpipe's loop
//! limit; cdf_reduce loops at most max(rows, row_length) = 2048 times per invocation.

use bounce_device::sync::Access;
use bounce_device::{vk, Binding, Buffer, BufferDesc, ComputePipeline, DescriptorWrites, Gpu};
use bounce_graph::bindings::{B_CDF, B_IMPORTANCE, WG_1D};
use bounce_graph::cpu_cdf::{self, pcg_hash, rand01, sanitise};
use bounce_graph::graph::{Graph, Persistent};
use bounce_graph::passes::cdf_reduce::CdfReduce;
use bounce_tests::TestGpu;
use std::time::Instant;

/// Test-only bindings of `glsl/test/cdf_sample.comp`.
const T_US: u32 = 28;
const T_DRAWS: u32 = 29;
/// The largest float below 1: the most `rand01` returns.
const U_MAX: f32 = 1.0 - 1.0 / 16777216.0;
/// Draws per dispatch of `cdf_sample.comp` (a large batch is split over several dispatches).
const PER_DISPATCH: u32 = 1 << 20;
/// The largest shape the renderer builds for one light: 2 faces × 1024 rows of 1024 texels.
const BIG: (u32, u32) = (2048, 1024);
/// How far (in units in the last place) the GPU's CDF of float weights may be from the twin's. Vulkan
/// requires float additions to be correctly rounded, and the shader and the twin add the same terms in
/// the same order, so a conforming device gives the same bits (lavapipe: 0 ulp, see the test). The
/// slack of 4 ulp (≈ 2.4e-7 relative) admits a driver that contracts or reassociates one step; a wrong
/// order, a skipped or doubled term of a comparable size, or a sum over the wrong row is far outside it.
const FLOAT_ULPS: u32 = 4;
/// How far the GPU's probability (weight / total, a division) may be from the twin's: Vulkan allows
/// 2.5 ulp for a float division.
const PROB_ULPS: u32 = 3;

/// xorshift64*: deterministic, no dependency (as in voxelize.rs).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in [0, 1).
    fn f32(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn below(&mut self, n: u32) -> u32 {
        (self.next() % n as u64) as u32
    }
}

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
            Binding::storage_buffer(B_CDF),
            Binding::storage_buffer(T_US),
            Binding::storage_buffer(T_DRAWS),
        ];
        let sample = ComputePipeline::new(
            gpu,
            "cdf_sample",
            &bounce_graph::spirv(bounce_graph::shaders::CDF_SAMPLE_COMP),
            &bindings,
            8,
            &[],
        )
        .unwrap();
        Kernels { reduce: CdfReduce::new(gpu).unwrap(), sample }
    }
}

/// What one GPU run gives back.
struct Run {
    cdf: Vec<f32>,
    /// (texel, probability) per u.
    draws: Vec<(u32, f32)>,
}

/// Uploads `weights` (`rows × row_length`), runs cdf_reduce through a graph as the frame does and, when
/// `us` is not empty, draws one texel per u with `cdf_sample.comp` in a pass after it.
fn run(gpu: &Gpu, k: &Kernels, weights: &[f32], rows: u32, row_length: u32, us: &[f32]) -> Run {
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let imp = Persistent::ready(Buffer::with_data(gpu, "importance", storage, bytemuck::cast_slice(weights)).unwrap());
    let ub = Persistent::ready(Buffer::with_data(gpu, "cdf test u", storage, bytemuck::cast_slice(us)).unwrap());
    let mut g = Graph::new(gpu);
    let hi = g.import_buffer(&imp);
    let cdf = k.reduce.add(&mut g, &hi, rows, row_length, 1);
    g.export(&cdf);
    let mut draws = None;
    if !us.is_empty() {
        let hu = g.import_buffer(&ub);
        let mut d = g.create_buffer(BufferDesc::storage("cdf test draws", 8 * us.len() as u64));
        let (hd, n, pipeline) = (d, us.len() as u32, &k.sample);
        g.add_pass("cdf_sample")
            .read(&hi, Access::ComputeRead)
            .read(&cdf, Access::ComputeRead)
            .read(&hu, Access::ComputeRead)
            .overwrite(&mut d, Access::ComputeWrite)
            .record(move |ctx| {
                let w = DescriptorWrites::new()
                    .storage_buffer(B_IMPORTANCE, ctx.buffer(&hi))
                    .storage_buffer(B_CDF, ctx.buffer(&cdf))
                    .storage_buffer(T_US, ctx.buffer(&hu))
                    .storage_buffer(T_DRAWS, ctx.buffer(&hd));
                let mut first = 0;
                while first < n {
                    let count = (n - first).min(PER_DISPATCH);
                    pipeline.dispatch(ctx.cmd, &w, bytemuck::cast_slice(&[first, count]), [count, 1, 1], [WG_1D, 1, 1]);
                    first += count;
                }
            });
        g.export(&d);
        draws = Some(d);
    }
    let done = g.execute().unwrap();
    let cdf: Vec<f32> = bytemuck::pod_collect_to_vec(&done.read_buffer(&cdf).unwrap());
    let draws = match draws {
        Some(d) => bytemuck::pod_collect_to_vec::<u8, [u32; 2]>(&done.read_buffer(&d).unwrap())
            .into_iter()
            .map(|[v, p]| (v, f32::from_bits(p)))
            .collect(),
        None => vec![],
    };
    Run { cdf, draws }
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
    let mut grand = 0u64;
    for r in 0..rows {
        let mut acc = 0u64;
        for i in 0..len {
            acc += sanitise(w[r * len + i]) as u64;
            assert_eq!(cdf[4 + rows + r * len + i] as u64, acc, "{what}: row {r} prefix at {i}");
        }
        grand += acc;
        assert_eq!(cdf[4 + r] as u64, grand, "{what}: prefix over rows at {r}");
    }
    assert!(grand < 1 << 24);
    assert_eq!(cdf[0] as u64, grand, "{what}: total");
}

#[test]
fn reduce_equals_the_twin_bit_for_bit_on_integer_weights() {
    let gpu = TestGpu::new();
    let k = Kernels::new(&gpu);
    let mut rng = Rng(0x5EED_0001);
    let mut cases: Vec<(&str, u32, u32, Vec<f32>)> = vec![];
    let random = |rng: &mut Rng, n: u32, max: u32| (0..n).map(|_| rng.below(max + 1) as f32).collect::<Vec<_>>();
    cases.push(("one texel", 1, 1, vec![5.0]));
    cases.push(("one row", 1, 1000, random(&mut rng, 1000, 9)));
    cases.push(("many short rows", 300, 7, random(&mut rng, 2100, 9)));
    // Rows of zeros: the first, the last, and every third one in between.
    let mut w = random(&mut rng, 64 * 33, 9);
    for r in (0..64).filter(|r| r % 3 == 0 || *r == 63) {
        w[r * 33..(r + 1) * 33].fill(0.0);
    }
    cases.push(("zero rows", 64, 33, w));
    let mut w = vec![0.0; 50 * 40];
    *w.last_mut().unwrap() = 3.0;
    cases.push(("one texel at the very end", 50, 40, w));
    // The full shape; weights 0..=7 keep the total (≈ 7.3e6) below 2²⁴, so every sum is exact.
    cases.push(("2 x 1024^2", BIG.0, BIG.1, random(&mut rng, BIG.0 * BIG.1, 7)));
    for (what, rows, len, w) in &cases {
        let t = Instant::now();
        let got = run(&gpu, &k, w, *rows, *len, &[]).cdf;
        let want = cpu_cdf::reduce(w, *rows, *len);
        assert_exact_integer_sums(what, w, *rows, *len, &want);
        assert_bits_equal(what, &got, &want);
        eprintln!(
            "{what} ({rows} x {len}): bit-identical, total {}, {:.0} ms",
            want[0],
            t.elapsed().as_secs_f64() * 1e3
        );
    }
}

#[test]
fn reduce_matches_the_twin_on_float_weights_and_zeroes_bad_ones() {
    let gpu = TestGpu::new();
    let k = Kernels::new(&gpu);
    let mut rng = Rng(0x5EED_0002);
    let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -1.0, -1e-3, 1e30, 3e38, -0.0, 0.0];
    for (rows, len) in [(1, 4096), (97, 61), BIG] {
        // 10^[-3, 3) with a random mantissa; 1 weight in 16 is one of the bad values.
        let w: Vec<f32> = (0..rows * len)
            .map(|_| {
                if rng.below(16) == 0 {
                    bad[rng.below(bad.len() as u32) as usize]
                } else {
                    10f32.powf(6.0 * rng.f32() - 3.0)
                }
            })
            .collect();
        let got = run(&gpu, &k, &w, rows, len, &[]).cdf;
        let want = cpu_cdf::reduce(&w, rows, len);
        assert_eq!(got.len(), want.len());
        assert_eq!(got[1..4].iter().map(|x| x.to_bits()).collect::<Vec<_>>(), [rows, len, 0]);
        let worst = (0..want.len()).filter(|&i| !(1..4).contains(&i)).map(|i| ulps(got[i], want[i])).max().unwrap();
        let differing = (0..want.len()).filter(|&i| got[i].to_bits() != want[i].to_bits()).count();
        eprintln!("{rows} x {len} floats: total {:e}, worst {worst} ulp, {differing} floats differ", want[0]);
        assert!(worst <= FLOAT_ULPS, "{rows} x {len}: {worst} ulp apart (allowed {FLOAT_ULPS})");
        // The bad values count as 0: the total equals the f64 sum of the good ones (to float32 rounding
        // of a sum of at most 2048 terms per level).
        let good: f64 = w.iter().filter(|x| **x > 0.0 && **x < 1e30).map(|x| *x as f64).sum();
        assert!(((got[0] as f64) - good).abs() <= 1e-4 * good, "{rows} x {len}: total {} vs {good}", got[0]);
    }
}

#[test]
fn all_zero_weights_give_a_zero_total_and_no_nan() {
    let gpu = TestGpu::new();
    let k = Kernels::new(&gpu);
    let junk = [0.0, -0.0, -2.0, f32::NAN, f32::NEG_INFINITY, f32::INFINITY, 1e30];
    for (rows, len) in [(1, 1), (3, 5), (64, 64)] {
        let w: Vec<f32> = (0..rows * len).map(|i| junk[i as usize % junk.len()]).collect();
        let got = run(&gpu, &k, &w, rows, len, &[]).cdf;
        assert_bits_equal("all zero", &got, &cpu_cdf::reduce(&w, rows, len));
        assert_eq!(got[0], 0.0, "{rows} x {len}: total");
        // Every float but the shape words is +0 (no NaN, no -0 from a -0 weight).
        assert!(got.iter().enumerate().all(|(i, x)| i == 1 || i == 2 || x.to_bits() == 0), "{rows} x {len}");
    }
}

/// Draws on the GPU for `us` and checks each against the twin: the same texel, a texel with weight, and
/// prob = weight / total (within [`PROB_ULPS`]). Returns the draws.
fn draws_match_twin(gpu: &Gpu, k: &Kernels, what: &str, w: &[f32], rows: u32, len: u32, us: &[f32]) -> Vec<(u32, f32)> {
    let r = run(gpu, k, w, rows, len, us);
    let cpu = cpu_cdf::reduce(w, rows, len);
    assert_bits_equal(what, &r.cdf, &cpu);
    let total = cpu[0];
    for (&u, &(v, p)) in us.iter().zip(&r.draws) {
        let (cv, cp) = cpu_cdf::sample(&cpu, w, u);
        assert_eq!(v, cv, "{what}: u = {u:e} ({:#x}): GPU texel {v}, twin {cv}", u.to_bits());
        let weight = sanitise(w[v as usize]);
        assert!(weight > 0.0 && p > 0.0, "{what}: u = {u:e} drew texel {v} of weight {}", w[v as usize]);
        assert_eq!(cp, weight / total);
        assert!(ulps(p, cp) <= PROB_ULPS, "{what}: u = {u:e}: prob {p:e} vs weight / total {cp:e}");
    }
    r.draws
}

#[test]
fn sampling_edge_cases_match_the_twin() {
    let gpu = TestGpu::new();
    let k = Kernels::new(&gpu);
    let edges = [0.0, f32::from_bits(1), 1e-7, 0.5, U_MAX, 1.0];

    // The hand-computed case of cpu_cdf's unit tests: rows [1, 0, 3], [0, 0, 0], [2, 0, 0].
    let w = [1.0, 0.0, 3.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0];
    let us = [0.0, 0.1666, 0.1667, 0.6666, 0.6667, U_MAX, 1.0];
    let d = draws_match_twin(&gpu, &k, "3 x 3", &w, 3, 3, &us);
    assert_eq!(d.iter().map(|x| x.0).collect::<Vec<_>>(), [0, 0, 2, 2, 6, 6, 6]);
    assert_eq!(
        d.iter().map(|x| x.1).collect::<Vec<_>>(),
        [1.0 / 6.0, 1.0 / 6.0, 0.5, 0.5, 2.0 / 6.0, 2.0 / 6.0, 2.0 / 6.0]
    );

    // The in-row clamp (see cpu_cdf's unit test): at u = U_MAX the rest equals row 1's total; without the
    // clamp the search ends on texel 5, which has no weight.
    let (a, b) = (1.6768258e-3f32, 3.204143e-2f32);
    let w = [a, 0.0, 0.0, b, 0.0, 0.0];
    let d = draws_match_twin(&gpu, &k, "in-row clamp", &w, 2, 3, &[U_MAX]);
    assert_eq!(d[0].0, 3);

    // A single texel with weight: at the very start, in the middle, at the very end.
    for at in [0usize, 2000, 64 * 64 - 1] {
        let mut w = vec![0.0f32; 64 * 64];
        w[at] = 0.25;
        let u = us_and_edges(&edges, 1000, at as u32);
        let d = draws_match_twin(&gpu, &k, "single texel", &w, 64, 64, &u);
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
    let d = draws_match_twin(&gpu, &k, "zero runs", &w, rows, len, &u);
    let first = w.iter().position(|x| sanitise(*x) > 0.0).unwrap() as u32;
    let last = w.iter().rposition(|x| sanitise(*x) > 0.0).unwrap() as u32;
    assert_eq!(d[20_000].0, first, "u = 0 draws the first texel with weight");
    assert_eq!(d[20_000 + 4].0, last, "u = 1 − 2⁻²⁴ draws the last texel with weight");
    assert_eq!(d[20_000 + 5].0, last, "u = 1 (out of contract) is clamped to the last texel with weight");
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
/// within 0.1 % of the exact quantile for df ≥ 50 (df = 57: 98.4 vs 98.32; df = 255: 330.6 vs 330.5).
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

/// Checks the draws' histogram over `bins` (texel → bin by `bin_of`) against weight / total and against
/// a uniform expectation over the bins with weight; returns (statistic, df, critical, uniform statistic).
fn fit(w: &[f32], draws: &[(u32, f32)], bins: usize, bin_of: impl Fn(u32) -> usize) -> (f64, usize, f64, f64) {
    let mut mass = vec![0.0f64; bins];
    for (v, x) in w.iter().enumerate() {
        mass[bin_of(v as u32)] += sanitise(*x) as f64;
    }
    let total: f64 = mass.iter().sum();
    let n = draws.len() as f64;
    let mut observed = vec![0u64; bins];
    for &(v, _) in draws {
        observed[bin_of(v)] += 1;
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
fn draws_follow_weight_over_total_on_64_bins() {
    let gpu = TestGpu::new();
    let k = Kernels::new(&gpu);
    // 8 rows × 8: weights 0..10 × 0.37 (six bins with zero weight, one a whole-row start), and a NaN.
    let mut w: Vec<f32> = (0..64u32).map(|i| ((i * 7) % 11) as f32 * 0.37).collect();
    w[40] = f32::NAN;
    let t = Instant::now();
    let u = us(0xC0FFEE, 200_000);
    let d = draws_match_twin(&gpu, &k, "64 bins", &w, 8, 8, &u);
    assert_fit("64 bins, 200k draws", fit(&w, &d, 64, |v| v as usize));
    eprintln!("64 bins: {:.2} s", t.elapsed().as_secs_f64());
}

#[test]
fn draws_follow_weight_over_total_on_two_faces_of_1024_squared() {
    let gpu = TestGpu::new();
    let k = Kernels::new(&gpu);
    let (rows, len) = BIG;
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
    let u = us(0xB16_C0DE, 1 << 21);
    let d = draws_match_twin(&gpu, &k, "2 x 1024^2", &w, rows, len, &u);
    // 256 groups of 8 consecutive rows (one in 8 has no weight), and 256 groups of 4 columns.
    assert_fit("2 x 1024^2 by 8-row groups, 2^21 draws", fit(&w, &d, 256, |v| (v / (8 * len)) as usize));
    assert_fit("2 x 1024^2 by 4-column groups, 2^21 draws", fit(&w, &d, 256, |v| ((v % len) / 4) as usize));
    eprintln!("2 x 1024^2: {:.2} s", t.elapsed().as_secs_f64());
}
