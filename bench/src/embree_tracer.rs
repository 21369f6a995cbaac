//! The same sample points traced by Intel Embree 3: its BVH over the frame's triangles, camera
//! rays (closest hit) and shadow rays (any hit), through the per-ray API (`rtcIntersect1`,
//! `rtcOccluded1`) or in streams of 16 (`rtcIntersect1M` / `rtcOccluded1M` on 16 rays at a
//! time), on the calling rayon pool's threads, a row of pixels per task.
//!
//! Hot loops allocate nothing per ray: a stream's 16 rays live in one vector per row.

use crate::{embree_shadow_start, shadow_ray, Samples};
use cgmath::Vector3;
use embree::{Device, Geometry, IntersectContext, Ray, RayHit, Scene, TriangleMesh};
use glam::DVec3;
use methods::Frame;
use rayon::prelude::*;
use std::time::Instant;

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

/// Traces `samples` of `frame` with Embree through `api` (see the module documentation).
pub fn trace(frame: &Frame<'_>, samples: &Samples, api: Api) -> Traced {
    let device = Device::new();
    let start = Instant::now();
    let mut all = Scene::new(&device);
    all.attach_geometry(mesh(&device, frame, |_| true));
    let mut casters_only = None;
    if (0..frame.geometry.len()).any(|t| !frame.is_caster(t)) {
        let mut s = Scene::new(&device);
        s.attach_geometry(mesh(&device, frame, |t| frame.is_caster(t)));
        casters_only = Some(s);
    }
    let all = all.commit();
    let casters = casters_only.as_ref().map(|s| s.commit());
    let build_ms = start.elapsed().as_secs_f64() * 1e3;
    let casters = casters.as_ref().unwrap_or(&all);

    let w = samples.width as usize * samples.rate;
    let start = Instant::now();
    let hits: Vec<Vec<Option<CameraHit>>> = samples
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
    let camera_ms = start.elapsed().as_secs_f64() * 1e3;

    let start = Instant::now();
    let light: Vec<Vec<f64>> = hits
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
    let shadow_ms = start.elapsed().as_secs_f64() * 1e3;

    let camera_rays = samples.points.len() as u64;
    let shadow_rays = hits.iter().flatten().filter(|h| h.is_some()).count() as u64;
    let triangle = hits
        .iter()
        .flatten()
        .map(|h| h.as_ref().map_or(methods::raster::NO_TRIANGLE, |h| h.triangle))
        .collect();
    Traced {
        triangle,
        light: light.into_iter().flatten().collect(),
        build_ms,
        camera_ms,
        shadow_ms,
        camera_rays,
        shadow_rays,
    }
}

/// The sample's hit from Embree's answer to the camera ray `origin + t direction`.
fn camera_hit(rh: &RayHit, origin: DVec3, direction: DVec3) -> Option<CameraHit> {
    (rh.hit.geomID != u32::MAX).then(|| CameraHit {
        triangle: rh.hit.primID,
        eye: origin,
        p: origin + f64::from(rh.ray.tfar) * direction,
    })
}
