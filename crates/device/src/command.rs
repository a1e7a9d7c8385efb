//! One-shot submission and push-descriptor writes.

use crate::error::{Result, VkContext};
use crate::gpu::Gpu;
use crate::memory::{Buffer, Image};
use ash::vk;

impl Gpu {
    /// Record `f` into a fresh command buffer, submit it, and wait for its fence.
    pub fn submit<R>(&self, f: impl FnOnce(vk::CommandBuffer) -> R) -> Result<R> {
        self.submit_synced(&[], &[], f)
    }

    /// [`Gpu::submit`], waiting on `wait` and signalling `signal` (binary semaphores with the stages
    /// they guard): how the swapchain orders its copy between acquire and present.
    pub fn submit_synced<R>(
        &self,
        wait: &[vk::SemaphoreSubmitInfo],
        signal: &[vk::SemaphoreSubmitInfo],
        f: impl FnOnce(vk::CommandBuffer) -> R,
    ) -> Result<R> {
        let d = &self.device;
        let pool = self.command_pool.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(*pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: `*pool` is this device's command pool and `pool` (the guard) keeps it locked, which is the
        // external synchronisation vkAllocateCommandBuffers needs; `info` asks for one primary buffer.
        let cmd = unsafe { d.allocate_command_buffers(&info) }.vk("vkAllocateCommandBuffers")?[0];
        // The pool stays locked while recording: one recording thread per device, by design.
        let result = (|| {
            // SAFETY: `cmd` was just allocated (initial state) from the pool this thread keeps locked.
            unsafe {
                d.begin_command_buffer(
                    cmd,
                    &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                )
            }
            .vk("vkBeginCommandBuffer")?;
            let r = f(cmd);
            // SAFETY: `cmd` was begun above and `f` only records into it (this crate's safe API never ends
            // or resets it); its pool is still locked by this thread.
            unsafe { d.end_command_buffer(cmd) }.vk("vkEndCommandBuffer")?;
            // SAFETY: `d` is alive while `self` is; the fence is destroyed below on every path past here.
            let fence = unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None) }.vk("vkCreateFence")?;
            let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
            let submit = [vk::SubmitInfo2::default()
                .wait_semaphore_infos(wait)
                .signal_semaphore_infos(signal)
                .command_buffer_infos(&cmds)];
            // SAFETY: `cmd` is executable (ended above); `fence` is new and unsignalled; `submit` and `cmds`
            // are locals alive across the call. The queue is externally synchronised by the pool lock held
            // here, which every `submit` takes (but see `Gpu::wait_idle` and `Swapchain`'s present, which
            // use the queue without it). Caller contract for `wait`/`signal` (not checked): binary
            // semaphores of this device, each waited one with a signal pending (the swapchain's acquire).
            let submitted = unsafe { d.queue_submit2(self.queue, &submit, fence) }.vk("vkQueueSubmit2");
            let waited = submitted.and_then(|_| {
                // SAFETY: `fence` is a live fence of this device, just submitted with `cmd`.
                unsafe { d.wait_for_fences(&[fence], true, u64::MAX) }.vk("vkWaitForFences")
            });
            // SAFETY: the fence is no longer in use: either the wait above saw it signalled or the submission
            // failed and never used it. NOTE: if the wait itself fails (out of memory, device lost) the
            // submission may still be pending here.
            unsafe { d.destroy_fence(fence, None) };
            waited.map(|_| r)
        })();
        // SAFETY: `cmd` came from `*pool`, which this thread still holds locked, and it is not pending: its
        // submission was waited for, or it was never submitted (same NOTE as the fence above on a failed wait).
        unsafe { d.free_command_buffers(*pool, &[cmd]) };
        drop(pool);
        result
    }
}

enum Info {
    Buffer(vk::DescriptorBufferInfo),
    Image(vk::DescriptorImageInfo),
    TexelBuffer(vk::BufferView),
}

/// Descriptor writes for one push-descriptor set, by binding number (the constants from
/// `glsl/shared/bindings.glsl`, never positions).
#[derive(Default)]
pub struct DescriptorWrites {
    entries: Vec<(u32, vk::DescriptorType, Info)>,
}

impl DescriptorWrites {
    pub fn new() -> Self {
        Self::default()
    }
    pub fn storage_buffer(mut self, binding: u32, b: &Buffer) -> Self {
        let info = vk::DescriptorBufferInfo { buffer: b.raw, offset: 0, range: vk::WHOLE_SIZE };
        self.entries.push((binding, vk::DescriptorType::STORAGE_BUFFER, Info::Buffer(info)));
        self
    }
    pub fn uniform_buffer(mut self, binding: u32, b: &Buffer) -> Self {
        let info = vk::DescriptorBufferInfo { buffer: b.raw, offset: 0, range: vk::WHOLE_SIZE };
        self.entries.push((binding, vk::DescriptorType::UNIFORM_BUFFER, Info::Buffer(info)));
        self
    }
    pub fn storage_image(mut self, binding: u32, i: &Image) -> Self {
        let info = vk::DescriptorImageInfo {
            sampler: vk::Sampler::null(),
            image_view: i.view,
            image_layout: vk::ImageLayout::GENERAL,
        };
        self.entries.push((binding, vk::DescriptorType::STORAGE_IMAGE, Info::Image(info)));
        self
    }
    /// A sampled image read with `texelFetch` or a sampler; `layout` is the layout it is in when read.
    pub fn sampled_image(mut self, binding: u32, i: &Image, sampler: vk::Sampler) -> Self {
        let layout = if i.desc.is_depth() {
            vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL
        } else {
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL
        };
        let info = vk::DescriptorImageInfo { sampler, image_view: i.view, image_layout: layout };
        self.entries.push((binding, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, Info::Image(info)));
        self
    }

    fn texel(mut self, binding: u32, view: vk::BufferView) -> Self {
        self.entries.push((binding, vk::DescriptorType::UNIFORM_TEXEL_BUFFER, Info::TexelBuffer(view)));
        self
    }

    /// A buffer read through its view with `texelFetch` (a `usamplerBuffer`).
    pub fn uniform_texel_buffer(self, binding: u32, b: &crate::TexelBuffer) -> Self {
        self.texel(binding, b.view)
    }

    /// A storage buffer read through its `R32_UINT` view ([`Buffer::texel_view`]: made with both usages).
    pub fn texel_view(self, binding: u32, b: &Buffer) -> Self {
        self.texel(binding, b.texel_view.unwrap_or_else(|| panic!("`{}` has no texel view", b.name)))
    }

    /// A storage buffer read through its `R32G32B32A32_UINT` view ([`Buffer::texel_view4`]).
    pub fn texel_view4(self, binding: u32, b: &Buffer) -> Self {
        self.texel(binding, b.texel_view4.unwrap_or_else(|| panic!("`{}` has no uvec4 texel view", b.name)))
    }

    /// Push the set as set 0 of `layout`.
    pub fn push(
        &self,
        gpu: &Gpu,
        cmd: vk::CommandBuffer,
        bind_point: vk::PipelineBindPoint,
        layout: vk::PipelineLayout,
    ) {
        let buffers: Vec<[vk::DescriptorBufferInfo; 1]> = self
            .entries
            .iter()
            .map(|(_, _, i)| match i {
                Info::Buffer(b) => [*b],
                _ => [vk::DescriptorBufferInfo::default()],
            })
            .collect();
        let images: Vec<[vk::DescriptorImageInfo; 1]> = self
            .entries
            .iter()
            .map(|(_, _, i)| match i {
                Info::Image(b) => [*b],
                _ => [vk::DescriptorImageInfo::default()],
            })
            .collect();
        let views: Vec<[vk::BufferView; 1]> = self
            .entries
            .iter()
            .map(|(_, _, i)| match i {
                Info::TexelBuffer(v) => [*v],
                _ => [vk::BufferView::null()],
            })
            .collect();
        let writes: Vec<vk::WriteDescriptorSet> = self
            .entries
            .iter()
            .enumerate()
            .map(|(k, (binding, ty, info))| {
                let w = vk::WriteDescriptorSet::default().dst_binding(*binding).descriptor_type(*ty);
                match info {
                    Info::Buffer(_) => w.buffer_info(&buffers[k]),
                    Info::Image(_) => w.image_info(&images[k]),
                    Info::TexelBuffer(_) => w.texel_buffer_view(&views[k]),
                }
            })
            .collect();
        // SAFETY: each write points into `buffers`, `images` or `views` (one element, matching its
        // descriptor count), all alive across the call. Caller contract (not checked): `cmd` is recording
        // under `Gpu::submit`'s pool lock, `layout` is a layout of this device whose set 0 is a push-
        // descriptor layout with these bindings and types (as `ComputePipeline`/`GraphicsPipeline` make),
        // and the buffers, views and samplers written are still alive when the submission executes (this
        // struct stores raw handles, not borrows).
        unsafe { gpu.push_descriptor.cmd_push_descriptor_set(cmd, bind_point, layout, 0, &writes) };
    }
}
