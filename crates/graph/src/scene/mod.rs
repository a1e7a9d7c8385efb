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

use crate::camera::Camera;
use crate::shader_types::{Light, Material, TextureInfo, Vertex};
use glam::{DVec3, Vec3};
use serde::Deserialize;
use std::cell::RefCell;
use std::collections::HashMap;
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

/// The validated contents of a scene TOML, before the mesh is loaded.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneDesc {
    /// The TOML file the description came from (used in messages and to resolve `mesh`).
    pub path: PathBuf,
    /// `mesh`, resolved against the directory of `path`.
    pub mesh_path: PathBuf,
    pub camera: Camera,
    pub lights: Vec<Light>,
    pub render_width: Option<u32>,
    pub render_height: Option<u32>,
    /// The camera's eye and target and the lights' positions as the file gives them, in f64: the
    /// f32 copies above lose precision far from the origin; these are rebased with the mesh.
    pub world: WorldPoints,
}

/// Positions of a scene description in world coordinates, at full precision.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldPoints {
    pub eye: DVec3,
    pub target: DVec3,
    pub lights: Vec<DVec3>,
}

// ---- TOML schema ------------------------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneToml {
    mesh: String,
    camera: CameraToml,
    light: Vec<LightToml>,
    #[serde(default)]
    render: Option<RenderToml>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraToml {
    eye: [f64; 3],
    target: [f64; 3],
    up: [f32; 3],
    fov_y: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightToml {
    position: [f64; 3],
    intensity: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderToml {
    #[serde(default)]
    width: Option<u32>,
    #[serde(default)]
    height: Option<u32>,
}

/// Builds the GPU light record of an isotropic point light.
pub fn point_light(position: Vec3, intensity: Vec3) -> Light {
    Light { position: position.extend(1.0).to_array(), intensity: intensity.extend(0.0).to_array() }
}

/// Parses and validates scene TOML `text` as if it were the file `path` (used in messages and to
/// resolve the relative `mesh` path). Does not touch the file system.
pub fn parse_desc(text: &str, path: &Path) -> Result<SceneDesc, SceneError> {
    let raw: SceneToml = toml::from_str(text).map_err(|e| SceneError::Toml {
        path: path.to_path_buf(),
        // toml's Display is a multi-line snippet; keep the message and compute the line ourselves.
        line: e.span().map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1),
        msg: one_line(e.message()),
    })?;

    let camera = Camera {
        eye: DVec3::from_array(raw.camera.eye).as_vec3(),
        target: DVec3::from_array(raw.camera.target).as_vec3(),
        up: Vec3::from_array(raw.camera.up),
        fov_y_deg: raw.camera.fov_y,
    };
    camera.validate().map_err(|m| invalid(path, format!("[camera]: {m}")))?;

    if raw.light.is_empty() {
        return Err(invalid(path, "at least one [[light]] is required"));
    }
    if raw.light.len() > MAX_LIGHTS {
        return Err(invalid(path, format!("{} lights given, at most {MAX_LIGHTS} are supported", raw.light.len())));
    }
    let mut lights = Vec::with_capacity(raw.light.len());
    for (k, l) in raw.light.iter().enumerate() {
        if !l.position.iter().all(|x| x.is_finite()) {
            return Err(invalid(path, format!("light[{k}].position {:?} must be finite", l.position)));
        }
        if !l.intensity.iter().all(|x| x.is_finite() && *x >= 0.0) {
            return Err(invalid(path, format!("light[{k}].intensity {:?} must be finite and >= 0", l.intensity)));
        }
        lights.push(point_light(DVec3::from_array(l.position).as_vec3(), Vec3::from_array(l.intensity)));
    }

    let (render_width, render_height) = match &raw.render {
        Some(r) => (r.width, r.height),
        None => (None, None),
    };
    for (name, v) in [("width", render_width), ("height", render_height)] {
        if let Some(v) = v {
            if !(1..=MAX_RENDER_DIM).contains(&v) {
                return Err(invalid(path, format!("[render] {name} = {v} is outside 1..={MAX_RENDER_DIM}")));
            }
        }
    }

    if raw.mesh.trim().is_empty() {
        return Err(invalid(path, "mesh path is empty"));
    }
    let mesh = Path::new(&raw.mesh);
    let mesh_path =
        if mesh.is_absolute() { mesh.to_path_buf() } else { path.parent().unwrap_or(Path::new("")).join(mesh) };

    let world = WorldPoints {
        eye: DVec3::from_array(raw.camera.eye),
        target: DVec3::from_array(raw.camera.target),
        lights: raw.light.iter().map(|l| DVec3::from_array(l.position)).collect(),
    };
    Ok(SceneDesc { path: path.to_path_buf(), mesh_path, camera, lights, render_width, render_height, world })
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
        let mesh = load_mesh(&desc.mesh_path)?;
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
        for (light, &p) in scene.lights.iter_mut().zip(&desc.world.lights) {
            light.position = local(p).extend(1.0).to_array();
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
            let n = face_normal(tri.map(|p| p.as_dvec3())).unwrap_or_else(|| {
                degenerate += 1;
                Vec3::Y
            });
            vertices.extend(tri.iter().map(|&p| make_vertex(p, n, [0.0, 0.0])));
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

    pub fn triangle_count(&self) -> usize {
        self.tri_material.len()
    }

    /// Length of the bounds diagonal (0 for an empty scene).
    pub fn diagonal(&self) -> f32 {
        (self.bounds_max - self.bounds_min).length()
    }

    /// A `(near, far)` pair for [`Camera::view_proj`] that never clips the scene: `far` is 1 % past
    /// the farthest bounds corner from the eye, `near = far · 1e-4` (small enough for an eye
    /// inside the scene; with forward Z in a D32 float buffer the 1e4 ratio keeps ample
    /// precision). Geometry closer than `near` to the eye is clipped.
    pub fn depth_range(&self) -> (f32, f32) {
        let eye = self.camera.eye;
        let mut far: f32 = 0.0;
        for k in 0..8 {
            let corner = Vec3::new(
                if k & 1 == 0 { self.bounds_min.x } else { self.bounds_max.x },
                if k & 2 == 0 { self.bounds_min.y } else { self.bounds_max.y },
                if k & 4 == 0 { self.bounds_min.z } else { self.bounds_max.z },
            );
            far = far.max(corner.distance(eye));
        }
        let far = (far * 1.01).max(1e-3);
        (far * 1e-4, far)
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

// ---- mesh loading -----------------------------------------------------------------------------

/// The flattened mesh, before camera and lights join it.
struct MeshData {
    /// World position of the local origin (the centre of the positions' bounds).
    origin: DVec3,
    /// Positions relative to `origin`.
    vertices: Vec<Vertex>,
    tri_material: Vec<u32>,
    materials: Vec<Material>,
    textures: Vec<TextureInfo>,
    texels: Vec<u32>,
    degenerate: usize,
    repaired_normals: usize,
}

fn make_vertex(p: Vec3, n: Vec3, uv: [f32; 2]) -> Vertex {
    Vertex { position_u: [p.x, p.y, p.z, uv[0]], normal_v: [n.x, n.y, n.z, uv[1]] }
}

/// Unit face normal `normalize(cross(p1 − p0, p2 − p0))`, or `None` for a zero-area or non-finite
/// triangle. Computed in f64 so tiny-but-valid triangles do not underflow to a zero vector.
fn face_normal(p: [DVec3; 3]) -> Option<Vec3> {
    let c = (p[1] - p[0]).cross(p[2] - p[0]);
    let len = c.length();
    if len.is_finite() && len > 0.0 {
        let n = (c / len).as_vec3();
        // Re-normalize in f32 so the stored normal is unit to f32 precision.
        let n = n.normalize_or_zero();
        (n != Vec3::ZERO).then_some(n)
    } else {
        None
    }
}

/// A usable vertex normal: `raw` normalized, or `None` when it is zero or non-finite.
fn unit_normal(raw: DVec3) -> Option<Vec3> {
    let len = raw.length();
    if len.is_finite() && len > 0.0 {
        let n = (raw / len).as_vec3().normalize_or_zero();
        (n != Vec3::ZERO).then_some(n)
    } else {
        None
    }
}

/// Result of the OBJ pre-scan: the text tobj gets, with lines tobj would mis-parse normalized.
struct Prescan {
    text: String,
}

/// Validates the OBJ line by line before tobj sees it, because tobj reports neither line numbers
/// nor non-finite coordinates (Rust's float parser accepts `nan` and `inf`). Also normalizes
/// lines tobj mis-parses:
/// * `mtllib`/`usemtl` with leading whitespace or a tab separator (tobj splits at the first space);
/// * `mtllib a.mtl b.mtl` (several libraries, allowed by the spec; tobj reads one file name with
///   spaces) becomes one `mtllib` line per file, unless a file with the spaced name exists;
/// * `l` polylines (tobj treats a 3-point polyline as a triangle) are blanked.
fn prescan_obj(text: &str, path: &Path) -> Result<Prescan, SceneError> {
    let obj_dir = path.parent().unwrap_or(Path::new(""));
    let (mut nv, mut nvt, mut nvn) = (0usize, 0usize, 0usize);
    // Largest absolute (positive) index per kind and the line that used it, checked at the end
    // against the final counts (tobj resolves positive indices after reading the whole file).
    let mut max_abs: [(usize, usize); 3] = [(0, 0); 3];
    let mut out = String::with_capacity(text.len() + 64);

    let parse_floats = |toks: &mut std::str::SplitWhitespace, n: usize| -> Option<Vec<f32>> {
        let mut v = Vec::with_capacity(n);
        for _ in 0..n {
            v.push(toks.next()?.parse::<f32>().ok()?);
        }
        Some(v)
    };

    for (k, line) in text.lines().enumerate() {
        let lineno = k + 1;
        let trimmed = line.trim_start();
        let mut toks = trimmed.split_whitespace();
        let Some(kw) = toks.next() else {
            out.push_str(line);
            out.push('\n');
            continue;
        };
        match kw {
            "v" => {
                let xyz = parse_floats(&mut toks, 3)
                    .ok_or_else(|| mesh_err(path, Some(lineno), "vertex position needs three numbers"))?;
                if !xyz.iter().all(|x| x.is_finite()) {
                    return Err(mesh_err(path, Some(lineno), format!("non-finite vertex position {xyz:?}")));
                }
                nv += 1;
            }
            "vt" => {
                // tobj needs u and v; a lone u (allowed by the spec) would be a parse error there.
                parse_floats(&mut toks, 2)
                    .ok_or_else(|| mesh_err(path, Some(lineno), "texture coordinate needs u and v"))?;
                nvt += 1;
            }
            "vn" => {
                parse_floats(&mut toks, 3)
                    .ok_or_else(|| mesh_err(path, Some(lineno), "vertex normal needs three numbers"))?;
                nvn += 1;
            }
            "f" => {
                let counts = [nv, nvt, nvn];
                let names = ["vertex", "texture coordinate", "normal"];
                let mut corners = 0;
                for corner in toks {
                    corners += 1;
                    for (slot, part) in corner.split('/').enumerate() {
                        if slot >= 3 {
                            return Err(mesh_err(path, Some(lineno), format!("malformed face corner `{corner}`")));
                        }
                        if part.is_empty() {
                            if slot == 0 {
                                return Err(mesh_err(
                                    path,
                                    Some(lineno),
                                    format!("face corner `{corner}` has no vertex index"),
                                ));
                            }
                            continue;
                        }
                        let idx: isize = part
                            .parse()
                            .map_err(|_| mesh_err(path, Some(lineno), format!("malformed face corner `{corner}`")))?;
                        if idx == 0 {
                            return Err(mesh_err(
                                path,
                                Some(lineno),
                                format!("{} index 0 in `{corner}` (OBJ indices start at 1)", names[slot]),
                            ));
                        }
                        if idx < 0 {
                            if idx.unsigned_abs() > counts[slot] {
                                return Err(mesh_err(
                                    path,
                                    Some(lineno),
                                    format!(
                                        "relative {} index {idx} in `{corner}` is out of range (only {} defined so far)",
                                        names[slot], counts[slot]
                                    ),
                                ));
                            }
                        } else if idx as usize > max_abs[slot].0 {
                            max_abs[slot] = (idx as usize, lineno);
                        }
                    }
                }
                if corners < 3 {
                    return Err(mesh_err(
                        path,
                        Some(lineno),
                        format!("face has {corners} corners, at least 3 are needed"),
                    ));
                }
            }
            "l" => {
                // Polylines are not surfaces; keep the line count.
                out.push('\n');
                continue;
            }
            "mtllib" | "usemtl" => {
                let rest = trimmed[kw.len()..].trim();
                if rest.is_empty() {
                    return Err(mesh_err(path, Some(lineno), format!("{kw} without a name")));
                }
                if kw == "mtllib" && rest.contains(char::is_whitespace) && !obj_dir.join(rest).is_file() {
                    for name in rest.split_whitespace() {
                        out.push_str("mtllib ");
                        out.push_str(name);
                        out.push('\n');
                    }
                } else {
                    out.push_str(kw);
                    out.push(' ');
                    out.push_str(rest);
                    out.push('\n');
                }
                continue;
            }
            _ => {}
        }
        out.push_str(line);
        out.push('\n');
    }

    let counts = [nv, nvt, nvn];
    let names = ["vertex", "texture coordinate", "normal"];
    for slot in 0..3 {
        let (idx, lineno) = max_abs[slot];
        if idx > counts[slot] {
            return Err(mesh_err(
                path,
                Some(lineno),
                format!("{} index {idx} is out of range (the file defines {})", names[slot], counts[slot]),
            ));
        }
    }
    Ok(Prescan { text: out })
}

/// Reads an MTL file and keeps only what the contract uses (`newmtl`, `Kd`, `map_Kd`), blanking
/// every other line (line numbers preserved). tobj aborts the whole library on a malformed line it
/// does not even need (and panics on `Ka`/`Ks`/`Ke` with fewer than three numbers), so ignored
/// statements must never reach it. `Kd r` (one value, allowed by the MTL spec) becomes `Kd r r r`.
fn sanitize_mtl(text: &str, path: &Path) -> Result<String, SceneError> {
    let mut out = String::with_capacity(text.len());
    for (k, line) in text.lines().enumerate() {
        let lineno = k + 1;
        let trimmed = line.trim();
        // Drop a trailing comment (`Kd 1 0 0 # red`).
        let code = trimmed.split('#').next().unwrap_or("").trim();
        let mut toks = code.split_whitespace();
        match toks.next() {
            Some("newmtl") => {
                if code["newmtl".len()..].trim().is_empty() {
                    return Err(mesh_err(path, Some(lineno), "newmtl without a name"));
                }
                out.push_str(code);
            }
            Some("Kd") => {
                let vals: Vec<&str> = toks.collect();
                let nums: Option<Vec<f32>> = vals.iter().map(|t| t.parse::<f32>().ok()).collect();
                let nums = match nums {
                    Some(n) if n.len() == 1 => vec![n[0]; 3],
                    Some(n) if n.len() == 3 => n,
                    _ => {
                        return Err(mesh_err(
                            path,
                            Some(lineno),
                            format!("`{code}`: only `Kd r g b` or `Kd r` is supported"),
                        ))
                    }
                };
                if !nums.iter().all(|x| x.is_finite() && *x >= 0.0) {
                    return Err(mesh_err(path, Some(lineno), format!("Kd {nums:?} must be finite and >= 0")));
                }
                let _ = write!(out, "Kd {} {} {}", nums[0], nums[1], nums[2]);
            }
            Some("map_Kd") => {
                // MTL has no escaping: '#' always starts a comment, so `code` is the statement.
                if code["map_Kd".len()..].trim().is_empty() {
                    return Err(mesh_err(path, Some(lineno), "map_Kd without a file name"));
                }
                out.push_str(code);
            }
            _ => {}
        }
        out.push('\n');
    }
    Ok(out)
}

/// The texture file of a `map_Kd` statement: options such as `-bm 1` or `-s 1 1 1` precede the
/// file name, so the name is the last token. Backslashes (Windows exporters) become `/`.
fn map_kd_file(spec: &str) -> Option<String> {
    spec.split_whitespace().last().map(|s| s.replace('\\', "/"))
}

/// Decodes an image file into packed sRGB RGBA8 texels (r in the low byte), row 0 = top.
fn load_texture(path: &Path) -> Result<(u32, u32, Vec<u32>), SceneError> {
    let terr = |msg: String| SceneError::Texture { path: path.to_path_buf(), msg };
    let reader = image::ImageReader::open(path)
        .map_err(|e| terr(format!("cannot open: {e}")))?
        .with_guessed_format()
        .map_err(|e| terr(format!("cannot read: {e}")))?;
    let img = reader.decode().map_err(|e| terr(format!("cannot decode: {}", one_line(&e.to_string()))))?;
    let rgba = img.to_rgba8();
    let (w, h) = rgba.dimensions();
    if w == 0 || h == 0 {
        return Err(terr("image is empty".to_string()));
    }
    let texels = rgba.pixels().map(|p| u32::from_le_bytes(p.0)).collect::<Vec<u32>>();
    Ok((w, h, texels))
}

/// Loads the OBJ at `obj_path` (with its MTL libraries and textures) and flattens it.
fn load_mesh(obj_path: &Path) -> Result<MeshData, SceneError> {
    let bytes = std::fs::read(obj_path).map_err(|source| SceneError::Io { path: obj_path.to_path_buf(), source })?;
    // Lossy: stray Latin-1 bytes in comments or group names must not make the file unreadable.
    let text = String::from_utf8_lossy(&bytes);
    let pre = prescan_obj(&text, obj_path)?;
    drop(bytes);

    let obj_dir = obj_path.parent().unwrap_or(Path::new("")).to_path_buf();
    // tobj's material loader cannot return our error type; stash the first failure here.
    let mtl_error: RefCell<Option<SceneError>> = RefCell::new(None);
    // (mtl file, number of materials it contributed), in load order: tobj appends each library's
    // materials, so these ranges map a material index back to its file (for texture paths).
    let libs: RefCell<Vec<(PathBuf, usize)>> = RefCell::new(Vec::new());

    // `..Default::default()` keeps this compiling if tobj's `merging`/`reordering` features (which
    // add fields) get enabled elsewhere in the build.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let loaded = tobj::load_obj_buf(&mut std::io::Cursor::new(pre.text.as_bytes()), &options, |rel: &Path| {
        let full = obj_dir.join(rel);
        let result = std::fs::read_to_string(&full)
            .map_err(|source| SceneError::Io { path: full.clone(), source })
            .and_then(|t| sanitize_mtl(&t, &full))
            .and_then(|t| {
                tobj::load_mtl_buf(&mut std::io::Cursor::new(t.as_bytes()))
                    .map_err(|e| mesh_err(&full, None, e.to_string()))
            });
        match result {
            Ok((mats, map)) => {
                libs.borrow_mut().push((full, mats.len()));
                Ok((mats, map))
            }
            Err(e) => {
                let mut slot = mtl_error.borrow_mut();
                if slot.is_none() {
                    *slot = Some(e);
                }
                Err(tobj::LoadError::GenericFailure)
            }
        }
    });
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    let (models, tobj_materials) = loaded.map_err(|e| mesh_err(obj_path, None, e.to_string()))?;
    let tobj_materials = tobj_materials.map_err(|e| mesh_err(obj_path, None, format!("material library: {e}")))?;
    let libs = libs.into_inner();

    // Materials and textures.
    let mut materials = Vec::with_capacity(tobj_materials.len() + 1);
    let mut textures: Vec<TextureInfo> = Vec::new();
    let mut texels: Vec<u32> = Vec::new();
    let mut texture_index: HashMap<PathBuf, usize> = HashMap::new();
    let mut lib_of_material: Vec<&Path> = Vec::with_capacity(tobj_materials.len());
    for (p, n) in &libs {
        for _ in 0..*n {
            lib_of_material.push(p);
        }
    }
    for (k, m) in tobj_materials.iter().enumerate() {
        let mtl_path = lib_of_material.get(k).copied().unwrap_or(obj_path);
        let mtl_dir = mtl_path.parent().unwrap_or(Path::new(""));
        let mut tex = -1.0f32;
        if let Some(spec) = &m.diffuse_texture {
            let file = map_kd_file(spec).ok_or_else(|| {
                mesh_err(mtl_path, None, format!("material `{}`: map_Kd without a file name", m.name))
            })?;
            let tex_path = mtl_dir.join(file);
            let idx = match texture_index.get(&tex_path) {
                Some(&i) => i,
                None => {
                    let (w, h, data) = load_texture(&tex_path).map_err(|e| match e {
                        SceneError::Texture { path, msg } => SceneError::Texture {
                            path,
                            msg: format!("{msg} (map_Kd of material `{}` in {})", m.name, mtl_path.display()),
                        },
                        other => other,
                    })?;
                    let offset = u32::try_from(texels.len())
                        .ok()
                        .filter(|o| o.checked_add(w.saturating_mul(h)).is_some())
                        .ok_or_else(|| SceneError::Texture {
                            path: tex_path.clone(),
                            msg: "the scene's textures exceed 2^32 texels".to_string(),
                        })?;
                    textures.push(TextureInfo { offset, width: w, height: h, pad: 0 });
                    texels.extend_from_slice(&data);
                    texture_index.insert(tex_path, textures.len() - 1);
                    textures.len() - 1
                }
            };
            tex = idx as f32;
        }
        let kd = match m.diffuse {
            Some(kd) => kd.map(|x| x as f32),
            None if tex >= 0.0 => [1.0; 3],
            None => [DEFAULT_ALBEDO; 3],
        };
        materials.push(Material { kd_tex: [kd[0], kd[1], kd[2], tex] });
    }
    // Index of the grey default material, appended only if some face needs it.
    let mut default_material: Option<u32> = None;

    let triangles: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
    let mut vertices = Vec::with_capacity(triangles * 3);
    let mut tri_material = Vec::with_capacity(triangles);
    let mut degenerate = 0usize;
    let mut repaired_normals = 0usize;

    // The local origin: the centre of all positions' bounds, in f64 (non-finite positions are
    // rejected below, where a face uses them).
    let (lo, hi) = models
        .iter()
        .flat_map(|m| m.mesh.positions.chunks_exact(3))
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .filter(|p| p.is_finite())
        .fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), p| (lo.min(p), hi.max(p)));
    let origin = if lo.x <= hi.x { (lo + hi) * 0.5 } else { DVec3::ZERO };

    for model in &models {
        let mesh = &model.mesh;
        let nverts = mesh.positions.len() / 3;
        // See `load`: vn/vt are trustworthy only if every vertex of this mesh has one.
        let has_normals = !mesh.normals.is_empty() && mesh.normals.len() == mesh.positions.len();
        let has_uv = !mesh.texcoords.is_empty() && mesh.texcoords.len() == 2 * nverts;
        let mat = match mesh.material_id {
            Some(id) if id < materials.len() => id as u32,
            _ => *default_material.get_or_insert_with(|| {
                materials.push(Material { kd_tex: [DEFAULT_ALBEDO, DEFAULT_ALBEDO, DEFAULT_ALBEDO, -1.0] });
                (materials.len() - 1) as u32
            }),
        };
        let pos = |i: usize| DVec3::new(mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2]);
        for tri in mesh.indices.chunks_exact(3) {
            let idx = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
            if idx.iter().any(|&i| i >= nverts) {
                return Err(mesh_err(obj_path, None, "face index out of range"));
            }
            let p = idx.map(pos);
            if !p.iter().all(|q| q.is_finite()) {
                return Err(mesh_err(obj_path, None, "non-finite vertex position"));
            }
            let face = face_normal(p).unwrap_or_else(|| {
                degenerate += 1;
                Vec3::Y
            });
            let mut normals = [face; 3];
            if has_normals {
                let vn = idx.map(|i| {
                    unit_normal(DVec3::new(mesh.normals[3 * i], mesh.normals[3 * i + 1], mesh.normals[3 * i + 2]))
                });
                if let [Some(a), Some(b), Some(c)] = vn {
                    normals = [a, b, c];
                } else {
                    repaired_normals += 1;
                }
            }
            for c in 0..3 {
                let uv = if has_uv {
                    let (u, v) = (mesh.texcoords[2 * idx[c]] as f32, mesh.texcoords[2 * idx[c] + 1] as f32);
                    // Non-finite UVs would make the texel index undefined on the GPU.
                    [if u.is_finite() { u } else { 0.0 }, if v.is_finite() { v } else { 0.0 }]
                } else {
                    [0.0, 0.0]
                };
                vertices.push(make_vertex((p[c] - origin).as_vec3(), normals[c], uv));
            }
            tri_material.push(mat);
        }
    }

    Ok(MeshData { origin, vertices, tri_material, materials, textures, texels, degenerate, repaired_normals })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// A directory under the system temp dir, removed when dropped.
    struct TempDir(PathBuf);
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
    fn temp_dir(tag: &str) -> TempDir {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("bounce-scene-test-{}-{tag}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create temp dir");
        TempDir(dir)
    }

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).expect("write temp file");
        p
    }

    const EXAMPLE: &str = r#"mesh = "room.obj"            # Wavefront OBJ; its mtllib is read for materials
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

    const QUAD_OBJ: &str = "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 4 3 2 1\n";

    fn replace(text: &str, from: &str, to: &str) -> String {
        assert!(text.contains(from), "test bug: {from:?} not in text");
        text.replacen(from, to, 1)
    }

    #[test]
    fn parses_the_contract_example() {
        let d = parse_desc(EXAMPLE, Path::new("/scenes/box/scene.toml")).expect("example parses");
        assert_eq!(d.mesh_path, Path::new("/scenes/box/room.obj"));
        assert_eq!(d.camera.eye, Vec3::new(0.0, 1.0, 3.9));
        assert_eq!(d.camera.target, Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(d.camera.up, Vec3::Y);
        assert_eq!(d.camera.fov_y_deg, 39.3);
        assert_eq!(d.lights.len(), 1);
        assert_eq!(d.lights[0].position[..3], [0.0, 1.8, 0.0]);
        assert_eq!(d.lights[0].intensity[..3], [5.0, 5.0, 5.0]);
        assert_eq!((d.render_width, d.render_height), (Some(256), Some(256)));

        // [render] is optional, integers are accepted for floats, several lights are fine.
        let text = EXAMPLE.split("[render]").next().unwrap_or_default().replace("3.9]", "4]")
            + "[[light]]\nposition = [1, 1, 1]\nintensity = [0, 0, 0]\n";
        let d = parse_desc(&text, Path::new("scene.toml")).expect("parses");
        assert_eq!((d.render_width, d.render_height), (None, None));
        assert_eq!(d.lights.len(), 2);
        assert_eq!(d.camera.eye.z, 4.0);
        assert_eq!(d.mesh_path, Path::new("room.obj"));
    }

    #[test]
    fn unknown_keys_are_rejected_in_every_table() {
        let cases = [
            ("mesh = \"room.obj\"", "mesh = \"room.obj\"\nmeshes = 1"),
            ("fov_y  = 39.3", "fov = 39.3\nfov_y = 39.3"),
            ("position  = [0.0, 1.8, 0.0]", "position = [0.0, 1.8, 0.0]\ncolor = 1"),
            ("width  = 256", "width = 256\nsamples = 4"),
        ];
        for (from, to) in cases {
            let text = replace(EXAMPLE, from, to);
            let err = parse_desc(&text, Path::new("scene.toml")).expect_err(to);
            let msg = err.to_string();
            assert!(matches!(err, SceneError::Toml { line: Some(_), .. }), "{msg}");
            assert!(msg.contains("unknown field"), "{msg}");
            assert!(msg.starts_with("scene.toml:"), "{msg}");
            assert!(!msg.contains('\n'), "{msg}");
        }
        let err =
            parse_desc(&replace(EXAMPLE, "fov_y  = 39.3", "fov = 39.3"), Path::new("s.toml")).expect_err("fov typo");
        // `fov` is on line 6 of the example.
        assert!(err.to_string().starts_with("s.toml:6: unknown field `fov`"), "{err}");
    }

    #[test]
    fn missing_required_keys_are_rejected() {
        for key in ["mesh = \"room.obj\"", "fov_y  = 39.3", "intensity = [5.0, 5.0, 5.0]"] {
            let text = replace(EXAMPLE, key, "");
            let err = parse_desc(&text, Path::new("scene.toml")).expect_err(key);
            assert!(err.to_string().contains("missing field"), "{err}");
        }
        // No light table at all.
        let no_light = EXAMPLE
            .lines()
            .filter(|l| !l.starts_with("[[light]]") && !l.starts_with("position") && !l.starts_with("intensity"))
            .collect::<Vec<_>>()
            .join("\n");
        let err = parse_desc(&no_light, Path::new("scene.toml")).expect_err("no light");
        assert!(err.to_string().contains("missing field `light`"), "{err}");
        // An empty light array.
        let text = format!("light = []\n{no_light}");
        let err = parse_desc(&text, Path::new("scene.toml")).expect_err("no lights");
        assert!(err.to_string().contains("at least one"), "{err}");
    }

    #[test]
    fn malformed_toml_names_the_line() {
        let text = replace(EXAMPLE, "up     = [0.0, 1.0, 0.0]", "up     = [0.0, 1.0 0.0]");
        let err = parse_desc(&text, Path::new("dir/scene.toml")).expect_err("malformed");
        let msg = err.to_string();
        assert!(matches!(err, SceneError::Toml { line: Some(5), .. }), "{msg}");
        assert!(msg.starts_with("dir/scene.toml:5: "), "{msg}");
        assert!(!msg.contains('\n'));
        // An unterminated array is noticed on the next line.
        let text = replace(EXAMPLE, "up     = [0.0, 1.0, 0.0]", "up     = [0.0, 1.0, 0.0");
        let err = parse_desc(&text, Path::new("scene.toml")).expect_err("unterminated");
        assert!(err.to_string().starts_with("scene.toml:6: "), "{err}");
        // Wrong type.
        let text = replace(EXAMPLE, "width  = 256", "width  = \"wide\"");
        let err = parse_desc(&text, Path::new("scene.toml")).expect_err("type");
        assert!(err.to_string().starts_with("scene.toml:11: "), "{err}");
    }

    #[test]
    fn out_of_range_values_are_rejected() {
        let bad = [
            ("fov_y  = 39.3", "fov_y = 0.0", "fov_y"),
            ("fov_y  = 39.3", "fov_y = 180.0", "fov_y"),
            ("fov_y  = 39.3", "fov_y = -10", "fov_y"),
            ("intensity = [5.0, 5.0, 5.0]", "intensity = [5.0, -1.0, 5.0]", "intensity"),
            ("intensity = [5.0, 5.0, 5.0]", "intensity = [5.0, inf, 5.0]", "intensity"),
            ("intensity = [5.0, 5.0, 5.0]", "intensity = [5.0, nan, 5.0]", "intensity"),
            ("position  = [0.0, 1.8, 0.0]", "position = [0.0, inf, 0.0]", "position"),
            ("width  = 256", "width = 0", "width"),
            ("height = 256", "height = 16385", "height"),
            ("target = [0.0, 1.0, 0.0]", "target = [0.0, 1.0, 3.9]", "coincide"),
            ("up     = [0.0, 1.0, 0.0]", "up = [0.0, 0.0, 1.0]", "parallel"),
        ];
        for (from, to, what) in bad {
            let text = replace(EXAMPLE, from, to);
            let err = parse_desc(&text, Path::new("scene.toml")).expect_err(to);
            let msg = err.to_string();
            assert!(msg.contains(what) && msg.starts_with("scene.toml"), "{to}: {msg}");
            assert!(!msg.contains('\n'));
        }
        // Negative width is a TOML type error (u32).
        let text = replace(EXAMPLE, "width  = 256", "width = -3");
        assert!(matches!(parse_desc(&text, Path::new("scene.toml")), Err(SceneError::Toml { .. })));
        // 17 lights.
        let mut text = EXAMPLE.to_string();
        for _ in 0..16 {
            text += "[[light]]\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\n";
        }
        let err = parse_desc(&text, Path::new("scene.toml")).expect_err("17 lights");
        assert!(err.to_string().contains("at most 16"), "{err}");
    }

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

    #[test]
    fn obj_errors_carry_line_numbers() {
        let dir = temp_dir("objerr");
        let cases = [
            ("v 0 0 0\nv 1 0 0\nv 0 nan 1\nf 1 2 3\n", 3, "non-finite"),
            ("v 0 0 0\nv 1 0 0\nv 0 inf 1\nf 1 2 3\n", 3, "non-finite"),
            ("v 0 0 0\nv 1 0 0\nv 0 1e39 1\nf 1 2 3\n", 3, "non-finite"),
            ("v 0 0 0\nv 1 0 0\nv 0 0 1\n\nf 1 2 4\n", 5, "out of range"),
            ("v 0 0 0\nv 1 0 0\nv 0 0 1\nf -1 -2 -4\n", 4, "out of range"),
            ("v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 0\n", 4, "index 0"),
            ("v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1/1 2/1 3/1\n", 4, "texture coordinate index 1"),
            ("v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 x\n", 4, "malformed"),
            ("v 0 0\n", 1, "three numbers"),
        ];
        for (obj, line, what) in cases {
            write(&dir, "room.obj", obj);
            let err = Scene::from_toml_str(EXAMPLE, &dir.join("scene.toml")).expect_err(obj);
            let msg = err.to_string();
            let want = format!("room.obj:{line}: ");
            assert!(msg.contains(&want) && msg.contains(what), "{obj:?}: {msg}");
        }
        // An empty mesh is an error too.
        write(&dir, "room.obj", "# nothing\n");
        let err = Scene::from_toml_str(EXAMPLE, &dir.join("scene.toml")).expect_err("empty");
        assert!(err.to_string().contains("no faces"), "{err}");
    }

    #[test]
    fn face_normals_vn_and_degenerate_triangles() {
        let dir = temp_dir("normals");
        let obj = "\
v 0 0 0
v 1 0 0
v 0 1 0
v 2 2 2
vn 0 0 2
vn 0 0 0
vn 1 1 0
g with_vn
f 1//1 2//1 3//3
g face_only
f 1 2 3
g bad_vn
f 1//2 2//1 3//1
g degenerate
f 1 1 2
f 4 4 4
";
        write(&dir, "room.obj", obj);
        let s = Scene::from_toml_str(EXAMPLE, &dir.join("scene.toml")).expect("loads");
        assert_eq!(s.triangle_count(), 5);
        assert_eq!(s.vertices.len(), 15);
        let n = |t: usize, c: usize| s.vertices[3 * t + c].normal();
        // vn given for all corners: normalized.
        assert_eq!(n(0, 0), Vec3::Z);
        assert_eq!(n(0, 1), Vec3::Z);
        assert!((n(0, 2) - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
        // No vn: face normal of a counter-clockwise triangle in the z=0 plane is +z.
        for c in 0..3 {
            assert_eq!(n(1, c), Vec3::Z);
        }
        // A zero vn falls back to the face normal for the whole face.
        for c in 0..3 {
            assert_eq!(n(2, c), Vec3::Z);
        }
        assert_eq!(s.stats.repaired_normals, 1);
        // Degenerate: kept, unit, finite.
        for t in 3..5 {
            for c in 0..3 {
                assert!(n(t, c).is_finite() && (n(t, c).length() - 1.0).abs() < 1e-6);
            }
        }
        assert_eq!(s.stats.degenerate_triangles, 2);
        // No mtllib: everything is the grey default; UVs are zero.
        assert_eq!(s.materials.len(), 1);
        assert_eq!(s.materials[0].kd_tex, [0.5, 0.5, 0.5, -1.0]);
        assert!(s.tri_material.iter().all(|&m| m == 0));
        assert!(s.vertices.iter().all(|v| v.uv() == glam::Vec2::ZERO));
        // Positions are stored relative to the bounds' centre (the local origin).
        assert_eq!(s.origin, glam::DVec3::splat(1.0));
        assert_eq!(s.bounds_min, Vec3::splat(-1.0));
        assert_eq!(s.bounds_max, Vec3::splat(1.0));
    }

    #[test]
    fn materials_kd_defaults_and_unknown_names() {
        let dir = temp_dir("mtl");
        write(
            &dir,
            "room.obj",
            "mtllib\tm.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n  usemtl\tnokd\nf 1 2 3\nusemtl missing\nf 1 2 3\nusemtl grey1\nf 1 2 3\n",
        );
        write(
            &dir,
            "m.mtl",
            "newmtl red\n  Ka 1 0\n  Kd 0.8 0.1 0.05 # red\n  Ns\n  d 1\nnewmtl nokd\nillum 2\nnewmtl grey1\nKd 0.25\n",
        );
        let s = Scene::from_toml_str(EXAMPLE, &dir.join("scene.toml")).expect("loads");
        let kd = |t: usize| s.materials[s.tri_material[t] as usize].kd_tex;
        assert_eq!(kd(0), [0.8, 0.1, 0.05, -1.0]);
        assert_eq!(kd(1), [0.5, 0.5, 0.5, -1.0]);
        assert_eq!(kd(2), [0.5, 0.5, 0.5, -1.0]);
        assert_eq!(kd(3), [0.25, 0.25, 0.25, -1.0]);

        // Several libraries on one mtllib line.
        write(
            &dir,
            "room.obj",
            "mtllib a.mtl b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 1 2 3\n",
        );
        write(&dir, "a.mtl", "newmtl a\nKd 0.1 0.2 0.3\n");
        write(&dir, "b.mtl", "newmtl b\nKd 0.4 0.5 0.6\n");
        let s = Scene::from_toml_str(EXAMPLE, &dir.join("scene.toml")).expect("loads");
        let kd = |t: usize| s.materials[s.tri_material[t] as usize].kd_tex;
        assert_eq!(kd(0), [0.1, 0.2, 0.3, -1.0]);
        assert_eq!(kd(1), [0.4, 0.5, 0.6, -1.0]);

        write(&dir, "room.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        write(&dir, "m.mtl", "newmtl red\nKd 0.8 0.1\n");
        let err = Scene::from_toml_str(EXAMPLE, &dir.join("scene.toml")).expect_err("bad Kd");
        assert!(err.to_string().contains("m.mtl:2: "), "{err}");
    }

    #[test]
    fn texture_round_trips_into_texels() {
        let dir = temp_dir("texture");
        // 3×2 RGBA image with distinct sRGB values; row 0 is the top row of the PNG.
        let px: [[u8; 4]; 6] =
            [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255], [10, 20, 30, 40], [128, 64, 32, 255], [1, 2, 3, 4]];
        let raw: Vec<u8> = px.iter().flatten().copied().collect();
        let img = image::RgbaImage::from_raw(3, 2, raw).expect("image");
        std::fs::create_dir_all(dir.join("tex")).expect("mkdir");
        img.save(dir.join("tex").join("ab.png")).expect("save png");
        write(
            &dir,
            "room.obj",
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0.25 0.75\nusemtl t\nf 1/1 2/2 3/3\nusemtl t2\nf 1/1 2/2 3/3\n",
        );
        write(&dir, "m.mtl", "newmtl t\nmap_Kd -bm 1 tex\\ab.png\nnewmtl t2\nKd 0.5 0.5 0.5\nmap_Kd tex/ab.png\n");
        let s = Scene::from_toml_str(EXAMPLE, &dir.join("scene.toml")).expect("loads");
        // Both materials share one texture.
        assert_eq!(s.textures.len(), 1);
        assert_eq!(s.textures[0], TextureInfo { offset: 0, width: 3, height: 2, pad: 0 });
        let want: Vec<u32> = px.iter().map(|p| u32::from_le_bytes(*p)).collect();
        assert_eq!(s.texels, want);
        assert_eq!(s.texels[0] & 0xff, 255, "r is the low byte");
        // map_Kd without Kd: Kd = 1.
        assert_eq!(s.materials[s.tri_material[0] as usize].kd_tex, [1.0, 1.0, 1.0, 0.0]);
        assert_eq!(s.materials[s.tri_material[1] as usize].kd_tex, [0.5, 0.5, 0.5, 0.0]);
        // Raw UVs are stored (no flip).
        assert_eq!(s.vertices[2].uv(), glam::Vec2::new(0.25, 0.75));
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
        let (near, far) = s.depth_range();
        assert!(near > 0.0 && near < 0.01 && far > 5.0 && far < 6.0, "{near} {far}");
        let summary = s.summary();
        assert!(summary.contains("36 triangles") && !summary.contains('\n'), "{summary}");
    }
}
