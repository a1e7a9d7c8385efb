//! The voxel grid (`passes/voxelize.rs`, `glsl/voxelize.comp`, `glsl/shared/voxel.glsl`, `cpu_voxel.rs`).
//!
//! Voxelization: the GPU bits equal the CPU twin's bit for bit (Cornell box at 32 and 64 cells, edge-case
//! meshes in an exact and in a fitted grid, a triangle with more candidate cells than one llvmpipe
//! invocation may loop over, a reused grid buffer), and both are checked against facts that do not come from
//! either implementation: closed-form cell sets of axis-aligned quads, segments and points (the grown-box
//! rule is separable per axis for them), the plane–box test of a triangle far larger than the grid, and
//! every sampled surface point of every triangle lying in a marked cell.
//!
//! March: a one-cell wall blocks every segment that crosses it and nothing blocks without it; points on a
//! flat floor never shadow themselves; every cell the offset segment passes through is visited and no
//! other; wherever the exact CPU ray cast finds a triangle on the offset segment the march reports
//! occluded; and the GPU march equals the CPU march on 2000 random Cornell box pairs.

use bounce_device::sync::Access;
use bounce_device::{vk, Binding, Buffer, BufferDesc, ComputePipeline, DescriptorWrites, Gpu, MemoryLocation};
use bounce_graph::bindings::{B_FRAME, B_VOXELS};
use bounce_graph::camera::Camera;
use bounce_graph::gpu_scene::GpuScene;
use bounce_graph::graph::{Graph, Persistent};
use bounce_graph::passes::voxelize::{self, VoxelGridSpec, Voxelize, VOXEL_EPS};
use bounce_graph::scene::{point_light, Scene};
use bounce_graph::shader_types::FrameUniforms;
use bounce_oracles::cpu_ref::{Bvh, Trace};
use bounce_oracles::cpu_voxel::{self, CpuGrid};
use bounce_tests::Rng;
use bounce_tests::TestGpu;
use glam::{DVec3, IVec3, UVec3, Vec3};
use std::collections::HashSet;

/// Test-only bindings of `glsl/test/voxel_march.comp` and `voxel_rcp.comp`.
const T_IN: u32 = bounce_graph::bindings::B_TEST_IN;
const T_OUT: u32 = bounce_graph::bindings::B_TEST_OUT;

fn scene_of(tris: &[[Vec3; 3]]) -> Scene {
    let camera = Camera { eye: Vec3::new(0.0, 0.0, 10.0), target: Vec3::ZERO, up: Vec3::Y, fov_y_deg: 45.0 };
    Scene::from_triangles(tris, &vec![Vec3::splat(0.5); tris.len()], camera, &[point_light(Vec3::ONE, Vec3::ONE)])
}

fn triangles(scene: &Scene) -> Vec<[Vec3; 3]> {
    scene.vertices.chunks_exact(3).map(|v| [v[0].position(), v[1].position(), v[2].position()]).collect()
}

fn cornell() -> Scene {
    Scene::load(&bounce_tests::default_scene()).unwrap()
}

/// A host-visible uniform buffer with the grid's fields (nothing else is read by these shaders).
fn uniform_buffer(gpu: &Gpu, spec: &VoxelGridSpec) -> Buffer {
    let (voxel_origin, voxel_dims) = spec.uniforms_fields();
    let u = FrameUniforms { voxel_origin, voxel_dims, ..Default::default() };
    let mut b = Buffer::new(
        gpu,
        &BufferDesc {
            name: "test uniforms".into(),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: vk::BufferUsageFlags::UNIFORM_BUFFER,
            location: MemoryLocation::CpuToGpu,
        },
    )
    .unwrap();
    b.mapped_mut().unwrap().copy_from_slice(bytemuck::bytes_of(&u));
    b
}

/// Runs `voxelize_clear` + `voxelize` on `scene` into `grid` (a persistent buffer, as the renderer keeps
/// it) and reads the bits back.
fn gpu_voxelize(gpu: &Gpu, vox: &Voxelize, scene: &Scene, spec: &VoxelGridSpec, grid: &Persistent<Buffer>) -> CpuGrid {
    let gs = GpuScene::upload(gpu, scene).unwrap();
    let ub = uniform_buffer(gpu, spec);
    let mut g = Graph::new(gpu);
    let mut h = g.import_buffer(grid);
    vox.add_scene(&mut g, &gs, &ub, &mut h).unwrap();
    g.export(&h);
    let done = g.execute().unwrap();
    assert_eq!(done.ran, ["voxelize_clear", "voxelize"]);
    CpuGrid::from_bytes(*spec, &done.read_buffer(&h).unwrap())
}

fn gpu_voxelize_once(gpu: &Gpu, vox: &Voxelize, scene: &Scene, spec: &VoxelGridSpec) -> CpuGrid {
    let grid = Persistent::new(voxelize::create_grid_buffer(gpu, spec).unwrap());
    gpu_voxelize(gpu, vox, scene, spec, &grid)
}

/// Bit-for-bit comparison, naming the first differing cells.
fn assert_same_bits(what: &str, gpu: &CpuGrid, cpu: &CpuGrid) {
    let g: HashSet<IVec3> = gpu.cells().into_iter().collect();
    let c: HashSet<IVec3> = cpu.cells().into_iter().collect();
    let only_gpu: Vec<_> = g.difference(&c).take(8).collect();
    let only_cpu: Vec<_> = c.difference(&g).take(8).collect();
    assert!(
        only_gpu.is_empty() && only_cpu.is_empty() && gpu.bits == cpu.bits,
        "{what}: GPU and CPU voxelizations differ ({} vs {} cells); only GPU: {only_gpu:?}; only CPU: {only_cpu:?}",
        g.len(),
        c.len()
    );
}

/// Every vertex, the centroid and `samples` random points of every triangle lie in a marked cell (the
/// cell found in f64, independently of the shaders' mapping).
fn assert_surface_points_marked(what: &str, grid: &CpuGrid, tris: &[[Vec3; 3]], samples: usize, rng: &mut Rng) {
    let s = grid.spec;
    let (o, cell) = (s.origin.as_dvec3(), s.cell as f64);
    let mut checked = 0;
    for (k, t) in tris.iter().enumerate() {
        let mut points = vec![t[0], t[1], t[2], (t[0] + t[1] + t[2]) / 3.0];
        points.extend((0..samples).map(|_| rng.on_triangle(t)));
        for p in points {
            let g = (p.as_dvec3() - o) / cell;
            let c = g.floor().as_ivec3();
            if grid.index(c).is_none() {
                continue;
            }
            checked += 1;
            assert!(grid.occupied(c), "{what}: point {p} of triangle {k} (grid {g}) lies in the unmarked cell {c}");
        }
    }
    assert!(checked > 0, "{what}: no surface point inside the grid");
}

#[test]
fn fit_gives_a_valid_grid_for_any_bounds() {
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let cases = [
        ("box", v(-1.0, 0.0, -1.0), v(1.0, 2.0, 1.5)),
        ("flat floor", v(-10.0, 0.3, -10.0), v(10.0, 0.3, 10.0)),
        ("segment", v(1.0, 1.0, 1.0), v(1.0, 1.0, 4.0)),
        ("point", v(0.25, -3.0, 7.0), v(0.25, -3.0, 7.0)),
        ("origin point", Vec3::ZERO, Vec3::ZERO),
        ("far point", v(1e6, 2e6, -3e6), v(1e6, 2e6, -3e6)),
        ("far small box", v(1e6, 1e6, 1e6), v(1e6 + 0.5, 1e6 + 0.1, 1e6 + 0.2)),
        ("empty (inverted)", Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        ("non-finite", v(f32::NAN, 0.0, 0.0), v(1.0, f32::INFINITY, 1.0)),
    ];
    for (name, lo, hi) in cases {
        for n in [0, 1, 2, 3, 4, 32, 128, 1024, 5000] {
            let s = voxelize::fit(lo, hi, n);
            let what = format!("{name}, {n} cells: {s:?}");
            s.validate().unwrap_or_else(|e| panic!("{what}: {e}"));
            let n = n.clamp(1, voxelize::MAX_VOXELS);
            assert!(s.cell.is_finite() && s.cell > 0.0 && s.origin.is_finite(), "{what}");
            assert_eq!(s.dims.max_element(), n, "{what}: the longest side has the asked number of cells");
            assert!(s.dims.min_element() >= 1, "{what}");
            assert_eq!(s.words() as u64, s.cells().div_ceil(32), "{what}");
            let (o, d) = s.uniforms_fields();
            assert_eq!(o, [s.origin.x, s.origin.y, s.origin.z, s.cell], "{what}");
            assert_eq!(d, [s.dims.x, s.dims.y, s.dims.z, s.cells() as u32], "{what}");
            if lo.is_finite() && hi.is_finite() && lo.cmple(hi).all() {
                // Covered with the margin: a whole cell (when there is room for one) on every side, less
                // the f32 rounding of the corner (half an ulp of the coordinates).
                let magnitude = lo.abs().max(hi.abs()).max_element().max(1.0) as f64;
                let ulp = magnitude / (1 << 23) as f64;
                let margin = if n >= 3 { s.cell as f64 - ulp } else { 0.0 };
                let glo = s.origin.as_dvec3();
                let ghi = glo + s.dims.as_dvec3() * s.cell as f64;
                assert!(glo.cmple(lo.as_dvec3() - margin).all(), "{what}: min corner not covered");
                assert!(ghi.cmpge(hi.as_dvec3() + margin).all(), "{what}: max corner not covered");
                // Never coarser than asked: the longest extent fills all but the margins, unless that
                // would make cells under 8 f32 ulps of the coordinates (then exactly that floor).
                let longest = (hi - lo).max_element() as f64;
                if n >= 3 {
                    let want = (longest * 1.002 / (n as f64 - 2.0)).max(magnitude / (1 << 20) as f64);
                    assert!((s.cell as f64 / want - 1.0).abs() < 1e-6, "{what}: cell {} instead of {want}", s.cell);
                }
            }
        }
    }
}

#[test]
fn create_grid_buffer_rejects_impossible_grids() {
    let gpu = TestGpu::new();
    let spec = |dims: UVec3, cell: f32| VoxelGridSpec { origin: Vec3::ZERO, cell, dims };
    for (s, says) in [
        (spec(UVec3::new(4, 0, 4), 1.0), "empty axis"),
        (spec(UVec3::splat(2048), 1.0), "cells"),
        (spec(UVec3::splat(4), 0.0), "cell size"),
        (spec(UVec3::splat(4), f32::NAN), "cell size"),
    ] {
        let e = voxelize::create_grid_buffer(&gpu, &s).err().unwrap_or_else(|| panic!("{s:?} was accepted"));
        assert!(e.to_string().contains(says), "{s:?}: `{e}` should mention `{says}`");
    }
    let ok = voxelize::create_grid_buffer(&gpu, &spec(UVec3::new(5, 6, 7), 0.5)).unwrap();
    assert_eq!(ok.size, 4 * (5 * 6 * 7u64).div_ceil(32));
}

#[test]
fn gpu_voxelization_matches_cpu_on_the_cornell_box() {
    let gpu = TestGpu::new();
    let vox = Voxelize::new(&gpu).unwrap();
    let scene = cornell();
    let tris = triangles(&scene);
    let mut rng = Rng(0x5EED_0001);
    for n in [32, 64] {
        let spec = voxelize::fit(scene.bounds_min, scene.bounds_max, n);
        let grid = Persistent::new(voxelize::create_grid_buffer(&gpu, &spec).unwrap());
        let g = gpu_voxelize(&gpu, &vox, &scene, &spec, &grid);
        let c = cpu_voxel::voxelize_scene(&scene, spec);
        assert_same_bits(&format!("Cornell box at {n}"), &g, &c);
        assert_surface_points_marked(&format!("Cornell box at {n}"), &g, &tris, 200, &mut rng);
        eprintln!(
            "Cornell box {n} cells: grid {} = {} cells, {} marked ({:.2} %), GPU = CPU",
            spec.dims,
            spec.cells(),
            g.count(),
            100.0 * g.count() as f64 / spec.cells() as f64
        );
        // The same buffer again with a one-triangle scene: the clear pass leaves no Cornell bits behind.
        let one = scene_of(&[[Vec3::new(-0.5, 0.5, 0.0), Vec3::new(0.5, 0.5, 0.0), Vec3::new(0.0, 1.5, 0.3)]]);
        let g1 = gpu_voxelize(&gpu, &vox, &one, &spec, &grid);
        let c1 = cpu_voxel::voxelize_scene(&one, spec);
        assert!(c1.count() > 0 && c1.count() < c.count());
        assert_same_bits(&format!("one triangle after the Cornell box at {n}"), &g1, &c1);
    }
}

/// The exact grid of the edge-case tests: origin 0, cell 0.25 (a power of two, so world · 4 = grid units
/// exactly), 16³ cells.
fn exact_spec() -> VoxelGridSpec {
    VoxelGridSpec { origin: Vec3::ZERO, cell: 0.25, dims: UVec3::splat(16) }
}

/// Grid units → world in the exact grid.
fn w(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z) * 0.25
}

/// Closed form for an axis-aligned box [lo, hi] (grid units; a quad, segment or point when flat): the cells
/// whose box grown by ε meets it are, per axis, the i with i − ε ≤ hi and i + 1 + ε ≥ lo, clamped to the
/// grid. Separable because both shapes are axis-aligned boxes.
fn axis_aligned_cells(lo: DVec3, hi: DVec3, dims: UVec3) -> HashSet<IVec3> {
    let eps = VOXEL_EPS as f64;
    let range = |k: usize| {
        let first = (lo[k] - 1.0 - eps).ceil().max(0.0) as i32;
        let last = ((hi[k] + eps).floor() as i32).min(dims[k] as i32 - 1);
        first..=last
    };
    let mut out = HashSet::new();
    for z in range(2) {
        for y in range(1) {
            for x in range(0) {
                out.insert(IVec3::new(x, y, z));
            }
        }
    }
    out
}

/// Two triangles spanning the axis-aligned rectangle [lo, hi] (one axis flat), in grid units.
fn quad(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    let flat = (0..3).find(|&k| lo[k] == hi[k]).expect("a flat box");
    let (u, v) = ((flat + 1) % 3, (flat + 2) % 3);
    let corner = |a: bool, b: bool| {
        let mut p = lo;
        p[u] = if a { hi[u] } else { lo[u] };
        p[v] = if b { hi[v] } else { lo[v] };
        p * 0.25
    };
    let (c00, c10, c11, c01) = (corner(false, false), corner(true, false), corner(true, true), corner(false, true));
    vec![[c00, c10, c11], [c00, c11, c01]]
}

#[test]
fn gpu_voxelization_matches_cpu_and_closed_forms_on_edge_cases() {
    let gpu = TestGpu::new();
    let vox = Voxelize::new(&gpu).unwrap();
    let spec = exact_spec();
    let mut rng = Rng(0x5EED_0002);
    let v = Vec3::new;

    // (name, triangles, expected cells in closed form when the shape is axis-aligned)
    type Case = (&'static str, Vec<[Vec3; 3]>, Option<HashSet<IVec3>>);
    let mut cases: Vec<Case> = vec![];
    let mut aligned = |name, lo: Vec3, hi: Vec3, tris: Vec<[Vec3; 3]>| {
        let want = axis_aligned_cells(lo.as_dvec3(), hi.as_dvec3(), spec.dims);
        cases.push((name, tris, Some(want)));
    };
    // 7 × 5 × 2 = 70 cells: x and z on cell faces (both neighbours count), y on cell centres.
    let (lo, hi) = (v(2.0, 1.5, 3.0), v(7.0, 5.5, 3.0));
    aligned("quad on cell faces", lo, hi, quad(lo, hi));
    // 6 × 7 × 1 = 42 cells: through cell centres in z.
    let (lo, hi) = (v(2.5, 1.0, 4.5), v(7.5, 6.0, 4.5));
    aligned("quad through cell centres", lo, hi, quad(lo, hi));
    // The grid's outer face z = 0 and beyond the grid in x, y: 16 × 16 × 1 cells.
    let (lo, hi) = (v(-3.0, -2.0, 0.0), v(19.0, 16.0, 0.0));
    aligned("quad on the grid's boundary", lo, hi, quad(lo, hi));
    // Degenerate: a segment (collinear vertices, exact midpoint) and points.
    let (lo, hi) = (v(2.5, 3.5, 4.5), v(7.5, 3.5, 4.5));
    aligned("segment along x", lo, hi, vec![[w(2.5, 3.5, 4.5), w(5.0, 3.5, 4.5), w(7.5, 3.5, 4.5)]]);
    let (lo, hi) = (v(9.0, 2.0, 6.5), v(9.0, 2.0, 11.0));
    aligned("segment on a cell edge", lo, hi, vec![[w(9.0, 2.0, 6.5), w(9.0, 2.0, 11.0), w(9.0, 2.0, 8.75)]]);
    let p = v(6.25, 7.75, 9.5);
    aligned("point in a cell", p, p, vec![[w(p.x, p.y, p.z); 3]]);
    let p = v(6.0, 7.0, 9.0);
    aligned("point on a cell corner", p, p, vec![[w(p.x, p.y, p.z); 3]]);
    // A tiny triangle well inside cell (3, 3, 3): exactly that cell.
    let tiny = [w(3.3, 3.4, 3.6), w(3.301, 3.4002, 3.6004), w(3.3003, 3.4011, 3.5995)];
    cases.push(("tiny triangle", vec![tiny], Some(HashSet::from([IVec3::splat(3)]))));
    // Slivers: a long triangle with its third vertex 1e-4 cell off the long edge, and a needle.
    let (a, b) = (v(0.3, 0.2, 0.7), v(15.6, 14.9, 13.3));
    let off = (a + b) * 0.5 + (b - a).cross(Vec3::X).normalize() * 1e-4;
    cases.push(("sliver", vec![[a * 0.25, b * 0.25, off * 0.25]], None));
    cases.push(("needle", vec![[w(1.1, 9.2, 2.3), w(14.7, 9.21, 2.31), w(14.7, 9.2, 2.3)]], None));
    // Larger than the grid: a tilted plane across all of it (edges far outside).
    let big = [w(-40.0, -30.0, 5.2), w(80.0, -30.0, 7.9), w(-40.0, 90.0, 9.6)];
    cases.push(("larger than the grid", vec![big], None));
    // Random triangles of every size, from a hundredth of a cell to most of the grid.
    let random: Vec<[Vec3; 3]> = (0..40)
        .map(|k| {
            let size = 0.01 * 1000f32.powf(k as f32 / 39.0);
            let c = rng.vec(Vec3::splat(0.5), Vec3::splat(15.5));
            [0, 1, 2].map(|_| (c + rng.unit() * size) * 0.25)
        })
        .collect();
    cases.push(("random triangles", random, None));

    let mut all = vec![];
    for (name, tris, want) in &cases {
        let scene = scene_of(tris);
        let g = gpu_voxelize_once(&gpu, &vox, &scene, &spec);
        let c = cpu_voxel::voxelize_triangles(spec, tris);
        assert_same_bits(name, &g, &c);
        assert_surface_points_marked(name, &g, tris, 100, &mut rng);
        if let Some(want) = want {
            let got: HashSet<IVec3> = g.cells().into_iter().collect();
            assert_eq!(&got, want, "{name}: marked cells differ from the closed form");
        }
        eprintln!("edge case `{name}`: {} cells marked, GPU = CPU", g.count());
        all.extend_from_slice(tris);
    }
    // The closed-form counts written out (a check of the closed form itself).
    let count = |name: &str| cases.iter().find(|c| c.0 == name).unwrap().2.as_ref().unwrap().len();
    assert_eq!(count("quad on cell faces"), 70);
    assert_eq!(count("quad through cell centres"), 42);
    assert_eq!(count("quad on the grid's boundary"), 256);
    assert_eq!(count("segment along x"), 6);
    assert_eq!(count("segment on a cell edge"), 4 * 6);
    assert_eq!(count("point in a cell"), 1);
    assert_eq!(count("point on a cell corner"), 8);

    // Degenerate "sliver" containment: the sliver contains its long edge, so it marks every cell of it.
    let sliver = cpu_voxel::voxelize_triangles(spec, &[[a * 0.25, b * 0.25, a * 0.25]]);
    let full = cpu_voxel::voxelize_triangles(spec, &cases.iter().find(|c| c.0 == "sliver").unwrap().1);
    assert!(sliver.count() > 16 && sliver.cells().iter().all(|&c| full.occupied(c)), "sliver misses its own edge");

    // The big triangle is a plane inside the grid: a cell is marked iff the plane meets its grown box, i.e.
    // the plane's signed distances at the 8 corners do not all have one sign (f64; cells within 1e-5 cell
    // of the decision are ambiguous and skipped).
    let g = gpu_voxelize_once(&gpu, &vox, &scene_of(&[big]), &spec);
    let p = big.map(|p| p.as_dvec3() * 4.0);
    let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
    let eps = VOXEL_EPS as f64;
    let (mut marked, mut ambiguous) = (0, 0);
    for c in (0..16 * 16 * 16).map(|i| IVec3::new(i % 16, (i / 16) % 16, i / 256)) {
        let lo = c.as_dvec3() - eps;
        let s: Vec<f64> = (0..8)
            .map(|k| {
                let corner =
                    lo + DVec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64) * (1.0 + 2.0 * eps);
                n.dot(corner - p[0])
            })
            .collect();
        let (mn, mx) = (s.iter().cloned().fold(f64::MAX, f64::min), s.iter().cloned().fold(f64::MIN, f64::max));
        if mn.abs() < 1e-5 || mx.abs() < 1e-5 {
            ambiguous += 1;
            continue;
        }
        let want = mn <= 0.0 && mx >= 0.0;
        assert_eq!(g.occupied(c), want, "plane larger than the grid: cell {c} (corner distances {mn:.3e}..{mx:.3e})");
        marked += want as u32;
    }
    eprintln!("plane larger than the grid: {marked} cells marked as the plane–box test says, {ambiguous} ambiguous");
    assert!(marked > 256 && ambiguous < 5);

    // Everything at once in a fitted grid, whose cell size is not a power of two.
    let scene = scene_of(&all);
    let fitted = voxelize::fit(scene.bounds_min, scene.bounds_max, 24);
    let g = gpu_voxelize_once(&gpu, &vox, &scene, &fitted);
    assert_same_bits("edge cases in a fitted grid", &g, &cpu_voxel::voxelize_scene(&scene, fitted));
    assert_surface_points_marked("edge cases in a fitted grid", &g, &all, 30, &mut rng);
}

#[test]
fn a_triangle_with_more_cells_than_one_invocation_may_loop_over_is_voxelized_whole() {
    let gpu = TestGpu::new();
    let vox = Voxelize::new(&gpu).unwrap();
    let spec = VoxelGridSpec { origin: Vec3::ZERO, cell: 0.25, dims: UVec3::splat(48) };
    // A diagonal triangle whose bounding box holds all 48³ = 110592 cells: on llvmpipe (65535 loop
    // iterations per invocation) the pass must split it over several invocations, with shares that start
    // in the middle of rows and slices.
    let tri = [w(0.3, 0.2, 0.1), w(47.8, 0.4, 47.9), w(0.2, 47.7, 47.6)];
    if let Some(limit) = gpu.loop_iteration_limit {
        assert!(spec.cells() > limit as u64, "the test must exceed the loop limit to exercise the split");
    }
    let g = gpu_voxelize_once(&gpu, &vox, &scene_of(&[tri]), &spec);
    let c = cpu_voxel::voxelize_triangles(spec, &[tri]);
    assert_same_bits("diagonal triangle across 48³", &g, &c);
    assert_surface_points_marked("diagonal triangle across 48³", &g, &[tri], 2000, &mut Rng(0x5EED_0008));
    eprintln!("diagonal triangle across 48³: {} cells marked, GPU = CPU", g.count());
}

/// Runs `voxel_visibility` on the GPU for each (x, nx, y, ny) with the grid `bits` of `spec`.
fn gpu_march(gpu: &Gpu, spec: &VoxelGridSpec, bits: &[u32], pairs: &[[Vec3; 4]]) -> Vec<f32> {
    let p = ComputePipeline::new(
        gpu,
        "voxel_march",
        &bounce_graph::spirv(bounce_graph::shaders::VOXEL_MARCH_COMP),
        &[
            Binding::uniform_buffer(B_FRAME),
            Binding::storage_buffer(B_VOXELS),
            Binding::storage_buffer(T_IN),
            Binding::storage_buffer(T_OUT),
        ],
        0,
        &[],
    )
    .unwrap();
    let ub = uniform_buffer(gpu, spec);
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let grid = Buffer::with_data(gpu, "voxels", storage, bytemuck::cast_slice(bits)).unwrap();
    let data: Vec<[f32; 4]> = pairs.iter().flat_map(|q| q.map(|v| v.extend(0.0).to_array())).collect();
    let inb = Buffer::with_data(gpu, "pairs", storage, bytemuck::cast_slice(&data)).unwrap();
    let outb = Buffer::new(gpu, &BufferDesc::storage("visibility", 4 * pairs.len() as u64)).unwrap();
    gpu.submit(|cmd| {
        let w = DescriptorWrites::new()
            .uniform_buffer(B_FRAME, &ub)
            .storage_buffer(B_VOXELS, &grid)
            .storage_buffer(T_IN, &inb)
            .storage_buffer(T_OUT, &outb);
        p.dispatch(cmd, &w, &[], [pairs.len() as u32, 1, 1], [bounce_graph::bindings::WG_1D, 1, 1]);
    })
    .unwrap();
    bytemuck::pod_collect_to_vec(&outb.read_back(Access::ComputeWrite).unwrap())
}

/// The CPU march for each pair, as 1.0 / 0.0.
fn cpu_march(grid: &CpuGrid, pairs: &[[Vec3; 4]]) -> Vec<f32> {
    pairs.iter().map(|q| if cpu_voxel::visible(grid, q[0], q[1], q[2], q[3]) { 1.0 } else { 0.0 }).collect()
}

fn assert_same_visibility(what: &str, gpu: &[f32], cpu: &[f32], pairs: &[[Vec3; 4]]) {
    let bad: Vec<String> = (0..pairs.len())
        .filter(|&i| gpu[i] != cpu[i])
        .take(8)
        .map(|i| format!("pair {i} {:?}: GPU {} CPU {}", pairs[i], gpu[i], cpu[i]))
        .collect();
    let n = (0..pairs.len()).filter(|&i| gpu[i] != cpu[i]).count();
    assert!(bad.is_empty(), "{what}: {n} of {} pairs differ:\n{}", pairs.len(), bad.join("\n"));
}

/// A normal that faces `towards` from `p`: a random unit vector with cos ≥ 0.1 to it.
fn facing(rng: &mut Rng, p: Vec3, towards: Vec3) -> Vec3 {
    let d = (towards - p).normalize();
    loop {
        let n = rng.unit();
        if n.dot(d) >= 0.1 {
            return n;
        }
    }
}

#[test]
fn a_one_cell_wall_blocks_every_crossing_segment_and_nothing_else_does() {
    let gpu = TestGpu::new();
    let spec = VoxelGridSpec { origin: Vec3::new(-1.0, 2.0, 0.5), cell: 0.5, dims: UVec3::splat(16) };
    // World = origin + grid · 0.5. The wall is the cell layer x = 8 (grid [8, 9]) except a hole at (8, 8, 8).
    let world = |g: Vec3| spec.origin + g * 0.5;
    let (mut wall, mut holed) = (CpuGrid::empty(spec), CpuGrid::empty(spec));
    for z in 0..16 {
        for y in 0..16 {
            wall.set(IVec3::new(8, y, z));
            if (y, z) != (8, 8) {
                holed.set(IVec3::new(8, y, z));
            }
        }
    }
    let empty = CpuGrid::empty(spec);

    // x on the left (its offset end stays at grid x ≤ 7.5), y on the right (offset end at grid x ≥ 9.5);
    // both offset ends stay inside the grid in y and z, so the segment crosses the wall inside the grid
    // (outside the grid nothing is occupied).
    let mut rng = Rng(0x5EED_0003);
    let pairs: Vec<[Vec3; 4]> = (0..500)
        .map(|_| {
            let x = rng.vec(Vec3::new(0.2, 2.2, 2.2), Vec3::new(5.5, 13.8, 13.8));
            let y = rng.vec(Vec3::new(11.5, 2.2, 2.2), Vec3::new(15.8, 13.8, 13.8));
            [world(x), facing(&mut rng, x, y), world(y), facing(&mut rng, y, x)]
        })
        .collect();
    let through_hole = [world(Vec3::new(3.5, 8.5, 8.5)), Vec3::X, world(Vec3::new(13.5, 8.5, 8.5)), -Vec3::X];
    let beside_hole = [world(Vec3::new(3.5, 8.5, 8.5)), Vec3::X, world(Vec3::new(13.5, 9.7, 8.5)), -Vec3::X];

    for (grid, name) in [(&wall, "wall"), (&empty, "no wall")] {
        let cpu = cpu_march(grid, &pairs);
        let want = if name == "wall" { 0.0 } else { 1.0 };
        let wrong = cpu.iter().filter(|&&v| v != want).count();
        assert_eq!(wrong, 0, "{name}: {wrong} of {} CPU marches say {}", pairs.len(), 1.0 - want);
        assert_same_visibility(name, &gpu_march(&gpu, &spec, &grid.bits, &pairs), &cpu, &pairs);
    }
    let probes = [through_hole, beside_hole];
    assert_eq!(cpu_march(&holed, &probes), [1.0, 0.0], "the hole lets exactly the straight segment through");
    assert_eq!(gpu_march(&gpu, &spec, &holed.bits, &probes), [1.0, 0.0]);
}

#[test]
fn a_flat_floor_does_not_shadow_itself() {
    let gpu = TestGpu::new();
    let vox = Voxelize::new(&gpu).unwrap();
    let h = 0.37;
    let v = Vec3::new;
    // The floor, plus a small marker triangle far up in a corner so that the grid has height.
    let tris = [
        [v(-5.0, h, -5.0), v(5.0, h, -5.0), v(5.0, h, 5.0)],
        [v(-5.0, h, -5.0), v(5.0, h, 5.0), v(-5.0, h, 5.0)],
        [v(4.6, 6.0, 4.6), v(4.9, 6.0, 4.6), v(4.6, 6.1, 4.9)],
    ];
    let scene = scene_of(&tris);
    let spec = voxelize::fit(scene.bounds_min, scene.bounds_max, 48);
    let cpu_grid = cpu_voxel::voxelize_scene(&scene, spec);
    let gpu_grid = gpu_voxelize_once(&gpu, &vox, &scene, &spec);
    assert_same_bits("floor", &gpu_grid, &cpu_grid);
    // x on the floor (normal up), y at least 4 cells above it, facing x: both offset ends stay ≥ 2 cells
    // above the floor, whose marked cells reach at most ~1 cell above it.
    let mut rng = Rng(0x5EED_0004);
    let pairs: Vec<[Vec3; 4]> = (0..3000)
        .map(|_| {
            let x = v(rng.range(-3.0, 3.0), h, rng.range(-3.0, 3.0));
            let y = v(rng.range(-3.0, 3.0), rng.range(h + 4.0 * spec.cell, 5.5), rng.range(-3.0, 3.0));
            [x, Vec3::Y, y, facing(&mut rng, y, x)]
        })
        .collect();
    let cpu = cpu_march(&cpu_grid, &pairs);
    let shadowed = cpu.iter().filter(|&&v| v != 1.0).count();
    assert_eq!(shadowed, 0, "{shadowed} of {} floor points shadow themselves", pairs.len());
    assert_same_visibility("floor", &gpu_march(&gpu, &spec, &gpu_grid.bits, &pairs), &cpu, &pairs);
    eprintln!("floor: {} pairs, all visible on CPU and GPU (grid {}, cell {})", pairs.len(), spec.dims, spec.cell);
}

/// Random pairs of surface points of `tris` whose normals (flipped, two-sided surfaces) face each other
/// with cos ≥ 0.05.
fn surface_pairs(tris: &[[Vec3; 3]], n: usize, rng: &mut Rng) -> Vec<[Vec3; 4]> {
    let areas: Vec<f32> = tris.iter().map(|t| (t[1] - t[0]).cross(t[2] - t[0]).length()).collect();
    let total: f32 = areas.iter().sum();
    let pick = |rng: &mut Rng| {
        let mut r = rng.f32() * total;
        let k = areas.iter().position(|&a| {
            r -= a;
            r < 0.0
        });
        let t = &tris[k.unwrap_or(tris.len() - 1)];
        (rng.on_triangle(t), (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero())
    };
    let mut out = vec![];
    while out.len() < n {
        let ((x, nx), (y, ny)) = (pick(rng), pick(rng));
        let d = (y - x).normalize_or_zero();
        let (cx, cy) = (nx.dot(d), -ny.dot(d));
        if cx.abs() < 0.05 || cy.abs() < 0.05 {
            continue;
        }
        out.push([x, nx * cx.signum(), y, ny * cy.signum()]);
    }
    out
}

#[test]
fn gpu_march_equals_cpu_march_and_sees_every_exact_hit_in_the_cornell_box() {
    let gpu = TestGpu::new();
    let vox = Voxelize::new(&gpu).unwrap();
    let scene = cornell();
    let spec = voxelize::fit(scene.bounds_min, scene.bounds_max, 64);
    let gpu_grid = gpu_voxelize_once(&gpu, &vox, &scene, &spec);
    let cpu_grid = cpu_voxel::voxelize_scene(&scene, spec);
    assert_same_bits("Cornell box at 64", &gpu_grid, &cpu_grid);
    let mut rng = Rng(0x5EED_0005);
    let pairs = surface_pairs(&triangles(&scene), 2000, &mut rng);
    let cpu = cpu_march(&cpu_grid, &pairs);
    assert_same_visibility("Cornell box", &gpu_march(&gpu, &spec, &gpu_grid.bits, &pairs), &cpu, &pairs);

    // Against the exact ray cast. On the offset segment (x + 2 cells·nx → y + 2 cells·ny) an exact hit
    // lies in a marked cell the march visits, so the march must say occluded; pairs whose offsets crossed
    // are visible by rule and left out. The exact visibility of x → y itself agrees most of the time
    // (the voxels only add occlusion near surfaces).
    let bvh = Bvh::new(&scene);
    let off = 2.0 * spec.cell as f64;
    let (mut crossed, mut missed, mut agree, mut occluded) = (0, vec![], 0, 0);
    for (q, &vis) in pairs.iter().zip(&cpu) {
        let [x, nx, y, ny] = q.map(|v| v.as_dvec3());
        let (a, b) = (x + nx * off, y + ny * off);
        occluded += (vis == 0.0) as usize;
        agree += (bvh.occluded(x, y) == (vis == 0.0)) as usize;
        if (b - a).dot(y - x) <= 0.0 {
            crossed += 1;
        } else if bvh.occluded(a, b) && vis != 0.0 {
            missed.push(format!("{q:?}"));
        }
    }
    eprintln!(
        "Cornell march, {} pairs: GPU = CPU; {occluded} occluded; {} exact hits on offset segments missed; \
         {crossed} crossed offsets; agreement with exact x→y visibility {:.1} %",
        pairs.len(),
        missed.len(),
        100.0 * agree as f64 / pairs.len() as f64
    );
    assert!(missed.is_empty(), "the march missed exact hits:\n{}", missed[..missed.len().min(8)].join("\n"));
    assert!(
        occluded > pairs.len() / 20 && occluded < pairs.len() * 19 / 20,
        "{occluded} occluded: a degenerate sample"
    );
    assert!(agree * 10 > pairs.len() * 8, "only {agree} of {} agree with exact visibility", pairs.len());
}

#[test]
fn the_march_visits_exactly_the_cells_the_offset_segment_crosses() {
    let scene = cornell();
    let spec = voxelize::fit(scene.bounds_min, scene.bounds_max, 32);
    let (o, cell) = (spec.origin.as_dvec3(), spec.cell as f64);
    let dims = spec.dims.as_dvec3();
    let mut rng = Rng(0x5EED_0006);
    let (lo, hi) = (spec.origin - 3.0 * spec.cell, spec.world_max() + 3.0 * spec.cell);
    let (mut walked, mut samples) = (0, 0);
    for _ in 0..1500 {
        let (x, y) = (rng.vec(lo, hi), rng.vec(lo, hi));
        let (nx, ny) = (facing(&mut rng, x, y), facing(&mut rng, y, x));
        let mut visited = vec![];
        cpu_voxel::march(&spec, x, nx, y, ny, |c| {
            visited.push(c);
            false
        });
        // The offset segment in f64 grid units, clipped to the grid box.
        let (gx, gy) = ((x.as_dvec3() - o) / cell, (y.as_dvec3() - o) / cell);
        let (a, b) = (gx + nx.as_dvec3() * 2.0, gy + ny.as_dvec3() * 2.0);
        let d = b - a;
        if d.dot(gy - gx) <= 0.0 {
            assert!(visited.is_empty(), "crossed offsets must not be marched");
            continue;
        }
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for k in 0..3 {
            if d[k] != 0.0 {
                let (ta, tb) = (-a[k] / d[k], (dims[k] - a[k]) / d[k]);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
        }
        if t0 > t1 - 1e-6 {
            continue; // misses (or grazes) the grid
        }
        walked += 1;
        let set: HashSet<IVec3> = visited.iter().copied().collect();
        assert_eq!(set.len(), visited.len(), "a cell visited twice: {visited:?}");
        for w in visited.windows(2) {
            assert_eq!((w[1] - w[0]).abs().element_sum(), 1, "not face-adjacent steps: {visited:?}");
        }
        // Every cell along the segment is visited (samples off cell faces and the clipped ends).
        for k in 1..400 {
            let t = t0 + (t1 - t0) * k as f64 / 400.0;
            let p = a + d * t;
            if (p - p.round()).abs().min_element() < 1e-4 {
                continue;
            }
            samples += 1;
            let c = p.floor().as_ivec3();
            assert!(set.contains(&c), "cell {c} at t = {t} of the segment {a} → {b} was not visited: {visited:?}");
        }
        // And every visited cell touches the segment (within 1e-4 cell).
        for c in &visited {
            let (bl, bh) = (c.as_dvec3() - 1e-4, c.as_dvec3() + 1.0 + 1e-4);
            let (mut s0, mut s1) = (t0, t1);
            for k in 0..3 {
                if d[k] == 0.0 {
                    assert!(a[k] >= bl[k] && a[k] <= bh[k]);
                } else {
                    let (ta, tb) = ((bl[k] - a[k]) / d[k], (bh[k] - a[k]) / d[k]);
                    s0 = s0.max(ta.min(tb));
                    s1 = s1.min(ta.max(tb));
                }
            }
            assert!(s0 <= s1, "visited cell {c} is off the segment {a} → {b}");
        }
    }
    eprintln!("DDA coverage: {walked} segments walked, {samples} sample points all in visited cells");
    assert!(walked > 500);
}

#[test]
fn gpu_reciprocal_has_the_cpu_bits_and_is_accurate() {
    let gpu = TestGpu::new();
    let mut rng = Rng(0x5EED_0007);
    let mut inputs: Vec<f32> = (-30..=30).map(|e| 2f32.powi(e)).collect();
    inputs.extend([3.0, 0.1, 0.3, 1.0 / 3.0, 0.0123, 7.77, 1e-9, 1e9, -0.25, -5.5]);
    inputs.extend((0..4000).map(|_| {
        let m = f32::from_bits(0x3F80_0000 | (rng.next_u64() as u32 & 0x007F_FFFF)); // [1, 2)
        let e = (rng.next_u64() % 61) as i32 - 30;
        let s = if rng.next_u64() & 1 == 0 { 1.0 } else { -1.0 };
        s * m * 2f32.powi(e)
    }));
    let shader = bounce_graph::shaders::VOXEL_RCP_COMP;
    let got: Vec<f32> = bounce_tests::run_test_kernel(&gpu, "voxel_rcp", shader, &inputs, inputs.len());
    let mut worst = 0.0f64;
    for (&c, &g) in inputs.iter().zip(&got) {
        let r = cpu_voxel::rcp(c);
        assert_eq!(g.to_bits(), r.to_bits(), "rcp({c:e}): GPU {g:e}, CPU {r:e}");
        let err = (r as f64 * c as f64 - 1.0).abs();
        worst = worst.max(err);
        assert!(err < f32::EPSILON as f64, "rcp({c:e}) = {r:e} is {err:e} off (more than 2⁻²³)");
    }
    for e in -30..=30 {
        assert_eq!(cpu_voxel::rcp(2f32.powi(e)), 2f32.powi(-e), "rcp of a power of two is exact");
    }
    eprintln!("voxel_rcp: {} inputs, GPU bits = CPU bits, worst |c·rcp(c) − 1| = {worst:.2e}", inputs.len());
}
