//! The one access table and the barrier planner. Every barrier in bounce is planned here, from a
//! resource's [`Tracked`] state and its next [`Access`], by the pure function [`plan`], and recorded by
//! [`transition`]; no pass writes stage or access masks by hand, and nothing else records a barrier.
//!
//! The planner's rules (unit-tested below, checked on the GPU by synchronization validation):
//! - read after write: wait for the writer and make its writes visible, unless this read's stages and
//!   accesses were already made visible since that write (read after read needs nothing more);
//! - write after read / write after write: wait for every reader since the last write and for the writer;
//! - a layout change is a write: it waits like one, and afterwards only the new access is visible;
//! - a resource resumed in a new submission after a read ([`Tracked::resumed`]) waits for any earlier
//!   write and makes it visible before its next read (a fence wait does not make device writes visible).

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
    /// A swapchain image just acquired: its acquire semaphore is waited at the transfer stage, which
    /// this access names so that the first barrier chains after the wait; old contents are discarded.
    Acquired,
    /// Written by an earlier submission, at a stage no longer known ([`Tracked::resumed`]): any write.
    Earlier,
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
            Access::Earlier => (S::ALL_COMMANDS, A::MEMORY_WRITE, L::GENERAL, true),
            Access::Present => (S::NONE, A::NONE, L::PRESENT_SRC_KHR, false),
            Access::Acquired => (S::ALL_TRANSFER, A::NONE, L::UNDEFINED, false),
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
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
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

/// What the planner knows of one resource: its layout, its last write, and who read it since.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tracked {
    pub layout: vk::ImageLayout,
    pub last_write: Option<Access>,
    /// Stages that read since the last write (a later write must wait for them).
    pub readers: vk::PipelineStageFlags2,
    /// Accesses already made visible since the last write (a read among them needs no barrier).
    pub visible: vk::AccessFlags2,
    pub visible_stages: vk::PipelineStageFlags2,
    /// The last access, so a resource kept across submissions resumes from it.
    pub last: Access,
}

impl Tracked {
    /// The state of a resource whose last use was `a` and whose earlier uses are all complete and
    /// visible to `a` (a fresh resource: `Access::Nothing`). `depth`: a depth image (its read layout).
    pub fn after(a: Access, depth: bool) -> Tracked {
        let i = a.info();
        Tracked {
            layout: a.layout_for(depth),
            last_write: i.writes.then_some(a),
            readers: if i.writes { vk::PipelineStageFlags2::NONE } else { i.stage },
            visible: vk::AccessFlags2::NONE,
            visible_stages: vk::PipelineStageFlags2::NONE,
            last: a,
        }
    }

    /// The state of a resource resumed in a new submission after its last use `a` in an earlier one
    /// (a kept or persistent resource). A fence wait between them orders the submissions but makes no
    /// device write visible to the next one's device reads, and after a read `a` the write it read is no
    /// longer known: so the first access here waits for any earlier write ([`Access::Earlier`]) and
    /// makes it visible, unless `a` is itself the write (then as [`Tracked::after`]) or nothing the
    /// device wrote can be pending (unused, presented, just acquired).
    pub fn resumed(a: Access, depth: bool) -> Tracked {
        let t = Tracked::after(a, depth);
        match a {
            Access::Nothing | Access::Present | Access::Acquired => t,
            _ if t.last_write.is_some() => t,
            _ => Tracked { last_write: Some(Access::Earlier), ..t },
        }
    }
}

/// A planned barrier. Layouts matter for images only.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Barrier {
    pub src: Src,
    pub dst: Access,
    pub old_layout: vk::ImageLayout,
    pub new_layout: vk::ImageLayout,
}

/// What the next access `next` of a resource in state `s` needs: the barrier (if any) and the state
/// after it. `image_depth`: `None` for a buffer, `Some(is_depth)` for an image. Pure: no Vulkan calls.
pub fn plan(s: &Tracked, next: Access, image_depth: Option<bool>) -> (Option<Barrier>, Tracked) {
    let ni = next.info();
    let new_layout = image_depth.map(|d| next.layout_for(d));
    let layout_change = new_layout.is_some_and(|l| l != s.layout);
    let write_src = s.last_write.map(Src::of).unwrap_or_default();
    let src = if ni.writes || layout_change {
        // WAR and WAW hazards, and layout transitions (which are writes), wait for readers and writer.
        Some(Src { stage: write_src.stage | s.readers, access: write_src.access })
    } else if s.last_write.is_some() && !(s.visible.contains(ni.access) && s.visible_stages.contains(ni.stage)) {
        Some(write_src)
    } else {
        None
    };
    let mut t = *s;
    if ni.writes {
        t.last_write = Some(next);
        t.readers = vk::PipelineStageFlags2::NONE;
        t.visible = vk::AccessFlags2::NONE;
        t.visible_stages = vk::PipelineStageFlags2::NONE;
    } else {
        t.readers |= ni.stage;
        if src.is_some() {
            if layout_change {
                t.visible = ni.access;
                t.visible_stages = ni.stage;
            } else {
                t.visible |= ni.access;
                t.visible_stages |= ni.stage;
            }
        }
    }
    if let Some(l) = new_layout {
        t.layout = l;
    }
    t.last = next;
    // From `Nothing` the old contents are discarded: UNDEFINED is the honest old layout.
    let barrier = src.map(|src| Barrier {
        src,
        dst: next,
        old_layout: if image_depth.is_some() { s.layout } else { vk::ImageLayout::UNDEFINED },
        new_layout: new_layout.unwrap_or(vk::ImageLayout::UNDEFINED),
    });
    (barrier, t)
}

/// The resource a barrier applies to.
#[derive(Clone, Copy)]
pub enum Target<'a> {
    Buffer(vk::Buffer),
    Image(&'a Image),
    /// An image bounce does not own (a swapchain image): its handle and the range to transition.
    External {
        image: vk::Image,
        range: vk::ImageSubresourceRange,
    },
}

impl Target<'_> {
    fn image_depth(&self) -> Option<bool> {
        match self {
            Target::Buffer(_) => None,
            Target::Image(i) => Some(i.desc.is_depth()),
            Target::External { range, .. } => Some(range.aspect_mask.contains(vk::ImageAspectFlags::DEPTH)),
        }
    }
}

/// Plan and record the barrier (if any) that makes `target`, in state `state`, ready for `next`, and
/// advance `state`. The only way bounce records a barrier.
pub fn transition(gpu: &Gpu, cmd: vk::CommandBuffer, target: Target, state: &mut Tracked, next: Access) {
    let (barrier, after) = plan(state, next, target.image_depth());
    if let Some(b) = barrier {
        record(gpu, cmd, target, &b);
    }
    *state = after;
}

fn record(gpu: &Gpu, cmd: vk::CommandBuffer, target: Target, b: &Barrier) {
    let d = b.dst.info();
    let dep = vk::DependencyInfo::default();
    let (image, range) = match target {
        Target::Buffer(buffer) => {
            let bb = [vk::BufferMemoryBarrier2::default()
                .src_stage_mask(b.src.stage)
                .src_access_mask(b.src.access)
                .dst_stage_mask(d.stage)
                .dst_access_mask(d.access)
                .buffer(buffer)
                .size(vk::WHOLE_SIZE)];
            // SAFETY: `bb` is a local alive across the call; synchronization2 is enabled by `create_device`,
            // and the stages and accesses come from the access table. Caller contract of `transition` (not
            // checked): `cmd` is `Gpu::submit`'s command buffer, recording under its pool lock, and `buffer`
            // is a live buffer of this device that outlives the submission.
            unsafe { gpu.device.cmd_pipeline_barrier2(cmd, &dep.buffer_memory_barriers(&bb)) };
            return;
        }
        Target::Image(i) => (i.raw, i.full_range()),
        Target::External { image, range } => (image, range),
    };
    let ib = [vk::ImageMemoryBarrier2::default()
        .src_stage_mask(b.src.stage)
        .src_access_mask(b.src.access)
        .dst_stage_mask(d.stage)
        .dst_access_mask(d.access)
        .old_layout(b.old_layout)
        .new_layout(b.new_layout)
        .image(image)
        .subresource_range(range)];
    // SAFETY: `ib` is a local alive across the call; synchronization2 is enabled by `create_device`; equal
    // (zero) queue family indices mean no ownership transfer; stages, accesses and layouts come from the
    // access table. Caller contract of `transition` (not checked): `cmd` is recording under `Gpu::submit`'s
    // pool lock, and `image` (borrowed for `Target::Image`, raw for `Target::External`) is a live image of
    // this device, `range` within it, that outlives the submission.
    unsafe { gpu.device.cmd_pipeline_barrier2(cmd, &dep.image_memory_barriers(&ib)) };
}

#[cfg(test)]
mod tests {
    use super::*;
    use vk::AccessFlags2 as A;
    use vk::ImageLayout as L;
    use vk::PipelineStageFlags2 as S;

    fn buf(a: Access) -> Tracked {
        Tracked::after(a, false)
    }

    /// A resource read last in an earlier submission, read now by another stage: the write it read must
    /// be made visible again (a fence wait does not); read by the same access, or resumed after its
    /// write, as within one submission.
    #[test]
    fn a_resumed_resource_makes_earlier_writes_visible_to_its_next_reads() {
        let (b, _) = plan(&Tracked::resumed(Access::ComputeRead, false), Access::TransferRead, None);
        let b = b.expect("a barrier before the transfer read");
        assert_eq!((b.src.stage, b.src.access), (S::ALL_COMMANDS, A::MEMORY_WRITE));
        let (b, _) = plan(&Tracked::resumed(Access::ComputeWrite, false), Access::ComputeRead, None);
        assert_eq!(b.map(|b| b.src.stage), Some(S::COMPUTE_SHADER));
        assert_eq!(plan(&Tracked::resumed(Access::Nothing, false), Access::ComputeRead, None).0, None);
        // Within one submission, read after read needs nothing (the write was made visible to it).
        let (_, t) = plan(&buf(Access::ComputeWrite), Access::ComputeRead, None);
        assert_eq!(plan(&t, Access::ComputeRead, None).0, None);
    }

    #[test]
    fn read_after_write_waits_for_the_writer_and_makes_its_writes_visible() {
        let (b, t) = plan(&buf(Access::ComputeWrite), Access::FragmentRead, None);
        let b = b.expect("RAW needs a barrier");
        assert_eq!(b.src, Src { stage: S::COMPUTE_SHADER, access: A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE });
        assert_eq!(b.dst, Access::FragmentRead);
        assert_eq!(t.readers, S::FRAGMENT_SHADER);
        assert_eq!(t.last_write, Some(Access::ComputeWrite));
    }

    #[test]
    fn read_after_read_of_what_is_already_visible_needs_nothing() {
        let (_, t) = plan(&buf(Access::ComputeWrite), Access::ComputeRead, None);
        let (b, t2) = plan(&t, Access::ComputeRead, None);
        assert_eq!(b, None);
        assert_eq!(t2.readers, S::COMPUTE_SHADER);
        // A read by another stage still needs the writer's results made visible to it.
        let (b, _) = plan(&t2, Access::FragmentRead, None);
        assert_eq!(b.expect("a new stage").src.stage, S::COMPUTE_SHADER);
    }

    #[test]
    fn read_of_a_never_written_resource_needs_nothing() {
        assert_eq!(plan(&buf(Access::Nothing), Access::ComputeRead, None).0, None);
    }

    #[test]
    fn write_after_read_waits_for_every_reader_since_the_last_write() {
        let (_, t) = plan(&buf(Access::ComputeWrite), Access::FragmentRead, None);
        let (_, t) = plan(&t, Access::ComputeRead, None);
        let (b, t) = plan(&t, Access::TransferWrite, None);
        let b = b.expect("WAR needs a barrier");
        assert_eq!(b.src.stage, S::COMPUTE_SHADER | S::FRAGMENT_SHADER);
        // The writer's accesses are still made available (WAW with the earlier write).
        assert_eq!(b.src.access, A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE);
        assert_eq!(t.readers, S::NONE);
        assert_eq!(t.visible, A::NONE);
        assert_eq!(t.last_write, Some(Access::TransferWrite));
    }

    #[test]
    fn write_after_write_waits_and_makes_available() {
        let (b, t) = plan(&buf(Access::ComputeWrite), Access::ComputeWrite, None);
        let b = b.expect("WAW (serialized accumulation) needs a barrier");
        assert_eq!(b.src.stage, S::COMPUTE_SHADER);
        assert_eq!(b.src.access, A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE);
        assert_eq!(t.last, Access::ComputeWrite);
    }

    #[test]
    fn a_layout_change_is_a_write_even_for_a_read() {
        let img = Tracked::after(Access::ColorAttachment, false);
        let (_, t) = plan(&img, Access::ComputeRead, Some(false));
        assert_eq!(t.layout, L::SHADER_READ_ONLY_OPTIMAL);
        // Read → transfer read: no write in between, but the layout changes, so it waits for the reader.
        let (b, t) = plan(&t, Access::TransferRead, Some(false));
        let b = b.expect("a layout change needs a barrier");
        assert_eq!((b.old_layout, b.new_layout), (L::SHADER_READ_ONLY_OPTIMAL, L::TRANSFER_SRC_OPTIMAL));
        assert!(b.src.stage.contains(S::COMPUTE_SHADER | S::COLOR_ATTACHMENT_OUTPUT));
        // After a layout change only the new access is visible.
        assert_eq!((t.visible, t.visible_stages), (A::TRANSFER_READ, S::ALL_TRANSFER));
    }

    #[test]
    fn a_first_use_discards_from_undefined_and_depth_reads_use_the_depth_layout() {
        let (b, t) = plan(&Tracked::after(Access::Nothing, true), Access::DepthAttachment, Some(true));
        let b = b.expect("the first write transitions the layout");
        assert_eq!(b.old_layout, L::UNDEFINED);
        assert_eq!(b.src.stage, S::NONE);
        let (b, _) = plan(&t, Access::FragmentRead, Some(true));
        assert_eq!(b.expect("RAW").new_layout, L::DEPTH_READ_ONLY_OPTIMAL);
    }

    #[test]
    fn buffers_have_no_layouts() {
        let (b, _) = plan(&buf(Access::TransferWrite), Access::HostRead, None);
        let b = b.expect("RAW");
        assert_eq!((b.old_layout, b.new_layout), (L::UNDEFINED, L::UNDEFINED));
        assert_eq!(b.src, Src { stage: S::ALL_TRANSFER, access: A::TRANSFER_WRITE });
    }
}
