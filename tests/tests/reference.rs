//! `--method reference` (`glsl/reference.comp`): the two-strategy MIS (cosine at x, light side at y,
//! balance heuristic), against
//! - the closed form inside a sphere (one light, and two lights of different colour and power: the light
//!   strategy picks by luminance, so a wrong P(l) in either density shows up as a wrong channel);
//! - the independent CPU one-bounce tracer (`bounce_oracles::cpu_ref`) on the Cornell box, with its
//!   light, and with two more lights, one of them behind the back wall (it draws points that light x
//!   does not reach: the two-sided density without the radiance);
//! - themselves: a frame's image does not depend on how its samples are split into submissions, and
//!   the mean of progressive frames is one frame of all their samples (they continue one sequence).

use super::vpl::sphere_scene;
use bounce_graph::frame::{Component, FrameSettings, Method, Renderer};
use bounce_graph::scene::{point_light, Scene};
use bounce_tests::TestGpu;
use glam::Vec3;
use std::f32::consts::PI;

/// The reference's indirect image: `spp` samples, `w` × `h`.
fn reference(r: &mut Renderer, spp: u32, seed: u64, w: u32, h: u32) -> Vec<[f32; 3]> {
    reference_with(
        r,
        FrameSettings { spp, seed, method: Method::Uniform, component: Component::Direct, ..FrameSettings::default() },
        w,
        h,
    )
}

fn reference_with(r: &mut Renderer, base: FrameSettings, w: u32, h: u32) -> Vec<[f32; 3]> {
    reference_and_stderr(r, base, w, h).0
}

/// The reference image and its own Monte Carlo error: the RMS over pixels and channels of each value's
/// standard error (`FrameOutput::stderr`).
fn reference_and_stderr(r: &mut Renderer, base: FrameSettings, w: u32, h: u32) -> (Vec<[f32; 3]>, f64) {
    // The light-map sizes do not matter to the reference; small ones keep the frame's other passes cheap.
    let s = FrameSettings {
        width: w,
        height: h,
        component: Component::Indirect,
        method: Method::Reference,
        dprsm_res: 32,
        voxels: 32,
        ..base
    };
    let f = r.render(&s).unwrap();
    assert!(f.radiance.iter().all(|p| p.iter().all(|c| c.is_finite())), "non-finite radiance");
    (f.radiance.iter().map(|p| [p[0], p[1], p[2]]).collect(), f.stderr.expect("the reference's error"))
}

fn channel_mean(img: &[[f32; 3]], c: usize) -> f64 {
    img.iter().map(|p| p[c] as f64).sum::<f64>() / img.len() as f64
}

/// Inside a closed sphere the bounce radiance is ρ²·ΣI/(πR²) per channel everywhere (tests/tests/vpl.rs),
/// whatever the lights' positions: with one light, and with a second of another colour and power.
#[test]
fn the_reference_matches_the_sphere_closed_form_with_one_and_two_lights() {
    let (radius, rho) = (1.0f32, 0.5f32);
    let one = sphere_scene(radius, 48, rho, Vec3::new(0.25, 0.3, -0.15), 2.0);
    let mut two = one.clone();
    two.lights.push(point_light(Vec3::new(-0.4, -0.5, 0.2), Vec3::new(0.3, 1.2, 4.0)));
    let gpu = TestGpu::new();
    for scene in [&one, &two] {
        let total: Vec3 = scene.lights.iter().map(|l| Vec3::from_slice(&l.intensity[..3])).sum();
        let want = total * rho * rho / (PI * radius * radius);
        let mut r = Renderer::new(&gpu, scene).unwrap();
        {
            let img = reference(&mut r, 64, 1, 16, 16);
            for c in 0..3 {
                let (m, w) = (channel_mean(&img, c), want[c] as f64);
                eprintln!(
                    "mis reference, sphere, {} light(s), channel {c}: {m:.5} vs closed form {w:.5} ({:+.2}%)",
                    scene.lights.len(),
                    100.0 * (m - w) / w
                );
                // 1 %: the tessellation's 0.5 % (see sphere_closed_form_all_and_uniform) and the noise of
                // 64 samples averaged over 256 pixels (below 0.3 % for either estimator here).
                assert!(((m - w) / w).abs() < 0.01, "mis: {m} vs {w}");
            }
        }
    }
}

/// The Cornell box with two more lights: a coloured one inside, and one behind the back wall.
fn cornell_three_lights() -> Scene {
    let mut scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let p = Vec3::from_slice(&scene.lights[0].position[..3]);
    scene.lights.push(point_light(p + Vec3::new(-0.5, -0.9, 0.3), Vec3::new(1.0, 0.6, 0.2)));
    scene.lights.push(point_light(p + Vec3::new(0.3, -0.8, -1.5), Vec3::new(2.0, 2.0, 2.0)));
    scene
}

/// The path tracer against the independent CPU one-bounce tracer on the Cornell box (one light; three,
/// one of them coloured and one behind a wall): the image means within 4 standard errors of their
/// difference (each tracer's own, from its samples' spread), the only occluded, many-light check of the
/// estimator the other tests take as the truth.
#[test]
fn the_reference_matches_the_cpu_tracer_in_the_cornell_box() {
    let gpu = TestGpu::new();
    let (w, h) = (20, 20);
    for scene in [Scene::load(&bounce_tests::default_scene()).unwrap(), cornell_three_lights()] {
        let bvh = bounce_oracles::cpu_ref::Bvh::new(&scene);
        let traced = bounce_oracles::cpu_ref::render_indirect(&scene, &bvh, w, h, 4096, 5);
        let cpu: Vec<[f32; 3]> = traced.iter().map(|(m, _)| *m).collect();
        // The standard error of an image mean over 3 · w · h values, its pixels independent; a pixel's three
        // channels come from the same paths, so their sum's variance is at most 3 × the sum of theirs (√3
        // on the error: a bound, not an estimate).
        let values = (3 * w * h) as f64;
        let se_cpu =
            3f64.sqrt() * traced.iter().flat_map(|(_, e)| e.map(|c| (c as f64).powi(2))).sum::<f64>().sqrt() / values;
        let mut r = Renderer::new(&gpu, &scene).unwrap();
        let base = FrameSettings { spp: 512, seed: 1, component: Component::Direct, ..FrameSettings::default() };
        let (img, rms_se) = reference_and_stderr(&mut r, base, w, h);
        let se_gpu = 3f64.sqrt() * rms_se / values.sqrt();
        let (mg, mc) = (bounce_tests::mean(&img), bounce_tests::mean(&cpu));
        let se = (se_cpu * se_cpu + se_gpu * se_gpu).sqrt();
        let err = bounce_tests::rel_mse(&img, &cpu);
        eprintln!(
            "mis reference vs cpu tracer, Cornell box, {} light(s): mean {mg:.5} vs {mc:.5} ({:+.2}%, {:.1} se of {:.2}%), relMSE {err:.4}",
            scene.lights.len(),
            100.0 * (mg - mc) / mc,
            (mg - mc).abs() / se,
            100.0 * se / mc
        );
        // The 4096-sample CPU tracer carries relMSE ≈ 0.0017 of noise on the one-light box, the MIS
        // estimate far less.
        assert!(err <= 0.01, "mis: relMSE {err} between two unbiased estimates of one integral");
        assert!((mg - mc).abs() <= 4.0 * se, "mis: means {mg} vs {mc}, {} standard errors", (mg - mc).abs() / se);
    }
}

/// A closed box split in two by a wall at x = 0, the light in the +x half; the camera at `eye` in the
/// sealed −x half, looking at `target`. No light reaches the sealed half in one bounce.
fn sealed_half(eye: Vec3, target: Vec3, fov_y_deg: f32) -> Scene {
    let mut tris = bounce_tests::closed_box(Vec3::ZERO, 1.0);
    let (a, b) = (Vec3::new(0.0, -1.0, -1.0), Vec3::new(0.0, 1.0, -1.0));
    let (c, d) = (Vec3::new(0.0, 1.0, 1.0), Vec3::new(0.0, -1.0, 1.0));
    tris.extend([[a, b, c], [a, c, d]]);
    let camera = bounce_graph::camera::Camera { eye, target, up: Vec3::Y, fov_y_deg };
    let light = point_light(Vec3::new(0.4, 0.2, 0.1), Vec3::splat(3.0));
    Scene::from_triangles(&tris, &vec![Vec3::splat(0.7); tris.len()], camera, &[light])
}

/// Light does not leak under a wall. A closed room split in two by a zero-thickness wall, the light in one
/// half, the camera in the other looking at the wall's foot from close by: nothing the camera sees is lit,
/// directly or by one bounce, so every pixel is exactly 0. The light side's shadow rays from a bounce point
/// y once started on y's surface with the 1e-4 relative window (`bvh_occluded`): a floor point within
/// 1e-4 of the segment's length of the wall's foot saw the light through the wall, and the pixels next to
/// the foot collected it (measured: 1 of 576 pixels lit, 6.9e-4; one such pixel on a generated
/// suite scene read 0.018 at any spp where every VPL method read 0).
#[test]
fn light_does_not_leak_under_a_wall() {
    let scene = sealed_half(Vec3::new(-0.3, -0.75, 0.05), Vec3::new(0.0, -1.0, 0.0), 70.0);
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let img = reference(&mut r, 256, 1, 24, 24);
    let lit: Vec<f32> = img.iter().map(|p| p[0].max(p[1]).max(p[2])).filter(|&v| v != 0.0).collect();
    let brightest = lit.iter().copied().fold(0.0f32, f32::max);
    eprintln!("sealed half: {} of {} pixels lit, the brightest {brightest:e}", lit.len(), img.len());
    assert!(lit.is_empty(), "light leaked under the wall: {} pixels lit, up to {brightest}", lit.len());
    // The control: the mirrored view, in the light's half, is lit (a reference that returns 0 passes above).
    let lit_half = sealed_half(Vec3::new(0.3, -0.75, 0.05), Vec3::new(0.0, -1.0, 0.0), 70.0);
    let seen = reference(&mut Renderer::new(&gpu, &lit_half).unwrap(), 64, 1, 24, 24);
    assert!(bounce_tests::mean(&seen) > 0.0, "the light's half is black: the reference returns nothing");
    // The independent CPU tracer's bounce points had the same window (measured with it: 2 of 576 pixels lit).
    let bvh = bounce_oracles::cpu_ref::Bvh::new(&scene);
    let cpu = bounce_oracles::cpu_ref::render_indirect(&scene, &bvh, 24, 24, 256, 1);
    let cpu_lit = cpu.iter().filter(|(m, _)| m.iter().any(|&c| c != 0.0)).count();
    eprintln!("sealed half, CPU tracer: {cpu_lit} of {} pixels lit", cpu.len());
    assert_eq!(cpu_lit, 0, "the CPU tracer's light leaked under the wall");
}

/// The sealed half of the test above, its dividing wall's vertex normals tilted 60° toward +y (a smooth
/// mesh's terminator). Seen from the sealed half, the wall's face can have a shading normal that faces the
/// light on the other side, whose shadow ray from there the wall does not block: the reference counted
/// that light as the wall's radiance toward the sealed floor (every one of the 576 pixels lit, the image's
/// sum 59.7, where `all` lights 60 with a sum of 17.8). A light lights only the face of a triangle on its
/// side, as the VPLs, which lie on that face, do: where `all` is 0 the reference must be too. (Both still
/// light the wall's own pixels, whose shading normal reaches through it: README, "Known limits".)
#[test]
fn light_does_not_reach_a_wall_face_from_behind_it() {
    let mut scene = sealed_half(Vec3::new(-0.6, -0.5, 0.05), Vec3::new(0.0, -0.8, 0.0), 80.0);
    let n = scene.vertices.len();
    for v in &mut scene.vertices[n - 6..] {
        let tilted = (0.5 * Vec3::from_slice(&v.normal_v[..3]) + 0.866 * Vec3::Y).normalize();
        v.normal_v[..3].copy_from_slice(&tilted.to_array());
    }
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h) = (24, 24);
    let s = FrameSettings {
        width: w,
        height: h,
        component: Component::Indirect,
        dprsm_res: 32,
        voxels: 32,
        ..FrameSettings::default()
    };
    let all = r.render(&FrameSettings { method: Method::All, ..s }).unwrap().radiance;
    let img = reference(&mut r, 256, 1, w, h);
    let dark = all.iter().filter(|p| p[..3].iter().all(|&c| c == 0.0)).count();
    let leaks =
        all.iter().zip(&img).filter(|(a, p)| a[..3].iter().all(|&c| c == 0.0) && p.iter().any(|&c| c != 0.0)).count();
    eprintln!("tilted wall: {dark} of {} pixels dark in all, {leaks} of them lit by the reference", all.len());
    assert!(dark > all.len() / 2, "the sealed floor is not in view: {dark} dark pixels");
    assert_eq!(leaks, 0, "the reference lit {leaks} pixels that no VPL reaches");
}

/// The samples of a frame are indexed globally, so splitting them into other submissions gives the same
/// image, bit for bit (each sample is added to the image in order of its index); a seed gives one image,
/// another seed another.
#[test]
fn a_reference_frame_does_not_depend_on_its_chunks() {
    let scene = cornell_three_lights();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    {
        let mut run = |chunk: Option<u32>, seed| {
            let s = FrameSettings {
                spp: 13,
                seed,
                reference_chunk: chunk.and_then(std::num::NonZeroU32::new),
                method: Method::Uniform,
                component: Component::Direct,
                ..FrameSettings::default()
            };
            reference_with(&mut r, s, 16, 16)
        };
        let whole = run(Some(13), 3);
        for chunk in [None, Some(1), Some(5)] {
            assert!(run(chunk, 3) == whole, "mis: chunks of {chunk:?} gave another image");
        }
        assert!(run(None, 4) != whole, "mis: another seed gave the same image");
    }
}

/// Progressive frames of the reference continue one sample sequence (`progressive::frame_settings`):
/// the mean of 4 frames of 2 samples is, up to float rounding, the one frame of 8 samples with the same
/// seed. Independent scrambles per frame would differ from it by the image's noise (checked: the frames
/// with another seed each do, by more than 100× the tolerance).
#[test]
fn progressive_reference_frames_are_one_sequence() {
    use bounce_graph::frame::progressive::frame_settings;
    let scene = cornell_three_lights();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    {
        let base = FrameSettings {
            spp: 2,
            seed: 7,
            method: Method::Uniform,
            component: Component::Direct,
            ..FrameSettings::default()
        };
        let mut mean = |base: &FrameSettings| {
            let mut sum = vec![[0.0f64; 3]; 16 * 16];
            for k in 0..4 {
                let frame = frame_settings(&FrameSettings { method: Method::Reference, ..base.clone() }, k, 0);
                assert_eq!(frame.seed, base.seed, "frame {k} changed the seed");
                for (a, p) in sum.iter_mut().zip(reference_with(&mut r, frame, 16, 16)) {
                    (0..3).for_each(|c| a[c] += p[c] as f64 / 4.0);
                }
            }
            sum
        };
        let frames = mean(&base);
        let other = mean(&FrameSettings { seed: 8, ..base.clone() });
        let whole = reference_with(&mut r, FrameSettings { spp: 8, ..base.clone() }, 16, 16);
        let dev = |img: &[[f64; 3]]| {
            img.iter()
                .zip(&whole)
                .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c] as f64).abs()))
                .fold(0.0, f64::max)
        };
        let scale = whole.iter().flat_map(|p| p.iter().map(|&c| c as f64)).fold(0.0, f64::max);
        assert!(scale > 0.0, "mis: a black image");
        let tol = 1e-5 * scale;
        assert!(
            dev(&frames) <= tol,
            "{}: frames differ from one frame of their samples by {:.3e} (tolerance {tol:.3e})",
            "mis",
            dev(&frames)
        );
        assert!(
            dev(&other) > 100.0 * tol,
            "{}: another seed's frames match ({:.3e}): the check cannot tell",
            "mis",
            dev(&other)
        );
    }
}

/// The sample points (`glsl/shared/owen_sobol.glsl`, run on the GPU by `glsl/test/owen_sobol.comp`):
/// bit for bit those of the CPU twin (`bounce_oracles::cpu_sobol`); in [0, 1); every power-of-two prefix of a 2D set, and an aligned block further on, is a (0, m, 2)-net
/// (exactly one point in each 2^a × 2^(m−a) elementary box, for every a); the 1D set's prefixes fall one
/// per 1/2^m interval; and other seeds (pixels) give other points.
#[test]
fn the_sample_points_are_stratified_in_every_power_of_two_prefix() {
    let gpu = TestGpu::new();
    let (n, seeds) = (1024u32, [0u32, 1, 0x2545F491, 0xdeadbeef]);
    let inputs: Vec<[u32; 2]> = seeds.iter().flat_map(|&s| (0..n).map(move |i| [i, s])).collect();
    let shader = bounce_graph::shaders::OWEN_SOBOL_COMP;
    let got: Vec<[f32; 4]> = bounce_tests::run_test_kernel(&gpu, "owen_sobol", shader, &inputs, inputs.len());
    // Bit for bit the CPU twin's, whose Sobol dimension 1 loops over its direction numbers.
    for (q, &[i, s]) in got.iter().zip(&inputs) {
        let [x, y] = bounce_oracles::cpu_sobol::owen_sobol2(i, s);
        let z = bounce_oracles::cpu_sobol::owen_sobol1(i, s);
        assert_eq!([q[0], q[1], q[2]].map(f32::to_bits), [x, y, z].map(f32::to_bits), "point {i} of seed {s:#x}");
    }
    assert!(got.iter().all(|q| q[..3].iter().all(|&v| (0.0..1.0).contains(&v))), "a point outside [0, 1)");
    let is_net = |pts: &[[f32; 4]], m: u32| {
        (0..=m).all(|a| {
            let (nx, ny) = (1u32 << a, 1u32 << (m - a));
            let mut cells = vec![0u32; 1 << m];
            for q in pts {
                let (cx, cy) = ((q[0] * nx as f32) as u32, (q[1] * ny as f32) as u32);
                cells[(cy * nx + cx) as usize] += 1;
            }
            cells.iter().all(|&c| c == 1)
        })
    };
    for (s, pts) in seeds.iter().zip(got.chunks(n as usize)) {
        for m in 0..=10 {
            let prefix = &pts[..1 << m];
            assert!(is_net(prefix, m), "seed {s:#x}: the first 2^{m} points are not a (0, {m}, 2)-net");
            let mut cells = vec![0u32; 1 << m];
            prefix.iter().for_each(|q| cells[(q[2] * (1u32 << m) as f32) as usize] += 1);
            assert!(cells.iter().all(|&c| c == 1), "seed {s:#x}: the 1D set's first 2^{m} points are not stratified");
        }
        assert!(is_net(&pts[256..512], 8), "seed {s:#x}: points 256..512 are not a (0, 8, 2)-net");
    }
    let (a, b) = (&got[..n as usize], &got[n as usize..2 * n as usize]);
    let same = a.iter().zip(b).filter(|(p, q)| p[0] == q[0] || p[1] == q[1]).count();
    assert!(same <= 4, "seeds 0 and 1 share {same} of {n} coordinates");
}
