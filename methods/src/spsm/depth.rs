//! Stage 4, consistent minimum depth (Lecocq et al. 2014, section 4, Fig. 9).
//!
//! The conservative depth of Hasselgren et al. evaluates the plane at a texel corner, which
//! underestimates the depth of a triangle that covers only part of the texel. The consistent
//! minimum depth is the smallest depth the stored triangle actually spawns inside the texel:
//! the minimum of its plane over the triangle clipped to the texel square.
//!
//! Choice: the paper finds that point from the corner's barycentric coordinates, clamping
//! them to the nearest edge or vertex; we clip the (decoded) triangle against the square
//! exactly (Sutherland-Hodgman in `f64`, at most seven vertices) and take the smallest plane
//! value at the clipped polygon's vertices: the minimum of an affine function over a convex
//! polygon is at a vertex, so this is the exact value the paper's construction approximates.
//! It is computed once per texel, for the 3x3 neighbourhoods of the uncertain pixels, the only
//! texels the tangent estimate reads (a GPU would compute it per lookup; the values are the
//! same).
//! Where quantization moved a packed triangle off its texel (the clipped polygon is empty),
//! the texel keeps the conservative corner depth, clamped to the decoded vertex depths.

use super::texel::{SpsmMap, Tri};
use glam::DVec2;
use rayon::prelude::*;

/// Clips the triangle to the square `[x0, x0 + 1] x [y0, y0 + 1]`; returns the polygon.
pub fn clip_to_texel(v: &[DVec2; 3], x0: f64, y0: f64) -> ([DVec2; 7], usize) {
    let mut poly = [DVec2::ZERO; 7];
    poly[..3].copy_from_slice(v);
    let mut n = 3;
    // Keep the side where `sign * (p[axis] - bound) >= 0`.
    for (axis, bound, sign) in
        [(0, x0, 1.0), (0, x0 + 1.0, -1.0), (1, y0, 1.0), (1, y0 + 1.0, -1.0)]
    {
        let mut out = [DVec2::ZERO; 7];
        let mut m = 0;
        for k in 0..n {
            let (a, b) = (poly[k], poly[(k + 1) % n]);
            let (da, db) = (sign * (a[axis] - bound), sign * (b[axis] - bound));
            if da >= 0.0 && m < 7 {
                out[m] = a;
                m += 1;
            }
            if (da >= 0.0) != (db >= 0.0) && m < 7 {
                let t = da / (da - db);
                let mut p = a + (b - a) * t;
                p[axis] = bound;
                out[m] = p;
                m += 1;
            }
        }
        poly = out;
        n = m;
        if n == 0 {
            break;
        }
    }
    (poly, n)
}

/// The consistent minimum depth of `tri` over texel `(x, y)`, and whether it was found by
/// clipping (false: the conservative fallback).
pub fn consistent_min_depth(tri: &Tri, x: usize, y: usize) -> (f64, bool) {
    let (poly, n) = clip_to_texel(&tri.v, x as f64, y as f64);
    if n > 0 {
        let m = poly[..n].iter().map(|&p| tri.depth_at(p)).fold(f64::INFINITY, f64::min);
        return (m, true);
    }
    (conservative_depth(tri, x, y), false)
}

/// Hasselgren's conservative depth of `tri` over texel `(x, y)`: the plane at the corner
/// where it is smallest, clamped to the range of the vertex depths.
pub fn conservative_depth(tri: &Tri, x: usize, y: usize) -> f64 {
    let cx = if tri.dz.x > 0.0 { x as f64 } else { x as f64 + 1.0 };
    let cy = if tri.dz.y > 0.0 { y as f64 } else { y as f64 + 1.0 };
    let zv = tri.v.map(|p| tri.depth_at(p));
    let (lo, hi) = (zv[0].min(zv[1]).min(zv[2]), zv[0].max(zv[1]).max(zv[2]));
    let d = tri.depth_at(DVec2::new(cx, cy));
    // Every vertex depth NaN (an f32 texel whose derivatives overflowed): nothing to clamp to.
    if lo.is_nan() {
        return d;
    }
    d.clamp(lo, hi)
}

/// Consistent minimum depths of a set of texels, by texel index (row by row).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ConsistentDepths {
    index: Vec<u32>,
    depth: Vec<f32>,
}

impl ConsistentDepths {
    /// The depths of the texels `index` (ascending, no repeats), one each.
    #[cfg(feature = "gpu")]
    pub(crate) fn from_parts(index: Vec<u32>, depth: Vec<f32>) -> Self {
        debug_assert_eq!(index.len(), depth.len());
        Self { index, depth }
    }

    /// The texels, ascending, and their depths.
    #[cfg(feature = "gpu")]
    pub(crate) fn parts(&self) -> (&[u32], &[f32]) {
        (&self.index, &self.depth)
    }

    /// The stored consistent minimum depth of texel `k`, if it was computed.
    #[inline]
    pub fn get(&self, k: u32) -> Option<f64> {
        self.index.binary_search(&k).ok().map(|i| f64::from(self.depth[i]))
    }
}

/// Stage 4: the consistent minimum depth of every texel the silhouette recovery will read,
/// the 3x3 neighbourhoods of `centres` (texel indices, in any order, repeats allowed), and the
/// number of those texels where it lies above the conservative corner depth by more than the
/// texel's own error bound (the depths the correction fixes). Computed where the paper
/// computes it, for the pixels that need a tangent estimate, once per texel.
pub fn consistent_depths(map: &SpsmMap, centres: &[u32]) -> (ConsistentDepths, u64) {
    let r = i64::from(map.res);
    let mut index: Vec<u32> = centres
        .par_iter()
        .flat_map_iter(|&k| {
            let (x, y) = (i64::from(k) % r, i64::from(k) / r);
            (-1..=1).flat_map(move |dy| (-1..=1).map(move |dx| (x + dx, y + dy)))
        })
        .filter(|&(x, y)| x >= 0 && y >= 0 && x < r && y < r)
        .map(|(x, y)| (y * r + x) as u32)
        .collect();
    index.par_sort_unstable();
    index.dedup();
    let out: Vec<(f32, bool)> = index
        .par_iter()
        .map(|&k| {
            let (x, y) = ((i64::from(k) % r) as usize, (i64::from(k) / r) as usize);
            let Some(tri) = map.get(x as i64, y as i64) else {
                return (f32::INFINITY, false);
            };
            let (m, _) = consistent_min_depth(&tri, x, y);
            let corner = conservative_depth(&tri, x, y);
            let slack = tri.error_at(tri.centre + DVec2::splat(0.5));
            (m as f32, m > corner + slack)
        })
        .collect();
    let corrected = out.iter().filter(|o| o.1).count() as u64;
    (ConsistentDepths { index, depth: out.into_iter().map(|o| o.0).collect() }, corrected)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(v: [DVec2; 3], dz: DVec2) -> Tri {
        Tri {
            v,
            centre: DVec2::new(0.5, 0.5),
            z: 1.0,
            dz,
            err_z: 0.0,
            err_dz: DVec2::ZERO,
            err_v: 0.0,
        }
    }

    #[test]
    fn infinite_derivatives_give_no_panic() {
        // An f32 texel whose derivatives overflowed: every vertex depth is inf - inf = NaN,
        // which once made the clamp to the vertex depths' range panic.
        let v = [DVec2::new(1.0, 0.0), DVec2::new(2.0, 0.2), DVec2::new(1.5, -1.0)];
        let t = tri(v, DVec2::splat(f64::INFINITY));
        assert!(v.iter().all(|&p| t.depth_at(p).is_nan()));
        assert_eq!(conservative_depth(&t, 0, 0), f64::NEG_INFINITY, "the corner's own depth");
        let (m, _) = consistent_min_depth(&t, 0, 0);
        assert!(!m.is_nan(), "the smallest depth of none is infinite, not NaN");
    }

    /// The minimum over the candidate vertices of triangle ∩ square, found independently:
    /// triangle vertices in the square, square corners in the triangle, edge crossings.
    fn candidates_min(t: &Tri, x: usize, y: usize) -> f64 {
        let (x0, y0, x1, y1) = (x as f64, y as f64, x as f64 + 1.0, y as f64 + 1.0);
        let in_square = |p: DVec2| p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1;
        let mut m = f64::INFINITY;
        let mut take = |p: DVec2| m = m.min(t.depth_at(p));
        t.v.iter().filter(|p| in_square(**p)).for_each(|&p| take(p));
        let corners =
            [DVec2::new(x0, y0), DVec2::new(x1, y0), DVec2::new(x1, y1), DVec2::new(x0, y1)];
        corners.iter().filter(|p| t.contains(**p)).for_each(|&p| take(p));
        for e in 0..3 {
            let (a, b) = (t.v[e], t.v[(e + 1) % 3]);
            for (axis, bound) in [(0, x0), (0, x1), (1, y0), (1, y1)] {
                let (da, db) = (a[axis] - bound, b[axis] - bound);
                if da * db < 0.0 {
                    let p = a + (b - a) * (da / (da - db));
                    let other = 1 - axis;
                    let (lo, hi) = if other == 0 { (x0, x1) } else { (y0, y1) };
                    if p[other] >= lo - 1e-12 && p[other] <= hi + 1e-12 {
                        take(p);
                    }
                }
            }
        }
        m
    }

    #[test]
    fn exact_partial_coverage_gives_the_depth_inside_the_texel_not_at_its_corner() {
        // A triangle covering the right part of texel (0, 0), depth rising to the right: the
        // corner depth (x = 0) underestimates; the consistent depth is at the triangle's left
        // edge inside the texel.
        let t = tri(
            [DVec2::new(0.6, -1.0), DVec2::new(3.0, 0.5), DVec2::new(0.6, 2.0)],
            DVec2::new(1.0, 0.0),
        );
        let (m, clipped) = consistent_min_depth(&t, 0, 0);
        assert!(clipped);
        assert!((m - (1.0 + 0.1)).abs() < 1e-12, "{m}");
        assert!(t.depth_at(DVec2::ZERO) < m - 0.5, "the corner underestimates");
        assert!((candidates_min(&t, 0, 0) - m).abs() < 1e-12);
    }

    #[test]
    fn exact_min_depth_at_a_vertex_inside_the_texel() {
        let t = tri(
            [DVec2::new(0.3, 0.4), DVec2::new(4.0, 1.0), DVec2::new(2.0, 5.0)],
            DVec2::new(0.7, 0.2),
        );
        let (m, _) = consistent_min_depth(&t, 0, 0);
        assert!((m - t.depth_at(DVec2::new(0.3, 0.4))).abs() < 1e-12);
        assert!((candidates_min(&t, 0, 0) - m).abs() < 1e-12);
    }

    #[test]
    fn a_triangle_off_the_texel_falls_back_to_the_corner_depth() {
        let t = tri(
            [DVec2::new(3.0, 3.0), DVec2::new(4.0, 3.0), DVec2::new(3.0, 4.0)],
            DVec2::new(1.0, 1.0),
        );
        let (m, clipped) = consistent_min_depth(&t, 0, 0);
        assert!(!clipped);
        assert_eq!(m, conservative_depth(&t, 0, 0));
    }

    proptest::proptest! {
        #[test]
        fn consistent_depth_is_the_minimum_over_the_covered_part(
            v in proptest::collection::vec((-1.0f64..2.0, -1.0f64..2.0), 3),
            g in (-3.0f64..3.0, -3.0f64..3.0),
        ) {
            let t = tri([0, 1, 2].map(|k| DVec2::new(v[k].0, v[k].1)), DVec2::new(g.0, g.1));
            let expected = candidates_min(&t, 0, 0);
            proptest::prop_assume!(expected.is_finite() && t.orientation() != 0.0);
            let (m, clipped) = consistent_min_depth(&t, 0, 0);
            proptest::prop_assert!(clipped);
            proptest::prop_assert!((m - expected).abs() <= 1e-9, "{} vs {}", m, expected);
            proptest::prop_assert!(m >= conservative_depth(&t, 0, 0) - 1e-12);
        }
    }
}
