//! The pinhole camera contract shared by the rasterizer (through [`Camera::view_proj`]) and every
//! CPU-side ray caster (through [`Camera::ray_dir`] / [`Camera::ray_dir_f`]).
//!
//! Both paths are derived from the same numbers so that the G-buffer pixel `(i, j)` and the CPU
//! reference ray for pixel `(i, j)` see the same surface point: the GPU-vs-CPU comparison is only
//! meaningful if they agree to float precision.
//!
//! Conventions (the contract):
//! * `forward = normalize(target - eye)`, `right = normalize(cross(forward, up))`,
//!   `true_up = cross(right, forward)`. Image +x is `right`; image row 0 is on the `up` side.
//! * Pixel `(i, j)` of a `W×H` image is evaluated at its centre `(i + 0.5, j + 0.5)`.
//! * `ndc = (x / W · 2 − 1, 1 − y / H · 2)` for continuous pixel coordinates `(x, y)`;
//!   `tan(fov_y / 2)` scales ndc.y and `tan(fov_y / 2) · W / H` scales ndc.x.

use glam::{Mat4, Vec3, Vec4};

/// A pinhole camera. `fov_y_deg` is the vertical field of view across the full image height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    pub fov_y_deg: f32,
}

impl Camera {
    /// Checks that the camera defines a unique, finite basis and a usable field of view.
    ///
    /// Rejected: non-finite components, `eye == target` (no forward direction), a zero `up`, `up`
    /// (nearly) parallel to the view direction (no `right` vector: the sine of the angle between
    /// them must be at least 1e-4), and `fov_y_deg` outside the open interval (0, 180).
    /// The error is a one-line description without a file name; callers add the context.
    pub fn validate(&self) -> Result<(), String> {
        let finite = |v: Vec3| v.is_finite();
        if !finite(self.eye) || !finite(self.target) || !finite(self.up) {
            return Err(format!(
                "camera eye/target/up must be finite (eye {:?}, target {:?}, up {:?})",
                self.eye.to_array(),
                self.target.to_array(),
                self.up.to_array()
            ));
        }
        if !(self.fov_y_deg.is_finite() && self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return Err(format!("camera fov_y must be in (0, 180) degrees, got {}", self.fov_y_deg));
        }
        let to_target = self.target - self.eye;
        // Relative test: a camera 1e6 units from the origin cannot resolve a 1e-9 offset in f32.
        let scale = self.eye.abs().max_element().max(self.target.abs().max_element()).max(1.0);
        if to_target.length() <= 1e-6 * scale {
            return Err(format!(
                "camera eye and target coincide ({:?}); the view direction is undefined",
                self.eye.to_array()
            ));
        }
        if self.up.length() <= 1e-12 {
            return Err("camera up vector is zero".to_string());
        }
        let sin = to_target.normalize().cross(self.up.normalize()).length();
        if sin.is_nan() || sin < 1e-4 {
            return Err(format!(
                "camera up {:?} is parallel to the view direction {:?}",
                self.up.to_array(),
                to_target.normalize().to_array()
            ));
        }
        Ok(())
    }

    /// `(right, true_up, forward)`, an orthonormal right-handed basis with
    /// `right = normalize(cross(forward, up))` and `true_up = cross(right, forward)`.
    ///
    /// Only meaningful for a camera that passes [`Camera::validate`].
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        let true_up = right.cross(forward);
        (right, true_up, forward)
    }

    /// `tan(fov_y / 2)`: the half-height of the image plane at unit distance.
    pub fn tan_half_fov(&self) -> f32 {
        (self.fov_y_deg.to_radians() * 0.5).tan()
    }

    /// Unit world direction through the centre of pixel `(i, j)` of a `w×h` image
    /// (row 0 = top = the `up` side).
    pub fn ray_dir(&self, i: u32, j: u32, w: u32, h: u32) -> Vec3 {
        self.ray_dir_f(i as f32 + 0.5, j as f32 + 0.5, w, h)
    }

    /// Unit world direction through the continuous pixel position `(x, y)` of a `w×h` image;
    /// pixel `(i, j)` covers `[i, i+1) × [j, j+1)`, so its centre is `(i + 0.5, j + 0.5)`.
    pub fn ray_dir_f(&self, x: f32, y: f32, w: u32, h: u32) -> Vec3 {
        let (right, true_up, forward) = self.basis();
        let t = self.tan_half_fov();
        let aspect = w as f32 / h as f32;
        let ndc_x = x / w as f32 * 2.0 - 1.0;
        let ndc_y = 1.0 - y / h as f32 * 2.0;
        (forward + (ndc_x * t * aspect) * right + (ndc_y * t) * true_up).normalize()
    }

    /// World → Vulkan clip space (column-major glam matrix) for a `w×h` viewport.
    ///
    /// Rasterizing with this matrix (viewport `x=0, y=0, width=w, height=h`, `minDepth=0,
    /// maxDepth=1`, no negative-height viewport trick) puts the centre of pixel `(i, j)` exactly on
    /// the ray [`Camera::ray_dir`] returns: Vulkan NDC is y-down, so NDC
    /// `((i+0.5)/w·2−1, (j+0.5)/h·2−1)` is pixel `(i, j)`.
    ///
    /// Depth is **forward Z** in `[0, 1]`: a point at view depth `near` maps to 0, `far` to 1
    /// (depth along `forward`, not Euclidean distance). Clear the depth buffer to 1.0 and test with
    /// `LESS` / `LESS_OR_EQUAL`. Clip `w` is the positive view depth.
    pub fn view_proj(&self, w: u32, h: u32, near: f32, far: f32) -> Mat4 {
        let (right, true_up, forward) = self.basis();
        // View space: x = right, y = true_up, z = -forward (right-handed, camera looks down -z).
        let view = Mat4::from_cols(
            Vec4::new(right.x, true_up.x, -forward.x, 0.0),
            Vec4::new(right.y, true_up.y, -forward.y, 0.0),
            Vec4::new(right.z, true_up.z, -forward.z, 0.0),
            Vec4::new(-right.dot(self.eye), -true_up.dot(self.eye), forward.dot(self.eye), 1.0),
        );
        let t = self.tan_half_fov();
        let aspect = w as f32 / h as f32;
        let sx = 1.0 / (t * aspect);
        // Negative: Vulkan NDC y points down while view-space y points up.
        let sy = -1.0 / t;
        let a = far / (near - far);
        let b = near * far / (near - far);
        // clip = (sx·x, sy·y, a·z + b, −z); with z = −depth: ndc.z = (b − a·depth)/depth, which is
        // 0 at depth = near and 1 at depth = far.
        let proj = Mat4::from_cols(
            Vec4::new(sx, 0.0, 0.0, 0.0),
            Vec4::new(0.0, sy, 0.0, 0.0),
            Vec4::new(0.0, 0.0, a, -1.0),
            Vec4::new(0.0, 0.0, b, 0.0),
        );
        proj * view
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera { eye: Vec3::new(0.3, 1.0, 3.9), target: Vec3::new(-0.2, 0.9, 0.0), up: Vec3::Y, fov_y_deg: 39.3 }
    }

    fn close(a: Vec3, b: Vec3, eps: f32) -> bool {
        (a - b).abs().max_element() <= eps
    }

    #[test]
    fn basis_is_orthonormal_and_right_handed() {
        let (r, u, f) = cam().basis();
        for v in [r, u, f] {
            assert!((v.length() - 1.0).abs() < 1e-6);
        }
        assert!(r.dot(u).abs() < 1e-6 && r.dot(f).abs() < 1e-6 && u.dot(f).abs() < 1e-6);
        assert!(close(r.cross(u), -f, 1e-6));
        assert!(u.dot(Vec3::Y) > 0.0);
    }

    #[test]
    fn centre_ray_is_forward_for_odd_sizes() {
        let c = cam();
        let (_, _, f) = c.basis();
        for (w, h) in [(1, 1), (257, 255), (33, 101)] {
            assert!(close(c.ray_dir(w / 2, h / 2, w, h), f, 1e-6), "{w}x{h}");
        }
    }

    #[test]
    fn corner_rays_follow_the_contract() {
        let c = cam();
        let (r, u, f) = c.basis();
        let (w, h) = (320u32, 200u32);
        let t = c.tan_half_fov();
        let aspect = w as f32 / h as f32;
        // The image corners (continuous coordinates): top-left is left and up.
        let tl = c.ray_dir_f(0.0, 0.0, w, h);
        assert!(close(tl, (f - t * aspect * r + t * u).normalize(), 1e-6));
        let br = c.ray_dir_f(w as f32, h as f32, w, h);
        assert!(close(br, (f + t * aspect * r - t * u).normalize(), 1e-6));
        // Pixel (0, 0)'s centre is half a pixel inside the corner.
        let p00 = c.ray_dir(0, 0, w, h);
        let ndc = Vec3::new(0.5 / w as f32 * 2.0 - 1.0, 1.0 - 0.5 / h as f32 * 2.0, 0.0);
        assert!(close(p00, (f + ndc.x * t * aspect * r + ndc.y * t * u).normalize(), 1e-6));
        assert!(p00.dot(r) < 0.0 && p00.dot(u) > 0.0);
        // The full vertical extent spans fov_y.
        let top = c.ray_dir_f(w as f32 / 2.0, 0.0, w, h);
        let bottom = c.ray_dir_f(w as f32 / 2.0, h as f32, w, h);
        let angle = top.dot(bottom).clamp(-1.0, 1.0).acos().to_degrees();
        assert!((angle - c.fov_y_deg).abs() < 1e-3, "{angle}");
    }

    #[test]
    fn view_proj_puts_pixel_centres_on_their_rays() {
        let c = cam();
        let (w, h) = (320u32, 200u32);
        let (near, far) = (0.05, 50.0);
        let m = c.view_proj(w, h, near, far);
        let (_, _, f) = c.basis();
        for (i, j) in [(0, 0), (319, 0), (0, 199), (319, 199), (160, 100), (17, 123)] {
            let d = c.ray_dir(i, j, w, h);
            for dist in [0.5f32, 3.0, 20.0] {
                let p = c.eye + d * dist;
                let clip = m * p.extend(1.0);
                let ndc = clip.truncate() / clip.w;
                let want_x = (i as f32 + 0.5) / w as f32 * 2.0 - 1.0;
                let want_y = (j as f32 + 0.5) / h as f32 * 2.0 - 1.0;
                assert!((ndc.x - want_x).abs() < 1e-5, "x {i},{j}: {} vs {want_x}", ndc.x);
                assert!((ndc.y - want_y).abs() < 1e-5, "y {i},{j}: {} vs {want_y}", ndc.y);
                // Clip w is the depth along forward; depth is in (0, 1).
                assert!((clip.w - d.dot(f) * dist).abs() < 1e-4);
                assert!(ndc.z > 0.0 && ndc.z < 1.0);
            }
        }
        // Forward Z: near -> 0, far -> 1.
        let z_at = |depth: f32| {
            let clip = m * (c.eye + f * depth).extend(1.0);
            clip.z / clip.w
        };
        // (f32 cancellation near the near plane limits this to ~1e-5.)
        assert!(z_at(near).abs() < 1e-4, "{}", z_at(near));
        assert!((z_at(far) - 1.0).abs() < 1e-4, "{}", z_at(far));
        assert!(z_at(1.0) < z_at(2.0));
    }

    #[test]
    fn invalid_cameras_are_rejected() {
        assert!(cam().validate().is_ok());
        let same = Camera { target: cam().eye, ..cam() };
        assert!(same.validate().unwrap_err().contains("coincide"));
        let parallel = Camera { eye: Vec3::ZERO, target: Vec3::new(0.0, 5.0, 0.0), up: Vec3::Y, fov_y_deg: 40.0 };
        assert!(parallel.validate().unwrap_err().contains("parallel"));
        let zero_up = Camera { up: Vec3::ZERO, ..cam() };
        assert!(zero_up.validate().is_err());
        for fov in [0.0, 180.0, -5.0, f32::NAN] {
            assert!(Camera { fov_y_deg: fov, ..cam() }.validate().is_err(), "{fov}");
        }
        let nan = Camera { eye: Vec3::new(f32::NAN, 0.0, 0.0), ..cam() };
        assert!(nan.validate().is_err());
    }
}
