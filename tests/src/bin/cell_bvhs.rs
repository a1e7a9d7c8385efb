//! Records per exact shadow ray through a grid of cell BVHs, against the threaded BVH the renderer walks
//! (`docs/experiments/cell-bvhs.patch` is the GPU side of the same structure; BENCHMARKS.md, first
//! section, has the figures).
//!
//! The structure: a G³ grid over the scene (G cells on its longest axis), each occupied cell a threaded
//! BVH of the triangles that touch it (within 1/64 of a cell), its boxes clipped to the cell. A ray steps
//! the grid (Amanatides–Woo) and walks each occupied cell's records, entering a box only where the ray's
//! part inside that cell meets it. Its cost: the grid steps plus the records read. The question it answers:
//! a segment between two surfaces pays, in one BVH, for a descent from the root at each end (`march-length`
//! splits the records); in a grid the descent starts at the cell.
//!
//! Also the same cells under one threaded array (a hierarchy of boxes over the cells, halving the longest
//! axis, instead of the grid steps): whether the stackless walk alone could use the cells.
//!
//! Pairs: with `--gather`, the gather's shadow rays of a 64² view: each pixel's first hit and 8 VPLs drawn
//! from 1,024 first hits of the first light's uniform directions. Otherwise 20,000 pairs of uniform points
//! on random triangles (as `march-length`). Every answer is checked against the threaded BVH's.
//!
//!     cargo run --release -p bounce-tests --bin cell-bvhs -- scene.toml [--gather] G [G …]

use bounce_graph::bvh::cells::{for_each_cell, CELL_MARGIN};
use bounce_graph::bvh::{Bvh, FlatBvh, GpuBvhTri, GpuThreadRec, NO_TRI, THREAD_TRI};
use bounce_graph::passes::voxelize::{self, VoxelGridSpec};
use bounce_graph::scene::Scene;
use bounce_graph::shader_types::Vertex;
use bounce_oracles::cpu_threaded;
use bounce_tests::Rng;
use glam::{DVec3, UVec3, Vec3};
use std::path::Path;

/// Triangles within this share of a cell of it are listed in it (`--visibility hybrid`'s rule).
const MARGIN: f64 = CELL_MARGIN;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else { anyhow::bail!("usage: cell-bvhs scene.toml [--gather] G [G …]") };
    let gather = args.iter().any(|a| a == "--gather");
    let sizes: Vec<u32> = args[1..].iter().filter(|a| *a != "--gather").map(|a| a.parse()).collect::<Result<_, _>>()?;
    let scene = Scene::load(Path::new(path))?;
    let flat = FlatBvh::new(&Bvh::new(&scene), &scene.vertices);
    let threaded = flat.threaded();
    let pairs = if gather { gather_pairs(&scene, &flat) } else { surface_pairs(&scene) };
    let n = pairs.len() as f64;
    let (mut records, mut visible_records, mut visible) = (0u64, 0u64, 0u64);
    let mut answers = Vec::with_capacity(pairs.len());
    for &(a, b) in &pairs {
        let w = cpu_threaded::walk(&threaded, a, b, 1e-4, 1.0 - 1e-4);
        records += w.records as u64;
        if !w.occluded {
            visible += 1;
            visible_records += w.records as u64;
        }
        answers.push(w.occluded);
    }
    let v = visible.max(1) as f64;
    println!(
        "threaded BVH ({} records, {} levels): {:.1} records per ray, {:.1} per visible ray ({visible} of {} visible)",
        threaded.len(),
        flat.height,
        records as f64 / n,
        visible_records as f64 / v,
        pairs.len()
    );
    for g in sizes {
        let grid = CellBvhs::build(&scene, &flat, g);
        let (mut steps, mut recs, mut vis_steps, mut vis_recs) = (0u64, 0u64, 0u64, 0u64);
        for (&(a, b), &occluded) in pairs.iter().zip(&answers) {
            let (s, r, occ) = grid.walk(a, b);
            anyhow::ensure!(occ == occluded, "the grid's answer differs from the BVH's");
            (steps, recs) = (steps + s, recs + r);
            if !occ {
                (vis_steps, vis_recs) = (vis_steps + s, vis_recs + r);
            }
        }
        let top = grid.one_array();
        let (mut top_records, mut top_visible) = (0u64, 0u64);
        for (&(a, b), &occluded) in pairs.iter().zip(&answers) {
            let w = cpu_threaded::walk(&top, a, b, 1e-4, 1.0 - 1e-4);
            anyhow::ensure!(w.occluded == occluded, "the one array's answer differs from the BVH's");
            top_records += w.records as u64;
            top_visible += if w.occluded { 0 } else { w.records as u64 };
        }
        println!(
            "G = {g}, grid {} ({} occupied cells, {} records): per ray {:.1} steps + {:.1} records = {:.1}; per visible ray {:.1} + {:.1} = {:.1}",
            grid.spec.dims,
            grid.cells.iter().filter(|c| !c.is_empty()).count(),
            grid.cells.iter().map(Vec::len).sum::<usize>(),
            steps as f64 / n,
            recs as f64 / n,
            (steps + recs) as f64 / n,
            vis_steps as f64 / v,
            vis_recs as f64 / v,
            (vis_steps + vis_recs) as f64 / v
        );
        println!(
            "  the same cells as one threaded array ({} records): {:.1} records per ray, {:.1} per visible ray",
            top.len(),
            top_records as f64 / n,
            top_visible as f64 / v
        );
    }
    Ok(())
}

/// 20,000 pairs of uniform points on random triangles.
fn surface_pairs(scene: &Scene) -> Vec<(DVec3, DVec3)> {
    let tris: Vec<[Vec3; 3]> =
        scene.vertices.chunks(3).map(|v| [v[0].position(), v[1].position(), v[2].position()]).collect();
    let mut rng = Rng(7);
    let mut point = || {
        let t = tris[rng.below(tris.len() as u32) as usize];
        rng.on_triangle(&t).as_dvec3()
    };
    (0..20_000).map(|_| (point(), point())).collect()
}

/// The gather's shadow rays of a 64² view: each pixel's first hit, to 8 of 1,024 VPLs (the first light's
/// first hits in uniform directions).
fn gather_pairs(scene: &Scene, flat: &FlatBvh) -> Vec<(DVec3, DVec3)> {
    let (pixels, vpls, mut rng) = bounce_tests::gather_ends(scene, flat);
    let pixels: Vec<Vec3> = pixels.iter().map(|p| p.0).collect();
    let vpls: Vec<Vec3> = vpls.iter().map(|v| v.0).collect();
    let mut pairs = Vec::with_capacity(pixels.len() * 8);
    for x in &pixels {
        for _ in 0..8.min(vpls.len()) {
            pairs.push((x.as_dvec3(), vpls[rng.below(vpls.len() as u32) as usize].as_dvec3()));
        }
    }
    pairs
}

/// The grid and its cells' threaded records (record links local to the cell).
struct CellBvhs {
    spec: VoxelGridSpec,
    cells: Vec<Vec<GpuThreadRec>>,
}

impl CellBvhs {
    fn build(scene: &Scene, flat: &FlatBvh, g: u32) -> CellBvhs {
        let spec = voxelize::fit(scene.bounds_min, scene.bounds_max, g);
        let (dims, origin, cell) = (spec.dims, spec.origin.as_dvec3(), spec.cell as f64);
        let mut lists: Vec<Vec<&GpuBvhTri>> = vec![Vec::new(); (dims.x * dims.y * dims.z) as usize];
        for t in flat.tris.iter().filter(|t| t.tri != NO_TRI) {
            let v = t.positions().map(|p| (p.as_dvec3() - origin) / cell);
            for_each_cell(&v, dims, |c| lists[(c.x + dims.x * (c.y + dims.y * c.z)) as usize].push(t));
        }
        let cells = lists
            .iter()
            .enumerate()
            .map(|(ci, list)| {
                if list.is_empty() {
                    return Vec::new();
                }
                let verts: Vec<Vertex> = list
                    .iter()
                    .flat_map(|t| t.positions())
                    .map(|p| Vertex { position_u: [p.x, p.y, p.z, 0.0], normal_v: [0.0; 4] })
                    .collect();
                let ci = ci as u32;
                let c = UVec3::new(ci % dims.x, (ci / dims.x) % dims.y, ci / (dims.x * dims.y)).as_dvec3();
                let (lo, hi) =
                    ((origin + (c - MARGIN) * cell).as_vec3(), (origin + (c + 1.0 + MARGIN) * cell).as_vec3());
                let mut recs = FlatBvh::new(&Bvh::from_vertices(&verts), &verts).threaded();
                for r in recs.iter_mut().filter(|r| r.link != THREAD_TRI) {
                    r.a = Vec3::from(r.a).max(lo).to_array();
                    r.b = Vec3::from(r.b).min(hi).to_array();
                }
                recs
            })
            .collect();
        CellBvhs { spec, cells }
    }

    /// Grid steps, records read and the answer for the segment a → b.
    fn walk(&self, a: DVec3, b: DVec3) -> (u64, u64, bool) {
        let (mut steps, mut records) = (0u64, 0u64);
        let dims = self.spec.dims;
        for (c, t0, t1) in bounce_tests::grid_cells_along(&self.spec, a, b) {
            steps += 1;
            let cell = &self.cells[(c.x as u32 + dims.x * (c.y as u32 + dims.y * c.z as u32)) as usize];
            if cell.is_empty() {
                continue;
            }
            let w = cpu_threaded::walk_clipped(cell, a, b, 1e-4, 1.0 - 1e-4, &[(t0 - 1e-6, t1 + 1e-6)]);
            records += w.records as u64;
            if w.occluded {
                return (steps, records, true);
            }
        }
        (steps, records, false)
    }

    /// The cells' records as one threaded array under a hierarchy of boxes over the cells.
    fn one_array(&self) -> Vec<GpuThreadRec> {
        let mut out = Vec::new();
        self.emit(&mut out, UVec3::ZERO, self.spec.dims);
        out
    }

    /// Emits the cell range [lo, hi): a box record over its cells' records and its two halves (halving the
    /// longest axis), or the one cell's records. Returns whether it emitted anything.
    fn emit(&self, out: &mut Vec<GpuThreadRec>, lo: UVec3, hi: UVec3) -> bool {
        let size = hi - lo;
        if size == UVec3::ONE {
            let cell = &self.cells[(lo.x + self.spec.dims.x * (lo.y + self.spec.dims.y * lo.z)) as usize];
            let o = out.len() as u32;
            out.extend(
                cell.iter().map(|&r| if r.link == THREAD_TRI { r } else { GpuThreadRec { link: r.link + o, ..r } }),
            );
            return !cell.is_empty();
        }
        let at = out.len();
        out.push(GpuThreadRec::default());
        let k = (0..3).fold(0, |m, k| if size[k] > size[m] { k } else { m });
        let (mut left_hi, mut right_lo) = (hi, lo);
        left_hi[k] = lo[k] + size[k] / 2;
        right_lo[k] = left_hi[k];
        let (l, r) = (self.emit(out, lo, left_hi), self.emit(out, right_lo, hi));
        if !l && !r {
            out.truncate(at);
            return false;
        }
        let (mut blo, mut bhi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for r in out[at + 1..].iter().filter(|r| r.link != THREAD_TRI) {
            blo = blo.min(Vec3::from(r.a));
            bhi = bhi.max(Vec3::from(r.b));
        }
        out[at] = GpuThreadRec { a: blo.to_array(), link: out.len() as u32, b: bhi.to_array(), ..Default::default() };
        true
    }
}
