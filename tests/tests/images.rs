//! Image tests on the default scene against committed references (made by the exact CPU reference,
//! `cargo run -p bounce-tests --bin make-references`). A missing reference fails; on a mismatch the
//! actual, reference and difference images are written to `target/test-output/`.

use bounce::output::{read_exr, RgbImage};
use bounce_graph::frame::{Component, FrameSettings, Method, Renderer};
use bounce_graph::scene::Scene;
use bounce_tests::{mean, rel_mse, write_evidence, TestGpu};

fn image_test(name: &str, component: Component, w: u32, h: u32, max_rel_mse: f64, max_mean_rel: f64) {
    let path = bounce_tests::workspace().join(format!("tests/references/{name}.exr"));
    assert!(
        path.exists(),
        "reference {} is missing: run `cargo run -p bounce-tests --bin make-references`",
        path.display()
    );
    let (reference, _) = read_exr(&path).unwrap();
    assert_eq!((reference.width, reference.height), (w, h), "reference size");
    let gpu = TestGpu::new();
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let frame = r
        .render(&FrameSettings { width: w, height: h, component, method: Method::Uniform, ..FrameSettings::default() })
        .unwrap();
    let actual = RgbImage::from_rgba(w, h, &frame.radiance);
    assert_eq!(actual.non_finite_count(), 0, "non-finite pixels");
    let e = rel_mse(&actual.pixels, &reference.pixels);
    let (ma, mr) = (mean(&actual.pixels), mean(&reference.pixels));
    let mean_rel = (ma - mr).abs() / mr;
    eprintln!("{name}: relMSE {e:.2e} (max {max_rel_mse:.0e}), mean {ma:.5} vs {mr:.5} ({:.3}%)", 100.0 * mean_rel);
    if e > max_rel_mse || mean_rel > max_mean_rel {
        let files = write_evidence(name, &actual, &reference);
        panic!(
            "{name}: relMSE {e:.3e} (max {max_rel_mse:.0e}), mean off by {:.3}% (max {:.1}%); see {files}",
            100.0 * mean_rel,
            100.0 * max_mean_rel
        );
    }
}

/// Tolerance: the direct light traces an exact shadow ray per pixel and light, so the image is the CPU
/// reference's up to f32 rounding (relMSE 9e-14 measured). A shadow pixel gone wrong on one outline
/// alone moves relMSE by about 1e-4, a wrong falloff or albedo by far more.
#[test]
fn cornell_direct_64_matches_the_reference() {
    image_test("cornell-direct-64", Component::Direct, 64, 64, 1e-8, 1e-5);
}
