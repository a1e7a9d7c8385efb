//! Mean number of voxel cells the visibility march visits per VPL–point pair (CPU twin of the GPU
//! march, `bounce_graph::cpu_voxel`), over random pairs of surface points of the default scene: the
//! factor between VPL evaluations/s and voxel steps/s in BENCHMARKS.md.
//!
//!     cargo run -p bounce-tests --bin march-length [voxels]

use bounce_graph::cpu_voxel;
use bounce_graph::passes::voxelize;
use bounce_graph::scene::Scene;
use glam::Vec3;

fn main() -> anyhow::Result<()> {
    let voxels: u32 = std::env::args().nth(1).map(|a| a.parse()).transpose()?.unwrap_or(128);
    let scene = Scene::load(&bounce_tests::default_scene())?;
    let spec = voxelize::fit(scene.bounds_min, scene.bounds_max, voxels);
    let grid = cpu_voxel::voxelize_scene(&scene, spec);
    let tris: Vec<[Vec3; 3]> =
        scene.vertices.chunks(3).map(|v| [v[0].position(), v[1].position(), v[2].position()]).collect();
    let mut state = 7u64;
    let mut rnd = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((state >> 40) as f32) / (1u64 << 24) as f32
    };
    let point = |rnd: &mut dyn FnMut() -> f32| {
        let t = tris[(rnd() * tris.len() as f32) as usize % tris.len()];
        let (a, b) = (rnd(), rnd());
        let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
        (t[0] + (t[1] - t[0]) * a + (t[2] - t[0]) * b, n)
    };
    let (mut cells, mut pairs, mut blocked) = (0u64, 0u64, 0u64);
    for _ in 0..20_000 {
        let ((x, nx), (y, ny)) = (point(&mut rnd), point(&mut rnd));
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
