//! The reflective dual paraboloid maps (the VPLs) against an exact CPU ray cast from the light through
//! every texel's sample point (the frame's offset in the texel, `Keys::vpl_offset`). The GPU casts the same
//! ray through its BVH (f32, watertight), so depths must agree to float rounding everywhere but at texels
//! whose ray grazes a triangle edge (there the two sides may legitimately pick different triangles). And the
//! VPLs' solid angles over seeds against a closed form, and the paraboloid maps' box depth (psm's raster).

use bounce_graph::bindings::VPL_MIN_COS;
use bounce_graph::camera::Camera;
use bounce_graph::frame::keys::{texel_offset, vpl_offset};
use bounce_graph::frame::{Component, FrameSettings, Method, Renderer};
use bounce_graph::scene::{point_light, Scene};
use bounce_oracles::cpu_ref::{Bvh, Trace};
use bounce_tests::TestGpu;
use glam::{DVec3, Vec3};

/// A 20×20 floor with the light 0.05 above it: from the light the floor fills almost a whole
/// hemisphere and crosses the boundary between the two paraboloid faces, the worst case for a
/// non-linear projection. A tilted blocker triangle hangs between.
pub fn big_floor_scene() -> Scene {
    let f = |x: f32, z: f32| Vec3::new(x, 0.0, z);
    let tris = [
        [f(-10.0, -10.0), f(10.0, -10.0), f(10.0, 10.0)],
        [f(-10.0, -10.0), f(10.0, 10.0), f(-10.0, 10.0)],
        [Vec3::new(-0.5, 0.3, -0.2), Vec3::new(0.6, 0.35, 0.1), Vec3::new(0.1, 0.32, 0.7)],
    ];
    let albedo = [Vec3::splat(0.5), Vec3::splat(0.5), Vec3::new(0.8, 0.2, 0.2)];
    let camera = Camera { eye: Vec3::new(0.0, 2.5, 2.5), target: Vec3::ZERO, up: Vec3::Y, fov_y_deg: 60.0 };
    let light = point_light(Vec3::new(0.13, 0.05, -0.07), Vec3::splat(1.0));
    // A second light, far off to the side, so the map array has more than one light.
    let light2 = point_light(Vec3::new(4.0, 3.0, 1.0), Vec3::splat(4.0));
    Scene::from_triangles(&tris, &albedo, camera, &[light, light2])
}

/// Paraboloid coordinates of texel (i, j) of an n² face, offset by (di, dj) texels from the point `o`
/// (in texels) where the face's texel rays pass (`bounce_graph::frame::keys::texel_offset`).
fn texel_uv(i: usize, j: usize, n: usize, o: [f32; 2], di: f64, dj: f64) -> (f64, f64) {
    let (oi, oj) = (o[0] as f64, o[1] as f64);
    ((i as f64 + oi + di) / n as f64 * 2.0 - 1.0, (j as f64 + oj + dj) / n as f64 * 2.0 - 1.0)
}

/// The unit direction of paraboloid coordinates (u, v) on face 0 (+z) or 1 (−z), in f64: the inverse of
/// the map the shaders use (`paraboloid_direction` in glsl/shared/common.glsl).
fn paraboloid_dir((u, v): (f64, f64), face: usize) -> DVec3 {
    let r2 = u * u + v * v;
    let d = DVec3::new(2.0 * u, 2.0 * v, 1.0 - r2) / (1.0 + r2);
    if face == 0 {
        d
    } else {
        DVec3::new(d.x, d.y, -d.z)
    }
}

/// Whether texel (i, j) of face `face` straddles a triangle edge: a hundredth of a texel away from its centre
/// the ray from `lp` leaves the unit disk or hits a different triangle (or nothing) than `tri`. Such texels
/// are rasterised by whichever triangle wins the tie, so they are not compared exactly.
fn near_triangle_edge(
    bvh: &Bvh,
    lp: DVec3,
    (i, j, n, face, o): (usize, usize, usize, usize, [f32; 2]),
    tri: Option<u32>,
) -> bool {
    [(0.01, 0.0), (-0.01, 0.0), (0.0, 0.01), (0.0, -0.01)].iter().any(|&(di, dj)| {
        let (pu, pv) = texel_uv(i, j, n, o, di, dj);
        pu * pu + pv * pv > 1.0 || bvh.intersect(lp, paraboloid_dir((pu, pv), face)).map(|h| h.tri) != tri
    })
}

/// The reflective DPRSM: every texel's VPL against a CPU ray cast through its sample point: position,
/// light-facing normal, solid angle Δω = 4/(1+u²+v²)² (2/res)², flux albedo · I · Δω and the patch area
/// A_v = Δω · t² / max(|cos α|, VPL_MIN_COS) (t the hit distance, α between the ray and the face); and the solid
/// angles of all texels inside the unit disk add up to 4π (minus the ring the disk's texels miss).
#[test]
fn reflective_dprsm_texels_match_a_cpu_ray_cast() {
    check_reflective_against_ray_cast(&big_floor_scene(), 64);
}

/// The same in the Cornell box: the light 1 cm below its ceiling panel sees the panel at grazing and
/// near-zero distances, and every wall at once.
#[test]
fn reflective_dprsm_texels_match_a_cpu_ray_cast_in_the_cornell_box() {
    check_reflective_against_ray_cast(&Scene::load(&bounce_tests::default_scene()).unwrap(), 64);
}

/// Every VPL of a light sealed in a box lies on the box's walls, edge texels included (a texel whose
/// ray slipped between two wall triangles would put a VPL on the floor outside and light the scene),
/// and the texels match the CPU ray cast.
#[test]
fn a_light_sealed_in_a_box_has_every_vpl_on_the_box() {
    let scene = sealed_light_scene();
    let c = Vec3::new(0.0, 1.5, 0.5);
    for res in [16u32, 64, 256] {
        let gpu = TestGpu::new();
        let r = Renderer::new(&gpu, &scene).unwrap();
        let [pos, _, _] = bounce_tests::maps::render_vpls(
            &r,
            &FrameSettings {
                dprsm_res: res,
                method: Method::Uniform,
                component: Component::Direct,
                ..FrameSettings::default()
            },
        )
        .unwrap();
        let outside: Vec<String> = pos
            .iter()
            .enumerate()
            .filter(|(_, p)| p[3] != 0.0 && (Vec3::new(p[0], p[1], p[2]) - c).abs().max_element() > 0.1001)
            .take(6)
            .map(|(k, p)| format!("texel {k} at {:?}", &p[..3]))
            .collect();
        assert!(outside.is_empty(), "{res}²: VPLs outside the box: {}", outside.join("; "));
    }
    check_reflective_against_ray_cast(&scene, 256);
}

fn check_reflective_against_ray_cast(scene: &Scene, res: u32) {
    let scene = scene.clone();
    let gpu = TestGpu::new();
    let r = Renderer::new(&gpu, &scene).unwrap();
    let s = FrameSettings {
        dprsm_res: res,
        method: Method::Uniform,
        component: Component::Direct,
        ..FrameSettings::default()
    };
    let [pos, nrm, flux] = bounce_tests::maps::render_vpls(&r, &s).unwrap();
    // Where the texel rays pass in layer 0 (the others follow from it): not the centre.
    let offset = vpl_offset(&s);
    let bvh = Bvh::new(&scene);
    let n = res as usize;
    let (mut checked, mut edge) = (0usize, 0usize);
    let mut omega_sum = [0.0f64; 2];
    let mut bad = vec![];
    for (li, light) in scene.lights.iter().enumerate() {
        let lp = DVec3::new(light.position[0] as f64, light.position[1] as f64, light.position[2] as f64);
        let intensity = light.intensity[0] as f64;
        #[allow(clippy::needless_range_loop)] // `face` also selects the layer and the mirrored direction
        for face in 0..2 {
            for j in 0..n {
                for i in 0..n {
                    let k = ((li * 2 + face) * n + j) * n + i;
                    let o = texel_offset(offset, (li * 2 + face) as u32);
                    let (u, v) = texel_uv(i, j, n, o, 0.0, 0.0);
                    let r2 = u * u + v * v;
                    if r2 > 1.0 {
                        assert_eq!(pos[k][3], 0.0, "texel outside the disk holds a VPL");
                        continue;
                    }
                    let d_omega = 4.0 / ((1.0 + r2) * (1.0 + r2)) * (2.0 / n as f64).powi(2);
                    if li == 0 {
                        omega_sum[face] += d_omega;
                    }
                    let hit = bvh.intersect(lp, paraboloid_dir((u, v), face));
                    if near_triangle_edge(&bvh, lp, (i, j, n, face, o), hit.as_ref().map(|h| h.tri)) {
                        edge += 1;
                        continue;
                    }
                    checked += 1;
                    let Some(h) = hit else {
                        if pos[k][3] != 0.0 {
                            bad.push(format!("texel {k}: GPU has a VPL where the ray misses"));
                        }
                        continue;
                    };
                    let p = lp + paraboloid_dir((u, v), face) * h.t;
                    let g = DVec3::new(pos[k][0] as f64, pos[k][1] as f64, pos[k][2] as f64);
                    if (g - p).length() > 1e-4 * h.t.max(1.0) {
                        bad.push(format!("texel {k}: position {g:?} vs {p:?}"));
                        continue;
                    }
                    // Face normal of the flat test scene, flipped to face the light.
                    let tv = &scene.vertices[3 * h.tri as usize..3 * h.tri as usize + 3];
                    let (a, b, c) =
                        (tv[0].position().as_dvec3(), tv[1].position().as_dvec3(), tv[2].position().as_dvec3());
                    let mut fnorm = (b - a).cross(c - a).normalize();
                    let cos_a = fnorm.dot(paraboloid_dir((u, v), face)).abs().max(VPL_MIN_COS as f64);
                    let area = d_omega * h.t * h.t / cos_a;
                    if ((pos[k][3] as f64) - area).abs() > 1e-4 * area {
                        bad.push(format!("texel {k}: patch area {} vs {area}", pos[k][3]));
                    }
                    if fnorm.dot(lp - p) < 0.0 {
                        fnorm = -fnorm;
                    }
                    let gn = DVec3::new(nrm[k][0] as f64, nrm[k][1] as f64, nrm[k][2] as f64);
                    if (gn - fnorm).length() > 1e-4 {
                        bad.push(format!("texel {k}: normal {gn:?} vs {fnorm:?}"));
                    }
                    let albedo = scene.materials[scene.tri_material[h.tri as usize] as usize].kd().as_dvec3();
                    let want = albedo * intensity * d_omega;
                    let gf = DVec3::new(flux[k][0] as f64, flux[k][1] as f64, flux[k][2] as f64);
                    if (gf - want).length() > 1e-5 * want.length()
                        || ((flux[k][3] as f64) - d_omega).abs() > 1e-5 * d_omega
                    {
                        bad.push(format!("texel {k}: flux {gf:?} (Δω {}) vs {want:?} (Δω {d_omega})", flux[k][3]));
                    }
                }
            }
        }
    }
    eprintln!(
        "reflective dprsm {res}²: {checked} texels checked, {edge} edge texels skipped; Σ Δω per face {omega_sum:?}"
    );
    assert!(bad.is_empty(), "{} bad texels: {}", bad.len(), bad[..bad.len().min(6)].join("; "));
    assert!(edge * 20 < checked);
    // Each face's texels inside the unit disk cover its hemisphere, 2π, except the ring of partly
    // covered rim texels: at most one texel ring, ~π·2·(2/res)·(Δω per unit area at r=1 = 1) ≈ 0.2 sr.
    for (f, sum) in omega_sum.iter().enumerate() {
        let miss = 2.0 * std::f64::consts::PI - sum;
        assert!((0.0..0.25).contains(&miss.abs()), "face {f}: Σ Δω = {sum}, 2π − Σ = {miss}");
    }
}

/// A light sealed in a small closed box (0.2 wide, the light at its centre) in a closed room, as a user's
/// OBJ would give it: written with decimal coordinates, loaded (f64 parse, rebased to its centre), then
/// rebased back to world coordinates. Every texel sees a box wall at 0.1–0.17; the light is exactly
/// central, so the diagonal texels' rays run exactly through the box's edges, and a texel ray that slips
/// between two wall triangles puts a VPL on the room outside (Möller–Trumbore let some through).
pub fn sealed_light_scene() -> Scene {
    use std::fmt::Write as _;
    let dir = std::env::temp_dir().join(format!("bounce-sealed-light-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let c = [0.0f64, 1.5, 0.5];
    let v = |x: f64, y: f64, z: f64| [c[0] + x * 0.1, c[1] + y * 0.1, c[2] + z * 0.1];
    let mut quads = vec![];
    for (a, b, cc, d) in [
        (v(-1., -1., -1.), v(1., -1., -1.), v(1., -1., 1.), v(-1., -1., 1.)),
        (v(-1., 1., -1.), v(-1., 1., 1.), v(1., 1., 1.), v(1., 1., -1.)),
        (v(-1., -1., -1.), v(-1., 1., -1.), v(1., 1., -1.), v(1., -1., -1.)),
        (v(-1., -1., 1.), v(1., -1., 1.), v(1., 1., 1.), v(-1., 1., 1.)),
        (v(-1., -1., -1.), v(-1., -1., 1.), v(-1., 1., 1.), v(-1., 1., -1.)),
        (v(1., -1., -1.), v(1., 1., -1.), v(1., 1., 1.), v(1., -1., 1.)),
    ] {
        quads.push([a, b, cc, d]);
    }
    // A closed room around it, so that a texel ray escaping the box always lands on something.
    let room = |x: f64, y: f64, z: f64| [x * 2.0, 1.0 + y * 2.0, z * 2.0];
    for (a, b, cc, d) in [
        (room(-1., -1., -1.), room(1., -1., -1.), room(1., -1., 1.), room(-1., -1., 1.)),
        (room(-1., 1., -1.), room(-1., 1., 1.), room(1., 1., 1.), room(1., 1., -1.)),
        (room(-1., -1., -1.), room(-1., 1., -1.), room(1., 1., -1.), room(1., -1., -1.)),
        (room(-1., -1., 1.), room(1., -1., 1.), room(1., 1., 1.), room(-1., 1., 1.)),
        (room(-1., -1., -1.), room(-1., -1., 1.), room(-1., 1., 1.), room(-1., 1., -1.)),
        (room(1., -1., -1.), room(1., 1., -1.), room(1., 1., 1.), room(1., -1., 1.)),
    ] {
        quads.push([a, b, cc, d]);
    }
    let mut obj = String::new();
    for (k, q) in quads.iter().enumerate() {
        for p in q {
            writeln!(obj, "v {} {} {}", p[0], p[1], p[2]).unwrap();
        }
        writeln!(obj, "f {} {} {} {}", 4 * k + 1, 4 * k + 2, 4 * k + 3, 4 * k + 4).unwrap();
    }
    std::fs::write(dir.join("sealed.obj"), obj).unwrap();
    let toml = "mesh = \"sealed.obj\"\n[camera]\neye = [0.0, 1.5, 1.8]\ntarget = [0.0, 1.5, 0.5]\nup = [0.0, 1.0, 0.0]\nfov_y = 60.0\n[[light]]\nposition = [0.0, 1.5, 0.5]\nintensity = [1.0, 1.0, 1.0]\n";
    std::fs::write(dir.join("sealed.toml"), toml).unwrap();
    let mut scene = Scene::load(&dir.join("sealed.toml")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    scene.rebase(DVec3::ZERO);
    scene
}

/// The closest point of triangle `t` to the origin in f64, by another route than the shader's (Ericson's
/// Voronoi regions): the projection onto the plane when it lies inside, else the nearest of the three
/// edges' closest points.
fn closest_point_f64(t: [DVec3; 3]) -> DVec3 {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    // The origin's foot on the plane: o − n (n·(o − a)) / |n|² with o = 0.
    let on_plane = n * (n.dot(t[0]) / n.length_squared());
    let inside = (0..3).all(|k| (t[(k + 1) % 3] - t[k]).cross(on_plane - t[k]).dot(n) >= 0.0);
    if inside {
        return on_plane;
    }
    (0..3)
        .map(|k| {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let s = ((-a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
            a + (b - a) * s
        })
        .min_by(|p, q| p.length().total_cmp(&q.length()))
        .unwrap()
}

/// psm's map fragment shaders declare `depth_greater` under the box the geometry shader emits at
/// `map_box_depth` (glsl/shared/map_depth.glsl), so a GPU may reject texels by that depth before they run.
/// The fragment never writes below its box's depth (`map_texel_depth` lifts it), which is harmless only
/// while the box lies below the triangle's true nearest distance: checked here against an f64 closest
/// point, on triangles from 1 mm to 10 km (random ones, the light 1e-3 of their size off the interior of a
/// huge one, next to an edge or a vertex, tiny ones far away, slivers; then 1500 slivers at 1e-6 and 1e-7,
/// where Ericson's face case alone put 12 boxes above the nearest point), with the bound tight enough that
/// early rejection still works. lavapipe tests depth after the shader, so no image shows a violation.
/// The test kernel also casts the fragment shader's texel rays through 271 points of each triangle (its
/// closest point among them): the points `map_texel_point` places (the VPLs, dprsm.comp) must not be nearer the light
/// than the triangle (on slivers the plane-form t fell up to 88 % short: 697 triangles failed this before
/// the barycentric fallback), nor off its plane (it also came out long, up to 97 % of the distance, until
/// slivers took the barycentric point always), and it reports how many hit nearer than the box (the
/// texels the lift moves).
#[test]
fn the_light_maps_box_depth_is_below_every_texel_depth() {
    let mut rng = bounce_tests::Rng(0x0DE9_7B0D);
    let mut cases: Vec<[[f32; 4]; 4]> = vec![];
    let mut tris: Vec<[DVec3; 3]> = vec![];
    for k in 0..3900 {
        let scale = 10f32.powf(rng.range(-3.0, 4.0));
        let (n, u) = (rng.unit(), rng.unit());
        let u = (u - n * u.dot(n)).normalize_or(n.any_orthonormal_vector());
        let v = n.cross(u);
        let in_plane = |x: f32, y: f32| u * x + v * y;
        let t: [Vec3; 3] = match if k < 2400 { k % 6 } else { 5 } {
            // Anywhere.
            0 => [0, 1, 2].map(|_| rng.vec(Vec3::splat(-scale), Vec3::splat(scale))),
            // The light a thousandth of the size off a huge triangle's interior.
            1 => {
                let h = n * scale * 1e-3 * rng.range(0.1, 1.0);
                [(-1.0, -1.0), (1.5, -0.5), (-0.3, 1.4)].map(|(x, y)| in_plane(x, y) * scale + h)
            }
            // Off an edge: the foot of the light just outside or on edge ab.
            2 => {
                let h = n * scale * 1e-3 * rng.range(0.0, 1.0);
                let out = v * scale * 1e-4 * rng.range(-1.0, 1.0);
                [(-1.0, 0.0), (1.0, 0.0), (0.2, 1.0)].map(|(x, y)| in_plane(x, y) * scale + h + out)
            }
            // Off a vertex.
            3 => {
                let h = n * scale * 1e-4 * rng.range(0.0, 1.0);
                [(0.0, 0.0), (1.0, 0.1), (0.3, 1.0)].map(|(x, y)| in_plane(x, y) * scale + h)
            }
            // A tiny triangle far away.
            4 => {
                let c = rng.unit() * scale;
                [0, 1, 2].map(|_| c + rng.unit() * scale * 1e-4)
            }
            // A sliver: c 1e-2 to 1e-6 of the size off segment ab; then 1500 at 1e-6 and 1e-7, where the
            // face case alone (Ericson's) put the box above the nearest point on 7 and 20 of 1500 each.
            _ => {
                let (a, b) = (rng.unit() * scale, rng.unit() * scale);
                let off = if k < 2400 { 10f32.powi(-2 - k / 6 % 5) } else { 10f32.powi(-6 - k % 2) };
                let c = a + (b - a) * rng.range(0.1, 0.9) + rng.unit() * scale * off;
                [a, b, c]
            }
        };
        let td = t.map(|p| p.as_dvec3());
        if (td[1] - td[0]).cross(td[2] - td[0]).length() == 0.0 {
            continue;
        }
        let q = closest_point_f64(td).as_vec3();
        let far = 2.0 * t.iter().map(|p| p.length()).fold(0.0f32, f32::max);
        let w = |p: Vec3, w: f32| [p.x, p.y, p.z, w];
        cases.push([w(t[0], far), w(t[1], 0.0), w(t[2], 0.0), w(q, 0.0)]);
        tris.push(td);
    }
    let gpu = TestGpu::new();
    let shader = bounce_graph::shaders::MAP_DEPTH_COMP;
    // Per case: the box and depths, the least placed distance, then each of the kernel's 271 rays' point.
    const STRIDE: usize = 2 + 271;
    let out: Vec<[f32; 4]> = bounce_tests::run_test_kernel(&gpu, "map_depth", shader, &cases, STRIDE * cases.len());
    let (got, placed): (Vec<[f32; 4]>, Vec<f32>) =
        (out.iter().step_by(STRIDE).copied().collect(), out.iter().skip(1).step_by(STRIDE).map(|p| p[0]).collect());
    // How far each placed point (a VPL) lies off its triangle's plane (f64), beyond 20 ulps of the
    // triangle's size, over its distance from the light: a plane-form t that came out long put a sliver's
    // VPLs behind its surface (up to 0.97 of their distance before slivers took the barycentric point).
    let mut worst_off = (0.0f64, 0usize);
    for (k, t) in tris.iter().enumerate() {
        for p in out[STRIDE * k + 2..STRIDE * (k + 1)].iter().filter(|p| p[3] == 1.0) {
            let p = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            let size = t.iter().map(|v| v.length()).fold(0.0, f64::max);
            let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            let off = (n.dot(p - t[0]).abs() - 2e-6 * size).max(0.0) / p.length();
            if off > worst_off.0 {
                worst_off = (off, k);
            }
        }
    }
    eprintln!("placed points: at most {:.2e} of their distance off their plane (case {})", worst_off.0, worst_off.1);
    assert!(
        worst_off.0 < 1e-5,
        "case {}: a placed point {:.2e} of its distance off its plane",
        worst_off.1,
        worst_off.0
    );
    let (mut bad, mut rays, mut hits, mut lifted, mut worst_short) = (vec![], 0usize, 0usize, 0usize, 0.0f64);
    for (k, (o, t)) in got.iter().zip(&tris).enumerate() {
        let far = cases[k][0][3] as f64;
        let size = t.iter().map(|p| p.length()).fold(0.0, f64::max);
        let exact = closest_point_f64(*t).length();
        let (box_z, least, n_hits, dist) = (o[0] as f64, o[1] as f64, o[2] as usize, o[3] as f64);
        // The aim check on the first 2400: the extreme slivers after them are too thin for most rays.
        if k < 2400 {
            rays += 271;
            hits += n_hits;
        }
        if box_z > exact / far {
            bad.push(format!("case {k} {t:?}: box depth {box_z} above the nearest point's {}", exact / far));
        }
        // Tight: f32 coordinates of magnitude `size` carry absolute errors of a few ulps of `size`.
        if box_z < exact / far * (1.0 - 2e-4) - 1e-5 * size / far - 2e-7 {
            bad.push(format!("case {k} {t:?}: box depth {box_z} loose below {}", exact / far));
        }
        // distance_to_triangle alone (Ericson's regions): exact but on slivers, whose face case divides by
        // a vanishing area; the box takes the edges' distances too.
        if (dist - exact).abs() > 1e-5 * size && k < 2400 && k % 6 != 5 {
            bad.push(format!("case {k} {t:?}: distance {dist}, f64 {exact}"));
        }
        // The VPLs: no texel's point nearer the light than the triangle's nearest point, within the box's
        // margin (a texel's t may fall short by that much before the lift and the barycentric point).
        if n_hits > 0 && (placed[k] as f64) * far < exact * (1.0 - 2e-4) - 1e-5 * size {
            let p = placed[k] as f64 * far;
            bad.push(format!("case {k} {t:?}: a texel's point at {p}, nearer than the triangle's {exact}"));
        }
        if n_hits > 0 && least < box_z {
            lifted += 1;
            worst_short = worst_short.max(1.0 - least / box_z);
        }
    }
    eprintln!(
        "map depth: {} triangles, {hits} of {rays} rays at the first 2400 hit; {lifted} triangles had a texel nearer than the box \
         (lifted; worst {:.2} % short)",
        tris.len(),
        100.0 * worst_short
    );
    assert!(bad.is_empty(), "{} bad cases: {}", bad.len(), bad[..bad.len().min(6)].join("\n"));
    assert!(hits * 10 > rays * 9, "only {hits} of {rays} rays hit their triangles: the rays are not aimed at them");
}

/// Solid angle of triangle (a, b, c) seen from the origin (Van Oosterom and Strackee 1983).
fn triangle_solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * a.dot(b.cross(c)).abs().atan2(den)
}

/// The VPLs' places in their texels are random (`Keys::vpl_offset`), so the VPL sum's mean over seeds is
/// the integral over the light's directions, where the texel centres' sum is a quadrature with an error of
/// its own. Here the integrand is 1 on a triangle a few texels wide: Σ Δω over its VPLs against its
/// solid angle in closed form, over 256 seeds. The centres' sum (on the CPU, as the maps held it before)
/// is off by far more than the test's tolerance, so the test can see that error come back.
#[test]
fn the_vpls_solid_angles_are_unbiased_over_seeds() {
    let v = |x: f32, y: f32| Vec3::new(x, y, 1.0);
    let tri = [v(0.1, 0.05), v(0.9, 0.2), v(0.3, 0.7)];
    let camera = Camera { eye: Vec3::new(0.0, 0.0, -1.0), target: Vec3::ZERO, up: Vec3::Y, fov_y_deg: 60.0 };
    let scene = Scene::from_triangles(&[tri], &[Vec3::splat(0.5)], camera, &[point_light(Vec3::ZERO, Vec3::ONE)]);
    let exact = triangle_solid_angle(tri[0].as_dvec3(), tri[1].as_dvec3(), tri[2].as_dvec3());
    let res = 24u32;
    let gpu = TestGpu::new();
    let r = Renderer::new(&gpu, &scene).unwrap();
    let sums: Vec<f64> = (1..=256u64)
        .map(|seed| {
            let s = FrameSettings {
                dprsm_res: res,
                seed,
                method: Method::Uniform,
                component: Component::Direct,
                ..FrameSettings::default()
            };
            let [pos, _, flux] = bounce_tests::maps::render_vpls(&r, &s).unwrap();
            pos.iter().zip(&flux).filter(|(p, _)| p[3] != 0.0).map(|(_, f)| f[3] as f64).sum()
        })
        .collect();
    let n = sums.len() as f64;
    let mean = sums.iter().sum::<f64>() / n;
    let se = (sums.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
    // The texel centres' sum: the directions through the centres of face 0 that hit the triangle.
    let bvh = Bvh::new(&scene);
    let n_res = res as usize;
    let mut centres = 0.0;
    for j in 0..n_res {
        for i in 0..n_res {
            let (u, v) = texel_uv(i, j, n_res, [0.5; 2], 0.0, 0.0);
            let r2 = u * u + v * v;
            if r2 <= 1.0 && bvh.intersect(DVec3::ZERO, paraboloid_dir((u, v), 0)).is_some() {
                centres += 4.0 / ((1.0 + r2) * (1.0 + r2)) * (2.0 / res as f64).powi(2);
            }
        }
    }
    eprintln!(
        "Ω = {exact:.5}: VPLs over 256 seeds {mean:.5} ± {se:.5} (per seed {:.5}..{:.5}); texel centres {centres:.5}",
        sums.iter().cloned().fold(f64::MAX, f64::min),
        sums.iter().cloned().fold(f64::MIN, f64::max)
    );
    assert!(se > 0.0, "every seed gave the same VPLs: the places are not random");
    assert!((mean - exact).abs() < 4.0 * se, "mean {mean} ± {se} against Ω = {exact}");
    // The test could see the centres' error: it is many standard errors.
    assert!((centres - exact).abs() > 8.0 * se, "the centres' sum {centres} is within 8 se {se} of Ω = {exact}");
}
