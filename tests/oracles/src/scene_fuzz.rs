//! The scene loader's robustness contract as one function, shared by the `cargo fuzz` target
//! (`tests/fuzz/fuzz_targets/scene.rs`) and the corpus replay test (`tests/tests/fuzz_corpus.rs`).
//!
//! [`check_load`] turns fuzzer bytes into the files of a scene (TOML, OBJ, MTL, PNG texture) in a
//! directory, loads them with [`Scene::load`], and panics if the contract is broken:
//! - an error is one non-empty line (what `bounce render` prints after `error:`);
//! - a loaded scene is usable: finite positions, unit finite normals, finite UVs, material and texture
//!   indices in range, finite non-negative albedo, a valid camera, finite lights with intensity ≥ 0.
//!
//! Input layout: byte 0 picks the mode, the rest is split at each `\n#--\n` (a comment line in all three
//! text formats, so mutations tend to keep the parts apart).
//! - even mode: parts are `scene.toml`, `mesh.obj`, `mesh.mtl`, `tex.png`;
//! - odd mode: `scene.toml` is the fixed valid [`FIXED_TOML`] and the parts are `mesh.obj`, `mesh.mtl`,
//!   `tex.png` (the fuzzer's effort goes into the mesh formats).
//!
//! A part that is absent leaves its file absent, so missing-file paths are exercised too.

use bounce_scene::scene::Scene;
use std::path::Path;

/// The part separator.
pub const SEPARATOR: &[u8] = b"\n#--\n";

/// The scene file of odd-mode inputs.
pub const FIXED_TOML: &str = "mesh = \"mesh.obj\"\n[camera]\neye = [0.0, 1.0, 3.0]\ntarget = [0.0, 1.0, 0.0]\n\
up = [0.0, 1.0, 0.0]\nfov_y = 60.0\n[[light]]\nposition = [0.0, 1.9, 0.0]\nintensity = [1.0, 1.0, 1.0]\n";

const NAMES: [&str; 4] = ["scene.toml", "mesh.obj", "mesh.mtl", "tex.png"];

fn split(data: &[u8]) -> Vec<&[u8]> {
    let mut parts = vec![];
    let mut rest = data;
    while let Some(i) = rest.windows(SEPARATOR.len()).position(|w| w == SEPARATOR) {
        parts.push(&rest[..i]);
        rest = &rest[i + SEPARATOR.len()..];
    }
    parts.push(rest);
    parts
}

/// Writes the scene files of `data` into `dir` (created if needed), loads `dir/scene.toml` and checks
/// the contract. Panics when it is broken; returns whether the scene loaded.
pub fn check_load(data: &[u8], dir: &Path) -> bool {
    let Some((&mode, rest)) = data.split_first() else { return false };
    std::fs::create_dir_all(dir).expect("fuzz dir");
    let mut parts = split(rest);
    let names: &[&str] = if mode % 2 == 1 {
        std::fs::write(dir.join(NAMES[0]), FIXED_TOML).expect("write");
        &NAMES[1..]
    } else {
        &NAMES
    };
    parts.truncate(names.len());
    for (k, name) in names.iter().enumerate() {
        let path = dir.join(name);
        match parts.get(k) {
            Some(bytes) => std::fs::write(&path, bytes).expect("write"),
            None => {
                let _ = std::fs::remove_file(&path);
            }
        }
    }
    match Scene::load(&dir.join(NAMES[0])) {
        Err(e) => {
            let msg = e.to_string();
            assert!(!msg.is_empty() && !msg.contains('\n') && !msg.contains('\r'), "error is not one line: {msg:?}");
            false
        }
        Ok(s) => {
            check_scene(&s);
            true
        }
    }
}

/// The invariants a loaded scene promises its users (the GPU upload, the CPU references).
pub fn check_scene(s: &Scene) {
    assert_eq!(s.vertices.len(), 3 * s.tri_material.len(), "one material per triangle");
    for v in &s.vertices {
        assert!(v.position().is_finite(), "non-finite position {:?}", v.position());
        let n = v.normal();
        assert!(n.is_finite() && (n.length() - 1.0).abs() < 1e-3, "bad normal {n:?}");
        assert!(v.uv().is_finite(), "non-finite uv");
    }
    for &m in &s.tri_material {
        assert!((m as usize) < s.materials.len(), "material index out of range");
    }
    for m in &s.materials {
        let kd = m.kd();
        assert!(kd.is_finite() && kd.min_element() >= 0.0, "bad albedo {kd:?}");
        if let Some(t) = m.texture() {
            assert!(t < s.textures.len(), "texture index out of range");
        }
    }
    for t in &s.textures {
        let end = t.offset as usize + t.width as usize * t.height as usize;
        assert!(t.width > 0 && t.height > 0 && end <= s.texels.len(), "texture out of range");
    }
    s.camera.validate().expect("camera");
    assert!(!s.lights.is_empty());
    for l in &s.lights {
        assert!(l.position.iter().all(|x| x.is_finite()), "light position");
        assert!(l.intensity.iter().all(|x| x.is_finite() && *x >= 0.0), "light intensity");
    }
    assert!(s.bounds_min.is_finite() && s.bounds_max.is_finite() && s.origin.is_finite(), "bounds");
}
