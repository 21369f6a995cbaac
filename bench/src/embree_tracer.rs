//! The same sample points traced by Intel Embree 3: its BVH over the frame's triangles, camera
//! rays (closest hit) and shadow rays (any hit), through the per-ray API (`rtcIntersect1`,
//! `rtcOccluded1`) or in streams of 16 (`rtcIntersect1M` / `rtcOccluded1M` on 16 rays at a
//! time), on the calling rayon pool's threads, a row of pixels per task.
//!
//! Hot loops allocate nothing per ray: a stream's 16 rays live in one vector per row.
//!
//! Timing: the parts are stages of an [`instrumentation::Stages`] ([`STAGE_BVH_BUILD`],
//! [`STAGE_CAMERA_RAYS`], [`STAGE_SHADOW_RAYS`]), each timed by [`Stages::time`] on both
//! clocks (wall-clock, and CPU time of the process's threads, Embree's own threads included),
//! so that a caller measuring [`trace_on`] or [`shadows_on`] through
//! `instrumentation::measure` has Embree's figures from the stages. The Embree device is the
//! caller's, made once outside the timed runs.

use crate::{embree_shadow_start, shadow_ray, Samples};
use cgmath::Vector3;
use embree::{
    CommittedScene, Device, Geometry, IntersectContext, Ray, RayHit, Scene, TriangleMesh,
};
use glam::DVec3;
use instrumentation::Stages;
use methods::Frame;
use rayon::prelude::*;

/// Stage name of Embree's BVH build (both scenes: every triangle, and the casters when some
/// triangle casts no shadow).
pub const STAGE_BVH_BUILD: &str = "Embree BVH build";
/// Stage name of Embree's camera rays.
pub const STAGE_CAMERA_RAYS: &str = "Embree camera rays";
/// Stage name of Embree's shadow rays.
pub const STAGE_SHADOW_RAYS: &str = "Embree shadow rays";

/// How rays are handed to Embree.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Api {
    /// One ray per call.
    PerRay,
    /// Streams of 16 rays per call.
    Stream16,
}

/// What Embree's traversal gave for every sample, and how long each part took.
#[derive(Debug, Clone)]
pub struct Traced {
    /// Each sample's camera hit (`methods::raster::NO_TRIANGLE` for background).
    pub triangle: Vec<u32>,
    /// Each sample's light: 1 lit (or background), 0 shadowed.
    pub light: Vec<f64>,
    /// BVH build time (both scenes), milliseconds.
    pub build_ms: f64,
    /// Camera rays' time, milliseconds.
    pub camera_ms: f64,
    /// Shadow rays' time, milliseconds.
    pub shadow_ms: f64,
    /// Camera rays traced.
    pub camera_rays: u64,
    /// Shadow rays traced.
    pub shadow_rays: u64,
}

fn v3(v: DVec3) -> Vector3<f32> {
    Vector3::new(v.x as f32, v.y as f32, v.z as f32)
}

/// An Embree mesh of the frame's triangles for which `keep` holds.
fn mesh<'d>(device: &'d Device, frame: &Frame<'_>, keep: impl Fn(usize) -> bool) -> Geometry<'d> {
    let g = &frame.geometry;
    let tris: Vec<usize> = (0..g.len()).filter(|&t| keep(t)).collect();
    let mut m = TriangleMesh::unanimated(device, tris.len(), g.positions.len());
    {
        let mut verts = m.vertex_buffer.map();
        for (k, p) in g.positions.iter().enumerate() {
            verts[k] = cgmath::Vector4::new(p.x as f32, p.y as f32, p.z as f32, 0.0);
        }
    }
    {
        let mut ids = m.index_buffer.map();
        for (k, &t) in tris.iter().enumerate() {
            let [a, b, c] = g.triangles[t];
            ids[k] = Vector3::new(a, b, c);
        }
    }
    let mut geometry = Geometry::Triangle(m);
    geometry.commit();
    geometry
}

/// A camera ray and its sample's hit point, from Embree's closest hit.
struct CameraHit {
    triangle: u32,
    eye: DVec3,
    p: DVec3,
}

/// Embree's camera hits of a frame's samples, row by row, to trace shadow rays from.
pub struct CameraHits {
    rows: Vec<Vec<Option<CameraHit>>>,
}

impl CameraHits {
    /// How many samples hit a surface: the shadow rays to trace.
    pub fn shadow_rays(&self) -> u64 {
        self.rows.iter().flatten().filter(|h| h.is_some()).count() as u64
    }
}

/// The milliseconds of the latest stage `name` of `stages` (0 when there is none).
fn stage_ms(stages: &Stages, name: &str) -> f64 {
    stages.stages.iter().rev().find(|s| s.name == name).map_or(0.0, |s| s.ms)
}

/// Builds Embree's scenes over `frame` on `device` as the stage [`STAGE_BVH_BUILD`] of
/// `stages`, then calls `f` with the scene of every triangle, the scene of the casters (the
/// same one when every triangle casts) and `stages`.
fn with_bvh<T>(
    device: &Device,
    frame: &Frame<'_>,
    stages: &mut Stages,
    f: impl FnOnce(&CommittedScene<'_>, &CommittedScene<'_>, &mut Stages) -> T,
) -> T {
    let needs_casters = (0..frame.geometry.len()).any(|t| !frame.is_caster(t));
    let mut all = Scene::new(device);
    let mut casters_only = needs_casters.then(|| Scene::new(device));
    let (all_ref, casters_ref) = (&mut all, casters_only.as_mut());
    let (all, casters) = stages.time(STAGE_BVH_BUILD, move || {
        all_ref.attach_geometry(mesh(device, frame, |_| true));
        let casters = casters_ref.map(|s| {
            s.attach_geometry(mesh(device, frame, |t| frame.is_caster(t)));
            let s: &Scene<'_> = s;
            s.commit()
        });
        let all_ref: &Scene<'_> = all_ref;
        (all_ref.commit(), casters)
    });
    f(&all, casters.as_ref().unwrap_or(&all), stages)
}

/// Traces `samples` of `frame` with Embree through `api` (see the module documentation), on a
/// device of its own, its stages' times in the result only.
pub fn trace(frame: &Frame<'_>, samples: &Samples, api: Api) -> Traced {
    trace_on(&Device::new(), frame, samples, api, &mut Stages::default())
}

/// Traces `samples` of `frame` with Embree on `device` through `api`: the BVH build, the
/// camera rays and the shadow rays, each a stage of `stages`.
pub fn trace_on(
    device: &Device,
    frame: &Frame<'_>,
    samples: &Samples,
    api: Api,
    stages: &mut Stages,
) -> Traced {
    with_bvh(device, frame, stages, |all, casters, stages| {
        let hits = stages.time(STAGE_CAMERA_RAYS, || camera_rays(all, frame, samples, api));
        let light = stages.time(STAGE_SHADOW_RAYS, || shadow_rays(casters, frame, &hits, api));
        let triangle = hits
            .rows
            .iter()
            .flatten()
            .map(|h| h.as_ref().map_or(methods::raster::NO_TRIANGLE, |h| h.triangle))
            .collect();
        Traced {
            triangle,
            light,
            build_ms: stage_ms(stages, STAGE_BVH_BUILD),
            camera_ms: stage_ms(stages, STAGE_CAMERA_RAYS),
            shadow_ms: stage_ms(stages, STAGE_SHADOW_RAYS),
            camera_rays: samples.points.len() as u64,
            shadow_rays: hits.shadow_rays(),
        }
    })
}

/// Embree's camera hits of `samples` of `frame` through `api`, on a BVH of their own, untimed.
pub fn camera_hits(device: &Device, frame: &Frame<'_>, samples: &Samples, api: Api) -> CameraHits {
    with_bvh(device, frame, &mut Stages::default(), |all, _, _| {
        camera_rays(all, frame, samples, api)
    })
}

/// Embree's BVH build and the shadow rays from `hits` through `api`, each a stage of
/// `stages`; the shadow rays traced.
pub fn shadows_on(
    device: &Device,
    frame: &Frame<'_>,
    hits: &CameraHits,
    api: Api,
    stages: &mut Stages,
) -> u64 {
    with_bvh(device, frame, stages, |_, casters, stages| {
        stages.time(STAGE_SHADOW_RAYS, || shadow_rays(casters, frame, hits, api));
        hits.shadow_rays()
    })
}

/// The camera rays of `samples` against `all`, a row of pixels per task.
fn camera_rays(
    all: &CommittedScene<'_>,
    frame: &Frame<'_>,
    samples: &Samples,
    api: Api,
) -> CameraHits {
    let w = samples.width as usize * samples.rate;
    let rows = samples
        .points
        .par_chunks(w.max(1))
        .map(|row| {
            let rays = row.iter().map(|&xy| frame.camera.ray(xy));
            let mut ctx = IntersectContext::coherent();
            match api {
                Api::PerRay => rays
                    .map(|r| {
                        let mut rh = RayHit::new(Ray::new(v3(r.origin), v3(r.direction)));
                        all.intersect(&mut ctx, &mut rh);
                        camera_hit(&rh, r.origin, r.direction)
                    })
                    .collect(),
                Api::Stream16 => {
                    let rays: Vec<scenes::Ray> = rays.collect();
                    let mut out = Vec::with_capacity(rays.len());
                    let mut batch: Vec<RayHit> = Vec::with_capacity(16);
                    for chunk in rays.chunks(16) {
                        batch.clear();
                        batch.extend(
                            chunk
                                .iter()
                                .map(|r| RayHit::new(Ray::new(v3(r.origin), v3(r.direction)))),
                        );
                        all.intersect_stream_aos(&mut ctx, &mut batch);
                        out.extend(
                            batch
                                .iter()
                                .zip(chunk)
                                .map(|(rh, r)| camera_hit(rh, r.origin, r.direction)),
                        );
                    }
                    out
                }
            }
        })
        .collect();
    CameraHits { rows }
}

/// The shadow rays from `hits` against `casters`, a row of pixels per task: each sample's
/// light, 1 lit (or background), 0 shadowed.
fn shadow_rays(
    casters: &CommittedScene<'_>,
    frame: &Frame<'_>,
    hits: &CameraHits,
    api: Api,
) -> Vec<f64> {
    let light: Vec<Vec<f64>> = hits
        .rows
        .par_iter()
        .map(|row| {
            let mut ctx = IntersectContext::incoherent();
            let rays: Vec<Option<Ray>> = row
                .iter()
                .map(|h| {
                    let h = h.as_ref()?;
                    let (dir, tmin, tmax) = shadow_ray(frame, h.eye, h.p)?;
                    let start = embree_shadow_start(h.eye, h.p, tmin);
                    (tmax > start)
                        .then(|| Ray::segment(v3(h.p), v3(dir), start as f32, tmax as f32))
                })
                .collect();
            let lit = |r: &Ray| if r.tfar == f32::NEG_INFINITY { 0.0 } else { 1.0 };
            match api {
                Api::PerRay => rays
                    .into_iter()
                    .map(|r| match r {
                        Some(mut r) => {
                            casters.occluded(&mut ctx, &mut r);
                            lit(&r)
                        }
                        None => 1.0,
                    })
                    .collect(),
                Api::Stream16 => {
                    let mut out = vec![1.0; rays.len()];
                    let live: Vec<(usize, Ray)> =
                        rays.into_iter().enumerate().filter_map(|(k, r)| Some((k, r?))).collect();
                    let mut batch: Vec<Ray> = Vec::with_capacity(16);
                    for chunk in live.chunks(16) {
                        batch.clear();
                        batch.extend(chunk.iter().map(|(_, r)| *r));
                        casters.occluded_stream_aos(&mut ctx, &mut batch);
                        for ((k, _), r) in chunk.iter().zip(&batch) {
                            out[*k] = lit(r);
                        }
                    }
                    out
                }
            }
        })
        .collect();
    light.into_iter().flatten().collect()
}

/// The sample's hit from Embree's answer to the camera ray `origin + t direction`.
fn camera_hit(rh: &RayHit, origin: DVec3, direction: DVec3) -> Option<CameraHit> {
    (rh.hit.geomID != u32::MAX).then(|| CameraHit {
        triangle: rh.hit.primID,
        eye: origin,
        p: origin + f64::from(rh.ray.tfar) * direction,
    })
}
