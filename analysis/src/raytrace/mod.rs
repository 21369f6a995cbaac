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
//! comparisons sample by sample. `exact` traces its few `edge` pixels by [`listed`]: each ray
//! tested against the triangles it lists for it, without BVHs, every decision the same.
//!
//! Stages: [`STAGE_BVH_BUILD`] ("BVH build": binary BVHs built by obvhs over all triangles
//! for camera rays and, when some triangle does not cast shadows, over the casters, each set
//! split into clusters of its own, see below) and [`STAGE_RAY_TRACING`] ("ray tracing", rayon
//! over bands of rows, by packets, see below). Counter: `rays_traced` = camera rays
//! (`W * H * rate`) + shadow rays (one per sub-sample that hit a surface), summed from
//! per-band counts. [`SampleImage::triangle_tests`] counts the ray-triangle tests, the work the
//! BVHs leave.
//!
//! # Packets
//!
//! The rays are traced by coherent packets of up to 256 (`packet::PACKET`): a band of rows is
//! cut into tiles of `256 / rate` pixels (16 x 16 pixel centres at rate 1, 2 x 2 pixels at rate
//! 64, one pixel in runs of 256 sub-samples above), whose sub-samples, the pixels in Z order,
//! form one packet of camera rays; the shadow rays of those that hit form the next packet
//! (parallel for a directional light, whose set-up they share), put in Z order of their
//! origins seen along the light where the hits scatter in depth (`order`). Each packet walks each
//! cluster's BVH together, one `f32` test of a node serving every ray (the first of the
//! active groups of four rays, interval bounds of the packet: `packet`), and each ray decides
//! its own hits in `f64` at the leaves, exactly as a ray traced alone would. Wald, Benthin,
//! Wagner and Slusallek, "Interactive Rendering with Coherent Ray Tracing" (Eurographics
//! 2001), Wald, Boulos and Shirley, "Ray Tracing Deformable Scenes Using Dynamic Bounding
//! Volume Hierarchies" (ACM TOG 26(1), 2007) and Overbeck, Ramamoorthi and Mark, "Large Ray
//! Packets for Real-Time Whitted Ray Tracing" (IRT 2008).
//!
//! obvhs builds the trees (PLOC; a cluster of more than 2^15 triangles in parts, halved at
//! median box centres, built in parallel and joined: `accel`) but its traversals cannot be
//! driven by packets: they take one ray, keep their stack and node test to themselves (the
//! CWBVH's sorts children by the ray's octant and ignores boxes left before frame distance
//! 1e-4), and call back per primitive only. The traversal is therefore our own, over obvhs'
//! binary tree converted to nodes that hold both children's boxes (`bvh`: half the node loads,
//! a quarter of the traversal's time on bunny-plane with obvhs' own nodes); its per-ray slab
//! test is obvhs' own, lane by lane.
//!
//! Measured against Embree 3's per-ray API (`scripts/embree-bench`, one run, BVH build +
//! camera + shadow rays on both sides, wall-clock medians of 3 interleaved runs, ours /
//! Embree; load average 1.0-1.9 on two cores, mostly the bench's own threads):
//!
//! | | bunny-plane | cage | random-1m |
//! |---|---|---|---|
//! | rate 1 (frames of 800 x 600, 1024 x 768), 1 thread | 0.80 | 0.87 | 0.94 |
//! | rate 1, 2 threads | 0.90 | 0.87 | 1.05 |
//! | rate 64 (320 x 240), 1 thread | 0.59 | 0.55 | 0.98 |
//! | rate 64, 2 threads | 0.62 | 0.58 | 0.98 |
//!
//! Rate 1 was 1.13 on bunny-plane and 1.05 on cage before the changes below, none of which
//! changed a sample. Branches the processor could not predict cost more than the `f64`
//! arithmetic:
//!
//! - a packet's lanes written through `Vec4`'s `IndexMut`, a jump on the lane (on
//!   bunny-plane, callgrind's `--branch-sim=yes` counted 1.16 million of its 1.17 million
//!   indirect jumps mispredicted);
//! - the triangle test's sign check as a chain of short circuits;
//! - a leaf's loop over the lanes of each group.
//!
//! Each is now evaluated without a branch per comparison or per lane (`packet`, `ray`). The
//! camera rays take their per-column and per-row parts from tables made once per frame
//! (`Projector::grid_rays`), not two divisions per ray. On random-1m (a million scattered
//! triangles) the packets' node tests are two thirds of the profile at rate 64: the boxes of
//! random triangles overlap, and a million nodes do not stay in cache. Keeping each node's
//! active groups as bits (`packet`) took a tenth off there. Packets of 128 rays made its
//! tracing 15-38 % slower at rates 1 and 64, and of 512 (with 128-bit masks) 10-13 % slower;
//! bunny-plane's changed within the noise (as with 64 and 128 before the bits).
//! Computing each triangle's box once for the clusters' seven passes instead of gathering its
//! corners at each saved 0-40 ms of 600 (within the noise) and was left out.
//!
//! Hot path: the packets' buffers are a band's, reused from packet to packet; no allocation
//! per ray or packet; one `f64` clip per ray and cluster, then `f32` group tests and `f64`
//! triangle tests only where a ray's own box test hits. Results do not depend on the thread
//! count: bands, tiles and packets are fixed by the image, and a ray's hits by its own tests.
//! With transparency, the product of the transmittances a shadow ray meets follows the order
//! in which the traversal meets them (as it did with obvhs' traversal), which rounding can
//! tell apart in the last bit when three or more different opacities lie on one ray.
//!
//! Memory: the tracer's own buffers (triangle copies, per-sample and per-pixel results) are
//! allocated fallibly; one that cannot be had is an [`AllocationError`] (as a
//! [`ReferenceError::NotApplicable`] through [`Reference::evaluate`]) naming its size and the
//! run's [`memory_estimate`]. obvhs' own allocations inside its build cannot be made fallible;
//! each build is preceded by a probe of its size (see `memory`). The two largest buffers, the
//! slots' corners and the BVH's nodes, are kept when a run ends and reused by the next run in
//! the process, whose build would otherwise first touch them page by page (`memory::Spare`).
//!
//! # Precision: f32 BVH, f64 triangles
//!
//! obvhs is `f32`-only (boxes, rays, its Möller-Trumbore test), and so are the packets' node
//! tests. The BVHs are used only to *find candidates*; every hit decision is made in `f64` by
//! our own triangle test (called at the leaves with the BVH slot, i.e. the position in obvhs'
//! `primitive_indices`, whose triangles we store in that order): Woop, Benthin and Wald's
//! watertight ray-triangle test (JCGT 2013), double-sided. What makes the `f32` search lose nothing, whatever the scene's
//! size and position (tested from scale 1e-6 to 1e6, translations of 1e7, objects 1e12 away),
//! and keeps its cost independent of a far object:
//!
//! - **Clusters**: the triangles are split around the per-axis median of their box centres;
//!   those whose farthest corner lies within 64 (median radius + median triangle size) of it
//!   form one cluster (at least half of them), the others are split again the same way. The
//!   medians are those of a sample of 4,096 boxes, evenly strided, or of all when the sample's
//!   keep fewer than half (the medians of every box took 18 ms of random-1m's 496 ms build at
//!   one thread, and 1.4 of bunny-plane's 22.5). A far object is a cluster of its own, so it
//!   neither stretches the main cluster's box padding nor the resolution of obvhs' Morton
//!   codes (one triangle 1e6 away once made every ray test a large part of the scene).
//! - **Its own frame** per cluster: its BVH is built and traversed in world coordinates minus
//!   the cluster's centre times a power of two near the inverse of its median triangle size.
//!   Every cluster looks to obvhs like one of unit triangles near the origin. Frame coordinates
//!   are kept below 1e15 so that obvhs' `f32` areas stay finite.
//! - **Rays clipped to the cluster**: each ray is clipped in `f64` to the cluster's box,
//!   enlarged by 1/64 of its extent and by a bound of the clip's rounding (the clip multiplies
//!   by the ray's reciprocal direction, one rounding more than a quotient, well within that
//!   bound); a ray that misses it
//!   within its range skips the cluster, the others start their frame ray at the entry point.
//!   The frame ray's start thus lies within the cluster's reach (its extent plus 1/32), whatever
//!   the ray's origin (the camera, another cluster). A ray from so far away that the `f64`
//!   rounding of its entry point exceeds half an `f32` epsilon of the reach (about 1e7 reaches
//!   away) tests the cluster's triangles one by one instead.
//! - **Padding from local magnitudes**: each box is computed in `f64` in the frame and padded
//!   by 32 `f32` epsilons of (its own largest coordinate + the reach) before rounding to `f32`:
//!   that covers the rounding of the ray's start and direction, obvhs' reciprocal of direction
//!   components below `f32::EPSILON` (clamped to `1/EPSILON`, a drift of `EPSILON` per unit
//!   travelled: the frame direction is the ray's scaled by a power of two to a largest
//!   component in [1, 2), so a unit of frame parameter is at least a unit of distance), the
//!   slab tests and the entry point's `f64` rounding.
//! - **No start shift**: a box is entered when the ray's exit from it lies at frame parameter
//!   0 or beyond, so a box the rounded start lies in (an occluder in contact with the receiver,
//!   whose padded box holds the start) is never culled, at any scale. (obvhs' CWBVH node test
//!   ignored boxes left before frame distance 1e-4; frame rays were started behind the entry
//!   point to make up for it.)
//! - The traversal prunes with `f32` frame distances rounded upwards, never losing the closest
//!   `f64` hit; clusters are visited in turn, each pruned by the closest hit found so far. The
//!   packets share node tests only where they provably change no ray's own test (`packet`).
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

mod accel;
mod bvh;
mod listed;
mod memory;
mod order;
mod packet;
mod ray;

pub(crate) use listed::TriangleLists;
pub use memory::{memory_estimate, AllocationError};

use crate::reference::{Reference, ReferenceError, ReferenceImage};
use accel::{Accel, Scratch};
use glam::DVec3;
use instrumentation::Recorder;
use memory::Allocator;
use methods::{afsm::shadow_offset, pattern::SamplePattern, Frame};
use packet::PACKET;
use ray::TraceRay;
use rayon::prelude::*;
use scenes::{
    projection::{GridRays, ProjectionKind},
    Geometry, Light,
};

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
    /// A directional light: the ray from the origin along the unit direction towards it,
    /// whose set-up every shadow ray shares (they are parallel).
    Towards(TraceRay),
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

impl From<AllocationError> for ReferenceError {
    /// A buffer the ray tracer could not have: the scene and frame are too large for the
    /// machine (bad input), as the message says with the estimate and what to lower.
    fn from(e: AllocationError) -> Self {
        ReferenceError::NotApplicable(e.to_string())
    }
}

/// Everything the rays of one frame share: acceleration structures, light, camera set-up.
struct Tracer<'a> {
    frame: &'a Frame<'a>,
    pattern: &'a SamplePattern,
    camera_accel: Accel,
    /// The casters' BVH, when some triangle does not cast shadows (else the camera's).
    caster_accel: Option<Accel>,
    rays: RaySetup,
    /// The run's buffers, allocated fallibly.
    alloc: Allocator,
}

/// How a frame's camera and shadow rays are made: the same numbers whether they are traced
/// through BVHs ([`Tracer`]) or against listed triangles ([`listed`]).
#[derive(Debug, Clone, Copy)]
struct RaySetup {
    light: LightSource,
    /// Camera rays start this far along their direction (orthographic cameras start behind
    /// the scene), and accept hits from `camera_tmin`.
    start_shift: f64,
    camera_tmin: f64,
}

impl RaySetup {
    /// The set-up of `frame`'s rays; an error when its light has no direction or position.
    fn new(frame: &Frame<'_>) -> Result<Self, ReferenceError> {
        let light = match frame.scene.light {
            Light::Directional { direction } => {
                let towards =
                    scenes::direction::unit(direction).and_then(|d| TraceRay::new(DVec3::ZERO, -d));
                let Some(towards) = towards else {
                    return Err(ReferenceError::NotApplicable(format!(
                        "raytrace: the directional light of scene `{}` has no direction",
                        frame.scene.name
                    )));
                };
                LightSource::Towards(towards)
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
        // Camera rays: perspective from depth `near`; orthographic from behind the scene.
        let camera = &frame.camera;
        let (start_shift, camera_tmin) = match camera.kind {
            ProjectionKind::Perspective { .. } => (0.0, camera.near),
            ProjectionKind::Orthographic { .. } => {
                let (lo, hi) = bounds(&frame.geometry).unwrap_or((DVec3::ZERO, DVec3::ZERO));
                let nearest = scenes::mesh::box_corners(lo, hi)
                    .iter()
                    .map(|&c| camera.depth_of(c))
                    .fold(f64::INFINITY, f64::min);
                (nearest.min(0.0) - (hi - lo).length() * 1e-3, 0.0)
            }
        };
        Ok(Self { light, start_shift, camera_tmin })
    }

    /// The camera ray of sub-sample `s` of pixel `(i, j)`; `None` when it has none (the
    /// sub-sample is background).
    #[inline(always)]
    fn camera(
        &self,
        frame: &Frame<'_>,
        pattern: &SamplePattern,
        (i, j, s): (u32, u32, usize),
    ) -> Option<TraceRay> {
        self.camera_along(frame.camera.ray(pattern.point(i, j, s)))
    }

    /// The camera ray along `r`, the camera's ray through a sub-sample.
    #[inline(always)]
    fn camera_along(&self, r: scenes::projection::Ray) -> Option<TraceRay> {
        TraceRay::new(r.origin + self.start_shift * r.direction, r.direction)
    }

    /// The shadow ray from the point where `camera` meets a surface at `t`, with the range
    /// `(tmin, tmax)` of the hits that block it; `None` when the point is lit without a ray
    /// (it lies at the light, or the ray is degenerate).
    #[inline(always)]
    fn shadow(&self, camera: &TraceRay, t: f64) -> Option<(TraceRay, (f64, f64))> {
        let (origin, p) = (camera.origin, camera.at(t));
        let (ray, tmax) = match self.light {
            LightSource::Towards(towards) => (towards.from(p), f64::INFINITY),
            LightSource::At(q) => {
                (scenes::direction::unit(q - p).and_then(|d| TraceRay::new(p, d)), (q - p).length())
            }
        };
        let tmin = shadow_offset(origin, p);
        ray.filter(|_| tmax > tmin).map(|ray| (ray, (tmin, tmax)))
    }
}

impl<'a> Tracer<'a> {
    /// Builds the BVHs (stage [`STAGE_BVH_BUILD`]) and the ray set-up for `frame`, whose rays
    /// will trace `samples` sub-samples, over the triangles `t` with `among[t]` (all with
    /// `None`).
    fn new(
        frame: &'a Frame<'a>,
        pattern: &'a SamplePattern,
        samples: u64,
        among: Option<&[bool]>,
        rec: &mut Recorder,
    ) -> Result<Self, ReferenceError> {
        let among = |t: usize| among.is_none_or(|a| a[t]);
        let rays = RaySetup::new(frame)?;
        let geometry = &frame.geometry;
        let transparency = frame.effects.transparency;
        let objects = &frame.scene.objects;
        let pass = |t: usize| {
            if transparency {
                objects.get(geometry.object[t] as usize).map_or(0.0, |o| 1.0 - o.material.opacity)
            } else {
                0.0
            }
        };

        // Triangles in the BVHs: all of them, and the casters again when some triangle casts
        // no shadow.
        let casters = (0..geometry.len()).filter(|&t| frame.is_caster(t)).count();
        let in_bvhs = geometry.len() + if casters < geometry.len() { casters } else { 0 };
        let alloc = Allocator { estimate: memory_estimate(in_bvhs as u64, samples) };
        let (camera_accel, caster_accel) = rec.stages.time(STAGE_BVH_BUILD, || {
            let all = Accel::build(geometry, among, pass, &alloc)?;
            let casters = if casters < geometry.len() {
                Some(Accel::build(geometry, |t| among(t) && frame.is_caster(t), pass, &alloc)?)
            } else {
                None
            };
            Ok::<_, AllocationError>((all, casters))
        })?;

        Ok(Self { frame, pattern, camera_accel, caster_accel, rays, alloc })
    }

    /// The parts of the camera rays of every sub-sample of the frame (per column and per row
    /// of sub-sample points, not two divisions per ray): `(width + height) * rate` vectors of
    /// 24 bytes, within the per-sample term of [`memory_estimate`] (48 bytes a sub-sample).
    fn camera_rays(&self) -> GridRays {
        let size = (self.frame.width() as usize, self.frame.height() as usize);
        self.frame.camera.grid_rays(size, self.pattern.offsets())
    }

    /// Pixels per packet tile `(width, height)` at `rate` sub-samples per pixel: `PACKET /
    /// rate` pixels (one pixel above [`PACKET`] sub-samples), as square as a power of two
    /// allows: 8 x 8 pixel centres at rate 1, 4 x 4 pixels at rate 4, one pixel at rate 64.
    fn tile(rate: usize) -> (u32, u32) {
        let pixels = (PACKET / rate.max(1)).max(1);
        let height = 1usize << (pixels.ilog2() / 2);
        ((pixels / height) as u32, height as u32)
    }

    /// Traces the sub-samples of the pixels of rows `rows` where `wanted(i, j)`, a tile at a
    /// time, and hands each one's result to `emit(i, j, s, hit)`, a pixel's sub-samples in
    /// order.
    fn trace_band(
        &self,
        camera_rays: &GridRays,
        rows: std::ops::Range<u32>,
        wanted: &impl Fn(u32, u32) -> bool,
        work: &mut Work,
        emit: &mut impl FnMut(u32, u32, usize, SampleHit),
    ) {
        let rate = self.pattern.rate() as usize;
        let (tile_w, tile_h) = Self::tile(rate);
        let side = tile_w.max(tile_h).next_power_of_two();
        let w = self.frame.width();
        for i0 in (0..w).step_by(tile_w as usize) {
            // The tile's pixels in Z order, so that each lane group (and each run of groups)
            // covers a compact block of pixels.
            for (x, y) in (0..side * side).map(scenes::morton::point) {
                let (i, j) = (i0 + x, rows.start + y);
                if x >= tile_w || i >= w || j >= rows.end || !wanted(i, j) {
                    continue;
                }
                for s in 0..rate {
                    work.ids.push((i, j, s));
                    if work.ids.len() == PACKET {
                        self.trace_packet(camera_rays, work, emit);
                    }
                }
            }
            if !work.ids.is_empty() {
                self.trace_packet(camera_rays, work, emit);
            }
        }
    }

    /// The camera rays of the sub-samples in `work.ids` as one packet, then the shadow rays of
    /// those that hit as another; each sub-sample's result goes to `emit`, in order.
    fn trace_packet(
        &self,
        camera_rays: &GridRays,
        work: &mut Work,
        emit: &mut impl FnMut(u32, u32, usize, SampleHit),
    ) {
        let Work { ids, hits, rays, of, best, limits, skip, light, order, scratch, tests } = work;
        rays.clear();
        of.clear();
        hits.clear();
        for &(i, j, s) in ids.iter() {
            let r = camera_rays.ray(&self.frame.camera, i as usize, j as usize, s);
            if let Some(ray) = self.rays.camera_along(r) {
                rays.push(ray);
                of.push(hits.len());
            }
            hits.push(SampleHit { triangle: None, light: 1.0, rays: 1 });
        }
        best.clear();
        best.resize(rays.len(), None);
        let camera_limits = (self.rays.camera_tmin, f64::INFINITY);
        self.camera_accel.closest(rays, camera_limits, best, scratch, tests);

        // The shadow rays replace the camera rays in `rays` and `of`.
        let mut n = 0;
        limits.clear();
        skip.clear();
        for c in 0..rays.len() {
            let Some((t, id)) = best[c] else { continue };
            let k = of[c];
            hits[k] = SampleHit { triangle: Some(id), light: 1.0, rays: 2 };
            // A point at the light (or a degenerate ray) is lit.
            if let Some((ray, range)) = self.rays.shadow(&rays[c], t) {
                (rays[n], of[n]) = (ray, k);
                limits.push(range);
                skip.push(id);
                n += 1;
            }
        }
        order.sort(n, rays, of, limits, skip);
        light.clear();
        light.resize(n, 1.0);
        let casters = self.caster_accel.as_ref().unwrap_or(&self.camera_accel);
        casters.transmittance(&rays[..n], (limits, skip), light, scratch, tests);
        for (&k, &l) in of[..n].iter().zip(light.iter()) {
            hits[k].light = l;
        }
        for (&(i, j, s), &hit) in ids.iter().zip(hits.iter()) {
            emit(i, j, s, hit);
        }
        ids.clear();
    }
}

/// A thread's buffers for tracing packets, reused from packet to packet (at most [`PACKET`]
/// entries each).
#[derive(Default)]
struct Work {
    /// The packet's sub-samples: pixel `(i, j)` and sub-sample index.
    ids: Vec<(u32, u32, usize)>,
    /// Each sub-sample's result.
    hits: Vec<SampleHit>,
    /// The camera rays of the sub-samples that have one, then the shadow rays.
    rays: Vec<TraceRay>,
    /// The sub-sample (index into `ids`) of each ray.
    of: Vec<usize>,
    /// Each camera ray's closest hit.
    best: Vec<Option<(f64, u32)>>,
    /// Each shadow ray's range and the triangle it leaves.
    limits: Vec<(f64, f64)>,
    skip: Vec<u32>,
    /// Each shadow ray's light.
    light: Vec<f64>,
    /// The shadow rays' order.
    order: order::Order,
    scratch: Scratch,
    /// Ray-triangle tests made.
    tests: u64,
}

/// The pixel results of a band of rows (row-major).
struct Band {
    lit: Vec<f64>,
    evaluated: Vec<bool>,
    rays: u64,
}

/// The sub-sample results of a band of rows (row-major, a pixel's sub-samples together).
struct SampleBand {
    triangle: Vec<u32>,
    light: Vec<f64>,
    rays: u64,
    tests: u64,
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
    /// Ray-triangle tests made by the camera and shadow rays of every sub-sample: the work
    /// the BVHs left to the `f64` test (the tracer's `Recorder` counts only rays).
    pub triangle_tests: u64,
}

impl RayTrace {
    /// Traces every sub-sample of `frame` and returns each one's hit and light (stages and
    /// counters as [`Reference::evaluate`]).
    pub fn sample_image(
        &self,
        frame: &Frame<'_>,
        rec: &mut Recorder,
    ) -> Result<SampleImage, ReferenceError> {
        let (w, h) = (frame.width(), frame.height());
        let rate = self.pattern.rate() as usize;
        let per_row = w as usize * rate;
        let n = per_row * h as usize;
        let tracer = Tracer::new(frame, &self.pattern, n as u64, None, rec)?;
        let alloc = tracer.alloc;
        let (_, band_h) = Tracer::tile(rate);
        let bands = rec.stages.time(STAGE_RAY_TRACING, || {
            let camera_rays = tracer.camera_rays();
            (0..h.div_ceil(band_h))
                .into_par_iter()
                .map(|b| {
                    let rows = b * band_h..((b + 1) * band_h).min(h);
                    let len = per_row * rows.len();
                    let mut band = SampleBand {
                        triangle: alloc.vec(len, "the sub-samples' triangles")?,
                        light: alloc.vec(len, "the sub-samples' light")?,
                        rays: 0,
                        tests: 0,
                    };
                    band.triangle.resize(len, methods::raster::NO_TRIANGLE);
                    band.light.resize(len, 1.0);
                    let mut work = Work::default();
                    let j0 = rows.start;
                    tracer.trace_band(
                        &camera_rays,
                        rows,
                        &|_, _| true,
                        &mut work,
                        &mut |i, j, s, hit| {
                            let k = (j - j0) as usize * per_row + i as usize * rate + s;
                            band.triangle[k] = hit.triangle.unwrap_or(methods::raster::NO_TRIANGLE);
                            band.light[k] = hit.light;
                            band.rays += hit.rays;
                        },
                    );
                    band.tests = work.tests;
                    Ok(band)
                })
                .collect::<Result<Vec<SampleBand>, AllocationError>>()
        })?;
        rec.counters.rays_traced += bands.iter().map(|b| b.rays).sum::<u64>();
        let triangle_tests = bands.iter().map(|b| b.tests).sum();
        let mut triangle = alloc.vec(n, "the sub-samples' triangles")?;
        let mut light = alloc.vec(n, "the sub-samples' light")?;
        for band in bands {
            triangle.extend(band.triangle);
            light.extend(band.light);
        }
        Ok(SampleImage { width: w, height: h, rate: rate as u32, triangle, light, triangle_tests })
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
    /// (1) and not evaluated, and cost no ray.
    pub fn evaluate_pixels(
        &self,
        frame: &Frame<'_>,
        mask: Option<&[bool]>,
        rec: &mut Recorder,
    ) -> Result<ReferenceImage, ReferenceError> {
        self.evaluate_pixels_among(frame, mask, None, rec)
    }

    /// [`Self::evaluate_pixels`] with the BVHs built over the triangles `t` with `among[t]`
    /// only (all with `None`): the caller vouches that every triangle the camera rays of the
    /// `mask` pixels and the shadow rays from their hits can meet is among them, so every
    /// decision is the same as over all triangles. `exact` uses it for its `edge` pixels.
    pub fn evaluate_pixels_among(
        &self,
        frame: &Frame<'_>,
        mask: Option<&[bool]>,
        among: Option<&[bool]>,
        rec: &mut Recorder,
    ) -> Result<ReferenceImage, ReferenceError> {
        let (w, h) = (frame.width(), frame.height());
        let rate = self.pattern.rate() as usize;
        let n = (w as usize) * (h as usize);
        let tracer = Tracer::new(frame, &self.pattern, (n * rate) as u64, among, rec)?;
        let alloc = tracer.alloc;
        let wanted = |i: u32, j: u32| mask.is_none_or(|m| m[(j * w + i) as usize]);
        let (_, band_h) = Tracer::tile(rate);
        let bands = rec.stages.time(STAGE_RAY_TRACING, || {
            let camera_rays = tracer.camera_rays();
            (0..h.div_ceil(band_h))
                .into_par_iter()
                .map(|b| {
                    let rows = b * band_h..((b + 1) * band_h).min(h);
                    let len = w as usize * rows.len();
                    let mut band = Band {
                        lit: alloc.vec(len, "the pixels' lit fractions")?,
                        evaluated: alloc.vec(len, "the pixels' evaluated flags")?,
                        rays: 0,
                    };
                    // Sums of the sub-samples' light and whether all hit, then the results.
                    band.lit.resize(len, 0.0);
                    band.evaluated.resize(len, true);
                    let mut work = Work::default();
                    let j0 = rows.start;
                    tracer.trace_band(
                        &camera_rays,
                        rows.clone(),
                        &wanted,
                        &mut work,
                        &mut |i, j, _, hit| {
                            let k = ((j - j0) * w + i) as usize;
                            band.lit[k] += hit.light;
                            band.evaluated[k] &= hit.triangle.is_some();
                            band.rays += hit.rays;
                        },
                    );
                    for (k, (lit, evaluated)) in
                        band.lit.iter_mut().zip(band.evaluated.iter_mut()).enumerate()
                    {
                        let (i, j) = (k as u32 % w, j0 + k as u32 / w);
                        if wanted(i, j) {
                            *lit = (*lit / rate as f64).clamp(0.0, 1.0);
                        } else {
                            (*lit, *evaluated) = (1.0, false);
                        }
                    }
                    Ok(band)
                })
                .collect::<Result<Vec<Band>, AllocationError>>()
        })?;

        rec.counters.rays_traced += bands.iter().map(|b| b.rays).sum::<u64>();
        let mut lit = alloc.vec(n, "the pixels' lit fractions")?;
        let mut evaluated = alloc.vec(n, "the pixels' evaluated flags")?;
        for band in bands {
            lit.extend(band.lit);
            evaluated.extend(band.evaluated);
        }
        let transmittance = if frame.effects.transparency {
            let mut t = alloc.vec(n, "the pixels' transmittance")?;
            t.extend(lit.iter().map(|&v| [v; 3]));
            Some(t)
        } else {
            None
        };
        Ok(ReferenceImage { width: w, height: h, lit, evaluated, transmittance, classes: None })
    }
}
