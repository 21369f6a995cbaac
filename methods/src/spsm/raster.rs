//! Stage 1, conservative rasterization (Lecocq et al. 2014, section 3.2, after Hasselgren,
//! Akenine-Möller and Ohlsson 2005).
//!
//! Every texel whose closed square `[i, i+1] x [j, j+1]` meets a caster triangle's closed
//! projection gets a fragment of it, decided exactly: the triangle and the square overlap iff
//! no separating axis exists among the two box axes (the triangle's bounding box) and the
//! three edge normals; for each edge, the square corner farthest inside is tested with
//! Shewchuk's exact `orient2d` (crate `robust`), and touching counts as overlap. Triangles of
//! zero projected area are skipped (they cast no shadow).
//!
//! Each fragment carries the **minimum conservative depth** of Hasselgren et al.: the
//! triangle's plane at the texel corner where it is smallest, clamped to the range of the
//! triangle's vertex depths; the texel keeps the fragment with the smallest such depth
//! (ties to the lower triangle id, so the result does not depend on thread scheduling). That
//! records grazing silhouette triangles (Fig. 3) ahead of the surfaces they overhang.
//!
//! Spot lights clip triangles at the near plane as the exact rasterizer does; a clipped
//! quadrilateral is split into two triangles of the same id. Work runs in parallel over bands
//! of rows, triangles binned to bands first.

use super::texel::{LightSpace, TexelData};
use crate::raster::clip_near;
use glam::DVec2;
use instrumentation::Counters;
use rayon::prelude::*;
use robust::{orient2d, Coord};
use scenes::{Geometry, Projector};

/// Index of "no triangle" in [`ConservativeMap::texel`].
pub const NONE: u32 = u32::MAX;

/// Rows per band of parallel work.
const BAND_ROWS: usize = 8;

/// A caster triangle in map space: vertices (positively oriented), map depths, depth plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriSetup {
    /// Vertices in map coordinates, positively oriented for `orient2d`.
    pub v: [DVec2; 3],
    /// Map depth `z̃` at the vertices.
    pub z: [f64; 3],
    /// Plane gradient `(∂z̃/∂x, ∂z̃/∂y)` per texel.
    pub dz: DVec2,
    /// Smallest vertex depth.
    pub z_min: f64,
    /// Largest vertex depth.
    pub z_max: f64,
    /// The scene triangle it comes from.
    pub id: u32,
}

impl TriSetup {
    /// Map depth of the triangle's plane at `q`.
    #[inline]
    pub fn plane(&self, q: DVec2) -> f64 {
        self.z[0] + (q - self.v[0]).dot(self.dz)
    }

    /// Hasselgren's minimum conservative depth over texel `(i, j)`.
    #[inline]
    pub fn conservative_depth(&self, i: usize, j: usize) -> f64 {
        let x = if self.dz.x > 0.0 { i as f64 } else { i as f64 + 1.0 };
        let y = if self.dz.y > 0.0 { j as f64 } else { j as f64 + 1.0 };
        self.plane(DVec2::new(x, y)).clamp(self.z_min, self.z_max)
    }

    /// What texel `(i, j)` stores of this triangle: vertices, depth at the centre, gradient.
    pub fn texel_data(&self, i: usize, j: usize) -> TexelData {
        let centre = DVec2::new(i as f64 + 0.5, j as f64 + 0.5);
        TexelData { v: self.v, z: self.plane(centre), dz: self.dz }
    }

    /// Whether the closed triangle meets the closed square of texel `(i, j)`, decided
    /// exactly (the caller has checked the bounding boxes).
    #[inline]
    pub fn touches(&self, i: usize, j: usize) -> bool {
        (0..3).all(|e| {
            let (a, b) = (self.v[e], self.v[(e + 1) % 3]);
            // The corner where the edge function (b - a) x (p - a) is largest.
            let x = if b.y - a.y < 0.0 { i as f64 + 1.0 } else { i as f64 };
            let y = if b.x - a.x > 0.0 { j as f64 + 1.0 } else { j as f64 };
            orient2d(coord(a), coord(b), Coord { x, y }) >= 0.0
        })
    }

    /// Texel columns whose squares the bounding box meets: `ceil(min) - 1 ..= floor(max)`,
    /// clamped to the map; likewise rows. `None` when the box misses the map.
    fn bounds(&self, res: usize) -> Option<[usize; 4]> {
        let (lo, hi) = self.v.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let r = res as f64;
        let first = |v: f64| (v.ceil() - 1.0).max(0.0);
        let last = |v: f64| v.floor().min(r - 1.0);
        let (x0, x1, y0, y1) = (first(lo.x), last(hi.x), first(lo.y), last(hi.y));
        (x0 <= x1 && y0 <= y1).then_some([x0 as usize, x1 as usize, y0 as usize, y1 as usize])
    }

    /// Columns whose squares may meet the triangle within the strip `y0 <= y <= y1`: the
    /// strip's slice of the triangle, widened by a margin against rounding (the exact test
    /// decides).
    fn strip_columns(&self, y0: f64, y1: f64, cols: (usize, usize)) -> Option<(usize, usize)> {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for e in 0..3 {
            let (a, b) = (self.v[e], self.v[(e + 1) % 3]);
            if a.y >= y0 && a.y <= y1 {
                lo = lo.min(a.x);
                hi = hi.max(a.x);
            }
            for yy in [y0, y1] {
                if (a.y - yy) * (b.y - yy) < 0.0 {
                    let x = a.x + (yy - a.y) * (b.x - a.x) / (b.y - a.y);
                    lo = lo.min(x);
                    hi = hi.max(x);
                }
            }
        }
        if lo > hi {
            return None;
        }
        let margin = 1e-9 * (1.0 + lo.abs().max(hi.abs()));
        let first = ((lo - margin).ceil() - 1.0).max(cols.0 as f64) as usize;
        let last = (hi + margin).floor().min(cols.1 as f64);
        (last >= first as f64).then_some((first, last as usize))
    }
}

#[inline]
fn coord(p: DVec2) -> Coord<f64> {
    Coord { x: p.x, y: p.y }
}

/// The prepared triangles of scene triangle `t`: one, two (a near-clipped quadrilateral) or
/// none (degenerate, not finite, or clipped away).
pub fn setup(
    geometry: &Geometry,
    t: usize,
    proj: &Projector,
    space: &LightSpace,
) -> ([Option<TriSetup>; 2], usize) {
    let none = ([None, None], 0);
    let corners = geometry.corners(t);
    let (world, count) = if proj.is_perspective() {
        clip_near(corners, corners.map(|c| proj.depth_of(c)), proj.near)
    } else {
        ([corners[0], corners[1], corners[2], glam::DVec3::ZERO], 3)
    };
    if count < 3 {
        return none;
    }
    let mut xy = [DVec2::ZERO; 4];
    let mut z = [0.0; 4];
    for k in 0..count {
        let (p, d) = proj.project_unclipped(world[k]);
        if !p.is_finite() || !d.is_finite() {
            return none;
        }
        xy[k] = p;
        z[k] = space.z(d);
    }
    let make = |a: usize, b: usize, c: usize| -> Option<TriSetup> {
        let s = orient2d(coord(xy[a]), coord(xy[b]), coord(xy[c]));
        if s == 0.0 {
            return None;
        }
        let (v, zz) = if s > 0.0 {
            ([xy[a], xy[b], xy[c]], [z[a], z[b], z[c]])
        } else {
            ([xy[a], xy[c], xy[b]], [z[a], z[c], z[b]])
        };
        let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
        let (d1, d2) = (zz[1] - zz[0], zz[2] - zz[0]);
        let det = e1.x * e2.y - e1.y * e2.x;
        let dz = DVec2::new((d1 * e2.y - d2 * e1.y) / det, (e1.x * d2 - e2.x * d1) / det);
        if !dz.is_finite() {
            return None;
        }
        let z_min = zz[0].min(zz[1]).min(zz[2]);
        let z_max = zz[0].max(zz[1]).max(zz[2]);
        Some(TriSetup { v, z: zz, dz, z_min, z_max, id: t as u32 })
    };
    let first = make(0, 1, 2);
    let second = if count == 4 { make(0, 2, 3) } else { None };
    ([first, second], count - 2)
}

/// The prepared triangles of the scene triangles `include` selects, in scene order, and the
/// texel rectangle each one's bounding box meets (`[x0, x1, y0, y1]`, `None` off the map);
/// counts the triangles offered as `triangles_rasterized`. Shared with the GPU's twin.
pub fn prepare(
    geometry: &Geometry,
    include: impl Fn(usize) -> bool + Sync,
    proj: &Projector,
    space: &LightSpace,
    counters: &mut Counters,
) -> (Vec<TriSetup>, Vec<Option<[usize; 4]>>) {
    let res = proj.width as usize;
    let offered: Vec<usize> = (0..geometry.len()).into_par_iter().filter(|&t| include(t)).collect();
    counters.triangles_rasterized += offered.len() as u64;
    let setups: Vec<TriSetup> = offered
        .par_iter()
        .flat_map_iter(|&t| {
            let (pair, n) = setup(geometry, t, proj, space);
            pair.into_iter().take(n).flatten()
        })
        .collect();
    let bounds = setups.par_iter().map(|s| s.bounds(res)).collect();
    (setups, bounds)
}

/// The conservatively rasterized map: per texel, the index of the kept triangle in
/// [`setups`](Self::setups) and its minimum conservative depth.
#[derive(Debug, Clone, PartialEq)]
pub struct ConservativeMap {
    /// Map resolution.
    pub res: u32,
    /// Prepared triangles, in scene order.
    pub setups: Vec<TriSetup>,
    /// Index into `setups` per texel, [`NONE`] where no triangle touches it.
    pub texel: Vec<u32>,
    /// Minimum conservative depth per texel, `f64::INFINITY` where none.
    pub depth: Vec<f64>,
}

impl ConservativeMap {
    /// The texel data (vertices, centre depth, gradient) of texel `k`, if any.
    pub fn texel_data(&self, k: usize) -> Option<TexelData> {
        let s = self.texel[k];
        let r = self.res as usize;
        (s != NONE).then(|| self.setups[s as usize].texel_data(k % r, k / r))
    }
}

/// Rasterizes the triangles `include` selects conservatively into an `R x R` map.
/// Counters: `triangles_rasterized` (triangles offered), `raster_samples_tested` (texels
/// tested exactly), `conservative_fragments` (texel-triangle overlaps found).
pub fn rasterize_conservative(
    geometry: &Geometry,
    include: impl Fn(usize) -> bool + Sync,
    proj: &Projector,
    space: &LightSpace,
    counters: &mut Counters,
) -> ConservativeMap {
    let res = proj.width as usize;
    let (setups, bounds) = prepare(geometry, include, proj, space, counters);

    let bands = res.div_ceil(BAND_ROWS).max(1);
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); bands];
    for (i, b) in bounds.iter().enumerate() {
        if let Some([_, _, y0, y1]) = b {
            for bin in &mut bins[y0 / BAND_ROWS..=y1 / BAND_ROWS] {
                bin.push(i as u32);
            }
        }
    }

    let mut texel = vec![NONE; res * res];
    let mut depth = vec![f64::INFINITY; res * res];
    let chunk = (res * BAND_ROWS).max(1);
    let (tested, fragments) = texel
        .par_chunks_mut(chunk)
        .zip(depth.par_chunks_mut(chunk))
        .zip(bins.par_iter())
        .enumerate()
        .map(|(band, ((texel, depth), bin))| {
            let row0 = band * BAND_ROWS;
            let rows = texel.len() / res.max(1);
            let (mut tested, mut fragments) = (0u64, 0u64);
            for &i in bin {
                let s = &setups[i as usize];
                let Some([x0, x1, y0, y1]) = bounds[i as usize] else { continue };
                for y in y0.max(row0)..=y1.min(row0 + rows - 1) {
                    let strip = s.strip_columns(y as f64, y as f64 + 1.0, (x0, x1));
                    let Some((c0, c1)) = strip else { continue };
                    for x in c0..=c1 {
                        tested += 1;
                        if !s.touches(x, y) {
                            continue;
                        }
                        fragments += 1;
                        let d = s.conservative_depth(x, y);
                        let k = (y - row0) * res + x;
                        if d < depth[k] {
                            depth[k] = d;
                            texel[k] = i;
                        }
                    }
                }
            }
            (tested, fragments)
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    counters.raster_samples_tested += tested;
    counters.conservative_fragments += fragments;
    ConservativeMap { res: res as u32, setups, texel, depth }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::tests::pixel_projector;
    use glam::DVec3;

    /// Geometry from triangles given in texel coordinates `(x, y, depth)`.
    pub(crate) fn geometry(tris: &[[[f64; 3]; 3]], res: u32) -> Geometry {
        let mut g = Geometry::default();
        for t in tris {
            let base = g.positions.len() as u32;
            for p in t {
                g.positions.push(DVec3::new(p[0], f64::from(res) - p[1], 10.0 - p[2]));
            }
            g.triangles.push([base, base + 1, base + 2]);
            g.object.push(0);
        }
        g
    }

    pub(crate) fn space(res: u32) -> LightSpace {
        LightSpace::new(&pixel_projector(res, res), (0.0, 20.0))
    }

    fn raster(tris: &[[[f64; 3]; 3]], res: u32) -> (ConservativeMap, Counters) {
        let mut c = Counters::default();
        let m = rasterize_conservative(
            &geometry(tris, res),
            |_| true,
            &pixel_projector(res, res),
            &space(res),
            &mut c,
        );
        (m, c)
    }

    /// Closed segments `ab` and `cd` meet (exact).
    fn segments_meet(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
        let o = |p: DVec2, q: DVec2, r: DVec2| orient2d(coord(p), coord(q), coord(r));
        let on = |p: DVec2, q: DVec2, r: DVec2| {
            r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
        };
        let (d1, d2, d3, d4) = (o(c, d, a), o(c, d, b), o(a, b, c), o(a, b, d));
        if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
            && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
        {
            return true;
        }
        (d1 == 0.0 && on(c, d, a))
            || (d2 == 0.0 && on(c, d, b))
            || (d3 == 0.0 && on(a, b, c))
            || (d4 == 0.0 && on(a, b, d))
    }

    /// Brute force: a closed triangle meets a closed box iff a vertex lies in the box, a box
    /// corner lies in the triangle, or an edge crosses an edge.
    fn overlaps(v: [DVec2; 3], i: usize, j: usize) -> bool {
        let (x0, y0, x1, y1) = (i as f64, j as f64, i as f64 + 1.0, j as f64 + 1.0);
        if v.iter().any(|p| p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1) {
            return true;
        }
        let box_pts =
            [DVec2::new(x0, y0), DVec2::new(x1, y0), DVec2::new(x1, y1), DVec2::new(x0, y1)];
        let o = |p: DVec2, q: DVec2, r: DVec2| orient2d(coord(p), coord(q), coord(r));
        let inside = |p: DVec2| {
            let s = [o(v[0], v[1], p), o(v[1], v[2], p), o(v[2], v[0], p)];
            s.iter().all(|&x| x >= 0.0) || s.iter().all(|&x| x <= 0.0)
        };
        if box_pts.iter().any(|&p| inside(p)) {
            return true;
        }
        (0..3).any(|e| {
            (0..4).any(|k| segments_meet(v[e], v[(e + 1) % 3], box_pts[k], box_pts[(k + 1) % 4]))
        })
    }

    #[test]
    fn a_thin_sliver_touches_every_texel_along_it_and_no_other() {
        // A sliver far thinner than a texel, between texel centres: an exact rasterizer
        // misses it, the conservative one records every texel it crosses.
        let tri = [[0.7, 0.7, 1.0], [14.3, 9.2, 1.0], [14.3, 9.2001, 1.0]];
        let (m, c) = raster(&[tri], 16);
        let v = m.setups[0].v;
        for j in 0..16 {
            for i in 0..16 {
                assert_eq!(m.texel[j * 16 + i] != NONE, overlaps(v, i, j), "texel ({i}, {j})");
            }
        }
        assert!(c.conservative_fragments >= 20, "{c:?}");
    }

    #[test]
    fn touching_a_texel_corner_counts() {
        let tri = [[2.0, 2.0, 1.0], [5.0, 2.0, 1.0], [2.0, 5.0, 1.0]];
        let (m, _) = raster(&[tri], 8);
        // (1, 1) touches only at the corner (2, 2); (4, 3) only at a point of the hypotenuse.
        for (i, j) in [(1, 1), (1, 2), (2, 1), (4, 1), (4, 2), (3, 3), (4, 0)] {
            assert_eq!(m.texel[j * 8 + i] != NONE, overlaps(m.setups[0].v, i, j), "({i}, {j})");
        }
        assert!(m.texel[8 + 1] != NONE);
        assert!(m.texel[8 * 4] == NONE);
    }

    #[test]
    fn nearer_conservative_depth_wins_and_ties_go_to_the_lower_id() {
        // A far flat triangle and a near steep one overhanging it: the steep one's corner
        // depth is smaller in every texel it touches.
        let flat = [[0.0, 0.0, 5.0], [8.0, 0.0, 5.0], [0.0, 8.0, 5.0]];
        let steep = [[1.0, 1.0, 2.0], [3.0, 1.0, 6.0], [1.0, 3.0, 6.0]];
        let (m, _) = raster(&[flat, steep], 8);
        assert_eq!(m.setups[m.texel[8 + 1] as usize].id, 1);
        assert_eq!(m.setups[m.texel[8 * 6] as usize].id, 0);
        let (m, _) = raster(&[flat, flat], 8);
        assert!(m.texel.iter().filter(|&&t| t != NONE).all(|&t| m.setups[t as usize].id == 0));
    }

    #[test]
    fn conservative_depth_is_the_smallest_plane_value_at_a_corner_clamped() {
        let tri = [[0.0, 0.0, 1.0], [8.0, 0.0, 5.0], [0.0, 8.0, 1.0]];
        let (m, _) = raster(&[tri], 8);
        // Depth grows by 0.5 per texel in x: texel (2, 1) is smallest at its left edge.
        assert!((m.depth[8 + 2] - 2.0).abs() < 1e-12);
        // Texel (0, 0): the corner x = 0 gives the vertex depth 1 (no clamp needed).
        assert!((m.depth[0] - 1.0).abs() < 1e-12);
        let s = &m.setups[0];
        assert!((s.dz - DVec2::new(0.5, 0.0)).length() < 1e-12);
        let d = m.texel_data(8 + 2).expect("covered");
        assert!((d.z - 2.25).abs() < 1e-12);
    }

    #[test]
    fn degenerate_triangles_are_skipped() {
        let line = [[0.5, 0.5, 1.0], [3.5, 3.5, 1.0], [6.5, 6.5, 1.0]];
        let (m, c) = raster(&[line], 8);
        assert!(m.setups.is_empty());
        assert!(m.texel.iter().all(|&t| t == NONE));
        assert_eq!(c.triangles_rasterized, 1);
    }

    proptest::proptest! {
        /// Every texel the triangle touches, and no other, gets a fragment; vertices on the
        /// quarter-texel grid put many edges and corners exactly on texel borders.
        #[test]
        fn conservative_coverage_is_exact_overlap(
            pts in proptest::collection::vec((-8i32..=72, -8i32..=72), 3),
            jitter in proptest::collection::vec(0.0f64..1.0, 6),
            use_jitter in proptest::bool::ANY,
        ) {
            let p: Vec<[f64; 3]> = pts
                .iter()
                .enumerate()
                .map(|(k, &(x, y))| {
                    let (jx, jy) = if use_jitter { (jitter[2 * k], jitter[2 * k + 1]) } else { (0.0, 0.0) };
                    [f64::from(x) * 0.25 + jx, f64::from(y) * 0.25 + jy, 1.0 + k as f64]
                })
                .collect();
            let (m, c) = raster(&[[p[0], p[1], p[2]]], 16);
            let v = [0, 1, 2].map(|k| DVec2::new(p[k][0], p[k][1]));
            let area = orient2d(coord(v[0]), coord(v[1]), coord(v[2]));
            let mut found = 0u64;
            for j in 0..16 {
                for i in 0..16 {
                    let expected = area != 0.0 && overlaps(v, i, j);
                    let got = m.texel[j * 16 + i] != NONE;
                    proptest::prop_assert_eq!(got, expected, "texel ({}, {}) of {:?}", i, j, v);
                    found += u64::from(got);
                }
            }
            proptest::prop_assert_eq!(found, c.conservative_fragments);
        }
    }
}
