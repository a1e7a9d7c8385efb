//! Named buffers and images on gpu-allocator memory, plus upload and readback.

use crate::error::{Error, Result, VkContext};
use crate::gpu::Gpu;
use crate::sync::{self, Access, Target, Tracked};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

#[derive(Clone, Debug, PartialEq)]
pub struct BufferDesc {
    pub name: String,
    pub size: u64,
    pub usage: vk::BufferUsageFlags,
    pub location: MemoryLocation,
}

impl BufferDesc {
    /// A device-local storage buffer that can also be copied to and from.
    pub fn storage(name: impl Into<String>, size: u64) -> Self {
        BufferDesc {
            name: name.into(),
            size,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            location: MemoryLocation::GpuOnly,
        }
    }
}

pub struct Buffer {
    pub raw: vk::Buffer,
    pub size: u64,
    pub name: String,
    /// An `R32_UINT` view of the whole buffer, made for a storage buffer whose usage also has
    /// `UNIFORM_TEXEL_BUFFER` (written as a storage buffer, read as a `usamplerBuffer`: see
    /// [`TexelBuffer`] for why).
    pub texel_view: Option<vk::BufferView>,
    /// The same as `R32G32B32A32_UINT` texels (when the size is a whole number of them).
    pub texel_view4: Option<vk::BufferView>,
    allocation: Option<Allocation>,
    gpu: Gpu,
}

impl std::fmt::Debug for Buffer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Buffer({}, {} B)", self.name, self.size)
    }
}

impl Buffer {
    pub fn new(gpu: &Gpu, desc: &BufferDesc) -> Result<Buffer> {
        // Zero-sized buffers are invalid in Vulkan; an empty upload still gets a valid 4-byte buffer.
        let size = desc.size.max(4);
        let info = vk::BufferCreateInfo::default().size(size).usage(desc.usage);
        // SAFETY: `gpu.device` is alive and `info` is a local with a non-zero size. The buffer is destroyed
        // on the allocation-failure path below or by `Buffer::drop` (which holds a `Gpu`).
        let raw = unsafe { gpu.device.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        // SAFETY: `raw` was just created from `gpu.device`.
        let requirements = unsafe { gpu.device.get_buffer_memory_requirements(raw) };
        let allocation = gpu.allocator().allocate(&AllocationCreateDesc {
            name: &desc.name,
            requirements,
            location: desc.location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(source) => {
                // SAFETY: `raw` was created above from this device and never bound or used.
                unsafe { gpu.device.destroy_buffer(raw, None) };
                return Err(Error::Alloc { name: desc.name.clone(), source });
            }
        };
        // SAFETY: `raw` is not bound yet; the allocation was made by this device's allocator from `raw`'s own
        // requirements (memory type, size, alignment), and it is freed only in `Buffer::drop`, after the
        // buffer is destroyed.
        let bound = unsafe { gpu.device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) };
        let mut buffer = Buffer {
            raw,
            size,
            name: desc.name.clone(),
            texel_view: None,
            texel_view4: None,
            allocation: Some(allocation),
            gpu: gpu.clone(),
        };
        bound.vk("vkBindBufferMemory")?;
        gpu.set_name(raw, &desc.name);
        let both = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
        if desc.usage.contains(both) {
            buffer.texel_view = Some(texel_view(gpu, &buffer, vk::Format::R32_UINT, 4)?);
            if size.is_multiple_of(16) {
                buffer.texel_view4 = Some(texel_view(gpu, &buffer, vk::Format::R32G32B32A32_UINT, 16)?);
            }
        }
        Ok(buffer)
    }

    /// Host-visible mapping, for buffers made with a CPU-visible [`MemoryLocation`].
    pub fn mapped(&self) -> Option<&[u8]> {
        self.allocation.as_ref()?.mapped_slice().map(|s| &s[..self.size as usize])
    }

    pub fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        let size = self.size as usize;
        self.allocation.as_mut()?.mapped_slice_mut().map(|s| &mut s[..size])
    }

    /// A GPU-only buffer filled with `data` (through a staging buffer; left ready for any shader read
    /// after the submission's fence, which this waits for).
    pub fn with_data(gpu: &Gpu, name: &str, usage: vk::BufferUsageFlags, data: &[u8]) -> Result<Buffer> {
        let dst = Buffer::new(
            gpu,
            &BufferDesc {
                name: name.into(),
                size: data.len() as u64,
                usage: usage | vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuOnly,
            },
        )?;
        if !data.is_empty() {
            let mut staging = Buffer::new(
                gpu,
                &BufferDesc {
                    name: format!("{name} (staging)"),
                    size: data.len() as u64,
                    usage: vk::BufferUsageFlags::TRANSFER_SRC,
                    location: MemoryLocation::CpuToGpu,
                },
            )?;
            staging.mapped_mut().expect("CpuToGpu memory is mapped")[..data.len()].copy_from_slice(data);
            gpu.submit(|cmd| {
                let region = vk::BufferCopy::default().size(data.len() as u64);
                // SAFETY: `cmd` is `submit`'s command buffer, recording. `staging` (TRANSFER_SRC) and `dst`
                // (TRANSFER_DST) are live buffers of this device holding at least `data.len()` bytes, and
                // both outlive the submission (`submit` waits for its fence). The host write above is
                // visible to the copy: the memory is host-coherent and submission orders earlier host writes.
                unsafe { gpu.device.cmd_copy_buffer(cmd, staging.raw, dst.raw, &[region]) };
                // Such buffers are bound without the graph's tracking, read by any shader of later
                // submissions: the copy is made visible to them here (a fence wait alone does not).
                let mut state = Tracked::after(Access::TransferWrite, false);
                sync::transition(gpu, cmd, Target::Buffer(dst.raw), &mut state, Access::ShaderRead);
            })?;
        }
        Ok(dst)
    }

    /// Copy the whole buffer back to the CPU. `current` is how it was last used (the barrier from it to a
    /// transfer read is recorded here); waits for completion.
    pub fn read_back(&self, current: Access) -> Result<Vec<u8>> {
        let gpu = &self.gpu;
        gpu.count_readback();
        let staging = Buffer::new(
            gpu,
            &BufferDesc {
                name: format!("{} (readback)", self.name),
                size: self.size,
                usage: vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuToCpu,
            },
        )?;
        gpu.submit(|cmd| {
            let mut state = Tracked::resumed(current, false);
            sync::transition(gpu, cmd, Target::Buffer(self.raw), &mut state, Access::TransferRead);
            let region = vk::BufferCopy::default().size(self.size);
            // SAFETY: `cmd` is `submit`'s command buffer, recording. `self` and `staging` are live buffers of
            // this device, both `self.size` bytes, alive until the submission completes (`submit` waits);
            // the barrier just recorded orders the copy after `current`. Not checked: that `self` was made
            // with TRANSFER_SRC usage (the caller's `BufferDesc`).
            unsafe { gpu.device.cmd_copy_buffer(cmd, self.raw, staging.raw, &[region]) };
            let mut staged = Tracked::after(Access::TransferWrite, false);
            sync::transition(gpu, cmd, Target::Buffer(staging.raw), &mut staged, Access::HostRead);
        })?;
        Ok(staging.mapped().expect("GpuToCpu memory is mapped").to_vec())
    }
}

/// A view of the whole of `b` as texels of `format` (`texel_bytes` each), within the device's limit.
fn texel_view(gpu: &Gpu, b: &Buffer, format: vk::Format, texel_bytes: u64) -> Result<vk::BufferView> {
    let texels = b.size / texel_bytes;
    let max = gpu.limits().max_texel_buffer_elements as u64;
    if texels > max {
        return Err(Error::Limit {
            what: format!("`{}` ({texels} texels)", b.name),
            limit: "maxTexelBufferElements",
            value: texels,
            max,
        });
    }
    let info = vk::BufferViewCreateInfo::default().buffer(b.raw).format(format).offset(0).range(texels * texel_bytes);
    // SAFETY: `b.raw` is a live, bound buffer of this device made with UNIFORM_TEXEL_BUFFER usage (both
    // callers ensure it); the range is a whole number of texels within its size and within
    // maxTexelBufferElements (checked above), and R32_UINT / R32G32B32A32_UINT are mandatory uniform-texel-
    // buffer formats. The view is destroyed before the buffer (`Buffer::drop`, `TexelBuffer::drop`).
    let view = unsafe { gpu.device.create_buffer_view(&info, None) }.vk("vkCreateBufferView")?;
    gpu.set_name(view, &b.name);
    Ok(view)
}

impl Drop for Buffer {
    fn drop(&mut self) {
        for v in [self.texel_view.take(), self.texel_view4.take()].into_iter().flatten() {
            // SAFETY: `v` was created from `self.raw` by `self.gpu.device` (alive: this `Gpu` clone), is
            // destroyed once (`take`), and no pending command buffer uses it: every submission waits for its
            // fence before returning.
            unsafe { self.gpu.device.destroy_buffer_view(v, None) };
        }
        // SAFETY: as above: a buffer of this live device, no longer used by the GPU; its views are gone and
        // its memory is freed only after this.
        unsafe { self.gpu.device.destroy_buffer(self.raw, None) };
        if let Some(a) = self.allocation.take() {
            let _ = self.gpu.allocator().free(a);
        }
    }
}

/// A read-only buffer of 16-byte texels (`R32G32B32A32_UINT`) with its view, for `usamplerBuffer`
/// `texelFetch`: on llvmpipe a texel fetch loads a vector's lanes as one gather, where a storage-buffer
/// read with a different index per lane loads them one by one.
pub struct TexelBuffer {
    pub buffer: Buffer,
    pub view: vk::BufferView,
}

impl TexelBuffer {
    /// Uploads `data` (whole 16-byte texels, at most `maxTexelBufferElements` of them) and makes its view.
    pub fn with_data(gpu: &Gpu, name: &str, data: &[u8]) -> Result<TexelBuffer> {
        assert!(data.len().is_multiple_of(16) && !data.is_empty(), "{name}: whole 16-byte texels");
        let buffer = Buffer::with_data(gpu, name, vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER, data)?;
        let view = texel_view(gpu, &buffer, vk::Format::R32G32B32A32_UINT, 16)?;
        Ok(TexelBuffer { buffer, view })
    }
}

impl Drop for TexelBuffer {
    fn drop(&mut self) {
        // SAFETY: `self.view` was created from `self.buffer` by its (live) device and is destroyed here, before
        // the `buffer` field drops; no pending command buffer uses it (every submission waits for its fence).
        unsafe { self.buffer.gpu.device.destroy_buffer_view(self.view, None) };
    }
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImageDesc {
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// Array layers.
    pub layers: u32,
    /// Viewed as a 2D array (set by [`ImageDesc::layers`], also for one layer: shaders that index
    /// layers need an array view whatever the count); otherwise a plain 2D image.
    pub array: bool,
    pub format: vk::Format,
    pub usage: vk::ImageUsageFlags,
}

impl ImageDesc {
    pub fn new(
        name: impl Into<String>,
        width: u32,
        height: u32,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
    ) -> Self {
        ImageDesc { name: name.into(), width, height, layers: 1, array: false, format, usage }
    }
    pub fn layers(mut self, layers: u32) -> Self {
        self.layers = layers;
        self.array = true;
        self
    }
    pub fn is_depth(&self) -> bool {
        is_depth_format(self.format)
    }
}

pub fn is_depth_format(f: vk::Format) -> bool {
    matches!(
        f,
        vk::Format::D32_SFLOAT | vk::Format::D16_UNORM | vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT
    )
}

/// Bytes per texel of the formats bounce reads back.
pub fn texel_size(f: vk::Format) -> u64 {
    match f {
        vk::Format::R32G32B32A32_SFLOAT | vk::Format::R32G32B32A32_UINT => 16,
        vk::Format::R16G16B16A16_SFLOAT => 8,
        vk::Format::R32_SFLOAT | vk::Format::D32_SFLOAT | vk::Format::R32_UINT => 4,
        vk::Format::R8G8B8A8_UNORM | vk::Format::R8G8B8A8_SRGB | vk::Format::B8G8R8A8_UNORM => 4,
        vk::Format::R32G32_SFLOAT => 8,
        other => panic!("texel_size: format {other:?} is not used by bounce"),
    }
}

pub struct Image {
    pub raw: vk::Image,
    /// The whole image: `TYPE_2D`, or `TYPE_2D_ARRAY` for array images; null when the usage takes no
    /// view (transfer only).
    pub view: vk::ImageView,
    pub desc: ImageDesc,
    allocation: Option<Allocation>,
    gpu: Gpu,
}

impl std::fmt::Debug for Image {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Image({}, {}x{}x{} {:?})",
            self.desc.name, self.desc.width, self.desc.height, self.desc.layers, self.desc.format
        )
    }
}

impl Image {
    pub fn new(gpu: &Gpu, desc: &ImageDesc) -> Result<Image> {
        let max = gpu.limits().max_image_dimension2_d;
        for (what, v) in [("width", desc.width), ("height", desc.height)] {
            if v == 0 || v > max {
                return Err(Error::Limit {
                    what: format!("image `{}` {what}", desc.name),
                    limit: "maxImageDimension2D",
                    value: v as u64,
                    max: max as u64,
                });
            }
        }
        let max_layers = gpu.limits().max_image_array_layers;
        if desc.layers == 0 || desc.layers > max_layers {
            return Err(Error::Limit {
                what: format!("image `{}` layers", desc.name),
                limit: "maxImageArrayLayers",
                value: desc.layers as u64,
                max: max_layers as u64,
            });
        }
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D { width: desc.width, height: desc.height, depth: 1 })
            .mip_levels(1)
            .array_layers(desc.layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: `gpu.device` is alive; extent and layer count are within the device limits (checked
        // above), with one mip level and one sample. Not checked: that the format supports `desc.usage`
        // (the caller's `ImageDesc`). The image is destroyed below on failure or by `Image::drop`.
        let raw = unsafe { gpu.device.create_image(&info, None) }.vk("vkCreateImage")?;
        // SAFETY: `raw` was just created from `gpu.device`.
        let requirements = unsafe { gpu.device.get_image_memory_requirements(raw) };
        let allocation = match gpu.allocator().allocate(&AllocationCreateDesc {
            name: &desc.name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        }) {
            Ok(a) => a,
            Err(source) => {
                // SAFETY: `raw` was created above from this device and never bound or used.
                unsafe { gpu.device.destroy_image(raw, None) };
                return Err(Error::Alloc { name: desc.name.clone(), source });
            }
        };
        let mut image = Image {
            raw,
            view: vk::ImageView::null(),
            desc: desc.clone(),
            allocation: Some(allocation),
            gpu: gpu.clone(),
        };
        let a = image.allocation.as_ref().unwrap();
        // SAFETY: `raw` is not bound yet; `a` was allocated by this device's allocator from `raw`'s own
        // requirements (non-linear, as the image is OPTIMAL-tiled), and is freed only in `Image::drop`, after
        // the image is destroyed.
        unsafe { gpu.device.bind_image_memory(raw, a.memory(), a.offset()) }.vk("vkBindImageMemory")?;
        // Views exist only for usages that take one (a transfer-only image has none).
        let viewable = vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
            | vk::ImageUsageFlags::INPUT_ATTACHMENT;
        if !desc.usage.intersects(viewable) {
            gpu.set_name(raw, &desc.name);
            return Ok(image);
        }
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(if desc.array { vk::ImageViewType::TYPE_2D_ARRAY } else { vk::ImageViewType::TYPE_2D })
            .format(desc.format)
            .subresource_range(image.full_range());
        // SAFETY: `raw` is a live image of this device, bound to memory above; the view has its format and
        // covers all its layers and its one mip level with its aspect. Not checked: a non-`array` desc must
        // have one layer for a TYPE_2D view (`ImageDesc`'s constructors ensure it; its fields are public).
        // The view is destroyed before the image in `Image::drop`.
        image.view = unsafe { gpu.device.create_image_view(&view_info, None) }.vk("vkCreateImageView")?;
        gpu.set_name(raw, &desc.name);
        gpu.set_name(image.view, &desc.name);
        Ok(image)
    }

    pub fn aspect(&self) -> vk::ImageAspectFlags {
        if self.desc.is_depth() {
            vk::ImageAspectFlags::DEPTH
        } else {
            vk::ImageAspectFlags::COLOR
        }
    }

    pub fn full_range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange::default().aspect_mask(self.aspect()).level_count(1).layer_count(self.desc.layers)
    }

    pub fn extent(&self) -> vk::Extent2D {
        vk::Extent2D { width: self.desc.width, height: self.desc.height }
    }

    /// Copy every layer back to the CPU (tightly packed, layer after layer). `current` is the image's
    /// last access; the image is left in [`Access::TransferRead`].
    pub fn read_back(&self, current: Access) -> Result<Vec<u8>> {
        let gpu = &self.gpu;
        gpu.count_readback();
        let layer_bytes = self.desc.width as u64 * self.desc.height as u64 * texel_size(self.desc.format);
        let staging = Buffer::new(
            gpu,
            &BufferDesc {
                name: format!("{} (readback)", self.desc.name),
                size: layer_bytes * self.desc.layers as u64,
                usage: vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuToCpu,
            },
        )?;
        gpu.submit(|cmd| {
            let mut state = Tracked::resumed(current, self.desc.is_depth());
            sync::transition(gpu, cmd, Target::Image(self), &mut state, Access::TransferRead);
            let region = vk::BufferImageCopy::default()
                .image_subresource(
                    vk::ImageSubresourceLayers::default().aspect_mask(self.aspect()).layer_count(self.desc.layers),
                )
                .image_extent(vk::Extent3D { width: self.desc.width, height: self.desc.height, depth: 1 });
            // SAFETY: `cmd` is `submit`'s command buffer, recording. The transition just recorded put the
            // image in TRANSFER_SRC_OPTIMAL; the region is its whole single-aspect extent, all layers, mip 0;
            // `staging` holds exactly that many tightly packed texels (`texel_size` panics for formats it
            // does not know). Both outlive the submission (`submit` waits). Not checked: that the image was
            // made with TRANSFER_SRC usage (the caller's `ImageDesc`).
            unsafe {
                gpu.device.cmd_copy_image_to_buffer(
                    cmd,
                    self.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    staging.raw,
                    &[region],
                )
            };
            let mut staged = Tracked::after(Access::TransferWrite, false);
            sync::transition(gpu, cmd, Target::Buffer(staging.raw), &mut staged, Access::HostRead);
        })?;
        Ok(staging.mapped().expect("GpuToCpu memory is mapped")[..(layer_bytes * self.desc.layers as u64) as usize]
            .to_vec())
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: the view (if any) and the image were created from `self.gpu.device`, alive through this
        // `Gpu` clone; the view goes first, the memory only after; no pending command buffer uses them, since
        // every submission waits for its fence before returning.
        unsafe {
            if self.view != vk::ImageView::null() {
                self.gpu.device.destroy_image_view(self.view, None);
            }
            self.gpu.device.destroy_image(self.raw, None);
        }
        if let Some(a) = self.allocation.take() {
            let _ = self.gpu.allocator().free(a);
        }
    }
}

/// A sampler that destroys itself.
pub struct Sampler {
    pub raw: vk::Sampler,
    gpu: Gpu,
}

impl Sampler {
    /// Nearest filtering, clamp to edge: bounce reads textures with `texelFetch`-exact semantics.
    pub fn nearest(gpu: &Gpu) -> Result<Sampler> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(0.0);
        // SAFETY: `gpu.device` is alive and `info` is a local; the sampler is destroyed in `Sampler::drop`.
        let raw = unsafe { gpu.device.create_sampler(&info, None) }.vk("vkCreateSampler")?;
        Ok(Sampler { raw, gpu: gpu.clone() })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // SAFETY: created from `self.gpu.device`, alive through this clone; no pending command buffer uses it,
        // since every submission waits for its fence before returning.
        unsafe { self.gpu.device.destroy_sampler(self.raw, None) };
    }
}
