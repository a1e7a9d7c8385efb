//! `--method realtime` (ris with two reservoirs per pixel, reused across frames through reprojection and
//! across pixels, `passes/reproject.rs`, and denoised, `passes/denoise.rs`) against independent judges:
//! each raw frame is unbiased with respect to `all` on a static view after frames of temporal and spatial
//! reuse (with the reuse's control variate and the learned visibility in every target), and so is the
//! first frame after a camera move, whose history is reprojected, and after a light move; the frame
//! traces at most two shadow rays per pixel, counted by the shade, while the camera and a light move;
//! the denoiser's output has a lower error than the raw estimate, and `--denoise off` shows the raw
//! estimate; a static view's progressive mean of realtime frames converges to the unbiased image;
//! `auto` learns visibility only where visibility blocks nearly everything; the raw frame's alpha is its
//! estimate's variance (against the spread of independent runs); the denoiser keeps most of a bright
//! corner's light, follows a change of the lighting at once and keeps its history while the camera pans;
//! a real-time sequence does not depend on what the renderer drew before it; and the frame, raw and
//! denoised, is linear in the light's intensity, bit for bit.

use crate::vpl::{converges_to, indirect_with};
use bounce_graph::frame::{Component, FrameSettings, Method, Renderer};
use bounce_graph::scene::Scene;
use bounce_tests::TestGpu;
use glam::Vec3;

const SIZE: (u32, u32, u32, u32) = (24, 24, 32, 32);

/// A raw real-time frame at the unbiasedness tests' settings (the 1/d² clamp at 1 % of the diagonal on
/// both sides, as `every_method_converges_to_all_at_the_monte_carlo_rate`), learning visibility (which
/// `auto` leaves off on the Cornell box) so that every reuse weighs learned targets.
fn realtime(seed: u64) -> FrameSettings {
    let mut s = FrameSettings {
        method: Method::Realtime,
        seed,
        // `all`'s VPL set (the default seed's places in the texels): the means are over the picks alone.
        vpl_seed: Some(FrameSettings::default().seed),
        clamp: 0.01,
        denoise: false,
        component: Component::Indirect,
        ..FrameSettings::default()
    };
    (s.ris.learn_visibility, s.ris.learn_auto) = (bounce_graph::passes::ris::AUTO_LEARN_FLOOR, false);
    s
}

/// Under `--learn-visibility auto` (the default) a real-time frame learns visibility where the view's
/// blocked share is at least `REALTIME_LEARN_BLOCKED` (the two rooms: the light in the next room), and
/// not on the Cornell box, whose frames are then those of `--learn-visibility off`, bit for bit.
#[test]
fn realtime_learns_visibility_only_where_visibility_blocks_nearly_everything() {
    use bounce_graph::frame::REALTIME_LEARN_BLOCKED;
    let gpu = TestGpu::new();
    let (w, h, res, vox) = SIZE;
    let frames = |scene: &Scene, auto: bool| {
        let mut r = Renderer::new(&gpu, scene).unwrap();
        let mut s = FrameSettings { clamp: 0.0, ..realtime(1) };
        (s.ris.learn_visibility, s.ris.learn_auto) = (0.0, auto);
        let b = r.blocked_share(w, h).unwrap().expect("the view is lit");
        (b, (0..3).map(|_| indirect_with(&mut r, s.clone(), w, h, res, vox)).last().unwrap())
    };
    let cornell = Scene::load(&bounce_tests::default_scene()).unwrap();
    let ((b, auto), (_, off)) = (frames(&cornell, true), frames(&cornell, false));
    assert!(b < REALTIME_LEARN_BLOCKED, "Cornell box: blocked share {b}");
    assert_eq!(auto, off, "auto learned on the Cornell box");
    let rooms = Scene::load(&bounce_tests::workspace().join("assets/two-rooms/scene.toml")).unwrap();
    let ((b, auto), (_, off)) = (frames(&rooms, true), frames(&rooms, false));
    assert!(b >= REALTIME_LEARN_BLOCKED, "two rooms: blocked share {b}");
    assert_ne!(auto, off, "auto did not learn in the two rooms");
}

fn all(r: &mut Renderer) -> Vec<[f32; 3]> {
    let (w, h, res, vox) = SIZE;
    let s = FrameSettings { method: Method::All, clamp: 0.01, ..FrameSettings::default() };
    indirect_with(r, s, w, h, res, vox)
}

/// The scene's camera moved sideways by 3 % of the diagonal, still looking at its target.
fn moved(scene: &Scene) -> bounce_graph::camera::Camera {
    let c = scene.camera;
    let side = (c.target - c.eye).cross(c.up).normalize();
    bounce_graph::camera::Camera { eye: c.eye + side * (0.03 * scene.diagonal()), ..c }
}

/// Frame 3 of a static view (its reservoirs combine two frames of history and four neighbours, and the
/// control variate's β has counted two frames of rays) is unbiased: over 48 runs, each from an empty
/// history, its mean converges to `all`; and the history is used: frame 3 has a lower error than frame
/// 1 (summed over the runs: measured 12 %, 17 % and 12 % lower with VPL seeds 1, 2 and 3; 24 % with the
/// texel centres, whose VPL set put spikes next to corners that frame 1 showed and the reuse smoothed). Then the camera moves: the first frame after the move
/// reprojects two frames of history made from the old view, and is unbiased against `all` from the new
/// view.
#[test]
fn realtime_frames_are_unbiased_with_reuse_and_after_a_camera_move() {
    const FRAMES: u64 = 3;
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = SIZE;
    let all_static = all(&mut r);
    let (mut first, mut last) = (0.0, 0.0);
    converges_to("realtime, frame 3 of a static view", &all_static, |run| {
        r.clear_frame_cache();
        let mut img = vec![];
        for k in 0..FRAMES {
            img = indirect_with(&mut r, realtime(run), w, h, res, vox);
            let e = bounce_tests::rel_mse(&img, &all_static);
            if k == 0 {
                first += e;
            }
            if k == FRAMES - 1 {
                last += e;
            }
        }
        img
    });
    eprintln!("realtime: relMSE of frame 1 {first:.4}, of frame {FRAMES} {last:.4} (sums over runs)");
    assert!(last < 0.9 * first, "the reuse does not help: frame 1 {first}, frame {FRAMES} {last}");

    r.set_camera(moved(&scene));
    let all_moved = all(&mut r);
    assert_ne!(all_moved, all_static, "the camera did not move");
    converges_to("realtime, the first frame after a camera move", &all_moved, |run| {
        r.clear_frame_cache();
        r.set_camera(scene.camera);
        for _ in 0..2 {
            indirect_with(&mut r, realtime(run), w, h, res, vox);
        }
        r.set_camera(moved(&scene));
        indirect_with(&mut r, realtime(run), w, h, res, vox)
    });
}

/// A real-time frame whose camera or light moved traces its shadow rays without end balls (they are kept
/// with the G-buffer and the VPL maps, so a move would rebuild them for two rays a pixel); the first frame
/// of a view builds them, and a still frame after a move builds what the move left without.
#[test]
fn realtime_skips_the_end_balls_while_the_camera_or_a_light_moves() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = SIZE;
    let s = FrameSettings {
        width: w,
        height: h,
        dprsm_res: res,
        voxels: vox,
        visibility: bounce_graph::frame::Visibility::Exact,
        ..realtime(5)
    };
    let balls =
        |f: &bounce_graph::frame::FrameOutput| (f.ran.contains(&"end_balls.pixels"), f.ran.contains(&"end_balls.vpls"));
    assert_eq!(balls(&r.render(&s).unwrap()), (true, true), "the first frame builds the balls");
    let l = scene.lights[0];
    r.set_light(
        0,
        glam::Vec3::from_slice(&l.position[..3]) + glam::Vec3::splat(0.01),
        glam::Vec3::from_slice(&l.intensity[..3]),
    );
    let light_moved = r.render(&s).unwrap();
    assert_eq!(balls(&light_moved), (false, false), "a light move builds balls");
    assert!(light_moved.ran.contains(&"ris_shade"), "{:?}", light_moved.ran);
    assert_eq!(balls(&r.render(&s).unwrap()), (false, true), "a still frame builds the moved light's VPLs' balls");
    r.set_camera(moved(&scene));
    let moving = r.render(&s).unwrap();
    assert_eq!(balls(&moving), (false, false), "a camera move builds balls");
    assert!(moving.ran.contains(&"ris_shade"), "{:?}", moving.ran);
}

/// At most two shadow rays per pixel per frame (the real-time bound; realtime traces one for each of its
/// two reservoirs' final samples), counted by the shade's counter, while the camera orbits and the light moves; and the counter
/// counts: ris with four reservoirs traces more than three per lit pixel on the same frames.
#[test]
fn realtime_traces_at_most_two_shadow_rays_per_pixel() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = SIZE;
    let light = r.lights()[0];
    for (method, vpls) in [(Method::Realtime, 1), (Method::Ris, 4)] {
        r.clear_frame_cache();
        let mut counts = vec![];
        for k in 0..4 {
            let t = k as f32 * 0.3;
            let c = scene.camera;
            r.set_camera(bounce_graph::camera::Camera {
                eye: c.eye + Vec3::new(t.sin(), 0.0, 1.0 - t.cos()) * 0.2,
                ..c
            });
            let p = Vec3::from_slice(&light.position[..3]) + Vec3::new(0.05 * k as f32, 0.0, 0.0);
            r.set_light(0, p, Vec3::from_slice(&light.intensity[..3]));
            let s = FrameSettings {
                width: w,
                height: h,
                dprsm_res: res,
                voxels: vox,
                vpls,
                method,
                ..FrameSettings::default()
            };
            counts.push(r.render(&s).unwrap().rays_per_pixel.expect("ris counts its rays"));
        }
        eprintln!("{}: shadow rays per pixel {counts:?}", method.name());
        match method {
            Method::Realtime => assert!(counts.iter().all(|&c| c > 0.5 && c <= 2.0), "{counts:?}"),
            _ => assert!(counts.iter().all(|&c| c > 3.0 && c <= 4.0), "{counts:?}"),
        }
    }
}

/// The denoiser (`--denoise on`, the default) lowers the error of the displayed frame: after six
/// frames of a static view its output is closer to `all` than the raw estimate (read beside it); with
/// `--denoise off` the frame is the raw estimate and nothing is read beside it. The raw estimate's GPU
/// time (`FrameOutput::raw_gpu_ms`) is the frame's less the denoiser's passes, and with `--denoise off`
/// the frame's (when the device has timestamps).
#[test]
fn the_denoiser_lowers_the_error_and_off_shows_the_raw_estimate() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = SIZE;
    let all = all(&mut r);
    let s = |denoise| FrameSettings { width: w, height: h, dprsm_res: res, voxels: vox, denoise, ..realtime(1) };
    let rgb = |v: &[[f32; 4]]| v.iter().map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>();
    let (mut raw, mut denoised) = (0.0, 0.0);
    for _ in 0..6 {
        let f = r.render(&s(true)).unwrap();
        if let (Some(all_ms), Some(raw_ms)) = (f.gpu_ms(), f.raw_gpu_ms()) {
            let filter: f64 = f.timings.iter().filter(|t| t.name.starts_with("denoise_")).filter_map(|t| t.ms).sum();
            assert!(filter > 0.0 && (all_ms - filter - raw_ms).abs() <= 1e-9 * all_ms, "{all_ms} {raw_ms} {filter}");
        }
        raw = bounce_tests::rel_mse(&rgb(f.raw.as_ref().expect("the raw estimate beside")), &all);
        denoised = bounce_tests::rel_mse(&rgb(&f.radiance), &all);
    }
    eprintln!("frame 6: relMSE raw {raw:.4}, denoised {denoised:.4}");
    assert!(denoised < 0.5 * raw, "the denoiser does not help: raw {raw}, denoised {denoised}");
    let f = r.render(&s(false)).unwrap();
    assert!(f.raw.is_none(), "--denoise off reads a raw image beside the frame");
    assert_eq!(f.raw_gpu_ms(), f.gpu_ms(), "--denoise off still runs denoiser passes");
    let e = bounce_tests::rel_mse(&rgb(&f.radiance), &all);
    assert!(e > 2.0 * denoised, "--denoise off still denoises: {e} vs {denoised}");
}

/// A light move: the first frame after it reuses two frames of history whose VPLs (light-map texels) are
/// re-evaluated where they now are, weighed with the target the history was made for (last frame's VPL
/// maps; passes/ris.rs), so it is unbiased however far the light moves: over 48 runs the image mean is
/// within 4 standard errors of `all`'s after a step of 10 % of the scene diagonal (ten times the default
/// orbit's step). Weighed with this frame's maps instead (as first built) the history is weighed for VPLs
/// it could not hold (texels empty last frame, or then behind the pixel's surface): measured −5.7 ± 0.5 %
/// at this step, which this test fails.
#[test]
fn realtime_after_a_light_move_is_unbiased() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = SIZE;
    let light = r.lights()[0];
    let (p0, intensity) = (Vec3::from_slice(&light.position[..3]), Vec3::from_slice(&light.intensity[..3]));
    let p1 = p0 + Vec3::new(1.0, -0.5, 0.5).normalize() * (0.1 * scene.diagonal());
    r.set_light(0, p1, intensity);
    let all_moved = all(&mut r);
    let mut means = vec![];
    for run in 0..48 {
        r.clear_frame_cache();
        r.set_light(0, p0, intensity);
        for _ in 0..2 {
            indirect_with(&mut r, realtime(run), w, h, res, vox);
        }
        r.set_light(0, p1, intensity);
        means.push(bounce_tests::mean(&indirect_with(&mut r, realtime(run), w, h, res, vox)));
    }
    let (m, se) = bounce_tests::mean_and_stderr(&means);
    let target = bounce_tests::mean(&all_moved);
    eprintln!(
        "realtime after a light move: {m:.5} ± {se:.5} vs all {target:.5} ({:+.2} %)",
        100.0 * (m / target - 1.0)
    );
    assert!((m - target).abs() <= 4.0 * se, "biased after a light move: {m} ± {se} vs {target}");
}

/// A static view's progressive mean of realtime frames (`render --time-limit`'s averaging,
/// `progressive::render_for`) averages their raw estimates, not the denoised output (which does not run):
/// one frame's mean is that frame's raw image. And in the steady state of reuse, frames 16–47 of a static view (correlated
/// through their reuse, each unbiased) average to `all`: over 16 runs their image mean is within 4
/// standard errors of `all`'s (measured −0.06 ± 0.15 %; one run's 32 frames spread by about 2 %).
#[test]
fn realtime_progressive_frames_converge_to_the_unbiased_image() {
    use bounce_graph::frame::progressive::{frame_settings, render_for};
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = SIZE;
    let all = all(&mut r);
    let s = FrameSettings { width: w, height: h, dprsm_res: res, voxels: vox, denoise: true, ..realtime(7) };
    // A budget of zero: exactly one frame.
    let p = render_for(&mut r, &s, std::time::Duration::ZERO, &mut |_, _| {}).unwrap();
    assert_eq!(p.frames, 1);
    // The denoiser does not run for frames whose raw estimates are averaged.
    assert!(p.last.raw.is_none() && !p.last.ran.contains(&"denoise_temporal"), "{:?}", p.last.ran);
    r.clear_frame_cache();
    let shown = r.render(&FrameSettings { denoise: true, ..frame_settings(&s, 0, 0) }).unwrap();
    let raw = shown.raw.as_ref().expect("the raw estimate beside the denoised one");
    assert_eq!(&p.radiance, raw, "the progressive mean is not the raw estimate");
    assert_ne!(p.radiance, shown.radiance, "the raw and the denoised frame are the same");
    let mut means = vec![];
    for run in 0..16u64 {
        r.clear_frame_cache();
        let s = FrameSettings { seed: 100 + run, ..s.clone() };
        let mut mean = 0.0;
        for k in 0..48u32 {
            let f = r.render(&frame_settings(&s, k, 0)).unwrap();
            if k >= 16 {
                // Progressive frames are the raw estimate (no denoiser).
                let img: Vec<[f32; 3]> = f.radiance.iter().map(|p| [p[0], p[1], p[2]]).collect();
                mean += bounce_tests::mean(&img) / 32.0;
            }
        }
        means.push(mean);
    }
    let (m, se) = bounce_tests::mean_and_stderr(&means);
    let target = bounce_tests::mean(&all);
    eprintln!(
        "realtime, frames 16-47 of a static view: {m:.5} ± {se:.5} vs all {target:.5} ({:+.2} %)",
        100.0 * (m / target - 1.0)
    );
    assert!((m - target).abs() <= 4.0 * se, "the steady state is biased: {m} ± {se} vs {target}");
}

/// The raw frame's alpha is its estimate's variance (ris's shade, over the pixel's two reservoirs: the
/// variance of their mean, of the luminance of the indirect light demodulated by the albedo), which the
/// denoiser's luminance stop is scaled by. Judged against the spread of independent runs: in a grey room
/// (albedo ½ everywhere, so demodulation is a factor 2) with a blocker, over 32 seeds, the pixels' mean
/// alpha sums to the pixels' sample variance across the seeds within 20 % (measured 1.04 at frame 1 and
/// 1.02 at frame 3, after reuse). The variance of one reservoir's estimate instead of their mean would
/// read 2, of their sum 4 (or ½ without the demodulation).
#[test]
fn the_raw_frames_alpha_is_its_estimates_variance() {
    let albedo = 0.5f32;
    let mut tris = bounce_tests::closed_box(Vec3::ZERO, 1.0);
    let q = |a: Vec3, b: Vec3, c: Vec3, d: Vec3| [[a, b, c], [a, c, d]];
    tris.extend(q(
        Vec3::new(-0.5, -0.2, -0.3),
        Vec3::new(0.3, -0.2, -0.5),
        Vec3::new(0.3, 0.5, -0.5),
        Vec3::new(-0.5, 0.5, -0.3),
    ));
    let camera = bounce_graph::camera::Camera {
        eye: Vec3::new(0.6, 0.3, 0.9),
        target: Vec3::new(-0.6, -0.4, -0.8),
        up: Vec3::Y,
        fov_y_deg: 70.0,
    };
    let light = bounce_graph::scene::point_light(Vec3::new(0.2, 0.6, 0.1), Vec3::splat(2.0));
    let scene = Scene::from_triangles(&tris, &vec![Vec3::splat(albedo); tris.len()], camera, &[light]);
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = SIZE;
    let s = |seed| FrameSettings {
        width: w,
        height: h,
        dprsm_res: res,
        voxels: vox,
        component: Component::Indirect,
        ..realtime(seed)
    };
    for frames in [1usize, 3] {
        let runs: Vec<Vec<[f32; 4]>> = (0..32)
            .map(|seed| {
                r.clear_frame_cache();
                (0..frames).map(|_| r.render(&s(seed)).unwrap().radiance).last().unwrap()
            })
            .collect();
        let lum = |p: &[f32; 4]| (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64 / albedo as f64;
        let (mut spread, mut alpha) = (0.0, 0.0);
        for i in 0..(w * h) as usize {
            let n = runs.len() as f64;
            let m = runs.iter().map(|f| lum(&f[i])).sum::<f64>() / n;
            spread += runs.iter().map(|f| (lum(&f[i]) - m).powi(2)).sum::<f64>() / (n - 1.0);
            alpha += runs.iter().map(|f| f[i][3] as f64).sum::<f64>() / n;
        }
        let ratio = alpha / spread;
        eprintln!("frame {frames}: Σ mean alpha {alpha:.5}, Σ variance across seeds {spread:.5}, ratio {ratio:.3}");
        assert!(spread > 0.0 && (0.8..=1.25).contains(&ratio), "frame {frames}: alpha / variance {ratio}");
    }
}

/// A grey room (albedo ½) with the light a few centimetres from a corner, the corner in view.
fn light_corner_room() -> Scene {
    let tris = bounce_tests::closed_box(Vec3::ZERO, 1.0);
    let camera = bounce_graph::camera::Camera {
        eye: Vec3::new(0.7, 0.5, 0.8),
        target: Vec3::new(-1.0, -1.0, -1.0),
        up: Vec3::Y,
        fov_y_deg: 70.0,
    };
    let light = bounce_graph::scene::point_light(Vec3::new(-0.93, -0.93, -0.93), Vec3::splat(0.2));
    Scene::from_triangles(&tris, &vec![Vec3::splat(0.5); tris.len()], camera, &[light])
}

/// The denoiser keeps most of a bright corner's light: with the light next to the corner, the indirect
/// light is a peak at the corner's edges, which a normalized gather averages into the dim planes around
/// it, losing light at each iteration (an edge pixel's taps are cut, so its neighbours, normalizing by
/// their larger sums, take less of its light than it gives up), and so does a luminance stop scaled by a
/// variance that counts the peak's own gradient as noise (SVGF's moments). Over the first 8 frames of a
/// static view every denoised frame's mean is at least 0.78 of `all`'s (measured 0.83–0.93 with four
/// gathering iterations, fitting planes, and one exchanging; 0.81–0.92 with two gathering by weighted means
/// and three exchanging; with five gathering by weighted means, 0.72–0.87, which this test fails from frame
/// 1; with SVGF's moments 0.53 at frame 0; the raw frames 0.95–1.04).
#[test]
fn the_denoiser_keeps_a_corners_light() {
    let scene = light_corner_room();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = SIZE;
    let all = all(&mut r);
    let s = FrameSettings { width: w, height: h, dprsm_res: res, voxels: vox, denoise: true, ..realtime(3) };
    let rgb = |v: &[[f32; 4]]| v.iter().map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>();
    let truth = bounce_tests::mean(&all);
    for frame in 0..8 {
        let f = r.render(&s).unwrap();
        let raw = bounce_tests::mean(&rgb(f.raw.as_ref().unwrap())) / truth;
        let den = bounce_tests::mean(&rgb(&f.radiance)) / truth;
        eprintln!("frame {frame}: image mean over all's: raw {raw:.3}, denoised {den:.3}");
        assert!(den >= 0.78, "frame {frame}: the denoiser lost the corner's light: {den:.3} of all's mean");
        // Nor does it add light (a filter's weights that sum above one, a history counted twice).
        assert!(den <= 1.1, "frame {frame}: the denoiser added light: {den:.3} of all's mean");
    }
}

/// A real-time sequence is the same whatever the renderer drew before it: its frames draw their random
/// numbers from the seed and the real-time frames rendered (since the renderer began or its frame
/// cache was cleared), not from every frame. `bench --animate` renders the ground truth first or reads
/// it from disk, and counting every frame made its realtime figures depend on which (a held-out scene's
/// raw relMSE read 0.058 and 0.109).
#[test]
fn a_realtime_sequence_does_not_depend_on_what_was_rendered_before() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let (w, h, res, vox) = SIZE;
    let s = FrameSettings { width: w, height: h, dprsm_res: res, voxels: vox, denoise: true, ..realtime(5) };
    let sequence = |before: Option<Method>| {
        let mut r = Renderer::new(&gpu, &scene).unwrap();
        if let Some(method) = before {
            r.render(&FrameSettings { method, ..s.clone() }).unwrap();
        }
        (0..3).map(|_| r.render(&s).unwrap()).map(|f| (f.radiance, f.raw)).collect::<Vec<_>>()
    };
    let alone = sequence(None);
    assert_eq!(alone, sequence(Some(Method::Uniform)), "a uniform frame first changed the realtime frames");
    assert_ne!(alone[1], alone[2], "the frames repeat");
}

/// The denoiser follows a change of the lighting at once: its temporal stage tests each 5 × 5 mean's
/// change against the estimate's measured noise and lets the history give way by the share beyond it.
/// After six frames of a static view the light's intensity doubles: the next denoised frame's mean is
/// at least 0.75 of `all`'s at the new intensity (measured 0.81: the share of the change beyond three
/// times its noise; the raw frame 1.005). The history's fixed weight alone kept 0.60, which this test fails.
#[test]
fn the_denoiser_follows_a_change_of_the_lighting() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = SIZE;
    let light = r.lights()[0];
    let (p, intensity) = (Vec3::from_slice(&light.position[..3]), Vec3::from_slice(&light.intensity[..3]));
    r.set_light(0, p, 2.0 * intensity);
    let truth = bounce_tests::mean(&all(&mut r));
    r.set_light(0, p, intensity);
    r.clear_frame_cache();
    let s = FrameSettings { width: w, height: h, dprsm_res: res, voxels: vox, denoise: true, ..realtime(11) };
    let rgb = |v: &[[f32; 4]]| v.iter().map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>();
    for _ in 0..6 {
        r.render(&s).unwrap();
    }
    r.set_light(0, p, 2.0 * intensity);
    let f = r.render(&s).unwrap();
    let (raw, shown) = (bounce_tests::mean(&rgb(f.raw.as_ref().unwrap())), bounce_tests::mean(&rgb(&f.radiance)));
    eprintln!("after the light doubled: image mean over all's: raw {:.3}, denoised {:.3}", raw / truth, shown / truth);
    assert!(shown / truth >= 0.75, "the denoiser lags: {:.3} of all's mean", shown / truth);
    assert!(shown / truth <= 1.1, "the denoiser added light: {:.3} of all's mean", shown / truth);
}

/// The scene's camera slid sideways by `px` pixels (at the target's distance), still looking ahead.
fn panned(scene: &Scene, px: f32, height: u32) -> bounce_graph::camera::Camera {
    let c = scene.camera;
    let side = (c.target - c.eye).cross(c.up).normalize();
    let footprint = 2.0 * (c.fov_y_deg.to_radians() / 2.0).tan() * (c.target - c.eye).length() / height as f32;
    let d = side * (px * footprint);
    bounce_graph::camera::Camera { eye: c.eye + d, target: c.target + d, ..c }
}

/// The denoiser's history follows a panning camera: the camera slides sideways 0.37 of a pixel a frame,
/// so that each frame's surface points fall between last frame's pixel centres, and the accumulation is
/// looked up there (bilinearly where the four pixels around hold the same surface). After 10 frames the
/// denoised frame's relMSE against `all` of its view, summed over 8 runs, is at most 1.8× a still view's
/// after 10 frames (measured 1.42×, 1.54× and 1.54× with three sets of seeds; looking the history up in
/// the pixel the point fell in, as first built, 2.16–2.22×, which this test fails) and below half the raw
/// estimate's.
#[test]
fn the_denoisers_history_follows_a_panning_camera() {
    const FRAMES: usize = 10;
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = SIZE;
    let rgb = |v: &[[f32; 4]]| v.iter().map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>();
    let all_still = all(&mut r);
    r.set_camera(panned(&scene, 0.37 * (FRAMES - 1) as f32, h));
    let all_panned = all(&mut r);
    let (mut still, mut moving, mut raw) = (0.0, 0.0, 0.0);
    for run in 0..8 {
        let s = FrameSettings { width: w, height: h, dprsm_res: res, voxels: vox, denoise: true, ..realtime(20 + run) };
        for pan in [false, true] {
            r.clear_frame_cache();
            let mut f = None;
            for k in 0..FRAMES {
                r.set_camera(if pan { panned(&scene, 0.37 * k as f32, h) } else { scene.camera });
                f = Some(r.render(&s).unwrap());
            }
            let f = f.unwrap();
            if pan {
                moving += bounce_tests::rel_mse(&rgb(&f.radiance), &all_panned);
                raw += bounce_tests::rel_mse(&rgb(f.raw.as_ref().unwrap()), &all_panned);
            } else {
                still += bounce_tests::rel_mse(&rgb(&f.radiance), &all_still);
            }
        }
    }
    eprintln!(
        "frame {FRAMES}: denoised relMSE still {still:.5}, panning {moving:.5} ({:.2}x), raw panning {raw:.5}",
        moving / still
    );
    assert!(moving <= 1.8 * still, "the history is lost under a pan: {moving} against {still} still");
    assert!(moving < 0.5 * raw, "the denoiser does not help under a pan: {moving} against raw {raw}");
}

/// The denoiser's gathers follow a ramp to a plane's edge: each fits a plane to its taps (a local linear
/// regression) and keeps the intercept, where SVGF's weighted mean is pulled toward the taps on the
/// open side. The corner-light room's indirect light rises toward the corner's edges; over 12 seeds
/// (frames 2–7 of a static view each, against `all`) the mean denoised relMSE is at most 0.00145
/// (measured 0.00122, the seeds 0.00102–0.00141; with weighted means in the gathers 0.00167, the same
/// seeds 0.00139–0.00196, each higher, which this test fails).
#[test]
fn the_denoisers_gathers_follow_a_ramp_to_a_planes_edge() {
    let scene = light_corner_room();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h, res, vox) = SIZE;
    let all = all(&mut r);
    let mut per_seed = Vec::new();
    for seed in 1..=12 {
        r.clear_frame_cache();
        let s = FrameSettings { width: w, height: h, dprsm_res: res, voxels: vox, denoise: true, ..realtime(seed) };
        let mut sum = 0.0;
        for frame in 0..8 {
            let f = r.render(&s).unwrap();
            if frame >= 2 {
                let rgb: Vec<[f32; 3]> = f.radiance.iter().map(|p| [p[0], p[1], p[2]]).collect();
                sum += bounce_tests::rel_mse(&rgb, &all) / 6.0;
            }
        }
        eprintln!("seed {seed}: denoised relMSE against all's, frames 2–7: {sum:.5}");
        per_seed.push(sum);
    }
    let e = per_seed.iter().sum::<f64>() / per_seed.len() as f64;
    eprintln!("mean over the seeds: {e:.5}");
    assert!(e <= 0.00145, "the denoised corner: relMSE {e:.5}");
}

/// The real-time frame is linear in the light: every threshold of its reuse and its denoiser is relative
/// (the luminance stop against the estimate's own noise, the clamp and the gradient test in standard
/// deviations, the reuse's targets as ratios), so a light 2^20 times brighter or dimmer gives the same
/// sequence, raw and denoised, scaled by exactly that power of two (bit for bit: multiplying by a power
/// of two is exact in floating point), while the camera and the light move.
#[test]
fn the_realtime_frame_is_linear_in_the_lights_intensity() {
    let scene = Scene::load(&bounce_tests::workspace().join("assets/two-rooms/scene.toml")).unwrap();
    let gpu = TestGpu::new();
    let (w, h, res, vox) = SIZE;
    let s = FrameSettings { width: w, height: h, dprsm_res: res, voxels: vox, denoise: true, ..realtime(7) };
    let s = FrameSettings { component: Component::Combined, clamp: 0.0, ..s };
    let sequence = |scale: f32| {
        let mut r = Renderer::new(&gpu, &scene).unwrap();
        let light = r.lights()[0];
        let (p, intensity) = (Vec3::from_slice(&light.position[..3]), Vec3::from_slice(&light.intensity[..3]));
        (0..6)
            .map(|k| {
                r.set_camera(panned(&scene, 0.7 * k as f32, h));
                r.set_light(0, p + Vec3::new(0.05, 0.0, 0.03) * k as f32, scale * intensity);
                let f = r.render(&s).unwrap();
                [f.raw.unwrap(), f.radiance]
            })
            .collect::<Vec<_>>()
    };
    let base = sequence(1.0);
    let lit = base.iter().flatten().flatten().filter(|p| p[0] > 0.0).count();
    assert!(lit > base.len() * 2 * (w * h) as usize / 4, "too few lit pixels: {lit}");
    for k in [20, -20] {
        let scale = 2f32.powi(k);
        for (i, (a, b)) in base.iter().zip(sequence(scale)).enumerate() {
            for (which, (a, b)) in ["raw", "denoised"].iter().zip(a.iter().zip(&b)) {
                let off = a.iter().zip(b).filter(|(p, q)| (0..3).any(|c| p[c] * scale != q[c])).count();
                assert_eq!(off, 0, "light × 2^{k}, frame {i}, {which}: {off} pixels are not the base scaled");
            }
        }
    }
}

/// The viewer renders real-time frames while anything moves and progressive ris frames while nothing
/// does. A still frame between two real-time frames leaves their state alone: the real-time frame after it
/// is bit for bit the one without it (raw and denoised: the reservoirs, the surfaces and the denoiser's
/// history are the last real-time frame's, the motion against its camera). Before, the still frame
/// remade the reservoirs, and the histories swapped at every frame, so the next real-time frame found its
/// history two frames old (or none). A still frame that moved on to a new VPL set (as a still view's
/// frames do) makes the next real-time frame forget its history, as one that moved the camera does: the
/// history would be weighed with the new set's maps, not those its reservoirs were drawn with.
#[test]
fn a_still_frame_between_real_time_frames_keeps_their_history() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let (w, h, res, vox) = SIZE;
    let s = FrameSettings { width: w, height: h, dprsm_res: res, voxels: vox, denoise: true, ..realtime(9) };
    let still = FrameSettings { method: Method::Ris, denoise: false, ..s.clone() };
    let new_set = FrameSettings { vpl_seed: Some(77), ..still.clone() };
    // The still frame before frame 4: none, one that sees frame 3's view, one with a new VPL set, one
    // seen from elsewhere.
    let sequence = |between: Option<(&FrameSettings, f32)>| {
        let mut r = Renderer::new(&gpu, &scene).unwrap();
        let mut out = vec![];
        for k in 0..6 {
            let pan = 0.4 * k as f32;
            if let (4, Some((still, moved))) = (k, between) {
                r.set_camera(panned(&scene, pan - 0.4 + moved, h));
                r.render(still).unwrap();
            }
            r.set_camera(panned(&scene, pan, h));
            // The real-time frames keep their set: the still frames' is theirs alone.
            let f = r.render(&s).unwrap();
            out.push((f.radiance, f.raw));
        }
        out
    };
    let plain = sequence(None);
    let with_still = sequence(Some((&still, 0.0)));
    assert!(
        plain[4] == with_still[4] && plain[5] == with_still[5],
        "a still frame between changed the real-time frames"
    );
    assert!(plain[3] != plain[4], "the frames repeat");
    let after_new_set = sequence(Some((&new_set, 0.0)));
    let after_moved = sequence(Some((&still, 0.9)));
    assert!(after_moved[4] != plain[4], "a still frame from elsewhere kept the history");
    assert!(after_new_set[4] == after_moved[4], "a still frame with a new VPL set kept the history");
}
