//! reference: the exact one-bounce integrator (the scene contract's `indirect`), traced against the real
//! triangles through the BVH (`crate::bvh`, `glsl/shared/bvh.glsl`). The estimator is stated in
//! `glsl/reference.comp`: two-strategy MIS (a cosine direction at x and a light-side point y, balance
//! heuristic, one of each per sample). It draws Owen-scrambled Sobol points indexed by the global sample index, so a frame's image does not
//! depend on how its samples are split. Inputs: the G-buffer (primary hits), the scene and BVH buffers,
//! and the direct image for the combined component. Outputs: Σ L_k / N (RGBA32F, plus the direct image
//! when asked) and Σ L_k² / N, accumulated over dispatches of at most `per_dispatch` samples (lavapipe's
//! loop limit).

use super::FrameInputs;
use crate::bindings::*;
use crate::gpu_bvh::GpuBvh;
use crate::gpu_scene::scene_bindings;
use crate::graph::{Graph, Handle};
use crate::pipelines::Lazy;
use crate::shader_types::GatherPush;
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{Binding, Gpu, Image, Sampler};

pub struct Reference {
    pipeline: Lazy<1>,
    /// `SPEC_TEXTURED`: whether the scene has textures.
    textured: bool,
    sampler: Sampler,
}

/// The images the reference reads and writes.
#[derive(Clone, Copy)]
pub struct ReferenceIo {
    pub g_position: Handle<Image>,
    pub g_normal: Handle<Image>,
    pub g_albedo: Handle<Image>,
    pub direct: Option<Handle<Image>>,
}

impl Reference {
    /// `textured`: whether the scene has textures (the `SPEC_TEXTURED` specialisation).
    pub fn new(gpu: &Gpu, textured: bool) -> Result<Self> {
        let mut bindings = scene_bindings();
        bindings.extend(super::gbuffer_bindings());
        bindings.extend([
            Binding::sampled_image(B_GATHER_DIRECT),
            Binding::storage_image(B_GATHER_OUT),
            Binding::storage_image(B_REF_SQ),
        ]);
        bindings.extend(GpuBvh::bindings());
        let push = std::mem::size_of::<GatherPush>() as u32;
        Ok(Reference {
            pipeline: Lazy::new(gpu, "reference", shaders::REFERENCE_COMP, &bindings, push),
            textured,
            sampler: Sampler::nearest(gpu)?,
        })
    }

    /// Samples one dispatch may take under the device's loop iteration limit. Per sample an invocation
    /// traces per strategy (two) one first hit and `lights` shadow rays (the shadow rays at y; the light
    /// side's x ↔ y ray replaces the drawing light's own), each bounded by its own traversal's bound, and
    /// over the lights twice more (the pick, the densities), plus 8 for the rest (the Sobol points have
    /// no loop).
    pub fn per_dispatch(gpu: &Gpu, bvh: &GpuBvh, lights: u32) -> u32 {
        let Some(limit) = gpu.loop_iteration_limit else { return u32::MAX };
        let strategies = 2;
        // First hits (bvh_closest_walk) and shadow rays walk the same threaded records.
        let rays = (1 + lights) * bvh.max_iterations_occluded();
        let per_sample = strategies * (rays + 2 * lights) + 8;
        (limit.saturating_sub(64 + lights) / per_sample).max(1)
    }

    /// Samples `push.first..push.last` of `push.samples` into `sum` and `sq` (overwritten when
    /// `push.accumulate == 0`), split into dispatches of at most `per_dispatch`.
    #[allow(clippy::too_many_arguments)]
    pub fn add<'a>(
        &'a self,
        g: &mut Graph<'a>,
        f: FrameInputs<'a>,
        io: ReferenceIo,
        sum: &mut Handle<Image>,
        sq: &mut Handle<Image>,
        push: GatherPush,
        per_dispatch: u32,
    ) -> Result<()> {
        let pipeline = self.pipeline.get(0, &[(crate::bindings::SPEC_TEXTURED, self.textured as u32)])?;
        let (hs, hq) = (*sum, *sq);
        let mut b = g
            .add_pass("reference")
            .read(&io.g_position, Access::ComputeRead)
            .read(&io.g_normal, Access::ComputeRead)
            .read(&io.g_albedo, Access::ComputeRead);
        if let Some(d) = &io.direct {
            b = b.read(d, Access::ComputeRead);
        }
        b = if push.accumulate != 0 {
            b.write(sum, Access::ComputeWrite).write(sq, Access::ComputeWrite)
        } else {
            b.overwrite(sum, Access::ComputeWrite).overwrite(sq, Access::ComputeWrite)
        };
        b.record(move |ctx| {
            let s = self.sampler.raw;
            let direct = match (&io.direct, push.add_direct) {
                (Some(d), 1) => ctx.image(d),
                _ => ctx.image(&io.g_albedo),
            };
            let writes = f.bvh.writes(
                super::gbuffer_writes(f.scene.writes(f.uniforms), ctx, [&io.g_position, &io.g_normal, &io.g_albedo], s)
                    .sampled_image(B_GATHER_DIRECT, direct, s)
                    .storage_image(B_GATHER_OUT, ctx.image(&hs))
                    .storage_image(B_REF_SQ, ctx.image(&hq)),
            );
            for (first, last) in super::dispatch_ranges(push.first, push.last, per_dispatch) {
                if first != push.first {
                    ctx.serialize(&hs);
                    ctx.serialize(&hq);
                }
                let p = push.chunk(first, last);
                pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&p), [f.width, f.height, 1], [WG_2D, WG_2D, 1]);
            }
        });
        Ok(())
    }
}
