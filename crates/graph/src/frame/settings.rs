//! Frame settings: what a frame computes and how (component, method, visibility, light map, sizes and
//! sampling parameters), their defaults, and their validation against the device's limits. Settings are
//! validated once, before anything is recorded; an impossible setting is a [`SettingsError`] (bad input,
//! one line naming the setting), never a failure deep in a pass.

use crate::passes::psm;
use bounce_device::Gpu;

/// A setting this device or scene cannot run: bad input, with one line that names the setting.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct SettingsError(pub String);

/// `return Err(SettingsError(format!(...)))`.
macro_rules! reject {
    ($($t:tt)*) => {
        return Err(SettingsError(format!($($t)*)))
    };
}
pub(crate) use reject;

/// Which radiance the frame computes (the scene contract's components).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Component {
    Direct,
    Indirect,
    Combined,
}

impl Component {
    pub fn name(self) -> &'static str {
        match self {
            Component::Direct => "direct",
            Component::Indirect => "indirect",
            Component::Combined => "combined",
        }
    }
}

/// How the gather picks its VPLs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// N VPLs per pixel, uniformly among the non-empty DPRSM texels.
    Uniform,
    /// Every VPL (p_v = 1): the converged VPL estimate, in tiles.
    All,
    /// Ritschel et al. 2011: a CDF from S random gather points (unshadowed).
    Global,
    /// Thesis §7.3.2: the global CDF from gather points spread over 4 screen quarters.
    Stratified,
    /// Thesis §7.3.3: one CDF per screen region; a pixel samples the CDFs of the regions around it,
    /// blended bilinearly (continuous over the screen: no seams).
    Local,
    /// Thesis §7.3.4: the gathering-based global CDF (cosine rays, per-texel averages, median holes).
    Gbg,
    /// Thesis §7.4: cosine gathering and gbg CDF sampling combined by the balance heuristic.
    Mis,
    /// The exact one-bounce integral (BVH path tracing, `spp` samples): the ground truth.
    Reference,
    /// Resampled importance sampling: `vpls` reservoirs per pixel, each keeping one of `candidates`
    /// VPLs from a source CDF by their unshadowed contribution there, with spatial and temporal reuse
    /// (`passes/ris.rs`).
    Ris,
    /// The real-time frame: ris with [`REALTIME_RESERVOIRS`] reservoirs per pixel
    /// ([`RisSettings::realtime`]), reused across frames through reprojection (`passes/reproject.rs`) and
    /// across pixels, one shadow ray each, and the denoiser for display (`passes/denoise.rs`,
    /// `FrameSettings::denoise`).
    Realtime,
}

/// Reservoirs per pixel of `Method::Realtime`, each with its own reuse chain and one shadow ray: the
/// real-time bound of two rays a pixel. Two against one (BENCHMARKS.md, "Real time under motion"): half the
/// raw error and flicker for 1.1–1.5× the frame time, 1.4–1.9× the raw efficiency in four runs of motion
/// (Sibenik and the two rooms, camera and light; measured there only).
pub const REALTIME_RESERVOIRS: u32 = 2;

/// The blocked share ([`crate::passes::ris::blocked_share`]) from which a real-time frame under
/// `--learn-visibility auto` learns. Under motion a count goes stale as its screen tile and light-map
/// cell move on, so learning pays only where visibility blocks nearly everything (measured at 64²,
/// 16 frames, light and camera orbits: learning cost 1.0–2.1× the raw error at blocked shares 0.43–0.55,
/// the doorway and the generated rooms lit from the next room, 1.2–1.3× on Sibenik at 0.16, and saved
/// 4–5× in the two rooms at 0.99 and 2.5× on the generated suite's dark rooms at 0.86–0.93; BENCHMARKS.md,
/// "Real time under motion"). The threshold sits between.
pub const REALTIME_LEARN_BLOCKED: f32 = 0.75;
/// A real-time frame's learning decision is made again every this many frames (`Renderer`).
pub const REALTIME_LEARN_EVERY: u64 = 16;
/// Once on, learning stays on until the blocked share falls this far below [`REALTIME_LEARN_BLOCKED`].
pub const REALTIME_LEARN_HYSTERESIS: f32 = 0.05;

/// The source distribution of `Method::Ris`'s candidates: one of the CDF methods' mixtures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RisSource {
    Uniform,
    Global,
    Stratified,
    Local,
    Gbg,
}

impl RisSource {
    /// The method that samples this distribution.
    pub fn method(self) -> Method {
        match self {
            RisSource::Uniform => Method::Uniform,
            RisSource::Global => Method::Global,
            RisSource::Stratified => Method::Stratified,
            RisSource::Local => Method::Local,
            RisSource::Gbg => Method::Gbg,
        }
    }
}

/// `Method::Ris`'s parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RisSettings {
    pub source: RisSource,
    /// Candidates M per reservoir.
    pub candidates: u32,
    /// Spatial reuse passes (0: none).
    pub spatial_passes: u32,
    /// Neighbours per spatial pass.
    pub spatial_neighbors: u32,
    /// Radius of the neighbourhood, pixels.
    pub spatial_radius: f32,
    /// Temporal reuse across frames of one view: the history's confidence is capped at this many times
    /// M (0: no temporal reuse).
    pub temporal_cap: f32,
    /// Candidates from a pool presampled once per frame: this many tiles of `RIS_POOL_TILE` source draws
    /// (RTXDI's light tiles), a candidate costing three texel fetches instead of a draw (0: each pixel
    /// draws its own, stratified).
    pub pool_tiles: u32,
    /// δ_L in (0, 1], or 0 for off: the target weighs a VPL by max(V̂, δ_L), V̂ the fraction of earlier
    /// frames' shadow rays from the pixel's screen tile to the VPL's light-map cell that were unoccluded
    /// (progressive frames of one view, or `Method::Realtime`'s frames; needs the pool).
    pub learn_visibility: f32,
    /// `--learn-visibility auto` (the default): with `learn_visibility` 0, the renderer turns learning on
    /// (δ_L = `passes::ris::AUTO_LEARN_FLOOR`) for a view where visibility blocks most of the unshadowed
    /// transport (`passes::ris::blocked_share` ≥ `AUTO_LEARN_BLOCKED`, estimated once per view on the
    /// CPU), when the other settings allow it (the pool, no reuse).
    pub learn_auto: bool,
    /// The learned visibility's smallest screen tile, pixels (0: 16). `auto` sets it from the view's
    /// blocked share (`passes::ris::auto_vis_tile`).
    pub learn_tile: u32,
    /// The last this many of each reservoir's M candidates come from the near window (0: none): texels of
    /// a light's map within `near_radius` of where the pixel projects into it, drawn uniformly, combined
    /// with the pool's by balance weights (multiple-importance RIS, unbiased). It proposes the VPLs next
    /// to the pixel, whose kernel makes the target's tail, which a pool of source draws almost never
    /// holds. At most M − 1 are used (the pool's candidates keep every VPL drawable). Only with the pool
    /// (off otherwise).
    pub near_candidates: u32,
    /// The near window's half-width, texels.
    pub near_radius: u32,
    /// Candidates per initial dispatch (`None`: as many as the device's loop limit allows). The image
    /// does not depend on it (the reservoirs' streaming state is carried between dispatches).
    pub candidates_chunk: Option<std::num::NonZeroU32>,
    /// The shade adds the unshadowed control variate β (U_g − g(y) W) to each reservoir's f(y) V(y) W
    /// (passes/ris.rs): the candidates' unshadowed estimate minus the kept sample's, mean 0. Where the
    /// kept VPL is visible the reservoir's estimate becomes (1 − β) f W + β U_g, the colour and spread of
    /// all M candidates instead of one's. Only without reuse (off otherwise).
    pub control_variate: bool,
    /// VPLs kept from each reservoir's M candidates (K in 1 ..= `RIS_MAX_PICKS`), each a choice of its own
    /// among the same candidates with its own shadow ray: K reservoirs for the candidates' price of
    /// one. Where a frame's error is the kept samples' own (their visibility, the choice among the
    /// candidates) rather than the candidates', K picks cut it nearly as K reservoirs would.
    pub picks: u32,
}

impl RisSettings {
    /// `Method::Realtime`'s ris: [`REALTIME_RESERVOIRS`] reservoirs of 32 candidates (8 from the near
    /// window) from the pool, last frame's reservoirs combined in through reprojection with their
    /// confidence capped at M (the history counts as much as this frame's candidates), one spatial pass
    /// of 4 neighbours within 4 pixels and the control variate over the spatial pass's inputs. The
    /// cap was chosen over four runs of motion (0 / ¼ / ½ / 1 / 2 / 8; BENCHMARKS.md, "Real time under
    /// motion"): against 8, 1 lowered the raw error in all four (0.65–0.98×) and the denoised error too
    /// (0.31–0.97×: a long history correlates the frames the denoiser's accumulation averages); below 1
    /// the raw error grew. The radius was chosen over 18 generated scenes under light and camera orbits
    /// and the four runs (2 / 4 / 8 / 16 / 32 px): 4 against 16 cut the raw error over ris at 4 from
    /// 1.60× to 1.17× (geomean; worst 3.96× to 2.53×), and 0.84–0.91× on the four runs, the denoised
    /// error level; 2 had less raw error on the suite but more on the two rooms and a worse worst case
    /// (nearby pixels' reservoirs are alike and their errors correlate: blotches the denoiser keeps).
    /// The learned visibility is `FrameSettings::ris`'s: under `auto` (the default)
    /// the renderer turns it on for a view whose blocked share is at least [`REALTIME_LEARN_BLOCKED`],
    /// every [`REALTIME_LEARN_EVERY`] frames, without dropping the history (the reuse's weights take any
    /// positive target).
    pub fn realtime() -> Self {
        RisSettings {
            temporal_cap: 1.0,
            spatial_passes: 1,
            spatial_neighbors: 4,
            spatial_radius: 4.0,
            control_variate: true,
            picks: 1,
            ..RisSettings::default()
        }
    }
}

impl Default for RisSettings {
    fn default() -> Self {
        RisSettings {
            // Measured at equal time (BENCHMARKS.md, "ris: what its settings buy"): a uniform source (a CDF
            // source adds rare heavy weights where it underrates a VPL the target favours), and no reuse
            // by default: spatial reuse cost more than it gained, and temporal reuse correlates the frames
            // a progressive render averages (3–10× the error in the two rooms).
            // A pool of 16 tiles and 32 candidates (2026-11-30): a pooled candidate costs about a tenth
            // of a drawn one, which bought 5–15× lower error at equal time on the Cornell box and the
            // two rooms.
            source: RisSource::Uniform,
            candidates: 32,
            spatial_passes: 0,
            spatial_neighbors: 4,
            spatial_radius: 16.0,
            temporal_cap: 0.0,
            pool_tiles: 16,
            learn_visibility: 0.0,
            learn_auto: true,
            learn_tile: 0,
            // 8 of 32 from a 17 × 17 window (2026-11-30, third session): 3–10× lower error at equal time
            // on Sibenik and Conference (BENCHMARKS.md, "ris: the near window").
            near_candidates: 8,
            near_radius: 8,
            candidates_chunk: None,
            control_variate: true,
            picks: 1,
        }
    }
}

/// How the VPL gather tests visibility: one value from the command line to the shaders
/// (`glsl/shared/visibility.glsl` answers "is this segment open" for each).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Visibility {
    /// Amanatides–Woo march through the voxel grid (the thesis's; 3–9 % dark on thin-walled and
    /// cluttered rooms, seams at junctions).
    Voxel,
    /// The default: shadow rays against the triangles (BVH); gbg's importance rays and mis's gathering
    /// rays hit the real surfaces, with no visibility bias. The gather's rays cost 0.4–0.8× the voxel
    /// march on lavapipe's small scenes and 1.2–1.6× on Sibenik and Conference; on an H200 0.2–0.3×,
    /// and 0.97–1.12× on the large two (BENCHMARKS.md).
    Exact,
    /// Per-VPL paraboloid shadow maps (thesis ch. 6) for a shared set of `vpls` VPLs per frame
    /// (`passes/psm.rs`).
    Psm,
}

impl Visibility {
    /// Whether the frame's shadow rays (and gbg's importance rays) go through the BVH.
    pub fn uses_bvh(self) -> bool {
        self == Visibility::Exact
    }
    /// Whether the frame gathers a shared VPL set (`Psm`).
    pub fn shared_set(self) -> bool {
        self == Visibility::Psm
    }
    /// Whether something of the frame marches the voxel grid: the voxel visibility, and `psm`'s
    /// gbg/mis gathering rays (the shared set keeps the thesis's voxel gathering).
    pub fn marches_voxels(self) -> bool {
        self != Visibility::Exact
    }
}

/// What a VPL's contribution to a point at distance d falls off with (`glsl/shared/vpl.glsl`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VplKernel {
    /// The thesis's point VPL: 1/d², unbounded next to the receiver (corners), so the VPL sum overshoots
    /// there and every sampled method's error is a few pixels' heavy tail.
    Point,
    /// The default: 1/√(d⁴ + (A_v/π)²), A_v the area of the surface patch the VPL's texel sees. Bounded
    /// next to the receiver by the patch's radiosity, the point kernel to second order where d² ≫ A_v, and
    /// converging to the same integral as the map's resolution grows (BENCHMARKS.md measures both, and the
    /// disk kernel 1/(d² + A_v/π) it was chosen over, against the exact one-bounce image).
    Patch,
}

impl VplKernel {
    /// The weight s of A_v in the kernel 1/√(d⁴ + (s·A_v)²) (`FrameUniforms::vpl[0]`; 0: 1/d²).
    pub fn area_weight(self) -> f32 {
        match self {
            VplKernel::Point => 0.0,
            VplKernel::Patch => std::f32::consts::FRAC_1_PI,
        }
    }
}

/// The VPL map at each light (thesis §6.3; `glsl/shared/lightmap.glsl`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightMap {
    /// Two paraboloid faces (the thesis's dual paraboloid RSM): every direction.
    Dprsm,
    /// One perspective face of this field of view (degrees) looking at the centre of the scene's
    /// bounds; what lies outside is never a VPL (the flux it misses is reported).
    Rsm { fov_deg: f32 },
    /// Six perspective faces of 90°: every direction, three times the texels of `Dprsm` per res².
    Cube,
}

impl LightMap {
    /// Faces per light.
    pub fn faces(self) -> u32 {
        match self {
            LightMap::Dprsm => 2,
            LightMap::Rsm { .. } => 1,
            LightMap::Cube => 6,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            LightMap::Dprsm => "dprsm",
            LightMap::Rsm { .. } => "rsm",
            LightMap::Cube => "cube",
        }
    }
    /// tan(fov/2) of a perspective face.
    pub(crate) fn tan_half_fov(self) -> f32 {
        match self {
            LightMap::Rsm { fov_deg } => (fov_deg.to_radians() / 2.0).tan(),
            _ => 1.0,
        }
    }
    /// The solid angle the faces cover around each light: 4π, or the RSM's square pyramid,
    /// 4 asin(sin²(fov/2)) (Ω of a square pyramid of half-angle α is 4 asin(sin² α)).
    pub fn solid_angle(self) -> f64 {
        match self {
            LightMap::Rsm { fov_deg } => {
                let a = (fov_deg as f64).to_radians() / 2.0;
                4.0 * (a.sin() * a.sin()).asin()
            }
            _ => 4.0 * std::f64::consts::PI,
        }
    }
}

/// Which MIS weights (`Method::Mis`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MisWeights {
    /// Both densities in solid angle: unbiased combination.
    Consistent,
    /// The thesis's literal weights (eqs. 7.10–7.11: cos θ sin θ/π against a discrete pdf).
    Thesis,
}

impl Method {
    /// Every method, in declaration order.
    pub const ALL: [Method; 10] = [
        Method::Uniform,
        Method::All,
        Method::Global,
        Method::Stratified,
        Method::Local,
        Method::Gbg,
        Method::Mis,
        Method::Reference,
        Method::Ris,
        Method::Realtime,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::Uniform => "uniform",
            Method::All => "all",
            Method::Global => "global",
            Method::Stratified => "stratified",
            Method::Local => "local",
            Method::Gbg => "gbg",
            Method::Mis => "mis",
            Method::Reference => "reference",
            Method::Ris => "ris",
            Method::Realtime => "realtime",
        }
    }
}

/// How a CDF method chooses the paraboloid face of a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceMode {
    /// Russian roulette by each face's total importance (thesis alg. 9). Equivalent to sampling the
    /// method's CDF over both faces at once.
    RussianRoulette,
    /// Every face with importance equally likely (the thesis's 0.5 baseline, alg. 4).
    Uniform,
}

/// The most VPLs (samples) a pixel may draw a frame: a frame records one dispatch per
/// `vpls_per_dispatch` of them, and beyond this a frame's commands and time grow to no use (the thesis's
/// largest count is 800; 4 billion filled the host's memory before the first frame).
pub const MAX_VPLS: u32 = 1 << 16;

#[derive(Clone, Debug)]
pub struct FrameSettings {
    pub width: u32,
    pub height: u32,
    pub component: Component,
    pub method: Method,
    /// VPLs per pixel (sampled methods).
    pub vpls: u32,
    pub seed: u64,
    /// The seed of the importance's gather points and rays (global, stratified, local, gbg, mis);
    /// `None`: derived from `seed`. The viewer fixes it so that progressive frames, which differ in
    /// `seed`, keep one CDF (each frame is unbiased given any CDF, so their mean is too).
    pub cdf_seed: Option<u64>,
    /// The seed of the VPLs' places in their texels (`Keys::vpl_offset`: each texel's light ray passes
    /// through a random point of the texel, the same for every texel of a face, so that the VPL sum's mean
    /// over seeds is the one-bounce integral itself, not the texel centres' quadrature of it). `None`:
    /// `cdf_seed`'s, else `seed`'s, and progressive frames draw new sets (`progressive::VplSets`); `Some`
    /// pins it (`--cdf-seed`). Animations (`render --frames`, `bench --animate`) fix it for the run, so
    /// the maps change only where a light moves.
    pub vpl_seed: Option<u64>,
    /// Resolution of each per-VPL paraboloid shadow map (`Visibility::Psm`).
    pub psm_res: u32,
    /// The VPL map at each light (`--light-map`).
    pub light_map: LightMap,
    /// Reflective DPRSM resolution per face (the VPLs: 2 × lights × res²).
    pub dprsm_res: u32,
    /// Voxels along the longest side of the scene bounds.
    pub voxels: u32,
    /// 1/d² clamp: minimum distance, as a fraction of the scene diagonal (0: off).
    pub clamp: f32,
    /// A VPL's falloff with distance (`--vpl-kernel`).
    pub vpl_kernel: VplKernel,
    /// VPLs per tile of the exhaustive (`all`) gather: one submission each.
    pub all_tile: u32,
    /// Gather points of the importance (global, stratified; local splits them among its regions).
    pub cdf_samples: u32,
    /// Screen regions of `local` (a perfect square: side × side).
    pub regions: u32,
    /// Cosine rays per gather point (gbg).
    pub gather_rays: u32,
    /// Share of samples drawn uniformly among the VPLs by the CDF methods (defensive sampling): it bounds a
    /// VPL's weight by 1 / share times a uniform draw's.
    pub defensive: f32,
    /// Share η of the CDF methods' draws (global, stratified, local, gbg) from the pixel's near window,
    /// the light-map texels around where the pixel projects into a light's map
    /// (`glsl/shared/near_window.glsl`, half-width `ris.near_radius`): p_v = η p_near(v) + (1 − η) p_mix(v).
    /// The VPLs next to a pixel, a concave edge's fireflies, are the part of the integrand a screen-wide
    /// CDF cannot know. 0: the thesis's mixtures. mis finds them by its gathering rays, ris by its own
    /// near candidates: neither takes it.
    pub near_share: f32,
    pub face: FaceMode,
    pub mis_weights: MisWeights,
    /// Samples per pixel of the reference integrator (a sample is one point of each of its two
    /// strategies).
    pub spp: u32,
    /// The reference's first sample index: its samples are `sample_offset .. sample_offset + spp` of
    /// the pixel's Owen-scrambled Sobol sequence for `seed`. Progressive frames keep the seed and move
    /// this on by `spp` ([`super::progressive`]), so F frames are the first F · spp points of one
    /// stratified sequence instead of F independent scrambles of its first `spp`.
    pub sample_offset: u32,
    /// Samples per submission of the reference (`None`: a few dispatches' worth under the device's loop
    /// limit, at most 64). The image does not depend on it.
    pub reference_chunk: Option<std::num::NonZeroU32>,
    pub visibility: Visibility,
    /// The exact shadow rays of the gather, mis and ris's shade skip their ends' empty balls
    /// (`passes/end_balls.rs`): the same images with fewer BVH records per ray. Not a command-line
    /// option; the tests turn it off to show that the images do not change.
    pub end_balls: bool,
    /// The per-VPL shadow maps' (`Visibility::Psm`) constant depth bias, as a fraction of the scene
    /// diagonal (`paraboloid_shadow_bias`, glsl/shared/scene.glsl).
    pub shadow_bias: f32,
    /// Their slope bias, in texels.
    pub shadow_slope_bias: f32,
    /// `Method::Ris`'s source, candidates and reuse.
    pub ris: RisSettings,
    /// `Method::Realtime` shows its estimate through the denoiser (`passes/denoise.rs`); the raw
    /// estimate is read beside it either way.
    pub denoise: bool,
}

/// The one table of defaults: what a frame is when nothing says otherwise, the same for the library, the
/// command line (every frame flag takes its default from here) and the tests.
impl Default for FrameSettings {
    fn default() -> Self {
        FrameSettings {
            width: 256,
            height: 256,
            component: Component::Combined,
            // The lowest error at equal time of the VPL methods on every scene measured (BENCHMARKS.md).
            method: Method::Ris,
            vpls: 64,
            seed: 1,
            cdf_seed: None,
            vpl_seed: None,
            psm_res: 256,
            light_map: LightMap::Dprsm,
            dprsm_res: 512,
            voxels: 128,
            clamp: 0.0,
            vpl_kernel: VplKernel::Patch,
            all_tile: 4096,
            cdf_samples: 64,
            regions: 4,
            gather_rays: 4,
            // Chosen over the generated suite's 45 scenes (BENCHMARKS.md, "On scenes of every kind"): at 0.1
            // a VPL a CDF underrates weighs up to 10× a uniform draw (gbg 4.3× uniform's error on a scene,
            // global 11.7×); 0.75 gave every method its best worst case.
            defensive: 0.75,
            // Chosen over the generated suite (BENCHMARKS.md, "On scenes of every kind").
            near_share: 0.25,
            face: FaceMode::RussianRoulette,
            mis_weights: MisWeights::Consistent,
            spp: 256,
            sample_offset: 0,
            reference_chunk: None,
            visibility: Visibility::Exact,
            end_balls: true,
            shadow_bias: 1e-5,
            shadow_slope_bias: 1.5,
            ris: RisSettings::default(),
            denoise: true,
        }
    }
}

impl FrameSettings {
    /// Whether the frame's shadow rays use end balls: `end_balls` with exact visibility, for the gather's
    /// methods (queue or pool), mis's shadow rays and ris's shade (not the reference, whose rays have no
    /// VPL end).
    pub fn uses_end_balls(&self) -> bool {
        self.end_balls
            && self.visibility == Visibility::Exact
            && self.component != Component::Direct
            && self.method != Method::Reference
    }

    /// The seed the VPLs' places in their texels are drawn from: `vpl_seed`, else `cdf_seed`, else `seed`.
    pub fn vpl_seed_or_derived(&self) -> u64 {
        self.vpl_seed.or(self.cdf_seed).unwrap_or(self.seed)
    }

    /// The method whose CDF and source mixture the frame samples: ris's source, else the method itself.
    pub fn sampling_method(&self) -> Method {
        if self.uses_ris() {
            self.ris_settings().source.method()
        } else {
            self.method
        }
    }

    /// Whether the frame runs ris's stages: `Method::Ris` and `Method::Realtime`.
    pub fn uses_ris(&self) -> bool {
        matches!(self.method, Method::Ris | Method::Realtime)
    }

    /// The ris settings the frame runs: `ris` for `Method::Ris`, [`RisSettings::realtime`] for
    /// `Method::Realtime` with `ris`'s learned visibility (decided per view under `auto`).
    pub fn ris_settings(&self) -> RisSettings {
        if self.method == Method::Realtime {
            let (learn_visibility, learn_auto) = (self.ris.learn_visibility, self.ris.learn_auto);
            RisSettings { learn_visibility, learn_auto, ..RisSettings::realtime() }
        } else {
            self.ris
        }
    }

    /// Reservoirs (candidate streams) per pixel of a ris frame: `vpls` for `Method::Ris`,
    /// [`REALTIME_RESERVOIRS`] for `Method::Realtime`.
    pub fn ris_streams(&self) -> u32 {
        if self.method == Method::Realtime {
            REALTIME_RESERVOIRS
        } else {
            self.vpls
        }
    }

    /// VPLs a frame shades per pixel, each with its own visibility test: `vpls`, or for ris its candidate
    /// streams times their picks (what a frame's reservoirs hold, as the shade traces them).
    pub fn vpls_per_frame(&self) -> u32 {
        if self.uses_ris() {
            self.ris_streams() * self.ris_settings().picks
        } else {
            self.vpls
        }
    }

    /// The sample counts, and where the pixel's sequence starts (`sample_offset`).
    fn validate_samples(&self) -> Result<(), SettingsError> {
        if self.spp == 0 {
            reject!("--spp must be at least 1");
        }
        if self.sample_offset.checked_add(self.spp).is_none() {
            reject!(
                "the reference's samples {} + {} run past its sequence's 2^32 points",
                self.sample_offset,
                self.spp
            );
        }
        Ok(())
    }

    /// The mixtures' shares and the clamp, each a fraction.
    fn validate_shares(&self) -> Result<(), SettingsError> {
        if !(self.defensive.is_finite() && (0.0..=1.0).contains(&self.defensive)) {
            reject!("--defensive must be in [0, 1] (got {})", self.defensive);
        }
        if !(self.near_share.is_finite() && (0.0..1.0).contains(&self.near_share)) {
            reject!("--near-share must be in [0, 1) (got {})", self.near_share);
        }
        if !(self.clamp.is_finite() && (0.0..1.0).contains(&self.clamp)) {
            reject!("the clamp must be a fraction of the scene diagonal in [0, 1) (got {})", self.clamp);
        }
        Ok(())
    }

    /// `Method::Ris`'s settings against each other and the device's limits (other methods ignore them).
    fn validate_ris(&self, gpu: &Gpu) -> Result<(), SettingsError> {
        if !self.uses_ris() {
            return Ok(());
        }
        let r = &self.ris_settings();
        if self.visibility.shared_set() {
            reject!("--method ris and realtime test visibility per pixel and sample: --visibility psm shares one VPL set across pixels (use voxel or exact)");
        }
        if !(1..=1024).contains(&r.candidates) {
            reject!("--candidates must be between 1 and 1024 (got {})", r.candidates);
        }
        let max_picks = crate::bindings::RIS_MAX_PICKS;
        if !(1..=max_picks).contains(&r.picks) {
            reject!("--picks must be between 1 and {max_picks} (got {})", r.picks);
        }
        let max_k = crate::bindings::RIS_MAX_NEIGHBORS;
        if r.spatial_neighbors > max_k {
            reject!("--spatial-neighbors must be at most {max_k} (got {})", r.spatial_neighbors);
        }
        if r.spatial_passes > 8 {
            reject!("--spatial-passes must be at most 8 (got {})", r.spatial_passes);
        }
        if r.spatial_passes > 0 && r.spatial_neighbors == 0 {
            reject!("--spatial-passes {} needs --spatial-neighbors of at least 1", r.spatial_passes);
        }
        if !(r.spatial_radius.is_finite() && r.spatial_radius >= 1.0 && r.spatial_radius <= 1024.0) {
            reject!("--spatial-radius must be between 1 and 1024 pixels (got {})", r.spatial_radius);
        }
        if !(r.learn_visibility >= 0.0 && r.learn_visibility <= 1.0) {
            reject!("--learn-visibility must be in [0, 1] (got {})", r.learn_visibility);
        }
        if r.learn_visibility > 0.0 && r.pool_tiles == 0 {
            reject!("--learn-visibility needs the pool (--pool-tiles ≥ 1)");
        }
        if r.near_radius > 1024 {
            reject!("--near-radius must be at most 1024 texels (got {})", r.near_radius);
        }
        if r.pool_tiles > 4096 {
            reject!("--pool-tiles must be at most 4096 (got {})", r.pool_tiles);
        }
        if !(r.temporal_cap.is_finite() && r.temporal_cap >= 0.0) {
            reject!("--temporal-cap must be finite and non-negative (got {})", r.temporal_cap);
        }
        let layers = self.ris_streams() as u64 * r.picks as u64;
        let bytes = crate::passes::ris::Ris::layer_bytes(self.width, self.height) * layers;
        let range = gpu.limits().max_storage_buffer_range as u64;
        if bytes > range {
            reject!("ris keeps {layers} reservoirs per pixel: {bytes} bytes exceed maxStorageBufferRange ({range}); lower --vpls, --picks or the size");
        }
        Ok(())
    }

    /// Reject impossible settings with a message naming the setting and the device limit.
    pub fn validate(&self, gpu: &Gpu) -> Result<(), SettingsError> {
        let max = gpu.limits().max_image_dimension2_d;
        for (what, v) in [("width", self.width), ("height", self.height), ("DPRSM resolution", self.dprsm_res)] {
            if v == 0 {
                reject!("{what} must be at least 1");
            }
            if v > max {
                reject!("{what} {v} exceeds the device limit maxImageDimension2D ({max})");
            }
        }
        if !(1..=MAX_VPLS).contains(&self.vpls) {
            reject!("the VPL count must be between 1 and {MAX_VPLS} (got {})", self.vpls);
        }
        if let LightMap::Rsm { fov_deg } = self.light_map {
            if !(fov_deg.is_finite() && fov_deg > 0.0 && fov_deg < 180.0) {
                reject!("--light-map rsm:FOV must be in (0, 180) degrees (got {fov_deg})");
            }
        }
        if self.visibility.shared_set() {
            if self.method == Method::All && self.component != Component::Direct {
                reject!("--visibility psm needs a sampled method (`all` would need a shadow map per VPL slot)");
            }
            if self.psm_res == 0 || self.psm_res > max {
                reject!("--psm-res must be between 1 and maxImageDimension2D ({max}) (got {})", self.psm_res);
            }
            // One layer a VPL, as an image's and as a render pass's (whose least guaranteed limit is 256).
            let limits = gpu.limits();
            for (layers, name) in [
                (limits.max_image_array_layers, "maxImageArrayLayers"),
                (limits.max_framebuffer_layers, "maxFramebufferLayers"),
            ] {
                if self.vpls > layers {
                    reject!("--visibility psm renders one map per VPL: {} VPLs exceed {name} ({layers})", self.vpls);
                }
            }
            let bytes = psm::Psm::bytes(self.vpls, self.psm_res);
            if bytes > psm::MAX_PSM_BYTES {
                reject!(
                    "{} shadow maps of {}² take {} MiB, over the {} MiB bound: lower --vpls or --psm-res",
                    self.vpls,
                    self.psm_res,
                    bytes >> 20,
                    psm::MAX_PSM_BYTES >> 20
                );
            }
        }
        self.validate_ris(gpu)?;
        self.validate_samples()?;
        if !(1..=1024).contains(&self.voxels) {
            reject!("voxels must be between 1 and 1024 (got {})", self.voxels);
        }
        if self.all_tile == 0 {
            reject!("the tile size must be at least 1");
        }
        if !(1..=4096).contains(&self.cdf_samples) {
            reject!("--cdf-samples must be between 1 and 4096 (got {})", self.cdf_samples);
        }
        let side = (self.regions as f64).sqrt().round() as u32;
        if self.regions == 0 || side * side != self.regions || side > 8 {
            reject!("--regions must be a perfect square from 1 to 64 (got {})", self.regions);
        }
        if !(1..=256).contains(&self.gather_rays) {
            reject!("--gather-rays must be between 1 and 256 (got {})", self.gather_rays);
        }
        self.validate_shares()?;
        let ok = |v: f32| v.is_finite() && v >= 0.0;
        if !ok(self.shadow_bias) || !ok(self.shadow_slope_bias) {
            reject!("shadow biases must be finite and non-negative");
        }
        Ok(())
    }
}
