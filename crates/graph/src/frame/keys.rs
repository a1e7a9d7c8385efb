//! Cache keys: for each product the recipe keeps across frames ([`crate::graph::Graph::cached`]), the
//! settings it depends on. A product is reused exactly while its key is unchanged, so a key must name
//! everything its passes read besides the scene (fixed for a `Renderer`): too little is a stale image,
//! too much only a recomputation. The lights are frame state: the light-side products (VPLs, direct
//! light, and through the VPLs the CDF) name them; the voxels and the G-buffer do not. The `graph` tests check each key against the passes that
//! a settings change must (and must not) redo.

use super::settings::FrameSettings;
use crate::camera::Camera;
use crate::graph::fingerprint;
use crate::passes::importance::{ImportanceKind, ImportanceParams};
use crate::passes::voxelize::VoxelGridSpec;
use crate::shader_types::Light;

/// f32 → bits, so keys hash exactly.
fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// The keys of one frame's products: fingerprints of what each depends on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Keys {
    /// The voxel grid: its fitted spec.
    pub voxels: u64,
    /// The reflective maps (the VPLs): resolution, light map, the VPLs' offset in their texels, and the
    /// lights.
    pub vpls: u64,
    /// The G-buffer: camera and image size.
    pub gbuffer: u64,
    /// The direct light (exact shadow rays): the G-buffer and the lights.
    pub direct: u64,
    /// Importance and CDF: the VPLs, the grid, the importance parameters, and for every kind that draws
    /// gather points the G-buffer and the seed (`uniform`'s validity depends on the maps alone), and for
    /// gbg whether its rays are traced (`exact`), and the VPL kernel (importance weighs each
    /// VPL by its unshadowed contribution).
    pub cdf: u64,
}

impl Keys {
    pub fn new(
        s: &FrameSettings,
        camera: &Camera,
        lights: &[Light],
        spec: &VoxelGridSpec,
        p: &ImportanceParams,
    ) -> Keys {
        let gbuffer = view_key(camera, s.width, s.height);
        let (positions, intensities) = light_bits(lights);
        let vpls = fingerprint(&(
            (s.dprsm_res, s.light_map.name(), s.light_map.tan_half_fov().to_bits(), bits(&vpl_offset(s))),
            &positions,
            &intensities,
        ));
        let voxels = fingerprint(&(bits(&spec.origin.to_array()), spec.cell.to_bits(), spec.dims.to_array()));
        let per_pixel = (p.kind != ImportanceKind::Uniform).then_some((gbuffer, p.seed));
        let params =
            (p.kind, p.samples, p.min_d2.to_bits(), p.fixed_scale.to_bits(), s.vpl_kernel.area_weight().to_bits());
        // gbg's rays find their hits through the BVH (exact) or the voxel grid: different hits.
        let traced = matches!(p.kind, ImportanceKind::Gbg { .. }) && s.visibility.uses_bvh();
        Keys {
            voxels,
            vpls,
            gbuffer,
            direct: fingerprint(&(gbuffer, &positions, &intensities)),
            cdf: fingerprint(&(vpls, voxels, params, per_pixel, traced)),
        }
    }
}

/// What sees the scene: the camera and the image size (the G-buffer's key, and that of the host's
/// per-view decisions, `Renderer::blocked_share`).
pub fn view_key(camera: &Camera, width: u32, height: u32) -> u64 {
    let c = camera;
    let cam =
        bits(&[c.eye.x, c.eye.y, c.eye.z, c.target.x, c.target.y, c.target.z, c.up.x, c.up.y, c.up.z, c.fov_y_deg]);
    fingerprint(&(cam, width, height))
}

/// The lights' positions and intensities as bits.
pub fn light_bits(lights: &[Light]) -> (Vec<u32>, Vec<u32>) {
    (lights.iter().flat_map(|l| bits(&l.position)).collect(), lights.iter().flat_map(|l| bits(&l.intensity)).collect())
}

/// Where in its texel each VPL's light ray passes in layer 0 of the light maps, in texels ([0, 1)²): a
/// uniform draw from the VPL seed ([`FrameSettings::vpl_seed`]). Layer k's is
/// [`texel_offset`]`(offset, k)`. A random shift of the whole texel grid (a Cranley–Patterson
/// rotation) makes each texel's VPL a uniform sample of its texel: Σ_v Φ_v · f(v), with Φ_v the flux
/// through the texel's solid angle Δω at that point, is then an unbiased estimate of the integral over
/// the light's directions of I · albedo · f, for any resolution, where the centres' sum is a quadrature
/// whose error does not average out over seeds (BENCHMARKS.md, "What the VPL sum converges to").
pub fn vpl_offset(s: &FrameSettings) -> [f32; 2] {
    let h = fingerprint(&(s.vpl_seed_or_derived(), "vpl offset"));
    let unit = |bits: u64| (bits & 0xFF_FFFF) as f32 / (1u32 << 24) as f32;
    [unit(h), unit(h >> 32)]
}

/// Layer `layer`'s offset from layer 0's: moved on by the R2 sequence's step per layer and wrapped, so
/// that each layer's is uniform in the texel and the layers do not share one. The host's twin of
/// `texel_offset` in glsl/shared/lightmap.glsl (the tests' CPU ray cast uses it).
pub fn texel_offset(offset: [f32; 2], layer: u32) -> [f32; 2] {
    use crate::bindings::{VPL_OFFSET_STEP_X, VPL_OFFSET_STEP_Y};
    let wrap = |x: f32| x - x.floor();
    [wrap(offset[0] + layer as f32 * VPL_OFFSET_STEP_X), wrap(offset[1] + layer as f32 * VPL_OFFSET_STEP_Y)]
}
