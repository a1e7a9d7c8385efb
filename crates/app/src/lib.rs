//! bounce, the application: the `bounce` command line (`render`, `info`, `compare`, `bench`, `view`) and
//! image output.
//!
//! Exit codes: 0 success; 2 bad input (unreadable or malformed scene, impossible settings, no usable
//! Vulkan device or validation layer: things the user fixes); 1 a runtime failure. Every error is one
//! line on stderr.

pub mod bench;
pub mod metrics;
pub mod output;
pub mod plot;
pub mod view;

use anyhow::{Context, Result};
use bounce_device::{Gpu, GpuOptions};
use bounce_graph::frame::{Component, FaceMode, FrameSettings, LightMap, Method, MisWeights, Renderer, Visibility};
use bounce_graph::scene::Scene;
use clap::{Parser, Subcommand, ValueEnum};
use output::RgbImage;
use std::ffi::OsString;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

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
    /// Error metrics of a test image against a reference image (both EXR).
    Compare(CompareArgs),
    /// Run time against error for methods × VPL counts: bench.csv, bench.md, time_vs_error.png.
    Bench(BenchArgs),
    /// Interactive viewer: fly camera, progressive accumulation, screenshots (needs a display).
    View(view::ViewArgs),
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ComponentArg {
    Direct,
    Indirect,
    Combined,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MethodArg {
    /// N VPLs per pixel, uniformly among the non-empty DPRSM texels.
    Uniform,
    /// Every VPL (the converged VPL estimate; slow, tiled, with a progress bar).
    All,
    /// Ritschel et al. 2011: a CDF from --cdf-samples random gather points.
    Global,
    /// The global CDF with its gather points spread over the 4 screen quarters (thesis §7.3.2).
    Stratified,
    /// One CDF per screen region (--regions), every pixel sampling all of them (thesis §7.3.3).
    Local,
    /// The gathering-based global CDF: --gather-rays cosine rays per pixel (thesis §7.3.4).
    Gbg,
    /// Cosine gathering (--gather-rays) and gbg CDF sampling (--vpls) by the balance heuristic (§7.4).
    Mis,
    /// The exact one-bounce integral: GPU path tracing against the triangles (BVH), --spp samples.
    Reference,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum VisibilityArg {
    /// Amanatides–Woo march through the voxel grid (the thesis's ch. 7).
    Voxel,
    /// Exact shadow rays against the triangles (BVH).
    Exact,
    /// Per-VPL paraboloid shadow maps (thesis ch. 6) for one shared set of --vpls VPLs per frame.
    Psm,
    /// The shared set of `psm` with exact shadow rays (the maps' own error).
    PsmExact,
    /// Exact shadow rays traced only through the voxel grid's occupied cells (`exact`'s answer).
    Hybrid,
}

fn visibility_of(v: VisibilityArg) -> Visibility {
    match v {
        VisibilityArg::Voxel => Visibility::Voxel,
        VisibilityArg::Exact => Visibility::Exact,
        VisibilityArg::Psm => Visibility::Psm,
        VisibilityArg::PsmExact => Visibility::PsmExact,
        VisibilityArg::Hybrid => Visibility::Hybrid,
    }
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightMapArg {
    /// Dual paraboloid RSM: two faces, every direction (the thesis's choice).
    Dprsm,
    /// One perspective RSM of --rsm-fov looking at the scene's centre (misses what lies outside).
    Rsm,
    /// Cube-map RSM: six 90° faces.
    Cube,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MisWeightsArg {
    /// Both densities in solid angle (unbiased).
    Consistent,
    /// The thesis's literal weights (mixed measures; for comparison).
    Thesis,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceArg {
    /// Russian roulette by each face's total importance (thesis alg. 9).
    Rr,
    /// Every face with importance equally likely (thesis alg. 4).
    Uniform,
}

#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Output EXR (linear float32 RGB).
    #[arg(long, default_value = "out.exr")]
    pub out: PathBuf,
    /// Also write a tone-mapped (Reinhard 2002) sRGB PNG.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Image width (default: the scene's [render] width, else 256).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default: the scene's [render] height, else 256).
    #[arg(long)]
    pub height: Option<u32>,
    #[arg(long, value_enum, default_value = "combined")]
    pub component: ComponentArg,
    /// How the gather picks VPLs.
    #[arg(long, value_enum, default_value = "uniform")]
    pub method: MethodArg,
    /// VPLs per pixel (sampled methods).
    #[arg(long, default_value_t = 64)]
    pub vpls: u32,
    /// Reflective DPRSM resolution per face (VPLs: 2 × lights × res²).
    #[arg(long, default_value_t = 512)]
    pub dprsm_res: u32,
    /// Voxels along the longest side of the scene (cubic cells).
    #[arg(long, default_value_t = 128)]
    pub voxels: u32,
    /// Clamp 1/d² below this distance, as a fraction of the scene diagonal (0: off, unbiased).
    #[arg(long, default_value_t = 0.0)]
    pub clamp: f32,
    /// Gather points per CDF (global, stratified, local).
    #[arg(long, default_value_t = 64)]
    pub cdf_samples: u32,
    /// Screen regions of `local` (a perfect square).
    #[arg(long, default_value_t = 4)]
    pub regions: u32,
    /// Cosine rays per gather point (gbg).
    #[arg(long, default_value_t = 4)]
    pub gather_rays: u32,
    /// Share of samples drawn uniformly among all VPLs by the CDF methods (keeps every VPL's pdf > 0).
    #[arg(long, default_value_t = 0.1)]
    pub defensive: f32,
    /// How CDF methods choose the paraboloid face.
    #[arg(long, value_enum, default_value = "rr")]
    pub face: FaceArg,
    /// MIS weights (--method mis).
    #[arg(long, value_enum, default_value = "consistent")]
    pub mis_weights: MisWeightsArg,
    /// Samples per pixel of --method reference (4096: its own noise is ≈ relMSE 0.002 on the default scene).
    #[arg(long, default_value_t = 4096)]
    pub spp: u32,
    /// Visibility of the VPL gather.
    #[arg(long, value_enum, default_value = "voxel")]
    pub visibility: VisibilityArg,
    /// Resolution of each per-VPL paraboloid shadow map (--visibility psm).
    #[arg(long, default_value_t = 256)]
    pub psm_res: u32,
    /// The VPL map at each light (its faces are --dprsm-res² each).
    #[arg(long, value_enum, default_value = "dprsm")]
    pub light_map: LightMapArg,
    /// Field of view of --light-map rsm, degrees.
    #[arg(long, default_value_t = 90.0)]
    pub rsm_fov: f32,
    /// Random seed (same seed, same image).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Seed of the importance's gather points and rays (default: --seed). `bounce view` keeps it fixed
    /// across its progressive frames.
    #[arg(long)]
    pub cdf_seed: Option<u64>,
    /// Use the first Vulkan device whose name contains this (also: BOUNCE_DEVICE).
    #[arg(long)]
    pub device: Option<String>,
    /// Enable the Vulkan validation layers; fail if they report anything.
    #[arg(long)]
    pub validation: bool,
    /// Print a per-pass GPU time table.
    #[arg(long)]
    pub timings: bool,
    /// Resolution per face of the paraboloid depth map used for direct-light shadows.
    #[arg(long, default_value_t = 2048)]
    pub shadow_res: u32,
}

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Output folder (also caches the reference image).
    #[arg(long)]
    pub out: PathBuf,
    /// Methods to sweep, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "uniform,global,stratified,local,gbg,mis")]
    pub methods: Vec<MethodArg>,
    /// VPL counts per pixel, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "16,64,256")]
    pub vpls: Vec<u32>,
    /// Frames (seeds 1..=K) per method and VPL count; medians are reported.
    #[arg(long, default_value_t = 3)]
    pub repeats: u32,
    #[arg(long, default_value_t = 128)]
    pub width: u32,
    #[arg(long, default_value_t = 128)]
    pub height: u32,
    /// Reflective DPRSM resolution per face.
    #[arg(long, default_value_t = 128)]
    pub dprsm_res: u32,
    #[arg(long, default_value_t = 128)]
    pub voxels: u32,
    #[arg(long, default_value_t = 0.0)]
    pub clamp: f32,
    #[arg(long)]
    pub device: Option<String>,
    #[arg(long)]
    pub validation: bool,
    /// What errors are measured against: the path-traced ground truth (`path`, --method reference) or
    /// the exhaustive VPL sum on the same VPL set (`all`: selection error alone).
    #[arg(long, value_enum, default_value = "path")]
    pub reference: ReferenceArg,
    /// Samples per pixel of the path-traced reference.
    #[arg(long, default_value_t = 4096)]
    pub reference_spp: u32,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReferenceArg {
    Path,
    All,
}

#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    pub test: PathBuf,
    pub reference: PathBuf,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Write the FLIP error map (magma colours) to this PNG.
    #[arg(long)]
    pub heatmap: Option<PathBuf>,
}

/// An error the user can fix by changing the input or the machine (exit code 2).
#[derive(Debug)]
struct BadInput(anyhow::Error);

impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:#}", self.0)
    }
}
impl std::error::Error for BadInput {}

fn bad(e: impl Into<anyhow::Error>) -> anyhow::Error {
    anyhow::Error::new(BadInput(e.into()))
}

fn gpu_error(e: bounce_device::Error) -> anyhow::Error {
    use bounce_device::Error as E;
    match e {
        E::Loader(_)
        | E::NoDevice(_)
        | E::NoMatchingDevice { .. }
        | E::MissingFeature { .. }
        | E::NoValidationLayer => bad(e),
        e => anyhow::Error::new(e).context("creating the Vulkan device"),
    }
}

/// Run the command line; returns the exit code. Output goes to `out`, the one-line error to `err`.
pub fn run(args: Vec<OsString>, out: &mut dyn Write, err: &mut dyn Write) -> i32 {
    let cli = match Cli::try_parse_from(args) {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let text = e.render().to_string();
            if code == 0 {
                let _ = write!(out, "{text}");
            } else {
                // clap's message is several lines; the first names the problem. One line, like every error.
                let first = text.lines().find(|l| !l.trim().is_empty()).unwrap_or("invalid arguments");
                let _ = writeln!(err, "error: {} (see `bounce --help`)", first.trim_start_matches("error: ").trim());
            }
            return code;
        }
    };
    let r = match cli.command {
        Command::Render(a) => render(&a, out, err),
        Command::Info => info(out),
        Command::Compare(a) => compare(&a, out),
        Command::Bench(a) => bench(&a, out, err),
        Command::View(a) => view::view(&a, out, err),
    };
    match r {
        Ok(()) => 0,
        Err(e) => {
            let one_line = format!("{e:#}").replace('\n', " ");
            let _ = writeln!(err, "error: {one_line}");
            if e.downcast_ref::<BadInput>().is_some() {
                2
            } else {
                1
            }
        }
    }
}

fn method_of(m: MethodArg) -> Method {
    match m {
        MethodArg::Uniform => Method::Uniform,
        MethodArg::All => Method::All,
        MethodArg::Global => Method::Global,
        MethodArg::Stratified => Method::Stratified,
        MethodArg::Local => Method::Local,
        MethodArg::Gbg => Method::Gbg,
        MethodArg::Mis => Method::Mis,
        MethodArg::Reference => Method::Reference,
    }
}

fn bench(a: &BenchArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    let scene = Scene::load(&a.scene).map_err(bad)?;
    writeln!(err, "{}", scene.summary())?;
    if a.methods.is_empty() || a.vpls.is_empty() || a.repeats == 0 {
        return Err(bad(anyhow::anyhow!("--methods, --vpls and --repeats must not be empty or zero")));
    }
    if a.methods.contains(&MethodArg::All) {
        return Err(bad(anyhow::anyhow!("`all` is the reference of `bounce bench`, not a method to sweep")));
    }
    let base = FrameSettings {
        width: a.width,
        height: a.height,
        component: Component::Indirect,
        dprsm_res: a.dprsm_res,
        voxels: a.voxels,
        clamp: a.clamp,
        ..FrameSettings::default()
    };
    let gpu = Gpu::new(&GpuOptions { validation: a.validation, device: a.device.clone(), ..GpuOptions::default() })
        .map_err(gpu_error)?;
    let mut renderer = Renderer::new(&gpu, &scene)?;
    for &n in &a.vpls {
        renderer.check(&FrameSettings { vpls: n, ..base.clone() }).map_err(bad)?;
    }
    let plan = bench::BenchPlan {
        methods: a.methods.iter().map(|m| method_of(*m)).collect(),
        vpls: a.vpls.clone(),
        repeats: a.repeats,
        base,
        reference: match a.reference {
            ReferenceArg::Path => bench::Reference::Path { spp: a.reference_spp },
            ReferenceArg::All => bench::Reference::All,
        },
    };
    let samples = bench::run(&mut renderer, &plan, &a.scene, &a.out, err)?;
    if a.validation {
        let msgs = gpu.validation().messages();
        anyhow::ensure!(msgs.is_empty(), "{} validation message(s); first: {}", msgs.len(), msgs[0]);
    }
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    bench::write_outputs(&a.out, &plan, &samples, &gpu.name, &command)?;
    writeln!(out, "{}", std::fs::read_to_string(a.out.join("bench.md")).unwrap_or_default())?;
    writeln!(err, "wrote {}/bench.csv, bench.md, time_vs_error.png", a.out.display())?;
    Ok(())
}

fn compare(a: &CompareArgs, out: &mut dyn Write) -> Result<()> {
    let (t, _) = output::read_exr(&a.test).map_err(bad)?;
    let (r, _) = output::read_exr(&a.reference).map_err(bad)?;
    if (t.width, t.height) != (r.width, r.height) {
        return Err(bad(anyhow::anyhow!(
            "{} is {}x{} but {} is {}x{}",
            a.test.display(),
            t.width,
            t.height,
            a.reference.display(),
            r.width,
            r.height
        )));
    }
    let m = metrics::Metrics::with_flip(&t, &r);
    if let Some(h) = &a.heatmap {
        let (_, map) = output::flip(&t, &r);
        output::write_png_bytes(h, t.width, t.height, map)?;
    }
    if a.json {
        writeln!(out, "{}", m.json())?;
    } else {
        writeln!(out, "{}", m.table())?;
    }
    Ok(())
}

fn info(out: &mut dyn Write) -> Result<()> {
    let devices = Gpu::enumerate().map_err(gpu_error)?;
    if devices.is_empty() {
        return Err(gpu_error(bounce_device::Error::NoDevice(String::new())));
    }
    for d in devices {
        writeln!(out, "{} ({:?}), Vulkan {}, driver {}", d.name, d.kind, d.api_version, d.driver)?;
        match &d.suitable {
            Ok(()) => writeln!(out, "  usable by bounce: yes")?,
            Err(what) => writeln!(out, "  usable by bounce: no (lacks {what})")?,
        }
        for (k, v) in &d.features {
            writeln!(out, "  feature {k}: {v}")?;
        }
        for (k, v) in &d.limits {
            writeln!(out, "  limit {k}: {v}")?;
        }
    }
    Ok(())
}

fn render(a: &RenderArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    let scene = Scene::load(&a.scene).map_err(bad)?;
    writeln!(err, "{}", scene.summary())?;
    let width = a.width.or(scene.render_width).unwrap_or(256);
    let height = a.height.or(scene.render_height).unwrap_or(256);
    let settings = FrameSettings {
        width,
        height,
        component: match a.component {
            ComponentArg::Direct => Component::Direct,
            ComponentArg::Indirect => Component::Indirect,
            ComponentArg::Combined => Component::Combined,
        },
        method: method_of(a.method),
        spp: a.spp,
        visibility: visibility_of(a.visibility),
        psm_res: a.psm_res,
        light_map: match a.light_map {
            LightMapArg::Dprsm => LightMap::Dprsm,
            LightMapArg::Rsm => LightMap::Rsm { fov_deg: a.rsm_fov },
            LightMapArg::Cube => LightMap::Cube,
        },
        mis_weights: match a.mis_weights {
            MisWeightsArg::Consistent => MisWeights::Consistent,
            MisWeightsArg::Thesis => MisWeights::Thesis,
        },
        cdf_samples: a.cdf_samples,
        regions: a.regions,
        gather_rays: a.gather_rays,
        defensive: a.defensive,
        face: match a.face {
            FaceArg::Rr => FaceMode::RussianRoulette,
            FaceArg::Uniform => FaceMode::Uniform,
        },
        vpls: a.vpls,
        seed: a.seed,
        cdf_seed: a.cdf_seed,
        dprsm_res: a.dprsm_res,
        shadow_res: a.shadow_res,
        voxels: a.voxels,
        clamp: a.clamp,
        ..FrameSettings::default()
    };
    let gpu = Gpu::new(&GpuOptions { validation: a.validation, device: a.device.clone(), ..GpuOptions::default() })
        .map_err(gpu_error)?;
    settings.validate(&gpu).map_err(bad)?;
    let mut renderer = Renderer::new(&gpu, &scene)?;
    renderer.check(&settings).map_err(bad)?;
    let t0 = Instant::now();
    let frame =
        renderer.render(&settings).map_err(
            |e| {
                if e.to_string().contains("needs the VPL passes") {
                    bad(e)
                } else {
                    e
                }
            },
        )?;
    let wall = t0.elapsed().as_secs_f64();
    for w in &frame.warnings {
        writeln!(err, "warning: {w}")?;
    }
    if let Some(se) = frame.stderr {
        writeln!(
            err,
            "reference: {} spp, standard error of the mean {se:.3e} (RMS over pixels and channels)",
            settings.spp
        )?;
    }
    if a.validation {
        let msgs = gpu.validation().messages();
        anyhow::ensure!(msgs.is_empty(), "{} validation message(s); first: {}", msgs.len(), msgs[0]);
    }
    let img = RgbImage::from_rgba(frame.width, frame.height, &frame.radiance);
    let bad_px = img.non_finite_count();
    if bad_px > 0 {
        writeln!(err, "warning: {bad_px} pixel(s) are not finite")?;
    }
    let gpu_ms = frame.gpu_ms();
    let meta = vec![
        ("scene", a.scene.display().to_string()),
        ("component", settings.component.name().to_string()),
        (
            "method",
            if settings.component == Component::Direct { "none".into() } else { settings.method.name().to_string() },
        ),
        ("vpls", settings.vpls.to_string()),
        ("voxels", settings.voxels.to_string()),
        ("clamp", settings.clamp.to_string()),
        ("visibility", format!("{:?}", settings.visibility).to_lowercase()),
        ("spp", settings.spp.to_string()),
        ("seed", a.seed.to_string()),
        ("device", gpu.name.clone()),
        ("gpu_ms", gpu_ms.map(|m| format!("{m:.3}")).unwrap_or_else(|| "n/a".into())),
        ("dprsm_res", settings.dprsm_res.to_string()),
        ("light_map", settings.light_map.name().to_string()),
        ("shadow_res", settings.shadow_res.to_string()),
        ("non_finite_pixels", bad_px.to_string()),
    ];
    output::write_exr(&a.out, &img, &meta)?;
    if let Some(p) = &a.png {
        output::write_png(p, &img)?;
    }
    if a.timings {
        writeln!(out, "{:<12} {:>10}", "pass", "GPU ms")?;
        for t in &frame.timings {
            let ms = t.ms.map(|m| format!("{m:10.3}")).unwrap_or_else(|| format!("{:>10}", "n/a"));
            writeln!(out, "{:<12} {ms}", t.name)?;
        }
        for s in &frame.skipped {
            writeln!(out, "{s:<12} {:>10}", "skipped")?;
        }
        let total = gpu_ms.map(|m| format!("{m:10.3}")).unwrap_or_else(|| format!("{:>10}", "n/a"));
        writeln!(out, "{:<12} {total}", "total")?;
        if settings.visibility.shared_set() && settings.component != Component::Direct {
            let bytes = bounce_graph::passes::psm::Psm::bytes(settings.vpls, settings.psm_res);
            writeln!(
                out,
                "psm maps: {} × {}² depth = {:.1} MiB (bound {} MiB)",
                settings.vpls,
                settings.psm_res,
                bytes as f64 / 1048576.0,
                bounce_graph::passes::psm::MAX_PSM_BYTES >> 20
            )?;
        }
        writeln!(out, "wall {wall:.3} s on {}", gpu.name)?;
    }
    writeln!(
        err,
        "wrote {}{}",
        a.out.display(),
        a.png.as_ref().map(|p| format!(" and {}", p.display())).unwrap_or_default()
    )
    .context("writing to stderr")?;
    Ok(())
}
