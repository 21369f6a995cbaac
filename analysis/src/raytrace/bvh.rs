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
//! (parent module, "Precision") is unchanged.

use super::memory::{AllocationError, Allocator};
use obvhs::{aabb::Aabb, bvh2::Bvh2};

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
