//! psm: per-VPL paraboloid shadow maps, the visibility of the thesis's chapter 6 (`--visibility psm`).
//!
//! A shadow map per (pixel, sample) is impossible, so the frame draws one shared set of N VPLs
//! (`psm.comp`: sample k from the method's CDF mixture, point k of one stratified set per seed, not per
//! pixel; N = `--vpls`),
//! renders one paraboloid depth map per VPL (around the VPL's normal; `psm.vert`, `psm.geom`, `psm.frag`),
//! and every pixel gathers those N VPLs:
//!
//!   L(x) = 1/N Σ_k albedo(x)/π · Φ_k (cos θ_k/π) cos θ_x / d² · V_psm(x, k) / p_k,
//!
//! unbiased for the VPL sum given V_psm, exactly as the per-pixel draws are (each pixel's N samples are
//! the same N draws from the same mixture; the pixels' errors are correlated instead of independent:
//! the structured noise of the thesis's Fig. 6.1). V_psm compares x's distance with the map's texel
//! along x's direction, with a depth bias (`paraboloid_shadow_bias`, `glsl/shared/scene.glsl`). Under `mis` the shared
//! set is its CDF strategy's samples, and its gathering rays march the voxel grid: `glsl/mis.comp` states what that blend
//! estimates.
//!
//! **The maps are rasterized exactly.** The paraboloid projection (u, v) = (x, y)/(|p| + z) (thesis eq.
//! 6.6; a stereographic projection of the direction) is not linear: a triangle's image is bounded by
//! circular arcs, and rasterizing the straight triangle between the projected vertices (what a plain
//! paraboloid shadow map does) cuts or overshoots large triangles. Tessellating only shrinks the error.
//! Instead (the approach of Gascuel et al. 2008 for non-linear projections):
//! 1. the geometry shader clips the triangle to the face's half-space z ≥ 0,
//! 2. bounds its exact image: the projected vertices plus, per edge, the closed-form extreme points of
//!    the edge's circular arc (`include_arc` in `psm.geom`), and emits that box at the depth of the
//!    triangle's nearest point to the VPL (a lower bound on every texel's hit distance;
//!    `glsl/shared/map_depth.glsl`),
//! 3. the fragment shader intersects the ray through each texel's centre with the original triangle and
//!    writes the hit distance as depth (discarding misses), never below the box's. It declares
//!    `depth_greater`, so the depth test rejects a box's texels behind what is already drawn before the
//!    shader runs (the light's former 2048² shadow map on Sibenik, the same geometry: 25 → 19 ms on an
//!    H200, whose fragment shading is scarce; the same images). The `dprsm` test
//!    `the_light_maps_box_depth_is_below_every_texel_depth` checks the box against an f64 closest point.
//!
//! (The reflective light maps were drawn the same way until they cast one ray per texel instead:
//! passes/dprsm.rs says why. These maps stay rasterized: they are the thesis's method, and the exact
//! shadow rays of `--visibility exact` are what replaces them.)
//!
//! Memory: N layers of `--psm-res`² f32 depth (N · res² · 4 bytes: 64 maps at 256² are 16 MiB), bounded
//! by [`MAX_PSM_BYTES`] and the device's array-layer limit, reported by `bounce render --timings`.
//! Inputs: the VPL images, importance and CDF. Outputs: the views buffer and the layered depth image.

use super::FrameInputs;
use crate::bindings::*;
use crate::gpu_scene::scene_bindings;
use crate::graph::{Graph, Handle};
use crate::passes::dprsm::DprsmOut;
use crate::pipelines::Lazy;
use crate::shader_types::{GatherPush, ParaboloidPush, PsmView};
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{
    vk, Binding, Buffer, BufferDesc, Gpu, GraphicsPipeline, GraphicsPipelineDesc, Image, ImageDesc, Sampler,
};
use std::sync::OnceLock;

pub const PSM_DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// The most memory the shadow maps of one frame may take.
pub const MAX_PSM_BYTES: u64 = 1 << 30;

/// Built when a frame first needs it (`--visibility psm`).
pub struct Psm {
    gpu: Gpu,
    select: Lazy<1>,
    maps: OnceLock<GraphicsPipeline>,
    sampler: Sampler,
}

/// The frame's shared VPL set and its shadow maps.
#[derive(Clone, Copy, Debug)]
pub struct PsmOut {
    /// N `PsmView`s.
    pub views: Handle<Buffer>,
    /// N layers of res² distance / far.
    pub depth: Handle<Image>,
}

impl Psm {
    pub fn new(gpu: &Gpu) -> Result<Self> {
        let mut bindings = scene_bindings();
        bindings.extend(super::vpl_bindings());
        bindings.extend([
            Binding::storage_buffer(B_IMPORTANCE),
            Binding::uniform_texel_buffer(B_CDF),
            Binding::storage_buffer(B_PSM_VIEWS),
        ]);
        let push = std::mem::size_of::<GatherPush>() as u32;
        let select = Lazy::new(gpu, "psm_select", shaders::PSM_COMP, &bindings, push);
        Ok(Psm { gpu: gpu.clone(), select, maps: OnceLock::new(), sampler: Sampler::nearest(gpu)? })
    }

    /// The maps' graphics pipeline (the paraboloid geometry shader with the VPL as viewpoint), built on
    /// first use.
    fn maps(&self) -> Result<&GraphicsPipeline> {
        if let Some(p) = self.maps.get() {
            return Ok(p);
        }
        let mut map_bindings = scene_bindings();
        map_bindings.push(Binding::storage_buffer(B_PSM_VIEWS));
        let p = GraphicsPipeline::new(
            &self.gpu,
            &GraphicsPipelineDesc {
                name: "psm",
                vertex: &crate::spirv(shaders::PSM_VERT),
                geometry: Some(&crate::spirv(shaders::PSM_GEOM)),
                fragment: &crate::spirv(shaders::PSM_FRAG),
                color_formats: &[],
                depth_format: Some(PSM_DEPTH_FORMAT),
                depth_compare: vk::CompareOp::LESS,
                bindings: &map_bindings,
                push_constant_size: std::mem::size_of::<ParaboloidPush>() as u32,
                spec: &[],
            },
        )?;
        Ok(self.maps.get_or_init(|| p))
    }

    /// Bytes of `n` maps of `res`².
    pub fn bytes(n: u32, res: u32) -> u64 {
        n as u64 * res as u64 * res as u64 * 4
    }

    /// Draws the shared set (`push` as the gather's: seed, sections, defensive share, face mode; `samples`
    /// = N) and renders its maps at `res`².
    #[allow(clippy::too_many_arguments)]
    pub fn add<'a>(
        &'a self,
        g: &mut Graph<'a>,
        f: FrameInputs<'a>,
        vpls: &DprsmOut,
        importance: Handle<Buffer>,
        cdf: Handle<Buffer>,
        res: u32,
        push: GatherPush,
    ) -> Result<PsmOut> {
        let (select, maps) = (self.select.pipeline()?, self.maps()?);
        let n = push.samples.max(1);
        let mut views =
            g.create_buffer(BufferDesc::storage("psm.views", n as u64 * std::mem::size_of::<PsmView>() as u64));
        let (v, view_h) = (*vpls, views);
        g.add_pass("psm_select")
            .read(&v.position, Access::ComputeRead)
            .read(&v.normal, Access::ComputeRead)
            .read(&v.flux, Access::ComputeRead)
            .read(&importance, Access::ComputeRead)
            .read(&cdf, Access::ComputeRead)
            .overwrite(&mut views, Access::ComputeWrite)
            .record(move |ctx| {
                let s = self.sampler.raw;
                let writes = super::vpl_writes(f.scene.writes(f.uniforms), ctx, [&v.position, &v.normal, &v.flux], s)
                    .storage_buffer(B_IMPORTANCE, ctx.buffer(&importance))
                    .texel_view(B_CDF, ctx.buffer(&cdf))
                    .storage_buffer(B_PSM_VIEWS, ctx.buffer(&view_h));
                select.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&push), [n, 1, 1], [WG_1D, 1, 1]);
            });
        let mut depth = depth_image(g, "psm.depth", res, n);
        let (vh, dh) = (views, depth);
        g.add_pass("psm").read(&views, Access::ShaderRead).overwrite(&mut depth, Access::DepthAttachment).record(
            move |ctx| {
                let writes = f.scene.writes(f.uniforms).storage_buffer(B_PSM_VIEWS, ctx.buffer(&vh));
                record_maps(ctx, maps, f, writes, res, n, &dh);
            },
        );
        Ok(PsmOut { views, depth })
    }
}

/// Binding declarations the gather adds for `--visibility psm`: the shared set's views and maps.
pub fn gather_bindings() -> Vec<Binding> {
    vec![Binding::storage_buffer(B_PSM_VIEWS), Binding::sampled_image(B_PSM_DEPTH)]
}

/// The maps' layered depth image: `layers` of `res`².
fn depth_image(g: &mut Graph, name: &str, res: u32, layers: u32) -> Handle<Image> {
    g.create_image(
        ImageDesc::new(
            name,
            res,
            res,
            PSM_DEPTH_FORMAT,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
                | vk::ImageUsageFlags::SAMPLED
                | vk::ImageUsageFlags::TRANSFER_SRC,
        )
        .layers(layers),
    )
}

/// Records the maps: `layers` instances of every scene triangle, instance k into layer k (the geometry
/// shader takes VPL k as the viewpoint), cleared to far depth first. Depth only, at the texel centres.
fn record_maps(
    ctx: &crate::graph::PassContext,
    pipeline: &GraphicsPipeline,
    f: FrameInputs,
    writes: bounce_device::DescriptorWrites,
    res: u32,
    layers: u32,
    depth: &Handle<Image>,
) {
    let d = &ctx.gpu.device;
    let extent = vk::Extent2D { width: res, height: res };
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
        .depth_attachment(&depth);
    // SAFETY: `ctx.cmd` is recording outside a rendering instance (the graph records passes one after
    // another); the depth image was transitioned to DepthAttachment by the graph for this pass; the
    // pipeline was built for this device with a D32 depth attachment and no colour ones, as rendered here.
    unsafe {
        d.cmd_begin_rendering(ctx.cmd, &info);
        if f.scene.triangle_count > 0 {
            let push = ParaboloidPush { map_res: res, pad: 0, offset: [0.5; 2] };
            pipeline.bind(ctx.cmd, extent, &writes, bytemuck::bytes_of(&push));
            d.cmd_draw(ctx.cmd, 3 * f.scene.triangle_count, layers, 0, 0);
        }
        d.cmd_end_rendering(ctx.cmd);
    }
}
