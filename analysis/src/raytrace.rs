//! `raytrace`: the ray-traced supersampling reference.
//!
//! Every pixel is sampled at the sub-pixel points of a shared [`SamplePattern`] (the same
//! points `pan09` and `afsm-ss` use at equal rate and pattern). For each sub-sample:
//!
//! 1. **Camera ray** through the sub-sample's image point (`frame.camera.ray`, parameterised by
//!    depth): the closest hit over *all* triangles of `frame.geometry` (camera rays see every
//!    object, casters or not). No hit: the sub-sample is background, counts as lit, and its
//!    pixel is not evaluated.
//! 2. **Shadow ray** from the hit point towards the light (directional: along `-direction`,
//!    unbounded; spot: towards `position`, ending at the light; the spot's cone is ignored, as
//!    in the shadow maps and `exact`), against caster triangles only (`frame.is_caster`),
//!    excluding the hit triangle itself and ignoring hits nearer than `afsm::shadow_offset`
//!    (local to the hit point, see Choices; `afsm` decides its shadows with the same offset).
//!    Opaque scenes (no `transparency` effect, also when the scene file forces it off): the
//!    first caster hit ends the ray (`ray_traverse_miss`). Scenes with `transparency`: every
//!    caster hit along the ray multiplies the transmittance by `1 - opacity` (an opaque caster
//!    ends the ray at 0).
//!
//! A pixel's `lit` is the mean of its sub-samples' visibility (1 lit, 0 shadowed, the
//! transmittance with transparency; background sub-samples count 1), so at rate `N` and without
//! transparency the values are exactly `k / N`. `evaluated` is true where every sub-sample hit
//! a surface. With transparency, `transmittance` is the per-pixel mean RGB transmittance.
//!
//! [`RayTrace::sample_image`] returns every sub-sample's hit triangle and light instead, for
//! comparisons sample by sample.
//!
//! Stages: [`STAGE_BVH_BUILD`] ("BVH build": one obvhs CWBVH over all triangles for camera rays
//! and, when some triangle does not cast shadows, a second one over the casters) and
//! [`STAGE_RAY_TRACING`] ("ray tracing", rayon over rows). Counter: `rays_traced` = camera rays
//! (`W * H * rate`) + shadow rays (one per sub-sample that hit a surface), summed from per-row
//! counts.
//!
//! # Precision: f32 BVH, f64 triangles
//!
//! obvhs is `f32`-only (boxes, rays, its Möller-Trumbore test). It is used only to *find
//! candidates*; every hit decision is made in `f64` by our own triangle test (called from
//! obvhs' traversal closures with the BVH slot, i.e. the position in `primitive_indices`, whose
//! triangles we store in that order): Woop, Benthin and Wald's watertight ray-triangle test
//! (JCGT 2013), double-sided. What makes the `f32` search lose nothing, whatever the scene's
//! size and position (tested from scale 1e-6 to 1e6, translations of 1e7, objects 1e12 away):
//!
//! - **Its own frame** (`BvhFrame`): the BVH is built and traversed in world coordinates
//!   minus a centre (the per-axis median of the triangles' box centres, so one far object does
//!   not move it) times a power of two near the inverse of the median triangle size. Every
//!   scene looks to obvhs like one of unit triangles near the origin; a far object is simply
//!   far. Frame coordinates are kept below 1e15 so that obvhs' `f32` areas stay finite.
//! - **Padding from local magnitudes**: each box is computed in `f64` in the frame and padded
//!   by 32 `f32` epsilons of (its own largest coordinate + the reach of ray origins) before
//!   rounding to `f32`: that covers the rounding of the ray's origin and direction, obvhs'
//!   reciprocal of direction components below `f32::EPSILON` (clamped to `1/EPSILON`, a drift
//!   of `EPSILON` per unit travelled), and its slab tests. The reach is the largest frame
//!   magnitude of the main body of the geometry (triangles within 1e6 typical radii of the
//!   centre) and of the camera's ray origins; a ray that starts farther out (on a far-away
//!   object) is tested against every triangle instead, so far objects neither widen every box
//!   nor lose hits.
//! - **Start shift**: obvhs' CWBVH node test ignores children left before frame distance 1e-4
//!   (its `EPSILON`); frame rays therefore start `2e-4` (plus 8 `f32` ulps of the origin) behind
//!   the world ray's origin, and frame parameters map back by that shift. Occluders in contact
//!   with the receiver are found at any scale.
//! - The traversal prunes with `f32` frame distances rounded upwards, never losing the closest
//!   `f64` hit.
//!
//! Edges and vertices: Woop's test evaluates the three edge functions of a triangle from
//! per-vertex quantities that depend only on the ray and the vertex, so two triangles that
//! share an edge compute the same edge value (exactly negated when they traverse it in
//! opposite directions). A ray through the interior of a closed mesh's silhouette therefore
//! never slips between triangles. Where an edge function is exactly zero (the ray passes
//! exactly through an edge or a vertex) a top-left rule in the ray's projection plane gives
//! the point to exactly one of the triangles around it, so a shadow ray through a shared edge
//! of a semi-transparent quad is attenuated once, not twice. Degenerate triangles (zero area
//! or non-finite corners) are left out of the BVH: they have no area and cannot be hit.
//!
//! # Choices
//!
//! - **Shadow ray start**: from the `f64` hit point, skipping the hit triangle, and ignoring
//!   hits nearer than `afsm::SHADOW_OFFSET` (`1e-10`) times the magnitude of the numbers that
//!   made the point: the larger coordinate magnitude of the camera ray's origin and the hit,
//!   plus their distance. The hit point's rounding error is about `1e-16` of that magnitude, so
//!   a coplanar neighbour (a subdivided lit plane, even under a light 89.9° from the vertical,
//!   which stretches the distance 573 times) is met about `1e-13` of it away: far inside the
//!   offset, so lit planes stay lit. The offset is local: it neither grows with a far-away
//!   object nor shrinks with the scene's size relative to its position, so at a translation of
//!   1e7 it is 1e-3 units (the resolution of `f64` coordinates there is 2e-9). A closed mesh
//!   cannot leak: a shadow ray leaving a point facing away from the light crosses the far side
//!   at a distance of the order of the mesh's thickness; only occluders closer than the offset
//!   (contact) are missed.
//! - **Transmittance is grey**: Aila and Laine (2004, section 4) give each sampling point an
//!   RGB colour, initially white, that "a semi-transparent surface ... modulates" and that
//!   opaque surfaces set to black, without saying how the caster's colour enters. Scenes have
//!   one scalar `opacity` per material, and `material.color` is the surface's albedo for the
//!   Lambert image, not a transmission filter, so each caster hit multiplies all three channels
//!   by `1 - opacity` (opacity 1 gives black, as in the paper). The three channels are equal;
//!   `lit` is their mean (equal to each). The RGB triple keeps the interface of the paper.
//! - **Orthographic cameras** see every depth (as the G-buffer does): their rays start behind
//!   the scene's bounds. Perspective rays start at depth `near`. Equal-depth hits go to the
//!   lower triangle id, as in the rasterizer.

use crate::reference::{Reference, ReferenceError, ReferenceImage};
use glam::{DVec3, Vec3A};
use instrumentation::Recorder;
use methods::{afsm::shadow_offset, pattern::SamplePattern, Frame};
use obvhs::{
    aabb::Aabb,
    cwbvh::{builder::build_cwbvh, CwBvh},
    ray::{Ray as BvhRay, RayHit},
    BvhBuildParams,
};
use rayon::prelude::*;
use scenes::{projection::ProjectionKind, Geometry, Light};

/// Name of the stage that builds the BVHs.
pub const STAGE_BVH_BUILD: &str = "BVH build";
/// Name of the stage that traces the camera and shadow rays.
pub const STAGE_RAY_TRACING: &str = "ray tracing";

/// The ray-traced reference: one camera ray and one shadow ray per sub-sample of `pattern`.
#[derive(Debug, Clone, PartialEq)]
pub struct RayTrace {
    /// Sub-pixel sample positions (rate and pattern).
    pub pattern: SamplePattern,
}

/// A ray in `f64` with the precomputed shear of Woop et al.'s watertight triangle test.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TraceRay {
    origin: DVec3,
    dir: DVec3,
    /// Axis indices: `kz` is the dominant axis of `dir`, `kx`, `ky` the other two (swapped
    /// when `dir[kz] < 0` to keep the winding).
    k: [usize; 3],
    /// `(dir[kx] / dir[kz], dir[ky] / dir[kz], 1 / dir[kz])`.
    shear: DVec3,
}

/// Whether the triangle owns its edge `p -> q` on which the ray's point lies exactly (edge
/// function 0), by the top-left rule on the edge's inward normal in the ray's projection
/// plane: `ccw` tells on which side of `p -> q` the triangle lies.
#[inline]
fn owns_edge(p: (f64, f64), q: (f64, f64), ccw: bool) -> bool {
    let (ex, ey) = (q.0 - p.0, q.1 - p.1);
    // Inward normal: the left perpendicular (-ey, ex) for a counter-clockwise triangle.
    let (nx, ny) = if ccw { (-ey, ex) } else { (ey, -ex) };
    ny > 0.0 || (ny == 0.0 && nx > 0.0)
}

impl TraceRay {
    /// The ray `origin + t * dir`; `None` unless both are finite and `dir` is non-zero.
    pub(crate) fn new(origin: DVec3, dir: DVec3) -> Option<Self> {
        if !origin.is_finite() || !dir.is_finite() || dir == DVec3::ZERO {
            return None;
        }
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / dir[kz];
        Some(Self {
            origin,
            dir,
            k: [kx, ky, kz],
            shear: DVec3::new(dir[kx] * sz, dir[ky] * sz, sz),
        })
    }

    /// The point at parameter `t`.
    #[inline]
    pub(crate) fn at(&self, t: f64) -> DVec3 {
        self.origin + t * self.dir
    }

    /// Parameter where the ray meets the triangle (either side), or `None`. Watertight; a
    /// point exactly on an edge or vertex belongs to one triangle (top-left rule).
    #[inline]
    pub(crate) fn intersect(&self, tri: &[DVec3; 3]) -> Option<f64> {
        let [kx, ky, kz] = self.k;
        let (sx, sy, sz) = (self.shear.x, self.shear.y, self.shear.z);
        let a = tri[0] - self.origin;
        let b = tri[1] - self.origin;
        let c = tri[2] - self.origin;
        let (ax, ay) = (a[kx] - sx * a[kz], a[ky] - sy * a[kz]);
        let (bx, by) = (b[kx] - sx * b[kz], b[ky] - sy * b[kz]);
        let (cx, cy) = (c[kx] - sx * c[kz], c[ky] - sy * c[kz]);
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        if u == 0.0 || v == 0.0 || w == 0.0 {
            // det = -2 * signed area of (A', B', C'), so the triangle is counter-clockwise in
            // the projection plane iff det < 0.
            let ccw = det < 0.0;
            let (pa, pb, pc) = ((ax, ay), (bx, by), (cx, cy));
            if (u == 0.0 && !owns_edge(pb, pc, ccw))
                || (v == 0.0 && !owns_edge(pc, pa, ccw))
                || (w == 0.0 && !owns_edge(pa, pb, ccw))
            {
                return None;
            }
        }
        let t = (u * (sz * a[kz]) + v * (sz * b[kz]) + w * (sz * c[kz])) / det;
        t.is_finite().then_some(t)
    }
}

/// An `f32` upper bound of a non-negative ray parameter, for obvhs' pruning.
#[inline]
fn upper_f32(t: f64) -> f32 {
    if t.is_finite() {
        (t * (1.0 + 1e-6)) as f32
    } else {
        f32::INFINITY
    }
}

/// The `f32` coordinate frame the BVH is built and traversed in: world coordinates centred on
/// the geometry and scaled by a power of two to its typical triangle, so that the BVH sees every
/// scene as it sees one of unit triangles at the origin, whatever its absolute size or position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BvhFrame {
    /// World point mapped to the origin (per-axis median of the triangles' box centres).
    centre: DVec3,
    /// World-to-frame scale, a power of two (exact in `f64`).
    scale: f64,
    /// Largest frame-space coordinate magnitude of a ray origin the box padding covers: the
    /// main body of the geometry and the camera's ray origins. Rays starting farther out
    /// (from geometry far beyond the rest) are tested against every triangle instead.
    reach: f64,
}

/// Box padding in units of `f32::EPSILON` times (reach + box magnitude): covers the `f32`
/// rounding of the ray's origin and direction, obvhs' clamped reciprocal of direction components
/// below `f32::EPSILON`, and the rounding of its slab tests, with a margin of about 8.
const PAD_ULPS: f64 = 32.0;

/// obvhs' CWBVH node test ignores children whose exit distance is below this (its `EPSILON`);
/// rays are started this far and more behind their origin so that nothing is lost to it.
const NODE_TMIN: f64 = 1e-4;

/// Geometry farther than this many typical radii from the centre does not widen the padding
/// of the rest (see [`BvhFrame::reach`]).
const OUTLIER_FACTOR: f64 = 1e6;

/// Largest frame-space coordinate magnitude: keeps obvhs' `f32` areas and costs finite.
const MAX_FRAME_COORDINATE: f64 = 1e15;

impl BvhFrame {
    /// Fits the frame to the finite, non-degenerate triangles of `geometry`; `origins` are
    /// further ray origins (the camera's) the padding must cover.
    pub(crate) fn fit(geometry: &Geometry, origins: &[DVec3]) -> Self {
        let boxes: Vec<(DVec3, DVec3)> =
            (0..geometry.len()).filter_map(|t| triangle_box(geometry, t)).collect();
        if boxes.is_empty() {
            return Self { centre: DVec3::ZERO, scale: 1.0, reach: 1.0 };
        }
        let axis = |k: usize| {
            let mut centres: Vec<f64> =
                boxes.iter().map(|(lo, hi)| 0.5 * lo[k] + 0.5 * hi[k]).collect();
            select_middle(&mut centres)
        };
        let centre = DVec3::new(axis(0), axis(1), axis(2));
        let mut sizes: Vec<f64> = boxes.iter().map(|(lo, hi)| (*hi - *lo).max_element()).collect();
        let typical = select_middle(&mut sizes);
        // World distances from the centre (in the max norm) of each triangle's farthest corner.
        let mut radii: Vec<f64> = boxes
            .iter()
            .map(|&(lo, hi)| (lo - centre).abs().max(hi - centre).max_element())
            .collect();
        let farthest = radii.iter().copied().fold(0.0, f64::max);
        let median_radius = select_middle(&mut radii);
        let mut scale = if typical > 0.0 { power_of_two_near(1.0 / typical) } else { 1.0 };
        if farthest * scale > MAX_FRAME_COORDINATE {
            scale = power_of_two_near(MAX_FRAME_COORDINATE / farthest) * 0.5;
        }
        let main_limit = OUTLIER_FACTOR * (median_radius + typical);
        let main = radii.iter().copied().filter(|&r| r <= main_limit).fold(0.0, f64::max);
        let origins = origins
            .iter()
            .filter(|o| o.is_finite())
            .map(|&o| (o - centre).abs().max_element())
            .fold(0.0, f64::max);
        // The start shift moves origins back by at most about 2 NODE_TMIN (see `start_shift`).
        let reach = (main.max(origins) * scale + 4.0 * NODE_TMIN).min(MAX_FRAME_COORDINATE);
        Self { centre, scale, reach }
    }

    /// `p` in frame coordinates (`f64`).
    #[inline]
    fn to_frame(self, p: DVec3) -> DVec3 {
        (p - self.centre) * self.scale
    }

    /// The `f32` box of a triangle with world box `(lo, hi)`, padded outwards.
    fn padded_box(&self, lo: DVec3, hi: DVec3) -> Aabb {
        let (lo, hi) = (self.to_frame(lo), self.to_frame(hi));
        let magnitude = lo.abs().max(hi.abs()).max_element();
        let pad = PAD_ULPS * f64::from(f32::EPSILON) * (self.reach + magnitude);
        let f = |v: DVec3| Vec3A::new(v.x as f32, v.y as f32, v.z as f32);
        Aabb::new(f(lo - DVec3::splat(pad)), f(hi + DVec3::splat(pad)))
    }

    /// How far (in frame units) a ray starting at frame point `o` is started behind its origin,
    /// so that obvhs' node test, which ignores boxes left before [`NODE_TMIN`], loses nothing
    /// despite the `f32` rounding of the shifted origin.
    #[inline]
    fn start_shift(o: DVec3) -> f64 {
        2.0 * NODE_TMIN + 8.0 * f64::from(f32::EPSILON) * o.abs().max_element()
    }

    /// The `f32` ray obvhs traverses for `ray` up to world parameter `tmax`. `None` when the
    /// ray starts beyond [`BvhFrame::reach`], where the padding does not cover its rounding.
    fn bvh_ray(&self, ray: &TraceRay, tmax: f64) -> Option<FrameRay> {
        let o = self.to_frame(ray.origin);
        let m = o.abs().max_element();
        if m.is_nan() || m > self.reach {
            return None;
        }
        // Frame rays take the world ray's direction made unit, so frame parameters are frame
        // distances; `step` is the frame distance per unit of world parameter.
        let len = ray.dir.length();
        let d = ray.dir / len;
        let step = len * self.scale;
        let shift = Self::start_shift(o);
        let start = o - shift * d;
        // `+ 0.0` turns -0.0 into +0.0: obvhs inverts -0.0 to -1/EPSILON but sorts it into the
        // positive octant, which would make every box test miss.
        let dir = |x: f64| x as f32 + 0.0;
        let ray = BvhRay::new(
            Vec3A::new(start.x as f32, start.y as f32, start.z as f32),
            Vec3A::new(dir(d.x), dir(d.y), dir(d.z)),
            0.0,
            upper_f32(shift + tmax * step),
        );
        Some(FrameRay { ray, shift, step })
    }
}

/// A ray in the BVH's frame: frame parameter `shift + t * step` is world parameter `t`.
struct FrameRay {
    ray: BvhRay,
    shift: f64,
    step: f64,
}

impl FrameRay {
    /// An `f32` frame parameter at or beyond world parameter `t`, for obvhs' pruning.
    #[inline]
    fn upper(&self, t: f64) -> f32 {
        upper_f32(self.shift + t * self.step)
    }
}

/// The world box of triangle `t` of `geometry`, or `None` when a corner is not finite or the
/// triangle has no area (it cannot be hit).
fn triangle_box(geometry: &Geometry, t: usize) -> Option<(DVec3, DVec3)> {
    let [a, b, c] = geometry.corners(t);
    if !(a.is_finite() && b.is_finite() && c.is_finite()) {
        return None;
    }
    // The area test is made on the corners scaled by their largest magnitude, so that neither
    // huge nor tiny coordinates overflow or underflow the cross product.
    let m = a.abs().max(b.abs()).max(c.abs()).max_element();
    if m == 0.0 {
        return None;
    }
    let (sa, sb, sc) = (a / m, b / m, c / m);
    if (sb - sa).cross(sc - sa) == DVec3::ZERO {
        return None;
    }
    Some((a.min(b).min(c), a.max(b).max(c)))
}

/// The middle value of `v` by selection (the upper one for even lengths): the median of
/// positions and sizes that places the BVH's frame, found in linear time, which is not a
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

/// A CWBVH over some triangles, with their `f64` corners in BVH slot order.
pub(crate) struct Accel {
    bvh: CwBvh,
    frame: BvhFrame,
    /// Corners of the triangle in each slot (the order of `bvh.primitive_indices`).
    corners: Vec<[DVec3; 3]>,
    /// Triangle id (index into the frame's geometry) of each slot.
    ids: Vec<u32>,
    /// Fraction of light passing through each slot's triangle (`1 - opacity`, or 0).
    pass: Vec<f64>,
}

impl Accel {
    /// Builds the BVH, in `frame`, over the triangles `t` of `geometry` with `keep(t)` that
    /// have finite corners and non-zero area; `pass(t)` is the light a triangle lets through.
    pub(crate) fn build(
        geometry: &Geometry,
        keep: impl Fn(usize) -> bool,
        pass: impl Fn(usize) -> f64,
        frame: BvhFrame,
    ) -> Self {
        let mut ids = Vec::new();
        let mut boxes = Vec::new();
        for t in 0..geometry.len() {
            if !keep(t) {
                continue;
            }
            if let Some((lo, hi)) = triangle_box(geometry, t) {
                ids.push(t as u32);
                boxes.push(frame.padded_box(lo, hi));
            }
        }
        let bvh = if boxes.is_empty() {
            CwBvh::default()
        } else {
            build_cwbvh(&boxes, BvhBuildParams::medium_build(), &mut Default::default())
        };
        let ids: Vec<u32> = bvh.primitive_indices.iter().map(|&p| ids[p as usize]).collect();
        let corners = ids.iter().map(|&t| geometry.corners(t as usize)).collect();
        let pass = ids.iter().map(|&t| pass(t as usize).clamp(0.0, 1.0)).collect();
        Self { bvh, frame, corners, ids, pass }
    }

    /// The closest hit with `tmin <= t <= tmax`, as `(t, triangle id)`; ties go to the lower id.
    pub(crate) fn closest(&self, ray: &TraceRay, tmin: f64, tmax: f64) -> Option<(f64, u32)> {
        let mut best: Option<(f64, u32)> = None;
        let mut visit = |slot: usize| -> Option<f64> {
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
        match self.frame.bvh_ray(ray, tmax) {
            Some(fr) => {
                self.bvh.ray_traverse(fr.ray, &mut RayHit::none(), |_, slot| {
                    visit(slot).map_or(f32::INFINITY, |t| fr.upper(t))
                });
            }
            None => (0..self.ids.len()).for_each(|slot| {
                visit(slot);
            }),
        }
        best
    }

    /// Light reaching the end of the ray: the product of `pass` over the triangles hit with
    /// `tmin < t < tmax`, other than `skip`; traversal stops at the first triangle that lets
    /// no light through (`ray_traverse_miss`).
    pub(crate) fn transmittance(&self, ray: &TraceRay, tmin: f64, tmax: f64, skip: u32) -> f64 {
        let mut light = 1.0;
        // Whether the ray is finished (no light left).
        let mut visit = |slot: usize| -> bool {
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
        match self.frame.bvh_ray(ray, tmax) {
            Some(fr) => {
                self.bvh.ray_traverse_miss(
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
            None => {
                for slot in 0..self.ids.len() {
                    if visit(slot) {
                        break;
                    }
                }
            }
        }
        light
    }
}

/// Bounds `(lo, hi)` of the finite positions of `geometry`, or `None` when there are none.
fn bounds(geometry: &Geometry) -> Option<(DVec3, DVec3)> {
    geometry.positions.iter().filter(|p| p.is_finite()).fold(None, |acc, &p| match acc {
        None => Some((p, p)),
        Some((lo, hi)) => Some((lo.min(p), hi.max(p))),
    })
}

/// Where the light is, seen from a shading point.
#[derive(Debug, Clone, Copy)]
enum LightSource {
    /// Unit direction towards a directional light.
    Towards(DVec3),
    /// Position of a spot light.
    At(DVec3),
}

/// What one sub-sample's rays found.
#[derive(Debug, Clone, Copy, PartialEq)]
struct SampleHit {
    /// The triangle the camera ray hit, `None` for background.
    triangle: Option<u32>,
    /// Light reaching the hit point (1 for background).
    light: f64,
    /// Rays traced (camera ray, and the shadow ray when it hit).
    rays: u64,
}

/// Everything the rays of one frame share: acceleration structures, light, camera set-up.
struct Tracer<'a> {
    frame: &'a Frame<'a>,
    pattern: &'a SamplePattern,
    camera_accel: Accel,
    /// The casters' BVH, when some triangle does not cast shadows (else the camera's).
    caster_accel: Option<Accel>,
    light: LightSource,
    /// Camera rays start this far along their direction (orthographic cameras start behind
    /// the scene), and accept hits from `camera_tmin`.
    start_shift: f64,
    camera_tmin: f64,
}

impl<'a> Tracer<'a> {
    /// Builds the BVHs (stage [`STAGE_BVH_BUILD`]) and the ray set-up for `frame`.
    fn new(
        frame: &'a Frame<'a>,
        pattern: &'a SamplePattern,
        rec: &mut Recorder,
    ) -> Result<Self, ReferenceError> {
        let light = match frame.scene.light {
            Light::Directional { direction } => {
                let Some(along) = scenes::direction::unit(direction) else {
                    return Err(ReferenceError::NotApplicable(format!(
                        "raytrace: the directional light of scene `{}` has no direction",
                        frame.scene.name
                    )));
                };
                LightSource::Towards(-along)
            }
            Light::Spot { position, .. } => {
                if !position.is_finite() {
                    return Err(ReferenceError::NotApplicable(format!(
                        "raytrace: the spot light of scene `{}` is not at a finite position",
                        frame.scene.name
                    )));
                }
                LightSource::At(position)
            }
        };
        let geometry = &frame.geometry;
        let (lo, hi) = bounds(geometry).unwrap_or((DVec3::ZERO, DVec3::ZERO));
        let diagonal = (hi - lo).length();
        let transparency = frame.effects.transparency;
        let objects = &frame.scene.objects;
        let pass = |t: usize| {
            if transparency {
                objects.get(geometry.object[t] as usize).map_or(0.0, |o| 1.0 - o.material.opacity)
            } else {
                0.0
            }
        };

        // Camera rays: perspective from depth `near`; orthographic from behind the scene.
        let camera = &frame.camera;
        let (start_shift, camera_tmin) = match camera.kind {
            ProjectionKind::Perspective { .. } => (0.0, camera.near),
            ProjectionKind::Orthographic { .. } => {
                let nearest = scenes::mesh::box_corners(lo, hi)
                    .iter()
                    .map(|&c| camera.depth_of(c))
                    .fold(f64::INFINITY, f64::min);
                (nearest.min(0.0) - diagonal * 1e-3, 0.0)
            }
        };
        // Where camera rays start: the eye, or the image rectangle's corners behind the scene.
        let (w, h) = (f64::from(frame.width()), f64::from(frame.height()));
        let origins: Vec<DVec3> = [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)]
            .into_iter()
            .map(|(x, y)| {
                let r = camera.ray(glam::DVec2::new(x, y));
                r.origin + start_shift * r.direction
            })
            .collect();

        let (camera_accel, caster_accel) = rec.stages.time(STAGE_BVH_BUILD, || {
            let bvh_frame = BvhFrame::fit(geometry, &origins);
            let all = Accel::build(geometry, |_| true, pass, bvh_frame);
            let casters = (0..geometry.len())
                .any(|t| !frame.is_caster(t))
                .then(|| Accel::build(geometry, |t| frame.is_caster(t), pass, bvh_frame));
            (all, casters)
        });

        Ok(Self { frame, pattern, camera_accel, caster_accel, light, start_shift, camera_tmin })
    }

    /// The camera ray and the shadow ray of sub-sample `s` of pixel `(i, j)`.
    fn sample(&self, i: u32, j: u32, s: usize) -> SampleHit {
        let r = self.frame.camera.ray(self.pattern.point(i, j, s));
        let origin = r.origin + self.start_shift * r.direction;
        let hit = TraceRay::new(origin, r.direction).and_then(|ray| {
            self.camera_accel
                .closest(&ray, self.camera_tmin, f64::INFINITY)
                .map(|(t, id)| (ray.at(t), id))
        });
        let Some((p, id)) = hit else {
            return SampleHit { triangle: None, light: 1.0, rays: 1 };
        };
        let (dir, tmax) = match self.light {
            LightSource::Towards(d) => (Some(d), f64::INFINITY),
            LightSource::At(q) => (scenes::direction::unit(q - p), (q - p).length()),
        };
        let tmin = shadow_offset(origin, p);
        let casters = self.caster_accel.as_ref().unwrap_or(&self.camera_accel);
        let light = match dir.and_then(|d| TraceRay::new(p, d)) {
            Some(ray) if tmax > tmin => casters.transmittance(&ray, tmin, tmax, id),
            // The point is at the light (or the ray is degenerate): lit.
            _ => 1.0,
        };
        SampleHit { triangle: Some(id), light, rays: 2 }
    }
}

/// One row of results.
struct Row {
    lit: Vec<f64>,
    evaluated: Vec<bool>,
    rays: u64,
}

/// Every sub-sample's result, for comparisons sample by sample: entry `pixel * rate + s` is
/// sub-sample `s` of pixel `pixel` (row-major).
#[derive(Debug, Clone, PartialEq)]
pub struct SampleImage {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Sub-samples per pixel.
    pub rate: u32,
    /// The triangle each sub-sample's camera ray hit ([`methods::raster::NO_TRIANGLE`] for
    /// background).
    pub triangle: Vec<u32>,
    /// Light reaching each sub-sample's hit point: 0 or 1 without transparency, the
    /// transmittance with it; 1 for background.
    pub light: Vec<f64>,
}

impl RayTrace {
    /// Traces every sub-sample of `frame` and returns each one's hit and light (stages and
    /// counters as [`Reference::evaluate`]).
    pub fn sample_image(
        &self,
        frame: &Frame<'_>,
        rec: &mut Recorder,
    ) -> Result<SampleImage, ReferenceError> {
        let tracer = Tracer::new(frame, &self.pattern, rec)?;
        let (w, h) = (frame.width(), frame.height());
        let rate = self.pattern.rate() as usize;
        let rows: Vec<(Vec<u32>, Vec<f64>, u64)> = rec.stages.time(STAGE_RAY_TRACING, || {
            (0..h)
                .into_par_iter()
                .map(|j| {
                    let mut row = (Vec::with_capacity(w as usize * rate), Vec::new(), 0);
                    for i in 0..w {
                        for s in 0..rate {
                            let hit = tracer.sample(i, j, s);
                            row.0.push(hit.triangle.unwrap_or(methods::raster::NO_TRIANGLE));
                            row.1.push(hit.light);
                            row.2 += hit.rays;
                        }
                    }
                    row
                })
                .collect()
        });
        rec.counters.rays_traced += rows.iter().map(|r| r.2).sum::<u64>();
        let (mut triangle, mut light) = (Vec::new(), Vec::new());
        for (t, l, _) in rows {
            triangle.extend(t);
            light.extend(l);
        }
        Ok(SampleImage { width: w, height: h, rate: rate as u32, triangle, light })
    }
}

impl Reference for RayTrace {
    fn name(&self) -> &'static str {
        "raytrace"
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = serde_json::Map::new();
        m.insert("rate".into(), self.pattern.rate().into());
        m.insert("pattern".into(), self.pattern.kind().name().into());
        m
    }

    fn evaluate(
        &self,
        frame: &Frame<'_>,
        rec: &mut Recorder,
    ) -> Result<ReferenceImage, ReferenceError> {
        self.evaluate_pixels(frame, None, rec)
    }
}

impl RayTrace {
    /// Traces the pixels where `mask` is true (every pixel with `None`); the others are lit
    /// (1) and not evaluated, and cost no ray. `exact` uses it for its `edge` pixels.
    pub fn evaluate_pixels(
        &self,
        frame: &Frame<'_>,
        mask: Option<&[bool]>,
        rec: &mut Recorder,
    ) -> Result<ReferenceImage, ReferenceError> {
        let tracer = Tracer::new(frame, &self.pattern, rec)?;
        let (w, h) = (frame.width(), frame.height());
        let rate = self.pattern.rate() as usize;
        let wanted = |i: u32, j: u32| mask.is_none_or(|m| m[(j * w + i) as usize]);
        let rows: Vec<Row> = rec.stages.time(STAGE_RAY_TRACING, || {
            (0..h)
                .into_par_iter()
                .map(|j| {
                    let mut row = Row {
                        lit: Vec::with_capacity(w as usize),
                        evaluated: Vec::with_capacity(w as usize),
                        rays: 0,
                    };
                    for i in 0..w {
                        if !wanted(i, j) {
                            row.lit.push(1.0);
                            row.evaluated.push(false);
                            continue;
                        }
                        let (mut sum, mut all_hit) = (0.0f64, true);
                        for s in 0..rate {
                            let hit = tracer.sample(i, j, s);
                            row.rays += hit.rays;
                            all_hit &= hit.triangle.is_some();
                            sum += hit.light;
                        }
                        row.lit.push((sum / rate as f64).clamp(0.0, 1.0));
                        row.evaluated.push(all_hit);
                    }
                    row
                })
                .collect()
        });

        let rays: u64 = rows.iter().map(|r| r.rays).sum();
        rec.counters.rays_traced += rays;
        let n = (w as usize) * (h as usize);
        let (mut lit, mut evaluated) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for row in rows {
            lit.extend(row.lit);
            evaluated.extend(row.evaluated);
        }
        let transmittance =
            frame.effects.transparency.then(|| lit.iter().map(|&t| [t; 3]).collect());
        Ok(ReferenceImage { width: w, height: h, lit, evaluated, transmittance, classes: None })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scenes::generators::{Generator, SpheresParams};

    fn geometry(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Geometry {
        let object = vec![0; triangles.len()];
        Geometry { positions, triangles, object }
    }

    /// A fan of `n` triangles around the origin in the plane z = 0, alternately wound.
    fn fan(n: u32) -> Geometry {
        let mut positions = vec![DVec3::ZERO];
        for k in 0..n {
            let a = std::f64::consts::TAU * f64::from(k) / f64::from(n);
            positions.push(DVec3::new(a.cos(), a.sin(), 0.0));
        }
        let triangles = (0..n)
            .map(|k| {
                let (p, q) = (1 + k, 1 + (k + 1) % n);
                if k % 2 == 0 {
                    [0, p, q]
                } else {
                    [q, 0, p]
                }
            })
            .collect();
        geometry(positions, triangles)
    }

    fn hits(g: &Geometry, ray: &TraceRay) -> usize {
        (0..g.len()).filter(|&t| ray.intersect(&g.corners(t)).is_some()).count()
    }

    #[test]
    fn rays_through_shared_vertices_and_edges_hit_exactly_one_triangle() {
        for n in [3, 4, 5, 6, 8, 12] {
            let g = fan(n);
            let mut targets = vec![DVec3::ZERO];
            for k in 0..n as usize {
                targets.push(0.5 * g.positions[1 + k]); // on an inner edge
                targets
                    .push(g.positions[1 + k] * 0.25 + g.positions[1 + (k + 1) % n as usize] * 0.25);
            }
            for target in targets {
                for origin in [
                    DVec3::new(0.0, 0.0, 3.0),
                    DVec3::new(0.3, -0.7, 2.0),
                    DVec3::new(-1.0, 0.5, -4.0),
                    DVec3::new(2.0, 2.0, 0.5),
                ] {
                    let ray = TraceRay::new(origin, target - origin).expect("finite");
                    assert_eq!(hits(&g, &ray), 1, "fan {n}, target {target}, origin {origin}");
                    let t = (0..g.len()).find_map(|t| ray.intersect(&g.corners(t)));
                    assert!((t.expect("hit") - 1.0).abs() < 1e-12);
                }
            }
        }
    }

    /// Exactly-zero edge functions: a 2 x 2 grid of unit quads (8 triangles, diagonals both
    /// ways) hit along dyadic directions through every vertex and edge midpoint, where the
    /// shear is exact and the ray's point lands exactly on the edges.
    #[test]
    fn exact_edge_and_vertex_hits_belong_to_one_triangle() {
        let positions: Vec<DVec3> =
            (0..9).map(|k| DVec3::new(f64::from(k % 3), f64::from(k / 3), 0.0)).collect();
        let mut triangles = Vec::new();
        for (qx, qy) in [(0u32, 0u32), (1, 0), (0, 1), (1, 1)] {
            let v = |dx: u32, dy: u32| (qy + dy) * 3 + qx + dx;
            if (qx + qy) % 2 == 0 {
                triangles.extend([[v(0, 0), v(1, 0), v(1, 1)], [v(0, 0), v(1, 1), v(0, 1)]]);
            } else {
                triangles.extend([[v(0, 0), v(1, 0), v(0, 1)], [v(1, 1), v(0, 1), v(1, 0)]]);
            }
        }
        let g = geometry(positions, triangles);
        for dir in [
            DVec3::NEG_Z,
            DVec3::new(0.5, 0.25, -1.0),
            DVec3::new(-0.25, 0.5, -1.0),
            DVec3::new(0.125, -0.375, 1.0),
        ] {
            for x2 in 1..4 {
                for y2 in 1..4 {
                    let target = DVec3::new(f64::from(x2) * 0.5, f64::from(y2) * 0.5, 0.0);
                    let ray = TraceRay::new(target - 4.0 * dir, dir).expect("finite");
                    assert_eq!(hits(&g, &ray), 1, "{dir} through {target}");
                }
            }
        }
    }

    #[test]
    fn degenerate_and_parallel_triangles_are_missed() {
        let ray = TraceRay::new(DVec3::new(0.1, 0.1, 5.0), DVec3::NEG_Z).expect("finite");
        let line = [DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0)];
        let point = [DVec3::ONE; 3];
        let edge_on = [DVec3::ZERO, DVec3::Z, DVec3::new(1.0, 1.0, 0.0)];
        for tri in [line, point, edge_on] {
            assert_eq!(ray.intersect(&tri), None);
        }
        assert!(TraceRay::new(DVec3::ZERO, DVec3::ZERO).is_none());
        assert!(TraceRay::new(DVec3::NAN, DVec3::X).is_none());
        let g = geometry(line.to_vec(), vec![[0, 1, 2]]);
        let accel = Accel::build(&g, |_| true, |_| 0.0, BvhFrame::fit(&g, &[ray.origin]));
        assert!(accel.ids.is_empty());
        assert_eq!(accel.closest(&ray, 0.0, f64::INFINITY), None);
        assert_eq!(accel.transmittance(&ray, 0.0, f64::INFINITY, u32::MAX), 1.0);
    }

    #[test]
    fn single_triangle_bvh_finds_its_hit() {
        let g = geometry(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]);
        let ray = TraceRay::new(DVec3::new(0.2, 0.2, 2.0), DVec3::NEG_Z).expect("finite");
        let accel = Accel::build(&g, |_| true, |_| 0.25, BvhFrame::fit(&g, &[ray.origin]));
        assert!(accel.frame.bvh_ray(&ray, f64::INFINITY).is_some());
        assert_eq!(accel.closest(&ray, 0.0, f64::INFINITY), Some((2.0, 0)));
        assert_eq!(accel.transmittance(&ray, 0.0, f64::INFINITY, u32::MAX), 0.25);
        assert_eq!(accel.transmittance(&ray, 0.0, f64::INFINITY, 0), 1.0);
        assert_eq!(accel.transmittance(&ray, 0.0, 1.5, u32::MAX), 1.0);
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
        let accel = Accel::build(&g, |_| true, |_| 0.0, BvhFrame::fit(&g, &[eye]));
        let up = -DVec3::new(0.0, -1.0, 0.0);
        assert!(up.x.is_sign_negative() && up.z.is_sign_negative());
        let ray = TraceRay::new(DVec3::new(0.1, 0.0, 0.2), up).expect("finite");
        assert_eq!(accel.closest(&ray, 0.0, f64::INFINITY), Some((2.0, 0)));
        assert_eq!(accel.transmittance(&ray, 1e-9, f64::INFINITY, u32::MAX), 0.0);
        let down = TraceRay::new(eye, DVec3::new(-0.0, -1.0, -0.0));
        assert!(accel.closest(&down.expect("finite"), 0.0, f64::INFINITY).is_some());
    }

    /// Camera rays aimed exactly at every vertex and edge midpoint of a closed icosphere, and a
    /// dense fan of rays across its silhouette, through the full BVH path: none whose line
    /// passes inside the inscribed ball may miss.
    #[test]
    fn closed_sphere_has_no_gaps() {
        let params = SpheresParams { count: 1, subdivisions: 4, ..Default::default() };
        let mesh = params.generate();
        let g = geometry(mesh.positions.clone(), mesh.triangles.clone());
        let (lo, hi) = bounds(&g).expect("non-empty");
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
        let accel = Accel::build(&g, |_| true, |_| 0.0, BvhFrame::fit(&g, &eyes));
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
                assert!(accel.frame.bvh_ray(&ray, f64::INFINITY).is_some());
                let off_axis = (centre - eye).cross(dir).length() / dir.length();
                if off_axis < r_in * (1.0 - 1e-9) {
                    tested += 1;
                    assert!(accel.closest(&ray, 0.0, f64::INFINITY).is_some(), "{eye} -> {target}");
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
        let accel = Accel::build(&g, |_| true, |_| 0.0, BvhFrame::fit(&g, &[eye]));
        let towards = DVec3::new(0.3, 1.0, 0.2).normalize();
        let (mut shadowed, mut brute) = (0, 0);
        for j in 0..64 {
            for i in 0..64 {
                let local = DVec3::new(f64::from(i) / 8.0 - 4.0, 0.0, f64::from(j) / 8.0 - 4.0);
                let p = place(local);
                let ray = TraceRay::new(p, towards).expect("finite");
                let t = shadow_offset(eye, p);
                if accel.transmittance(&ray, t, f64::INFINITY, u32::MAX) == 0.0 {
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
            let accel = Accel::build(&g, |_| true, |_| 0.0, BvhFrame::fit(&g, &[eye]));
            let p = DVec3::new(0.0, 0.0, 0.0);
            let ray = TraceRay::new(p, DVec3::Y).expect("finite");
            let t = shadow_offset(eye, p);
            assert!(t < h);
            assert_eq!(accel.transmittance(&ray, t, f64::INFINITY, 0), 0.0, "scale {scale}");
        }
    }
}
