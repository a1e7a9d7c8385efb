//! dprsm: the reflective dual paraboloid map at each point light (pass `dprsm`), `dprsm_res`² per face,
//! whose texels are the VPLs. (`--light-map rsm|cube` swaps the faces for perspective ones:
//! glsl/shared/lightmap.glsl.) psm's per-VPL shadow maps reuse its geometry shader and `dprsm.frag`.
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
//! The depth is the distance t to the nearest surface along d divided by `far`
//! (`FrameUniforms.scene_max.w`), or 1 where nothing is hit or u² + v² > 1 (kept inside the pass). Per
//! texel (RGBA32F each):
//! - `position`: xyz of the hit, w = 1 (0: empty texel, never sampled);
//! - `normal`: the interpolated shading normal flipped to face the light, w = t;
//! - `flux`: the VPL's reflected flux Φ_v = albedo(v) · I · Δω_v, w = Δω_v, where
//!   Δω_v = 4 / (1 + u² + v²)² · (2/res)² is the texel's solid angle seen from the light (the Jacobian of
//!   the paraboloid map at the VPL's (u, v), dω = 4/(1 + u² + v²)² du dv, times the texel's area: the
//!   weight of a uniform point of the texel). The thesis's eqs. 7.1–7.3 leave this factor
//!   out; without it the VPL sum does not converge to the one-bounce integral. Σ_v Δω_v over both faces
//!   is 4π up to the texels cut by the unit circle (the `dprsm` test checks both).
//!
//! **Why not rasterize the projected vertices.** The paraboloid projection (u, v) = (x, y)/(|p| + z)
//! (thesis eq. 6.6; it is a stereographic projection of the direction) is not linear: a triangle's
//! image is bounded by circular arcs, and rasterizing the straight triangle between the projected
//! vertices (what a plain paraboloid shadow map does) cuts or overshoots large triangles. Tessellating
//! only shrinks the error. Instead (the approach of Gascuel et al. 2008 for non-linear projections):
//! 1. the geometry shader clips the triangle to the face's half-space z ≥ 0 (triangles crossing the
//!    face boundary are split between the faces exactly),
//! 2. bounds its exact image: the projected vertices plus, per edge, the closed-form extreme points of
//!    the edge's circular arc (see `include_arc` in `dprsm.geom`), and emits that box at the depth of
//!    the triangle's nearest point to the light (a lower bound on every texel's hit distance;
//!    `glsl/shared/map_depth.glsl`),
//! 3. the fragment shader intersects the ray through each texel's point with the original triangle and
//!    writes the hit distance as depth (discarding misses), never below the box's. It declares
//!    `depth_greater`, so the depth test rejects a box's texels behind what is already drawn before the
//!    shader runs (Sibenik's former 2048² direct-light shadow map, the same geometry: 25 → 19 ms on an
//!    H200, whose fragment shading is scarce; the same images). The `dprsm` test
//!    `the_light_maps_box_depth_is_below_every_texel_depth` checks the box against an f64 closest point.
//!
//! So every texel holds exactly what a ray cast from the light through its point hits first: the
//! `dprsm` test compares it with a CPU ray cast and finds only float rounding.

use super::FrameInputs;
use crate::gpu_scene::scene_bindings;
use crate::graph::{Graph, Handle};
use crate::shader_types::ParaboloidPush;
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{vk, Gpu, GraphicsPipeline, GraphicsPipelineDesc, Image, ImageDesc};

pub const DPRSM_DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
pub const VPL_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

pub struct Dprsm {
    reflective: GraphicsPipeline,
}

/// The reflective DPRSM: one VPL per non-empty texel. (Its depth attachment stays inside the pass.)
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
        let spec = [(crate::bindings::SPEC_TEXTURED, textured as u32)];
        let reflective = GraphicsPipeline::new(
            gpu,
            &GraphicsPipelineDesc {
                name: "dprsm",
                vertex: &crate::spirv(shaders::DPRSM_VERT),
                geometry: Some(&crate::spirv(shaders::DPRSM_GEOM)),
                fragment: &crate::spirv(shaders::DPRSM_REFLECTIVE_FRAG),
                color_formats: &[VPL_FORMAT; 3],
                depth_format: Some(DPRSM_DEPTH_FORMAT),
                depth_compare: vk::CompareOp::LESS,
                bindings: &scene_bindings(),
                push_constant_size: std::mem::size_of::<ParaboloidPush>() as u32,
                spec: &spec,
            },
        )?;
        Ok(Dprsm { reflective })
    }

    pub(crate) fn depth_image(g: &mut Graph, name: &str, res: u32, layers: u32) -> Handle<Image> {
        g.create_image(
            ImageDesc::new(
                name,
                res,
                res,
                DPRSM_DEPTH_FORMAT,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
                    | vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::TRANSFER_SRC,
            )
            .layers(layers),
        )
    }

    /// The reflective DPRSM (`dprsm_res` per face).
    pub fn add<'a>(&'a self, g: &mut Graph<'a>, f: FrameInputs<'a>) -> DprsmOut {
        let layers = f.vpl_faces * f.scene.light_count;
        let res = f.dprsm_res;
        let color = |g: &mut Graph<'a>, name: &str| {
            g.create_image(
                ImageDesc::new(
                    name,
                    res,
                    res,
                    VPL_FORMAT,
                    vk::ImageUsageFlags::COLOR_ATTACHMENT
                        | vk::ImageUsageFlags::SAMPLED
                        | vk::ImageUsageFlags::TRANSFER_SRC,
                )
                .layers(layers),
            )
        };
        let mut out = DprsmOut {
            position: color(g, "dprsm.position"),
            normal: color(g, "dprsm.normal"),
            flux: color(g, "dprsm.flux"),
        };
        let mut depth = Self::depth_image(g, "dprsm.depth", res, layers);
        let (o, d) = (out, depth);
        g.add_pass("dprsm")
            .overwrite(&mut out.position, Access::ColorAttachment)
            .overwrite(&mut out.normal, Access::ColorAttachment)
            .overwrite(&mut out.flux, Access::ColorAttachment)
            .overwrite(&mut depth, Access::DepthAttachment)
            .record(move |ctx| {
                let colors = [o.position, o.normal, o.flux].map(|h| ctx.image(&h).view);
                let writes = f.scene.writes(f.uniforms);
                record_paraboloid(ctx, &self.reflective, f, writes, res, layers, &colors, &d, f.vpl_offset)
            });
        out
    }
}

/// Records one layered map rendering: `layers` instances of every scene triangle, instance k into
/// layer k (the geometry shader picks the viewpoint: a light's face here, a VPL in `psm.rs`), cleared
/// to far depth and zero colour first.
#[allow(clippy::too_many_arguments)]
pub(crate) fn record_paraboloid(
    ctx: &crate::graph::PassContext,
    pipeline: &GraphicsPipeline,
    f: FrameInputs,
    writes: bounce_device::DescriptorWrites,
    res: u32,
    layers: u32,
    colors: &[vk::ImageView],
    depth: &Handle<Image>,
    offset: [f32; 2],
) {
    let d = &ctx.gpu.device;
    let extent = vk::Extent2D { width: res, height: res };
    let color_attachments: Vec<_> = colors
        .iter()
        .map(|&view| {
            vk::RenderingAttachmentInfo::default()
                .image_view(view)
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: [0.0; 4] } })
        })
        .collect();
    let depth = vk::RenderingAttachmentInfo::default()
        .image_view(ctx.image(depth).view)
        .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::STORE)
        .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } });
    // Layered rendering: the geometry shader routes each instance to its layer.
    let info = vk::RenderingInfo::default()
        .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
        .layer_count(layers)
        .color_attachments(&color_attachments)
        .depth_attachment(&depth);
    unsafe {
        d.cmd_begin_rendering(ctx.cmd, &info);
        if f.scene.triangle_count > 0 {
            let push = ParaboloidPush { map_res: res, pad: 0, offset };
            pipeline.bind(ctx.cmd, extent, &writes, bytemuck::bytes_of(&push));
            d.cmd_draw(ctx.cmd, 3 * f.scene.triangle_count, layers, 0, 0);
        }
        d.cmd_end_rendering(ctx.cmd);
    }
}
