//! How much of the exact gather's shadow rays, after their ends' empty balls, two more ways of skipping
//! empty space would leave unwalked, on the gather's pairs of a 64² view (as `end-balls`: each pixel's
//! first hit to 8 of 1,024 VPLs, the balls capped at the renderer's END_BALL_MAX_RADIUS):
//! - *an occupancy grid*: the rays whose window (the segment less both balls) crosses no occupied cell of
//!   a G³ grid need no walk at all. The grid is the renderer's conservative voxelization (its CPU twin
//!   `bounce_oracles::cpu_voxel`, G cells on the longest side). Printed per G: the share of
//!   rays (and of visible rays) with such a window, and the cells an Amanatides–Woo march visits until it
//!   meets an occupied cell or the window's end;
//! - *the VPL's direction cones*: for each VPL and each bin of a cube map of m × m directions a face, the
//!   distance from the ray's lifted end to the nearest triangle (more than τ above the VPL's plane) that
//!   meets the bin's cone; a ray in that bin skips that much of its VPL's side. Printed per m: the walk's
//!   records per ray (and per visible ray) against the balls' alone.
//!
//! Every claim is checked against the exact walk: a window called free must be unoccluded, and a walk
//! shortened by a cone must give the whole segment's answer. Figures: BENCHMARKS.md, "Skipping more of
//! the exact rays' empty space".
//!
//!     cargo run --release -p bounce-lab --bin ray-windows -- scene.toml [G,G,…] [m,m,…]

use bounce_graph::bvh::query::BvhView;
use bounce_graph::bvh::{Bvh, FlatBvh};
use bounce_graph::passes::voxelize::{self, VoxelGridSpec};
use bounce_graph::scene::Scene;
use bounce_lab::windows::{ball_exit, ball_radius, nearest_above};
use bounce_oracles::{cpu_threaded, cpu_voxel};
use glam::{DVec3, Vec3};
use std::path::Path;

/// A comma-separated list of sizes from 1 to `max` (`default` when absent).
fn list(arg: Option<&String>, default: &[usize], max: usize) -> anyhow::Result<Vec<usize>> {
    let Some(a) = arg else { return Ok(default.to_vec()) };
    a.split(',')
        .map(|x| match x.parse::<usize>() {
            Ok(n) if (1..=max).contains(&n) => Ok(n),
            _ => anyhow::bail!("'{x}' in '{a}' is not a size from 1 to {max}"),
        })
        .collect()
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else { anyhow::bail!("usage: ray-windows scene.toml [G,G,…] [m,m,…]") };
    let (grids, bins) = (list(args.get(1), &[32, 64, 128, 256], 1024)?, list(args.get(2), &[2, 4, 8], 64)?);
    let scene = Scene::load(Path::new(path))?;
    anyhow::ensure!(!scene.lights.is_empty(), "{path} has no light, so no VPLs");
    let flat = FlatBvh::new(&Bvh::new(&scene), &scene.vertices);
    let threaded = flat.threaded();
    let view = BvhView { nodes: &flat.nodes, tris: &flat.tris };
    let diag = (scene.bounds_max - scene.bounds_min).length();
    let lift = |x: Vec3| (1e-5 * diag).max(x.abs().max_element() / 262144.0);
    let cap = bounce_graph::bindings::END_BALL_MAX_RADIUS as f64 * diag as f64;
    let (pixels, vpls, mut rng) = bounce_lab::gather_ends(&scene, &flat);
    let light = Vec3::from_slice(&scene.lights[0].position[..3]);
    let rx: Vec<f64> = pixels.iter().map(|&(x, n)| ball_radius(&view, x, n, lift(x) / 16.0).min(cap)).collect();
    let ry: Vec<f64> = vpls.iter().map(|&(y, n)| ball_radius(&view, y, n, lift(y) / 16.0).min(cap)).collect();
    let occupied: Vec<(VoxelGridSpec, cpu_voxel::CpuGrid)> = grids
        .iter()
        .map(|&g| {
            let spec = voxelize::fit(scene.bounds_min, scene.bounds_max, g as u32);
            (spec, cpu_voxel::voxelize_scene(&scene, spec))
        })
        .collect();
    let ends: Vec<DVec3> = vpls.iter().map(|&(y, _)| (y + (light - y).normalize() * lift(y)).as_dvec3()).collect();
    let cones: Vec<Vec<Vec<f64>>> = bins.iter().map(|&m| cone_distances(&view, &vpls, &ends, m, &lift)).collect();
    let (mut rays, mut visible, mut balls, mut balls_vis) = (0u64, 0u64, 0u64, 0u64);
    let (mut free, mut free_vis, mut cells) =
        (vec![0u64; grids.len()], vec![0u64; grids.len()], vec![0u64; grids.len()]);
    let (mut coned, mut coned_vis) = (vec![0u64; bins.len()], vec![0u64; bins.len()]);
    for (pi, vi) in bounce_lab::gather_pairs(&pixels, &vpls, &mut rng) {
        let ((x, nx), (y, ny)) = (pixels[pi], vpls[vi]);
        let (o, e) = ((x + nx * lift(x)).as_dvec3(), ends[vi]);
        let whole = cpu_threaded::walk(&threaded, o, e, 1e-6, 1.0 - 1e-6);
        let (mx, my) = (lift(x) as f64 / 8.0, lift(y) as f64 / 8.0);
        let a = ball_exit(o, e, x.as_dvec3(), nx.as_dvec3(), rx[pi] - lift(x) as f64, mx).max(1e-6);
        let b = (1.0 - ball_exit(e, o, y.as_dvec3(), ny.as_dvec3(), ry[vi] - lift(y) as f64, my)).min(1.0 - 1e-6);
        let walk = |b: f64| match a < b {
            true => cpu_threaded::walk_clipped(&threaded, o, e, a, b, &[(a, b)]),
            false => cpu_threaded::WalkCount::default(),
        };
        let w = walk(b);
        anyhow::ensure!(w.occluded == whole.occluded, "the balls changed pixel {pi}'s answer");
        rays += 1;
        visible += u64::from(!whole.occluded);
        balls += w.records as u64;
        balls_vis += if whole.occluded { 0 } else { w.records as u64 };
        for (k, &g) in grids.iter().enumerate() {
            let (spec, grid) = &occupied[k];
            let (empty, n) = if a < b { march(spec, grid, o, e, a, b) } else { (true, 0) };
            anyhow::ensure!(!(empty && whole.occluded), "an occluded ray's window is empty on the {g}³ grid");
            cells[k] += n as u64;
            free[k] += u64::from(empty);
            free_vis[k] += u64::from(empty && !whole.occluded);
        }
        let len = (o - e).length();
        let above = ny.as_dvec3().dot(e - y.as_dvec3()) > my && ny.as_dvec3().dot(o - y.as_dvec3()) > my;
        for (k, &m) in bins.iter().enumerate() {
            let d = if above { (cones[k][vi][bin_of((o - e) / len, m)] - 1e-6 * len).max(0.0) } else { 0.0 };
            let c = walk(b.min(1.0 - d / len));
            anyhow::ensure!(c.occluded == whole.occluded, "the {m}² cones changed pixel {pi}'s answer");
            coned[k] += c.records as u64;
            coned_vis[k] += if whole.occluded { 0 } else { c.records as u64 };
        }
    }
    let (n, nv) = (rays as f64, visible as f64);
    println!(
        "{rays} rays ({visible} visible): records per ray with the balls {:.1}, per visible ray {:.1}",
        balls as f64 / n,
        balls_vis as f64 / nv
    );
    for (k, g) in grids.iter().enumerate() {
        println!(
            "{g}³ grid: window free of occupied cells for {:.1} % of rays ({:.1} % of visible ones); {:.1} cells a march",
            100.0 * free[k] as f64 / n,
            100.0 * free_vis[k] as f64 / nv,
            cells[k] as f64 / n
        );
    }
    for (k, m) in bins.iter().enumerate() {
        println!(
            "VPL cones, {m}×{m} a face: records per ray {:.1}, per visible ray {:.1}",
            coned[k] as f64 / n,
            coned_vis[k] as f64 / nv
        );
    }
    Ok(())
}

/// Whether the segment o → e between parameters a and b crosses no occupied cell of `grid`, and the
/// cells visited until the first occupied one (or the window's end).
fn march(spec: &VoxelGridSpec, grid: &cpu_voxel::CpuGrid, o: DVec3, e: DVec3, a: f64, b: f64) -> (bool, u32) {
    let cells = bounce_lab::grid_cells_along(spec, o + (e - o) * a, o + (e - o) * b);
    match cells.iter().position(|&(c, _, _)| grid.occupied(c)) {
        Some(k) => (false, k as u32 + 1),
        None => (true, cells.len() as u32),
    }
}

/// The direction of (u, v) ∈ [0, 1]² on cube face `face`.
fn face_dir(face: usize, u: f64, v: f64) -> DVec3 {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    let d = match face {
        0 => DVec3::new(1.0, a, b),
        1 => DVec3::new(-1.0, a, b),
        2 => DVec3::new(a, 1.0, b),
        3 => DVec3::new(a, -1.0, b),
        4 => DVec3::new(a, b, 1.0),
        _ => DVec3::new(a, b, -1.0),
    };
    d.normalize()
}

/// Bin k of m × m a face: its axis, and the largest angle between it and the bin's corners.
fn bin_cone(k: usize, m: usize) -> (DVec3, f64) {
    let (face, i, j) = (k / (m * m), (k % (m * m)) % m, (k % (m * m)) / m);
    let at = |di: f64, dj: f64| face_dir(face, (i as f64 + di) / m as f64, (j as f64 + dj) / m as f64);
    let axis = at(0.5, 0.5);
    let corners = [at(0.0, 0.0), at(1.0, 0.0), at(0.0, 1.0), at(1.0, 1.0)];
    (axis, corners.iter().map(|c| axis.dot(*c).clamp(-1.0, 1.0).acos()).fold(0.0, f64::max) * 1.0001)
}

fn bin_of(d: DVec3, m: usize) -> usize {
    let a = d.abs();
    let (face, u, v) = if a.x >= a.y && a.x >= a.z {
        (if d.x > 0.0 { 0 } else { 1 }, d.y / a.x, d.z / a.x)
    } else if a.y >= a.z {
        (if d.y > 0.0 { 2 } else { 3 }, d.x / a.y, d.z / a.y)
    } else {
        (if d.z > 0.0 { 4 } else { 5 }, d.x / a.z, d.y / a.z)
    };
    let cell = |t: f64| (((t + 1.0) * 0.5 * m as f64) as usize).min(m - 1);
    face * m * m + cell(v) * m + cell(u)
}

/// Per VPL, per bin of m × m a face: the distance from its lifted end to the nearest triangle meeting
/// the bin's cone (a sphere meets the cone when its angle from the axis is within the cone's half-angle
/// plus the sphere's own angular radius).
fn cone_distances(
    view: &BvhView,
    vpls: &[bounce_lab::SurfacePoint],
    ends: &[DVec3],
    m: usize,
    lift: &dyn Fn(Vec3) -> f32,
) -> Vec<Vec<f64>> {
    let cones: Vec<(DVec3, f64)> = (0..6 * m * m).map(|k| bin_cone(k, m)).collect();
    vpls.iter()
        .zip(ends)
        .map(|(&(y, ny), &e)| {
            let tau = lift(y) as f64 / 16.0;
            cones
                .iter()
                .map(|&(axis, half)| {
                    let meets = |c: DVec3, r: f64| {
                        let w = c - e;
                        let l = w.length();
                        l <= r || (w.dot(axis) / l).clamp(-1.0, 1.0).acos() <= half + (r / l).asin()
                    };
                    nearest_above(view, e, y.as_dvec3(), ny.as_dvec3(), tau, &meets)
                })
                .collect()
        })
        .collect()
}
