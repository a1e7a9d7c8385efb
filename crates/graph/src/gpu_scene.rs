//! The scene on the GPU: uploaded once, read-only afterwards. Because nothing writes these buffers after
//! the upload (which waits for its fence), the graph does not track them; passes bind them with
//! [`GpuScene::writes`] at the binding numbers of `glsl/shared/scene.glsl`.
//!
//! The lights are the exception: they are frame state (`Renderer::set_light`), so their buffer is
//! host-visible and rewritten by [`GpuScene::write_lights`] before each frame is recorded. Every frame
//! waits for its submission, so no GPU work reads the buffer while the host writes it, and a host write
//! before `vkQueueSubmit` is visible to the submission without a barrier. The bounds (and so the voxel
//! grid and the paraboloid far plane) stay those of the upload: a light should stay inside them.

use crate::bindings::*;
use crate::scene::Scene;
use crate::shader_types::Light;
use anyhow::{Context, Result};
use bounce_device::{vk, Buffer, BufferDesc, DescriptorWrites, Gpu, MemoryLocation};
use glam::Vec3;

pub struct GpuScene {
    pub vertices: Buffer,
    pub tri_material: Buffer,
    pub materials: Buffer,
    pub textures: Buffer,
    pub texels: Buffer,
    pub lights: Buffer,
    pub triangle_count: u32,
    pub light_count: u32,
    /// Bounds of the geometry and the lights together.
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
}

impl GpuScene {
    pub fn upload(gpu: &Gpu, scene: &Scene) -> Result<Self> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let up = |name: &str, bytes: &[u8]| {
            Buffer::with_data(gpu, name, storage, bytes).with_context(|| format!("uploading {name}"))
        };
        let max_range = gpu.limits().max_storage_buffer_range as u64;
        // A scene too large for the device is the user's to change (a smaller texture): a settings error.
        for (what, n) in [("vertex buffer", scene.vertices.len() * 32), ("texel buffer", scene.texels.len() * 4)] {
            if n as u64 > max_range {
                return Err(crate::frame::SettingsError(format!(
                    "the scene's {what} ({n} bytes) exceeds the device limit maxStorageBufferRange ({max_range} bytes)"
                ))
                .into());
            }
        }
        let (mut lo, mut hi) = (scene.bounds_min, scene.bounds_max);
        if scene.vertices.is_empty() {
            lo = Vec3::splat(f32::MAX);
            hi = Vec3::splat(f32::MIN);
        }
        for l in &scene.lights {
            let p = Vec3::from_slice(&l.position[..3]);
            lo = lo.min(p);
            hi = hi.max(p);
        }
        Ok(GpuScene {
            vertices: up("vertices", bytemuck::cast_slice(&scene.vertices))?,
            tri_material: up("tri_material", bytemuck::cast_slice(&scene.tri_material))?,
            materials: up("materials", bytemuck::cast_slice(&scene.materials))?,
            textures: up("textures", bytemuck::cast_slice(&scene.textures))?,
            texels: up("texels", bytemuck::cast_slice(&scene.texels))?,
            lights: lights_buffer(gpu, &scene.lights)?,
            triangle_count: scene.tri_material.len() as u32,
            light_count: scene.lights.len() as u32,
            bounds_min: lo,
            bounds_max: hi,
        })
    }

    /// Writes `lights` (as many as the scene has) into the light buffer; the same records give the same
    /// bits as the upload did, so a static light renders the same image.
    pub fn write_lights(&mut self, lights: &[Light]) -> Result<()> {
        anyhow::ensure!(lights.len() == self.light_count as usize, "the scene has {} lights", self.light_count);
        let bytes: &[u8] = bytemuck::cast_slice(lights);
        let dst = self.lights.mapped_mut().context("the light buffer is not host-visible")?;
        dst[..bytes.len()].copy_from_slice(bytes);
        Ok(())
    }

    /// Length of the diagonal of the bounds (geometry and lights).
    pub fn diagonal(&self) -> f32 {
        (self.bounds_max - self.bounds_min).length().max(1e-6)
    }

    /// The scene bindings plus the frame's uniform buffer.
    pub fn writes(&self, uniforms: &Buffer) -> DescriptorWrites {
        DescriptorWrites::new()
            .uniform_buffer(B_FRAME, uniforms)
            .storage_buffer(B_VERTICES, &self.vertices)
            .storage_buffer(B_TRI_MATERIAL, &self.tri_material)
            .storage_buffer(B_MATERIALS, &self.materials)
            .storage_buffer(B_TEXTURES, &self.textures)
            .storage_buffer(B_TEXELS, &self.texels)
            .storage_buffer(B_LIGHTS, &self.lights)
    }
}

/// The host-visible light buffer, holding `lights`.
fn lights_buffer(gpu: &Gpu, lights: &[Light]) -> Result<Buffer> {
    let bytes: &[u8] = bytemuck::cast_slice(lights);
    let mut b = Buffer::new(
        gpu,
        &BufferDesc {
            name: "lights".into(),
            size: bytes.len().max(4) as u64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::CpuToGpu,
        },
    )
    .context("creating the light buffer")?;
    b.mapped_mut().context("the light buffer is not host-visible")?[..bytes.len()].copy_from_slice(bytes);
    Ok(b)
}

/// The descriptor bindings of the scene, for pipeline layouts.
pub fn scene_bindings() -> Vec<bounce_device::Binding> {
    use bounce_device::Binding;
    vec![
        Binding::uniform_buffer(B_FRAME),
        Binding::storage_buffer(B_VERTICES),
        Binding::storage_buffer(B_TRI_MATERIAL),
        Binding::storage_buffer(B_MATERIALS),
        Binding::storage_buffer(B_TEXTURES),
        Binding::storage_buffer(B_TEXELS),
        Binding::storage_buffer(B_LIGHTS),
    ]
}
