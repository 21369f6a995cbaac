//! The binary BVH the packets walk: obvhs' `Bvh2` (its PLOC build over the padded triangle
//! boxes) converted to nodes that each hold both children's boxes, one cache line per node,
//! in depth-first order.
//!
//! Why not obvhs' own nodes: a `Bvh2Node` holds its own box (48 bytes), so testing the two
//! children of a node loads two more nodes, and PLOC builds bottom-up, so a subtree's nodes
//! lie far apart. On bunny-plane (75 k triangles) the loads of those nodes were a quarter of
//! the traversal's time. Here a node is the two children's boxes with their references (64
//! bytes), the packet tests both children from their parent's line, and the nodes are laid
//! out in depth-first order. The boxes are obvhs' `f32` boxes, copied, so the padding argument
//! (parent module, "Precision") is unchanged. A cluster built in parts has one obvhs tree per
//! part; [`join`] converts them into one vector of nodes, under the nodes of the halvings that
//! made the parts (a parent's boxes are unions of `f32` boxes, so they hold what they held in
//! the parts).

use super::memory::{AllocationError, Allocator, Spare};
use bytemuck::Zeroable;
use obvhs::{aabb::Aabb, bvh2::Bvh2};
use rayon::prelude::*;
use std::ops::Range;

/// `Node::count` of a missing child (the other child of a tree that is a single leaf).
pub(crate) const EMPTY: u32 = u32::MAX;

/// An `f32` box.
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Zeroable)]
pub(crate) struct Bounds {
    pub(crate) lo: [f32; 3],
    pub(crate) hi: [f32; 3],
}

impl Bounds {
    /// The box a missing child holds.
    const EMPTY: Self = Self { lo: [0.0; 3], hi: [0.0; 3] };
}

impl From<&Aabb> for Bounds {
    fn from(b: &Aabb) -> Self {
        Self { lo: b.min.to_array(), hi: b.max.to_array() }
    }
}

/// An inner node: its two children's boxes and what they are.
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Zeroable)]
#[repr(C, align(64))]
pub(crate) struct Node {
    pub(crate) boxes: [Bounds; 2],
    /// The child's node index (inner child), or its first slot (leaf).
    pub(crate) child: [u32; 2],
    /// 0 for an inner child, the number of slots of a leaf, or [`EMPTY`].
    pub(crate) count: [u32; 2],
}

/// The nodes a dropped tracer left for the next [`join`].
pub(crate) static SPARE_NODES: Spare<Node> = Spare::new();

/// Most triangles in a leaf: obvhs builds leaves of one, [`join`] joins pairs.
const MAX_LEAF: u32 = 2;

/// The cost of a node's traversal relative to a triangle test, in the collapse rule.
const TRAVERSAL_COST: f32 = 1.0;

/// The trees [`join`]ed: their nodes, and each slot's primitive, leaf after leaf.
pub(crate) struct Converted {
    pub(crate) nodes: Vec<Node>,
    /// Each slot's box: its index among the boxes the parts were built over, part `p`'s boxes
    /// following those of the parts before it.
    pub(crate) prims: Vec<u32>,
}

/// The collapse rule: leaves are collapsed as obvhs' `leaf_collapser::collapse` collapses them
/// with at most [`MAX_LEAF`] primitives per leaf and traversal cost [`TRAVERSAL_COST`]: a node
/// whose two children are leaves holding at most [`MAX_LEAF`] primitives together becomes one
/// leaf (left child's primitives first) when its half area times `count - TRAVERSAL_COST` is at
/// most the children's half areas times their counts, the same `f32` operations, and not in a
/// tree of at most `2 * MAX_LEAF + 1` nodes, which obvhs leaves as it is; so the tree is the
/// one obvhs' collapse makes. Its collapse copies every node and primitive index once more and
/// was a sixth of the BVH build on bunny-plane (one thread).
struct Collapse<'a> {
    bvh: &'a Bvh2,
    collapsing: bool,
}

impl<'a> Collapse<'a> {
    fn new(bvh: &'a Bvh2) -> Self {
        let collapsing = bvh.nodes.len() > (2 * MAX_LEAF + 1) as usize
            && bvh.primitive_indices.len() > MAX_LEAF as usize;
        Self { bvh, collapsing }
    }

    /// The leaf obvhs node `i` is or becomes: its leaves' `(first index, count)` in
    /// `primitive_indices`, one or two runs; `None` for an inner node.
    #[inline]
    fn leaf(&self, i: usize) -> Option<[(u32, u32); 2]> {
        let n = &self.bvh.nodes[i];
        if n.prim_count > 0 {
            return Some([(n.first_index, n.prim_count), (0, 0)]);
        }
        if !self.collapsing {
            return None;
        }
        let first = n.first_index as usize;
        let (a, b) = (&self.bvh.nodes[first], &self.bvh.nodes[first + 1]);
        let total = a.prim_count + b.prim_count;
        if a.prim_count == 0 || b.prim_count == 0 || total > MAX_LEAF {
            return None;
        }
        let collapsed = n.aabb.half_area() * (total as f32 - TRAVERSAL_COST);
        let apart =
            a.aabb.half_area() * a.prim_count as f32 + b.aabb.half_area() * b.prim_count as f32;
        (collapsed <= apart)
            .then_some([(a.first_index, a.prim_count), (b.first_index, b.prim_count)])
    }

    /// The tree's inner nodes as [`Node`]s in depth-first order (root first) into `nodes`
    /// (room for every inner node obvhs made), numbered from `first_node`; a tree that is a
    /// single leaf becomes one node with an [`EMPTY`] second child where `nodes` has room for
    /// it. Each leaf takes the next slots of `prims` (one per primitive), numbered from
    /// `first_slot`, which also numbers the boxes: a slot holds `first_slot` plus obvhs'
    /// primitive index. Returns how many nodes it wrote.
    fn write(
        &self,
        nodes: &mut [Node],
        prims: &mut [u32],
        first_node: u32,
        first_slot: u32,
    ) -> usize {
        let bvh = self.bvh;
        let Some(root) = bvh.nodes.first() else {
            return 0;
        };
        // The next slot; `put` fills the next slots with runs of primitives, and gives the
        // first slot and how many.
        let mut slot = 0;
        let mut put = |runs: &[(u32, u32)]| {
            let start = slot;
            for &(first, count) in runs {
                for &p in &bvh.primitive_indices[first as usize..(first + count) as usize] {
                    prims[slot] = first_slot + p;
                    slot += 1;
                }
            }
            (first_slot + start as u32, (slot - start) as u32)
        };
        if root.prim_count > 0 {
            put(&[(root.first_index, root.prim_count)]);
            if let Some(node) = nodes.first_mut() {
                *node = Node {
                    boxes: [Bounds::from(&root.aabb), Bounds::EMPTY],
                    child: [first_slot, 0],
                    count: [root.prim_count, EMPTY],
                };
                return 1;
            }
            return 0;
        }
        // (obvhs node, our node) pairs whose children are still to be filled in. A node's two
        // children are numbered together when it is filled in, and the first child's subtree
        // is filled in before the second's: siblings lie side by side, subtrees close
        // together.
        let mut todo: Vec<(usize, usize)> = Vec::with_capacity(2 * bvh.max_depth + 2);
        let mut next = 1;
        todo.push((0, 0));
        while let Some((theirs, ours)) = todo.pop() {
            let first = bvh.nodes[theirs].first_index as usize;
            let mut inner_children = [None; 2];
            for (c, inner_child) in inner_children.iter_mut().enumerate() {
                let n = &bvh.nodes[first + c];
                let (child, count) = match self.leaf(first + c) {
                    Some(runs) => put(&runs),
                    None => {
                        let index = next;
                        next += 1;
                        *inner_child = Some((first + c, index));
                        (first_node + index as u32, 0)
                    }
                };
                let node = &mut nodes[ours];
                (node.boxes[c], node.child[c], node.count[c]) =
                    (Bounds::from(&n.aabb), child, count);
            }
            todo.extend(inner_children.into_iter().rev().flatten());
        }
        next
    }
}

/// A subtree of a BVH built in parts ([`join`]): a node that splits two subtrees, or a part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Piece {
    Split(usize),
    Part(usize),
}

/// The smallest box holding `a` and `b`.
fn union(a: &Bounds, b: &Bounds) -> Bounds {
    let f = |k: usize| (a.lo[k].min(b.lo[k]), a.hi[k].max(b.hi[k]));
    let (x, y, z) = (f(0), f(1), f(2));
    Bounds { lo: [x.0, y.0, z.0], hi: [x.1, y.1, z.1] }
}

/// The trees of a BVH built in parts, each part's tree made by `build` (part `p` over the boxes
/// `parts[p]`, ranges that follow one another from 0), converted and joined under the nodes
/// `splits` into one tree: split `s` (its children, splits or parts) becomes node `s`, split 0
/// the root (children of a split come after it), then each part's nodes follow, and part `p`'s
/// slots are the places of its boxes, `parts[p]`. A part whose tree is a single leaf is
/// referenced as a leaf by its split. With no split, the single part's tree is returned alone
/// (one node with an [`EMPTY`] second child for a single leaf, none for an empty tree).
///
/// Each part is built, written straight into its own range of one vector of nodes and dropped,
/// in parallel, so that the next part's build reuses its memory. That vector is the spare a
/// dropped tracer left ([`SPARE_NODES`]) when it has room, zeroed in parallel. A part of `m`
/// boxes has room for obvhs' `m - 1` inner nodes; those its collapses leave unused stay zero
/// between the parts (no traversal reaches them). Converting each part into a vector of its own
/// and copying those into the joined one took 27 ms of random-1m's BVH build (a million
/// triangles, two threads).
pub(crate) fn join(
    splits: &[[Piece; 2]],
    parts: &[Range<usize>],
    build: impl Fn(Range<usize>) -> Result<Bvh2, AllocationError> + Sync,
    alloc: &Allocator,
) -> Result<Converted, AllocationError> {
    // Each part's room: its inner nodes; with no split, a single leaf is a node too; with
    // splits, a single leaf is its split's reference.
    let room = |len: usize| match len {
        0 => 0,
        1 => usize::from(splits.is_empty()),
        m => m - 1,
    };
    let total_nodes = splits.len() + parts.iter().map(|r| room(r.len())).sum::<usize>();
    let total_slots = parts.last().map_or(0, |r| r.end);
    let mut nodes: Vec<Node> = SPARE_NODES.take(alloc, total_nodes, "the BVH's nodes")?;
    nodes.par_extend(rayon::iter::repeat_n(Node::zeroed(), total_nodes));
    let mut prims: Vec<u32> = alloc.zeroed(total_slots, "the BVH's triangle lists")?;
    // Each part's ranges of nodes and slots, and its first node's index.
    let mut jobs = Vec::with_capacity(parts.len());
    let (mut node_rest, mut slot_rest) = (&mut nodes[splits.len()..], &mut prims[..]);
    let mut first_node = splits.len();
    for r in parts {
        let (part_nodes, rest) = std::mem::take(&mut node_rest).split_at_mut(room(r.len()));
        node_rest = rest;
        let (part_slots, rest) = std::mem::take(&mut slot_rest).split_at_mut(r.len());
        slot_rest = rest;
        jobs.push((r.clone(), part_nodes, part_slots, first_node as u32));
        first_node += room(r.len());
    }
    // Each part's reference from its split, (box, child, count) as in a `Node`, and how many
    // nodes it wrote.
    let refs = jobs
        .into_par_iter()
        .map(|(r, part_nodes, part_slots, first_node)| {
            let bvh = build(r.clone())?;
            let written =
                Collapse::new(&bvh).write(part_nodes, part_slots, first_node, r.start as u32);
            let reference = match bvh.nodes.first() {
                None => (Bounds::EMPTY, 0, EMPTY),
                Some(root) if root.prim_count > 0 => {
                    (Bounds::from(&root.aabb), r.start as u32, root.prim_count)
                }
                Some(_) => (union(&part_nodes[0].boxes[0], &part_nodes[0].boxes[1]), first_node, 0),
            };
            Ok((reference, written))
        })
        .collect::<Result<Vec<_>, AllocationError>>()?;
    if splits.is_empty() {
        nodes.truncate(refs.first().map_or(0, |&(_, written)| written));
    }
    // The splits from the last (whose children come after it) to the root.
    let mut boxes = vec![Bounds::EMPTY; splits.len()];
    for s in (0..splits.len()).rev() {
        let mut node = nodes[s];
        for (c, piece) in splits[s].iter().enumerate() {
            (node.boxes[c], node.child[c], node.count[c]) = match *piece {
                Piece::Split(k) => (boxes[k], k as u32, 0),
                Piece::Part(p) => refs[p].0,
            };
        }
        boxes[s] = union(&node.boxes[0], &node.boxes[1]);
        nodes[s] = node;
    }
    Ok(Converted { nodes, prims })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;
    use obvhs::{bvh2::builder::build_bvh2, BvhBuildParams};
    use proptest::prelude::*;

    /// Boxes of `n` triangles scattered by `seed`, sizes spread over two orders of magnitude.
    fn boxes(n: usize, seed: u64) -> Vec<Aabb> {
        let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n)
            .map(|_| {
                let c = Vec3A::new(next(), next(), next()) * 10.0;
                let h = Vec3A::new(next(), next(), next()) * (0.01 + next());
                Aabb::new(c - h, c + h)
            })
            .collect()
    }

    proptest! {
        /// The tree `join` collapses from obvhs' leaves of one is the one obvhs' own
        /// collapse makes with leaves of at most two, node for node and slot for slot.
        #[test]
        fn collapsing_here_makes_obvhs_collapsed_tree(n in 1usize..400, seed in any::<u64>()) {
            let boxes = boxes(n, seed);
            let alloc = Allocator { estimate: 0 };
            let ones = build_bvh2(&boxes, BvhBuildParams::fastest_build(), &mut Default::default());
            let twos = BvhBuildParams { max_prims_per_leaf: 2, ..BvhBuildParams::fastest_build() };
            let collapsed = build_bvh2(&boxes, twos, &mut Default::default());
            let whole = 0..n;
            let whole = std::slice::from_ref(&whole);
            let here = join(&[], whole, |_| Ok(ones.clone()), &alloc).expect("small");
            let theirs = join(&[], whole, |_| Ok(collapsed.clone()), &alloc).expect("small");
            prop_assert_eq!(&here.nodes, &theirs.nodes);
            prop_assert_eq!(&here.prims, &theirs.prims);
            let mut prims = here.prims.clone();
            prims.sort_unstable();
            prop_assert_eq!(prims, (0..n as u32).collect::<Vec<_>>());
            let leaves: Vec<u32> =
                here.nodes.iter().flat_map(|n| n.count).filter(|&c| c != 0 && c != EMPTY).collect();
            prop_assert!(leaves.iter().all(|&c| c <= MAX_LEAF));
        }
    }

    /// The slots under each child reachable from the root of `nodes`, with the child's box:
    /// `(box, first slot, count)` for every leaf.
    fn leaves(nodes: &[Node]) -> Vec<(Bounds, u32, u32)> {
        let mut out = Vec::new();
        let mut todo = vec![0usize];
        while let Some(i) = todo.pop() {
            for c in 0..2 {
                match nodes[i].count[c] {
                    EMPTY => {}
                    0 => todo.push(nodes[i].child[c] as usize),
                    count => out.push((nodes[i].boxes[c], nodes[i].child[c], count)),
                }
            }
        }
        out
    }

    proptest! {
        /// Parts joined under splits, each written into its own range of nodes (with the room
        /// its collapses leave unused between them): every box is in exactly one slot reached
        /// from the root, inside its leaf's box, and a split's box holds its parts' boxes.
        #[test]
        fn parts_joined_hold_every_box_once_inside_its_leaf(
            n in 2usize..300,
            cuts in proptest::collection::vec(0.0f64..1.0, 2),
            seed in any::<u64>(),
        ) {
            let boxes = boxes(n, seed);
            // Three parts, the first possibly a single box, under two splits.
            let a = 1 + ((n - 1) as f64 * cuts[0]) as usize % (n - 1);
            let b = a + ((n - a) as f64 * cuts[1]) as usize;
            let parts: Vec<Range<usize>> =
                [0..a, a..b, b..n].into_iter().filter(|r| !r.is_empty()).collect();
            let splits: Vec<[Piece; 2]> = match parts.len() {
                3 => vec![[Piece::Part(0), Piece::Split(1)], [Piece::Part(1), Piece::Part(2)]],
                _ => vec![[Piece::Part(0), Piece::Part(1)]],
            };
            let build = |r: Range<usize>| {
                Ok(build_bvh2(&boxes[r], BvhBuildParams::fastest_build(), &mut Default::default()))
            };
            let tree = join(&splits, &parts, build, &Allocator { estimate: 0 }).expect("small");
            let mut seen = vec![0u32; n];
            for (b, first, count) in leaves(&tree.nodes) {
                for slot in first..first + count {
                    let k = tree.prims[slot as usize] as usize;
                    seen[k] += 1;
                    let (lo, hi) = (boxes[k].min.to_array(), boxes[k].max.to_array());
                    prop_assert!((0..3).all(|i| b.lo[i] <= lo[i] && hi[i] <= b.hi[i]));
                }
            }
            prop_assert!(seen.iter().all(|&s| s == 1), "{:?}", seen);
            let root = tree.nodes[0];
            let all = union(&root.boxes[0], &root.boxes[1]);
            for b in &boxes {
                let (lo, hi) = (b.min.to_array(), b.max.to_array());
                prop_assert!((0..3).all(|i| all.lo[i] <= lo[i] && hi[i] <= all.hi[i]));
            }
        }
    }

    /// The rule is not idle: on a thousand scattered boxes many pairs collapse, and many do
    /// not.
    #[test]
    fn some_pairs_collapse_and_some_do_not() {
        let boxes = boxes(1000, 7);
        let ones = build_bvh2(&boxes, BvhBuildParams::fastest_build(), &mut Default::default());
        let alloc = Allocator { estimate: 0 };
        let whole = 0..1000;
        let whole = std::slice::from_ref(&whole);
        let tree = join(&[], whole, |_| Ok(ones.clone()), &alloc).expect("small");
        let leaves =
            |count: u32| tree.nodes.iter().flat_map(|n| n.count).filter(|&c| c == count).count();
        assert!(leaves(2) > 10 && leaves(1) > 10, "{} pairs, {} single", leaves(2), leaves(1));
    }
}
