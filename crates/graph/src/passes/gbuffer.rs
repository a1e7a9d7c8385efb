//! gbuffer: rasterizes the scene from the camera.
//!
//! Inputs: the scene buffers, `FrameUniforms.view_proj`. Outputs (W×H): `position` RGBA32F (xyz world
//! position, w = 1 where geometry was hit, 0 elsewhere), `normal` RGBA32F (xyz unit shading normal
//! flipped to face the camera, w = triangle index bits), `albedo` RGBA32F (Kd × nearest map_Kd texel,
//! sRGB-decoded), `depth` D32 (reverse Z: 1 at near, 0 at far). Rasterization samples pixel centres, so each pixel holds the
//! surface point on the camera ray of the scene contract (perspective-correct interpolation of a
//! position on a plane is exact).

use super::FrameInputs;
use crate::gpu_scene::scene_bindings;
use crate::graph::{Graph, Handle};
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{vk, Gpu, GraphicsPipeline, GraphicsPipelineDesc, Image, ImageDesc};

pub const GBUFFER_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

pub struct GBuffer {
    pipeline: GraphicsPipeline,
}

#[derive(Clone, Copy, Debug)]
pub struct GBufferOut {
    pub position: Handle<Image>,
    pub normal: Handle<Image>,
    pub albedo: Handle<Image>,
    pub depth: Handle<Image>,
}
crate::products!(GBufferOut { position, normal, albedo, depth });

impl GBuffer {
    /// `textured`: whether the scene has textures (the `SPEC_TEXTURED` specialisation).
    pub fn new(gpu: &Gpu, textured: bool) -> Result<Self> {
        let spec = [(crate::bindings::SPEC_TEXTURED, textured as u32)];
        let pipeline = GraphicsPipeline::new(
            gpu,
            &GraphicsPipelineDesc {
                name: "gbuffer",
                vertex: &crate::spirv(shaders::GBUFFER_VERT),
                geometry: None,
                fragment: &crate::spirv(shaders::GBUFFER_FRAG),
                color_formats: &[GBUFFER_FORMAT; 3],
                depth_format: Some(DEPTH_FORMAT),
                // Reverse Z (1 at the near plane, 0 at the far one): float depth keeps its precision
                // where the values are small, i.e. far away. Forward Z with a small near plane could
                // not separate the Cornell box's light panel from the ceiling 1 cm above it.
                depth_compare: vk::CompareOp::GREATER,
                bindings: &scene_bindings(),
                push_constant_size: 0,
                spec: &spec,
            },
        )?;
        Ok(GBuffer { pipeline })
    }

    pub fn add<'a>(&'a self, g: &mut Graph<'a>, f: FrameInputs<'a>) -> GBufferOut {
        let usage =
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        let color = |name: &str| ImageDesc::new(name, f.width, f.height, GBUFFER_FORMAT, usage);
        let mut out = GBufferOut {
            position: g.create_image(color("gbuffer.position")),
            normal: g.create_image(color("gbuffer.normal")),
            albedo: g.create_image(color("gbuffer.albedo")),
            depth: g.create_image(ImageDesc::new(
                "gbuffer.depth",
                f.width,
                f.height,
                DEPTH_FORMAT,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
            )),
        };
        let o = out;
        g.add_pass("gbuffer")
            .overwrite(&mut out.position, Access::ColorAttachment)
            .overwrite(&mut out.normal, Access::ColorAttachment)
            .overwrite(&mut out.albedo, Access::ColorAttachment)
            .overwrite(&mut out.depth, Access::DepthAttachment)
            .record(move |ctx| {
                let d = &ctx.gpu.device;
                let extent = vk::Extent2D { width: f.width, height: f.height };
                let clear = vk::ClearValue { color: vk::ClearColorValue { float32: [0.0; 4] } };
                let colors: Vec<_> = [o.position, o.normal, o.albedo]
                    .iter()
                    .map(|h| {
                        vk::RenderingAttachmentInfo::default()
                            .image_view(ctx.image(h).view)
                            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                            .load_op(vk::AttachmentLoadOp::CLEAR)
                            .store_op(vk::AttachmentStoreOp::STORE)
                            .clear_value(clear)
                    })
                    .collect();
                let depth = vk::RenderingAttachmentInfo::default()
                    .image_view(ctx.image(&o.depth).view)
                    .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(vk::ClearValue {
                        depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 },
                    });
                let info = vk::RenderingInfo::default()
                    .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
                    .layer_count(1)
                    .color_attachments(&colors)
                    .depth_attachment(&depth);
                unsafe {
                    d.cmd_begin_rendering(ctx.cmd, &info);
                    if f.scene.triangle_count > 0 {
                        self.pipeline.bind(ctx.cmd, extent, &f.scene.writes(f.uniforms), &[]);
                        d.cmd_draw(ctx.cmd, 3 * f.scene.triangle_count, 1, 0, 0);
                    }
                    d.cmd_end_rendering(ctx.cmd);
                }
            });
        out
    }
}
