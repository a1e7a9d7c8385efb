//! Materials: the MTL libraries an OBJ names, sanitised for tobj ([`read_library`]), and the
//! contract's materials built from what tobj read ([`materials`]: `Kd` and `map_Kd` only, with the
//! defaults of [`super::load`]).
//!
//! Input: the library paths (resolved by tobj against the OBJ's directory) and tobj's materials;
//! output: [`Material`]s and their [`Textures`]. Errors are [`SceneError::Mesh`] with the MTL line,
//! [`SceneError::Io`], or a texture's [`SceneError::Texture`].

use super::textures::{map_kd_file, Textures};
use super::{mesh_err, SceneError, DEFAULT_ALBEDO};
use crate::layout::Material;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The MTL file at `path`, read and sanitised ([`sanitize_mtl`]) for tobj.
pub(super) fn read_library(path: &Path) -> Result<String, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io { path: path.to_path_buf(), source })?;
    sanitize_mtl(&text, path)
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

/// The contract's materials of tobj's `tobj_materials`, loaded from the libraries `libs` (`(file,
/// materials it contributed)`, in load order), with their textures. A material with `map_Kd` but no
/// `Kd` gets Kd = 1 (the texture is the albedo); with neither, [`DEFAULT_ALBEDO`].
pub(super) fn materials(
    tobj_materials: &[tobj::Material],
    libs: &[(PathBuf, usize)],
    obj_path: &Path,
) -> Result<(Vec<Material>, Textures), SceneError> {
    let mut materials = Vec::with_capacity(tobj_materials.len() + 1);
    let mut textures = Textures::default();
    let mut lib_of_material: Vec<&Path> = Vec::with_capacity(tobj_materials.len());
    for (p, n) in libs {
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
            tex = textures.get_or_load(&mtl_dir.join(file), &m.name, mtl_path)? as f32;
        }
        let kd = match m.diffuse {
            Some(kd) => kd.map(|x| x as f32),
            None if tex >= 0.0 => [1.0; 3],
            None => [DEFAULT_ALBEDO; 3],
        };
        materials.push(Material { kd_tex: [kd[0], kd[1], kd[2], tex] });
    }
    Ok((materials, textures))
}

#[cfg(test)]
mod tests {
    use super::super::test_files::*;
    use super::super::Scene;

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
}
