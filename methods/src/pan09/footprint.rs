//! Convex footprints on the light's image plane (projected facets and triangles) and the
//! texel tests of the software rasterization (section 3.3, Fig. 5).
//!
//! A texel inside a footprint's bounding rectangle intersects the footprint unless one of the
//! footprint's own edges separates them (separating axis theorem; the axes of the texel's
//! edges need no test, their projections overlap inside the rectangle). The tests here are
//! *conservative*: a texel whose closed square touches the closed footprint, or lies within a
//! rounding margin of it, passes, so no texel holding a point of the footprint is ever lost.

use glam::DVec2;

/// Most corners a footprint can have: a pixel square clipped by up to four half-planes.
pub const MAX_CORNERS: usize = 8;

/// A convex polygon on the light's image plane, in texel units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footprint {
    corners: [DVec2; MAX_CORNERS],
    count: usize,
    /// Bounding box.
    pub lo: DVec2,
    /// Bounding box.
    pub hi: DVec2,
    /// Whether the corners are counter-clockwise in image coordinates (positive area); a
    /// footprint of zero area is tested by its bounding box only.
    orientation: f64,
}

impl Footprint {
    /// The footprint with the given corners in order (either winding); `None` when there are
    /// fewer than one or more than [`MAX_CORNERS`] corners, or one is not finite.
    pub fn new(points: &[DVec2]) -> Option<Self> {
        if points.is_empty() || points.len() > MAX_CORNERS || !points.iter().all(|p| p.is_finite())
        {
            return None;
        }
        let mut corners = [DVec2::ZERO; MAX_CORNERS];
        corners[..points.len()].copy_from_slice(points);
        let (lo, hi) = points.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let area: f64 =
            (0..points.len()).map(|i| points[i].perp_dot(points[(i + 1) % points.len()])).sum();
        let scale = (hi - lo).max_element().max(f64::MIN_POSITIVE);
        // Areas within rounding of zero (collinear corners) fall back to the box test.
        let orientation = if area.abs() <= 1e-12 * scale * scale { 0.0 } else { area.signum() };
        Some(Self { corners, count: points.len(), lo, hi, orientation })
    }

    /// The corners.
    pub fn corners(&self) -> &[DVec2] {
        &self.corners[..self.count]
    }

    /// The texels `(x0, y0, x1, y1)` (inclusive) of a `res x res` map whose closed squares
    /// meet the bounding box, or `None` when the box misses the map.
    #[inline]
    pub fn texel_rect(&self, res: u32) -> Option<(usize, usize, usize, usize)> {
        let r = f64::from(res);
        if !(self.hi.x >= 0.0 && self.hi.y >= 0.0 && self.lo.x <= r && self.lo.y <= r) {
            return None;
        }
        // Texel x covers [x, x + 1]: it meets [lo, hi] when x <= hi and x + 1 >= lo.
        let first = |v: f64| (v - 1.0).ceil().max(0.0) as usize;
        let last = |v: f64| v.floor().min(r - 1.0) as usize;
        Some((first(self.lo.x), first(self.lo.y), last(self.hi.x), last(self.hi.y)))
    }

    /// The texels `x0..=x1` of row `y` (clamped to `0..res`) whose closed squares may meet the
    /// footprint: those meeting the footprint's x-extent over the strip `y <= Y <= y + 1`,
    /// widened by a rounding margin; `None` when the footprint misses the strip.
    #[inline]
    pub fn row_texels(&self, y: usize, res: u32) -> Option<(usize, usize)> {
        let (lo, hi) = (y as f64, y as f64 + 1.0);
        let (mut xmin, mut xmax) = (f64::INFINITY, f64::NEG_INFINITY);
        let pts = self.corners();
        for i in 0..self.count {
            let (a, b) = (pts[i], pts[(i + 1) % self.count]);
            let (ylo, yhi) = (a.y.min(b.y).max(lo), a.y.max(b.y).min(hi));
            if ylo > yhi {
                continue;
            }
            let xs = if a.y == b.y {
                (a.x.min(b.x), a.x.max(b.x))
            } else {
                let at = |v: f64| a.x + (v - a.y) * (b.x - a.x) / (b.y - a.y);
                let (p, q) = (at(ylo), at(yhi));
                (p.min(q), q.max(p))
            };
            xmin = xmin.min(xs.0);
            xmax = xmax.max(xs.1);
        }
        if xmin > xmax {
            return None;
        }
        let margin = 1e-9 * (1.0 + xmin.abs().max(xmax.abs()));
        let r = f64::from(res);
        let (first, last) =
            ((xmin - margin - 1.0).ceil().max(0.0), (xmax + margin).floor().min(r - 1.0));
        (first <= last).then_some((first as usize, last as usize))
    }

    /// Whether the closed texel square `[x, x + 1] x [y, y + 1]` meets the footprint (up to a
    /// rounding margin, conservatively). The texel should meet the bounding box.
    #[inline]
    pub fn touches_texel(&self, x: usize, y: usize) -> bool {
        if self.orientation == 0.0 {
            return true;
        }
        let lo = DVec2::new(x as f64, y as f64);
        let hi = lo + DVec2::ONE;
        let pts = self.corners();
        for i in 0..self.count {
            let (a, b) = (pts[i], pts[(i + 1) % self.count]);
            let e = (b - a) * self.orientation;
            // Inside is where e.perp_dot(p - a) >= 0; the texel corner farthest inside:
            let px = if e.y < 0.0 { hi.x } else { lo.x };
            let py = if e.x > 0.0 { hi.y } else { lo.y };
            let (u, v) = (e.x * (py - a.y), e.y * (px - a.x));
            let margin = 1e-9 * (u.abs() + v.abs()) + 1e-300;
            if u - v < -margin {
                return false;
            }
        }
        true
    }
}

/// The parameter interval `[t0, t1]` of the segment `p0 + t (p1 - p0)`, `t` in `[0, 1]`, that
/// lies in the closed box `lo..=hi` widened by `margin` (Liang-Barsky), or `None`.
#[inline]
pub fn clip_segment(p0: DVec2, p1: DVec2, lo: DVec2, hi: DVec2, margin: f64) -> Option<(f64, f64)> {
    let d = p1 - p0;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-d.x, p0.x - (lo.x - margin)),
        (d.x, (hi.x + margin) - p0.x),
        (-d.y, p0.y - (lo.y - margin)),
        (d.y, (hi.y + margin) - p0.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Whether point `p` lies in the closed convex polygon (either winding).
    fn inside(poly: &[DVec2], p: DVec2) -> bool {
        let signs: Vec<f64> = (0..poly.len())
            .map(|i| (poly[(i + 1) % poly.len()] - poly[i]).perp_dot(p - poly[i]))
            .collect();
        signs.iter().all(|&s| s >= 0.0) || signs.iter().all(|&s| s <= 0.0)
    }

    fn convex_hull(mut pts: Vec<DVec2>) -> Vec<DVec2> {
        pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        pts.dedup();
        if pts.len() < 3 {
            return pts;
        }
        let mut hull: Vec<DVec2> = Vec::new();
        for pass in 0..2 {
            let start = hull.len();
            let iter: Box<dyn Iterator<Item = &DVec2>> =
                if pass == 0 { Box::new(pts.iter()) } else { Box::new(pts.iter().rev()) };
            for &p in iter {
                while hull.len() >= start + 2
                    && (hull[hull.len() - 1] - hull[hull.len() - 2])
                        .perp_dot(p - hull[hull.len() - 2])
                        <= 0.0
                {
                    hull.pop();
                }
                hull.push(p);
            }
            hull.pop();
        }
        hull
    }

    proptest! {
        /// Every texel holding a point of the footprint (sampled on a fine grid) passes the
        /// test, and texels the test passes lie in the bounding rectangle.
        #[test]
        fn texel_test_is_conservative(
            raw in proptest::collection::vec((0u32..=64, 0u32..=64), 3..7),
            reverse in any::<bool>(),
        ) {
            let pts: Vec<DVec2> =
                raw.iter().map(|&(x, y)| DVec2::new(f64::from(x) / 8.0, f64::from(y) / 8.0)).collect();
            let mut hull = convex_hull(pts);
            prop_assume!(hull.len() >= 3 && hull.len() <= MAX_CORNERS);
            if reverse {
                hull.reverse();
            }
            let f = Footprint::new(&hull).expect("finite");
            let (x0, y0, x1, y1) = f.texel_rect(8).expect("inside the map");
            for j in 0..=64 {
                for i in 0..=64 {
                    let p = DVec2::new(f64::from(i) / 8.0, f64::from(j) / 8.0);
                    if !inside(&hull, p) {
                        continue;
                    }
                    // Every texel whose closed square holds p.
                    for ty in (p.y.ceil() as usize).saturating_sub(1)..=(p.y.floor() as usize).min(7) {
                        for tx in (p.x.ceil() as usize).saturating_sub(1)..=(p.x.floor() as usize).min(7) {
                            prop_assert!((x0..=x1).contains(&tx) && (y0..=y1).contains(&ty));
                            prop_assert!(f.touches_texel(tx, ty), "texel ({}, {}) holds {}", tx, ty, p);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn texel_test_rejects_separated_texels() {
        // A thin diagonal sliver crosses texels (0,0), (1,1), (2,2); its box reaches x = 3 and
        // y = 3, where texels of column and row 3 touch the box but not the sliver.
        let f = Footprint::new(&[
            DVec2::new(0.1, 0.0),
            DVec2::new(3.0, 2.9),
            DVec2::new(2.9, 3.0),
            DVec2::new(0.0, 0.1),
        ])
        .expect("finite");
        assert_eq!(f.texel_rect(8), Some((0, 0, 3, 3)));
        let cases = [(0, 0, true), (1, 1, true), (2, 2, true), (2, 0, false), (0, 2, false)];
        for (x, y, hit) in cases.into_iter().chain([(3, 3, false), (3, 2, true)]) {
            assert_eq!(f.touches_texel(x, y), hit, "({x}, {y})");
        }
        assert_eq!(Footprint::new(&[DVec2::new(-3.0, -3.0)]).expect("finite").texel_rect(8), None);
        assert!(Footprint::new(&[DVec2::new(f64::NAN, 0.0)]).is_none());
    }

    proptest! {
        /// Every texel the edge test passes lies in its row's span.
        #[test]
        fn row_spans_hold_every_touched_texel(
            raw in proptest::collection::vec((0u32..=64, 0u32..=64), 3..7),
        ) {
            let pts: Vec<DVec2> =
                raw.iter().map(|&(x, y)| DVec2::new(f64::from(x) / 8.0, f64::from(y) / 8.0)).collect();
            let hull = convex_hull(pts);
            prop_assume!(hull.len() >= 3);
            let f = Footprint::new(&hull).expect("finite");
            let (x0, y0, x1, y1) = f.texel_rect(8).expect("inside the map");
            for y in y0..=y1 {
                let span = f.row_texels(y, 8);
                for x in x0..=x1 {
                    if f.touches_texel(x, y) {
                        prop_assert!(span.is_some_and(|(a, b)| a <= x && x <= b), "({}, {}) {:?}", x, y, span);
                    }
                }
            }
        }
    }

    #[test]
    fn segments_clip_to_closed_boxes() {
        let (lo, hi) = (DVec2::ZERO, DVec2::ONE);
        let c = clip_segment(DVec2::new(-1.0, 0.5), DVec2::new(3.0, 0.5), lo, hi, 0.0);
        assert_eq!(c, Some((0.25, 0.5)));
        // Touching a corner counts.
        let c = clip_segment(DVec2::new(1.0, 2.0), DVec2::new(2.0, 1.0), lo + 1.0, hi + 1.0, 0.0);
        assert_eq!(c, Some((0.0, 1.0)));
        assert_eq!(clip_segment(DVec2::new(2.0, 0.0), DVec2::new(2.0, 1.0), lo, hi, 0.0), None);
        assert!(clip_segment(DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0), lo, hi, 0.0).is_some());
    }
}
