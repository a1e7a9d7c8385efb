//! direct: shadowed direct light from the point lights, per pixel of the G-buffer.
//!
//! L_direct(x) = Σ_l albedo(x)/π · I_l · max(0, cos θ_l) / d_l² · V(x, l)   (the scene contract)
//!
//! Inputs: G-buffer position/normal/albedo, the `dprsm_depth` array. Output: `radiance` RGBA32F W×H
//! (rgb radiance, 0 where the camera ray hits nothing). Dispatch: ⌈W/8⌉ × ⌈H/8⌉ groups of 8×8.
//!
//! **Visibility and its bias.** x is projected into its light's paraboloid face and compared with the
//! depth stored at the nearest texel: lit when d(x) ≤ stored + bias. The stored depth belongs to the
//! texel-centre direction, up to 0.71 texel away from x's direction; on a surface tilted by θ from the
//! light direction that shifts the depth by about d · Δα · tan θ, where Δα = 2/(1+u²+v²) · 2/res is
//! the texel's angular size. So bias = c + s · d · Δα · tan θ (tan θ capped at 50), with
//! c = `FrameUniforms.shadow.x` (default 1e-5 × scene diagonal: float rounding of the stored
//! distance) and s = `shadow.y` (default 1.5 texels). Effect: a too-small bias gives self-shadowing
//! acne on tilted lit surfaces; the bias instead lets a surface closer than `bias` behind an occluder
//! count as lit, so contact shadows start up to about 1.5 texels late ("peter-panning"). At the default
//! 512² per face, a texel spans ≤ 0.45° from the light.

use super::FrameInputs;
use crate::bindings::*;
use crate::gpu_scene::scene_bindings;
use crate::graph::{Graph, Handle};
use crate::passes::dprsm::DprsmDepth;
use crate::passes::gbuffer::GBufferOut;
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{vk, Binding, ComputePipeline, Gpu, Image, ImageDesc, Sampler};

pub const RADIANCE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

pub struct Direct {
    pipeline: ComputePipeline,
    sampler: Sampler,
}

impl Direct {
    pub fn new(gpu: &Gpu) -> Result<Self> {
        let mut bindings = scene_bindings();
        bindings.extend([
            Binding::sampled_image(B_DIRECT_GPOSITION),
            Binding::sampled_image(B_DIRECT_GNORMAL),
            Binding::sampled_image(B_DIRECT_GALBEDO),
            Binding::sampled_image(B_DIRECT_SHADOW),
            Binding::storage_image(B_DIRECT_OUT),
        ]);
        let pipeline = ComputePipeline::new(gpu, "direct", &crate::spirv(shaders::DIRECT_COMP), &bindings, 0, &[])?;
        Ok(Direct { pipeline, sampler: Sampler::nearest(gpu)? })
    }

    pub fn add<'a>(
        &'a self,
        g: &mut Graph<'a>,
        f: FrameInputs<'a>,
        gb: &GBufferOut,
        shadow: &DprsmDepth,
    ) -> Handle<Image> {
        let mut radiance = g.create_image(ImageDesc::new(
            "direct.radiance",
            f.width,
            f.height,
            RADIANCE_FORMAT,
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC,
        ));
        let (gb, shadow, out) = (*gb, *shadow, radiance);
        g.add_pass("direct")
            .read(&gb.position, Access::ComputeRead)
            .read(&gb.normal, Access::ComputeRead)
            .read(&gb.albedo, Access::ComputeRead)
            .read(&shadow.depth, Access::ComputeRead)
            .overwrite(&mut radiance, Access::ComputeWrite)
            .record(move |ctx| {
                let s = self.sampler.raw;
                let writes = f
                    .scene
                    .writes(f.uniforms)
                    .sampled_image(B_DIRECT_GPOSITION, ctx.image(&gb.position), s)
                    .sampled_image(B_DIRECT_GNORMAL, ctx.image(&gb.normal), s)
                    .sampled_image(B_DIRECT_GALBEDO, ctx.image(&gb.albedo), s)
                    .sampled_image(B_DIRECT_SHADOW, ctx.image(&shadow.depth), s)
                    .storage_image(B_DIRECT_OUT, ctx.image(&out));
                self.pipeline.dispatch(ctx.cmd, &writes, &[], [f.width, f.height, 1], [WG_2D, WG_2D, 1]);
            });
        radiance
    }
}
