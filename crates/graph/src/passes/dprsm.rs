//! dprsm: the dual paraboloid map at each point light (depth part; the reflective attachments come with
//! the VPL pass).
//!
//! Output: one D32 array image, `2 × lights` layers of `res × res` texels; layer `2l + f` is face `f`
//! (0: +z hemisphere, 1: −z) of light `l`. Texel (i, j) has paraboloid coordinates
//! (u, v) = ((i + ½)/res · 2 − 1, (j + ½)/res · 2 − 1) and stores, for the direction
//! d = (2u, 2v, 1 − u² − v²)/(1 + u² + v²) (z mirrored on face 1), the distance t to the nearest surface
//! divided by `far` (`FrameUniforms.scene_max.w`), or 1 where nothing is hit or u² + v² > 1.
//!
//! **Why not rasterize the projected vertices.** The paraboloid projection (u, v) = (x, y)/(|p| + z)
//! (thesis eq. 6.6; it is a stereographic projection of the direction) is not linear: a triangle's
//! image is bounded by circular arcs, and rasterizing the straight triangle between the projected
//! vertices (what a plain paraboloid shadow map does) cuts or overshoots large triangles. Tessellating
//! only shrinks the error. Instead (the approach of Gascuel et al. 2008 for non-linear projections):
//! 1. the geometry shader clips the triangle to the face's half-space z ≥ 0 (triangles crossing the
//!    face boundary are split between the faces exactly),
//! 2. bounds its exact image: the projected vertices plus, per edge, the closed-form extreme points of
//!    the edge's circular arc (see `include_arc` in `dprsm.geom`), and emits that box,
//! 3. the fragment shader intersects the ray through each texel centre with the original triangle and
//!    writes the hit distance as depth (discarding misses).
//!
//! So every texel holds exactly what a ray cast from the light through its centre hits first: the
//! `dprsm` test compares it with a CPU ray cast and finds only float rounding.

use super::FrameInputs;
use crate::gpu_scene::scene_bindings;
use crate::graph::{Graph, Handle};
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{vk, Gpu, GraphicsPipeline, GraphicsPipelineDesc, Image, ImageDesc};

pub const DPRSM_DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

pub struct Dprsm {
    pipeline: GraphicsPipeline,
}

#[derive(Clone, Copy, Debug)]
pub struct DprsmOut {
    /// Distance / far per texel, `2 × lights` layers.
    pub depth: Handle<Image>,
}

impl Dprsm {
    pub fn new(gpu: &Gpu) -> Result<Self> {
        let pipeline = GraphicsPipeline::new(
            gpu,
            &GraphicsPipelineDesc {
                name: "dprsm",
                vertex: &crate::spirv(shaders::DPRSM_VERT),
                geometry: Some(&crate::spirv(shaders::DPRSM_GEOM)),
                fragment: &crate::spirv(shaders::DPRSM_FRAG),
                color_formats: &[],
                depth_format: Some(DPRSM_DEPTH_FORMAT),
                depth_compare: vk::CompareOp::LESS,
                bindings: &scene_bindings(),
                push_constant_size: 0,
                spec: &[],
            },
        )?;
        Ok(Dprsm { pipeline })
    }

    pub fn add<'a>(&'a self, g: &mut Graph<'a>, f: FrameInputs<'a>) -> DprsmOut {
        let layers = 2 * f.scene.light_count;
        let mut out = DprsmOut {
            depth: g.create_image(
                ImageDesc::new(
                    "dprsm.depth",
                    f.shadow_res,
                    f.shadow_res,
                    DPRSM_DEPTH_FORMAT,
                    vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
                        | vk::ImageUsageFlags::SAMPLED
                        | vk::ImageUsageFlags::TRANSFER_SRC,
                )
                .layers(layers),
            ),
        };
        let o = out;
        g.add_pass("dprsm").overwrite(&mut out.depth, Access::DepthAttachment).record(move |ctx| {
            let d = &ctx.gpu.device;
            let extent = vk::Extent2D { width: f.shadow_res, height: f.shadow_res };
            let depth = vk::RenderingAttachmentInfo::default()
                .image_view(ctx.image(&o.depth).view)
                .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } });
            // Layered rendering: the geometry shader routes each (light, face) instance to its layer.
            let info = vk::RenderingInfo::default()
                .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
                .layer_count(layers)
                .depth_attachment(&depth);
            unsafe {
                d.cmd_begin_rendering(ctx.cmd, &info);
                if f.scene.triangle_count > 0 {
                    self.pipeline.bind(ctx.cmd, extent, &f.scene.writes(f.uniforms), &[]);
                    d.cmd_draw(ctx.cmd, 3 * f.scene.triangle_count, layers, 0, 0);
                }
                d.cmd_end_rendering(ctx.cmd);
            }
        });
        out
    }
}
