//! Tracing a few pixels without BVHs: each ray is tested against the triangles its caller
//! lists for it.
//!
//! `exact` traces only its `edge` pixels (about 1 % of the frame on `bunny-plane`), and it
//! already knows, for each, the triangles whose screen polygon overlaps the pixel (every
//! camera ray through the pixel hits one of them or none) and, through its light-space grid,
//! the casters that can shadow a point of each ([`TriangleLists`]). At a few rays per pixel,
//! testing each ray against those lists costs less than building BVHs over every triangle
//! (15 ms of `exact`'s 255 on `bunny-plane` at 800 x 600).
//!
//! Every decision is the one [`super::Tracer`] makes: the same rays ([`RaySetup`]), the same
//! `f64` triangle test on the same triangles (those the BVHs hold: hittable, casters for the
//! shadow rays), the closest camera hit with ties to the lower id, a shadow ray blocked by a
//! hit strictly inside its range on any triangle but the one it leaves. The BVHs only find
//! candidates; here the lists do, so the results are equal bit for bit when the lists hold
//! every triangle a ray can meet (tested in `exact`).
//!
//! Opaque scenes only: with transparency the transmittances would multiply in the lists'
//! order rather than the traversal's, which rounding can tell apart.
//!
//! Hot path: pixels in parallel over bands of rows, nothing allocated per ray; the lists'
//! own scratch is a thread's.

use super::accel::hittable;
use super::{RaySetup, RayTrace, SampleHit, STAGE_BVH_BUILD, STAGE_RAY_TRACING};
use crate::reference::{ReferenceError, ReferenceImage};
use glam::DVec3;
use instrumentation::Recorder;
use methods::Frame;
use rayon::prelude::*;

/// The triangles the rays of some pixels can meet, as their caller knows them.
pub(crate) trait TriangleLists: Sync {
    /// What a thread reuses from query to query.
    type Scratch: Default;

    /// Every triangle the camera ray through a sub-sample of pixel `(i, j)` can hit.
    fn camera(&self, i: u32, j: u32) -> &[u32];

    /// Every caster that can block the shadow ray from `point`, a point of triangle `t`.
    fn casters<'s>(&self, t: u32, point: DVec3, scratch: &'s mut Self::Scratch) -> &'s [u32];
}

/// Rows per parallel band.
const BAND: u32 = 4;

impl RayTrace {
    /// [`RayTrace::evaluate_pixels`] on the pixels where `mask` is true, every ray tested
    /// against the triangles `lists` gives for it (stage [`STAGE_RAY_TRACING`]; no BVH is
    /// built, and [`STAGE_BVH_BUILD`] is recorded as skipped). The caller vouches that the
    /// lists hold every triangle a ray can meet.
    pub(crate) fn evaluate_pixels_listed<L: TriangleLists>(
        &self,
        frame: &Frame<'_>,
        mask: &[bool],
        lists: &L,
        rec: &mut Recorder,
    ) -> Result<ReferenceImage, ReferenceError> {
        if frame.effects.transparency {
            return Err(ReferenceError::NotApplicable(format!(
                "raytrace: scene `{}` has transparency; listed triangles trace opaque scenes only",
                frame.scene.name
            )));
        }
        let setup = RaySetup::new(frame)?;
        let (w, h) = (frame.width(), frame.height());
        let rate = self.pattern.rate() as usize;
        rec.stages.skip(STAGE_BVH_BUILD);
        // Each band writes its rows of the image in place: gathered band by band and joined
        // afterwards, the image's copy was serial (2 ms of `exact` on `bunny-plane` at two
        // threads, 800 x 600, mostly the pages of the joined image touched for the first time).
        let n = (w * h) as usize;
        let rows = (BAND * w).max(1) as usize;
        let (lit, evaluated, rays) = rec.stages.time(STAGE_RAY_TRACING, || {
            let mut lit = methods::parallel::filled(n, 1.0);
            let mut evaluated = methods::parallel::filled(n, false);
            let rays: u64 = lit
                .par_chunks_mut(rows)
                .zip(evaluated.par_chunks_mut(rows))
                .enumerate()
                .map_init(L::Scratch::default, |scratch, (b, (lit, evaluated))| {
                    let first = b * rows;
                    let mut rays = 0;
                    for (local, (lit, evaluated)) in lit.iter_mut().zip(evaluated).enumerate() {
                        let k = first + local;
                        if !mask[k] {
                            continue;
                        }
                        let (i, j) = ((k % w as usize) as u32, (k / w as usize) as u32);
                        let (mut sum, mut all_hit) = (0.0, true);
                        for s in 0..rate {
                            let hit = self.sample(frame, &setup, lists, (i, j, s), scratch);
                            sum += hit.light;
                            all_hit &= hit.triangle.is_some();
                            rays += hit.rays;
                        }
                        *lit = (sum / rate as f64).clamp(0.0, 1.0);
                        *evaluated = all_hit;
                    }
                    rays
                })
                .sum();
            (lit, evaluated, rays)
        });
        rec.counters.rays_traced += rays;
        Ok(ReferenceImage {
            width: w,
            height: h,
            lit,
            evaluated,
            transmittance: None,
            classes: None,
        })
    }

    /// Sub-sample `id` of a pixel: its camera ray's closest hit among the listed triangles,
    /// then its shadow ray against the listed casters.
    fn sample<L: TriangleLists>(
        &self,
        frame: &Frame<'_>,
        setup: &RaySetup,
        lists: &L,
        id: (u32, u32, usize),
        scratch: &mut L::Scratch,
    ) -> SampleHit {
        let g = &frame.geometry;
        let (i, j, _) = id;
        let Some(ray) = setup.camera(frame, &self.pattern, id) else {
            return SampleHit { triangle: None, light: 1.0, rays: 1 };
        };
        let mut best: Option<(f64, u32)> = None;
        for &t in lists.camera(i, j) {
            if !hittable(g, t as usize) {
                continue;
            }
            let Some(d) = ray.intersect(&g.corners(t as usize)) else { continue };
            if !(d >= setup.camera_tmin && d <= f64::INFINITY) {
                continue;
            }
            match best {
                Some((bd, bt)) if bd < d || (bd == d && bt <= t) => {}
                _ => best = Some((d, t)),
            }
        }
        let Some((d, hit)) = best else {
            return SampleHit { triangle: None, light: 1.0, rays: 1 };
        };
        let Some((shadow, (tmin, tmax))) = setup.shadow(&ray, d) else {
            return SampleHit { triangle: Some(hit), light: 1.0, rays: 2 };
        };
        let blocked = lists.casters(hit, shadow.origin, scratch).iter().any(|&c| {
            c != hit
                && frame.is_caster(c as usize)
                && hittable(g, c as usize)
                && shadow.intersect(&g.corners(c as usize)).is_some_and(|x| x > tmin && x < tmax)
        });
        SampleHit { triangle: Some(hit), light: if blocked { 0.0 } else { 1.0 }, rays: 2 }
    }
}
