//! Exact visibility (`--visibility exact`, the default): shadow rays against the triangles through the
//! threaded BVH. A sealed room lets no light through a zero-thickness wall (a closed form: black), and the
//! threaded walk's CPU twin finds an occluder exactly when a brute force over every triangle does.

use bounce_graph::camera::Camera;
use bounce_graph::frame::{Component, FrameSettings, Method, Renderer, Visibility};
use bounce_graph::scene::{point_light, Scene};
use bounce_tests::TestGpu;
use glam::Vec3;

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

/// Thin walls: a closed room split by a zero-thickness wall with no opening, the light on one side, the
/// camera on the other. No VPL is visible from any gather point (every VPL lies on the light's side), so
/// the indirect image is exactly black with exact rays; seen from the light's side it is lit.
#[test]
fn exact_rays_do_not_leak_through_thin_walls() {
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
    let light = [point_light(v(1.8, 1.6, -0.6), Vec3::splat(6.0))];
    let gpu = TestGpu::new();
    // The control: the same room seen from the light's half is lit through exact rays, so a black image
    // below is the wall's doing, not a gather that returns nothing.
    let mirrored = Camera { eye: v(2.8, 1.3, -1.3), target: v(0.0, 0.9, 0.6), ..camera };
    let lit_side = Scene::from_triangles(&tris, &albedo, mirrored, &light);
    let seen = render(&mut Renderer::new(&gpu, &lit_side).unwrap(), &settings(Method::All, Visibility::Exact));
    assert!(bounce_tests::mean(&seen) > 0.0, "the light's half is black: the gather returns nothing");
    let scene = Scene::from_triangles(&tris, &albedo, camera, &light);
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let exact = render(&mut r, &settings(Method::All, Visibility::Exact));
    let lit = exact.iter().flatten().filter(|c| **c != 0.0).count();
    eprintln!(
        "sealed wall: exact mean {:.3e}, seen from the light's half {:.3e}",
        bounce_tests::mean(&exact),
        bounce_tests::mean(&seen)
    );
    assert_eq!(lit, 0, "{lit} channels of the sealed room are lit through the wall");
}

/// The threaded BVH the shadow rays walk (`FlatBvh::threaded`, `bvh_any_hit`): a box's link may skip
/// only triangles inside the box, so the CPU twin of the walk (`bounce_oracles::cpu_threaded`) finds an
/// occluder exactly when a brute force over every triangle does, on the stress scenes; and it skips
/// (reads fewer than three quarters of the records, on scenes of 35 to a few hundred). Its steps, two
/// boxes at a time where a met box's successor is packed into it, are fewer than its records.
#[test]
fn the_threaded_walk_finds_every_occluder_a_segment_meets() {
    use bounce_graph::bvh::{Bvh, FlatBvh};
    use bounce_oracles::{cpu_segment, cpu_threaded};
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
            let truth = cpu_segment::brute_force(&flat.tris, a, b, 1e-4, 1.0 - 1e-4);
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
