//! `--light-map dprsm|rsm|cube` (thesis §6.3): the same VPL pipeline on three maps at the light. Their
//! texels' solid angles must tile what they cover (a light sealed in a box makes every texel a VPL, so
//! Σ Δω is the covered solid angle), the three must converge to the same `all` image where the RSM sees
//! the whole scene, and the RSM must report the flux it cannot see.

use bounce_graph::camera::Camera;
use bounce_graph::frame::{Component, FrameSettings, LightMap, Method, Renderer};
use bounce_graph::scene::{point_light, Scene};
use bounce_tests::TestGpu;
use glam::Vec3;
use std::f64::consts::PI;

fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> [[Vec3; 3]; 2] {
    [[a, b, c], [a, c, d]]
}

/// Σ Δω over the texels of a light sealed in a box: 4π for the dual paraboloid (its rim's texels in
/// or out by where their VPLs fall) and the cube map; the square pyramid 4 asin(sin²(fov/2)) for
/// the RSM (2π/3 at 90°, 3.392 at 120°).
#[test]
fn texel_solid_angles_cover_each_map() {
    let c = Vec3::new(0.0, 1.0, 0.0);
    let tris = bounce_tests::closed_box(c, 0.5);
    let camera = Camera { eye: c, target: c + Vec3::Z, up: Vec3::Y, fov_y_deg: 60.0 };
    let scene = Scene::from_triangles(&tris, &vec![Vec3::splat(0.5); tris.len()], camera, &[point_light(c, Vec3::ONE)]);
    let gpu = TestGpu::new();
    let r = Renderer::new(&gpu, &scene).unwrap();
    let res = 64;
    for (map, want, tol) in [
        // The rim: ~400 texels of ~1e-3 sr that the disk cuts, each in or out by where its VPL falls in it
        // (`Keys::vpl_offset`): σ ≈ 0.01 sr, so 3e-3 of 4π is about 4 σ.
        (LightMap::Dprsm, 4.0 * PI, 3e-3),
        (LightMap::Cube, 4.0 * PI, 1e-3),
        (LightMap::Rsm { fov_deg: 90.0 }, 2.0 * PI / 3.0, 1e-3),
        (LightMap::Rsm { fov_deg: 120.0 }, 4.0 * (0.75f64).asin(), 1e-3),
    ] {
        assert!((map.solid_angle() - want).abs() < 1e-9, "{map:?}: solid_angle() {}", map.solid_angle());
        let [pos, _, flux] = bounce_tests::maps::render_vpls(
            &r,
            &FrameSettings {
                dprsm_res: res,
                light_map: map,
                method: Method::Uniform,
                component: Component::Direct,
                ..FrameSettings::default()
            },
        )
        .unwrap();
        let valid = pos.iter().filter(|p| p[3] != 0.0).count();
        let sum: f64 = flux.iter().zip(&pos).filter(|(_, p)| p[3] != 0.0).map(|(f, _)| f[3] as f64).sum();
        eprintln!("{map:?}: {valid} VPLs, Σ Δω = {sum:.5} vs {want:.5}");
        assert!((sum - want).abs() <= tol * want, "{map:?}: Σ Δω = {sum} vs {want}");
        if map != LightMap::Dprsm {
            assert_eq!(valid, pos.len(), "{map:?}: every texel of a sealed light sees a wall");
        }
    }
}

/// A floor and a wall that the RSM's 90° pyramid (looking from the light at the scene's centre) sees
/// whole: `all` with each of the three maps converges to the same image. They differ only by where
/// their texels put VPLs (each an unbiased estimate of the same integral: `Keys::vpl_offset`), so over
/// 16 VPL seeds the image means agree within 4 standard errors of their difference (each map's from its
/// seeds' spread) and the mean images' relMSE stays under 0.01 at 128² texels per face; and the RSM's
/// warning gives the flux it misses.
#[test]
fn the_three_light_maps_converge_to_the_same_image() {
    let v = Vec3::new;
    let mut tris = vec![];
    tris.extend(quad(v(-1.0, 0.0, -1.0), v(1.0, 0.0, -1.0), v(1.0, 0.0, 1.0), v(-1.0, 0.0, 1.0)));
    tris.extend(quad(v(-1.0, 0.0, -1.0), v(-1.0, 1.0, -1.0), v(-1.0, 1.0, 1.0), v(-1.0, 0.0, 1.0)));
    let camera = Camera { eye: v(1.8, 1.2, 0.3), target: v(-0.6, 0.2, 0.0), up: Vec3::Y, fov_y_deg: 60.0 };
    let scene = Scene::from_triangles(
        &tris,
        &vec![Vec3::splat(0.7); tris.len()],
        camera,
        &[point_light(v(0.0, 3.0, 0.0), Vec3::splat(20.0))],
    );
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    const SEEDS: u64 = 16;
    let image_mean = |img: &[[f32; 4]]| img.iter().map(|p| p[0] as f64).sum::<f64>() / img.len() as f64;
    // The mean image over the VPL seeds (and the last frame, for its warnings), and each seed's image mean.
    let mut render = |map| {
        let mut f = None;
        let mut sum = vec![[0.0f32; 4]; 32 * 32];
        let mut means = vec![];
        for seed in 1..=SEEDS {
            let s = FrameSettings {
                width: 32,
                height: 32,
                seed,
                component: Component::Indirect,
                method: Method::All,
                dprsm_res: 128,
                voxels: 64,
                light_map: map,
                ..FrameSettings::default()
            };
            let frame = r.render(&s).unwrap();
            for (a, p) in sum.iter_mut().zip(&frame.radiance) {
                (0..4).for_each(|c| a[c] += p[c] / SEEDS as f32);
            }
            means.push(image_mean(&frame.radiance));
            f = Some(frame);
        }
        let (_, se) = bounce_tests::mean_and_stderr(&means);
        (bounce_graph::frame::FrameOutput { radiance: sum, ..f.unwrap() }, se)
    };
    let (dprsm, se0) = render(LightMap::Dprsm);
    let m0 = image_mean(&dprsm.radiance);
    assert!(m0 > 0.0);
    for map in [LightMap::Cube, LightMap::Rsm { fov_deg: 90.0 }] {
        let (f, se) = render(map);
        let m = image_mean(&f.radiance);
        let se = (se * se + se0 * se0).sqrt();
        let rel_mse = f
            .radiance
            .iter()
            .zip(&dprsm.radiance)
            .map(|(a, b)| ((a[0] - b[0]) as f64).powi(2) / ((b[0] as f64).powi(2) + 0.01))
            .sum::<f64>()
            / f.radiance.len() as f64;
        eprintln!(
            "{map:?}: mean {m:.5} vs dprsm {m0:.5} ({:+.2}%, {:.1} standard errors of {:.2}%), relMSE {rel_mse:.2e}",
            100.0 * (m - m0) / m0,
            (m - m0).abs() / se,
            100.0 * se / m0
        );
        assert!((m - m0).abs() <= 4.0 * se, "{map:?}: {m} vs {m0} ({se})");
        assert!(rel_mse < 0.01, "{map:?}: relMSE {rel_mse}");
        let missing = f.warnings.iter().any(|w| w.contains("83.3 %"));
        assert_eq!(missing, matches!(map, LightMap::Rsm { .. }), "{:?}", f.warnings);
    }
}

/// Every method runs on every light map, and every sampled method under per-VPL shadow maps:
/// finite images, no validation message (the TestGpu), on the Cornell box at 16².
#[test]
fn every_method_runs_on_every_light_map_and_psm() {
    use bounce_graph::frame::Visibility;
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let methods = Method::ALL;
    let mut runs = 0;
    for map in [LightMap::Dprsm, LightMap::Rsm { fov_deg: 90.0 }, LightMap::Cube] {
        for visibility in [Visibility::Voxel, Visibility::Psm] {
            for &method in &methods {
                if visibility == Visibility::Psm
                    && matches!(method, Method::All | Method::Reference | Method::Ris | Method::Realtime)
                {
                    continue;
                }
                let s = FrameSettings {
                    width: 16,
                    height: 16,
                    component: Component::Combined,
                    method,
                    visibility,
                    light_map: map,
                    vpls: 8,
                    spp: 8,
                    dprsm_res: 16,
                    psm_res: 32,
                    voxels: 16,
                    ..FrameSettings::default()
                };
                let f = r.render(&s).unwrap_or_else(|e| panic!("{map:?} {visibility:?} {method:?}: {e:#}"));
                assert!(
                    f.radiance.iter().all(|p| p.iter().all(|c| c.is_finite())),
                    "{map:?} {visibility:?} {method:?}: non-finite"
                );
                runs += 1;
            }
        }
    }
    assert_eq!(runs, 3 * (10 + 6));
}
