//! The OBJ mesh: a line-numbered pre-scan ([`prescan_obj`]), tobj's parse (with the material
//! libraries through [`super::mtl`]), and the flattening into the non-indexed vertex list of the
//! contract (f64 positions made local to the bounds' centre, face or `vn` normals, raw `vt` UVs).
//!
//! Input: the OBJ path from the scene description; output: [`MeshData`], which [`super::Scene`]
//! takes over. Errors are [`SceneError::Mesh`] (`file:line:` where the pre-scan knows the line),
//! [`SceneError::Io`], or the material and texture errors of `mtl` and `textures`.

use super::{mesh_err, mtl, SceneError, DEFAULT_ALBEDO};
use crate::layout::{Material, TextureInfo, Vertex};
use glam::{DVec3, Vec3};
use std::cell::RefCell;
use std::path::{Path, PathBuf};

/// The flattened mesh, before camera and lights join it.
pub(super) struct MeshData {
    /// World position of the local origin (the centre of the positions' bounds).
    pub origin: DVec3,
    /// Positions relative to `origin`.
    pub vertices: Vec<Vertex>,
    pub tri_material: Vec<u32>,
    pub materials: Vec<Material>,
    pub textures: Vec<TextureInfo>,
    pub texels: Vec<u32>,
    pub degenerate: usize,
    pub repaired_normals: usize,
}

pub(super) fn make_vertex(p: Vec3, n: Vec3, uv: [f32; 2]) -> Vertex {
    Vertex { position_u: [p.x, p.y, p.z, uv[0]], normal_v: [n.x, n.y, n.z, uv[1]] }
}

/// Unit face normal `normalize(cross(p1 − p0, p2 − p0))`, or `None` for a zero-area or non-finite
/// triangle. Computed in f64 so tiny-but-valid triangles do not underflow to a zero vector.
pub(super) fn face_normal(p: [DVec3; 3]) -> Option<Vec3> {
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

/// The kinds of OBJ data a face corner indexes (`v/vt/vn`), as messages name them.
const KINDS: [&str; 3] = ["vertex", "texture coordinate", "normal"];

/// The pre-scan's state: how many `v`, `vt`, `vn` lines came so far, and per kind the largest
/// absolute (positive) index and the line that used it, checked at the end against the final counts
/// (tobj resolves positive indices after reading the whole file).
struct ObjScan<'a> {
    path: &'a Path,
    counts: [usize; 3],
    max_abs: [(usize, usize); 3],
}

/// Validates the OBJ line by line before tobj sees it, and returns the text tobj gets.
///
/// Why a second scanner beside tobj: tobj reports no line numbers (and its errors name no
/// statement), and it accepts non-finite coordinates (Rust's float parser takes `nan` and `inf`, and
/// `1e39` is finite in tobj's f64 but not in the f32 the GPU gets), so every `file:line:` message of
/// the contract needs this pass; post-checks on tobj's output could only say `file:`. It is kept to
/// what needs a line: the numbers of `v`/`vt`/`vn`, the indices of `f`, and the lines tobj
/// mis-parses, which it normalizes:
/// * `mtllib`/`usemtl` with leading whitespace or a tab separator (tobj splits at the first space);
/// * `mtllib a.mtl b.mtl` (several libraries, allowed by the spec; tobj reads one file name with
///   spaces) becomes one `mtllib` line per file, unless a file with the spaced name exists;
/// * `l` polylines (tobj treats a 3-point polyline as a triangle) are blanked.
fn prescan_obj(text: &str, path: &Path) -> Result<String, SceneError> {
    let obj_dir = path.parent().unwrap_or(Path::new(""));
    let mut scan = ObjScan { path, counts: [0; 3], max_abs: [(0, 0); 3] };
    let mut out = String::with_capacity(text.len() + 64);
    for (k, line) in text.lines().enumerate() {
        let lineno = k + 1;
        let trimmed = line.trim_start();
        let mut toks = trimmed.split_whitespace();
        match toks.next() {
            Some("v") => scan.numbers(0, toks, lineno)?,
            Some("vt") => scan.numbers(1, toks, lineno)?,
            Some("vn") => scan.numbers(2, toks, lineno)?,
            Some("f") => scan.face(toks, lineno)?,
            // Polylines are not surfaces; keep the line count.
            Some("l") => {
                out.push('\n');
                continue;
            }
            Some(kw @ ("mtllib" | "usemtl")) => {
                let rest = trimmed[kw.len()..].trim();
                if rest.is_empty() {
                    return Err(mesh_err(path, Some(lineno), format!("{kw} without a name")));
                }
                if kw == "mtllib" && rest.contains(char::is_whitespace) && !obj_dir.join(rest).is_file() {
                    for name in rest.split_whitespace() {
                        out.push_str(&format!("mtllib {name}\n"));
                    }
                } else {
                    out.push_str(&format!("{kw} {rest}\n"));
                }
                continue;
            }
            _ => {}
        }
        out.push_str(line);
        out.push('\n');
    }
    scan.finish()?;
    Ok(out)
}

impl ObjScan<'_> {
    /// A `v` (kind 0), `vt` (1) or `vn` (2) line: three numbers (`vt`: u and v; tobj needs both, while
    /// the spec allows a lone u), and finite ones for a position.
    fn numbers(&mut self, kind: usize, mut toks: std::str::SplitWhitespace, lineno: usize) -> Result<(), SceneError> {
        let (n, what) = [
            (3, "vertex position needs three numbers"),
            (2, "texture coordinate needs u and v"),
            (3, "vertex normal needs three numbers"),
        ][kind];
        let mut v = Vec::with_capacity(n);
        for _ in 0..n {
            match toks.next().and_then(|t| t.parse::<f32>().ok()) {
                Some(x) => v.push(x),
                None => return Err(mesh_err(self.path, Some(lineno), what)),
            }
        }
        if kind == 0 && !v.iter().all(|x| x.is_finite()) {
            return Err(mesh_err(self.path, Some(lineno), format!("non-finite vertex position {v:?}")));
        }
        self.counts[kind] += 1;
        Ok(())
    }

    /// An `f` line: at least three corners, each `v`, `v/vt`, `v//vn` or `v/vt/vn` with nonzero
    /// indices, relative ones within what is defined so far.
    fn face(&mut self, toks: std::str::SplitWhitespace, lineno: usize) -> Result<(), SceneError> {
        let err = |msg: String| mesh_err(self.path, Some(lineno), msg);
        let mut corners = 0;
        for corner in toks {
            corners += 1;
            for (slot, part) in corner.split('/').enumerate() {
                if slot >= 3 {
                    return Err(err(format!("malformed face corner `{corner}`")));
                }
                if part.is_empty() {
                    if slot == 0 {
                        return Err(err(format!("face corner `{corner}` has no vertex index")));
                    }
                    continue;
                }
                let idx: isize = part.parse().map_err(|_| err(format!("malformed face corner `{corner}`")))?;
                if idx == 0 {
                    return Err(err(format!("{} index 0 in `{corner}` (OBJ indices start at 1)", KINDS[slot])));
                }
                if idx < 0 {
                    if idx.unsigned_abs() > self.counts[slot] {
                        return Err(err(format!(
                            "relative {} index {idx} in `{corner}` is out of range (only {} defined so far)",
                            KINDS[slot], self.counts[slot]
                        )));
                    }
                } else if idx as usize > self.max_abs[slot].0 {
                    self.max_abs[slot] = (idx as usize, lineno);
                }
            }
        }
        if corners < 3 {
            return Err(err(format!("face has {corners} corners, at least 3 are needed")));
        }
        Ok(())
    }

    /// The absolute indices against the whole file's counts.
    fn finish(&self) -> Result<(), SceneError> {
        for ((&(idx, lineno), &count), kind) in self.max_abs.iter().zip(&self.counts).zip(KINDS) {
            if idx > count {
                return Err(mesh_err(
                    self.path,
                    Some(lineno),
                    format!("{kind} index {idx} is out of range (the file defines {count})"),
                ));
            }
        }
        Ok(())
    }
}

/// Loads the OBJ at `obj_path` (with its MTL libraries and textures) and flattens it.
pub(super) fn load_mesh(obj_path: &Path) -> Result<MeshData, SceneError> {
    let bytes = std::fs::read(obj_path).map_err(|source| SceneError::Io { path: obj_path.to_path_buf(), source })?;
    // Lossy: stray Latin-1 bytes in comments or group names must not make the file unreadable.
    let text = prescan_obj(&String::from_utf8_lossy(&bytes), obj_path)?;
    drop(bytes);
    let (models, tobj_materials, libs) = parse_obj(&text, obj_path)?;
    let (mut materials, textures) = mtl::materials(&tobj_materials, &libs, obj_path)?;
    let origin = local_origin(&models);
    let flat = flatten(&models, &mut materials, origin, obj_path)?;
    Ok(MeshData {
        origin,
        vertices: flat.vertices,
        tri_material: flat.tri_material,
        materials,
        textures: textures.infos,
        texels: textures.texels,
        degenerate: flat.degenerate,
        repaired_normals: flat.repaired_normals,
    })
}

/// The pre-scanned OBJ `text` through tobj: its models, its materials, and `(mtl file, number of
/// materials it contributed)` in load order (tobj appends each library's materials, so these ranges
/// map a material index back to its file, for texture paths).
#[allow(clippy::type_complexity)]
fn parse_obj(
    text: &str,
    obj_path: &Path,
) -> Result<(Vec<tobj::Model>, Vec<tobj::Material>, Vec<(PathBuf, usize)>), SceneError> {
    let obj_dir = obj_path.parent().unwrap_or(Path::new("")).to_path_buf();
    // tobj's material loader cannot return our error type; stash the first failure here.
    let mtl_error: RefCell<Option<SceneError>> = RefCell::new(None);
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
    let loaded = tobj::load_obj_buf(&mut std::io::Cursor::new(text.as_bytes()), &options, |rel: &Path| {
        let full = obj_dir.join(rel);
        let result = mtl::read_library(&full).and_then(|t| {
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
    Ok((models, tobj_materials, libs.into_inner()))
}

/// The local origin: the centre of all positions' bounds, in f64 (non-finite positions are rejected
/// by [`flatten`], where a face uses them).
fn local_origin(models: &[tobj::Model]) -> DVec3 {
    let (lo, hi) = models
        .iter()
        .flat_map(|m| m.mesh.positions.chunks_exact(3))
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .filter(|p| p.is_finite())
        .fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), p| (lo.min(p), hi.max(p)));
    if lo.x <= hi.x {
        (lo + hi) * 0.5
    } else {
        DVec3::ZERO
    }
}

/// The triangles of every model, flattened.
struct Flat {
    vertices: Vec<Vertex>,
    tri_material: Vec<u32>,
    degenerate: usize,
    repaired_normals: usize,
}

/// Flattens tobj's models into the non-indexed list, positions relative to `origin`. Faces without a
/// known material get a grey default, appended to `materials` only if some face needs it.
fn flatten(
    models: &[tobj::Model],
    materials: &mut Vec<Material>,
    origin: DVec3,
    obj_path: &Path,
) -> Result<Flat, SceneError> {
    let mut default_material: Option<u32> = None;
    let triangles: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
    let mut flat = Flat {
        vertices: Vec::with_capacity(triangles * 3),
        tri_material: Vec::with_capacity(triangles),
        degenerate: 0,
        repaired_normals: 0,
    };
    for model in models {
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
        let vn =
            |i: usize| unit_normal(DVec3::new(mesh.normals[3 * i], mesh.normals[3 * i + 1], mesh.normals[3 * i + 2]));
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
                flat.degenerate += 1;
                Vec3::Y
            });
            let mut normals = [face; 3];
            if has_normals {
                if let [Some(a), Some(b), Some(c)] = idx.map(vn) {
                    normals = [a, b, c];
                } else {
                    flat.repaired_normals += 1;
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
                let at = (p[c] - origin).as_vec3();
                if !at.is_finite() {
                    // tobj divides by a fourth coordinate (w): `v 0 1 0 1e-300` passes the f32 prescan.
                    return Err(mesh_err(obj_path, None, "a vertex lies beyond f32's range (a tiny w coordinate?)"));
                }
                flat.vertices.push(make_vertex(at, normals[c], uv));
            }
            flat.tri_material.push(mat);
        }
    }
    Ok(flat)
}

#[cfg(test)]
mod tests {
    use super::super::test_files::*;
    use super::super::Scene;
    use glam::Vec3;

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
}
