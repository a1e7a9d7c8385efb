//! bounce-lab: the measuring tools behind BENCHMARKS.md's experiments, apart from the product and its
//! tests. `end-balls` and `ray-windows` measure how much of the exact shadow rays' walks the end balls
//! and other structures could spare, on the CPU twins of the gather's rays; `static-frames` times what
//! a frame skips when nothing or only the camera changed. Their helpers: the gather's ray ends and pairs
//! drawn like the renderer's ([`gather_ends`], [`gather_pairs`]), a grid DDA ([`grid_cells_along`]) and
//! the empty balls around the ends ([`windows`]).

pub mod windows;

use bounce_tests::Rng;

/// The cells of `spec`'s grid that the segment a → b crosses, in order, each with the parameter interval
/// (t in [0, 1]) it spends there: a DDA (Amanatides–Woo) in f64, for the measuring tools' structures
/// over a grid (`march-length`'s occupied runs, `cell-bvhs`, `ray-windows`). The segment is taken to start inside the
/// grid (its first cell is clamped to it) and ends where it leaves.
pub fn grid_cells_along(
    spec: &bounce_graph::passes::voxelize::VoxelGridSpec,
    a: glam::DVec3,
    b: glam::DVec3,
) -> Vec<(glam::IVec3, f64, f64)> {
    use glam::{DVec3, IVec3};
    let (origin, cell, dims) = (spec.origin.as_dvec3(), spec.cell as f64, spec.dims.as_ivec3());
    let (ga, gb) = ((a - origin) / cell, (b - origin) / cell);
    let d = gb - ga;
    let mut c = ga.floor().as_ivec3().clamp(IVec3::ZERO, dims - 1);
    let (mut next, mut delta) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::INFINITY));
    for k in 0..3 {
        if d[k] != 0.0 {
            next[k] = (if d[k] > 0.0 { c[k] as f64 + 1.0 } else { c[k] as f64 } - ga[k]) / d[k];
            delta[k] = 1.0 / d[k].abs();
        }
    }
    let (mut t, mut out) = (0.0f64, Vec::new());
    loop {
        // The axis whose cell wall comes first.
        let k = if next.x < next.y {
            if next.x < next.z {
                0
            } else {
                2
            }
        } else if next.y < next.z {
            1
        } else {
            2
        };
        out.push((c, t, next[k].min(1.0)));
        if next[k] >= 1.0 {
            return out;
        }
        t = next[k];
        next[k] += delta[k];
        c[k] += if d[k] > 0.0 { 1 } else { -1 };
        if c[k] < 0 || c[k] >= dims[k] {
            return out;
        }
    }
}

/// The gather's shadow-ray ends in a 64² view of `scene`, for the measuring tools (`cell-bvhs --gather`,
/// `end-balls`): each pixel's first hit, and the first light's first hits in up to 1,024 uniform directions
/// (the VPLs, drawn with `Rng(7)`), each with the unit normal of the triangle hit, turned toward the ray
/// that found it. Also the generator, to draw the pairs from it next.
pub type SurfacePoint = (glam::Vec3, glam::Vec3);
pub fn gather_ends(
    scene: &bounce_graph::scene::Scene,
    flat: &bounce_graph::bvh::FlatBvh,
) -> (Vec<SurfacePoint>, Vec<SurfacePoint>, Rng) {
    let view = bounce_graph::bvh::query::BvhView { nodes: &flat.nodes, tris: &flat.tris };
    let hit = |o: glam::Vec3, d: glam::Vec3| {
        view.closest(o, d, 1e-4, f32::MAX).map(|(t, i)| {
            let [a, b, c] = flat.tris[i].positions();
            let n = (b - a).cross(c - a).normalize();
            (o + d * t, if n.dot(d) > 0.0 { -n } else { n })
        })
    };
    let cam = &scene.camera;
    let pixels = (0..64 * 64).filter_map(|k| hit(cam.eye, cam.ray_dir(k % 64, k / 64, 64, 64))).collect();
    let light = glam::Vec3::from_slice(&scene.lights[0].position[..3]);
    let mut rng = Rng(7);
    let mut vpls = Vec::new();
    for _ in 0..100_000 {
        if let Some(v) = hit(light, rng.unit()) {
            vpls.push(v);
        }
        if vpls.len() == 1024 {
            break;
        }
    }
    (pixels, vpls, rng)
}

/// The gather's pairs as the measuring tools draw them after [`gather_ends`]: for each pixel, 8 VPLs
/// drawn from `rng`, kept where each end lies in front of the other's plane (the rays a gather traces),
/// as (pixel, VPL) indices.
pub fn gather_pairs(pixels: &[SurfacePoint], vpls: &[SurfacePoint], rng: &mut Rng) -> Vec<(usize, usize)> {
    let mut pairs = Vec::new();
    for (pi, &(x, nx)) in pixels.iter().enumerate() {
        for _ in 0..8 {
            let vi = rng.below(vpls.len() as u32) as usize;
            let (y, ny) = vpls[vi];
            if nx.dot(y - x) > 0.0 && ny.dot(x - y) > 0.0 {
                pairs.push((pi, vi));
            }
        }
    }
    pairs
}
