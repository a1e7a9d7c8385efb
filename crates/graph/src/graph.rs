//! The pass graph: typed resource handles, passes that declare what they read and write, barriers planned
//! from the one access table (`bounce_device::sync`), a debug label and two GPU timestamps around every
//! pass, culling of passes whose outputs nothing consumes, and the resources that outlive a frame.
//!
//! Life of a frame: passes call [`Graph::add_pass`] with their reads and writes and a recording closure;
//! the caller marks what it wants with [`Graph::export`]; [`Graph::execute`] walks the passes backwards
//! to find the live ones, allocates transient resources, records everything into one command buffer
//! (before each pass, the planner's barriers from the resources' tracked state), submits, waits, and
//! returns an [`Executed`] frame from which exported resources are read back, with per-pass GPU times.
//!
//! **Across frames** (kajiya's `get_or_create_temporal`, generalised to keyed products): a graph made
//! with [`Graph::with_retained`] borrows a [`Retained`] store.
//! - [`Graph::cached`] asks for a pass's products under a name and a key built from everything they
//!   depend on. With a stored product of that name and key, its resources are lent to this graph and the
//!   build closure does not run (its passes are not even added); otherwise the closure adds the passes,
//!   and when they ran, the products are kept for the next graph. The recipe asks the same way either
//!   way, so it has no branch on what is cached. The product a new key replaced is lent for that graph
//!   only ([`Graph::replaced`]: last frame's VPLs after a light moved).
//! - [`Graph::temporal_image`] / [`Graph::temporal_buffer`] are one resource per name that lives across
//!   graphs (accumulators), recreated empty when its description or key changes; [`Graph::history_image`]
//!   is this frame's and last frame's version of one (ping-pong, swapped by [`Retained::next_frame`]).
//!
//! The store is handed back when the [`Executed`] frame is dropped, with each resource's last access, so
//! the next graph's barriers start from the right state. Resources owned outside the graph (test inputs)
//! are imported from a [`Persistent`]. No reordering, aliasing or async compute: passes run in the order
//! they were added.

use anyhow::{Context, Result};
use bounce_device::sync::{self, Access, Target, Tracked};
use bounce_device::{vk, Buffer, BufferDesc, Gpu, Image, ImageDesc, TimestampPool};
use std::cell::Cell;
use std::hash::{Hash, Hasher};
use std::marker::PhantomData;

mod products;
mod retained;
pub use products::{Products, RawHandle};
pub use retained::Retained;
use retained::{Kept, Product, TemporalSlot};

/// A typed reference to a graph resource. Reads take `&Handle`, writes `&mut Handle`.
pub struct Handle<T> {
    id: usize,
    _t: PhantomData<fn() -> T>,
}

impl<T> Handle<T> {
    fn new(id: usize) -> Self {
        Handle { id, _t: PhantomData }
    }
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

/// A resource owned outside the graph (a test's uploaded input), with its last access, so the next
/// graph's barriers start from the right state.
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
    /// After a use outside any graph (the swapchain's copy of the viewer's picture).
    pub fn set_last_access(&self, access: Access) {
        self.last.set(access);
    }
}

/// A realised resource the graph keeps between frames.
enum Res {
    Buffer(Buffer),
    Image(Image),
}

impl Res {
    fn depth(&self) -> bool {
        matches!(self, Res::Image(i) if i.desc.is_depth())
    }
}

/// A stable 64-bit fingerprint of a cache key (std's SipHash with fixed keys: the same in every run).
pub fn fingerprint(key: &impl Hash) -> u64 {
    #[allow(deprecated)]
    let mut h = std::hash::SipHasher::new();
    key.hash(&mut h);
    h.finish()
}

/// A temporal resource as a graph lends it.
#[derive(Clone, Copy, Debug)]
pub struct Temporal<T> {
    pub handle: Handle<T>,
    /// The contents are undefined (just made, or its description or key changed): the first pass must
    /// overwrite rather than add to it.
    pub fresh: bool,
}

/// This frame's and last frame's version of a temporal image.
#[derive(Clone, Copy, Debug)]
pub struct History<T = Image> {
    pub current: Handle<T>,
    /// Last frame's version, `None` when there is none with the same description (first frame, resize).
    pub previous: Option<Handle<T>>,
}

enum Storage<'a> {
    TransientBuffer(BufferDesc, Option<Buffer>),
    TransientImage(ImageDesc, Option<Image>),
    /// Lent by the [`Retained`] store (a cached product or a temporal resource).
    Lent(Res),
    ExternalBuffer(&'a Persistent<Buffer>),
    ExternalImage(&'a Persistent<Image>),
    /// Moved back to the store when the frame ended.
    Returned,
}

impl Storage<'_> {
    fn buffer(&self) -> Option<&Buffer> {
        match self {
            Storage::TransientBuffer(_, Some(b)) | Storage::Lent(Res::Buffer(b)) => Some(b),
            Storage::ExternalBuffer(p) => Some(&p.res),
            _ => None,
        }
    }
    fn image(&self) -> Option<&Image> {
        match self {
            Storage::TransientImage(_, Some(i)) | Storage::Lent(Res::Image(i)) => Some(i),
            Storage::ExternalImage(p) => Some(&p.res),
            _ => None,
        }
    }
    /// Realised and owned by the graph (transient or lent), so it can be kept.
    fn keepable(&self) -> bool {
        matches!(self, Storage::TransientBuffer(_, Some(_)) | Storage::TransientImage(_, Some(_)) | Storage::Lent(_))
    }
    fn target(&self) -> Option<Target<'_>> {
        self.image().map(Target::Image).or_else(|| self.buffer().map(|b| Target::Buffer(b.raw)))
    }
    /// Move the realised resource out (to keep it); `None` if it was never realised or is external.
    fn take(&mut self) -> Option<Res> {
        match std::mem::replace(self, Storage::Returned) {
            Storage::TransientBuffer(_, Some(b)) => Some(Res::Buffer(b)),
            Storage::TransientImage(_, Some(i)) => Some(Res::Image(i)),
            Storage::Lent(r) => Some(r),
            other => {
                *self = other;
                None
            }
        }
    }
}

/// Where a resource goes when the frame is done.
#[derive(Clone, Debug)]
enum Home {
    /// Dropped with the frame (or, if a cached product claims it, kept with that product).
    Frame,
    /// Back to the store's temporal slot of this name, made for this fingerprint.
    Temporal(String, u64),
}

struct ResourceEntry<'a> {
    name: String,
    storage: Storage<'a>,
    /// Interior mutability so a pass can serialize its own commands through the planner while it
    /// holds references to other resources ([`PassContext::serialize`]).
    state: Cell<Tracked>,
    home: Home,
}

impl ResourceEntry<'_> {
    /// Plan and record the barrier that makes this resource ready for `next`.
    fn transition(&self, gpu: &Gpu, cmd: vk::CommandBuffer, next: Access) {
        let target = self.storage.target().unwrap_or_else(|| panic!("`{}` used before it was realised", self.name));
        let mut s = self.state.get();
        sync::transition(gpu, cmd, target, &mut s, next);
        self.state.set(s);
    }
}

type Record<'a> = Box<dyn FnOnce(&PassContext) + 'a>;

struct PassEntry<'a> {
    name: &'static str,
    uses: Vec<(usize, Access, Use)>,
    record: Option<Record<'a>>,
    /// Added by a [`Graph::cached`] build: the next frame with its key will not run it.
    kept: bool,
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

/// What a recording closure sees: the device, the command buffer, and the resources it declared.
pub struct PassContext<'r> {
    pub gpu: &'r Gpu,
    pub cmd: vk::CommandBuffer,
    resources: &'r [ResourceEntry<'r>],
    declared: &'r [(usize, Access, Use)],
}

impl PassContext<'_> {
    /// The access this pass declared for resource `id`. A handle it did not declare is a bug that would
    /// go without a barrier, in release builds too: it panics (a scan of the pass's few uses).
    fn declared(&self, id: usize) -> Access {
        let found = self.declared.iter().find(|(d, _, _)| *d == id).map(|(_, a, _)| *a);
        found.unwrap_or_else(|| panic!("pass used `{}` without declaring it", self.resources[id].name))
    }
    pub fn buffer(&self, h: &Handle<Buffer>) -> &Buffer {
        self.declared(h.id);
        let r = &self.resources[h.id];
        r.storage.buffer().unwrap_or_else(|| panic!("`{}` is not a realised buffer", r.name))
    }
    pub fn image(&self, h: &Handle<Image>) -> &Image {
        self.declared(h.id);
        let r = &self.resources[h.id];
        r.storage.image().unwrap_or_else(|| panic!("`{}` is not a realised image", r.name))
    }
    /// Serialized accumulation inside one pass: the pass's next command reads or adds to what its
    /// previous command wrote to `h`. The planner records the write-after-write barrier from `h`'s tracked
    /// state to the access the pass declared for it.
    pub fn serialize<T>(&self, h: &Handle<T>) {
        let access = self.declared(h.id);
        assert!(access.info().writes, "serialize() on `{}`, which this pass only reads", self.resources[h.id].name);
        self.resources[h.id].transition(self.gpu, self.cmd, access);
    }
}

/// GPU time of one pass that ran.
#[derive(Clone, Debug)]
pub struct PassTiming {
    pub name: &'static str,
    /// The pass makes a product the graph keeps ([`Graph::cached`]): a next frame with its key skips it.
    pub kept: bool,
    /// `None` when the device has no timestamps.
    pub ms: Option<f64>,
}

/// One [`Graph::cached`] request: its key and its handles.
struct Request {
    key: u64,
    handles: Vec<RawHandle>,
}

pub struct Graph<'a> {
    gpu: Gpu,
    resources: Vec<ResourceEntry<'a>>,
    passes: Vec<PassEntry<'a>>,
    exported: Vec<usize>,
    retained: Option<&'a mut Retained>,
    requests: Vec<(&'static str, Request)>,
    /// Products that [`Graph::try_cached`] found under another key: kept for this graph only, for
    /// [`Graph::replaced`].
    replaced: Vec<(&'static str, Vec<Kept>)>,
    /// How deep in [`Graph::cached`] builds the passes being added are.
    building: u32,
}

impl<'a> Graph<'a> {
    /// A graph that keeps nothing across frames (`cached` always builds).
    pub fn new(gpu: &Gpu) -> Self {
        Graph {
            gpu: gpu.clone(),
            resources: vec![],
            passes: vec![],
            exported: vec![],
            retained: None,
            requests: vec![],
            replaced: vec![],
            building: 0,
        }
    }

    /// A graph that borrows `retained` for its cached products and temporal resources.
    pub fn with_retained(gpu: &Gpu, retained: &'a mut Retained) -> Self {
        Graph { retained: Some(retained), ..Graph::new(gpu) }
    }

    fn push(&mut self, name: String, storage: Storage<'a>, state: Tracked, home: Home) -> usize {
        self.resources.push(ResourceEntry { name, storage, state: Cell::new(state), home });
        self.resources.len() - 1
    }

    /// A buffer that lives for this frame only.
    pub fn create_buffer(&mut self, desc: BufferDesc) -> Handle<Buffer> {
        let name = desc.name.clone();
        Handle::new(self.push(
            name,
            Storage::TransientBuffer(desc, None),
            Tracked::after(Access::Nothing, false),
            Home::Frame,
        ))
    }
    /// An image that lives for this frame only.
    pub fn create_image(&mut self, desc: ImageDesc) -> Handle<Image> {
        let name = desc.name.clone();
        Handle::new(self.push(
            name,
            Storage::TransientImage(desc, None),
            Tracked::after(Access::Nothing, false),
            Home::Frame,
        ))
    }
    pub fn import_buffer(&mut self, p: &'a Persistent<Buffer>) -> Handle<Buffer> {
        let state = Tracked::resumed(p.last.get(), false);
        Handle::new(self.push(p.res.name.clone(), Storage::ExternalBuffer(p), state, Home::Frame))
    }
    pub fn import_image(&mut self, p: &'a Persistent<Image>) -> Handle<Image> {
        let state = Tracked::resumed(p.last.get(), p.res.desc.is_depth());
        Handle::new(self.push(p.res.desc.name.clone(), Storage::ExternalImage(p), state, Home::Frame))
    }

    /// The products of `build` under `name`, kept across frames while `key` stays the same. With a kept
    /// product of this name and key, its resources are lent to this graph and `build` does not run;
    /// otherwise `build` adds its passes, and if they run, what it returns is kept (an older product of
    /// the name is dropped). Asking twice in one graph returns the same handles.
    pub fn cached<P: Products>(
        &mut self,
        name: &'static str,
        key: &impl Hash,
        build: impl FnOnce(&mut Self) -> P,
    ) -> P {
        match self.try_cached(name, key, |g| Ok::<P, std::convert::Infallible>(build(g))) {
            Ok(p) => p,
            Err(never) => match never {},
        }
    }

    /// [`Graph::cached`] with a `build` that may fail (a pass whose pipeline is built on first use):
    /// its error is returned and nothing is kept.
    pub fn try_cached<P: Products, E>(
        &mut self,
        name: &'static str,
        key: &impl Hash,
        build: impl FnOnce(&mut Self) -> Result<P, E>,
    ) -> Result<P, E> {
        let key = fingerprint(key);
        if let Some((_, r)) = self.requests.iter().find(|(n, r)| *n == name && r.key == key) {
            return Ok(P::from_handles(&mut r.handles.iter().copied()));
        }
        let mut stale = None;
        let kept = self.retained.as_mut().and_then(|st| match st.products.remove(name) {
            Some(p) if p.key == key => Some(p.resources),
            // A product made under another key is stale: kept for this graph only (`replaced`), then
            // freed with it (no GPU work is pending on it).
            Some(p) => {
                stale = Some(p.resources);
                None
            }
            None => None,
        });
        if let Some(resources) = stale {
            self.replaced.push((name, resources));
        }
        let p = match kept {
            Some(resources) => {
                let handles: Vec<RawHandle> = resources.into_iter().map(|k| self.lend(name, k)).collect();
                P::from_handles(&mut handles.iter().copied())
            }
            None => {
                self.building += 1;
                let built = build(self);
                self.building -= 1;
                built?
            }
        };
        let mut handles = vec![];
        p.handles(&mut handles);
        // Each resource is kept once: a product naming one twice (or a temporal resource, which has its
        // own slot) would be taken twice when the frame hands them back.
        let own = |h: &RawHandle| matches!(self.resources[h.id].home, Home::Frame);
        assert!(
            handles.iter().enumerate().all(|(i, h)| own(h) && handles[..i].iter().all(|g| g.id != h.id)),
            "cached product `{name}` names a resource twice, or a temporal one"
        );
        self.requests.push((name, Request { key, handles }));
        Ok(p)
    }

    /// The product that `name` held before this graph asked for it under another key (last frame's VPLs
    /// after a light moved), lent for this frame only; `None` when the key was the same or nothing was
    /// kept. Ask after [`Graph::cached`] under `name`.
    pub fn replaced<P: Products>(&mut self, name: &'static str) -> Option<P> {
        let at = self.replaced.iter().position(|(n, _)| *n == name)?;
        let (_, resources) = self.replaced.swap_remove(at);
        let handles: Vec<RawHandle> = resources.into_iter().map(|k| self.lend(name, k)).collect();
        Some(P::from_handles(&mut handles.iter().copied()))
    }

    fn lend(&mut self, name: &str, k: Kept) -> RawHandle {
        let image = matches!(k.res, Res::Image(_));
        let state = Tracked::resumed(k.last, k.res.depth());
        let res_name = match &k.res {
            Res::Image(i) => i.desc.name.clone(),
            Res::Buffer(b) => b.name.clone(),
        };
        RawHandle { id: self.push(format!("{res_name} ({name})"), Storage::Lent(k.res), state, Home::Frame), image }
    }

    fn temporal(&mut self, name: &str, fingerprint: u64, fresh_storage: Storage<'a>) -> (usize, bool) {
        // Asked twice in one graph: the same resource.
        let same = |r: &ResourceEntry| matches!(&r.home, Home::Temporal(n, f) if n == name && *f == fingerprint);
        if let Some(id) = self.resources.iter().position(same) {
            return (id, false);
        }
        let slot = self.retained.as_mut().and_then(|st| st.temporal.remove(name));
        let home = Home::Temporal(name.to_string(), fingerprint);
        match slot {
            Some(s) if s.fingerprint == fingerprint => {
                let state = Tracked::resumed(s.kept.last, s.kept.res.depth());
                (self.push(name.to_string(), Storage::Lent(s.kept.res), state, home), false)
            }
            _ => (self.push(name.to_string(), fresh_storage, Tracked::after(Access::Nothing, false), home), true),
        }
    }

    /// An image that lives across graphs under `name` (an accumulator), recreated with undefined contents
    /// when `desc` or `key` changes. Without a [`Retained`] store it lives for this frame only.
    pub fn temporal_image(&mut self, name: &str, desc: ImageDesc, key: &impl Hash) -> Temporal<Image> {
        let fp = fingerprint(&(format!("{desc:?}"), fingerprint(key)));
        let (id, fresh) = self.temporal(name, fp, Storage::TransientImage(desc, None));
        Temporal { handle: Handle::new(id), fresh }
    }

    /// The temporal image `name` (see [`Graph::temporal_image`]) where an earlier graph, or this one, made
    /// it with this `desc` and `key`; `None` (and nothing made) otherwise. For state that only a writer
    /// may create: a reader that made it would find undefined contents in the next frames.
    pub fn existing_temporal_image(&mut self, name: &str, desc: &ImageDesc, key: &impl Hash) -> Option<Handle<Image>> {
        let fp = fingerprint(&(format!("{desc:?}"), fingerprint(key)));
        let here = self.resources.iter().any(|r| matches!(&r.home, Home::Temporal(n, f) if n == name && *f == fp));
        let kept = self.retained.as_ref().and_then(|st| st.temporal.get(name)).is_some_and(|s| s.fingerprint == fp);
        (here || kept).then(|| self.temporal_image(name, desc.clone(), key).handle)
    }

    /// A buffer that lives across graphs under `name` (see [`Graph::temporal_image`]).
    pub fn temporal_buffer(&mut self, name: &str, desc: BufferDesc, key: &impl Hash) -> Temporal<Buffer> {
        let fp = fingerprint(&(format!("{desc:?}"), fingerprint(key)));
        let (id, fresh) = self.temporal(name, fp, Storage::TransientBuffer(desc, None));
        Temporal { handle: Handle::new(id), fresh }
    }

    /// The slots of history `name` for this frame: (current, previous). They swap at each frame that uses
    /// the history, not at each frame: a frame of another method between two that use it (the viewer's
    /// still frame) leaves it as it was, so the next use finds the last use's version, not the one before.
    fn history_slots(&mut self, name: &str) -> (String, String) {
        let uses = match self.retained.as_mut() {
            Some(st) => {
                let frame = st.frame;
                let e = st.histories.entry(name.to_string()).or_insert((0, frame));
                if e.1 != frame {
                    *e = (e.0 + 1, frame);
                }
                e.0
            }
            None => 0,
        };
        (format!("{name}#{}", uses % 2), format!("{name}#{}", (uses + 1) % 2))
    }

    /// This frame's and the last use's version of an image (two temporal images that swap roles at each
    /// frame that uses them). `previous` is `None` when that version has another description or key, or
    /// was never written. The frames between two uses must not have moved what the history follows (the
    /// camera, the lights): the renderer forgets the histories where they did
    /// ([`Retained::forget_histories`]). This frame's version is exported: the passes that write it run
    /// even where nothing later in the frame reads it (the next use does).
    pub fn history_image(&mut self, name: &str, desc: ImageDesc, key: &impl Hash) -> History {
        let (now, before) = self.history_slots(name);
        let current = self.temporal_image(&now, desc.clone(), key).handle;
        let previous = self.temporal_image(&before, desc, key);
        // What writes this frame's version is live whether or not this frame reads it: the next use does.
        self.export(&current);
        History { current, previous: (!previous.fresh).then_some(previous.handle) }
    }

    /// This frame's and the last use's version of a buffer (see [`Graph::history_image`]).
    pub fn history_buffer(&mut self, name: &str, desc: BufferDesc, key: &impl Hash) -> History<Buffer> {
        let (now, before) = self.history_slots(name);
        let current = self.temporal_buffer(&now, desc.clone(), key).handle;
        let previous = self.temporal_buffer(&before, desc, key);
        self.export(&current);
        History { current, previous: (!previous.fresh).then_some(previous.handle) }
    }

    /// Start declaring a pass. `name` is the pass's file stem: labels, timing rows and tests use it.
    pub fn add_pass<'g>(&'g mut self, name: &'static str) -> PassBuilder<'g, 'a> {
        let kept = self.building > 0;
        PassBuilder { graph: self, pass: PassEntry { name, uses: vec![], record: None, kept } }
    }

    /// A pass `name` that zeroes `buffers` (a transfer fill): accumulators the next passes add into.
    pub fn add_clear(&mut self, name: &'static str, buffers: &mut [&mut Handle<Buffer>]) {
        let handles: Vec<Handle<Buffer>> = buffers.iter().map(|h| **h).collect();
        let mut pass = self.add_pass(name);
        for h in buffers.iter_mut() {
            pass = pass.overwrite(*h, Access::TransferWrite);
        }
        pass.record(move |ctx| {
            for h in &handles {
                unsafe { ctx.gpu.device.cmd_fill_buffer(ctx.cmd, ctx.buffer(h).raw, 0, vk::WHOLE_SIZE, 0) };
            }
        });
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

    /// Create the transient resources that live passes use or that are exported.
    fn realise(&mut self, live: &[bool]) -> Result<()> {
        let mut used = vec![false; self.resources.len()];
        for (p, _) in self.passes.iter().zip(live).filter(|(_, &l)| l) {
            for (id, _, _) in &p.uses {
                used[*id] = true;
            }
        }
        for &e in &self.exported {
            used[e] = true;
        }
        for (r, _) in self.resources.iter_mut().zip(&used).filter(|(_, &u)| u) {
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
        Ok(())
    }

    /// Record, submit and wait. Returns the executed frame (exported resources, timings, pass lists).
    pub fn execute(mut self) -> Result<Executed<'a>> {
        let live = self.live_passes();
        self.realise(&live)?;
        let n_live = live.iter().filter(|&&l| l).count() as u32;
        let mut ts = TimestampPool::new(&self.gpu, 2 * n_live)?;
        let (mut ran, mut skipped, mut stamps) = (vec![], vec![], vec![]);
        let gpu = self.gpu.clone();
        let passes = std::mem::take(&mut self.passes);
        let resources = &self.resources;
        gpu.submit(|cmd| {
            ts.reset(cmd);
            for (pass, is_live) in passes.into_iter().zip(live) {
                if !is_live {
                    skipped.push(pass.name);
                    continue;
                }
                for (id, access, _) in &pass.uses {
                    resources[*id].transition(&gpu, cmd, *access);
                }
                gpu.begin_label(cmd, pass.name);
                let begin = ts.write(cmd);
                let ctx = PassContext { gpu: &gpu, cmd, resources: resources.as_slice(), declared: &pass.uses };
                (pass.record.expect("a pass is added only by record()"))(&ctx);
                let end = ts.write(cmd);
                gpu.end_label(cmd);
                ran.push(pass.name);
                stamps.push((begin, end, pass.kept));
            }
        })?;
        // The frame ran whatever its timestamps say: one that cannot be read leaves it untimed, and the
        // frame's resources still go back with their states (dropping them here would lose both).
        let ticks = ts.ticks().unwrap_or_default();
        let timings = ran
            .iter()
            .zip(&stamps)
            .map(|(name, (b, e, kept))| PassTiming {
                name,
                kept: *kept,
                ms: match (b, e) {
                    (Some(b), Some(e)) if !ticks.is_empty() => Some(ts.elapsed_ms(&ticks, *b, *e)),
                    _ => None,
                },
            })
            .collect();
        Ok(Executed {
            resources: std::mem::take(&mut self.resources),
            retained: self.retained.take(),
            requests: std::mem::take(&mut self.requests),
            timings,
            ran,
            skipped,
        })
    }
}

/// A frame that ran: exported resources can be read back; when it is dropped, kept products and temporal
/// resources go back to the [`Retained`] store and the rest is freed.
pub struct Executed<'a> {
    resources: Vec<ResourceEntry<'a>>,
    retained: Option<&'a mut Retained>,
    requests: Vec<(&'static str, Request)>,
    pub timings: Vec<PassTiming>,
    /// Passes recorded, in order.
    pub ran: Vec<&'static str>,
    /// Passes culled because nothing consumed their outputs.
    pub skipped: Vec<&'static str>,
}

impl Executed<'_> {
    pub fn read_image(&self, h: &Handle<Image>) -> Result<Vec<u8>> {
        let r = &self.resources[h.id];
        let img = r.storage.image().with_context(|| format!("image `{}` was not produced (not exported?)", r.name))?;
        let bytes = img.read_back(r.state.get().last)?;
        self.after_read_back(r);
        Ok(bytes)
    }
    pub fn read_buffer(&self, h: &Handle<Buffer>) -> Result<Vec<u8>> {
        let r = &self.resources[h.id];
        let b = r.storage.buffer().with_context(|| format!("buffer `{}` was not produced (not exported?)", r.name))?;
        let bytes = b.read_back(r.state.get().last)?;
        self.after_read_back(r);
        Ok(bytes)
    }
    /// A read-back leaves the resource in `TransferRead`, its readback's fence waited.
    fn after_read_back(&self, r: &ResourceEntry) {
        r.state.set(Tracked::after(Access::TransferRead, false));
        match &r.storage {
            Storage::ExternalBuffer(p) => p.last.set(Access::TransferRead),
            Storage::ExternalImage(p) => p.last.set(Access::TransferRead),
            _ => {}
        }
    }

    /// Total GPU time of the passes that ran, if timestamps are available.
    pub fn gpu_ms(&self) -> Option<f64> {
        self.timings.iter().map(|t| t.ms).sum()
    }
}

impl Drop for Executed<'_> {
    /// Hand kept products and temporal resources back to the store, with their last accesses; external
    /// resources get their last access back too.
    fn drop(&mut self) {
        for r in &self.resources {
            match &r.storage {
                Storage::ExternalBuffer(p) => p.last.set(r.state.get().last),
                Storage::ExternalImage(p) => p.last.set(r.state.get().last),
                _ => {}
            }
        }
        let Some(store) = self.retained.as_mut() else { return };
        for (name, req) in std::mem::take(&mut self.requests) {
            // A product is kept only whole: every resource realised (its passes ran) and not yet claimed.
            if !req.handles.iter().all(|h| self.resources[h.id].storage.keepable()) {
                continue;
            }
            let resources = req
                .handles
                .iter()
                .map(|h| {
                    let r = &mut self.resources[h.id];
                    Kept { last: r.state.get().last, res: r.storage.take().expect("checked complete") }
                })
                .collect();
            store.products.insert(name, Product { key: req.key, resources });
        }
        for r in &mut self.resources {
            if let Home::Temporal(name, fingerprint) = r.home.clone() {
                if let Some(res) = r.storage.take() {
                    let kept = Kept { last: r.state.get().last, res };
                    store.temporal.insert(name, TemporalSlot { fingerprint, kept });
                }
            }
        }
    }
}
