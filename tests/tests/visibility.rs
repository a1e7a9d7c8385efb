//! `--visibility hybrid` (glsl/shared/hybrid.glsl): a march through a grid of triangle lists
//! (crates/graph/src/bvh/cells.rs) that tests each entered cell's own triangles. It must give
//! `--visibility exact`'s answer (the default), so every GPU test compares it with exact, per pixel, on the stress scenes of scripts/make-scenes.py, where the plain voxel march
//! (`--visibility voxel`) goes measurably wrong: each test also checks that the voxel march does differ
//! there, so the scene really exposes the cause. Sizes are tiny (24², DPRSM 16², 32 cells).
//!
//! Tolerance: the two variants bound a dispatch's VPLs differently (Renderer::vpls_per_dispatch), so the
//! f32 sums over VPLs are split at other places; that changes a pixel by a few ulps of its sum
//! (measured: ≤ 6e-8 absolute). Any visibility decision that differs moves a pixel by a whole VPL's
//! contribution, orders of magnitude above `PIXEL_TOL`.

use bounce_graph::camera::Camera;
use bounce_graph::frame::{Component, FrameSettings, Method, Renderer, ShadowRays, Visibility};
use bounce_graph::scene::{point_light, Scene};
use bounce_tests::TestGpu;
use glam::Vec3;

/// Per pixel: |hybrid − exact| ≤ PIXEL_TOL · (exact + 1e-3) (see the module doc).
const PIXEL_TOL: f32 = 1e-5;

fn stress_scene(name: &str) -> Scene {
    Scene::load(&bounce_tests::workspace().join(format!("assets/{name}/scene.toml"))).unwrap()
}

fn settings(method: Method, visibility: Visibility) -> FrameSettings {
    FrameSettings {
        width: 24,
        height: 24,
        component: Component::Indirect,
        method,
        visibility,
        vpls: 16,
        seed: 5,
        dprsm_res: 16,
        voxels: 32,
        ..FrameSettings::default()
    }
}

fn render(r: &mut Renderer, s: &FrameSettings) -> Vec<[f32; 3]> {
    let f = r.render(s).unwrap();
    assert!(f.radiance.iter().all(|p| p.iter().all(|c| c.is_finite())), "non-finite radiance");
    f.radiance.iter().map(|p| [p[0], p[1], p[2]]).collect()
}

/// The worst pixel of `a` against `b`, relative as PIXEL_TOL is.
fn worst_pixel(a: &[[f32; 3]], b: &[[f32; 3]]) -> f32 {
    a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| (x - y).abs() / (y.abs() + 1e-3)).fold(0.0, f32::max)
}

/// Renders `method` with exact, hybrid and voxel visibility; asserts hybrid = exact per pixel; returns
/// (exact mean, voxel mean, worst voxel pixel).
fn hybrid_matches_exact(name: &str, r: &mut Renderer, method: Method) -> (f64, f64, f32) {
    let exact = render(r, &settings(method, Visibility::Exact));
    let hybrid = render(r, &settings(method, Visibility::Hybrid));
    let voxel = render(r, &settings(method, Visibility::Voxel));
    let worst = worst_pixel(&hybrid, &exact);
    let (me, mh, mv) = (bounce_tests::mean(&exact), bounce_tests::mean(&hybrid), bounce_tests::mean(&voxel));
    let wv = worst_pixel(&voxel, &exact);
    eprintln!("{name} {method:?}: exact mean {me:.6}, hybrid {mh:.6} (worst pixel {worst:.2e}), voxel {mv:.6} (worst pixel {wv:.2e})");
    assert!(me > 0.0, "{name}: the indirect image is black");
    assert!(worst <= PIXEL_TOL, "{name} {method:?}: hybrid differs from exact by {worst:.3e} at a pixel");
    (me, mv, wv)
}

/// The converged sum (`all`) on each stress scene: hybrid = exact per pixel, while the voxel march is off
/// by several percent somewhere (so each scene exposes the march's error).
#[test]
fn hybrid_all_is_exact_on_the_stress_scenes() {
    for name in ["box-on-floor", "doorway", "clutter"] {
        let scene = stress_scene(name);
        let gpu = TestGpu::new();
        let mut r = Renderer::new(&gpu, &scene).unwrap();
        let (_, _, voxel_worst) = hybrid_matches_exact(name, &mut r, Method::All);
        assert!(voxel_worst > 0.05, "{name}: the voxel march is within 5% everywhere: the scene exposes nothing");
    }
}

/// The sampled methods that trace: `uniform` (shadow rays) and `mis` (also its gathering rays' first hits,
/// hybrid_trace in closest-hit mode). Same seed, so the same samples: the same image as exact.
#[test]
fn hybrid_sampled_and_mis_are_exact() {
    let scene = stress_scene("clutter");
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    for method in [Method::Uniform, Method::Mis] {
        hybrid_matches_exact("clutter", &mut r, method);
    }
}

/// `--shadow-rays pool` (the gather's exact rays shared by a subgroup) renders the queue's images: the
/// same samples and the same answers, so bit for bit where both fit one dispatch (40 samples), and
/// within PIXEL_TOL for `all`, whose dispatches the two loop bounds split at other VPLs. The image is
/// 27 × 21, so the last workgroups hold invocations off the image, which the pool still needs.
#[test]
fn the_subgroup_pool_renders_the_queues_images() {
    let scene = stress_scene("clutter");
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    for (method, vpls) in [(Method::Uniform, 40), (Method::All, 16)] {
        let s = FrameSettings { width: 27, height: 21, vpls, ..settings(method, Visibility::Exact) };
        let queue = render(&mut r, &s);
        let pool = render(&mut r, &FrameSettings { shadow_rays: ShadowRays::Pool, ..s });
        assert!(bounce_tests::mean(&queue) > 0.0, "{method:?}: the indirect image is black");
        if method == Method::Uniform {
            assert!(queue == pool, "{method:?}: the pool's image differs from the queue's");
        } else {
            let worst = worst_pixel(&pool, &queue);
            assert!(worst <= PIXEL_TOL, "{method:?}: the pool differs from the queue by {worst:.3e} at a pixel");
        }
    }
}

/// Wall junctions: the camera looks into the corner where two walls meet the floor, and at the base of
/// the green box, so nearly every pixel lies within a few pixels of a junction. Hybrid = exact at every
/// pixel; the voxel march darkens there (its conservative cells and 2-cell end skip).
#[test]
fn hybrid_has_no_seams_at_junctions() {
    let mut scene = stress_scene("box-on-floor");
    scene.camera =
        Camera { eye: Vec3::new(0.9, 0.9, 0.9), target: Vec3::new(-1.6, 0.1, -1.6), up: Vec3::Y, fov_y_deg: 50.0 };
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (me, mv, _) = hybrid_matches_exact("box-on-floor junctions", &mut r, Method::All);
    assert!(mv < 0.97 * me, "the voxel march does not darken the junctions ({mv} vs {me}): nothing exposed");
}

/// Thin walls: a closed room split by a zero-thickness wall with no opening, the light on one side, the
/// camera on the other. No VPL is visible from any gather point (every VPL lies on the light's side), so
/// the indirect image is exactly black with hybrid, as with exact rays; and the doorway scene (the same
/// wall with an opening) agrees with exact per pixel.
#[test]
fn hybrid_does_not_leak_through_thin_walls() {
    let q = |a: Vec3, b: Vec3, c: Vec3, d: Vec3| [[a, b, c], [a, c, d]];
    let v = Vec3::new;
    let (x0, x1, y1, z0, z1) = (-3.0, 3.0, 2.5, -1.5, 1.5);
    let mut tris = vec![];
    for (a, b, c, d) in [
        (v(x0, 0.0, z0), v(x1, 0.0, z0), v(x1, 0.0, z1), v(x0, 0.0, z1)),
        (v(x0, y1, z0), v(x0, y1, z1), v(x1, y1, z1), v(x1, y1, z0)),
        (v(x0, 0.0, z0), v(x0, 0.0, z1), v(x0, y1, z1), v(x0, y1, z0)),
        (v(x1, 0.0, z0), v(x1, y1, z0), v(x1, y1, z1), v(x1, 0.0, z1)),
        (v(x0, 0.0, z0), v(x0, y1, z0), v(x1, y1, z0), v(x1, 0.0, z0)),
        (v(x0, 0.0, z1), v(x1, 0.0, z1), v(x1, y1, z1), v(x0, y1, z1)),
        // The dividing wall, zero thickness, floor to ceiling.
        (v(0.0, 0.0, z0), v(0.0, y1, z0), v(0.0, y1, z1), v(0.0, 0.0, z1)),
    ] {
        tris.extend(q(a, b, c, d));
    }
    let albedo = vec![Vec3::splat(0.7); tris.len()];
    let camera = Camera { eye: v(-2.8, 1.3, -1.3), target: v(0.0, 0.9, 0.6), up: Vec3::Y, fov_y_deg: 70.0 };
    let scene = Scene::from_triangles(&tris, &albedo, camera, &[point_light(v(1.8, 1.6, -0.6), Vec3::splat(6.0))]);
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let hybrid = render(&mut r, &settings(Method::All, Visibility::Hybrid));
    let voxel = render(&mut r, &settings(Method::All, Visibility::Voxel));
    let lit = hybrid.iter().flatten().filter(|c| **c != 0.0).count();
    eprintln!(
        "sealed wall: hybrid mean {:.3e}, voxel mean {:.3e}",
        bounce_tests::mean(&hybrid),
        bounce_tests::mean(&voxel)
    );
    assert_eq!(lit, 0, "{lit} channels of the sealed room are lit through the wall");

    let scene = stress_scene("doorway");
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    hybrid_matches_exact("doorway", &mut r, Method::All);
}

/// The triangle lists the GPU marches, checked by their CPU twin (bounce_oracles::cpu_cells) against
/// every triangle of the scene: on random pairs of surface points of each stress scene and the Cornell
/// box, at a coarse and a fine voxel grid, the march over the lists finds a segment occluded exactly when
/// some triangle crosses it. A list that missed a triangle a segment crosses would show here.
#[test]
fn the_triangle_lists_hold_every_occluder_a_segment_meets() {
    use bounce_graph::bvh::cells::CellLists;
    use bounce_graph::bvh::{Bvh, FlatBvh};
    use bounce_oracles::cpu_cells;
    for name in ["cornell-box", "box-on-floor", "doorway", "clutter"] {
        let scene = stress_scene(name);
        let flat = FlatBvh::new(&Bvh::new(&scene), &scene.vertices);
        let tris: Vec<[Vec3; 3]> =
            scene.vertices.chunks(3).map(|v| [v[0].position(), v[1].position(), v[2].position()]).collect();
        for voxels in [16, 128] {
            let spec = bounce_graph::passes::voxelize::fit(scene.bounds_min, scene.bounds_max, voxels);
            let lists = CellLists::build(&flat.tris, &spec);
            let mut rng = bounce_tests::Rng(11 + voxels as u64);
            let (mut occluded, mut tested) = (0, 0u64);
            for _ in 0..3000 {
                let ta = tris[rng.below(tris.len() as u32) as usize];
                let tb = tris[rng.below(tris.len() as u32) as usize];
                let (a, b) = (rng.on_triangle(&ta).as_dvec3(), rng.on_triangle(&tb).as_dvec3());
                let m = cpu_cells::march(&lists, &spec, &flat.tris, a, b, 1e-4, 1.0 - 1e-4);
                let truth = cpu_cells::brute_force(&flat.tris, a, b, 1e-4, 1.0 - 1e-4);
                assert_eq!(
                    m.occluded, truth,
                    "{name}, {voxels} voxels: the lists disagree with every triangle on {a} → {b}"
                );
                occluded += truth as u32;
                tested += m.tests as u64;
            }
            eprintln!(
                "{name}, {voxels} voxels: {occluded} of 3000 occluded, {:.1} tests per march",
                tested as f64 / 3000.0
            );
            // Both answers occur often, so the comparison has teeth.
            assert!(occluded > 100 && occluded < 2900, "{name}: {occluded} occluded");
        }
    }
}

/// The threaded BVH the shadow rays walk (`FlatBvh::threaded`, `bvh_any_hit`): a box's link may skip
/// only triangles inside the box, so the CPU twin of the walk (`bounce_oracles::cpu_threaded`) finds an
/// occluder exactly when a brute force over every triangle does, on the stress scenes; and it skips
/// (reads fewer than three quarters of the records, on scenes of 35 to a few hundred). Its steps, two
/// boxes at a time where a met box's successor is packed into it, are fewer than its records.
#[test]
fn the_threaded_walk_finds_every_occluder_a_segment_meets() {
    use bounce_graph::bvh::{Bvh, FlatBvh};
    use bounce_oracles::{cpu_cells, cpu_threaded};
    for name in ["cornell-box", "box-on-floor", "doorway", "clutter"] {
        let scene = stress_scene(name);
        let flat = FlatBvh::new(&Bvh::new(&scene), &scene.vertices);
        let records = flat.threaded();
        let tris: Vec<[Vec3; 3]> =
            scene.vertices.chunks(3).map(|v| [v[0].position(), v[1].position(), v[2].position()]).collect();
        let mut rng = bounce_tests::Rng(23);
        let (mut occluded, mut read, mut steps) = (0, 0u64, 0u64);
        for _ in 0..3000 {
            let ta = tris[rng.below(tris.len() as u32) as usize];
            let tb = tris[rng.below(tris.len() as u32) as usize];
            let (a, b) = (rng.on_triangle(&ta).as_dvec3(), rng.on_triangle(&tb).as_dvec3());
            let w = cpu_threaded::walk(&records, a, b, 1e-4, 1.0 - 1e-4);
            let truth = cpu_cells::brute_force(&flat.tris, a, b, 1e-4, 1.0 - 1e-4);
            assert_eq!(w.occluded, truth, "{name}: the walk disagrees with every triangle on {a} → {b}");
            occluded += truth as u32;
            read += w.records as u64;
            steps += w.steps as u64;
        }
        let per_ray = read as f64 / 3000.0;
        eprintln!(
            "{name}: {occluded} of 3000 occluded, {per_ray:.1} of {} records read per ray in {:.1} steps",
            records.len(),
            steps as f64 / 3000.0
        );
        assert!(steps < read, "{name}: {steps} steps for {read} records: no box was read with the one before it");
        assert!(occluded > 100 && occluded < 2900, "{name}: {occluded} occluded");
        assert!(per_ray < 0.75 * records.len() as f64, "{name}: the walk reads {per_ray:.0} records per ray");
    }
}
