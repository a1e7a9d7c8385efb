//! The pass graph: typed resource handles, passes that declare what they read and write, barriers derived
//! from the one access table, a debug label and two GPU timestamps around every pass, and culling of
//! passes whose outputs nothing consumes.
//!
//! Life of a frame: passes call [`Graph::add_pass`] with their reads and writes and a recording closure;
//! the caller marks what it wants with [`Graph::export`]; [`Graph::execute`] walks the passes backwards
//! to find the live ones, allocates transient resources, records everything into one command buffer
//! (barriers before each pass from the resources' tracked state), submits, waits, and returns an
//! [`Executed`] frame from which exported resources are read back, with per-pass GPU times.
//!
//! No reordering, aliasing or async compute: passes run in the order they were added.

use anyhow::{Context, Result};
use bounce_device::sync::{self, Access, Src};
use bounce_device::{vk, Buffer, BufferDesc, Gpu, Image, ImageDesc, TimestampPool};
use std::cell::Cell;
use std::marker::PhantomData;

/// A typed reference to a graph resource. Reads take `&Handle`, writes `&mut Handle`.
pub struct Handle<T> {
    id: usize,
    _t: PhantomData<fn() -> T>,
}

impl<T> Clone for Handle<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Handle<T> {}
impl<T> std::fmt::Debug for Handle<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Handle#{}", self.id)
    }
}

/// A resource that outlives frames (owned by a pass struct or the renderer) with its last access, so the
/// next frame's barriers start from the right state.
pub struct Persistent<T> {
    pub res: T,
    last: Cell<Access>,
}

impl<T> Persistent<T> {
    pub fn new(res: T) -> Self {
        Persistent { res, last: Cell::new(Access::Nothing) }
    }
    /// A resource whose contents were written outside the graph and are complete (e.g. an upload that
    /// waited for its fence), ready for any shader read.
    pub fn ready(res: T) -> Self {
        Persistent { res, last: Cell::new(Access::TransferWrite) }
    }
    pub fn last_access(&self) -> Access {
        self.last.get()
    }
}

enum Storage<'a> {
    TransientBuffer(BufferDesc, Option<Buffer>),
    TransientImage(ImageDesc, Option<Image>),
    ImportedBuffer(&'a Persistent<Buffer>),
    ImportedImage(&'a Persistent<Image>),
}

/// Per-resource synchronisation state while recording.
#[derive(Clone, Copy)]
struct State {
    layout: vk::ImageLayout,
    last_write: Option<Access>,
    /// Stages that read since the last write (a later write must wait for them).
    readers: vk::PipelineStageFlags2,
    /// Accesses already made visible since the last write (a read among them needs no barrier).
    visible: vk::AccessFlags2,
    visible_stages: vk::PipelineStageFlags2,
    /// The last access, handed back to a [`Persistent`] after execution.
    last: Access,
}

impl State {
    fn from_access(a: Access, depth: bool) -> State {
        let i = a.info();
        State {
            layout: a.layout_for(depth),
            last_write: i.writes.then_some(a),
            readers: if i.writes { vk::PipelineStageFlags2::NONE } else { i.stage },
            visible: vk::AccessFlags2::NONE,
            visible_stages: vk::PipelineStageFlags2::NONE,
            last: a,
        }
    }
}

struct ResourceEntry<'a> {
    name: String,
    storage: Storage<'a>,
    state: State,
}

type Record<'a> = Box<dyn FnOnce(&PassContext) + 'a>;

struct PassEntry<'a> {
    name: &'static str,
    uses: Vec<(usize, Access, Use)>,
    record: Option<Record<'a>>,
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Use {
    Read,
    /// Read-modify-write: earlier writers stay live.
    Write,
    /// Full overwrite: earlier contents are dead.
    Overwrite,
}

/// Declares one pass's resource uses; finish with [`PassBuilder::record`].
pub struct PassBuilder<'g, 'a> {
    graph: &'g mut Graph<'a>,
    pass: PassEntry<'a>,
}

impl<'g, 'a> PassBuilder<'g, 'a> {
    pub fn read<T>(mut self, h: &Handle<T>, access: Access) -> Self {
        debug_assert!(!access.info().writes, "read() with a writing access {access:?}");
        self.pass.uses.push((h.id, access, Use::Read));
        self
    }
    /// The pass writes `h` and may read what was there before.
    pub fn write<T>(mut self, h: &mut Handle<T>, access: Access) -> Self {
        debug_assert!(access.info().writes, "write() with a read-only access {access:?}");
        self.pass.uses.push((h.id, access, Use::Write));
        self
    }
    /// The pass overwrites every element of `h` (attachments it clears, images it fills completely).
    pub fn overwrite<T>(mut self, h: &mut Handle<T>, access: Access) -> Self {
        debug_assert!(access.info().writes, "overwrite() with a read-only access {access:?}");
        self.pass.uses.push((h.id, access, Use::Overwrite));
        self
    }
    pub fn record(mut self, f: impl FnOnce(&PassContext) + 'a) {
        self.pass.record = Some(Box::new(f));
        self.graph.passes.push(self.pass);
    }
}

/// What a recording closure sees: the device, the command buffer, and its resources.
pub struct PassContext<'r> {
    pub gpu: &'r Gpu,
    pub cmd: vk::CommandBuffer,
    resources: &'r [ResourceEntry<'r>],
}

impl PassContext<'_> {
    pub fn buffer(&self, h: &Handle<Buffer>) -> &Buffer {
        match &self.resources[h.id].storage {
            Storage::TransientBuffer(_, Some(b)) => b,
            Storage::ImportedBuffer(p) => &p.res,
            _ => panic!("handle {} is not a realised buffer", h.id),
        }
    }
    pub fn image(&self, h: &Handle<Image>) -> &Image {
        match &self.resources[h.id].storage {
            Storage::TransientImage(_, Some(i)) => i,
            Storage::ImportedImage(p) => &p.res,
            _ => panic!("handle {} is not a realised image", h.id),
        }
    }
}

/// GPU time of one pass that ran.
#[derive(Clone, Debug)]
pub struct PassTiming {
    pub name: &'static str,
    /// `None` when the device has no timestamps.
    pub ms: Option<f64>,
}

pub struct Graph<'a> {
    gpu: Gpu,
    resources: Vec<ResourceEntry<'a>>,
    passes: Vec<PassEntry<'a>>,
    exported: Vec<usize>,
}

impl<'a> Graph<'a> {
    pub fn new(gpu: &Gpu) -> Self {
        Graph { gpu: gpu.clone(), resources: vec![], passes: vec![], exported: vec![] }
    }

    fn push(&mut self, name: String, storage: Storage<'a>, state: State) -> usize {
        self.resources.push(ResourceEntry { name, storage, state });
        self.resources.len() - 1
    }

    /// A buffer that lives for this frame only.
    pub fn create_buffer(&mut self, desc: BufferDesc) -> Handle<Buffer> {
        let id = self.push(
            desc.name.clone(),
            Storage::TransientBuffer(desc, None),
            State::from_access(Access::Nothing, false),
        );
        Handle { id, _t: PhantomData }
    }
    /// An image that lives for this frame only.
    pub fn create_image(&mut self, desc: ImageDesc) -> Handle<Image> {
        let id = self.push(
            desc.name.clone(),
            Storage::TransientImage(desc, None),
            State::from_access(Access::Nothing, false),
        );
        Handle { id, _t: PhantomData }
    }
    pub fn import_buffer(&mut self, p: &'a Persistent<Buffer>) -> Handle<Buffer> {
        let id = self.push(p.res.name.clone(), Storage::ImportedBuffer(p), State::from_access(p.last.get(), false));
        Handle { id, _t: PhantomData }
    }
    pub fn import_image(&mut self, p: &'a Persistent<Image>) -> Handle<Image> {
        let depth = p.res.desc.is_depth();
        let id = self.push(p.res.desc.name.clone(), Storage::ImportedImage(p), State::from_access(p.last.get(), depth));
        Handle { id, _t: PhantomData }
    }

    /// Start declaring a pass. `name` is the pass's file stem: labels, timing rows and tests use it.
    pub fn add_pass<'g>(&'g mut self, name: &'static str) -> PassBuilder<'g, 'a> {
        PassBuilder { graph: self, pass: PassEntry { name, uses: vec![], record: None } }
    }

    /// Mark a resource as wanted after execution: the passes producing it are live.
    pub fn export<T>(&mut self, h: &Handle<T>) {
        self.exported.push(h.id);
    }

    /// Which passes are live: a backward walk from the exported resources.
    fn live_passes(&self) -> Vec<bool> {
        let mut live_res = vec![false; self.resources.len()];
        for &e in &self.exported {
            live_res[e] = true;
        }
        let mut live = vec![false; self.passes.len()];
        for (k, p) in self.passes.iter().enumerate().rev() {
            let needed = p.uses.iter().any(|(id, _, u)| *u != Use::Read && live_res[*id]);
            if !needed {
                continue;
            }
            live[k] = true;
            for (id, _, u) in &p.uses {
                if *u == Use::Overwrite {
                    live_res[*id] = false;
                }
            }
            for (id, _, u) in &p.uses {
                if *u != Use::Overwrite {
                    live_res[*id] = true;
                }
            }
        }
        live
    }

    /// Record, submit and wait. Returns the executed frame (exported resources, timings, pass lists).
    pub fn execute(mut self) -> Result<Executed<'a>> {
        let live = self.live_passes();
        let mut used = vec![false; self.resources.len()];
        for (p, &l) in self.passes.iter().zip(&live) {
            if l {
                for (id, _, _) in &p.uses {
                    used[*id] = true;
                }
            }
        }
        for &e in &self.exported {
            used[e] = true;
        }
        for (r, &u) in self.resources.iter_mut().zip(&used) {
            if !u {
                continue;
            }
            match &mut r.storage {
                Storage::TransientBuffer(d, slot @ None) => {
                    *slot = Some(Buffer::new(&self.gpu, d).with_context(|| format!("creating buffer `{}`", d.name))?)
                }
                Storage::TransientImage(d, slot @ None) => {
                    *slot = Some(Image::new(&self.gpu, d).with_context(|| format!("creating image `{}`", d.name))?)
                }
                _ => {}
            }
        }

        let n_live = live.iter().filter(|&&l| l).count() as u32;
        let mut ts = TimestampPool::new(&self.gpu, 2 * n_live)?;
        let mut ran = vec![];
        let mut skipped = vec![];
        let mut stamps = vec![];
        let gpu = self.gpu.clone();
        let passes = std::mem::take(&mut self.passes);
        let resources = &mut self.resources;
        gpu.submit(|cmd| {
            ts.reset(cmd);
            for (pass, is_live) in passes.into_iter().zip(live) {
                if !is_live {
                    skipped.push(pass.name);
                    continue;
                }
                for (id, access, _) in &pass.uses {
                    transition(&gpu, cmd, &mut resources[*id], *access);
                }
                gpu.begin_label(cmd, pass.name);
                let begin = ts.write(cmd);
                let ctx = PassContext { gpu: &gpu, cmd, resources: resources.as_slice() };
                (pass.record.expect("a pass is added only by record()"))(&ctx);
                let end = ts.write(cmd);
                gpu.end_label(cmd);
                ran.push(pass.name);
                stamps.push((begin, end));
            }
        })?;
        let ticks = ts.ticks()?;
        let timings = ran
            .iter()
            .zip(&stamps)
            .map(|(name, (b, e))| PassTiming {
                name,
                ms: match (b, e) {
                    (Some(b), Some(e)) if !ticks.is_empty() => Some(ts.elapsed_ms(&ticks, *b, *e)),
                    _ => None,
                },
            })
            .collect();
        for r in resources.iter() {
            match &r.storage {
                Storage::ImportedBuffer(p) => p.last.set(r.state.last),
                Storage::ImportedImage(p) => p.last.set(r.state.last),
                _ => {}
            }
        }
        Ok(Executed { resources: std::mem::take(&mut self.resources), timings, ran, skipped })
    }
}

/// Record the barrier (if any) that makes `r` ready for `next`.
fn transition(gpu: &Gpu, cmd: vk::CommandBuffer, r: &mut ResourceEntry, next: Access) {
    let ni = next.info();
    let s = &mut r.state;
    let image = match &r.storage {
        Storage::TransientImage(_, Some(i)) => Some(i),
        Storage::ImportedImage(p) => Some(&p.res),
        _ => None,
    };
    let new_layout = image.map(|i| next.layout_for(i.desc.is_depth()));
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
    if let Some(src) = src {
        match (image, &r.storage) {
            (Some(img), _) => {
                // From `Nothing` the old contents are discarded: UNDEFINED is the honest old layout.
                sync::image_barrier_src(gpu, cmd, img, src, s.layout, next);
            }
            (None, Storage::TransientBuffer(_, Some(b))) => sync::buffer_barrier_src(gpu, cmd, b.raw, src, next),
            (None, Storage::ImportedBuffer(p)) => sync::buffer_barrier_src(gpu, cmd, p.res.raw, src, next),
            _ => unreachable!("resource `{}` used before it was realised", r.name),
        }
    }
    if ni.writes {
        s.last_write = Some(next);
        s.readers = vk::PipelineStageFlags2::NONE;
        s.visible = vk::AccessFlags2::NONE;
        s.visible_stages = vk::PipelineStageFlags2::NONE;
    } else {
        s.readers |= ni.stage;
        if src.is_some() {
            if layout_change {
                s.visible = ni.access;
                s.visible_stages = ni.stage;
            } else {
                s.visible |= ni.access;
                s.visible_stages |= ni.stage;
            }
        }
    }
    if let Some(l) = new_layout {
        s.layout = l;
    }
    s.last = next;
}

/// A frame that ran: exported resources can be read back; the rest is dropped with it.
pub struct Executed<'a> {
    resources: Vec<ResourceEntry<'a>>,
    pub timings: Vec<PassTiming>,
    /// Passes recorded, in order.
    pub ran: Vec<&'static str>,
    /// Passes culled because nothing consumed their outputs.
    pub skipped: Vec<&'static str>,
}

impl Executed<'_> {
    pub fn read_image(&self, h: &Handle<Image>) -> Result<Vec<u8>> {
        let r = &self.resources[h.id];
        let img = match &r.storage {
            Storage::TransientImage(_, Some(i)) => i,
            Storage::ImportedImage(p) => &p.res,
            _ => anyhow::bail!("image `{}` was not produced (not exported?)", r.name),
        };
        let bytes = img.read_back(r.state.last)?;
        if let Storage::ImportedImage(p) = &r.storage {
            p.last.set(Access::TransferRead);
        }
        Ok(bytes)
    }
    pub fn read_buffer(&self, h: &Handle<Buffer>) -> Result<Vec<u8>> {
        let r = &self.resources[h.id];
        let b = match &r.storage {
            Storage::TransientBuffer(_, Some(b)) => b,
            Storage::ImportedBuffer(p) => &p.res,
            _ => anyhow::bail!("buffer `{}` was not produced (not exported?)", r.name),
        };
        let bytes = b.read_back(r.state.last)?;
        if let Storage::ImportedBuffer(p) = &r.storage {
            p.last.set(Access::TransferRead);
        }
        Ok(bytes)
    }
    /// Move a transient image out of the frame, with its last access, so a later graph can import it.
    pub fn take_image(&mut self, h: &Handle<Image>) -> Result<Persistent<Image>> {
        let r = &mut self.resources[h.id];
        match &mut r.storage {
            Storage::TransientImage(_, slot @ Some(_)) => {
                Ok(Persistent { res: slot.take().unwrap(), last: Cell::new(r.state.last) })
            }
            _ => anyhow::bail!("image `{}` is not a realised transient image", r.name),
        }
    }
    /// Move a transient buffer out of the frame (see [`Executed::take_image`]).
    pub fn take_buffer(&mut self, h: &Handle<Buffer>) -> Result<Persistent<Buffer>> {
        let r = &mut self.resources[h.id];
        match &mut r.storage {
            Storage::TransientBuffer(_, slot @ Some(_)) => {
                Ok(Persistent { res: slot.take().unwrap(), last: Cell::new(r.state.last) })
            }
            _ => anyhow::bail!("buffer `{}` is not a realised transient buffer", r.name),
        }
    }

    /// Total GPU time of the passes that ran, if timestamps are available.
    pub fn gpu_ms(&self) -> Option<f64> {
        self.timings.iter().map(|t| t.ms).sum()
    }
}
