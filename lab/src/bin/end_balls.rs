//! Records per exact shadow ray with and without the end balls (`crates/graph/src/passes/end_balls.rs`):
//! the CPU twin of the threaded walk (`bounce_oracles::cpu_threaded`) on the gather's pairs of a 64²
//! view (each pixel's first hit to 8 of 1,024 VPLs, the first light's first hits in uniform directions,
//! as `cell-bvhs --gather`), with each end's plane its triangle's. It prints the radii's medians, the
//! records one ball costs by the threaded walk for a few caps on the radius, and the records per ray
//! (all, visible) walking whole segments against skipping both balls and only the pixel's, then the walk's
//! loop iterations per ray when 1, 8 or 32 pixels walk their queues of rays in lock step (on lavapipe
//! the time follows these only in part: 19 % fewer of them bought 8 % on Sibenik, BENCHMARKS.md, "Where
//! the exact gather's time goes on this CPU"). Every clipped walk's answer is checked against the whole
//! segment's. `CAP=c` caps the radii at c × the
//! scene diagonal (default: the renderer's, END_BALL_MAX_RADIUS); like the renderer it subtracts one lift.
//! (Here each end is lifted along its face normal, the renderer lifts x along its shading normal.)
//! Figures: BENCHMARKS.md, "Exact shadow rays that skip their ends' empty balls" and "An optimized BVH".
//!
//!     cargo run --release -p bounce-lab --bin end-balls -- scene.toml

use bounce_graph::bvh::query::BvhView;
use bounce_graph::bvh::{Bvh, FlatBvh};
use bounce_graph::scene::Scene;
use bounce_oracles::cpu_end_balls::point_triangle_distance;
use bounce_oracles::cpu_threaded;
use glam::{DVec3, Vec3};
use std::path::Path;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else { anyhow::bail!("usage: end-balls scene.toml") };
    let scene = Scene::load(Path::new(path))?;
    let flat = FlatBvh::new(&Bvh::new(&scene), &scene.vertices);
    let threaded = flat.threaded();
    let paired = threaded.iter().filter(|r| r.pad2 != 0).count();
    println!(
        "{} threaded records ({:.1} MiB), {paired} of them boxes holding the box after them",
        threaded.len(),
        std::mem::size_of_val(threaded.as_slice()) as f64 / (1 << 20) as f64
    );
    let view = BvhView { nodes: &flat.nodes, tris: &flat.tris };
    let diag = (scene.bounds_max - scene.bounds_min).length();
    let lift = |x: Vec3| (1e-5 * diag).max(x.abs().max_element() / 262144.0);
    let (pixels, vpls, mut rng) = bounce_lab::gather_ends(&scene, &flat);
    let light = Vec3::from_slice(&scene.lights[0].position[..3]);
    let t0 = std::time::Instant::now();
    let rx: Vec<f64> =
        pixels.iter().map(|&(x, n)| bounce_lab::windows::ball_radius(&view, x, n, lift(x) / 16.0)).collect();
    let cap: f64 = std::env::var("CAP")
        .ok()
        .and_then(|c| c.parse().ok())
        .unwrap_or(bounce_graph::bindings::END_BALL_MAX_RADIUS as f64)
        * diag as f64;
    let rx: Vec<f64> = rx.iter().map(|r| r.min(cap)).collect();
    let ry: Vec<f64> =
        vpls.iter().map(|&(y, n)| bounce_lab::windows::ball_radius(&view, y, n, lift(y) / 16.0).min(cap)).collect();
    println!("radii in {:.1} s", t0.elapsed().as_secs_f64());
    let med = |v: &[f64]| {
        let mut s = v.to_vec();
        s.sort_by(f64::total_cmp);
        s[s.len() / 2]
    };
    for rmax_frac in [0.01f64, 0.03, 0.1, 1.0] {
        let (mut recs, mut maxr, mut same) = (0u64, 0u32, 0usize);
        for (k, &(x, n)) in pixels.iter().enumerate() {
            let (r, c) = threaded_radius(&threaded, x, n, lift(x) / 16.0, rmax_frac * diag as f64);
            recs += c as u64;
            maxr = maxr.max(c);
            if (r - rx[k].min(rmax_frac * diag as f64)).abs() <= 1e-9 * diag as f64 {
                same += 1;
            }
        }
        println!(
            "rmax {rmax_frac} diag: threaded ball query {:.1} records (max {maxr}), {same}/{} equal",
            recs as f64 / pixels.len() as f64,
            pixels.len()
        );
    }
    println!("median r: pixels {:.3}, vpls {:.3}, diag {:.1}", med(&rx), med(&ry), diag);
    let mut xonly = 0u64;
    let mut steps = 0u64;
    // Each pixel's loop iterations: the gather walks a pixel's rays one after another from a queue
    // (`glsl/shared/shadow_queue.glsl`), each taking whole iterations of THREAD_UNROLL steps.
    let unroll = bounce_graph::bvh::THREAD_UNROLL;
    let mut per_pixel = vec![0u64; pixels.len()];
    let (mut rays, mut full, mut clipped, mut none_needed, mut vis, mut vis_full, mut vis_clip) =
        (0u64, 0u64, 0u64, 0u64, 0u64, 0u64, 0u64);
    for (pi, vi) in bounce_lab::gather_pairs(&pixels, &vpls, &mut rng) {
        let ((x, nx), (y, ny)) = (pixels[pi], vpls[vi]);
        rays += 1;
        let o = (x + nx * lift(x)).as_dvec3();
        let e = (y + (light - y).normalize() * lift(y)).as_dvec3();
        let (lo, hi) = (1e-6, 1.0 - 1e-6);
        let w = cpu_threaded::walk(&threaded, o, e, lo, hi);
        full += w.records as u64;
        let t1 = bounce_lab::windows::ball_exit(
            o,
            e,
            x.as_dvec3(),
            nx.as_dvec3(),
            rx[pi] - lift(x) as f64,
            lift(x) as f64 / 8.0,
        );
        let t2 = 1.0
            - bounce_lab::windows::ball_exit(
                e,
                o,
                y.as_dvec3(),
                ny.as_dvec3(),
                ry[vi] - lift(y) as f64,
                lift(y) as f64 / 8.0,
            );
        let (a, b) = (t1.max(lo), t2.min(hi));
        let c = if a >= b {
            none_needed += 1;
            cpu_threaded::WalkCount::default()
        } else {
            cpu_threaded::walk_clipped(&threaded, o, e, a, b, &[(a, b)])
        };
        anyhow::ensure!(c.occluded == w.occluded, "answers differ at pixel {pi}");
        let cx = cpu_threaded::walk_clipped(&threaded, o, e, t1.max(lo), hi, &[(t1.max(lo), hi)]);
        anyhow::ensure!(cx.occluded == w.occluded, "answers differ at pixel {pi}");
        xonly += cx.records as u64;
        clipped += c.records as u64;
        steps += c.steps as u64;
        per_pixel[pi] += c.steps.div_ceil(unroll) as u64;
        if !w.occluded {
            vis += 1;
            vis_full += w.records as u64;
            vis_clip += c.records as u64;
        }
    }
    let n = rays as f64;
    println!(
        "{rays} rays ({vis} visible, {none_needed} need no walk): records per ray {:.1} -> {:.1}; per visible ray {:.1} -> {:.1}",
        full as f64 / n,
        clipped as f64 / n,
        vis_full as f64 / vis as f64,
        vis_clip as f64 / vis as f64
    );
    println!("pixel end only: {:.1}", xonly as f64 / n);
    println!("steps per ray with the balls (two boxes a step): {:.1}", steps as f64 / n);
    // What a SIMD machine pays: lanes (pixels, in the order drawn) run in lock step until the one with the
    // most iterations is done (8 lanes: llvmpipe's 256-bit vectors; 32: a GPU's warp).
    for lanes in [1usize, 8, 32] {
        let iterations: u64 = per_pixel.chunks(lanes).map(|g| g.iter().max().unwrap_or(&0) * g.len() as u64).sum();
        println!("{lanes} lanes: loop iterations per ray {:.2}", iterations as f64 / n);
    }
    Ok(())
}

fn threaded_radius(recs: &[bounce_graph::bvh::GpuThreadRec], p: Vec3, n: Vec3, tau: f32, rmax: f64) -> (f64, u32) {
    let (p, n, tau) = (p.as_dvec3(), n.as_dvec3(), tau as f64);
    let mut best = rmax;
    let (mut i, mut count) = (0usize, 0u32);
    while i < recs.len() {
        let r = &recs[i];
        count += 1;
        let (a, b, c) = (Vec3::from(r.a).as_dvec3(), Vec3::from(r.b).as_dvec3(), Vec3::from(r.c).as_dvec3());
        if r.link == bounce_graph::bvh::THREAD_TRI {
            if [a, b, c].iter().any(|&v| n.dot(v - p) > tau) {
                best = best.min(point_triangle_distance(p, &[a, b, c]));
            }
            i += 1;
        } else {
            let q = p.clamp(a, b);
            let top = DVec3::new(
                if n.x > 0.0 { b.x } else { a.x },
                if n.y > 0.0 { b.y } else { a.y },
                if n.z > 0.0 { b.z } else { a.z },
            );
            i = if (q - p).length() < best && n.dot(top - p) > tau { i + 1 } else { r.link as usize };
        }
    }
    (best, count)
}
