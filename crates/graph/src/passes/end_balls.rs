//! end_balls: the part of each exact shadow ray next to its ends that the gather need not walk.
//!
//! A shadow ray runs between two surfaces, so a BVH walk pays for the nested boxes around both ends
//! whatever lies between (BENCHMARKS.md, "Where a visible ray's records go"). Around an end p on a
//! triangle with plane normal n (turned to the side its rays leave from), the ball of radius r is *empty
//! above its plane* when every triangle that comes within r of p lies at most τ = lift(p)/16 above that
//! plane:
//!
//!   r(p) = min { dist(p, T) : T a triangle with a vertex v, n·(v − p) > τ } − lift(p),  capped at
//!   END_BALL_MAX_RADIUS · diagonal.
//!
//! A segment whose two ends lie more than 2τ above the plane meets no triangle inside that ball (its
//! height is linear along it, and the triangles there lie at or below τ), so the walk may start where
//! the segment leaves the ball: the same answer, fewer records. `glsl/shared/end_balls.glsl` states the
//! rule, its margins against rounding, and the exit parameter; the exact shadow rays of the gather's
//! queue, mis and ris's shade apply it at both ends (always, with exact visibility; not the reference's,
//! which have no VPL end). The ray's own ends are lifted off their surfaces along the shading
//! normal (x) and toward the light (a VPL), so the condition fails, and the ball is not used, only for
//! rays that leave at a grazing angle.
//!
//! Two products, each kept as long as its input:
//! - per pixel (`add_pixels`): the G-buffer's point and triangle (its normal's w), the plane turned to
//!   the shading normal's side; kept with the G-buffer;
//! - per VPL texel (`add_vpls`): the VPL's triangle, found again as the light's first hit toward it, the
//!   plane turned to the light; kept with the VPLs.
//!
//! Output: RGBA32F (n, r), 0 where there is no end or no ball, at the G-buffer's size or the VPL maps'
//! (an array image, their layers). Each end's radius comes from a walk of the threaded BVH records that
//! enters a box only if it is nearer than the nearest blocking triangle so far and reaches more than τ
//! above the plane; a walk that has not finished after END_BALL_MAX_STEPS records gives no ball.
//! Dispatch: ⌈W/8⌉ × ⌈H/8⌉ (× layers) groups of 8×8. `tests/tests/end_balls.rs` checks the radii against
//! a CPU twin, and the gather's, mis's and ris's images with and without the balls.

use super::FrameInputs;
use crate::bindings::*;
use crate::gpu_bvh::GpuBvh;
use crate::gpu_scene::scene_bindings;
use crate::graph::{Graph, Handle, PassContext};
use crate::passes::dprsm::DprsmOut;
use crate::passes::gbuffer::GBufferOut;
use crate::pipelines::Lazy;
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{vk, Binding, DescriptorWrites, Gpu, Image, ImageDesc, Sampler};

pub const END_BALL_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

pub struct EndBalls {
    pixels: Lazy<1>,
    vpls: Lazy<1>,
    sampler: Sampler,
}

/// Both ends' balls, as the exact gather reads them.
#[derive(Clone, Copy, Debug)]
pub struct EndBallImages {
    /// Per G-buffer pixel.
    pub pixels: Handle<Image>,
    /// Per VPL texel (the VPL maps' layers).
    pub vpls: Handle<Image>,
}

/// What the exact gather binds to read the balls (`glsl/gather.comp`).
pub fn gather_bindings() -> [Binding; 2] {
    [Binding::sampled_image(B_END_BALL_PIXELS), Binding::sampled_image(B_END_BALL_VPLS)]
}

impl EndBalls {
    pub fn new(gpu: &Gpu) -> Result<Self> {
        let pipeline = |name, spirv: &'static [u8], inputs: &[Binding]| {
            let mut bindings = scene_bindings();
            bindings.extend(GpuBvh::bindings());
            bindings.extend_from_slice(inputs);
            bindings.push(Binding::storage_image(B_END_BALL_OUT));
            Lazy::new(gpu, name, spirv, &bindings, 0)
        };
        let g = [Binding::sampled_image(B_GATHER_GPOSITION), Binding::sampled_image(B_GATHER_GNORMAL)];
        Ok(EndBalls {
            pixels: pipeline("end_balls.pixels", shaders::END_BALLS_COMP, &g),
            vpls: pipeline("end_balls.vpls", shaders::END_BALLS_VPLS_COMP, &[Binding::sampled_image(B_VPL_POSITION)]),
            sampler: Sampler::nearest(gpu)?,
        })
    }

    fn desc(name: &str, width: u32, height: u32) -> ImageDesc {
        ImageDesc::new(
            name,
            width,
            height,
            END_BALL_FORMAT,
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC,
        )
    }

    /// The balls of the G-buffer's points.
    pub fn add_pixels<'a>(&'a self, g: &mut Graph<'a>, f: FrameInputs<'a>, gb: &GBufferOut) -> Result<Handle<Image>> {
        let pipeline = self.pixels.pipeline()?;
        let desc = Self::desc("end_balls.pixels", f.width, f.height);
        let mut out = g.create_image(desc);
        let (gb, o) = (*gb, out);
        g.add_pass("end_balls.pixels")
            .read(&gb.position, Access::ComputeRead)
            .read(&gb.normal, Access::ComputeRead)
            .overwrite(&mut out, Access::ComputeWrite)
            .record(move |ctx| {
                let s = self.sampler.raw;
                let w = self
                    .writes(f, ctx, &o)
                    .sampled_image(B_GATHER_GPOSITION, ctx.image(&gb.position), s)
                    .sampled_image(B_GATHER_GNORMAL, ctx.image(&gb.normal), s);
                pipeline.dispatch(ctx.cmd, &w, &[], [f.width, f.height, 1], [WG_2D, WG_2D, 1]);
            });
        Ok(out)
    }

    /// The balls of the VPLs (one per texel of the VPL maps).
    pub fn add_vpls<'a>(&'a self, g: &mut Graph<'a>, f: FrameInputs<'a>, vpls: &DprsmOut) -> Result<Handle<Image>> {
        let pipeline = self.vpls.pipeline()?;
        let layers = f.vpl_faces * f.scene.light_count;
        let desc = Self::desc("end_balls.vpls", f.dprsm_res, f.dprsm_res).layers(layers);
        let mut out = g.create_image(desc);
        let (position, o) = (vpls.position, out);
        g.add_pass("end_balls.vpls")
            .read(&position, Access::ComputeRead)
            .overwrite(&mut out, Access::ComputeWrite)
            .record(move |ctx| {
                let w = self.writes(f, ctx, &o).sampled_image(B_VPL_POSITION, ctx.image(&position), self.sampler.raw);
                let size = [f.dprsm_res, f.dprsm_res, layers];
                pipeline.dispatch(ctx.cmd, &w, &[], size, [WG_2D, WG_2D, 1]);
            });
        Ok(out)
    }

    /// What both dispatches bind: the scene, the BVH and the output.
    fn writes(&self, f: FrameInputs, ctx: &PassContext, out: &Handle<Image>) -> DescriptorWrites {
        f.bvh.writes(f.scene.writes(f.uniforms)).storage_image(B_END_BALL_OUT, ctx.image(out))
    }
}
