//! Scripted light motion (`--light-path`), for `view --frames N`, `render --frames N --out-dir DIR` and
//! `bench --animate`: where every light is at frame k of an animation.
//!
//! - `orbit[:PERIOD]`: every light circles its own start in the horizontal plane,
//!   p_k = p_0 + r · (cos θ_k, 0, sin θ_k), θ_k = 2πk / PERIOD (default 60 frames), with
//!   r = [`ORBIT_RADIUS`] × the scene diagonal (the camera's speed is scaled to the diagonal alike).
//! - `FILE.toml`: keyframes, `[[key]]` tables of `frame`, `light` (index into the scene's lights),
//!   `position` (world coordinates, as in the scene file) and an optional `intensity` (W/sr per channel;
//!   a key without one keeps the previous key's, the first the scene's). Between two keys of a light
//!   the position and intensity are interpolated linearly in the frame number; before its first key a
//!   light is at its first key, after its last at its last; a light without keys stays where the scene
//!   puts it.
//!
//! A keyframe outside the scene's bounds (geometry and lights: the voxel grid and the paraboloid far
//! plane are fitted to them once) is refused, as is any malformed file: one `error:` line, exit 2.

use crate::error::bad;
use anyhow::{Context, Result};
use bounce_graph::frame::Renderer;
use bounce_graph::scene::Scene;
use glam::Vec3;
use serde::Deserialize;
use std::path::Path;

/// The orbit's radius as a fraction of the scene diagonal.
pub const ORBIT_RADIUS: f32 = 0.1;
/// The orbit's period in frames when `orbit` names none.
pub const ORBIT_PERIOD: u32 = 60;

/// One light's state at a frame (scene-local position).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightState {
    pub position: Vec3,
    pub intensity: Vec3,
}

/// A light's keyframes, sorted by frame, intensities resolved.
#[derive(Clone, Debug)]
struct Track {
    keys: Vec<(u32, LightState)>,
}

/// Where every light is at every frame.
#[derive(Clone, Debug)]
pub struct LightPath {
    start: Vec<LightState>,
    motion: Motion,
}

#[derive(Clone, Debug)]
enum Motion {
    Orbit {
        period: u32,
        radius: f32,
    },
    /// One track per light (empty: the light does not move).
    Keys(Vec<Track>),
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
    light: usize,
    position: [f64; 3],
    intensity: Option<[f32; 3]>,
}

impl LightPath {
    /// `orbit`, `orbit:PERIOD` or a keyframe file, for `scene`'s lights. Bad input is a [`bad`] error.
    pub fn parse(arg: &str, scene: &Scene) -> Result<LightPath> {
        let start: Vec<LightState> = scene
            .lights
            .iter()
            .map(|l| LightState {
                position: Vec3::from_slice(&l.position[..3]),
                intensity: Vec3::from_slice(&l.intensity[..3]),
            })
            .collect();
        let motion = match orbit_period(arg, "--light-path")? {
            Some(period) => Motion::Orbit { period, radius: ORBIT_RADIUS * scene.diagonal() },
            None => Motion::Keys(read_keys(Path::new(arg), scene, &start)?),
        };
        Ok(LightPath { start, motion })
    }

    /// Every light's state at frame `k`.
    pub fn at(&self, k: u32) -> Vec<LightState> {
        match &self.motion {
            Motion::Orbit { period, radius } => {
                let theta = std::f64::consts::TAU * (k % period) as f64 / *period as f64;
                let offset = Vec3::new(theta.cos() as f32, 0.0, theta.sin() as f32) * *radius;
                self.start.iter().map(|l| LightState { position: l.position + offset, ..*l }).collect()
            }
            Motion::Keys(tracks) => {
                tracks.iter().zip(&self.start).map(|(t, s)| if t.keys.is_empty() { *s } else { t.at(k) }).collect()
            }
        }
    }

    /// Puts the renderer's lights where they are at frame `k`.
    pub fn apply(&self, r: &mut Renderer, k: u32) {
        for (i, l) in self.at(k).into_iter().enumerate() {
            r.set_light(i, l.position, l.intensity);
        }
    }
}

impl Track {
    fn at(&self, k: u32) -> LightState {
        let after = self.keys.partition_point(|(f, _)| *f <= k);
        match (after, self.keys.get(after)) {
            (0, _) => self.keys[0].1,
            (_, None) => self.keys[after - 1].1,
            (_, Some(&(f1, b))) => {
                let (f0, a) = self.keys[after - 1];
                let t = (k - f0) as f32 / (f1 - f0) as f32;
                LightState { position: lerp(a.position, b.position, t), intensity: lerp(a.intensity, b.intensity, t) }
            }
        }
    }
}

/// a + (b − a) t between two keys: exactly a where both hold the same value (glam's `lerp`,
/// a (1 − t) + b t, moves it by an ulp, and a camera an ulp away renders another image). Shared with
/// `crate::camera_path`.
pub(crate) fn lerp(a: Vec3, b: Vec3, t: f32) -> Vec3 {
    a + (b - a) * t
}

/// `Some(PERIOD)` for `orbit` (PERIOD [`ORBIT_PERIOD`]) or `orbit:PERIOD`, `None` for a keyframe file
/// (whose name may well begin with "orbit"); a malformed orbit, or neither, is a [`bad`] error naming
/// `flag`. Shared with `crate::camera_path`.
pub(crate) fn orbit_period(arg: &str, flag: &str) -> Result<Option<u32>> {
    if arg == "orbit" {
        return Ok(Some(ORBIT_PERIOD));
    }
    let Some(p) = arg.strip_prefix("orbit:") else {
        if !Path::new(arg).is_file() {
            return Err(bad(anyhow::anyhow!("{flag}: `{arg}` is neither `orbit[:PERIOD]` nor a keyframe file")));
        }
        return Ok(None);
    };
    p.parse::<u32>()
        .ok()
        .filter(|p| *p > 0)
        .map(Some)
        .ok_or_else(|| bad(anyhow::anyhow!("{flag} orbit:PERIOD needs a positive whole number of frames (got `{p}`)")))
}

/// A keyframe file read as `T`: a missing file or a TOML error is a [`bad`] error naming the file (and the
/// line). Shared with `crate::camera_path`.
pub(crate) fn read_toml<T: serde::de::DeserializeOwned>(path: &Path, flag: &str) -> Result<T> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| bad(anyhow::anyhow!("{flag} {}: {e}", path.display())))
        .context("reading a keyframe file")?;
    toml::from_str(&text).map_err(|e| {
        let msg = e.message().to_string();
        let line = e.span().map(|s| 1 + text[..s.start].matches('\n').count());
        bad(anyhow::anyhow!("{}:{}: {msg}", path.display(), line.map_or(String::new(), |l| l.to_string())))
    })
}

/// The keyframe file's tracks, checked against the scene.
fn read_keys(path: &Path, scene: &Scene, start: &[LightState]) -> Result<Vec<Track>> {
    let file: KeyFile = read_toml(path, "--light-path")?;
    let (mut lo, mut hi) = (scene.bounds_min, scene.bounds_max);
    for l in start {
        lo = lo.min(l.position);
        hi = hi.max(l.position);
    }
    let slack = 1e-4 * scene.diagonal();
    let mut tracks = vec![Track { keys: vec![] }; start.len()];
    let mut entries = file.key;
    entries.sort_by_key(|e| e.frame);
    for e in entries {
        let fail = |what: String| {
            bad(anyhow::anyhow!("{}: the key of light {} at frame {}: {what}", path.display(), e.light, e.frame))
        };
        let track = tracks.get_mut(e.light).ok_or_else(|| fail(format!("the scene has {} light(s)", start.len())))?;
        let world = glam::DVec3::from_array(e.position);
        let p = (world - scene.origin).as_vec3();
        if !(p.cmpge(lo - slack).all() && p.cmple(hi + slack).all()) {
            return Err(fail(format!(
                "position {:?} lies outside the scene's bounds {:?}..{:?} (world coordinates)",
                e.position,
                (lo.as_dvec3() + scene.origin).to_array(),
                (hi.as_dvec3() + scene.origin).to_array()
            )));
        }
        if track.keys.last().is_some_and(|(f, _)| *f == e.frame) {
            return Err(fail("a second key for the same light and frame".into()));
        }
        let previous = track.keys.last().map_or(start[e.light].intensity, |(_, s)| s.intensity);
        let intensity = e.intensity.map_or(previous, Vec3::from_array);
        if !intensity.is_finite() || intensity.min_element() < 0.0 {
            return Err(fail(format!("intensity {intensity:?} must be finite and non-negative")));
        }
        track.keys.push((e.frame, LightState { position: p, intensity }));
    }
    Ok(tracks)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track(keys: &[(u32, f32)]) -> Track {
        let s = |x: f32| LightState { position: Vec3::splat(x), intensity: Vec3::splat(2.0 * x) };
        Track { keys: keys.iter().map(|&(f, x)| (f, s(x))).collect() }
    }

    #[test]
    fn keyframes_interpolate_linearly_and_hold_outside_their_range() {
        let t = track(&[(10, 1.0), (20, 3.0), (30, 0.0)]);
        assert_eq!(t.at(0).position, Vec3::splat(1.0));
        assert_eq!(t.at(10).position, Vec3::splat(1.0));
        assert_eq!(t.at(15).position, Vec3::splat(2.0));
        assert_eq!(t.at(15).intensity, Vec3::splat(4.0));
        assert_eq!(t.at(20).position, Vec3::splat(3.0));
        // 3 + (0 − 3) · 0.7 in f32: 0.9 to within its rounding.
        assert!((t.at(27).position - Vec3::splat(0.9)).abs().max_element() < 2e-7);
        assert_eq!(t.at(99).position, Vec3::splat(0.0));
        // Two keys of one value hold it exactly between them (a light or camera that stays put).
        let held = track(&[(0, 0.3), (10, 0.3)]);
        assert!((1..10).all(|k| held.at(k).position == Vec3::splat(0.3)));
    }

    #[test]
    fn the_orbit_circles_the_start_at_its_radius() {
        let start = vec![LightState { position: Vec3::new(1.0, 2.0, 3.0), intensity: Vec3::ONE }];
        let p = LightPath { start: start.clone(), motion: Motion::Orbit { period: 8, radius: 0.5 } };
        for k in 0..16 {
            let l = p.at(k)[0];
            assert!(((l.position - start[0].position).length() - 0.5).abs() < 1e-6);
            assert_eq!(l.position.y, 2.0);
            assert_eq!(l.intensity, Vec3::ONE);
        }
        assert_eq!(p.at(0), p.at(8), "one period");
        assert!((p.at(4)[0].position - p.at(0)[0].position).length() > 0.99, "half a period: the far side");
    }
}
