//! reference: the exact one-bounce integrator (the scene contract's `indirect`), traced against the real
//! triangles through the BVH (`crate::bvh`, `glsl/shared/bvh.glsl`). The estimator is stated in
//! `glsl/reference.comp`. Inputs: the G-buffer (primary hits), the scene and BVH buffers, and the direct
//! image for the combined component. Outputs: Σ L_k / N (RGBA32F, plus the direct image when asked) and
//! Σ L_k² / N, accumulated over dispatches of at most `per_dispatch` samples (lavapipe's loop limit: one
//! sample traces 1 + lights rays of at most `GpuBvh::max_iterations_per_ray` iterations each).

use super::FrameInputs;
use crate::bindings::*;
use crate::bvh::GpuBvh;
use crate::gpu_scene::scene_bindings;
use crate::graph::{Graph, Handle};
use crate::shader_types::GatherPush;
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{Binding, ComputePipeline, Gpu, Image, Sampler};

pub struct Reference {
    pipeline: ComputePipeline,
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
        let spec = [(crate::bindings::SPEC_TEXTURED, textured as u32)];
        let pipeline =
            ComputePipeline::new(gpu, "reference", &crate::spirv(shaders::REFERENCE_COMP), &bindings, push, &spec)?;
        Ok(Reference { pipeline, sampler: Sampler::nearest(gpu)? })
    }

    /// Samples one dispatch may take under the device's loop iteration limit.
    pub fn per_dispatch(gpu: &Gpu, bvh: &GpuBvh, lights: u32) -> u32 {
        match gpu.loop_iteration_limit {
            Some(limit) => (limit.saturating_sub(64) / ((1 + lights) * bvh.max_iterations_per_ray() + 8)).max(1),
            None => u32::MAX,
        }
    }

    /// Samples `push.first..push.last` of `push.samples` into `sum` and `sq` (overwritten when
    /// `push.accumulate == 0`), split into dispatches of at most `per_dispatch`.
    #[allow(clippy::too_many_arguments)]
    pub fn add<'a>(
        &'a self,
        g: &mut Graph<'a>,
        f: FrameInputs<'a>,
        bvh: &'a GpuBvh,
        io: ReferenceIo,
        sum: &mut Handle<Image>,
        sq: &mut Handle<Image>,
        push: GatherPush,
        per_dispatch: u32,
    ) {
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
            let writes = bvh.writes(
                super::gbuffer_writes(f.scene.writes(f.uniforms), ctx, [&io.g_position, &io.g_normal, &io.g_albedo], s)
                    .sampled_image(B_GATHER_DIRECT, direct, s)
                    .storage_image(B_GATHER_OUT, ctx.image(&hs))
                    .storage_image(B_REF_SQ, ctx.image(&hq)),
            );
            let mut first = push.first;
            loop {
                let last = first.saturating_add(per_dispatch.max(1)).min(push.last);
                let p = GatherPush {
                    first,
                    last,
                    accumulate: if first == push.first { push.accumulate } else { 1 },
                    add_direct: if first == push.first { push.add_direct } else { 0 },
                    ..push
                };
                if first != push.first {
                    ctx.serialize(&hs);
                    ctx.serialize(&hq);
                }
                self.pipeline.dispatch(
                    ctx.cmd,
                    &writes,
                    bytemuck::bytes_of(&p),
                    [f.width, f.height, 1],
                    [WG_2D, WG_2D, 1],
                );
                first = last;
                if first >= push.last {
                    break;
                }
            }
        });
    }
}
