//! importance: one non-negative weight per DPRSM texel (VPL), the input of `cdf_reduce`.
//!
//! Input: the reflective DPRSM. Output: `importance`, `2 × lights × dprsm_res²` floats in texel order
//! v = (layer · res + j) · res + i. Dispatch: res × res × layers in 8×8 groups.
//! The uniform method's weight is 1 for every non-empty texel and 0 for empty ones, so sampling the
//! CDF picks uniformly among the VPLs that exist (p_v = 1 / #VPLs).

use super::FrameInputs;
use crate::bindings::*;
use crate::gpu_scene::scene_bindings;
use crate::graph::{Graph, Handle};
use crate::passes::dprsm::DprsmOut;
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{Binding, Buffer, BufferDesc, ComputePipeline, Gpu, Sampler};

pub struct Importance {
    pipeline: ComputePipeline,
    sampler: Sampler,
}

impl Importance {
    pub fn new(gpu: &Gpu) -> Result<Self> {
        let mut bindings = scene_bindings();
        bindings.extend([Binding::sampled_image(B_VPL_POSITION), Binding::storage_buffer(B_IMPORTANCE)]);
        let pipeline =
            ComputePipeline::new(gpu, "importance", &crate::spirv(shaders::IMPORTANCE_COMP), &bindings, 0, &[])?;
        Ok(Importance { pipeline, sampler: Sampler::nearest(gpu)? })
    }

    /// Number of texels (VPL slots) of the reflective DPRSM.
    pub fn texel_count(f: &FrameInputs) -> u64 {
        2 * f.scene.light_count as u64 * (f.dprsm_res as u64).pow(2)
    }

    /// The uniform method's weights: 1 per non-empty texel.
    pub fn add_uniform<'a>(&'a self, g: &mut Graph<'a>, f: FrameInputs<'a>, vpls: &DprsmOut) -> Handle<Buffer> {
        let mut importance = g.create_buffer(BufferDesc::storage("importance", 4 * Self::texel_count(&f)));
        let (vpls, out) = (*vpls, importance);
        g.add_pass("importance")
            .read(&vpls.position, Access::ComputeRead)
            .overwrite(&mut importance, Access::ComputeWrite)
            .record(move |ctx| {
                let writes = f
                    .scene
                    .writes(f.uniforms)
                    .sampled_image(B_VPL_POSITION, ctx.image(&vpls.position), self.sampler.raw)
                    .storage_buffer(B_IMPORTANCE, ctx.buffer(&out));
                let layers = 2 * f.scene.light_count;
                self.pipeline.dispatch(ctx.cmd, &writes, &[], [f.dprsm_res, f.dprsm_res, layers], [WG_2D, WG_2D, 1]);
            });
        importance
    }
}
