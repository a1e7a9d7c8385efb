//! The VPL core against closed forms and against itself:
//! - inside a closed sphere of radius R, uniform albedo ρ, a point light of intensity I anywhere inside,
//!   the one-bounce indirect radiance is ρ²·I/(π·R²) everywhere (cos θ_x cos θ_y / d² = 1/(4R²) on a
//!   sphere, so the bounce irradiance is ρ·Φ/(4πR²) with Φ = 4πI, and radiance = ρ/π · that);
//! - `uniform` is unbiased with respect to `all`: the mean over K seeds approaches it at the 1/√K rate;
//! - the VPL kernel: the patch kernel's converged sum is closer to the exact one-bounce image than the
//!   point kernel's.

use bounce_graph::camera::Camera;
use bounce_graph::frame::{Component, FaceMode, FrameSettings, Method, MisWeights, Renderer, Visibility, VplKernel};
use bounce_graph::scene::{point_light, Scene};
use bounce_tests::TestGpu;
use glam::Vec3;
use std::f32::consts::PI;

/// A UV sphere of radius `r` (lat × 2·lat quads, two triangles each), uniform albedo, seen from inside.
pub fn sphere_scene(r: f32, lat: usize, albedo: f32, light: Vec3, intensity: f32) -> Scene {
    let lon = 2 * lat;
    let p = |i: usize, j: usize| {
        let th = PI * i as f32 / lat as f32;
        let ph = 2.0 * PI * j as f32 / lon as f32;
        Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()) * r
    };
    let mut tris = vec![];
    for i in 0..lat {
        for j in 0..lon {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            if i != 0 {
                tris.push([a, c, d]);
            }
            if i != lat - 1 {
                tris.push([a, b, c]);
            }
        }
    }
    let albedo = vec![Vec3::splat(albedo); tris.len()];
    let camera =
        Camera { eye: Vec3::new(0.1, -0.2, 0.6 * r), target: Vec3::new(0.0, 0.0, -r), up: Vec3::Y, fov_y_deg: 70.0 };
    Scene::from_triangles(&tris, &albedo, camera, &[point_light(light, Vec3::splat(intensity))])
}

#[allow(clippy::too_many_arguments)]
fn indirect(
    r: &mut Renderer,
    method: Method,
    seed: u64,
    vpls: u32,
    w: u32,
    h: u32,
    dprsm_res: u32,
    voxels: u32,
) -> Vec<[f32; 3]> {
    indirect_with(
        r,
        FrameSettings { method, seed, vpls, component: Component::Direct, ..FrameSettings::default() },
        w,
        h,
        dprsm_res,
        voxels,
    )
}

pub(crate) fn indirect_with(
    r: &mut Renderer,
    base: FrameSettings,
    w: u32,
    h: u32,
    dprsm_res: u32,
    voxels: u32,
) -> Vec<[f32; 3]> {
    let s = FrameSettings { width: w, height: h, component: Component::Indirect, dprsm_res, voxels, ..base };
    let f = r.render(&s).unwrap();
    assert!(f.radiance.iter().all(|p| p.iter().all(|c| c.is_finite())), "non-finite radiance");
    f.radiance.iter().map(|p| [p[0], p[1], p[2]]).collect()
}

/// Tolerances: the tessellation (48 × 96 quads) moves the surface by under 0.1% of R and tilts facets
/// by under 2°, and the 64² DPRSM is a midpoint quadrature of a smooth integrand (flux ∝ Δω, G
/// constant): together well under 1%; the bar is 2% on the mean. Per pixel `all` must be within
/// 3% (facet-scale variation of cos terms near x), `uniform` with 256 VPLs within 15% RMS (its noise:
/// the flux per texel varies 4× from a face's centre to its rim).
#[test]
fn sphere_closed_form_all_and_uniform() {
    let (radius, rho, intensity) = (1.0f32, 0.5f32, 2.0f32);
    let scene = sphere_scene(radius, 48, rho, Vec3::new(0.25, 0.3, -0.15), intensity);
    let want = rho * rho * intensity / (PI * radius * radius);
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    for (method, vpls, mean_tol, pixel_tol) in [(Method::Uniform, 256, 0.02, 0.15), (Method::All, 1, 0.02, 0.03)] {
        let img = indirect(&mut r, method, 7, vpls, 24, 24, 64, 32);
        let vals: Vec<f32> = img.iter().map(|p| p[0]).collect();
        assert!(img.iter().all(|p| p[0] == p[1] && p[1] == p[2]), "grey scene, grey result");
        let mean = vals.iter().sum::<f32>() / vals.len() as f32;
        let rms = (vals.iter().map(|v| ((v - want) / want).powi(2)).sum::<f32>() / vals.len() as f32).sqrt();
        let worst = vals.iter().map(|v| ((v - want) / want).abs()).fold(0.0f32, f32::max);
        eprintln!(
            "sphere {}: mean {mean:.5} vs closed form {want:.5} ({:+.2}%), per-pixel rms {:.2}%, worst {:.2}%",
            method.name(),
            100.0 * (mean - want) / want,
            100.0 * rms,
            100.0 * worst
        );
        assert!(((mean - want) / want).abs() <= mean_tol, "{}: mean {mean} vs {want}", method.name());
        if method == Method::All {
            assert!(worst <= pixel_tol, "all: worst pixel off by {:.2}%", 100.0 * worst);
        } else {
            assert!(rms <= pixel_tol, "uniform: per-pixel rms {:.2}%", 100.0 * rms);
        }
    }
}

/// Mean of K seeds of each sampling method against `all` on the Cornell box (occlusion, corners): the
/// squared error of the K-seed mean falls like 1/K (1/√K in RMS), and the image-mean difference stays
/// within 4 standard errors (estimated from the seeds' spread) of zero.
///
/// The estimators are heavy-tailed (a VPL drawn rarely but contributing much: near a corner, or one a
/// CDF built from 16 gather points undervalues), and then a few seeds underestimate the spread and
/// the mean: with the default defensive share 0.1, 48 seeds put `global` at −6 σ, 64 others at −0.8 σ.
/// Unbiasedness holds for any defensive share ε > 0 (p_v ≥ ε / #VPLs > 0 wherever a VPL can
/// contribute), so the test uses ε = 0.5, which bounds c/p like `uniform`'s, the 1/d² clamp (1 % of the
/// diagonal) on both sides, and 48 seeds: then the 4 σ criterion means what it says. (The biased
/// alternatives this catches, e.g. a probability that does not match the draw, shift the mean by
/// many σ at this spread; the `cdf` tests check the draws themselves.)
#[test]
fn every_method_converges_to_all_at_the_monte_carlo_rate() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = (24, 24, 32, 32);
    let clamp = 0.01;
    // One VPL set for `all` and every run: the seed mean converges to `all` on it.
    let vpl_seed = Some(1);
    let all = indirect_with(
        &mut r,
        FrameSettings {
            method: Method::All,
            clamp,
            vpl_seed,
            component: Component::Direct,
            ..FrameSettings::default()
        },
        w,
        h,
        res,
        vox,
    );
    for (method, face) in [
        (Method::Uniform, FaceMode::RussianRoulette),
        (Method::Global, FaceMode::RussianRoulette),
        (Method::Stratified, FaceMode::RussianRoulette),
        (Method::Local, FaceMode::RussianRoulette),
        (Method::Gbg, FaceMode::RussianRoulette),
        (Method::Gbg, FaceMode::Uniform),
        (Method::Mis, FaceMode::RussianRoulette),
    ] {
        let settings = |seed| FrameSettings {
            method,
            face,
            seed,
            vpl_seed,
            vpls: 8,
            cdf_samples: 16,
            clamp,
            defensive: 0.5,
            component: Component::Direct,
            ..FrameSettings::default()
        };
        let name = format!("{} (face {:?})", method.name(), face);
        converges_to(&name, &all, |seed| indirect_with(&mut r, settings(seed), w, h, res, vox));
    }
}

/// The CDF methods' near share (`FrameSettings::near_share`) where the default scene does not reach it:
/// two lights (a draw picks a window among every light's, `glsl/shared/near_window.glsl`) and every
/// light map (the paraboloid pair, the cube's six faces, and the one perspective face, whose map leaves
/// some pixels outside: their windows stay closed and they draw from the mixture alone). A 5 × 5
/// window for half the samples, so a window is a strict part of each face; unbiased against `all` with
/// the same light map.
#[test]
fn near_share_is_unbiased_with_two_lights_and_every_light_map() {
    use bounce_graph::frame::LightMap;
    let scene = Scene::load(&bounce_tests::workspace().join("assets/clutter/scene.toml")).unwrap();
    assert_eq!(scene.lights.len(), 2);
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = (24, 24, 32, 32);
    for light_map in [LightMap::Dprsm, LightMap::Cube, LightMap::Rsm { fov_deg: 60.0 }] {
        let base = FrameSettings {
            clamp: 0.01,
            light_map,
            component: Component::Direct,
            defensive: 0.5,
            near_share: 0.5,
            vpls: 8,
            // `all`'s VPL set in every run.
            vpl_seed: Some(1),
            ..FrameSettings::default()
        };
        let all = indirect_with(&mut r, FrameSettings { method: Method::All, ..base.clone() }, w, h, res, vox);
        converges_to(&format!("global (near share 0.5, 5 × 5, two lights, {light_map:?})"), &all, |seed| {
            let mut s = FrameSettings { method: Method::Global, seed, ..base.clone() };
            s.ris.near_radius = 2;
            indirect_with(&mut r, s, w, h, res, vox)
        });
    }
}

pub(crate) fn converges_to(name: &str, all: &[[f32; 3]], mut run: impl FnMut(u64) -> Vec<[f32; 3]>) {
    let k_max = 48usize;
    let runs: Vec<Vec<[f32; 3]>> = (0..k_max).map(|k| run(1000 + k as u64)).collect();
    let mse_of_mean = |k: usize| {
        let mut s = 0.0f64;
        for px in 0..all.len() {
            for c in 0..3 {
                let m = runs[..k].iter().map(|img| img[px][c] as f64).sum::<f64>() / k as f64;
                s += (m - all[px][c] as f64).powi(2);
            }
        }
        s / (3 * all.len()) as f64
    };
    let image_mean =
        |img: &[[f32; 3]]| img.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / (3 * img.len()) as f64;
    // Average the single-seed error over all seeds, so the rate is measured against a stable baseline.
    let mse1 = (0..k_max)
        .map(|k| {
            runs[k]
                .iter()
                .zip(all)
                .map(|(a, b)| (0..3).map(|c| (a[c] as f64 - b[c] as f64).powi(2)).sum::<f64>())
                .sum::<f64>()
                / (3 * all.len()) as f64
        })
        .sum::<f64>()
        / k_max as f64;
    let mse16 = mse_of_mean(k_max);
    let ratio = mse16 / (mse1 / k_max as f64);
    let means: Vec<f64> = runs.iter().map(|r| image_mean(r)).collect();
    let m = means.iter().sum::<f64>() / k_max as f64;
    let sd = (means.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (k_max - 1) as f64).sqrt();
    let stderr = sd / (k_max as f64).sqrt();
    let target = image_mean(all);
    eprintln!(
        "{name} vs all: MSE(1 seed) {mse1:.3e}, MSE(mean of {k_max}) {mse16:.3e} = {ratio:.2} × MSE1/{k_max}; image mean {m:.5} ± {stderr:.5} vs all {target:.5}"
    );
    assert!((0.4..2.5).contains(&ratio), "{name}: the error of the mean does not fall like 1/K: ratio {ratio}");
    assert!((m - target).abs() <= 4.0 * stderr.max(1e-9), "{name} biased: {m} vs {target} (stderr {stderr})");
}

/// The CPU one-bounce path tracer (`cpu_ref::indirect_at_pixel`) must itself reproduce the closed form,
/// within its own Monte Carlo error, before it can judge the VPL estimate.
#[test]
fn the_cpu_one_bounce_reference_matches_the_sphere_closed_form() {
    let (radius, rho, intensity) = (1.0f32, 0.5f32, 2.0f32);
    let scene = sphere_scene(radius, 48, rho, Vec3::new(0.25, 0.3, -0.15), intensity);
    let want = (rho * rho * intensity / (PI * radius * radius)) as f64;
    let bvh = bounce_oracles::cpu_ref::Bvh::new(&scene);
    let img = bounce_oracles::cpu_ref::render_indirect(&scene, &bvh, 8, 8, 256, 3);
    let mean = img.iter().map(|(m, _)| m[0] as f64).sum::<f64>() / img.len() as f64;
    let se = (img.iter().map(|(_, e)| (e[0] as f64).powi(2)).sum::<f64>()).sqrt() / img.len() as f64;
    eprintln!("cpu one-bounce on the sphere: {mean:.5} ± {se:.5} vs {want:.5}");
    // 4 standard errors, plus 0.5 % for the tessellation (see sphere_closed_form_all_and_uniform).
    assert!((mean - want).abs() <= 4.0 * se + 0.005 * want, "{mean} vs {want}");
}

/// `all` (the converged VPL estimate, voxel visibility) against the exact one-bounce integral on the
/// Cornell box, at the acceptance setting (DPRSM 128² per face).
#[test]
fn all_agrees_with_the_exact_one_bounce_reference_in_the_cornell_box() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let (w, h) = (24, 24);
    let bvh = bounce_oracles::cpu_ref::Bvh::new(&scene);
    let reference = bounce_oracles::cpu_ref::render_indirect(&scene, &bvh, w, h, 2048, 11);
    let r_img: Vec<[f32; 3]> = reference.iter().map(|(m, _)| *m).collect();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let all = indirect(&mut r, Method::All, 0, 1, w, h, 128, 128);
    let e = bounce_tests::rel_mse(&all, &r_img);
    let (ma, mr) = (bounce_tests::mean(&all), bounce_tests::mean(&r_img));
    // The reference's own noise, in the same metric.
    let noise = reference
        .iter()
        .map(|(m, s)| (0..3).map(|c| (s[c] as f64).powi(2) / ((m[c] as f64).powi(2) + 0.01)).sum::<f64>())
        .sum::<f64>()
        / (3 * reference.len()) as f64;
    eprintln!(
        "all vs exact one-bounce: relMSE {e:.4} (reference noise {noise:.4}), mean {ma:.5} vs {mr:.5} ({:+.2}%)",
        100.0 * (ma - mr) / mr
    );
    // The acceptance bar for `all` against an independent one-bounce tracer. What separates
    // them: the DPRSM's discretisation, the voxel march (conservative cells fatten occluders: darker)
    // and the VPL singularity at corners (brighter); the reference's own noise is in `noise`.
    assert!(e <= 0.02, "relMSE {e}");
    assert!(((ma - mr) / mr).abs() <= 0.03, "mean {ma} vs {mr}");
}

/// The VPL kernel (`--vpl-kernel`, glsl/shared/vpl.glsl) against the exact one-bounce image: the converged
/// sum (`all`, exact visibility) with the patch kernel must be at least 2× closer in relMSE than with the
/// thesis's point kernel on the Cornell box, whose corners put receivers next to VPLs, over 8 VPL sets (the
/// VPLs' places in their texels, `FrameSettings::vpl_seed`: where a VPL lands next to a receiver decides
/// the point kernel's error), and its mean, which loses the energy the kernel bounds next to receivers,
/// must stay within 2.5 % of the reference at 32² per face and 1.5 % at 64², the loss shrinking as the
/// maps grow. At these coarse maps the patches are large, so both the point kernel's spikes and the patch
/// kernel's loss show most (measured here: relMSE 0.021 → 0.0024 at 32², 0.0029 → 0.0010 at 64²; the patch
/// kernel's mean −1.8 % and −0.7 %, the point kernel's, unbiased, −0.5 % and −0.0 %; with the texel
/// centres, one VPL set, the patch kernel read +0.7 % and −1.1 %: the centres' own error offset its loss).
/// The reference is the GPU path tracer
/// (`Method::Reference`, checked against the CPU tracer and closed forms in reference.rs) at 16384 paths
/// per pixel, whose own relMSE (≈ 1e-4) is well under the differences measured; the CPU tracer at a
/// test's budget is not (2048 paths: 0.0033).
#[test]
fn the_patch_kernel_brings_the_vpl_sum_closer_to_the_exact_one_bounce_image() {
    const SEEDS: u64 = 8;
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let (w, h) = (24, 24);
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let reference = FrameSettings {
        method: Method::Reference,
        spp: 16384,
        component: Component::Direct,
        ..FrameSettings::default()
    };
    let r_img = indirect_with(&mut r, reference, w, h, 32, 32);
    let mr = bounce_tests::mean(&r_img);
    let mut biases = vec![];
    for res in [32, 64] {
        let sum = |r: &mut Renderer, vpl_kernel, seed| {
            let s = FrameSettings {
                method: Method::All,
                vpl_kernel,
                seed,
                component: Component::Direct,
                ..FrameSettings::default()
            };
            indirect_with(r, s, w, h, res, 32)
        };
        let (mut ep, mut eq, mut mq, mut mp) = (0.0, 0.0, 0.0, 0.0);
        for seed in 1..=SEEDS {
            let (point, patch) = (sum(&mut r, VplKernel::Point, seed), sum(&mut r, VplKernel::Patch, seed));
            let (p, q) = (bounce_tests::rel_mse(&point, &r_img), bounce_tests::rel_mse(&patch, &r_img));
            eprintln!("{res}², VPL seed {seed}: relMSE point {p:.5}, patch {q:.5}");
            ep += p / SEEDS as f64;
            eq += q / SEEDS as f64;
            mq += bounce_tests::mean(&patch) / SEEDS as f64;
            mp += bounce_tests::mean(&point) / SEEDS as f64;
        }
        eprintln!(
            "{res}² per face, over {SEEDS} VPL sets: relMSE against the exact image: point {ep:.5}, patch {eq:.5}; patch mean {:+.2}%, point {:+.2}%",
            100.0 * (mq - mr) / mr,
            100.0 * (mp - mr) / mr
        );
        assert!(2.0 * eq <= ep, "{res}²: the patch kernel's relMSE {eq} is not 2× below the point kernel's {ep}");
        biases.push((mq - mr) / mr);
        assert!(
            biases[biases.len() - 1].abs() <= if res == 32 { 0.025 } else { 0.015 },
            "{res}²: patch kernel mean {mq} vs {mr}"
        );
    }
    // The patch kernel's loss is the patches' size next to the receivers: it shrinks as the maps grow.
    assert!(biases[1].abs() < 0.6 * biases[0].abs(), "the patch kernel's bias does not shrink: {biases:?}");
}

/// `mis` against `all` with either visibility (voxel march, BVH) and at the default defensive share:
/// the mean of 64 seeds within 4 standard errors. Both strategies' densities are exact (see
/// glsl/mis.comp), so this holds at any ray count; the bias the planar-patch model had (−6 % voxel,
/// −3 % exact) would be over 10 σ here. The thesis's literal weights (`--mis-weights thesis`) do not add
/// to one per sample: their mean must lie more than 4 standard errors from `all`'s (the test sees their
/// bias), and their images must be finite.
#[test]
fn mis_is_unbiased_with_either_visibility_and_the_thesis_weights_are_not() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = (24, 24, 32, 32);
    for visibility in [Visibility::Voxel, Visibility::Exact] {
        let base = FrameSettings {
            clamp: 0.01,
            visibility,
            method: Method::Uniform,
            component: Component::Direct,
            ..FrameSettings::default()
        };
        let all = indirect_with(&mut r, FrameSettings { method: Method::All, ..base.clone() }, w, h, res, vox);
        let target = bounce_tests::mean(&all);
        for weights in [MisWeights::Consistent, MisWeights::Thesis] {
            let seeds = if weights == MisWeights::Consistent { 64 } else { 8 };
            let s = FrameSettings { mis_weights: weights, ..base.clone() };
            let (m, se) = mis_seed_mean(&mut r, &s, 5000..5000 + seeds, (w, h, res, vox));
            eprintln!(
                "mis {weights:?}, {visibility:?} visibility: mean of {seeds} seeds {m:.5} ± {se:.5} vs all {target:.5} ({:+.2}%)",
                100.0 * (m - target) / target
            );
            assert!(m.is_finite() && m > 0.0);
            if weights == MisWeights::Consistent {
                assert!((m - target).abs() <= 4.0 * se.max(1e-9), "mis biased: {m} vs {target} (stderr {se})");
            } else {
                // Measured −12 % (voxel) and −8 % (exact), 6–8 standard errors of 8 seeds.
                assert!((m - target).abs() > 4.0 * se, "the thesis's weights are not biased: {m} vs {target} ({se})");
            }
        }
    }
}

/// The image means of `mis` renders of `base` (8 VPLs, 16 gathering rays) for each seed of `seeds` at
/// (width, height, DPRSM resolution, voxels) `size`: their mean and its standard error.
fn mis_seed_mean(
    r: &mut Renderer,
    base: &FrameSettings,
    seeds: std::ops::Range<u64>,
    (w, h, res, vox): (u32, u32, u32, u32),
) -> (f64, f64) {
    let means: Vec<f64> = seeds
        .map(|seed| {
            // `all`'s VPL set (its seed's places in the texels): the mean is over the picks alone.
            let vpl_seed = Some(base.seed);
            let s = FrameSettings { method: Method::Mis, seed, vpl_seed, vpls: 8, gather_rays: 16, ..base.clone() };
            bounce_tests::mean(&indirect_with(r, s, w, h, res, vox))
        })
        .collect();
    bounce_tests::mean_and_stderr(&means)
}

/// Two triangles: the quad a, b, c, d.
fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> [[Vec3; 3]; 2] {
    [[a, b, c], [a, c, d]]
}

/// A floor meeting a wall, seen close up, with a coarse DPRSM (8² a face): the floor texels next to the
/// wall have footprints reaching behind the wall's plane, so at the wall's pixels only their front part
/// Q_v⁺ counts (glsl/mis.comp). `mis` must still average to `all`: the mean of 64 seeds within 4
/// standard errors, with exact visibility. (Giving the gathering rays the whole patch's area made it
/// −1.9 % biased here, drawing the CDF samples' y from the whole patch +2.5 %: 14 and 18 σ. The
/// default scene's test above passed both.)
#[test]
fn mis_is_unbiased_where_patches_reach_behind_a_junction() {
    let v = Vec3::new;
    let mut tris = vec![];
    tris.extend(quad(v(-2.0, 0.0, -1.0), v(2.0, 0.0, -1.0), v(2.0, 0.0, 2.0), v(-2.0, 0.0, 2.0)));
    tris.extend(quad(v(-2.0, 0.0, -1.0), v(2.0, 0.0, -1.0), v(2.0, 2.0, -1.0), v(-2.0, 2.0, -1.0)));
    let albedo = vec![Vec3::splat(0.7); tris.len()];
    let camera = Camera { eye: v(0.0, 0.5, 0.6), target: v(0.0, 0.1, -1.0), up: Vec3::Y, fov_y_deg: 60.0 };
    let scene = Scene::from_triangles(&tris, &albedo, camera, &[point_light(v(0.3, 1.2, 0.2), Vec3::splat(20.0))]);
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = (24, 24, 8, 32);
    let base = FrameSettings {
        clamp: 0.01,
        visibility: Visibility::Exact,
        method: Method::Uniform,
        component: Component::Direct,
        ..FrameSettings::default()
    };
    let all = indirect_with(&mut r, FrameSettings { method: Method::All, ..base.clone() }, w, h, res, vox);
    let target = bounce_tests::mean(&all);
    let (m, se) = mis_seed_mean(&mut r, &base, 7000..7064, (w, h, res, vox));
    eprintln!(
        "mis at a junction: mean of 64 seeds {m:.5} ± {se:.5} vs all {target:.5} ({:+.2}%)",
        100.0 * (m - target) / target
    );
    assert!(target > 0.0 && (m - target).abs() <= 4.0 * se.max(1e-9), "mis biased: {m} vs {target} (stderr {se})");
}

/// The part of the rectangle [lo, hi]² (as corners) where s0 + s1·a + s2·b ≥ 0: its vertices (the test's
/// oracle for `glsl/shared/patch.glsl`'s Q_v⁺, computed exactly in f64).
fn clip_rect(lo: [f64; 2], hi: [f64; 2], s: [f64; 3]) -> Vec<[f64; 2]> {
    let f = |p: [f64; 2]| s[0] + s[1] * p[0] + s[2] * p[1];
    let rect = [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]];
    let mut out = vec![];
    for i in 0..4 {
        let (p, r) = (rect[i], rect[(i + 1) % 4]);
        let (fp, fr) = (f(p), f(r));
        if fp >= 0.0 {
            out.push(p);
        }
        if (fp >= 0.0) != (fr >= 0.0) {
            let t = fp / (fp - fr);
            out.push([p[0] + (r[0] - p[0]) * t, p[1] + (r[1] - p[1]) * t]);
        }
    }
    out
}

/// Area, centroid and second moments (E[a²], E[b²], E[ab]) of a polygon (standard polygon moment sums).
fn polygon_moments(p: &[[f64; 2]]) -> (f64, [f64; 2], [f64; 3]) {
    let (mut a, mut cx, mut cy, mut ixx, mut iyy, mut ixy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for i in 0..p.len() {
        let ([x0, y0], [x1, y1]) = (p[i], p[(i + 1) % p.len()]);
        let c = x0 * y1 - x1 * y0;
        a += c;
        cx += (x0 + x1) * c;
        cy += (y0 + y1) * c;
        ixx += (x0 * x0 + x0 * x1 + x1 * x1) * c;
        iyy += (y0 * y0 + y0 * y1 + y1 * y1) * c;
        ixy += (x0 * y1 + 2.0 * x0 * y0 + 2.0 * x1 * y1 + x1 * y0) * c;
    }
    let area = a / 2.0;
    if area.abs() < 1e-300 {
        return (0.0, [0.0; 2], [0.0; 3]);
    }
    (area, [cx / (6.0 * area), cy / (6.0 * area)], [ixx / (12.0 * area), iyy / (12.0 * area), ixy / (24.0 * area)])
}

/// mis's patch in front of the receiver (`glsl/shared/patch.glsl`, through `glsl/test/front_part.comp`):
/// its share of the square is the exactly clipped square's area, and its 32 × 32 stratified points all lie
/// in the clipped square and are uniform there: their mean and second moments are the polygon's, and
/// each cell of a 4 × 4 grid over the square holds its share of them. Cases: random cuts, and the edge
/// cases (cuts parallel to an edge, through a corner, missing the square, taking all of it).
#[test]
fn mis_front_part_is_the_clipped_square_and_its_points_are_uniform() {
    let mut rng = bounce_tests::Rng(0xF00D_5EED);
    let mut cases: Vec<[f32; 4]> = vec![
        [0.3, 0.0, 0.0, 0.0],   // parallel: all in front
        [-0.3, 0.0, 0.0, 0.0],  // parallel: all behind
        [0.1, 1.0, 0.0, 0.0],   // a cut parallel to b
        [0.1, 0.0, -1.0, 0.0],  // a cut parallel to a, flipped
        [0.0, 1.0, 1.0, 0.0],   // the diagonal: half
        [1.0, 1.0, 1.0, 0.0],   // through a corner: all in front
        [-1.0, 1.0, 1.0, 0.0],  // through the other corner: nothing
        [0.25, 0.5, 0.5, 0.0],  // the ramp's end at b = 0
        [0.05, 2.0, -0.3, 0.0], // steep and shallow
    ];
    cases.extend((0..300).map(|_| [rng.range(-1.2, 1.2), rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), 0.0]));
    let gpu = TestGpu::new();
    let shader = bounce_graph::shaders::FRONT_PART_COMP;
    let got: Vec<f32> = bounce_tests::run_test_kernel(&gpu, "front_part", shader, &cases, 2049 * cases.len());
    let (mut checked, mut worst_mean, mut worst_cell) = (0, 0.0f64, 0.0f64);
    for (q, c) in cases.iter().enumerate() {
        let s = [c[0] as f64, c[1] as f64, c[2] as f64];
        let out = &got[q * 2049..(q + 1) * 2049];
        let poly = clip_rect([-0.5, -0.5], [0.5, 0.5], s);
        let (area, centroid, second) = polygon_moments(&poly);
        let frac = out[0] as f64;
        assert!((frac - area).abs() <= 1e-5, "case {q} {c:?}: share {frac}, the clipped square's {area}");
        if area < 0.02 {
            continue;
        }
        let pts: Vec<[f64; 2]> = out[1..].chunks(2).map(|p| [p[0] as f64, p[1] as f64]).collect();
        for pt in &pts {
            let inside = pt[0].abs() <= 0.5 + 1e-6 && pt[1].abs() <= 0.5 + 1e-6;
            assert!(inside && s[0] + s[1] * pt[0] + s[2] * pt[1] >= -1e-5, "case {q} {c:?}: point {pt:?} outside");
        }
        let n = pts.len() as f64;
        let mean = [0, 1].map(|k| pts.iter().map(|p| p[k]).sum::<f64>() / n);
        let sec = [
            pts.iter().map(|p| p[0] * p[0]).sum::<f64>() / n,
            pts.iter().map(|p| p[1] * p[1]).sum::<f64>() / n,
            pts.iter().map(|p| p[0] * p[1]).sum::<f64>() / n,
        ];
        let dm = (0..2).map(|k| (mean[k] - centroid[k]).abs()).chain((0..3).map(|k| (sec[k] - second[k]).abs()));
        let dm = dm.fold(0.0, f64::max);
        worst_mean = worst_mean.max(dm);
        assert!(dm <= 2e-3, "case {q} {c:?}: moments {mean:?} {sec:?} against {centroid:?} {second:?}");
        for (i, j) in (0..4).flat_map(|i| (0..4).map(move |j| (i, j))) {
            let lo = [-0.5 + 0.25 * i as f64, -0.5 + 0.25 * j as f64];
            let hi = [lo[0] + 0.25, lo[1] + 0.25];
            let share = polygon_moments(&clip_rect(lo, hi, s)).0 / area;
            let got = pts.iter().filter(|p| (lo[0]..hi[0]).contains(&p[0]) && (lo[1]..hi[1]).contains(&p[1])).count();
            let d = (got as f64 / n - share).abs();
            worst_cell = worst_cell.max(d);
            // The points are 32 strata per axis, so a cell's share is off by up to about 1/32.
            assert!(d <= 0.045, "case {q} {c:?}: cell ({i}, {j}) holds {got} of {n} points, its share is {share}");
        }
        checked += 1;
    }
    eprintln!(
        "front_part: {checked} cases; worst moment error {worst_mean:.2e}, worst cell share error {worst_cell:.2e}"
    );
    assert!(checked > 200, "only {checked} cases had a part worth checking");
}

/// Two rooms joined by a door: the light is in the right room, the camera in the left one looking at
/// its walls, so most VPLs (the right room's) are invisible from every gather point.
pub fn corner_scene() -> Scene {
    let v = Vec3::new;
    let mut tris = vec![];
    // The outer box [−2, 2] × [0, 2] × [−2, 2].
    tris.extend(quad(v(-2.0, 0.0, -2.0), v(2.0, 0.0, -2.0), v(2.0, 0.0, 2.0), v(-2.0, 0.0, 2.0)));
    tris.extend(quad(v(-2.0, 2.0, -2.0), v(2.0, 2.0, -2.0), v(2.0, 2.0, 2.0), v(-2.0, 2.0, 2.0)));
    tris.extend(quad(v(-2.0, 0.0, -2.0), v(-2.0, 2.0, -2.0), v(-2.0, 2.0, 2.0), v(-2.0, 0.0, 2.0)));
    tris.extend(quad(v(2.0, 0.0, -2.0), v(2.0, 2.0, -2.0), v(2.0, 2.0, 2.0), v(2.0, 0.0, 2.0)));
    tris.extend(quad(v(-2.0, 0.0, -2.0), v(2.0, 0.0, -2.0), v(2.0, 2.0, -2.0), v(-2.0, 2.0, -2.0)));
    tris.extend(quad(v(-2.0, 0.0, 2.0), v(2.0, 0.0, 2.0), v(2.0, 2.0, 2.0), v(-2.0, 2.0, 2.0)));
    // The dividing wall at x = 0, with a door at z ∈ [1, 2].
    tris.extend(quad(v(0.0, 0.0, -2.0), v(0.0, 2.0, -2.0), v(0.0, 2.0, 1.0), v(0.0, 0.0, 1.0)));
    let albedo = vec![Vec3::splat(0.7); tris.len()];
    let camera = Camera { eye: v(-1.8, 1.0, 1.8), target: v(-1.0, 0.8, -2.0), up: Vec3::Y, fov_y_deg: 60.0 };
    Scene::from_triangles(&tris, &albedo, camera, &[point_light(v(1.2, 1.6, -1.4), Vec3::splat(100.0))])
}

/// The thesis's claim, checked: with the light around a corner, the gathering-based CDF and MIS beat
/// `uniform` and `global` at equal VPL count (relMSE against `all`, averaged over 3 seeds).
///
/// Measured at 64² (32 VPLs; defaults: 64 gather points for global, 4 rays per pixel for gbg): uniform
/// 0.42, global 0.11, gbg 0.010, mis 0.010. The claim depends on gbg's ray budget (pixels × rays): at
/// 32² (4096 rays in all) gbg scored 0.15 against global's 0.11 and lost; at 128² it wins by 18×
/// (BENCHMARKS.md).
#[test]
fn around_a_corner_gbg_and_mis_beat_uniform_and_global() {
    let scene = corner_scene();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = (64, 64, 64, 64);
    let all = indirect(&mut r, Method::All, 0, 1, w, h, res, vox);
    eprintln!("around the corner: mean indirect radiance {:.4}", bounce_tests::mean(&all));
    let mut err = std::collections::BTreeMap::new();
    for method in [Method::Uniform, Method::Global, Method::Gbg, Method::Mis] {
        let e = (0..3)
            .map(|k| {
                let s = FrameSettings {
                    method,
                    seed: 40 + k,
                    vpls: 32,
                    component: Component::Direct,
                    ..FrameSettings::default()
                };
                bounce_tests::rel_mse(&indirect_with(&mut r, s, w, h, res, vox), &all)
            })
            .sum::<f64>()
            / 3.0;
        eprintln!("around the corner, 32 VPLs: {} relMSE {e:.4}", method.name());
        err.insert(method.name(), e);
    }
    for good in ["gbg", "mis"] {
        for base in ["uniform", "global"] {
            assert!(err[good] < err[base], "{good} ({}) is not better than {base} ({})", err[good], err[base]);
        }
    }
}

/// `local` is unbiased where a pixel blends regions (its mixture's weights change fastest at a region
/// border): the error (against `all`) of the columns on either side of the vertical region border has
/// the same mean, within noise.
#[test]
fn local_is_unbiased_at_region_borders() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = (32, 32, 32, 32);
    let all = indirect(&mut r, Method::All, 0, 1, w, h, res, vox);
    let mut diffs = vec![];
    for k in 0..12 {
        let s = FrameSettings {
            method: Method::Local,
            regions: 4,
            seed: 70 + k,
            vpls: 8,
            component: Component::Direct,
            ..FrameSettings::default()
        };
        let img = indirect_with(&mut r, s, w, h, res, vox);
        for y in 0..h as usize {
            let (l, rr) = (y * w as usize + w as usize / 2 - 1, y * w as usize + w as usize / 2);
            let lum = |p: [f32; 3]| (p[0] + p[1] + p[2]) as f64 / 3.0;
            diffs.push((lum(img[l]) - lum(all[l])) - (lum(img[rr]) - lum(all[rr])));
        }
    }
    let (m, se) = bounce_tests::mean_and_stderr(&diffs);
    eprintln!("local seam: mean error difference across the border {m:.5} ± {se:.5}");
    assert!(m.abs() <= 4.0 * se, "a seam: {m} ± {se}");
}

/// `local`'s blend of regions (`glsl/shared/regions.glsl`, through `glsl/test/region_weights.comp`):
/// at every pixel of screens of several shapes and grids, the weights are the bilinear weights of the
/// four nearest region centres (computed here independently, as the tent 1 − |c − k| per axis around
/// each centre k, clamped at the screen's edges), sum to 1, give a pixel at a region's centre to that
/// region alone, and change between neighbouring pixels by at most side / size per axis: no seam (the
/// thesis's one CDF per region would jump by 1 at each border).
#[test]
fn local_blends_regions_continuously() {
    let gpu = TestGpu::new();
    let mut cases: Vec<[u32; 4]> = vec![];
    for (w, h, side) in [(32u32, 32u32, 2u32), (48, 20, 3), (17, 29, 4), (64, 64, 8), (9, 9, 1)] {
        for y in 0..h {
            for x in 0..w {
                cases.push([x, y, w | (h << 16), side]);
            }
        }
    }
    let shader = bounce_graph::shaders::REGION_WEIGHTS_COMP;
    let got: Vec<f32> = bounce_tests::run_test_kernel(&gpu, "region_weights", shader, &cases, 8 * cases.len());
    // The weight of each region at case q, summed over the entries that name it.
    let per_region = |q: usize, side: u32| {
        let mut r = vec![0.0f64; (side * side) as usize];
        for j in 0..4 {
            r[got[q * 8 + j] as usize] += got[q * 8 + 4 + j] as f64;
        }
        r
    };
    // The tent weight of centre k along one axis at pixel p of n, the edges' halves clamped to the
    // outermost centre.
    let tent = |p: u32, n: u32, side: u32, k: u32| {
        let c = ((p as f64 + 0.5) * side as f64 / n as f64 - 0.5).clamp(0.0, (side - 1) as f64);
        (1.0 - (c - k as f64).abs()).max(0.0)
    };
    let mut worst_step = 0.0f64;
    for (q, c) in cases.iter().enumerate() {
        let ([x, y, _, side], (w, h)) = (*c, (c[2] & 0xFFFF, c[2] >> 16));
        let r = per_region(q, side);
        assert!((r.iter().sum::<f64>() - 1.0).abs() < 1e-5, "weights do not sum to 1 at {c:?}: {r:?}");
        for (k, got_w) in r.iter().enumerate() {
            let (kx, ky) = (k as u32 % side, k as u32 / side);
            let want = tent(x, w, side, kx) * tent(y, h, side, ky);
            assert!((got_w - want).abs() < 1e-5, "region {k} at {c:?}: {got_w} against {want}");
        }
        // Continuity: against the next pixel to the right and below, on the same screen.
        for (dx, dy, n) in [(1u32, 0u32, w), (0, 1, h)] {
            if x + dx >= w || y + dy >= h {
                continue;
            }
            let next = q + (dx + dy * w) as usize;
            let rn = per_region(next, side);
            let step = r.iter().zip(&rn).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            let bound = side as f64 / n as f64 + 1e-5;
            assert!(step <= bound, "a seam between {c:?} and its neighbour: {step} > {bound}");
            worst_step = worst_step.max(step * n as f64 / side as f64);
        }
    }
    eprintln!("local's blend: {} pixels; largest step between neighbours {worst_step:.3} of side / size", cases.len());
}

/// A given seed gives the same image (bit for bit), also for gbg, whose importance is a sum of atomic
/// adds (u64 fixed point, so the order threads add in does not matter); another seed gives another.
#[test]
fn a_seed_gives_one_image() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    for method in [Method::Uniform, Method::Gbg, Method::Mis] {
        let mut run = |seed| {
            indirect_with(
                &mut r,
                FrameSettings { method, seed, vpls: 4, component: Component::Direct, ..FrameSettings::default() },
                16,
                16,
                32,
                32,
            )
        };
        let (a, b, c) = (run(9), run(9), run(10));
        assert_eq!(a, b, "{}: the same seed gave two images", method.name());
        assert_ne!(a, c, "{}: another seed gave the same image", method.name());
    }
}

/// With exact visibility (`--visibility exact`: shadow rays against the BVH) the converged VPL sum `all`
/// agrees with the GPU reference up to the reference's noise and the DPRSM's discretisation: what
/// remains of the voxel version's difference is the voxel march's own error.
#[test]
fn all_with_exact_visibility_agrees_with_the_reference() {
    use bounce_graph::frame::Visibility;
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h) = (24, 24);
    let exact = indirect_with(
        &mut r,
        FrameSettings {
            method: Method::All,
            visibility: Visibility::Exact,
            component: Component::Direct,
            ..FrameSettings::default()
        },
        w,
        h,
        64,
        64,
    );
    let reference = indirect_with(
        &mut r,
        FrameSettings { method: Method::Reference, spp: 256, component: Component::Direct, ..FrameSettings::default() },
        w,
        h,
        64,
        64,
    );
    let e = bounce_tests::rel_mse(&exact, &reference);
    let (me, mr) = (bounce_tests::mean(&exact), bounce_tests::mean(&reference));
    eprintln!(
        "all (exact visibility) vs reference: relMSE {e:.4}, mean {me:.5} vs {mr:.5} ({:+.2}%)",
        100.0 * (me - mr) / mr
    );
    // The 256-sample reference (MIS, stratified) alone carries relMSE ≈ 1e-4 here (8.4e-5 measured at
    // 64² against an 8192-sample one), so what remains is `all`'s own difference.
    assert!(e <= 0.01, "relMSE {e}");
    assert!(((me - mr) / mr).abs() <= 0.02, "mean {me} vs {mr}");
}
