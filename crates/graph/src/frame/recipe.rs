//! The frame recipe: [`build_frame`] is the one place that says what runs, in what order, on what data.
//!
//! ```text
//!   voxelize ──────────────────────────────┐ (kept per grid)
//!   dprsm (VPLs) ─────────────┬────────────┤ (kept per map settings and lights)
//!   gbuffer ──────── direct ──┤            │ (kept per camera, size and lights; exact shadow rays)
//!                             ├ importance → cdf_reduce (kept per CDF key; `uniform`'s in its own slot)
//!                             ├ end_balls (per pixel, per VPL: kept with the G-buffer, the VPLs; exact gather)
//!                             ├ [psm_select → psm] → gather | mis | reference → radiance (temporal)
//!                             └ reproject → ris (initial, temporal, spatial, shade) → [denoise] → radiance
//! ```
//!
//! Every product above the last line is asked for with [`Graph::cached`] under its key
//! ([`super::keys::Keys`]); the graph lends what it kept or records the passes, so the recipe reads the
//! same whether a product is reused or made. Passes whose outputs the frame does not need are culled by
//! the graph (`--component direct` records no VPL pass). The radiance is a temporal image, so the chunks
//! of one frame (the tiles of `all`, the sample batches of `reference`) add into the same image.

use super::keys::Keys;
use super::settings::{Component, FaceMode, FrameSettings, Method, MisWeights, RisSource};
use crate::bindings::*;
use crate::graph::{Graph, Handle};
use crate::passes::cdf_reduce::CdfReduce;
use crate::passes::end_balls::EndBallImages;
use crate::passes::gather::GatherInputs;
use crate::passes::importance::{ImportanceKind, ImportanceParams};
use crate::passes::reference::ReferenceIo;
use crate::passes::ris::{LastFrame, RisFrame};
use crate::passes::voxelize::VoxelGridSpec;
use crate::passes::{FrameInputs, Passes};
use crate::shader_types::{GatherPush, RisPush};
use bounce_device::{vk, Buffer, Image, ImageDesc};
use std::ops::Range;

/// Importance and CDF: what `importance` → `cdf_reduce` make, kept together.
#[derive(Clone, Copy, Debug)]
pub struct Cdf {
    pub importance: Handle<Buffer>,
    pub cdf: Handle<Buffer>,
}
crate::products!(Cdf { importance, cdf });

/// What a frame hands back to be read.
#[derive(Clone, Copy, Debug)]
pub struct FrameOut {
    /// The asked component's radiance.
    pub radiance: Handle<Image>,
    /// The reference's per-pixel sum of squares (its standard error).
    pub second_moment: Option<Handle<Image>>,
    /// The CDF the gather sampled (sampled methods).
    pub cdf: Option<Handle<Buffer>>,
    /// The raw estimate, where `radiance` is the denoised one (`Method::Realtime`).
    pub raw: Option<Handle<Image>>,
    /// The frame's shadow rays, one uint (ris and realtime).
    pub rays: Option<Handle<Buffer>>,
}

/// What the recipe reads besides the settings: the frame's keys, the importance parameters and grid.
pub struct RecipeInputs<'a> {
    pub f: FrameInputs<'a>,
    pub keys: Keys,
    pub importance: ImportanceParams,
    pub grid: VoxelGridSpec,
    /// The reference's samples per dispatch under the loop limit.
    pub reference_per_dispatch: u32,
    /// ris's candidates per initial dispatch under the loop limit.
    pub ris_candidates_per_dispatch: u32,
}

/// The frame recipe, for the part `chunk` of the frame's work: the VPL tile of `all`, the sample range
/// of `reference`, everything (`0..1`) for the sampled methods.
pub fn build_frame<'a>(
    r: &'a Passes,
    g: &mut Graph<'a>,
    s: &FrameSettings,
    i: &RecipeInputs<'a>,
    chunk: Range<u32>,
) -> anyhow::Result<FrameOut> {
    let (f, k) = (i.f, &i.keys);
    // The voxel grid only where something marches it: exact rays need none.
    let voxels = s
        .visibility
        .marches_voxels()
        .then(|| g.try_cached("voxels", &k.voxels, |g| r.voxelize.add(g, f, &i.grid)))
        .transpose()?;
    let vpls = g.cached("vpls", &k.vpls, |g| r.dprsm.add(g, f));
    let gbuffer = g.cached("gbuffer", &k.gbuffer, |g| r.gbuffer.add(g, f));
    let direct = g.cached("direct", &k.direct, |g| r.direct.add(g, f, &gbuffer));
    let combined = (s.component == Component::Combined).then_some(direct);
    if s.component == Component::Direct {
        return Ok(FrameOut::default_for(direct));
    }
    let desc = |name| radiance_desc(name, f.width, f.height);
    let mut out = g.temporal_image("radiance", desc(out_name(s.method)), &()).handle;
    if s.method == Method::Reference {
        let mut sq = g.temporal_image("radiance.sq", desc("reference.sq"), &()).handle;
        let io = ReferenceIo {
            g_position: gbuffer.position,
            g_normal: gbuffer.normal,
            g_albedo: gbuffer.albedo,
            direct: combined,
        };
        let (push, per_dispatch) = (reference_push(s, chunk), i.reference_per_dispatch);
        r.reference.add(g, f, io, &mut out, &mut sq, push, per_dispatch)?;
        return Ok(FrameOut { second_moment: Some(sq), ..FrameOut::default_for(out) });
    }
    let p = i.importance;
    let rows = f.vpl_faces * f.scene.light_count * f.dprsm_res;
    // `uniform`'s CDF (the VPLs' validity) depends on the maps alone: it has its own slot, so switching
    // to a method's CDF and back does not redo it.
    let slot = if p.kind == ImportanceKind::Uniform { "validity_cdf" } else { "cdf" };
    let cdf = g.try_cached(slot, &k.cdf, |g| {
        let imp = r.importance.add(g, f, &gbuffer, &vpls, voxels, p)?;
        let cdf = r.cdf_reduce.add(g, &imp.importance, rows, f.dprsm_res, imp.sections);
        anyhow::Ok(Cdf { importance: imp.importance, cdf })
    })?;
    let mut inputs = GatherInputs::new(&gbuffer, &vpls, voxels, cdf.importance, cdf.cdf, combined);
    if s.uses_end_balls() {
        inputs.ends = Some(EndBallImages {
            pixels: g.try_cached("end_balls.pixels", &k.gbuffer, |g| r.end_balls.add_pixels(g, f, &gbuffer))?,
            vpls: g.try_cached("end_balls.vpls", &k.vpls, |g| r.end_balls.add_vpls(g, f, &vpls))?,
        });
    }
    let push = gather_push(s, f, p, chunk);
    if s.visibility.shared_set() {
        // One shared VPL set (and its shadow maps) for every pixel: passes/psm.rs. Under `mis` it is the
        // CDF strategy's samples; the gathering rays stay per pixel.
        inputs.psm = Some(r.psm.add(g, f, &vpls, cdf.importance, cdf.cdf, s.psm_res, push)?);
    }
    if s.uses_ris() {
        let frame = ris_frame(s, i, push);
        // Temporal reuse follows each pixel's surface to where it was last frame.
        let motion = (frame.push.history_cap > 0.0).then(|| r.reproject.add(g, f, &gbuffer)).transpose()?;
        // Last frame's VPLs weigh the history: the maps this frame replaced when a light moved.
        let last = motion.map(|motion| LastFrame { motion, vpls: g.replaced("vpls").unwrap_or(vpls) });
        let rays = Some(r.ris.add(g, f, &inputs, &mut out, push, frame, last)?);
        let cdf = Some(cdf.cdf);
        if let (Method::Realtime, true, Some(m)) = (s.method, s.denoise, motion) {
            let denoised = r.denoise.add(g, f, &gbuffer, &m, out, combined)?;
            return Ok(FrameOut { raw: Some(out), rays, cdf, ..FrameOut::default_for(denoised) });
        }
        return Ok(FrameOut { rays, cdf, ..FrameOut::default_for(out) });
    }
    let pass = if s.method == Method::Mis { &r.mis } else { &r.gather };
    pass.add(g, f, &inputs, &mut out, push)?;
    Ok(FrameOut { cdf: Some(cdf.cdf), ..FrameOut::default_for(out) })
}

impl FrameOut {
    /// Marks what the frame hands back as wanted (the graph culls passes nothing wants).
    pub fn export(&self, g: &mut Graph) {
        g.export(&self.radiance);
        for h in self.raw.iter() {
            g.export(h);
        }
        for h in self.rays.iter() {
            g.export(h);
        }
    }

    /// A frame whose only product is `radiance`.
    fn default_for(radiance: Handle<Image>) -> FrameOut {
        FrameOut { radiance, second_moment: None, cdf: None, raw: None, rays: None }
    }
}

/// The radiance image's name (labels and validation messages).
fn out_name(m: Method) -> &'static str {
    if m == Method::Reference {
        "reference.sum"
    } else {
        "gather.radiance"
    }
}

pub fn radiance_desc(name: &str, w: u32, h: u32) -> ImageDesc {
    ImageDesc::new(
        name,
        w,
        h,
        crate::passes::direct::RADIANCE_FORMAT,
        vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC,
    )
}

/// Fold a 64-bit seed into the shader's 32-bit one.
pub fn seed32(seed: u64) -> u32 {
    (seed ^ (seed >> 32)) as u32
}

/// The gather's (and mis's) push constants: every VPL of the tile `chunk` for `all`, else `--vpls`
/// samples per pixel (plus the gathering rays for mis).
fn gather_push(s: &FrameSettings, f: FrameInputs, p: ImportanceParams, chunk: Range<u32>) -> GatherPush {
    let d = f.scene.diagonal() * s.clamp;
    let common = GatherPush {
        seed: seed32(s.seed),
        clamp_d2: d * d,
        add_direct: (chunk.start == 0 && s.component == Component::Combined) as u32,
        ..GatherPush::default()
    };
    if s.method == Method::All {
        let all = GATHER_ALL;
        return GatherPush {
            mode: all,
            samples: 1,
            first: chunk.start,
            last: chunk.end,
            accumulate: (chunk.start > 0) as u32,
            ..common
        };
    }
    let rows = f.vpl_faces * f.scene.light_count * f.dprsm_res;
    let push = GatherPush {
        mode: GATHER_SAMPLE,
        samples: s.vpls,
        first: 0,
        last: s.vpls,
        sections: p.kind.method_sections(),
        defensive: if s.sampling_method() == Method::Uniform { 0.0 } else { s.defensive },
        face_mode: match s.face {
            FaceMode::RussianRoulette => FACE_RR,
            FaceMode::Uniform => FACE_UNIFORM,
        },
        cdf_len: CdfReduce::section_len(rows, f.dprsm_res) as u32,
        rays: s.gather_rays,
        // ris has near candidates of its own and mis its gathering rays; `uniform` is the baseline.
        near_share: match s.method {
            Method::Global | Method::Stratified | Method::Local | Method::Gbg => s.near_share,
            _ => 0.0,
        },
        near_radius: s.ris.near_radius,
        ..common
    };
    match (s.method, s.mis_weights) {
        (Method::Mis, w) => GatherPush {
            mode: if w == MisWeights::Consistent { MIS_CONSISTENT } else { MIS_THESIS },
            last: s.vpls + s.gather_rays,
            ..push
        },
        _ => push,
    }
}

/// ris's stages' parameters. The history's key is everything the reservoirs depend on but the seed: the
/// camera and size (G-buffer key), the CDF, and every sampling and reuse setting.
///
/// `Method::Realtime`'s history is kept across camera and light moves (its temporal stage reprojects,
/// and a reservoir's VPL is a light-map texel, re-evaluated where it now is): its key is the size and the
/// settings alone.
fn ris_frame(s: &FrameSettings, i: &RecipeInputs, gather: GatherPush) -> RisFrame {
    let ris = &s.ris_settings();
    let push = ris_push(s);
    let sampling = GatherPush { seed: 0, ..gather };
    let (view, keyed) = if s.method == Method::Realtime {
        // The light maps' size too: a reservoir's VPL is a texel index. Whether the view learns
        // visibility is decided per frame and changes no reservoir's meaning.
        (crate::graph::fingerprint(&(s.width, s.height, s.dprsm_res)), RisPush { learned: 0.0, ..push })
    } else {
        (crate::graph::fingerprint(&(i.keys.gbuffer, i.keys.cdf)), push)
    };
    let key = crate::graph::fingerprint(&(
        view,
        bytemuck::bytes_of(&sampling),
        bytemuck::bytes_of(&keyed),
        ris.spatial_passes,
    ));
    let candidates_per_dispatch =
        ris.candidates_chunk.map_or(i.ris_candidates_per_dispatch, |c| c.get().min(i.ris_candidates_per_dispatch));
    let uniform_source = ris_uniform_source(s);
    RisFrame { push, spatial_passes: ris.spatial_passes, candidates_per_dispatch, key, uniform_source }
}

/// Whether ris's candidates take the uniform source's shortcut (`RisFrame::uniform_source`). `--face`
/// chooses among a CDF's sections only; the uniform source is the validity section alone, whatever it says.
pub(crate) fn ris_uniform_source(s: &FrameSettings) -> bool {
    s.ris_settings().source == RisSource::Uniform
}

/// ris's stages' settings (`pass` and `history` are set per stage).
pub(crate) fn ris_push(s: &FrameSettings) -> RisPush {
    let ris = &s.ris_settings();
    RisPush {
        candidates: ris.candidates,
        // Each candidate stream (--vpls of them; realtime: one) keeps `picks` VPLs, a layer of reservoirs each.
        reservoirs: s.ris_streams() * ris.picks,
        picks: ris.picks,
        neighbors: ris.spatial_neighbors,
        radius: ris.spatial_radius,
        history_cap: ris.temporal_cap,
        pool_tiles: ris.pool_tiles,
        learned: ris.learn_visibility,
        vis_tile: crate::passes::ris::vis_tile(s.width, s.height, ris.learn_tile),
        vis_cell: crate::passes::ris::vis_cell(s.dprsm_res),
        // The near window needs the pool: off otherwise.
        near_candidates: if ris.pool_tiles > 0 { ris.near_candidates.min(ris.candidates.saturating_sub(1)) } else { 0 },
        near_radius: ris.near_radius,
        // The control variate's mean is 0 given the last resampling's inputs: a reservoir's own candidates
        // without reuse (with one candidate it is 0 outright, U_g = g(y) W, so it is not computed), the last
        // spatial pass's reservoirs with it. Temporal reuse alone has no U_g.
        control: match (ris.control_variate, ris.spatial_passes, ris.temporal_cap > 0.0) {
            (false, _, _) => RIS_CONTROL_OFF,
            (true, 0, false) if ris.candidates > 1 => RIS_CONTROL_CANDIDATES,
            (true, 0, _) => RIS_CONTROL_OFF,
            (true, _, _) => RIS_CONTROL_REUSE,
        },
        ..RisPush::default()
    }
}

/// The reference's push constants for the sample range `chunk` of `--spp`, which starts at sample
/// `s.sample_offset` of the pixel's sequence.
fn reference_push(s: &FrameSettings, chunk: Range<u32>) -> GatherPush {
    GatherPush {
        samples: s.spp,
        seed: seed32(s.seed),
        first: s.sample_offset + chunk.start,
        last: s.sample_offset + chunk.end,
        accumulate: (chunk.start > 0) as u32,
        add_direct: (chunk.start == 0 && s.component == Component::Combined) as u32,
        ..GatherPush::default()
    }
}
