//! direct: shadowed direct light from the point lights, per pixel of the G-buffer.
//!
//! L_direct(x) = Σ_l albedo(x)/π · I_l · max(0, cos θ_l) / d_l² · V(x, l)   (the scene contract)
//!
//! Inputs: G-buffer position/normal/albedo, the scene's BVH. Output: `radiance` RGBA32F W×H (rgb
//! radiance, 0 where the camera ray hits nothing). Dispatch: ⌈W/8⌉ × ⌈H/8⌉ groups of 8×8.
//!
//! **Visibility: one exact shadow ray per pixel and light**, from x lifted off its surface (`surface_lift`,
//! as the path tracer's rays leave theirs) to the light, through the BVH. No bias to tune and no leaks: a
//! paraboloid shadow map (the thesis's, here until 2026-12-04) lit seams where two walls meet behind a
//! light (the two rooms: p99.9 |error| 1.55 in the dark room's direct image) and was the dearest raster
//! pass of a moving light (H200, 1080p: 6–8 ms at 1024² per face, 18–20 ms at 2048²); on lavapipe the
//! direct component's GPU time fell 43–208× (Sibenik 1769 → 8.5 ms at 96×72; BENCHMARKS.md, Things tried).
//! These rays are the direct light's, one per light; the rays per pixel that `render --timings` and `bench`
//! report are the bounce's (ris, realtime).

use super::FrameInputs;
use crate::bindings::*;
use crate::gpu_scene::scene_bindings;
use crate::graph::{Graph, Handle};
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
            Binding::storage_image(B_DIRECT_OUT),
        ]);
        bindings.extend(crate::gpu_bvh::GpuBvh::bindings());
        let pipeline = ComputePipeline::new(gpu, "direct", &crate::spirv(shaders::DIRECT_COMP), &bindings, 0, &[])?;
        Ok(Direct { pipeline, sampler: Sampler::nearest(gpu)? })
    }

    pub fn add<'a>(&'a self, g: &mut Graph<'a>, f: FrameInputs<'a>, gb: &GBufferOut) -> Handle<Image> {
        let mut radiance = g.create_image(ImageDesc::new(
            "direct.radiance",
            f.width,
            f.height,
            RADIANCE_FORMAT,
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC,
        ));
        let (gb, out) = (*gb, radiance);
        g.add_pass("direct")
            .read(&gb.position, Access::ComputeRead)
            .read(&gb.normal, Access::ComputeRead)
            .read(&gb.albedo, Access::ComputeRead)
            .overwrite(&mut radiance, Access::ComputeWrite)
            .record(move |ctx| {
                let s = self.sampler.raw;
                let writes = f
                    .bvh
                    .writes(f.scene.writes(f.uniforms))
                    .sampled_image(B_DIRECT_GPOSITION, ctx.image(&gb.position), s)
                    .sampled_image(B_DIRECT_GNORMAL, ctx.image(&gb.normal), s)
                    .sampled_image(B_DIRECT_GALBEDO, ctx.image(&gb.albedo), s)
                    .storage_image(B_DIRECT_OUT, ctx.image(&out));
                self.pipeline.dispatch(ctx.cmd, &writes, &[], [f.width, f.height, 1], [WG_2D, WG_2D, 1]);
            });
        radiance
    }
}
