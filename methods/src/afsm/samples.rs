//! Stage "transformation of samples" (Aila and Laine 2004, section 3): every visible
//! sub-sample's surface point is moved to the light's image plane, keeping its exact `f64`
//! image coordinates (no discretisation) and its light depth.

use super::shadow_offset;
use crate::{pattern::SamplePattern, raster::NO_TRIANGLE};
use glam::DVec2;
use rayon::prelude::*;
use scenes::{projection::ProjectionKind, Projector};

/// A visible sample on the light's image plane.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Sample {
    /// Light image x.
    pub x: f64,
    /// Light image y.
    pub y: f64,
    /// Shadow threshold depth: a caster shadows the sample where its light depth is below
    /// this value (the sample's light depth less the shadow offset, see [`threshold_depth`]).
    pub zt: f64,
    /// Sample id: `pixel * rate + s` for sub-sample `s` of pixel `pixel` (row-major).
    pub id: u32,
    /// The triangle the sample lies on; it never shadows its own sample.
    pub tri: u32,
}

/// The camera's nearest surface at one sub-sample position of every pixel.
#[derive(Debug, Clone, Copy)]
pub struct Surface<'a> {
    /// Nearest triangle per pixel, [`NO_TRIANGLE`] for background.
    pub triangle: &'a [u32],
    /// Its camera depth per pixel.
    pub depth: &'a [f64],
}

/// The depth below which a caster shadows a point of light depth `z` at light image point
/// `xy`: `z - offset / |ray(xy)|`, where `ray(xy)` is the light's ray through `xy`
/// parameterised by depth. A caster at depth `d` on that ray lies `(z - d) * |ray(xy)|` from
/// the point in world units, so `d < threshold` says exactly "nearer the light than the point
/// by more than `offset` world units", the shadow rays' test of the ray-traced reference.
/// Orthographic lights have unit rays (`forward` is a unit vector): `z - offset`.
#[inline]
pub fn threshold_depth(light: &Projector, xy: DVec2, z: f64, offset: f64) -> f64 {
    match light.kind {
        ProjectionKind::Orthographic { .. } => z - offset,
        ProjectionKind::Perspective { .. } => z - offset / light.ray(xy).direction.length(),
    }
}

/// Transforms the visible sub-samples to the light's image plane.
///
/// `surfaces[s]` is the camera's nearest surface at sub-sample `s` of `pattern` (for the
/// centre sample, the frame's G-buffer). A sub-sample's surface point is
/// `camera.ray(point).at(depth)` at its image point, as the G-buffer computes positions; its
/// threshold depth takes the point's own [`shadow_offset`] from the camera ray's origin.
/// Background sub-samples, and points a spot light cannot project (nearer than its `near`
/// plane, or behind it), give no sample. Samples come out in id order.
///
/// Every row of pixels is transformed in parallel into its own slots of one vector, its
/// samples packed at the front of them (no index is divided, no per-thread list is
/// concatenated); the rows' samples are then moved together in row order. Every pass but that
/// last move runs in parallel.
pub fn transform_samples(
    camera: &Projector,
    light: &Projector,
    surfaces: &[Surface<'_>],
    pattern: &SamplePattern,
    width: u32,
) -> Vec<Sample> {
    let rate = pattern.rate() as usize;
    let pixels = surfaces.first().map_or(0, |s| s.triangle.len());
    let w = width as usize;
    let row_len = (w * rate).max(1);
    let mut samples = Vec::new();
    (0..pixels * rate)
        .into_par_iter()
        .with_min_len(4096)
        .map(|_| Sample::default())
        .collect_into_vec(&mut samples);
    let counts: Vec<usize> = samples
        .par_chunks_mut(row_len)
        .enumerate()
        .map(|(row, slots)| {
            let mut count = 0;
            for x in 0..slots.len() / rate {
                let pixel = row * w + x;
                for (s, surface) in surfaces.iter().enumerate() {
                    let tri = surface.triangle[pixel];
                    if tri == NO_TRIANGLE {
                        continue;
                    }
                    let ray = camera.ray(pattern.point(x as u32, row as u32, s));
                    let position = ray.at(surface.depth[pixel]);
                    let Some((xy, z)) = light.project(position) else { continue };
                    let zt = threshold_depth(light, xy, z, shadow_offset(ray.origin, position));
                    if zt.is_finite() {
                        let id = (pixel * rate + s) as u32;
                        slots[count] = Sample { x: xy.x, y: xy.y, zt, id, tri };
                        count += 1;
                    }
                }
            }
            count
        })
        .collect();
    let mut end = 0;
    for (row, &count) in counts.iter().enumerate() {
        let start = row * row_len;
        if start != end {
            samples.copy_within(start..start + count, end);
        }
        end += count;
    }
    samples.truncate(end);
    samples
}
