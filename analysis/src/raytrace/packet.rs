//! Packet traversal of one cluster's binary BVH: up to [`PACKET`] frame rays walk the tree
//! together, sharing each node's test, and every ray still decides its own leaves.
//!
//! The scheme is Wald, Boulos and Shirley's ("Ray Tracing Deformable Scenes Using Dynamic
//! Bounding Volume Hierarchies", ACM Transactions on Graphics 26(1), 2007), itself built on
//! the coherent packets of Wald, Benthin, Wagner and Slusallek ("Interactive Rendering with
//! Coherent Ray Tracing", Eurographics 2001), with the active range of Overbeck, Ramamoorthi
//! and Mark ("Large Ray Packets for Real-Time Whitted Ray Tracing", IRT 2008):
//!
//! - Each stack entry is a node and the index of its **first active ray**: the rays before it
//!   are known to miss the node (or an ancestor). A node is entered when the first active ray
//!   hits it (one slab test for the whole packet in the common, coherent case). Otherwise the
//!   packet's **interval bound** is tried: if it proves that no ray of the packet can hit the
//!   box, the node is culled; if not, the rays after the first are tested one by one, and the
//!   first that hits becomes the children's first active ray.
//! - Children are visited nearer first, by the first active ray's entry distances.
//! - At a **leaf**, each ray from the first active one whose own slab test hits the leaf's box
//!   calls the leaf closure for each of the leaf's slots (the `f64` triangle test); the closure
//!   may shorten the ray (closest hit) or end it (`f32::NEG_INFINITY`: no light left).
//!
//! Why it loses nothing: a ray's own slab test is obvhs' (`Aabb::intersect_ray`, the same
//! `f32` operations, with the same clamped reciprocal of direction components below
//! `f32::EPSILON`), which the boxes' padding covers (parent module, "Precision"). The interval
//! bound only culls a node when it proves that this per-ray test fails for every ray: it
//! bounds the rays' origins and reciprocal directions per axis, and each slab distance
//! `(plane - o) * inv` by the extreme values over the corners of that box, computed with the
//! same `f32` operations. Correctly rounded subtraction and multiplication are monotone in each
//! argument, and a product is bilinear, so its rounded value over the box lies between the
//! rounded values at the corners: the bound holds for each ray's computed (rounded) slab
//! distances, not only for exact ones. A ray whose maximum only decreases (closest hit) or
//! that is ended keeps missing a box it missed before, so the first active index never skips
//! a ray that could still hit.
//!
//! Hot path: fixed-size structure-of-arrays, no allocation (the stack is the caller's, reused
//! from packet to packet), no division in the loop.

use glam::Vec3A;
use obvhs::{aabb::Aabb, bvh2::Bvh2, ray::safe_inverse};

/// Most rays in a packet: a pixel's 64 sub-samples, or 8 x 8 pixel centres at rate 1.
pub(crate) const PACKET: usize = 64;

/// Up to [`PACKET`] rays in a cluster's frame, structure of arrays, with the interval bounds of
/// the active ones.
pub(crate) struct FramePacket {
    len: usize,
    /// Rays not yet ended (inactive slots and ended rays excluded).
    live: usize,
    ox: [f32; PACKET],
    oy: [f32; PACKET],
    oz: [f32; PACKET],
    ix: [f32; PACKET],
    iy: [f32; PACKET],
    iz: [f32; PACKET],
    /// Frame parameter beyond which hits no longer count; `-inf` for an inactive or ended ray.
    tmax: [f32; PACKET],
    /// Per-axis bounds of the active rays' origins and reciprocal directions.
    omin: Vec3A,
    omax: Vec3A,
    imin: Vec3A,
    imax: Vec3A,
    /// The largest `tmax` of an active ray when the packet was filled.
    max_tmax: f32,
}

impl Default for FramePacket {
    fn default() -> Self {
        Self {
            len: 0,
            live: 0,
            ox: [0.0; PACKET],
            oy: [0.0; PACKET],
            oz: [0.0; PACKET],
            ix: [0.0; PACKET],
            iy: [0.0; PACKET],
            iz: [0.0; PACKET],
            tmax: [f32::NEG_INFINITY; PACKET],
            omin: Vec3A::INFINITY,
            omax: Vec3A::NEG_INFINITY,
            imin: Vec3A::INFINITY,
            imax: Vec3A::NEG_INFINITY,
            max_tmax: f32::NEG_INFINITY,
        }
    }
}

impl FramePacket {
    /// Empties the packet.
    pub(crate) fn clear(&mut self) {
        self.len = 0;
        self.live = 0;
        (self.omin, self.omax) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        (self.imin, self.imax) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        self.max_tmax = f32::NEG_INFINITY;
    }

    /// Adds the ray `origin + t * dir`, `0 <= t <= tmax` (finite `f32` frame coordinates).
    pub(crate) fn push(&mut self, origin: Vec3A, dir: Vec3A, tmax: f32) {
        let k = self.len;
        let inv = Vec3A::new(safe_inverse(dir.x), safe_inverse(dir.y), safe_inverse(dir.z));
        (self.ox[k], self.oy[k], self.oz[k]) = (origin.x, origin.y, origin.z);
        (self.ix[k], self.iy[k], self.iz[k]) = (inv.x, inv.y, inv.z);
        self.tmax[k] = tmax;
        self.omin = self.omin.min(origin);
        self.omax = self.omax.max(origin);
        self.imin = self.imin.min(inv);
        self.imax = self.imax.max(inv);
        self.max_tmax = self.max_tmax.max(tmax);
        self.len += 1;
        self.live += 1;
    }

    /// Adds a slot for a ray that does not traverse this BVH (it misses every box).
    pub(crate) fn push_inactive(&mut self) {
        let k = self.len;
        (self.ox[k], self.oy[k], self.oz[k]) = (0.0, 0.0, 0.0);
        (self.ix[k], self.iy[k], self.iz[k]) = (0.0, 0.0, 0.0);
        self.tmax[k] = f32::NEG_INFINITY;
        self.len += 1;
    }

    /// Ray `k`'s entry distance into box `b` (obvhs' `Aabb::intersect_ray`, bounded by the
    /// ray's `tmax`), or `f32::INFINITY` when it misses.
    #[inline(always)]
    fn entry(&self, k: usize, b: &Aabb) -> f32 {
        let (o, inv) = (
            Vec3A::new(self.ox[k], self.oy[k], self.oz[k]),
            Vec3A::new(self.ix[k], self.iy[k], self.iz[k]),
        );
        let t1 = (b.min - o) * inv;
        let t2 = (b.max - o) * inv;
        let near = t1.min(t2).max_element();
        let far = t1.max(t2).min_element();
        if far >= near && far >= 0.0 && near <= self.tmax[k] {
            near
        } else {
            f32::INFINITY
        }
    }

    /// Whether ray `k` hits box `b` within its range.
    #[inline(always)]
    fn hits(&self, k: usize, b: &Aabb) -> bool {
        self.entry(k, b) != f32::INFINITY
    }

    /// False only when no active ray of the packet can hit `b` (see the module doc).
    #[inline]
    fn may_hit(&self, b: &Aabb) -> bool {
        // Slab distances to the `min` and `max` planes, bounded over the box of origins and
        // reciprocal directions by their values at its corners.
        let bound = |plane: Vec3A| {
            let (a_lo, a_hi) = (plane - self.omax, plane - self.omin);
            let c = [a_lo * self.imin, a_lo * self.imax, a_hi * self.imin, a_hi * self.imax];
            (c[0].min(c[1]).min(c[2].min(c[3])), c[0].max(c[1]).max(c[2].max(c[3])))
        };
        let (lo1, hi1) = bound(b.min);
        let (lo2, hi2) = bound(b.max);
        // Per axis, the entry plane is `min` where every reciprocal is positive, `max` where
        // every one is negative, either where the signs differ.
        let positive = self.imin.cmpgt(Vec3A::ZERO);
        let negative = self.imax.cmplt(Vec3A::ZERO);
        let near = Vec3A::select(positive, lo1, Vec3A::select(negative, lo2, lo1.min(lo2)));
        let far = Vec3A::select(positive, hi2, Vec3A::select(negative, hi1, hi1.max(hi2)));
        let (near, far) = (near.max_element(), far.min_element());
        far >= near && far >= 0.0 && near <= self.max_tmax
    }
}

/// Walks `bvh` with `packet`; `leaf(k, slot)` tests ray `k` against the triangle in `slot` and
/// returns the ray's new `tmax` when it changes (`f32::NEG_INFINITY` ends the ray). `stack` is
/// scratch space.
pub(crate) fn traverse(
    bvh: &Bvh2,
    packet: &mut FramePacket,
    stack: &mut Vec<(u32, u32)>,
    mut leaf: impl FnMut(usize, usize) -> Option<f32>,
) {
    let len = packet.len;
    if packet.live == 0 || bvh.nodes.is_empty() {
        return;
    }
    stack.clear();
    stack.push((0, 0));
    while let Some((index, first)) = stack.pop() {
        let node = &bvh.nodes[index as usize];
        let b = &node.aabb;
        let mut first = first as usize;
        if !packet.hits(first, b) {
            if !packet.may_hit(b) {
                continue;
            }
            first += 1;
            while first < len && !packet.hits(first, b) {
                first += 1;
            }
            if first == len {
                continue;
            }
        }
        if node.prim_count == 0 {
            let (l, r) = (node.first_index, node.first_index + 1);
            let tl = packet.entry(first, &bvh.nodes[l as usize].aabb);
            let tr = packet.entry(first, &bvh.nodes[r as usize].aabb);
            let (near, far) = if tl <= tr { (l, r) } else { (r, l) };
            stack.push((far, first as u32));
            stack.push((near, first as u32));
            continue;
        }
        let slots = node.first_index as usize..(node.first_index + node.prim_count) as usize;
        for k in first..len {
            if k != first && !packet.hits(k, b) {
                continue;
            }
            for slot in slots.clone() {
                if let Some(t) = leaf(k, slot) {
                    packet.tmax[k] = t;
                    if t == f32::NEG_INFINITY {
                        packet.live -= 1;
                        break;
                    }
                }
            }
        }
        if packet.live == 0 {
            return;
        }
    }
}
