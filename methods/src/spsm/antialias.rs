//! Stage 6, antialiasing (Lecocq et al. 2014, section 5): the silhouette function recovered
//! once per uncertain pixel is evaluated at the pixel's sub-samples, and the pixel's value is
//! the lit fraction. Only uncertain pixels are antialiased; the others keep their binary
//! value (the paper's "multi-sampling only at shadow boundaries").
//!
//! A sub-sample's map position: the camera ray through the sub-sample's image point (the
//! shared [`SamplePattern`]) meets the plane of the surface seen at the pixel centre
//! (G-buffer position and face normal); that point is projected into the light's map. Where
//! the ray misses the plane or the point does not project, the sub-sample takes the centre's
//! position.
//!
//! Counter: `antialiased_samples`, one per sub-sample evaluated (pixels whose pattern was
//! full or empty have a constant value and are not evaluated).

use super::classify::{Lookup, UncertainPixel};
use super::recover::{Pattern, Resolved, Silhouette};
use crate::frame::Frame;
use crate::pattern::SamplePattern;
use instrumentation::Counters;
use rayon::prelude::*;

/// Antialiases the uncertain pixels (indices into the frame, with their silhouettes in the
/// same order), writing their lit fraction into `lit`.
pub fn antialias_pixels(
    frame: &Frame<'_>,
    lookup: &Lookup<'_>,
    pattern: &SamplePattern,
    uncertain: &[UncertainPixel],
    silhouettes: &[Option<Silhouette>],
    lit: &mut [f32],
) -> Counters {
    let g = &frame.gbuffer;
    let w = g.width;
    let rate = pattern.offsets().len();
    let out: Vec<Option<f32>> = uncertain
        .par_iter()
        .zip(silhouettes)
        .map(|(u, s)| {
            let s = s.as_ref()?;
            if !matches!(s.pattern(), Pattern::Tangents { .. }) {
                return None;
            }
            let k = u.pixel as usize;
            let (position, normal) = (g.position[k], g.normal[k]);
            let centre = lookup.tester.projector.project(position)?.0;
            let resolved = Resolved::new(lookup.map, s);
            let (i, j) = ((k % w as usize) as u32, (k / w as usize) as u32);
            let offset = normal.dot(position);
            let lit_samples = (0..rate)
                .filter(|&s| {
                    let ray = frame.camera.ray(pattern.point(i, j, s));
                    let q = ray
                        .intersect_plane(normal, offset)
                        .and_then(|t| lookup.tester.projector.project(ray.at(t)))
                        .map_or(centre, |(xy, _)| xy);
                    resolved.lit(q)
                })
                .count();
            Some(lit_samples as f32 / rate as f32)
        })
        .collect();
    let mut c = Counters::default();
    for (u, v) in uncertain.iter().zip(out) {
        if let Some(v) = v {
            lit[u.pixel as usize] = v;
            c.antialiased_samples += rate as u64;
        }
    }
    c
}
