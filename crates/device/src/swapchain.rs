//! Presentation: a swapchain on a surface the caller created (the app owns the window and its
//! handles; this crate knows no windowing library), and two ways to show an image: a tone-mapped RGBA8
//! device image copied into the next swapchain image (`vkCmdCopyImage`, [`Swapchain::present_image`]:
//! the viewer's, nothing crosses to the host), or a host RGBA8 image copied in from a staging buffer
//! (`vkCmdCopyBufferToImage`, [`Swapchain::present_rgba8`]).
//!
//! Synchronisation, one frame in flight: the acquire semaphore is waited by the copy's submission
//! (`Gpu::submit_synced`), which completes before the next acquire; each swapchain image has its own "copied" semaphore
//! for the present to wait on (a present's wait semaphore may only be reused once that image is
//! acquired again).

use crate::error::{Error, Result, VkContext};
use crate::gpu::Gpu;
use crate::memory::{Buffer, BufferDesc, Image};
use crate::sync::{self, Access, Target, Tracked};
use ash::{khr, vk};
use gpu_allocator::MemoryLocation;

/// What [`Swapchain::present_rgba8`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Presented {
    Yes,
    /// The surface changed (resize): call [`Swapchain::recreate`] and draw again.
    OutOfDate,
}

pub struct Swapchain {
    gpu: Gpu,
    surface_fn: khr::surface::Instance,
    swapchain_fn: khr::swapchain::Device,
    surface: vk::SurfaceKHR,
    raw: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    /// B8G8R8A8_UNORM or R8G8B8A8_UNORM: the host image is already sRGB-encoded.
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub present_mode: vk::PresentModeKHR,
    vsync: bool,
    acquired: vk::Semaphore,
    copied: Vec<vk::Semaphore>,
    staging: Option<Buffer>,
}

impl Swapchain {
    /// Takes ownership of `surface` (destroyed with the swapchain). `vsync: false` asks for an
    /// immediate or mailbox present mode and falls back to FIFO (always there) when neither is.
    pub fn new(gpu: &Gpu, surface: vk::SurfaceKHR, width: u32, height: u32, vsync: bool) -> Result<Swapchain> {
        let surface_fn = khr::surface::Instance::new(&gpu.entry, &gpu.instance);
        let swapchain_fn = khr::swapchain::Device::new(&gpu.instance, &gpu.device);
        // SAFETY: `surface_fn` was loaded from this `Gpu`'s live entry and instance, and `gpu.physical` /
        // `gpu.queue_family` are this device's. Caller contract (not checked: a raw handle): `surface` is a
        // live surface created from `gpu.instance` (which implies VK_KHR_surface is enabled on it) and owned
        // by nobody else.
        let supported =
            unsafe { surface_fn.get_physical_device_surface_support(gpu.physical, gpu.queue_family, surface) }
                .unwrap_or(false);
        let d = &gpu.device;
        if !supported {
            // SAFETY: this function owns `surface` (caller contract above); no swapchain was created on it and it
            // is destroyed once, before the instance (held alive by `gpu`).
            unsafe { surface_fn.destroy_surface(surface, None) };
            return Err(Error::MissingFeature {
                device: gpu.name.clone(),
                what: "presentation to this window from its graphics queue".into(),
                hint: String::new(),
            });
        }
        // SAFETY: `d` is alive; the semaphore is destroyed in `Swapchain::drop`.
        let acquired =
            unsafe { d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }.vk("vkCreateSemaphore")?;
        let mut s = Swapchain {
            gpu: gpu.clone(),
            surface_fn,
            swapchain_fn,
            surface,
            raw: vk::SwapchainKHR::null(),
            images: vec![],
            format: vk::Format::UNDEFINED,
            extent: vk::Extent2D::default(),
            present_mode: vk::PresentModeKHR::FIFO,
            vsync,
            acquired,
            copied: vec![],
            staging: None,
        };
        if !s.recreate(width, height)? {
            return Err(Error::NoWindowArea);
        }
        Ok(s)
    }

    /// (Re)creates the swapchain for a window of `width` × `height` (the surface's own extent wins
    /// where it fixes one). `false` where that extent has no area (a minimised window, or one whose
    /// resize the surface reports before the window does): nothing is made and the old swapchain stays.
    pub fn recreate(&mut self, width: u32, height: u32) -> Result<bool> {
        let d = &self.gpu.device;
        // SAFETY: `d` is alive (this `Gpu` clone). NOTE: vkDeviceWaitIdle needs the queue externally
        // synchronised, which holds only while no other thread submits on a clone of this `Gpu` (not
        // enforced, as for `Gpu::wait_idle`).
        unsafe { d.device_wait_idle() }.vk("vkDeviceWaitIdle")?;
        let pd = self.gpu.physical;
        // SAFETY: `self.surface` is the live surface this swapchain owns, created from the instance `pd` was
        // enumerated from; `surface_fn` was loaded from that instance.
        let caps = unsafe { self.surface_fn.get_physical_device_surface_capabilities(pd, self.surface) }
            .vk("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?;
        // SAFETY: as above.
        let formats = unsafe { self.surface_fn.get_physical_device_surface_formats(pd, self.surface) }
            .vk("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
        // SAFETY: as above.
        let modes = unsafe { self.surface_fn.get_physical_device_surface_present_modes(pd, self.surface) }
            .vk("vkGetPhysicalDeviceSurfacePresentModesKHR")?;
        let format = [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM]
            .into_iter()
            .find_map(|f| formats.iter().find(|s| s.format == f).copied())
            .ok_or_else(|| Error::MissingFeature {
                device: self.gpu.name.clone(),
                what: "a B8G8R8A8_UNORM or R8G8B8A8_UNORM surface format".into(),
                hint: String::new(),
            })?;
        if !caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_DST) {
            return Err(Error::MissingFeature {
                device: self.gpu.name.clone(),
                what: "swapchain images usable as copy destinations".into(),
                hint: String::new(),
            });
        }
        let present_mode = if self.vsync {
            vk::PresentModeKHR::FIFO
        } else {
            [vk::PresentModeKHR::IMMEDIATE, vk::PresentModeKHR::MAILBOX]
                .into_iter()
                .find(|m| modes.contains(m))
                .unwrap_or(vk::PresentModeKHR::FIFO)
        };
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        if extent.width == 0 || extent.height == 0 {
            return Ok(false);
        }
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(vk::ImageUsageFlags::TRANSFER_DST)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(present_mode)
            .clipped(true)
            .old_swapchain(self.raw);
        // SAFETY: the surface is live and supports presentation from this queue family (checked in `new`);
        // format, usage (TRANSFER_DST, checked), extent (the surface's, or clamped into its range), image count
        // and present mode (listed, or FIFO, always supported) come from the surface's own queries;
        // `old_swapchain` is null or this surface's current swapchain. NOTE, not checked: the device must
        // have VK_KHR_swapchain enabled (`GpuOptions::swapchain`; `Gpu` does not record it). The extent is
        // non-zero (checked above).
        let raw = unsafe { self.swapchain_fn.create_swapchain(&info, None) }.vk("vkCreateSwapchainKHR")?;
        if self.raw != vk::SwapchainKHR::null() {
            // SAFETY: the old swapchain was retired by the create above and the device is idle (waited above),
            // so no pending command buffer writes its images; it is destroyed once, as `self.raw` is replaced.
            unsafe { self.swapchain_fn.destroy_swapchain(self.raw, None) };
        }
        self.raw = raw;
        // SAFETY: `raw` is the swapchain just created from this device.
        self.images = unsafe { self.swapchain_fn.get_swapchain_images(raw) }.vk("vkGetSwapchainImagesKHR")?;
        for s in self.copied.drain(..) {
            // SAFETY: the device is idle, so the submissions that signalled `s` are complete; each semaphore is
            // destroyed once (`drain`). NOTE: vkDeviceWaitIdle does not formally cover a present's wait on `s`
            // (only VK_EXT_swapchain_maintenance1's present fences do); this relies on the idle device.
            unsafe { d.destroy_semaphore(s, None) };
        }
        for _ in 0..self.images.len() {
            // SAFETY: `d` is alive; these are destroyed by the next `recreate` or by `Swapchain::drop`.
            let s = unsafe { d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }.vk("vkCreateSemaphore")?;
            self.copied.push(s);
        }
        self.format = format.format;
        self.extent = extent;
        self.present_mode = present_mode;
        Ok(true)
    }

    /// Copies `src` (an RGBA8 UNORM image, already sRGB-encoded and in the swapchain's channel order,
    /// made with `TRANSFER_SRC` usage) into the next swapchain image and presents it. `last` is `src`'s
    /// last access; the returned access is its new one. Where the sizes differ (a resize in flight) the
    /// overlap is copied. The two formats are both 32-bit, so the copy moves bytes unchanged.
    pub fn present_image(&mut self, src: &Image, last: Access) -> Result<(Presented, Access)> {
        let Some(index) = self.acquire()? else { return Ok((Presented::OutOfDate, last)) };
        let image = self.images[index as usize];
        let layers = vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1);
        let region = vk::ImageCopy::default().src_subresource(layers).dst_subresource(layers).extent(vk::Extent3D {
            width: src.desc.width.min(self.extent.width),
            height: src.desc.height.min(self.extent.height),
            depth: 1,
        });
        let d = self.gpu.device.clone();
        self.submit_and_present(index, |gpu, cmd| {
            let mut from = Tracked::resumed(last, false);
            sync::transition(gpu, cmd, Target::Image(src), &mut from, Access::TransferRead);
            let target = Target::External { image, range: color_range() };
            let mut state = Tracked::after(Access::Acquired, false);
            sync::transition(gpu, cmd, target, &mut state, Access::TransferWrite);
            // SAFETY: `cmd` is `submit_synced`'s command buffer, recording. The transitions just recorded put
            // `src` in TRANSFER_SRC_OPTIMAL and `image` (the swapchain image just acquired, alive while
            // `self.raw` is, which cannot change under `&mut self`) in TRANSFER_DST_OPTIMAL; the region is one
            // colour layer within both extents. `src` is borrowed past the submission, which is waited for.
            // Not checked (documented caller contract): `src` is a one-layer 32-bit colour image (size-
            // compatible with the swapchain format) made with TRANSFER_SRC usage.
            unsafe {
                d.cmd_copy_image(
                    cmd,
                    src.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                )
            };
            sync::transition(gpu, cmd, target, &mut state, Access::Present);
        })
        .map(|p| (p, Access::TransferRead))
    }

    /// The next image's index, `None` when the swapchain is out of date.
    fn acquire(&mut self) -> Result<Option<u32>> {
        // SAFETY: `self.raw` is this swapchain's live handle; `self.acquired` is unsignalled with no pending
        // operation, because every successful acquire is followed by `submit_and_present`, whose submission
        // waits on it and is itself waited for. NOTE: if an error is returned between a successful acquire
        // and that submission (e.g. the staging allocation in `present_rgba8`), the semaphore stays signalled
        // and the next acquire breaks this rule.
        match unsafe { self.swapchain_fn.acquire_next_image(self.raw, u64::MAX, self.acquired, vk::Fence::null()) } {
            Ok((index, _suboptimal)) => Ok(Some(index)),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(None),
            Err(result) => Err(Error::Vk { call: "vkAcquireNextImageKHR", result }),
        }
    }

    /// Submits `record` (which fills image `index`), waiting for the acquire and signalling that image's
    /// "copied" semaphore, then presents it. One frame in flight: this waits for the submission, so the
    /// acquire semaphore and any staging memory are free again before the next present.
    fn submit_and_present(&mut self, index: u32, record: impl FnOnce(&Gpu, vk::CommandBuffer)) -> Result<Presented> {
        let wait =
            [vk::SemaphoreSubmitInfo::default().semaphore(self.acquired).stage_mask(vk::PipelineStageFlags2::COPY)];
        let signal = [vk::SemaphoreSubmitInfo::default()
            .semaphore(self.copied[index as usize])
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let gpu = self.gpu.clone();
        self.gpu.submit_synced(&wait, &signal, |cmd| record(&gpu, cmd))?;
        let waits = [self.copied[index as usize]];
        let swapchains = [self.raw];
        let indices = [index];
        let present =
            vk::PresentInfoKHR::default().wait_semaphores(&waits).swapchains(&swapchains).image_indices(&indices);
        // SAFETY: `index` was acquired from the live `self.raw` and not presented yet; `copied[index]` was
        // signalled by the submission just waited for; `present` borrows locals alive across the call. NOTE:
        // the queue must be externally synchronised, but the present does not hold the command-pool lock
        // that `submit` takes, so another thread submitting on a clone of this `Gpu` would race with it.
        match unsafe { self.swapchain_fn.queue_present(self.gpu.queue, &present) } {
            Ok(_) => Ok(Presented::Yes),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Presented::OutOfDate),
            Err(result) => Err(Error::Vk { call: "vkQueuePresentKHR", result }),
        }
    }

    /// Copies `rgba` (`width` × `height` sRGB-encoded RGBA8, row 0 at the top) into the next swapchain
    /// image and presents it. Where the sizes differ (a resize in flight) the overlap is copied.
    pub fn present_rgba8(&mut self, width: u32, height: u32, rgba: &[u8]) -> Result<Presented> {
        assert_eq!(rgba.len(), 4 * width as usize * height as usize, "RGBA8 image size");
        let d = self.gpu.device.clone();
        let Some(index) = self.acquire()? else { return Ok(Presented::OutOfDate) };
        let size = rgba.len() as u64;
        if self.staging.as_ref().is_none_or(|b| b.size < size) {
            self.staging = Some(Buffer::new(
                &self.gpu,
                &BufferDesc {
                    name: "present.staging".into(),
                    size,
                    usage: vk::BufferUsageFlags::TRANSFER_SRC,
                    location: MemoryLocation::CpuToGpu,
                },
            )?);
        }
        let staging = self.staging.as_mut().expect("made above");
        let dst = staging.mapped_mut().expect("a CpuToGpu buffer is mapped");
        if self.format == vk::Format::B8G8R8A8_UNORM {
            for (o, i) in dst.chunks_exact_mut(4).zip(rgba.chunks_exact(4)) {
                o.copy_from_slice(&[i[2], i[1], i[0], i[3]]);
            }
        } else {
            dst[..rgba.len()].copy_from_slice(rgba);
        }
        let image = self.images[index as usize];
        let staging_raw = staging.raw;
        let copy = vk::BufferImageCopy::default()
            .buffer_row_length(width)
            .image_subresource(
                vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1),
            )
            .image_extent(vk::Extent3D {
                width: width.min(self.extent.width),
                height: height.min(self.extent.height),
                depth: 1,
            });
        self.submit_and_present(index, |gpu, cmd| {
            // The barriers come from the access table like every other: acquired (the semaphore's wait
            // at the transfer stage, old contents discarded) → copy destination → presentation.
            let target = Target::External { image, range: color_range() };
            let mut state = Tracked::after(Access::Acquired, false);
            sync::transition(gpu, cmd, target, &mut state, Access::TransferWrite);
            // SAFETY: `cmd` is `submit_synced`'s command buffer, recording; `image` is the swapchain image
            // just acquired, in TRANSFER_DST_OPTIMAL after the transition above; `staging_raw` is
            // `self.staging`, alive and unchanged until the submission (waited for) completes, holding at least
            // 4 × width × height bytes, which bounds every row the copy reads (row length `width`, at most
            // `height` rows). The staging texels have the swapchain format's byte order (swizzled above).
            // Not checked: a zero `width` or `height` makes an invalid zero-sized copy.
            unsafe {
                d.cmd_copy_buffer_to_image(cmd, staging_raw, image, vk::ImageLayout::TRANSFER_DST_OPTIMAL, &[copy])
            };
            sync::transition(gpu, cmd, target, &mut state, Access::Present);
        })
    }
}

/// The colour subresource of a swapchain image.
fn color_range() -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default().aspect_mask(vk::ImageAspectFlags::COLOR).level_count(1).layer_count(1)
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        let d = &self.gpu.device;
        // SAFETY: `d` is alive (this `Gpu` clone). Same NOTE on the queue's external synchronisation as in
        // `recreate`.
        let _ = unsafe { d.device_wait_idle() };
        // SAFETY: the device is idle, so no pending submission waits on or signals these semaphores (same
        // NOTE on presents as in `recreate`); each is destroyed once.
        unsafe {
            for s in self.copied.drain(..) {
                d.destroy_semaphore(s, None);
            }
            d.destroy_semaphore(self.acquired, None);
        }
        // SAFETY: no pending command buffer writes the swapchain's images (device idle); the swapchain is
        // destroyed before its surface, and the surface before the instance, which this `Gpu` clone keeps
        // alive; the surface is owned by this swapchain (taken in `new`).
        unsafe {
            if self.raw != vk::SwapchainKHR::null() {
                self.swapchain_fn.destroy_swapchain(self.raw, None);
            }
            self.surface_fn.destroy_surface(self.surface, None);
        }
    }
}
