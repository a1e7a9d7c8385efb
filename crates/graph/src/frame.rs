//! The frame recipe. [`build_frame`] is the one place that says what runs, in what order, on what data:
//! gbuffer → dprsm (+ its depth map) → direct → voxelize → importance → cdf_reduce → [psm_select → psm]
//! → gather (or mis), handles flowing from call to call. Passes whose outputs the asked component does
//! not need are culled by the graph (`--component direct` records no VPL pass). [`Renderer`] owns the
//! passes (their pipelines), the uploaded scene, the voxel grid (built once per scene and grid size)
//! and two caches that let a frame import instead of record: the light cache (the VPL maps, the shadow
//! map and `uniform`'s validity CDF: kept until the map settings change, lights being fixed) and the
//! frame cache (G-buffer, direct light, importance, CDF: kept while the camera and settings stay).
//! [`Renderer::render`] builds, executes and reads back one frame.

use crate::gpu_scene::GpuScene;
use crate::graph::{Graph, Handle, PassTiming, Persistent};
use crate::passes::cdf_reduce::CdfReduce;
use crate::passes::dprsm::{Dprsm, DprsmDepth, DprsmOut};
use crate::passes::gather::{Gather, GatherInputs};
use crate::passes::importance::{Importance, ImportanceKind, ImportanceOut, ImportanceParams};
use crate::passes::voxelize::{self, VoxelGridSpec, Voxelize};
use crate::passes::{direct::Direct, gbuffer::GBuffer, FrameInputs};
use crate::scene::Scene;
use crate::shader_types::{FrameUniforms, GatherPush};
use anyhow::{bail, Context, Result};
use bounce_device::{vk, Buffer, BufferDesc, Gpu, Image, ImageDesc, MemoryLocation};
use std::cell::RefCell;

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
    /// Thesis §7.3.3: one CDF per screen region, all sampled by every pixel (a mixture: no seams).
    Local,
    /// Thesis §7.3.4: the gathering-based global CDF (cosine rays, per-texel averages, median holes).
    Gbg,
    /// Thesis §7.4: cosine gathering and gbg CDF sampling combined by the balance heuristic.
    Mis,
    /// The exact one-bounce integral (BVH path tracing, `spp` samples): the ground truth.
    Reference,
}

/// How the VPL gather tests visibility.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Visibility {
    /// Amanatides–Woo march through the voxel grid (the thesis).
    Voxel,
    /// Shadow rays against the triangles (BVH): separates the voxel error from the rest.
    Exact,
    /// Per-VPL paraboloid shadow maps (thesis ch. 6) for a shared set of `vpls` VPLs per frame
    /// (`passes/psm.rs`).
    Psm,
    /// The shared set of `Psm` with exact shadow rays: the maps' own error, on identical VPLs.
    PsmExact,
}

impl Visibility {
    /// Whether the gather's shadow rays go through the BVH.
    pub fn uses_bvh(self) -> bool {
        matches!(self, Visibility::Exact | Visibility::PsmExact)
    }
    /// Whether the frame gathers a shared VPL set (`Psm`, `PsmExact`).
    pub fn shared_set(self) -> bool {
        matches!(self, Visibility::Psm | Visibility::PsmExact)
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
    fn tan_half_fov(self) -> f32 {
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
    pub const ALL: [Method; 8] = [
        Method::Uniform,
        Method::All,
        Method::Global,
        Method::Stratified,
        Method::Local,
        Method::Gbg,
        Method::Mis,
        Method::Reference,
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
    /// VPLs per tile of the exhaustive (`all`) gather: one submission each.
    pub all_tile: u32,
    /// Gather points per CDF (global, stratified, local).
    pub cdf_samples: u32,
    /// Screen regions of `local` (a perfect square: side × side).
    pub regions: u32,
    /// Cosine rays per gather point (gbg).
    pub gather_rays: u32,
    /// Share of samples drawn uniformly among the VPLs by the CDF methods (defensive sampling).
    pub defensive: f32,
    pub face: FaceMode,
    pub mis_weights: MisWeights,
    /// Samples per pixel of the reference integrator.
    pub spp: u32,
    pub visibility: Visibility,
    /// Resolution per face of the paraboloid depth map used for direct-light visibility. It is separate
    /// from the reflective map's (VPL) resolution: shadow outlines want fine texels, the VPL count
    /// wants few. 2048 keeps outline errors below relMSE 1e-3 on the default scene at 64².
    pub shadow_res: u32,
    /// Constant shadow bias, as a fraction of the scene diagonal.
    pub shadow_bias: f32,
    /// Slope shadow bias, in texels.
    pub shadow_slope_bias: f32,
}

impl Default for FrameSettings {
    fn default() -> Self {
        FrameSettings {
            width: 256,
            height: 256,
            component: Component::Direct,
            method: Method::Uniform,
            vpls: 64,
            seed: 1,
            cdf_seed: None,
            psm_res: 256,
            light_map: LightMap::Dprsm,
            dprsm_res: 512,
            voxels: 128,
            clamp: 0.0,
            all_tile: 4096,
            cdf_samples: 64,
            regions: 4,
            gather_rays: 4,
            defensive: 0.1,
            face: FaceMode::RussianRoulette,
            mis_weights: MisWeights::Consistent,
            spp: 4096,
            visibility: Visibility::Voxel,
            shadow_res: 2048,
            shadow_bias: 1e-5,
            shadow_slope_bias: 1.5,
        }
    }
}

impl FrameSettings {
    /// Reject impossible settings with a message naming the setting and the device limit.
    pub fn validate(&self, gpu: &Gpu) -> Result<()> {
        let max = gpu.limits().max_image_dimension2_d;
        for (what, v) in [
            ("width", self.width),
            ("height", self.height),
            ("shadow map resolution", self.shadow_res),
            ("DPRSM resolution", self.dprsm_res),
        ] {
            if v == 0 {
                bail!("{what} must be at least 1");
            }
            if v > max {
                bail!("{what} {v} exceeds the device limit maxImageDimension2D ({max})");
            }
        }
        if self.vpls == 0 {
            bail!("the VPL count must be at least 1");
        }
        if let LightMap::Rsm { fov_deg } = self.light_map {
            if !(fov_deg.is_finite() && fov_deg > 0.0 && fov_deg < 180.0) {
                bail!("--rsm-fov must be in (0, 180) degrees (got {fov_deg})");
            }
        }
        if self.visibility.shared_set() {
            if self.method == Method::All && self.component != Component::Direct {
                bail!("--visibility psm needs a sampled method (`all` would need a shadow map per VPL slot)");
            }
            if self.psm_res == 0 || self.psm_res > max {
                bail!("--psm-res must be between 1 and maxImageDimension2D ({max}) (got {})", self.psm_res);
            }
            let layers = gpu.limits().max_image_array_layers;
            if self.vpls > layers {
                bail!(
                    "--visibility psm renders one map per VPL: {} VPLs exceed maxImageArrayLayers ({layers})",
                    self.vpls
                );
            }
            let bytes = crate::passes::psm::Psm::bytes(self.vpls, self.psm_res);
            if bytes > crate::passes::psm::MAX_PSM_BYTES {
                bail!(
                    "{} shadow maps of {}² take {} MiB, over the {} MiB bound: lower --vpls or --psm-res",
                    self.vpls,
                    self.psm_res,
                    bytes >> 20,
                    crate::passes::psm::MAX_PSM_BYTES >> 20
                );
            }
        }
        if self.spp == 0 {
            bail!("--spp must be at least 1");
        }
        if !(1..=1024).contains(&self.voxels) {
            bail!("voxels must be between 1 and 1024 (got {})", self.voxels);
        }
        if self.all_tile == 0 {
            bail!("the tile size must be at least 1");
        }
        if !(1..=4096).contains(&self.cdf_samples) {
            bail!("--cdf-samples must be between 1 and 4096 (got {})", self.cdf_samples);
        }
        let side = (self.regions as f64).sqrt().round() as u32;
        if self.regions == 0 || side * side != self.regions || side > 8 {
            bail!("--regions must be a perfect square from 1 to 64 (got {})", self.regions);
        }
        if !(1..=256).contains(&self.gather_rays) {
            bail!("--gather-rays must be between 1 and 256 (got {})", self.gather_rays);
        }
        if !(self.defensive.is_finite() && (0.0..=1.0).contains(&self.defensive)) {
            bail!("--defensive must be in [0, 1] (got {})", self.defensive);
        }
        if !(self.clamp.is_finite() && (0.0..1.0).contains(&self.clamp)) {
            bail!("the clamp must be a fraction of the scene diagonal in [0, 1) (got {})", self.clamp);
        }
        let ok = |v: f32| v.is_finite() && v >= 0.0;
        if !ok(self.shadow_bias) || !ok(self.shadow_slope_bias) {
            bail!("shadow biases must be finite and non-negative");
        }
        Ok(())
    }
}

/// What a frame's static products (G-buffer, VPL maps, direct light, importance, CDF) depend on. The
/// lights are fixed for a `Renderer`; the camera ([`Renderer::set_camera`]) and everything else that
/// feeds those passes is here.
#[derive(Clone, Debug, PartialEq)]
struct CacheKey {
    camera: crate::camera::Camera,
    width: u32,
    height: u32,
    combined: bool,
    dprsm_res: u32,
    shadow_res: u32,
    voxels: u32,
    shadow_bias_bits: (u32, u32),
    importance: ImportanceKind,
    cdf_samples: u32,
    min_d2_bits: u32,
    /// The importance's random seed, for the kinds that draw gather points or rays.
    importance_seed: Option<u32>,
}

/// The static products of the last sampled frame, kept so that a frame whose [`CacheKey`] is unchanged
/// records only the gather ("skip what a scene does not need"). The VPL maps are in the [`LightCache`].
pub struct FrameCache {
    key: CacheKey,
    /// G-buffer position, normal, albedo; then the direct image if combined.
    images: Vec<Persistent<Image>>,
    /// `None` for `uniform`, whose importance and CDF (the VPLs' validity) live in the light cache.
    importance: Option<Persistent<Buffer>>,
    cdf: Option<Persistent<Buffer>>,
    sections: u32,
}

/// The light-side products: the reflective DPRSM (VPL position, normal, flux) and the direct light's
/// shadow map. They depend on the lights (fixed for a `Renderer`) and the two map resolutions only, so
/// a camera move keeps them: only the G-buffer, direct light, importance and CDF are redone.
pub struct LightCache {
    /// [`light_key`].
    key: (u32, u32, &'static str, u32),
    vpls: Vec<Persistent<Image>>,
    /// Kept when the frame computed direct light (the indirect component alone never renders it).
    shadow: Option<Persistent<Image>>,
    /// `uniform`'s importance and CDF: the VPLs' validity, which depends on the maps alone, so a camera
    /// move does not redo them (once a uniform frame has made them).
    uniform: Option<(Persistent<Buffer>, Persistent<Buffer>)>,
}

/// The voxel grid of the scene: built once per grid size, reused by every frame and method.
struct VoxelState {
    voxels: u32,
    buffer: Persistent<Buffer>,
    built: bool,
}

/// Owns the passes, the uploaded scene and the voxel grid.
pub struct Renderer {
    pub gpu: Gpu,
    pub scene: GpuScene,
    pub camera: crate::camera::Camera,
    /// The largest intensity component of any light (for the gbg fixed-point scale).
    max_intensity: f32,
    gbuffer: GBuffer,
    dprsm: Dprsm,
    direct: Direct,
    voxelize: Voxelize,
    importance: Importance,
    cdf_reduce: CdfReduce,
    gather: Gather,
    mis: Gather,
    psm: crate::passes::psm::Psm,
    reference: crate::passes::reference::Reference,
    /// The scene's triangles, kept for the BVH (built on first use by the reference).
    vertices: Vec<crate::shader_types::Vertex>,
    bvh: std::cell::OnceCell<crate::bvh::GpuBvh>,
    voxel_state: RefCell<Option<VoxelState>>,
    frame_cache: RefCell<Option<FrameCache>>,
    light_cache: RefCell<Option<LightCache>>,
}

/// A rendered frame, read back.
pub struct FrameOutput {
    pub width: u32,
    pub height: u32,
    /// RGBA32F radiance, row-major, row 0 = top.
    pub radiance: Vec<[f32; 4]>,
    /// Per pass GPU times; passes recorded several times (tiles) appear once per recording.
    pub timings: Vec<PassTiming>,
    pub ran: Vec<&'static str>,
    pub skipped: Vec<&'static str>,
    /// Things the user should know about this frame (e.g. an all-zero importance).
    pub warnings: Vec<String>,
    /// The reference integrator's own Monte Carlo error: the RMS over pixels and channels of the standard
    /// error of the mean (indirect component only).
    pub stderr: Option<f64>,
}

impl FrameOutput {
    pub fn gpu_ms(&self) -> Option<f64> {
        self.timings.iter().map(|t| t.ms).sum()
    }
}

/// What [`build_frame`] hands back: the image to read and, for the exhaustive method, what the tiled
/// gathers read.
pub struct FrameHandles {
    /// The image of the asked component (for `all` with VPLs: `None`; the tiles produce it).
    pub out: Option<Handle<Image>>,
    /// The VPL maps and shadow map when this graph renders them (not imported from a [`LightCache`]).
    pub fresh_light: Option<(DprsmOut, DprsmDepth)>,
    /// `uniform`'s importance and CDF were computed by this graph (not imported from the light cache).
    pub fresh_uniform: bool,
    pub direct: Handle<Image>,
    pub gather_inputs: GatherInputs,
}

/// The frame recipe.
pub fn build_frame<'a>(
    r: &'a Renderer,
    g: &mut Graph<'a>,
    f: FrameInputs<'a>,
    s: &FrameSettings,
    mut voxels: Handle<Buffer>,
    voxels_built: bool,
    cached: Option<&'a FrameCache>,
    light: Option<&'a LightCache>,
) -> FrameHandles {
    if !voxels_built {
        r.voxelize.add(g, f, &mut voxels);
    }
    let rows = f.vpl_faces * f.scene.light_count * f.dprsm_res;
    // The light side: imported when the lights' maps are cached, else rendered (and handed back).
    let mut fresh_light = None;
    let (vpls, shadow) = match light {
        Some(l) => (
            DprsmOut {
                position: g.import_image(&l.vpls[0]),
                normal: g.import_image(&l.vpls[1]),
                flux: g.import_image(&l.vpls[2]),
            },
            l.shadow.as_ref().map(|p| DprsmDepth { depth: g.import_image(p) }),
        ),
        None => {
            let v = r.dprsm.add(g, f);
            let d = r.dprsm.add_depth(g, f);
            fresh_light = Some((v, d));
            (v, Some(d))
        }
    };
    let uniform_kind = r.importance_params(s).kind == ImportanceKind::Uniform;
    let cached_uniform = if uniform_kind { light.and_then(|l| l.uniform.as_ref()) } else { None };
    let mut fresh_uniform = false;
    let (gather_inputs, direct, imp) = match cached {
        // Nothing these passes read has changed since the cached frame: import their results instead.
        Some(c) => {
            let im: Vec<Handle<Image>> = c.images.iter().map(|p| g.import_image(p)).collect();
            let inputs = GatherInputs {
                g_position: im[0],
                g_normal: im[1],
                g_albedo: im[2],
                vpl_position: vpls.position,
                vpl_normal: vpls.normal,
                vpl_flux: vpls.flux,
                voxels,
                importance: match (&c.importance, cached_uniform) {
                    (Some(i), _) => g.import_buffer(i),
                    (None, Some((i, _))) => g.import_buffer(i),
                    (None, None) => unreachable!("a uniform frame cache hit needs the light cache's CDF"),
                },
                cdf: match (&c.cdf, cached_uniform) {
                    (Some(x), _) => g.import_buffer(x),
                    (None, Some((_, x))) => g.import_buffer(x),
                    (None, None) => unreachable!("a uniform frame cache hit needs the light cache's CDF"),
                },
                direct: im.get(3).copied(),
                psm: None,
            };
            let imp = ImportanceOut { importance: inputs.importance, sections: c.sections };
            (inputs, im.get(3).copied().unwrap_or(im[2]), imp)
        }
        None => {
            let gbuffer = r.gbuffer.add(g, f);
            // A light cache kept without the shadow map (an indirect frame's): the direct pass that
            // needs it is then unread too and culled with it.
            let shadow = shadow.unwrap_or_else(|| r.dprsm.add_depth(g, f));
            let direct = r.direct.add(g, f, &gbuffer, &shadow);
            let (imp, cdf) = match cached_uniform {
                Some((i, c)) => (ImportanceOut { importance: g.import_buffer(i), sections: 1 }, g.import_buffer(c)),
                None => {
                    fresh_uniform = uniform_kind;
                    let imp = r.importance.add(g, f, &gbuffer, &vpls, &voxels, r.importance_params(s));
                    let cdf = r.cdf_reduce.add(g, &imp.importance, rows, f.dprsm_res, imp.sections);
                    (imp, cdf)
                }
            };
            let inputs = GatherInputs::new(
                &gbuffer,
                &vpls,
                voxels,
                imp.importance,
                cdf,
                (s.component == Component::Combined).then_some(direct),
            );
            (inputs, direct, imp)
        }
    };
    let out = match (s.component, s.method) {
        (Component::Direct, _) => Some(direct),
        (_, Method::All) => None,
        (_, _) => {
            let mut out = g.create_image(radiance_desc("gather.radiance", f.width, f.height));
            let push = GatherPush {
                mode: crate::bindings::GATHER_SAMPLE,
                samples: s.vpls,
                first: 0,
                last: s.vpls,
                seed: seed32(s.seed),
                add_direct: (s.component == Component::Combined) as u32,
                clamp_d2: clamp_d2(s, f.scene),
                sections: imp.sections - 1,
                defensive: if s.method == Method::Uniform { 0.0 } else { s.defensive },
                face_mode: match s.face {
                    FaceMode::RussianRoulette => crate::bindings::FACE_RR,
                    FaceMode::Uniform => crate::bindings::FACE_UNIFORM,
                },
                cdf_len: CdfReduce::section_len(rows, f.dprsm_res) as u32,
                rays: s.gather_rays,
                ..GatherPush::default()
            };
            if s.method == Method::Mis {
                let push = GatherPush {
                    mode: match s.mis_weights {
                        MisWeights::Consistent => crate::bindings::MIS_CONSISTENT,
                        MisWeights::Thesis => crate::bindings::MIS_THESIS,
                    },
                    last: s.vpls + s.gather_rays,
                    ..push
                };
                if s.visibility.shared_set() {
                    // The CDF samples are the shared set (passes/psm.rs); the gathering rays stay per pixel.
                    let psm = r.psm.add(g, f, &vpls, gather_inputs.importance, gather_inputs.cdf, s.psm_res, push);
                    let inputs = GatherInputs { psm: Some(psm), ..gather_inputs };
                    r.mis.add(g, f, &inputs, &mut out, push);
                } else {
                    r.mis.add(g, f, &gather_inputs, &mut out, push);
                }
            } else if s.visibility.shared_set() {
                // One shared VPL set (and its shadow maps) for every pixel: passes/psm.rs.
                let psm = r.psm.add(g, f, &vpls, gather_inputs.importance, gather_inputs.cdf, s.psm_res, push);
                let inputs = GatherInputs { psm: Some(psm), ..gather_inputs };
                r.gather.add(g, f, &inputs, &mut out, push);
            } else {
                r.gather.add(g, f, &gather_inputs, &mut out, push);
            }
            Some(out)
        }
    };
    FrameHandles { out, fresh_light, fresh_uniform, direct, gather_inputs }
}

fn radiance_desc(name: &str, w: u32, h: u32) -> ImageDesc {
    ImageDesc::new(
        name,
        w,
        h,
        crate::passes::direct::RADIANCE_FORMAT,
        vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC,
    )
}

/// What the light-side products depend on besides the lights: the map resolutions and the VPL map.
fn light_key(s: &FrameSettings) -> (u32, u32, &'static str, u32) {
    (s.dprsm_res, s.shadow_res, s.light_map.name(), s.light_map.tan_half_fov().to_bits())
}

/// Fold a 64-bit seed into the shader's 32-bit one.
fn seed32(seed: u64) -> u32 {
    (seed ^ (seed >> 32)) as u32
}

fn clamp_d2(s: &FrameSettings, scene: &GpuScene) -> f32 {
    let d = s.clamp * scene.diagonal();
    d * d
}

impl Renderer {
    pub fn new(gpu: &Gpu, scene: &Scene) -> Result<Self> {
        let textured = !scene.textures.is_empty();
        Ok(Renderer {
            gpu: gpu.clone(),
            scene: GpuScene::upload(gpu, scene).context("uploading the scene")?,
            camera: scene.camera,
            max_intensity: scene.lights.iter().flat_map(|l| l.intensity[..3].to_vec()).fold(0.0, f32::max),
            // Untextured scenes get the shader variants without texture fetches.
            gbuffer: GBuffer::new(gpu, textured).context("creating the gbuffer pass")?,
            dprsm: Dprsm::new(gpu, textured).context("creating the dprsm pass")?,
            direct: Direct::new(gpu).context("creating the direct pass")?,
            voxelize: Voxelize::new(gpu).context("creating the voxelize pass")?,
            importance: Importance::new(gpu).context("creating the importance pass")?,
            cdf_reduce: CdfReduce::new(gpu).context("creating the cdf_reduce pass")?,
            gather: Gather::new(gpu).context("creating the gather pass")?,
            mis: crate::passes::mis::create(gpu).context("creating the mis pass")?,
            psm: crate::passes::psm::Psm::new(gpu).context("creating the psm pass")?,
            reference: crate::passes::reference::Reference::new(gpu, textured)
                .context("creating the reference pass")?,
            vertices: scene.vertices.clone(),
            bvh: std::cell::OnceCell::new(),
            voxel_state: RefCell::new(None),
            frame_cache: RefCell::new(None),
            light_cache: RefCell::new(None),
        })
    }

    /// VPLs per gather dispatch under the device's loop iteration limit. Per VPL an invocation loops at
    /// most: the march's steps (≤ dims.x + dims.y + dims.z + 3; its small loops are unrolled, one loop
    /// iteration per cell) and the CDF's two binary searches (≤ 2 · 32), plus 64 for the rest;
    /// another 64 are kept for the loops outside.
    pub fn vpls_per_dispatch(&self, s: &FrameSettings) -> u32 {
        let Some(limit) = self.gpu.loop_iteration_limit else { return u32::MAX };
        let dims = self.voxel_spec(s).dims;
        // Sampling adds loops over the CDF sections and, with uniform face choice, over the faces.
        let sections = 1 + self.importance_params(s).kind.method_sections();
        let faces = s.light_map.faces() * self.scene.light_count;
        let march = match (s.visibility, self.bvh.get()) {
            (v, Some(b)) if v.uses_bvh() => b.max_iterations_per_ray(),
            _ => dims.x + dims.y + dims.z + 3,
        };
        let per_vpl = march + 64 + 2 * 32 + 3 * sections + 2 * faces * (sections + 1);
        // MIS: a CDF sample adds one march (its gathering indicator); a gathering ray marches once to
        // its hit and then, per light, does a CDF sample's work (visibility march, probability look-up).
        let per_vpl = if s.method == Method::Mis {
            (per_vpl + march + 64).max(march + 64 + self.scene.light_count * per_vpl)
        } else {
            per_vpl
        };
        ((limit.saturating_sub(64)) / per_vpl).max(1)
    }

    /// Moves the camera (the viewer's fly camera). The next frame re-records what depends on it.
    pub fn set_camera(&mut self, camera: crate::camera::Camera) {
        self.camera = camera;
    }

    /// Forget the cached static products: the next frame records every pass it needs. `bounce bench`
    /// does this before each timed frame, so that every method pays for its full frame.
    pub fn clear_frame_cache(&self) {
        *self.frame_cache.borrow_mut() = None;
        *self.light_cache.borrow_mut() = None;
    }

    fn cache_key(&self, s: &FrameSettings) -> CacheKey {
        let p = self.importance_params(s);
        CacheKey {
            camera: self.camera,
            width: s.width,
            height: s.height,
            combined: s.component == Component::Combined,
            dprsm_res: s.dprsm_res,
            shadow_res: s.shadow_res,
            voxels: s.voxels,
            shadow_bias_bits: (s.shadow_bias.to_bits(), s.shadow_slope_bias.to_bits()),
            importance: p.kind,
            cdf_samples: s.cdf_samples,
            min_d2_bits: p.min_d2.to_bits(),
            importance_seed: (p.kind != ImportanceKind::Uniform).then_some(p.seed),
        }
    }

    /// The importance pass's parameters for `s`.
    pub fn importance_params(&self, s: &FrameSettings) -> ImportanceParams {
        let cell = self.voxel_spec(s).cell;
        let min_d = cell.max(s.clamp * self.scene.diagonal());
        // gbg fixed point: a contribution of c_ref (the largest a VPL can give at distance min_d:
        // albedo ≤ 1, the texel of largest solid angle 4·(2/res)², the brightest light) maps to 2³²;
        // smaller ones keep ≥ 2³²·(min_d/d)² units, plenty for a weight.
        let i_max = self.max_intensity.max(1e-30);
        let c_ref = i_max * 4.0 * (2.0 / s.dprsm_res as f32).powi(2) / (std::f32::consts::PI.powi(2) * min_d * min_d);
        ImportanceParams {
            kind: match s.method {
                Method::Uniform | Method::All | Method::Reference => ImportanceKind::Uniform,
                Method::Global => ImportanceKind::Global,
                Method::Stratified => ImportanceKind::Stratified,
                Method::Local => ImportanceKind::Local { side: (s.regions as f64).sqrt().round() as u32 },
                Method::Gbg | Method::Mis => ImportanceKind::Gbg { rays: s.gather_rays },
            },
            samples: s.cdf_samples,
            seed: seed32(s.cdf_seed.unwrap_or(s.seed) ^ 0xC0FFEE),
            min_d2: min_d * min_d,
            fixed_scale: (4294967296.0 / c_ref as f64).min(f32::MAX as f64) as f32,
        }
    }

    /// The voxel grid spec for `s` (fitted to the bounds of geometry and lights).
    pub fn voxel_spec(&self, s: &FrameSettings) -> VoxelGridSpec {
        voxelize::fit(self.scene.bounds_min, self.scene.bounds_max, s.voxels)
    }

    /// The per-frame constants for `s`.
    pub fn uniforms(&self, s: &FrameSettings) -> FrameUniforms {
        let diag = self.scene.diagonal();
        let eye = self.camera.eye;
        // Camera far plane: beyond the farthest corner of the bounds; near: a small fraction of it.
        let (lo, hi) = (self.scene.bounds_min, self.scene.bounds_max);
        let mut far_cam = 0.0f32;
        for k in 0..8 {
            let c = glam::Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            far_cam = far_cam.max((c - eye).length());
        }
        let far_cam = far_cam.max(diag) * 1.01;
        let near = far_cam * 1e-5;
        // Paraboloid far: no light-to-surface distance exceeds the diagonal of bounds that hold both.
        let far_light = diag * 1.01;
        let (voxel_origin, voxel_dims) = self.voxel_spec(s).uniforms_fields();
        let vpl_slots = s.light_map.faces() * self.scene.light_count * s.dprsm_res * s.dprsm_res;
        FrameUniforms {
            // near and far swapped: reverse Z (see passes/gbuffer.rs).
            view_proj: self.camera.view_proj(s.width, s.height, far_cam, near).to_cols_array_2d(),
            eye: [eye.x, eye.y, eye.z, 0.0],
            scene_min: [lo.x, lo.y, lo.z, diag],
            scene_max: [hi.x, hi.y, hi.z, far_light],
            size: [s.width, s.height, self.scene.light_count, s.dprsm_res],
            maps: [s.shadow_res, vpl_slots, s.psm_res, s.vpls],
            light_map: [
                match s.light_map {
                    LightMap::Dprsm => crate::bindings::LIGHT_MAP_DPRSM,
                    LightMap::Rsm { .. } => crate::bindings::LIGHT_MAP_RSM,
                    LightMap::Cube => crate::bindings::LIGHT_MAP_CUBE,
                },
                s.light_map.faces(),
                s.light_map.tan_half_fov().to_bits(),
                0,
            ],
            shadow: [s.shadow_bias * diag, s.shadow_slope_bias, 0.0, 0.0],
            voxel_origin,
            voxel_dims,
        }
    }

    /// The per-frame inputs every pass reads, for settings `s` and their uniform buffer.
    fn frame_inputs<'a>(&'a self, s: &FrameSettings, uniforms: &'a Buffer) -> FrameInputs<'a> {
        FrameInputs {
            bvh: if s.visibility.uses_bvh() { self.bvh.get() } else { None },
            scene: &self.scene,
            uniforms,
            width: s.width,
            height: s.height,
            shadow_res: s.shadow_res,
            dprsm_res: s.dprsm_res,
            vpl_faces: s.light_map.faces(),
            vpls_per_dispatch: self.vpls_per_dispatch(s),
        }
    }

    /// A host-visible uniform buffer holding [`Renderer::uniforms`] (written once, before recording).
    fn uniform_buffer(&self, s: &FrameSettings) -> Result<Buffer> {
        let mut uniforms = Buffer::new(
            &self.gpu,
            &BufferDesc {
                name: "frame uniforms".into(),
                size: std::mem::size_of::<FrameUniforms>() as u64,
                usage: vk::BufferUsageFlags::UNIFORM_BUFFER,
                location: MemoryLocation::CpuToGpu,
            },
        )?;
        uniforms
            .mapped_mut()
            .context("uniform buffer is not host-visible")?
            .copy_from_slice(bytemuck::bytes_of(&self.uniforms(s)));
        Ok(uniforms)
    }

    /// Memory the paraboloid depth maps take: 2 faces × lights × res² × 4 bytes.
    pub fn shadow_map_bytes(&self, s: &FrameSettings) -> u64 {
        2 * self.scene.light_count as u64 * (s.shadow_res as u64).pow(2) * 4
    }

    /// Memory the reflective DPRSM takes: 3 RGBA32F images + depth, plus importance and CDF.
    pub fn dprsm_bytes(&self, s: &FrameSettings) -> u64 {
        s.light_map.faces() as u64 * self.scene.light_count as u64 * (s.dprsm_res as u64).pow(2) * (3 * 16 + 4 + 4 + 4)
    }

    /// Reject settings this device or scene cannot run (bad input, not a runtime failure).
    pub fn check(&self, s: &FrameSettings) -> Result<()> {
        s.validate(&self.gpu)?;
        const MAX_MAP_BYTES: u64 = 2 << 30;
        for (what, bytes, flag) in [
            ("shadow maps", self.shadow_map_bytes(s), "--shadow-res"),
            ("reflective DPRSM", self.dprsm_bytes(s), "--dprsm-res"),
        ] {
            if bytes > MAX_MAP_BYTES {
                bail!(
                    "the {what} would take {} MiB ({} lights); lower {flag} (limit {} MiB)",
                    bytes >> 20,
                    self.scene.light_count,
                    MAX_MAP_BYTES >> 20
                );
            }
        }
        let max_range = self.gpu.limits().max_storage_buffer_range as u64;
        let cdf_bytes = 4
            * (s.light_map.faces() as u64 * self.scene.light_count as u64 * (s.dprsm_res as u64).pow(2)
                + s.light_map.faces() as u64 * self.scene.light_count as u64 * s.dprsm_res as u64
                + 4);
        if cdf_bytes > max_range {
            bail!("the CDF would take {cdf_bytes} bytes, over the device limit maxStorageBufferRange ({max_range}); lower --dprsm-res");
        }
        Ok(())
    }

    /// Make sure the voxel grid for `s` exists (not necessarily built yet).
    fn ensure_voxels(&self, s: &FrameSettings) -> Result<()> {
        let mut st = self.voxel_state.borrow_mut();
        if st.as_ref().is_some_and(|v| v.voxels == s.voxels) {
            return Ok(());
        }
        let spec = self.voxel_spec(s);
        let buffer = voxelize::create_grid_buffer(&self.gpu, &spec)?;
        *st = Some(VoxelState { voxels: s.voxels, buffer: Persistent::new(buffer), built: false });
        Ok(())
    }

    /// Build, execute and read back one frame. `progress(done, total)` is called between the tiles of
    /// the exhaustive method.
    pub fn render(&self, s: &FrameSettings) -> Result<FrameOutput> {
        self.render_with_progress(s, &mut |_, _| {})
    }

    pub fn render_with_progress(&self, s: &FrameSettings, progress: &mut dyn FnMut(u64, u64)) -> Result<FrameOutput> {
        self.check(s)?;
        if s.visibility.uses_bvh() {
            self.bvh()?;
        }
        if s.method == Method::Reference && s.component != Component::Direct {
            return self.render_reference(s, progress);
        }
        self.ensure_voxels(s)?;
        let uniforms = self.uniform_buffer(s)?;
        let f = self.frame_inputs(s, &uniforms);
        let vox_guard = self.voxel_state.borrow();
        let vox = vox_guard.as_ref().expect("ensure_voxels made the grid");
        // Sampled indirect/combined frames keep their static products for the next frame.
        let cacheable = s.component != Component::Direct && s.method != Method::All;
        let key = self.cache_key(s);
        let needs_shadow = s.component == Component::Combined;
        let light_guard = self.light_cache.borrow();
        let light_hit = light_guard
            .as_ref()
            .filter(|l| cacheable && l.key == light_key(s) && (l.shadow.is_some() || !needs_shadow));
        let cache_guard = self.frame_cache.borrow();
        let uniform_kind = self.importance_params(s).kind == ImportanceKind::Uniform;
        let hit = cache_guard
            .as_ref()
            .filter(|c| cacheable && c.key == key && light_hit.is_some_and(|l| !uniform_kind || l.uniform.is_some()));
        let mut g = Graph::new(&self.gpu);
        let voxels = g.import_buffer(&vox.buffer);
        let h = build_frame(self, &mut g, f, s, voxels, vox.built, hit, light_hit);
        let keep_products = cacheable && hit.is_none();
        let keep_light = cacheable && h.fresh_light.is_some();
        let keep_uniform = cacheable && h.fresh_uniform;
        if keep_products {
            for img in h.gather_inputs.camera_images() {
                g.export(&img);
            }
        }
        if (keep_products && !uniform_kind) || keep_uniform {
            g.export(&h.gather_inputs.importance);
            g.export(&h.gather_inputs.cdf);
        }
        if keep_light {
            let (v, d) = h.fresh_light.expect("checked");
            for img in [v.position, v.normal, v.flux] {
                g.export(&img);
            }
            if needs_shadow {
                g.export(&d.depth);
            }
        }
        if let Some(out) = &h.out {
            g.export(out);
        } else {
            // The tiles read these after this graph has run.
            for img in h.gather_inputs.images() {
                g.export(&img);
            }
            for b in h.gather_inputs.buffers() {
                g.export(&b);
            }
        }
        let mut done = g.execute()?;
        let voxelized = done.ran.contains(&"voxelize");
        let mut timings = done.timings.clone();
        let mut ran = done.ran.clone();
        let skipped = done.skipped.clone();
        let mut warnings = vec![];
        if let LightMap::Rsm { fov_deg } = s.light_map {
            let omega = s.light_map.solid_angle();
            let missing = 1.0 - omega / (4.0 * std::f64::consts::PI);
            warnings.push(format!(
                "rsm ({fov_deg}° field of view): the map covers {omega:.3} sr around each light, so {:.1} % of each light's emitted flux (I · (4π − Ω) = {:.3} W per W/sr) reaches no VPL",
                100.0 * missing,
                4.0 * std::f64::consts::PI - omega
            ));
        }
        let mut new_cache = None;
        let mut new_light = None;
        let mut new_uniform = None;
        let method_sections = self.importance_params(s).kind.method_sections();
        let radiance_bytes = if let Some(out) = &h.out {
            // Checked on the frame that builds the CDF (a cached one was checked when it was built, and a
            // viewer frame should not read it back again). Only the section headers are needed, but a
            // whole readback is cheap next to a frame that ran the importance.
            if s.component != Component::Direct && method_sections > 0 && hit.is_none() {
                let cdf: Vec<f32> = bytemuck::pod_collect_to_vec(&done.read_buffer(&h.gather_inputs.cdf)?);
                let len =
                    CdfReduce::section_len(s.light_map.faces() * self.scene.light_count * s.dprsm_res, s.dprsm_res)
                        as usize;
                let live =
                    (1..=method_sections as usize).filter(|k| cdf.get(k * len).is_some_and(|t| *t > 0.0)).count();
                if live == 0 {
                    warnings.push(format!(
                        "the {} importance is zero for every VPL; sampling uniformly instead",
                        s.method.name()
                    ));
                }
            }
            let bytes = done.read_image(out)?;
            if keep_light {
                let (v, d) = h.fresh_light.expect("checked");
                let vpls = [v.position, v.normal, v.flux].iter().map(|x| done.take_image(x)).collect::<Result<_>>()?;
                let shadow = if needs_shadow { Some(done.take_image(&d.depth)?) } else { None };
                new_light = Some(LightCache { key: light_key(s), vpls, shadow, uniform: None });
            }
            if keep_uniform {
                let i = &h.gather_inputs;
                new_uniform = Some((done.take_buffer(&i.importance)?, done.take_buffer(&i.cdf)?));
            }
            if keep_products {
                let i = h.gather_inputs;
                let images: Vec<Persistent<Image>> =
                    i.camera_images().iter().map(|x| done.take_image(x)).collect::<Result<_>>()?;
                let (importance, cdf) = if uniform_kind {
                    (None, None)
                } else {
                    (Some(done.take_buffer(&i.importance)?), Some(done.take_buffer(&i.cdf)?))
                };
                new_cache =
                    Some(FrameCache { key: key.clone(), images, importance, cdf, sections: method_sections + 1 });
            }
            bytes
        } else {
            // Keep what the tiles read: each tile is its own graph (and submission) importing these.
            let i = h.gather_inputs;
            let kept: Vec<Persistent<Image>> = i.images().iter().map(|x| done.take_image(x)).collect::<Result<_>>()?;
            let importance = done.take_buffer(&i.importance)?;
            let cdf = done.take_buffer(&i.cdf)?;
            drop(done);
            let out = Persistent::new(Image::new(&self.gpu, &radiance_desc("gather.radiance", s.width, s.height))?);
            let total = s.light_map.faces() * self.scene.light_count * s.dprsm_res * s.dprsm_res;
            let mut first = 0u32;
            loop {
                let last = first.saturating_add(s.all_tile).min(total);
                let mut g = Graph::new(&self.gpu);
                let imported: Vec<Handle<Image>> = kept.iter().map(|p| g.import_image(p)).collect();
                let inputs = GatherInputs {
                    g_position: imported[0],
                    g_normal: imported[1],
                    g_albedo: imported[2],
                    vpl_position: imported[3],
                    vpl_normal: imported[4],
                    vpl_flux: imported[5],
                    voxels: g.import_buffer(&vox.buffer),
                    importance: g.import_buffer(&importance),
                    cdf: g.import_buffer(&cdf),
                    direct: imported.get(6).copied(),
                    psm: None,
                };
                let mut o = g.import_image(&out);
                let push = GatherPush {
                    mode: crate::bindings::GATHER_ALL,
                    samples: 1,
                    seed: seed32(s.seed),
                    first,
                    last,
                    accumulate: (first > 0) as u32,
                    add_direct: (first == 0 && s.component == Component::Combined) as u32,
                    clamp_d2: clamp_d2(s, &self.scene),
                    ..GatherPush::default()
                };
                self.gather.add(&mut g, f, &inputs, &mut o, push);
                g.export(&o);
                let d = g.execute()?;
                timings.extend(d.timings.iter().cloned());
                ran.extend(d.ran.iter().copied());
                progress(last as u64, total as u64);
                first = last;
                if first >= total {
                    break d.read_image(&o)?;
                }
            }
        };
        drop(vox_guard);
        drop(cache_guard);
        drop(light_guard);
        if new_light.is_some() {
            *self.light_cache.borrow_mut() = new_light;
        }
        if new_uniform.is_some() {
            if let Some(l) = self.light_cache.borrow_mut().as_mut() {
                l.uniform = new_uniform;
            }
        }
        if voxelized {
            self.voxel_state.borrow_mut().as_mut().expect("grid exists").built = true;
        }
        if new_cache.is_some() {
            *self.frame_cache.borrow_mut() = new_cache;
        }
        Ok(FrameOutput {
            width: s.width,
            height: s.height,
            radiance: bytemuck::pod_collect_to_vec(&radiance_bytes),
            timings,
            ran,
            skipped,
            warnings,
            stderr: None,
        })
    }

    /// The voxel grid as built on the GPU (its spec and occupancy bytes), if a frame has built it.
    pub fn voxel_grid(&self) -> Result<Option<(VoxelGridSpec, Vec<u8>)>> {
        let st = self.voxel_state.borrow();
        let Some(v) = st.as_ref().filter(|v| v.built) else { return Ok(None) };
        let bytes = v.buffer.res.read_back(v.buffer.last_access())?;
        Ok(Some((self.voxel_spec(&FrameSettings { voxels: v.voxels, ..FrameSettings::default() }), bytes)))
    }

    /// The BVH of the scene, built on first use.
    pub fn bvh(&self) -> Result<&crate::bvh::GpuBvh> {
        if self.bvh.get().is_none() {
            let cpu = crate::bvh::Bvh::from_vertices(&self.vertices);
            let flat = crate::bvh::FlatBvh::new(&cpu, &self.vertices);
            let _ = self.bvh.set(crate::bvh::GpuBvh::upload(&self.gpu, &flat).context("uploading the BVH")?);
        }
        Ok(self.bvh.get().expect("set above"))
    }

    /// The exact one-bounce integral by GPU path tracing (`--method reference`): `s.spp` cosine bounce
    /// samples per pixel in chunks (one submission each, `progress` between them), with its own standard
    /// error in [`FrameOutput::stderr`].
    fn render_reference(&self, s: &FrameSettings, progress: &mut dyn FnMut(u64, u64)) -> Result<FrameOutput> {
        use crate::passes::reference::{Reference, ReferenceIo};
        let bvh = self.bvh()?;
        let uniforms = self.uniform_buffer(s)?;
        let f = self.frame_inputs(s, &uniforms);
        let combined = s.component == Component::Combined;
        let mut g = Graph::new(&self.gpu);
        let gb = self.gbuffer.add(&mut g, f);
        let direct = combined.then(|| {
            let shadow = self.dprsm.add_depth(&mut g, f);
            self.direct.add(&mut g, f, &gb, &shadow)
        });
        let mut keep = vec![gb.position, gb.normal, gb.albedo];
        keep.extend(direct);
        for h in &keep {
            g.export(h);
        }
        let mut done = g.execute()?;
        let mut timings = done.timings.clone();
        let mut ran = done.ran.clone();
        let skipped = done.skipped.clone();
        let kept: Vec<Persistent<Image>> = keep.iter().map(|h| done.take_image(h)).collect::<Result<_>>()?;
        drop(done);
        let sum = Persistent::new(Image::new(&self.gpu, &radiance_desc("reference.sum", s.width, s.height))?);
        let sq = Persistent::new(Image::new(&self.gpu, &radiance_desc("reference.sq", s.width, s.height))?);
        let per_dispatch = Reference::per_dispatch(&self.gpu, bvh, self.scene.light_count);
        // Enough samples per submission to keep the GPU busy, few enough for a live progress bar.
        let per_submit = per_dispatch.saturating_mul(4).clamp(1, 64);
        let mut first = 0u32;
        let (sum_bytes, sq_bytes) = loop {
            let last = first.saturating_add(per_submit).min(s.spp);
            let mut g = Graph::new(&self.gpu);
            let imported: Vec<Handle<Image>> = kept.iter().map(|p| g.import_image(p)).collect();
            let io = ReferenceIo {
                g_position: imported[0],
                g_normal: imported[1],
                g_albedo: imported[2],
                direct: imported.get(3).copied(),
            };
            let (mut hs, mut hq) = (g.import_image(&sum), g.import_image(&sq));
            let push = GatherPush {
                samples: s.spp,
                seed: seed32(s.seed),
                first,
                last,
                accumulate: (first > 0) as u32,
                add_direct: (first == 0 && combined) as u32,
                ..GatherPush::default()
            };
            self.reference.add(&mut g, f, bvh, io, &mut hs, &mut hq, push, per_dispatch);
            g.export(&hs);
            g.export(&hq);
            let d = g.execute()?;
            timings.extend(d.timings.iter().cloned());
            ran.extend(d.ran.iter().copied());
            progress(last as u64, s.spp as u64);
            first = last;
            if first >= s.spp {
                break (d.read_image(&hs)?, d.read_image(&hq)?);
            }
        };
        let radiance: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&sum_bytes);
        let second: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&sq_bytes);
        // Standard error of the mean per pixel and channel, sqrt((E[L²] − E[L]²) / (N − 1)), for the
        // indirect component (the combined image's mean also holds the exact direct light).
        let n = s.spp.max(2) as f64;
        let (mut se2, mut count) = (0.0f64, 0usize);
        if !combined {
            for (m, q) in radiance.iter().zip(&second) {
                for c in 0..3 {
                    se2 += ((q[c] as f64 - (m[c] as f64).powi(2)).max(0.0)) / (n - 1.0);
                    count += 1;
                }
            }
        }
        let stderr = (count > 0).then(|| (se2 / count as f64).sqrt());
        Ok(FrameOutput { width: s.width, height: s.height, radiance, timings, ran, skipped, warnings: vec![], stderr })
    }

    /// Render one product of the dual paraboloid maps alone (for tests and diagnostics).
    pub fn render_dprsm(&self, s: &FrameSettings) -> Result<Vec<f32>> {
        self.check(s)?;
        let uniforms = self.uniform_buffer(s)?;
        let f = self.frame_inputs(s, &uniforms);
        let mut g = Graph::new(&self.gpu);
        let shadow = self.dprsm.add_depth(&mut g, f);
        g.export(&shadow.depth);
        let done = g.execute()?;
        Ok(bytemuck::pod_collect_to_vec(&done.read_image(&shadow.depth)?))
    }

    /// The reflective DPRSM read back: (position, normal, flux) RGBA32F per texel, layer after layer.
    pub fn render_vpls(&self, s: &FrameSettings) -> Result<[Vec<[f32; 4]>; 3]> {
        self.check(s)?;
        let uniforms = self.uniform_buffer(s)?;
        let f = self.frame_inputs(s, &uniforms);
        let mut g = Graph::new(&self.gpu);
        let v = self.dprsm.add(&mut g, f);
        for h in [&v.position, &v.normal, &v.flux] {
            g.export(h);
        }
        let done = g.execute()?;
        let read =
            |h: &Handle<Image>| -> Result<Vec<[f32; 4]>> { Ok(bytemuck::pod_collect_to_vec(&done.read_image(h)?)) };
        Ok([read(&v.position)?, read(&v.normal)?, read(&v.flux)?])
    }
}
