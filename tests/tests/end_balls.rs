//! The exact gather's end balls (`crates/graph/src/passes/end_balls.rs`, `glsl/shared/end_balls.glsl`).
//!
//! - Each pixel's and VPL's radius against a CPU twin in f64 over every triangle: the distance to the
//!   nearest triangle with a vertex more than a threshold above the end's plane, capped, less one lift.
//!   The GPU classifies at τ in f32, so its radius must lie between the twin's at τ/2 and at 2τ. The upper
//!   bound is the safety the gather relies on: no triangle reaching 2τ above the plane comes within the
//!   ball (a ray's ends lie more than 2τ above it when the ball is used).
//! - The plane is the end's triangle's: the G-buffer's triangle for a pixel (turned to its shading
//!   normal), and for a VPL a triangle that contains it (turned to the light).
//! - The exact gather's, mis's and ris's images with the balls and without are the same, bit for bit, on
//!   the stress scenes and the Cornell box: `uniform`, `all`, `mis` and `ris`.

use bounce_graph::bindings::END_BALL_MAX_RADIUS;
use bounce_graph::frame::{Component, FrameSettings, Method, Renderer, Visibility};
use bounce_graph::scene::Scene;
use bounce_oracles::cpu_end_balls::{lift, point_triangle_distance, radius as twin_radius};
use bounce_tests::TestGpu;
use glam::DVec3;

fn settings(w: u32, dprsm_res: u32) -> FrameSettings {
    FrameSettings {
        width: w,
        height: w,
        component: Component::Indirect,
        dprsm_res,
        visibility: Visibility::Exact,
        method: Method::Uniform,
        ..FrameSettings::default()
    }
}

/// Checks every end of one scene; returns the share of ends (pixels, VPLs) that got a ball.
fn check_radii(path: &str) -> (f64, f64) {
    let gpu = TestGpu::new();
    let scene = Scene::load(&bounce_tests::workspace().join(path)).unwrap();
    let r = Renderer::new(&gpu, &scene).unwrap();
    let s = settings(24, 16);
    let m = bounce_tests::maps::render_end_balls(&r, &s).unwrap();
    let diag = r.uniforms(&s).scene_min[3] as f64;
    let tris: Vec<[DVec3; 3]> = scene
        .vertices
        .chunks(3)
        .map(|v| [v[0].position().as_dvec3(), v[1].position().as_dvec3(), v[2].position().as_dvec3()])
        .collect();
    let rmax = END_BALL_MAX_RADIUS as f64 * diag;
    // f32 rounding of a distance within the cap, generously.
    let eps = 1e-6 * diag;
    let check = |what: &str, p: DVec3, ball: [f32; 4]| -> bool {
        let n = DVec3::new(ball[0] as f64, ball[1] as f64, ball[2] as f64);
        let r_gpu = ball[3] as f64;
        let l = lift(p, diag);
        let tau = l / 16.0;
        let hi = twin_radius(&tris, p, n, 2.0 * tau).min(rmax) - l;
        let lo = twin_radius(&tris, p, n, 0.5 * tau).min(rmax) - l;
        assert!(r_gpu <= hi.max(0.0) + eps, "{path}: {what} at {p}: radius {r_gpu} > {hi}, the largest safe one");
        assert!(r_gpu >= lo - eps, "{path}: {what} at {p}: radius {r_gpu} < {lo}");
        r_gpu > 0.0
    };
    let (mut pixels, mut balls) = (0usize, 0usize);
    for (k, (gp, gn)) in m.g_position.iter().zip(&m.g_normal).enumerate() {
        let ball = m.pixels[k];
        if gp[3] == 0.0 {
            assert_eq!(ball, [0.0; 4], "{path}: a pixel without a surface has a ball");
            continue;
        }
        let p = DVec3::new(gp[0] as f64, gp[1] as f64, gp[2] as f64);
        let t = tris[gn[3].to_bits() as usize];
        let face = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
        let shading = DVec3::new(gn[0] as f64, gn[1] as f64, gn[2] as f64);
        let face = if face.dot(shading) < 0.0 { -face } else { face };
        let n = DVec3::new(ball[0] as f64, ball[1] as f64, ball[2] as f64);
        assert!((n - face).length() < 1e-5, "{path}: pixel {k}'s plane {n} is not its triangle's {face}");
        pixels += 1;
        balls += check("pixel", p, ball) as usize;
    }
    let (mut vpls, mut vpl_balls) = (0usize, 0usize);
    let per_layer = (s.dprsm_res * s.dprsm_res) as usize;
    for (k, (vp, ball)) in m.vpl_position.iter().zip(&m.vpls).enumerate() {
        if vp[3] == 0.0 {
            assert_eq!(*ball, [0.0; 4], "{path}: a texel without a VPL has a ball");
            continue;
        }
        let p = DVec3::new(vp[0] as f64, vp[1] as f64, vp[2] as f64);
        // Layer 2l + f is light l's face f.
        let light = glam::Vec3::from_slice(&scene.lights[k / per_layer / 2].position[..3]).as_dvec3();
        let n = DVec3::new(ball[0] as f64, ball[1] as f64, ball[2] as f64);
        if ball[3] > 0.0 {
            // The plane is a triangle's that holds the VPL, turned to the light.
            assert!(n.dot(light - p) > 0.0, "{path}: VPL {k}'s plane faces away from its light");
            let on = tris.iter().any(|t| {
                let f = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
                (f - n).length().min((f + n).length()) < 1e-5 && point_triangle_distance(p, t) < 1e-4 * diag
            });
            assert!(on, "{path}: VPL {k}'s plane {n} is no triangle's under it");
        }
        vpls += 1;
        vpl_balls += check("VPL", p, *ball) as usize;
    }
    assert!(pixels > 0 && vpls > 0, "{path}: nothing to check");
    (balls as f64 / pixels as f64, vpl_balls as f64 / vpls as f64)
}

/// The radii against the twin on the Cornell box, the doorway wall and the cluttered room; on the Cornell
/// box most ends get a ball (its walls are large planes).
#[test]
fn end_ball_radii_match_the_cpu_twin() {
    let (p, v) = check_radii("assets/cornell-box/scene.toml");
    assert!(p > 0.5 && v > 0.5, "Cornell box: only {p:.2} of the pixels and {v:.2} of the VPLs got a ball");
    for path in ["assets/doorway/scene.toml", "assets/clutter/scene.toml"] {
        check_radii(path);
    }
}

/// The exact gather, mis and ris's shade with the balls and without: the same images, bit for bit.
#[test]
fn end_balls_change_no_image() {
    let gpu = TestGpu::new();
    for path in [
        "assets/cornell-box/scene.toml",
        "assets/box-on-floor/scene.toml",
        "assets/doorway/scene.toml",
        "assets/clutter/scene.toml",
    ] {
        let scene = Scene::load(&bounce_tests::workspace().join(path)).unwrap();
        // One renderer per scene for the methods without state across frames, with the balls first so that
        // the frame without them cannot reuse them; ris (its history and learned counts carry over) gets
        // a fresh one per frame.
        let mut r = Renderer::new(&gpu, &scene).unwrap();
        // mis and ris on two scenes only: they cost the most here, and their rays are the same queue's
        // (ris) or the same windows (mis) as the gather's.
        let heavy: &[Method] =
            if path.contains("cornell") || path.contains("clutter") { &[Method::Mis, Method::Ris] } else { &[] };
        for &method in [Method::Uniform, Method::All].iter().chain(heavy) {
            let s = FrameSettings { method, vpls: 32, all_tile: 512, ..settings(32, 16) };
            let mut fresh = (method == Method::Ris).then(|| Renderer::new(&gpu, &scene).unwrap());
            let on = fresh.as_mut().unwrap_or(&mut r).render(&s).unwrap();
            // Made by the scene's first frame (and lent to the later ones by the graph's cache).
            if method == Method::Uniform {
                assert!(on.ran.contains(&"end_balls.pixels") && on.ran.contains(&"end_balls.vpls"), "{:?}", on.ran);
            }
            let mut fresh = (method == Method::Ris).then(|| Renderer::new(&gpu, &scene).unwrap());
            let off = fresh.as_mut().unwrap_or(&mut r).render(&FrameSettings { end_balls: false, ..s }).unwrap();
            assert!(!off.ran.contains(&"end_balls.pixels"), "{:?}", off.ran);
            assert!(on.radiance == off.radiance, "{path} {method:?}: the end balls changed the image");
        }
    }
}
