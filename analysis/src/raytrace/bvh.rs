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
//! (parent module, "Precision") is unchanged. A cluster built in parts has one such tree per
//! part; [`join`] puts them under the nodes of the halvings that made the parts (a parent's
//! boxes are unions of `f32` boxes, so they hold what they held in the parts).

use super::memory::{AllocationError, Allocator};
use obvhs::{aabb::Aabb, bvh2::Bvh2};
use rayon::prelude::*;

/// `Node::count` of a missing child (the other child of a tree that is a single leaf).
pub(crate) const EMPTY: u32 = u32::MAX;

/// An `f32` box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Bounds {
    pub(crate) lo: [f32; 3],
    pub(crate) hi: [f32; 3],
}

impl From<&Aabb> for Bounds {
    fn from(b: &Aabb) -> Self {
        Self { lo: b.min.to_array(), hi: b.max.to_array() }
    }
}

/// An inner node: its two children's boxes and what they are.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct Node {
    pub(crate) boxes: [Bounds; 2],
    /// The child's node index (inner child), or its first slot (leaf).
    pub(crate) child: [u32; 2],
    /// 0 for an inner child, the number of slots of a leaf, or [`EMPTY`].
    pub(crate) count: [u32; 2],
}

/// Most triangles in a leaf: obvhs builds leaves of one, [`convert`] joins pairs.
const MAX_LEAF: u32 = 2;

/// The cost of a node's traversal relative to a triangle test, in the collapse rule.
const TRAVERSAL_COST: f32 = 1.0;

/// A tree [`convert`]ed: its nodes, and the primitive (index into the boxes obvhs built over)
/// in each slot, leaf after leaf.
pub(crate) struct Converted {
    pub(crate) nodes: Vec<Node>,
    pub(crate) prims: Vec<u32>,
}

/// `bvh`'s inner nodes as [`Node`]s in depth-first order (root first); a tree that is a single
/// leaf becomes one node with an [`EMPTY`] second child; no node for an empty tree. Each leaf
/// takes the next slots, so a leaf's primitives are consecutive in [`Converted::prims`].
///
/// Leaves are collapsed here as obvhs' `leaf_collapser::collapse` collapses them with at most
/// [`MAX_LEAF`] primitives per leaf and traversal cost [`TRAVERSAL_COST`]: a node whose two
/// children are leaves holding at most [`MAX_LEAF`] primitives together becomes one leaf
/// (left child's primitives first) when its half area times `count - TRAVERSAL_COST` is at
/// most the children's half areas times their counts, the same `f32` operations, and not in a
/// tree of at most `2 * MAX_LEAF + 1` nodes, which obvhs leaves as it is; so the tree is the
/// one obvhs' collapse makes. Its collapse copies every node and primitive index once more and
/// was a sixth of the BVH build on bunny-plane (one thread).
pub(crate) fn convert(bvh: &Bvh2, alloc: &Allocator) -> Result<Converted, AllocationError> {
    let Some(root) = bvh.nodes.first() else {
        return Ok(Converted { nodes: Vec::new(), prims: Vec::new() });
    };
    let mut prims: Vec<u32> = alloc.vec(bvh.primitive_indices.len(), "the BVH's triangle lists")?;
    let empty = Bounds { lo: [0.0; 3], hi: [0.0; 3] };
    if root.prim_count > 0 {
        let mut nodes: Vec<Node> = alloc.vec(1, "the BVH's nodes")?;
        let first = root.first_index as usize;
        prims.extend_from_slice(&bvh.primitive_indices[first..first + root.prim_count as usize]);
        nodes.push(Node {
            boxes: [Bounds::from(&root.aabb), empty],
            child: [0, 0],
            count: [root.prim_count, EMPTY],
        });
        return Ok(Converted { nodes, prims });
    }
    let collapsing = bvh.nodes.len() > (2 * MAX_LEAF + 1) as usize
        && bvh.primitive_indices.len() > MAX_LEAF as usize;
    // The leaf node `i` is or becomes: its leaves' `(first index, count)` in
    // `primitive_indices`, one or two runs; `None` for an inner node.
    let leaf = |i: usize| -> Option<[(u32, u32); 2]> {
        let n = &bvh.nodes[i];
        if n.prim_count > 0 {
            return Some([(n.first_index, n.prim_count), (0, 0)]);
        }
        if !collapsing {
            return None;
        }
        let (a, b) = (&bvh.nodes[n.first_index as usize], &bvh.nodes[n.first_index as usize + 1]);
        let total = a.prim_count + b.prim_count;
        if a.prim_count == 0 || b.prim_count == 0 || total > MAX_LEAF {
            return None;
        }
        let collapsed = n.aabb.half_area() * (total as f32 - TRAVERSAL_COST);
        let apart =
            a.aabb.half_area() * a.prim_count as f32 + b.aabb.half_area() * b.prim_count as f32;
        (collapsed <= apart)
            .then_some([(a.first_index, a.prim_count), (b.first_index, b.prim_count)])
    };
    // A binary tree of `m` nodes has `(m - 1) / 2` inner ones; collapses leave fewer.
    let mut nodes: Vec<Node> = alloc.vec((bvh.nodes.len() / 2).max(1), "the BVH's nodes")?;
    // (obvhs node, our node) pairs whose children are still to be filled in. A node's two
    // children are numbered together when it is filled in, and the first child's subtree is
    // filled in before the second's: siblings lie side by side, subtrees close together.
    let blank = Node { boxes: [empty; 2], child: [0; 2], count: [0; 2] };
    let mut todo: Vec<(usize, usize)> = alloc.vec(2 * bvh.max_depth + 2, "the BVH's nodes")?;
    nodes.push(blank);
    todo.push((0, 0));
    while let Some((theirs, ours)) = todo.pop() {
        let first = bvh.nodes[theirs].first_index as usize;
        let mut inner_children = [None; 2];
        for (c, inner_child) in inner_children.iter_mut().enumerate() {
            let n = &bvh.nodes[first + c];
            let (child, count) = match leaf(first + c) {
                Some(runs) => {
                    let slot = prims.len() as u32;
                    for (start, count) in runs {
                        let run = start as usize..(start + count) as usize;
                        prims.extend_from_slice(&bvh.primitive_indices[run]);
                    }
                    (slot, prims.len() as u32 - slot)
                }
                None => {
                    let index = nodes.len();
                    nodes.push(blank);
                    *inner_child = Some((first + c, index));
                    (index as u32, 0)
                }
            };
            let node = &mut nodes[ours];
            (node.boxes[c], node.child[c], node.count[c]) = (Bounds::from(&n.aabb), child, count);
        }
        todo.extend(inner_children.into_iter().rev().flatten());
    }
    Ok(Converted { nodes, prims })
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

/// The trees of `parts` (each [`convert`]ed over its own slots, numbered from 0; part `p` has
/// `slots[p]` of them, following those of the parts before it) joined under the nodes
/// `splits` into one tree: split `s` (its children, splits or parts) becomes node `s`, split 0
/// the root (children of a split come after it), then each part's nodes follow with their
/// references moved by the part's offsets. A part whose tree is a single leaf is referenced
/// as a leaf by its split. With no split, the single part's tree is returned as it is.
pub(crate) fn join(
    splits: &[[Piece; 2]],
    mut parts: Vec<Vec<Node>>,
    slots: &[usize],
    alloc: &Allocator,
) -> Result<Vec<Node>, AllocationError> {
    if splits.is_empty() {
        return Ok(parts.pop().unwrap_or_default());
    }
    let is_leaf = |part: &[Node]| part.first().is_none_or(|n| n.count[1] == EMPTY);
    let inner: usize = parts.iter().filter(|p| !is_leaf(p)).map(Vec::len).sum();
    let mut nodes: Vec<Node> = alloc.vec(splits.len() + inner, "the BVH's nodes")?;
    let empty = Bounds { lo: [0.0; 3], hi: [0.0; 3] };
    nodes.resize(splits.len(), Node { boxes: [empty; 2], child: [0; 2], count: [0; 2] });
    // Each part's reference from its split: (box, child, count) as in a `Node`; and each
    // inner part's place (first node among the parts' nodes, part, node offset, first slot).
    let mut refs = Vec::with_capacity(parts.len());
    let mut places = Vec::with_capacity(parts.len());
    let (mut first_slot, mut first_node) = (0u32, 0usize);
    for (k, (part, &len)) in parts.iter().zip(slots).enumerate() {
        let Some(root) = part.first() else {
            refs.push((empty, 0, EMPTY));
            continue;
        };
        if is_leaf(part) {
            refs.push((root.boxes[0], root.child[0] + first_slot, root.count[0]));
        } else {
            let offset = (splits.len() + first_node) as u32;
            refs.push((union(&root.boxes[0], &root.boxes[1]), offset, 0));
            places.push((first_node, k, offset, first_slot));
            first_node += part.len();
        }
        first_slot += len as u32;
    }
    // The parts' nodes, their references moved, copied in parallel straight into place (on
    // random-1m, a million nodes: 30 ms copied in turn at 2 threads).
    nodes.par_extend((0..inner).into_par_iter().map(|x| {
        let (first, k, offset, first_slot) = places[places.partition_point(|p| p.0 <= x) - 1];
        let mut n = parts[k][x - first];
        for c in 0..2 {
            if n.count[c] == 0 {
                n.child[c] += offset;
            } else if n.count[c] != EMPTY {
                n.child[c] += first_slot;
            }
        }
        n
    }));
    // The splits from the last (whose children come after it) to the root.
    let mut boxes = vec![empty; splits.len()];
    for s in (0..splits.len()).rev() {
        let mut node = nodes[s];
        for (c, piece) in splits[s].iter().enumerate() {
            (node.boxes[c], node.child[c], node.count[c]) = match *piece {
                Piece::Split(k) => (boxes[k], k as u32, 0),
                Piece::Part(p) => refs[p],
            };
        }
        boxes[s] = union(&node.boxes[0], &node.boxes[1]);
        nodes[s] = node;
    }
    Ok(nodes)
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
        /// The tree `convert` collapses from obvhs' leaves of one is the one obvhs' own
        /// collapse makes with leaves of at most two, node for node and slot for slot.
        #[test]
        fn collapsing_here_makes_obvhs_collapsed_tree(n in 1usize..400, seed in any::<u64>()) {
            let boxes = boxes(n, seed);
            let alloc = Allocator { estimate: 0 };
            let ones = build_bvh2(&boxes, BvhBuildParams::fastest_build(), &mut Default::default());
            let twos = BvhBuildParams { max_prims_per_leaf: 2, ..BvhBuildParams::fastest_build() };
            let collapsed = build_bvh2(&boxes, twos, &mut Default::default());
            let here = convert(&ones, &alloc).expect("small");
            let theirs = convert(&collapsed, &alloc).expect("small");
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

    /// The rule is not idle: on a thousand scattered boxes many pairs collapse, and many do
    /// not.
    #[test]
    fn some_pairs_collapse_and_some_do_not() {
        let boxes = boxes(1000, 7);
        let ones = build_bvh2(&boxes, BvhBuildParams::fastest_build(), &mut Default::default());
        let tree = convert(&ones, &Allocator { estimate: 0 }).expect("small");
        let leaves =
            |count: u32| tree.nodes.iter().flat_map(|n| n.count).filter(|&c| c == count).count();
        assert!(leaves(2) > 10 && leaves(1) > 10, "{} pairs, {} single", leaves(2), leaves(1));
    }
}
