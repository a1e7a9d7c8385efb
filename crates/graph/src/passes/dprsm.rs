//! dprsm: the reflective dual paraboloid map at each point light (pass `dprsm`, `glsl/dprsm.comp`),
//! `dprsm_res`² per face, whose texels are the VPLs. (`--light-map rsm|cube` swaps the faces for
//! perspective ones: glsl/shared/lightmap.glsl.)
//!
//! An array image of `2 × lights` layers; layer `2l + f` is face `f` (0: +z hemisphere, 1: −z)
//! of light `l`. Texel (i, j) has paraboloid coordinates (u, v) = ((i + o_x)/res · 2 − 1, (j + o_y)/res · 2
//! − 1) and stands for the direction d = (2u, 2v, 1 − u² − v²)/(1 + u² + v²) (z mirrored on face 1), where
//! o ∈ [0, 1)² is the layer's offset in its texels (`texel_offset` in glsl/shared/lightmap.glsl): one
//! random point per layer, drawn from the VPL seed (`Keys::vpl_offset`). So each VPL is a
//! uniform sample of its texel, and the VPL sum's mean over seeds is the one-bounce integral over the
//! light's directions at any resolution. With the texel centres (o = ½, the thesis's) the sum is a
//! quadrature whose error stays in every seed: 4.3 % of a generated room's indirect light at 128² per face
//! (BENCHMARKS.md, "What the VPL sum converges to"; the `dprsm` test
//! `the_vpls_solid_angles_are_unbiased_over_seeds` checks the mean against a closed form).
//! Per texel (RGBA32F each; all zero where the ray leaves the scene or u² + v² > 1):
//! - `position`: xyz of the hit, w = A_v = Δω_v · t² / cos α, the surface patch the texel sees, for the
//!   patch kernel (glsl/shared/vpl.glsl); 0: empty texel, never sampled;
//! - `normal`: the interpolated shading normal flipped to face the light, w = t, the distance to it;
//! - `flux`: the VPL's reflected flux Φ_v = albedo(v) · I · Δω_v, w = Δω_v, where
//!   Δω_v = 4 / (1 + u² + v²)² · (2/res)² is the texel's solid angle seen from the light (the Jacobian of
//!   the paraboloid map at the VPL's (u, v), dω = 4/(1 + u² + v²)² du dv, times the texel's area: the
//!   weight of a uniform point of the texel). The thesis's eqs. 7.1–7.3 leave this factor
//!   out; without it the VPL sum does not converge to the one-bounce integral. Σ_v Δω_v over both faces
//!   is 4π up to the texels cut by the unit circle (the `dprsm` test checks both).
//!
//! **Ray casting, not rasterization.** Each texel casts its ray from the light through the scene's BVH
//! (closest hit, the watertight test), so every texel holds exactly what that ray hits first: the `dprsm`
//! test compares it with a CPU ray cast and finds only float rounding. The thesis rasterizes the map, and
//! the paraboloid projection (u, v) = (x, y)/(|p| + z) (thesis eq. 6.6, a stereographic projection of the
//! direction) is not linear: a triangle's image is bounded by circular arcs, so rasterizing the straight
//! triangle between the projected vertices cuts or overshoots large triangles. bounce rasterized an exact
//! box around each triangle's curved image and intersected per texel (the approach psm's per-VPL maps
//! still take: passes/psm.rs), the same images as this pass's (bit for bit but for ties); but a
//! rasterized map costs what the scene has (a geometry shader per triangle and face) and this one what
//! the map has (one ray per texel). Under a moving light on lavapipe, Sibenik's map 379 → 29–45 ms at 128² a face and 962 →
//! 435–536 ms at 512², Conference's 1050 → 24 and 1303 → 383 ms; rooms of tens of triangles lose up to
//! 2.8× (12 → 21 ms at 128²; BENCHMARKS.md, "Things tried"). The rays take the threaded walk
//! (`bvh_closest_walk`): the stack traversal took 0.6–1.3× its time.

use super::FrameInputs;
use crate::bindings::*;
use crate::gpu_scene::scene_bindings;
use crate::graph::{Graph, Handle};
use crate::shader_types::ParaboloidPush;
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{vk, Binding, ComputePipeline, Gpu, Image, ImageDesc};

pub const VPL_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

pub struct Dprsm {
    pipeline: ComputePipeline,
}

/// The reflective DPRSM: one VPL per non-empty texel.
#[derive(Clone, Copy, Debug)]
pub struct DprsmOut {
    pub position: Handle<Image>,
    pub normal: Handle<Image>,
    pub flux: Handle<Image>,
}
crate::products!(DprsmOut { position, normal, flux });

impl Dprsm {
    /// `textured`: whether the scene has textures (the `SPEC_TEXTURED` specialisation).
    pub fn new(gpu: &Gpu, textured: bool) -> Result<Self> {
        let spec = [(SPEC_TEXTURED, textured as u32)];
        let mut bindings = scene_bindings();
        bindings.extend(crate::gpu_bvh::GpuBvh::bindings());
        bindings.extend([
            Binding::storage_image(B_DPRSM_POSITION_OUT),
            Binding::storage_image(B_DPRSM_NORMAL_OUT),
            Binding::storage_image(B_DPRSM_FLUX_OUT),
        ]);
        let push = std::mem::size_of::<ParaboloidPush>() as u32;
        let pipeline = ComputePipeline::new(gpu, "dprsm", &crate::spirv(shaders::DPRSM_COMP), &bindings, push, &spec)?;
        Ok(Dprsm { pipeline })
    }

    /// The reflective DPRSM (`dprsm_res` per face).
    pub fn add<'a>(&'a self, g: &mut Graph<'a>, f: FrameInputs<'a>) -> DprsmOut {
        let layers = f.vpl_faces * f.scene.light_count;
        let res = f.dprsm_res;
        let image = |g: &mut Graph<'a>, name: &str| {
            g.create_image(
                ImageDesc::new(
                    name,
                    res,
                    res,
                    VPL_FORMAT,
                    vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC,
                )
                .layers(layers),
            )
        };
        let mut out = DprsmOut {
            position: image(g, "dprsm.position"),
            normal: image(g, "dprsm.normal"),
            flux: image(g, "dprsm.flux"),
        };
        let o = out;
        let push = ParaboloidPush { map_res: res, pad: 0, offset: f.vpl_offset };
        g.add_pass("dprsm")
            .overwrite(&mut out.position, Access::ComputeWrite)
            .overwrite(&mut out.normal, Access::ComputeWrite)
            .overwrite(&mut out.flux, Access::ComputeWrite)
            .record(move |ctx| {
                let writes = f
                    .bvh
                    .writes(f.scene.writes(f.uniforms))
                    .storage_image(B_DPRSM_POSITION_OUT, ctx.image(&o.position))
                    .storage_image(B_DPRSM_NORMAL_OUT, ctx.image(&o.normal))
                    .storage_image(B_DPRSM_FLUX_OUT, ctx.image(&o.flux));
                self.pipeline.dispatch(
                    ctx.cmd,
                    &writes,
                    bytemuck::bytes_of(&push),
                    [res, res, layers],
                    [WG_2D, WG_2D, 1],
                );
            });
        out
    }
}
