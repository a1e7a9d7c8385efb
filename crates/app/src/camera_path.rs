//! Scripted camera motion (`--camera-path`), for `view --frames N`, `render --frames N --out-dir DIR`
//! and `bench --animate`, alone or with a light path: where the camera is at frame k of an animation.
//!
//! - `orbit[:PERIOD]`: the eye circles its start in the horizontal plane while it keeps looking at the
//!   scene's target, e_k = e_0 + r · (cos θ_k − 1, 0, sin θ_k), θ_k = 2πk / PERIOD (default
//!   `light_path::ORBIT_PERIOD` frames), r = [`ORBIT_RADIUS`] × the scene diagonal: frame 0 is the scene's own
//!   view, and every frame both turns and moves the camera (what reprojection must follow).
//! - `FILE.toml`: keyframes, `[[key]]` tables of `frame`, `eye` and `target` (world coordinates, as in
//!   the scene file) and an optional `fov_y` (degrees; a key without one keeps the previous key's, the
//!   first the scene's). Between two keys the eye, target and field of view are interpolated linearly
//!   in the frame number; before the first key the camera is at the first key, after the last at the
//!   last.
//!
//! A malformed file, an eye on its target or a field of view outside (0, 180) is refused: one `error:`
//! line, exit 2.

use crate::error::bad;
use crate::light_path::{lerp, orbit_period, read_toml, ORBIT_RADIUS};
use anyhow::Result;
use bounce_graph::camera::Camera;
use bounce_graph::frame::Renderer;
use bounce_graph::scene::Scene;
use glam::Vec3;
use serde::Deserialize;
use std::path::Path;

/// Where the camera is at every frame.
#[derive(Clone, Debug)]
pub struct CameraPath {
    start: Camera,
    motion: Motion,
}

#[derive(Clone, Debug)]
enum Motion {
    Orbit {
        period: u32,
        radius: f32,
    },
    /// Sorted by frame, fields of view resolved.
    Keys(Vec<(u32, Camera)>),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyFile {
    key: Vec<KeyEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyEntry {
    frame: u32,
    eye: [f64; 3],
    target: [f64; 3],
    fov_y: Option<f32>,
}

impl CameraPath {
    /// `orbit`, `orbit:PERIOD` or a keyframe file, for `scene`'s camera. Bad input is a [`bad`] error.
    pub fn parse(arg: &str, scene: &Scene) -> Result<CameraPath> {
        let start = scene.camera;
        let motion = match orbit_period(arg, "--camera-path")? {
            Some(period) => Motion::Orbit { period, radius: ORBIT_RADIUS * scene.diagonal() },
            None => Motion::Keys(read_keys(Path::new(arg), scene)?),
        };
        Ok(CameraPath { start, motion })
    }

    /// The camera at frame `k`.
    pub fn at(&self, k: u32) -> Camera {
        match &self.motion {
            Motion::Orbit { period, radius } => {
                let theta = std::f64::consts::TAU * (k % period) as f64 / *period as f64;
                let offset = Vec3::new(theta.cos() as f32 - 1.0, 0.0, theta.sin() as f32) * *radius;
                Camera { eye: self.start.eye + offset, ..self.start }
            }
            Motion::Keys(keys) => {
                let after = keys.partition_point(|(f, _)| *f <= k);
                match (after, keys.get(after)) {
                    (0, _) => keys[0].1,
                    (_, None) => keys[after - 1].1,
                    (_, Some(&(f1, b))) => {
                        let (f0, a) = keys[after - 1];
                        let t = (k - f0) as f32 / (f1 - f0) as f32;
                        Camera {
                            eye: lerp(a.eye, b.eye, t),
                            target: lerp(a.target, b.target, t),
                            fov_y_deg: a.fov_y_deg + (b.fov_y_deg - a.fov_y_deg) * t,
                            ..a
                        }
                    }
                }
            }
        }
    }

    /// Puts the renderer's camera where it is at frame `k`.
    pub fn apply(&self, r: &mut Renderer, k: u32) {
        r.set_camera(self.at(k));
    }
}

/// The keyframe file's keys, checked.
fn read_keys(path: &Path, scene: &Scene) -> Result<Vec<(u32, Camera)>> {
    let file: KeyFile = read_toml(path, "--camera-path")?;
    let mut entries = file.key;
    entries.sort_by_key(|e| e.frame);
    let mut keys: Vec<(u32, Camera)> = vec![];
    for e in entries {
        let fail = |what: &str| bad(anyhow::anyhow!("{}: the key at frame {}: {what}", path.display(), e.frame));
        let local = |p: [f64; 3]| (glam::DVec3::from_array(p) - scene.origin).as_vec3();
        let (eye, target) = (local(e.eye), local(e.target));
        if !(eye.is_finite() && target.is_finite()) || (target - eye).length() <= 1e-6 * scene.diagonal() {
            return Err(fail("the eye must be finite and away from its target"));
        }
        let fov = e.fov_y.unwrap_or(keys.last().map_or(scene.camera.fov_y_deg, |(_, c)| c.fov_y_deg));
        if !(fov > 0.0 && fov < 180.0) {
            return Err(fail("fov_y must be in (0, 180) degrees"));
        }
        if keys.last().is_some_and(|(f, _)| *f == e.frame) {
            return Err(fail("a second key for the same frame"));
        }
        let camera = Camera { eye, target, fov_y_deg: fov, ..scene.camera };
        camera.validate().map_err(|m| fail(&m))?;
        if let Some(&(f0, a)) = keys.last() {
            between(a, camera).map_err(|m| {
                bad(anyhow::anyhow!("{}: between the keys at frames {f0} and {}: {m}", path.display(), e.frame))
            })?;
        }
        keys.push((e.frame, camera));
    }
    if keys.is_empty() {
        return Err(bad(anyhow::anyhow!("{}: no [[key]]", path.display())));
    }
    Ok(keys)
}

/// Whether the cameras interpolated between keys `a` and `b` all have a view: the view direction
/// d(t) = (1 − t) d_a + t d_b is never zero nor along `up`. Its part across `up` is linear in t, so its
/// shortest (the camera nearest to looking straight up or down) is the closest point of a segment to
/// the origin; that camera is checked as a key is.
fn between(a: Camera, b: Camera) -> Result<(), String> {
    let up = a.up.normalize();
    let across = |c: &Camera| {
        let d = c.target - c.eye;
        d - up * d.dot(up)
    };
    let (pa, pb) = (across(&a), across(&b));
    let step = pb - pa;
    let t = if step.length_squared() > 0.0 { (-pa.dot(step) / step.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
    let c = Camera { eye: lerp(a.eye, b.eye, t), target: lerp(a.target, b.target, t), ..a };
    c.validate().map_err(|m| format!("at {:.0} % of the way, {m}", 100.0 * t))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(x: f32) -> Camera {
        Camera { eye: Vec3::new(x, 1.0, 0.0), target: Vec3::new(x, 1.0, -1.0), up: Vec3::Y, fov_y_deg: 40.0 + x }
    }

    #[test]
    fn keyframes_interpolate_linearly_and_hold_outside_their_range() {
        let p = CameraPath { start: cam(0.0), motion: Motion::Keys(vec![(10, cam(1.0)), (20, cam(3.0))]) };
        assert_eq!(p.at(0).eye, cam(1.0).eye);
        assert_eq!(p.at(15).eye, cam(2.0).eye);
        assert_eq!(p.at(15).fov_y_deg, 42.0);
        assert_eq!(p.at(99).target, cam(3.0).target);
    }

    #[test]
    fn the_cameras_between_keys_must_have_a_view() {
        let look = |eye: Vec3, target: Vec3| Camera { eye, target, up: Vec3::Y, fov_y_deg: 40.0 };
        let (a, b) = (look(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0)), look(Vec3::X, Vec3::new(1.0, 0.5, -1.0)));
        assert_eq!(between(a, b), Ok(()));
        // Eye and target trade places: halfway they coincide.
        let swapped = look(Vec3::new(0.0, 0.0, -1.0), Vec3::ZERO);
        assert!(between(a, swapped).unwrap_err().contains("coincide"), "{:?}", between(a, swapped));
        // Looking ahead and down, then back and down: halfway straight down, along up.
        let (ahead, back) = (look(Vec3::ZERO, Vec3::new(0.0, -1.0, -1.0)), look(Vec3::ZERO, Vec3::new(0.0, -1.0, 1.0)));
        assert!(between(ahead, back).unwrap_err().contains("parallel"), "{:?}", between(ahead, back));
        // A quarter turn passes nowhere near it.
        assert_eq!(between(ahead, look(Vec3::ZERO, Vec3::new(1.0, -1.0, 0.0))), Ok(()));
    }

    #[test]
    fn the_orbit_starts_at_the_scene_view_and_keeps_its_target() {
        let p = CameraPath { start: cam(0.0), motion: Motion::Orbit { period: 8, radius: 0.5 } };
        assert_eq!(p.at(0).eye, cam(0.0).eye);
        for k in 0..16 {
            let c = p.at(k);
            assert_eq!(c.target, cam(0.0).target);
            assert!(((c.eye - Vec3::new(-0.5, 1.0, 0.0)).length() - 0.5).abs() < 1e-6, "on the circle");
        }
        assert_eq!(p.at(3).eye, p.at(11).eye, "one period");
    }
}
