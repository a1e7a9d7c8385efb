//! The GPU layout of the BVH: the SAH tree of [`super::build`] flattened to the nodes and triangles
//! that shaders ray cast against (`glsl/shared/bvh.glsl`: `bvh_closest`, `bvh_occluded`), for exact
//! visibility where the voxel march is too coarse.
//!
//! Owns: the flattening ([`FlatBvh`]; the graph crate's `gpu_bvh` uploads it), the layout mirrors ([`GpuBvhNode`], [`GpuBvhTri`]) and the
//! constants the shaders share ([`MAX_STEPS`], [`STACK_SIZE`], [`SHADOW_EPS`], the binding numbers).
//! The traversal itself is in `bvh.glsl`, whose header is its contract.
//!
//! **Why the SAH tree's shape.** The CPU reference (`bounce-oracles`) casts its f64 rays through the
//! same [`Bvh`], so the GPU and the reference it is checked against walk the same tree. Only its shape
//! is taken: the boxes are recomputed here in f32 from the f32 vertices (min/max are exact, so a box
//! holds its triangles exactly).
//!
//! **Layout** (three read-only `uvec4` texel buffers, bindings [`B_BVH_NODES`], [`B_BVH_TRIS`] and
//! [`B_BVH_THREADED`], holding the std430 bytes below; texel buffers because llvmpipe fetches a texel
//! for a whole SIMD vector at once, where a storage-buffer read with a per-lane index goes lane by lane:
//! measured 1.8× on Sibenik's shadow rays, BENCHMARKS.md):
//! * nodes: [`GpuBvhNode`] `{ vec3 lo; uint first; vec3 hi; uint count; }`, 32 bytes. A leaf
//!   (`count > 0`) holds `tris[first .. first + count]`; an interior node (`count == 0`) has the
//!   children `first` and `first + 1`, adjacent so that one visit reads both boxes (the traversal tests
//!   both and descends into the nearer first). Node 0 is the root; children always come after their
//!   parent.
//! * tris: [`GpuBvhTri`] `{ vec3 v0; uint tri; vec3 v1; uint -; vec3 v2; uint -; }`, 48 bytes: the
//!   three positions of scene triangle `tri` (vertices `3·tri .. 3·tri + 3`), copied in leaf order so
//!   that a leaf is one contiguous run (coherent reads, no index indirection). The scene's vertex
//!   buffer is not reused: its 96 bytes per triangle interleave normals and uvs the traversal never
//!   reads. Zero-area triangles are absent (never hit, as in the CPU reference). A scene without
//!   triangles becomes one leaf holding one degenerate triangle that nothing hits.
//! * threaded: [`GpuThreadRec`], 48 bytes, [`FlatBvh::threaded`]: the same tree in depth-first preorder,
//!   one record per triangle (its positions) and per node whose box is worth testing
//!   ([`FlatBvh::box_records`]: its box and the index past its subtree), for the stackless any-hit walk
//!   of the shadow rays (`bvh_any_hit`). A box record whose successor is a box also holds that box,
//!   packed into its own ([`super::quant`]), so a step that meets it tests both.
//!
//! **Depth and stack.** The traversal keeps a stack of [`STACK_SIZE`] = 64 entries, and a tree of
//! height h (levels below the root) needs at most h. The SAH builder may go deeper on pathological
//! input (it switches to median splits only at depth [`super::build::MEDIAN_DEPTH`]), so
//! [`FlatBvh::new`] copies the tree where it can and rebuilds a subtree by median splits (each halves the count, height
//! ⌈log2(n / 2)⌉) wherever a child would otherwise be unable to fit below the limit: the result never
//! exceeds 64 levels for any triangle count the buffers can hold. On real scenes nothing is rebuilt.
//!
//! **Iteration bound.** An occlusion test (`bvh_occluded*`) and `bvh_closest_walk` walk the threaded
//! records forward, at most min([`MAX_STEPS`], records + 1) steps, [`THREAD_UNROLL`] steps to a loop
//! iteration: `GpuBvh::max_iterations_occluded`. The stack traversal (`bvh_trace`, behind
//! `bvh_closest`) runs one loop of at most [`MAX_STEPS`] iterations (one triangle
//! test, node visit or culled pop each; see `bvh.glsl`), and never more than nodes + triangles + 1:
//! `GpuBvh::max_iterations_per_ray` (the graph crate's upload) is the smaller of the two, an honest upper bound of either. llvmpipe stops
//! every loop of an invocation after 65535 iterations in total (`bounce_device::Gpu`'s
//! `loop_iteration_limit`), so a shader that traces n rays per invocation needs
//! n · `max_iterations_per_ray()` + (its other loop iterations) ≤ the limit, and must otherwise split
//! its rays over dispatches. A trace that reaches the bound answers "no hit" / "not occluded" and sets
//! `bvh_exhausted`. Measured worst cases, in iterations per trace (lavapipe; tests/tests/bvh.rs, and
//! once on the archive scenes with 20,000 gather-like rays from surface points and 20,000 segments
//! between surface points, a third of them lifted to skim the surfaces): 41 on the Cornell box (where
//! the bound is 74: nodes + triangles + 1), 237 on the 52k sphere, 324 on the 301k terrain, 169 on
//! Sibenik (75k triangles), 355 on Conference (278k hittable triangles), and 1,152 for horizontal rays
//! skimming a 301k-triangle rippled floor, the worst case found. 16384 is 14× that, and still lets an
//! llvmpipe invocation make 3 full-length traces.
//!
//! **Bindings.** [`B_BVH_NODES`], [`B_BVH_TRIS`], [`MAX_STEPS`] and [`STACK_SIZE`] come from
//! `glsl/shared/bindings.glsl` (generated constants); a test checks the rest of `bvh.glsl`'s constants.

use super::build::Bvh;
use super::quant;
use crate::layout::Vertex;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::mem::{offset_of, size_of};

pub use crate::bindings::{B_BVH_NODES, B_BVH_THREADED, B_BVH_TRIS};
/// The link bit of a threaded triangle record (`BVH_THREAD_TRI`).
pub const THREAD_TRI: u32 = crate::bindings::BVH_THREAD_TRI;
/// Steps of the threaded walk per loop iteration (`BVH_THREAD_UNROLL`).
pub const THREAD_UNROLL: u32 = crate::bindings::BVH_THREAD_UNROLL;
const _: () = assert!(MAX_STEPS.is_multiple_of(THREAD_UNROLL));
/// Most loop iterations of one trace (`BVH_MAX_STEPS`); see the module doc.
pub const MAX_STEPS: u32 = crate::bindings::BVH_MAX_STEPS;
/// Traversal stack entries, and the most levels below the root a tree may have (`BVH_STACK_SIZE`).
pub const STACK_SIZE: u32 = crate::bindings::BVH_STACK_SIZE;
/// The triangle index of "no hit" (`BVH_NO_TRI`).
pub const NO_TRI: u32 = crate::bindings::BVH_NO_TRI;
/// Relative end epsilon of `bvh_occluded` (`BVH_SHADOW_EPS` of `glsl/shared/bindings.glsl`): only
/// occluders at segment parameter `t ∈ (SHADOW_EPS, 1 − SHADOW_EPS)` count. Relative (not absolute) so it
/// scales with the scene: it keeps a segment's own end surfaces (and a light lying on a surface) from
/// occluding, while an occluder closer than 0.01 % of the segment length to either end is ignored.
pub const SHADOW_EPS: f32 = crate::bindings::BVH_SHADOW_EPS;
/// Triangles per leaf of a median-rebuilt subtree (the SAH builder's smallest leaf, too).
const MEDIAN_LEAF: u32 = 2;

/// A node: box `[lo, hi]`; a leaf (`count > 0`) holds `tris[first .. first + count]`, an interior node
/// (`count == 0`) has the children `first` and `first + 1`. GLSL: `BvhNode`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuBvhNode {
    pub lo: [f32; 3],
    pub first: u32,
    pub hi: [f32; 3],
    pub count: u32,
}
const _: () = assert!(size_of::<GpuBvhNode>() == 32);
const _: () = assert!(offset_of!(GpuBvhNode, first) == 12);
const _: () = assert!(offset_of!(GpuBvhNode, hi) == 16);
const _: () = assert!(offset_of!(GpuBvhNode, count) == 28);

/// A triangle's vertex positions and its scene index. GLSL: `BvhTri`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuBvhTri {
    pub v0: [f32; 3],
    /// Scene triangle index (vertices `3·tri .. 3·tri + 3`).
    pub tri: u32,
    pub v1: [f32; 3],
    pub pad1: u32,
    pub v2: [f32; 3],
    pub pad2: u32,
}
const _: () = assert!(size_of::<GpuBvhTri>() == 48);
const _: () = assert!(offset_of!(GpuBvhTri, tri) == 12);
const _: () = assert!(offset_of!(GpuBvhTri, v1) == 16);
const _: () = assert!(offset_of!(GpuBvhTri, v2) == 32);

/// A record of the threaded layout ([`FlatBvh::threaded`]): a box (`a` = lo, `b` = hi, `link` = the index
/// of the first record after its subtree; where the next record is a box too, `c` holds the bits of that
/// box packed into three words and `pad2` its link, else `pad2` = 0: [`super::quant`]) or a triangle
/// (`a`, `b`, `c` its positions, `link` = [`THREAD_TRI`], `tri` the scene triangle, which the closest-hit
/// walk reports; the next record follows). GLSL: the walk's steps in `bvh.glsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuThreadRec {
    pub a: [f32; 3],
    pub link: u32,
    pub b: [f32; 3],
    /// The scene triangle of a triangle record (0 for a box).
    pub tri: u32,
    pub c: [f32; 3],
    pub pad2: u32,
}
const _: () = assert!(size_of::<GpuThreadRec>() == 48);
const _: () = assert!(offset_of!(GpuThreadRec, link) == 12);
const _: () = assert!(offset_of!(GpuThreadRec, b) == 16);
const _: () = assert!(offset_of!(GpuThreadRec, c) == 32);

impl GpuBvhTri {
    pub fn positions(&self) -> [Vec3; 3] {
        [Vec3::from(self.v0), Vec3::from(self.v1), Vec3::from(self.v2)]
    }
}

impl GpuBvhNode {
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// The GPU layout on the CPU: what the graph crate's `GpuBvh` uploads.
#[derive(Clone, Debug)]
pub struct FlatBvh {
    pub nodes: Vec<GpuBvhNode>,
    /// In leaf order; never empty (see the module doc for a scene without triangles).
    pub tris: Vec<GpuBvhTri>,
    /// Scene triangles that can be hit (`tris.len()`, or 0 for a scene without any).
    pub triangle_count: u32,
    /// Levels below the root (a lone root leaf: 0); at most [`STACK_SIZE`].
    pub height: u32,
    /// Subtrees of the SAH tree rebuilt by median splits to fit the height limit (0 on real scenes).
    pub rebuilt_subtrees: u32,
}

/// Height of a median-split tree over `n` triangles: halve until at most [`MEDIAN_LEAF`] remain.
fn median_height(mut n: u32) -> u32 {
    let mut h = 0;
    while n > MEDIAN_LEAF {
        n = n.div_ceil(2);
        h += 1;
    }
    h
}

impl FlatBvh {
    /// The GPU layout of `bvh`, the SAH tree of the flat triangle list `vertices` (the same list it was
    /// built from), at most [`STACK_SIZE`] levels deep.
    pub fn new(bvh: &Bvh, vertices: &[Vertex]) -> FlatBvh {
        FlatBvh::with_max_height(bvh, vertices, STACK_SIZE)
    }

    /// [`FlatBvh::new`] with at most `max_height` (≤ [`STACK_SIZE`]) levels below the root. Where even a
    /// median-split tree cannot fit (more than 2^(max_height + 1) triangles, only for tiny limits), the
    /// deepest leaves hold more triangles instead.
    pub fn with_max_height(bvh: &Bvh, vertices: &[Vertex], max_height: u32) -> FlatBvh {
        let order = bvh.leaf_order();
        if order.is_empty() {
            return FlatBvh {
                nodes: vec![GpuBvhNode { count: 1, ..Default::default() }],
                tris: vec![GpuBvhTri { tri: NO_TRI, ..Default::default() }],
                triangle_count: 0,
                height: 0,
                rebuilt_subtrees: 0,
            };
        }
        let (count, start) = subtree_ranges(bvh);
        let mut f = Flattener {
            bvh,
            vertices,
            max_height: max_height.min(STACK_SIZE),
            count,
            start,
            items: order.to_vec(),
            nodes: vec![GpuBvhNode::default()],
            work: vec![(Src::Tree(0), 0, 0)],
            rebuilt: 0,
        };
        let mut tris: Vec<GpuBvhTri> = Vec::with_capacity(order.len());
        let mut height = 0;
        while let Some((src, slot, depth)) = f.work.pop() {
            height = height.max(depth);
            let Some((s, e)) = f.expand(src, slot, depth) else { continue };
            // A leaf: its triangles, appended in order.
            f.nodes[slot].first = tris.len() as u32;
            f.nodes[slot].count = (e - s) as u32;
            tris.extend(f.items[s..e].iter().map(|&t| gpu_tri(vertices, t)));
        }
        let mut nodes = f.nodes;
        fit_boxes(&mut nodes, &tris);
        let triangle_count = tris.len() as u32;
        FlatBvh { nodes, tris, triangle_count, height, rebuilt_subtrees: f.rebuilt }
    }

    /// The tree threaded for stackless any-hit traversal (`bvh_any_hit`): its triangles, and the boxes
    /// worth testing ([`FlatBvh::box_records`]), in depth-first preorder, one record each. A node's
    /// subtree follows its box record if it has one (a leaf's triangles, or its two children's subtrees,
    /// the child of larger surface area first: a random ray meets it more often, so an occluded ray tends
    /// to stop sooner); a box's link skips its subtree. A node without a box record is walked
    /// unconditionally: its box only filtered, so leaving it out changes the records read, never the
    /// answer. The walk only moves forward (to the next record, or past a missed box's subtree), so it
    /// visits each record at most once: at most nodes + triangles iterations, the bound of the stack
    /// traversal.
    pub fn threaded(&self) -> Vec<GpuThreadRec> {
        let keep = self.box_records();
        let mut out: Vec<GpuThreadRec> = Vec::with_capacity(self.nodes.len() + self.tris.len());
        // (node, index of its box record once placed): patched with the subtree's end when it is done.
        let mut stack: Vec<(u32, Option<usize>)> = vec![(0, None)];
        while let Some((i, placed)) = stack.pop() {
            if let Some(at) = placed {
                out[at].link = out.len() as u32;
                continue;
            }
            let n = self.nodes[i as usize];
            if keep[i as usize] {
                let at = out.len();
                out.push(GpuThreadRec { a: n.lo, b: n.hi, ..Default::default() });
                stack.push((i, Some(at)));
            }
            if n.is_leaf() {
                for t in &self.tris[n.first as usize..(n.first + n.count) as usize] {
                    out.push(GpuThreadRec { a: t.v0, link: THREAD_TRI, b: t.v1, tri: t.tri, c: t.v2, pad2: 0 });
                }
            } else {
                let (l, r) = (n.first, n.first + 1);
                let (first, second) = if self.area(r) > self.area(l) { (r, l) } else { (l, r) };
                stack.push((second, None));
                stack.push((first, None));
            }
        }
        quant::pair_records(&mut out);
        out
    }

    /// Surface area (half of it: only ratios are used) of node `i`'s box.
    fn area(&self, i: u32) -> f64 {
        let c = self.nodes[i as usize];
        let d = (Vec3::from(c.hi) - Vec3::from(c.lo)).max(Vec3::ZERO).as_dvec3();
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    /// Which nodes' boxes are records of the threaded walk: those whose test is expected to save more
    /// records than it reads. A box record costs one step and, when missed, saves its subtree's records;
    /// without it the subtree is walked whenever the walk gets there. On llvmpipe a box step and a
    /// triangle step cost the same (a SIMD vector runs both kinds of code under masks), so the cost is
    /// records read. The chance that a ray which met the box of the nearest tested ancestor A also
    /// meets node N's box is taken as area(N) / area(A) (the surface-area rule for random lines), and the
    /// expected records of each subtree are minimized over keep/drop by dynamic programming: for each
    /// node N at depth d and each depth k < d of its nearest tested ancestor,
    ///   f(N, k) = min(1 + p(N | k) · g(N, d), g(N, k)),   g(N, k) = count(N) for a leaf, else
    ///   f(left, k) + f(right, k),
    /// and the decisions are read off top-down. Depth 0 is the scene's box (every shadow ray lies
    /// inside it); the root's box is kept anyway (one step), and a one-triangle leaf's never is
    /// (1 + p ≥ 1).
    /// Measured with the CPU twin (`march-length`, records per ray) and the GPU (BENCHMARKS.md).
    pub fn box_records(&self) -> Vec<bool> {
        let n = self.nodes.len();
        // Parents and depths (children come after their parent); the root has depth 1.
        let mut parent = vec![u32::MAX; n];
        let mut depth = vec![1usize; n];
        for i in 0..n {
            let nd = self.nodes[i];
            if !nd.is_leaf() {
                for c in [nd.first, nd.first + 1] {
                    parent[c as usize] = i as u32;
                    depth[c as usize] = depth[i] + 1;
                }
            }
        }
        let areas: Vec<f64> = (0..n as u32).map(|i| self.area(i)).collect();
        // The areas of node i's ancestors by depth (index 0: the scene's box, the root's own).
        let ancestors = |i: usize| {
            let mut a = vec![0.0f64; depth[i]];
            let mut j = parent[i];
            let mut k = depth[i] - 1;
            while j != u32::MAX {
                a[k] = areas[j as usize];
                j = parent[j as usize];
                k -= 1;
            }
            a[0] = areas[0];
            a
        };
        let p = |area: f64, of: f64| if of > 0.0 { (area / of).min(1.0) } else { 1.0 };
        // g[i][k], k = 0 ..= depth(i): the expected records of i's subtree below its own box, the nearest
        // tested ancestor at depth k (k = depth(i): i's own box, tested and met).
        let mut g: Vec<Vec<f64>> = vec![Vec::new(); n];
        for i in (0..n).rev() {
            let nd = self.nodes[i];
            let d = depth[i];
            g[i] = if nd.is_leaf() {
                vec![nd.count as f64; d + 1]
            } else {
                let mut sum = vec![0.0f64; d + 1];
                for c in [nd.first as usize, nd.first as usize + 1] {
                    let anc = ancestors(c);
                    let own = g[c][depth[c]];
                    for (k, s) in sum.iter_mut().enumerate() {
                        *s += (1.0 + p(areas[c], anc[k]) * own).min(g[c][k]);
                    }
                }
                sum
            };
        }
        // Top-down: keep a box where testing it is the cheaper choice, given the nearest tested ancestor.
        let mut keep = vec![false; n];
        // (node, depth of the nearest tested ancestor, that ancestor's area).
        let mut stack = vec![(0usize, 0usize, areas[0])];
        while let Some((i, k, of)) = stack.pop() {
            let d = depth[i];
            // The root's box stays: it costs one step, and a segment outside the scene's box (which the
            // renderer never casts, but a caller may) then reads nothing more.
            keep[i] = i == 0 || 1.0 + p(areas[i], of) * g[i][d] < g[i][k];
            let nd = self.nodes[i];
            if !nd.is_leaf() {
                let next = if keep[i] { (d, areas[i]) } else { (k, of) };
                stack.push((nd.first as usize, next.0, next.1));
                stack.push((nd.first as usize + 1, next.0, next.1));
            }
        }
        keep
    }

    /// An upper bound of the loop iterations of one trace (see the module doc).
    pub fn max_iterations_per_ray(&self) -> u32 {
        let walk = self.nodes.len() as u64 + self.tris.len() as u64 + 1;
        walk.min(MAX_STEPS as u64) as u32
    }

    /// An upper bound of the loop iterations of one occlusion test (`bvh_occluded*`, the threaded walk):
    /// its steps, at most min([`MAX_STEPS`], records + 1), [`THREAD_UNROLL`] to an iteration.
    pub fn max_iterations_occluded(&self) -> u32 {
        self.max_iterations_per_ray().div_ceil(THREAD_UNROLL)
    }
}

/// The positions of scene triangle `t`.
fn positions(vertices: &[Vertex], t: u32) -> [Vec3; 3] {
    let v = &vertices[3 * t as usize..3 * t as usize + 3];
    [v[0].position(), v[1].position(), v[2].position()]
}

fn gpu_tri(vertices: &[Vertex], t: u32) -> GpuBvhTri {
    let [a, b, c] = positions(vertices, t);
    GpuBvhTri { v0: a.into(), tri: t, v1: b.into(), pad1: 0, v2: c.into(), pad2: 0 }
}

/// Triangle count and first position in `leaf_order` of every SAH subtree (children come after their
/// parent, so one reverse sweep; a left child's range directly precedes its sibling's).
fn subtree_ranges(bvh: &Bvh) -> (Vec<u32>, Vec<u32>) {
    let n = bvh.node_count();
    let (mut count, mut start) = (vec![0u32; n], vec![0u32; n]);
    for i in (0..n).rev() {
        let (first, c) = bvh.node_links(i);
        if c > 0 {
            (count[i], start[i]) = (c, first);
        } else {
            let l = first as usize;
            (count[i], start[i]) = (count[l] + count[l + 1], start[l]);
        }
    }
    (count, start)
}

/// Where a GPU node's content comes from.
enum Src {
    /// Node `i` of the SAH tree, copied as it is where its children fit under the height limit.
    Tree(usize),
    /// `items[s..e]`, rebuilt by median splits.
    Range(usize, usize),
}

/// The state of [`FlatBvh::with_max_height`].
struct Flattener<'a> {
    bvh: &'a Bvh,
    vertices: &'a [Vertex],
    max_height: u32,
    /// Per SAH node: its subtree's triangle count and first position in `items` ([`subtree_ranges`]).
    count: Vec<u32>,
    start: Vec<u32>,
    /// The leaf order; a rebuilt range is permuted in place (SAH leaves read the same positions, which
    /// no rebuild of another subtree touches).
    items: Vec<u32>,
    nodes: Vec<GpuBvhNode>,
    /// Nodes still to fill: (source, GPU node, depth).
    work: Vec<(Src, usize, u32)>,
    rebuilt: u32,
}

impl Flattener<'_> {
    /// Whether `tris` triangles fit below a node at `depth`, even by median splits.
    fn fits(&self, depth: u32, tris: u32) -> bool {
        depth + median_height(tris) <= self.max_height
    }

    /// Two adjacent new nodes as the children of `slot`; returns the left one.
    fn children(&mut self, slot: usize) -> usize {
        let left = self.nodes.len();
        self.nodes.push(GpuBvhNode::default());
        self.nodes.push(GpuBvhNode::default());
        self.nodes[slot].first = left as u32;
        left
    }

    /// Fills node `slot` from `src`: the `items` range of a leaf, or `None` when it queued the
    /// node's children (or its rebuild).
    fn expand(&mut self, src: Src, slot: usize, depth: u32) -> Option<(usize, usize)> {
        match src {
            Src::Tree(i) => {
                let (first, c) = self.bvh.node_links(i);
                if c > 0 {
                    return Some((first as usize, (first + c) as usize));
                }
                let l = first as usize;
                if self.fits(depth + 1, self.count[l]) && self.fits(depth + 1, self.count[l + 1]) {
                    let left = self.children(slot);
                    self.work.push((Src::Tree(l + 1), left + 1, depth + 1));
                    self.work.push((Src::Tree(l), left, depth + 1));
                } else {
                    self.rebuilt += 1;
                    let s = self.start[i] as usize;
                    self.work.push((Src::Range(s, s + self.count[i] as usize), slot, depth));
                }
                None
            }
            Src::Range(s, e) => {
                if e - s <= MEDIAN_LEAF as usize || depth >= self.max_height {
                    return Some((s, e));
                }
                let m = self.median_split(s, e);
                let left = self.children(slot);
                self.work.push((Src::Range(s + m, e), left + 1, depth + 1));
                self.work.push((Src::Range(s, s + m), left, depth + 1));
                None
            }
        }
    }

    /// Splits `items[s..e]` at its median along the widest axis of the centroids; returns the left
    /// count.
    fn median_split(&mut self, s: usize, e: usize) -> usize {
        let vertices = self.vertices;
        let centroid = |t: u32| {
            let [a, b, c] = positions(vertices, t);
            (a.min(b).min(c) + a.max(b).max(c)) * 0.5
        };
        let range = &mut self.items[s..e];
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for &t in range.iter() {
            lo = lo.min(centroid(t));
            hi = hi.max(centroid(t));
        }
        let ext = hi - lo;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let m = range.len() / 2;
        range.select_nth_unstable_by(m, |&a, &b| centroid(a)[axis].total_cmp(&centroid(b)[axis]).then(a.cmp(&b)));
        m
    }
}

/// The boxes, bottom-up (children come after their parent): f32 min/max of the positions, exact.
fn fit_boxes(nodes: &mut [GpuBvhNode], tris: &[GpuBvhTri]) {
    for i in (0..nodes.len()).rev() {
        let nd = nodes[i];
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        if nd.is_leaf() {
            for t in &tris[nd.first as usize..(nd.first + nd.count) as usize] {
                for p in t.positions() {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
            }
        } else {
            for c in &nodes[nd.first as usize..nd.first as usize + 2] {
                lo = lo.min(Vec3::from(c.lo));
                hi = hi.max(Vec3::from(c.hi));
            }
        }
        nodes[i].lo = lo.into();
        nodes[i].hi = hi.into();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::scene::{point_light, Scene};
    use std::collections::HashSet;

    fn scene_of(tris: &[[Vec3; 3]]) -> Scene {
        let camera = Camera { eye: Vec3::new(0.0, 0.0, 10.0), target: Vec3::ZERO, up: Vec3::Y, fov_y_deg: 45.0 };
        Scene::from_triangles(tris, &vec![Vec3::splat(0.5); tris.len()], camera, &[point_light(Vec3::ONE, Vec3::ONE)])
    }

    /// A deterministic soup of small random triangles plus a degenerate one (index `n`).
    fn soup(n: usize) -> Vec<[Vec3; 3]> {
        let mut r = crate::bvh::test_uniforms(0x1234_5678_9abc_def1u64);
        let mut tris: Vec<[Vec3; 3]> = (0..n)
            .map(|_| {
                let c = Vec3::new(r(), r(), r()) * 10.0;
                [0, 1, 2].map(|_| c + Vec3::new(r(), r(), r()) - 0.5)
            })
            .collect();
        tris.push([Vec3::ONE; 3]);
        tris
    }

    /// The invariants the traversal relies on, whatever the height limit.
    fn check(flat: &FlatBvh, scene: &Scene, max_height: u32) {
        let tris: Vec<[Vec3; 3]> =
            scene.vertices.chunks_exact(3).map(|v| [v[0].position(), v[1].position(), v[2].position()]).collect();
        let hittable: HashSet<u32> = (0..tris.len() as u32)
            .filter(|&t| {
                let [a, b, c] = tris[t as usize];
                let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
                (b - a).cross(c - a) != glam::DVec3::ZERO
            })
            .collect();
        // Every hittable triangle exactly once, with its own positions.
        let seen: Vec<u32> = flat.tris.iter().map(|t| t.tri).collect();
        assert_eq!(seen.len(), hittable.len());
        assert_eq!(seen.iter().copied().collect::<HashSet<_>>(), hittable);
        for t in &flat.tris {
            assert_eq!(t.positions(), tris[t.tri as usize]);
        }
        // Walk: children after their parent and inside its box, leaves cover the triangle array once,
        // depths within the limit.
        let mut covered = vec![false; flat.tris.len()];
        let mut stack = vec![(0usize, 0u32)];
        let mut max_depth = 0;
        let mut visited = 0;
        while let Some((i, depth)) = stack.pop() {
            visited += 1;
            max_depth = max_depth.max(depth);
            let n = flat.nodes[i];
            let (lo, hi) = (Vec3::from(n.lo), Vec3::from(n.hi));
            if n.is_leaf() {
                for k in n.first..n.first + n.count {
                    assert!(!covered[k as usize], "triangle slot {k} in two leaves");
                    covered[k as usize] = true;
                    for p in flat.tris[k as usize].positions() {
                        assert!(p.cmpge(lo).all() && p.cmple(hi).all(), "node {i} misses a vertex of its leaf");
                    }
                }
            } else {
                let l = n.first as usize;
                assert!(l > i && l + 1 < flat.nodes.len(), "node {i}: children {l}, {}", l + 1);
                for c in [l, l + 1] {
                    let cn = flat.nodes[c];
                    assert!(Vec3::from(cn.lo).cmpge(lo).all() && Vec3::from(cn.hi).cmple(hi).all());
                    stack.push((c, depth + 1));
                }
            }
        }
        assert_eq!(visited, flat.nodes.len(), "every node reachable once");
        assert!(covered.iter().all(|&c| c));
        assert_eq!(max_depth, flat.height);
        assert!(flat.height <= max_height.min(STACK_SIZE), "height {} > {max_height}", flat.height);
        assert_eq!(flat.triangle_count as usize, hittable.len());
        // The threaded layout: one record per triangle and kept box; a box's link closes its subtree, which
        // lies inside the box and nests in the subtrees around it; every triangle once.
        let th = flat.threaded();
        let boxes = flat.box_records().iter().filter(|&&k| k).count();
        assert_eq!(th.len(), boxes + flat.tris.len());
        let mut ends = vec![th.len()];
        let mut tri_records = Vec::new();
        for (k, r) in th.iter().enumerate() {
            while ends.last() == Some(&k) {
                ends.pop();
            }
            if r.link == THREAD_TRI {
                tri_records.push([r.a, r.b, r.c]);
                continue;
            }
            let end = r.link as usize;
            assert!(end > k && end <= *ends.last().unwrap(), "record {k}: link {end} does not nest");
            // The packed successor: present where the next record is a box, and holding it.
            match th.get(k + 1).filter(|n| n.link != THREAD_TRI) {
                Some(n) => {
                    assert_eq!(r.pad2, n.link, "record {k}: the pair's link");
                    let (plo, phi) = quant::unpack(r.a, r.b, r.c.map(f32::to_bits));
                    let (nlo, nhi) = (Vec3::from(n.a), Vec3::from(n.b));
                    assert!(plo.cmple(nlo).all() && phi.cmpge(nhi).all(), "record {k}: the packed box");
                }
                None => assert_eq!(r.pad2, 0, "record {k}: a pair without a box after it"),
            }
            ends.push(end);
            let (lo, hi) = (Vec3::from(r.a), Vec3::from(r.b));
            for q in &th[k + 1..end] {
                let pts = if q.link == THREAD_TRI { vec![q.a, q.b, q.c] } else { vec![q.a, q.b] };
                for p in pts {
                    assert!(Vec3::from(p).cmpge(lo).all() && Vec3::from(p).cmple(hi).all(), "record {k}");
                }
            }
        }
        let mut want: Vec<[[f32; 3]; 3]> = flat.tris.iter().map(|t| [t.v0, t.v1, t.v2]).collect();
        let key = |t: &[[f32; 3]; 3]| t.map(|v| v.map(f32::to_bits));
        want.sort_by_key(key);
        tri_records.sort_by_key(key);
        assert_eq!(tri_records, want);
        let bound = (flat.nodes.len() + flat.tris.len() + 1).min(MAX_STEPS as usize) as u32;
        assert_eq!(flat.max_iterations_per_ray(), bound);
    }

    #[test]
    fn flattening_keeps_the_sah_tree_and_every_triangle() {
        let scene = scene_of(&soup(3000));
        let bvh = Bvh::new(&scene);
        let flat = FlatBvh::new(&bvh, &scene.vertices);
        check(&flat, &scene, STACK_SIZE);
        // Nothing rebuilt: the GPU tree has the SAH tree's shape.
        assert_eq!(flat.rebuilt_subtrees, 0);
        assert_eq!(flat.nodes.len(), bvh.node_count());
        assert_eq!(flat.triangle_count, 3000);
    }

    #[test]
    fn height_limits_rebuild_subtrees_and_never_exceed_the_limit() {
        let scene = scene_of(&soup(3000));
        let bvh = Bvh::new(&scene);
        let full = FlatBvh::new(&bvh, &scene.vertices);
        assert!(full.height > 12, "the soup's SAH tree is {} deep; the test needs a deeper one", full.height);
        // 3000 triangles need 11 median levels: limits 11..=full.height − 1 rebuild part of the tree.
        for limit in [11, 12, full.height - 1] {
            let flat = FlatBvh::with_max_height(&bvh, &scene.vertices, limit);
            check(&flat, &scene, limit);
            assert!(flat.rebuilt_subtrees > 0, "limit {limit}");
        }
        // Below what median splits need: fat leaves at the limit, still every triangle once.
        for limit in [0, 1, 4] {
            let flat = FlatBvh::with_max_height(&bvh, &scene.vertices, limit);
            check(&flat, &scene, limit);
            assert_eq!(flat.height, limit);
        }
        assert_eq!(median_height(0), 0);
        assert_eq!(median_height(2), 0);
        assert_eq!(median_height(3), 1);
        assert_eq!(median_height(3000), 11);
        assert_eq!(median_height(u32::MAX), 31);
    }

    #[test]
    fn an_empty_scene_is_one_leaf_that_nothing_hits() {
        let scene = scene_of(&[[Vec3::ZERO, Vec3::X, Vec3::X * 2.0]]); // collinear: zero area
        let flat = FlatBvh::new(&Bvh::new(&scene), &scene.vertices);
        assert_eq!(flat.nodes, vec![GpuBvhNode { count: 1, ..Default::default() }]);
        assert_eq!(flat.tris.len(), 1);
        assert_eq!(flat.tris[0].positions(), [Vec3::ZERO; 3]);
        assert_eq!(flat.tris[0].tri, NO_TRI);
        assert_eq!(flat.triangle_count, 0);
        assert_eq!(flat.max_iterations_per_ray(), 3);
    }
}
