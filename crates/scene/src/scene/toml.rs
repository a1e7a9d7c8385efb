//! The scene file: parses and validates a scene TOML (the contract in the `scene` module doc) into a
//! [`SceneDesc`], before any mesh is read. Every table rejects unknown keys; errors are
//! [`SceneError::Toml`] (with the line, computed from toml's span) or [`SceneError::Invalid`].
//! Used by [`super::load`] and by tools that only need the camera and lights.

use super::{invalid, one_line, point_light, SceneError, MAX_LIGHTS, MAX_RENDER_DIM};
use crate::camera::Camera;
use crate::layout::Light;
use glam::{DVec3, Vec3};
use serde::Deserialize;
use std::path::{Path, PathBuf};

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

/// Parses and validates scene TOML `text` as if it were the file `path` (used in messages and to
/// resolve the relative `mesh` path). Does not touch the file system.
pub fn parse_desc(text: &str, path: &Path) -> Result<SceneDesc, SceneError> {
    let raw: SceneToml = ::toml::from_str(text).map_err(|e| SceneError::Toml {
        path: path.to_path_buf(),
        // toml's Display is a multi-line snippet; keep the message and compute the line ourselves.
        line: e.span().map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1),
        msg: one_line(e.message()),
    })?;

    let (eye, target) = (DVec3::from_array(raw.camera.eye), DVec3::from_array(raw.camera.target));
    let camera = Camera {
        eye: eye.as_vec3(),
        target: target.as_vec3(),
        up: Vec3::from_array(raw.camera.up),
        fov_y_deg: raw.camera.fov_y,
    };
    // Checked from the eye (in f64, then f32): far from the world's origin the f32 world copies cannot tell
    // a near target from the eye. The local camera is checked again once the scene is rebased.
    let from_eye = Camera { eye: Vec3::ZERO, target: (target - eye).as_vec3(), ..camera };
    let finite = eye.is_finite() && target.is_finite();
    let checked = if finite { from_eye.validate() } else { camera.validate() };
    checked.map_err(|m| invalid(path, format!("[camera]: {m}")))?;

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

#[cfg(test)]
mod tests {
    use super::super::test_files::*;
    use super::*;

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

    /// A camera far from the world's origin (UTM-like coordinates) whose target is 4 units off: its f32
    /// world copies are 0.5 apart per unit of 5e6, which a check relative to the coordinates took for
    /// coinciding points; checked from the eye it is valid. Eye on target still is not.
    #[test]
    fn a_camera_far_from_the_origin_is_checked_from_its_eye() {
        let far = replace(EXAMPLE, "eye    = [0.0, 1.0, 3.9]", "eye    = [500000.0, 100.0, 5000000.0]");
        let far = replace(&far, "target = [0.0, 1.0, 0.0]", "target = [500000.0, 100.0, 4999996.0]");
        parse_desc(&far, Path::new("s.toml")).expect("a valid far camera");
        let on = replace(&far, "target = [500000.0, 100.0, 4999996.0]", "target = [500000.0, 100.0, 5000000.0]");
        let err = parse_desc(&on, Path::new("s.toml")).expect_err("eye on target");
        assert!(err.to_string().contains("coincide"), "{err}");
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
}
