//! The one access table. Every barrier in bounce goes through [`Access::info`]; no pass writes stage or
//! access masks by hand.

use crate::gpu::Gpu;
use crate::memory::Image;
use ash::vk;

/// How a pass touches a resource. One variant per use bounce has; add one here, never a raw mask.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Access {
    /// Not yet used (or contents may be discarded).
    Nothing,
    /// Read as a uniform or storage buffer, or a sampled image, by any graphics or compute stage.
    ShaderRead,
    /// Read as a sampled image (or storage buffer) by compute shaders.
    ComputeRead,
    /// Written (and maybe read) as a storage image or buffer by compute shaders.
    ComputeWrite,
    /// Read as a storage buffer or sampled image by fragment shaders.
    FragmentRead,
    /// Written as a storage buffer or image by fragment shaders (atomics included).
    FragmentWrite,
    /// Color attachment, written by rasterization.
    ColorAttachment,
    /// Depth attachment, tested and written.
    DepthAttachment,
    TransferRead,
    TransferWrite,
    HostRead,
    /// Ready for presentation by the swapchain.
    Present,
}

/// What an access means to Vulkan.
#[derive(Clone, Copy, Debug)]
pub struct AccessInfo {
    pub stage: vk::PipelineStageFlags2,
    pub access: vk::AccessFlags2,
    /// The layout an image must be in (ignored for buffers).
    pub layout: vk::ImageLayout,
    pub writes: bool,
}

impl Access {
    pub fn info(self) -> AccessInfo {
        use vk::AccessFlags2 as A;
        use vk::ImageLayout as L;
        use vk::PipelineStageFlags2 as S;
        let (stage, access, layout, writes) = match self {
            Access::Nothing => (S::NONE, A::NONE, L::UNDEFINED, false),
            Access::ShaderRead => (
                S::VERTEX_SHADER | S::GEOMETRY_SHADER | S::FRAGMENT_SHADER | S::COMPUTE_SHADER,
                A::SHADER_SAMPLED_READ | A::SHADER_STORAGE_READ | A::UNIFORM_READ,
                L::SHADER_READ_ONLY_OPTIMAL,
                false,
            ),
            Access::ComputeRead => (
                S::COMPUTE_SHADER,
                A::SHADER_SAMPLED_READ | A::SHADER_STORAGE_READ | A::UNIFORM_READ,
                L::SHADER_READ_ONLY_OPTIMAL,
                false,
            ),
            Access::ComputeWrite => {
                (S::COMPUTE_SHADER, A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE, L::GENERAL, true)
            }
            Access::FragmentRead => (
                S::FRAGMENT_SHADER,
                A::SHADER_SAMPLED_READ | A::SHADER_STORAGE_READ | A::UNIFORM_READ,
                L::SHADER_READ_ONLY_OPTIMAL,
                false,
            ),
            Access::FragmentWrite => {
                (S::FRAGMENT_SHADER, A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE, L::GENERAL, true)
            }
            Access::ColorAttachment => (
                S::COLOR_ATTACHMENT_OUTPUT,
                A::COLOR_ATTACHMENT_READ | A::COLOR_ATTACHMENT_WRITE,
                L::COLOR_ATTACHMENT_OPTIMAL,
                true,
            ),
            Access::DepthAttachment => (
                S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
                A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE,
                L::DEPTH_ATTACHMENT_OPTIMAL,
                true,
            ),
            Access::TransferRead => (S::ALL_TRANSFER, A::TRANSFER_READ, L::TRANSFER_SRC_OPTIMAL, false),
            Access::TransferWrite => (S::ALL_TRANSFER, A::TRANSFER_WRITE, L::TRANSFER_DST_OPTIMAL, true),
            Access::HostRead => (S::HOST, A::HOST_READ, L::GENERAL, false),
            Access::Present => (S::NONE, A::NONE, L::PRESENT_SRC_KHR, false),
        };
        AccessInfo { stage, access, layout, writes }
    }

    /// The layout for a depth image: depth attachments read by shaders use the read-only depth layout.
    pub fn layout_for(self, depth: bool) -> vk::ImageLayout {
        let l = self.info().layout;
        if depth && l == vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL {
            vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL
        } else {
            l
        }
    }
}

/// Source half of a barrier: what must finish (stages) and be made available (write accesses).
#[derive(Clone, Copy, Debug, Default)]
pub struct Src {
    pub stage: vk::PipelineStageFlags2,
    pub access: vk::AccessFlags2,
}

impl Src {
    pub fn of(a: Access) -> Src {
        let i = a.info();
        // Only writes need making available; reads only need the execution dependency.
        Src { stage: i.stage, access: if i.writes { i.access } else { vk::AccessFlags2::NONE } }
    }
}

/// Record a buffer barrier from `src` to `dst`.
pub fn buffer_barrier(gpu: &Gpu, cmd: vk::CommandBuffer, buffer: vk::Buffer, src: Access, dst: Access) {
    buffer_barrier_src(gpu, cmd, buffer, Src::of(src), dst)
}

pub fn buffer_barrier_src(gpu: &Gpu, cmd: vk::CommandBuffer, buffer: vk::Buffer, src: Src, dst: Access) {
    let d = dst.info();
    let b = [vk::BufferMemoryBarrier2::default()
        .src_stage_mask(src.stage)
        .src_access_mask(src.access)
        .dst_stage_mask(d.stage)
        .dst_access_mask(d.access)
        .buffer(buffer)
        .size(vk::WHOLE_SIZE)];
    unsafe { gpu.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().buffer_memory_barriers(&b)) };
}

/// Record an image barrier (with layout transition) from `src` to `dst`.
pub fn image_barrier(gpu: &Gpu, cmd: vk::CommandBuffer, image: &Image, src: Access, dst: Access) {
    let depth = image.desc.is_depth();
    image_barrier_src(gpu, cmd, image, Src::of(src), src.layout_for(depth), dst)
}

pub fn image_barrier_src(
    gpu: &Gpu,
    cmd: vk::CommandBuffer,
    image: &Image,
    src: Src,
    old_layout: vk::ImageLayout,
    dst: Access,
) {
    let d = dst.info();
    let b = [vk::ImageMemoryBarrier2::default()
        .src_stage_mask(src.stage)
        .src_access_mask(src.access)
        .dst_stage_mask(d.stage)
        .dst_access_mask(d.access)
        .old_layout(old_layout)
        .new_layout(dst.layout_for(image.desc.is_depth()))
        .image(image.raw)
        .subresource_range(image.full_range())];
    unsafe { gpu.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&b)) };
}
