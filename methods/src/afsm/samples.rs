//! Stage "transformation of samples" (Aila and Laine 2004, section 3): every visible
//! sub-sample's surface point is moved to the light's image plane, keeping its exact `f64`
//! image coordinates (no discretisation) and its light depth.
//!
//! The rows of pixels are transformed in parallel, each into its own slots of one vector,
//! sized by a first count of the covered sub-samples per row, so that the samples lie packed
//! in id order as they are written. One slot per pixel and a serial move of every row's
//! samples to the front afterwards cost more: on `cage` (800x600, 325,840 samples, one thread
//! pinned, load 5-7 on 2 cores, CPU time of the stage, three alternating runs of 7 frames) the
//! stage took 11.5, 11.2 and 8.3 ms that way and 6.7, 6.9 and 7.5 ms with the count; on
//! `bunny-plane` 8.4, 8.6, 8.7 against 8.2, 6.9, 7.0 ms. At two threads the move was also the
//! stage's serial part.
//!
//! A camera ray is the sum of a part that depends on its image point's column and one that
//! depends on its row ([`Projector::column`], [`Projector::row`]), each with a division: both
//! are made once per column and once per row of every sub-sample (tables of `rate` times the
//! width and the height), and [`Projector::ray_from`] adds them, the numbers of
//! [`Projector::ray`]. At one pinned thread, 800x600, 7 alternating runs of 5 frames (load
//! 1.4-1.8 on 2 cores), the stage's median went from 10.4 to 9.6 ms on `bunny-plane` and from
//! 9.4 to 7.5 on `cage`, the same samples bit for bit.

use super::shadow_offset;
use crate::{pattern::SamplePattern, raster::NO_TRIANGLE};
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use scenes::{
    projection::{GridRays, ProjectionKind},
    Projector,
};

/// A visible sample on the light's image plane.
#[derive(Debug, Clone, Copy, Default, PartialEq, bytemuck::Zeroable)]
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

/// What makes one sub-sample's [`Sample`]: the camera, the light and the pattern, with the
/// parts of the camera's rays per column and per row of sub-sample points.
struct SampleAt<'a> {
    camera: &'a Projector,
    light: &'a Projector,
    pattern: &'a SamplePattern,
    rays: GridRays,
}

impl<'a> SampleAt<'a> {
    fn new(
        camera: &'a Projector,
        light: &'a Projector,
        pattern: &'a SamplePattern,
        size: (usize, usize),
    ) -> Self {
        let rays = camera.grid_rays(size, pattern.offsets());
        Self { camera, light, pattern, rays }
    }

    /// The surface point of sub-sample `s` of pixel `pixel` (at `(x, y)`) on `surface`,
    /// `camera.ray(point).at(depth)`, with the camera ray's origin; `None` for a background
    /// sub-sample. The ray is made from the point's column and row parts ([`GridRays`]), the
    /// numbers of `camera.ray(point)` (`pattern.point` adds the offset to the pixel's corner).
    #[inline]
    fn surface_point(
        &self,
        surface: &Surface<'_>,
        pixel: usize,
        (x, y): (u32, u32),
        s: usize,
    ) -> Option<(DVec3, DVec3)> {
        if surface.triangle[pixel] == NO_TRIANGLE {
            return None;
        }
        let ray = self.rays.ray(self.camera, x as usize, y as usize, s);
        Some((ray.origin, ray.at(surface.depth[pixel])))
    }

    /// The sample of sub-sample `s` of pixel `pixel`, on triangle `tri` at `position` (seen
    /// from `origin`), moved to the light's image with its threshold depth; `None` for a point
    /// the light cannot project.
    #[inline]
    fn sample(
        &self,
        tri: u32,
        pixel: usize,
        s: usize,
        (origin, position): (DVec3, DVec3),
    ) -> Option<Sample> {
        let (xy, z) = self.light.project(position)?;
        let zt = threshold_depth(self.light, xy, z, shadow_offset(origin, position));
        let id = (pixel * self.pattern.rate() as usize + s) as u32;
        zt.is_finite().then_some(Sample { x: xy.x, y: xy.y, zt, id, tri })
    }
}

/// The visible sub-samples on the light's image plane, with the bounds of the camera's surface
/// points at pixel centres.
#[derive(Debug, Clone, PartialEq)]
pub struct Transformed {
    /// The samples, in id order.
    pub samples: Vec<Sample>,
    /// The smallest and the largest coordinates of the surface points of the centre sub-sample
    /// of every covered pixel (`+inf` and `-inf` when none is covered): those the frame's
    /// G-buffer holds, whether or not the light projects them.
    pub centre_bounds: (DVec3, DVec3),
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
/// Every row of pixels gets as many slots of one vector as it has covered sub-samples (a
/// count of the G-buffers' triangles, in parallel), so the slots already lie in id order
/// without gaps; the rows are then transformed in parallel, each into its own slots (no index
/// is divided, no per-thread list is concatenated). A spot light drops the points it cannot
/// project: only then are the rows' samples moved together, in row order. Each row also
/// bounds its centre sub-samples' surface points, which are at hand
/// ([`Transformed::centre_bounds`]).
pub fn transform_samples(
    camera: &Projector,
    light: &Projector,
    surfaces: &[Surface<'_>],
    pattern: &SamplePattern,
    width: u32,
) -> Transformed {
    let pixels = surfaces.first().map_or(0, |s| s.triangle.len());
    let w = (width as usize).max(1);
    let rows = pixels.div_ceil(w);
    let at = SampleAt::new(camera, light, pattern, (w, rows));
    let row_pixels = |row: usize| row * w..((row + 1) * w).min(pixels);
    let covered: Vec<usize> = (0..rows)
        .into_par_iter()
        .map(|row| {
            let range = row_pixels(row);
            let count = |s: &Surface<'_>| {
                s.triangle[range.clone()].iter().filter(|&&t| t != NO_TRIANGLE).count()
            };
            surfaces.iter().map(count).sum()
        })
        .collect();
    // Zeroed by the allocator (fresh pages are zero) rather than filled with defaults, so the
    // slots are written once: on `bunny-plane` at one thread the stage went from 7.1 to 6.7 ms
    // (medians of 8 alternating runs of 5 frames; at two threads within the noise).
    let mut samples = bytemuck::zeroed_vec::<Sample>(covered.iter().sum());
    let row_slots = crate::parallel::cut(&mut samples, covered.iter().copied());
    let centre = pattern.centre_index();
    let rows_done: Vec<(usize, (DVec3, DVec3))> = row_slots
        .into_par_iter()
        .enumerate()
        .map(|(row, slots)| {
            let mut count = 0;
            let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            for pixel in row_pixels(row) {
                let x = (pixel - row * w) as u32;
                for (s, surface) in surfaces.iter().enumerate() {
                    let Some(point) = at.surface_point(surface, pixel, (x, row as u32), s) else {
                        continue;
                    };
                    if s == centre {
                        (lo, hi) = (lo.min(point.1), hi.max(point.1));
                    }
                    if let Some(sample) = at.sample(surface.triangle[pixel], pixel, s, point) {
                        slots[count] = sample;
                        count += 1;
                    }
                }
            }
            (count, (lo, hi))
        })
        .collect();
    let centre_bounds =
        rows_done.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &(_, (a, b))| {
            (lo.min(a), hi.max(b))
        });
    let counts: Vec<usize> = rows_done.iter().map(|&(count, _)| count).collect();
    if counts != covered {
        let (mut start, mut end) = (0, 0);
        for (&count, &slots) in counts.iter().zip(&covered) {
            if start != end {
                samples.copy_within(start..start + count, end);
            }
            start += slots;
            end += count;
        }
        samples.truncate(end);
    }
    Transformed { samples, centre_bounds }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{
        pattern::PatternKind,
        raster::tests::{pixel_projector, spot_above},
    };

    /// A spot light at height 12 above the camera's image, looking down, `near` 0.5: surface
    /// points above height 11.5 are dropped.
    fn spot() -> Projector {
        spot_above(3.5, 2.5)
    }

    /// Every sub-sample in id order, one at a time, its ray `camera.ray(pattern.point(..))`.
    fn one_by_one(
        camera: &Projector,
        light: &Projector,
        surfaces: &[Surface<'_>],
        pattern: &SamplePattern,
        width: usize,
    ) -> Vec<Sample> {
        let mut out = Vec::new();
        for pixel in 0..surfaces[0].triangle.len() {
            for (s, surface) in surfaces.iter().enumerate() {
                let (x, y) = ((pixel % width) as u32, (pixel / width) as u32);
                if surface.triangle[pixel] == NO_TRIANGLE {
                    continue;
                }
                let ray = camera.ray(pattern.point(x, y, s));
                let position = ray.at(surface.depth[pixel]);
                let Some((xy, z)) = light.project(position) else { continue };
                let zt = threshold_depth(light, xy, z, shadow_offset(ray.origin, position));
                let id = (pixel * pattern.rate() as usize + s) as u32;
                if zt.is_finite() {
                    out.push(Sample { x: xy.x, y: xy.y, zt, id, tri: surface.triangle[pixel] });
                }
            }
        }
        out
    }

    /// A perspective camera above the image, slightly turned, with field-of-view tangents
    /// whose products round.
    fn perspective_camera(w: usize, h: usize) -> Projector {
        let aim = DVec3::new(0.1, -0.07, -1.0).normalize();
        let (right, up, forward) = scenes::projection::look_basis(aim, DVec3::Y);
        Projector {
            origin: DVec3::new(3.3, 2.1, 14.0),
            right,
            up,
            forward,
            kind: ProjectionKind::Perspective { tan_half_x: 0.37, tan_half_y: 0.61 },
            near: 0.01,
            width: w as f64,
            height: h as f64,
        }
    }

    /// The rows transformed in parallel, each ray made from its column's and row's parts,
    /// equal the samples made one by one from `camera.ray(pattern.point(..))`, bit for bit:
    /// orthographic and perspective cameras, grid and rotated patterns, both lights.
    #[test]
    fn rows_packed_in_parallel_equal_samples_one_by_one() {
        let (w, h, rate) = (7usize, 5usize, 4u32);
        // Background on a third of the sub-samples; camera depths 0..16 put surface points
        // from height 10 down to -6, and depths below 0 up to height 13, beside the spot.
        let tris: Vec<Vec<u32>> = (0..rate as usize)
            .map(|s| {
                (0..w * h)
                    .map(|p| if (p * 7 + s * 3) % 3 == 0 { NO_TRIANGLE } else { (p + s) as u32 })
                    .collect()
            })
            .collect();
        let depths: Vec<Vec<f64>> = (0..rate as usize)
            .map(|s| (0..w * h).map(|p| ((p * 5 + s * 11) % 19) as f64 - 3.0).collect())
            .collect();
        let surfaces: Vec<Surface<'_>> =
            tris.iter().zip(&depths).map(|(triangle, depth)| Surface { triangle, depth }).collect();
        let covered = tris.iter().flatten().filter(|&&t| t != NO_TRIANGLE).count();
        for kind in [PatternKind::Grid, PatternKind::Rotated] {
            let pattern = SamplePattern::new(rate, kind).expect("pattern");
            for camera in [pixel_projector(w as u32, h as u32), perspective_camera(w, h)] {
                for light in [pixel_projector(16, 16), spot()] {
                    let got = transform_samples(&camera, &light, &surfaces, &pattern, w as u32);
                    let want = one_by_one(&camera, &light, &surfaces, &pattern, w);
                    assert_eq!(got.samples, want);
                    let centre = pattern.centre_index();
                    let (lo, hi) = (0..w * h)
                        .filter(|&p| tris[centre][p] != NO_TRIANGLE)
                        .map(|p| {
                            let (x, y) = ((p % w) as u32, (p / w) as u32);
                            camera.ray(pattern.point(x, y, centre)).at(depths[centre][p])
                        })
                        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), q| {
                            (lo.min(q), hi.max(q))
                        });
                    assert_eq!(got.centre_bounds, (lo, hi), "the centre points' bounds");
                    assert!(lo.is_finite());
                    assert!(!want.is_empty());
                    if camera.is_perspective() {
                        continue;
                    }
                    if light.is_perspective() {
                        assert!(want.len() < covered, "the spot drops some points");
                    } else {
                        assert_eq!(want.len(), covered);
                    }
                }
            }
        }
    }
}
