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
//!   S / side² gather points of its own region (the thesis: S each) (a pixel samples the regions around
//!   it, blended bilinearly: `region_mixture` in glsl/shared/sampling.glsl);
//! - `gbg` (§7.3.4): R cosine rays per gather point (`--gather-rays R`) marched through the voxels; the
//!   first hit projected into each light's DPRSM credits its VPL with its unshadowed contribution; the
//!   per-texel average (sum / hits) is the weight, and texels no ray reached take the median of their
//!   reached 3×3 neighbours ("hole filling"). Sums are u64 fixed point, so the result is independent of
//!   thread order.
//!
//! In all of them 1/d² is clamped below one voxel cell (importance only: the estimator stays exact).
//! Dispatch: res × res × layers per section (gbg: `importance_clear` zeroes the scratch sums, then W × H
//! for the rays, then res × res × layers), each dispatch serialized after the previous one by the graph.

use super::FrameInputs;
use crate::bindings::*;
use crate::frame::Visibility;
use crate::gpu_scene::scene_bindings;
use crate::graph::{Graph, Handle, PassContext};
use crate::passes::dprsm::DprsmOut;
use crate::passes::gbuffer::GBufferOut;
use crate::pipelines::Lazy;
use crate::shader_types::ImportancePush;
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{vk, Binding, Buffer, BufferDesc, ComputePipeline, DescriptorWrites, Gpu, Sampler};

/// Which weights the method sections hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
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
    /// Gather points of the importance (global, stratified; local splits them among its regions).
    pub samples: u32,
    pub seed: u32,
    /// 1/d² is clamped below this squared distance (importance only).
    pub min_d2: f32,
    /// gbg: fixed-point units per unit of contribution.
    pub fixed_scale: f32,
}

pub struct Importance {
    pipeline: Lazy<1>,
    gbg: Lazy<1>,
    /// gbg's scatter with `--visibility exact`: each ray's real first hit (binds the BVH).
    gbg_exact: Lazy<1>,
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
        let pipeline = Lazy::new(gpu, "importance", shaders::IMPORTANCE_COMP, &bindings, push);
        bindings.extend([
            Binding::storage_buffer(B_VOXELS),
            Binding::storage_buffer(B_GBG_SUM),
            Binding::storage_buffer(B_GBG_COUNT),
        ]);
        let gbg = Lazy::new(gpu, "importance_gbg", shaders::IMPORTANCE_GBG_COMP, &bindings, push);
        bindings.extend(crate::gpu_bvh::GpuBvh::bindings());
        let gbg_exact = Lazy::new(gpu, "importance_gbg", shaders::IMPORTANCE_GBG_EXACT_COMP, &bindings, push);
        Ok(Importance { pipeline, gbg, gbg_exact, sampler: Sampler::nearest(gpu)? })
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
        voxels: Option<Handle<Buffer>>,
        p: ImportanceParams,
    ) -> Result<ImportanceOut> {
        let pipelines = Pipelines {
            validity: self.pipeline.pipeline()?,
            scatter: match (p.kind, f.visibility) {
                (ImportanceKind::Gbg { .. }, Visibility::Exact) => Some(self.gbg_exact.pipeline()?),
                (ImportanceKind::Gbg { .. }, Visibility::Voxel | Visibility::Psm) => Some(self.gbg.pipeline()?),
                _ => None,
            },
        };
        let texels = Self::texel_count(&f);
        let sections = 1 + p.kind.method_sections();
        let mut importance = g.create_buffer(BufferDesc::storage("importance", 4 * texels * sections as u64));
        let gbg = matches!(p.kind, ImportanceKind::Gbg { .. });
        let mut scratch = gbg.then(|| Self::add_clear(g, texels));
        let io = Io { gb: *gb, vpls: *vpls, voxels, out: importance, scratch, sampler: self.sampler.raw };
        let mut b = g.add_pass("importance");
        for h in [&gb.position, &gb.normal, &gb.albedo, &vpls.position, &vpls.normal, &vpls.flux] {
            b = b.read(h, Access::ComputeRead);
        }
        if let (true, Some(v)) = (gbg, &voxels) {
            b = b.read(v, Access::ComputeRead);
        }
        if let Some((sums, counts)) = &mut scratch {
            b = b.write(sums, Access::ComputeWrite).write(counts, Access::ComputeWrite);
        }
        b.overwrite(&mut importance, Access::ComputeWrite).record(move |ctx| Self::record(ctx, f, p, io, pipelines));
        Ok(ImportanceOut { importance, sections })
    }

    /// gbg's scratch sums and counts, zeroed by `importance_clear` (the scatter adds into them).
    fn add_clear(g: &mut Graph, texels: u64) -> (Handle<Buffer>, Handle<Buffer>) {
        let mut sums = g.create_buffer(BufferDesc::storage("gbg.sums", 8 * texels));
        let mut counts = g.create_buffer(BufferDesc::storage("gbg.counts", 4 * texels));
        g.add_clear("importance_clear", &mut [&mut sums, &mut counts]);
        (sums, counts)
    }

    /// The dispatches: validity (section 0), then the method's sections, or gbg's scatter and resolve.
    /// Sections are disjoint ranges of one whole-buffer binding; each dispatch is serialized after the
    /// previous one through the graph (as in `cdf_reduce`).
    fn record(ctx: &PassContext, f: FrameInputs, p: ImportanceParams, io: Io, pipelines: Pipelines) {
        let s = io.sampler;
        let (gb, vpls, out) = (io.gb, io.vpls, io.out);
        let writes = super::gbuffer_writes(f.scene.writes(f.uniforms), ctx, [&gb.position, &gb.normal, &gb.albedo], s);
        let mut writes = super::vpl_writes(writes, ctx, [&vpls.position, &vpls.normal, &vpls.flux], s)
            .storage_buffer(B_IMPORTANCE, ctx.buffer(&out));
        let layers = f.vpl_faces * f.scene.light_count;
        let res = f.dprsm_res;
        let push = |mode, section| ImportancePush {
            mode,
            // local splits the S gather points among its regions: the importance of every kind costs
            // the same at one S (the thesis gives each region S: 4× global's cost, which lost at equal
            // time over the generated suite: BENCHMARKS.md).
            samples: match p.kind {
                ImportanceKind::Local { side } => (p.samples / (side * side)).max(1),
                _ => p.samples,
            },
            seed: p.seed,
            regions: match p.kind {
                ImportanceKind::Local { side } => side,
                _ => 1,
            },
            min_d2: p.min_d2,
            fixed_scale: p.fixed_scale,
            section,
            first: 0,
        };
        let dispatch = |pipeline: &ComputePipeline, writes: &DescriptorWrites, push: ImportancePush, size| {
            pipeline.dispatch(ctx.cmd, writes, bytemuck::bytes_of(&push), size, [WG_2D, WG_2D, 1]);
        };
        dispatch(pipelines.validity, &writes, push(IMP_UNIFORM, 0), [res, res, layers]);
        let method = match p.kind {
            ImportanceKind::Uniform | ImportanceKind::Gbg { .. } => None,
            ImportanceKind::Global => Some((IMP_GLOBAL, 1)),
            ImportanceKind::Stratified => Some((IMP_STRATIFIED, 1)),
            ImportanceKind::Local { side } => Some((IMP_LOCAL, side * side)),
        };
        if let Some((mode, n)) = method {
            ctx.serialize(&out);
            dispatch(pipelines.validity, &writes, push(mode, 1), [res, res, layers * n]);
        }
        if let (ImportanceKind::Gbg { rays }, Some((sums, counts)), Some(scatter)) =
            (p.kind, &io.scratch, pipelines.scatter)
        {
            if let Some(v) = &io.voxels {
                writes = writes.storage_buffer(B_VOXELS, ctx.buffer(v));
            }
            writes = writes.storage_buffer(B_GBG_SUM, ctx.buffer(sums)).storage_buffer(B_GBG_COUNT, ctx.buffer(counts));
            ctx.serialize(&out);
            // The voxel march's rays all fit one dispatch; traced rays go in shares under the loop limit.
            let chunk = f.traces_per_dispatch.max(1);
            let (chunk, writes) = match f.visibility {
                Visibility::Exact => (chunk, f.bvh.writes(writes)),
                Visibility::Voxel | Visibility::Psm => (rays.max(1), writes),
            };
            for first in (0..rays).step_by(chunk as usize) {
                if first > 0 {
                    // The next share adds to the same sums (atomics: the order does not matter, the hazard does).
                    ctx.serialize(sums);
                    ctx.serialize(counts);
                }
                let p = ImportancePush { samples: rays, regions: chunk, first, ..push(IMP_GBG_SCATTER, 1) };
                dispatch(scatter, &writes, p, [f.width, f.height, 1]);
            }
            // The resolve reads the scattered sums and counts and writes section 1.
            ctx.serialize(sums);
            ctx.serialize(counts);
            ctx.serialize(&out);
            dispatch(scatter, &writes, push(IMP_GBG_RESOLVE, 1), [res, res, layers]);
        }
    }
}

/// The importance pass's resources, as its recording sees them.
#[derive(Clone, Copy)]
struct Io {
    gb: GBufferOut,
    vpls: DprsmOut,
    voxels: Option<Handle<Buffer>>,
    out: Handle<Buffer>,
    scratch: Option<(Handle<Buffer>, Handle<Buffer>)>,
    sampler: vk::Sampler,
}

/// The importance pass's pipelines for a frame: the validity and CDF methods', and gbg's scatter and
/// resolve for the frame's visibility.
#[derive(Clone, Copy)]
struct Pipelines<'a> {
    validity: &'a ComputePipeline,
    scatter: Option<&'a ComputePipeline>,
}
