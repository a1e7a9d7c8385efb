//! The GPU BVH (`crates/scene/src/bvh/` built, `crates/graph/src/gpu_bvh.rs` uploaded, `glsl/shared/bvh.glsl` walked) against the exact CPU reference
//! (`bounce_oracles::cpu_ref`: f64 Möller–Trumbore through the same SAH tree), through the test kernel
//! `glsl/test/bvh_trace.comp` (one invocation per query: a closest-hit ray and an occlusion segment).
//!
//! Compared, on the Cornell box, a closed 50k-triangle bumpy sphere with a soup inside (also flattened
//! with a height limit that forces median rebuilds) and a 301k-triangle terrain:
//! * closest hits: the same triangle, the same t and barycentrics (to the tolerances below);
//! * occlusion of segments between surface points (and towards free points): the same flag.
//!
//! **The grazing rule.** f32 and f64 may disagree where the answer turns on rounding: where a ray passes
//! within [`EDGE`] = 1e-4 (in barycentric coordinates, i.e. relative to the triangle's size) of a
//! triangle's edge; where it meets a triangle's plane at a grazing angle, |cos| < [`GRAZE`] = 1e-3 (two
//! surface points on one face give a segment that lies in its plane up to rounding, so where it crosses
//! the plane is noise); where two different triangles are hit at the same distance to [`TIE`] = 1e-5
//! (coplanar or touching surfaces); or where an occluder lies within half the end epsilon of the
//! `SHADOW_EPS` window of a segment's ends. A mismatch is excused only if the triangle it turns on (the
//! CPU's hit, the GPU's hit re-evaluated in f64, or every CPU hit along a segment the GPU calls free) is
//! such a case; excused mismatches are counted and bounded, anything else fails. Matching hits must agree
//! on t to 1e-4 · t + 1e-6 · R (1 + s/h) / (|cos| |d|) and on the barycentrics to
//! 1e-4 + 1e-6 · R / (|cos| h), with R the distance from the origin to the farthest vertex, s the longest
//! edge, h the smallest height and cos the angle to the normal ([`rounding_scales`]): f32 rounds the
//! vertices relative to the origin, so for a ray starting next to a triangle, or a thin triangle met
//! obliquely, the error is far larger than 1e-4 · t (grazing hits are exempt).
//!
//! Also: rays from inside a closed sphere aimed exactly at its vertices and shared edges all hit (the
//! triangle test is watertight), the loop iterations of every trace stay below the bound and within
//! `max_iterations_per_ray()`, and a trace that cannot finish within the bound gives the documented
//! answer (no hit / not occluded, `bvh_exhausted`) without disturbing its neighbours. The threaded
//! closest-hit walk (`bvh_closest_walk`, the reference's) gives `bvh_closest`'s answer bit for bit on
//! every query, and the shadow-ray queue (`glsl/shared/shadow_queue.glsl`, through the test kernel
//! `glsl/test/shadow_queue.comp`) gives `bvh_occluded_lifted`'s on every ray.

use bounce_device::sync::Access;
use bounce_device::{vk, Binding, Buffer, BufferDesc, ComputePipeline, DescriptorWrites, Gpu};
use bounce_graph::bvh::{FlatBvh, MAX_STEPS, NO_TRI, SHADOW_EPS};
use bounce_graph::gpu_bvh::GpuBvh;
use bounce_graph::scene::Scene;
use bounce_graph::shader_types::Vertex;
use bounce_oracles::cpu_ref::{self, Bvh, Trace};
use bounce_tests::Rng;
use bounce_tests::TestGpu;
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};
use std::time::Instant;

/// Test-only bindings of `glsl/test/bvh_trace.comp`.
const T_IN: u32 = bounce_graph::bindings::B_TEST_IN;
const T_OUT: u32 = bounce_graph::bindings::B_TEST_OUT;

/// Barycentric distance from an edge below which f32 and f64 may disagree (the grazing rule).
const EDGE: f64 = 1e-4;
/// |cos| of the angle between a ray and a triangle's normal below which the ray grazes the triangle.
const GRAZE: f64 = 1e-3;
/// Relative distance at which two different triangles count as hit at the same point.
const TIE: f64 = 1e-5;
/// Relative t tolerance of a matching hit.
const T_TOL: f64 = 1e-4;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct Query {
    /// xyz origin, w tmax.
    o: [f32; 4],
    d: [f32; 4],
    a: [f32; 4],
    b: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct Res {
    t: f32,
    tri: u32,
    bary: [f32; 2],
    occluded: u32,
    occ_tri: u32,
    occ_t: f32,
    steps: u32,
    occ_steps: u32,
    exhausted: u32,
    walk_t: f32,
    walk_tri: u32,
    walk_bary: [f32; 2],
}
const _: () = assert!(std::mem::size_of::<Res>() == 56);

impl Query {
    fn ray(o: Vec3, d: Vec3, tmax: f32) -> Query {
        Query { o: o.extend(tmax).to_array(), d: d.extend(0.0).to_array(), ..Default::default() }
    }
    fn with_segment(mut self, a: Vec3, b: Vec3) -> Query {
        self.a = a.extend(0.0).to_array();
        self.b = b.extend(0.0).to_array();
        self
    }
    fn origin(&self) -> DVec3 {
        Vec3::from_slice(&self.o[..3]).as_dvec3()
    }
    fn dir(&self) -> DVec3 {
        Vec3::from_slice(&self.d[..3]).as_dvec3()
    }
    fn seg(&self) -> (DVec3, DVec3) {
        (Vec3::from_slice(&self.a[..3]).as_dvec3(), Vec3::from_slice(&self.b[..3]).as_dvec3())
    }
}

/// Triangles with area-weighted sampling of surface points.
struct Mesh {
    tris: Vec<[Vec3; 3]>,
    cdf: Vec<f64>,
    lo: Vec3,
    hi: Vec3,
}

impl Mesh {
    fn new(tris: Vec<[Vec3; 3]>) -> Mesh {
        let mut cdf = Vec::with_capacity(tris.len());
        let mut sum = 0.0;
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for [a, b, c] in &tris {
            sum += (*b - *a).as_dvec3().cross((*c - *a).as_dvec3()).length();
            cdf.push(sum);
            lo = lo.min(a.min(b.min(*c)));
            hi = hi.max(a.max(b.max(*c)));
        }
        Mesh { tris, cdf, lo, hi }
    }
    fn of_scene(scene: &Scene) -> Mesh {
        Mesh::new(scene.vertices.chunks_exact(3).map(|v| [v[0].position(), v[1].position(), v[2].position()]).collect())
    }
    fn vertices(&self) -> Vec<Vertex> {
        self.tris
            .iter()
            .flat_map(|t| t.map(|p| Vertex { position_u: [p.x, p.y, p.z, 0.0], normal_v: [0.0, 1.0, 0.0, 0.0] }))
            .collect()
    }
    /// A random surface point (uniform by area), rounded to f32 as a shader would have it.
    fn surface_point(&self, rng: &mut Rng) -> Vec3 {
        let x = rng.f32() as f64 * self.cdf.last().unwrap();
        let k = self.cdf.partition_point(|&c| c <= x).min(self.tris.len() - 1);
        let [a, b, c] = self.tris[k];
        let (mut u, mut v) = (rng.f32(), rng.f32());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        a + (b - a) * u + (c - a) * v
    }
    fn diagonal(&self) -> f32 {
        (self.hi - self.lo).length()
    }
}

/// Runs the kernel; returns the results and the wall time of the dispatch.
fn gpu_trace(gpu: &Gpu, bvh: &GpuBvh, queries: &[Query]) -> (Vec<Res>, f64) {
    let mut bindings = GpuBvh::bindings().to_vec();
    bindings.extend([Binding::storage_buffer(T_IN), Binding::storage_buffer(T_OUT)]);
    let p = ComputePipeline::new(
        gpu,
        "bvh_trace",
        &bounce_graph::spirv(bounce_graph::shaders::BVH_TRACE_COMP),
        &bindings,
        0,
        &[],
    )
    .unwrap();
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let inb = Buffer::with_data(gpu, "queries", storage, bytemuck::cast_slice(queries)).unwrap();
    let outb =
        Buffer::new(gpu, &BufferDesc::storage("results", (std::mem::size_of::<Res>() * queries.len()) as u64)).unwrap();
    let start = Instant::now();
    gpu.submit(|cmd| {
        let w = bvh.writes(DescriptorWrites::new()).storage_buffer(T_IN, &inb).storage_buffer(T_OUT, &outb);
        p.dispatch(cmd, &w, &[], [queries.len() as u32, 1, 1], [bounce_graph::bindings::WG_1D, 1, 1]);
    })
    .unwrap();
    let secs = start.elapsed().as_secs_f64();
    (bytemuck::pod_collect_to_vec(&outb.read_back(Access::ComputeWrite).unwrap()), secs)
}

/// The ray's line against triangle `tri` in f64: (t, barycentrics) whether or not it is inside.
fn line_tri(tri: &[Vec3; 3], o: DVec3, d: DVec3) -> Option<(f64, [f64; 3])> {
    let [a, b, c] = tri.map(|p| p.as_dvec3());
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let s = o - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    Some((e2.dot(q) / det, [1.0 - u - v, u, v]))
}

/// Whether direction `d` meets the triangle's plane at a grazing angle.
fn grazing(tri: &[Vec3; 3], d: DVec3) -> bool {
    let [a, b, c] = tri.map(|p| p.as_dvec3());
    let n = (b - a).cross(c - a);
    n.dot(d).abs() < GRAZE * n.length() * d.length()
}

/// The scales of f32 rounding in a hit of `tri` by o + t·d, for t (length) and for the barycentrics. f32
/// rounds the vertices relative to the origin by ~6e-8 of R, the distance to the farthest vertex; the plane
/// stretches a lateral error by 1/|cos| (cos: between `d` and the normal); over the triangle's smallest
/// height h that is a barycentric error, and the edge functions' errors move t by up to the depth spread
/// of the triangle (~ its longest edge s) times them, hence the s / h of thin triangles.
fn rounding_scales(tri: &[Vec3; 3], o: DVec3, d: DVec3) -> (f64, f64) {
    let [a, b, c] = tri.map(|p| p.as_dvec3());
    let n = (b - a).cross(c - a).normalize();
    let cos = n.dot(d.normalize()).abs();
    let reach = [a, b, c].iter().map(|p| (*p - o).length()).fold(0.0, f64::max);
    let longest = (b - a).length().max((c - b).length()).max((a - c).length());
    let h = min_height(tri);
    (reach * (1.0 + longest / h) / cos, reach / (cos * h))
}

/// The smallest height of the triangle (its size in the barycentric sense).
fn min_height(tri: &[Vec3; 3]) -> f64 {
    let [a, b, c] = tri.map(|p| p.as_dvec3());
    let twice_area = (b - a).cross(c - a).length();
    twice_area / (b - a).length().max((c - b).length()).max((a - c).length())
}

fn min3(b: [f64; 3]) -> f64 {
    b[0].min(b[1]).min(b[2])
}

/// Within the grazing band of an edge, on either side.
fn near_edge(b: [f64; 3]) -> bool {
    min3(b).abs() < EDGE
}

/// Within half the end epsilon of either end of the occlusion window.
fn near_end(t: f64) -> bool {
    let eps = cpu_ref::SHADOW_EPS;
    (t - eps).abs() < 0.5 * eps || (t - (1.0 - eps)).abs() < 0.5 * eps
}

/// Why a hit of triangle `tri` by o + t·d may go either way between f32 and f64, if it may: a grazing
/// angle, a grazing edge, or (for a segment, `window`) an end of the occlusion window.
fn ambiguous(tri: &[Vec3; 3], o: DVec3, d: DVec3, window: bool) -> Option<&'static str> {
    if grazing(tri, d) {
        return Some("angle");
    }
    let (t, b) = line_tri(tri, o, d)?;
    if near_edge(b) {
        Some("edge")
    } else if window && near_end(t) {
        Some("end")
    } else {
        None
    }
}

#[derive(Debug, Default)]
struct Stats {
    hits: usize,
    segments: usize,
    occluded: usize,
    /// Mismatches the grazing rule excused, by query kind and reason, and the first few of them.
    excused: std::collections::BTreeMap<String, usize>,
    examples: Vec<String>,
    max_steps: u32,
    mean_steps: f64,
    /// Largest |t_gpu − t_cpu| of a matching, non-grazing hit, as a fraction of its tolerance.
    max_t_err_of_tol: f64,
    /// The same for the barycentrics.
    max_bary_err_of_tol: f64,
}

impl Stats {
    fn excuse(&mut self, kind: &str, reason: &str) {
        *self.excused.entry(format!("{kind}/{reason}")).or_default() += 1;
    }
    fn excused_total(&self) -> usize {
        self.excused.values().sum()
    }
}

/// Compares every query with the CPU reference; panics on any mismatch the grazing rule does not excuse.
fn compare(what: &str, mesh: &Mesh, cpu: &Bvh, queries: &[Query], res: &[Res], bound: u32) -> Stats {
    let mut s = Stats { segments: queries.len(), ..Default::default() };
    let mut bad = vec![];
    let mut steps_sum = 0u64;
    for (i, (q, r)) in queries.iter().zip(res).enumerate() {
        assert_eq!(
            r.exhausted, 0,
            "{what}: query {i} exhausted the iteration bound ({} / {} steps)",
            r.steps, r.occ_steps
        );
        assert!(
            r.steps < MAX_STEPS && r.occ_steps < MAX_STEPS && r.steps <= bound && r.occ_steps <= bound,
            "{what}: query {i}: {} / {} steps, bound {bound}",
            r.steps,
            r.occ_steps
        );
        s.max_steps = s.max_steps.max(r.steps).max(r.occ_steps);
        steps_sum += (r.steps + r.occ_steps) as u64;
        // The threaded closest-hit walk gives the stack traversal's answer, bit for bit.
        let walk = (r.walk_t.to_bits(), r.walk_tri, r.walk_bary.map(f32::to_bits));
        assert_eq!(
            walk,
            (r.t.to_bits(), r.tri, r.bary.map(f32::to_bits)),
            "{what}: query {i}: bvh_closest_walk differs from bvh_closest: {r:?}"
        );

        // Closest hit.
        let (o, d) = (q.origin(), q.dir());
        let want = cpu.intersect_range(o, d, 0.0, q.o[3] as f64);
        let got = (r.t >= 0.0).then_some(r);
        s.hits += want.is_some() as usize;
        match (want, got) {
            (None, None) => {}
            (Some(c), Some(g)) if c.tri == g.tri => {
                let tri = &mesh.tris[c.tri as usize];
                let (scale_t, scale_b) = rounding_scales(tri, o, d);
                let terr = (g.t as f64 - c.t).abs() / (T_TOL * c.t + 1e-6 * scale_t / d.length());
                let berr = (g.bary[0] as f64 - c.barycentrics.y).abs().max((g.bary[1] as f64 - c.barycentrics.z).abs())
                    / (EDGE + 1e-6 * scale_b);
                if grazing(tri, d) {
                    if terr > 1.0 || berr > 1.0 {
                        s.excuse("ray", "angle");
                    }
                } else {
                    s.max_t_err_of_tol = s.max_t_err_of_tol.max(terr);
                    s.max_bary_err_of_tol = s.max_bary_err_of_tol.max(berr);
                    if terr > 1.0 || berr > 1.0 {
                        bad.push(format!(
                            "ray {i}: tri {} t {} vs {} ({terr:.2} of the tolerance), barycentrics {berr:.2} of theirs",
                            c.tri, g.t, c.t
                        ));
                    }
                }
            }
            (c, g) => {
                let cpu_why = c.and_then(|c| ambiguous(&mesh.tris[c.tri as usize], o, d, false));
                let gpu_why = g.and_then(|g| ambiguous(&mesh.tris[g.tri as usize], o, d, false));
                let gpu_eval = g.and_then(|g| line_tri(&mesh.tris[g.tri as usize], o, d));
                let tie = match (c, gpu_eval) {
                    (Some(c), Some((t, b))) => ((t - c.t).abs() <= TIE * c.t && min3(b) > -EDGE).then_some("tie"),
                    _ => None,
                };
                if let Some(why) = cpu_why.or(gpu_why).or(tie) {
                    if s.examples.len() < 4 {
                        s.examples.push(format!(
                            "ray {i} {o} + t {d}: CPU {:?}, GPU tri {} t {}: {why}",
                            c.map(|c| (c.tri, c.t)),
                            r.tri,
                            r.t
                        ));
                    }
                    s.excuse("ray", why);
                } else {
                    bad.push(format!(
                        "ray {i} ({o} + t {d}): CPU {:?}, GPU tri {} t {} (f64 re-evaluation {gpu_eval:?})",
                        c.map(|c| (c.tri, c.t, c.barycentrics)),
                        r.tri,
                        r.t
                    ));
                }
            }
        }

        // Occlusion.
        let (a, b) = q.seg();
        let want = cpu.occluded(a, b);
        let got = r.occluded != 0;
        assert_eq!(got, r.occ_tri != NO_TRI, "{what}: segment {i}: bvh_occluded and bvh_trace disagree");
        s.occluded += want as usize;
        if want == got {
            continue;
        }
        let why = if got {
            // The GPU's occluder, in f64, must be ambiguous.
            ambiguous(&mesh.tris[r.occ_tri as usize], a, b - a, true)
        } else {
            // Every CPU hit in (and near) the window must be ambiguous.
            let eps = cpu_ref::SHADOW_EPS;
            let mut t_lo = 0.5 * eps;
            let mut why = Some("end");
            while let Some(h) = cpu.intersect_range(a, b - a, t_lo, 1.0 - 0.5 * eps) {
                why = ambiguous(&mesh.tris[h.tri as usize], a, b - a, true);
                if why.is_none() {
                    break;
                }
                t_lo = h.t;
            }
            why
        };
        match why {
            Some(why) => {
                if s.examples.len() < 4 {
                    let tri = (r.occ_tri != NO_TRI).then(|| line_tri(&mesh.tris[r.occ_tri as usize], a, b - a));
                    s.examples.push(format!(
                        "segment {i} {a} → {b}: CPU {want}, GPU {got} (tri {}, t {}, f64 (t, bary) {tri:?}): {why}",
                        r.occ_tri, r.occ_t
                    ));
                }
                s.excuse("segment", why)
            }
            None => bad.push(format!(
                "segment {i} ({a} → {b}): CPU occluded {want}, GPU {got} (GPU tri {} at t {})",
                r.occ_tri, r.occ_t
            )),
        }
    }
    s.mean_steps = steps_sum as f64 / (2 * queries.len()) as f64;
    eprintln!(
        "{what}: {} queries, {} hits, {} occluded, excused {:?}, steps max {} mean {:.1}, t error ≤ {:.3} of the \
         tolerance, barycentric error ≤ {:.3} of theirs",
        queries.len(),
        s.hits,
        s.occluded,
        s.excused,
        s.max_steps,
        s.mean_steps,
        s.max_t_err_of_tol,
        s.max_bary_err_of_tol
    );
    for e in &s.examples {
        eprintln!("  excused: {e}");
    }
    assert!(bad.is_empty(), "{what}: {} mismatches, first: {}", bad.len(), bad[..bad.len().min(6)].join("\n"));
    s
}

/// `n` queries: rays from random points of the padded bounds in random directions (a quarter with a finite
/// tmax), and segments between random surface points (a quarter from a surface point to a free point).
fn random_queries(mesh: &Mesh, n: usize, rng: &mut Rng) -> Vec<Query> {
    let pad = (mesh.hi - mesh.lo) * 0.2;
    let (lo, hi) = (mesh.lo - pad, mesh.hi + pad);
    (0..n)
        .map(|k| {
            let o = rng.vec(lo, hi);
            let d = rng.unit() * (0.5 + rng.f32());
            let tmax = if k % 4 == 0 { rng.f32() * mesh.diagonal() } else { f32::INFINITY };
            let a = mesh.surface_point(rng);
            let b = if k % 4 == 1 { rng.vec(lo, hi) } else { mesh.surface_point(rng) };
            Query::ray(o, d, tmax).with_segment(a, b)
        })
        .collect()
}

/// `bumpy_sphere(rings, segments, 0.12)` with `soup` small random triangles inside, so that segments
/// between surface points are often blocked.
fn sphere_with_soup(rings: usize, segments: usize, soup: usize, rng: &mut Rng) -> Vec<[Vec3; 3]> {
    let mut tris = bumpy_sphere(rings, segments, 0.12);
    for _ in 0..soup {
        let c = rng.unit() * 0.6 * rng.f32();
        tris.push([0, 1, 2].map(|_| c + rng.unit() * 0.08));
    }
    tris
}

/// A closed, star-shaped sphere with bumps of relative height `bump` (0: a convex polyhedron, every vertex on
/// the unit sphere): `rings` × `segments` UV grid with one vertex per pole, every vertex shared exactly by its
/// triangles (2·segments·(rings − 1) triangles).
fn bumpy_sphere(rings: usize, segments: usize, bump: f32) -> Vec<[Vec3; 3]> {
    let point = |j: usize, i: usize| {
        let theta = std::f32::consts::PI * j as f32 / rings as f32;
        let phi = 2.0 * std::f32::consts::PI * (i % segments) as f32 / segments as f32;
        let r = 1.0 + bump * ((5.0 * theta).sin() * (7.0 * phi).cos() + 0.25 * (23.0 * theta + 3.0 * phi).sin());
        Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()) * r
    };
    let (north, south) = (point(0, 0), point(rings, 0));
    let mut tris = Vec::with_capacity(2 * segments * (rings - 1));
    for i in 0..segments {
        tris.push([north, point(1, i + 1), point(1, i)]);
        for j in 1..rings - 1 {
            let (a, b, c, d) = (point(j, i), point(j, i + 1), point(j + 1, i + 1), point(j + 1, i));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
        tris.push([south, point(rings - 1, i), point(rings - 1, i + 1)]);
    }
    tris
}

/// `m` × `m` quads of a rolling terrain over [0, 10]² (2m² triangles), with a fine ripple.
fn terrain(m: usize) -> Vec<[Vec3; 3]> {
    let h = |x: f32, z: f32| 0.4 * (0.9 * x).sin() * (0.7 * z).cos() + 0.02 * (13.0 * x + 7.0 * z).sin();
    let p = |i: usize, j: usize| {
        let (x, z) = (10.0 * i as f32 / m as f32, 10.0 * j as f32 / m as f32);
        Vec3::new(x, h(x, z), z)
    };
    let mut tris = Vec::with_capacity(2 * m * m);
    for j in 0..m {
        for i in 0..m {
            tris.push([p(i, j), p(i + 1, j + 1), p(i + 1, j)]);
            tris.push([p(i, j), p(i, j + 1), p(i + 1, j + 1)]);
        }
    }
    tris
}

#[test]
fn gpu_bvh_matches_the_cpu_reference_on_the_cornell_box() {
    let gpu = TestGpu::new();
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let mesh = Mesh::of_scene(&scene);
    let cpu = Bvh::new(&scene);
    let bvh = GpuBvh::new(&gpu, &scene).unwrap();
    assert_eq!(bvh.triangle_count as usize, scene.triangle_count());
    let bound = bvh.max_iterations_per_ray();
    assert_eq!(bound, bvh.node_count + bvh.triangle_count + 1, "a small scene's bound is its node and triangle count");
    let mut rng = Rng(0xB0A7_0001);
    let mut queries = random_queries(&mesh, 5000, &mut rng);
    // Camera-like rays from in front of the open side, and segments from surface points to the light.
    let light = Vec3::from_slice(&scene.lights[0].position[..3]);
    let eye = scene.camera.eye;
    for _ in 0..1000 {
        let target = mesh.surface_point(&mut rng);
        queries.push(Query::ray(eye, target - eye, f32::INFINITY).with_segment(target, light));
    }
    let (res, secs) = gpu_trace(&gpu, &bvh, &queries);
    let s = compare("Cornell box", &mesh, &cpu, &queries, &res, bound);
    eprintln!("Cornell box: {} queries in {secs:.3} s, bound {bound}", queries.len());
    // The occlusion walk reads two boxes a step where a met box's successor is packed into it: its steps
    // against the records the CPU twin reads, and against the twin's steps. Those differ a little: the
    // twin tests the exact successor in f64 where the GPU tests the packed box around it in f32, and the
    // twin's f64 triangle test misses some of the grazing hits that stop the GPU's walk (the excused
    // cases above).
    let records = FlatBvh::new(&cpu, &scene.vertices).threaded();
    let (mut gpu_steps, mut twin_steps, mut twin_records) = (0u64, 0u64, 0u64);
    for (q, r) in queries.iter().zip(&res) {
        let (a, b) = q.seg();
        let window = (SHADOW_EPS as f64, 1.0 - SHADOW_EPS as f64);
        let w = bounce_oracles::cpu_threaded::walk_clipped(&records, a, b, window.0, window.1, &[window]);
        (gpu_steps, twin_steps, twin_records) =
            (gpu_steps + r.occ_steps as u64, twin_steps + w.steps as u64, twin_records + w.records as u64);
    }
    eprintln!(
        "Cornell box: occlusion steps {gpu_steps} on the GPU, {twin_steps} in the twin, of {twin_records} records"
    );
    assert!(gpu_steps < twin_records * 19 / 20, "the GPU pairs few boxes: {gpu_steps} steps, {twin_records} records");
    assert!(
        gpu_steps >= twin_steps * 19 / 20 && gpu_steps <= twin_steps * 21 / 20,
        "GPU steps {gpu_steps} against the twin's {twin_steps}"
    );
    assert!(s.hits > 2000 && s.occluded > 500 && s.occluded < s.segments - 500, "{s:?}");
    // Most excused cases are segments between two floor points that pass under a box: they run exactly
    // through the bottom edges of its side faces (barycentric 0, in the floor plane), which the
    // edge-inclusive watertight test counts as occluding and f64 rounding may not (~0.8 %).
    assert!(s.excused_total() <= queries.len() * 3 / 200, "too many grazing cases: {s:?}");
}

#[test]
fn gpu_bvh_matches_the_cpu_reference_on_a_50k_sphere_even_height_limited() {
    let gpu = TestGpu::new();
    let mut rng = Rng(0xB0A7_0002);
    let mesh = Mesh::new(sphere_with_soup(158, 160, 2000, &mut rng));
    let vertices = mesh.vertices();
    let start = Instant::now();
    let cpu = Bvh::from_vertices(&vertices);
    let full = FlatBvh::new(&cpu, &vertices);
    eprintln!("50k sphere: CPU build + flatten {:.2} s, height {}", start.elapsed().as_secs_f64(), full.height);
    assert_eq!(full.rebuilt_subtrees, 0);
    // A limit 4 below the SAH tree's height (still above the 15 levels median splits need).
    let limited = FlatBvh::with_max_height(&cpu, &vertices, full.height - 4);
    assert!(limited.rebuilt_subtrees > 0 && limited.height <= full.height - 4);

    let queries = random_queries(&mesh, 5000, &mut rng);
    for (name, flat) in [("50k sphere", &full), ("50k sphere, height-limited", &limited)] {
        let bvh = GpuBvh::upload(&gpu, flat).unwrap();
        let (res, secs) = gpu_trace(&gpu, &bvh, &queries);
        let s = compare(name, &mesh, &cpu, &queries, &res, bvh.max_iterations_per_ray());
        eprintln!("{name}: {} queries in {secs:.3} s, height {}", queries.len(), bvh.height);
        assert!(s.hits > 1000 && s.occluded > 1000 && s.occluded < s.segments - 500, "{s:?}");
        assert!(s.excused_total() <= queries.len() / 50, "too many grazing cases: {s:?}");
    }
}

#[test]
fn rays_through_shared_edges_and_vertices_never_escape_a_closed_mesh() {
    let gpu = TestGpu::new();
    let mut rng = Rng(0xB0A7_0004);
    // Convex, so that a ray from inside leaves it exactly once: where it was aimed.
    let mesh = Mesh::new(bumpy_sphere(158, 160, 0.0));
    let vertices = mesh.vertices();
    let bvh = GpuBvh::upload(&gpu, &FlatBvh::new(&Bvh::from_vertices(&vertices), &vertices)).unwrap();
    // From random points inside, exactly through a vertex (every vertex is shared by 6 triangles, a pole
    // by 160), through the f32 midpoint of an edge, or through a random f32 point of one: the rounded
    // target is off the exact edge by less than the rounding of a ray–triangle test, so a test that is not
    // watertight lets some of these rays slip between the two triangles of the edge.
    let queries: Vec<Query> = (0..20_000)
        .map(|k| {
            let [a, b, c] = mesh.tris[(rng.next_u64() % mesh.tris.len() as u64) as usize];
            let target = match k % 3 {
                0 => [a, b, c][k % 9 / 3],
                1 => (a + b) * 0.5,
                _ => b + (c - b) * rng.f32(),
            };
            let o = rng.unit() * 0.5 * rng.f32();
            Query::ray(o, target - o, f32::INFINITY)
        })
        .collect();
    let (res, _) = gpu_trace(&gpu, &bvh, &queries);
    // Each must hit at its target, t = 1 up to rounding; a miss is a leak.
    let leaks: Vec<usize> = (0..queries.len()).filter(|&i| (res[i].t - 1.0).abs() > 1e-5).collect();
    assert!(
        leaks.is_empty(),
        "{} of {} rays through vertices / edges leaked through the closed sphere, e.g. {:?}",
        leaks.len(),
        queries.len(),
        leaks.iter().take(4).map(|&i| (queries[i].o, queries[i].d, res[i].t)).collect::<Vec<_>>()
    );
}

#[test]
fn the_iteration_bound_is_not_hit_on_a_300k_terrain() {
    let gpu = TestGpu::new();
    let mut rng = Rng(0xB0A7_0003);
    let mesh = Mesh::new(terrain(388));
    assert!(mesh.tris.len() > 300_000);
    let vertices = mesh.vertices();
    let start = Instant::now();
    let cpu = Bvh::from_vertices(&vertices);
    let flat = FlatBvh::new(&cpu, &vertices);
    let build = start.elapsed().as_secs_f64();
    let bvh = GpuBvh::upload(&gpu, &flat).unwrap();
    assert_eq!(bvh.max_iterations_per_ray(), MAX_STEPS);
    // The slow cases: segments between surface points skim the terrain (long, close to many boxes), and
    // so do horizontal rays from just above it; the other rays come from above, many at grazing angles.
    let queries: Vec<Query> = (0..4000)
        .map(|k| {
            let (o, d) = if k % 2 == 0 {
                let mut d = rng.unit();
                d.y = 0.0;
                (mesh.surface_point(&mut rng) + Vec3::Y * 0.01, d)
            } else {
                let mut d = rng.unit();
                d.y = -d.y.abs() * 0.3;
                (rng.vec(Vec3::new(-1.0, 0.5, -1.0), Vec3::new(11.0, 3.0, 11.0)), d)
            };
            Query::ray(o, d, f32::INFINITY).with_segment(mesh.surface_point(&mut rng), mesh.surface_point(&mut rng))
        })
        .collect();
    let (res, secs) = gpu_trace(&gpu, &bvh, &queries);
    let s = compare("301k terrain", &mesh, &cpu, &queries, &res, bvh.max_iterations_per_ray());
    eprintln!(
        "301k terrain: {} nodes, height {}, build + flatten {build:.2} s, {} queries in {secs:.3} s",
        bvh.node_count,
        bvh.height,
        queries.len()
    );
    assert!(s.max_steps < MAX_STEPS / 4, "worst trace {} steps: within 4x of the bound {MAX_STEPS}", s.max_steps);
    assert!(s.hits > 500 && s.occluded > 500, "{s:?}");
    assert!(s.excused_total() <= queries.len() / 100, "too many grazing cases: {s:?}");
}

#[test]
fn a_trace_past_the_bound_answers_no_hit_and_leaves_its_neighbours_alone() {
    let gpu = TestGpu::new();
    // 40000 copies of one triangle: a ray through it must test every copy (equal t, lowest index wins), a
    // segment through its box but beside it enters every leaf and hits nothing.
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let mesh = Mesh::new(vec![tri; 40_000]);
    let vertices = mesh.vertices();
    let cpu = Bvh::from_vertices(&vertices);
    let bvh = GpuBvh::upload(&gpu, &FlatBvh::new(&cpu, &vertices)).unwrap();
    assert_eq!(bvh.max_iterations_per_ray(), MAX_STEPS);
    let z = Vec3::Z;
    let through = Vec3::new(0.2, 0.2, 0.0);
    let beside = Vec3::new(0.9, 0.9, 0.0); // in the box, outside the triangle
    let far = Vec3::new(5.0, 5.0, 0.0); // outside the box
    let queries = [
        Query::ray(through + z, -z, f32::INFINITY).with_segment(beside + z, beside - z),
        Query::ray(far + z, -z, f32::INFINITY).with_segment(through + z, through - z),
        Query::ray(beside + z, -z, f32::INFINITY).with_segment(far + z, far - z),
    ];
    let (res, _) = gpu_trace(&gpu, &bvh, &queries);
    // Query 0: every trace gives up at the bound with the documented answers.
    assert_eq!(cpu.intersect(queries[0].origin(), queries[0].dir()).map(|h| h.tri), Some(0));
    assert_eq!((res[0].t, res[0].tri, res[0].steps), (-1.0, NO_TRI, MAX_STEPS), "{:?}", res[0]);
    assert_eq!((res[0].occluded, res[0].occ_steps, res[0].exhausted), (0, MAX_STEPS, 7), "{:?}", res[0]);
    // Query 1: a miss outside the box is immediate; the segment is occluded at its first triangle test.
    assert_eq!((res[1].t, res[1].exhausted, res[1].occluded), (-1.0, 0, 1), "{:?}", res[1]);
    assert!(res[1].steps <= 1 && res[1].occ_steps < 64, "{:?}", res[1]);
    assert!((res[1].occ_t - 0.5).abs() < 1e-6, "{:?}", res[1]);
    // Query 2: a ray beside the triangle exhausts the bound too (it must test every copy); the segment
    // outside the box does not.
    assert_eq!((res[2].t, res[2].steps, res[2].exhausted), (-1.0, MAX_STEPS, 5), "{:?}", res[2]);
    assert_eq!((res[2].occluded, res[2].occ_steps <= 1), (0, true), "{:?}", res[2]);
    // The threaded closest-hit walk gives up on queries 0 and 2 as well (bit 2), with the same answers.
    for r in &res {
        assert_eq!((r.walk_t, r.walk_tri), (r.t, r.tri), "{r:?}");
    }
}

/// Rays per queue of `glsl/test/shadow_queue.comp` (`SHADOW_QUEUE`).
const QUEUE: usize = bounce_graph::bindings::SHADOW_QUEUE as usize;

/// One queue: rays from `o` to each of the first `n[0]` ends.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct QueueIn {
    o: [f32; 4],
    n: [u32; 4],
    ends: [[f32; 4]; QUEUE],
}

/// Bit j: ray j not occluded, from the queue and from one `bvh_occluded_lifted` per ray.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct QueueOut {
    queued: u32,
    single: u32,
    pad: [u32; 2],
}

/// The shadow-ray queue (`glsl/shared/shadow_queue.glsl`, the gather's and ris's shade) answers every ray
/// as `bvh_occluded_lifted` does, bit for bit, whatever its neighbours in a SIMD vector hold: queues of
/// every length from 0 to SHADOW_QUEUE side by side, rays blocked at once, rays that walk the whole
/// tree, and rays the walk refuses (a zero-length ray, a NaN end: "no hit"). The one-ray walk itself is
/// checked against the CPU reference by the tests above.
#[test]
fn the_shadow_queue_answers_every_ray_as_one_occlusion_test_does() {
    check_shadow_queue(&TestGpu::new(), "shadow_queue", bounce_graph::shaders::SHADOW_QUEUE_COMP);
}

fn check_shadow_queue(gpu: &TestGpu, name: &'static str, kernel: &[u8]) {
    let mut rng = Rng(0xB0A7_0009);
    let mesh = Mesh::new(sphere_with_soup(24, 32, 300, &mut rng));
    let vertices = mesh.vertices();
    let flat = FlatBvh::new(&Bvh::from_vertices(&vertices), &vertices);
    let bvh = GpuBvh::upload(gpu, &flat).unwrap();
    // Each invocation traces its queue twice; its loops must stay under llvmpipe's limit (65535).
    let m = bvh.max_iterations_occluded();
    let loops = 2 * QUEUE as u32 * (m + 1) + m + 4;
    assert!(loops < 65535, "the test's mesh is too large for one invocation: {loops} loop iterations");
    let queues: Vec<QueueIn> = (0..1200)
        .map(|k| {
            let o = mesh.surface_point(&mut rng);
            let mut ends = [[0.0; 4]; QUEUE];
            for (j, e) in ends.iter_mut().enumerate() {
                let p = match (k + j) % 23 {
                    0 => o,                             // zero length: refused, "no hit"
                    1 => Vec3::new(f32::NAN, 0.0, 0.0), // not finite: refused, "no hit"
                    2 => rng.unit() * 3.0,              // outside the sphere: crosses it
                    _ => mesh.surface_point(&mut rng),
                };
                *e = p.extend(0.0).to_array();
            }
            QueueIn { o: o.extend(0.0).to_array(), n: [(k % (QUEUE + 1)) as u32, 0, 0, 0], ends }
        })
        .collect();
    let mut bindings = GpuBvh::bindings().to_vec();
    bindings.extend([Binding::storage_buffer(T_IN), Binding::storage_buffer(T_OUT)]);
    let spirv = bounce_graph::spirv(kernel);
    let p = ComputePipeline::new(gpu, name, &spirv, &bindings, 0, &[]).unwrap();
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let inb = Buffer::with_data(gpu, "queues", storage, bytemuck::cast_slice(&queues)).unwrap();
    let size = (std::mem::size_of::<QueueOut>() * queues.len()) as u64;
    let outb = Buffer::new(gpu, &BufferDesc::storage("answers", size)).unwrap();
    gpu.submit(|cmd| {
        let w = bvh.writes(DescriptorWrites::new()).storage_buffer(T_IN, &inb).storage_buffer(T_OUT, &outb);
        p.dispatch(cmd, &w, &[], [queues.len() as u32, 1, 1], [bounce_graph::bindings::WG_1D, 1, 1]);
    })
    .unwrap();
    let out: Vec<QueueOut> = bytemuck::pod_collect_to_vec(&outb.read_back(Access::ComputeWrite).unwrap());
    let (mut visible, mut blocked) = (0, 0);
    for (k, (q, a)) in queues.iter().zip(&out).enumerate() {
        let n = q.n[0] as usize;
        assert_eq!(a.queued, a.single, "queue {k} ({n} rays): the queue's answers differ from one ray at a time");
        let mask = if n == QUEUE { u32::MAX } else { (1u32 << n) - 1 };
        assert_eq!(a.queued & !mask, 0, "queue {k}: an answer past its {n} rays");
        visible += a.queued.count_ones();
        blocked += n as u32 - a.queued.count_ones();
    }
    eprintln!("{name}: {visible} rays visible, {blocked} blocked, bound {loops} loop iterations");
    assert!(visible > 2000 && blocked > 2000, "visible {visible}, blocked {blocked}: the scene should mix both");
}

#[test]
fn an_empty_scene_and_bad_rays_give_no_hit() {
    let gpu = TestGpu::new();
    let empty = Mesh::new(vec![[Vec3::ZERO, Vec3::X, Vec3::X * 2.0]]); // zero area: nothing to hit
    let v = empty.vertices();
    let bvh = GpuBvh::upload(&gpu, &FlatBvh::new(&Bvh::from_vertices(&v), &v)).unwrap();
    assert_eq!((bvh.triangle_count, bvh.max_iterations_per_ray()), (0, 3));
    let (res, _) = gpu_trace(
        &gpu,
        &bvh,
        &[Query::ray(Vec3::new(0.5, 0.0, -1.0), Vec3::Z, 10.0)
            .with_segment(Vec3::new(0.5, 0.0, -1.0), Vec3::new(0.5, 0.0, 1.0))],
    );
    assert_eq!((res[0].t, res[0].occluded, res[0].exhausted), (-1.0, 0, 0), "{:?}", res[0]);
    assert!(res[0].steps <= 3 && res[0].occ_steps <= 3, "{:?}", res[0]);

    // One quad: degenerate queries answer "no hit" at once, good ones hit.
    let quad = Mesh::new(vec![[Vec3::ZERO, Vec3::X, Vec3::Y], [Vec3::X, Vec3::ONE.with_z(0.0), Vec3::Y]]);
    let v = quad.vertices();
    let bvh = GpuBvh::upload(&gpu, &FlatBvh::new(&Bvh::from_vertices(&v), &v)).unwrap();
    let o = Vec3::new(0.3, 0.6, 1.0);
    let queries = [
        Query::ray(o, -Vec3::Z, f32::INFINITY).with_segment(o, o - 2.0 * Vec3::Z), // hit, occluded
        Query::ray(o, Vec3::ZERO, f32::INFINITY).with_segment(o, o),               // zero direction / segment
        Query::ray(o, -Vec3::Z, 0.5).with_segment(o, o - 0.5 * Vec3::Z),           // stops short
        Query::ray(Vec3::splat(f32::NAN), -Vec3::Z, 1.0).with_segment(o, Vec3::splat(f32::INFINITY)),
        Query::ray(o, -Vec3::Z, 1.0).with_segment(o, o - Vec3::Z), // hit exactly at tmax / at the segment's end
    ];
    let (res, _) = gpu_trace(&gpu, &bvh, &queries);
    assert_eq!((res[0].t, res[0].tri, res[0].occluded), (1.0, 0, 1), "{:?}", res[0]);
    assert!((res[0].bary[0] - 0.3).abs() < 1e-6 && (res[0].bary[1] - 0.6).abs() < 1e-6, "{:?}", res[0]);
    for (i, r) in res.iter().enumerate().skip(1).take(3) {
        assert_eq!((r.t, r.tri, r.occluded, r.exhausted), (-1.0, NO_TRI, 0, 0), "query {i}: {r:?}");
    }
    assert_eq!((res[4].t, res[4].occluded), (1.0, 0), "tmax is inclusive, the segment's end is not: {:?}", res[4]);

    // Ties at exactly equal t go to the lowest triangle index, whatever the traversal order (cpu_ref's rule).
    let mut tris = vec![[Vec3::ZERO, Vec3::X, Vec3::Y]; 9];
    tris[0] = [Vec3::splat(5.0), Vec3::splat(5.0) + Vec3::X, Vec3::splat(5.0) + Vec3::Y]; // elsewhere
    let dupes = Mesh::new(tris);
    let v = dupes.vertices();
    let cpu = Bvh::from_vertices(&v);
    let bvh = GpuBvh::upload(&gpu, &FlatBvh::new(&cpu, &v)).unwrap();
    let q = Query::ray(Vec3::new(0.2, 0.3, 1.0), -Vec3::Z, f32::INFINITY);
    let (res, _) = gpu_trace(&gpu, &bvh, &[q]);
    assert_eq!(cpu.intersect(q.origin(), q.dir()).map(|h| h.tri), Some(1));
    assert_eq!((res[0].t, res[0].tri), (1.0, 1), "{:?}", res[0]);
    assert_eq!(SHADOW_EPS, cpu_ref::SHADOW_EPS as f32);
}

/// The host's ray queries (`bvh::query`, for ris's automatic learned visibility) against the f64
/// reference on the default scene: closest hits at the same t, and occlusion between random points
/// (inside the room and on its surfaces) with the same answer, up to a few grazing or end-window cases.
#[test]
fn the_host_ray_queries_agree_with_the_reference() {
    use bounce_graph::bvh::query::BvhView;
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let cpu = Bvh::from_vertices(&scene.vertices);
    let flat = FlatBvh::new(&cpu, &scene.vertices);
    let view = BvhView { nodes: &flat.nodes, tris: &flat.tris };
    let (lo, hi) = (scene.bounds_min, scene.bounds_max);
    let mut rng = Rng(11);
    let (mut hits, mut occluded, mut off) = (0, 0, 0);
    const N: usize = 4000;
    for _ in 0..N {
        let (o, d) = (rng.vec(lo, hi), rng.unit());
        let want = cpu.intersect(o.as_dvec3(), d.as_dvec3()).map(|h| h.t);
        let got = view.closest(o, d, 0.0, f32::INFINITY).map(|(t, _)| t as f64);
        match (want, got) {
            (Some(w), Some(g)) if (w - g).abs() <= 1e-4 * w.max(1.0) => hits += 1,
            (None, None) => {}
            _ => off += 1,
        }
        let b = rng.vec(lo, hi);
        let want = cpu.occluded(o.as_dvec3(), b.as_dvec3());
        occluded += want as usize;
        off += (view.occluded(o, b, SHADOW_EPS) != want) as usize;
    }
    assert!(hits > N / 2 && occluded > N / 10 && occluded < N * 9 / 10, "{hits} hits, {occluded} occluded");
    assert!(off <= N / 500, "{off} of {} answers differ from the reference", 2 * N);
}
