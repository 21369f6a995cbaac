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
//! Stages: [`STAGE_BVH_BUILD`] ("BVH build": obvhs CWBVHs over all triangles for camera rays
//! and, when some triangle does not cast shadows, over the casters, each set split into
//! clusters of its own, see below) and [`STAGE_RAY_TRACING`] ("ray tracing", rayon over rows).
//! Counter: `rays_traced` = camera rays (`W * H * rate`) + shadow rays (one per sub-sample that
//! hit a surface), summed from per-row counts. [`SampleImage::triangle_tests`] counts the
//! ray-triangle tests, the work the BVHs leave.
//!
//! Memory: the tracer's own buffers (triangle copies, per-sample and per-pixel results) are
//! allocated fallibly; one that cannot be had is an [`AllocationError`] (as a
//! [`ReferenceError::NotApplicable`] through [`Reference::evaluate`]) naming its size and the
//! run's [`memory_estimate`]. obvhs' own allocations inside its build cannot be made fallible;
//! each build is preceded by a probe of its size (see `memory`).
//!
//! # Precision: f32 BVH, f64 triangles
//!
//! obvhs is `f32`-only (boxes, rays, its Möller-Trumbore test). It is used only to *find
//! candidates*; every hit decision is made in `f64` by our own triangle test (called from
//! obvhs' traversal closures with the BVH slot, i.e. the position in `primitive_indices`, whose
//! triangles we store in that order): Woop, Benthin and Wald's watertight ray-triangle test
//! (JCGT 2013), double-sided. What makes the `f32` search lose nothing, whatever the scene's
//! size and position (tested from scale 1e-6 to 1e6, translations of 1e7, objects 1e12 away),
//! and keeps its cost independent of a far object:
//!
//! - **Clusters**: the triangles are split around the per-axis median of their box centres;
//!   those whose farthest corner lies within 64 (median radius + median triangle size) of it
//!   form one cluster (at least half of them), the others are split again the same way. A far
//!   object is a cluster of its own, so it neither stretches the main cluster's box padding
//!   nor the resolution of obvhs' Morton codes (one triangle 1e6 away once made every ray test
//!   a large part of the scene).
//! - **Its own frame** per cluster: its BVH is built and traversed in world coordinates minus
//!   the cluster's centre times a power of two near the inverse of its median triangle size.
//!   Every cluster looks to obvhs like one of unit triangles near the origin. Frame coordinates
//!   are kept below 1e15 so that obvhs' `f32` areas stay finite.
//! - **Rays clipped to the cluster**: each ray is clipped in `f64` to the cluster's box,
//!   enlarged by 1/64 of its extent and by a bound of the clip's rounding; a ray that misses it
//!   within its range skips the cluster, the others start their frame ray at the entry point.
//!   The frame ray's start thus lies within the cluster's reach (its extent plus 1/32), whatever
//!   the ray's origin (the camera, another cluster). A ray from so far away that the `f64`
//!   rounding of its entry point exceeds half an `f32` epsilon of the reach (about 1e7 reaches
//!   away) tests the cluster's triangles one by one instead.
//! - **Padding from local magnitudes**: each box is computed in `f64` in the frame and padded
//!   by 32 `f32` epsilons of (its own largest coordinate + the reach) before rounding to `f32`:
//!   that covers the rounding of the ray's start and direction, obvhs' reciprocal of direction
//!   components below `f32::EPSILON` (clamped to `1/EPSILON`, a drift of `EPSILON` per unit
//!   travelled), its slab tests and the entry point's `f64` rounding.
//! - **Start shift**: obvhs' CWBVH node test ignores children left before frame distance 1e-4
//!   (its `EPSILON`); frame rays therefore start `2e-4` (plus 8 `f32` ulps of the start) behind
//!   the entry point, and frame parameters map back by that shift. Occluders in contact with
//!   the receiver are found at any scale.
//! - The traversal prunes with `f32` frame distances rounded upwards, never losing the closest
//!   `f64` hit; clusters are visited in turn, each pruned by the closest hit found so far.
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
mod memory;
mod ray;

pub use memory::{memory_estimate, AllocationError};

use crate::reference::{Reference, ReferenceError, ReferenceImage};
use accel::Accel;
use glam::DVec3;
use instrumentation::Recorder;
use memory::Allocator;
use methods::{afsm::shadow_offset, pattern::SamplePattern, Frame};
use ray::TraceRay;
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
    /// Ray-triangle tests made by both rays.
    tests: u64,
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
    light: LightSource,
    /// Camera rays start this far along their direction (orthographic cameras start behind
    /// the scene), and accept hits from `camera_tmin`.
    start_shift: f64,
    camera_tmin: f64,
    /// The run's buffers, allocated fallibly.
    alloc: Allocator,
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

        Ok(Self {
            frame,
            pattern,
            camera_accel,
            caster_accel,
            light,
            start_shift,
            camera_tmin,
            alloc,
        })
    }

    /// The camera ray and the shadow ray of sub-sample `s` of pixel `(i, j)`.
    fn sample(&self, i: u32, j: u32, s: usize) -> SampleHit {
        let r = self.frame.camera.ray(self.pattern.point(i, j, s));
        let origin = r.origin + self.start_shift * r.direction;
        let mut tests = 0;
        let hit = TraceRay::new(origin, r.direction).and_then(|ray| {
            self.camera_accel
                .closest(&ray, self.camera_tmin, f64::INFINITY, &mut tests)
                .map(|(t, id)| (ray.at(t), id))
        });
        let Some((p, id)) = hit else {
            return SampleHit { triangle: None, light: 1.0, rays: 1, tests };
        };
        let (dir, tmax) = match self.light {
            LightSource::Towards(d) => (Some(d), f64::INFINITY),
            LightSource::At(q) => (scenes::direction::unit(q - p), (q - p).length()),
        };
        let tmin = shadow_offset(origin, p);
        let casters = self.caster_accel.as_ref().unwrap_or(&self.camera_accel);
        let light = match dir.and_then(|d| TraceRay::new(p, d)) {
            Some(ray) if tmax > tmin => casters.transmittance(&ray, tmin, tmax, id, &mut tests),
            // The point is at the light (or the ray is degenerate): lit.
            _ => 1.0,
        };
        SampleHit { triangle: Some(id), light, rays: 2, tests }
    }
}

/// One row of pixel results.
struct Row {
    lit: Vec<f64>,
    evaluated: Vec<bool>,
    rays: u64,
}

/// One row of sub-sample results.
struct SampleRow {
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
        let rows = rec.stages.time(STAGE_RAY_TRACING, || {
            (0..h)
                .into_par_iter()
                .map(|j| {
                    let mut row = SampleRow {
                        triangle: alloc.vec(per_row, "the sub-samples' triangles")?,
                        light: alloc.vec(per_row, "the sub-samples' light")?,
                        rays: 0,
                        tests: 0,
                    };
                    for i in 0..w {
                        for s in 0..rate {
                            let hit = tracer.sample(i, j, s);
                            row.triangle.push(hit.triangle.unwrap_or(methods::raster::NO_TRIANGLE));
                            row.light.push(hit.light);
                            row.rays += hit.rays;
                            row.tests += hit.tests;
                        }
                    }
                    Ok(row)
                })
                .collect::<Result<Vec<SampleRow>, AllocationError>>()
        })?;
        rec.counters.rays_traced += rows.iter().map(|r| r.rays).sum::<u64>();
        let triangle_tests = rows.iter().map(|r| r.tests).sum();
        let mut triangle = alloc.vec(n, "the sub-samples' triangles")?;
        let mut light = alloc.vec(n, "the sub-samples' light")?;
        for row in rows {
            triangle.extend(row.triangle);
            light.extend(row.light);
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
        let rows = rec.stages.time(STAGE_RAY_TRACING, || {
            (0..h)
                .into_par_iter()
                .map(|j| {
                    let mut row = Row {
                        lit: alloc.vec(w as usize, "the pixels' lit fractions")?,
                        evaluated: alloc.vec(w as usize, "the pixels' evaluated flags")?,
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
                    Ok(row)
                })
                .collect::<Result<Vec<Row>, AllocationError>>()
        })?;

        let rays: u64 = rows.iter().map(|r| r.rays).sum();
        rec.counters.rays_traced += rays;
        let mut lit = alloc.vec(n, "the pixels' lit fractions")?;
        let mut evaluated = alloc.vec(n, "the pixels' evaluated flags")?;
        for row in rows {
            lit.extend(row.lit);
            evaluated.extend(row.evaluated);
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
