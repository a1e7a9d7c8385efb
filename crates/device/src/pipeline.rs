//! Compute and graphics pipelines from SPIR-V, each with one push-descriptor set layout built from binding
//! constants, and an optional push-constant block visible to every stage.

use crate::error::{Result, VkContext};
use crate::gpu::Gpu;
use ash::vk;

/// One descriptor binding of a pipeline's set 0.
#[derive(Clone, Copy, Debug)]
pub struct Binding {
    pub binding: u32,
    pub ty: vk::DescriptorType,
}

impl Binding {
    pub const fn storage_buffer(binding: u32) -> Self {
        Binding { binding, ty: vk::DescriptorType::STORAGE_BUFFER }
    }
    pub const fn uniform_buffer(binding: u32) -> Self {
        Binding { binding, ty: vk::DescriptorType::UNIFORM_BUFFER }
    }
    pub const fn storage_image(binding: u32) -> Self {
        Binding { binding, ty: vk::DescriptorType::STORAGE_IMAGE }
    }
    pub const fn sampled_image(binding: u32) -> Self {
        Binding { binding, ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER }
    }
    pub const fn uniform_texel_buffer(binding: u32) -> Self {
        Binding { binding, ty: vk::DescriptorType::UNIFORM_TEXEL_BUFFER }
    }
}

struct Layouts {
    set: vk::DescriptorSetLayout,
    pipeline: vk::PipelineLayout,
}

fn make_layouts(gpu: &Gpu, bindings: &[Binding], push_constant_size: u32, name: &str) -> Result<Layouts> {
    let stages = vk::ShaderStageFlags::ALL_GRAPHICS | vk::ShaderStageFlags::COMPUTE;
    let b: Vec<_> = bindings
        .iter()
        .map(|b| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(b.binding)
                .descriptor_type(b.ty)
                .descriptor_count(1)
                .stage_flags(stages)
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default()
        .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
        .bindings(&b);
    // SAFETY: `gpu.device` is alive; `info` borrows the local `b`; PUSH_DESCRIPTOR_KHR is allowed because
    // `create_device` enables VK_KHR_push_descriptor. Not checked: distinct binding numbers and at most
    // maxPushDescriptors of them (the caller's `bindings`). Destroyed below on failure or by the pipeline's
    // `Drop`.
    let set = unsafe { gpu.device.create_descriptor_set_layout(&info, None) }.vk("vkCreateDescriptorSetLayout")?;
    gpu.set_name(set, name);
    let ranges = [vk::PushConstantRange { stage_flags: stages, offset: 0, size: push_constant_size }];
    let sets = [set];
    let mut pinfo = vk::PipelineLayoutCreateInfo::default().set_layouts(&sets);
    if push_constant_size > 0 {
        pinfo = pinfo.push_constant_ranges(&ranges);
    }
    // SAFETY: `pinfo` borrows `sets` (the live `set` just made) and `ranges`, locals alive across the call.
    // Not checked: `push_constant_size` a multiple of 4 and within maxPushConstantsSize.
    let pipeline = match unsafe { gpu.device.create_pipeline_layout(&pinfo, None) } {
        Ok(p) => p,
        Err(result) => {
            // SAFETY: `set` was created above from this device and nothing references it.
            unsafe { gpu.device.destroy_descriptor_set_layout(set, None) };
            return Err(crate::Error::Vk { call: "vkCreatePipelineLayout", result });
        }
    };
    Ok(Layouts { set, pipeline })
}

fn shader_module(gpu: &Gpu, words: &[u32]) -> Result<vk::ShaderModule> {
    let info = vk::ShaderModuleCreateInfo::default().code(words);
    // SAFETY: `words` is a `u32` slice (aligned, a whole number of words) alive across the call; callers
    // destroy the module right after creating their pipeline. NOTE, not checked: the spec requires `words`
    // to be valid SPIR-V for this device, and this safe path accepts any words (bounce passes only
    // shaderc output).
    unsafe { gpu.device.create_shader_module(&info, None) }.vk("vkCreateShaderModule")
}

/// Specialization constants: (constant id, u32 value).
fn spec_info<'a>(entries: &'a [vk::SpecializationMapEntry], data: &'a [u8]) -> vk::SpecializationInfo<'a> {
    vk::SpecializationInfo::default().map_entries(entries).data(data)
}

fn spec_entries(spec: &[(u32, u32)]) -> (Vec<vk::SpecializationMapEntry>, Vec<u8>) {
    let entries = spec
        .iter()
        .enumerate()
        .map(|(k, (id, _))| vk::SpecializationMapEntry { constant_id: *id, offset: 4 * k as u32, size: 4 })
        .collect();
    let data = spec.iter().flat_map(|(_, v)| v.to_ne_bytes()).collect();
    (entries, data)
}

pub struct ComputePipeline {
    pub pipeline: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    gpu: Gpu,
}

impl ComputePipeline {
    pub fn new(
        gpu: &Gpu,
        name: &str,
        spirv: &[u32],
        bindings: &[Binding],
        push_constant_size: u32,
        spec: &[(u32, u32)],
    ) -> Result<Self> {
        let l = make_layouts(gpu, bindings, push_constant_size, name)?;
        let mut me =
            ComputePipeline { pipeline: vk::Pipeline::null(), layout: l.pipeline, set_layout: l.set, gpu: gpu.clone() };
        let module = shader_module(gpu, spirv)?;
        let (entries, data) = spec_entries(spec);
        let si = spec_info(&entries, &data);
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main")
            .specialization_info(&si);
        let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(me.layout)];
        // SAFETY: `module` is live, `me.layout` was made by `make_layouts` from this device, and `info`,
        // `stage` and `si` (borrowing `entries` and `data`, consistent: 4 bytes per constant) are locals
        // alive across the call. Not checked: that the shader's interface matches the layout.
        let r = unsafe { gpu.device.create_compute_pipelines(vk::PipelineCache::null(), &info, None) };
        // SAFETY: pipeline creation has returned, and a pipeline does not need its module afterwards; the
        // module is destroyed once, whether creation succeeded or not.
        unsafe { gpu.device.destroy_shader_module(module, None) };
        me.pipeline = r.map_err(|(_, e)| e).vk("vkCreateComputePipelines")?[0];
        gpu.set_name(me.pipeline, name);
        Ok(me)
    }

    /// Bind the pipeline and push its descriptors and constants.
    pub fn bind(&self, cmd: vk::CommandBuffer, writes: &crate::DescriptorWrites, push: &[u8]) {
        let d = &self.gpu.device;
        // SAFETY: `self.pipeline` is a live compute pipeline of this device (owned by `self`). Caller contract
        // (not checked): `cmd` is `Gpu::submit`'s command buffer, recording under its pool lock, and `self`
        // outlives the submission.
        unsafe { d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline) };
        writes.push(&self.gpu, cmd, vk::PipelineBindPoint::COMPUTE, self.layout);
        if !push.is_empty() {
            // SAFETY: `self.layout` is alive (owned by `self`) and the stage flags are exactly those of its
            // push-constant range; `push` is read only during the call (ash passes its length). Caller
            // contract, as for the bind. NOTE, not checked: `push.len()` must be a multiple of 4 and at most
            // the `push_constant_size` the pipeline was made with (0: the layout has no range at all).
            unsafe {
                d.cmd_push_constants(
                    cmd,
                    self.layout,
                    vk::ShaderStageFlags::ALL_GRAPHICS | vk::ShaderStageFlags::COMPUTE,
                    0,
                    push,
                )
            };
        }
    }

    /// Bind, push, and dispatch enough `local`-sized groups to cover `size` invocations per axis.
    pub fn dispatch(
        &self,
        cmd: vk::CommandBuffer,
        writes: &crate::DescriptorWrites,
        push: &[u8],
        size: [u32; 3],
        local: [u32; 3],
    ) {
        self.bind(cmd, writes, push);
        let g = |n: u32, l: u32| n.div_ceil(l).max(1);
        // SAFETY: `bind` just bound this pipeline and pushed its descriptors on `cmd`; group counts are >= 1.
        // Caller contract, as for `bind`, plus outside a rendering instance. Not checked: the counts against
        // maxComputeWorkGroupCount.
        unsafe { self.gpu.device.cmd_dispatch(cmd, g(size[0], local[0]), g(size[1], local[1]), g(size[2], local[2])) };
    }
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        // SAFETY: all three were created from `self.gpu.device`, alive through this `Gpu` clone, and are
        // destroyed once; `pipeline` may still be null (creation failed), which vkDestroyPipeline accepts. No
        // pending command buffer uses them: every submission waits for its fence before returning.
        unsafe {
            self.gpu.device.destroy_pipeline(self.pipeline, None);
            self.gpu.device.destroy_pipeline_layout(self.layout, None);
            self.gpu.device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// A graphics pipeline for dynamic rendering: no vertex input (vertices are pulled from storage
/// buffers), no culling (every surface is two-sided), depth test `depth_compare` when a depth format is
/// given.
pub struct GraphicsPipelineDesc<'a> {
    pub name: &'a str,
    pub vertex: &'a [u32],
    pub geometry: Option<&'a [u32]>,
    pub fragment: &'a [u32],
    pub color_formats: &'a [vk::Format],
    pub depth_format: Option<vk::Format>,
    /// Depth test (with writes) when `depth_format` is set.
    pub depth_compare: vk::CompareOp,
    pub bindings: &'a [Binding],
    pub push_constant_size: u32,
    pub spec: &'a [(u32, u32)],
}

pub struct GraphicsPipeline {
    pub pipeline: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    gpu: Gpu,
}

impl GraphicsPipeline {
    pub fn new(gpu: &Gpu, desc: &GraphicsPipelineDesc) -> Result<Self> {
        let l = make_layouts(gpu, desc.bindings, desc.push_constant_size, desc.name)?;
        let mut me = GraphicsPipeline {
            pipeline: vk::Pipeline::null(),
            layout: l.pipeline,
            set_layout: l.set,
            gpu: gpu.clone(),
        };
        let mut modules = vec![(vk::ShaderStageFlags::VERTEX, shader_module(gpu, desc.vertex)?)];
        if let Some(g) = desc.geometry {
            modules.push((vk::ShaderStageFlags::GEOMETRY, shader_module(gpu, g)?));
        }
        modules.push((vk::ShaderStageFlags::FRAGMENT, shader_module(gpu, desc.fragment)?));
        let (entries, data) = spec_entries(desc.spec);
        let si = spec_info(&entries, &data);
        let stages: Vec<_> = modules
            .iter()
            .map(|(s, m)| {
                vk::PipelineShaderStageCreateInfo::default().stage(*s).module(*m).name(c"main").specialization_info(&si)
            })
            .collect();
        let vi = vk::PipelineVertexInputStateCreateInfo::default();
        let ia = vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let vp = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let rs = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let ms = vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let ds = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(desc.depth_format.is_some())
            .depth_write_enable(desc.depth_format.is_some())
            .depth_compare_op(desc.depth_compare);
        let blend: Vec<_> = desc
            .color_formats
            .iter()
            .map(|_| vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA))
            .collect();
        let cb = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend);
        let dyn_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dy = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dyn_states);
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(desc.color_formats)
            .depth_attachment_format(desc.depth_format.unwrap_or(vk::Format::UNDEFINED));
        let info = [vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vi)
            .input_assembly_state(&ia)
            .viewport_state(&vp)
            .rasterization_state(&rs)
            .multisample_state(&ms)
            .depth_stencil_state(&ds)
            .color_blend_state(&cb)
            .dynamic_state(&dy)
            .layout(me.layout)
            .push_next(&mut rendering)];
        // SAFETY: the modules are live, `me.layout` was made by `make_layouts` from this device, and every
        // state structure `info` points at (stages, `si`, `rendering` in the pNext chain, blend attachments
        // matching `color_formats`) is a local alive across the call; dynamic rendering is enabled by
        // `create_device`. Not checked: that the shaders' interface matches the layout.
        let r = unsafe { gpu.device.create_graphics_pipelines(vk::PipelineCache::null(), &info, None) };
        for (_, m) in modules {
            // SAFETY: pipeline creation has returned and no longer needs the module; each is destroyed once.
            unsafe { gpu.device.destroy_shader_module(m, None) };
        }
        me.pipeline = r.map_err(|(_, e)| e).vk("vkCreateGraphicsPipelines")?[0];
        gpu.set_name(me.pipeline, desc.name);
        Ok(me)
    }

    /// Bind the pipeline, set a full-extent viewport and scissor, push descriptors and constants.
    pub fn bind(&self, cmd: vk::CommandBuffer, extent: vk::Extent2D, writes: &crate::DescriptorWrites, push: &[u8]) {
        let d = &self.gpu.device;
        let vp = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: extent.width as f32,
            height: extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        // SAFETY: `self.pipeline` is a live graphics pipeline of this device (owned by `self`) with dynamic
        // viewport and scissor, one each, as set here. Caller contract (not checked): `cmd` is
        // `Gpu::submit`'s command buffer, recording under its pool lock, and `self` outlives the submission.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipeline);
            d.cmd_set_viewport(cmd, 0, &[vp]);
            d.cmd_set_scissor(cmd, 0, &[vk::Rect2D { offset: vk::Offset2D::default(), extent }]);
        }
        writes.push(&self.gpu, cmd, vk::PipelineBindPoint::GRAPHICS, self.layout);
        if !push.is_empty() {
            // SAFETY: `self.layout` is alive (owned by `self`) and the stage flags are exactly those of its
            // push-constant range; `push` is read only during the call (ash passes its length). Caller
            // contract, as for the bind. NOTE, not checked: `push.len()` must be a multiple of 4 and at most
            // the `push_constant_size` the pipeline was made with (0: the layout has no range at all).
            unsafe {
                d.cmd_push_constants(
                    cmd,
                    self.layout,
                    vk::ShaderStageFlags::ALL_GRAPHICS | vk::ShaderStageFlags::COMPUTE,
                    0,
                    push,
                )
            };
        }
    }
}

impl Drop for GraphicsPipeline {
    fn drop(&mut self) {
        // SAFETY: all three were created from `self.gpu.device`, alive through this `Gpu` clone, and are
        // destroyed once; `pipeline` may still be null (creation failed), which vkDestroyPipeline accepts. No
        // pending command buffer uses them: every submission waits for its fence before returning.
        unsafe {
            self.gpu.device.destroy_pipeline(self.pipeline, None);
            self.gpu.device.destroy_pipeline_layout(self.layout, None);
            self.gpu.device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
