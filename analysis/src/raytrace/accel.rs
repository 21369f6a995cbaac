//! The acceleration structure that finds candidate triangles for the `f64` test: the triangles
//! split into clusters, each a binary BVH built by obvhs (PLOC; a large cluster in parts of at
//! most [`PART`] triangles, in parallel, joined under median halvings) and traversed by packets
//! ([`super::packet`]) in an `f32` frame of its own (see the parent module's "Precision" for
//! why nothing is lost and how far objects are kept apart).
//!
//! Hot path: [`Accel::closest`] and [`Accel::transmittance`] take a packet of rays and a
//! [`Scratch`] reused from packet to packet; per ray they make one `f64` clip per cluster
//! ([`Cluster::route`]) and the `f64` triangle tests the traversal leaves, and allocate nothing.

use super::bvh::{self, Node, Piece};
use super::memory::{AllocationError, Allocator, Spare};
use super::packet::{self, FramePacket, PACKET};
use super::ray::TraceRay;
use glam::{DVec3, Vec3A};
use obvhs::{aabb::Aabb, bvh2::builder::build_bvh2, Boundable, BvhBuildParams};
use rayon::prelude::*;
use scenes::Geometry;
use std::ops::Range;

/// Box padding in units of `f32::EPSILON` times (reach + box magnitude): covers the `f32`
/// rounding of the ray's start and direction, obvhs' clamped reciprocal of direction components
/// below `f32::EPSILON`, the rounding of its slab tests, and the `f64` rounding of the start
/// point (at most half an `f32` epsilon of the reach, see [`Cluster::route`]), with a margin of
/// about 7.
const PAD_ULPS: f64 = 32.0;

/// A triangle whose farthest corner lies more than this many (median radius + typical size)
/// from its cluster's centre goes to a further cluster: the padding of a cluster's boxes and
/// the resolution of obvhs' Morton codes follow the cluster's extent, so a far object must not
/// stretch the cluster of the rest.
const OUTLIER_FACTOR: f64 = 64.0;

/// Largest frame-space coordinate magnitude: keeps obvhs' `f32` areas and costs finite.
const MAX_FRAME_COORDINATE: f64 = 1e15;

/// obvhs' build: its `fastest_build` (PLOC with search distance 1, no reinsertion, leaves of
/// one triangle), whose leaves [`bvh::convert`] collapses into leaves of at most 2 triangles
/// as obvhs' own collapse would. The build is part of the run: on bunny-plane (75 k
/// triangles) at rate 1, side by side with Embree at one thread (load 4.3-5), our time over
/// Embree's per-ray time was 1.39 with `medium_build`, 1.26 `fast_build`, 1.20
/// `very_fast_build` and 1.17 with this one, and at rate 64 (4.9 M samples) no worse (0.95,
/// 0.94, 0.71, 0.90): packets share the node tests, so a better tree saves little, while every
/// triangle in a leaf costs each ray that reaches it an `f64` test.
const BUILD: BvhBuildParams = BvhBuildParams::fastest_build();

/// Boxes a cluster's frame is placed by: its medians are taken over every `n / FRAME_SAMPLE`-th
/// of the `n` boxes (the frame only places the `f32` search, which decides nothing), unless
/// they keep less than half of the triangles in the cluster.
const FRAME_SAMPLE: usize = 1 << 12;

/// Most triangles of a cluster that obvhs builds one BVH over: a larger cluster is halved at
/// the median of its box centres along their widest axis until its parts are this small, the
/// parts' BVHs are built in parallel (rayon) and joined under the halving nodes (`bvh::join`).
/// obvhs' build runs on one thread (its `parallel` feature is off), so at two threads Embree's
/// build scaled and ours did not. The median halvings also make a better top of the tree than
/// PLOC's with search distance 1 on random-1m (1 M scattered triangles, rate 1, 1024 x 768,
/// stage CPU times of the calling thread, 2 threads, load 4-6 on two shared cores): ray
/// tracing 1195-1202 ms in one piece, 1049-1111 in parts of 2^15 (1021-1069 in parts of 2^9
/// to 2^13, within the noise), BVH build 626-667 ms before, 584-616 after on the calling
/// thread; bunny-plane's (75 k triangles) tracing is unchanged (69-72 ms).
const PART: usize = 1 << 15;

/// The binary exponent `e` of the finite `x >= f64::MIN_POSITIVE` (`2^e <= x < 2^(e+1)`),
/// at most 1022 (so that `2^-e` is normal).
#[inline(always)]
fn exponent(x: f64) -> i32 {
    (((x.to_bits() >> 52) & 0x7ff) as i32 - 1023).min(1022)
}

/// The smaller and the larger of a slab's two ray parameters, a NaN among them left out as
/// `f64::min` and `f64::max` leave it out (both NaN: NaN, which bounds nothing). Comparisons
/// instead of `min` and `max`, whose NaN handling adds a select to each, in the clip of every
/// ray from outside a cluster (the camera's): cage's and bunny-plane's tracing at rate 1 took
/// 2-4 % less time (one pinned thread, minima of 15 runs in alternating processes), every
/// sample's hit and light unchanged.
#[inline(always)]
fn slab(a: f64, b: f64) -> (f64, f64) {
    if a < b {
        (a, b)
    } else if b <= a {
        (b, a)
    } else if a.is_nan() {
        (b, b)
    } else {
        (a, a)
    }
}

/// `2^e` for `e` in `[-1022, 1023]`, exactly.
#[inline(always)]
fn power_of_two(e: i32) -> f64 {
    f64::from_bits(((e + 1023) as u64) << 52)
}

/// An `f32` upper bound of a non-negative ray parameter, for the traversal's pruning.
#[inline]
fn upper_f32(t: f64) -> f32 {
    if t.is_finite() {
        (t * (1.0 + 1e-6)) as f32
    } else {
        f32::INFINITY
    }
}

/// The box `(lo, hi)` of three corners.
#[inline]
fn corners_box(c: [DVec3; 3]) -> (DVec3, DVec3) {
    (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]))
}

/// Whether triangle `t` of `geometry` can be hit: finite corners and a non-zero area.
pub(crate) fn hittable(geometry: &Geometry, t: usize) -> bool {
    let [a, b, c] = geometry.corners(t);
    if !(a.is_finite() && b.is_finite() && c.is_finite()) {
        return false;
    }
    // The area test is made on the corners scaled by their largest magnitude, so that neither
    // huge nor tiny coordinates overflow or underflow the cross product.
    let m = a.abs().max(b.abs()).max(c.abs()).max_element();
    if m == 0.0 {
        return false;
    }
    let (sa, sb, sc) = (a / m, b / m, c / m);
    (sb - sa).cross(sc - sa) != DVec3::ZERO
}

/// The middle value of `v` by selection (the upper one for even lengths): the median of
/// positions and sizes that places a cluster's frame, found in linear time, which is not a
/// summary of times ([`instrumentation::stats`] has that one); `v` is reordered. `v` is not
/// empty.
fn select_middle(v: &mut [f64]) -> f64 {
    let k = v.len() / 2;
    *v.select_nth_unstable_by(k, f64::total_cmp).1
}

/// The power of two nearest to the finite positive `x` (in the log scale), within `2^±1000`.
fn power_of_two_near(x: f64) -> f64 {
    let k = x.log2().round().clamp(-1000.0, 1000.0);
    2f64.powi(k as i32)
}

/// The `f32` coordinate frame a cluster's BVH is built and traversed in: world coordinates
/// centred on the cluster and scaled by a power of two to its typical triangle, so that the BVH
/// sees every cluster as it sees one of unit triangles at the origin, whatever its absolute size
/// or position.
#[derive(Debug, Clone, Copy, PartialEq)]
struct BvhFrame {
    /// World point mapped to the origin (per-axis median of the triangles' box centres, or of
    /// a sample of them: [`FRAME_SAMPLE`]).
    centre: DVec3,
    /// World-to-frame scale, a power of two (exact in `f64`).
    scale: f64,
    /// The cluster's box relative to `centre` (world units).
    lo: DVec3,
    hi: DVec3,
    /// Largest world distance (max norm) of a corner from `centre`.
    extent: f64,
    /// Largest frame-space coordinate magnitude of a frame ray's start that the box padding
    /// covers: the cluster's extent enlarged by 1/32 (the clip's margin and its rounding).
    reach: f64,
}

impl BvhFrame {
    /// The frame of a cluster centred on `centre`, of typical triangle size `typical`, whose
    /// corners lie within `(lo, hi)` (relative to `centre`), at most `extent` from it.
    fn new(centre: DVec3, typical: f64, lo: DVec3, hi: DVec3, extent: f64) -> Self {
        let mut scale = if typical > 0.0 { power_of_two_near(1.0 / typical) } else { 1.0 };
        if extent * scale > MAX_FRAME_COORDINATE {
            scale = power_of_two_near(MAX_FRAME_COORDINATE / extent) * 0.5;
        }
        let reach = extent * scale * (1.0 + 1.0 / 32.0);
        Self { centre, scale, lo, hi, extent, reach }
    }

    /// Whether the frame's coordinates stay within [`MAX_FRAME_COORDINATE`] (false only for
    /// coordinates near the limit of `f64`, far beyond the supported scenes).
    fn traversable(&self) -> bool {
        self.reach <= MAX_FRAME_COORDINATE
    }

    /// `p` (relative to `centre`) in frame coordinates.
    #[inline]
    fn to_frame(self, p: DVec3) -> DVec3 {
        p * self.scale
    }

    /// The `f32` box of a triangle with world box `(lo, hi)`, padded outwards.
    fn padded_box(&self, (lo, hi): (DVec3, DVec3)) -> Aabb {
        let (lo, hi) = (self.to_frame(lo - self.centre), self.to_frame(hi - self.centre));
        let magnitude = lo.abs().max(hi.abs()).max_element();
        let pad = PAD_ULPS * f64::from(f32::EPSILON) * (self.reach + magnitude);
        let f = |v: DVec3| Vec3A::new(v.x as f32, v.y as f32, v.z as f32);
        Aabb::new(f(lo - DVec3::splat(pad)), f(hi + DVec3::splat(pad)))
    }
}

/// How a ray meets a cluster.
enum Route<'a> {
    /// The ray cannot meet the cluster's triangles within its range.
    Skip,
    /// Every triangle of the cluster is tested (the ray starts too far away for its `f64`
    /// start point to be within the padding, or the cluster has no BVH).
    All,
    /// The cluster's BVH is traversed with this frame ray.
    Bvh(&'a [Node], FrameRay),
}

/// A ray in a cluster's frame, started near the cluster: frame parameter `(t - t0) * step` is
/// world parameter `t`.
#[derive(Debug, Clone, Copy)]
struct FrameRay {
    origin: Vec3A,
    /// Direction, its largest component in `[1, 2)` in magnitude.
    dir: Vec3A,
    /// Frame parameter of the ray's end (rounded upwards).
    tmax: f32,
    t0: f64,
    step: f64,
}

impl FrameRay {
    /// An `f32` frame parameter at or beyond world parameter `t`, for the traversal's pruning.
    #[inline]
    fn upper(&self, t: f64) -> f32 {
        upper_f32((t - self.t0) * self.step)
    }
}

/// What [`Cluster::route`] computes from a ray's origin alone ([`Cluster::origin_part`]).
#[derive(Debug, Clone, Copy)]
struct OriginPart {
    /// The origin relative to the cluster's centre.
    o: DVec3,
    /// World bound of the rounding of the clip and of the start point.
    err: f64,
    /// The enlarged box's corners relative to the origin.
    to_lo: DVec3,
    to_hi: DVec3,
    /// Whether the origin lies outside the enlarged box (the ray is clipped).
    outside: bool,
}

/// A cluster: its frame, its BVH, and its slots in the [`Accel`]'s arrays.
struct Cluster {
    frame: BvhFrame,
    /// `None` when the frame is not [`BvhFrame::traversable`].
    bvh: Option<Vec<Node>>,
    /// The cluster's first slot.
    first: usize,
    /// Its number of slots.
    len: usize,
}

impl Cluster {
    /// What [`Cluster::route`] computes from the ray's origin alone: rays from one point (a
    /// perspective camera's) share it, made once per packet and cluster. That made cage's and
    /// bunny-plane's tracing 3-5 % faster at rate 1 and 5-6 % at rate 64 (one pinned thread,
    /// minima of runs in alternating processes). The same sharing of the direction of a
    /// directional light's shadow rays (its power of two and reciprocal) made them 2-3 %
    /// slower, so each shadow ray makes its own.
    #[inline(always)]
    fn origin_part(&self, origin: DVec3) -> OriginPart {
        let f = &self.frame;
        let o = origin - f.centre;
        // World bound of the rounding of the slab test and of the start point `o + t0 * d`
        // (`|t0 * d|` is at most `|o|` plus the enlarged box's size).
        let err = 8.0 * f64::EPSILON * (2.0 * o.abs().max_element() + 2.0 * f.extent);
        let m = DVec3::splat(f.extent / 64.0 + err);
        let (lo, hi) = (f.lo - m, f.hi + m);
        // A ray starting inside the enlarged box (every shadow ray of a one-cluster scene)
        // starts there; the others are clipped by the slab test.
        let outside = o.cmplt(lo).any() || o.cmpgt(hi).any();
        OriginPart { o, err, to_lo: lo - o, to_hi: hi - o, outside }
    }

    /// How `ray` meets the cluster for world parameters in `[0, tmax]`. The ray is clipped in
    /// `f64` to the cluster's box enlarged by `extent / 64` plus a bound of the clip's own
    /// rounding, and the frame ray starts at the entry point: a ray from far away starts near
    /// the cluster, so the padding need only cover the cluster's own extent. Inlined into the
    /// packet's set-up loop, where the latency of each ray's chain of dependent operations
    /// overlaps from ray to ray (it takes no square root or division: the clip multiplies by
    /// the ray's reciprocal direction).
    #[inline(always)]
    fn route(&self, ray: &TraceRay, tmax: f64) -> Route<'_> {
        self.route_from(ray, tmax, &self.origin_part(ray.origin))
    }

    /// [`Cluster::route`] with the part that depends on the origin alone given:
    /// `origin_part(ray.origin)`.
    #[inline(always)]
    fn route_from(&self, ray: &TraceRay, tmax: f64, origin: &OriginPart) -> Route<'_> {
        let f = &self.frame;
        let OriginPart { o, err, to_lo, to_hi, outside } = *origin;
        let d = ray.dir;
        let mut t0 = 0.0f64;
        if outside {
            let mut t1 = tmax;
            for k in 0..3 {
                if d[k] == 0.0 {
                    // `o < lo` as `lo - o > 0`: a difference of floats is zero only where they
                    // are equal, and has the sign of the exact difference.
                    if to_lo[k] > 0.0 || to_hi[k] < 0.0 {
                        return Route::Skip;
                    }
                } else {
                    // The reciprocal's rounding adds one to the quotient's: within `err`.
                    let inv = ray.inv[k];
                    let (a, b) = (to_lo[k] * inv, to_hi[k] * inv);
                    let (near, far) = slab(a, b);
                    if near > t0 {
                        t0 = near;
                    }
                    if far < t1 {
                        t1 = far;
                    }
                }
            }
            if t0 > t1 {
                return Route::Skip;
            }
        }
        let Some(bvh) = self.bvh.as_deref() else { return Route::All };
        // Also false for NaN (an overflowing `err`).
        let start_is_precise = err * f.scale <= 0.5 * f64::from(f32::EPSILON) * f.reach;
        if !start_is_precise {
            return Route::All;
        }
        let start = f.to_frame(o + t0 * d);
        let start_is_covered = start.abs().max_element() <= f.reach;
        if !start_is_covered {
            return Route::All;
        }
        // The direction scaled by the power of two `2^-e` that brings its largest component
        // into [1, 2): exact, and no square root or division per ray. Frame parameter `s`
        // is then `(t - t0) * scale * 2^e`.
        let largest = d.abs().max_element();
        if largest < f64::MIN_POSITIVE {
            // A subnormal direction (far below any scene's): every triangle is tested.
            return Route::All;
        }
        let e = exponent(largest);
        let dir = d * power_of_two(-e);
        let step = f.scale * power_of_two(e);
        let f32s = |v: DVec3| Vec3A::new(v.x as f32, v.y as f32, v.z as f32);
        Route::Bvh(
            bvh,
            FrameRay {
                origin: f32s(start),
                dir: f32s(dir),
                tmax: upper_f32((tmax - t0) * step),
                t0,
                step,
            },
        )
    }
}

/// The triangles `tris` split into a cluster around their median and the rest: the cluster's
/// frame, its triangles and the others (at most half of `tris`); where the cluster holds every
/// triangle, `tris` itself. The world boxes are made from the corners in each pass, not kept:
/// on random-1m (a million triangles) a kept vector of them was 48 MB of fresh pages, whose
/// faults cost more than reading the corners again.
fn split(
    geometry: &Geometry,
    tris: Vec<u32>,
    alloc: &Allocator,
) -> Result<(BvhFrame, Vec<u32>, Vec<u32>), AllocationError> {
    let world = |&t: &u32| corners_box(geometry.corners(t as usize));
    let n = tris.len();
    let mut values: Vec<f64> = alloc.vec(n, "the BVH frame's medians")?;
    let radius = |centre: DVec3, &(lo, hi): &(DVec3, DVec3)| {
        (lo - centre).abs().max(hi - centre).max_element()
    };
    // The medians over every `stride`-th box.
    let mut place = |stride: usize| {
        let mut middle = |f: &(dyn Fn(&(DVec3, DVec3)) -> f64 + Sync)| {
            values.clear();
            values.par_extend(tris.par_iter().step_by(stride).map(|t| f(&world(t))));
            select_middle(&mut values)
        };
        let mut centre = DVec3::ZERO;
        for k in 0..3 {
            centre[k] = middle(&|(lo, hi)| 0.5 * lo[k] + 0.5 * hi[k]);
        }
        let typical = middle(&|(lo, hi)| (*hi - *lo).max_element());
        let median_radius = middle(&|b| radius(centre, b));
        (centre, typical, OUTLIER_FACTOR * (median_radius + typical))
    };
    // How many boxes lie within the limit, and their minima, maxima and largest radius: the
    // same in any order of reduction.
    let within = |(centre, _, limit): (DVec3, f64, f64)| {
        let empty = (0usize, DVec3::INFINITY, DVec3::NEG_INFINITY, 0.0f64);
        tris.par_iter()
            .map(world)
            .filter(|b| radius(centre, b) <= limit)
            .map(|b| (1, b.0 - centre, b.1 - centre, radius(centre, &b)))
            .reduce(|| empty, |a, b| (a.0 + b.0, a.1.min(b.1), a.2.max(b.2), a.3.max(b.3)))
    };
    let sampled = place((n / FRAME_SAMPLE).max(1));
    let mut kept = within(sampled);
    // A sample's medians keep less than half the boxes only by bad luck; the whole set's
    // always keep at least half.
    let (centre, typical, limit) = if 2 * kept.0 >= n {
        sampled
    } else {
        let exact = place(1);
        kept = within(exact);
        exact
    };
    drop(values);
    let (count, lo, hi, extent) = kept;
    let frame = BvhFrame::new(centre, typical, lo, hi, extent);
    if count == n {
        return Ok((frame, tris, Vec::new()));
    }
    let inside = |t: &&u32| radius(centre, &world(t)) <= limit;
    let mut main = alloc.vec(count, "the BVH's triangle lists")?;
    let mut rest = alloc.vec(n - count, "the BVH's triangle lists")?;
    main.par_extend(tris.par_iter().filter(inside).copied());
    rest.par_extend(tris.par_iter().filter(|t| !inside(t)).copied());
    Ok((frame, main, rest))
}

/// A triangle's padded `f32` box in its cluster's frame, and its place in the cluster's list
/// of triangles: what the halvings ([`cut`]) reorder and obvhs builds over, 28 bytes, so that
/// the halvings read the boxes in order and each part's build reads its own range of them.
#[derive(Debug, Clone, Copy)]
struct Placed {
    lo: [f32; 3],
    /// Index into the cluster's list of triangles.
    at: u32,
    hi: [f32; 3],
}

impl Placed {
    /// Twice the box's centre along `axis`, as an `f32`.
    #[inline]
    fn centre(&self, axis: usize) -> f32 {
        self.lo[axis] + self.hi[axis]
    }
}

impl Boundable for Placed {
    #[inline]
    fn aabb(&self) -> Aabb {
        Aabb::new(Vec3A::from_array(self.lo), Vec3A::from_array(self.hi))
    }
}

/// Cuts `boxes` (the triangles of `boxes[0]` onwards being slots `start` onwards) into parts
/// of at most `max_part` triangles, halving it at the median of the box centres along the axis
/// where they spread most, and again each half; each part's range of slots goes to `parts`,
/// each halving to `splits` (its halves, in pre-order). The halves are cut in parallel (on
/// random-1m the serial cuts took 72 ms of the 345 of the BVH build at 2 threads), each into
/// lists of its own, appended in order.
fn cut(
    boxes: &mut [Placed],
    start: usize,
    max_part: usize,
    parts: &mut Vec<Range<usize>>,
    splits: &mut Vec<[Piece; 2]>,
) -> Piece {
    if boxes.len() <= max_part.max(1) {
        parts.push(start..start + boxes.len());
        return Piece::Part(parts.len() - 1);
    }
    let centre = |b: &Placed| Vec3A::from_array(b.lo) + Vec3A::from_array(b.hi);
    // Minima and maxima: the same in any order of reduction.
    let (lo, hi) = boxes
        .par_iter()
        .fold(
            || (Vec3A::INFINITY, Vec3A::NEG_INFINITY),
            |(lo, hi), b| (lo.min(centre(b)), hi.max(centre(b))),
        )
        .reduce(|| (Vec3A::INFINITY, Vec3A::NEG_INFINITY), |a, b| (a.0.min(b.0), a.1.max(b.1)));
    let spread = hi - lo;
    let axis = if spread.x >= spread.y && spread.x >= spread.z {
        0
    } else if spread.y >= spread.z {
        1
    } else {
        2
    };
    let half = boxes.len() / 2;
    boxes.select_nth_unstable_by(half, |a, b| a.centre(axis).total_cmp(&b.centre(axis)));
    let s = splits.len();
    splits.push([Piece::Part(0); 2]);
    let (left, right) = boxes.split_at_mut(half);
    let alone = |boxes: &mut [Placed], start: usize| {
        let (mut parts, mut splits) = (Vec::new(), Vec::new());
        let piece = cut(boxes, start, max_part, &mut parts, &mut splits);
        (piece, parts, splits)
    };
    let (l, r) = rayon::join(|| alone(left, start), || alone(right, start + half));
    let l = append(parts, splits, l);
    let r = append(parts, splits, r);
    splits[s] = [l, r];
    Piece::Split(s)
}

/// Appends a subtree cut alone (its piece, parts and splits, numbered from 0) to `parts` and
/// `splits`, renumbered; its piece, renumbered.
fn append(
    parts: &mut Vec<Range<usize>>,
    splits: &mut Vec<[Piece; 2]>,
    (piece, more_parts, more_splits): (Piece, Vec<Range<usize>>, Vec<[Piece; 2]>),
) -> Piece {
    let (p, s) = (parts.len(), splits.len());
    let shift = |piece: Piece| match piece {
        Piece::Split(k) => Piece::Split(k + s),
        Piece::Part(k) => Piece::Part(k + p),
    };
    parts.extend(more_parts);
    splits.extend(more_splits.into_iter().map(|[a, b]| [shift(a), shift(b)]));
    shift(piece)
}

/// BVHs over some triangles, one per cluster, with their `f64` corners in slot order.
pub(crate) struct Accel {
    clusters: Vec<Cluster>,
    /// Corners of the triangle in each slot (cluster by cluster, each in the order of its
    /// `bvh.primitive_indices`).
    corners: Vec<[DVec3; 3]>,
    /// Triangle id (index into the frame's geometry) of each slot.
    ids: Vec<u32>,
    /// Fraction of light passing through each slot's triangle (`1 - opacity`, or 0).
    pass: Vec<f64>,
}

/// The slots' corners a dropped [`Accel`] left for the next build.
static SPARE_CORNERS: Spare<[DVec3; 3]> = Spare::new();

impl Drop for Accel {
    /// Gives the corners and the largest cluster's nodes back for the next build to reuse.
    fn drop(&mut self) {
        SPARE_CORNERS.give(std::mem::take(&mut self.corners));
        let largest = self.clusters.iter_mut().filter_map(|c| c.bvh.take());
        if let Some(nodes) = largest.max_by_key(Vec::capacity) {
            bvh::SPARE_NODES.give(nodes);
        }
    }
}

impl Accel {
    /// Builds the clusters and their BVHs over the triangles `t` of `geometry` with `keep(t)`
    /// that have finite corners and non-zero area; `pass(t)` is the light a triangle lets
    /// through. The first cluster holds at least half the triangles, around their median; the
    /// triangles beyond [`OUTLIER_FACTOR`] of it are clustered again the same way, so there
    /// are at most `log2(n) + 1` clusters.
    pub(crate) fn build(
        geometry: &Geometry,
        keep: impl Fn(usize) -> bool + Sync,
        pass: impl Fn(usize) -> f64 + Sync,
        alloc: &Allocator,
    ) -> Result<Self, AllocationError> {
        Self::build_in_parts(geometry, keep, pass, alloc, PART)
    }

    /// [`Accel::build`] with each cluster's BVH built in parts of at most `max_part`
    /// triangles (see [`PART`]).
    fn build_in_parts(
        geometry: &Geometry,
        keep: impl Fn(usize) -> bool + Sync,
        pass: impl Fn(usize) -> f64 + Sync,
        alloc: &Allocator,
        max_part: usize,
    ) -> Result<Self, AllocationError> {
        // Room for every triangle, so that each is tested for area once.
        let mut tris: Vec<u32> = alloc.vec(geometry.len(), "the BVH's triangle lists")?;
        tris.par_extend(
            (0..geometry.len())
                .into_par_iter()
                .filter(|&t| keep(t) && hittable(geometry, t))
                .map(|t| t as u32),
        );
        let n = tris.len();
        let mut accel = Self {
            clusters: Vec::new(),
            corners: SPARE_CORNERS.take(alloc, n, "the triangles' corners")?,
            ids: alloc.vec(n, "the triangle ids")?,
            pass: alloc.vec(n, "the triangles' transmittance")?,
        };
        while !tris.is_empty() {
            let (frame, main, rest) = split(geometry, tris, alloc)?;
            let first = accel.ids.len();
            let bvh = if frame.traversable() {
                let mut boxes: Vec<Placed> = alloc.vec(main.len(), "the BVH's boxes")?;
                boxes.par_extend(main.par_iter().enumerate().map(|(at, &t)| {
                    let b = frame.padded_box(corners_box(geometry.corners(t as usize)));
                    Placed { lo: b.min.to_array(), at: at as u32, hi: b.max.to_array() }
                }));
                let (mut parts, mut splits) = (Vec::new(), Vec::new());
                cut(&mut boxes, 0, max_part, &mut parts, &mut splits);
                // Each part: obvhs' build over its range of boxes; then the trees joined, and
                // the triangle in each slot.
                let build = |r: Range<usize>| {
                    alloc.probe_bvh_build(r.len())?;
                    Ok(build_bvh2(&boxes[r], BUILD, &mut Default::default()))
                };
                let tree = bvh::join(&splits, &parts, build, alloc)?;
                accel.ids.par_extend(
                    tree.prims.par_iter().map(|&b| main[boxes[b as usize].at as usize]),
                );
                Some(tree.nodes)
            } else {
                accel.ids.extend_from_slice(&main);
                None
            };
            // The cluster's slots' corners and transmittance, written straight into place (no
            // zeroed buffer to overwrite).
            let slotted = &accel.ids[first..];
            accel.corners.par_extend(slotted.par_iter().map(|&t| geometry.corners(t as usize)));
            accel.pass.par_extend(slotted.par_iter().map(|&t| pass(t as usize).clamp(0.0, 1.0)));
            let len = accel.ids.len() - first;
            accel.clusters.push(Cluster { frame, bvh, first, len });
            tris = rest;
        }
        Ok(accel)
    }

    /// The closest hit of each of `rays` (at most [`PACKET`]) with `tmin <= t <= tmax`, as
    /// `(t, triangle id)`, into `best` (same length, `None` on entry); ties go to the lower
    /// id. The rays are traced as one packet through each cluster. `tests` counts the
    /// triangles tested.
    pub(crate) fn closest(
        &self,
        rays: &[TraceRay],
        (tmin, tmax): (f64, f64),
        best: &mut [Option<(f64, u32)>],
        scratch: &mut Scratch,
        tests: &mut u64,
    ) {
        debug_assert!(rays.len() <= PACKET && best.len() == rays.len());
        // Ray `k`'s hit in `slot`, if it is the closest so far: its new frame bound.
        let visit = |k: usize, slot: usize, best: &mut [Option<(f64, u32)>]| -> Option<f64> {
            let t = rays[k].intersect(&self.corners[slot])?;
            if !(t >= tmin && t <= tmax) {
                return None;
            }
            let id = self.ids[slot];
            match best[k] {
                Some((bt, bid)) if bt < t || (bt == t && bid <= id) => None,
                _ => {
                    best[k] = Some((t, id));
                    Some(t)
                }
            }
        };
        // Rays from one point (a perspective camera's) share their origin's part of the route.
        let bits = |v: DVec3| v.to_array().map(f64::to_bits);
        let origin = rays.first().map(|r| r.origin);
        let shared = origin.filter(|&p| rays.iter().all(|r| bits(r.origin) == bits(p)));
        let Scratch { packet, frames, stack } = scratch;
        for c in &self.clusters {
            packet.clear();
            let mut bvh = None;
            let shared = shared.map(|p| c.origin_part(p));
            for (k, ray) in rays.iter().enumerate() {
                let t = best[k].map_or(tmax, |(t, _)| t);
                let route = match &shared {
                    Some(origin) => c.route_from(ray, t, origin),
                    None => c.route(ray, t),
                };
                match route {
                    Route::Bvh(b, fr) => {
                        bvh = Some(b);
                        frames[k] = fr;
                        packet.push(fr.origin, fr.dir, fr.tmax);
                    }
                    route => {
                        if matches!(route, Route::All) {
                            for slot in c.first..c.first + c.len {
                                *tests += 1;
                                visit(k, slot, best);
                            }
                        }
                        packet.push_inactive();
                    }
                }
            }
            let Some(bvh) = bvh else { continue };
            packet::traverse(bvh, packet, stack, |k, slot| {
                *tests += 1;
                visit(k, c.first + slot, best).map(|t| frames[k].upper(t))
            });
        }
    }

    /// Light reaching the end of each of `rays` (at most [`PACKET`]) into `light` (same
    /// length, 1 on entry): the product of `pass` over the triangles ray `k` hits with
    /// `tmin < t < tmax`, `(tmin, tmax) = limits[k]`, other than `skip[k]`. A ray ends at the first triangle that
    /// lets no light through. The rays are traced as one packet through each cluster. `tests`
    /// counts the triangles tested.
    pub(crate) fn transmittance(
        &self,
        rays: &[TraceRay],
        (limits, skip): (&[(f64, f64)], &[u32]),
        light: &mut [f64],
        scratch: &mut Scratch,
        tests: &mut u64,
    ) {
        debug_assert!(rays.len() <= PACKET && light.len() == rays.len());
        // Whether ray `k` is finished (no light left) after the triangle in `slot`.
        let visit = |k: usize, slot: usize, light: &mut [f64]| -> bool {
            if self.ids[slot] == skip[k] {
                return false;
            }
            match rays[k].intersect(&self.corners[slot]) {
                Some(t) if t > limits[k].0 && t < limits[k].1 => {
                    light[k] *= self.pass[slot];
                    light[k] == 0.0
                }
                _ => false,
            }
        };
        let Scratch { packet, stack, .. } = scratch;
        for c in &self.clusters {
            packet.clear();
            let mut bvh = None;
            let mut live = false;
            for (k, ray) in rays.iter().enumerate() {
                if light[k] == 0.0 {
                    packet.push_inactive();
                    continue;
                }
                live = true;
                match c.route(ray, limits[k].1) {
                    Route::Bvh(b, fr) => {
                        bvh = Some(b);
                        packet.push(fr.origin, fr.dir, fr.tmax);
                    }
                    route => {
                        if matches!(route, Route::All) {
                            for slot in c.first..c.first + c.len {
                                *tests += 1;
                                if visit(k, slot, light) {
                                    break;
                                }
                            }
                        }
                        packet.push_inactive();
                    }
                }
            }
            if !live {
                break;
            }
            let Some(bvh) = bvh else { continue };
            packet::traverse(bvh, packet, stack, |k, slot| {
                *tests += 1;
                visit(k, c.first + slot, light).then_some(f32::NEG_INFINITY)
            });
        }
    }
}

/// What a thread reuses from packet to packet: the frame rays and the traversal stack.
pub(crate) struct Scratch {
    packet: FramePacket,
    /// Each ray's frame mapping in the cluster being traversed.
    frames: [FrameRay; PACKET],
    stack: Vec<(u32, u64)>,
}

impl Default for Scratch {
    fn default() -> Self {
        let none =
            FrameRay { origin: Vec3A::ZERO, dir: Vec3A::ZERO, tmax: 0.0, t0: 0.0, step: 0.0 };
        Self { packet: FramePacket::default(), frames: [none; PACKET], stack: Vec::new() }
    }
}

#[cfg(test)]
impl Accel {
    /// Whether `ray` is traced through a BVH in every cluster it may meet (none is tested
    /// triangle by triangle).
    fn traverses(&self, ray: &TraceRay) -> bool {
        self.clusters.iter().all(|c| !matches!(c.route(ray, f64::INFINITY), Route::All))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use methods::afsm::shadow_offset;
    use scenes::generators::{Generator, SpheresParams};

    fn geometry(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Geometry {
        let object = vec![0; triangles.len()];
        Geometry { positions, triangles, object }
    }

    /// The clusters over every triangle of `g`, each letting `pass` through.
    fn build(g: &Geometry, pass: f64) -> Accel {
        Accel::build(g, |_| true, |_| pass, &Allocator { estimate: 0 }).expect("small")
    }

    /// The first cluster holds at least half the triangles also when the sample its frame is
    /// placed by sees only the far ones: every `stride`-th of 3 * 8192 small triangles lies
    /// 1e6 away, and those are the sample.
    #[test]
    fn a_misleading_sample_still_leaves_half_in_the_first_cluster() {
        let n = 3 * 8192;
        let stride = n / FRAME_SAMPLE;
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        for t in 0..n {
            let base = if t % stride == 0 { DVec3::new(1e6, 0.0, 0.0) } else { DVec3::ZERO };
            let p = base + DVec3::new((t % 97) as f64, (t / 97) as f64, 0.0) * 0.01;
            let k = positions.len() as u32;
            positions.extend([p, p + DVec3::X * 0.01, p + DVec3::Y * 0.01]);
            triangles.push([k, k + 1, k + 2]);
        }
        let accel = build(&geometry(positions, triangles), 0.0);
        assert!(2 * accel.clusters[0].len >= n, "{} of {n}", accel.clusters[0].len);
        assert_eq!(accel.clusters.iter().map(|c| c.len).sum::<usize>(), n);
    }

    /// The closest hit of `ray` alone (a packet of one).
    fn closest(accel: &Accel, ray: &TraceRay, tmin: f64, tmax: f64) -> Option<(f64, u32)> {
        let mut best = [None];
        accel.closest(&[*ray], (tmin, tmax), &mut best, &mut Scratch::default(), &mut 0);
        best[0]
    }

    /// The transmittance of `ray` alone (a packet of one).
    fn transmittance(accel: &Accel, ray: &TraceRay, tmin: f64, tmax: f64, skip: u32) -> f64 {
        let mut light = [1.0];
        let limits = (&[(tmin, tmax)][..], &[skip][..]);
        accel.transmittance(&[*ray], limits, &mut light, &mut Scratch::default(), &mut 0);
        light[0]
    }

    #[test]
    fn degenerate_triangles_are_left_out() {
        let ray = TraceRay::new(DVec3::new(0.1, 0.1, 5.0), DVec3::NEG_Z).expect("finite");
        let line = [DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0)];
        let g = geometry(line.to_vec(), vec![[0, 1, 2]]);
        let accel = build(&g, 0.0);
        assert!(accel.ids.is_empty() && accel.clusters.is_empty());
        assert_eq!(closest(&accel, &ray, 0.0, f64::INFINITY), None);
        assert_eq!(transmittance(&accel, &ray, 0.0, f64::INFINITY, u32::MAX), 1.0);
    }

    #[test]
    fn single_triangle_bvh_finds_its_hit() {
        let g = geometry(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]);
        let ray = TraceRay::new(DVec3::new(0.2, 0.2, 2.0), DVec3::NEG_Z).expect("finite");
        let accel = build(&g, 0.25);
        assert!(accel.traverses(&ray));
        assert_eq!(closest(&accel, &ray, 0.0, f64::INFINITY), Some((2.0, 0)));
        assert_eq!(transmittance(&accel, &ray, 0.0, f64::INFINITY, u32::MAX), 0.25);
        assert_eq!(transmittance(&accel, &ray, 0.0, f64::INFINITY, 0), 1.0);
        assert_eq!(transmittance(&accel, &ray, 0.0, 1.5, u32::MAX), 1.0);
    }

    /// The clip of a ray parallel to an axis asks `lo - o > 0` for `o < lo` (and `hi - o < 0`
    /// for `o > hi`): the same answers, infinities, zeros and subnormals included.
    #[test]
    fn differences_have_the_sign_of_the_comparison() {
        let values = [f64::NEG_INFINITY, -1e300, -2.0, -1e-310, -0.0, 0.0, 1e-310, 3.0, 1e300];
        for a in values.into_iter().chain([f64::INFINITY]) {
            for b in values.into_iter().chain([f64::INFINITY]) {
                assert_eq!(b - a > 0.0, a < b, "{a}, {b}");
                assert_eq!(b - a < 0.0, a > b, "{a}, {b}");
            }
        }
    }

    /// `slab` gives what `f64::min` and `f64::max` give, NaN, infinities and zeros included
    /// (zeros by value: the sign of a zero bound changes no clip).
    #[test]
    fn slab_is_min_and_max() {
        let values = [f64::NAN, f64::NEG_INFINITY, -3.5, -0.0, 0.0, 1e-300, 2.0, f64::INFINITY];
        let same = |x: f64, y: f64| (x.is_nan() && y.is_nan()) || x == y;
        for a in values {
            for b in values {
                let (near, far) = slab(a, b);
                assert!(same(near, a.min(b)) && same(far, a.max(b)), "{a}, {b}: {near}, {far}");
            }
        }
    }

    /// Axis-aligned rays whose zero components are -0.0 (e.g. `-direction` of a vertical
    /// light) must still find their boxes (-0.0 inverts to `-1 / f32::EPSILON`, and obvhs' own
    /// CWBVH traversal, which sorts it into the positive octant, missed them all).
    #[test]
    fn negative_zero_direction_components_do_not_miss() {
        let g = geometry(
            vec![
                DVec3::new(-1.0, 2.0, -1.0),
                DVec3::new(1.0, 2.0, -1.0),
                DVec3::new(0.0, 2.0, 1.0),
            ],
            vec![[0, 1, 2]],
        );
        let eye = DVec3::new(0.1, 5.0, 0.2);
        let accel = build(&g, 0.0);
        let up = -DVec3::new(0.0, -1.0, 0.0);
        assert!(up.x.is_sign_negative() && up.z.is_sign_negative());
        let ray = TraceRay::new(DVec3::new(0.1, 0.0, 0.2), up).expect("finite");
        assert_eq!(closest(&accel, &ray, 0.0, f64::INFINITY), Some((2.0, 0)));
        assert_eq!(transmittance(&accel, &ray, 1e-9, f64::INFINITY, u32::MAX), 0.0);
        let down = TraceRay::new(eye, DVec3::new(-0.0, -1.0, -0.0));
        assert!(closest(&accel, &down.expect("finite"), 0.0, f64::INFINITY).is_some());
    }

    /// Camera rays aimed exactly at every vertex and edge midpoint of a closed icosphere, and a
    /// dense fan of rays across its silhouette, through the full BVH path: none whose line
    /// passes inside the inscribed ball may miss.
    #[test]
    fn closed_sphere_has_no_gaps() {
        let params = SpheresParams { count: 1, subdivisions: 4, ..Default::default() };
        let mesh = params.generate();
        let g = geometry(mesh.positions.clone(), mesh.triangles.clone());
        let (lo, hi) = g
            .positions
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |b, &p| (b.0.min(p), b.1.max(p)));
        let centre = 0.5 * (lo + hi);
        let r_in = (0..g.len())
            .map(|t| {
                let [a, b, c] = g.corners(t);
                (b - a).cross(c - a).normalize().dot(a - centre).abs()
            })
            .fold(f64::INFINITY, f64::min);
        let eyes = [
            centre + DVec3::new(0.0, 0.0, 7.0),
            centre + DVec3::new(3.1, 4.7, -5.3),
            centre + DVec3::new(-0.01, 9.0, 0.02),
        ];
        let accel = build(&g, 0.0);
        let mut targets: Vec<DVec3> = g.positions.clone();
        for tri in &g.triangles {
            for e in 0..3 {
                let (p, q) = (g.positions[tri[e] as usize], g.positions[tri[(e + 1) % 3] as usize]);
                targets.push(0.5 * (p + q));
            }
        }
        let mut tested = 0;
        for eye in eyes {
            for &target in &targets {
                let dir = target - eye;
                let ray = TraceRay::new(eye, dir).expect("finite");
                assert!(accel.traverses(&ray));
                let off_axis = (centre - eye).cross(dir).length() / dir.length();
                if off_axis < r_in * (1.0 - 1e-9) {
                    tested += 1;
                    assert!(
                        closest(&accel, &ray, 0.0, f64::INFINITY).is_some(),
                        "{eye} -> {target}"
                    );
                }
            }
        }
        assert!(tested > 10_000, "{tested}");
    }

    /// A ground of 2 x 16 triangles under a tilted occluder, the shadow rays of a grid of ground
    /// points (with the offset the tracer uses, from an eye above), and optionally one triangle
    /// far away: returns the number of points the BVH finds shadowed and the number a test of
    /// every triangle finds shadowed.
    fn shadowed_points(scale: f64, shift: DVec3, far: Option<f64>) -> (usize, usize) {
        let place = |p: DVec3| p * scale + shift;
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        let n = 4u32;
        for j in 0..=n {
            for i in 0..=n {
                let (x, z) = (f64::from(i) * 4.0 - 8.0, f64::from(j) * 4.0 - 8.0);
                positions.push(place(DVec3::new(x, 0.0, z)));
            }
        }
        for j in 0..n {
            for i in 0..n {
                let v = |di: u32, dj: u32| (j + dj) * (n + 1) + i + di;
                triangles.push([v(0, 0), v(1, 0), v(1, 1)]);
                triangles.push([v(0, 0), v(1, 1), v(0, 1)]);
            }
        }
        let k = positions.len() as u32;
        positions.extend([
            place(DVec3::new(-2.0, 1.0, -2.0)),
            place(DVec3::new(2.5, 1.5, -1.0)),
            place(DVec3::new(0.0, 0.001, 2.0)),
        ]);
        triangles.push([k, k + 1, k + 2]);
        if let Some(d) = far {
            let k = positions.len() as u32;
            positions.extend([
                DVec3::new(d, d, 0.0),
                DVec3::new(d + 1.0, d, 0.0),
                DVec3::new(d, d + 1.0, 0.0),
            ]);
            triangles.push([k, k + 1, k + 2]);
        }
        let g = geometry(positions, triangles);
        let eye = place(DVec3::new(0.0, 6.0, 9.0));
        let accel = build(&g, 0.0);
        let towards = DVec3::new(0.3, 1.0, 0.2).normalize();
        let (mut shadowed, mut brute) = (0, 0);
        for j in 0..64 {
            for i in 0..64 {
                let local = DVec3::new(f64::from(i) / 8.0 - 4.0, 0.0, f64::from(j) / 8.0 - 4.0);
                let p = place(local);
                let ray = TraceRay::new(p, towards).expect("finite");
                let t = shadow_offset(eye, p);
                if transmittance(&accel, &ray, t, f64::INFINITY, u32::MAX) == 0.0 {
                    shadowed += 1;
                }
                if (0..g.len()).any(|k| ray.intersect(&g.corners(k)).is_some_and(|h| h > t)) {
                    brute += 1;
                }
            }
        }
        (shadowed, brute)
    }

    #[test]
    fn shadows_do_not_depend_on_scale_position_or_far_objects() {
        let (base, brute) = shadowed_points(1.0, DVec3::ZERO, None);
        assert_eq!(base, brute);
        assert!(base > 200 && base < 4000, "{base}");
        let mut cases = Vec::new();
        for scale in [1e-6, 1e-5, 1e-3, 1e3, 1e6] {
            cases.push((scale, DVec3::ZERO, None));
        }
        for shift in [DVec3::splat(1e7), DVec3::new(-1e7, 3e6, 1e5)] {
            cases.push((1.0, shift, None));
            cases.push((1e-3, shift * 1e-3, None));
        }
        for d in [1e8, 1e10, 1e12] {
            cases.push((1.0, DVec3::ZERO, Some(d)));
        }
        for (scale, shift, far) in cases {
            // The BVH finds every occluder a test of all triangles finds; the count moves from
            // the scale-1 one only where a point lies on the shadow's edge to within rounding.
            let (count, brute) = shadowed_points(scale, shift, far);
            assert_eq!(count, brute, "scale {scale}, shift {shift}, far {far:?}");
            assert!(count.abs_diff(base) <= 4, "{count} vs {base}: {scale}, {shift}, {far:?}");
        }
    }

    /// Coordinates far beyond the supported range (1e24, 1e300) must not make the BVH builder
    /// panic (they are refused earlier, at scene validation, but the tracer stands alone).
    #[test]
    fn huge_coordinates_do_not_panic() {
        for scale in [1e24, 1e300] {
            let (count, _) = shadowed_points(scale, DVec3::ZERO, None);
            assert!(count <= 4096);
        }
        let (count, brute) = shadowed_points(1.0, DVec3::ZERO, Some(1e300));
        assert_eq!(count, brute);
    }

    /// An occluder lying a millionth of its size above the ground: its padded box holds the
    /// shadow ray's `f32` start, and a box the ray starts in is never culled (obvhs' own CWBVH
    /// node test ignored boxes left within 1e-4 of a ray's start).
    #[test]
    fn occluders_in_contact_are_found() {
        for scale in [1e-6, 1.0, 1e6] {
            let h = 4e-6 * scale;
            let positions = vec![
                DVec3::new(-4.0, 0.0, -4.0) * scale,
                DVec3::new(4.0, 0.0, -4.0) * scale,
                DVec3::new(0.0, 0.0, 4.0) * scale,
                DVec3::new(-2.0 * scale, h, -2.0 * scale),
                DVec3::new(2.0 * scale, h, -2.0 * scale),
                DVec3::new(0.0, h, 2.0 * scale),
            ];
            let g = geometry(positions, vec![[0, 1, 2], [3, 4, 5]]);
            let eye = DVec3::new(0.0, 6.0, 9.0) * scale;
            let accel = build(&g, 0.0);
            let p = DVec3::new(0.0, 0.0, 0.0);
            let ray = TraceRay::new(p, DVec3::Y).expect("finite");
            let t = shadow_offset(eye, p);
            assert!(t < h);
            assert_eq!(transmittance(&accel, &ray, t, f64::INFINITY, 0), 0.0, "scale {scale}");
        }
    }

    /// Spheres over a ground grid, with a triangle far away (a second cluster): the geometry
    /// of the packet tests, built once in one piece per cluster and in parts of at most 7 and
    /// 2 triangles (joined under many halving nodes; parts of one or two triangles are single
    /// leaves).
    fn packet_scene() -> &'static (Geometry, [Accel; 3]) {
        static SCENE: std::sync::OnceLock<(Geometry, [Accel; 3])> = std::sync::OnceLock::new();
        SCENE.get_or_init(|| {
            let params = SpheresParams { count: 6, subdivisions: 2, ..Default::default() };
            let mesh = params.generate();
            let (mut positions, mut triangles) = (mesh.positions, mesh.triangles);
            let n = 8u32;
            let k = positions.len() as u32;
            for j in 0..=n {
                for i in 0..=n {
                    let (x, z) = (f64::from(i) - 4.0, f64::from(j) - 4.0);
                    positions.push(DVec3::new(x, -1.0, z) * 2.0);
                }
            }
            for j in 0..n {
                for i in 0..n {
                    let v = |di: u32, dj: u32| k + (j + dj) * (n + 1) + i + di;
                    triangles.push([v(0, 0), v(1, 0), v(1, 1)]);
                    triangles.push([v(0, 0), v(1, 1), v(0, 1)]);
                }
            }
            let k = positions.len() as u32;
            positions.extend([DVec3::new(1e6, 1.0, 0.0), DVec3::new(1e6, 3.0, 1.0), DVec3::Y]);
            triangles.push([k, k + 1, k + 2]);
            let g = geometry(positions, triangles);
            let accel = build(&g, 0.5);
            assert!(accel.clusters[0].len <= PART, "one part");
            let alloc = Allocator { estimate: 0 };
            let parts = |max| Accel::build_in_parts(&g, |_| true, |_| 0.5, &alloc, max);
            let (sevens, twos) = (parts(7).expect("small"), parts(2).expect("small"));
            (g, [accel, sevens, twos])
        })
    }

    /// A packet of `len` rays of one of four kinds, from `seed`: 0, from one point in a narrow
    /// cone (camera rays through a pixel); 1, parallel from points over a small patch (shadow
    /// rays of a directional light), half the time along an axis with two -0.0 components; 2,
    /// incoherent (any origin, any direction); 3, grazing the ground plane, in it or 1e-12
    /// above it, with a 0.0 or -0.0 vertical component.
    fn packet_rays(kind: u32, seed: u64, len: usize) -> Vec<TraceRay> {
        let mut state = seed | 1;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let unit =
            |next: &mut dyn FnMut() -> f64| DVec3::new(next(), next(), next()) * 2.0 - DVec3::ONE;
        let (eye, aim) = (unit(&mut next) * 8.0 + DVec3::new(0.0, 6.0, 0.0), unit(&mut next));
        let axis = [DVec3::X, DVec3::Y, DVec3::Z, DVec3::NEG_X, DVec3::NEG_Y][seed as usize % 5];
        let along =
            if seed.is_multiple_of(2) { -axis } else { (unit(&mut next) + DVec3::Y).normalize() };
        let patch = unit(&mut next) * 3.0;
        let mut rays = Vec::new();
        for _ in 0..len {
            let (origin, dir) = match kind {
                0 => (eye, aim - eye + unit(&mut next) * 0.05),
                1 => (patch + unit(&mut next) * 0.2, along),
                2 => (unit(&mut next) * 6.0, unit(&mut next)),
                _ => {
                    let height = if next() < 0.5 { -2.0 } else { -2.0 + 1e-12 };
                    let (x, z) = (next() * 20.0 - 10.0, next() * 20.0 - 10.0);
                    let vertical = if next() < 0.5 { 0.0 } else { -0.0 };
                    (DVec3::new(x, height, z), DVec3::new(next() - 0.5, vertical, next() - 0.5))
                }
            };
            rays.push(TraceRay::new(origin, dir).expect("finite, non-zero"));
        }
        rays
    }

    /// A build into the buffers that a dropped build of another, larger scene left (its
    /// corners and nodes, [`Spare`]) makes the same clusters, slots and nodes as the build
    /// before it.
    #[test]
    fn a_build_into_spare_buffers_equals_one_into_new_buffers() {
        let (g, _) = packet_scene();
        let alloc = Allocator { estimate: 0 };
        let parts = |g: &Geometry| Accel::build_in_parts(g, |_| true, |_| 0.5, &alloc, 7);
        let key = |a: &Accel| {
            let clusters: Vec<_> =
                a.clusters.iter().map(|c| (c.frame, c.bvh.clone(), c.first, c.len)).collect();
            (clusters, a.corners.clone(), a.ids.clone(), a.pass.clone())
        };
        let before = key(&parts(g).expect("small"));
        // Twice the triangles, the copy moved, so that its buffers hold other values.
        let mut positions = g.positions.clone();
        positions.extend(g.positions.iter().map(|&p| p * 3.0 + DVec3::X));
        let k = g.positions.len() as u32;
        let mut triangles = g.triangles.clone();
        triangles.extend(g.triangles.iter().map(|t| t.map(|v| v + k)));
        drop(parts(&geometry(positions, triangles)).expect("small"));
        assert_eq!(key(&parts(g).expect("small")), before);
    }

    /// Level rays from one point (the route's part from the origin shared by the packet; a
    /// zero vertical component, of either sign, takes the clip's parallel branch), from within
    /// the spheres' height and from above them, find what a test of every triangle finds, and
    /// the ray aimed at a sphere triangle's centre at its height hits.
    #[test]
    fn level_rays_from_one_point_find_what_every_triangle_finds() {
        let (g, accels) = packet_scene();
        let centre = |t: usize| g.corners(t).iter().sum::<DVec3>() / 3.0;
        let aimed = centre(0);
        for height in [aimed.y, 100.0] {
            let eye = DVec3::new(-30.0, height, -25.0);
            let rays: Vec<TraceRay> = (0..PACKET)
                .map(|k| {
                    let c = centre(k * 7 % g.len());
                    let y = if k % 2 == 0 { 0.0 } else { -0.0 };
                    TraceRay::new(eye, DVec3::new(c.x - eye.x, y, c.z - eye.z)).expect("finite")
                })
                .collect();
            for accel in accels {
                let mut best = vec![None; rays.len()];
                accel.closest(
                    &rays,
                    (0.0, f64::INFINITY),
                    &mut best,
                    &mut Scratch::default(),
                    &mut 0,
                );
                for (k, ray) in rays.iter().enumerate() {
                    let brute = (0..g.len())
                        .filter_map(|t| ray.intersect(&g.corners(t)).map(|h| (h, t as u32)))
                        .filter(|&(h, _)| h >= 0.0)
                        .min_by(|a, b| a.partial_cmp(b).expect("finite"));
                    assert_eq!(best[k], brute, "height {height}, ray {k}");
                }
                assert_eq!(best[0].is_some(), height == aimed.y);
            }
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]

        /// A packet finds exactly what each of its rays finds alone and what a test of every
        /// triangle finds: the closest hit (ties to the lower id) and the light through the
        /// half-transparent triangles.
        #[test]
        fn packets_agree_with_single_rays_and_every_triangle(
            kind in 0u32..4, seed in proptest::num::u64::ANY, len in 1usize..=PACKET,
        ) {
            let (g, accels) = packet_scene();
            for accel in accels {
            let rays = packet_rays(kind, seed, len);
            let mut best = vec![None; len];
            let mut scratch = Scratch::default();
            accel.closest(&rays, (0.0, f64::INFINITY), &mut best, &mut scratch, &mut 0);
            let limits: Vec<(f64, f64)> = (0..len).map(|k| (1e-9, 4.0 + k as f64)).collect();
            let skip: Vec<u32> = (0..len as u32).map(|k| k * 7).collect();
            let mut light = vec![1.0; len];
            accel.transmittance(&rays, (&limits, &skip), &mut light, &mut scratch, &mut 0);
            for (k, ray) in rays.iter().enumerate() {
                let (tmin, tmax) = limits[k];
                let mut brute = 1.0;
                let mut brute_best: Option<(f64, u32)> = None;
                for t in 0..g.len() {
                    let Some(h) = ray.intersect(&g.corners(t)) else { continue };
                    if h >= 0.0 && brute_best.is_none_or(|b| (h, t as u32) < b) {
                        brute_best = Some((h, t as u32));
                    }
                    if t as u32 != skip[k] && h > tmin && h < tmax {
                        brute *= 0.5;
                    }
                }
                let single = transmittance(accel, ray, tmin, tmax, skip[k]);
                proptest::prop_assert_eq!(light[k], single, "ray {} {:?}", k, ray);
                proptest::prop_assert_eq!(light[k], brute, "ray {} {:?}", k, ray);
                let alone = closest(accel, ray, 0.0, f64::INFINITY);
                proptest::prop_assert_eq!(best[k], alone, "ray {} {:?}", k, ray);
                proptest::prop_assert_eq!(best[k], brute_best, "ray {} {:?}", k, ray);
            }
            }
        }
    }
}
