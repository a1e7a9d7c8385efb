//! Cells visited per visibility march, over random pairs of surface points of a scene (default: the
//! Cornell box), for the voxel march (CPU twin `bounce_oracles::cpu_voxel`, which stops at the first
//! occupied cell) and for `--visibility hybrid`'s march over its triangle lists (CPU twin
//! `bounce_oracles::cpu_cells`: list cells entered and triangle tests), and the records the exact shadow
//! rays' threaded BVH walk reads (CPU twin `bounce_oracles::cpu_threaded`). Also checks both against
//! every triangle: a pair the brute force finds occluded must be found occluded by both.
//!
//! For the pairs that see each other, also where the walk's records are: those it reads for the segment's
//! first 1 %, its last 1 % and the 98 % between (each a walk of its own, entering a box only where that
//! part of the segment meets it). A segment's ends lie on surfaces, inside many nested boxes, so a visible
//! ray pays for both ends' descents whatever lies between (endpoint overlap).
//!
//! With a third argument G, also the records the walk would read if each ray were clipped to the runs of
//! occupied cells of a G³ conservative grid (a box is entered only where a run of the segment meets it):
//! whether skipping empty space could shorten the exact rays.
//!
//!     cargo run -p bounce-tests --bin march-length [scene.toml] [voxels] [G]

use bounce_graph::bvh::cells::CellLists;
use bounce_graph::bvh::{Bvh, FlatBvh};
use bounce_graph::passes::voxelize;
use bounce_graph::scene::Scene;
use bounce_oracles::{cpu_cells, cpu_threaded, cpu_voxel};
use glam::{DVec3, Vec3};

fn main() -> anyhow::Result<()> {
    let path = std::env::args().nth(1).map_or_else(bounce_tests::default_scene, Into::into);
    let voxels: u32 = std::env::args().nth(2).map(|a| a.parse()).transpose()?.unwrap_or(128);
    let clip: Option<u32> = std::env::args().nth(3).map(|a| a.parse()).transpose()?;
    let scene = Scene::load(&path)?;
    let spec = voxelize::fit(scene.bounds_min, scene.bounds_max, voxels);
    let grid = cpu_voxel::voxelize_scene(&scene, spec);
    let flat = FlatBvh::new(&Bvh::new(&scene), &scene.vertices);
    let lists = CellLists::build(&flat.tris, &spec);
    let threaded = flat.threaded();
    let clip_grid = clip.map(|g| {
        let spec = voxelize::fit(scene.bounds_min, scene.bounds_max, g);
        (spec, cpu_voxel::voxelize_scene(&scene, spec))
    });
    let (mut c_records, mut c_runs) = (0u64, 0u64);
    let tris: Vec<[Vec3; 3]> =
        scene.vertices.chunks(3).map(|v| [v[0].position(), v[1].position(), v[2].position()]).collect();
    let mut rng = bounce_tests::Rng(7);
    let mut point = || {
        let t = tris[rng.below(tris.len() as u32) as usize];
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
        (rng.on_triangle(&t), n)
    };
    let (mut cells, mut pairs, mut blocked) = (0u64, 0u64, 0u64);
    let (mut h_cells, mut h_tests, mut h_blocked, mut missed) = (0u64, 0u64, 0u64, 0u64);
    let (mut t_records, mut t_tests, mut t_missed) = (0u64, 0u64, 0u64);
    // Visible pairs: their records, and those of the first 1 %, the last 1 % and the middle alone.
    let (mut v_pairs, mut v_records, mut v_parts) = (0u64, 0u64, [0u64; 3]);
    let check = flat.tris.len() <= 20_000;
    for _ in 0..20_000 {
        let ((x, nx), (y, ny)) = (point(), point());
        let nx = if nx.dot(y - x) < 0.0 { -nx } else { nx };
        let ny = if ny.dot(x - y) < 0.0 { -ny } else { ny };
        let mut k = 0u64;
        // The march stops at the first occupied cell, as the GPU's does.
        if !cpu_voxel::march(&spec, x, nx, y, ny, |c| {
            k += 1;
            grid.occupied(c)
        }) {
            blocked += 1;
        }
        cells += k;
        pairs += 1;
        // Hybrid: the segment between the points, a window of 1e-4 of it at both ends.
        let (a, b) = (x.as_dvec3(), y.as_dvec3());
        let h = cpu_cells::march(&lists, &spec, &flat.tris, a, b, 1e-4, 1.0 - 1e-4);
        h_cells += h.cells as u64;
        h_tests += h.tests as u64;
        h_blocked += h.occluded as u64;
        let w = cpu_threaded::walk(&threaded, a, b, 1e-4, 1.0 - 1e-4);
        t_records += w.records as u64;
        t_tests += w.tests as u64;
        if !w.occluded {
            v_pairs += 1;
            v_records += w.records as u64;
            for (part, run) in v_parts.iter_mut().zip([(0.0, 0.01), (0.99, 1.0), (0.01, 0.99)]) {
                *part += cpu_threaded::walk_clipped(&threaded, a, b, 1e-4, 1.0 - 1e-4, &[run]).records as u64;
            }
        }
        if let Some((spec, grid)) = &clip_grid {
            let runs = occupied_runs(spec, grid, a, b);
            let c = cpu_threaded::walk_clipped(&threaded, a, b, 1e-4, 1.0 - 1e-4, &runs);
            anyhow::ensure!(c.occluded == w.occluded, "clipping to the occupied runs changed an answer");
            c_records += c.records as u64;
            c_runs += runs.len() as u64;
        }
        if check {
            let truth = cpu_cells::brute_force(&flat.tris, a, b, 1e-4, 1.0 - 1e-4);
            missed += (h.occluded != truth) as u64;
            t_missed += (w.occluded != truth) as u64;
        }
    }
    let s = lists.stats();
    let n = pairs as f64;
    println!(
        "{voxels} voxels: voxel march {:.1} cells per march ({:.0} % occluded); hybrid ({}³-ish list grid of {} cells, factor {}, {} entries, longest list {}): {:.1} cells and {:.1} triangle tests per march ({:.0} % occluded){}",
        cells as f64 / n,
        100.0 * blocked as f64 / n,
        lists.dims.max_element(),
        s.cells,
        lists.factor,
        s.entries,
        s.max_list,
        h_cells as f64 / n,
        h_tests as f64 / n,
        100.0 * h_blocked as f64 / n,
        if check { format!("; {missed} of {pairs} pairs disagree with the brute force") } else { String::new() }
    );
    println!(
        "exact (the threaded BVH walk, {} records): {:.1} records read per ray, {:.1} of them triangles{}",
        threaded.len(),
        t_records as f64 / n,
        t_tests as f64 / n,
        if check { format!("; {t_missed} of {pairs} pairs disagree with the brute force") } else { String::new() }
    );
    let v = v_pairs.max(1) as f64;
    println!(
        "  visible pairs ({v_pairs}): {:.1} records, of which a walk of the first 1 % alone reads {:.1}, of the last 1 % {:.1}, of the 98 % between {:.1}",
        v_records as f64 / v,
        v_parts[0] as f64 / v,
        v_parts[1] as f64 / v,
        v_parts[2] as f64 / v
    );
    if let Some(g) = clip {
        println!(
            "exact clipped to the occupied runs of a {g}³ grid ({:.2} runs per ray): {:.1} records read per ray",
            c_runs as f64 / n,
            c_records as f64 / n
        );
    }
    anyhow::ensure!(missed == 0, "the triangle lists miss an occluder");
    anyhow::ensure!(t_missed == 0, "the threaded walk misses an occluder");
    Ok(())
}

/// The parameter intervals of the segment a → b that lie in occupied cells of `grid`, each widened by
/// 1e-6 against rounding, merged where they touch.
fn occupied_runs(spec: &voxelize::VoxelGridSpec, grid: &cpu_voxel::CpuGrid, a: DVec3, b: DVec3) -> Vec<(f64, f64)> {
    let mut runs = Vec::<(f64, f64)>::new();
    for (c, t0, t1) in bounce_tests::grid_cells_along(spec, a, b) {
        if grid.occupied(c) {
            let (t0, t1) = (t0 - 1e-6, t1 + 1e-6);
            match runs.last_mut() {
                Some(last) if last.1 >= t0 => last.1 = t1,
                _ => runs.push((t0, t1)),
            }
        }
    }
    runs
}
