//! Union of screen polygons with i_overlay's integer engine, and triangulation of the union
//! with spade's constrained Delaunay triangulation.
//!
//! i_overlay computes on integer coordinates. Its float API maps a bounding rectangle onto the
//! integer grid with a power-of-two scale around the rectangle's centre; here the integer
//! engine (`i64`) is driven directly with a grid chosen so that converting back is exact: with
//! every coordinate in `[0, 2^e]` (`2^e >= max(width, height)`), the grid step is
//! `2^(e - 53)` pixels, the finest step at which every grid point up to `2^e` is an `f64`. An
//! input coordinate moves by at most half a step when snapped (not at all when it is already a
//! multiple of the step, e.g. any dyadic value with few bits), integer magnitudes stay below
//! `2^53`, far inside the engine's 61-bit budget. i_overlay's solver runs at
//! `Precision::HIGH`: crossing points within one grid step of an edge's end snap to it, and the
//! radius doubles only on repeated splitting passes (`Precision::ABSOLUTE`, which never widens
//! it, does not terminate on the built-in scene `grazing`).

use super::clip::Pt;
use super::ScreenPolygons;
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay::{ContourDirection, IntOverlayOptions, Overlay, ShapeType};
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::core::solver::{Precision, Solver, Strategy};
use i_overlay::i_float::int::point::IntPoint;
use i_overlay::i_shape::flat::buffer::FlatContoursBuffer;
use spade::{ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation};

/// Grid step (pixels) of the union for a `width x height` frame: `2^(e - 53)` with
/// `2^e >= max(width, height)`.
pub fn grid_step(width: f64, height: f64) -> f64 {
    let size = width.max(height).max(1.0);
    let e = size.log2().ceil() as i32;
    2f64.powi(e - 53)
}

/// The union of the polygons (each simple, all of one orientation: callers orient them
/// counter-clockwise), on the grid of step `step` (see [`grid_step`]). Returns the union's
/// contours: outer contours and holes, whose interior is the set of points of odd crossing
/// parity.
pub(crate) fn union(polys: &ScreenPolygons, step: f64) -> ScreenPolygons {
    overlay(polys, None, step)
}

/// The union of the polygons (as [`union`]) intersected with the convex polygon `within`, in
/// one overlay: the boundary the two share is `within`'s own edges, once.
pub(crate) fn union_within(
    polys: &ScreenPolygons,
    within: &[[f64; 2]],
    step: f64,
) -> ScreenPolygons {
    overlay(polys, Some(within), step)
}

fn overlay(polys: &ScreenPolygons, within: Option<&[[f64; 2]]>, step: f64) -> ScreenPolygons {
    let (points, ranges) = (&polys.points, &polys.ranges);
    if ranges.is_empty() {
        return ScreenPolygons::default();
    }
    let scale = 1.0 / step;
    let options = IntOverlayOptions {
        preserve_input_collinear: false,
        output_direction: ContourDirection::CounterClockwise,
        preserve_output_collinear: false,
        min_output_area: 0,
        ogc: false,
    };
    let solver = Solver::with_strategy_and_precision(Strategy::Auto, Precision::HIGH);
    let snap = move |p: &[f64; 2]| {
        IntPoint::new((p[0] * scale).round() as i64, (p[1] * scale).round() as i64)
    };
    let mut overlay = Overlay::<i64>::new_custom(points.len() + 8, options, solver);
    for r in ranges {
        overlay.add_path_iter(points[r.clone()].iter().map(snap), ShapeType::Subject);
    }
    let rule = match within {
        Some(c) => {
            overlay.add_path_iter(c.iter().map(snap), ShapeType::Clip);
            OverlayRule::Intersect
        }
        None => OverlayRule::Subject,
    };
    let mut out = FlatContoursBuffer::<i64>::with_capacity(0);
    overlay.overlay_into(rule, FillRule::NonZero, &mut out);
    let points = out.points.iter().map(|p| [p.x as f64 * step, p.y as f64 * step]).collect();
    ScreenPolygons { points, ranges: out.ranges }
}

/// Triangles covering the interior (odd crossing parity) of the closed contours, from spade's constrained Delaunay triangulation with the contour edges
/// as constraints; and the number of constraint edges spade had to skip because they crossed
/// another (0 for a valid union).
pub(crate) fn triangulate(contours: &ScreenPolygons) -> (Vec<[Pt; 3]>, usize) {
    let (points, ranges) = (&contours.points, &contours.ranges);
    if ranges.is_empty() {
        return (Vec::new(), 0);
    }
    let vertices: Vec<Point2<f64>> = points.iter().map(|p| Point2::new(p[0], p[1])).collect();
    let mut edges = Vec::with_capacity(points.len());
    for r in ranges {
        for k in r.clone() {
            let next = if k + 1 == r.end { r.start } else { k + 1 };
            if points[k] != points[next] {
                edges.push([k, next]);
            }
        }
    }
    let mut conflicts = 0usize;
    let cdt =
        ConstrainedDelaunayTriangulation::<Point2<f64>>::try_bulk_load_cdt(vertices, edges, |_| {
            conflicts += 1
        });
    let Ok(mut cdt) = cdt else {
        // Only non-finite or out-of-range coordinates fail; the union has neither.
        return (Vec::new(), conflicts + 1);
    };
    let result = cdt.refine(
        RefinementParameters::<f64>::new()
            .exclude_outer_faces(true)
            .with_max_additional_vertices(0),
    );
    let mut excluded = vec![false; cdt.num_all_faces()];
    for f in &result.excluded_faces {
        if let Some(e) = excluded.get_mut(f.index()) {
            *e = true;
        }
    }
    let tris = cdt
        .inner_faces()
        .filter(|f| !excluded[f.fix().index()])
        .map(|f| f.positions().map(|p| [p.x, p.y]))
        .collect();
    (tris, conflicts)
}
