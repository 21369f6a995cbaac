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

/// `bvh`'s inner nodes as [`Node`]s in depth-first order (root first); a tree that is a single
/// leaf becomes one node with an [`EMPTY`] second child; no node for an empty tree.
pub(crate) fn convert(bvh: &Bvh2, alloc: &Allocator) -> Result<Vec<Node>, AllocationError> {
    let Some(root) = bvh.nodes.first() else { return Ok(Vec::new()) };
    let inner = bvh.nodes.iter().filter(|n| n.prim_count == 0).count().max(1);
    let mut nodes: Vec<Node> = alloc.vec(inner, "the BVH's nodes")?;
    let empty = Bounds { lo: [0.0; 3], hi: [0.0; 3] };
    if root.prim_count > 0 {
        nodes.push(Node {
            boxes: [Bounds::from(&root.aabb), empty],
            child: [root.first_index, 0],
            count: [root.prim_count, EMPTY],
        });
        return Ok(nodes);
    }
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
            let (child, count) = if n.prim_count > 0 {
                (n.first_index, n.prim_count)
            } else {
                let index = nodes.len();
                nodes.push(blank);
                *inner_child = Some((first + c, index));
                (index as u32, 0)
            };
            let node = &mut nodes[ours];
            (node.boxes[c], node.child[c], node.count[c]) = (Bounds::from(&n.aabb), child, count);
        }
        todo.extend(inner_children.into_iter().rev().flatten());
    }
    Ok(nodes)
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
