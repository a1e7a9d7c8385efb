//! GPU time of a first frame, of an unchanged next frame (the frame cache: it records only the gather)
//! and of a frame after a camera move (the light-side cache: the paraboloid maps are kept), per method,
//! on the default scene. The figures of BENCHMARKS.md, "Skipping what a
//! frame does not need".
//!
//!     cargo run -p bounce-lab --bin static-frames [width] [vpls]

use bounce_device::{Gpu, GpuOptions};
use bounce_graph::frame::{Component, FrameSettings, Method, Renderer};
use bounce_graph::scene::Scene;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let size: u32 = args.next().map(|a| a.parse()).transpose()?.unwrap_or(128);
    let vpls: u32 = args.next().map(|a| a.parse()).transpose()?.unwrap_or(64);
    let scene = Scene::load(&bounce_tests::default_scene())?;
    let gpu = Gpu::new(&GpuOptions::default())?;
    println!("{} — default scene, {size}², combined, {vpls} VPLs, DPRSM 512², 128 voxels\n", gpu.name);
    println!("| method | first frame GPU ms | unchanged next frame GPU ms | next / first | passes of the next frame | after a camera move GPU ms | moved / first | passes after the move |");
    println!("|---|---:|---:|---:|---|---:|---:|---|");
    for method in [Method::Uniform, Method::Global, Method::Stratified, Method::Local, Method::Gbg, Method::Mis] {
        let mut r = Renderer::new(&gpu, &scene)?;
        let s = FrameSettings {
            width: size,
            height: size,
            component: Component::Combined,
            method,
            vpls,
            ..FrameSettings::default()
        };
        // A throw-away frame builds the voxel grid (once per scene), which is not part of a frame's cost.
        r.render(&FrameSettings { width: 8, height: 8, vpls: 1, ..s.clone() })?;
        r.clear_frame_cache();
        let first = r.render(&s)?;
        let next = r.render(&s)?;
        let mut moved = scene.camera;
        moved.eye += glam::Vec3::new(0.1, 0.0, -0.2);
        r.set_camera(moved);
        let after = r.render(&s)?;
        let (a, b, c) =
            (first.gpu_ms().unwrap_or(f64::NAN), next.gpu_ms().unwrap_or(f64::NAN), after.gpu_ms().unwrap_or(f64::NAN));
        println!(
            "| {} | {a:.1} | {b:.1} | {:.0} % | {} | {c:.1} | {:.0} % | {} |",
            method.name(),
            100.0 * b / a,
            next.ran.join(", "),
            100.0 * c / a,
            after.ran.join(", ")
        );
    }
    Ok(())
}
