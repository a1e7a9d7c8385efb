//! reproject: where each pixel's surface was last frame (motion from the G-buffer), and this frame's
//! surface kept for the next one. `glsl/reproject.comp`, one dispatch of W × H.
//!
//! Inputs: the G-buffer (position, normal, albedo), last frame's surface (a history kept by this pass),
//! `FrameUniforms::prev_view_proj`. Outputs: `motion` RGBA32F (xy: where the point was on last frame's
//! screen, in pixels, its previous pixel q = ⌊xy⌋; z: 1 where last frame saw the same surface at q, else 0;
//! w: a 4-bit mask of the four pixels around xy that saw it, whose centres a bilinear lookup weighs) and
//! this frame's surface (`surface.position` RGBA32F: xyz,
//! hit; `surface` RGBA32UI: the normal's float bits and the albedo as unorm8), which ris's temporal
//! stage and the denoiser read as last frame's.
//!
//! The scene is static, so a surface point's motion is the camera's: x projects through last frame's
//! view-projection to p + ½ + (ndc_prev(x) − ndc(x)) · ½ · (W, H) (p the pixel; the difference of x's two
//! projections, so that their rounding cancels and a still camera maps each pixel onto itself exactly: by
//! the projection alone a still camera's points landed off the pixel centres, and on a millimetre room the
//! denoiser's bilinear lookups blurred its history, 3.2× the flicker), and q is its floor. q is x's
//! previous pixel when last frame's point there lies within `plane` pixel footprints of x's tangent
//! plane, |n · (x_q − x)| ≤ plane · θ_px · |x − eye| (θ_px = 2 tan(fov/2) / H: scale-free, from
//! millimetres to kilometres), and its normal within acos(`normal`) of n: disocclusion by depth and
//! normal. A point that was off screen
//! or hidden gets no previous pixel. Where a history is reused by weights that evaluate last frame's
//! target at last frame's surface (ris's temporal stage), this test decides only how often the history
//! is used, never whether the result is unbiased.

use super::FrameInputs;
use crate::bindings::*;
use crate::graph::{Graph, Handle};
use crate::passes::gbuffer::GBufferOut;
use crate::pipelines::Lazy;
use crate::shader_types::ReprojectPush;
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{vk, Binding, Gpu, Image, ImageDesc, Sampler};

/// Disocclusion: the most a point may lie off last frame's surface, in pixel footprints (a pixel's
/// surface point moves within its footprint between frames; 2 leaves room for a slanted one).
pub const PLANE_FOOTPRINTS: f32 = 2.0;
/// Disocclusion: the least cosine between the normals (about 25°).
pub const NORMAL_COS: f32 = 0.9;

pub struct Reproject {
    pipeline: Lazy<1>,
    sampler: Sampler,
}

/// What reprojection gives the frame's temporal stages.
#[derive(Clone, Copy, Debug)]
pub struct Motion {
    /// Per pixel: where its point was (xy, in pixels; the previous pixel is ⌊xy⌋), whether that pixel holds
    /// the same surface (z), and which of the four around xy do (w, a 4-bit mask).
    pub motion: Handle<Image>,
    /// Last frame's surface (stand-ins of 1 × 1 on a first frame, when `history` is false).
    pub prev_position: Handle<Image>,
    pub prev_surface: Handle<Image>,
    /// Whether last frame's surface was kept.
    pub history: bool,
}

fn desc(name: &str, w: u32, h: u32, format: vk::Format) -> ImageDesc {
    ImageDesc::new(name, w, h, format, vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED)
}

impl Reproject {
    pub fn new(gpu: &Gpu) -> Result<Self> {
        let mut bindings = crate::gpu_scene::scene_bindings();
        bindings.extend(super::gbuffer_bindings());
        bindings.extend([
            Binding::sampled_image(B_PREV_POSITION),
            Binding::sampled_image(B_PREV_SURFACE),
            Binding::storage_image(B_MOTION),
            Binding::storage_image(B_SURFACE_POSITION_OUT),
            Binding::storage_image(B_SURFACE_OUT),
        ]);
        let push = std::mem::size_of::<ReprojectPush>() as u32;
        Ok(Reproject {
            pipeline: Lazy::new(gpu, "reproject", shaders::REPROJECT_COMP, &bindings, push),
            sampler: Sampler::nearest(gpu)?,
        })
    }

    /// Motion for this frame's G-buffer, and its surface kept (a history of its own, keyed by the size).
    pub fn add<'a>(&'a self, g: &mut Graph<'a>, f: FrameInputs<'a>, gb: &GBufferOut) -> Result<Motion> {
        let (w, h) = (f.width, f.height);
        let pipeline = self.pipeline.pipeline()?;
        let key = (w, h);
        let position = g.history_image("surface.position", desc("surface.position", w, h, POSITION), &key);
        let surface = g.history_image("surface", desc("surface", w, h, SURFACE), &key);
        let history = position.previous.is_some() && surface.previous.is_some();
        let (prev_position, prev_surface) = match (position.previous, surface.previous) {
            (Some(p), Some(s)) => (p, s),
            _ => (
                g.create_image(desc("surface.position (none)", 1, 1, POSITION)),
                g.create_image(desc("surface (none)", 1, 1, SURFACE)),
            ),
        };
        let mut motion = g.create_image(desc("motion", w, h, vk::Format::R32G32B32A32_SFLOAT));
        let (mut cur_position, mut cur_surface) = (position.current, surface.current);
        let (gb, m, cp, cs) = (*gb, motion, cur_position, cur_surface);
        let push = ReprojectPush { history: history as u32, plane: PLANE_FOOTPRINTS, normal: NORMAL_COS, pad: 0 };
        g.add_pass("reproject")
            .read(&gb.position, Access::ComputeRead)
            .read(&gb.normal, Access::ComputeRead)
            .read(&gb.albedo, Access::ComputeRead)
            .read(&prev_position, Access::ComputeRead)
            .read(&prev_surface, Access::ComputeRead)
            .overwrite(&mut motion, Access::ComputeWrite)
            .overwrite(&mut cur_position, Access::ComputeWrite)
            .overwrite(&mut cur_surface, Access::ComputeWrite)
            .record(move |ctx| {
                let s = self.sampler.raw;
                let writes =
                    super::gbuffer_writes(f.scene.writes(f.uniforms), ctx, [&gb.position, &gb.normal, &gb.albedo], s)
                        .sampled_image(B_PREV_POSITION, ctx.image(&prev_position), s)
                        .sampled_image(B_PREV_SURFACE, ctx.image(&prev_surface), s)
                        .storage_image(B_MOTION, ctx.image(&m))
                        .storage_image(B_SURFACE_POSITION_OUT, ctx.image(&cp))
                        .storage_image(B_SURFACE_OUT, ctx.image(&cs));
                pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&push), [w, h, 1], [WG_2D, WG_2D, 1]);
            });
        Ok(Motion { motion, prev_position, prev_surface, history })
    }
}

const POSITION: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const SURFACE: vk::Format = vk::Format::R32G32B32A32_UINT;
