//! ris: resampled importance sampling over the VPLs (Talbot et al. 2005) with spatial and temporal
//! reuse (ReSTIR, Bitterli et al. 2020; generalized RIS, Lin et al. 2022), for `Method::Ris` and
//! `Method::Realtime` (two reservoirs per pixel with both reuses, `RisSettings::realtime`). One shader
//! per stage (`glsl/ris_<stage>.comp`), the presampling first with `--pool-tiles` T > 0 (the default):
//!
//! - `ris_presample` (1024 × T invocations): the candidate pool, T tiles of `RIS_POOL_TILE` = 1024 draws
//!   of the source; tile j holds points 0..1024 of one stratified set (seeded by j and the frame's seed)
//!   with each draw's VPL data and exact probability p_v. A reservoir then takes its M candidates as
//!   consecutive entries of one tile from a start, tile and start picked by a hash of (pixel, layer,
//!   seed): a candidate costs three texel fetches instead of a draw (RTXDI's light tiles, Wyman and
//!   Panteleev 2021). Why it stays unbiased: each entry is a draw of p (a point of an Owen-scrambled
//!   set is uniform), and the entry a candidate reads is uniform and independent of the entries'
//!   values, so each candidate is marginally a draw of p. RIS needs nothing more: given the candidates
//!   the kept one is y = x_i with probability w_i / Σw, so E[f(y) W | candidates] = 1/M Σ_i f(x_i) /
//!   p(x_i), whose expectation is Σ_v f(v) however the candidates depend on each other (they do: a
//!   tile's entries are stratified, and neighbouring pixels share tiles). Pixels sharing a tile have
//!   correlated errors; what that does to each pixel's error is measured (BENCHMARKS.md), not assumed.
//! - With `--learn-visibility δ_L` > 0 (the pool; `Method::Realtime` always): the target is p̂(v) · max(V̂, δ_L), where V̂ =
//!   (visible + 1) / (traced + 2) counts the earlier frames' shadow rays from the pixel's screen tile to
//!   the VPL's light-map cell (`ris.visibility`, kept across the frames of one view like the history; the
//!   shade adds to it after the frame's initial stage has read it). Unbiased frame by frame: a frame's
//!   target depends on earlier frames only, so given them it is a fixed function, positive wherever p̂
//!   is (δ_L > 0), and RIS is unbiased for any such target; the progressive mean of unbiased frames is
//!   unbiased. It is what makes a VPL behind a wall rare once the rays have seen the wall. The reuse
//!   stages resample by the target with the factor at their own pixel (it cancels from the estimate),
//!   but weigh their inputs (the MIS weights m_i) by the targets without it: the counts hold the rays
//!   earlier frames traced for the inputs' own samples (a history's sample was traced last frame), and
//!   weights that depended on the sample they weigh would not average to the integral.
//! - With `--near-candidates N` > 0 (the default, 8 of 32; the pool, not the voxel target): the last N
//!   candidates are texels of (2r + 1)² windows (`--near-radius r`) around where x projects into each
//!   light's map: the VPLs next to x, which hold the target's tail. A near candidate picks light l's
//!   window with probability α_l ∝ luminance(I_l) / |x − light_l|² among the open ones (the radiosity
//!   its VPLs next to x have), then a texel uniformly (the first `RIS_NEAR_LIGHTS` lights; one window
//!   in a one-light scene). Every candidate's weight is p̂(v) / q(v) with the balance mixture
//!   q = ((M − N) p(v) + N p_near(v)) / M (Talbot's multiple-importance RIS), p_near(v) = α_l / (2r + 1)²
//!   inside light l's window and 0 outside. Unbiased given the windows (fixed by x before any
//!   candidate, so also overall): Σ_s M_s p_s(v) / (Σ_s M_s p_s(v)) = 1 for every v the pool can draw,
//!   which is every VPL with p(v) > 0. (One window per reservoir, its light chosen at random, left a
//!   VPL next to x of the other light's to the pool, which drew it rarely and with a huge weight: the
//!   two-light clutter scene's fireflies, 3× its error at equal time.)
//!
//! - `ris_initial` (W × H × R invocations; R / K with picks, below): each of a pixel's R reservoirs
//!   streams M candidates v_i ~ p (the gather's source mixture, `draw_vpl`, exact p_v, points r·M + i of the pixel's
//!   stratified set) with weights w_i = p̂(v_i) / p(v_i), where the target p̂(v) is the luminance of the
//!   unshadowed contribution at the pixel (flux, both cosines, 1/d², albedo: `vpl_unshadowed`). It keeps
//!   y with probability w_y / Σw and sets W = Σw / (M p̂(y)), the unbiased contribution weight, with
//!   confidence c = M. With a history (temporal reuse), it then combines that reservoir with last frame's
//!   final one at the same pixel and layer, whose confidence is capped at `history_cap` · M.
//! - **Picks** (`--picks K`, `RisPush::picks`): an invocation streams one candidate set into K
//!   reservoirs at once (layers s·K + j, R = S·K layers for S candidate sets, `ris_initial` then runs
//!   W × H × S invocations), each keeping its own y_j; they share Σw (so W_j = Σw / (M p̂(y_j))) and
//!   U_g. Pick j decides with pick 0's uniform rotated by j/K, which for each pick alone is uniform and
//!   independent across candidates, so each pick is, on its own, exactly the reservoir above: each is
//!   unbiased, and so is their mean. Jointly the rotation keeps two picks off one candidate unless its
//!   running share w/Σw exceeds 1/K (a repeated pick traces the same shadow ray again). Why: once the
//!   candidates are good, most of a frame's error is the choice among them and its visibility
//!   (measured: 128 → 1024 candidates cut box-on-floor's error per frame by a quarter, 2 → 4
//!   reservoirs by half), and a pick costs a random number per candidate and a shadow ray, not M
//!   candidates.
//! - `ris_spatial` (P passes of W × H × R): each reservoir is combined with those of up to k neighbours
//!   of the same layer within `radius` pixels, picked by a hash of (pixel, seed, pass, layer) and kept
//!   only if their normal and eye distance are close (a deterministic function of the two G-buffer
//!   texels), by pairwise MIS weights (each neighbour paired with the pixel's own reservoir: 3k + 1
//!   target evaluations instead of the generalized balance weights' (k + 1)²; the spatial pass 20 %
//!   cheaper in the two rooms at 128², 9.9 against 12.4 ms, the same error; BENCHMARKS.md).
//! - `ris_shade` (W × H): L(x) = 1/R Σ_r f(y_r) V(y_r) W_r, f the unshadowed RGB contribution and V the
//!   gather's visibility (`contribution()`: voxel march or exact shadow rays). Exact rays go
//!   through the gather's queue (`glsl/shared/shadow_queue.glsl`): a block's rays are traced back to
//!   back first, then its reservoirs are shaded in order with their answers (the same image). The
//!   image's alpha is the estimate's variance from its R reservoirs' own estimates (of the luminance of
//!   the albedo-demodulated indirect light, Σ_r (l_r − l̄)² / (R (R − 1))): the denoiser's noise scale.
//! - With `--control-variate on` (the default; with M > 1 or reuse) each reservoir's
//!   term is f(y) V(y) W + β (U_g − g(y) W), the **unshadowed control variate**. g = f · s for a guess s
//!   at visibility fixed before the frame, U_g = 1/M Σ_i g(v_i) / p(v_i) over the reservoir's own
//!   candidates (the initial stage sums it as it streams them, into `ris.unshadowed`). Given the
//!   candidates, the kept y is v_i with probability w_i / Σw and W = Σw / (M p̂(y)), so
//!   E[g(y) W | candidates] = 1/M Σ_i w_i g(v_i) / p̂(v_i) = U_g: the added term has mean 0 for any β
//!   and s that do not depend on this reservoir's choice, and the estimate stays unbiased. What it buys:
//!   where the kept VPL is visible and s = 1 the term is (1 − β) f W + β U_g, so with β near 1 the
//!   colour and spread of all M candidates replace one VPL's (the Cornell box's red and green walls
//!   seen from the white one were most of its error); only occluded choices add the selection's noise.
//!   Without the learned visibility s = 1 and β = visible / (traced + 1) counts the pixel's earlier
//!   shadow rays (`ris.cv`, kept across the frames of one view; earlier candidate sets of the same
//!   frame count too, being independent of this one's choice given the pool, but not this set's other
//!   picks, whose choices depend on this one's): 0 until one got through, so a
//!   pixel no ray reaches stays exactly black. With it, β = 1 and s(v) = visible / (traced + 1) of the
//!   pixel's screen tile and the VPL's light-map cell, the counts the target already read: U_g is then
//!   the estimate with the learned visibility in place of the real one, and the shadow ray only
//!   corrects it. The term is computed as g(y) W = (f / luminance(f))(y) · p̂(y) W · s(y) / (p̂ /
//!   luminance(f))(y), the last ratio carried with the reservoir. With one candidate it is 0 outright.
//!   **With spatial reuse** the identity is the last spatial pass's: given its inputs (y_i, W_i), the
//!   kept y is y_i with probability w_i / Σw and W = Σw / p̂(y), so E[g(y) W | inputs] = Σ_i m_i(y_i)
//!   g(y_i) W_i =: U_g, which that pass writes (`RIS_CONTROL_REUSE`); β as above. Where the kept VPL is
//!   visible the estimate is then the inputs' unshadowed mean: the colour of several well-chosen VPLs
//!   instead of one's.
//!
//! **Why this is unbiased with respect to `all`.** A combination of reservoirs (y_i, W_i, c_i), each with
//! E[g(y_i) W_i] = Σ_v g(v) for every g vanishing outside {p̂_i > 0} (its target p̂_i, i.e. the pixel it
//! was made at), picks y_i with probability ∝ w_i = m_i(y_i) p̂_x(y_i) W_i and sets W = Σ w / p̂_x(y), so
//! E[g(y) W | inputs] = Σ_i m_i(y_i) g(y_i) W_i and, by linearity alone (the inputs may be correlated:
//! neighbours share histories), E[g(y) W] = Σ_v g(v) Σ_i m_i(v). The weights, the generalized balance
//! weights m_i(v) = c_i p̂_i(v) / Σ_j c_j p̂_j(v) (temporal) or their pairwise form with the pixel's own
//! reservoir as input 0, m_i = (c_i / S) p̂_i / (p̂_i + a p̂_0) and m_0 = Σ_i (c_i / S) a p̂_0 / (p̂_i +
//! a p̂_0), S = Σ_{i ≥ 1} c_i, a = c_0 / S (spatial), are deterministic given the neighbour choice
//! (confidences count candidates, never samples) and sum to 1 wherever p̂_x(v) = p̂_0(v) > 0 (the
//! pixel's own reservoir is an input); an input is only weighted where its own p̂_i > 0, which its
//! sample covers. So W is an
//! unbiased contribution weight for the target support {p̂_x > 0} ⊇ {f_x ≠ 0}, and because the target
//! has no visibility, the visibility tested at the receiving pixel in the shade is just part of the
//! integrand: E[f(y) V(y) W] = Σ_v f(v) V(v), the `all` sum. (A target with visibility would need it
//! re-evaluated at the receiving pixel for every neighbour sample; the unshadowed one needs no ray.)
//! The source needs p_v > 0 wherever p̂ > 0: the defensive share ε > 0 of the CDF sources, or `uniform`.
//! The temporal input is last frame's final reservoir at the pixel's previous pixel q (`passes/
//! reproject.rs`; the pixel itself for an unchanged view), weighted with p̂_1 evaluated at last frame's
//! surface at q (kept by reproject) with last frame's VPL maps ([`LastFrame`]), the target the history
//! was made for. A VPL is a light-map texel: when a light moves, the history's VPL is re-evaluated where
//! it now is in p̂_x, while p̂_1 keeps where it was, so m_1 vanishes exactly where the history could not
//! hold a VPL (a texel empty last frame) and the weights sum to 1 everywhere else: the reuse stays
//! unbiased under moving lights. (With this frame's maps in p̂_1, as first built, a VPL that moved
//! towards the pixel was weighed as if drawn for its new place: fireflies, and a darkening where a map's
//! silhouette swept; BENCHMARKS.md, "Real time under motion".)
//!
//! Loop bounds: the initial stage's candidates are split over dispatches ([`candidates_per_dispatch`]),
//! its streaming state (y, Σw, p̂(y)) carried in the output; the shade's reservoirs too (the gather's
//! `vpls_per_dispatch`); a spatial pass loops over at most 3k + 1 target evaluations, k ≤
//! `RIS_MAX_NEIGHBORS`. Reservoirs: one `Reservoir` (16 bytes) per pixel and layer, the final ones in a
//! history buffer (this frame's and last frame's version), the spatial passes ping-ponging with a
//! transient one.

use super::dprsm::DprsmOut;
use super::gather::{GatherInputs, VisibilityVariants};
use super::reproject::Motion;
use super::FrameInputs;
use crate::bindings::*;
use crate::frame::Visibility;
use crate::graph::{Graph, Handle, History, PassBuilder, PassContext};
use crate::pipelines::Lazy;
use crate::shader_types::{GatherPush, Reservoir, RisPush, RisPushBlock};
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{vk, Binding, Buffer, BufferDesc, ComputePipeline, DescriptorWrites, Gpu, Image, Sampler};

/// Specialisations of the initial stage: picks K (1 ..= `RIS_MAX_PICKS`) × near window × its windows
/// (one light's, or every light's) × the uniform source's shortcut ([`Ris::initial_spec`]).
const INITIAL_SLOTS: usize = RIS_MAX_PICKS as usize * 8;

pub struct Ris {
    /// The pool's presampling (`--pool-tiles` > 0): any source, or (slot 1) the uniform source with
    /// faces by Russian roulette, whose mixture is one CDF.
    presample: Lazy<2>,
    /// The initial stage: drawing its own candidates (`--pool-tiles 0`), from the pool, and from the pool
    /// with the learned visibility in the target (`--learn-visibility`); the variants that bind
    /// something of their own. Each is specialised to the frame's picks, near window and source.
    initial: [Lazy<INITIAL_SLOTS>; 3],
    /// Last frame's reservoirs combined in, while they are kept (`--temporal-cap` > 0).
    temporal: Lazy<1>,
    spatial: Lazy<1>,
    /// The shade in the gather's per-pixel visibility variants (voxel, exact).
    shade: VisibilityVariants,
    sampler: Sampler,
}

/// The shade's inputs and outputs: the final reservoirs and their U_g; the counts it adds to (learned
/// visibility, control variate, rays); the radiance it writes.
struct ShadeIo<'h> {
    reservoirs: Handle<Buffer>,
    unshadowed: Handle<Buffer>,
    vis: &'h mut Handle<Buffer>,
    cv: &'h mut Handle<Buffer>,
    rays: &'h mut Handle<Buffer>,
    out: &'h mut Handle<Image>,
}

/// What a ris frame does besides the gather's sampling fields.
#[derive(Clone, Copy, Debug)]
pub struct RisFrame {
    /// The stages' push constants (`pass` and `history` are set per stage).
    pub push: RisPush,
    /// Spatial passes P.
    pub spatial_passes: u32,
    /// Candidates one initial dispatch may stream per reservoir under the loop limit.
    pub candidates_per_dispatch: u32,
    /// The source is `uniform`: its mixture is the validity CDF alone, which the pool draws from directly.
    pub uniform_source: bool,
    /// What the history depends on (camera, CDF, every setting but the seed): reservoirs are carried to
    /// the next frame only while it is unchanged.
    pub key: u64,
}

/// `--learn-visibility auto` turns the learned visibility on (at this floor) for a view where visibility
/// blocks at least [`AUTO_LEARN_BLOCKED`] of the unshadowed transport ([`blocked_share`]). For a real-time
/// frame over the generated dark rooms 0.05 read level and 0.2 1.08× the error (BENCHMARKS.md, "Real time
/// under motion").
pub const AUTO_LEARN_FLOOR: f32 = 0.1;
/// The blocked share from which `auto` learns (and `render --time-limit` gives a frame its blocked
/// budget, `cli::RIS_FRAME_BLOCKED`). Measured with the control variate (BENCHMARKS.md, "ris: the
/// unshadowed control variate"): 0.99 in the two rooms and 0.52 in the doorway, where learning cut the
/// error 1.3–2.2× at equal time; 0.08–0.29 on the Cornell box, box-on-floor, clutter, Sibenik and
/// Conference, where it cost 1.1–1.4×. The threshold sits between the two groups.
pub const AUTO_LEARN_BLOCKED: f32 = 0.4;

/// The share 1 − T/U of the unshadowed one-bounce transport into the view that visibility blocks,
/// estimated on the CPU from the scene's BVH: U sums, over pairs of an 8 × 8 grid of pixel points x (the
/// camera rays' first hits) and 64 points y per light (the first hits of a spherical Fibonacci set of
/// directions: each stands for the VPLs of an equal solid angle, whose flux is the light's intensity
/// times it), the point-to-point transport I_l · cos θ_x · cos θ_y / max(d², (diag/100)²); T sums the
/// same over the pairs that see each other. None when nothing is lit in view (U = 0). Near 1 where most
/// VPLs the unshadowed target favours are hidden (the light in the next room), which is where ris's
/// learned visibility pays for its counting. Deterministic: the same view gives the same share.
pub fn blocked_share(
    bvh: crate::bvh::query::BvhView,
    camera: &crate::camera::Camera,
    lights: &[crate::shader_types::Light],
    (width, height): (u32, u32),
    diagonal: f32,
) -> Option<f32> {
    use glam::Vec3;
    let normal = |k: usize, towards: Vec3| {
        let t = &bvh.tris[k];
        let n = (Vec3::from(t.v1) - Vec3::from(t.v0)).cross(Vec3::from(t.v2) - Vec3::from(t.v0)).normalize_or_zero();
        if n.dot(towards) < 0.0 {
            -n
        } else {
            n
        }
    };
    let lift = diagonal * 1e-4;
    let hit = |o: Vec3, d: Vec3| {
        bvh.closest(o, d, 0.0, f32::INFINITY).map(|(t, k)| {
            let n = normal(k, -d);
            (o + d * t + n * lift, n)
        })
    };
    const SIDE: u32 = 8;
    let pixels: Vec<(Vec3, Vec3)> = (0..SIDE * SIDE)
        .filter_map(|k| {
            let (i, j) = ((k % SIDE) as f32 + 0.5, (k / SIDE) as f32 + 0.5);
            let d = camera.ray_dir_f(i * width as f32 / SIDE as f32, j * height as f32 / SIDE as f32, width, height);
            hit(camera.eye, d)
        })
        .collect();
    const PER_LIGHT: u32 = 64;
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let mut lit: Vec<(Vec3, Vec3, f32)> = Vec::new();
    for l in lights {
        let p = Vec3::from_slice(&l.position[..3]);
        let weights =
            Vec3::new(crate::bindings::LUMINANCE_R, crate::bindings::LUMINANCE_G, crate::bindings::LUMINANCE_B);
        let flux = Vec3::from_slice(&l.intensity[..3]).dot(weights);
        for k in 0..PER_LIGHT {
            let z = 1.0 - 2.0 * (k as f32 + 0.5) / PER_LIGHT as f32;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let a = golden * k as f32;
            if let Some((y, n)) = hit(p, Vec3::new(r * a.cos(), r * a.sin(), z)) {
                lit.push((y, n, flux));
            }
        }
    }
    let min_d2 = (diagonal / 100.0).powi(2);
    let (mut unshadowed, mut visible) = (0.0f64, 0.0f64);
    for &(x, nx) in &pixels {
        for &(y, ny, flux) in &lit {
            let d = y - x;
            let d2 = d.length_squared();
            let g = flux * nx.dot(d).max(0.0) * ny.dot(-d).max(0.0) / (d2 * d2.max(min_d2));
            if !(g > 0.0 && g.is_finite()) {
                continue;
            }
            unshadowed += g as f64;
            if !bvh.occluded(x, y, 1e-4) {
                visible += g as f64;
            }
        }
    }
    (unshadowed > 0.0).then(|| (1.0 - visible / unshadowed) as f32)
}

/// The learned visibility's screen tiles, pixels per side: at least `tile` (0: 16), and at most 64 tiles
/// a side. Larger tiles learn from more rays per count, smaller ones follow visibility more closely.
pub fn vis_tile(width: u32, height: u32, tile: u32) -> u32 {
    width.max(height).div_ceil(64).max(if tile > 0 { tile } else { 16 })
}

/// `--learn-visibility auto`'s tile for a view whose estimated blocked share is `blocked`: 8 px where
/// about half the transport gets through, growing as 1 / √(unblocked share) to 32 px. A count's
/// relative error goes as 1 / √(visible rays), and the rays that get through fall with the unblocked
/// share, so the fewer get through, the more pixels a count must pool. Measured at 128², equal time
/// (BENCHMARKS.md, "ris: several picks per reservoir"): the doorway (0.52) 8 against 16 px, 1.08× lower
/// error; the two rooms (0.99) 32 against 16 px, 1.07× lower, and 8 px 1.27× higher.
pub fn auto_vis_tile(blocked: f32) -> u32 {
    (8.0 * (0.5 / (1.0 - blocked).max(1e-3)).sqrt()).round().clamp(8.0, 32.0) as u32
}

/// The learned visibility's light-map cells, texels per side: at least 4, and at most 16 cells a side.
pub fn vis_cell(res: u32) -> u32 {
    res.div_ceil(16).max(4)
}

/// Bytes of the learned visibility's counts: two per (screen tile, light-map cell).
pub fn vis_bytes(width: u32, height: u32, tile: u32, res: u32, faces: u32) -> u64 {
    let (t, c) = (tile, vis_cell(res));
    let tiles = width.div_ceil(t) as u64 * height.div_ceil(t) as u64;
    8 * tiles * faces as u64 * (res.div_ceil(c) as u64).pow(2)
}

/// Candidates per initial dispatch under a loop iteration `limit`: per candidate `draw_vpl`'s loops (two
/// binary searches, ≤ 32 each, the sections 3 · `sections`, the faces
/// 2 · `faces` · (`sections` + 1)), or none for a candidate from the pool (`pool`), and 64 for the rest;
/// 128 kept for the code outside the loop.
pub fn candidates_per_dispatch(limit: Option<u32>, sections: u32, faces: u32, pool: bool) -> u32 {
    let Some(limit) = limit else { return u32::MAX };
    let draw = if pool { 0 } else { 2 * 32 + 3 * (sections + 1) + 2 * faces * (sections + 2) };
    (limit.saturating_sub(128) / (64 + draw)).max(1)
}

/// What the temporal stage reads of last frame besides its reservoirs.
#[derive(Clone, Copy, Debug)]
pub struct LastFrame {
    /// Where each pixel's surface was, and that surface.
    pub motion: Motion,
    /// Last frame's VPL maps (this frame's when no light moved): the history's target.
    pub vpls: DprsmOut,
}

impl Ris {
    pub fn new(gpu: &Gpu) -> Result<Self> {
        use shaders::*;
        let base = super::gather::sampling_bindings;
        let push = std::mem::size_of::<RisPushBlock>() as u32;
        let with = |extra: &[Binding]| {
            let mut b = base();
            b.extend_from_slice(extra);
            b
        };
        let initial = with(&[Binding::storage_buffer(B_RIS_OUT), Binding::storage_buffer(B_RIS_UNSHADOWED)]);
        let temporal = with(&[
            Binding::storage_buffer(B_RIS_OUT),
            Binding::storage_buffer(B_RIS_HISTORY),
            Binding::sampled_image(B_MOTION),
            Binding::sampled_image(B_PREV_POSITION),
            Binding::sampled_image(B_PREV_SURFACE),
            Binding::sampled_image(B_PREV_VPL_POSITION),
            Binding::sampled_image(B_PREV_VPL_NORMAL),
            Binding::sampled_image(B_PREV_VPL_FLUX),
            Binding::uniform_texel_buffer(B_RIS_VIS),
        ]);
        let mut pooled = initial.clone();
        pooled.push(Binding::uniform_texel_buffer(B_RIS_POOL));
        let mut learned = pooled.clone();
        learned.push(Binding::uniform_texel_buffer(B_RIS_VIS));
        let spatial = with(&[
            Binding::storage_buffer(B_RIS_IN),
            Binding::storage_buffer(B_RIS_OUT),
            Binding::storage_buffer(B_RIS_UNSHADOWED),
            Binding::uniform_texel_buffer(B_RIS_VIS),
        ]);
        let mut shade = base();
        shade.extend([B_RIS_IN, B_RIS_VIS, B_RIS_UNSHADOWED, B_RIS_CV, B_RIS_RAYS].map(Binding::storage_buffer));
        shade.extend([Binding::sampled_image(B_GATHER_DIRECT), Binding::storage_image(B_GATHER_OUT)]);
        Ok(Ris {
            presample: Lazy::new(
                gpu,
                "ris_presample",
                RIS_PRESAMPLE_COMP,
                &with(&[Binding::storage_buffer(B_RIS_POOL)]),
                push,
            ),
            initial: [
                Lazy::new(gpu, "ris_initial", RIS_INITIAL_COMP, &initial, push),
                Lazy::new(gpu, "ris_initial", RIS_INITIAL_POOL_COMP, &pooled, push),
                Lazy::new(gpu, "ris_initial", RIS_INITIAL_POOL_LEARNED_COMP, &learned, push),
            ],
            temporal: Lazy::new(gpu, "ris_temporal", RIS_TEMPORAL_COMP, &temporal, push),
            spatial: Lazy::new(gpu, "ris_spatial", RIS_SPATIAL_COMP, &spatial, push),
            shade: VisibilityVariants::new(gpu, "ris_shade", [RIS_SHADE_COMP, RIS_SHADE_EXACT_COMP], shade, push),
            sampler: Sampler::nearest(gpu)?,
        })
    }

    /// Bytes of one layer of reservoirs for a `w` × `h` image.
    pub fn layer_bytes(w: u32, h: u32) -> u64 {
        w as u64 * h as u64 * std::mem::size_of::<Reservoir>() as u64
    }

    /// Record a ris frame into `out` (overwritten; the direct image added when `push.add_direct`):
    /// initial (+ temporal, with `last`), `spatial_passes` spatial passes, shade. `push` holds the
    /// gather's sampling fields (`samples` = R). Returns the shade's shadow-ray count (one uint).
    #[allow(clippy::too_many_arguments)]
    pub fn add<'a>(
        &'a self,
        g: &mut Graph<'a>,
        f: FrameInputs<'a>,
        i: &GatherInputs,
        out: &mut Handle<Image>,
        push: GatherPush,
        r: RisFrame,
        last: Option<LastFrame>,
    ) -> Result<Handle<Buffer>> {
        let reservoirs = r.push.reservoirs;
        let desc = |name: &str| BufferDesc::storage(name, Self::layer_bytes(f.width, f.height) * reservoirs as u64);
        // Frames with temporal reuse (realtime) keep their reservoirs as a history; the others (progressive
        // ris) keep none and use names of their own for what they keep across frames, so that the viewer's
        // still frames and its moving ones never remake each other's state.
        let temporal = r.push.history_cap > 0.0;
        let kept = |what: &str| if temporal { what.to_string() } else { format!("{what} (progressive)") };
        let history = match temporal {
            true => g.history_buffer("ris.reservoirs", desc("ris.reservoirs"), &r.key),
            false => History { current: g.create_buffer(desc("ris.reservoirs")), previous: None },
        };
        // The last use's reservoirs, with where each pixel was (and that frame's surface), when both were kept.
        let previous = match (history.previous, last) {
            (Some(p), Some(l)) if l.motion.history => Some((p, l)),
            _ => None,
        };
        // Stage s (0: initial, 1..=P: spatial) writes the history's current buffer when P − s is even, so
        // the last stage's reservoirs are the ones kept for the next frame.
        let mut current = history.current;
        let mut scratch = (r.spatial_passes > 0).then(|| g.create_buffer(desc("ris.scratch")));
        let target = |s: u32| (r.spatial_passes - s).is_multiple_of(2);
        let pool =
            (r.push.pool_tiles > 0).then(|| self.add_presample(g, f, i, push, r.push, r.uniform_source)).transpose()?;
        let mut vis = Self::learned_counts(g, f, &r, &kept("ris.visibility"));
        // The control variate's U_g per reservoir (this frame's), and its per-pixel shadow-ray counts, kept
        // across the frames of one view like the learned visibility (stand-ins, never touched, when off).
        let mut unshadowed = if r.push.control != 0 {
            g.create_buffer(desc("ris.unshadowed"))
        } else {
            g.create_buffer(BufferDesc::storage("ris.unshadowed (off)", 16))
        };
        let mut cv = if r.push.control != 0 {
            let t = g.temporal_buffer(
                &kept("ris.cv"),
                BufferDesc::storage("ris.cv", 16 * f.width as u64 * f.height as u64),
                &r.key,
            );
            let mut h = t.handle;
            if t.fresh {
                g.add_clear("ris_cv_clear", &mut [&mut h]);
            }
            h
        } else {
            g.create_buffer(BufferDesc::storage("ris.cv (off)", 16))
        };
        {
            let dst = if target(0) { &mut current } else { scratch.as_mut().expect("P > 0") };
            let learned = (r.push.learned > 0.0).then_some(vis);
            self.add_initial(g, f, i, dst, &mut unshadowed, pool, learned, push, r)?;
            if let Some((previous, last)) = previous {
                self.add_temporal(g, f, i, (previous, last, vis), dst, push, r.push)?;
            }
        }
        for pass in 0..r.spatial_passes {
            let s = pass + 1;
            let (src, dst) = match (target(s), scratch.as_mut()) {
                (true, Some(t)) => (*t, &mut current),
                (false, Some(t)) => (current, t),
                (_, None) => unreachable!("spatial passes have a scratch buffer"),
            };
            // Only the last pass's inputs are the final choice's: it alone writes U_g (RIS_CONTROL_REUSE).
            let control = if s == r.spatial_passes { r.push.control } else { RIS_CONTROL_OFF };
            self.add_spatial(g, f, i, (src, vis), dst, &mut unshadowed, push, RisPush { pass, control, ..r.push })?;
        }
        // The frame's shadow rays, counted by the shade.
        let mut rays = g.create_buffer(BufferDesc::storage("ris.rays", 4));
        g.add_clear("ris_rays_clear", &mut [&mut rays]);
        let shade = ShadeIo { reservoirs: current, unshadowed, vis: &mut vis, cv: &mut cv, rays: &mut rays, out };
        self.add_shade(g, f, i, shade, push, r.push)?;
        Ok(rays)
    }

    /// The learned visibility's counts: kept across the frames of one view (the history's key; realtime's
    /// across moves), zeroed when new; off, a stand-in that the shade never writes and the reuse stages,
    /// which bind it as a texel buffer either way, never read.
    fn learned_counts<'a>(g: &mut Graph<'a>, f: FrameInputs<'a>, r: &RisFrame, name: &str) -> Handle<Buffer> {
        if r.push.learned > 0.0 {
            let faces = f.vpl_faces * f.scene.light_count;
            let bytes = vis_bytes(f.width, f.height, r.push.vis_tile, f.dprsm_res, faces);
            let mut desc = BufferDesc::storage("ris.visibility", bytes);
            desc.usage |= vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
            let t = g.temporal_buffer(name, desc, &r.key);
            let mut h = t.handle;
            if t.fresh {
                g.add_clear("ris_visibility_clear", &mut [&mut h]);
            }
            h
        } else {
            // The reuse stages bind it as a texel buffer either way (and read it only when on).
            let mut desc = BufferDesc::storage("ris.visibility (off)", 16);
            desc.usage |= vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
            g.create_buffer(desc)
        }
    }

    /// The descriptor writes every stage shares: scene, G-buffer, VPLs, voxels, importance, CDF.
    fn base_writes(&self, f: FrameInputs, ctx: &PassContext, i: &GatherInputs) -> DescriptorWrites {
        i.sampling_writes(&f, ctx, self.sampler.raw)
    }

    /// The initial stage's pipeline for a frame of `push` (`multi`: more than one light), built on first
    /// use: the variant by what it binds (its own candidates, the pool, the pool and the learned
    /// visibility), specialised to the picks and, with the near window, to its windows and the source.
    fn initial_pipeline(&self, push: &RisPush, uniform_source: bool, multi: bool) -> Result<&ComputePipeline> {
        let variant = match (push.pool_tiles > 0, push.learned > 0.0) {
            (false, _) => 0,
            (true, false) => 1,
            (true, true) => 2,
        };
        let (slot, spec) = Self::initial_spec(push, uniform_source, multi);
        self.initial[variant].get(slot, &spec)
    }

    /// The initial stage's specialisation slot and constants: K picks, and with the near window (which
    /// needs the pool) whether it has every light's windows and the uniform source's shortcut (both
    /// matter only there).
    fn initial_spec(push: &RisPush, uniform_source: bool, multi: bool) -> (usize, [(u32, u32); 4]) {
        let near = push.pool_tiles > 0 && push.near_candidates > 0;
        let (multi, uniform) = (near && multi, near && uniform_source);
        let slot = (push.picks as usize - 1) * 8 + near as usize * 4 + multi as usize * 2 + uniform as usize;
        let lights = if multi { RIS_NEAR_LIGHTS } else { 1 };
        let spec = [
            (SPEC_RIS_PICKS, push.picks),
            (SPEC_RIS_NEAR, near as u32),
            (SPEC_RIS_NEAR_LIGHTS, lights),
            (SPEC_RIS_UNIFORM_SOURCE, uniform as u32),
        ];
        (slot, spec)
    }

    /// The presampling's pipeline (slot 1: the uniform source's shortcut).
    fn presample_pipeline(&self, uniform_source: bool) -> Result<&ComputePipeline> {
        self.presample.get(uniform_source as usize, &[(SPEC_RIS_UNIFORM_SOURCE, uniform_source as u32)])
    }

    /// Builds the pipelines a frame of `push` will use, so that a timed run does not pay for them in its
    /// first frame.
    pub fn prepare(&self, push: &RisPush, uniform_source: bool, multi: bool) -> Result<()> {
        self.initial_pipeline(push, uniform_source, multi)?;
        if push.pool_tiles > 0 {
            self.presample_pipeline(uniform_source)?;
        }
        Ok(())
    }

    /// Declare the reads every stage shares.
    fn reads<'g, 'a>(mut b: PassBuilder<'g, 'a>, i: &GatherInputs) -> PassBuilder<'g, 'a> {
        for h in [i.g_position, i.g_normal, i.g_albedo, i.vpl_position, i.vpl_normal, i.vpl_flux] {
            b = b.read(&h, Access::ComputeRead);
        }
        for h in i.buffers() {
            b = b.read(&h, Access::ComputeRead);
        }
        b
    }

    /// The candidate pool: `pool_tiles` tiles of `RIS_POOL_TILE` draws of the source with their VPLs'
    /// data and probabilities, three `uvec4` texels each (written as a storage buffer, read through its
    /// texel view).
    fn add_presample<'a>(
        &'a self,
        g: &mut Graph<'a>,
        f: FrameInputs<'a>,
        i: &GatherInputs,
        push: GatherPush,
        ris: RisPush,
        uniform_source: bool,
    ) -> Result<Handle<Buffer>> {
        let i = *i;
        let pipeline = self.presample_pipeline(uniform_source)?;
        let mut desc = BufferDesc::storage("ris.pool", 48 * RIS_POOL_TILE as u64 * ris.pool_tiles as u64);
        desc.usage |= vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
        let mut pool = g.create_buffer(desc);
        let o = pool;
        Self::reads(g.add_pass("ris_presample"), &i).overwrite(&mut pool, Access::ComputeWrite).record(move |ctx| {
            let writes = self.base_writes(f, ctx, &i).storage_buffer(B_RIS_POOL, ctx.buffer(&o));
            let block = RisPushBlock { gather: push, ris };
            let size = [RIS_POOL_TILE, ris.pool_tiles, 1];
            pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&block), size, [WG_2D, WG_2D, 1]);
        });
        Ok(pool)
    }

    #[allow(clippy::too_many_arguments)]
    fn add_initial<'a>(
        &'a self,
        g: &mut Graph<'a>,
        f: FrameInputs<'a>,
        i: &GatherInputs,
        dst: &mut Handle<Buffer>,
        unshadowed: &mut Handle<Buffer>,
        pool: Option<Handle<Buffer>>,
        learned: Option<Handle<Buffer>>,
        push: GatherPush,
        r: RisFrame,
    ) -> Result<()> {
        let (i, o, u) = (*i, *dst, *unshadowed);
        // The variant, specialised to the frame's picks (built here on first use, so a failure is an error
        // of this frame, not of the recorded pass).
        let pipeline = self.initial_pipeline(&r.push, r.uniform_source, f.scene.light_count > 1)?;
        let mut b = Self::reads(g.add_pass("ris_initial"), &i);
        for p in pool.iter().chain(learned.iter()) {
            b = b.read(p, Access::ComputeRead);
        }
        b = b.overwrite(unshadowed, Access::ComputeWrite);
        b.overwrite(dst, Access::ComputeWrite).record(move |ctx| {
            let writes = self
                .base_writes(f, ctx, &i)
                .storage_buffer(B_RIS_OUT, ctx.buffer(&o))
                .storage_buffer(B_RIS_UNSHADOWED, ctx.buffer(&u));
            let writes = match (&pool, &learned) {
                (Some(p), Some(v)) => {
                    writes.texel_view4(B_RIS_POOL, ctx.buffer(p)).texel_view(B_RIS_VIS, ctx.buffer(v))
                }
                (Some(p), None) => writes.texel_view4(B_RIS_POOL, ctx.buffer(p)),
                (None, _) => writes,
            };
            for (first, last) in super::dispatch_ranges(0, r.push.candidates, r.candidates_per_dispatch) {
                if first > 0 {
                    // The next candidates continue the reservoirs (and sums) the previous dispatch stored.
                    ctx.serialize(&o);
                    ctx.serialize(&u);
                }
                let block = RisPushBlock { gather: GatherPush { first, last, ..push }, ris: r.push };
                let size = [f.width, f.height, r.push.reservoirs / r.push.picks];
                pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&block), size, [WG_2D, WG_2D, 1]);
            }
        });
        Ok(())
    }

    /// Last frame's final reservoirs (`previous`) combined into this frame's initial ones (`dst`), layer by
    /// layer.
    #[allow(clippy::too_many_arguments)]
    fn add_temporal<'a>(
        &'a self,
        g: &mut Graph<'a>,
        f: FrameInputs<'a>,
        i: &GatherInputs,
        (previous, LastFrame { motion: m, vpls }, vis): (Handle<Buffer>, LastFrame, Handle<Buffer>),
        dst: &mut Handle<Buffer>,
        push: GatherPush,
        ris: RisPush,
    ) -> Result<()> {
        let (i, o) = (*i, *dst);
        let pipeline = self.temporal.pipeline()?;
        let mut b = Self::reads(g.add_pass("ris_temporal"), &i).read(&previous, Access::ComputeRead);
        b = b.read(&vis, Access::ComputeRead);
        for h in [m.motion, m.prev_position, m.prev_surface, vpls.position, vpls.normal, vpls.flux] {
            b = b.read(&h, Access::ComputeRead);
        }
        b.write(dst, Access::ComputeWrite).record(move |ctx| {
            let s = self.sampler.raw;
            let writes = self
                .base_writes(f, ctx, &i)
                .storage_buffer(B_RIS_OUT, ctx.buffer(&o))
                .storage_buffer(B_RIS_HISTORY, ctx.buffer(&previous))
                .sampled_image(B_MOTION, ctx.image(&m.motion), s)
                .sampled_image(B_PREV_POSITION, ctx.image(&m.prev_position), s)
                .sampled_image(B_PREV_SURFACE, ctx.image(&m.prev_surface), s)
                .sampled_image(B_PREV_VPL_POSITION, ctx.image(&vpls.position), s)
                .sampled_image(B_PREV_VPL_NORMAL, ctx.image(&vpls.normal), s)
                .sampled_image(B_PREV_VPL_FLUX, ctx.image(&vpls.flux), s)
                .texel_view(B_RIS_VIS, ctx.buffer(&vis));
            let block = RisPushBlock { gather: push, ris };
            let size = [f.width, f.height, ris.reservoirs];
            pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&block), size, [WG_2D, WG_2D, 1]);
        });
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn add_spatial<'a>(
        &'a self,
        g: &mut Graph<'a>,
        f: FrameInputs<'a>,
        i: &GatherInputs,
        (src, vis): (Handle<Buffer>, Handle<Buffer>),
        dst: &mut Handle<Buffer>,
        unshadowed: &mut Handle<Buffer>,
        push: GatherPush,
        ris: RisPush,
    ) -> Result<()> {
        let (i, o, u) = (*i, *dst, *unshadowed);
        let pipeline = self.spatial.pipeline()?;
        let b =
            Self::reads(g.add_pass("ris_spatial"), &i).read(&src, Access::ComputeRead).read(&vis, Access::ComputeRead);
        // U_g is written by the last pass only (declared by each: the stand-in or the buffer).
        let b = b.write(unshadowed, Access::ComputeWrite);
        b.overwrite(dst, Access::ComputeWrite).record(move |ctx| {
            let writes = self
                .base_writes(f, ctx, &i)
                .storage_buffer(B_RIS_IN, ctx.buffer(&src))
                .storage_buffer(B_RIS_OUT, ctx.buffer(&o))
                .storage_buffer(B_RIS_UNSHADOWED, ctx.buffer(&u))
                .texel_view(B_RIS_VIS, ctx.buffer(&vis));
            let block = RisPushBlock { gather: push, ris };
            let size = [f.width, f.height, ris.reservoirs];
            pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&block), size, [WG_2D, WG_2D, 1]);
        });
        Ok(())
    }

    fn add_shade<'a>(
        &'a self,
        g: &mut Graph<'a>,
        f: FrameInputs<'a>,
        i: &GatherInputs,
        io: ShadeIo,
        push: GatherPush,
        ris: RisPush,
    ) -> Result<()> {
        let (reservoirs, unshadowed) = (io.reservoirs, io.unshadowed);
        let (i, o, hv, hc, hr) = (*i, *io.out, *io.vis, *io.cv, *io.rays);
        let pipeline = self.shade.pipeline(&f, false)?;
        let mut b = Self::reads(g.add_pass("ris_shade"), &i)
            .read(&reservoirs, Access::ComputeRead)
            .read(&unshadowed, Access::ComputeRead);
        // The learned visibility's and the control's counts are added to (or, off, the stand-ins are never
        // touched), and so is the ray count.
        b = b
            .write(io.vis, Access::ComputeWrite)
            .write(io.cv, Access::ComputeWrite)
            .write(io.rays, Access::ComputeWrite);
        if let Some(d) = &i.direct {
            b = b.read(d, Access::ComputeRead);
        }
        for h in i.end_ball_images() {
            b = b.read(&h, Access::ComputeRead);
        }
        b.overwrite(io.out, Access::ComputeWrite).record(move |ctx| {
            let direct = match (&i.direct, push.add_direct) {
                (Some(d), 1) => ctx.image(d),
                _ => ctx.image(&i.g_albedo),
            };
            let writes = self
                .base_writes(f, ctx, &i)
                .storage_buffer(B_RIS_IN, ctx.buffer(&reservoirs))
                .storage_buffer(B_RIS_VIS, ctx.buffer(&hv))
                .storage_buffer(B_RIS_UNSHADOWED, ctx.buffer(&unshadowed))
                .storage_buffer(B_RIS_CV, ctx.buffer(&hc))
                .storage_buffer(B_RIS_RAYS, ctx.buffer(&hr))
                .sampled_image(B_GATHER_DIRECT, direct, self.sampler.raw)
                .storage_image(B_GATHER_OUT, ctx.image(&o));
            // The gather's visibility variants, chosen and bound as the gather's (with the end balls where
            // the layout has them: exact).
            let (writes, end_balls) = match f.visibility {
                Visibility::Exact => super::gather::end_ball_writes(ctx, &i, writes, self.sampler.raw),
                _ => (writes, 0),
            };
            let writes = VisibilityVariants::writes(&f, writes);
            // All reservoirs of a pixel, accumulated over dispatches as the gather's samples.
            let whole = GatherPush { first: 0, last: ris.reservoirs, accumulate: 0, end_balls, ..push };
            for (first, last) in super::dispatch_ranges(0, ris.reservoirs, f.vpls_per_dispatch) {
                if first > 0 {
                    // The next reservoirs add to what the previous dispatch stored (image and counts).
                    ctx.serialize(&o);
                    ctx.serialize(&hv);
                    ctx.serialize(&hc);
                    ctx.serialize(&hr);
                }
                let block = RisPushBlock { gather: whole.chunk(first, last), ris };
                pipeline.dispatch(
                    ctx.cmd,
                    &writes,
                    bytemuck::bytes_of(&block),
                    [f.width, f.height, 1],
                    [WG_2D, WG_2D, 1],
                );
            }
        });
        Ok(())
    }
}
