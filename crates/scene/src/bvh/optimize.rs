//! Insertion-based optimization of the SAH tree (Bittner, Hapala and Havran 2013, "Fast
//! insertion-based optimization of bounding volume hierarchies").
//!
//! A top-down binned build decides each split once, from the top, and never revisits it: a subtree that
//! ended up under a large parent box stays there. This pass takes the built tree ([`super::build`]) and
//! repeatedly moves the subtrees that cost the most to where they cost the least, which lowers the
//! tree's surface-area cost
//!
//!   C = Σ_interior A(N) + Σ_leaf A(N) · count(N)   (in units of the root's area),
//!
//! the expected boxes and triangles a random line that meets the root tests (Goldsmith and Salmon's
//! rule). A shadow ray's walk reads one record per box or triangle it reaches, so it tends to read
//! fewer; shadow rays are not random lines (they run between surfaces), and on one scene of the suite
//! it reads more (BENCHMARKS.md).
//!
//! One move: take an interior node N (not the root) whose box is large against its children's,
//! `A(N)³ / (½ (A(L) + A(R)) · min(A(L), A(R)))` (the paper's combined measure: the product of A(N),
//! A(N) against its children's mean and against their minimum), out of the tree with
//! its parent P (N's sibling takes P's place), and insert N's children L and R back one at a time, each
//! where it adds least to C: as the sibling of the node X that minimizes
//!
//!   A(X ∪ L) + Σ_{ancestors Y of X} (A(Y ∪ L) − A(Y)),
//!
//! found by branch and bound over the tree (a node's subtree can add no less than its ancestors'
//! increase plus A(L)). N and P become the new parents. A round moves the worst [`BATCH`] of the
//! interior nodes; rounds stop when C falls by less than [`MIN_GAIN`] in [`PATIENCE`] rounds in a row,
//! or after [`MAX_ROUNDS`]. The moves keep every leaf as it is (its triangles and box), so each triangle
//! stays in exactly one leaf; the boxes above are refit to the exact union of their children.
//!
//! The answer of any ray query is unchanged (the same triangles, exact boxes); only which records a
//! walk reads changes. Measured: BENCHMARKS.md ("An optimized BVH").

use super::build::{area, BvhNode, MEDIAN_DEPTH};
use glam::DVec3;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The share of interior nodes a round takes out and inserts again.
const BATCH: f64 = 0.05;
/// A round that lowers the cost by less than this share counts as no gain.
const MIN_GAIN: f64 = 1e-4;
/// Rounds without gain before the pass stops.
const PATIENCE: usize = 3;
/// The most rounds the pass runs.
const MAX_ROUNDS: usize = 200;

const NONE: u32 = u32::MAX;

/// The tree with parent and child links, where a move is a few link changes.
#[derive(Clone)]
struct Linked {
    lo: Vec<DVec3>,
    hi: Vec<DVec3>,
    parent: Vec<u32>,
    /// Children of an interior node; `[NONE, NONE]` for a leaf.
    child: Vec<[u32; 2]>,
    /// Triangles of a leaf (its count; 0 for an interior node).
    count: Vec<u32>,
    /// A leaf's first position in the input's leaf order.
    first: Vec<u32>,
    root: u32,
}

/// The tree `nodes` (links as in [`super::Bvh::node_links`]) over the leaf order `order`, optimized
/// (module doc): the same leaves, boxes refit, in the same layout. A tree the moves would make deeper
/// than the build's bound (`MEDIAN_DEPTH + 32` levels, the CPU reference's stack) is returned as it was.
pub(super) fn optimized(nodes: Vec<BvhNode>, order: Vec<u32>) -> (Vec<BvhNode>, Vec<u32>) {
    if order.is_empty() || nodes.len() < 3 {
        return (nodes, order);
    }
    let mut t = Linked::from_nodes(&nodes);
    t.optimize();
    if t.height() > MEDIAN_DEPTH + 32 {
        return (nodes, order);
    }
    t.to_nodes(&order)
}

/// A non-negative f64 as a key that orders like it (the IEEE bits of a non-negative float do).
fn key(x: f64) -> u64 {
    x.max(0.0).to_bits()
}

impl Linked {
    fn from_nodes(nodes: &[BvhNode]) -> Linked {
        let n = nodes.len();
        let mut t = Linked {
            lo: nodes.iter().map(|x| x.lo).collect(),
            hi: nodes.iter().map(|x| x.hi).collect(),
            parent: vec![NONE; n],
            child: vec![[NONE, NONE]; n],
            count: nodes.iter().map(|x| x.count).collect(),
            first: nodes.iter().map(|x| x.first).collect(),
            root: 0,
        };
        for (i, x) in nodes.iter().enumerate() {
            if x.count == 0 {
                t.child[i] = [x.first, x.first + 1];
                t.parent[x.first as usize] = i as u32;
                t.parent[x.first as usize + 1] = i as u32;
            }
        }
        t
    }

    /// The layout of [`super::Bvh`]: the root first, children adjacent and after their parent, the
    /// leaves' triangles in depth-first order (left before right).
    fn to_nodes(&self, order: &[u32]) -> (Vec<BvhNode>, Vec<u32>) {
        let mut nodes = vec![BvhNode { lo: DVec3::ZERO, hi: DVec3::ZERO, first: 0, count: 0 }; self.count.len()];
        let mut out = Vec::with_capacity(order.len());
        let mut used = 1;
        let mut stack = vec![(self.root, 0usize)];
        while let Some((i, slot)) = stack.pop() {
            let i = i as usize;
            nodes[slot].lo = self.lo[i];
            nodes[slot].hi = self.hi[i];
            if self.child[i][0] == NONE {
                nodes[slot].first = out.len() as u32;
                nodes[slot].count = self.count[i];
                let s = self.first[i] as usize;
                out.extend_from_slice(&order[s..s + self.count[i] as usize]);
            } else {
                nodes[slot].first = used as u32;
                let [l, r] = self.child[i];
                stack.push((r, used + 1));
                stack.push((l, used));
                used += 2;
            }
        }
        nodes.truncate(used);
        (nodes, out)
    }

    fn area_of(&self, i: u32) -> f64 {
        area(self.lo[i as usize], self.hi[i as usize])
    }

    fn is_leaf(&self, i: u32) -> bool {
        self.child[i as usize][0] == NONE
    }

    /// The surface-area cost C of the module doc, times the root's area.
    fn cost(&self) -> f64 {
        let mut c = 0.0;
        let mut stack = vec![self.root];
        while let Some(i) = stack.pop() {
            if self.is_leaf(i) {
                c += self.area_of(i) * self.count[i as usize] as f64;
            } else {
                c += self.area_of(i);
                stack.extend(self.child[i as usize]);
            }
        }
        c
    }

    /// Levels below the root of the deepest leaf.
    fn height(&self) -> usize {
        let mut h = 0;
        let mut stack = vec![(self.root, 0usize)];
        while let Some((i, d)) = stack.pop() {
            h = h.max(d);
            if !self.is_leaf(i) {
                for c in self.child[i as usize] {
                    stack.push((c, d + 1));
                }
            }
        }
        h
    }

    /// Boxes from node `i` up to the root made the union of their children's again.
    fn refit_up(&mut self, mut i: u32) {
        while i != NONE {
            let [a, b] = self.child[i as usize];
            self.lo[i as usize] = self.lo[a as usize].min(self.lo[b as usize]);
            self.hi[i as usize] = self.hi[a as usize].max(self.hi[b as usize]);
            i = self.parent[i as usize];
        }
    }

    /// Puts `new` in `old`'s place under `old`'s parent (or as the root).
    fn replace_child(&mut self, old: u32, new: u32) {
        let p = self.parent[old as usize];
        self.parent[new as usize] = p;
        if p == NONE {
            self.root = new;
        } else {
            let slot = &mut self.child[p as usize];
            let k = if slot[0] == old { 0 } else { 1 };
            slot[k] = new;
        }
    }

    /// The paper's combined measure of how much node `i`'s box costs beyond its children's.
    fn inefficiency(&self, i: u32) -> f64 {
        let [l, r] = self.child[i as usize];
        let (a, al, ar) = (self.area_of(i), self.area_of(l), self.area_of(r));
        let min = al.min(ar);
        if min <= 0.0 {
            return a * a;
        }
        a * a * a / (0.5 * (al + ar) * min)
    }

    /// The node beside which a new sibling of box `[lo, hi]` adds least to the cost (branch and bound).
    fn best_sibling(&self, lo: DVec3, hi: DVec3) -> u32 {
        let own = area(lo, hi);
        let (mut best, mut best_cost) = (self.root, f64::INFINITY);
        // Min-heap on the cost the ancestors of a candidate add (its lower bound before its own box).
        let mut heap = BinaryHeap::new();
        heap.push(Reverse((key(0.0), self.root)));
        while let Some(Reverse((k, x))) = heap.pop() {
            let induced = f64::from_bits(k);
            if induced + own >= best_cost {
                break;
            }
            let merged = area(self.lo[x as usize].min(lo), self.hi[x as usize].max(hi));
            let total = induced + merged;
            if total < best_cost {
                (best, best_cost) = (x, total);
            }
            if !self.is_leaf(x) {
                let below = total - self.area_of(x);
                if below + own < best_cost {
                    for c in self.child[x as usize] {
                        heap.push(Reverse((key(below), c)));
                    }
                }
            }
        }
        best
    }

    /// Inserts the detached subtree `x` beside its best sibling, with the free interior node `parent`
    /// (one taken out by [`Linked::reinsert`]) above both.
    fn insert(&mut self, x: u32, parent: u32) {
        let (lo, hi) = (self.lo[x as usize], self.hi[x as usize]);
        let s = self.best_sibling(lo, hi);
        self.replace_child(s, parent);
        self.child[parent as usize] = [s, x];
        self.parent[s as usize] = parent;
        self.parent[x as usize] = parent;
        self.refit_up(parent);
    }

    /// Takes interior node `n` and its parent out of the tree and inserts `n`'s children again.
    fn reinsert(&mut self, n: u32) {
        let p = self.parent[n as usize];
        if p == NONE || self.is_leaf(n) {
            return;
        }
        let [a, b] = self.child[p as usize];
        let sibling = if a == n { b } else { a };
        self.replace_child(p, sibling);
        let g = self.parent[sibling as usize];
        if g != NONE {
            self.refit_up(g);
        }
        let [l, r] = self.child[n as usize];
        let (first, second) = if self.area_of(l) >= self.area_of(r) { (l, r) } else { (r, l) };
        self.parent[first as usize] = NONE;
        self.parent[second as usize] = NONE;
        self.insert(first, n);
        self.insert(second, p);
    }

    /// Runs rounds of moves until they stop paying (module doc).
    fn optimize(&mut self) {
        let interior: usize = (0..self.count.len() as u32).filter(|&i| !self.is_leaf(i)).count();
        let batch = ((interior as f64 * BATCH).ceil() as usize).max(1);
        let mut cost = self.cost();
        let mut best = (cost, self.clone());
        let mut idle = 0;
        for _ in 0..MAX_ROUNDS {
            let mut worst: Vec<(u64, u32)> = (0..self.count.len() as u32)
                .filter(|&i| !self.is_leaf(i) && self.parent[i as usize] != NONE)
                .map(|i| (key(self.inefficiency(i)), i))
                .collect();
            if worst.is_empty() {
                break;
            }
            let k = batch.min(worst.len());
            worst.select_nth_unstable_by(k - 1, |a, b| b.cmp(a));
            for &(_, i) in &worst[..k] {
                self.reinsert(i);
            }
            let next = self.cost();
            if next < cost * (1.0 - MIN_GAIN) {
                idle = 0;
            } else {
                idle += 1;
            }
            cost = next;
            if cost < best.0 {
                best = (cost, self.clone());
            }
            if idle >= PATIENCE {
                break;
            }
        }
        *self = best.1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::query::BvhView;
    use crate::bvh::{test_uniforms, Bvh, FlatBvh};
    use crate::layout::Vertex;
    use glam::Vec3;

    /// A deterministic soup of `n` random triangles in a 10³ box, of sizes up to `size` times 1 to
    /// `spread` (log-uniform: a few large triangles among many small ones, as in a furnished room).
    fn soup(n: usize, size: f32, spread: f32, seed: u64) -> Vec<Vertex> {
        let mut r = test_uniforms(seed);
        let mut v = Vec::new();
        for _ in 0..n {
            let c = Vec3::new(r(), r(), r()) * 10.0;
            let size = size * spread.powf(r());
            for _ in 0..3 {
                let p = c + (Vec3::new(r(), r(), r()) - 0.5) * size;
                v.push(Vertex { position_u: [p.x, p.y, p.z, 0.0], normal_v: [0.0, 0.0, 1.0, 0.0] });
            }
        }
        v
    }

    /// Leaves as (box, triangles), sorted: what the moves must keep.
    fn leaves(nodes: &[BvhNode], order: &[u32]) -> Vec<([u64; 6], Vec<u32>)> {
        let mut out: Vec<_> = nodes
            .iter()
            .filter(|n| n.count > 0)
            .map(|n| {
                let b = [n.lo.x, n.lo.y, n.lo.z, n.hi.x, n.hi.y, n.hi.z].map(f64::to_bits);
                let mut t = order[n.first as usize..(n.first + n.count) as usize].to_vec();
                t.sort();
                (b, t)
            })
            .collect();
        out.sort();
        out
    }

    #[test]
    fn the_moves_keep_every_leaf_refit_every_box_and_lower_the_cost() {
        for (n, size, spread, seed) in
            [(2000, 0.8, 1.0, 1u64), (2000, 0.05, 200.0, 2), (500, 6.0, 1.0, 3), (60, 0.3, 1.0, 4)]
        {
            let sah = Bvh::sah(&soup(n, size, spread, seed));
            let before = Linked::from_nodes(sah.nodes());
            let (nodes, order) = optimized(sah.nodes().to_vec(), sah.leaf_order().to_vec());
            assert_eq!(leaves(&nodes, &order), leaves(sah.nodes(), sah.leaf_order()));
            let mut sorted = order.clone();
            sorted.sort();
            let mut want = sah.leaf_order().to_vec();
            want.sort();
            assert_eq!(sorted, want, "every triangle once");
            // The layout: children adjacent and after their parent, every node reached once, each interior
            // box the exact union of its children's, leaves' ranges consecutive in depth-first order.
            let mut reached = vec![false; nodes.len()];
            let mut next_leaf = 0;
            let mut stack = vec![0usize];
            while let Some(i) = stack.pop() {
                assert!(!reached[i]);
                reached[i] = true;
                let x = nodes[i];
                if x.count > 0 {
                    assert_eq!(x.first, next_leaf);
                    next_leaf += x.count;
                    continue;
                }
                let (l, r) = (x.first as usize, x.first as usize + 1);
                assert!(l > i && r < nodes.len());
                assert_eq!(x.lo, nodes[l].lo.min(nodes[r].lo), "node {i}");
                assert_eq!(x.hi, nodes[l].hi.max(nodes[r].hi), "node {i}");
                stack.push(r);
                stack.push(l);
            }
            assert!(reached.iter().all(|&r| r));
            assert_eq!(next_leaf as usize, order.len());
            let after = Linked::from_nodes(&nodes);
            assert!(after.height() <= MEDIAN_DEPTH + 32);
            let (c0, c1) = (before.cost(), after.cost());
            // A uniform soup is what a top-down build does best (its cost falls by < 1 %); mixed sizes
            // are where it errs (7.5 % here).
            let bound = if spread > 1.0 { 0.95 * c0 } else { c0 };
            assert!(c1 < bound, "soup {n}, spread {spread}: cost {c0} -> {c1}");
        }
    }

    #[test]
    fn rays_through_the_optimized_tree_find_what_they_found_before() {
        let vertices = soup(1500, 0.1, 30.0, 5);
        let sah = Bvh::sah(&vertices);
        let opt = Bvh::from_vertices(&vertices);
        let (a, b) = (FlatBvh::new(&sah, &vertices), FlatBvh::new(&opt, &vertices));
        let (va, vb) = (BvhView { nodes: &a.nodes, tris: &a.tris }, BvhView { nodes: &b.nodes, tris: &b.tris });
        let mut r = test_uniforms(5);
        let (mut hits, mut blocked) = (0, 0);
        for _ in 0..4000 {
            let p = Vec3::new(r(), r(), r()) * 12.0 - 1.0;
            let q = Vec3::new(r(), r(), r()) * 12.0 - 1.0;
            let ha = va.closest(p, q - p, 0.0, f32::INFINITY).map(|(t, k)| (t, a.tris[k].tri));
            let hb = vb.closest(p, q - p, 0.0, f32::INFINITY).map(|(t, k)| (t, b.tris[k].tri));
            assert_eq!(ha, hb);
            let oa = va.occluded(p, q, 1e-4);
            assert_eq!(oa, vb.occluded(p, q, 1e-4));
            hits += ha.is_some() as u32;
            blocked += oa as u32;
        }
        // Both kinds of answer occur, so the comparison means something.
        assert!(hits > 400 && hits < 3600 && blocked > 400 && blocked < 3600, "{hits} hits, {blocked} blocked");
    }

    #[test]
    fn degenerate_scenes_keep_their_leaves_and_the_height_bound() {
        // A geometric row (each triangle 17× the last and as far out: the SAH build peels one a level) and
        // a thousand copies of one triangle (no split separates them).
        let tri = |p: Vec3, s: f32| {
            [p, p + Vec3::X * s, p + Vec3::Y * s]
                .map(|q| Vertex { position_u: [q.x, q.y, q.z, 0.0], normal_v: [0.0, 0.0, 1.0, 0.0] })
        };
        let row: Vec<Vertex> = (-30..30).flat_map(|i| tri(Vec3::X * 17f32.powi(i), 0.1 * 17f32.powi(i))).collect();
        let copies: Vec<Vertex> = (0..1000).flat_map(|_| tri(Vec3::ONE, 1.0)).collect();
        for (name, v) in [("row", row), ("copies", copies)] {
            let sah = Bvh::sah(&v);
            let height = |nodes: &[BvhNode]| Linked::from_nodes(nodes).height();
            let (nodes, order) = optimized(sah.nodes().to_vec(), sah.leaf_order().to_vec());
            assert_eq!(leaves(&nodes, &order), leaves(sah.nodes(), sah.leaf_order()), "{name}");
            assert!(height(&nodes) <= MEDIAN_DEPTH + 32, "{name}: height {}", height(&nodes));
            assert!(Linked::from_nodes(&nodes).cost() <= Linked::from_nodes(sah.nodes()).cost(), "{name}");
            if name == "row" {
                assert!(height(sah.nodes()) > 50, "the row should build a deep tree: {}", height(sah.nodes()));
            }
        }
    }
}
