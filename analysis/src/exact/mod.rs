//! `exact`: the exact ground truth for planar receivers.
//!
//! A pixel's value is the fraction of its square, mapped onto the receiver plane, that the
//! light sees. The method:
//!
//! 1. **Shadow polygons.** Every caster triangle (a triangle `t` with `frame.is_caster(t)` of
//!    an object other than the receiver: a plane cannot shadow itself) is clipped to the part
//!    strictly between the light and the receiver plane and projected along light rays onto
//!    the plane (directional: parallel; spot: central from the light), then through the
//!    camera onto the screen and clipped to the frame `[0, W] x [0, H]`. Both maps are
//!    composed in homogeneous coordinates (see [`shadow`](self)): every clip is a linear
//!    inequality on the triangle, so clipping happens before any division.
//! 2. **Union** of all shadow polygons with i_overlay's integer engine on an exact grid.
//! 3. **Triangulation** of the union's contours with spade's constrained Delaunay
//!    triangulation; faces of odd crossing parity (inside, holes excluded) are kept.
//! 4. **Pixel clipping**: each triangle is clipped exactly against the pixel grid in `f64`
//!    (row strips, then columns), in parallel over bands of rows; the shadowed area of every
//!    pixel is accumulated and `lit = 1 - shadowed`, clamped to `[0, 1]`.
//! 5. **Evaluated pixels**: a pixel is evaluated iff its whole square sees the receiver:
//!    the receiver object's screen coverage of the square (computed with the same union,
//!    triangulation and pixel clipping) is at least `1 - 1e-9`, and no triangle of another
//!    object that lies (at least partly) on the camera's side of the receiver plane touches
//!    the closed square. The touch test is conservative: the part of the triangle on the
//!    camera's side (within `1e-9` of the receiver's extent, the precision of its plane: a
//!    far-away object must not widen it), clipped at the camera's near plane,
//!    is projected, and every pixel whose closed square, widened by `1e-7` pixels, meets it is
//!    disqualified. Triangles entirely behind the plane as seen from the camera do not count.
//!    Pixels not evaluated still get the value computed for them.
//!
//! Stages, timed under these names: `shadow polygons`, `union`, `triangulation`,
//! `pixel clipping`, `evaluated pixels`.
//!
//! # Precision
//!
//! The only approximations are the `f64` rounding of the projections and clips, and the
//! snapping of the union to i_overlay's integer grid (its float API would map a bounding box
//! onto the integers with a power-of-two scale around the box's centre; here the `i64` engine
//! is driven directly, see [`union`](self)). The grid step is `2^(e - 53)` pixels with
//! `2^e >= max(W, H)` ([`union_grid_step`]; 1.1e-13 px at 800 x 600): the finest step whose
//! grid points in the frame are all `f64`, so the union's output converts back exactly and
//! spade triangulates exactly the polygons i_overlay produced. Snapping moves an input vertex
//! by at most half a step, and crossing points by about a step (i_overlay's `Precision::HIGH`
//! snap radius); coordinates already on the grid, such as the dyadic ones of an axis-aligned
//! square under a vertical light seen by an axis-aligned orthographic camera, do not move, and
//! that case comes out exact to the last bit.
//!
//! Measured (`analysis/tests/exact.rs`, against a union computed without any grid by
//! vertical slabs from the same shadow polygons): the worst per-pixel error of everything after
//! the shadow polygons (union, triangulation, pixel clipping) is about three grid steps:
//! 1.5e-14 at 64 x 48, 2.3e-13 on `bunny-plane` and 2.9e-13 on `cage` at 800 x 600, 6.5e-13 at
//! 2000 x 1500, 1.2e-12 at 3000 x 2000. Stated bound: **4 grid steps per pixel** (4.5e-13 at
//! 800 x 600, below 1e-11 for any frame up to 16384 pixels on a side), far below the 1e-9 the
//! ground truth must meet. Against analytic areas (rotated squares, spot lights, a grazing
//! perspective view) the agreement is 1e-13 or better.
//!
//! # Choices where the issue is vague
//!
//! - Receiver: `scene.receiver_plane()` (the largest visible planar object). `exact` does not
//!   apply (`ReferenceError::NotApplicable`) when the scene has transparency, when
//!   `planar_receiver` is off or there is no receiver plane, when a directional light runs
//!   parallel to the plane, or when a spot light lies in it.
//! - Caster parts: directional lights keep the part with height `h >= 0` above the plane on the
//!   light's side (triangles with every corner at `h <= 0`, e.g. lying in the plane, are
//!   dropped); spot lights also keep `h <= H`, the light's height (parts beyond the plane
//!   through the light, parallel to the receiver, cast no shadow on it). A point at height
//!   `H` projects to infinity on the plane; in homogeneous coordinates it is the receiver's
//!   horizon, which the camera maps to a finite screen point (perspective) or which the frame
//!   clip removes (orthographic), so no coordinate is ever infinite: no epsilon is needed near
//!   the light plane. The spot's cone is ignored: visibility only asks whether the segment to
//!   the light is blocked (surfaces outside the cone count as lit, as for the shadow maps).
//! - Shadow points must lie at camera depth `>= near` (perspective); orthographic cameras see
//!   every depth.
//! - Degenerate shadow polygons (fewer than three vertices, zero area, a vertex at or behind
//!   the eye) are ignored; they have no area.
//! - The receiver's own side is not considered: a receiver seen from the side away from the
//!   light gets the same visibility (its points still see the light through the open side).

mod clip;
mod shadow;
mod union;

use crate::reference::{Reference, ReferenceError, ReferenceImage};
use instrumentation::Recorder;
use methods::Frame;
use shadow::Setup;
use std::ops::Range;

/// Receiver coverage a pixel needs to be evaluated.
pub const MIN_RECEIVER_COVERAGE: f64 = 1.0 - 1e-9;

/// Widening, in pixels, of the closed pixel squares in the occluder touch test.
pub const TOUCH_EPS: f64 = 1e-7;

/// Polygons in screen space (pixels from the top-left, y down), stored flat: contour `k` is
/// `points[ranges[k].clone()]`, closed implicitly (the last point connects to the first).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ScreenPolygons {
    /// All vertices, contour after contour.
    pub points: Vec<[f64; 2]>,
    /// The vertex range of each contour.
    pub ranges: Vec<Range<usize>>,
}

impl ScreenPolygons {
    /// Appends a contour.
    pub fn push(&mut self, contour: &[[f64; 2]]) {
        let start = self.points.len();
        self.points.extend_from_slice(contour);
        self.ranges.push(start..self.points.len());
    }

    /// Number of contours.
    pub fn len(&self) -> usize {
        self.ranges.len()
    }

    /// Whether there is no contour.
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// The contours, each as a slice of vertices.
    pub fn contours(&self) -> impl Iterator<Item = &[[f64; 2]]> + '_ {
        self.ranges.iter().map(|r| &self.points[r.clone()])
    }

    /// Sum of the contours' signed areas (shoelace, screen coordinates). For a union's
    /// contours (outer contours one way, holes the other) its absolute value is the union's
    /// area.
    pub fn signed_area(&self) -> f64 {
        self.contours()
            .map(|c| {
                let n = c.len();
                0.5 * (0..n)
                    .map(|k| {
                        let (p, q) = (c[k], c[(k + 1) % n]);
                        p[0] * q[1] - q[0] * p[1]
                    })
                    .sum::<f64>()
            })
            .sum()
    }
}

/// The exact reference for planar receivers (name `exact`; no options).
#[derive(Debug, Clone, Copy, Default)]
pub struct ExactCoverage;

impl Reference for ExactCoverage {
    fn name(&self) -> &'static str {
        "exact"
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        serde_json::Map::new()
    }

    fn evaluate(
        &self,
        frame: &Frame<'_>,
        rec: &mut Recorder,
    ) -> Result<ReferenceImage, ReferenceError> {
        evaluate(frame, rec)
    }
}

/// The screen-space shadow polygons of every caster, before the union: each the shadow of one
/// caster triangle on the receiver plane, clipped to the frame, with positive shoelace area in
/// screen coordinates ([`ScreenPolygons::signed_area`]).
pub fn shadow_polygons(frame: &Frame<'_>) -> Result<ScreenPolygons, ReferenceError> {
    Ok(Setup::new(frame)?.shadow_polygons(frame))
}

/// The union of the shadow polygons in screen space, exactly as `exact` triangulates it:
/// outer contours and holes, whose interior is the set of points of odd crossing parity
/// (fill with the even-odd rule).
pub fn shadow_union(frame: &Frame<'_>) -> Result<ScreenPolygons, ReferenceError> {
    let setup = Setup::new(frame)?;
    let step = union::grid_step(setup.width, setup.height);
    Ok(union::union(&setup.shadow_polygons(frame), step))
}

/// The grid step, in pixels, on which `exact` forms unions for a `width x height` frame:
/// `2^(e - 53)` with `2^e >= max(width, height)` (`2^-43` at 800 x 600).
pub fn union_grid_step(width: u32, height: u32) -> f64 {
    union::grid_step(f64::from(width), f64::from(height))
}

/// Area of every pixel covered by the union of `polys` (all of one orientation).
fn covered_area(polys: &ScreenPolygons, w: usize, h: usize, step: f64) -> Vec<f64> {
    let (tris, _) = union::triangulate(&union::union(polys, step));
    clip::accumulate_area(&tris, w, h)
}

fn evaluate(frame: &Frame<'_>, rec: &mut Recorder) -> Result<ReferenceImage, ReferenceError> {
    let setup = Setup::new(frame)?;
    let (width, height) = (frame.width(), frame.height());
    let (w, h) = (width as usize, height as usize);
    let step = union::grid_step(setup.width, setup.height);
    let polys = rec.stages.time("shadow polygons", || setup.shadow_polygons(frame));
    let contours = rec.stages.time("union", || union::union(&polys, step));
    let (tris, conflicts) = rec.stages.time("triangulation", || union::triangulate(&contours));
    let shadowed = rec.stages.time("pixel clipping", || clip::accumulate_area(&tris, w, h));
    let evaluated = rec.stages.time("evaluated pixels", || {
        let coverage = covered_area(&setup.receiver_polygons(frame), w, h, step);
        let mut touched = vec![false; w * h];
        clip::mark_touched(&setup.occluder_polygons(frame), w, h, TOUCH_EPS, &mut touched);
        coverage
            .iter()
            .zip(&touched)
            .map(|(&c, &t)| c >= MIN_RECEIVER_COVERAGE && !t)
            .collect::<Vec<bool>>()
    });
    rec.notes.push(format!(
        "exact: {} shadow polygons, union of {} contours ({} vertices), {} triangles",
        polys.len(),
        contours.len(),
        contours.points.len(),
        tris.len()
    ));
    if conflicts > 0 {
        rec.notes.push(format!(
            "exact: spade skipped {conflicts} crossing constraint edges of the union; values \
             near them may be off"
        ));
    }
    let lit = shadowed
        .iter()
        .map(|&a| if a.is_nan() { 0.0 } else { (1.0 - a).clamp(0.0, 1.0) })
        .collect();
    Ok(ReferenceImage { width, height, lit, evaluated, transmittance: None })
}
