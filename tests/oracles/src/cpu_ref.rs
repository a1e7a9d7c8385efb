//! An exact CPU reference for the *direct* lighting component, used to check the GPU passes
//! pixel by pixel, and a Monte Carlo one-bounce reference ([`indirect_at_pixel`]). It owns the f64
//! ray casting through the renderer's SAH tree ([`Trace`] on [`Bvh`]: Möller–Trumbore and slab tests
//! in f64, its own traversal) and the shading contract:
//!
//! * every surface is two-sided Lambertian, BRDF = albedo / π;
//! * albedo = Kd × `map_Kd` texel, sRGB-decoded, NEAREST filtering, repeat wrap, v flipped
//!   (see [`texel_coords`]);
//! * shading normal = barycentric interpolation of the vertex normals, normalized, flipped to face
//!   the camera (`dot(n, eye − x) < 0 ? −n : n`);
//! * `direct(x) = Σ_l albedo/π · I_l · max(0, dot(n, l̂)) / d² · V(x, l)`, with `V` a hard
//!   visibility test of the segment x → light ([`Trace::occluded`]);
//! * a camera ray that hits nothing gives 0.
//!
//! Everything geometric is done in f64 so that the reference is limited by the scene's f32 data,
//! not by its own arithmetic: differences against the GPU are then the GPU's. The tree is the
//! renderer's ([`bounce_scene::bvh::build`]): only which triangles are tested depends on it, and the
//! brute-force comparison in the unit tests checks that the traversal misses none.
//!
//! Used by the integration tests and `tests/src/bin/make_references.rs`.

pub use bounce_scene::bvh::Bvh;
use bounce_scene::bvh::{BvhNode, BvhTri, MEDIAN_DEPTH};
use bounce_scene::scene::Scene;
use glam::{DVec3, Vec2, Vec3};

/// Relative epsilon of segment visibility tests: [`Trace::occluded`] only counts hits with
/// `t ∈ (SHADOW_EPS, 1 − SHADOW_EPS)` of the segment. It is the renderer's
/// ([`bounce_scene::bvh::SHADOW_EPS`], `BVH_SHADOW_EPS` of `bindings.glsl`) before its rounding to f32
/// (in f64 here, because the reference tests segments in f64; `tests/tests/bvh.rs` checks that the two
/// agree).
/// Relative (not absolute) so it scales with the scene: it keeps the origin's own triangle (hit at
/// `t ≈ 1e-12` since the origin is computed on it in f64) and a light lying on a surface from
/// occluding, while an occluder closer than 0.01 % of the segment length to either end is ignored.
pub const SHADOW_EPS: f64 = 1e-4;

/// Largest angle (degrees) between the shading normals of the centre and a corner hit of a
/// pixel before the pixel counts as a geometry edge (see [`DirectSample::shadow_edge`]).
pub const EDGE_NORMAL_DEG: f64 = 5.0;

/// Largest distance of a corner hit from the centre hit's plane, relative to the centre hit
/// distance, before the pixel counts as a depth edge (see [`DirectSample::shadow_edge`]).
pub const EDGE_PLANE_REL: f64 = 1e-3;

/// Traversal stack entries: the SAH build's height is at most `MEDIAN_DEPTH + 32`.
const STACK: usize = MEDIAN_DEPTH + 40;

/// A ray–triangle hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter: the hit is at `origin + t · dir` (in units of `|dir|`).
    pub t: f64,
    /// Triangle index (vertices `3·tri .. 3·tri+3` of the scene).
    pub tri: u32,
    /// Weights of the triangle's vertices 0, 1, 2 (they sum to 1).
    pub barycentrics: DVec3,
}

/// Exact f64 ray casting through the renderer's tree. Zero-area triangles are never hit (the build
/// leaves them out).
pub trait Trace {
    /// Closest hit along the ray `origin + t · dir`, `t > 0` (`dir` need not be unit; `t` is in
    /// units of `|dir|`). Ties at exactly equal `t` (coplanar duplicates, shared edges) go to
    /// the lower triangle index, so the result does not depend on the traversal order.
    fn intersect(&self, origin: DVec3, dir: DVec3) -> Option<Hit>;
    /// Closest hit with `t ∈ (t_min, t_max]`; tie rule as in [`Trace::intersect`].
    fn intersect_range(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<Hit>;
    /// The same as [`Trace::intersect`] by testing every triangle: O(n), for tests of the BVH.
    fn intersect_brute_force(&self, origin: DVec3, dir: DVec3) -> Option<Hit>;
    /// Whether any triangle blocks the open segment `origin → target`, both ends excluded:
    /// only hits with segment parameter `t ∈ (SHADOW_EPS, 1 − SHADOW_EPS)` count (see
    /// [`SHADOW_EPS`]).
    fn occluded(&self, origin: DVec3, target: DVec3) -> bool;
}

impl Trace for Bvh {
    fn intersect(&self, origin: DVec3, dir: DVec3) -> Option<Hit> {
        self.intersect_range(origin, dir, 0.0, f64::INFINITY)
    }

    fn intersect_range(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        traverse(self, origin, dir, t_min, t_max, |k, t, u, v, cur_max| {
            let better = match &best {
                None => true,
                Some(b) => t < b.t || (t == b.t && k < b.tri),
            };
            if better {
                best = Some(Hit { t, tri: k, barycentrics: DVec3::new(1.0 - u - v, u, v) });
                Some(t)
            } else {
                Some(cur_max)
            }
        });
        best
    }

    fn intersect_brute_force(&self, origin: DVec3, dir: DVec3) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        for &k in self.leaf_order() {
            if let Some((t, u, v)) = hit_tri(&self.triangles()[k as usize], origin, dir) {
                if t <= 0.0 {
                    continue;
                }
                let better = match &best {
                    None => true,
                    Some(b) => t < b.t || (t == b.t && k < b.tri),
                };
                if better {
                    best = Some(Hit { t, tri: k, barycentrics: DVec3::new(1.0 - u - v, u, v) });
                }
            }
        }
        best
    }

    fn occluded(&self, origin: DVec3, target: DVec3) -> bool {
        let d = target - origin;
        let mut blocked = false;
        traverse(self, origin, d, SHADOW_EPS, 1.0 - SHADOW_EPS, |_, t, _, _, _| {
            if t < 1.0 - SHADOW_EPS {
                blocked = true;
                None
            } else {
                Some(1.0 - SHADOW_EPS)
            }
        });
        blocked
    }
}

/// Möller–Trumbore in f64: `(t, u, v)` with `u`, `v` the weights of vertices 1 and 2, or
/// `None` for a miss, a parallel ray or any NaN. Edges and vertices count as inside, so a ray
/// through a shared edge hits at least one of the two triangles.
fn hit_tri(tri: &BvhTri, o: DVec3, d: DVec3) -> Option<(f64, f64, f64)> {
    let p = d.cross(tri.e2);
    let det = tri.e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - tri.p0;
    let u = s.dot(p) * inv;
    if u.is_nan() || !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(tri.e1);
    let v = d.dot(q) * inv;
    if v.is_nan() || v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = tri.e2.dot(q) * inv;
    t.is_finite().then_some((t, u, v))
}

/// Slab test in f64. Returns the entry distance if the ray segment `(t_min, t_max)` meets
/// the box. `t_max` is inflated by a few ulps (PBRT's conservative trick) so that rounding
/// never culls a hit lying on the box boundary (flat boxes of axis-aligned walls are common).
#[inline]
fn hit_box(node: &BvhNode, o: DVec3, inv_d: DVec3, t_min: f64, t_max: f64) -> Option<f64> {
    let t0 = (node.lo - o) * inv_d;
    let t1 = (node.hi - o) * inv_d;
    let mut near = t_min;
    let mut far = t_max;
    for a in 0..3 {
        // NaN (0 · ∞: origin on a slab plane, ray parallel to it) is ignored by min/max,
        // which treats the ray as inside that slab.
        let (lo, hi) = (t0[a].min(t1[a]), t0[a].max(t1[a]));
        near = near.max(lo);
        far = far.min(hi * (1.0 + 4.0 * f64::EPSILON));
    }
    (near <= far).then_some(near)
}

/// Visits every triangle whose node the ray segment `(t_min, t_max)` may touch, in
/// front-to-back-ish order. `visit(tri_index, t, u, v, t_max)` is called for every triangle hit with
/// `t ∈ (t_min, t_max_current)`; it returns the new upper bound (to shrink the search) or
/// `None` to stop the traversal.
fn traverse(
    bvh: &Bvh,
    o: DVec3,
    d: DVec3,
    t_min: f64,
    mut t_max: f64,
    mut visit: impl FnMut(u32, f64, f64, f64, f64) -> Option<f64>,
) {
    let (nodes, order, tris) = (bvh.nodes(), bvh.leaf_order(), bvh.triangles());
    if order.is_empty() {
        return;
    }
    let inv_d = DVec3::ONE / d;
    let mut stack = [0u32; STACK];
    let mut sp = 0usize;
    let mut node = 0usize;
    loop {
        let n = &nodes[node];
        if hit_box(n, o, inv_d, t_min, t_max).is_some() {
            if n.count > 0 {
                for &k in &order[n.first as usize..(n.first + n.count) as usize] {
                    if let Some((t, u, v)) = hit_tri(&tris[k as usize], o, d) {
                        if t > t_min && t <= t_max {
                            match visit(k, t, u, v, t_max) {
                                Some(new_max) => t_max = new_max,
                                None => return,
                            }
                        }
                    }
                }
            } else {
                // Visit the nearer child first.
                let l = n.first as usize;
                let (tl, tr) =
                    (hit_box(&nodes[l], o, inv_d, t_min, t_max), hit_box(&nodes[l + 1], o, inv_d, t_min, t_max));
                match (tl, tr) {
                    (Some(a), Some(b)) => {
                        let (first, second) = if a <= b { (l, l + 1) } else { (l + 1, l) };
                        stack[sp] = second as u32;
                        sp += 1;
                        node = first;
                        continue;
                    }
                    (Some(_), None) => {
                        node = l;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = l + 1;
                        continue;
                    }
                    (None, None) => {}
                }
            }
        }
        if sp == 0 {
            return;
        }
        sp -= 1;
        node = stack[sp] as usize;
    }
}

/// sRGB transfer function decode of one channel in [0, 1].
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// GLSL `fract`: `x − floor(x)` (Rust's `f32::fract` truncates toward zero instead, which is
/// wrong for negative coordinates under repeat wrapping).
fn fract(x: f32) -> f32 {
    x - x.floor()
}

/// The texel NEAREST sampling with repeat wrap reads for texture coordinate `uv` of a `w×h`
/// texture: `x = floor(fract(u) · w)`, `y = floor(fract(1 − v) · h)`, each clamped to the last
/// texel (fract can round up to 1.0). v is flipped because OBJ v = 0 is the bottom of the image
/// while texel row 0 is its top row.
pub fn texel_coords(uv: Vec2, w: u32, h: u32) -> (u32, u32) {
    let x = ((fract(uv.x) * w as f32).floor() as u32).min(w.saturating_sub(1));
    let y = ((fract(1.0 - uv.y) * h as f32).floor() as u32).min(h.saturating_sub(1));
    (x, y)
}

/// Linear albedo of material `material` at texture coordinate `uv` (Kd × decoded texel).
pub fn albedo(scene: &Scene, material: u32, uv: Vec2) -> Vec3 {
    let Some(m) = scene.materials.get(material as usize) else {
        return Vec3::splat(bounce_scene::scene::DEFAULT_ALBEDO);
    };
    let kd = m.kd();
    let Some(info) = m.texture().and_then(|t| scene.textures.get(t)) else {
        return kd;
    };
    if info.width == 0 || info.height == 0 {
        return kd;
    }
    let (x, y) = texel_coords(uv, info.width, info.height);
    let idx = info.offset as usize + (y as usize * info.width as usize) + x as usize;
    let Some(&texel) = scene.texels.get(idx) else {
        return kd;
    };
    let [r, g, b, _] = texel.to_le_bytes();
    let lin = |c: u8| srgb_to_linear(c as f32 / 255.0);
    kd * Vec3::new(lin(r), lin(g), lin(b))
}

/// A shaded surface point.
#[derive(Clone, Copy, Debug)]
struct Surface {
    x: DVec3,
    /// Shading normal, flipped toward the eye.
    n: DVec3,
    /// Geometric normal, flipped toward the eye.
    ng: DVec3,
    albedo: Vec3,
}

fn surface(scene: &Scene, bvh: &Bvh, hit: &Hit, eye: DVec3) -> Surface {
    let t = hit.tri as usize;
    let v = &scene.vertices[3 * t..3 * t + 3];
    let w = hit.barycentrics;
    let x = v[0].position().as_dvec3() * w.x + v[1].position().as_dvec3() * w.y + v[2].position().as_dvec3() * w.z;
    let tri = &bvh.triangles()[t];
    let mut ng = tri.e1.cross(tri.e2).normalize_or_zero();
    let interp = v[0].normal().as_dvec3() * w.x + v[1].normal().as_dvec3() * w.y + v[2].normal().as_dvec3() * w.z;
    let mut n = interp.normalize_or_zero();
    if n == DVec3::ZERO {
        n = ng;
    }
    let to_eye = eye - x;
    if n.dot(to_eye) < 0.0 {
        n = -n;
    }
    if ng.dot(to_eye) < 0.0 {
        ng = -ng;
    }
    let uv = v[0].uv().as_dvec2() * w.x + v[1].uv().as_dvec2() * w.y + v[2].uv().as_dvec2() * w.z;
    let material = scene.tri_material.get(t).copied().unwrap_or(u32::MAX);
    Surface { x, n, ng, albedo: albedo(scene, material, uv.as_vec2()) }
}

/// `x` moved off its surface along unit `n` by 1e-6 of its scale: a ray's start that its own triangle
/// cannot block.
fn lift_off(x: DVec3, n: DVec3) -> DVec3 {
    x + n * (1e-6 * (1.0 + x.abs().max_element()))
}

/// Direct radiance toward the eye at `s`, and the bit mask of lights that reach it
/// (front-facing and unoccluded).
fn shade(scene: &Scene, bvh: &Bvh, s: &Surface) -> (Vec3, u32) {
    shade_from(scene, bvh, s, false)
}

/// [`shade`], with `lifted`: each shadow ray starts from `s` lifted toward the light's side of its
/// surface and counts every occluder but within 1e-9 of the segment's ends, as the path tracer's light
/// side does (`glsl/reference.comp`). For bounce points: on the surface with the [`SHADOW_EPS`] window, a
/// wall between a point at its foot and the light fell inside the window, and light leaked under it.
fn shade_from(scene: &Scene, bvh: &Bvh, s: &Surface, lifted: bool) -> (Vec3, u32) {
    let mut sum = DVec3::ZERO;
    let mut lit = 0u32;
    let brdf = s.albedo.as_dvec3() / std::f64::consts::PI;
    for (k, l) in scene.lights.iter().enumerate() {
        let lp = DVec3::new(l.position[0] as f64, l.position[1] as f64, l.position[2] as f64);
        let to = lp - s.x;
        let d2 = to.length_squared();
        if d2 <= 0.0 {
            continue;
        }
        let cos = s.n.dot(to) / d2.sqrt();
        let blocked = if lifted {
            let start = lift_off(s.x, if s.ng.dot(to) >= 0.0 { s.ng } else { -s.ng });
            bvh.intersect_range(start, lp - start, 1e-9, 1.0 - 1e-9).is_some()
        } else {
            bvh.occluded(s.x, lp)
        };
        if cos <= 0.0 || blocked {
            continue;
        }
        lit |= 1 << k.min(31);
        let i = DVec3::new(l.intensity[0] as f64, l.intensity[1] as f64, l.intensity[2] as f64);
        sum += brdf * i * (cos / d2);
    }
    (sum.as_vec3(), lit)
}

/// The reference result for one pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectSample {
    /// Direct radiance toward the camera (linear RGB).
    pub radiance: Vec3,
    /// World position of the primary hit.
    pub position: Vec3,
    /// Shading normal, flipped to face the camera.
    pub normal: Vec3,
    /// Linear albedo (Kd × texel).
    pub albedo: Vec3,
    /// Triangle hit by the centre ray.
    pub tri: u32,
    /// True when the pixel must be excluded from a per-pixel GPU-vs-CPU comparison because its
    /// footprint straddles a discontinuity that the rasterizer and the reference may resolve
    /// differently. The footprint is probed at its four corners (continuous pixel coordinates
    /// `(i, j)`, `(i+1, j)`, `(i, j+1)`, `(i+1, j+1)`, i.e. ±0.5 px from the centre); the pixel is
    /// an edge when, for any corner:
    /// * the corner ray hits nothing while the centre ray hits (silhouette);
    /// * the shading normals (flipped to the camera) of the centre and corner hits differ by
    ///   more than [`EDGE_NORMAL_DEG`] (a crease, or a different surface). Shading rather than
    ///   triangle normals: for a flat-shaded mesh they are the same thing, while a smooth-shaded
    ///   (`vn`) tessellation has no radiance discontinuity at its triangle edges and flagging them
    ///   would exclude most pixels of a finely tessellated model;
    /// * the corner hit lies off the centre hit's plane by more than [`EDGE_PLANE_REL`] × the
    ///   centre hit distance (a surface at another depth with a similar normal, e.g. a box top
    ///   over the floor);
    /// * the set of lights that reach the point (front-facing and unoccluded) differs between the
    ///   centre and the corner (shadow boundary or terminator).
    ///
    /// Texture (texel-boundary) and material boundaries are *not* flagged: both sides evaluate
    /// at the pixel centre.
    pub shadow_edge: bool,
}

fn primary_ray(scene: &Scene, x: f32, y: f32, w: u32, h: u32) -> (DVec3, DVec3) {
    let eye = scene.camera.eye.as_dvec3();
    let dir = scene.camera.ray_dir_f(x, y, w, h).as_dvec3().normalize();
    (eye, dir)
}

/// The reference for pixel `(i, j)` of a `w×h` image (centre ray), or `None` when the centre ray
/// hits nothing (radiance 0). See [`DirectSample::shadow_edge`] for the edge rule.
pub fn direct_at_pixel(scene: &Scene, bvh: &Bvh, i: u32, j: u32, w: u32, h: u32) -> Option<DirectSample> {
    let (eye, dir) = primary_ray(scene, i as f32 + 0.5, j as f32 + 0.5, w, h);
    let hit = bvh.intersect(eye, dir)?;
    let s = surface(scene, bvh, &hit, eye);
    let (radiance, lit) = shade(scene, bvh, &s);

    let cos_edge = EDGE_NORMAL_DEG.to_radians().cos();
    let mut edge = false;
    for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
        let (o, d) = primary_ray(scene, i as f32 + dx, j as f32 + dy, w, h);
        let Some(ch) = bvh.intersect(o, d) else {
            edge = true;
            break;
        };
        let cs = surface(scene, bvh, &ch, eye);
        if cs.n.dot(s.n) < cos_edge
            || s.ng.dot(cs.x - s.x).abs() > EDGE_PLANE_REL * hit.t
            || shade(scene, bvh, &cs).1 != lit
        {
            edge = true;
            break;
        }
    }

    Some(DirectSample {
        radiance,
        position: s.x.as_vec3(),
        normal: s.n.as_vec3(),
        albedo: s.albedo,
        tri: hit.tri,
        shadow_edge: edge,
    })
}

/// Direct radiance of pixel `(i, j)` (centre ray only, no edge classification); 0 on a miss.
pub fn direct_radiance_at_pixel(scene: &Scene, bvh: &Bvh, i: u32, j: u32, w: u32, h: u32) -> Vec3 {
    let (eye, dir) = primary_ray(scene, i as f32 + 0.5, j as f32 + 0.5, w, h);
    match bvh.intersect(eye, dir) {
        Some(hit) => shade(scene, bvh, &surface(scene, bvh, &hit, eye)).0,
        None => Vec3::ZERO,
    }
}

/// Runs `f(i, j)` for every pixel of a `w×h` image on all cores; row-major, row 0 = top.
/// Rows are dealt out in small chunks round-robin so that expensive regions spread over threads.
fn per_pixel<T: Send + Clone + Default>(w: u32, h: u32, f: impl Fn(u32, u32) -> T + Sync) -> Vec<T> {
    let mut out = vec![T::default(); w as usize * h as usize];
    if out.is_empty() {
        return out;
    }
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(64);
    let rows_per_chunk = (h as usize).div_ceil(threads * 8).max(1);
    let mut buckets: Vec<Vec<(usize, &mut [T])>> = (0..threads).map(|_| Vec::new()).collect();
    for (ci, chunk) in out.chunks_mut(rows_per_chunk * w as usize).enumerate() {
        buckets[ci % threads].push((ci * rows_per_chunk, chunk));
    }
    let f = &f;
    std::thread::scope(|scope| {
        for bucket in buckets {
            scope.spawn(move || {
                for (j0, rows) in bucket {
                    for (k, px) in rows.iter_mut().enumerate() {
                        let (i, j) = ((k % w as usize) as u32, (j0 + k / w as usize) as u32);
                        *px = f(i, j);
                    }
                }
            });
        }
    });
    out
}

/// The reference direct image of a `w×h` render: row-major, row 0 = top, linear RGB radiance
/// (0 where the camera ray misses). Builds its own BVH; use [`render_direct_with`] to reuse one.
pub fn render_direct(scene: &Scene, w: u32, h: u32) -> Vec<[f32; 3]> {
    render_direct_with(scene, &Bvh::new(scene), w, h)
}

/// [`render_direct`] with a prebuilt BVH.
pub fn render_direct_with(scene: &Scene, bvh: &Bvh, w: u32, h: u32) -> Vec<[f32; 3]> {
    per_pixel(w, h, |i, j| direct_radiance_at_pixel(scene, bvh, i, j, w, h).to_array())
}

/// [`direct_at_pixel`] for every pixel (row-major, row 0 = top), on all cores.
pub fn sample_image(scene: &Scene, bvh: &Bvh, w: u32, h: u32) -> Vec<Option<DirectSample>> {
    per_pixel(w, h, |i, j| direct_at_pixel(scene, bvh, i, j, w, h))
}

/// A small PCG32 stream for the Monte Carlo reference (deterministic per pixel and seed).
struct Pcg(u64);

impl Pcg {
    fn new(i: u32, j: u32, seed: u64) -> Pcg {
        let mut p = Pcg((u64::from(i) << 32 | u64::from(j)) ^ seed.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        p.next();
        p.next();
        p
    }
    fn next(&mut self) -> u32 {
        let old = self.0;
        self.0 = old.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }
    /// Uniform in [0, 1) with 32 bits.
    fn uniform(&mut self) -> f64 {
        self.next() as f64 * (1.0 / 4294967296.0)
    }
}

/// One-bounce indirect radiance at pixel (i, j), by Monte Carlo with `spp` cosine-distributed bounce
/// rays around the shading normal, traced exactly (BVH) to the first hit y, whose direct light (normal
/// flipped toward x, exact shadow rays) is the incoming radiance:
///   L_ind(x) = ∫ albedo(x)/π · L_direct(y → x) cos θ dω ≈ albedo(x) · 1/spp Σ L_direct(y_k → x)
/// (the cosine pdf cos θ/π cancels the BRDF's 1/π and the cosine). Independent of everything on the
/// GPU: the reference the VPL estimate converges to. Returns (mean, standard error of the mean).
pub fn indirect_at_pixel(
    scene: &Scene,
    bvh: &Bvh,
    i: u32,
    j: u32,
    w: u32,
    h: u32,
    spp: u32,
    seed: u64,
) -> (Vec3, Vec3) {
    let (eye, dir) = primary_ray(scene, i as f32 + 0.5, j as f32 + 0.5, w, h);
    let Some(hit) = bvh.intersect(eye, dir) else { return (Vec3::ZERO, Vec3::ZERO) };
    let s = surface(scene, bvh, &hit, eye);
    // An orthonormal frame around the shading normal.
    let n = s.n;
    let t = if n.x.abs() > 0.9 { DVec3::Y } else { DVec3::X }.cross(n).normalize();
    let b = n.cross(t);
    let mut rng = Pcg::new(i, j, seed);
    let (mut sum, mut sum2) = (DVec3::ZERO, DVec3::ZERO);
    let origin = lift_off(s.x, s.ng);
    for _ in 0..spp {
        // Cosine-distributed direction (Malley's method).
        let (u1, u2) = (rng.uniform(), rng.uniform());
        let r = u1.sqrt();
        let phi = 2.0 * std::f64::consts::PI * u2;
        let d = t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt();
        let value = match bvh.intersect(origin, d) {
            Some(hy) => {
                let y = surface(scene, bvh, &hy, s.x);
                let (l, _) = shade_from(scene, bvh, &y, true);
                l.as_dvec3()
            }
            None => DVec3::ZERO,
        };
        sum += value;
        sum2 += value * value;
    }
    let k = spp.max(1) as f64;
    let mean = sum / k;
    let var = (sum2 / k - mean * mean).max(DVec3::ZERO) / (k - 1.0).max(1.0);
    let a = s.albedo.as_dvec3();
    ((a * mean).as_vec3(), (a * var.map(f64::sqrt)).as_vec3())
}

/// [`indirect_at_pixel`] for every pixel, on all cores: (radiance, standard error) per pixel.
pub fn render_indirect(scene: &Scene, bvh: &Bvh, w: u32, h: u32, spp: u32, seed: u64) -> Vec<([f32; 3], [f32; 3])> {
    per_pixel(w, h, |i, j| {
        let (m, e) = indirect_at_pixel(scene, bvh, i, j, w, h, spp, seed);
        (m.to_array(), e.to_array())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use bounce_scene::camera::Camera;
    use bounce_scene::layout::{Material, TextureInfo, Vertex};
    use bounce_scene::scene::point_light;
    use std::f32::consts::PI;

    /// A 20×20 floor quad at y = 0 (two triangles, counter-clockwise seen from +y).
    fn floor() -> Vec<[Vec3; 3]> {
        let (a, b, c, d) = (
            Vec3::new(-10.0, 0.0, -10.0),
            Vec3::new(10.0, 0.0, -10.0),
            Vec3::new(10.0, 0.0, 10.0),
            Vec3::new(-10.0, 0.0, 10.0),
        );
        vec![[a, c, b], [a, d, c]]
    }

    fn floor_scene(h: f32, intensity: f32, blocker: bool) -> Scene {
        let mut tris = floor();
        if blocker {
            // Small triangle halfway up, around the light's axis; clear of the camera ray.
            let y = h * 0.5;
            tris.push([Vec3::new(-0.3, y, -0.3), Vec3::new(0.3, y, -0.3), Vec3::new(0.0, y, 0.3)]);
        }
        let albedo = vec![Vec3::splat(0.5); tris.len()];
        let camera = Camera { eye: Vec3::new(2.0, 3.0, 0.0), target: Vec3::ZERO, up: Vec3::Y, fov_y_deg: 40.0 };
        let light = point_light(Vec3::new(0.0, h, 0.0), Vec3::splat(intensity));
        Scene::from_triangles(&tris, &albedo, camera, &[light])
    }

    #[test]
    fn floor_under_a_point_light_matches_the_closed_form() {
        let (h, i) = (1.5f32, 4.0f32);
        let scene = floor_scene(h, i, false);
        let bvh = Bvh::new(&scene);
        // Odd size: the centre pixel's ray goes exactly through the target (0, 0, 0).
        let (w, hh) = (31, 21);
        let s = direct_at_pixel(&scene, &bvh, 15, 10, w, hh).expect("hits the floor");
        assert!(s.position.length() < 1e-5, "{:?}", s.position);
        assert_eq!(s.normal, Vec3::Y);
        let want = 0.5 / PI * i / (h * h);
        assert!((s.radiance - Vec3::splat(want)).abs().max_element() < 1e-6 * want.max(1.0));
        assert!(!s.shadow_edge);
        // Any other pixel: the general formula at the returned hit point.
        let s = direct_at_pixel(&scene, &bvh, 3, 17, w, hh).expect("hits the floor");
        let to = Vec3::new(0.0, h, 0.0) - s.position;
        let want = 0.5 / PI * i * (to.normalize().y) / to.length_squared();
        assert!((s.radiance.x - want).abs() < 1e-5 * want, "{} vs {want}", s.radiance.x);
        assert_eq!(direct_radiance_at_pixel(&scene, &bvh, 3, 17, w, hh), s.radiance);
        // render_direct agrees with the per-pixel call, row 0 = top.
        let img = render_direct(&scene, w, hh);
        assert_eq!(img.len(), (w * hh) as usize);
        assert_eq!(img[(17 * w + 3) as usize], s.radiance.to_array());
    }

    #[test]
    fn a_blocker_casts_a_shadow_with_edges() {
        let scene = floor_scene(1.5, 4.0, true);
        let bvh = Bvh::new(&scene);
        let (w, h) = (31, 21);
        let s = direct_at_pixel(&scene, &bvh, 15, 10, w, h).expect("hits the floor");
        assert!(s.position.length() < 1e-5, "camera ray not blocked: {:?}", s.position);
        assert_eq!(s.radiance, Vec3::ZERO);
        assert!(!s.shadow_edge, "the shadow centre is uniform");
        // Walk right from the centre until lit: the boundary pixel is flagged.
        let mut saw_edge = false;
        let mut lit_clear = false;
        for i in 16..31 {
            let p = direct_at_pixel(&scene, &bvh, i, 10, w, h).expect("floor");
            if p.shadow_edge {
                saw_edge = true;
            } else if p.radiance.x > 0.0 {
                lit_clear = true;
                break;
            }
        }
        assert!(saw_edge && lit_clear);
        // Pixels that miss the scene entirely are None / 0.
        let sky = Scene::from_triangles(
            &floor(),
            &[Vec3::ONE; 2],
            Camera { eye: Vec3::new(0.0, 1.0, 0.0), target: Vec3::new(0.0, 2.0, 1.0), up: Vec3::Y, fov_y_deg: 30.0 },
            &scene.lights,
        );
        let sky_bvh = Bvh::new(&sky);
        assert!(direct_at_pixel(&sky, &sky_bvh, 5, 5, 11, 11).is_none());
        assert_eq!(render_direct(&sky, 11, 11)[60], [0.0; 3]);
    }

    #[test]
    fn silhouettes_are_edges() {
        // A small square floating over the floor, seen from above: its border pixels are edges.
        let mut tris = floor();
        let (a, b, c, d) = (
            Vec3::new(-0.5, 0.5, -0.5),
            Vec3::new(0.5, 0.5, -0.5),
            Vec3::new(0.5, 0.5, 0.5),
            Vec3::new(-0.5, 0.5, 0.5),
        );
        tris.push([a, c, b]);
        tris.push([a, d, c]);
        let camera = Camera { eye: Vec3::new(0.0, 5.0, 0.0), target: Vec3::ZERO, up: Vec3::NEG_Z, fov_y_deg: 30.0 };
        // The light is far to the side, so the square's shadow falls outside the view.
        let light = point_light(Vec3::new(40.0, 3.0, 0.0), Vec3::splat(100.0));
        let scene = Scene::from_triangles(&tris, &[Vec3::splat(0.5); 4], camera, &[light]);
        let bvh = Bvh::new(&scene);
        let n = 64;
        let img = sample_image(&scene, &bvh, n, n);
        let on_square = |s: &DirectSample| (s.position.y - 0.5).abs() < 1e-4;
        let mut edges = 0;
        for j in 1..n - 1 {
            for i in 1..n - 1 {
                let s = img[(j * n + i) as usize].expect("everything hits");
                // A pixel is interior when its whole 3×3 neighbourhood sees the same surface.
                let same = (j - 1..=j + 1).all(|y| {
                    (i - 1..=i + 1).all(|x| on_square(&img[(y * n + x) as usize].expect("hit")) == on_square(&s))
                });
                if same {
                    assert!(!s.shadow_edge, "interior pixel {i},{j} flagged");
                } else {
                    edges += 1;
                }
            }
        }
        assert!(edges > 0);
        let flagged = img.iter().flatten().filter(|s| s.shadow_edge).count();
        // Every boundary pixel on at least one side is flagged (the two sides of the silhouette).
        assert!(flagged >= edges / 2, "{flagged} flagged, {edges} boundary pixels");
    }

    #[test]
    fn textured_albedo_is_nearest_repeat_and_v_flipped() {
        // 2×2 texture: row 0 (top) red, green; row 1 (bottom) blue, white (sRGB 255 / 128).
        let texels = [[255u8, 0, 0, 255], [0, 255, 0, 255], [0, 0, 128, 255], [255, 255, 255, 255]]
            .map(u32::from_le_bytes)
            .to_vec();
        let v = |p: [f32; 3], uv: [f32; 2]| Vertex {
            position_u: [p[0], p[1], p[2], uv[0]],
            normal_v: [0.0, 1.0, 0.0, uv[1]],
        };
        let vertices =
            vec![v([0.0, 0.0, 0.0], [0.0, 0.0]), v([1.0, 0.0, 0.0], [1.0, 0.0]), v([0.0, 0.0, -1.0], [0.0, 1.0])];
        let scene = Scene::from_raw(
            vertices,
            vec![0],
            vec![Material { kd_tex: [0.5, 1.0, 1.0, 0.0] }],
            vec![TextureInfo { offset: 0, width: 2, height: 2, pad: 0 }],
            texels,
            Camera { eye: Vec3::new(0.0, 3.0, 0.0), target: Vec3::ZERO, up: Vec3::NEG_Z, fov_y_deg: 40.0 },
            vec![point_light(Vec3::Y, Vec3::ONE)],
        );
        // v small = bottom of the image = texel row 1.
        assert_eq!(texel_coords(Vec2::new(0.1, 0.1), 2, 2), (0, 1));
        assert_eq!(texel_coords(Vec2::new(0.9, 0.9), 2, 2), (1, 0));
        // Repeat wrap, negative coordinates included.
        assert_eq!(texel_coords(Vec2::new(-0.1, 1.1), 2, 2), (1, 1));
        assert_eq!(texel_coords(Vec2::new(2.6, -0.6), 2, 2), (1, 1));
        assert_eq!(texel_coords(Vec2::new(0.2, -0.7), 2, 2), (0, 1));
        // fract(-1e-9) rounds to 1.0 in f32: clamped to the last texel, never past it.
        assert_eq!(texel_coords(Vec2::new(-1e-9, 0.5), 2, 2), (1, 1));
        assert_eq!(texel_coords(Vec2::new(1.0 - 1e-9, 0.0), 2, 2), (0, 0));
        assert_eq!(texel_coords(Vec2::new(0.0, 0.0), 2, 2), (0, 0));

        let blue = srgb_to_linear(128.0 / 255.0);
        assert!((blue - 0.2158605).abs() < 1e-6);
        assert_eq!(albedo(&scene, 0, Vec2::new(0.1, 0.1)), Vec3::new(0.0, 0.0, blue));
        assert_eq!(albedo(&scene, 0, Vec2::new(0.1, 0.9)), Vec3::new(0.5, 0.0, 0.0));
        assert_eq!(albedo(&scene, 0, Vec2::new(0.9, 0.1)), Vec3::new(0.5, 1.0, 1.0));
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.04) - 0.04 / 12.92).abs() < 1e-9);
    }

    /// Deterministic xorshift for the randomized tests (no rand dependency).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn dir(&mut self) -> DVec3 {
            loop {
                let v = DVec3::new(self.next(), self.next(), self.next()) * 2.0 - 1.0;
                let l = v.length();
                if l > 1e-3 && l <= 1.0 {
                    return v / l;
                }
            }
        }
    }

    fn check_bvh_against_brute_force(scene: &Scene, rays: usize, seed: u64) -> usize {
        let bvh = Bvh::new(scene);
        let mut rng = Rng(seed);
        let (lo, hi) = (scene.bounds_min.as_dvec3(), scene.bounds_max.as_dvec3());
        let pad = (hi - lo) * 0.2;
        let mut hits = 0;
        for _ in 0..rays {
            let o = lo - pad + DVec3::new(rng.next(), rng.next(), rng.next()) * (hi - lo + 2.0 * pad);
            let d = rng.dir();
            let a = bvh.intersect(o, d);
            let b = bvh.intersect_brute_force(o, d);
            assert_eq!(a, b, "ray {o} {d}");
            hits += a.is_some() as usize;
            // occluded agrees with the closest hit on a segment of random length.
            let len = rng.next() * 4.0;
            let target = o + d * len;
            let want = b.is_some_and(|h| h.t > SHADOW_EPS * len && h.t < (1.0 - SHADOW_EPS) * len);
            if let Some(h) = b {
                // Skip segments ending within rounding of the hit.
                if (h.t - len).abs() < 1e-6 || h.t <= SHADOW_EPS * len * 1.01 {
                    continue;
                }
            }
            assert_eq!(bvh.occluded(o, target), want, "segment {o} -> {target}");
        }
        hits
    }

    #[test]
    fn bvh_matches_brute_force_on_the_cornell_box() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/cornell-box/scene.toml");
        let scene = bounce_scene::scene::load(&path).expect("cornell box loads");
        let hits = check_bvh_against_brute_force(&scene, 20_000, 0x9e3779b97f4a7c15);
        assert!(hits > 10_000, "{hits}");
    }

    #[test]
    fn bvh_matches_brute_force_on_a_triangle_soup() {
        let mut rng = Rng(12345);
        let mut tris = Vec::new();
        for _ in 0..3000 {
            let c = DVec3::new(rng.next(), rng.next(), rng.next()) * 10.0;
            let tri = [0, 1, 2].map(|_| (c + rng.dir() * (0.05 + rng.next() * 0.5)).as_vec3());
            tris.push(tri);
        }
        // Clustered duplicates and a degenerate triangle.
        tris.push(tris[0]);
        tris.push([Vec3::ONE; 3]);
        let camera = Camera { eye: Vec3::splat(-5.0), target: Vec3::splat(5.0), up: Vec3::Y, fov_y_deg: 60.0 };
        let scene = Scene::from_triangles(
            &tris,
            &vec![Vec3::splat(0.5); tris.len()],
            camera,
            &[point_light(Vec3::splat(5.0), Vec3::ONE)],
        );
        let hits = check_bvh_against_brute_force(&scene, 3000, 777);
        assert!(hits > 300, "{hits}");
    }

    #[test]
    fn cornell_box_direct_image_is_sane() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/cornell-box/scene.toml");
        let scene = bounce_scene::scene::load(&path).expect("cornell box loads");
        let bvh = Bvh::new(&scene);
        let n = 64;
        let img = render_direct_with(&scene, &bvh, n, n);
        let lum: Vec<f32> = img.iter().map(|p| (p[0] + p[1] + p[2]) / 3.0).collect();
        assert!(img.iter().flatten().all(|c| c.is_finite() && *c >= 0.0));
        let samples = sample_image(&scene, &bvh, n, n);
        // The box fills the view except for a thin ring around the open front (the view is
        // slightly taller than the box there); those rays miss and are 0 / None.
        for (k, s) in samples.iter().enumerate() {
            let (i, j) = ((k % n as usize) as u32, (k / n as usize) as u32);
            let border = i < 4 || j < 4 || i >= n - 4 || j >= n - 4;
            assert!(s.is_some() || border, "pixel {i},{j} misses");
            if s.is_none() {
                assert_eq!(img[k], [0.0; 3]);
            }
        }
        // Direct radiance of order 0.1 (hot spot on the ceiling right above the light aside).
        let mut sorted = lum.clone();
        sorted.sort_by(f32::total_cmp);
        let (median, p90) = (sorted[sorted.len() / 2], sorted[sorted.len() * 9 / 10]);
        assert!(median > 0.05 && median < 0.5, "median direct radiance {median}");
        assert!(p90 > 0.1 && p90 < 1.0, "90th percentile {p90}");
        // The boxes cast shadows: some pixels that hit get no direct light.
        let shadowed = samples.iter().flatten().filter(|s| s.radiance == Vec3::ZERO).count();
        assert!(shadowed > 100, "{shadowed}");
        // The left wall is red, the right wall green (image +x = camera right).
        let mid = (n / 2) as usize * n as usize;
        let left = img[mid + 2 + 4];
        let right = img[mid + n as usize - 1 - 6];
        assert!(left[0] > 2.0 * left[1], "{left:?}");
        assert!(right[1] > 2.0 * right[0], "{right:?}");
        // Edge pixels exist but are a minority.
        let edges = samples.iter().flatten().filter(|s| s.shadow_edge).count();
        assert!(edges > 0 && edges < (n * n / 4) as usize, "{edges}");
    }

    #[test]
    fn big_meshes_build_quickly() {
        // 200k triangles in a grid: the build must be fast even in the test profile.
        let m = 316;
        let mut tris = Vec::with_capacity(2 * m * m);
        for z in 0..m {
            for x in 0..m {
                let p = |dx: usize, dz: usize| {
                    let (fx, fz) = ((x + dx) as f32 * 0.01, (z + dz) as f32 * 0.01);
                    Vec3::new(fx, (fx * 7.0).sin() * (fz * 5.0).cos() * 0.1, fz)
                };
                tris.push([p(0, 0), p(1, 1), p(1, 0)]);
                tris.push([p(0, 0), p(0, 1), p(1, 1)]);
            }
        }
        let vertices: Vec<Vertex> = tris
            .iter()
            .flat_map(|t| t.map(|p| Vertex { position_u: [p.x, p.y, p.z, 0.0], normal_v: [0.0, 1.0, 0.0, 0.0] }))
            .collect();
        let start = std::time::Instant::now();
        let bvh = Bvh::from_vertices(&vertices);
        let secs = start.elapsed().as_secs_f64();
        assert!(secs < 20.0, "BVH build took {secs} s");
        assert!(bvh.node_count() > 1000);
        // A vertical ray through the middle hits the surface.
        let hit = bvh.intersect(DVec3::new(1.575, 5.0, 1.575), DVec3::NEG_Y).expect("hit");
        assert!((hit.t - 5.0).abs() < 0.2);
    }
}
