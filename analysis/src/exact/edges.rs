//! Edge pixels: the triangles their rays can meet, for `raytrace`.
//!
//! `exact` leaves its `edge` pixels to `raytrace` and knows, for each, the triangles whose
//! screen polygon overlaps it (`Classes::edge_overlaps`: every camera ray through the pixel
//! hits one of them or none), and the light-space grid gives the casters that can shadow a
//! point ([`CasterGrid::query_part`]). The edge pixels are traced in one of three ways,
//! chosen by [`EdgeTrace::choose`]:
//!
//! - **Listed**: each ray is tested against its pixel's triangles and the casters the grid
//!   returns for its shadow ray's start, with no BVH ([`EdgeLists`], `raytrace`'s listed
//!   tracer), when the edge pixels' sub-samples are few beside the triangles: on
//!   `bunny-plane` at 800 x 600 and one sample per pixel, 2,873 edge pixels (5,263 rays)
//!   among 75,410 triangles, where the BVH build over every triangle took 15 ms of `exact`'s
//!   255.
//! - **Among**: the BVHs are built over the pixels' triangles and the casters the grid
//!   returns for the part of each a pixel sees ([`edge_casters`]), when the (pixel, triangle)
//!   overlaps are far fewer than the triangles (on `bumpy`, 10,304 of 530,688 triangles are
//!   kept).
//! - Otherwise the BVHs hold every triangle.
//!
//! The three give the same lit fractions bit for bit (tested below): the lists hold every
//! triangle a ray can meet, and every decision is the ray tracer's own `f64` test.

use super::casters::{Candidates, CasterGrid};
use super::shadow::{plane_depth, Screen};
use crate::raytrace::TriangleLists;
use glam::DVec3;
use methods::Frame;
use rayon::prelude::*;

/// How the edge pixels are traced.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum EdgeTrace {
    /// Every ray against its lists, no BVH ([`EdgeLists`]).
    Listed,
    /// BVHs over the triangles of the lists only ([`edge_casters`]).
    Among,
    /// BVHs over every triangle.
    All,
}

/// The lists serve without BVHs when the edge pixels' sub-samples, times this, are fewer than
/// the triangles: a listed sub-sample tests its pixel's triangles and one grid query's
/// casters (a few tens), against a BVH build over every triangle.
const LISTED_RATIO: usize = 4;

/// The BVHs are built over the lists' triangles only when the (pixel, triangle) overlaps of
/// the edge pixels, times this, are fewer than the triangles: each costs a grid query.
const AMONG_RATIO: usize = 8;

impl EdgeTrace {
    /// The way to trace `edge_pixels` pixels of `rate` sub-samples, whose (pixel, triangle)
    /// overlaps number `overlaps`, among `triangles` triangles.
    pub(crate) fn choose(
        edge_pixels: usize,
        rate: usize,
        overlaps: usize,
        triangles: usize,
    ) -> Self {
        if edge_pixels.saturating_mul(rate).saturating_mul(LISTED_RATIO) < triangles {
            EdgeTrace::Listed
        } else if overlaps.saturating_mul(AMONG_RATIO) < triangles {
            EdgeTrace::Among
        } else {
            EdgeTrace::All
        }
    }
}

/// The triangles the rays of the edge pixels can meet, as a mask over the triangles: those
/// overlapping the pixels (`edge_overlaps`, `(pixel, triangle)`: every camera ray's hit lies
/// on one of them) and the casters the grid returns for the part of each such triangle the
/// pixel sees (every caster that can shadow a point of it). That part lies within the
/// quadrilateral where the rays through the pixel's corners meet the triangle's plane, when
/// all four meet it in front of the camera; otherwise the whole triangle is asked for.
pub(crate) fn edge_casters(
    frame: &Frame<'_>,
    grid: &CasterGrid<'_>,
    edge_overlaps: &[(u32, u32)],
) -> Vec<bool> {
    let g = &frame.geometry;
    let screen = Screen::new(frame);
    let w = frame.width() as usize;
    let found: Vec<Vec<u32>> = edge_overlaps
        .par_chunks(256)
        .map_init(Candidates::default, |candidates, run| {
            let mut found = Vec::new();
            for &(k, t) in run {
                let tri = g.corners(t as usize);
                let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
                let part = screen.corner_rays(k as usize % w, k as usize / w).map(|ray| {
                    let depth = plane_depth(&ray, n, tri[0]);
                    (depth.is_finite() && depth > 0.0).then(|| ray.origin + depth * ray.direction)
                });
                let part = match part {
                    [Some(a), Some(b), Some(c), Some(d)] => Some([a, b, c, d]),
                    _ => None,
                };
                grid.query_part(&tri, part.as_ref(), candidates);
                found.push(t);
                found.extend_from_slice(&candidates.casters);
            }
            found
        })
        .collect();
    let mut among = vec![false; g.len()];
    for &t in found.iter().flatten() {
        among[t as usize] = true;
    }
    among
}

/// The edge pixels' lists, for `raytrace`'s listed tracer: a pixel's overlapping triangles,
/// and for a shadow ray, the casters the grid returns for its start point (the segment from
/// a point to the light is one point of light space, so a grid query for the point alone is
/// as conservative as one for the triangle it lies on, and returns far fewer casters than a
/// query for the triangle or the pixel's part of it, which near the horizon spans the
/// frame).
pub(crate) struct EdgeLists<'a> {
    frame: &'a Frame<'a>,
    grid: &'a CasterGrid<'a>,
    /// The pixel of each overlap, ascending, and its triangle.
    pixels: Vec<u32>,
    triangles: Vec<u32>,
}

impl<'a> EdgeLists<'a> {
    /// The lists of the pixels of `edge_overlaps` (`(pixel, triangle)`, by ascending pixel),
    /// their casters from `grid`.
    pub(crate) fn new(
        frame: &'a Frame<'a>,
        grid: &'a CasterGrid<'a>,
        edge_overlaps: &[(u32, u32)],
    ) -> Self {
        debug_assert!(edge_overlaps.windows(2).all(|p| p[0].0 <= p[1].0));
        Self {
            frame,
            grid,
            pixels: edge_overlaps.iter().map(|&(k, _)| k).collect(),
            triangles: edge_overlaps.iter().map(|&(_, t)| t).collect(),
        }
    }
}

impl TriangleLists for EdgeLists<'_> {
    type Scratch = Candidates;

    fn camera(&self, i: u32, j: u32) -> &[u32] {
        let k = j * self.frame.width() + i;
        let from = self.pixels.partition_point(|&p| p < k);
        let to = from + self.pixels[from..].partition_point(|&p| p == k);
        &self.triangles[from..to]
    }

    fn casters<'s>(&self, t: u32, point: DVec3, scratch: &'s mut Candidates) -> &'s [u32] {
        let tri = self.frame.geometry.corners(t as usize);
        self.grid.query_part(&tri, Some(&[point; 4]), scratch);
        &scratch.casters
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact::classify;
    use crate::pixel_class::PixelClass;
    use crate::raytrace::RayTrace;
    use instrumentation::Recorder;
    use methods::pattern::{PatternKind, SamplePattern};

    /// The edge pixels traced among the triangles `edge_casters` keeps, and traced against
    /// their lists without BVHs, give the same lit fractions, bit for bit, as traced among all
    /// triangles: directional and spot lights, self-shadowing surfaces, planes seen at grazing
    /// angles, 1 and 16 sub-samples per pixel.
    #[test]
    fn edge_pixels_traced_by_their_lists_equal_all_triangles() {
        for rate in [1, 16] {
            let rt =
                RayTrace { pattern: SamplePattern::new(rate, PatternKind::Grid).expect("rate") };
            for name in ["bumpy", "cage", "spot-spheres", "plane-square"] {
                let scene = scenes::load(name).expect("built-in");
                let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
                let classes = classify(&frame);
                let edges: Vec<bool> =
                    classes.class.iter().map(|&c| c == PixelClass::Edge).collect();
                let mut triangles: Vec<u32> =
                    classes.edge_overlaps.iter().map(|&(_, t)| t).collect();
                triangles.sort_unstable();
                triangles.dedup();
                let grid = CasterGrid::new(&frame, &triangles);
                let among = edge_casters(&frame, &grid, &classes.edge_overlaps);
                let kept = among.iter().filter(|&&a| a).count();
                let some = rt.evaluate_pixels_among(
                    &frame,
                    Some(&edges),
                    Some(&among),
                    &mut Recorder::default(),
                );
                // The listed tracer asks the grid of the surface receivers, whose region need
                // not cover the edge pixels' points.
                let mut marked = vec![false; frame.geometry.len()];
                for k in (0..edges.len()).filter(|&k| classes.class[k] == PixelClass::Surface) {
                    classes.tiles_of(k).iter().for_each(|&t| marked[t as usize] = true);
                }
                let receivers: Vec<u32> =
                    (0..marked.len() as u32).filter(|&t| marked[t as usize]).collect();
                let surface_grid = CasterGrid::new(&frame, &receivers);
                let lists = EdgeLists::new(&frame, &surface_grid, &classes.edge_overlaps);
                let mut rec = Recorder::default();
                let listed = rt.evaluate_pixels_listed(&frame, &edges, &lists, &mut rec);
                let all = rt.evaluate_pixels(&frame, Some(&edges), &mut Recorder::default());
                let (some, listed, all) =
                    (some.expect("traces"), listed.expect("traces"), all.expect("traces"));
                let traced = edges.iter().filter(|&&e| e).count();
                assert!(traced > 50, "{name}: {traced} edge pixels");
                assert!(some.lit == all.lit && some.evaluated == all.evaluated, "{name}");
                assert!(listed.lit == all.lit && listed.evaluated == all.evaluated, "{name}");
                assert!(
                    all.lit.iter().zip(&edges).any(|(&l, &e)| e && l < 1.0),
                    "{name}: some edge pixel is shadowed"
                );
                let rays = (traced * rate as usize) as u64;
                assert!(rec.counters.rays_traced > rays, "{name}: camera and shadow rays");
                assert!(rec.stages.skipped.iter().any(|s| s == crate::raytrace::STAGE_BVH_BUILD));
                if name == "bumpy" {
                    assert!(kept * 4 < among.len(), "{name}: {kept} of {}", among.len());
                }
            }
        }
    }

    /// The listed tracer serves few sub-samples among many triangles, the BVHs over the lists'
    /// triangles few overlaps, and every triangle otherwise.
    #[test]
    fn the_way_to_trace_follows_the_counts() {
        assert_eq!(EdgeTrace::choose(5_263, 1, 40_000, 75_410), EdgeTrace::Listed);
        assert_eq!(EdgeTrace::choose(5_263, 16, 40_000, 75_410), EdgeTrace::All);
        assert_eq!(EdgeTrace::choose(8_000, 64, 10_304, 530_688), EdgeTrace::Among);
        assert_eq!(EdgeTrace::choose(usize::MAX, usize::MAX, usize::MAX, 10), EdgeTrace::All);
    }
}
