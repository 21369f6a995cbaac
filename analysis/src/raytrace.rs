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
//!    excluding the hit triangle itself and starting at [`SHADOW_RAY_OFFSET`] times the scene's
//!    bounding-box diagonal. Opaque scenes (no `transparency` effect, also when the scene file
//!    forces it off): the first caster hit ends the ray (`ray_traverse_miss`). Scenes with
//!    `transparency`: every caster hit along the ray multiplies the transmittance by
//!    `1 - opacity` (an opaque caster ends the ray at 0).
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
//! candidates*: the BVH is built from boxes computed in `f64` and padded outwards by
//! [`BOX_PADDING`] of the scene diagonal plus 8 `f32` ulps of the largest coordinate before
//! rounding to `f32`, so that every box contains its `f64` triangle and absorbs the `f32`
//! rounding of the ray (origin, direction, obvhs' reciprocal direction, which it clamps to
//! `1/f32::EPSILON` for tiny components: the padding is 80 times the distance such a ray
//! drifts across the scene). Every hit decision is made in `f64` by our own triangle test
//! (called from obvhs' traversal closures with the BVH slot, i.e. the position in
//! `primitive_indices`, whose triangles we store in that order): Woop, Benthin and Wald's
//! watertight ray-triangle test (JCGT 2013), double-sided. Consequences: the traversal prunes
//! with `f32` distances rounded upwards (never losing the closest `f64` hit); obvhs' node test
//! clamps the near distance to `f32::EPSILON` (1.2e-7 world units), so a shadow ray also
//! ignores occluders closer than that to its start, which is already below the shadow offset
//! in any scene larger than 120 units and a contact-sized gap otherwise.
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
//!   hits nearer than `1e-9` of the scene diagonal. The hit point lies within about `1e-15` of
//!   the camera distance off its plane, so a coplanar neighbour (a subdivided lit plane, even
//!   under a light 85° from the vertical) is met at most about `1e-13` of the scene size away:
//!   four orders of magnitude inside the offset, so lit planes stay lit. A closed mesh cannot
//!   leak: a shadow ray leaving a point facing away from the light crosses the far side at a
//!   distance of the order of the mesh's thickness, far beyond the offset; only occluders
//!   within `1e-9` of the scene size of the point (contact) are missed.
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
use methods::{pattern::SamplePattern, Frame};
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

/// Shadow rays ignore hits nearer than this fraction of the scene's bounding-box diagonal.
pub const SHADOW_RAY_OFFSET: f64 = 1e-9;

/// BVH boxes are padded outwards by this fraction of the scene's bounding-box diagonal (plus
/// 8 `f32` ulps of the largest coordinate) before rounding to `f32`.
pub const BOX_PADDING: f64 = 1e-5;

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

    /// The `f32` ray obvhs traverses, with `tmax` rounded upwards.
    fn bvh_ray(&self, tmax: f64) -> BvhRay {
        let tmax = if tmax.is_finite() { (tmax * (1.0 + 1e-6)) as f32 } else { f32::INFINITY };
        // `+ 0.0` turns -0.0 into +0.0: obvhs inverts -0.0 to -1/EPSILON but sorts it into the
        // positive octant, which would make every box test miss.
        let dir = |x: f64| x as f32 + 0.0;
        BvhRay::new(
            Vec3A::new(self.origin.x as f32, self.origin.y as f32, self.origin.z as f32),
            Vec3A::new(dir(self.dir.x), dir(self.dir.y), dir(self.dir.z)),
            0.0,
            tmax,
        )
    }
}

/// An `f32` upper bound of a ray parameter, for obvhs' pruning.
#[inline]
fn upper_f32(t: f64) -> f32 {
    (t * (1.0 + 1e-6)) as f32
}

/// A CWBVH over some triangles, with their `f64` corners in BVH slot order.
pub(crate) struct Accel {
    bvh: CwBvh,
    /// Corners of the triangle in each slot (the order of `bvh.primitive_indices`).
    corners: Vec<[DVec3; 3]>,
    /// Triangle id (index into the frame's geometry) of each slot.
    ids: Vec<u32>,
    /// Fraction of light passing through each slot's triangle (`1 - opacity`, or 0).
    pass: Vec<f64>,
}

impl Accel {
    /// Builds the BVH over the triangles `t` of `geometry` with `keep(t)` that have finite
    /// corners and non-zero area; `pass(t)` is the light a triangle lets through.
    pub(crate) fn build(
        geometry: &Geometry,
        keep: impl Fn(usize) -> bool,
        pass: impl Fn(usize) -> f64,
        pad: f64,
    ) -> Self {
        let mut ids = Vec::new();
        let mut boxes = Vec::new();
        let down =
            |v: DVec3| Vec3A::new((v.x - pad) as f32, (v.y - pad) as f32, (v.z - pad) as f32);
        let up = |v: DVec3| Vec3A::new((v.x + pad) as f32, (v.y + pad) as f32, (v.z + pad) as f32);
        for t in 0..geometry.len() {
            if !keep(t) {
                continue;
            }
            let [a, b, c] = geometry.corners(t);
            if !(a.is_finite() && b.is_finite() && c.is_finite())
                || (b - a).cross(c - a) == DVec3::ZERO
            {
                continue;
            }
            ids.push(t as u32);
            boxes.push(Aabb::new(down(a.min(b).min(c)), up(a.max(b).max(c))));
        }
        let bvh = if boxes.is_empty() {
            CwBvh::default()
        } else {
            build_cwbvh(&boxes, BvhBuildParams::medium_build(), &mut Default::default())
        };
        let ids: Vec<u32> = bvh.primitive_indices.iter().map(|&p| ids[p as usize]).collect();
        let corners = ids.iter().map(|&t| geometry.corners(t as usize)).collect();
        let pass = ids.iter().map(|&t| pass(t as usize).clamp(0.0, 1.0)).collect();
        Self { bvh, corners, ids, pass }
    }

    /// The closest hit with `tmin <= t <= tmax`, as `(t, triangle id)`; ties go to the lower id.
    pub(crate) fn closest(&self, ray: &TraceRay, tmin: f64, tmax: f64) -> Option<(f64, u32)> {
        let mut best: Option<(f64, u32)> = None;
        self.bvh.ray_traverse(ray.bvh_ray(tmax), &mut RayHit::none(), |_, slot| {
            let Some(t) = ray.intersect(&self.corners[slot]) else { return f32::INFINITY };
            if !(t >= tmin && t <= tmax) {
                return f32::INFINITY;
            }
            let id = self.ids[slot];
            match best {
                Some((bt, bid)) if bt < t || (bt == t && bid <= id) => f32::INFINITY,
                _ => {
                    best = Some((t, id));
                    upper_f32(t)
                }
            }
        });
        best
    }

    /// Light reaching the end of the ray: the product of `pass` over the triangles hit with
    /// `tmin < t < tmax`, other than `skip`; traversal stops at the first triangle that lets
    /// no light through (`ray_traverse_miss`).
    pub(crate) fn transmittance(&self, ray: &TraceRay, tmin: f64, tmax: f64, skip: u32) -> f64 {
        let mut light = 1.0;
        self.bvh.ray_traverse_miss(ray.bvh_ray(tmax), |_, slot| {
            if self.ids[slot] == skip {
                return f32::INFINITY;
            }
            match ray.intersect(&self.corners[slot]) {
                Some(t) if t > tmin && t < tmax => {
                    light *= self.pass[slot];
                    if light == 0.0 {
                        0.0
                    } else {
                        f32::INFINITY
                    }
                }
                _ => f32::INFINITY,
            }
        });
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
    shadow_tmin: f64,
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
                let towards = -direction.normalize_or_zero();
                if !towards.is_finite() || towards == DVec3::ZERO {
                    return Err(ReferenceError::NotApplicable(format!(
                        "raytrace: the directional light of scene `{}` has no direction",
                        frame.scene.name
                    )));
                }
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
        let geometry = &frame.geometry;
        let (lo, hi) = bounds(geometry).unwrap_or((DVec3::ZERO, DVec3::ZERO));
        let diagonal = (hi - lo).length();
        let largest = lo.abs().max(hi.abs()).max_element();
        let pad = (BOX_PADDING * diagonal + 8.0 * f64::from(f32::EPSILON) * largest).max(1e-30);
        let transparency = frame.effects.transparency;
        let objects = &frame.scene.objects;
        let pass = |t: usize| {
            if transparency {
                objects.get(geometry.object[t] as usize).map_or(0.0, |o| 1.0 - o.material.opacity)
            } else {
                0.0
            }
        };

        let (camera_accel, caster_accel) = rec.stages.time(STAGE_BVH_BUILD, || {
            let all = Accel::build(geometry, |_| true, pass, pad);
            let casters = (0..geometry.len())
                .any(|t| !frame.is_caster(t))
                .then(|| Accel::build(geometry, |t| frame.is_caster(t), pass, pad));
            (all, casters)
        });

        // Camera rays: perspective from depth `near`; orthographic from behind the scene.
        let camera = &frame.camera;
        let (start_shift, camera_tmin) = match camera.kind {
            ProjectionKind::Perspective { .. } => (0.0, camera.near),
            ProjectionKind::Orthographic { .. } => {
                let nearest = (0..8)
                    .map(|i| {
                        let c = DVec3::new(
                            if i & 1 == 0 { lo.x } else { hi.x },
                            if i & 2 == 0 { lo.y } else { hi.y },
                            if i & 4 == 0 { lo.z } else { hi.z },
                        );
                        camera.depth_of(c)
                    })
                    .fold(f64::INFINITY, f64::min);
                (nearest.min(0.0) - diagonal.max(1.0) * 1e-3, 0.0)
            }
        };
        Ok(Self {
            frame,
            pattern,
            camera_accel,
            caster_accel,
            light,
            shadow_tmin: SHADOW_RAY_OFFSET * diagonal,
            start_shift,
            camera_tmin,
        })
    }

    /// The camera ray and the shadow ray of sub-sample `s` of pixel `(i, j)`.
    fn sample(&self, i: u32, j: u32, s: usize) -> SampleHit {
        let r = self.frame.camera.ray(self.pattern.point(i, j, s));
        let hit =
            TraceRay::new(r.origin + self.start_shift * r.direction, r.direction).and_then(|ray| {
                self.camera_accel
                    .closest(&ray, self.camera_tmin, f64::INFINITY)
                    .map(|(t, id)| (ray.at(t), id))
            });
        let Some((p, id)) = hit else {
            return SampleHit { triangle: None, light: 1.0, rays: 1 };
        };
        let (dir, tmax) = match self.light {
            LightSource::Towards(d) => (d, f64::INFINITY),
            LightSource::At(q) => {
                let v = q - p;
                let dist = v.length();
                (v / dist, dist)
            }
        };
        let casters = self.caster_accel.as_ref().unwrap_or(&self.camera_accel);
        let light = match TraceRay::new(p, dir) {
            Some(ray) if tmax > self.shadow_tmin => {
                casters.transmittance(&ray, self.shadow_tmin, tmax, id)
            }
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
        let tracer = Tracer::new(frame, &self.pattern, rec)?;
        let (w, h) = (frame.width(), frame.height());
        let rate = self.pattern.rate() as usize;
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
        Ok(ReferenceImage { width: w, height: h, lit, evaluated, transmittance })
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
        let accel = Accel::build(&g, |_| true, |_| 0.0, 1e-6);
        assert!(accel.ids.is_empty());
        assert_eq!(accel.closest(&ray, 0.0, f64::INFINITY), None);
        assert_eq!(accel.transmittance(&ray, 0.0, f64::INFINITY, u32::MAX), 1.0);
    }

    #[test]
    fn single_triangle_bvh_finds_its_hit() {
        let g = geometry(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]);
        let accel = Accel::build(&g, |_| true, |_| 0.25, 1e-6);
        let ray = TraceRay::new(DVec3::new(0.2, 0.2, 2.0), DVec3::NEG_Z).expect("finite");
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
        let accel = Accel::build(&g, |_| true, |_| 0.0, 1e-6);
        let up = -DVec3::new(0.0, -1.0, 0.0);
        assert!(up.x.is_sign_negative() && up.z.is_sign_negative());
        let ray = TraceRay::new(DVec3::new(0.1, 0.0, 0.2), up).expect("finite");
        assert_eq!(accel.closest(&ray, 0.0, f64::INFINITY), Some((2.0, 0)));
        assert_eq!(accel.transmittance(&ray, 1e-9, f64::INFINITY, u32::MAX), 0.0);
        let down = TraceRay::new(DVec3::new(0.1, 5.0, 0.2), DVec3::new(-0.0, -1.0, -0.0));
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
        let accel = Accel::build(&g, |_| true, |_| 0.0, 1e-5 * (hi - lo).length());
        let mut targets: Vec<DVec3> = g.positions.clone();
        for tri in &g.triangles {
            for e in 0..3 {
                let (p, q) = (g.positions[tri[e] as usize], g.positions[tri[(e + 1) % 3] as usize]);
                targets.push(0.5 * (p + q));
            }
        }
        let mut tested = 0;
        for eye in [
            centre + DVec3::new(0.0, 0.0, 7.0),
            centre + DVec3::new(3.1, 4.7, -5.3),
            centre + DVec3::new(-0.01, 9.0, 0.02),
        ] {
            for &target in &targets {
                let dir = target - eye;
                let ray = TraceRay::new(eye, dir).expect("finite");
                let off_axis = (centre - eye).cross(dir).length() / dir.length();
                if off_axis < r_in * (1.0 - 1e-9) {
                    tested += 1;
                    assert!(accel.closest(&ray, 0.0, f64::INFINITY).is_some(), "{eye} -> {target}");
                }
            }
        }
        assert!(tested > 10_000, "{tested}");
    }
}
