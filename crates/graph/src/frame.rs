//! The frame recipe. [`build_frame`] is the one place that says what runs, in what order, on what data:
//! gbuffer → dprsm → direct, handles flowing from call to call. [`Renderer`] owns the passes (their
//! pipelines) and the uploaded scene; [`Renderer::render`] builds, executes and reads back one frame.

use crate::gpu_scene::GpuScene;
use crate::graph::{Graph, Handle, PassTiming};
use crate::passes::{direct::Direct, dprsm::Dprsm, gbuffer::GBuffer, FrameInputs};
use crate::scene::Scene;
use crate::shader_types::FrameUniforms;
use anyhow::{bail, Context, Result};
use bounce_device::{vk, Buffer, BufferDesc, Gpu, Image, MemoryLocation};

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

#[derive(Clone, Debug)]
pub struct FrameSettings {
    pub width: u32,
    pub height: u32,
    pub component: Component,
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
        for (what, v) in [("width", self.width), ("height", self.height), ("shadow map resolution", self.shadow_res)] {
            if v == 0 {
                bail!("{what} must be at least 1");
            }
            if v > max {
                bail!("{what} {v} exceeds the device limit maxImageDimension2D ({max})");
            }
        }
        let ok = |v: f32| v.is_finite() && v >= 0.0;
        if !ok(self.shadow_bias) || !ok(self.shadow_slope_bias) {
            bail!("shadow biases must be finite and non-negative");
        }
        Ok(())
    }
}

/// Owns the passes and the uploaded scene.
pub struct Renderer {
    pub gpu: Gpu,
    pub scene: GpuScene,
    pub camera: crate::camera::Camera,
    gbuffer: GBuffer,
    dprsm: Dprsm,
    direct: Direct,
}

/// A rendered frame, read back.
pub struct FrameOutput {
    pub width: u32,
    pub height: u32,
    /// RGBA32F radiance, row-major, row 0 = top.
    pub radiance: Vec<[f32; 4]>,
    pub timings: Vec<PassTiming>,
    pub ran: Vec<&'static str>,
    pub skipped: Vec<&'static str>,
}

impl FrameOutput {
    pub fn gpu_ms(&self) -> Option<f64> {
        self.timings.iter().map(|t| t.ms).sum()
    }
}

/// The frame recipe: gbuffer → dprsm → direct. Returns the radiance image of the asked component.
pub fn build_frame<'a>(
    r: &'a Renderer,
    g: &mut Graph<'a>,
    f: FrameInputs<'a>,
    s: &FrameSettings,
) -> Result<Handle<Image>> {
    let gbuffer = r.gbuffer.add(g, f);
    let shadow = r.dprsm.add(g, f);
    let direct = r.direct.add(g, f, &gbuffer, &shadow);
    match s.component {
        Component::Direct => Ok(direct),
        Component::Indirect | Component::Combined => {
            bail!("--component {} needs the VPL passes, which this build does not have yet", s.component.name())
        }
    }
}

impl Renderer {
    pub fn new(gpu: &Gpu, scene: &Scene) -> Result<Self> {
        Ok(Renderer {
            gpu: gpu.clone(),
            scene: GpuScene::upload(gpu, scene).context("uploading the scene")?,
            camera: scene.camera,
            gbuffer: GBuffer::new(gpu).context("creating the gbuffer pass")?,
            dprsm: Dprsm::new(gpu).context("creating the dprsm pass")?,
            direct: Direct::new(gpu).context("creating the direct pass")?,
        })
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
        FrameUniforms {
            // near and far swapped: reverse Z (see passes/gbuffer.rs).
            view_proj: self.camera.view_proj(s.width, s.height, far_cam, near).to_cols_array_2d(),
            eye: [eye.x, eye.y, eye.z, 0.0],
            scene_min: [lo.x, lo.y, lo.z, diag],
            scene_max: [hi.x, hi.y, hi.z, far_light],
            size: [s.width, s.height, self.scene.light_count, s.shadow_res],
            shadow: [s.shadow_bias * diag, s.shadow_slope_bias, 0.0, 0.0],
            voxel_origin: [0.0; 4],
            voxel_dims: [0; 4],
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

    /// Reject settings this device or scene cannot run (bad input, not a runtime failure).
    pub fn check(&self, s: &FrameSettings) -> Result<()> {
        s.validate(&self.gpu)?;
        const MAX_SHADOW_BYTES: u64 = 2 << 30;
        let bytes = self.shadow_map_bytes(s);
        if bytes > MAX_SHADOW_BYTES {
            bail!(
                "the shadow maps would take {} MiB ({} lights × 2 faces × {}²); lower --shadow-res (limit {} MiB)",
                bytes >> 20,
                self.scene.light_count,
                s.shadow_res,
                MAX_SHADOW_BYTES >> 20
            );
        }
        Ok(())
    }

    /// Build, execute and read back one frame.
    pub fn render(&self, s: &FrameSettings) -> Result<FrameOutput> {
        self.check(s)?;
        let uniforms = self.uniform_buffer(s)?;
        let inputs = FrameInputs {
            scene: &self.scene,
            uniforms: &uniforms,
            width: s.width,
            height: s.height,
            shadow_res: s.shadow_res,
        };
        let mut g = Graph::new(&self.gpu);
        let out = build_frame(self, &mut g, inputs, s)?;
        g.export(&out);
        let done = g.execute()?;
        let bytes = done.read_image(&out)?;
        let radiance: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&bytes);
        Ok(FrameOutput {
            width: s.width,
            height: s.height,
            radiance,
            timings: done.timings.clone(),
            ran: done.ran.clone(),
            skipped: done.skipped.clone(),
        })
    }

    /// Render the dual paraboloid depth maps alone (for tests and diagnostics): distance/far per texel.
    pub fn render_dprsm(&self, s: &FrameSettings) -> Result<Vec<f32>> {
        self.check(s)?;
        let uniforms = self.uniform_buffer(s)?;
        let inputs = FrameInputs {
            scene: &self.scene,
            uniforms: &uniforms,
            width: s.width,
            height: s.height,
            shadow_res: s.shadow_res,
        };
        let mut g = Graph::new(&self.gpu);
        let shadow = self.dprsm.add(&mut g, inputs);
        g.export(&shadow.depth);
        let done = g.execute()?;
        Ok(bytemuck::pod_collect_to_vec(&done.read_image(&shadow.depth)?))
    }
}
