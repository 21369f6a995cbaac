//! Stage "silhouette mask map" (section 3.2, Fig. 4a): every texel a silhouette edge touches
//! is marked, unless the edge is hidden there behind nearer geometry.
//!
//! **Conservative rasterization.** The paper draws each edge as a line of width 2 with points
//! of size 3 at its ends and keeps the fragments the edge actually crosses. Here every texel
//! whose closed square meets the projected segment (widened by [`EDGE_MARGIN`] texels against
//! rounding) is visited: the segment is clipped to each candidate texel exactly
//! (Liang-Barsky), which also gives the part of the edge inside the texel. Spot lights clip
//! edges at their `near` plane first.
//!
//! **Hidden silhouettes.** "If the depth value stored in the depth map is smaller, then all
//! silhouette edges in this texel are occluded by triangles closer to the light source". A
//! texel's single centre sample cannot tell that soundly: an edge can be visible in a corner
//! of the texel that the centre's surface does not cover. We compare against the depth map's
//! nine samples around the texel (its centre and its eight neighbours' centres): the edge is
//! hidden in the texel when its nearest point inside the texel lies farther from the light
//! than every one of the nine surfaces, each by more than the shared depth tolerance
//! ([`crate::depth_test::DepthTester::tolerance`] with a reach of 1.5 texels per axis, the
//! farthest a point of the texel lies from a neighbour's centre). A visible edge crossing the
//! texel has samples on both sides, and the surface seen on its far side lies at or beyond
//! the edge, so it keeps the texel marked; texels on the map's border lack neighbours and are
//! never hidden.

use super::footprint::clip_segment;
use crate::depth_map::LightDepthMap;
use crate::depth_test::DepthTester;
use crate::raster::{clip_near, NO_TRIANGLE};
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use scenes::Geometry;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// Widening of every texel, in texels, when testing whether an edge touches it.
pub const EDGE_MARGIN: f64 = 1e-7;

/// The depth beyond which a silhouette edge is hidden in a texel: the largest of its nine
/// samples' depth plus tolerance (`f64::INFINITY` where some sample sees no caster or lies
/// off the map). Computed on demand for the texels edges touch, and remembered.
pub struct HiddenDepths<'a> {
    geometry: &'a Geometry,
    map: &'a LightDepthMap,
    tester: &'a DepthTester,
    /// Depth plus tolerance per texel, `f64` bits; [`UNKNOWN`] until computed.
    reach: Vec<AtomicU64>,
    /// Hidden depth per texel, `f64` bits; [`UNKNOWN`] until computed.
    memo: Vec<AtomicU64>,
}

/// Marks a value not computed yet (a NaN no computation yields).
const UNKNOWN: u64 = 0x7ff8_dead_beef_0001;

/// Reach of the tolerance: the farthest a point of a texel lies from a neighbour's centre.
const REACH: f64 = 1.5;

impl<'a> HiddenDepths<'a> {
    /// The hidden depths of `map`, with the tolerances of `tester`.
    pub fn new(geometry: &'a Geometry, map: &'a LightDepthMap, tester: &'a DepthTester) -> Self {
        let n = map.res as usize * map.res as usize;
        let unknown = || (0..n).map(|_| AtomicU64::new(UNKNOWN)).collect();
        Self { geometry, map, tester, reach: unknown(), memo: unknown() }
    }

    /// Depth plus tolerance of the sample of texel `k`.
    fn reach(&self, k: usize) -> f64 {
        let known = self.reach[k].load(Ordering::Relaxed);
        if known != UNKNOWN {
            return f64::from_bits(known);
        }
        let map = self.map;
        let res = map.res as usize;
        let (z, t) = (map.depth[k], map.triangle[k]);
        let d = if t == NO_TRIANGLE || !z.is_finite() {
            f64::INFINITY
        } else {
            let xy = DVec2::new((k % res) as f64 + 0.5, (k / res) as f64 + 0.5) + map.shift;
            let [a, b, c] = self.geometry.corners(t as usize);
            let normal = (b - a).cross(c - a).normalize_or_zero();
            match self.tester.receiver(map.projector.ray(xy).at(z), normal) {
                Some(r) => z + self.tester.tolerance(&r, DVec2::splat(REACH)),
                None => f64::INFINITY,
            }
        };
        self.reach[k].store(d.to_bits(), Ordering::Relaxed);
        d
    }

    /// The hidden depth of texel `k`.
    pub fn get(&self, k: usize) -> f64 {
        let known = self.memo[k].load(Ordering::Relaxed);
        if known != UNKNOWN {
            return f64::from_bits(known);
        }
        let res = self.map.res as usize;
        let (x, y) = (k % res, k / res);
        let d = if x == 0 || y == 0 || x + 1 >= res || y + 1 >= res {
            f64::INFINITY
        } else {
            (y - 1..=y + 1)
                .flat_map(|j| (x - 1..=x + 1).map(move |i| j * res + i))
                .map(|c| self.reach(c))
                .fold(f64::NEG_INFINITY, f64::max)
        };
        self.memo[k].store(d.to_bits(), Ordering::Relaxed);
        d
    }
}

/// A silhouette edge on the light's image plane: endpoints and their light depths.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ProjectedEdge {
    p: [DVec2; 2],
    depth: [f64; 2],
    perspective: bool,
}

impl ProjectedEdge {
    /// The edge `a b` seen by `light`, clipped at a spot light's `near` plane.
    fn new(a: DVec3, b: DVec3, light: &scenes::Projector) -> Option<Self> {
        let (a, b) = if light.is_perspective() {
            let (da, db) = (light.depth_of(a), light.depth_of(b));
            if da < light.near && db < light.near {
                return None;
            }
            // Clip as the rasterizer clips triangles: the degenerate triangle (a, b, b).
            let (pts, n) = clip_near([a, b, b], [da, db, db], light.near);
            let pts = &pts[..n];
            let first = pts[0];
            let last = pts.iter().copied().find(|&q| q != first).unwrap_or(first);
            (first, last)
        } else {
            (a, b)
        };
        let (pa, da) = light.project_unclipped(a);
        let (pb, db) = light.project_unclipped(b);
        let finite = pa.is_finite() && pb.is_finite() && da.is_finite() && db.is_finite();
        finite.then_some(Self { p: [pa, pb], depth: [da, db], perspective: light.is_perspective() })
    }

    /// Light depth at parameter `t` of the image segment (`1 / depth` is affine in the image
    /// for perspective lights, depth itself for orthographic ones).
    #[inline]
    fn depth_at(&self, t: f64) -> f64 {
        let [d0, d1] = self.depth;
        if self.perspective {
            1.0 / (1.0 / d0 + t * (1.0 / d1 - 1.0 / d0))
        } else {
            d0 + t * (d1 - d0)
        }
    }
}

/// The silhouette mask map of `edges` at `res x res`: `true` where a visible silhouette edge
/// touches the texel. `hidden(k)` is the depth beyond which an edge is hidden in texel `k`
/// ([`HiddenDepths::get`]).
pub fn silhouette_mask(
    edges: &[[DVec3; 2]],
    light: &scenes::Projector,
    res: u32,
    hidden: impl Fn(usize) -> f64 + Sync,
) -> Vec<bool> {
    let n = res as usize;
    let marks: Vec<AtomicBool> = (0..n * n).map(|_| AtomicBool::new(false)).collect();
    let r = f64::from(res);
    edges.par_iter().with_min_len(64).for_each(|&[a, b]| {
        let Some(e) = ProjectedEdge::new(a, b, light) else { return };
        let [p0, p1] = e.p;
        let (lo, hi) = (p0.min(p1), p0.max(p1));
        if hi.x < -EDGE_MARGIN
            || hi.y < -EDGE_MARGIN
            || lo.x > r + EDGE_MARGIN
            || lo.y > r + EDGE_MARGIN
        {
            return;
        }
        let col = |v: f64| (v.floor().clamp(0.0, r - 1.0)) as usize;
        for x in col(lo.x - EDGE_MARGIN)..=col(hi.x + EDGE_MARGIN) {
            // The part of the edge over this column, then the rows it spans.
            let column = (DVec2::new(x as f64, 0.0), DVec2::new(x as f64 + 1.0, r));
            let Some((t0, t1)) = clip_segment(p0, p1, column.0, column.1, EDGE_MARGIN) else {
                continue;
            };
            let (y0, y1) = (p0.y + t0 * (p1.y - p0.y), p0.y + t1 * (p1.y - p0.y));
            for y in col(y0.min(y1) - EDGE_MARGIN)..=col(y0.max(y1) + EDGE_MARGIN) {
                let k = y * n + x;
                if marks[k].load(Ordering::Relaxed) {
                    continue;
                }
                let texel =
                    (DVec2::new(x as f64, y as f64), DVec2::new(x as f64 + 1.0, y as f64 + 1.0));
                let Some((u0, u1)) = clip_segment(p0, p1, texel.0, texel.1, EDGE_MARGIN) else {
                    continue;
                };
                let nearest = e.depth_at(u0).min(e.depth_at(u1));
                if nearest <= hidden(k) || nearest.is_nan() {
                    marks[k].store(true, Ordering::Relaxed);
                }
            }
        }
    });
    marks.into_iter().map(AtomicBool::into_inner).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::tests::pixel_projector;

    fn marked(mask: &[bool], res: usize) -> Vec<(usize, usize)> {
        (0..mask.len()).filter(|&k| mask[k]).map(|k| (k % res, k / res)).collect()
    }

    #[test]
    fn every_touched_texel_is_marked_and_no_other() {
        let res = 8;
        let never = vec![f64::INFINITY; 64];
        // A diagonal through texel corners touches the texels sharing those corners.
        let edge = [DVec3::new(1.0, 7.0, 0.0), DVec3::new(3.0, 5.0, 0.0)]; // image (1,1)-(3,3)
        let m = silhouette_mask(&[edge], &pixel_projector(res, res), res, |k| never[k]);
        let mut got = marked(&m, 8);
        got.sort();
        let mut want = vec![(0, 0), (1, 1), (2, 2), (3, 3), (0, 1), (1, 0), (1, 2), (2, 1)];
        want.extend([(2, 3), (3, 2)]);
        want.sort();
        assert_eq!(got, want);
        // A short edge inside one texel marks only it.
        let edge = [DVec3::new(4.2, 3.3, 0.0), DVec3::new(4.7, 3.6, 0.0)];
        assert_eq!(
            marked(&silhouette_mask(&[edge], &pixel_projector(res, res), res, |k| never[k]), 8),
            [(4, 4)]
        );
    }

    #[test]
    fn edges_behind_the_hidden_depth_are_not_marked() {
        let res = 8;
        // Edge at depth 10 - 2 = 8 across row 4; texel (2, 4) hides beyond depth 5.
        let edge = [DVec3::new(0.5, 3.5, 2.0), DVec3::new(7.5, 3.5, 2.0)];
        let mut hidden = vec![f64::INFINITY; 64];
        hidden[4 * 8 + 2] = 5.0;
        hidden[4 * 8 + 3] = 8.5;
        let m = silhouette_mask(&[edge], &pixel_projector(res, res), res, |k| hidden[k]);
        assert!(!m[4 * 8 + 2], "hidden behind a surface 3 units nearer");
        assert!(m[4 * 8 + 3], "a surface behind the edge hides nothing");
        assert_eq!(m.iter().filter(|&&b| b).count(), 7);
    }
}
