//! The scene contract (v1): parsing and validating a scene TOML file, loading its Wavefront OBJ mesh
//! (plus MTL materials and `map_Kd` textures), and flattening everything into the GPU-ready arrays
//! of [`Scene`] (the layouts of `glsl/shared/types.glsl`).
//!
//! A scene is a TOML file; relative paths in it are relative to the TOML file:
//! ```toml
//! mesh = "room.obj"            # Wavefront OBJ; its mtllib is read for materials
//! [camera]
//! eye    = [0.0, 1.0, 3.9]
//! target = [0.0, 1.0, 0.0]
//! up     = [0.0, 1.0, 0.0]
//! fov_y  = 39.3                # vertical field of view in degrees, across the full image height
//! [[light]]                    # isotropic point light; one to MAX_LIGHTS tables
//! position  = [0.0, 1.8, 0.0]
//! intensity = [5.0, 5.0, 5.0]  # radiant intensity, W/sr, linear RGB
//! [render]                     # optional defaults; the command line overrides
//! width  = 256
//! height = 256
//! ```
//! Every table rejects unknown keys: a typo (`fov = ...`) must fail loudly rather than silently
//! render a different image. All errors are [`SceneError`]s whose `Display` is one line naming
//! the offending file (and the line where one is known).
//!
//! Mesh rules: faces are triangulated as fans by tobj and flattened into a non-indexed triangle
//! list (triangle `t` owns vertices `3t..3t+3`). Normals come from `vn` when every corner of a
//! face has one (per tobj mesh, see [`load`]), else the face normal; zero-area triangles are kept
//! with a +Y normal (they are never hit but must not produce NaN). UVs are the raw OBJ `vt` values
//! (0 when absent); the consumers flip v (`texel row = floor(fract(1 − v) · height)`), since OBJ v=0 is
//! the bottom of the image while texel row 0 is its top.
//!
//! One file per format: `toml` parses and validates the scene file into a [`SceneDesc`]; `obj`
//! pre-scans and loads the mesh (tobj) and flattens it; `mtl` sanitises the material libraries and
//! builds the materials; `textures` decodes the `map_Kd` images. This file holds the [`Scene`], the
//! errors, and [`load`], which runs them in that order. Used by the renderer, the app and the tests.

mod mtl;
mod obj;
mod textures;
mod toml;

pub use self::toml::{parse_desc, SceneDesc, WorldPoints};

use crate::camera::Camera;
use crate::layout::{Light, Material, TextureInfo, Vertex};
use glam::{DVec3, Vec3};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Most point lights a scene may have: `MAX_LIGHTS` of `glsl/shared/bindings.glsl` (the shaders
/// size their per-light arrays with it).
pub const MAX_LIGHTS: usize = crate::bindings::MAX_LIGHTS as usize;
/// Largest `[render]` width / height accepted (the largest image dimension Vulkan guarantees).
pub const MAX_RENDER_DIM: u32 = 16384;
/// Albedo of faces without a (known) material, and of materials that give neither `Kd` nor `map_Kd`.
pub const DEFAULT_ALBEDO: f32 = 0.5;

/// A scene loading error. `Display` is always a single line that names the file.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file could not be read (scene, mesh or material library).
    #[error("{}", one_line(&format!("cannot read {}: {source}", path.display())))]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The scene TOML is malformed or does not match the contract (unknown or missing keys, wrong
    /// types). `line` is 1-based.
    #[error("{}", located(path, *line, msg))]
    Toml { path: PathBuf, line: Option<usize>, msg: String },
    /// The scene TOML parsed but a value is out of range (fov, intensity, light count, camera...).
    #[error("{}", one_line(&format!("{}: {msg}", path.display())))]
    Invalid { path: PathBuf, msg: String },
    /// The OBJ or MTL file is malformed. `line` is 1-based where it is known.
    #[error("{}", located(path, *line, msg))]
    Mesh { path: PathBuf, line: Option<usize>, msg: String },
    /// A `map_Kd` texture is missing or cannot be decoded.
    #[error("{}", one_line(&format!("texture {}: {msg}", path.display())))]
    Texture { path: PathBuf, msg: String },
}

/// `file:line: msg` or `file: msg`, collapsed to one line.
fn located(path: &Path, line: Option<usize>, msg: &str) -> String {
    one_line(&match line {
        Some(line) => format!("{}:{line}: {msg}", path.display()),
        None => format!("{}: {msg}", path.display()),
    })
}

/// Collapses whitespace runs (including newlines and carriage returns, which file and material names
/// may carry: the fuzzer found `newmtl a\rKd …`) to single spaces: every error is one line.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn mesh_err(path: &Path, line: Option<usize>, msg: impl Into<String>) -> SceneError {
    SceneError::Mesh { path: path.to_path_buf(), line, msg: msg.into() }
}

fn invalid(path: &Path, msg: impl Into<String>) -> SceneError {
    SceneError::Invalid { path: path.to_path_buf(), msg: msg.into() }
}

/// Timing and size facts about a load, for logging.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadStats {
    /// Triangles after triangulation (= `vertices.len() / 3`).
    pub triangles: usize,
    /// Zero-area (or non-finite-area) triangles kept with a +Y normal.
    pub degenerate_triangles: usize,
    /// Triangles whose OBJ normals were unusable (zero or non-finite) and replaced by the face normal.
    pub repaired_normals: usize,
    pub materials: usize,
    pub textures: usize,
    /// Total texels over all textures (4 bytes each).
    pub texels: usize,
    /// Wall time of the whole load (TOML + OBJ + MTL + textures + flattening), seconds.
    pub load_seconds: f64,
}

/// A loaded scene, flattened into the arrays the GPU buffers are filled from.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene TOML file (or the name given to [`Scene::from_toml_str`]).
    pub path: PathBuf,
    /// The OBJ file, resolved against the TOML's directory (empty for in-memory scenes).
    pub mesh_path: PathBuf,
    /// Non-indexed triangle list: triangle `t` owns `vertices[3t..3t+3]`.
    pub vertices: Vec<Vertex>,
    /// Material index per triangle.
    pub tri_material: Vec<u32>,
    pub materials: Vec<Material>,
    pub textures: Vec<TextureInfo>,
    /// Packed sRGB RGBA8 texels, r in the low byte; texture `k` occupies
    /// `texels[offset..offset + width * height]`, row-major, row 0 = top row of the image file.
    pub texels: Vec<u32>,
    pub camera: Camera,
    pub lights: Vec<Light>,
    /// `[render] width`, when given.
    pub render_width: Option<u32>,
    /// `[render] height`, when given.
    pub render_height: Option<u32>,
    /// Where the local origin lies in the file's world coordinates: every position above (vertices,
    /// camera, lights, bounds) is `world − origin`, in f32. Loading puts it at the centre of the
    /// mesh's bounds (computed in f64), so a scene far from its world origin keeps full f32 precision
    /// between its surface points, which is what one-bounce transport differences (see README,
    /// "Far from the origin"). Zero for in-memory scenes until [`Scene::rebase`].
    pub origin: DVec3,
    /// Axis-aligned bounds of all vertices (both zero for an empty scene).
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
    pub stats: LoadStats,
}

/// Builds the GPU light record of an isotropic point light.
pub fn point_light(position: Vec3, intensity: Vec3) -> Light {
    Light { position: position.extend(1.0).to_array(), intensity: intensity.extend(0.0).to_array() }
}

/// Loads the scene TOML at `path` and everything it references.
///
/// Materials: MTL `Kd` and `map_Kd` are used; everything else (`Ka`, `Ks`, `Ke`, `Ns`, `d`, ...)
/// is ignored. A `mtllib` that is named but missing is an error; a face with no `usemtl` or an
/// unknown material name gets [`DEFAULT_ALBEDO`]. A material with `map_Kd` but no `Kd` gets Kd = 1
/// (the texture is the albedo); with neither, [`DEFAULT_ALBEDO`].
///
/// Normals: tobj (`single_index`) stores per-vertex normals only for corners that have a `vn`, so
/// the `vn`s of a tobj mesh (one group × material) are used only when *every* corner in that mesh
/// has one; otherwise the whole mesh uses face normals (a mesh mixing corners with and without
/// `vn` is rare and cannot be attributed reliably).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let start = Instant::now();
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io { path: path.to_path_buf(), source })?;
    let mut scene = Scene::from_desc(parse_desc(&text, path)?)?;
    scene.stats.load_seconds = start.elapsed().as_secs_f64();
    Ok(scene)
}

impl Scene {
    /// Same as the free function [`load`].
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        load(path)
    }

    /// Parses scene TOML `text` as if it were the file `path` (its directory resolves `mesh`)
    /// and loads the mesh it references. For tests and tools that generate scenes.
    pub fn from_toml_str(text: &str, path: &Path) -> Result<Scene, SceneError> {
        let start = Instant::now();
        let mut scene = Scene::from_desc(parse_desc(text, path)?)?;
        scene.stats.load_seconds = start.elapsed().as_secs_f64();
        Ok(scene)
    }

    /// Loads the mesh of an already validated description.
    pub fn from_desc(desc: SceneDesc) -> Result<Scene, SceneError> {
        let start = Instant::now();
        let mesh = obj::load_mesh(&desc.mesh_path)?;
        if mesh.vertices.is_empty() {
            return Err(mesh_err(&desc.mesh_path, None, "the mesh has no faces"));
        }
        let mut scene = Scene::from_raw(
            mesh.vertices,
            mesh.tri_material,
            mesh.materials,
            mesh.textures,
            mesh.texels,
            desc.camera,
            desc.lights,
        );
        // The mesh is already local to its centre (f64 parse); bring the camera and lights over from
        // their f64 world positions, not from the rounded f32 copies.
        scene.origin = mesh.origin;
        let local = |p: DVec3| (p - mesh.origin).as_vec3();
        scene.camera.eye = local(desc.world.eye);
        scene.camera.target = local(desc.world.target);
        for (k, (light, &p)) in scene.lights.iter_mut().zip(&desc.world.lights).enumerate() {
            let at = local(p);
            if !at.is_finite() {
                let msg = format!("light[{k}].position lies beyond f32's range from the mesh (at {:?})", p.to_array());
                return Err(invalid(&desc.path, msg));
            }
            light.position = at.extend(1.0).to_array();
        }
        scene.camera.validate().map_err(|m| invalid(&desc.path, format!("[camera]: {m}")))?;
        scene.path = desc.path;
        scene.mesh_path = desc.mesh_path;
        scene.render_width = desc.render_width;
        scene.render_height = desc.render_height;
        scene.stats.degenerate_triangles = mesh.degenerate;
        scene.stats.repaired_normals = mesh.repaired_normals;
        scene.stats.load_seconds = start.elapsed().as_secs_f64();
        Ok(scene)
    }

    /// Builds an in-memory scene from already flattened arrays (computes bounds and stats).
    ///
    /// # Panics
    /// If the arrays are inconsistent (`vertices.len() != 3 · tri_material.len()`, a material or
    /// texture index out of range): this is a programming error, not bad user input.
    pub fn from_raw(
        vertices: Vec<Vertex>,
        tri_material: Vec<u32>,
        materials: Vec<Material>,
        textures: Vec<TextureInfo>,
        texels: Vec<u32>,
        camera: Camera,
        lights: Vec<Light>,
    ) -> Scene {
        assert_eq!(vertices.len(), 3 * tri_material.len(), "one material per triangle");
        assert!(tri_material.iter().all(|&m| (m as usize) < materials.len()), "material index out of range");
        assert!(
            materials.iter().all(|m| m.texture().into_iter().all(|t| t < textures.len())),
            "texture index out of range"
        );
        assert!(
            textures.iter().all(|t| t.offset as usize + (t.width as usize * t.height as usize) <= texels.len()),
            "texture texels out of range"
        );
        let (bounds_min, bounds_max) = if vertices.is_empty() {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            vertices.iter().fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), v| {
                (lo.min(v.position()), hi.max(v.position()))
            })
        };
        let stats = LoadStats {
            triangles: tri_material.len(),
            materials: materials.len(),
            textures: textures.len(),
            texels: texels.len(),
            ..Default::default()
        };
        Scene {
            path: PathBuf::from("<memory>"),
            mesh_path: PathBuf::new(),
            vertices,
            tri_material,
            materials,
            textures,
            texels,
            camera,
            lights,
            render_width: None,
            render_height: None,
            origin: DVec3::ZERO,
            bounds_min,
            bounds_max,
            stats,
        }
    }

    /// Moves the local origin to `origin` (world coordinates): every position is recomputed as
    /// `world − origin` through f64, so no precision is lost beyond the final f32 rounding.
    pub fn rebase(&mut self, origin: DVec3) {
        let shift = self.origin - origin;
        let move_point = |p: Vec3| (p.as_dvec3() + shift).as_vec3();
        for v in &mut self.vertices {
            let p = move_point(v.position());
            v.position_u[..3].copy_from_slice(&p.to_array());
        }
        self.camera.eye = move_point(self.camera.eye);
        self.camera.target = move_point(self.camera.target);
        for l in &mut self.lights {
            let p = move_point(Vec3::new(l.position[0], l.position[1], l.position[2]));
            l.position[..3].copy_from_slice(&p.to_array());
        }
        if !self.vertices.is_empty() {
            self.bounds_min = move_point(self.bounds_min);
            self.bounds_max = move_point(self.bounds_max);
        }
        self.origin = origin;
    }

    /// Builds an in-memory untextured scene: one material (linear albedo) per triangle, face
    /// normals (counter-clockwise winding seen from the normal side), UV 0. For tests.
    ///
    /// # Panics
    /// If `albedo.len() != triangles.len()`.
    pub fn from_triangles(triangles: &[[Vec3; 3]], albedo: &[Vec3], camera: Camera, lights: &[Light]) -> Scene {
        assert_eq!(triangles.len(), albedo.len(), "one albedo per triangle");
        let mut vertices = Vec::with_capacity(triangles.len() * 3);
        let mut degenerate = 0;
        for tri in triangles {
            let n = obj::face_normal(tri.map(|p| p.as_dvec3())).unwrap_or_else(|| {
                degenerate += 1;
                Vec3::Y
            });
            vertices.extend(tri.iter().map(|&p| obj::make_vertex(p, n, [0.0, 0.0])));
        }
        let materials = albedo.iter().map(|a| Material { kd_tex: [a.x, a.y, a.z, -1.0] }).collect();
        let mut scene = Scene::from_raw(
            vertices,
            (0..triangles.len() as u32).collect(),
            materials,
            Vec::new(),
            Vec::new(),
            camera,
            lights.to_vec(),
        );
        scene.stats.degenerate_triangles = degenerate;
        scene
    }

    /// A fingerprint of what the scene renders: its triangles, materials, textures, lights, camera and
    /// origin, not the files' names; results cached for a scene (a ground truth) carry it, so an edited
    /// scene is never measured against its old self. FNV-1a over the bytes: stable across builds and
    /// platforms, unlike `std`'s hashers.
    pub fn fingerprint(&self) -> u64 {
        let c = &self.camera;
        let camera = [c.eye.to_array(), c.target.to_array(), c.up.to_array(), [c.fov_y_deg, 0.0, 0.0]];
        let origin = self.origin.to_array();
        let parts: [&[u8]; 8] = [
            bytemuck::cast_slice(&self.vertices),
            bytemuck::cast_slice(&self.tri_material),
            bytemuck::cast_slice(&self.materials),
            bytemuck::cast_slice(&self.textures),
            bytemuck::cast_slice(&self.texels),
            bytemuck::cast_slice(&self.lights),
            bytemuck::cast_slice(&camera),
            bytemuck::cast_slice(&origin),
        ];
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        for part in parts {
            // Each part's length first, so that bytes moved from one part to the next change the result.
            for b in (part.len() as u64).to_le_bytes().iter().chain(part) {
                h = (h ^ *b as u64).wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
        h
    }

    pub fn triangle_count(&self) -> usize {
        self.tri_material.len()
    }

    /// Length of the bounds diagonal (0 for an empty scene).
    pub fn diagonal(&self) -> f32 {
        (self.bounds_max - self.bounds_min).length()
    }

    /// One line for the log: file, triangle count, materials, textures, bounds, lights, load time.
    pub fn summary(&self) -> String {
        // World bounds (the stored ones are local to `origin`).
        let (lo, hi) = (self.bounds_min.as_dvec3() + self.origin, self.bounds_max.as_dvec3() + self.origin);
        let mut s = format!("{}: {} triangles", self.path.display(), self.triangle_count());
        if self.stats.degenerate_triangles > 0 {
            let _ = write!(s, " ({} degenerate)", self.stats.degenerate_triangles);
        }
        if self.origin != DVec3::ZERO {
            // Rounded to 1e-6 for the log (the f64 value itself is exact).
            let o = (self.origin * 1e6).round() / 1e6;
            let _ = write!(s, ", local origin at [{}, {}, {}]", o.x, o.y, o.z);
        }
        let _ = write!(
            s,
            ", {} materials, {} textures ({:.1} MiB), bounds [{:.3}, {:.3}, {:.3}]..[{:.3}, {:.3}, {:.3}], {} light{}, loaded in {:.1} ms",
            self.materials.len(),
            self.textures.len(),
            (self.texels.len() * 4) as f64 / (1024.0 * 1024.0),
            lo.x,
            lo.y,
            lo.z,
            hi.x,
            hi.y,
            hi.z,
            self.lights.len(),
            if self.lights.len() == 1 { "" } else { "s" },
            self.stats.load_seconds * 1e3
        );
        s
    }
}

/// Files for the loader's unit tests (each format's tests are beside its code).
#[cfg(test)]
mod test_files {
    use std::path::{Path, PathBuf};
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// A directory under the system temp dir, removed when dropped.
    pub(super) struct TempDir(PathBuf);
    impl std::ops::Deref for TempDir {
        type Target = Path;
        fn deref(&self) -> &Path {
            &self.0
        }
    }
    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    /// A fresh, empty directory under the system temp dir, unique per test and process.
    pub(super) fn temp_dir(tag: &str) -> TempDir {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("bounce-scene-test-{}-{tag}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create temp dir");
        TempDir(dir)
    }

    pub(super) fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).expect("write temp file");
        p
    }

    pub(super) const EXAMPLE: &str = r#"mesh = "room.obj"            # Wavefront OBJ; its mtllib is read for materials
[camera]
eye    = [0.0, 1.0, 3.9]
target = [0.0, 1.0, 0.0]
up     = [0.0, 1.0, 0.0]
fov_y  = 39.3                # vertical field of view in degrees, across the full image height
[[light]]                    # isotropic point light; one or more tables
position  = [0.0, 1.8, 0.0]
intensity = [5.0, 5.0, 5.0]  # radiant intensity, W/sr, linear RGB
[render]                     # defaults; the command line overrides
width  = 256
height = 256
"#;

    pub(super) const QUAD_OBJ: &str = "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 4 3 2 1\n";

    pub(super) fn replace(text: &str, from: &str, to: &str) -> String {
        assert!(text.contains(from), "test bug: {from:?} not in text");
        text.replacen(from, to, 1)
    }
}

#[cfg(test)]
mod tests {
    use super::test_files::*;
    use super::*;

    #[test]
    fn missing_files_are_named() {
        let dir = temp_dir("missing");
        let err = Scene::from_toml_str(EXAMPLE, &dir.join("scene.toml")).expect_err("no mesh");
        let msg = err.to_string();
        assert!(matches!(err, SceneError::Io { .. }));
        assert!(msg.contains(&*dir.join("room.obj").to_string_lossy()), "{msg}");

        let err = load(&dir.join("nope.toml")).expect_err("no toml");
        assert!(err.to_string().contains("nope.toml"), "{err}");

        // A named but missing mtllib is an error naming it.
        write(&dir, "room.obj", &format!("mtllib gone.mtl\n{QUAD_OBJ}"));
        let err = Scene::from_toml_str(EXAMPLE, &dir.join("scene.toml")).expect_err("no mtl");
        assert!(err.to_string().contains("gone.mtl"), "{err}");

        // A missing texture is an error naming it (and the material).
        write(&dir, "room.obj", &format!("mtllib m.mtl\nusemtl tex\n{QUAD_OBJ}"));
        write(&dir, "m.mtl", "newmtl tex\nKd 1 1 1\nmap_Kd -bm 1 textures/albedo.png\n");
        let err = Scene::from_toml_str(EXAMPLE, &dir.join("scene.toml")).expect_err("no png");
        let msg = err.to_string();
        assert!(matches!(err, SceneError::Texture { .. }), "{msg}");
        assert!(msg.contains("albedo.png") && msg.contains("`tex`"), "{msg}");
        assert!(!msg.contains('\n'));
    }

    /// Far from the origin the loader keeps what f32 world coordinates would lose: at 10⁶ a f32 step is
    /// 0.0625, but positions 10⁶ + 0.3 parse in f64 and land at exactly their offset from the centre.
    #[test]
    fn positions_far_from_the_origin_keep_full_precision() {
        let dir = temp_dir("far");
        let obj = "v 1000000.3 2000000.0 -1000000.0\nv 1000001.3 2000000.0 -1000000.0\nv 1000000.3 2000001.0 -1000000.0\nf 1 2 3\n";
        std::fs::write(dir.join("far.obj"), obj).unwrap();
        let toml = "mesh = \"far.obj\"\n[camera]\neye = [1000000.8, 2000000.5, -999990.0]\ntarget = [1000000.8, 2000000.5, -1000000.0]\nup = [0.0, 1.0, 0.0]\nfov_y = 40.0\n[[light]]\nposition = [1000000.55, 2000000.25, -999999.0]\nintensity = [1.0, 1.0, 1.0]\n";
        std::fs::write(dir.join("far.toml"), toml).unwrap();
        let s = load(&dir.join("far.toml")).unwrap();
        assert_eq!(s.origin, glam::DVec3::new(1000000.8, 2000000.5, -1000000.0));
        let p: Vec<Vec3> = s.vertices.iter().map(|v| v.position()).collect();
        assert_eq!(p, vec![Vec3::new(-0.5, -0.5, 0.0), Vec3::new(0.5, -0.5, 0.0), Vec3::new(-0.5, 0.5, 0.0)]);
        assert!((s.camera.eye - Vec3::new(0.0, 0.0, 10.0)).length() < 1e-6);
        assert!((Vec3::from_slice(&s.lights[0].position[..3]) - Vec3::new(-0.25, -0.25, 1.0)).length() < 1e-6);
    }

    #[test]
    fn cornell_box_loads() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/cornell-box/scene.toml");
        let s = load(&path).expect("cornell box loads");
        // 18 `f` lines, all quads: 36 triangles.
        assert_eq!(s.triangle_count(), 36);
        assert_eq!(s.stats.degenerate_triangles, 0);
        assert_eq!(s.lights.len(), 1);
        assert_eq!((s.render_width, s.render_height), (Some(256), Some(256)));
        // World bounds = local bounds + origin (the bounds' centre).
        let world = |p: Vec3| (p.as_dvec3() + s.origin).as_vec3();
        assert!((world(s.bounds_min) - Vec3::new(-1.02, 0.0, -1.04)).abs().max_element() < 1e-6);
        assert!((world(s.bounds_max) - Vec3::new(1.0, 1.99, 0.99)).abs().max_element() < 1e-6);
        assert!((s.bounds_min + s.bounds_max).abs().max_element() < 1e-6, "centred on the origin");
        // Every face has a material from the MTL (no default grey needed).
        assert_eq!(s.materials.len(), 8);
        let red = s.materials.iter().position(|m| m.kd_tex[..3] == [0.63, 0.065, 0.05]);
        assert!(red.is_some());
        for v in &s.vertices {
            assert!((v.normal().length() - 1.0).abs() < 1e-6);
        }
        // The floor's normal points into the room (+y) with the file's winding.
        let floor_y = s.bounds_min.y; // the floor is the lowest surface (world y = 0)
        let floor =
            s.vertices.chunks(3).position(|t| t.iter().all(|v| v.position().y == floor_y)).expect("floor triangle");
        assert_eq!(s.vertices[3 * floor].normal(), Vec3::Y);
        let summary = s.summary();
        assert!(summary.contains("36 triangles") && !summary.contains('\n'), "{summary}");
    }
}
