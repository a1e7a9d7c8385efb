//! The viewer's presentation on the GPU (passes/present.rs): its tone mapping against the PNG writer's
//! (crates/app/src/output.rs, f64 on the host), its running mean against the mean of the frames
//! `Renderer::render` reads back, and that a presented frame copies nothing to host memory unless a
//! screenshot is asked for.

use bounce::output::{linear_to_srgb8, tonemap_reinhard, RgbImage};
use bounce_device::sync::Access;
use bounce_device::{vk, Buffer, Image, ImageDesc};
use bounce_graph::bindings::{STOP_PRIOR_FADE, STOP_PRIOR_FIRST, STOP_PRIOR_MAX};
use bounce_graph::frame::{Component, FrameSettings, Method, Renderer};
use bounce_graph::graph::Graph;
use bounce_graph::passes::direct::RADIANCE_FORMAT;
use bounce_graph::passes::present::{Present, PresentParams, Prior};
use bounce_graph::scene::Scene;
use bounce_tests::TestGpu;
use glam::Vec3;

fn settings() -> FrameSettings {
    FrameSettings {
        width: 24,
        height: 20,
        component: Component::Combined,
        method: Method::Uniform,
        vpls: 4,
        dprsm_res: 16,
        voxels: 16,
        ..FrameSettings::default()
    }
}

fn params(frames: u32, reset: bool) -> PresentParams {
    PresentParams { frames, reset, exposure: 1.0, swap_rb: false, prior: Prior::None }
}

/// The PNG writer's bytes (RGBA, alpha 255) for `img`.
fn cpu_bytes(img: &RgbImage) -> Vec<u8> {
    tonemap_reinhard(img)
        .iter()
        .flat_map(|p| [p[0], p[1], p[2]].map(linear_to_srgb8).into_iter().chain([255]))
        .collect()
}

fn max_step(a: &[u8], b: &[u8]) -> u8 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0)
}

/// An HDR test image with what the mapping must survive: six decades of luminance, saturated colours,
/// black, negative, NaN and infinite pixels; its size is no multiple of the workgroup, so partial
/// groups take part in the reductions. The GPU's 8-bit picture equals the PNG writer's within one step.
#[test]
fn the_gpu_tone_map_equals_the_png_writers_within_one_step() {
    let gpu = TestGpu::new();
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let r = Renderer::new(&gpu, &scene).unwrap();
    let (w, h) = (37u32, 23u32);
    let mut pixels: Vec<[f32; 4]> = (0..w * h)
        .map(|i| {
            let t = i as f32 / (w * h) as f32;
            let l = 10f32.powf(-3.0 + 6.0 * t);
            [l * (0.2 + 0.8 * (i % 3 == 0) as u32 as f32), l * (0.5 + 0.5 * t), l * (1.0 - 0.9 * t), 1.0]
        })
        .collect();
    pixels[5] = [0.0; 4];
    pixels[17] = [-1.0, 0.5, 0.2, 1.0];
    pixels[40] = [f32::NAN, 1.0, 1.0, 1.0];
    pixels[41] = [f32::INFINITY, 0.0, 0.0, 1.0];
    pixels[100] = [0.0, 0.0, 3.0, 1.0];
    let upload =
        Buffer::with_data(&gpu, "test radiance", vk::BufferUsageFlags::TRANSFER_SRC, bytemuck::cast_slice(&pixels))
            .unwrap();
    let ldr = Present::ldr_image(&gpu, w, h).unwrap();
    for swap in [false, true] {
        let mut g = Graph::new(&gpu);
        let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        let mut radiance = g.create_image(ImageDesc::new("test.radiance", w, h, RADIANCE_FORMAT, usage));
        let (rh, src) = (radiance, upload.raw);
        g.add_pass("upload").overwrite(&mut radiance, Access::TransferWrite).record(move |ctx| {
            let img: &Image = ctx.image(&rh);
            let region = vk::BufferImageCopy::default()
                .image_subresource(
                    vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1),
                )
                .image_extent(vk::Extent3D { width: w, height: h, depth: 1 });
            unsafe {
                ctx.gpu.device.cmd_copy_buffer_to_image(
                    ctx.cmd,
                    src,
                    img.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                )
            };
        });
        let mut out = g.import_image(&ldr);
        r.passes
            .present
            .add(&mut g, &radiance, &mut out, w, h, PresentParams { swap_rb: swap, ..params(1, true) })
            .unwrap();
        g.export(&out);
        drop(g.execute().unwrap());
        let mut got = ldr.res.read_back(ldr.last_access()).unwrap();
        ldr.set_last_access(Access::TransferRead);
        if swap {
            got.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
        }
        let img = RgbImage::from_rgba(w, h, &pixels);
        let want = cpu_bytes(&img);
        assert!(want.chunks_exact(4).any(|p| p[0] > 200) && want.chunks_exact(4).any(|p| p[0] < 30 && p[0] > 0));
        assert!(
            max_step(&got, &want) <= 1,
            "swap {swap}: the GPU mapping differs from the PNG writer's by more than one step"
        );
    }
}

/// Presented frames add up on the GPU: after K frames (seeds S..S+K) the read-back mean is the mean of
/// the K frames `render` gives (f32 sums in the same order: equal bits), and its picture equals the PNG
/// writer's within one step. No presented frame copies anything to host memory; the screenshot's frame
/// copies once. A light move resets the mean, and still reads nothing back.
#[test]
fn presented_frames_accumulate_on_the_gpu_and_read_nothing_back() {
    let gpu = TestGpu::new();
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let s = settings();
    let mut reference = Renderer::new(&gpu, &scene).unwrap();
    let frames: Vec<Vec<[f32; 4]>> = (0..3u64)
        .map(|k| reference.render(&FrameSettings { seed: s.seed + k, ..s.clone() }).unwrap().radiance)
        .collect();
    let n = frames[0].len();
    let mut want = vec![[0f32; 4]; n];
    for f in &frames {
        for (a, p) in want.iter_mut().zip(f) {
            *a = [a[0] + p[0], a[1] + p[1], a[2] + p[2], a[3] + p[3]];
        }
    }
    want.iter_mut().for_each(|p| *p = p.map(|c| c / 3.0));

    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let ldr = Present::ldr_image(&gpu, s.width, s.height).unwrap();
    let before = gpu.readbacks();
    for k in 0..2u32 {
        let f = r
            .present(&FrameSettings { seed: s.seed + k as u64, ..s.clone() }, &ldr, params(k + 1, k == 0), false)
            .unwrap();
        assert!(f.ran.contains(&"present") && f.radiance.is_empty(), "{:?}", f.ran);
    }
    assert_eq!(gpu.readbacks(), before, "a presented frame copied to host memory");
    let last = r.present(&FrameSettings { seed: s.seed + 2, ..s.clone() }, &ldr, params(3, false), true).unwrap();
    assert_eq!(gpu.readbacks(), before + 1, "the screenshot's frame reads back once");
    assert_eq!(last.radiance, want, "the GPU's running mean is not the mean of the frames");
    let picture = ldr.res.read_back(ldr.last_access()).unwrap();
    ldr.set_last_access(Access::TransferRead);
    let mean = RgbImage::from_rgba(s.width, s.height, &want);
    assert!(max_step(&picture, &cpu_bytes(&mean)) <= 1);

    let before = gpu.readbacks();
    let p = Vec3::from_slice(&scene.lights[0].position[..3]);
    r.set_light(0, p + Vec3::new(0.1, 0.0, 0.1), Vec3::from_slice(&scene.lights[0].intensity[..3]));
    let moved = r.present(&s, &ldr, params(1, true), true).unwrap();
    assert!(moved.ran.contains(&"dprsm") && moved.ran.contains(&"cdf_reduce"), "{:?}", moved.ran);
    assert_eq!(gpu.readbacks(), before + 1, "only the mean is read back (no dead-CDF check)");
    let mut fresh = Renderer::new(&gpu, &scene).unwrap();
    fresh.set_light(0, p + Vec3::new(0.1, 0.0, 0.1), Vec3::from_slice(&scene.lights[0].intensity[..3]));
    assert_eq!(moved.radiance, fresh.render(&s).unwrap().radiance, "a reset mean is the frame itself");
}

/// present.comp's `prior_weight` on the host, in f64 with two-pass variances: the kept prior's weight in
/// frames at pixel `i` of a `w`-wide image after the first `n` still `frames`.
fn prior_weight(n: usize, frames: &[Vec<[f32; 4]>], prior: &[[f32; 4]], (w, h): (usize, usize), i: usize) -> f64 {
    let fade = (1.0 - (n as f64 - 1.0) / STOP_PRIOR_FADE as f64).max(0.0);
    if n == 1 {
        return STOP_PRIOR_FIRST as f64 * fade;
    }
    let lum = |p: &[f32; 4]| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
    let (x, y) = ((i % w) as i64, (i / w) as i64);
    let (mut v, mut dev, mut count) = (0.0, 0.0, 0.0);
    for (dx, dy) in (-1..=1).flat_map(|dy| (-1..=1).map(move |dx| (dx, dy))) {
        let (qx, qy) = (x + dx, y + dy);
        if qx < 0 || qy < 0 || qx >= w as i64 || qy >= h as i64 {
            continue;
        }
        let q = qy as usize * w + qx as usize;
        let ls: Vec<f64> = frames[..n].iter().map(|f| lum(&f[q])).collect();
        let mean = ls.iter().sum::<f64>() / n as f64;
        v += ls.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / (n as f64 - 1.0);
        dev += (lum(&prior[q]) - mean).powi(2);
        count += 1.0;
    }
    v /= count;
    let e2 = (dev / count - v / n as f64).max(1e-30);
    (v / e2).min(STOP_PRIOR_MAX as f64) * fade
}

/// A stop: the present pass keeps a real-time frame D (`Prior::Keep`); the still frames after it
/// (`Prior::Use`) show (Σ_{k ≤ n} P_k + w D) / (n + w), w per pixel by the rule of present.comp
/// (against its host twin above), the mean of `render`'s frames with D worth w frames, and from frame
/// STOP_PRIOR_FADE + 1 on the plain mean. D has other random numbers than every P_k, so a pass that
/// dropped it, kept it too long, or weighed it alike everywhere (one frame's worth) is seen.
#[test]
fn a_still_mean_after_a_move_carries_the_last_real_time_frame_then_lets_it_go() {
    let gpu = TestGpu::new();
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let s = settings();
    let n = STOP_PRIOR_FADE as u32 + 2;
    let size = (s.width as usize, s.height as usize);
    let mut reference = Renderer::new(&gpu, &scene).unwrap();
    let mut render = |seed: u64| reference.render(&FrameSettings { seed, ..s.clone() }).unwrap().radiance;
    let prior = render(s.seed + 1000);
    let frames: Vec<Vec<[f32; 4]>> = (0..n as u64).map(|k| render(s.seed + k)).collect();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let ldr = Present::ldr_image(&gpu, s.width, s.height).unwrap();
    let kept = PresentParams { prior: Prior::Keep, ..params(1, true) };
    let shown = r.present(&FrameSettings { seed: s.seed + 1000, ..s.clone() }, &ldr, kept, true).unwrap();
    assert_eq!(shown.radiance, prior, "a real-time frame is shown alone");
    let mut sum = vec![[0f64; 3]; prior.len()];
    for k in 0..n as usize {
        for (a, p) in sum.iter_mut().zip(&frames[k]) {
            (0..3).for_each(|c| a[c] += p[c] as f64);
        }
        let count = k + 1;
        let read = [0, 1, 7, n as usize - 2, n as usize - 1].contains(&k);
        let p = PresentParams { prior: Prior::Use, ..params(count as u32, k == 0) };
        let got = r.present(&FrameSettings { seed: s.seed + k as u64, ..s.clone() }, &ldr, p, read).unwrap();
        if !read {
            continue;
        }
        // What the picture shows, beside the plain mean and the mean with D as one frame everywhere.
        let (mut worst, mut scale, mut off_plain, mut off_one) = (0f64, 0f64, 0f64, 0f64);
        for (i, ((g, a), d)) in got.radiance.iter().zip(&sum).zip(&prior).enumerate() {
            let w = prior_weight(count, &frames, &prior, size, i);
            for c in 0..3 {
                let want = (a[c] + w * d[c] as f64) / (count as f64 + w);
                worst = worst.max((g[c] as f64 - want).abs());
                scale = scale.max(want.abs());
                off_plain = off_plain.max((g[c] as f64 - a[c] / count as f64).abs());
                off_one = off_one.max((g[c] as f64 - (a[c] + d[c] as f64) / (count as f64 + 1.0)).abs());
            }
        }
        assert!(worst <= 1e-4 * scale, "frame {count}: {worst} from the blend (scale {scale})");
        match (count as f32) < 1.0 + STOP_PRIOR_FADE {
            true => assert!(off_plain > 1e-3 * scale, "frame {count}: the prior left no trace ({off_plain})"),
            false => assert!(off_plain <= 1e-5 * scale, "frame {count}: the prior stayed ({off_plain})"),
        }
        if count > 1 && (count as f32) < 1.0 + STOP_PRIOR_FADE {
            assert!(off_one > 1e-3 * scale, "frame {count}: one weight everywhere ({off_one})");
        }
    }
}

/// A stop finds the kept real-time frame only where a kept frame wrote it: after a resize (a real-time
/// frame at one size, the still frames at another) there is none at the new size, and the still frames
/// show the plain mean from the first on, not a blend with an image nothing wrote (which the stop's
/// second frame read when its first one made the prior's image without writing it).
#[test]
fn a_stop_after_a_resize_shows_the_plain_mean() {
    let gpu = TestGpu::new();
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let s = settings();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let ldr = Present::ldr_image(&gpu, s.width, s.height).unwrap();
    let kept = PresentParams { prior: Prior::Keep, ..params(1, true) };
    r.present(&FrameSettings { seed: s.seed + 1000, ..s.clone() }, &ldr, kept, false).unwrap();
    let resized = FrameSettings { width: s.width + 8, height: s.height + 4, ..s.clone() };
    let ldr = Present::ldr_image(&gpu, resized.width, resized.height).unwrap();
    let mut reference = Renderer::new(&gpu, &scene).unwrap();
    let mut sum = vec![[0f64; 3]; (resized.width * resized.height) as usize];
    for k in 0..3u64 {
        let still = FrameSettings { seed: s.seed + k, ..resized.clone() };
        for (a, p) in sum.iter_mut().zip(&reference.render(&still).unwrap().radiance) {
            (0..3).for_each(|c| a[c] += p[c] as f64);
        }
        let p = PresentParams { prior: Prior::Use, ..params(k as u32 + 1, k == 0) };
        let got = r.present(&still, &ldr, p, true).unwrap();
        let n = (k + 1) as f64;
        let (mut worst, mut scale) = (0f64, 0f64);
        for (g, a) in got.radiance.iter().zip(&sum) {
            for c in 0..3 {
                worst = worst.max((g[c] as f64 - a[c] / n).abs());
                scale = scale.max(a[c].abs() / n);
            }
        }
        assert!(worst <= 1e-5 * scale, "still frame {}: {worst} from the plain mean (scale {scale})", k + 1);
    }
}
