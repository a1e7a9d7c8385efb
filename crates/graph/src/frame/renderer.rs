//! The renderer: an immutable [`RenderContext`] (device, uploaded scene, passes and pipelines, the BVH)
//! and a `&mut` [`FrameState`] (the camera and what the graph keeps across frames). [`Renderer::render`]
//! validates the settings once, then runs the frame recipe ([`super::recipe::build_frame`]) as one or
//! more chunks ([`super::chunks`]): one for the sampled methods, a tile of VPLs each for `all`, a batch
//! of samples each for `reference`. Static products are kept by the graph under their keys
//! ([`super::keys`]), so a frame whose camera and settings did not change records only the gather.
//! The lights are frame state too ([`Renderer::set_light`]): written to the scene's light buffer before
//! each frame, and named by the keys of the light-side products, so moving a light redoes the VPLs,
//! direct light and CDF and keeps the voxels and the G-buffer.

use super::chunks::{for_each_chunk, FrameLog};
use super::keys::Keys;
use super::recipe::{build_frame, seed32, RecipeInputs};
use super::settings::{
    reject, Component, FrameSettings, LightMap, Method, RisSettings, SettingsError, Visibility, REALTIME_LEARN_BLOCKED,
    REALTIME_LEARN_EVERY, REALTIME_LEARN_HYSTERESIS,
};
use super::state::FrameState;
use crate::camera::Camera;
use crate::gpu_bvh::GpuBvh;
use crate::gpu_scene::GpuScene;
use crate::graph::{Graph, PassTiming, Persistent, Retained};
use crate::passes::cdf_reduce::CdfReduce;
use crate::passes::importance::{ImportanceKind, ImportanceParams};
use crate::passes::present::PresentParams;
use crate::passes::reference::Reference;
use crate::passes::voxelize::{self, VoxelGridSpec};
use crate::passes::{FrameInputs, Passes};
use crate::scene::Scene;
use crate::shader_types::{FrameUniforms, Light};
use anyhow::{Context, Result};
use bounce_device::{vk, Buffer, BufferDesc, Gpu, Image, MemoryLocation};
use glam::Vec3;

/// What does not change from frame to frame: the device, the uploaded scene, every pass's pipelines,
/// and the scene's BVH (built with the scene: every exact ray and the reference trace it).
pub struct RenderContext {
    pub gpu: Gpu,
    pub scene: GpuScene,
    pub passes: Passes,
    /// The largest intensity component of any light (for the gbg fixed-point scale): the current
    /// lights', set before each frame.
    max_intensity: f32,
    /// The light maps' far distance for the current lights, set before each frame ([`far_light`]).
    far_light: f32,
    bvh: GpuBvh,
    /// The BVH's triangles in its leaf order, kept for the host's ray queries.
    bvh_tris: Vec<crate::bvh::GpuBvhTri>,
    /// Its nodes, kept for the host's ray queries ([`crate::bvh::query`]).
    bvh_nodes: Vec<crate::bvh::GpuBvhNode>,
    /// `--learn-visibility auto`'s blocked share for the last view asked about: (view key, share).
    blocked: Option<(u64, Option<f32>)>,
    /// A real-time frame's learning decision under `auto`: (the frame it was made at, on).
    realtime_learns: Option<(u64, bool)>,
}

/// Renders frames of one scene. Derefs to its [`RenderContext`] (the read-only part).
pub struct Renderer {
    ctx: RenderContext,
    state: FrameState,
}

impl std::ops::Deref for Renderer {
    type Target = RenderContext;
    fn deref(&self) -> &RenderContext {
        &self.ctx
    }
}

/// A rendered frame, read back ([`Renderer::present`]: only the screenshot's mean, if asked).
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
    /// The raw estimate where `radiance` is the denoised one (`Method::Realtime`), as `radiance`.
    pub raw: Option<Vec<[f32; 4]>>,
    /// Shadow rays the frame traced per pixel (ris and realtime: counted by the shade).
    pub rays_per_pixel: Option<f64>,
}

impl FrameOutput {
    pub fn gpu_ms(&self) -> Option<f64> {
        self.timings.iter().map(|t| t.ms).sum()
    }

    /// The frame's GPU time in passes that made products a next frame of the same settings keeps (maps,
    /// G-buffer, CDF, …) and does not run again; `None` without timestamps.
    pub fn kept_gpu_ms(&self) -> Option<f64> {
        self.timings.iter().filter(|t| t.kept).map(|t| t.ms).sum()
    }

    /// The frame's GPU time less the display filter's passes (`passes/denoise.rs`): what its raw
    /// estimate costs (`--denoise off`).
    pub fn raw_gpu_ms(&self) -> Option<f64> {
        self.timings.iter().filter(|t| !t.name.starts_with("denoise_")).map(|t| t.ms).sum()
    }
}

impl Renderer {
    pub fn new(gpu: &Gpu, scene: &Scene) -> Result<Self> {
        let flat = crate::bvh::FlatBvh::new(&crate::bvh::Bvh::from_vertices(&scene.vertices), &scene.vertices);
        let uploaded = GpuScene::upload(gpu, scene).context("uploading the scene")?;
        let far = far_light(uploaded.bounds_min, uploaded.bounds_max, &scene.lights);
        let ctx = RenderContext {
            gpu: gpu.clone(),
            scene: uploaded,
            passes: Passes::new(gpu, !scene.textures.is_empty())?,
            max_intensity: max_intensity(&scene.lights),
            far_light: far,
            bvh: GpuBvh::upload(gpu, &flat).context("uploading the BVH")?,
            bvh_tris: flat.tris,
            bvh_nodes: flat.nodes,
            blocked: None,
            realtime_learns: None,
        };
        let state = FrameState {
            camera: scene.camera,
            lights: scene.lights.clone(),
            retained: Retained::default(),
            previous: None,
            history_view: None,
            realtime_frames: 0,
        };
        Ok(Renderer { ctx, state })
    }

    /// The current lights (scene-local coordinates).
    pub fn lights(&self) -> &[Light] {
        &self.state.lights
    }

    /// Moves light `i` to `position` (scene-local) with `intensity` (W/sr per channel). The next frame
    /// re-records the light-side passes and what depends on them. Panics on a light the scene lacks.
    pub fn set_light(&mut self, i: usize, position: Vec3, intensity: Vec3) {
        self.state.lights[i] = crate::scene::point_light(position, intensity);
    }

    /// The current camera.
    pub fn camera(&self) -> Camera {
        self.state.camera
    }

    /// Moves the camera (the viewer's fly camera). The next frame re-records what depends on it.
    pub fn set_camera(&mut self, camera: Camera) {
        self.state.camera = camera;
    }

    /// Forget every kept product: the next frame records every pass it needs. `bounce bench` does this
    /// before each timed frame, so that every method pays for its full frame.
    pub fn clear_frame_cache(&mut self) {
        self.state.retained.clear();
        self.state.previous = None;
        self.state.history_view = None;
        self.state.realtime_frames = 0;
        self.ctx.realtime_learns = None;
    }

    /// Two untimed frames of `s` at about 8 × 8 pixels (maps about 32² a face), then
    /// [`Self::clear_frame_cache`]:
    /// a driver that compiles a shader at its first dispatch does it here, not inside the next frame's
    /// timestamps. llvmpipe does (on a cold shader cache the Cornell box's passes read 47–675 ms in their
    /// first frame against 0.2–28 ms after it); drivers that compile at pipeline creation pay nothing
    /// here. The next frame's image does not change: it records every pass as a first frame does.
    pub fn warm_up(&mut self, s: &FrameSettings) -> Result<()> {
        // llvmpipe keys a shader's compiled variant on whether each image's sides are powers of two
        // (bounce_device::workarounds), so
        // a smaller stand-in keeps that: a power of two becomes `cap`, any other size 1.5 · cap.
        let small = |n: u32, cap: u32| match n {
            n if n <= cap => n,
            n if n.is_power_of_two() => cap,
            _ => cap + cap / 2,
        };
        let small = FrameSettings {
            width: small(s.width, 8),
            height: small(s.height, 8),
            dprsm_res: small(s.dprsm_res, 32),
            psm_res: small(s.psm_res, 32),
            ..s.clone()
        };
        self.prepare(&small)?;
        // Twice: the second frame runs what only a frame with history runs (the temporal reuse, the
        // denoiser's history), whose pipelines a first timed frame after one warm-up frame still built
        // (`bench --animate` of realtime read 3× its GPU time on a cold driver cache).
        for _ in 0..2 {
            self.render(&small).context("the untimed warm-up frame")?;
        }
        self.clear_frame_cache();
        Ok(())
    }

    /// The per-frame constants for `s` with the current camera.
    pub fn uniforms(&self, s: &FrameSettings) -> FrameUniforms {
        self.ctx.uniforms(s, &self.state.camera)
    }

    /// A uniform buffer for `s` with the current camera (and last frame's, for reprojection).
    pub fn uniform_buffer(&self, s: &FrameSettings) -> Result<Buffer> {
        let mut u = self.uniforms(s);
        if let Some(previous) = &self.state.previous {
            u.prev_view_proj = self.ctx.uniforms(s, &previous.camera).view_proj;
        }
        self.ctx.uniform_buffer(&u)
    }

    /// Build, execute and read back one frame.
    pub fn render(&mut self, s: &FrameSettings) -> Result<FrameOutput> {
        self.render_with_progress(s, &mut |_, _| {})
    }

    /// [`Renderer::render`], calling `progress(done, total)` between the chunks of `all` and `reference`.
    pub fn render_with_progress(
        &mut self,
        s: &FrameSettings,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<FrameOutput> {
        self.frame(s, progress, None)
    }

    /// Renders a frame and presents it on the GPU (the viewer): the present pass adds it to the running
    /// mean and writes the tone-mapped picture into `ldr` ([`crate::passes::present::Present::ldr_image`]). Nothing is read
    /// back (no radiance, no dead-CDF check), unless `read_mean`: then the returned radiance is the
    /// running mean (a screenshot), else it is empty.
    pub fn present(
        &mut self,
        s: &FrameSettings,
        ldr: &Persistent<Image>,
        params: PresentParams,
        read_mean: bool,
    ) -> Result<FrameOutput> {
        self.frame(s, &mut |_, _| {}, Some(PresentTo { ldr, params, read_mean }))
    }

    /// `--learn-visibility auto`'s share of the unshadowed transport into the current view that visibility
    /// blocks ([`crate::passes::ris::blocked_share`]), computed once per view and size.
    pub fn blocked_share(&mut self, width: u32, height: u32) -> Result<Option<f32>> {
        let c = &self.state.camera;
        let key = crate::graph::fingerprint(&(
            super::keys::view_key(c, width, height),
            super::keys::light_bits(&self.state.lights),
        ));
        if let Some((k, share)) = self.ctx.blocked {
            if k == key {
                return Ok(share);
            }
        }
        let bvh = crate::bvh::query::BvhView { nodes: &self.ctx.bvh_nodes, tris: &self.ctx.bvh_tris };
        let diagonal = (self.ctx.scene.bounds_max - self.ctx.scene.bounds_min).length();
        let share = crate::passes::ris::blocked_share(bvh, c, &self.state.lights, (width, height), diagonal);
        self.ctx.blocked = Some((key, share));
        Ok(share)
    }

    /// Builds what a frame of `s` will build on first use and is not part of its work: ris's initial
    /// pipeline for its pick count (`passes::ris::Ris::prepare`). Timed runs call it before the clock.
    pub fn prepare(&mut self, s: &FrameSettings) -> Result<()> {
        self.check(s)?;
        let auto = self.auto_learn(s)?;
        let s = auto.as_ref().unwrap_or(s);
        if s.uses_ris() {
            let push = super::recipe::ris_push(s);
            let uniform_source = super::recipe::ris_uniform_source(s);
            self.ctx.passes.ris.prepare(&push, uniform_source, self.ctx.scene.light_count > 1)?;
        }
        Ok(())
    }

    /// `s` as this frame renders it (None: as it is): `--learn-visibility auto` decided for the current
    /// view; a real-time frame's seed moved on by the real-time frames rendered, so that each draws new
    /// random numbers and its reuse combines independent frames.
    fn effective(&mut self, s: &FrameSettings) -> Result<Option<FrameSettings>> {
        if s.method == Method::Realtime {
            let seed = s.seed.wrapping_add(self.state.realtime_frames.wrapping_mul(0x9E37_79B9));
            let mut ris = s.ris;
            if ris.learn_auto && ris.learn_visibility == 0.0 && self.realtime_learns(s)? {
                ris.learn_visibility = crate::passes::ris::AUTO_LEARN_FLOOR;
            }
            // While the camera or a light moves, the end balls (the pixels' kept with the G-buffer, the
            // VPLs' with the maps) would be rebuilt for one frame's two rays a pixel: a ball costs two
            // BVH walks and saves part of one for each ray that ends in it, and a frame has about one ray
            // per VPL. The shade's rays walk whole segments instead (the same answers; the frame 0.91–0.94×
            // on Sibenik under the camera, 0.94× in the two rooms and 0.92× on Sibenik under a light; BENCHMARKS.md).
            let previous = self.state.previous.as_ref();
            let camera_moved = previous.is_some_and(|p| p.camera != self.state.camera);
            let lights_moved = previous.is_some_and(|p| p.lights != self.state.lights);
            let end_balls = s.end_balls && !camera_moved && !lights_moved;
            return Ok(Some(FrameSettings { seed, ris, end_balls, ..s.clone() }));
        }
        self.auto_learn(s)
    }

    /// Whether a real-time frame under `auto` learns visibility: where the view's blocked share is at
    /// least [`REALTIME_LEARN_BLOCKED`], decided again every [`REALTIME_LEARN_EVERY`] frames (the estimate
    /// costs about 2.5 ms of CPU on Sibenik, 4096 occlusion tests a light, and the share drifts slowly
    /// under motion), and kept on until the share falls [`REALTIME_LEARN_HYSTERESIS`] below the threshold
    /// (a view whose share sits at it does not switch back and forth). Either choice is unbiased: a stale
    /// decision costs efficiency only.
    fn realtime_learns(&mut self, s: &FrameSettings) -> Result<bool> {
        let (last, now) = (self.ctx.realtime_learns, self.state.realtime_frames);
        let decision = realtime_learning(last, now, || self.blocked_share(s.width, s.height))?;
        self.ctx.realtime_learns = Some(decision);
        Ok(decision.1)
    }

    /// `s` with `--learn-visibility auto` decided for the current view (None: `s` as it is).
    fn auto_learn(&mut self, s: &FrameSettings) -> Result<Option<FrameSettings>> {
        let r = &s.ris;
        let allowed = r.pool_tiles > 0 && r.spatial_passes == 0 && r.temporal_cap == 0.0;
        if s.method != Method::Ris || !r.learn_auto || r.learn_visibility > 0.0 || !allowed {
            return Ok(None);
        }
        let blocked = self.blocked_share(s.width, s.height)?;
        if !blocked.is_some_and(|b| b >= crate::passes::ris::AUTO_LEARN_BLOCKED) {
            return Ok(None);
        }
        let ris = RisSettings {
            learn_visibility: crate::passes::ris::AUTO_LEARN_FLOOR,
            learn_tile: crate::passes::ris::auto_vis_tile(blocked.expect("checked above")),
            ..s.ris
        };
        Ok(Some(FrameSettings { ris, ..s.clone() }))
    }

    fn frame(
        &mut self,
        s: &FrameSettings,
        progress: &mut dyn FnMut(u64, u64),
        present: Option<PresentTo>,
    ) -> Result<FrameOutput> {
        self.check(s)?;
        let effective = self.effective(s)?;
        let s = effective.as_ref().unwrap_or(s);
        self.ctx.set_lights(&self.state.lights)?;
        let uniforms = self.uniform_buffer(s)?;
        self.state.forget_moved_histories();
        let (ctx, state) = (&self.ctx, &mut self.state);
        let i = ctx.recipe_inputs(s, &state.camera, &state.lights, &uniforms);
        let (total, per_chunk) = ctx.chunking(s, &i);
        let vpls_key = i.keys.vpls;
        let mut log = FrameLog::default();
        let mut read = Read::default();
        // What the presented image read back is divided by for its mean (present's `add`).
        let mut divide_by = 1.0f32;
        for_each_chunk(total, per_chunk, progress, |chunk, last| {
            let mut g = Graph::with_retained(&ctx.gpu, &mut state.retained);
            let out = build_frame(&ctx.passes, &mut g, s, &i, chunk)?;
            out.export(&mut g);
            let presented = match &present {
                Some(p) if last => {
                    let mut ldr = g.import_image(p.ldr);
                    let shown = ctx.passes.present.add(&mut g, &out.radiance, &mut ldr, s.width, s.height, p.params)?;
                    g.export(&ldr);
                    Some(shown)
                }
                _ => None,
            };
            let done = g.execute()?;
            log.add(&done);
            match (&present, presented) {
                (Some(p), Some((image, k))) if p.read_mean => {
                    read.radiance = done.read_image(&image)?;
                    divide_by = k;
                }
                (Some(_), _) => {}
                (None, _) => {
                    if done.ran.contains(&"cdf_reduce") {
                        if let Some(cdf) = &out.cdf {
                            log.warnings.extend(ctx.dead_cdf_warning(s, &done.read_buffer(cdf)?));
                        }
                    }
                    if last {
                        read = Read::of(&done, &out)?;
                    }
                }
            }
            Ok(())
        })?;
        state.frame_done(vpls_key);
        state.realtime_frames += (s.method == Method::Realtime) as u64;
        let mut radiance: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&read.radiance);
        if present.is_some() {
            radiance.iter_mut().for_each(|px| *px = px.map(|c| c / divide_by));
        }
        let stderr = read.second.and_then(|sq| reference_stderr(s, &radiance, &bytemuck::pod_collect_to_vec(&sq)));
        log.warnings.extend(super::warnings::rsm_warning(s));
        log.warnings.extend(super::warnings::defensive_warning(s));
        Ok(FrameOutput {
            width: s.width,
            height: s.height,
            radiance,
            timings: log.timings,
            ran: log.ran,
            skipped: log.skipped,
            warnings: log.warnings,
            stderr,
            raw: read.raw.map(|b| bytemuck::pod_collect_to_vec(&b)),
            rays_per_pixel: read.rays.map(|b| {
                let count: u32 = bytemuck::pod_read_unaligned(&b[..4]);
                count as f64 / (s.width as f64 * s.height as f64)
            }),
        })
    }
}

/// A frame's products read back: the radiance (or the viewer's mean), the reference's second moment,
/// the raw estimate beside a denoised one, the shadow-ray count.
#[derive(Default)]
struct Read {
    radiance: Vec<u8>,
    second: Option<Vec<u8>>,
    raw: Option<Vec<u8>>,
    rays: Option<Vec<u8>>,
}

impl Read {
    fn of(done: &crate::graph::Executed, out: &super::recipe::FrameOut) -> Result<Read> {
        Ok(Read {
            radiance: done.read_image(&out.radiance)?,
            second: out.second_moment.map(|h| done.read_image(&h)).transpose()?,
            raw: out.raw.map(|h| done.read_image(&h)).transpose()?,
            rays: out.rays.map(|h| done.read_buffer(&h)).transpose()?,
        })
    }
}

/// Where [`Renderer::present`] puts its picture.
struct PresentTo<'p> {
    ldr: &'p Persistent<Image>,
    params: PresentParams,
    read_mean: bool,
}

/// The light maps' far distance (their rays' and the paraboloid shadow maps' depth range): the diagonal of
/// the bounds, which at load hold the geometry and the lights, or, for a light moved outside them (an
/// orbit near a wall), its distance to their farthest corner; 1 % beyond either. A light inside the
/// bounds is never farther than the diagonal from any surface.
fn far_light(lo: Vec3, hi: Vec3, lights: &[Light]) -> f32 {
    let beyond = lights.iter().map(|l| farthest_corner(lo, hi, Vec3::from_slice(&l.position[..3])));
    (hi - lo).length().max(beyond.fold(0.0f32, f32::max)) * 1.01
}

/// The distance from `p` to the farthest corner of the box `lo`..`hi`.
fn farthest_corner(lo: Vec3, hi: Vec3, p: Vec3) -> f32 {
    let corner = |k: usize| Vec3::new([lo.x, hi.x][k & 1], [lo.y, hi.y][(k >> 1) & 1], [lo.z, hi.z][(k >> 2) & 1]);
    (0..8).map(|k| (corner(k) - p).length()).fold(0.0f32, f32::max)
}

/// The largest intensity component of any of `lights`.
fn max_intensity(lights: &[Light]) -> f32 {
    lights.iter().flat_map(|l| l.intensity[..3].to_vec()).fold(0.0, f32::max)
}

/// The RMS over pixels and channels of the reference's standard error of the mean per pixel,
/// sqrt((E[L²] − E[L]²) / (N − 1)), for the indirect component (a combined image's mean also holds the
/// exact direct light, so none is given for it). It is the error of N independent samples; the
/// reference's stratified samples do better, so it is an upper estimate (on the default scene at 64²
/// and 1024 samples, 3.4× the measured RMS error for `cosine`, 6× for `mis`).
fn reference_stderr(s: &FrameSettings, mean: &[[f32; 4]], second: &[[f32; 4]]) -> Option<f64> {
    if s.component != Component::Indirect {
        return None;
    }
    let n = s.spp.max(2) as f64;
    let (mut se2, mut count) = (0.0f64, 0usize);
    for (m, q) in mean.iter().zip(second) {
        for c in 0..3 {
            se2 += ((q[c] as f64 - (m[c] as f64).powi(2)).max(0.0)) / (n - 1.0);
            count += 1;
        }
    }
    (count > 0).then(|| (se2 / count as f64).sqrt())
}

impl RenderContext {
    /// The frame's lights: uploaded, and what depends on them (the gbg scale, the light maps' far).
    fn set_lights(&mut self, lights: &[Light]) -> Result<()> {
        self.scene.write_lights(lights)?;
        self.max_intensity = max_intensity(lights);
        self.far_light = far_light(self.scene.bounds_min, self.scene.bounds_max, lights);
        Ok(())
    }

    /// VPLs per gather dispatch under the device's loop iteration limit. Per VPL an invocation loops at
    /// most: the visibility's (the march's steps, ≤ dims.x + dims.y + dims.z + 3, or a trace's bound),
    /// the CDF's two binary searches (≤ 32 each), the sections and faces, plus 64 for the rest; another
    /// 64 are kept for the loops outside. (The Sobol points have no loop: `glsl/shared/owen_sobol.glsl`.)
    pub fn vpls_per_dispatch(&self, s: &FrameSettings) -> u32 {
        let Some(limit) = self.gpu.loop_iteration_limit else { return u32::MAX };
        let dims = self.voxel_spec(s).dims;
        // Sampling adds loops over the CDF sections and, with uniform face choice, over the faces.
        let sections = 1 + self.importance_params(s).kind.method_sections();
        let faces = s.light_map.faces() * self.scene.light_count;
        let grid_march = dims.x + dims.y + dims.z + 3;
        // A shadow ray's (exact: the threaded any-hit walk) and a first-hit ray's (MIS's gathering rays).
        let occlusion = match s.visibility {
            Visibility::Exact => self.bvh.max_iterations_occluded(),
            _ => grid_march,
        };
        let march = self.trace_iterations(s).unwrap_or(grid_march);
        // draw_vpl: its two binary searches (≤ 32 each), the sections and faces.
        let per_vpl = occlusion + 64 + 2 * 32 + 3 * sections + 2 * faces * (sections + 1);
        // MIS: a CDF sample adds one march (its gathering indicator); a gathering ray marches once to
        // its hit and then, per light, does a CDF sample's work (visibility march, probability look-up).
        let per_vpl = if s.method == Method::Mis {
            (per_vpl + march + 64).max(march + 64 + self.scene.light_count * per_vpl)
        } else {
            per_vpl
        };
        ((limit.saturating_sub(64)) / per_vpl).max(1)
    }

    /// Loop iterations of one traced ray (exact visibility), `None` for the voxel march.
    fn trace_iterations(&self, s: &FrameSettings) -> Option<u32> {
        s.visibility.uses_bvh().then(|| self.bvh.max_iterations_per_ray())
    }

    /// Traced rays per invocation and dispatch under the loop limit (gbg's importance rays), each with
    /// a look-up per light.
    fn traces_per_dispatch(&self, s: &FrameSettings) -> u32 {
        match (self.gpu.loop_iteration_limit, self.trace_iterations(s)) {
            // Per ray: the trace and the look-up per light.
            (Some(limit), Some(per)) => (limit.saturating_sub(64) / (per + 16 * self.scene.light_count + 16)).max(1),
            _ => u32::MAX,
        }
    }

    /// What the recipe reads besides the settings, for settings `s` seen from `camera`.
    fn recipe_inputs<'a>(
        &'a self,
        s: &FrameSettings,
        camera: &Camera,
        lights: &[Light],
        uniforms: &'a Buffer,
    ) -> RecipeInputs<'a> {
        let importance = self.importance_params(s);
        let grid = self.voxel_spec(s);
        RecipeInputs {
            f: self.frame_inputs(s, uniforms),
            keys: Keys::new(s, camera, lights, &grid, &importance),
            importance,
            grid,
            ris_candidates_per_dispatch: crate::passes::ris::candidates_per_dispatch(
                self.gpu.loop_iteration_limit,
                importance.kind.method_sections(),
                s.light_map.faces() * self.scene.light_count,
                s.ris_settings().pool_tiles > 0,
            ),
            reference_per_dispatch: Reference::per_dispatch(&self.gpu, &self.bvh, self.scene.light_count),
        }
    }

    /// (units of work, units per chunk) of a frame: VPL slots in tiles of `--all-tile` for `all`, samples
    /// for `reference` (`reference_chunk`, else enough per submission to keep the GPU busy and few
    /// enough for a live progress bar), one unit for the rest.
    fn chunking(&self, s: &FrameSettings, i: &RecipeInputs) -> (u32, u32) {
        match (s.component, s.method) {
            (Component::Direct, _) => (1, 1),
            (_, Method::All) => (s.light_map.faces() * self.scene.light_count * s.dprsm_res * s.dprsm_res, s.all_tile),
            (_, Method::Reference) => {
                (s.spp, s.reference_chunk.map_or(i.reference_per_dispatch.saturating_mul(4).clamp(1, 64), |c| c.get()))
            }
            _ => (1, 1),
        }
    }

    /// A warning when every method section of a freshly built CDF is empty (the method then samples
    /// uniformly). Only the section headers are needed, but a whole readback is cheap next to a frame
    /// that ran the importance.
    fn dead_cdf_warning(&self, s: &FrameSettings, bytes: &[u8]) -> Option<String> {
        let sections = self.importance_params(s).kind.method_sections() as usize;
        if sections == 0 {
            return None;
        }
        let cdf: Vec<f32> = bytemuck::pod_collect_to_vec(bytes);
        let len =
            CdfReduce::section_len(s.light_map.faces() * self.scene.light_count * s.dprsm_res, s.dprsm_res) as usize;
        let live = (1..=sections).filter(|k| cdf.get(k * len).is_some_and(|t| *t > 0.0)).count();
        (live == 0)
            .then(|| format!("the {} importance is zero for every VPL; sampling uniformly instead", s.method.name()))
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
            kind: match s.sampling_method() {
                Method::Uniform | Method::All | Method::Reference | Method::Ris | Method::Realtime => {
                    ImportanceKind::Uniform
                }
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
    pub fn uniforms(&self, s: &FrameSettings, camera: &Camera) -> FrameUniforms {
        let diag = self.scene.diagonal();
        let eye = camera.eye;
        // Camera far plane: beyond the farthest corner of the bounds; near: a small fraction of it.
        let (lo, hi) = (self.scene.bounds_min, self.scene.bounds_max);
        let far_cam = farthest_corner(lo, hi, eye).max(diag) * 1.01;
        let near = far_cam * 1e-5;
        let (voxel_origin, voxel_dims) = self.voxel_spec(s).uniforms_fields();
        let vpl_slots = s.light_map.faces() * self.scene.light_count * s.dprsm_res * s.dprsm_res;
        let view_proj = camera.view_proj(s.width, s.height, far_cam, near).to_cols_array_2d();
        FrameUniforms {
            // near and far swapped: reverse Z (see passes/gbuffer.rs).
            view_proj,
            prev_view_proj: view_proj,
            camera: [2.0 * camera.tan_half_fov() / s.height as f32, 0.0, 0.0, 0.0],
            eye: [eye.x, eye.y, eye.z, 0.0],
            scene_min: [lo.x, lo.y, lo.z, diag],
            scene_max: [hi.x, hi.y, hi.z, self.far_light],
            size: [s.width, s.height, self.scene.light_count, s.dprsm_res],
            maps: [0, vpl_slots, s.psm_res, s.vpls],
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
            vpl: [s.vpl_kernel.area_weight(), 0.0, 0.0, 0.0],
        }
    }

    /// The per-frame inputs every pass reads, for settings `s` and their uniform buffer.
    pub fn frame_inputs<'a>(&'a self, s: &FrameSettings, uniforms: &'a Buffer) -> FrameInputs<'a> {
        FrameInputs {
            visibility: s.visibility,
            bvh: &self.bvh,
            traces_per_dispatch: self.traces_per_dispatch(s),
            scene: &self.scene,
            uniforms,
            width: s.width,
            height: s.height,
            dprsm_res: s.dprsm_res,
            vpl_faces: s.light_map.faces(),
            vpl_offset: crate::frame::keys::vpl_offset(s),
            vpls_per_dispatch: self.vpls_per_dispatch(s),
        }
    }

    /// A host-visible uniform buffer holding `u` (written once, before recording).
    pub fn uniform_buffer(&self, u: &FrameUniforms) -> Result<Buffer> {
        let mut uniforms = Buffer::new(
            &self.gpu,
            &BufferDesc {
                name: "frame uniforms".into(),
                size: std::mem::size_of::<FrameUniforms>() as u64,
                usage: vk::BufferUsageFlags::UNIFORM_BUFFER,
                location: MemoryLocation::CpuToGpu,
            },
        )?;
        uniforms.mapped_mut().context("uniform buffer is not host-visible")?.copy_from_slice(bytemuck::bytes_of(u));
        Ok(uniforms)
    }

    /// Memory the reflective DPRSM takes: 3 RGBA32F images, plus importance and CDF.
    pub fn dprsm_bytes(&self, s: &FrameSettings) -> u64 {
        s.light_map.faces() as u64 * self.scene.light_count as u64 * (s.dprsm_res as u64).pow(2) * (3 * 16 + 4 + 4)
    }

    /// Reject settings this device or scene cannot run (bad input, not a runtime failure).
    pub fn check(&self, s: &FrameSettings) -> Result<(), SettingsError> {
        s.validate(&self.gpu)?;
        const MAX_MAP_BYTES: u64 = 2 << 30;
        let bytes = self.dprsm_bytes(s);
        if bytes > MAX_MAP_BYTES {
            reject!(
                "the reflective DPRSM would take {} MiB ({} lights); lower --dprsm-res (limit {} MiB)",
                bytes >> 20,
                self.scene.light_count,
                MAX_MAP_BYTES >> 20
            );
        }
        let max_range = self.gpu.limits().max_storage_buffer_range as u64;
        let texels = s.light_map.faces() as u64 * self.scene.light_count as u64 * (s.dprsm_res as u64).pow(2);
        let cdf_bytes =
            4 * (texels + s.light_map.faces() as u64 * self.scene.light_count as u64 * s.dprsm_res as u64 + 4);
        // cdf_reduce binds the whole CDF, and the importance passes and the samplers the whole importance,
        // every section, as storage buffers.
        let sections = 1 + self.importance_params(s).kind.method_sections() as u64;
        for (what, bytes) in [("CDF", cdf_bytes * sections), ("importance", 4 * texels * sections)] {
            if bytes > max_range {
                reject!("the {what} would take {bytes} bytes, over the device limit maxStorageBufferRange ({max_range}); lower --dprsm-res or --regions");
            }
        }
        // The samplers read the CDF (every section) through a texel view.
        let cdf_texels = cdf_bytes / 4 * sections;
        let max_texels = self.gpu.limits().max_texel_buffer_elements as u64;
        if cdf_texels > max_texels {
            reject!("the CDF would take {cdf_texels} texels, over the device limit maxTexelBufferElements ({max_texels}); lower --dprsm-res or --regions");
        }
        voxelize::check_grid(&self.gpu, &self.voxel_spec(s)).map_err(|e| SettingsError(e.to_string()))?;
        if let (true, Some(limit)) = (s.uses_ris(), self.gpu.loop_iteration_limit) {
            // A spatial pass evaluates (k + 1)² targets per reservoir.
            let evals = (s.ris_settings().spatial_neighbors + 1).pow(2);
            if evals * 64 + 256 > limit {
                reject!("ris: {evals} target evaluations of a spatial pass overrun this device's loop limit ({limit}); lower --spatial-neighbors");
            }
        }
        Ok(())
    }
}

/// [`Renderer::realtime_learns`]'s rule: the last decision (frame, on) while it is younger than
/// [`REALTIME_LEARN_EVERY`] frames, else a new one from the blocked share (`share`, called only then),
/// whose threshold is lowered by [`REALTIME_LEARN_HYSTERESIS`] while learning is on.
fn realtime_learning(
    last: Option<(u64, bool)>,
    now: u64,
    share: impl FnOnce() -> Result<Option<f32>>,
) -> Result<(u64, bool)> {
    if let Some((at, on)) = last {
        if now.wrapping_sub(at) < REALTIME_LEARN_EVERY {
            return Ok((at, on));
        }
    }
    let was_on = last.is_some_and(|(_, on)| on);
    let threshold = REALTIME_LEARN_BLOCKED - if was_on { REALTIME_LEARN_HYSTERESIS } else { 0.0 };
    Ok((now, share()?.is_some_and(|b| b >= threshold)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn share(b: f32) -> impl FnOnce() -> Result<Option<f32>> {
        move || Ok(Some(b))
    }

    #[test]
    fn realtime_learning_is_decided_every_few_frames_with_hysteresis() {
        let never = || -> Result<Option<f32>> { panic!("the share was estimated again") };
        let t = REALTIME_LEARN_BLOCKED;
        // First frame: the threshold; nothing lit in view: off.
        assert_eq!(realtime_learning(None, 3, share(t)).unwrap(), (3, true));
        assert_eq!(realtime_learning(None, 3, share(t - 0.01)).unwrap(), (3, false));
        assert_eq!(realtime_learning(None, 3, || Ok(None)).unwrap(), (3, false));
        // A young decision is kept without an estimate.
        let young = 3 + REALTIME_LEARN_EVERY - 1;
        assert_eq!(realtime_learning(Some((3, true)), young, never).unwrap(), (3, true));
        assert_eq!(realtime_learning(Some((3, false)), young, never).unwrap(), (3, false));
        // An old one is made again: on stays on down to the hysteresis band, off needs the threshold.
        let old = 3 + REALTIME_LEARN_EVERY;
        let inside = t - 0.5 * REALTIME_LEARN_HYSTERESIS;
        assert_eq!(realtime_learning(Some((3, true)), old, share(inside)).unwrap(), (old, true));
        assert_eq!(realtime_learning(Some((3, false)), old, share(inside)).unwrap(), (old, false));
        let below = t - 2.0 * REALTIME_LEARN_HYSTERESIS;
        assert_eq!(realtime_learning(Some((3, true)), old, share(below)).unwrap(), (old, false));
    }
}
