//! Stage "rasterization of blockers" (Aila and Laine 2004, section 5.1; semi-transparent
//! casters, section 4): every caster triangle is rasterized hierarchically into the 2D BSP of
//! the samples, and the samples it covers in front of them are shadowed (or attenuated).
//!
//! Per triangle ([`Blocker`]): the light's projection of its corners (clipped at the spot
//! light's `near` plane), wound positively, with its bounding box, the depth range of its
//! corners and the rational function giving the light depth of its plane at any image point.
//!
//! Per node, in this order: the triangle must *overlap* the node (its box meets the node's box
//! and no edge has the whole box strictly outside; a conservative test, see
//! [`Blocker::overlaps`]); the node is then *visited* (`bsp_nodes_visited`); *max-depth
//! culling* skips it when the triangle's nearest corner is not in front of the node's largest
//! threshold depth (`nodes_depth_culled`); *occlusion culling* skips it when all its samples
//! are already dark (`nodes_occlusion_culled`); otherwise the triangle goes on to both children,
//! or, in a leaf, to every sample that is not dark yet: inside the bounding box (the samples
//! counted by `sampling_points_tested`), not the sample's own triangle, depth in front of the
//! sample's threshold, and covered by the exact test ([`Blocker::covers`]). The counter keeps
//! its meaning whatever filter below decides a sample, so it stays comparable with the
//! paper's Table 1 and with the GPU twin's.
//!
//! Neither culling changes a result: a depth-culled triangle's depth (clamped to its corners'
//! range) is at or beyond every threshold in the node, and a dark sample stays dark.
//!
//! The per-sample test ([`Blocker::shadows_boxed`]) runs its cheap parts first: the sample's
//! own triangle, the threshold against the nearest corner's depth, then coverage, then the
//! plane's depth (a division) only where the threshold lies within the corners' depth range.
//! Coverage evaluates each edge function in `f64` with a forward error bound
//! ([`edge_sign`]) and calls Shewchuk's exact `orient2d` (with the top-left rule) only where
//! the bound cannot decide the sign, so the answer is the exact predicate's: for a long thin
//! caster most samples in its bounding box are far outside an edge and cost a few
//! multiplications (the paper does not say how its leaves test points).
//!
//! Parallel scheme: the BSP's top [`TOP_LEVELS`] levels are walked per triangle first
//! (binning, in parallel over fixed chunks of triangles), giving for each *frontier* node (at
//! depth [`TOP_LEVELS`], or a shallower leaf) the triangles that reach it, in triangle order.
//! Each frontier subtree, with its samples and occlusion state, is then owned by one task that
//! rasterizes its triangles in triangle order. Samples are thus attenuated in the same order
//! whatever the scheduling, and the result, the counters included, does not depend on the
//! number of threads. Nodes above the frontier carry no occlusion state (they are only depth
//! culled). The bins hold copies of the blockers, so that each subtree task reads its
//! triangles sequentially (indices into one list of blockers missed the cache on every
//! blocker on bunny-plane).

use super::{
    bsp::{Bsp, Node},
    samples::Sample,
};
use crate::raster::{clip_near, inside_edge};
use glam::{DVec2, DVec3};
use instrumentation::Counters;
use rayon::prelude::*;
use robust::{orient2d, Coord};
use scenes::{projection::ProjectionKind, Geometry, Projector};

/// Depth of the frontier nodes, whose subtrees are the parallel tasks (up to 64).
pub const TOP_LEVELS: usize = 6;

/// A leaf's samples in a triangle's bounding box are tested one by one up to this many;
/// beyond, the edge masks ([`Blocker::edge_masks`]) first drop those certainly outside.
const SCALAR_MAX: u32 = 6;

/// Triangles per binning task.
const BIN_CHUNK: usize = 1024;

/// Binning tasks per batch: triangles are binned and rasterized in batches of
/// `BIN_CHUNK * BATCH_CHUNKS`, so that the bins stay small and their memory is reused. Each
/// batch walks every subtree again, so smaller batches cost more than they save (8192
/// triangles per batch made bunny-plane's rasterization some 15% slower).
const BATCH_CHUNKS: usize = 64;

/// Which culling tests run (both on by default; off only to measure them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Culling {
    /// Skip nodes whose samples are all dark, and dark samples in leaves.
    pub occlusion: bool,
    /// Skip nodes whose farthest sample lies in front of the triangle.
    pub depth: bool,
}

/// The light a sample receives, as the casters rasterized so far leave it.
pub trait Shade: Copy + Send + Sync {
    /// Fully lit.
    const LIT: Self;
    /// Whether a sample is either lit or dark, nothing between (opaque casters only).
    const ALL_OR_NOTHING: bool;
    /// Whether no light reaches the sample any more (further casters cannot change it).
    fn is_dark(&self) -> bool;
    /// A caster letting `pass` of the light through covers the sample; returns whether the
    /// sample became dark.
    fn attenuate(&mut self, pass: &[f64; 3]) -> bool;
    /// The RGB transmittance.
    fn rgb(&self) -> [f64; 3];
}

/// Opaque casters: `true` once the sample is shadowed.
impl Shade for bool {
    const LIT: bool = false;
    const ALL_OR_NOTHING: bool = true;

    #[inline]
    fn is_dark(&self) -> bool {
        *self
    }

    #[inline]
    fn attenuate(&mut self, _pass: &[f64; 3]) -> bool {
        let became = !*self;
        *self = true;
        became
    }

    #[inline]
    fn rgb(&self) -> [f64; 3] {
        if *self {
            [0.0; 3]
        } else {
            [1.0; 3]
        }
    }
}

/// Semi-transparent casters: the RGB transmittance, initially white (section 4).
impl Shade for [f64; 3] {
    const LIT: [f64; 3] = [1.0; 3];
    const ALL_OR_NOTHING: bool = false;

    #[inline]
    fn is_dark(&self) -> bool {
        self.iter().all(|&c| c == 0.0)
    }

    #[inline]
    fn attenuate(&mut self, pass: &[f64; 3]) -> bool {
        let was_dark = self.is_dark();
        for (c, p) in self.iter_mut().zip(pass) {
            *c *= p;
        }
        !was_dark && self.is_dark()
    }

    #[inline]
    fn rgb(&self) -> [f64; 3] {
        *self
    }
}

#[inline]
fn coord(p: DVec2) -> Coord<f64> {
    Coord { x: p.x, y: p.y }
}

/// A caster triangle prepared for rasterization on the light's image plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blocker {
    /// The (clipped) convex outline, positively oriented, with the first corner repeated.
    outline: [DVec2; 5],
    /// Corners of the outline (3, or 4 after near clipping).
    corners: usize,
    /// Per edge, a bound on the rounding error of its edge function anywhere in the bounding
    /// box (see [`Blocker::edge_masks`]).
    edge_bounds: [f64; 4],
    /// Bounding box of the outline.
    lo: DVec2,
    hi: DVec2,
    /// Light depth of the plane at `(x, y)`: `(n0 + n1 x + n2 y) / (d0 + d1 x + d2 y)`.
    num: [f64; 3],
    den: [f64; 3],
    /// Depth range of the outline's corners.
    dmin: f64,
    dmax: f64,
    /// Triangle id.
    id: u32,
    /// Object index (for its opacity).
    object: u32,
}

impl Blocker {
    /// Prepares triangle `t`; `None` when it covers nothing (zero area, collinear projection,
    /// non-finite corners, or wholly nearer a spot light than its `near` plane).
    pub fn new(geometry: &Geometry, t: usize, light: &Projector) -> Option<Self> {
        let [i, j, k] = geometry.triangles[t];
        let p = &geometry.positions;
        let corners = [p[i as usize], p[j as usize], p[k as usize]];
        // Any length will do: the depth is a ratio of two linear functions of the normal.
        let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        if normal == DVec3::ZERO || !normal.is_finite() {
            return None;
        }
        let mut outline = [DVec2::ZERO; 5];
        let mut depth = [0.0; 4];
        let count = if light.is_perspective() {
            let (world, count) = clip_near(corners, corners.map(|c| light.depth_of(c)), light.near);
            for i in 0..count {
                (outline[i], depth[i]) = light.project_unclipped(world[i]);
            }
            count
        } else {
            for i in 0..3 {
                (outline[i], depth[i]) = light.project_unclipped(corners[i]);
            }
            3
        };
        if count < 3 || !outline[..count].iter().all(|q| q.is_finite()) {
            return None;
        }
        let (dmin, dmax) = depth[..count]
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &d| (lo.min(d), hi.max(d)));
        if !(dmin.is_finite() && dmax.is_finite()) {
            return None;
        }
        let orientation = (1..count - 1)
            .map(|i| orient2d(coord(outline[0]), coord(outline[i]), coord(outline[i + 1])))
            .find(|&s| s != 0.0)?;
        if orientation < 0.0 {
            outline[..count].reverse();
        }
        outline[count] = outline[0];
        let (lo, hi) = outline[..count].iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let size = hi - lo;
        let mut edge_bounds = [0.0; 4];
        for (e, bound) in edge_bounds[..count].iter_mut().enumerate() {
            let d = outline[e + 1] - outline[e];
            *bound =
                EDGE_FILTER_BOUND * (d.x.abs() * size.y + d.y.abs() * size.x) + f64::MIN_POSITIVE;
        }
        // The plane n·p = offset met by the light's ray through (x, y), with the projector's
        // sx = 2x / W - 1 and sy = 1 - 2y / H (see `Projector::ray`).
        let offset = normal.dot(corners[0]);
        let (nr, nu, nf, no) = (
            normal.dot(light.right),
            normal.dot(light.up),
            normal.dot(light.forward),
            normal.dot(light.origin),
        );
        let (w, h) = (light.width, light.height);
        let (num, den) = match light.kind {
            ProjectionKind::Orthographic { half_width: hw, half_height: hh } => (
                [offset - no + nr * hw - nu * hh, -2.0 * nr * hw / w, 2.0 * nu * hh / h],
                [nf, 0.0, 0.0],
            ),
            ProjectionKind::Perspective { tan_half_x: tx, tan_half_y: ty } => (
                [offset - no, 0.0, 0.0],
                [nf - nr * tx + nu * ty, 2.0 * nr * tx / w, -2.0 * nu * ty / h],
            ),
        };
        Some(Self {
            outline,
            corners: count,
            edge_bounds,
            lo,
            hi,
            num,
            den,
            dmin,
            dmax,
            id: t as u32,
            object: geometry.object[t],
        })
    }

    /// The bounding box `(lo, hi)` of the outline on the light's image plane.
    pub fn bounds(&self) -> (DVec2, DVec2) {
        (self.lo, self.hi)
    }

    /// The nearest light depth of the outline's corners: the triangle shadows no point whose
    /// threshold depth is at or in front of it.
    pub fn nearest_depth(&self) -> f64 {
        self.dmin
    }

    /// Whether the triangle may cover a point of the box `lo..=hi`. Conservative: `false` only
    /// when the boxes are disjoint or, for some edge, the box's corner farthest inside lies
    /// outside by more than `1e-12` of the terms' magnitude, far beyond the rounding of the
    /// edge function (about `4.4e-16` of it); the exact test then rejects every point of
    /// the box.
    #[inline(always)]
    pub fn overlaps(&self, lo: DVec2, hi: DVec2) -> bool {
        if self.hi.x < lo.x || self.lo.x > hi.x || self.hi.y < lo.y || self.lo.y > hi.y {
            return false;
        }
        // A box holding the whole triangle passes every edge test.
        let inside =
            lo.x <= self.lo.x && self.hi.x <= hi.x && lo.y <= self.lo.y && self.hi.y <= hi.y;
        inside || self.edges_meet(lo, hi)
    }

    /// The edge part of [`Blocker::overlaps`].
    #[inline(never)]
    fn edges_meet(&self, lo: DVec2, hi: DVec2) -> bool {
        for e in 0..self.corners {
            let (a, b) = (self.outline[e], self.outline[e + 1]);
            let (dx, dy) = (b.x - a.x, b.y - a.y);
            // orient2d(a, b, p) = dx (p.y - a.y) - dy (p.x - a.x), largest at this corner:
            let px = if dy < 0.0 { hi.x } else { lo.x };
            let py = if dx > 0.0 { hi.y } else { lo.y };
            let (u, v) = (dx * (py - a.y), dy * (px - a.x));
            if u - v < -1e-12 * (u.abs() + v.abs()) {
                return false;
            }
        }
        true
    }

    /// Whether `p` lies inside the outline: exact orientation predicates, ties on an edge
    /// decided by the rasterizer's top-left rule ([`crate::raster::inside_edge`]). Each edge is
    /// first decided by the floating-point filter [`edge_sign`]; the exact predicate runs only
    /// where the filter cannot decide, so the answer is always the exact one.
    #[inline]
    pub fn covers(&self, p: DVec2) -> bool {
        (0..self.corners).all(|e| {
            let (a, b) = (self.outline[e], self.outline[e + 1]);
            match edge_sign(a, b - a, p) {
                Some(inside) => inside,
                None => inside_edge(a, b, p),
            }
        })
    }

    /// Two masks over samples `i` (coordinates `xs[i]`, `ys[i]`, at most 64) inside the
    /// bounding box and inside the box `lo..=hi` (a BSP node's): `maybe` clears the samples
    /// that lie certainly outside an edge, `surely` sets those certainly inside every edge;
    /// [`Blocker::covers`] is false where `maybe` is clear and true where `surely` is set.
    ///
    /// Per edge, the floating-point edge function is compared with the edge's bound for the
    /// whole bounding box (in `edge_bounds`: [`EDGE_FILTER_BOUND`] times the largest
    /// `|d.x (p.y - a.y)| + |d.y (p.x - a.x)|` there, which bounds every term of
    /// [`edge_sign`]'s analysis for a point of the box). An edge whose inner side certainly
    /// holds all of `lo..=hi` ([`edge_sign`] at the box corner where the edge function is
    /// smallest) is skipped. Branch-free, one edge at a time over the samples, so that the
    /// compiler can vectorise it.
    #[inline]
    pub fn edge_masks(&self, xs: &[f64], ys: &[f64], lo: DVec2, hi: DVec2) -> (u64, u64) {
        let (mut maybe, mut surely) = (u64::MAX, u64::MAX);
        for e in 0..self.corners {
            let (a, bound) = (self.outline[e], self.edge_bounds[e]);
            let d = self.outline[e + 1] - a;
            let corner = DVec2::new(
                if d.y > 0.0 { hi.x } else { lo.x },
                if d.x > 0.0 { lo.y } else { hi.y },
            );
            if edge_sign(a, d, corner) == Some(true) {
                continue;
            }
            let (mut keep, mut inside) = (0u64, 0u64);
            for (i, (&x, &y)) in xs.iter().zip(ys).enumerate() {
                let det = d.x * (y - a.y) - d.y * (x - a.x);
                // A NaN (overflowed) edge function is not certainly outside: kept.
                let outside = det < -bound;
                keep |= u64::from(!outside) << i;
                inside |= u64::from(det > bound) << i;
            }
            maybe &= keep;
            surely &= inside;
        }
        (maybe, surely)
    }

    /// Whether `p` lies inside the outline by the exact predicates alone (no filter).
    #[cfg(test)]
    fn covers_exactly(&self, p: DVec2) -> bool {
        (0..self.corners).all(|e| inside_edge(self.outline[e], self.outline[e + 1], p))
    }

    /// The light depth of the triangle's plane at image point `(x, y)`, clamped to the depth
    /// range of its corners (the nearest corner's depth when the ray misses the plane).
    #[inline]
    pub fn depth_at(&self, x: f64, y: f64) -> f64 {
        let d = (self.num[0] + self.num[1] * x + self.num[2] * y)
            / (self.den[0] + self.den[1] * x + self.den[2] * y);
        if d.is_finite() {
            d.clamp(self.dmin, self.dmax)
        } else {
            self.dmin
        }
    }

    /// Whether the triangle shadows `s`, which lies in its bounding box: not the sample's own
    /// triangle, in front of its threshold depth, and covering it. The clamped depth lies in
    /// `dmin..=dmax`, so a threshold at or in front of `dmin` rejects the sample, and one
    /// beyond `dmax` accepts it, without the plane's division; the cheap tests run first.
    #[inline]
    pub fn shadows_boxed(&self, s: &Sample) -> bool {
        s.tri != self.id
            && self.dmin < s.zt
            && self.covers(DVec2::new(s.x, s.y))
            && (self.dmax < s.zt || self.depth_at(s.x, s.y) < s.zt)
    }

    /// [`Blocker::shadows_boxed`] for a sample the triangle is known to cover.
    #[inline]
    pub fn shadows_covered(&self, s: &Sample) -> bool {
        s.tri != self.id && self.dmin < s.zt && (self.dmax < s.zt || self.depth_at(s.x, s.y) < s.zt)
    }

    /// Whether the triangle shadows `s` (the predicate the hierarchy evaluates in leaves).
    pub fn shadows(&self, s: &Sample) -> bool {
        let inside = s.x >= self.lo.x && s.x <= self.hi.x && s.y >= self.lo.y && s.y <= self.hi.y;
        inside && self.shadows_boxed(s)
    }
}

/// Relative error bound of the filter of [`edge_sign`]: `8u` (`u = 2^-53`, the unit roundoff),
/// twice the bound `4u` of its rounded operations (see there).
pub const EDGE_FILTER_BOUND: f64 = 4.0 * f64::EPSILON;

/// The sign of `orient2d(a, a + d, p)` where a floating-point evaluation decides it: `Some(true)`
/// when positive, `Some(false)` when negative, `None` when it may be zero or the rounding may
/// hide its sign (the caller then runs the exact predicate). `d` is the edge vector as computed
/// (`b - a` rounded), and the determinant `d.x (p.y - a.y) - d.y (p.x - a.x)` equals
/// `orient2d(a, b, p)` in exact arithmetic. Evaluated in `f64`, each of the two products carries
/// the rounding of one difference and of the product (relative error below `3u`, `u = 2^-53`),
/// and the final difference one more, so the result lies within `4u (|u1| + |u2|)` of the exact
/// value (plus underflow, at most `f64::MIN_POSITIVE`); the filter trusts a sign only beyond
/// twice that ([`EDGE_FILTER_BOUND`]). Non-finite terms leave the sign undecided.
#[inline(always)]
pub fn edge_sign(a: DVec2, d: DVec2, p: DVec2) -> Option<bool> {
    let (u, v) = (d.x * (p.y - a.y), d.y * (p.x - a.x));
    let det = u - v;
    let bound = EDGE_FILTER_BOUND * (u.abs() + v.abs()) + f64::MIN_POSITIVE;
    if det > bound {
        Some(true)
    } else if det < -bound {
        Some(false)
    } else {
        None
    }
}

/// The triangles of one chunk that reach each frontier node, in triangle order.
struct Chunk {
    /// For each frontier slot, the blockers that reach it (copied while they are in cache, so
    /// that each subtree task reads its own triangles sequentially).
    bins: Vec<Vec<Blocker>>,
    counters: Counters,
}

/// Walks the top levels of the BSP.
struct Binner<'a> {
    nodes: &'a [Node],
    /// Frontier nodes, increasing (preorder).
    frontier: &'a [usize],
    depth_culling: bool,
}

impl Binner<'_> {
    /// Bins a blocker into every frontier node it reaches.
    fn bin(&self, b: &Blocker, bins: &mut [Vec<Blocker>], c: &mut Counters) {
        let root = &self.nodes[0];
        if b.overlaps(root.lo, root.hi) {
            c.bsp_nodes_visited += 1;
            self.descend(b, 0, 0, bins, c);
        }
    }

    /// `g` overlaps the blocker and was counted as visited.
    fn descend(
        &self,
        b: &Blocker,
        g: usize,
        depth: usize,
        bins: &mut [Vec<Blocker>],
        c: &mut Counters,
    ) {
        let node = &self.nodes[g];
        if self.depth_culling && b.dmin >= node.max_zt {
            c.nodes_depth_culled += 1;
            return;
        }
        if depth == TOP_LEVELS || node.is_leaf() {
            if let Ok(slot) = self.frontier.binary_search(&g) {
                bins[slot].push(*b);
            }
            return;
        }
        for child in [g + 1, g + node.right as usize] {
            let n = &self.nodes[child];
            if b.overlaps(n.lo, n.hi) {
                c.bsp_nodes_visited += 1;
                self.descend(b, child, depth + 1, bins, c);
            }
        }
    }
}

/// The frontier nodes (depth [`TOP_LEVELS`], or shallower leaves) in preorder.
fn frontier(bsp: &Bsp) -> Vec<usize> {
    fn walk(bsp: &Bsp, g: usize, depth: usize, out: &mut Vec<usize>) {
        let node = &bsp.nodes[g];
        if depth == TOP_LEVELS || node.is_leaf() {
            out.push(g);
        } else {
            walk(bsp, g + 1, depth + 1, out);
            walk(bsp, g + node.right as usize, depth + 1, out);
        }
    }
    let mut out = Vec::new();
    walk(bsp, 0, 0, &mut out);
    out
}

/// One frontier subtree with its exclusive state.
struct Subtree<'a, S> {
    nodes: &'a [Node],
    bsp: &'a Bsp,
    /// The frontier node; `live[g - root]` belongs to node `g`.
    root: usize,
    /// First sample of the subtree; `state[k - sample_base]` belongs to sample `k`.
    sample_base: usize,
    /// Samples not dark yet, per node of the subtree.
    live: &'a mut [u32],
    state: &'a mut [S],
    passes: &'a [[f64; 3]],
    culling: Culling,
    counters: Counters,
}

impl<S: Shade> Subtree<'_, S> {
    /// Rasterizes a blocker that reached the frontier node (overlap, visit and depth culling
    /// done while binning).
    fn rasterize(&mut self, b: &Blocker) {
        let pass = self.passes.get(b.object as usize).copied().unwrap_or([0.0; 3]);
        self.visit(self.root, b, &pass);
    }

    /// `g` overlaps the blocker, was counted as visited and passed depth culling; returns
    /// the number of samples that became dark.
    fn visit(&mut self, g: usize, b: &Blocker, pass: &[f64; 3]) -> u32 {
        let nodes = self.nodes;
        let node = &nodes[g];
        if self.culling.occlusion && self.live[g - self.root] == 0 {
            self.counters.nodes_occlusion_culled += 1;
            return 0;
        }
        let darkened = if node.is_leaf() {
            self.leaf(node, b, pass)
        } else {
            let mut darkened = 0;
            for child in [g + 1, g + node.right as usize] {
                let n = &nodes[child];
                if !b.overlaps(n.lo, n.hi) {
                    continue;
                }
                self.counters.bsp_nodes_visited += 1;
                if self.culling.depth && b.dmin >= n.max_zt {
                    self.counters.nodes_depth_culled += 1;
                    continue;
                }
                darkened += self.visit(child, b, pass);
            }
            darkened
        };
        self.live[g - self.root] -= darkened;
        darkened
    }

    fn leaf(&mut self, node: &Node, b: &Blocker, pass: &[f64; 3]) -> u32 {
        let bsp = self.bsp;
        let (start, end) = (node.start as usize, node.end as usize);
        let skip_dark = self.culling.occlusion;
        let (mut darkened, mut tested) = (0u32, 0u64);
        let (lo, hi) = (b.lo, b.hi);
        // A leaf inside the triangle's box needs no box test.
        let all_boxed =
            lo.x <= node.lo.x && node.hi.x <= hi.x && lo.y <= node.lo.y && node.hi.y <= hi.y;
        for first in (start..end).step_by(64) {
            let last = (first + 64).min(end);
            let (xs, ys) = (&bsp.xs[first..last], &bsp.ys[first..last]);
            // Branch-free box test of up to 64 samples, one bit each.
            let mut boxed = u64::MAX >> (64 - (last - first));
            if !all_boxed {
                boxed = 0;
                for (i, (&x, &y)) in xs.iter().zip(ys).enumerate() {
                    let inside = (x >= lo.x) & (x <= hi.x) & (y >= lo.y) & (y <= hi.y);
                    boxed |= u64::from(inside) << i;
                }
            }
            if boxed.count_ones() <= SCALAR_MAX {
                // Few samples (a small triangle): test them one by one.
                while boxed != 0 {
                    let i = boxed.trailing_zeros() as usize;
                    boxed &= boxed - 1;
                    let st = &mut self.state[first + i - self.sample_base];
                    if skip_dark && st.is_dark() {
                        continue;
                    }
                    tested += 1;
                    if b.shadows_boxed(&bsp.samples[first + i]) {
                        darkened += u32::from(st.attenuate(pass));
                    }
                }
                continue;
            }
            let states = &mut self.state[first - self.sample_base..last - self.sample_base];
            let mut dark = 0u64;
            if skip_dark {
                for (i, st) in states.iter().enumerate() {
                    dark |= u64::from(st.is_dark()) << i;
                }
            }
            let live = boxed & !dark;
            tested += u64::from(live.count_ones());
            // Samples certainly outside an edge are not shadowed: skip them without a branch;
            // those certainly inside every edge need only the depth test.
            let (maybe, surely) = b.edge_masks(xs, ys, node.lo, node.hi);
            let mut mask = live & maybe;
            while mask != 0 {
                let i = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                let s = &bsp.samples[first + i];
                let shadowed =
                    if surely & (1 << i) != 0 { b.shadows_covered(s) } else { b.shadows_boxed(s) };
                if shadowed {
                    darkened += u32::from(states[i].attenuate(pass));
                }
            }
        }
        self.counters.sampling_points_tested += tested;
        darkened
    }
}

/// Rasterizes every triangle `t` with `is_caster(t)` into the BSP: the light each sample
/// receives, in the BSP's sample order, and the counters (`bsp_nodes_visited`,
/// `nodes_depth_culled`, `nodes_occlusion_culled`, `sampling_points_tested`). `passes[o]`
/// is the RGB fraction of light that object `o`'s triangles let through (used by
/// `S = [f64; 3]`).
pub fn rasterize_blockers<S: Shade>(
    geometry: &Geometry,
    is_caster: impl Fn(usize) -> bool + Sync,
    passes: &[[f64; 3]],
    light: &Projector,
    bsp: &Bsp,
    culling: Culling,
) -> (Vec<S>, Counters) {
    let frontier = frontier(bsp);
    let binner = Binner { nodes: &bsp.nodes, frontier: &frontier, depth_culling: culling.depth };
    let mut live: Vec<u32> = bsp.nodes.iter().map(|node| node.len() as u32).collect();
    let mut state = vec![S::LIT; bsp.samples.len()];
    let mut tasks = Vec::with_capacity(frontier.len());
    {
        let (mut live_rest, mut live_at): (&mut [u32], usize) = (&mut live, 0);
        let (mut state_rest, mut state_at): (&mut [S], usize) = (&mut state, 0);
        for &f in &frontier {
            let end = bsp.subtree_end(f);
            let (_, rest) = std::mem::take(&mut live_rest).split_at_mut(f - live_at);
            let (mine, rest) = rest.split_at_mut(end - f);
            (live_rest, live_at) = (rest, end);
            let node = &bsp.nodes[f];
            let skip = node.start as usize - state_at;
            let (_, rest) = std::mem::take(&mut state_rest).split_at_mut(skip);
            let (own, rest) = rest.split_at_mut(node.len());
            (state_rest, state_at) = (rest, node.end as usize);
            tasks.push(Subtree {
                nodes: &bsp.nodes,
                bsp,
                root: f,
                sample_base: node.start as usize,
                live: mine,
                state: own,
                passes,
                culling,
                counters: Counters::default(),
            });
        }
    }
    // Batches of triangles, binned then rasterized, reusing the bins' memory.
    let n = geometry.len();
    let mut chunks: Vec<Chunk> = (0..n.div_ceil(BIN_CHUNK).min(BATCH_CHUNKS))
        .map(|_| Chunk { bins: vec![Vec::new(); frontier.len()], counters: Counters::default() })
        .collect();
    for batch in (0..n).step_by(BIN_CHUNK * BATCH_CHUNKS) {
        chunks.par_iter_mut().enumerate().for_each(|(c, chunk)| {
            chunk.bins.iter_mut().for_each(Vec::clear);
            let first = batch + c * BIN_CHUNK;
            for t in first..(first + BIN_CHUNK).min(n) {
                if !is_caster(t) {
                    continue;
                }
                if let Some(b) = Blocker::new(geometry, t, light) {
                    binner.bin(&b, &mut chunk.bins, &mut chunk.counters);
                }
            }
        });
        tasks.par_iter_mut().enumerate().for_each(|(slot, task)| {
            for chunk in &chunks {
                for b in &chunk.bins[slot] {
                    task.rasterize(b);
                }
            }
        });
    }
    let mut counters: Counters = tasks.iter().map(|t| t.counters).sum();
    for chunk in &chunks {
        counters.merge(&chunk.counters);
    }
    (state, counters)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::{
        tests::{pixel_projector, spot_above},
        NO_TRIANGLE,
    };
    use proptest::prelude::*;

    /// A spot light above the square `[0, 16]^2` at height 12, looking straight down.
    fn spot() -> Projector {
        spot_above(8.0, 8.0)
    }

    fn geometry(tris: &[[(f64, f64, f64); 3]]) -> Geometry {
        let mut g = Geometry::default();
        for (i, t) in tris.iter().enumerate() {
            let base = g.positions.len() as u32;
            g.positions.extend(t.iter().map(|&(x, y, z)| DVec3::new(x, 16.0 - y, z)));
            g.triangles.push([base, base + 1, base + 2]);
            g.object.push((i % 3) as u32);
        }
        g
    }

    /// Light each sample receives, by testing every (sample, triangle) pair in triangle order.
    fn brute_force<S: Shade>(
        g: &Geometry,
        light: &Projector,
        samples: &[Sample],
        passes: &[[f64; 3]],
    ) -> Vec<S> {
        let blockers: Vec<Blocker> =
            (0..g.len()).filter_map(|t| Blocker::new(g, t, light)).collect();
        samples
            .iter()
            .map(|s| {
                let mut l = S::LIT;
                for b in blockers.iter().filter(|b| b.shadows(s)) {
                    l.attenuate(&passes[b.object as usize]);
                }
                l
            })
            .collect()
    }

    fn tri() -> impl Strategy<Value = [(f64, f64, f64); 3]> {
        // Corners on a quarter-unit grid put many samples exactly on edges and corners.
        let corner = (0u32..=64, 0u32..=64, 0u32..=8)
            .prop_map(|(x, y, z)| (f64::from(x) / 4.0, f64::from(y) / 4.0, f64::from(z) / 2.0));
        [corner.clone(), corner.clone(), corner]
    }

    fn sample_strategy(triangles: usize) -> impl Strategy<Value = (f64, f64, f64, u32)> {
        (0u32..=64, 0u32..=64, 0u32..=20, 0..triangles as u32 + 1).prop_map(move |(x, y, z, t)| {
            let tri = if t as usize == triangles { NO_TRIANGLE } else { t };
            (f64::from(x) / 4.0, f64::from(y) / 4.0, f64::from(z) / 4.0, tri)
        })
    }

    proptest! {
        /// The hierarchy, with every combination of culling, gives exactly the light of the
        /// brute-force test of every pair, for opaque and semi-transparent casters (the
        /// products in the same triangle order, so bit for bit).
        #[test]
        fn hierarchy_equals_brute_force(
            tris in proptest::collection::vec(tri(), 1..40),
            raw in proptest::collection::vec(sample_strategy(40), 0..600),
            leaf_size in 2usize..20,
            perspective in any::<bool>(),
        ) {
            let g = geometry(&tris);
            let light = if perspective { spot() } else { pixel_projector(16, 16) };
            let samples: Vec<Sample> = raw
                .iter()
                .enumerate()
                .filter_map(|(i, &(x, y, z, tri))| {
                    // Depth from the light of the world point (x, 16 - y, z): through the
                    // light's projection, so spot samples get their perspective image point.
                    let (xy, d) = light.project(DVec3::new(x, 16.0 - y, z))?;
                    let tri = if (tri as usize) < g.len() || tri == NO_TRIANGLE { tri } else { 0 };
                    Some(Sample { x: xy.x, y: xy.y, zt: d - 1e-9, id: i as u32, tri })
                })
                .collect();
            let bsp = Bsp::build(samples, leaf_size);
            let passes = [[0.5, 0.25, 0.75], [0.0; 3], [0.9, 0.9, 0.9]];
            let opaque: Vec<bool> = brute_force(&g, &light, &bsp.samples, &passes);
            let rgb: Vec<[f64; 3]> = brute_force(&g, &light, &bsp.samples, &passes);
            for occlusion in [false, true] {
                for depth in [false, true] {
                    let culling = Culling { occlusion, depth };
                    let (o, _) = rasterize_blockers::<bool>(&g, |_| true, &passes, &light, &bsp, culling);
                    prop_assert_eq!(&o, &opaque);
                    let (t, _) =
                        rasterize_blockers::<[f64; 3]>(&g, |_| true, &passes, &light, &bsp, culling);
                    prop_assert_eq!(&t, &rgb);
                }
            }
        }

        /// Where the floating-point edge filter decides, it gives the sign of the exact
        /// `orient2d`; on points exactly on or a few ulps beside an edge it must abstain or agree.
        #[test]
        fn edge_filter_agrees_with_orient2d(
            a in (-1e3f64..1e3, -1e3f64..1e3),
            b in (-1e3f64..1e3, -1e3f64..1e3),
            t in -0.5f64..1.5,
            nudge in (-4i64..=4, -4i64..=4),
            scale in prop_oneof![Just(1.0), Just(1e-7), Just(3.0e5), Just(1e-150), Just(1e150)],
            random in (-1e3f64..1e3, -1e3f64..1e3),
            on_line in any::<bool>(),
        ) {
            let (a, b) = (DVec2::new(a.0, a.1) * scale, DVec2::new(b.0, b.1) * scale);
            // A point on the line through a and b (rounded), moved by a few ulps, or anywhere.
            let p = if on_line {
                let q = a + (b - a) * t;
                let step = |v: f64, k: i64| {
                    let bits = v.to_bits() as i64 + if v >= 0.0 { k } else { -k };
                    f64::from_bits(bits as u64)
                };
                DVec2::new(step(q.x, nudge.0), step(q.y, nudge.1))
            } else {
                DVec2::new(random.0, random.1) * scale
            };
            let exact = orient2d(coord(a), coord(b), coord(p));
            match edge_sign(a, b - a, p) {
                Some(true) => prop_assert!(exact > 0.0, "{a} {b} {p}: filter +, exact {exact}"),
                Some(false) => prop_assert!(exact < 0.0, "{a} {b} {p}: filter -, exact {exact}"),
                None => {}
            }
        }

        /// Coverage through the filter equals the exact predicates alone, on samples of a
        /// quarter-unit grid (many exactly on edges and corners) and off it.
        #[test]
        fn filtered_coverage_equals_exact_coverage(
            t in tri(),
            points in proptest::collection::vec((0u32..=64, 0u32..=64, -1.0f64..1.0), 1..200),
            perspective in any::<bool>(),
        ) {
            let g = geometry(&[t]);
            let light = if perspective { spot() } else { pixel_projector(16, 16) };
            let Some(b) = Blocker::new(&g, 0, &light) else { return Ok(()) };
            for &(x, y, jitter) in &points {
                let on_grid = DVec2::new(f64::from(x), f64::from(y)) / 4.0;
                for p in [on_grid, on_grid + DVec2::splat(jitter * 1e-13)] {
                    prop_assert_eq!(b.covers(p), b.covers_exactly(p), "{}", p);
                }
            }
        }

        /// The leaves' edge masks clear only samples the triangle does not cover and set only
        /// samples it covers, whatever node box holds the samples.
        #[test]
        fn edge_masks_agree_with_exact_coverage(
            t in tri(),
            points in proptest::collection::vec((0u32..=64, 0u32..=64, -1.0f64..1.0), 1..=64),
            grow in 0.0f64..4.0,
            perspective in any::<bool>(),
        ) {
            let g = geometry(&[t]);
            let light = if perspective { spot() } else { pixel_projector(16, 16) };
            let Some(b) = Blocker::new(&g, 0, &light) else { return Ok(()) };
            // Grid points (on edges and corners) and points 1e-13 beside them, in the box.
            let ps: Vec<DVec2> = points
                .iter()
                .map(|&(x, y, j)| {
                    let p = DVec2::new(f64::from(x), f64::from(y)) / 4.0 + DVec2::splat(j * 1e-13);
                    p.clamp(b.lo, b.hi)
                })
                .collect();
            let xs: Vec<f64> = ps.iter().map(|p| p.x).collect();
            let ys: Vec<f64> = ps.iter().map(|p| p.y).collect();
            let (lo, hi) = ps.iter().fold((ps[0], ps[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)));
            let (maybe, surely) = b.edge_masks(&xs, &ys, lo - grow, hi + grow);
            for (i, &p) in ps.iter().enumerate() {
                let covered = b.covers_exactly(p);
                if maybe & (1 << i) == 0 {
                    prop_assert!(!covered, "{} cleared but covered", p);
                }
                if surely & (1 << i) != 0 {
                    prop_assert!(covered, "{} set but not covered", p);
                }
            }
        }

        /// A box holding a point the triangle covers always overlaps the triangle.
        #[test]
        fn overlap_is_conservative(
            t in tri(),
            p in (0u32..=64, 0u32..=64),
            grow in (0u32..8, 0u32..8, 0u32..8, 0u32..8),
            perspective in any::<bool>(),
        ) {
            let g = geometry(&[t]);
            let light = if perspective { spot() } else { pixel_projector(16, 16) };
            let Some(b) = Blocker::new(&g, 0, &light) else { return Ok(()) };
            let Some((p, _)) = light.project(DVec3::new(f64::from(p.0) / 4.0, 16.0 - f64::from(p.1) / 4.0, 0.0)) else {
                return Ok(())
            };
            let (a, bb, c, d) = grow;
            let lo = p - DVec2::new(f64::from(a), f64::from(bb)) / 8.0;
            let hi = p + DVec2::new(f64::from(c), f64::from(d)) / 8.0;
            if b.covers(p) {
                prop_assert!(b.overlaps(lo, hi));
                prop_assert!(b.overlaps(p, p));
            }
        }

        /// The rational depth function equals the ray-plane intersection.
        #[test]
        fn depth_is_the_ray_plane_intersection(
            t in tri(),
            q in (0.0f64..16.0, 0.0f64..16.0),
            perspective in any::<bool>(),
        ) {
            let g = geometry(&[t]);
            let light = if perspective { spot() } else { pixel_projector(16, 16) };
            let Some(b) = Blocker::new(&g, 0, &light) else { return Ok(()) };
            let xy = DVec2::new(q.0, q.1);
            if !b.covers(xy) {
                return Ok(());
            }
            let [p0, p1, p2] = g.corners(0);
            let n = (p1 - p0).cross(p2 - p0).normalize();
            let Some(d) = light.ray(xy).intersect_plane(n, n.dot(p0)) else { return Ok(()) };
            let d = d.clamp(b.dmin, b.dmax);
            let got = b.depth_at(xy.x, xy.y);
            prop_assert!((got - d).abs() <= 1e-9 * d.abs().max(1.0), "{} vs {}", got, d);
        }
    }

    #[test]
    fn culling_skips_nodes_on_a_covered_scene() {
        // A far ground quad of samples under a near square covering its middle, and a second
        // square farther than every sample: occlusion and depth culling both apply.
        let tris = [
            [(4.0, 4.0, 4.0), (12.0, 4.0, 4.0), (12.0, 12.0, 4.0)],
            [(4.0, 4.0, 4.0), (12.0, 12.0, 4.0), (4.0, 12.0, 4.0)],
            [(0.0, 0.0, -5.0), (16.0, 0.0, -5.0), (16.0, 16.0, -5.0)],
            [(5.0, 5.0, 5.0), (6.0, 5.0, 5.0), (6.0, 6.0, 5.0)],
        ];
        let g = geometry(&tris);
        let light = pixel_projector(16, 16);
        let samples: Vec<Sample> = (0..64 * 64)
            .map(|i| {
                let (x, y) = ((i % 64) as f64 / 4.0 + 0.125, (i / 64) as f64 / 4.0 + 0.125);
                Sample { x, y, zt: 10.0 - 1e-9, id: i as u32, tri: NO_TRIANGLE }
            })
            .collect();
        let bsp = Bsp::build(samples, 8);
        let passes = [[0.0; 3]; 3];
        let run = |occlusion, depth| {
            rasterize_blockers::<bool>(
                &g,
                |_| true,
                &passes,
                &light,
                &bsp,
                Culling { occlusion, depth },
            )
        };
        let (all, on) = run(true, true);
        let (no_occlusion, off_o) = run(false, true);
        let (no_depth, off_d) = run(true, false);
        assert_eq!(all, no_occlusion);
        assert_eq!(all, no_depth);
        assert_eq!(all.iter().filter(|&&d| d).count(), 32 * 32);
        assert!(on.nodes_occlusion_culled > 0 && off_o.nodes_occlusion_culled == 0);
        assert!(on.nodes_depth_culled > 0 && off_d.nodes_depth_culled == 0);
        assert!(on.sampling_points_tested < off_o.sampling_points_tested);
        assert!(on.sampling_points_tested < off_d.sampling_points_tested);
    }
}
