//! `--visibility psm` (thesis ch. 6): per-VPL paraboloid shadow maps for a shared VPL set per frame.
//! Checked against the same shared set with exact shadow rays (`psm-exact`), which the BVH tests vouch
//! for, and the shared-set estimator against `all`.

use bounce_graph::frame::{Component, FrameSettings, Method, Renderer, Visibility};
use bounce_graph::scene::Scene;
use bounce_tests::TestGpu;

fn settings(visibility: Visibility, seed: u64) -> FrameSettings {
    FrameSettings {
        width: 32,
        height: 32,
        component: Component::Indirect,
        method: Method::Gbg,
        visibility,
        vpls: 32,
        psm_res: 256,
        dprsm_res: 64,
        voxels: 64,
        seed,
        ..FrameSettings::default()
    }
}

fn mean(img: &[[f32; 4]]) -> f64 {
    img.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / (3 * img.len()) as f64
}

/// On identical VPLs (same seed, same shared set), the maps' visibility agrees with exact shadow rays
/// but within the bias band: the image means agree to 2 %, and at most 5 % of the pixels differ by more
/// than 10 % (those next to contact shadows, where the bias lets light through, and along shadow
/// outlines, where a texel's depth stands for its neighbours'). A map that ignored occluders, or
/// mis-projected, would fail both (the Cornell box's tall block shadows much of the floor).
#[test]
fn psm_visibility_agrees_with_exact_rays_on_the_same_vpls() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    for seed in [1u64, 2] {
        let psm = r.render(&settings(Visibility::Psm, seed)).unwrap();
        let exact = r.render(&settings(Visibility::PsmExact, seed)).unwrap();
        assert!(psm.ran.contains(&"psm") && psm.ran.contains(&"psm_select"), "{:?}", psm.ran);
        let (mp, me) = (mean(&psm.radiance), mean(&exact.radiance));
        let off = psm
            .radiance
            .iter()
            .zip(&exact.radiance)
            .filter(|(a, b)| (0..3).any(|c| (a[c] - b[c]).abs() > 0.1 * b[c].abs().max(1e-3)))
            .count();
        let frac = off as f64 / psm.radiance.len() as f64;
        eprintln!(
            "seed {seed}: psm mean {mp:.5} vs exact {me:.5} ({:+.2}%), {:.1}% of pixels off by > 10%",
            100.0 * (mp - me) / me,
            100.0 * frac
        );
        assert!(((mp - me) / me).abs() < 0.02, "means {mp} vs {me}");
        assert!(frac < 0.05, "{:.1}% of pixels differ by more than 10%", 100.0 * frac);
    }
}

/// The shared-set estimator is unbiased for the VPL sum: with exact visibility (`psm-exact`), the mean
/// of 32 seeds of 256 shared VPLs is within 4 standard errors of `all` with exact visibility. (One set
/// for all pixels makes the image mean as noisy as one pixel's estimate: hence the VPL count.)
#[test]
fn the_shared_vpl_set_is_unbiased() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let all = r
        .render(&FrameSettings { method: Method::All, visibility: Visibility::Exact, ..settings(Visibility::Exact, 0) })
        .unwrap();
    let target = mean(&all.radiance);
    let means: Vec<f64> = (0..32)
        .map(|k| {
            let s = FrameSettings { vpls: 256, ..settings(Visibility::PsmExact, 100 + k) };
            mean(&r.render(&s).unwrap().radiance)
        })
        .collect();
    let (m, se) = bounce_tests::mean_and_stderr(&means);
    eprintln!("shared set: {m:.5} ± {se:.5} vs all {target:.5} ({:+.2}%)", 100.0 * (m - target) / target);
    assert!((m - target).abs() <= 4.0 * se, "{m} ± {se} vs {target}");
}

/// Impossible PSM settings are refused with a reason: `all` (a map per VPL slot), more maps than the
/// device's array layers, more memory than the bound.
#[test]
fn impossible_psm_settings_are_refused() {
    let gpu = TestGpu::new();
    for (s, want) in [
        (FrameSettings { method: Method::All, ..settings(Visibility::Psm, 1) }, "sampled method"),
        (FrameSettings { vpls: 1_000_000, ..settings(Visibility::Psm, 1) }, "maxImageArrayLayers"),
        (FrameSettings { vpls: 2048, psm_res: 4096, ..settings(Visibility::Psm, 1) }, "MiB"),
    ] {
        let e = s.validate(&gpu).unwrap_err().to_string();
        assert!(e.contains(want), "{e}");
    }
}

/// mis under `psm-exact`: its CDF samples are the shared set, both strategies with exact rays, so the
/// mean of 32 seeds is within 4 standard errors of `all` with exact visibility. Under `psm` (maps for the
/// shared set, the voxel march for the gathering rays) it renders and stays within 2 % of `psm-exact`.
#[test]
fn mis_with_a_shared_vpl_set() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let mis = |visibility, seed| FrameSettings { method: Method::Mis, vpls: 64, ..settings(visibility, seed) };
    let all = r
        .render(&FrameSettings { method: Method::All, visibility: Visibility::Exact, ..settings(Visibility::Exact, 0) })
        .unwrap();
    let target = mean(&all.radiance);
    let means: Vec<f64> =
        (0..32).map(|k| mean(&r.render(&mis(Visibility::PsmExact, 300 + k)).unwrap().radiance)).collect();
    let (m, se) = bounce_tests::mean_and_stderr(&means);
    eprintln!("mis, shared set, exact: {m:.5} ± {se:.5} vs all {target:.5} ({:+.2}%)", 100.0 * (m - target) / target);
    assert!((m - target).abs() <= 4.0 * se, "{m} ± {se} vs {target}");
    let maps = r.render(&mis(Visibility::Psm, 300)).unwrap();
    assert!(maps.ran.contains(&"psm") && maps.ran.contains(&"mis"), "{:?}", maps.ran);
    let (a, b) = (mean(&maps.radiance), means[0]);
    eprintln!("mis, shared set: maps {a:.5} vs exact {b:.5} ({:+.2}%)", 100.0 * (a - b) / b);
    assert!(((a - b) / b).abs() < 0.02, "{a} vs {b}");
}
