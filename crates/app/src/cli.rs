//! The command line's schema (clap): the commands, their arguments, and how the arguments become the
//! graph's `FrameSettings` and the device's `GpuOptions`.
//!
//! `render`, `view` and `bench` share one flattened [`FrameArgs`]; `render` and `view` also share
//! [`PictureArgs`] (what one picture is: size, component, method, VPLs, seed), which `bench` sweeps
//! instead. A command that wants other defaults than `render` sets them with `mut_arg`, next to its
//! arguments, so `--help` shows each command its own defaults.
//!
//! The choice flags (`--method`, `--visibility`, …) parse straight into the graph's enums through one
//! table per flag ([`Choices`]): name on the command line, graph value, `--help` line.

use bounce_device::GpuOptions;
use bounce_graph::frame::{
    Component, FaceMode, FrameSettings, LightMap, Method, MisWeights, RisSettings, RisSource, Visibility, VplKernel,
};
use bounce_graph::scene::Scene;
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand, ValueEnum};
use std::ffi::OsStr;
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(
    name = "bounce",
    version,
    about = "One-bounce global illumination from point lights with virtual point lights, on Vulkan."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene to a linear float32 EXR (and optionally a tone-mapped PNG).
    Render(RenderArgs),
    /// List the Vulkan devices with the features and limits bounce uses.
    Info,
    /// Error metrics of a test image against a reference image (both EXR): relMSE = mean over pixels and
    /// channels of (t − r)² / (r² + 0.01), RMSE, the ratio of the means, p99 and p99.9 of |t − r|, mean FLIP.
    Compare(CompareArgs),
    /// Run time against error for methods × VPL counts: bench.csv, bench.md, time_vs_error.png.
    Bench(BenchArgs),
    /// Interactive viewer: fly camera, progressive accumulation, screenshots (needs a display).
    View(ViewArgs),
    /// Every method at equal time on every scene of a suite against each scene's ground truth:
    /// suite.csv, suite.md, suite.png (`scripts/make-scenes.py --suite DIR` writes a suite).
    Suite(SuiteArgs),
}

/// A choice flag's values: (name on the command line, the graph's value, its `--help` line).
#[derive(Clone, Copy)]
pub struct Choices<T: 'static>(&'static [(&'static str, T, &'static str)]);

impl<T: PartialEq> Choices<T> {
    /// The command-line name of `value` (the defaults' flags show it); a value the table lacks is a bug
    /// that `frame_flag_defaults_are_the_graph_defaults` catches.
    pub fn name_of(&self, value: &T) -> &'static str {
        self.0.iter().find(|(_, v, _)| v == value).map_or("?", |(name, ..)| *name)
    }
}

impl<T: Clone + Send + Sync + 'static> TypedValueParser for Choices<T> {
    type Value = T;

    fn parse_ref(&self, cmd: &clap::Command, arg: Option<&clap::Arg>, value: &OsStr) -> Result<T, clap::Error> {
        // clap's own parser, so an unknown value reads exactly like any other clap error.
        let names = PossibleValuesParser::new(self.0.iter().map(|(name, ..)| PossibleValue::new(*name)));
        let name = names.parse_ref(cmd, arg, value)?;
        let (_, value, _) = self.0.iter().find(|(n, ..)| *n == name).expect("clap accepted one of the listed names");
        Ok(value.clone())
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(self.0.iter().map(|(name, _, help)| PossibleValue::new(*name).help(*help))))
    }
}

pub const COMPONENTS: Choices<Component> = Choices(&[
    ("direct", Component::Direct, "Direct light from the point lights (one exact shadow ray per light)"),
    ("indirect", Component::Indirect, "One bounce of indirect light, gathered from the VPLs"),
    ("combined", Component::Combined, "Direct plus indirect"),
]);

pub const METHODS: Choices<Method> = Choices(&[
    ("uniform", Method::Uniform, "N VPLs per pixel, uniformly among the non-empty DPRSM texels"),
    ("all", Method::All, "Every VPL (the converged VPL estimate; slow, tiled, with a progress bar)"),
    ("global", Method::Global, "Ritschel et al. 2011: a CDF from --cdf-samples random gather points"),
    (
        "stratified",
        Method::Stratified,
        "The global CDF with its gather points spread over the 4 screen quarters (thesis §7.3.2)",
    ),
    ("local", Method::Local, "One CDF per screen region (--regions), a pixel sampling those around it blended bilinearly (thesis §7.3.3)"),
    ("gbg", Method::Gbg, "The gathering-based global CDF: --gather-rays cosine rays per pixel (thesis §7.3.4)"),
    (
        "mis",
        Method::Mis,
        "Cosine gathering (--gather-rays) and gbg CDF sampling (--vpls) by the balance heuristic (§7.4)",
    ),
    (
        "reference",
        Method::Reference,
        "The exact one-bounce integral: GPU path tracing against the triangles (BVH), --spp samples",
    ),
    (
        "ris",
        Method::Ris,
        "Resampling: --vpls reservoirs per pixel, each one of --candidates VPLs from --source by its unshadowed contribution, spatial and temporal reuse",
    ),
    (
        "realtime",
        Method::Realtime,
        "Real time: two reservoirs per pixel, one shadow ray each, reused across frames (reprojected) and pixels, then denoised (--denoise)",
    ),
]);

pub const RIS_SOURCES: Choices<RisSource> = Choices(&[
    ("uniform", RisSource::Uniform, "Uniformly among the VPLs"),
    ("global", RisSource::Global, "The global CDF (--cdf-samples gather points)"),
    ("stratified", RisSource::Stratified, "The global CDF from gather points over the 4 screen quarters"),
    (
        "local",
        RisSource::Local,
        "The local method's CDFs (--regions); the presampled pool, shared by the screen, mixes them all",
    ),
    ("gbg", RisSource::Gbg, "The gathering-based global CDF (--gather-rays)"),
]);

pub const VISIBILITIES: Choices<Visibility> = Choices(&[
    ("voxel", Visibility::Voxel, "Amanatides–Woo march through the voxel grid (the thesis's ch. 7)"),
    ("exact", Visibility::Exact, "Default. Exact shadow rays against the triangles (BVH)"),
    (
        "psm",
        Visibility::Psm,
        "Per-VPL paraboloid shadow maps (thesis ch. 6) for one shared set of --vpls VPLs per frame",
    ),
]);

/// `rsm` is 90°; `rsm:FOV` another field of view ([`LightMaps`]).
pub const LIGHT_MAPS: Choices<LightMap> = Choices(&[
    ("dprsm", LightMap::Dprsm, "Dual paraboloid RSM: two faces, every direction (the thesis's choice)"),
    (
        "rsm",
        LightMap::Rsm { fov_deg: 90.0 },
        "One perspective RSM of 90° (rsm:FOV: FOV degrees) looking at the scene's centre (misses what lies outside)",
    ),
    ("cube", LightMap::Cube, "Cube-map RSM: six 90° faces"),
]);

/// `--light-map`'s parser: [`LIGHT_MAPS`]' names, and `rsm:FOV` for a perspective map of FOV degrees
/// (one value for one concept: the map and its field of view).
#[derive(Clone, Copy)]
pub struct LightMaps;

impl TypedValueParser for LightMaps {
    type Value = LightMap;

    fn parse_ref(&self, cmd: &clap::Command, arg: Option<&clap::Arg>, value: &OsStr) -> Result<LightMap, clap::Error> {
        if let Some(fov) = value.to_str().and_then(|v| v.strip_prefix("rsm:")) {
            return fov.parse::<f32>().map(|fov_deg| LightMap::Rsm { fov_deg }).map_err(|_| {
                clap::Error::raw(
                    clap::error::ErrorKind::ValueValidation,
                    format!("--light-map rsm:FOV needs a number of degrees (got `{fov}`)\n"),
                )
                .with_cmd(cmd)
            });
        }
        LIGHT_MAPS.parse_ref(cmd, arg, value)
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        LIGHT_MAPS.possible_values()
    }
}

pub const VPL_KERNELS: Choices<VplKernel> = Choices(&[
    (
        "patch",
        VplKernel::Patch,
        "Default. 1/√(d⁴ + (A/π)²), A the VPL's patch area: 1/d² far away, bounded next to the receiver",
    ),
    ("point", VplKernel::Point, "The thesis's point VPL: 1/d², unbounded next to the receiver"),
]);

pub const MIS_WEIGHTS: Choices<MisWeights> = Choices(&[
    ("consistent", MisWeights::Consistent, "Both densities in solid angle (unbiased)"),
    ("thesis", MisWeights::Thesis, "The thesis's literal weights (mixed measures; for comparison)"),
]);

pub const FACES: Choices<FaceMode> = Choices(&[
    ("rr", FaceMode::RussianRoulette, "Russian roulette by each face's total importance (thesis alg. 9)"),
    ("uniform", FaceMode::Uniform, "Every face with importance equally likely (thesis alg. 4)"),
]);

/// The one table of defaults: `FrameSettings::default()`, what a frame is when nothing says otherwise.
/// Every flag of a frame setting takes its default from it (clap evaluates these at parse time), so the
/// library, the command line and the tests share one renderer. A command with other defaults (`view`,
/// `bench`) says so with `mut_arg` beside its arguments.
fn d() -> FrameSettings {
    FrameSettings::default()
}
/// `render --time-limit`'s method when neither --method nor --vpls is given: the path tracer. Its progressive frames
/// continue one stratified sample sequence per pixel, and at equal time it had the lowest error of every
/// method on every scene of the suite, below ris and below the Mitsuba MIS tracer of
/// `lab/compare-mitsuba.py` (BENCHMARKS.md, "The path tracer's frames").
pub const TIME_LIMIT_METHOD: Method = Method::Reference;
/// The reference's samples per pixel per progressive frame under `render --time-limit` when --spp is
/// not given. Frames of one sequence differ only in how many samples the budget holds: a frame costs a
/// few ms besides its samples, which 4 a frame pays more often, and 16 or 32 lose more to the last
/// frame that does not fit. 8 reached the most samples, or nearly, on every scene measured
/// (BENCHMARKS.md, "The path tracer's frames").
pub const TIME_LIMIT_SPP: u32 = 8;
/// ris's budget per progressive frame under `render --time-limit` when neither --vpls nor --candidates
/// is given: (reservoirs, candidates, near-window candidates, picks), chosen per view by the share of
/// the unshadowed transport that visibility blocks (`Renderer::blocked_share`, the threshold of
/// `--learn-visibility auto`). Where visibility blocks most of it, each shadow ray is the scarce
/// resource: 2 reservoirs of 64 candidates. Elsewhere the candidates are: 2 reservoirs of 128. Either
/// way each reservoir keeps 3 picks (`--picks`), 6 shadow rays a frame: most of a frame's error is
/// the kept samples' own, which picks cut at the price of a shadow ray each, not of new candidates.
/// Measured at equal time (BENCHMARKS.md, "ris: several picks per reservoir").
pub const RIS_FRAME_BLOCKED: (u32, u32, u32, u32) = (2, 64, 8, 3);
pub const RIS_FRAME_OPEN: (u32, u32, u32, u32) = (2, 128, 16, 3);
/// Under the same budget choice, where visibility blocks at least this share of the view's unshadowed
/// transport, ris draws its candidates from the gathering-based CDF (`--source gbg`: the VPLs the view's
/// own cosine rays reach) with a defensive share of `RIS_GATHERED_DEFENSIVE` (or --defensive's), unless
/// --source is given. A uniform pool then holds almost nothing visible, and which few visible VPLs
/// it holds moves every pixel's estimate at once: in the two rooms (blocked 0.99) the image mean of a
/// 0.7 s render varied by 1.5 % RMS from run to run, 0.5 % with the gathered source, at 1.1–1.2× lower
/// relMSE. In the doorway (0.52) it cost 1.5× (BENCHMARKS.md, "ris: several picks per reservoir"). On
/// the generated suite's five dark rooms (0.86–0.93), chosen before they existed, the uniform source read
/// 1.9× and the open views' budget 1.6× the error (BENCHMARKS.md, "The source").
pub const RIS_GATHERED_BLOCKED: f32 = 0.8;
pub const RIS_GATHERED_DEFENSIVE: f32 = 0.5;

/// What one picture is: its size, component, method, VPL count and seed (`render` and `view`; `bench`
/// sweeps method, VPLs and seed itself).
#[derive(Args, Debug)]
pub struct PictureArgs {
    /// Image width (default: the scene's [render] width, else 256).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default: the scene's [render] height, else 256).
    #[arg(long)]
    pub height: Option<u32>,
    /// Which radiance to render.
    #[arg(long, value_parser = COMPONENTS, default_value = COMPONENTS.name_of(&d().component))]
    pub component: Component,
    /// How the gather picks VPLs. Default ris: the lowest error at equal time of the VPL methods on every
    /// scene measured (BENCHMARKS.md); `render --time-limit` without it renders `reference`, the lowest
    /// error at equal time of all methods (BENCHMARKS.md).
    #[arg(long, value_parser = METHODS)]
    pub method: Option<Method>,
    /// VPLs per pixel (sampled methods; ris: reservoirs, one shadow ray per pick; not `all`, `realtime` or
    /// `reference`). Default 64; `render --time-limit` with ris and without --vpls chooses reservoirs,
    /// candidates and picks per view (it prints them): many cheap frames, which at equal time had lower
    /// error than few costly ones (BENCHMARKS.md).
    #[arg(long)]
    pub vpls: Option<u32>,
    /// Random seed (same seed, same image).
    #[arg(long, default_value_t = d().seed)]
    pub seed: u64,
}

impl PictureArgs {
    /// The settings of this picture: the size from the flags, else the scene's `[render]` size, else
    /// `fallback_size`; everything else from `frame`.
    pub fn settings(&self, frame: &FrameArgs, scene: &Scene, fallback_size: u32) -> FrameSettings {
        let width = self.width.or(scene.render_width).unwrap_or(fallback_size);
        let height = self.height.or(scene.render_height).unwrap_or(fallback_size);
        FrameSettings {
            component: self.component,
            method: self.method.unwrap_or(d().method),
            vpls: self.vpls.unwrap_or(d().vpls),
            seed: self.seed,
            ..frame.settings(width, height)
        }
    }
}

/// The frame settings and device flags of every command that renders (`render`, `view`, `bench`).
#[derive(Args, Debug)]
pub struct FrameArgs {
    /// Reflective DPRSM resolution per face (VPLs: 2 × lights × res²).
    #[arg(long, default_value_t = d().dprsm_res)]
    pub dprsm_res: u32,
    /// Voxels along the longest side of the scene (cubic cells): the grid of --visibility voxel, and the
    /// distance below which the CDF methods' importance bounds 1/d² (one cell).
    #[arg(long, default_value_t = d().voxels)]
    pub voxels: u32,
    /// A VPL's falloff with distance.
    #[arg(long, value_parser = VPL_KERNELS, default_value = VPL_KERNELS.name_of(&d().vpl_kernel))]
    pub vpl_kernel: VplKernel,
    /// Gather points of the importance (global, stratified; local splits them among its regions).
    #[arg(long, default_value_t = d().cdf_samples)]
    pub cdf_samples: u32,
    /// Screen regions of `local` (a perfect square).
    #[arg(long, default_value_t = d().regions)]
    pub regions: u32,
    /// Cosine rays per gather point (gbg).
    #[arg(long, default_value_t = d().gather_rays)]
    pub gather_rays: u32,
    /// Share of samples drawn uniformly among all VPLs by the CDF methods (bounds every VPL's weight;
    /// default 0.75, chosen over the generated suite, or 0.5 where `render --time-limit` picks ris's
    /// gathered source for the view).
    #[arg(long)]
    pub defensive: Option<f32>,
    /// How CDF methods choose the paraboloid face.
    #[arg(long, value_parser = FACES, default_value = FACES.name_of(&d().face))]
    pub face: FaceMode,
    /// MIS weights (--method mis).
    #[arg(long, value_parser = MIS_WEIGHTS, default_value = MIS_WEIGHTS.name_of(&d().mis_weights))]
    pub mis_weights: MisWeights,
    /// Samples per pixel of --method reference (default 256: its own noise is ≈ relMSE 1e-4 on the
    /// default scene at 128²); under a time limit (`render --time-limit`, `bench --time-limits`,
    /// `suite`), per frame (default 8).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Visibility of the VPL gather.
    #[arg(long, value_parser = VISIBILITIES, default_value = VISIBILITIES.name_of(&d().visibility))]
    pub visibility: Visibility,
    /// Resolution of each per-VPL paraboloid shadow map (--visibility psm).
    #[arg(long, default_value_t = d().psm_res)]
    pub psm_res: u32,
    /// The VPL map at each light (its faces are --dprsm-res² each).
    #[arg(long, value_parser = LightMaps, default_value = LIGHT_MAPS.name_of(&d().light_map))]
    pub light_map: LightMap,
    /// Seed of the light side: the importance's gather points and rays, and where in its texel each VPL
    /// lies (default: --seed). Given, progressive frames (`render --time-limit`, `bounce view`) keep one
    /// VPL set; without it they draw a new one as the time allows (at most 1/28 of it), so that their
    /// mean converges to the one-bounce image, not to one set's VPL sum.
    #[arg(long)]
    pub cdf_seed: Option<u64>,
    /// Candidate distribution of --method ris (the CDF methods' mixtures, --defensive included, without
    /// their near share: ris has near candidates of its own; default
    /// uniform, or gbg where `render --time-limit` finds the view's transport nearly all blocked).
    #[arg(long, value_parser = RIS_SOURCES)]
    pub source: Option<RisSource>,
    /// Candidates per reservoir of --method ris (M; default 32, or chosen per view under `render
    /// --time-limit` without --vpls).
    #[arg(long)]
    pub candidates: Option<u32>,
    /// VPLs each reservoir of --method ris keeps from its candidates, each a choice of its own with its
    /// own shadow ray (1 to 4; default 1, or chosen per view under `render --time-limit` without --vpls).
    #[arg(long)]
    pub picks: Option<u32>,
    /// --method realtime shows its estimate through the denoiser (SVGF: temporal accumulation and an
    /// edge-aware à-trous filter): `on` or `off` (the raw estimate).
    #[arg(long, default_value = "on", value_parser = parse_on_off, action = clap::ArgAction::Set)]
    pub denoise: bool,
    /// Switches that exist for A/B measurement (the `lab` cargo feature; BENCHMARKS.md says what each
    /// measured): ris's reuse, pool and near window, the CDF methods' near share, learned visibility,
    /// control variate, the 1/d² clamp.
    #[cfg(feature = "lab")]
    #[command(flatten)]
    pub lab: LabArgs,
    /// Use the first Vulkan device whose name contains this (also: BOUNCE_DEVICE).
    #[arg(long)]
    pub device: Option<String>,
    /// Enable the Vulkan validation layers; fail if they report anything.
    #[arg(long)]
    pub validation: bool,
    /// The frame settings given on the command line, not left at their defaults (`lib::run` fills it).
    #[arg(skip)]
    pub given: Vec<bounce_graph::frame::Setting>,
}

/// The A/B switches of the `lab` cargo feature (left out of the default build; CI builds it once).
#[cfg(feature = "lab")]
#[derive(Args, Debug)]
pub struct LabArgs {
    /// Clamp 1/d² below this distance, as a fraction of the scene diagonal (0: off, unbiased).
    #[arg(long, default_value_t = d().clamp)]
    pub clamp: f32,
    /// Spatial reuse passes of --method ris (0: none).
    #[arg(long, default_value_t = RisSettings::default().spatial_passes)]
    pub spatial_passes: u32,
    /// Neighbours per spatial pass of --method ris.
    #[arg(long, default_value_t = RisSettings::default().spatial_neighbors)]
    pub spatial_neighbors: u32,
    /// Radius of the spatial neighbourhood of --method ris, pixels.
    #[arg(long, default_value_t = RisSettings::default().spatial_radius)]
    pub spatial_radius: f32,
    /// Temporal reuse of --method ris over progressive frames of one view: last frame's reservoirs count
    /// at most this many times --candidates (0: no temporal reuse).
    #[arg(long, default_value_t = RisSettings::default().temporal_cap)]
    pub temporal_cap: f32,
    /// --method ris draws its candidates from a pool of this many tiles of 1024 source draws, made once
    /// per frame (0: each pixel draws its own).
    #[arg(long, default_value_t = RisSettings::default().pool_tiles)]
    pub pool_tiles: u32,
    /// --method ris draws this many of each reservoir's candidates from the near window: light-map
    /// texels around where the pixel projects into a light's map (0: none; needs the pool; default 8,
    /// or chosen per view with --candidates).
    #[arg(long)]
    pub near_candidates: Option<u32>,
    /// Half-width of the near window (--near-candidates' and --near-share's), texels.
    #[arg(long, default_value_t = RisSettings::default().near_radius)]
    pub near_radius: u32,
    /// Share of the samples of global, stratified, local and gbg drawn from the pixel's near window, the
    /// light-map texels around where the pixel projects into a light's map: the VPLs next to it, whose
    /// 1/d² makes the fireflies of concave edges (0: the thesis's mixtures; the default chosen over the
    /// generated suite).
    #[arg(long, default_value_t = d().near_share)]
    pub near_share: f32,
    /// --method ris weighs its target by the visibility learned from earlier progressive frames' shadow
    /// rays, floored at δ: `auto` (learn at δ = 0.1 where the view's estimated blocked share of the
    /// unshadowed transport is at least 0.4), `off`, or δ in (0, 1].
    #[arg(long, default_value = "auto", value_parser = parse_learn)]
    pub learn_visibility: Learn,
    /// --method ris adds the unshadowed control variate to each reservoir's estimate (its candidates'
    /// unshadowed sum minus the kept one's, mean 0; without reuse): `on` or `off`.
    #[arg(long, default_value = "on", value_parser = parse_on_off, action = clap::ArgAction::Set)]
    pub control_variate: bool,
}

#[cfg(feature = "lab")]
impl LabArgs {
    /// `s` with these switches.
    fn apply(&self, s: &mut FrameSettings) {
        s.clamp = self.clamp;
        s.near_share = self.near_share;
        let r = &mut s.ris;
        r.spatial_passes = self.spatial_passes;
        r.spatial_neighbors = self.spatial_neighbors;
        r.spatial_radius = self.spatial_radius;
        r.temporal_cap = self.temporal_cap;
        r.pool_tiles = self.pool_tiles;
        if let Some(n) = self.near_candidates {
            r.near_candidates = n;
        }
        r.near_radius = self.near_radius;
        r.learn_visibility = self.learn_visibility.floor();
        r.learn_auto = self.learn_visibility == Learn::Auto;
        r.control_variate = self.control_variate;
    }
}

impl FrameArgs {
    /// The frame settings these flags give a `width` × `height` image; what they do not set (component,
    /// method, VPLs, seed, the graph's internal knobs) keeps `FrameSettings::default()`.
    pub fn settings(&self, width: u32, height: u32) -> FrameSettings {
        #[allow(unused_mut)] // the `lab` feature's switches change it
        let mut s = FrameSettings {
            width,
            height,
            spp: self.spp.unwrap_or(d().spp),
            visibility: self.visibility,
            psm_res: self.psm_res,
            light_map: self.light_map,
            mis_weights: self.mis_weights,
            cdf_samples: self.cdf_samples,
            regions: self.regions,
            gather_rays: self.gather_rays,
            defensive: self.defensive.unwrap_or(FrameSettings::default().defensive),
            face: self.face,
            cdf_seed: self.cdf_seed,
            // A given light-side seed pins the VPL set (`progressive::VplSets`).
            vpl_seed: self.cdf_seed,
            dprsm_res: self.dprsm_res,
            voxels: self.voxels,
            vpl_kernel: self.vpl_kernel,
            denoise: self.denoise,
            ris: RisSettings {
                source: self.source.unwrap_or(RisSettings::default().source),
                candidates: self.candidates.unwrap_or(RisSettings::default().candidates),
                picks: self.picks.unwrap_or(RisSettings::default().picks),
                ..RisSettings::default()
            },
            ..FrameSettings::default()
        };
        #[cfg(feature = "lab")]
        self.lab.apply(&mut s);
        s
    }

    /// Whether the command line chose ris's near-window candidates itself (the `lab` feature's
    /// `--near-candidates`).
    pub fn near_candidates_given(&self) -> bool {
        #[cfg(feature = "lab")]
        return self.lab.near_candidates.is_some();
        #[cfg(not(feature = "lab"))]
        false
    }

    /// The device to open: `--device`, `--validation`, no window.
    pub fn gpu_options(&self) -> GpuOptions {
        GpuOptions { validation: self.validation, device: self.device.clone(), ..GpuOptions::default() }
    }
}

/// A scene argument: a folder holding `scene.toml` names that file (a suite's scenes are folders);
/// anything else is taken as given, and loading says what is wrong with it.
fn scene_path(arg: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(arg);
    let inside = path.join("scene.toml");
    Ok(if path.is_dir() && inside.is_file() { inside } else { path })
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// The scene file (TOML), or its folder (holding `scene.toml`, as `make-scenes.py` writes them).
    #[arg(value_parser = scene_path)]
    pub scene: PathBuf,
    /// Output EXR (linear float32 RGB). An animation (--frames) writes into --out-dir instead.
    #[arg(long, default_value = "out.exr", conflicts_with = "frames")]
    pub out: PathBuf,
    /// Also write a tone-mapped (Reinhard 2002) sRGB PNG.
    #[arg(long, conflicts_with = "frames")]
    pub png: Option<PathBuf>,
    #[command(flatten)]
    pub picture: PictureArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    /// Print a per-pass GPU time table (of the frame's own work: an untimed small frame runs first, so a
    /// driver's first-use shader compilation is not counted).
    #[arg(long)]
    pub timings: bool,
    /// Render progressive frames (seed, seed + 1, …; one CDF; the reference continues one sample
    /// sequence) for this many seconds of wall time (to within half a frame: a frame runs where half of it
    /// fits) and write their mean: equal-time comparisons in one flag. Without --method (and --vpls), the path tracer (the lowest error at equal time). Not for
    /// `all` (the same every frame).
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    pub time_limit: Option<f64>,
    /// Render an animation of this many frames (with --light-path) into --out-dir: frame_0000.exr and
    /// .png, … (with --timings and no --out-dir: time the frames, back to back, and write nothing)
    #[arg(long)]
    pub frames: Option<u32>,
    /// Where --frames writes its frames.
    #[arg(long)]
    pub out_dir: Option<PathBuf>,
    #[command(flatten)]
    pub animation: AnimationArgs,
}

/// `view` renders a frame per redraw, so it starts from a smaller window and cheaper maps than
/// `render`; the rest of its flags mean what they mean for `render`.
#[derive(Args, Debug)]
#[command(mut_arg("width", |a| a.help("Window width in pixels (default: the scene's [render] width, else 384)")))]
#[command(mut_arg("height", |a| a.help("Window height in pixels (default: the scene's [render] height, else 384)")))]
#[command(mut_arg("vpls", |a| a.default_value("16").help("VPLs per pixel per frame (+/− double and halve it)")))]
#[command(mut_arg("method", |a| a.help("The method (M cycles through the sampled ones, ris and reference)")))]
#[command(mut_arg("seed", |a| a.help("Seed of the first frame; frame k uses seed + k")))]
#[command(mut_arg("dprsm_res", |a| a.default_value("256")))]
pub struct ViewArgs {
    /// The scene file (TOML), or its folder (holding `scene.toml`, as `make-scenes.py` writes them).
    #[arg(value_parser = scene_path)]
    pub scene: PathBuf,
    #[command(flatten)]
    pub picture: PictureArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    /// Render this many frames, write --screenshot and exit.
    #[arg(long)]
    pub frames: Option<u32>,
    /// Where --frames writes its screenshot (PNG; the linear mean goes next to it as EXR).
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Present without waiting for vertical sync (immediate or mailbox, where the surface has one).
    #[arg(long)]
    pub no_vsync: bool,
    #[command(flatten)]
    pub animation: AnimationArgs,
}

/// The seeds of an animation's frames (`--temporal`).
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Temporal {
    /// Common random numbers: every frame after a change starts again from --seed, so each pixel's
    /// stratified points stay the same while the light moves and its draws follow the CDF
    /// continuously; frames of an unchanged scene still take seed + 1, + 2, … (progressive).
    Coherent,
    /// Frame k of the animation uses seed + k: fresh random numbers every frame.
    Fresh,
}

impl Temporal {
    /// The seed of a frame: `since_change` frames after the last change of camera, lights or settings,
    /// `frame` frames after the first.
    pub fn seed(self, base: u64, frame: u32, since_change: u32) -> u64 {
        match self {
            Temporal::Coherent => base.wrapping_add(since_change as u64),
            Temporal::Fresh => base.wrapping_add(frame as u64),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Temporal::Coherent => "coherent",
            Temporal::Fresh => "fresh",
        }
    }
}

/// The scripted light and camera motion and how its frames draw their random numbers (`render`, `view`).
#[derive(Args, Debug)]
pub struct AnimationArgs {
    /// Move the lights: `orbit[:PERIOD]` (each light circles its start, PERIOD frames per turn, default
    /// 60) or a TOML file of keyframes (see README). Needs --frames.
    #[arg(long, value_name = "orbit[:PERIOD]|FILE.toml")]
    pub light_path: Option<String>,
    /// Move the camera: `orbit[:PERIOD]` (the eye circles its start looking at the scene's target) or a
    /// TOML file of keyframes (`frame`, `eye`, `target`, optional `fov_y`). Needs --frames.
    #[arg(long, value_name = "orbit[:PERIOD]|FILE.toml")]
    pub camera_path: Option<String>,
    /// The seeds of consecutive frames (an A/B switch of the `lab` feature; default coherent).
    #[cfg(feature = "lab")]
    #[arg(long, value_enum, default_value = "coherent")]
    pub temporal: Temporal,
}

impl AnimationArgs {
    /// The seed schedule of consecutive frames: `coherent`, measured to flicker least (BENCHMARKS.md),
    /// unless the `lab` feature's `--temporal` says otherwise.
    pub fn temporal(&self) -> Temporal {
        #[cfg(feature = "lab")]
        return self.temporal;
        #[cfg(not(feature = "lab"))]
        Temporal::Coherent
    }

    /// Whether anything moves by script.
    pub fn moves(&self) -> bool {
        self.light_path.is_some() || self.camera_path.is_some()
    }
}

/// The window size of `view` when neither the flags nor the scene give one.
pub const VIEW_FALLBACK_SIZE: u32 = 384;
/// The image size of `render` when neither the flags nor the scene give one.
pub const RENDER_FALLBACK_SIZE: u32 = 256;

/// `bench` renders many frames, so its maps default to a smaller resolution than `render`'s.
#[derive(Args, Debug)]
#[command(mut_arg("dprsm_res", |a| a.default_value("128")))]
pub struct BenchArgs {
    /// The scene file (TOML), or its folder (holding `scene.toml`, as `make-scenes.py` writes them).
    #[arg(value_parser = scene_path)]
    pub scene: PathBuf,
    /// Output folder (also caches the reference image).
    #[arg(long)]
    pub out: PathBuf,
    /// Methods to sweep, comma-separated (any but `all`, which is the reference of `--reference all`).
    #[arg(long, value_parser = METHODS, value_delimiter = ',', default_value = "uniform,global,stratified,local,gbg,mis")]
    pub methods: Vec<Method>,
    /// VPL counts per pixel, comma-separated (default 16,64,256; with --time-limits the first is the VPLs
    /// per frame, and without --vpls ris takes the per-view budget of `render --time-limit`).
    #[arg(long, value_delimiter = ',')]
    pub vpls: Vec<u32>,
    /// Wall-time budgets in seconds, comma-separated: instead of one frame per VPL count, each method
    /// renders progressive frames for each budget (`render --time-limit`), so every column is an
    /// equal-time comparison.
    #[arg(long, value_delimiter = ',', value_name = "SECONDS", value_parser = parse_seconds)]
    pub time_limits: Vec<f64>,
    /// Runs per method and VPL count (each its own seed); medians are reported.
    #[arg(long, default_value_t = 3)]
    pub repeats: u32,
    /// Image width.
    #[arg(long, default_value_t = 128)]
    pub width: u32,
    /// Image height.
    #[arg(long, default_value_t = 128)]
    pub height: u32,
    #[command(flatten)]
    pub frame: FrameArgs,
    /// What errors are measured against: the path-traced ground truth (`path`, --method reference) or
    /// the exhaustive VPL sum on the same VPL set (`all`: selection error alone).
    #[arg(long, value_enum, default_value = "path")]
    pub reference: ReferenceArg,
    /// Samples per pixel of the path-traced reference (two-strategy MIS, stratified: 1024 is well
    /// below every method's error; see BENCHMARKS.md).
    #[arg(long, default_value_t = 1024)]
    pub reference_spp: u32,
    /// Measure temporal stability instead: move the lights along this path (`orbit[:PERIOD]` or a
    /// keyframe TOML, as --light-path; `none`: they stay put) and report per method the mean per-frame
    /// relMSE and flicker against a per-frame ground truth, at --vpls's first value per frame.
    #[arg(long, value_name = "orbit[:PERIOD]|FILE.toml|none")]
    pub animate: Option<String>,
    /// Move the camera along this path (`orbit[:PERIOD]` or a keyframe TOML, as `render --camera-path`),
    /// measured as --animate measures (alone it is `--animate none`: the lights stay put).
    #[arg(long, value_name = "orbit[:PERIOD]|FILE.toml")]
    pub camera_path: Option<String>,
    /// Frames of the --animate animation.
    #[arg(long, default_value_t = 16)]
    pub frames: u32,
    /// The seed schedules --animate compares, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "fresh,coherent")]
    pub temporal: Vec<Temporal>,
}

impl BenchArgs {
    /// The VPL counts to sweep: --vpls, else 16, 64 and 256.
    pub fn vpl_counts(&self) -> Vec<u32> {
        if self.vpls.is_empty() {
            vec![16, 64, 256]
        } else {
            self.vpls.clone()
        }
    }
}

/// `suite` renders many frames on many scenes, so its maps default to a smaller resolution than `render`'s.
#[derive(Args, Debug)]
#[command(mut_arg("dprsm_res", |a| a.default_value("128")))]
pub struct SuiteArgs {
    /// Scene files, a scene's folder (holding its `scene.toml`), or folders whose `*/scene.toml` are the suite.
    #[arg(required = true)]
    pub scenes: Vec<PathBuf>,
    /// Output folder (suite.csv, suite.md, suite.png, and each scene's cached ground truth).
    #[arg(long)]
    pub out: PathBuf,
    /// Methods to compare (must include uniform, the baseline).
    #[arg(long, value_parser = METHODS, value_delimiter = ',', default_value = "uniform,global,stratified,local,gbg,mis,ris")]
    pub methods: Vec<Method>,
    /// Seeds per method and scene (1..=N).
    #[arg(long, default_value_t = 4)]
    pub seeds: u32,
    /// Wall-time budget of progressive frames per method, seed and scene (equal time).
    #[arg(long, value_name = "SECONDS", default_value_t = 1.0, value_parser = parse_seconds)]
    pub time_limit: f64,
    /// One frame of --vpls VPLs per pixel per method and seed (equal VPL count, the thesis's comparison)
    /// instead of --time-limit's equal time.
    #[arg(long, conflicts_with = "time_limit")]
    pub equal_count: bool,
    /// VPLs per pixel per frame (default 16; ris: reservoirs). Without it, ris at equal time takes the
    /// per-view budget of `render --time-limit` (its reservoirs, candidates, picks and source).
    #[arg(long)]
    pub vpls: Option<u32>,
    /// Image width.
    #[arg(long, default_value_t = 128)]
    pub width: u32,
    /// Image height.
    #[arg(long, default_value_t = 128)]
    pub height: u32,
    /// Samples per pixel of each scene's path-traced ground truth.
    #[arg(long, default_value_t = 1024)]
    pub reference_spp: u32,
    #[command(flatten)]
    pub frame: FrameArgs,
}

/// What `bench` measures errors against (`commands::bench::Reference` adds the sample count).
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReferenceArg {
    /// The path-traced one-bounce ground truth (--method reference, --reference-spp samples).
    Path,
    /// The exhaustive VPL sum on the same VPL set (--method all): the selection error alone.
    All,
}

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// The image to measure (EXR).
    pub test: PathBuf,
    /// The image it is measured against (EXR).
    pub reference: PathBuf,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Write the FLIP error map (magma colours) to this PNG.
    #[arg(long)]
    pub heatmap: Option<PathBuf>,
}

/// `--learn-visibility`: `auto`, `off`, or a floor δ.
#[cfg(feature = "lab")]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Learn {
    Auto,
    Floor(f32),
}

#[cfg(feature = "lab")]
impl Learn {
    /// The floor δ_L the settings carry (0: off, or left to `auto`).
    pub fn floor(self) -> f32 {
        match self {
            Learn::Auto => 0.0,
            Learn::Floor(d) => d,
        }
    }
}

// The value parsers of the flags above.
#[path = "cli_values.rs"]
mod values;
#[cfg(feature = "lab")]
use values::parse_learn;
use values::{parse_on_off, parse_seconds};

#[cfg(test)]
#[path = "cli_tests.rs"]
mod tests;
