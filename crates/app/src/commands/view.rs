//! `bounce view`: the interactive viewer. A winit window with an ash-window surface and a swapchain
//! (`bounce_device::Swapchain`); each redraw renders one frame with the same `Renderer` as
//! `bounce render` and presents it on the GPU (`Renderer::present`, passes/present.rs): the present pass
//! adds it to a running mean while camera, lights and settings stay put (progressive accumulation,
//! frame k after a change with seed `--seed + k`, or for the reference samples k · spp … of one
//! sequence: `progressive::frame_settings`, as `render --time-limit`), tone-maps the mean (Reinhard,
//! as the PNG output) into an 8-bit image, and the swapchain copies that image in. No frame is read back to the host
//! except a screenshot's. What does not change is not re-rendered: the renderer's frame cache keeps the G-buffer,
//! the paraboloid maps, the direct light, the importance and the CDF, so a static frame records only
//! the gather (the title names what was reused).
//!
//! Controls: left-drag looks around, W/A/S/D move, Q/E down/up (speed ∝ the scene's diagonal, Shift ×4);
//! Tab selects the next light, the arrow keys move it in the horizontal plane and PageUp/PageDown up
//! and down (the camera's speed), [ and ] scale its intensity by 0.8 and 1.25; M cycles the sampling
//! method, +/− double/halve the VPL count, C cycles the component, Space toggles accumulation, P writes
//! a screenshot (PNG + EXR of the linear mean), Esc quits. The title shows method, VPLs, frames
//! accumulated, the selected light, frame time and the slowest passes' GPU times (after an untimed
//! warm-up frame, as `render` runs one, so that the first frame's do not hold the driver's shader
//! compilation).
//!
//! `--light-path orbit[:PERIOD]|FILE.toml` moves the lights by script (`crate::light_path`): frame k
//! of the run puts them where the path says. `--temporal` picks the seeds (`cli::Temporal`): with
//! `coherent` (the default) every frame after a change starts again from `--seed`, so a moving light's
//! frames share their random numbers; `fresh` gives frame k of the run `--seed + k`.
//!
//! When the camera or a light stops, the still view's new mean carries the last real-time frame, per
//! pixel as many frames' worth as its error against the still frames' noise warrants, fading out over
//! its first 32 frames (`Prior`, passes/present.rs): the picture goes on from the denoised frame instead
//! of breaking into one still frame's noise, and is the plain mean after. A screenshot is what the
//! picture shows (its EXR's `carries_last_real_time_frame` says whether the prior was in it).
//!
//! A still view's frames move on to a new VPL set as `render --time-limit`'s do (`progressive::VplSets`:
//! the light side at most 1/28 of the time), so that the mean converges to the one-bounce image, not
//! to one set's VPL sum; a move goes on with the set the maps hold, and `--cdf-seed` keeps one set.
//!
//! `--frames N --screenshot out.png` renders N frames, writes the screenshot (and `out.exr`) and exits:
//! for scripts and tests (under Xvfb on lavapipe). With `--cdf-seed C` the mean of those N frames is the
//! mean of `bounce render --seed S+k --cdf-seed C` for k < N with the same settings (the reference's
//! frames continue one sequence of seed S instead): the frames share one CDF and one VPL set, so the
//! light-side passes run only when the camera or a setting changes. The frame flags are `render`'s, with
//! cheaper defaults (`cli::ViewArgs`).
//!
//! The screenshot reads the GPU's running mean back once (f32 sums: equal to the mean of the frames
//! `render` makes, bit for bit) and writes it as EXR and, tone-mapped on the host, as PNG; the log line
//! says how many copies to host memory the whole run made.

use crate::camera_path::CameraPath;
use crate::cli::{ViewArgs, VIEW_FALLBACK_SIZE};
use crate::error::{self, bad};
use crate::light_path::LightPath;
use crate::output::{self, RgbImage};
use anyhow::{Context, Result};
use bounce_device::{vk, Gpu, GpuOptions, Image, Presented, Swapchain};
use bounce_graph::camera::Camera;
use bounce_graph::frame::progressive::{frame_settings, VplSets};
use bounce_graph::frame::{Component, FrameOutput, FrameSettings, Method, Renderer};
use bounce_graph::graph::Persistent;
use bounce_graph::passes::present::{Present, PresentParams, Prior};
use bounce_graph::scene::Scene;
use glam::Vec3;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use std::collections::HashSet;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// The methods M cycles through: the sampled ones, back to ris (the default), then the path tracer.
const CYCLE: [Method; 8] = [
    Method::Uniform,
    Method::Global,
    Method::Stratified,
    Method::Local,
    Method::Gbg,
    Method::Mis,
    Method::Ris,
    Method::Reference,
];

pub fn run(a: &ViewArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    if a.frames == Some(0) {
        return Err(bad(anyhow::anyhow!("--frames must be at least 1")));
    }
    if a.frames.is_some() != a.screenshot.is_some() {
        return Err(bad(anyhow::anyhow!("--frames and --screenshot go together")));
    }
    if let Some(png) = &a.screenshot {
        if png.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
            return Err(bad(anyhow::anyhow!(
                "--screenshot names the PNG (the EXR goes next to it, as .exr): got {}",
                png.display()
            )));
        }
        output::check_destination(png, "png").map_err(bad)?;
        output::check_destination(&png.with_extension("exr"), "exr").map_err(bad)?;
    }
    let vpls = a.picture.vpls.unwrap_or(bounce_graph::frame::FrameSettings::default().vpls);
    if !(1..=4096).contains(&vpls) {
        return Err(bad(anyhow::anyhow!("--vpls must be between 1 and 4096 (got {vpls})")));
    }
    let scene = super::load_scene(&a.scene, err)?;
    // Without a display winit cannot start; say what to do instead of its own message alone.
    let event_loop = EventLoop::new().map_err(|e| {
        bad(anyhow::anyhow!(
            "no display to open a window on ({e}); run it in a desktop session, under `xvfb-run`, or use `bounce render`"
        ))
    })?;
    let settings = FrameSettings {
        // One CDF for all progressive frames: the importance is redone only when the camera moves.
        cdf_seed: Some(a.frame.cdf_seed.unwrap_or(a.picture.seed)),
        ..a.picture.settings(&a.frame, &scene, VIEW_FALLBACK_SIZE)
    };
    if matches!(settings.method, Method::All) {
        return Err(bad(anyhow::anyhow!("`all` is not progressive; view a sampled method or use `bounce render`")));
    }
    if a.animation.moves() && a.frames.is_none() {
        return Err(bad(anyhow::anyhow!("--light-path and --camera-path need --frames (and --screenshot)")));
    }
    let path = a.animation.light_path.as_deref().map(|p| LightPath::parse(p, &scene)).transpose()?;
    let camera = a.animation.camera_path.as_deref().map(|p| CameraPath::parse(p, &scene)).transpose()?;
    // Without --method the viewer is real time while anything moves (ris accumulates while nothing does);
    // --method realtime is real time always; any other method is what was asked, every frame.
    let realtime = match a.picture.method {
        None | Some(Method::Realtime) => Some(settings.method == Method::Realtime),
        Some(_) => None,
    };
    let mut app =
        Viewer { args: a, scene: &scene, settings, realtime, path, camera, state: None, error: None, log: vec![] };
    event_loop.run_app(&mut app).context("running the window's event loop")?;
    for line in &app.log {
        writeln!(out, "{line}")?;
    }
    if let Some(e) = app.error {
        return Err(e);
    }
    Ok(())
}

struct Viewer<'a> {
    args: &'a ViewArgs,
    scene: &'a Scene,
    settings: FrameSettings,
    /// `Some(always)`: frames are `realtime` (denoised, never accumulated) while the camera or a light
    /// moves, and always where `always`; `None`: every frame is `settings.method`'s.
    realtime: Option<bool>,
    /// `--light-path`: where the lights are at each frame of the run.
    path: Option<LightPath>,
    /// `--camera-path`: where the camera is at each frame of the run (the fly camera's keys then do
    /// nothing).
    camera: Option<CameraPath>,
    state: Option<State>,
    error: Option<anyhow::Error>,
    /// Lines for stdout after the window closes (screenshots written).
    log: Vec<String>,
}

/// Everything that lives with the window. Field order is drop order: the swapchain (and its surface)
/// before the window it presents to.
struct State {
    swapchain: Swapchain,
    renderer: Renderer,
    gpu: Gpu,
    window: Window,
    fly: Fly,
    lamp: Lamp,
    /// The present pass's 8-bit picture, copied into the swapchain.
    ldr: Persistent<Image>,
    /// Frames in the running mean (since the last change), and since the start.
    frames: u32,
    /// The running mean's VPL sets, as `render --time-limit` draws them.
    vpl_sets: VplSets,
    total: u32,
    /// Frames rendered by `realtime` (while moving).
    realtime_frames: u32,
    /// The last frame was a real-time one (the present pass kept it), and the running mean is a still
    /// view's after such a frame (it carries it: passes/present.rs, a stop).
    last_realtime: bool,
    prior_running: bool,
    /// Copies to host memory before the first frame (the run's count is reported against it).
    readbacks: u64,
    accumulate: bool,
    /// P was pressed: the next frame reads its mean back and writes a screenshot.
    shot_requested: bool,
    last: Instant,
    /// The passes the first frame after a change ran: what a static frame reuses is the difference.
    full_passes: Vec<&'static str>,
    shots: u32,
    minimized: bool,
}

/// Moves the camera and the lights for a frame `dt` seconds after the last (their paths, else the keys
/// held down); whether either moved. A move restarts the mean, whether a path or a key made it.
fn step_motion(camera: Option<&CameraPath>, path: Option<&LightPath>, st: &mut State, dt: f32) -> bool {
    let mut moved = false;
    match camera {
        Some(c) => {
            let before = st.renderer.camera();
            c.apply(&mut st.renderer, st.total);
            // Past its last key the path holds the camera still: the mean goes on.
            if st.renderer.camera() != before {
                (st.frames, moved) = (0, true);
            }
        }
        None if st.fly.step(dt) => {
            st.renderer.set_camera(st.fly.camera());
            (st.frames, moved) = (0, true);
        }
        None => {}
    }
    let before = st.renderer.lights().to_vec();
    match path {
        Some(p) => p.apply(&mut st.renderer, st.total),
        None => _ = st.lamp.step(&st.fly.keys, &mut st.renderer, dt),
    }
    if st.renderer.lights() != before.as_slice() {
        (st.frames, moved) = (0, true);
    }
    moved
}

/// The fly camera: position, yaw about +Y, pitch, and the input held down.
struct Fly {
    eye: Vec3,
    yaw: f32,
    pitch: f32,
    fov_y_deg: f32,
    speed: f32,
    keys: HashSet<KeyCode>,
    dragging: bool,
    cursor: Option<(f64, f64)>,
    moved: bool,
}

impl Fly {
    fn new(c: &Camera, diagonal: f32) -> Fly {
        let f = (c.target - c.eye).normalize();
        Fly {
            eye: c.eye,
            yaw: f.x.atan2(f.z),
            pitch: f.y.clamp(-1.0, 1.0).asin(),
            fov_y_deg: c.fov_y_deg,
            speed: 0.3 * diagonal,
            keys: HashSet::new(),
            dragging: false,
            cursor: None,
            moved: false,
        }
    }
    fn forward(&self) -> Vec3 {
        Vec3::new(self.pitch.cos() * self.yaw.sin(), self.pitch.sin(), self.pitch.cos() * self.yaw.cos())
    }
    fn camera(&self) -> Camera {
        Camera { eye: self.eye, target: self.eye + self.forward(), up: Vec3::Y, fov_y_deg: self.fov_y_deg }
    }
    /// Moves by the held keys over `dt` seconds; whether anything moved.
    fn step(&mut self, dt: f32) -> bool {
        let f = self.forward();
        let right = f.cross(Vec3::Y).normalize_or_zero();
        let mut d = Vec3::ZERO;
        for (k, v) in [
            (KeyCode::KeyW, f),
            (KeyCode::KeyS, -f),
            (KeyCode::KeyD, right),
            (KeyCode::KeyA, -right),
            (KeyCode::KeyE, Vec3::Y),
            (KeyCode::KeyQ, -Vec3::Y),
        ] {
            if self.keys.contains(&k) {
                d += v;
            }
        }
        let fast =
            if self.keys.contains(&KeyCode::ShiftLeft) || self.keys.contains(&KeyCode::ShiftRight) { 4.0 } else { 1.0 };
        if d != Vec3::ZERO {
            self.eye += d.normalize() * self.speed * fast * dt.min(0.5);
            self.moved = true;
        }
        std::mem::take(&mut self.moved)
    }
}

/// The selected light and the keys that move it: arrows in the horizontal plane, PageUp/PageDown up and
/// down, at the camera's speed; the light stays inside the scene's bounds (the voxel grid's and the
/// paraboloid far plane's, fitted once).
struct Lamp {
    selected: usize,
    speed: f32,
    lo: Vec3,
    hi: Vec3,
}

impl Lamp {
    fn new(scene: &Scene, r: &Renderer) -> Lamp {
        Lamp { selected: 0, speed: 0.3 * scene.diagonal(), lo: r.scene.bounds_min, hi: r.scene.bounds_max }
    }

    /// Moves the selected light by the held keys over `dt` seconds; whether it moved.
    fn step(&self, keys: &HashSet<KeyCode>, r: &mut Renderer, dt: f32) -> bool {
        let mut d = Vec3::ZERO;
        for (k, v) in [
            (KeyCode::ArrowRight, Vec3::X),
            (KeyCode::ArrowLeft, -Vec3::X),
            (KeyCode::ArrowDown, Vec3::Z),
            (KeyCode::ArrowUp, -Vec3::Z),
            (KeyCode::PageUp, Vec3::Y),
            (KeyCode::PageDown, -Vec3::Y),
        ] {
            if keys.contains(&k) {
                d += v;
            }
        }
        if d == Vec3::ZERO {
            return false;
        }
        let (p, i) = light(r, self.selected);
        let to = (p + d.normalize() * self.speed * dt.min(0.5)).clamp(self.lo, self.hi);
        r.set_light(self.selected, to, i);
        to != p
    }

    /// Scales the selected light's intensity.
    fn scale(&self, r: &mut Renderer, factor: f32) {
        let (p, i) = light(r, self.selected);
        r.set_light(self.selected, p, i * factor);
    }

    /// The title's words for the selected light.
    fn describe(&self, r: &Renderer) -> String {
        let (p, i) = light(r, self.selected);
        format!(
            "light {}/{} at ({:.2}, {:.2}, {:.2}) I {:.2}",
            self.selected + 1,
            r.lights().len(),
            p.x,
            p.y,
            p.z,
            i.max_element()
        )
    }
}

/// Position and intensity of light `i`.
fn light(r: &Renderer, i: usize) -> (Vec3, Vec3) {
    let l = r.lights()[i];
    (Vec3::from_slice(&l.position[..3]), Vec3::from_slice(&l.intensity[..3]))
}

impl Viewer<'_> {
    fn start(&mut self, el: &ActiveEventLoop) -> Result<State> {
        let attrs = Window::default_attributes()
            .with_title("bounce view")
            .with_inner_size(PhysicalSize::new(self.settings.width, self.settings.height));
        let window = el.create_window(attrs).context("creating the window")?;
        let display = window.display_handle().context("the window's display handle")?.as_raw();
        let handle = window.window_handle().context("the window's handle")?.as_raw();
        let exts = ash_window::enumerate_required_extensions(display)
            .map_err(|r| bad(anyhow::anyhow!("this window system has no Vulkan surface support ({r:?})")))?;
        // ash-window gives 'static extension names (its own constants).
        let exts = exts.iter().map(|&p| unsafe { std::ffi::CStr::from_ptr(p) }).collect();
        let gpu = Gpu::new(&GpuOptions { instance_extensions: exts, swapchain: true, ..self.args.frame.gpu_options() })
            .map_err(error::device)?;
        self.settings.validate(&gpu)?;
        let surface = unsafe { ash_window::create_surface(&gpu.entry, &gpu.instance, display, handle, None) }
            .map_err(|r| anyhow::anyhow!("vkCreate*SurfaceKHR failed: {r:?}"))?;
        let size = window.inner_size();
        let swapchain =
            Swapchain::new(&gpu, surface, size.width, size.height, !self.args.no_vsync).map_err(error::device)?;
        self.settings.width = swapchain.extent.width;
        self.settings.height = swapchain.extent.height;
        let mut renderer = Renderer::new(&gpu, self.scene)?;
        renderer.check(&self.settings)?;
        // As `render` does: a driver that compiles a shader at its first dispatch does it here, so the
        // first frame's title shows its passes' own times.
        renderer.warm_up(&frame_settings(&self.settings, 0, 0))?;
        if self.realtime.is_some() {
            // The real-time frame's pipelines too, so that the first move does not stall on them.
            renderer.warm_up(&FrameSettings { method: Method::Realtime, ..self.settings.clone() })?;
        }
        let fly = Fly::new(&self.scene.camera, self.scene.diagonal());
        let lamp = Lamp::new(self.scene, &renderer);
        let ldr = Present::ldr_image(&gpu, self.settings.width, self.settings.height)?;
        Ok(State {
            swapchain,
            renderer,
            readbacks: gpu.readbacks(),
            gpu,
            window,
            fly,
            lamp,
            ldr,
            frames: 0,
            vpl_sets: VplSets::new(&self.settings),
            total: 0,
            realtime_frames: 0,
            last_realtime: false,
            prior_running: false,
            accumulate: true,
            shot_requested: false,
            last: Instant::now(),
            full_passes: vec![],
            shots: 0,
            minimized: false,
        })
    }

    /// Renders, accumulates and presents one frame; `Ok(true)` when `--frames` is reached.
    fn redraw(&mut self) -> Result<bool> {
        let st = self.state.as_mut().expect("started");
        if st.minimized {
            return Ok(false);
        }
        let now = Instant::now();
        let dt = (now - st.last).as_secs_f32();
        st.last = now;
        let moved = step_motion(self.camera.as_ref(), self.path.as_ref(), st, dt);
        let realtime = self.realtime.is_some_and(|always| always || moved);
        if !st.accumulate {
            st.frames = 0;
        }
        let last = self.args.frames.is_some_and(|n| st.total + 1 >= n);
        let shot = last || std::mem::take(&mut st.shot_requested);
        // The run's seed where this accumulation began, then its frame st.frames as `render --time-limit`
        // takes it (seed + k; the reference: the next samples of one sequence).
        let seed = self.args.animation.temporal().seed(self.settings.seed, st.total.saturating_sub(st.frames), 0);
        if st.frames == 0 {
            st.vpl_sets.restart(&self.settings);
        }
        // Every frame on the current VPL set, so that a move does not redraw the maps.
        let still = frame_settings(&FrameSettings { seed, ..self.settings.clone() }, st.frames, st.vpl_sets.set());
        let s = match realtime {
            // One real-time frame, shown alone: its history lives in the renderer, not in the mean.
            true => FrameSettings { method: Method::Realtime, vpl_seed: still.vpl_seed, ..self.settings.clone() },
            false => still,
        };
        // A real-time frame is kept; the still view's mean right after it carries it for its first frames,
        // so that the picture does not break into one frame's noise when the view stops.
        if !realtime && st.frames == 0 {
            st.prior_running = st.last_realtime && st.accumulate;
        }
        let prior = match (realtime, st.prior_running) {
            (true, _) => Prior::Keep,
            (false, true) => Prior::Use,
            (false, false) => Prior::None,
        };
        st.last_realtime = realtime;
        let params = PresentParams {
            frames: st.frames + 1,
            reset: st.frames == 0,
            exposure: 1.0,
            swap_rb: st.swapchain.format == vk::Format::B8G8R8A8_UNORM,
            prior,
        };
        let t0 = Instant::now();
        let f = st.renderer.present(&s, &st.ldr, params, shot)?;
        let frame_ms = t0.elapsed().as_secs_f64() * 1e3;
        if st.frames == 0 {
            st.full_passes = f.ran.clone();
        }
        if !realtime {
            st.vpl_sets.frame_done(frame_ms / 1e3);
        }
        st.frames += 1;
        st.total += 1;
        if realtime {
            // The next still frame starts a new mean.
            st.frames = 0;
            st.realtime_frames += 1;
        }
        // What this frame's picture is: a real-time frame alone, or the mean of st.frames still frames.
        let shown = (s.method, if realtime { 1 } else { st.frames });
        let (presented, access) =
            st.swapchain.present_image(&st.ldr.res, st.ldr.last_access()).map_err(error::device)?;
        st.ldr.set_last_access(access);
        if presented == Presented::OutOfDate {
            let size = st.window.inner_size();
            self.resize(size.width, size.height)?;
        }
        self.set_title(&f, frame_ms);
        if shot {
            self.take_screenshot(&f, shown, last, params.carries_prior())?;
        }
        Ok(last)
    }

    /// The screenshot of this frame: `--screenshot`'s after the last of `--frames`, else (P) under the next
    /// name no earlier screenshot holds; one of those that cannot be written is said, and the session (and
    /// its mean) goes on.
    fn take_screenshot(&mut self, f: &FrameOutput, shown: (Method, u32), last: bool, prior: bool) -> Result<()> {
        if let (Some(p), true) = (&self.args.screenshot, last) {
            return self.screenshot(&p.clone(), f, shown, prior);
        }
        let st = self.state.as_mut().expect("started");
        let path = loop {
            st.shots += 1;
            let p = PathBuf::from(format!("bounce-screenshot-{}.png", st.shots));
            if !p.exists() && !p.with_extension("exr").exists() {
                break p;
            }
        };
        if let Err(e) = self.screenshot(&path, f, shown, prior) {
            self.log.push(format!("screenshot not written: {e:#}"));
        }
        Ok(())
    }

    /// The title: method, VPLs, component, frames, the selected light, frame time, the slowest passes.
    fn set_title(&self, f: &FrameOutput, frame_ms: f64) {
        let (st, s) = (self.state.as_ref().expect("started"), &self.settings);
        let mut passes: Vec<(&str, f64)> = f.timings.iter().filter_map(|t| Some((t.name, t.ms?))).collect();
        passes.sort_by(|a, b| b.1.total_cmp(&a.1));
        let shown: Vec<String> = passes.iter().take(4).map(|(n, ms)| format!("{n} {ms:.1}")).collect();
        let reused: Vec<&str> = st.full_passes.iter().copied().filter(|p| !f.ran.contains(p)).collect();
        let method = if f.ran.contains(&"denoise_temporal") { Method::Realtime } else { s.method };
        let mut title = format!(
            "bounce view — {} · {} VPLs · {} · {} frame{} · {} · {frame_ms:.0} ms · GPU ms: {}",
            method.name(),
            s.vpls,
            s.component.name(),
            st.frames,
            if st.frames == 1 { "" } else { "s" },
            st.lamp.describe(&st.renderer),
            shown.join(", "),
        );
        if !reused.is_empty() {
            title += &format!(" · reused: {}", reused.join(" "));
        }
        st.window.set_title(&title);
    }

    /// Writes the frame's read-back mean (`f.radiance`) as EXR and PNG.
    /// `shown`: the frame's method and how many frames its picture averages; `prior`: the mean carries the
    /// last real-time frame (a stop's first frames).
    fn screenshot(&mut self, png: &Path, f: &FrameOutput, shown: (Method, u32), prior: bool) -> Result<()> {
        let st = self.state.as_mut().expect("started");
        let img = RgbImage::from_rgba(f.width, f.height, &f.radiance);
        let exr = png.with_extension("exr");
        let meta = vec![
            ("scene", self.args.scene.display().to_string()),
            ("component", self.settings.component.name().to_string()),
            ("method", shown.0.name().to_string()),
            ("vpls", self.settings.vpls.to_string()),
            ("frames", shown.1.to_string()),
            ("carries_last_real_time_frame", prior.to_string()),
            ("seed", format!("{} ({})", self.settings.seed, self.args.animation.temporal().name())),
            ("light_path", self.args.animation.light_path.clone().unwrap_or_else(|| "none".into())),
            ("camera_path", self.args.animation.camera_path.clone().unwrap_or_else(|| "none".into())),
            ("device", st.gpu.name.clone()),
            ("non_finite_pixels", img.non_finite_count().to_string()),
        ];
        output::write_exr_and_png(&exr, Some(png), &img, &meta)?;
        let copies = st.gpu.readbacks() - st.readbacks;
        // A real-time frame is shown alone (`frames` is already 0 for the next still one).
        let mean = st.frames.max(1);
        self.log.push(format!(
            "wrote {} and {} ({} frame{} in the mean{}, {} in all, {} real-time; {copies} cop{} to host memory)",
            png.display(),
            exr.display(),
            mean,
            if mean == 1 { "" } else { "s" },
            if prior { " with the last real-time frame" } else { "" },
            st.total,
            st.realtime_frames,
            if copies == 1 { "y" } else { "ies" }
        ));
        Ok(())
    }

    fn resize(&mut self, width: u32, height: u32) -> Result<()> {
        let st = self.state.as_mut().expect("started");
        // A window with no area (minimised), or one whose surface has none yet: no frames until it has.
        st.minimized = width == 0 || height == 0 || !st.swapchain.recreate(width, height).map_err(error::device)?;
        if st.minimized {
            return Ok(());
        }
        self.settings.width = st.swapchain.extent.width;
        self.settings.height = st.swapchain.extent.height;
        st.ldr = Present::ldr_image(&st.gpu, self.settings.width, self.settings.height)?;
        st.frames = 0;
        Ok(())
    }

    /// A key press that changes settings; whether accumulation must restart.
    fn key(&mut self, code: KeyCode, el: &ActiveEventLoop) -> Result<bool> {
        let s = &mut self.settings;
        match code {
            KeyCode::Escape => el.exit(),
            KeyCode::KeyM => {
                let i = CYCLE.iter().position(|m| *m == s.method).map_or(0, |i| (i + 1) % CYCLE.len());
                s.method = CYCLE[i];
                return Ok(true);
            }
            KeyCode::Equal | KeyCode::NumpadAdd => {
                s.vpls = (s.vpls * 2).min(4096);
                return Ok(true);
            }
            KeyCode::Minus | KeyCode::NumpadSubtract => {
                s.vpls = (s.vpls / 2).max(1);
                return Ok(true);
            }
            KeyCode::KeyC => {
                s.component = match s.component {
                    Component::Combined => Component::Indirect,
                    Component::Indirect => Component::Direct,
                    Component::Direct => Component::Combined,
                };
                return Ok(true);
            }
            KeyCode::Space => {
                let st = self.state.as_mut().expect("started");
                st.accumulate = !st.accumulate;
                return Ok(true);
            }
            KeyCode::KeyP => self.state.as_mut().expect("started").shot_requested = true,
            KeyCode::Tab => {
                let st = self.state.as_mut().expect("started");
                st.lamp.selected = (st.lamp.selected + 1) % st.renderer.lights().len();
            }
            KeyCode::BracketLeft | KeyCode::BracketRight => {
                let st = self.state.as_mut().expect("started");
                st.lamp.scale(&mut st.renderer, if code == KeyCode::BracketLeft { 0.8 } else { 1.25 });
                return Ok(true);
            }
            _ => {}
        }
        Ok(false)
    }

    fn fail(&mut self, el: &ActiveEventLoop, e: anyhow::Error) {
        if self.error.is_none() {
            self.error = Some(e);
        }
        el.exit();
    }
}

impl ApplicationHandler for Viewer<'_> {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.state.is_some() {
            return;
        }
        match self.start(el) {
            Ok(st) => {
                st.window.request_redraw();
                self.state = Some(st);
            }
            Err(e) => self.fail(el, e),
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        if self.state.is_none() {
            return;
        }
        let r: Result<()> = (|| {
            match event {
                WindowEvent::CloseRequested => el.exit(),
                WindowEvent::Resized(size) => self.resize(size.width, size.height)?,
                WindowEvent::RedrawRequested => {
                    let finished = self.redraw()?;
                    if finished {
                        el.exit();
                    }
                }
                WindowEvent::KeyboardInput { event, .. } => {
                    let PhysicalKey::Code(code) = event.physical_key else { return Ok(()) };
                    let st = self.state.as_mut().expect("started");
                    match event.state {
                        ElementState::Pressed => {
                            st.fly.keys.insert(code);
                            if !event.repeat && self.key(code, el)? {
                                self.state.as_mut().expect("started").frames = 0;
                            }
                        }
                        ElementState::Released => {
                            st.fly.keys.remove(&code);
                        }
                    }
                }
                WindowEvent::MouseInput { state, button: MouseButton::Left, .. } => {
                    let st = self.state.as_mut().expect("started");
                    st.fly.dragging = state == ElementState::Pressed;
                }
                WindowEvent::CursorMoved { position, .. } => {
                    let st = self.state.as_mut().expect("started");
                    if let (true, Some((x, y))) = (st.fly.dragging, st.fly.cursor) {
                        st.fly.yaw -= ((position.x - x) * 0.005) as f32;
                        st.fly.pitch = (st.fly.pitch - ((position.y - y) * 0.005) as f32).clamp(-1.5, 1.5);
                        st.fly.moved = true;
                    }
                    st.fly.cursor = Some((position.x, position.y));
                }
                _ => {}
            }
            Ok(())
        })();
        if let Err(e) = r {
            self.fail(el, e);
        }
    }

    fn about_to_wait(&mut self, el: &ActiveEventLoop) {
        let Some(st) = &self.state else { return };
        // A window whose surface had no area while the window had: try again (no Resized may follow).
        let size = st.window.inner_size();
        if st.minimized && size.width > 0 && size.height > 0 {
            if let Err(e) = self.resize(size.width, size.height) {
                return self.fail(el, e);
            }
        }
        // Progressive: keep drawing while the window is visible.
        if let Some(st) = &self.state {
            if !st.minimized {
                st.window.request_redraw();
            }
        }
    }

    fn exiting(&mut self, _el: &ActiveEventLoop) {
        if let Some(st) = &self.state {
            if let Err(e) = super::check_validation(&st.gpu, self.args.frame.validation) {
                self.error.get_or_insert(e);
            }
        }
        // Drop the swapchain, surface and device while the window (and its display) still exist.
        self.state = None;
    }
}
