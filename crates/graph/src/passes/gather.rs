//! gather: one-bounce indirect radiance at every G-buffer pixel from VPLs.
//!
//!   L_ind(x) ≈ 1/N Σ_k albedo(x)/π · Φ_v · (cos θ_v / π) · cos θ_x · k(d²) · V(x, v) / p_v
//!
//! Φ_v is the VPL's reflected flux (see `dprsm.rs`); Φ_v · cos θ_v / π is its radiant intensity toward
//! x (a Lambertian emitter). V comes from an Amanatides–Woo march through the voxel grid
//! (`glsl/shared/voxel.glsl` states where the march starts and stops), from shadow rays against the
//! BVH (`--visibility exact`), or from per-VPL shadow maps (`psm`). Exact rays are traced from a
//! per-invocation queue (`glsl/shared/shadow_queue.glsl`): each block of 32 samples is drawn first and
//! its rays walked back to back, so a SIMD lane whose ray is done starts its next at once instead of
//! waiting for the vector's longest (the same answers and sums, bit for bit; 5–20 % less gather time on
//! lavapipe, BENCHMARKS.md). Modes:
//! - sampled: N VPLs per pixel drawn from the mixture of `glsl/shared/sampling.glsl`,
//!   p_v = η p_near(v) + (1 − η) (ε / #VPLs + (1 − ε) importance_v / total): the near share η
//!   (`--near-share`) from the pixel's near window, the defensive share ε uniformly, the rest by the
//!   method's CDF (`cdf_reduce`); `uniform` has η = 0, ε = 1;
//! - all: every VPL of a tile [first, last) with p_v = 1 and N = 1, accumulated over tiles: the exhaustive
//!   (converged) VPL estimate, against which every sampling method is judged.
//!
//! The kernel k (`--vpl-kernel`, `glsl/shared/vpl.glsl`). The thesis's point VPL has k = 1/d²: a VPL
//! stands for the surface patch its texel sees (area A_v = Δω_v · d_l² / cos α), but the point's 1/d² has
//! no bound as x nears it, so the VPL sum overshoots next to corners and every sampled method's error
//! is a few pixels' heavy tail (on Sibenik, 0.1 % of the pixels held 90 % of ris's relMSE). The default
//! `patch` kernel k = 1/√(d⁴ + (A_v/π)²) gives at most the patch's radiosity next to x (a disk of area
//! A_v seen from its centre) and differs from 1/d² by (A_v/π)²/(2d⁴) relatively farther out, so the sum
//! keeps the energy of the point VPLs, and both converge to the same one-bounce integral as the map's
//! resolution grows. The disk kernel 1/(d² + A_v/π) (the on-axis disk exactly) was measured too and
//! dropped: its first-order deficit A_v/(πd²) reaches far and darkened Sibenik by 0.9 % (BENCHMARKS.md).
//! `clamp_d2` replaces the denominator by max(·, clamp²), trading variance for a darkening bias near
//! corners; 0 disables it (default). Inputs: G-buffer, reflective DPRSM, voxel grid, importance + CDF,
//! and for the combined component the direct image. Output: RGBA32F radiance. Dispatch ⌈W/8⌉ × ⌈H/8⌉.

use super::FrameInputs;
use crate::bindings::*;
use crate::frame::Visibility;
use crate::gpu_scene::scene_bindings;
use crate::graph::PassContext;
use crate::graph::{Graph, Handle};
use crate::passes::dprsm::DprsmOut;
use crate::passes::gbuffer::GBufferOut;
use crate::pipelines::Lazy;
use crate::shader_types::GatherPush;
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{vk, Binding, Buffer, ComputePipeline, DescriptorWrites, Gpu, Image, Sampler};

pub struct Gather {
    name: &'static str,
    /// The voxel and exact variants.
    vis: VisibilityVariants,
    /// The `--visibility psm` variant (the frame's shared VPL set and its shadow maps).
    psm: Lazy<1>,
    sampler: Sampler,
}

/// One shader in its two per-pixel visibility variants (`voxel.glsl`'s march; `EXACT_VISIBILITY`, which
/// also binds the BVH and the end balls), each built when a frame first needs it: the gather, mis and
/// ris's shade share it. Each has two specialisations: slot 1 gives the near share every light's window
/// (`glsl/shared/near_window.glsl`, NEAR_LIGHTS), for scenes of more than one light; slot 0 one window.
pub struct VisibilityVariants {
    voxel: Lazy<2>,
    exact: Lazy<2>,
}

impl VisibilityVariants {
    /// `spirv`: the voxel and exact variants; `bindings`: what both bind.
    pub fn new(
        gpu: &Gpu,
        name: &'static str,
        spirv: [&'static [u8]; 2],
        mut bindings: Vec<Binding>,
        push: u32,
    ) -> Self {
        let [voxel, exact] = spirv;
        let voxel = Lazy::new(gpu, name, voxel, &bindings, push);
        bindings.extend(crate::gpu_bvh::GpuBvh::bindings());
        bindings.extend(crate::passes::end_balls::gather_bindings());
        let exact = Lazy::new(gpu, name, exact, &bindings, push);
        VisibilityVariants { voxel, exact }
    }

    /// The variant of the frame's visibility (built on first use), with every light's near window when
    /// `near` (the push's near share) and the scene has more than one light.
    pub fn pipeline(&self, f: &FrameInputs, near: bool) -> Result<&ComputePipeline> {
        let multi = near && f.scene.light_count > 1;
        let spec = [(SPEC_RIS_NEAR_LIGHTS, if multi { RIS_NEAR_LIGHTS } else { 1 })];
        match f.visibility {
            Visibility::Exact => self.exact.get(multi as usize, &spec),
            Visibility::Voxel | Visibility::Psm => self.voxel.get(multi as usize, &spec),
        }
    }

    /// `w` plus what the frame's variant binds besides the common set (the BVH).
    pub fn writes(f: &FrameInputs, w: DescriptorWrites) -> DescriptorWrites {
        match f.visibility {
            Visibility::Exact => f.bvh.writes(w),
            Visibility::Voxel | Visibility::Psm => w,
        }
    }
}

/// What every VPL-sampling pass binds: scene, G-buffer, VPL images, voxels, importance and CDF
/// (written by [`GatherInputs::sampling_writes`]).
pub fn sampling_bindings() -> Vec<Binding> {
    let mut bindings = scene_bindings();
    bindings.extend(super::gbuffer_bindings());
    bindings.extend(super::vpl_bindings());
    bindings.extend([
        Binding::storage_buffer(B_VOXELS),
        Binding::storage_buffer(B_IMPORTANCE),
        Binding::uniform_texel_buffer(B_CDF),
    ]);
    bindings
}

/// Everything the gather reads.
#[derive(Clone, Copy)]
pub struct GatherInputs {
    pub g_position: Handle<Image>,
    pub g_normal: Handle<Image>,
    pub g_albedo: Handle<Image>,
    pub vpl_position: Handle<Image>,
    pub vpl_normal: Handle<Image>,
    pub vpl_flux: Handle<Image>,
    /// The voxel grid, when the frame's visibility marches it (`voxel`, and the voxel gathering of
    /// `psm`'s mis); exact rays need none, and then the grid is not made.
    pub voxels: Option<Handle<Buffer>>,
    pub importance: Handle<Buffer>,
    pub cdf: Handle<Buffer>,
    /// Added to the result when set (the combined component).
    pub direct: Option<Handle<Image>>,
    /// `--visibility psm`: the frame's shared VPL set and its shadow maps.
    pub psm: Option<crate::passes::psm::PsmOut>,
    /// The exact gather's end balls: its rays skip them.
    pub ends: Option<crate::passes::end_balls::EndBallImages>,
}

impl GatherInputs {
    pub fn new(
        gbuffer: &GBufferOut,
        vpls: &DprsmOut,
        voxels: Option<Handle<Buffer>>,
        importance: Handle<Buffer>,
        cdf: Handle<Buffer>,
        direct: Option<Handle<Image>>,
    ) -> Self {
        GatherInputs {
            g_position: gbuffer.position,
            g_normal: gbuffer.normal,
            g_albedo: gbuffer.albedo,
            vpl_position: vpls.position,
            vpl_normal: vpls.normal,
            vpl_flux: vpls.flux,
            voxels,
            importance,
            cdf,
            direct,
            psm: None,
            ends: None,
        }
    }

    pub fn images(&self) -> Vec<Handle<Image>> {
        let mut v =
            vec![self.g_position, self.g_normal, self.g_albedo, self.vpl_position, self.vpl_normal, self.vpl_flux];
        v.extend(self.direct);
        v
    }

    /// What depends on the camera: the G-buffer images, then the direct image when there is one.
    pub fn camera_images(&self) -> Vec<Handle<Image>> {
        let mut v = vec![self.g_position, self.g_normal, self.g_albedo];
        v.extend(self.direct);
        v
    }

    /// The end balls' images, when the frame has them.
    pub fn end_ball_images(&self) -> Vec<Handle<Image>> {
        self.ends.iter().flat_map(|e| [e.pixels, e.vpls]).collect()
    }

    pub fn buffers(&self) -> Vec<Handle<Buffer>> {
        self.voxels.into_iter().chain([self.importance, self.cdf]).collect()
    }

    /// The writes of [`sampling_bindings`] (the voxel grid when the frame has one).
    pub fn sampling_writes(&self, f: &FrameInputs, ctx: &PassContext, s: vk::Sampler) -> DescriptorWrites {
        let w = super::gbuffer_writes(
            f.scene.writes(f.uniforms),
            ctx,
            [&self.g_position, &self.g_normal, &self.g_albedo],
            s,
        );
        let w = super::vpl_writes(w, ctx, [&self.vpl_position, &self.vpl_normal, &self.vpl_flux], s);
        let w = match &self.voxels {
            Some(v) => w.storage_buffer(B_VOXELS, ctx.buffer(v)),
            None => w,
        };
        w.storage_buffer(B_IMPORTANCE, ctx.buffer(&self.importance)).texel_view(B_CDF, ctx.buffer(&self.cdf))
    }
}

/// The end balls' writes and the push's `end_balls`, for a layout that holds their bindings (the exact
/// variants): the balls when the frame has them, else stand-ins of the same view types (the
/// G-buffer normal, the VPL normals), which the shader then does not read.
pub(crate) fn end_ball_writes(
    ctx: &PassContext,
    i: &GatherInputs,
    w: DescriptorWrites,
    s: vk::Sampler,
) -> (DescriptorWrites, u32) {
    let (pixels, vpls, on) = match &i.ends {
        Some(e) => (e.pixels, e.vpls, 1),
        None => (i.g_normal, i.vpl_normal, 0),
    };
    (w.sampled_image(B_END_BALL_PIXELS, ctx.image(&pixels), s).sampled_image(B_END_BALL_VPLS, ctx.image(&vpls), s), on)
}

impl Gather {
    pub fn new(gpu: &Gpu) -> Result<Self> {
        use shaders::*;
        Self::with_shaders(gpu, "gather", [GATHER_COMP, GATHER_EXACT_COMP, GATHER_PSM_COMP])
    }

    fn bindings() -> (Vec<Binding>, u32) {
        let mut bindings = sampling_bindings();
        bindings.extend([Binding::sampled_image(B_GATHER_DIRECT), Binding::storage_image(B_GATHER_OUT)]);
        (bindings, std::mem::size_of::<GatherPush>() as u32)
    }

    /// A gather-shaped pass (same bindings and push constants) running other shaders: `mis`. The three
    /// SPIR-V variants, one per [`Visibility`]: the voxel march; exact rays (also binds the BVH and the
    /// end balls); `psm` (also binds the shared set and its maps).
    pub fn with_shaders(gpu: &Gpu, name: &'static str, spirv: [&'static [u8]; 3]) -> Result<Self> {
        let [spirv, exact, psm] = spirv;
        let (bindings, push) = Self::bindings();
        let mut b = bindings.clone();
        b.extend(crate::passes::psm::gather_bindings());
        let psm = Lazy::new(gpu, name, psm, &b, push);
        let vis = VisibilityVariants::new(gpu, name, [spirv, exact], bindings, push);
        Ok(Gather { name, vis, psm, sampler: Sampler::nearest(gpu)? })
    }

    /// The shader variant of the frame's visibility (built on first use).
    fn pipeline(&self, f: &FrameInputs, i: &GatherInputs, push: &GatherPush) -> Result<&ComputePipeline> {
        match (f.visibility, &i.psm) {
            (Visibility::Psm, Some(_)) => self.psm.pipeline(),
            _ => self.vis.pipeline(f, push.near_share > 0.0),
        }
    }

    /// What the frame's variant binds besides the common set, and the push's `end_balls`.
    fn variant_writes(
        &self,
        ctx: &PassContext,
        f: FrameInputs,
        i: &GatherInputs,
        writes: DescriptorWrites,
    ) -> (DescriptorWrites, u32) {
        match (f.visibility, &i.psm) {
            (Visibility::Psm, Some(p)) => {
                let writes = writes.storage_buffer(B_PSM_VIEWS, ctx.buffer(&p.views)).sampled_image(
                    B_PSM_DEPTH,
                    ctx.image(&p.depth),
                    self.sampler.raw,
                );
                (writes, 0)
            }
            (Visibility::Exact, _) => {
                // The exact layout holds the end balls' bindings.
                let (writes, on) = end_ball_writes(ctx, i, writes, self.sampler.raw);
                (VisibilityVariants::writes(&f, writes), on)
            }
            _ => (VisibilityVariants::writes(&f, writes), 0),
        }
    }

    /// Record the gather of `push.first..push.last` (VPLs for `GATHER_ALL`, sample indices for
    /// `GATHER_SAMPLE`) into `out`: overwritten when `push.accumulate == 0`, else added to. The range is
    /// split into dispatches of at most `f.vpls_per_dispatch` (see `FrameInputs`), each adding to the
    /// previous one's result. `direct` is bound only when `push.add_direct` is set; otherwise the G-buffer
    /// albedo stands in for the unused binding.
    pub fn add<'a>(
        &'a self,
        g: &mut Graph<'a>,
        f: FrameInputs<'a>,
        i: &GatherInputs,
        out: &mut Handle<Image>,
        push: GatherPush,
    ) -> Result<()> {
        let (i, o) = (*i, *out);
        let pipeline = self.pipeline(&f, &i, &push)?;
        let mut b = g.add_pass(self.name);
        for h in i.images() {
            b = b.read(&h, Access::ComputeRead);
        }
        for h in i.buffers() {
            b = b.read(&h, Access::ComputeRead);
        }
        for h in i.end_ball_images() {
            b = b.read(&h, Access::ComputeRead);
        }
        if let Some(p) = &i.psm {
            b = b.read(&p.views, Access::ComputeRead).read(&p.depth, Access::ComputeRead);
        }
        b = if push.accumulate != 0 {
            b.write(out, Access::ComputeWrite)
        } else {
            b.overwrite(out, Access::ComputeWrite)
        };
        b.record(move |ctx| {
            let s = self.sampler.raw;
            let direct = match (&i.direct, push.add_direct) {
                (Some(d), 1) => ctx.image(d),
                _ => ctx.image(&i.g_albedo),
            };
            let writes = i
                .sampling_writes(&f, ctx, s)
                .sampled_image(B_GATHER_DIRECT, direct, s)
                .storage_image(B_GATHER_OUT, ctx.image(&o));
            let (writes, end_balls) = self.variant_writes(ctx, f, &i, writes);
            for (first, last) in super::dispatch_ranges(push.first, push.last, f.vpls_per_dispatch) {
                if first != push.first {
                    // The next chunk adds to what the previous one stored.
                    ctx.serialize(&o);
                }
                let p = GatherPush { end_balls, ..push.chunk(first, last) };
                pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&p), [f.width, f.height, 1], [WG_2D, WG_2D, 1]);
            }
        });
        Ok(())
    }
}
