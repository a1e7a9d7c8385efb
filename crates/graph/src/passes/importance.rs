//! importance: one non-negative weight per DPRSM texel (VPL) and CDF section, the input of `cdf_reduce`.
//!
//! Output: `importance`, `sections × 2 · lights · dprsm_res²` floats; section s holds texel v at
//! s · texels + v (v = (layer · res + j) · res + i). Section 0 is always the validity map (1 where a
//! texel holds a VPL): the `uniform` method samples it, and every other method mixes it in as its
//! defensive part. The method's sections follow:
//! - `global` (Ritschel et al. 2011, thesis §7.2.2): each VPL's average unshadowed contribution
//!   (luminance, eq. 7.6) to S gather points drawn uniformly over the image (`--cdf-samples S`);
//! - `stratified` (§7.3.2): the same with the gather points spread evenly over the 4 screen quarters;
//! - `local` (§7.3.3): one section per region of a side × side grid (`--regions` = side²), each from
//!   S gather points of its own region;
//! - `gbg` (§7.3.4): R cosine rays per gather point (`--gather-rays R`) marched through the voxels; the
//!   first hit projected into each light's DPRSM credits its VPL with its unshadowed contribution; the
//!   per-texel average (sum / hits) is the weight, and texels no ray reached take the median of their
//!   reached 3×3 neighbours ("hole filling"). Sums are u64 fixed point, so the result is independent of
//!   thread order.
//!
//! In all of them 1/d² is clamped below one voxel cell (importance only: the estimator stays exact).
//! Dispatch: res × res × layers per section (gbg: W × H for the rays, then res × res × layers).

use super::FrameInputs;
use crate::bindings::*;
use crate::gpu_scene::scene_bindings;
use crate::graph::{Graph, Handle};
use crate::passes::dprsm::DprsmOut;
use crate::passes::gbuffer::GBufferOut;
use crate::shader_types::ImportancePush;
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::{self, Access};
use bounce_device::{Binding, Buffer, BufferDesc, ComputePipeline, Gpu, Sampler};

/// Which weights the method sections hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImportanceKind {
    /// No method section: uniform over the VPLs.
    Uniform,
    Global,
    Stratified,
    /// `side × side` regions, one section each.
    Local {
        side: u32,
    },
    /// `rays` cosine rays per gather point.
    Gbg {
        rays: u32,
    },
}

impl ImportanceKind {
    /// Method sections after the validity section.
    pub fn method_sections(self) -> u32 {
        match self {
            ImportanceKind::Uniform => 0,
            ImportanceKind::Local { side } => side * side,
            _ => 1,
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct ImportanceParams {
    pub kind: ImportanceKind,
    /// Gather points per CDF (global, stratified, local).
    pub samples: u32,
    pub seed: u32,
    /// 1/d² is clamped below this squared distance (importance only).
    pub min_d2: f32,
    /// gbg: fixed-point units per unit of contribution.
    pub fixed_scale: f32,
}

pub struct Importance {
    pipeline: ComputePipeline,
    gbg: ComputePipeline,
    sampler: Sampler,
}

/// What the gather needs to know about the importance buffer.
#[derive(Clone, Copy, Debug)]
pub struct ImportanceOut {
    pub importance: Handle<Buffer>,
    /// Sections in all (1 + method sections).
    pub sections: u32,
}

impl Importance {
    pub fn new(gpu: &Gpu) -> Result<Self> {
        let mut bindings = scene_bindings();
        bindings.extend(super::gbuffer_bindings());
        bindings.extend(super::vpl_bindings());
        bindings.push(Binding::storage_buffer(B_IMPORTANCE));
        let push = std::mem::size_of::<ImportancePush>() as u32;
        let pipeline =
            ComputePipeline::new(gpu, "importance", &crate::spirv(shaders::IMPORTANCE_COMP), &bindings, push, &[])?;
        bindings.extend([
            Binding::storage_buffer(B_VOXELS),
            Binding::storage_buffer(B_GBG_SUM),
            Binding::storage_buffer(B_GBG_COUNT),
        ]);
        let gbg = ComputePipeline::new(
            gpu,
            "importance_gbg",
            &crate::spirv(shaders::IMPORTANCE_GBG_COMP),
            &bindings,
            push,
            &[],
        )?;
        Ok(Importance { pipeline, gbg, sampler: Sampler::nearest(gpu)? })
    }

    /// Number of texels (VPL slots) of the reflective DPRSM.
    pub fn texel_count(f: &FrameInputs) -> u64 {
        f.vpl_faces as u64 * f.scene.light_count as u64 * (f.dprsm_res as u64).pow(2)
    }

    pub fn add<'a>(
        &'a self,
        g: &mut Graph<'a>,
        f: FrameInputs<'a>,
        gb: &GBufferOut,
        vpls: &DprsmOut,
        voxels: &Handle<Buffer>,
        p: ImportanceParams,
    ) -> ImportanceOut {
        let texels = Self::texel_count(&f);
        let sections = 1 + p.kind.method_sections();
        let mut importance = g.create_buffer(BufferDesc::storage("importance", 4 * texels * sections as u64));
        let gbg = matches!(p.kind, ImportanceKind::Gbg { .. });
        let mut scratch = gbg.then(|| {
            (
                g.create_buffer(BufferDesc::storage("gbg.sums", 8 * texels)),
                g.create_buffer(BufferDesc::storage("gbg.counts", 4 * texels)),
            )
        });
        let (gb, vpls, voxels, out) = (*gb, *vpls, *voxels, importance);
        let mut b = g
            .add_pass("importance")
            .read(&gb.position, Access::ComputeRead)
            .read(&gb.normal, Access::ComputeRead)
            .read(&gb.albedo, Access::ComputeRead)
            .read(&vpls.position, Access::ComputeRead)
            .read(&vpls.normal, Access::ComputeRead)
            .read(&vpls.flux, Access::ComputeRead);
        if gbg {
            b = b.read(&voxels, Access::ComputeRead);
        }
        if let Some((sums, counts)) = &mut scratch {
            b = b.overwrite(sums, Access::ComputeWrite).overwrite(counts, Access::ComputeWrite);
        }
        let scratch = scratch;
        b.overwrite(&mut importance, Access::ComputeWrite).record(move |ctx| {
            let s = self.sampler.raw;
            let writes =
                super::gbuffer_writes(f.scene.writes(f.uniforms), ctx, [&gb.position, &gb.normal, &gb.albedo], s);
            let mut writes = super::vpl_writes(writes, ctx, [&vpls.position, &vpls.normal, &vpls.flux], s)
                .storage_buffer(B_IMPORTANCE, ctx.buffer(&out));
            let layers = f.vpl_faces * f.scene.light_count;
            let res = f.dprsm_res;
            let push = |mode, section| ImportancePush {
                mode,
                samples: p.samples,
                seed: p.seed,
                regions: match p.kind {
                    ImportanceKind::Local { side } => side,
                    _ => 1,
                },
                min_d2: p.min_d2,
                fixed_scale: p.fixed_scale,
                section,
                pad: 0,
            };
            // Section 0: validity.
            let p0 = push(IMP_UNIFORM, 0);
            self.pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&p0), [res, res, layers], [WG_2D, WG_2D, 1]);
            let method = match p.kind {
                ImportanceKind::Uniform => None,
                ImportanceKind::Global => Some((IMP_GLOBAL, 1)),
                ImportanceKind::Stratified => Some((IMP_STRATIFIED, 1)),
                ImportanceKind::Local { side } => Some((IMP_LOCAL, side * side)),
                ImportanceKind::Gbg { .. } => None,
            };
            if let Some((mode, n)) = method {
                let pm = push(mode, 1);
                self.pipeline.dispatch(
                    ctx.cmd,
                    &writes,
                    bytemuck::bytes_of(&pm),
                    [res, res, layers * n],
                    [WG_2D, WG_2D, 1],
                );
            }
            if let (ImportanceKind::Gbg { rays }, Some((sums, counts))) = (p.kind, &scratch) {
                let (sb, cb) = (ctx.buffer(sums), ctx.buffer(counts));
                unsafe {
                    ctx.gpu.device.cmd_fill_buffer(ctx.cmd, sb.raw, 0, bounce_device::vk::WHOLE_SIZE, 0);
                    ctx.gpu.device.cmd_fill_buffer(ctx.cmd, cb.raw, 0, bounce_device::vk::WHOLE_SIZE, 0);
                }
                for b in [sb, cb] {
                    sync::buffer_barrier(ctx.gpu, ctx.cmd, b.raw, Access::TransferWrite, Access::ComputeWrite);
                }
                writes = writes
                    .storage_buffer(B_VOXELS, ctx.buffer(&voxels))
                    .storage_buffer(B_GBG_SUM, sb)
                    .storage_buffer(B_GBG_COUNT, cb);
                let scatter = ImportancePush { samples: rays, ..push(IMP_GBG_SCATTER, 1) };
                self.gbg.dispatch(
                    ctx.cmd,
                    &writes,
                    bytemuck::bytes_of(&scatter),
                    [f.width, f.height, 1],
                    [WG_2D, WG_2D, 1],
                );
                for b in [sb, cb] {
                    sync::buffer_barrier(ctx.gpu, ctx.cmd, b.raw, Access::ComputeWrite, Access::ComputeWrite);
                }
                let resolve = push(IMP_GBG_RESOLVE, 1);
                self.gbg.dispatch(
                    ctx.cmd,
                    &writes,
                    bytemuck::bytes_of(&resolve),
                    [res, res, layers],
                    [WG_2D, WG_2D, 1],
                );
            }
        });
        ImportanceOut { importance, sections }
    }
}
