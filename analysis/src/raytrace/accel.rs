//! The acceleration structure that finds candidate triangles for the `f64` test: the triangles
//! split into clusters, each an obvhs CWBVH built and traversed in an `f32` frame of its own
//! (see the parent module's "Precision" for why nothing is lost and how far objects are kept
//! apart).

use super::memory::{AllocationError, Allocator};
use super::ray::TraceRay;
use glam::{DVec3, Vec3A};
use obvhs::{
    aabb::Aabb,
    cwbvh::{builder::build_cwbvh, CwBvh},
    ray::{Ray as BvhRay, RayHit},
    BvhBuildParams,
};
use scenes::Geometry;

/// Box padding in units of `f32::EPSILON` times (reach + box magnitude): covers the `f32`
/// rounding of the ray's start and direction, obvhs' clamped reciprocal of direction components
/// below `f32::EPSILON`, the rounding of its slab tests, and the `f64` rounding of the start
/// point (at most half an `f32` epsilon of the reach, see [`Cluster::route`]), with a margin of
/// about 7.
const PAD_ULPS: f64 = 32.0;

/// obvhs' CWBVH node test ignores children whose exit distance is below this (its `EPSILON`);
/// rays are started this far and more behind their start point so that nothing is lost to it.
const NODE_TMIN: f64 = 1e-4;

/// A triangle whose farthest corner lies more than this many (median radius + typical size)
/// from its cluster's centre goes to a further cluster: the padding of a cluster's boxes and
/// the resolution of obvhs' Morton codes follow the cluster's extent, so a far object must not
/// stretch the cluster of the rest.
const OUTLIER_FACTOR: f64 = 64.0;

/// Largest frame-space coordinate magnitude: keeps obvhs' `f32` areas and costs finite.
const MAX_FRAME_COORDINATE: f64 = 1e15;

/// An `f32` upper bound of a non-negative ray parameter, for obvhs' pruning.
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
fn hittable(geometry: &Geometry, t: usize) -> bool {
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
    /// World point mapped to the origin (per-axis median of the triangles' box centres).
    centre: DVec3,
    /// World-to-frame scale, a power of two (exact in `f64`).
    scale: f64,
    /// The cluster's box relative to `centre` (world units).
    lo: DVec3,
    hi: DVec3,
    /// Largest world distance (max norm) of a corner from `centre`.
    extent: f64,
    /// Largest frame-space coordinate magnitude of a frame ray's start that the box padding
    /// covers: the cluster's box enlarged by [`BvhFrame::margin`], plus the start shift.
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
        let reach = extent * scale * (1.0 + 1.0 / 32.0) + 4.0 * NODE_TMIN;
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

    /// How far (in frame units) a ray starting at frame point `o` is started behind it, so
    /// that obvhs' node test, which ignores boxes left before [`NODE_TMIN`], loses nothing
    /// despite the `f32` rounding of the shifted start.
    #[inline]
    fn start_shift(o: DVec3) -> f64 {
        2.0 * NODE_TMIN + 8.0 * f64::from(f32::EPSILON) * o.abs().max_element()
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
    Bvh(&'a CwBvh, FrameRay),
}

/// A ray in a cluster's frame, started near the cluster: frame parameter
/// `shift + (t - t0) * step` is world parameter `t`.
struct FrameRay {
    ray: BvhRay,
    shift: f64,
    t0: f64,
    step: f64,
}

impl FrameRay {
    /// An `f32` frame parameter at or beyond world parameter `t`, for obvhs' pruning.
    #[inline]
    fn upper(&self, t: f64) -> f32 {
        upper_f32(self.shift + (t - self.t0) * self.step)
    }
}

/// A cluster: its frame, its BVH, and its slots in the [`Accel`]'s arrays.
struct Cluster {
    frame: BvhFrame,
    /// `None` when the frame is not [`BvhFrame::traversable`].
    bvh: Option<CwBvh>,
    /// The cluster's first slot.
    first: usize,
    /// Its number of slots.
    len: usize,
}

impl Cluster {
    /// How `ray` meets the cluster for world parameters in `[0, tmax]`. The ray is clipped in
    /// `f64` to the cluster's box enlarged by `extent / 64` plus a bound of the clip's own
    /// rounding, and the frame ray starts at the entry point: a ray from far away starts near
    /// the cluster, so the padding need only cover the cluster's own extent.
    #[inline]
    fn route(&self, ray: &TraceRay, tmax: f64) -> Route<'_> {
        let f = &self.frame;
        let o = ray.origin - f.centre;
        let d = ray.dir;
        // World bound of the rounding of the slab test and of the start point `o + t0 * d`
        // (`|t0 * d|` is at most `|o|` plus the enlarged box's size).
        let err = 8.0 * f64::EPSILON * (2.0 * o.abs().max_element() + 2.0 * f.extent);
        let m = DVec3::splat(f.extent / 64.0 + err);
        let (lo, hi) = (f.lo - m, f.hi + m);
        // A ray starting inside the enlarged box (every shadow ray of a one-cluster scene)
        // starts there; the others are clipped by the slab test.
        let mut t0 = 0.0f64;
        if o.cmplt(lo).any() || o.cmpgt(hi).any() {
            let mut t1 = tmax;
            for k in 0..3 {
                if d[k] == 0.0 {
                    if o[k] < lo[k] || o[k] > hi[k] {
                        return Route::Skip;
                    }
                } else {
                    let inv = 1.0 / d[k];
                    let (a, b) = ((lo[k] - o[k]) * inv, (hi[k] - o[k]) * inv);
                    t0 = t0.max(a.min(b));
                    t1 = t1.min(a.max(b));
                }
            }
            if t0 > t1 {
                return Route::Skip;
            }
        }
        let Some(bvh) = &self.bvh else { return Route::All };
        // Also false for NaN (an overflowing `err`).
        let start_is_precise = err * f.scale <= 0.5 * f64::from(f32::EPSILON) * f.reach;
        if !start_is_precise {
            return Route::All;
        }
        let p = f.to_frame(o + t0 * d);
        let len = d.length();
        let dn = d * (1.0 / len);
        let shift = BvhFrame::start_shift(p);
        let start = p - shift * dn;
        let start_is_covered = start.abs().max_element() <= f.reach;
        if !start_is_covered {
            return Route::All;
        }
        // `+ 0.0` turns -0.0 into +0.0: obvhs inverts -0.0 to -1/EPSILON but sorts it into the
        // positive octant, which would make every box test miss.
        let dir = |x: f64| x as f32 + 0.0;
        let step = len * f.scale;
        let ray = BvhRay::new(
            Vec3A::new(start.x as f32, start.y as f32, start.z as f32),
            Vec3A::new(dir(dn.x), dir(dn.y), dir(dn.z)),
            0.0,
            upper_f32(shift + (tmax - t0) * step),
        );
        Route::Bvh(bvh, FrameRay { ray, shift, t0, step })
    }
}

/// The world boxes of `tris` split into a cluster around their median and the rest: the
/// cluster's frame, its triangles and the others (at most half of `tris`).
fn split(
    geometry: &Geometry,
    tris: &[u32],
    alloc: &Allocator,
) -> Result<(BvhFrame, Vec<u32>, Vec<u32>), AllocationError> {
    let boxes = || tris.iter().map(|&t| corners_box(geometry.corners(t as usize)));
    let mut values: Vec<f64> = alloc.vec(tris.len(), "the BVH frame's medians")?;
    let middle = |v: &mut Vec<f64>, it: &mut dyn Iterator<Item = f64>| {
        v.clear();
        v.extend(it);
        select_middle(v)
    };
    let mut centre = DVec3::ZERO;
    for k in 0..3 {
        centre[k] = middle(&mut values, &mut boxes().map(|(lo, hi)| 0.5 * lo[k] + 0.5 * hi[k]));
    }
    let typical = middle(&mut values, &mut boxes().map(|(lo, hi)| (hi - lo).max_element()));
    let radius = |(lo, hi): (DVec3, DVec3)| (lo - centre).abs().max(hi - centre).max_element();
    let median_radius = middle(&mut values, &mut boxes().map(radius));
    drop(values);
    let limit = OUTLIER_FACTOR * (median_radius + typical);
    let count = boxes().filter(|&b| radius(b) <= limit).count();
    let mut main = alloc.vec(count, "the BVH's triangle lists")?;
    let mut rest = alloc.vec(tris.len() - count, "the BVH's triangle lists")?;
    let (mut lo, mut hi, mut extent) = (DVec3::INFINITY, DVec3::NEG_INFINITY, 0.0f64);
    for (&t, b) in tris.iter().zip(boxes()) {
        if radius(b) <= limit {
            main.push(t);
            lo = lo.min(b.0 - centre);
            hi = hi.max(b.1 - centre);
            extent = extent.max(radius(b));
        } else {
            rest.push(t);
        }
    }
    Ok((BvhFrame::new(centre, typical, lo, hi, extent), main, rest))
}

/// CWBVHs over some triangles, one per cluster, with their `f64` corners in slot order.
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

impl Accel {
    /// Builds the clusters and their BVHs over the triangles `t` of `geometry` with `keep(t)`
    /// that have finite corners and non-zero area; `pass(t)` is the light a triangle lets
    /// through. The first cluster holds at least half the triangles, around their median; the
    /// triangles beyond [`OUTLIER_FACTOR`] of it are clustered again the same way, so there
    /// are at most `log2(n) + 1` clusters.
    pub(crate) fn build(
        geometry: &Geometry,
        keep: impl Fn(usize) -> bool,
        pass: impl Fn(usize) -> f64,
        alloc: &Allocator,
    ) -> Result<Self, AllocationError> {
        let wanted = |t: &usize| keep(*t) && hittable(geometry, *t);
        let n = (0..geometry.len()).filter(wanted).count();
        let mut tris: Vec<u32> = alloc.vec(n, "the BVH's triangle lists")?;
        tris.extend((0..geometry.len()).filter(wanted).map(|t| t as u32));
        let mut accel = Self {
            clusters: Vec::new(),
            corners: alloc.vec(n, "the triangles' corners")?,
            ids: alloc.vec(n, "the triangle ids")?,
            pass: alloc.vec(n, "the triangles' transmittance")?,
        };
        let push = |accel: &mut Self, t: u32| {
            accel.ids.push(t);
            accel.corners.push(geometry.corners(t as usize));
            accel.pass.push(pass(t as usize).clamp(0.0, 1.0));
        };
        while !tris.is_empty() {
            let (frame, main, rest) = split(geometry, &tris, alloc)?;
            drop(tris);
            let first = accel.ids.len();
            let bvh = if frame.traversable() {
                let mut boxes = alloc.vec(main.len(), "the BVH's boxes")?;
                boxes.extend(
                    main.iter()
                        .map(|&t| frame.padded_box(corners_box(geometry.corners(t as usize)))),
                );
                alloc.probe_bvh_build(main.len())?;
                let bvh =
                    build_cwbvh(&boxes, BvhBuildParams::medium_build(), &mut Default::default());
                for &p in &bvh.primitive_indices {
                    push(&mut accel, main[p as usize]);
                }
                Some(bvh)
            } else {
                for &t in &main {
                    push(&mut accel, t);
                }
                None
            };
            let len = accel.ids.len() - first;
            accel.clusters.push(Cluster { frame, bvh, first, len });
            tris = rest;
        }
        Ok(accel)
    }

    /// The closest hit with `tmin <= t <= tmax`, as `(t, triangle id)`; ties go to the lower id.
    /// `tests` counts the triangles tested.
    pub(crate) fn closest(
        &self,
        ray: &TraceRay,
        tmin: f64,
        tmax: f64,
        tests: &mut u64,
    ) -> Option<(f64, u32)> {
        let mut best: Option<(f64, u32)> = None;
        for c in &self.clusters {
            let route = c.route(ray, best.map_or(tmax, |(t, _)| t));
            let mut visit = |slot: usize| -> Option<f64> {
                *tests += 1;
                let slot = c.first + slot;
                let t = ray.intersect(&self.corners[slot])?;
                if !(t >= tmin && t <= tmax) {
                    return None;
                }
                let id = self.ids[slot];
                match best {
                    Some((bt, bid)) if bt < t || (bt == t && bid <= id) => None,
                    _ => {
                        best = Some((t, id));
                        Some(t)
                    }
                }
            };
            match route {
                Route::Bvh(bvh, fr) => {
                    bvh.ray_traverse(fr.ray, &mut RayHit::none(), |_, slot| {
                        visit(slot).map_or(f32::INFINITY, |t| fr.upper(t))
                    });
                }
                Route::Skip => {}
                Route::All => (0..c.len).for_each(|slot| {
                    visit(slot);
                }),
            }
        }
        best
    }

    /// Light reaching the end of the ray: the product of `pass` over the triangles hit with
    /// `tmin < t < tmax`, other than `skip`; traversal stops at the first triangle that lets
    /// no light through (`ray_traverse_miss`). `tests` counts the triangles tested.
    pub(crate) fn transmittance(
        &self,
        ray: &TraceRay,
        tmin: f64,
        tmax: f64,
        skip: u32,
        tests: &mut u64,
    ) -> f64 {
        let mut light = 1.0;
        for c in &self.clusters {
            // Whether the ray is finished (no light left).
            let mut visit = |slot: usize| -> bool {
                *tests += 1;
                let slot = c.first + slot;
                if self.ids[slot] == skip {
                    return false;
                }
                match ray.intersect(&self.corners[slot]) {
                    Some(t) if t > tmin && t < tmax => {
                        light *= self.pass[slot];
                        light == 0.0
                    }
                    _ => false,
                }
            };
            match c.route(ray, tmax) {
                Route::Bvh(bvh, fr) => {
                    bvh.ray_traverse_miss(
                        fr.ray,
                        |_, slot| {
                            if visit(slot) {
                                0.0
                            } else {
                                f32::INFINITY
                            }
                        },
                    );
                }
                Route::Skip => {}
                Route::All => {
                    for slot in 0..c.len {
                        if visit(slot) {
                            break;
                        }
                    }
                }
            }
            if light == 0.0 {
                break;
            }
        }
        light
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

    fn closest(accel: &Accel, ray: &TraceRay, tmin: f64, tmax: f64) -> Option<(f64, u32)> {
        accel.closest(ray, tmin, tmax, &mut 0)
    }

    fn transmittance(accel: &Accel, ray: &TraceRay, tmin: f64, tmax: f64, skip: u32) -> f64 {
        accel.transmittance(ray, tmin, tmax, skip, &mut 0)
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

    /// Axis-aligned rays whose zero components are -0.0 (e.g. `-direction` of a vertical
    /// light) must still find their boxes (obvhs alone misses them all).
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

    /// An occluder lying a millionth of its size above the ground: obvhs' node test ignores
    /// boxes left within 1e-4 of a ray's start, which the start shift must make up for.
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
}
