//! Progressive rendering's VPL sets (`progressive::VplSets`, `progressive::frame_settings`): the mean
//! over frames that move on to new VPL sets converges to the one-bounce image, where the frames of one
//! set converge to that set's VPL sum and keep its quadrature error however long they run.

use crate::vpl::indirect_with;
use bounce_graph::frame::progressive::frame_settings;
use bounce_graph::frame::{FrameSettings, Method, Renderer, VplKernel};
use bounce_graph::scene::Scene;
use bounce_tests::TestGpu;

/// Each set's VPL sum (`all`) against the path tracer at 16384 paths a pixel on the Cornell box, 24²
/// pixels, 64² a face: eight sets, as a progressive render draws them (`frame_settings(s, k, set)`),
/// average most of one set's error away. With the point kernel the sum over sets is unbiased (the dprsm
/// tests check Σ Δω against a closed form), so what is left is the path tracer's noise and an eighth
/// of one set's: the mean of the sets must have at most half one set's relMSE (measured: 0.00206 →
/// 0.00063), its image mean within 1 % of the exact image's (0.9988), and no set may repeat another.
/// With the patch kernel and 128² a face, as a render has them (`bounce render --method all --cdf-seed
/// j`, j = 1..8): 0.00055 → 0.00019, of which the spread between sets was 0.00042.
#[test]
fn vpl_sets_average_away_one_sets_quadrature_error() {
    const SETS: u32 = 8;
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let (w, h, res) = (24, 24, 64);
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let exact = FrameSettings { method: Method::Reference, spp: 16384, ..FrameSettings::default() };
    let exact = indirect_with(&mut r, exact, w, h, res, 32);
    let base = FrameSettings { method: Method::All, vpl_kernel: VplKernel::Point, seed: 3, ..FrameSettings::default() };
    let (mut one, mut mean) = (0.0, vec![[0.0f32; 3]; (w * h) as usize]);
    let mut images = vec![];
    for set in 0..SETS {
        let img = indirect_with(&mut r, frame_settings(&base, 0, set), w, h, res, 32);
        one += bounce_tests::rel_mse(&img, &exact) / SETS as f64;
        for (m, p) in mean.iter_mut().zip(&img) {
            for c in 0..3 {
                m[c] += p[c] / SETS as f32;
            }
        }
        assert!(!images.contains(&img), "set {set} repeats an earlier set's VPLs");
        images.push(img);
    }
    let sets = bounce_tests::rel_mse(&mean, &exact);
    let ratio = bounce_tests::mean(&mean) / bounce_tests::mean(&exact);
    eprintln!(
        "relMSE against the exact image: one set {one:.5}, the mean of {SETS} sets {sets:.5}; image mean {ratio:.4}"
    );
    assert!(sets <= 0.5 * one, "the mean of {SETS} sets {sets} against one set's {one}");
    assert!((ratio - 1.0).abs() <= 0.01, "the mean of {SETS} sets is {ratio} of the exact image's");
}

/// A progressive render judges its second frame by the first's time less the GPU time of the passes
/// that made what the second keeps (`FrameOutput::kept_gpu_ms`): the passes the graph marks as making kept products must be those
/// the second frame does not run, and it runs no pass the first did not run unmarked.
#[test]
fn the_passes_marked_kept_are_those_the_next_frame_skips() {
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    // (realtime's temporal passes run from its second frame on; `all` renders one frame.)
    for method in Method::ALL.into_iter().filter(|m| !matches!(m, Method::All | Method::Realtime)) {
        let s =
            FrameSettings { method, width: 16, height: 16, dprsm_res: 16, vpls: 2, spp: 2, ..FrameSettings::default() };
        r.clear_frame_cache();
        let first = r.render(&frame_settings(&s, 0, 0)).unwrap();
        let next = r.render(&frame_settings(&s, 1, 0)).unwrap();
        let kept: Vec<&str> = first.timings.iter().filter(|t| t.kept).map(|t| t.name).collect();
        let again: Vec<&str> = first.timings.iter().filter(|t| !t.kept).map(|t| t.name).collect();
        assert!(!kept.is_empty(), "{method:?}: the first frame made nothing to keep");
        // (A temporal resource's first clear, ris's control counts, runs in the first frame alone.)
        assert!(
            next.ran.iter().all(|p| again.contains(p) && !kept.contains(p)),
            "{method:?}: the second frame ran {:?}, the first {again:?} again and {kept:?} kept",
            next.ran
        );
        let (kept_ms, all_ms) = (first.kept_gpu_ms().unwrap(), first.gpu_ms().unwrap());
        assert!(kept_ms > 0.0 && kept_ms < all_ms, "{method:?}: {kept_ms} of {all_ms} ms kept");
    }
}
