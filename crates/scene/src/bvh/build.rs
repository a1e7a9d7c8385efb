//! The SAH build: a binned surface-area-heuristic bounding volume hierarchy over a scene's flat
//! triangle list, in f64.
//!
//! Input: the scene's non-indexed vertices (triangle `t` = vertices `3t..3t+3`). Output: a [`Bvh`],
//! the tree's shape ([`Bvh::node_links`], [`Bvh::leaf_order`]) with f64 boxes ([`BvhNode`]) and the
//! triangles as corner + two edges ([`BvhTri`], Möller–Trumbore's form). [`super::FlatBvh`] flattens
//! the shape into the GPU layout; the CPU reference (`bounce-oracles`, `cpu_ref`) casts f64 rays
//! through the same tree, so the GPU and the reference it is checked against walk one tree.
//!
//! Zero-area and non-finite triangles are left out of the tree (never hit). Nodes stop splitting at
//! [`LEAF_MIN`] triangles; SAH may keep up to [`LEAF_MAX`] where splitting does not pay; beyond depth
//! [`MEDIAN_DEPTH`] the build splits at the median (each halves the count), which bounds the height to
//! `MEDIAN_DEPTH + 32`. The top-down tree is then optimized by moving subtrees
//! ([`super::optimize`]): the same leaves under boxes that cost less, within the same height bound.

use crate::layout::Vertex;
use crate::scene::Scene;
use glam::DVec3;

/// Leaves stop splitting at this size.
const LEAF_MIN: usize = 2;
/// SAH may keep leaves up to this size when splitting does not pay.
const LEAF_MAX: usize = 8;
/// Binned SAH resolution.
const BINS: usize = 16;
/// Beyond this depth the builder switches to median splits (each halves the count), which bounds
/// the depth to `MEDIAN_DEPTH + 32` and therefore a traversal's stack.
pub const MEDIAN_DEPTH: usize = 96;

/// A triangle as the builder and an f64 ray caster see it: corner `p0` and the edges to the other two
/// corners (`p1 − p0`, `p2 − p0`), from the f32 positions.
#[derive(Clone, Copy, Debug)]
pub struct BvhTri {
    pub p0: DVec3,
    pub e1: DVec3,
    pub e2: DVec3,
}

/// A node of the tree: box `[lo, hi]` (f64, exact bounds of its triangles).
#[derive(Clone, Copy, Debug)]
pub struct BvhNode {
    pub lo: DVec3,
    pub hi: DVec3,
    /// Leaf: first index into [`Bvh::leaf_order`]; interior: index of the left child (right = left + 1).
    pub first: u32,
    /// Triangle count of a leaf; 0 for an interior node.
    pub count: u32,
}

/// A bounding volume hierarchy over a flat triangle list (binned SAH build).
///
/// Zero-area triangles are never hit (they are excluded at build time).
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<BvhNode>,
    order: Vec<u32>,
    tris: Vec<BvhTri>,
}

/// Surface area of the box `[lo, hi]` (0 for an empty box).
pub(super) fn area(lo: DVec3, hi: DVec3) -> f64 {
    let d = (hi - lo).max(DVec3::ZERO);
    2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
}

/// Per-triangle bounds and centroids, indexed by triangle.
struct Prims {
    lo: Vec<DVec3>,
    hi: Vec<DVec3>,
    centroid: Vec<DVec3>,
}

/// How a node of more than [`LEAF_MIN`] triangles is split.
enum Split {
    /// SAH says a leaf is cheaper.
    Leaf,
    /// The first `m` triangles of the node's (partitioned) range go left.
    At(usize),
    /// No usable SAH split: split at the median of the widest axis.
    Median,
}

impl Bvh {
    /// Builds the BVH of a scene's triangles.
    pub fn new(scene: &Scene) -> Bvh {
        Bvh::from_vertices(&scene.vertices)
    }

    /// Builds the BVH of a flat triangle list (`3t..3t+3` = triangle `t`; a trailing partial
    /// triangle is ignored): the SAH build, then the insertion-based optimization
    /// ([`super::optimize`]).
    pub fn from_vertices(vertices: &[Vertex]) -> Bvh {
        let Bvh { nodes, order, tris } = Bvh::sah(vertices);
        let (nodes, order) = super::optimize::optimized(nodes, order);
        Bvh { nodes, order, tris }
    }

    /// The binned SAH build alone, top down (module doc).
    pub(super) fn sah(vertices: &[Vertex]) -> Bvh {
        let tris: Vec<BvhTri> = vertices
            .chunks_exact(3)
            .map(|v| {
                let p0 = v[0].position().as_dvec3();
                BvhTri { p0, e1: v[1].position().as_dvec3() - p0, e2: v[2].position().as_dvec3() - p0 }
            })
            .collect();
        let (mut order, prims) = prepare(&tris);

        let mut nodes = vec![BvhNode { lo: DVec3::ZERO, hi: DVec3::ZERO, first: 0, count: order.len() as u32 }];
        // (node index, depth)
        let mut work = vec![(0usize, 0usize)];
        while let Some((ni, depth)) = work.pop() {
            let first = nodes[ni].first as usize;
            let count = nodes[ni].count as usize;
            let items = &mut order[first..first + count];
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            let (mut clo, mut chi) = (lo, hi);
            for &k in items.iter() {
                lo = lo.min(prims.lo[k as usize]);
                hi = hi.max(prims.hi[k as usize]);
                clo = clo.min(prims.centroid[k as usize]);
                chi = chi.max(prims.centroid[k as usize]);
            }
            if count == 0 {
                lo = DVec3::ZERO;
                hi = DVec3::ZERO;
            }
            nodes[ni].lo = lo;
            nodes[ni].hi = hi;
            if count <= LEAF_MIN {
                continue;
            }

            let extent = chi - clo;
            let split =
                if depth < MEDIAN_DEPTH { sah_split(items, &prims, lo, hi, clo, extent) } else { Split::Median };
            let mid = match split {
                Split::Leaf => continue,
                Split::At(m) => m,
                Split::Median => median_split(items, &prims.centroid, extent),
            };
            let left = nodes.len();
            nodes.push(BvhNode { lo: DVec3::ZERO, hi: DVec3::ZERO, first: first as u32, count: mid as u32 });
            nodes.push(BvhNode {
                lo: DVec3::ZERO,
                hi: DVec3::ZERO,
                first: (first + mid) as u32,
                count: (count - mid) as u32,
            });
            nodes[ni].first = left as u32;
            nodes[ni].count = 0;
            work.push((left, depth + 1));
            work.push((left + 1, depth + 1));
        }
        Bvh { nodes, order, tris }
    }

    /// Number of triangles (including zero-area ones, which are never hit).
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// Number of BVH nodes (for logging).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The structure of node `i` (`i < node_count()`), for flattening the tree into another layout
    /// (the GPU BVH, [`super::FlatBvh`]): `(first, count)`. A leaf (`count > 0`) holds the triangles
    /// `leaf_order()[first..first + count]`; an interior node (`count == 0`) has the children `first`
    /// and `first + 1`, which cover consecutive ranges of `leaf_order()` (left before right). Node 0 is
    /// the root; a tree without triangles is the single node `(0, 0)`, which has no children.
    pub fn node_links(&self, i: usize) -> (u32, u32) {
        (self.nodes[i].first, self.nodes[i].count)
    }

    /// The nodes with their f64 boxes (links as in [`Bvh::node_links`]), for a ray caster.
    pub fn nodes(&self) -> &[BvhNode] {
        &self.nodes
    }

    /// Every triangle of the input, indexed by triangle (zero-area ones included; they are in no leaf).
    pub fn triangles(&self) -> &[BvhTri] {
        &self.tris
    }

    /// The indices of the triangles that can be hit (zero-area ones excluded), in leaf order (see
    /// [`Bvh::node_links`]).
    pub fn leaf_order(&self) -> &[u32] {
        &self.order
    }
}

/// The triangles that can be hit (nonzero finite area, finite bounds), in input order, and the bounds
/// and centroids of all of them.
fn prepare(tris: &[BvhTri]) -> (Vec<u32>, Prims) {
    let mut order = Vec::with_capacity(tris.len());
    let mut prims = Prims {
        lo: Vec::with_capacity(tris.len()),
        hi: Vec::with_capacity(tris.len()),
        centroid: Vec::with_capacity(tris.len()),
    };
    for (k, t) in tris.iter().enumerate() {
        let (a, b, c) = (t.p0, t.p0 + t.e1, t.p0 + t.e2);
        let lo = a.min(b).min(c);
        let hi = a.max(b).max(c);
        prims.lo.push(lo);
        prims.hi.push(hi);
        prims.centroid.push((lo + hi) * 0.5);
        let cross = t.e1.cross(t.e2);
        if cross != DVec3::ZERO && cross.is_finite() && lo.is_finite() && hi.is_finite() {
            order.push(k as u32);
        }
    }
    (order, prims)
}

/// The binned SAH decision for a node with box `[lo, hi]` and centroid box `clo + [0, extent]` over
/// `items`, which it partitions (left first) when it splits.
fn sah_split(items: &mut [u32], prims: &Prims, lo: DVec3, hi: DVec3, clo: DVec3, extent: DVec3) -> Split {
    let Some((cost, axis, left_bins)) = best_binned_split(items, prims, clo, extent) else {
        return Split::Median;
    };
    let count = items.len();
    let leaf_cost = count as f64 * area(lo, hi);
    if cost >= leaf_cost && count <= LEAF_MAX {
        return Split::Leaf;
    }
    let scale = BINS as f64 / extent[axis];
    let split = partition(items, |k| {
        ((((prims.centroid[k as usize][axis] - clo[axis]) * scale) as usize).min(BINS - 1)) < left_bins
    });
    if split > 0 && split < count {
        Split::At(split)
    } else {
        Split::Median
    }
}

/// The cheapest binned split over all three axes: `(cost, axis, bins on the left)`, or `None` when
/// no axis has two non-empty sides.
fn best_binned_split(items: &[u32], prims: &Prims, clo: DVec3, extent: DVec3) -> Option<(f64, usize, usize)> {
    let mut best: Option<(f64, usize, usize)> = None;
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let scale = BINS as f64 / extent[axis];
        let bin_of = |k: u32| (((prims.centroid[k as usize][axis] - clo[axis]) * scale) as usize).min(BINS - 1);
        let mut bcount = [0usize; BINS];
        let mut blo = [DVec3::splat(f64::INFINITY); BINS];
        let mut bhi = [DVec3::splat(f64::NEG_INFINITY); BINS];
        for &k in items.iter() {
            let b = bin_of(k);
            bcount[b] += 1;
            blo[b] = blo[b].min(prims.lo[k as usize]);
            bhi[b] = bhi[b].max(prims.hi[k as usize]);
        }
        // Sweep from the right to get suffix areas, then from the left.
        let mut right_area = [0.0; BINS];
        let mut right_count = [0usize; BINS];
        let (mut rlo, mut rhi, mut rc) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY), 0);
        for b in (1..BINS).rev() {
            rlo = rlo.min(blo[b]);
            rhi = rhi.max(bhi[b]);
            rc += bcount[b];
            right_area[b] = area(rlo, rhi);
            right_count[b] = rc;
        }
        let (mut llo, mut lhi, mut lc) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY), 0);
        for b in 0..BINS - 1 {
            llo = llo.min(blo[b]);
            lhi = lhi.max(bhi[b]);
            lc += bcount[b];
            let rc = right_count[b + 1];
            if lc == 0 || rc == 0 {
                continue;
            }
            let cost = lc as f64 * area(llo, lhi) + rc as f64 * right_area[b + 1];
            let better = match best {
                None => true,
                Some((c, _, _)) => cost < c,
            };
            if better {
                best = Some((cost, axis, b + 1));
            }
        }
    }
    best
}

/// Splits `items` at the median centroid of the widest axis (all centroids coincide, or too deep):
/// returns the left count, `items.len() / 2`.
fn median_split(items: &mut [u32], centroid: &[DVec3], extent: DVec3) -> usize {
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let m = items.len() / 2;
    items.select_nth_unstable_by(m, |&a, &b| centroid[a as usize][axis].total_cmp(&centroid[b as usize][axis]));
    m
}

/// In-place partition: elements satisfying `left` first; returns their count.
fn partition(items: &mut [u32], left: impl Fn(u32) -> bool) -> usize {
    let mut i = 0;
    for j in 0..items.len() {
        if left(items[j]) {
            items.swap(i, j);
            i += 1;
        }
    }
    i
}
