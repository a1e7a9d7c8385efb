//! Numerical stress (a first slice of the stress suite): pathological scenes rendered with every method
//! at a tiny size must give finite images, with no validation message (the TestGpu), and the CDF
//! methods must fall back to uniform rather than fail when the importance is zero everywhere.

use bounce_graph::camera::Camera;
use bounce_graph::frame::{Component, FrameSettings, Method, Renderer};
use bounce_graph::scene::{point_light, Scene};
use bounce_tests::TestGpu;
use glam::Vec3;

const METHODS: [Method; 8] = [
    Method::Uniform,
    Method::All,
    Method::Global,
    Method::Stratified,
    Method::Local,
    Method::Gbg,
    Method::Mis,
    Method::Reference,
];

fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> [[Vec3; 3]; 2] {
    [[a, b, c], [a, c, d]]
}

/// An open box (floor, back wall, left wall) and a small blocker: some occlusion, some corners.
fn base_tris(scale: f32, offset: Vec3) -> Vec<[Vec3; 3]> {
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z) * scale + offset;
    let mut t = vec![];
    t.extend(quad(v(-1.0, 0.0, -1.0), v(1.0, 0.0, -1.0), v(1.0, 0.0, 1.0), v(-1.0, 0.0, 1.0)));
    t.extend(quad(v(-1.0, 0.0, -1.0), v(1.0, 0.0, -1.0), v(1.0, 2.0, -1.0), v(-1.0, 2.0, -1.0)));
    t.extend(quad(v(-1.0, 0.0, -1.0), v(-1.0, 2.0, -1.0), v(-1.0, 2.0, 1.0), v(-1.0, 0.0, 1.0)));
    t.push([v(-0.3, 0.5, 0.0), v(0.3, 0.5, 0.0), v(0.0, 0.9, 0.2)]);
    t
}

fn scene(tris: &[[Vec3; 3]], albedo: f32, scale: f32, offset: Vec3, light: Vec3, intensity: f32) -> Scene {
    let albedo = vec![Vec3::splat(albedo); tris.len()];
    let camera = Camera {
        eye: Vec3::new(0.2, 1.2, 3.0) * scale + offset,
        target: Vec3::new(0.0, 0.6, 0.0) * scale + offset,
        up: Vec3::Y,
        fov_y_deg: 60.0,
    };
    Scene::from_triangles(tris, &albedo, camera, &[point_light(light * scale + offset, Vec3::splat(intensity))])
}

/// Every method, combined component, 16×16: finite radiance everywhere; returns the mean per method.
fn render_all_methods(name: &str, s: &Scene) -> Vec<(Method, f64)> {
    let gpu = TestGpu::new();
    let r = Renderer::new(&gpu, s).unwrap_or_else(|e| panic!("{name}: {e:#}"));
    METHODS
        .iter()
        .map(|&method| {
            let fs = FrameSettings {
                width: 16,
                height: 16,
                component: Component::Combined,
                method,
                vpls: 8,
                spp: 16,
                dprsm_res: 16,
                shadow_res: 64,
                voxels: 16,
                ..FrameSettings::default()
            };
            let f = r.render(&fs).unwrap_or_else(|e| panic!("{name}, {}: {e:#}", method.name()));
            let bad = f.radiance.iter().filter(|p| p.iter().any(|c| !c.is_finite())).count();
            assert_eq!(bad, 0, "{name}, {}: {bad} non-finite pixels", method.name());
            let m = f.radiance.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / (3 * f.radiance.len()) as f64;
            (method, m)
        })
        .collect()
}

#[test]
fn zero_albedo_everywhere_renders_black_without_nan() {
    let s = scene(&base_tris(1.0, Vec3::ZERO), 0.0, 1.0, Vec3::ZERO, Vec3::new(0.0, 1.5, 0.5), 2.0);
    for (m, mean) in render_all_methods("zero albedo", &s) {
        assert_eq!(mean, 0.0, "{}: a black scene must render black", m.name());
    }
}

#[test]
fn degenerate_duplicated_and_huge_triangles() {
    let mut t = base_tris(1.0, Vec3::ZERO);
    let p = Vec3::new(0.1, 0.2, 0.3);
    t.push([p, p, p]); // a point
    t.push([p, p + Vec3::X, p + 2.0 * Vec3::X]); // a line
    t.push(t[0]); // a duplicate
    t.push([Vec3::new(-50.0, -0.01, -50.0), Vec3::new(50.0, -0.01, -50.0), Vec3::new(0.0, -0.01, 80.0)]); // huge, under the floor
    let s = scene(&t, 0.6, 1.0, Vec3::ZERO, Vec3::new(0.0, 1.5, 0.5), 2.0);
    render_all_methods("degenerate", &s);
}

#[test]
fn a_light_on_a_surface_and_one_outside_the_scene() {
    let t = base_tris(1.0, Vec3::ZERO);
    // Exactly on the floor (y = 0), and far outside the geometry's bounds.
    render_all_methods("light on the floor", &scene(&t, 0.6, 1.0, Vec3::ZERO, Vec3::new(0.2, 0.0, 0.1), 2.0));
    render_all_methods("light outside", &scene(&t, 0.6, 1.0, Vec3::ZERO, Vec3::new(30.0, 20.0, 40.0), 2000.0));
}

#[test]
fn a_single_triangle_and_nothing_in_front_of_the_light() {
    let one = [[Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0)]];
    render_all_methods("single triangle", &scene(&one, 0.6, 1.0, Vec3::ZERO, Vec3::new(0.0, 1.0, 0.0), 2.0));
    // The light below the floor, facing its underside only from far away: no VPL lights anything visible.
    render_all_methods("light behind", &scene(&one, 0.6, 1.0, Vec3::ZERO, Vec3::new(0.0, -5.0, 0.0), 2.0));
}

/// Scaling a scene by s with intensity scaled by s² leaves radiance unchanged (every term is a ratio of
/// an area or flux to a squared distance): the converged `all` and the reference agree across 1e-3, 1
/// and 1e3 to float precision and noise.
#[test]
fn scaled_scenes_keep_their_radiance() {
    let means: Vec<Vec<(Method, f64)>> = [1e-3f32, 1.0, 1e3]
        .iter()
        .map(|&k| {
            let s = scene(&base_tris(k, Vec3::ZERO), 0.6, k, Vec3::ZERO, Vec3::new(0.0, 1.5, 0.5), 2.0 * k * k);
            render_all_methods(&format!("scale {k}"), &s)
        })
        .collect();
    for (i, &m) in METHODS.iter().enumerate() {
        if !matches!(m, Method::All | Method::Reference | Method::Uniform) {
            continue;
        }
        let base = means[1][i].1;
        for (k, row) in [1e-3, 1e3].iter().zip([&means[0], &means[2]]) {
            let rel = (row[i].1 - base).abs() / base;
            eprintln!("scale {k}, {}: mean {:.5} vs {:.5} ({:+.3}%)", m.name(), row[i].1, base, 100.0 * rel);
            assert!(rel < 0.01, "{} at scale {k}: {} vs {base}", m.name(), row[i].1);
        }
    }
}

/// A scene translated far from the origin renders the same radiance. World coordinates are float32
/// (no camera-relative rendering yet), so this holds to 1 % up to offsets of 10⁴ × the scene's size; at
/// 10⁵ the G-buffer positions are quantised to ~1 % of the scene and the means drift by 4–5 % (printed,
/// README Known issues). The reference's ray origins are lifted by `surface_lift`, which scales with the
/// coordinates: with a fixed lift it was already 6 % off at 10³.
#[test]
fn translated_scenes_keep_their_radiance_up_to_1e4() {
    let mean_of = |off: f32| {
        let o = Vec3::new(off, off * 0.5, -off);
        let s = scene(&base_tris(1.0, o), 0.6, 1.0, o, Vec3::new(0.0, 1.5, 0.5), 2.0);
        render_all_methods(&format!("offset {off}"), &s)
    };
    let base = mean_of(0.0);
    for off in [1e3f32, 1e4, 1e5] {
        let row = mean_of(off);
        for (i, &m) in METHODS.iter().enumerate() {
            if !matches!(m, Method::All | Method::Reference | Method::Uniform) {
                continue;
            }
            let rel = (row[i].1 - base[i].1) / base[i].1;
            eprintln!("offset {off:e}, {}: {:.5} vs {:.5} ({:+.2}%)", m.name(), row[i].1, base[i].1, 100.0 * rel);
            if off <= 1e4 {
                assert!(rel.abs() < 0.01, "{} at offset {off}: {rel:+.4}", m.name());
            }
        }
    }
}
