//! Mean number of voxel cells the visibility march visits per VPL–point pair (CPU twin of the GPU
//! march, `bounce_oracles::cpu_voxel`), over random pairs of surface points of the default scene: the
//! factor between VPL evaluations/s and voxel steps/s in BENCHMARKS.md.
//!
//!     cargo run -p bounce-tests --bin march-length [voxels]

use bounce_graph::passes::voxelize;
use bounce_graph::scene::Scene;
use bounce_oracles::cpu_voxel;
use glam::Vec3;

fn main() -> anyhow::Result<()> {
    let voxels: u32 = std::env::args().nth(1).map(|a| a.parse()).transpose()?.unwrap_or(128);
    let scene = Scene::load(&bounce_tests::default_scene())?;
    let spec = voxelize::fit(scene.bounds_min, scene.bounds_max, voxels);
    let grid = cpu_voxel::voxelize_scene(&scene, spec);
    let tris: Vec<[Vec3; 3]> =
        scene.vertices.chunks(3).map(|v| [v[0].position(), v[1].position(), v[2].position()]).collect();
    let mut rng = bounce_tests::Rng(7);
    let mut point = || {
        let t = tris[rng.below(tris.len() as u32) as usize];
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
        (rng.on_triangle(&t), n)
    };
    let (mut cells, mut pairs, mut blocked) = (0u64, 0u64, 0u64);
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
    }
    println!(
        "{voxels} voxels: {:.1} cells visited per march on average over {pairs} random surface pairs ({:.0} % occluded)",
        cells as f64 / pairs as f64,
        100.0 * blocked as f64 / pairs as f64
    );
    Ok(())
}
