//! The area a union of convex polygons covers in each pixel, in `f64`, without building the
//! union.
//!
//! In each pixel, the part of a region (the pixel square, or a receiver triangle's screen
//! polygon clipped to the square) that no polygon covers is kept as a set of disjoint convex
//! pieces. Every polygon overlapping the pixel is subtracted from each piece it meets by cutting
//! the piece along the polygon's edge lines in turn ([`clip::split_left`]): the part outside the
//! first edge is kept, the rest is cut by the second edge, and so on; what lies inside every edge
//! is covered and dropped. The covered area is the region's area less the pieces' areas.
//!
//! A pixel wholly inside one polygon needs no cut: for a convex polygon clipped to a row strip,
//! the pixel square lies inside it exactly when its cross-sections at the strip's top and
//! bottom (the vertices the strip clip put on those lines, with their coordinate set exactly)
//! both span the pixel's columns. Such pixels are covered; the others are cut only by the
//! polygons that reach them.
//!
//! Nor does a pixel the union's outline does not meet, where the polygons are a mesh's
//! shadows: neighbours' shadows share their edges bit for bit, and an edge two polygons have
//! in opposite directions lies inside their union, so the outline is what is left
//! ([`boundary_pixels`]); a pixel away from it that a polygon reaches is covered, and a
//! polygon all of whose pixels are away from it is not swept at all ([`union_area`]'s
//! `seams`).
//!
//! # Why not a polygon-union library
//!
//! `exact` used to union the shadow polygons with i_overlay 9.1 on an integer grid and
//! triangulate the union with spade. At grazing light the shadows of `cage`'s bars are slivers
//! whose long edges nearly coincide; on five of them (kept as a test below) i_overlay's segment
//! splitting added segments on every pass, doubling them until memory ran out (24 GB after
//! 240 s at 80 x 60, whatever the grid step or snap precision). Here there is no topology to get
//! wrong: each cut is a convex clip by one line, whose crossing points both sides share bit
//! for bit, and a sliver is just a piece of small area.
//!
//! # Bounds
//!
//! - **Work**: every piece is bounded by edge lines of the pixel's polygons and the pieces are
//!   disjoint, so each holds at least one cell of the arrangement of those `L` lines in the
//!   pixel: there are at most `O(L^2)` pieces, whatever the polygons' shapes.
//! - **Rounding**: coordinates are taken relative to the pixel's corner (exact for the
//!   coordinates of a pixel of a frame up to 2^52 pixels wide), so every cut and area is
//!   computed on numbers in `[0, 1]` with relative rounding near `1e-16`. Pieces whose doubled
//!   area is below [`MIN_AREA2`] are dropped (at most `1e-24` px² each, far below the `1e-9`
//!   the ground truth states, even for the `O(L^2)` pieces the bound allows).
//!
//! Rows are processed in parallel bands ([`clip::BAND`] rows); each worker reuses its buffers,
//! so a pixel allocates nothing once the buffers have grown.

use super::clip::{self, Poly, Pt};
use super::ScreenPolygons;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// Pieces with a doubled area (in px²) at or below this are dropped.
pub(crate) const MIN_AREA2: f64 = 2e-24;

/// Buffers a worker reuses from row to row and pixel to pixel.
#[derive(Default)]
pub(crate) struct Scratch {
    /// Every polygon's part below the rows swept so far, with its `y` range.
    rests: Vec<(Poly, f64, f64)>,
    /// Polygons clipped to the current row strip, with their column range.
    strips: Vec<(Poly, usize, usize)>,
    /// Columns of the current row wholly covered by one polygon.
    full: Vec<bool>,
    /// (column, rank of the strip) pairs of polygons partly covering a pixel.
    pairs: Vec<(u32, u32)>,
    /// The strips by decreasing area (`order[rank]` is a strip), and each strip's rank; in
    /// [`Scratch::covers`], the polygons by decreasing area.
    order: Vec<(f64, u32)>,
    rank: Vec<u32>,
    pieces: Vec<Poly>,
    next: Vec<Poly>,
}

/// Work counts of a coverage computation.
#[derive(Debug, Default, Clone, Copy)]
pub(crate) struct Work {
    /// Pixels wholly inside one polygon, or inside the union off its boundary.
    pub covered_pixels: u64,
    /// Pixel-polygon pairs resolved by cutting (the polygon partly covers the pixel).
    pub pixel_polygon_pairs: u64,
}

impl std::ops::AddAssign for Work {
    fn add_assign(&mut self, rhs: Self) {
        self.covered_pixels += rhs.covered_pixels;
        self.pixel_polygon_pairs += rhs.pixel_polygon_pairs;
    }
}

/// Whether a pixel's covered area is wanted ([`rows_areas`]), and what the caller knows of
/// it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Want {
    /// Not wanted.
    No,
    /// Wanted.
    Yes,
    /// Wanted, and the union's outline does not meet the pixel: if a polygon reaches it, it
    /// lies wholly inside the union.
    OffOutline,
}

/// The area the union of `polygons` (convex, positive [`Poly::area2_rel`]) covers in every
/// pixel `k` of a `width x height` frame with `accept(k)`; 0 elsewhere.
///
/// With `seams` (worth it where polygons share edges, as the shadows of a mesh's neighbouring
/// triangles do), the pixels the union's outline may meet are found first
/// ([`boundary_pixels`]). A polygon within the frame whose pixels it meets none of lies
/// inside the union with all of them (they are connected, and the polygon reaches one): they
/// are covered, and the polygon is not swept. A pixel the outline does not meet that a swept
/// polygon reaches is covered without a cut.
///
/// On `bunny-plane` at 800 x 600 the outline of the ground's 35,672 shadow polygons meets
/// 2,636 pixels; 13,080 polygons are left to sweep, the pixel-polygon pairs cut fall from
/// 67,974 to 13,183, and the stage `pixel unions` took 35.2 -> 24.3 ms at one thread (4
/// alternating runs, load 1.1-1.5) and 20.4 -> 15.1 at two (6 runs), with the same image bit
/// for bit.
pub(crate) fn union_area(
    polygons: &ScreenPolygons,
    width: usize,
    height: usize,
    accept: impl Fn(usize) -> bool + Sync,
    seams: bool,
) -> (Vec<f64>, Work) {
    let mut area = methods::parallel::filled(width * height, 0.0);
    if width == 0 || height == 0 || polygons.is_empty() {
        return (area, Work::default());
    }
    let outline = seams.then(|| boundary_pixels(polygons, width, height));
    // With the outline: the pixels of the polygons it does not meet, and the other polygons
    // (by number), both found in parallel (serially, 1.8 ms of `bunny-plane`'s stage at two
    // threads went to one thread).
    let (inner, kept) = match &outline {
        Some(met) => {
            let inner: Vec<AtomicBool> =
                (0..width * height).into_par_iter().map(|_| AtomicBool::new(false)).collect();
            let kept: Vec<u32> = (0..polygons.len() as u32)
                .into_par_iter()
                .filter(|&p| {
                    let c = polygons.contour(p as usize);
                    let ((x0, x1), (y0, y1)) = (clip::range(c, 0), clip::range(c, 1));
                    let (Some((i0, i1)), Some((j0, j1))) = (
                        clip::overlapped_rows(x0, x1, width),
                        clip::overlapped_rows(y0, y1, height),
                    ) else {
                        return false;
                    };
                    let rows = (j0..=j1).map(|j| j * width + i0..=j * width + i1);
                    // Within the frame, a polygon of positive area reaches one of its pixels.
                    let framed =
                        x0 >= 0.0 && x1 <= width as f64 && y0 >= 0.0 && y1 <= height as f64;
                    if !framed || rows.clone().any(|r| met[r].contains(&true)) {
                        return true;
                    }
                    // A mark is only ever set: the order of the stores does not matter.
                    rows.flatten().for_each(|k| inner[k].store(true, Ordering::Relaxed));
                    false
                })
                .collect();
            (inner, Some(kept))
        }
        None => (Vec::new(), None),
    };
    let swept_count = kept.as_ref().map_or(polygons.len(), Vec::len);
    let swept = |p: usize| polygons.contour(kept.as_ref().map_or(p, |kept| kept[p] as usize));
    let want = |i: usize, j: usize| {
        let k = j * width + i;
        match &outline {
            _ if !accept(k) => Want::No,
            Some(met) if !met[k] => Want::OffOutline,
            _ => Want::Yes,
        }
    };
    let (offsets, items) = methods::bands::bin_by_band(swept_count, height, clip::BAND, |p| {
        let (lo, hi) = clip::range(swept(p), 1);
        clip::overlapped_rows(lo, hi, height)
    });
    let mut work = area
        .par_chunks_mut(clip::BAND * width)
        .enumerate()
        .map_init(Scratch::default, |scratch, (band, chunk)| {
            let mut work = Work::default();
            let r0 = band * clip::BAND;
            let ids = &items[offsets[band]..offsets[band + 1]];
            let band_polys = ids.iter().map(|&p| swept(p as usize));
            let rows = r0..r0 + chunk.len() / width;
            work += rows_areas(band_polys, rows, 0..width, None, want, scratch, |i, j, a| {
                chunk[(j - r0) * width + i] = a
            });
            work
        })
        .reduce(Work::default, |mut a, b| {
            a += b;
            a
        });
    // The pixels of the polygons not swept that no swept polygon reached.
    if !inner.is_empty() {
        work.covered_pixels += area
            .par_iter_mut()
            .zip(&inner)
            .enumerate()
            .filter(|(k, (a, held))| held.load(Ordering::Relaxed) && **a == 0.0 && accept(*k))
            .map(|(_, (a, _))| {
                *a = 1.0;
                1
            })
            .sum::<u64>();
    }
    (area, work)
}

/// The area the union of `polygons` (convex, positive [`Poly::area2_rel`]) covers inside the
/// region `within` (convex, positive [`Poly::area2_rel`]; `None`: the whole pixel) in every
/// pixel of rows `rows` and columns `cols` that `want(i, j)` wants: calls `emit(i, j, area)`
/// for each such pixel the union reaches, row by row in column order. A pixel off the union's
/// outline ([`Want::OffOutline`]) that a polygon reaches is covered without a cut.
///
/// The rows are swept downwards: each polygon is split once at every row line it crosses,
/// the part above being that row's strip and the part below kept for the next rows (as the
/// pixel classes' clipper does), rather than clipped from scratch to every row.
pub(crate) fn rows_areas<'a>(
    polygons: impl Iterator<Item = &'a [Pt]>,
    rows: std::ops::Range<usize>,
    cols: std::ops::Range<usize>,
    within: Option<&Poly>,
    want: impl Fn(usize, usize) -> Want,
    scratch: &mut Scratch,
    mut emit: impl FnMut(usize, usize, f64),
) -> Work {
    let mut work = Work::default();
    if cols.end <= cols.start || rows.end <= rows.start {
        return work;
    }
    let (top, bottom) = (rows.start as f64, rows.end as f64);
    let mut rests = std::mem::take(&mut scratch.rests);
    rests.clear();
    for points in polygons {
        let (lo, hi) = clip::range(points, 1);
        if !(hi > top && lo < bottom) {
            continue;
        }
        let mut poly = Poly::from_slice(points);
        if lo < top {
            poly = clip::keep(&poly, 1, top, true);
        }
        rests.push((poly, lo.max(top), hi));
    }
    let (mut above, mut below) = (Poly::new(), Poly::new());
    for j in rows {
        let y1 = j as f64 + 1.0;
        scratch.strips.clear();
        for (rest, lo, hi) in rests.iter_mut() {
            if rest.n < 3 || *lo >= y1 {
                continue;
            }
            if *hi > y1 {
                clip::split(rest, 1, y1, &mut above, &mut below);
                rest.assign(&below);
                *lo = y1;
                scratch.strips.push((above, 0, 0));
            } else {
                scratch.strips.push((*rest, 0, 0));
                rest.n = 0;
            }
        }
        work += row_areas(j, cols.clone(), within, |i| want(i, j), scratch, |i, a| emit(i, j, a));
    }
    scratch.rests = rests;
    work
}

/// One row of [`rows_areas`]: the polygons' strips in the row are in `scratch.strips`.
fn row_areas(
    j: usize,
    cols: std::ops::Range<usize>,
    within: Option<&Poly>,
    want: impl Fn(usize) -> Want,
    scratch: &mut Scratch,
    mut emit: impl FnMut(usize, f64),
) -> Work {
    let mut work = Work::default();
    let Scratch { rests: _, strips, full, pairs, order, rank, pieces, next } = scratch;
    let (y0, y1) = (j as f64, j as f64 + 1.0);
    let (c0, c1) = (cols.start, cols.end);
    full.clear();
    full.resize(c1 - c0, false);
    strips.retain_mut(|(strip, first_col, last_col)| {
        if strip.n < 3 {
            return false;
        }
        let (xa, xb) = strip.range(0);
        if !(xb > c0 as f64 && xa < c1 as f64) {
            return false;
        }
        let first = (xa.floor().max(c0 as f64)) as usize;
        let last = ((xb.ceil() as usize).max(1) - 1).min(c1 - 1);
        if first > last {
            return false;
        }
        // Columns wholly inside: both cross-sections span them.
        if let (Some(top), Some(bottom)) = (section(strip, y0), section(strip, y1)) {
            let (a, b) = (top.0.max(bottom.0), top.1.min(bottom.1));
            if b - a >= 1.0 {
                let from = (a.ceil().max(c0 as f64)) as usize;
                let to = (b.floor().min(c1 as f64)) as usize;
                if to > from {
                    full[from - c0..to - c0].iter_mut().for_each(|f| *f = true);
                }
            }
        }
        (*first_col, *last_col) = (first, last);
        true
    });
    // A pixel's polygons are cut from it largest first: the pieces run out sooner.
    order.clear();
    order.extend(
        strips.iter().enumerate().map(|(s, (p, _, _))| (p.area2_rel(c0 as f64, y0), s as u32)),
    );
    order.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    rank.clear();
    rank.resize(strips.len(), 0);
    for (r, &(_, s)) in order.iter().enumerate() {
        rank[s as usize] = r as u32;
    }
    pairs.clear();
    for (s, &(_, first, last)) in strips.iter().enumerate() {
        for i in first..=last {
            if !full[i - c0] && want(i) != Want::No {
                pairs.push((i as u32, rank[s]));
            }
        }
    }
    pairs.sort_unstable();
    let mut next_pair = 0;
    let whole = |i: usize| region(within, i, j).map_or(0.0, |r| 0.5 * r.area2_rel(0.0, 0.0));
    for i in c0..c1 {
        if full[i - c0] {
            if want(i) != Want::No {
                work.covered_pixels += 1;
                emit(i, whole(i));
            }
            continue;
        }
        let start = next_pair;
        while next_pair < pairs.len() && pairs[next_pair].0 as usize == i {
            next_pair += 1;
        }
        if start == next_pair {
            continue;
        }
        // A polygon reaches the pixel (a strip of positive area spans its column) and the
        // union's boundary does not: the union holds it.
        if want(i) == Want::OffOutline {
            work.covered_pixels += 1;
            emit(i, whole(i));
            continue;
        }
        work.pixel_polygon_pairs += (next_pair - start) as u64;
        let group =
            pairs[start..next_pair].iter().map(|&(_, r)| &strips[order[r as usize].1 as usize].0);
        emit(i, pixel_area(i, j, within, group, pieces, next));
    }
    work
}

/// How far (in pixels) beyond an edge a pixel counts as met by it: far above the rounding of
/// the edge's crossings with the row lines (`1e-12` px in a frame 16,384 pixels wide).
const BOUNDARY_PAD: f64 = 1e-6;

/// Edges per bucket of [`boundary_pixels`], about: from 32 to 1,024 the stage's outline took
/// the same time on `bunny-plane` (7.5-9 ms at one thread, 4.2-4.7 at two).
const EDGES_PER_BUCKET: usize = 256;

/// Which pixels of a `width x height` frame the boundary of the union of `polygons` (convex,
/// positive [`Poly::area2_rel`]) may meet: those an edge of a polygon meets (within
/// [`BOUNDARY_PAD`]), except edges that another polygon has reversed (the same two points bit
/// for bit, in the other order; a polygon's own edges never pair up, as a degenerate one's
/// could).
///
/// Two polygons of positive orientation, one with an edge `a -> b` and one with `b -> a`, lie
/// on its two sides, so every point inside the edge is inside their union, and the union's
/// boundary lies on the other edges. A pixel none of them meets lies wholly inside the union
/// or wholly outside it (its square is connected); if a polygon overlaps it, inside. The
/// shadows of a mesh's neighbouring triangles facing the light share their edges bit for bit
/// (a shared corner is projected by the same operations from the same numbers, and both
/// polygons are turned to positive orientation), so only the shadow's outline and the edges
/// a clip made are left. Edges whose two polygons do not match bit for bit are kept: more
/// pixels are cut than need be, none is covered that is not.
///
/// The edges are put in buckets by a hash of their ends, each with its two ends in one order
/// and a flag for its direction, and each bucket is sorted, so that an edge and its reverse
/// are neighbours; the outline's edges then mark the pixels of each row they cross, serially.
/// (Looking each edge's reverse up in the sorted edges made the stage 6.7 ms slower on
/// `bunny-plane` at one thread, 29.5 against 22.8, in cache misses.)
pub(crate) fn boundary_pixels(polygons: &ScreenPolygons, width: usize, height: usize) -> Vec<bool> {
    // Every edge as its two ends' bits, the smaller first, whether it runs the other way, and
    // its polygon: sorted in its bucket, an edge's copies and reverses are neighbours.
    let bits = |p: Pt| [p[0].to_bits(), p[1].to_bits()];
    // Written in place by parts of the polygons, each part's edges after the previous
    // part's (gathered by a parallel `flat_map` and joined in one thread, 2.9 ms of the stage
    // at two threads on `bunny-plane` went to one thread).
    const PART: usize = 1024;
    let count = |ps: std::ops::Range<usize>| ps.map(|p| polygons.ranges[p].len()).sum::<usize>();
    let mut edges_all =
        methods::parallel::filled(count(0..polygons.len()), ([0u64; 4], false, 0u32));
    let part_of = |k: usize| k * PART..((k + 1) * PART).min(polygons.len());
    let lens = (0..polygons.len().div_ceil(PART)).map(|k| count(part_of(k)));
    let parts = methods::parallel::cut(&mut edges_all, lens);
    parts.into_par_iter().enumerate().for_each(|(k, part)| {
        let ps = part_of(k);
        let all = ps.flat_map(|p| edges(polygons.contour(p)).map(move |e| (p, e)));
        for (slot, (p, (a, b))) in part.iter_mut().zip(all) {
            let (a, b) = (bits(a), bits(b));
            *slot = if a <= b {
                ([a[0], a[1], b[0], b[1]], false, p as u32)
            } else {
                ([b[0], b[1], a[0], a[1]], true, p as u32)
            };
        }
    });
    // An edge's copies and reverses share a bucket (a hash of its ends' bits): the buckets
    // are filled in parallel, each sorted in cache by one thread. With one parallel sort of
    // every edge, whose first partition runs in one thread, the outline took 10.2 ms at one
    // thread on `bunny-plane` and 5.4 at two; with the buckets, 7.8 and 4.4.
    let bits_per_bucket = (edges_all.len() / EDGES_PER_BUCKET).max(1).ilog2();
    let buckets = 1usize << bits_per_bucket;
    let bucket = |k: usize| {
        let [a, b, c, d] = edges_all[k].0;
        let h = (a ^ b.rotate_left(17) ^ c.rotate_left(31) ^ d.rotate_left(47))
            .wrapping_mul(0x9e37_79b9_7f4a_7c15);
        // The top `bits_per_bucket` bits (none when there is one bucket).
        h.checked_shr(64 - bits_per_bucket).unwrap_or(0) as usize
    };
    let (offsets, items) =
        methods::bands::bin_by_band(edges_all.len(), buckets, 1, |k| Some((bucket(k), bucket(k))));
    // The outline's edges, found in parallel, then marked serially (on `bunny-plane`, 2,636
    // pixels): both serially, 1.5 ms of the stage at two threads went to one thread.
    let outline: Vec<[u64; 4]> = (0..buckets)
        .into_par_iter()
        .map_init(Vec::new, |same_bucket, b| {
            same_bucket.clear();
            same_bucket
                .extend(items[offsets[b]..offsets[b + 1]].iter().map(|&k| edges_all[k as usize]));
            same_bucket.sort_unstable();
            same_bucket
                .chunk_by(|x, y| x.0 == y.0)
                .filter(|same| {
                    // Both ways, from two polygons (a degenerate polygon can hold both
                    // itself): sorted, `false` comes first, each way by polygon.
                    let (first, last) = (same[0], same[same.len() - 1]);
                    first.1 == last.1 || (first.2 == last.2 && same.iter().all(|e| e.2 == first.2))
                })
                .map(|same| same[0].0)
                .collect::<Vec<_>>()
        })
        .flatten_iter()
        .collect();
    let mut met = methods::parallel::filled(width * height, false);
    for k in outline {
        let (a, b) = (
            [f64::from_bits(k[0]), f64::from_bits(k[1])],
            [f64::from_bits(k[2]), f64::from_bits(k[3])],
        );
        mark_edge(a, b, width, height, &mut met);
    }
    met
}

/// The edges of polygon `c`, each from a vertex to the next.
fn edges(c: &[Pt]) -> impl Iterator<Item = (Pt, Pt)> + '_ {
    let n = c.len();
    (0..n).map(move |k| (c[k], c[(k + 1) % n]))
}

/// Marks in `met` (a `width x height` frame) every pixel the segment from `a` to `b` meets,
/// within [`BOUNDARY_PAD`].
fn mark_edge(a: Pt, b: Pt, width: usize, height: usize, met: &mut [bool]) {
    let pad = BOUNDARY_PAD;
    // The pixel rows or columns `[lo, hi]` (padded) meets, within `0..n`.
    let span = |lo: f64, hi: f64, n: usize| {
        let (lo, hi) = ((lo - pad).floor(), (hi + pad).floor());
        // NaN meets nothing.
        (hi >= 0.0 && lo < n as f64).then(|| (lo.max(0.0) as usize, (hi as usize).min(n - 1)))
    };
    let Some((j0, j1)) = span(a[1].min(b[1]), a[1].max(b[1]), height) else { return };
    for j in j0..=j1 {
        // The segment's part within the row, widened by the pad: its x range.
        let (y0, y1) = (j as f64 - pad, j as f64 + 1.0 + pad);
        let (x0, x1) = if a[1] == b[1] {
            (a[0].min(b[0]), a[0].max(b[0]))
        } else {
            let at = |y: f64| {
                let t = ((y - a[1]) / (b[1] - a[1])).clamp(0.0, 1.0);
                a[0] + t * (b[0] - a[0])
            };
            let (u, v) = (at(y0), at(y1));
            (u.min(v), u.max(v))
        };
        if let Some((i0, i1)) = span(x0, x1, width) {
            met[j * width + i0..=j * width + i1].iter_mut().for_each(|m| *m = true);
        }
    }
}

/// The cross-section `[min x, max x]` of the convex polygon `strip` on the line `y = c`, from
/// its vertices on that line; `None` when it has none.
fn section(strip: &Poly, c: f64) -> Option<(f64, f64)> {
    strip.points().iter().filter(|p| p[1] == c).fold(None, |acc, p| match acc {
        None => Some((p[0], p[0])),
        Some((a, b)) => Some((f64::min(a, p[0]), f64::max(b, p[0]))),
    })
}

/// The part of `within` (or the whole square) in pixel `(i, j)`, in coordinates relative to
/// the pixel's corner; `None` when empty.
fn region(within: Option<&Poly>, i: usize, j: usize) -> Option<Poly> {
    let r = match within {
        None => Poly::from_slice(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
        Some(w) => to_local(&clip::clip_to_pixel(w, i, j), i, j),
    };
    (r.n >= 3).then_some(r)
}

/// `poly` with coordinates relative to the corner of pixel `(i, j)`: exact for points in
/// the pixel (`x - i` for `x` in `[i, i + 1]`).
fn to_local(poly: &Poly, i: usize, j: usize) -> Poly {
    let mut out = *poly;
    to_local_in_place(&mut out, i, j);
    out
}

/// [`to_local`] in place.
fn to_local_in_place(poly: &mut Poly, i: usize, j: usize) {
    let (x, y) = (i as f64, j as f64);
    for p in &mut poly.v[..poly.n] {
        *p = [p[0] - x, p[1] - y];
    }
}

/// The area of pixel `(i, j)`'s region ([`region`]) the polygons cover; each polygon lies in
/// the pixel's row strip.
fn pixel_area<'a>(
    i: usize,
    j: usize,
    within: Option<&Poly>,
    polygons: impl Iterator<Item = &'a Poly>,
    pieces: &mut Vec<Poly>,
    next: &mut Vec<Poly>,
) -> f64 {
    let Some(start) = region(within, i, j) else { return 0.0 };
    let total2 = start.area2_rel(0.0, 0.0);
    if total2 <= 0.0 {
        return 0.0;
    }
    pieces.clear();
    pieces.push(start);
    let x = i as f64;
    // The polygon's part in the pixel, built in two buffers reused from polygon to polygon.
    let (mut column, mut p) = (Poly::new(), Poly::new());
    for strip in polygons {
        clip::keep_into(strip, 0, x, true, &mut column);
        clip::keep_into(&column, 0, x + 1.0, false, &mut p);
        to_local_in_place(&mut p, i, j);
        if cut_pieces(pieces, &mut p, next) {
            break;
        }
    }
    let left = area2(pieces);
    (0.5 * (total2 - left)).clamp(0.0, 0.5 * total2)
}

/// Twice the area of `pieces` (in local coordinates), summed.
fn area2(pieces: &[Poly]) -> f64 {
    pieces.iter().map(|q| q.area2_rel(0.0, 0.0)).sum()
}

/// Cuts the convex polygon `p` (made strictly convex first) out of the disjoint convex
/// `pieces`; true when none is left. `next` is scratch space.
fn cut_pieces(pieces: &mut Vec<Poly>, p: &mut Poly, next: &mut Vec<Poly>) -> bool {
    make_strictly_convex(p);
    if p.n < 3 || p.area2_rel(0.0, 0.0) <= MIN_AREA2 {
        return pieces.is_empty();
    }
    let ((px0, px1), (py0, py1)) = (p.range(0), p.range(1));
    // Pieces `p` misses stay where they are (compacted over the ones it cuts); the parts of
    // the cut ones outside `p` are appended.
    next.clear();
    let mut kept = 0;
    for r in 0..pieces.len() {
        let ((qx0, qx1), (qy0, qy1)) = (pieces[r].range(0), pieces[r].range(1));
        if qx1 <= px0 || qx0 >= px1 || qy1 <= py0 || qy0 >= py1 {
            if kept != r {
                pieces[kept] = pieces[r];
            }
            kept += 1;
        } else {
            subtract(&pieces[r], p, 0, next);
        }
    }
    pieces.truncate(kept);
    pieces.append(next);
    pieces.is_empty()
}

/// Doubled area (px²) that [`Scratch::covers`] may find uncovered and still call the region
/// covered: far above the slivers rounding leaves along the polygons' shared edges (on the
/// order of `1e-16` times the square of the region's size in pixels), far below the `1e-9` px²
/// the ground truth states.
pub(crate) const COVER_SLACK2: f64 = 2e-12;

impl Scratch {
    /// Whether the union of `polygons` (convex, positive [`Poly::area2_rel`]) covers the convex
    /// region `region`, but for at most [`COVER_SLACK2`]: the region is cut by each polygon in
    /// turn, largest first, as a pixel is in [`pixel_area`], in coordinates relative to its
    /// first vertex. Cheap necessary conditions come first: the polygons' areas add up to the
    /// region's, and some polygon holds each of the probe points (the region's centroid, the
    /// points halfway from each corner to it, and those 1/1024 of the way from each corner and
    /// each edge's midpoint); the cutting stops once what is left exceeds the polygons still
    /// to cut.
    pub(crate) fn covers(&mut self, region: &Poly, polygons: &ScreenPolygons) -> bool {
        if region.n < 3 || polygons.is_empty() {
            return false;
        }
        let [ox, oy] = region.v[0];
        let total2 = region.area2_rel(ox, oy);
        let Scratch { pieces, next, order, .. } = self;
        order.clear();
        order.extend(
            polygons
                .contours()
                .enumerate()
                .map(|(k, p)| (Poly::from_slice(p).area2_rel(ox, oy), k as u32)),
        );
        let sum2: f64 = order.iter().map(|o| o.0).sum();
        if !(total2 > 0.0 && sum2 >= total2 - COVER_SLACK2) {
            return false;
        }
        let points = region.points();
        let inv = 1.0 / points.len() as f64;
        let centre = points.iter().fold([0.0, 0.0], |c, p| [c[0] + p[0] * inv, c[1] + p[1] * inv]);
        let toward = |p: Pt, f: f64| [p[0] + (centre[0] - p[0]) * f, p[1] + (centre[1] - p[1]) * f];
        let held = |q: Pt| polygons.contours().any(|poly| clip::holds(poly, q));
        let mid = |k: usize| {
            let (p, q) = (points[k], points[if k + 1 == points.len() { 0 } else { k + 1 }]);
            [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])]
        };
        if !held(centre)
            || !(0..points.len()).all(|k| {
                held(toward(points[k], 0.5))
                    && held(toward(points[k], 1.0 / 1024.0))
                    && held(toward(mid(k), 1.0 / 1024.0))
            })
        {
            return false;
        }
        let local = |points: &[Pt]| {
            let mut q = Poly::from_slice(points);
            for v in &mut q.v[..q.n] {
                *v = [v[0] - ox, v[1] - oy];
            }
            q
        };
        order.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        pieces.clear();
        pieces.push(local(points));
        // `order` is not empty, so what is left is measured at least once.
        let (mut rest2, mut left2) = (sum2, total2);
        for &(a2, k) in order.iter() {
            if cut_pieces(pieces, &mut local(polygons.contour(k as usize)), next) {
                return true;
            }
            rest2 -= a2;
            left2 = area2(pieces);
            if left2 > rest2 + COVER_SLACK2 {
                return false;
            }
        }
        left2 <= COVER_SLACK2
    }
}

/// Vertex count at which a piece is halved before it is stored or cut again, so that no cut
/// can overflow [`clip::CAP`] (a cut by one line adds at most one vertex).
const HALVE_AT: usize = 16;

/// Pushes onto `out` the convex pieces of `piece` outside the convex polygon `cut`, cutting by
/// `cut`'s edges from edge `first` on: the part outside each edge is kept and the inside goes
/// on to the next edge; what is inside every edge is covered.
fn subtract(piece: &Poly, cut: &Poly, first: usize, out: &mut Vec<Poly>) {
    let mut rest = *piece;
    let (mut inside, mut outside) = (Poly::new(), Poly::new());
    // `rest` takes `inside`'s valid vertices only at each edge (`Poly::assign`).
    for k in first..cut.n {
        if rest.n >= clip::CAP - 1 {
            let (a, b) = halve(&rest);
            subtract(&a, cut, k, out);
            subtract(&b, cut, k, out);
            return;
        }
        let (s, e) = (cut.v[k], cut.v[if k + 1 == cut.n { 0 } else { k + 1 }]);
        clip::split_left(&rest, s, e, &mut inside, &mut outside);
        store(&outside, out);
        if inside.n < 3 || inside.area2_rel(0.0, 0.0) <= MIN_AREA2 {
            return;
        }
        rest.assign(&inside);
    }
}

/// Removes from `out` the vertices where it does not turn strictly left (repeated points, and
/// points that rounding left on or just inside the line through their neighbours).
///
/// Cutting along every edge line of a polygon gives back the polygon only where it is
/// strictly convex: a vertex a rounding inside its neighbours' line makes the two edges
/// through it point anywhere (an edge 1e-14 long has no direction), and their lines, extended
/// across the pixel, would cut away covered area far from the vertex. Dropping such a vertex
/// `v` between `u` and `w` changes the area by the triangle `(u, v, w)`, whose doubled area is
/// the turn `cross(v - u, w - v) <= 0` measured at `v`: on the order of the rounding.
fn make_strictly_convex(out: &mut Poly) {
    let mut changed = true;
    while changed && out.n >= 3 {
        changed = false;
        let mut k = 0;
        while out.n >= 3 && k < out.n {
            let n = out.n;
            let (u, v, w) = (out.v[(k + n - 1) % n], out.v[k], out.v[(k + 1) % n]);
            if (v[0] - u[0]) * (w[1] - v[1]) - (v[1] - u[1]) * (w[0] - v[0]) > 0.0 {
                k += 1;
            } else {
                out.v.copy_within(k + 1..n, k);
                out.n -= 1;
                changed = true;
            }
        }
    }
    if out.n < 3 {
        out.n = 0;
    }
}

/// Pushes `piece` onto `out` unless it is empty or below [`MIN_AREA2`]; halved first when it
/// has [`HALVE_AT`] vertices or more.
fn store(piece: &Poly, out: &mut Vec<Poly>) {
    if piece.n < 3 || piece.area2_rel(0.0, 0.0) <= MIN_AREA2 {
        return;
    }
    if piece.n >= HALVE_AT {
        let (a, b) = halve(piece);
        store(&a, out);
        store(&b, out);
    } else {
        out.push(*piece);
    }
}

/// The convex polygon `poly` split along its diagonal from vertex 0 to vertex `n / 2` (both
/// lie on the line exactly): two convex parts of about half the vertices each.
fn halve(poly: &Poly) -> (Poly, Poly) {
    let (mut a, mut b) = (Poly::new(), Poly::new());
    clip::split_left(poly, poly.v[0], poly.v[poly.n / 2], &mut a, &mut b);
    (a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn polys(list: &[&[Pt]]) -> ScreenPolygons {
        let mut out = ScreenPolygons::default();
        for p in list {
            let mut q = Poly::from_slice(p);
            if q.area2_rel(0.0, 0.0) < 0.0 {
                q.reverse();
            }
            out.push(q.points());
        }
        out
    }

    /// The fan of `region`'s edges around `c`: triangles sharing their edges bit for bit.
    fn fan(region: &[Pt], c: Pt) -> Vec<[Pt; 3]> {
        (0..region.len()).map(|k| [region[k], region[(k + 1) % region.len()], c]).collect()
    }

    #[test]
    fn several_polygons_cover_a_region_only_without_a_gap() {
        let region = oriented(&[[10.25, 20.5], [14.75, 20.5], [15.5, 23.0], [12.0, 24.125]]);
        let covers = |list: &[[Pt; 3]]| {
            let refs: Vec<&[Pt]> = list.iter().map(|t| &t[..]).collect();
            Scratch::default().covers(&region, &polys(&refs))
        };
        let c = [12.3, 21.7];
        let tiles = fan(region.points(), c);
        assert!(covers(&tiles), "the fan tiles the region");
        // An overlapping extra polygon changes nothing.
        let mut more = tiles.clone();
        more.push([[9.0, 19.0], [16.0, 19.0], [12.0, 22.0]]);
        assert!(covers(&more));
        // One tile missing, or one pulled away from the centre by 1e-3 or 1e-7 px (a
        // sliver of about 1e-3 or 1e-7 px² uncovered): not covered.
        assert!(!covers(&tiles[1..]));
        for gap in [1e-3, 1e-7] {
            let mut apart = tiles.clone();
            apart[2][2] = [c[0] + gap, c[1] - gap];
            assert!(!covers(&apart), "gap {gap}");
        }
        // Two large polygons that overlap and leave a corner of the region out.
        let two =
            [[[9.0, 20.0], [16.0, 20.0], [9.0, 25.0]], [[16.0, 20.0], [16.0, 25.0], [11.0, 25.0]]];
        assert!(!covers(&two));
    }

    proptest::proptest! {
        /// Whenever several polygons are said to cover a region, the pixels' unions within the
        /// region cover each pixel's part of it.
        #[test]
        fn a_covered_region_is_covered_in_every_pixel(
            region in triangle(),
            c in (0.0f64..1.0, 0.0f64..1.0),
            others in proptest::collection::vec(triangle(), 0..5),
        ) {
            let region = oriented(&region);
            proptest::prop_assume!(region.area2_rel(0.0, 0.0) > 1e-6);
            let v = region.points();
            // A point inside the region (barycentric), the fan's centre.
            let (a, b) = if c.0 + c.1 > 1.0 { (1.0 - c.0, 1.0 - c.1) } else { c };
            let centre = [
                v[0][0] + a * (v[1][0] - v[0][0]) + b * (v[2][0] - v[0][0]),
                v[0][1] + a * (v[1][1] - v[0][1]) + b * (v[2][1] - v[0][1]),
            ];
            let mut list = fan(v, centre);
            list.extend(others);
            let refs: Vec<&[Pt]> = list.iter().map(|t| &t[..]).collect();
            let all = polys(&refs);
            if Scratch::default().covers(&region, &all) {
                let whole = single(&region, 8);
                let mut got = vec![0.0; 64];
                rows_areas(all.contours(), 0..8, 0..8, Some(&region), |_, _| Want::Yes,
                    &mut Scratch::default(), |i, j, a| got[j * 8 + i] = a);
                for k in 0..64 {
                    proptest::prop_assert!((got[k] - whole[k]).abs() < 1e-9, "pixel {}: {} of {}", k, got[k], whole[k]);
                }
            }
        }
    }

    #[test]
    fn overlapping_squares_count_their_overlap_once() {
        // Two 2 x 2 squares overlapping in a 1 x 1 square, off the grid by a quarter pixel.
        let p = polys(&[
            &[[1.25, 1.25], [3.25, 1.25], [3.25, 3.25], [1.25, 3.25]],
            &[[2.25, 2.25], [4.25, 2.25], [4.25, 4.25], [2.25, 4.25]],
        ]);
        let (area, work) = union_area(&p, 6, 6, |_| true, false);
        let total: f64 = area.iter().sum();
        assert!((total - 7.0).abs() < 1e-14, "{total}");
        assert_eq!(area[2 * 6 + 2], 1.0, "inside both: covered without a cut");
        assert!((area[6 + 1] - 0.5625).abs() < 1e-15, "{}", area[6 + 1]);
        assert!(work.covered_pixels >= 2);
        assert!(area.iter().all(|a| (0.0..=1.0).contains(a)));
    }

    #[test]
    fn a_hole_stays_uncovered() {
        // A ring of four bars around the pixel (2, 2).
        let p = polys(&[
            &[[1.0, 1.0], [4.0, 1.0], [4.0, 2.0], [1.0, 2.0]],
            &[[1.0, 3.0], [4.0, 3.0], [4.0, 4.0], [1.0, 4.0]],
            &[[1.0, 1.0], [2.0, 1.0], [2.0, 4.0], [1.0, 4.0]],
            &[[3.0, 1.0], [4.0, 1.0], [4.0, 4.0], [3.0, 4.0]],
        ]);
        let (area, _) = union_area(&p, 5, 5, |_| true, false);
        assert_eq!(area[2 * 5 + 2], 0.0);
        assert_eq!(area.iter().sum::<f64>(), 8.0);
    }

    #[test]
    fn only_accepted_pixels_are_evaluated() {
        let p = polys(&[&[[0.0, 0.0], [3.0, 0.0], [3.0, 3.0], [0.0, 3.0]]]);
        let (area, _) = union_area(&p, 3, 3, |k| k % 2 == 0, false);
        for (k, a) in area.iter().enumerate() {
            assert_eq!(*a, if k % 2 == 0 { 1.0 } else { 0.0 }, "pixel {k}");
        }
    }

    #[test]
    fn within_a_region_only_its_part_counts() {
        // A triangle region covering half of pixel (0, 0): the points with x <= y.
        let mut within = Poly::from_slice(&[[0.0, 0.0], [0.0, 1.0], [1.0, 1.0]]);
        if within.area2_rel(0.0, 0.0) < 0.0 {
            within.reverse();
        }
        let area_in_region = |poly: &[Pt]| {
            let mut got = Vec::new();
            rows_areas(
                polys(&[poly]).contours(),
                0..1,
                0..1,
                Some(&within),
                |_, _| Want::Yes,
                &mut Scratch::default(),
                |i, _, a| got.push((i, a)),
            );
            assert_eq!(got.len(), 1, "{got:?}");
            got[0].1
        };
        // A polygon covering the pixel covers the region's half.
        assert_eq!(area_in_region(&[[-1.0, -1.0], [2.0, -1.0], [2.0, 2.0], [-1.0, 2.0]]), 0.5);
        // One over the right half (x >= 0.5) meets the region in the triangle (0.5, 0.5),
        // (0.5, 1), (1, 1).
        let a = area_in_region(&[[0.5, -1.0], [2.0, -1.0], [2.0, 2.0], [0.5, 2.0]]);
        assert!((a - 0.125).abs() < 1e-15, "{a}");
    }

    /// Five shadow triangles of `cage`'s bars under a light 45 degrees from vertical in the
    /// plane of the bars (80 x 60): slivers with nearly coincident edges, on which i_overlay's
    /// union did not terminate. The covered area is bounded by the sum of the parts and at
    /// least the largest part, and comes out in a blink.
    #[test]
    fn slivers_from_a_grazing_cage_are_cut_in_bounded_time() {
        let tris: [[Pt; 3]; 5] = [
            [
                [3.161695234729119e1, 2.498630517900011e1],
                [4.8396341289063415e1, 2.503003800999215e1],
                [3.1603658710936575e1, 2.503003800999215e1],
            ],
            [
                [4.838304765270881e1, 2.498630517900012e1],
                [3.1616952347291182e1, 2.498630517900012e1],
                [3.163020395547951e1, 2.4942710610455176e1],
            ],
            [
                [3.161695234729119e1, 2.498630517900011e1],
                [3.163020395547951e1, 2.4942710610455176e1],
                [4.836979604452049e1, 2.4942710610455176e1],
            ],
            [
                [2.9882578909935745e1, 3.0691972040170636e1],
                [2.9863209246074735e1, 3.075569352415061e1],
                [3.1924580014539455e1, 2.3974284959598013e1],
            ],
            [
                [3.1936877608425938e1, 2.3933828866118365e1],
                [3.1924580014539455e1, 2.3974284959598013e1],
                [2.9882578909935745e1, 3.0691972040170636e1],
            ],
        ];
        let p = polys(&tris.iter().map(|t| &t[..]).collect::<Vec<_>>());
        let parts: Vec<f64> =
            p.contours().map(|c| 0.5 * Poly::from_slice(c).area2_rel(0.0, 0.0)).collect();
        let (area, _) = union_area(&p, 80, 60, |_| true, false);
        let total: f64 = area.iter().sum();
        let largest = parts.iter().copied().fold(0.0, f64::max);
        assert!(total >= largest - 1e-12 && total <= parts.iter().sum::<f64>() + 1e-12, "{total}");
        assert!(area.iter().all(|a| (0.0..=1.0).contains(a)));
    }

    /// Per-pixel areas of one convex polygon over a `size x size` frame.
    fn single(poly: &Poly, size: usize) -> Vec<f64> {
        let mut acc = vec![0.0; size * size];
        clip::for_each_pixel(poly, 0, size, size, |i, j, a| acc[j * size + i] += a);
        acc
    }

    fn oriented(points: &[Pt]) -> Poly {
        let mut p = Poly::from_slice(points);
        if p.area2_rel(0.0, 0.0) < 0.0 {
            p.reverse();
        }
        p
    }

    /// A triangle in an 8 x 8 frame; with `thin`, its third corner lies within `1e-9` px of the
    /// line through the first two (a sliver, as grazing light casts).
    fn triangle() -> impl proptest::strategy::Strategy<Value = [Pt; 3]> {
        use proptest::prelude::*;
        let pt = || (-1.0f64..9.0, -1.0f64..9.0).prop_map(|(x, y)| [x, y]);
        (pt(), pt(), pt(), 0.0f64..1.0, -1e-9f64..1e-9, any::<bool>()).prop_map(
            |(a, b, c, t, off, thin)| {
                if !thin {
                    return [a, b, c];
                }
                let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                [a, b, [a[0] + t * dx - off * dy, a[1] + t * dy + off * dx]]
            },
        )
    }

    proptest::proptest! {
        /// Two polygons: the union's area in each pixel is the sum of their areas less their
        /// intersection's (inclusion-exclusion, computed by other code).
        #[test]
        fn two_polygons_follow_inclusion_exclusion(a in triangle(), b in triangle()) {
            let (pa, pb) = (oriented(&a), oriented(&b));
            proptest::prop_assume!(pa.area2_rel(0.0, 0.0) > 0.0 && pb.area2_rel(0.0, 0.0) > 0.0);
            let (area, _) = union_area(&polys(&[&a, &b]), 8, 8, |_| true, false);
            let both = single(&clip::intersect(&pa, &pb), 8);
            let (sa, sb) = (single(&pa, 8), single(&pb, 8));
            for k in 0..64 {
                let expect = sa[k] + sb[k] - both[k];
                proptest::prop_assert!((area[k] - expect).abs() < 1e-12, "pixel {}: {} vs {}", k, area[k], expect);
            }
        }

        /// Several polygons: every pixel's covered area is in [0, 1], at least each part's and
        /// at most their sum, and the same in any order and with the outline found first.
        #[test]
        fn union_areas_are_bounded_and_order_free(tris in proptest::collection::vec(triangle(), 1..12)) {
            let list: Vec<&[Pt]> = tris.iter().map(|t| &t[..]).collect();
            let (area, _) = union_area(&polys(&list), 8, 8, |_| true, false);
            let reversed: Vec<&[Pt]> = list.iter().rev().copied().collect();
            let (again, _) = union_area(&polys(&reversed), 8, 8, |_| true, false);
            let (seamed, _) = union_area(&polys(&list), 8, 8, |_| true, true);
            let parts: Vec<Vec<f64>> = list.iter().map(|t| single(&oriented(t), 8)).collect();
            for k in 0..64 {
                proptest::prop_assert!((0.0..=1.0).contains(&area[k]));
                proptest::prop_assert!((area[k] - again[k]).abs() < 1e-12);
                proptest::prop_assert!((area[k] - seamed[k]).abs() < 1e-12);
                let largest = parts.iter().map(|p| p[k]).fold(0.0, f64::max);
                let sum: f64 = parts.iter().map(|p| p[k]).sum();
                proptest::prop_assert!(area[k] >= largest - 1e-12 && area[k] <= sum + 1e-12);
            }
        }
    }

    /// The triangles of a grid of `n x n` square cells of side `cell` from `origin`, each cut
    /// along a diagonal, every corner moved by its `jitter` (times the cell), without the
    /// triangles `holes` marks: neighbours share their edges bit for bit.
    fn mesh(
        n: usize,
        cell: f64,
        origin: Pt,
        jitter: &[(f64, f64)],
        holes: &[bool],
    ) -> Vec<[Pt; 3]> {
        let corner = |a: usize, b: usize| {
            let (dx, dy) = jitter[(b * (n + 1) + a) % jitter.len()];
            [origin[0] + cell * (a as f64 + dx), origin[1] + cell * (b as f64 + dy)]
        };
        let mut out = Vec::new();
        for b in 0..n {
            for a in 0..n {
                let (p, q, r, t) =
                    (corner(a, b), corner(a + 1, b), corner(a + 1, b + 1), corner(a, b + 1));
                out.extend([[p, q, r], [p, r, t]]);
            }
        }
        out.into_iter()
            .enumerate()
            .filter(|(k, _)| !holes[k % holes.len()])
            .map(|(_, t)| t)
            .collect()
    }

    proptest::proptest! {
        /// A jittered mesh with holes, its cells from a third of a pixel to three pixels wide,
        /// reaching beyond the frame: the areas with the outline found first are those without
        /// it, and no more pixel-polygon pairs are cut.
        #[test]
        fn the_outline_first_changes_no_area(
            n in 2usize..14,
            cell in 0.3f64..3.0,
            origin in (-2.0f64..2.0, -2.0f64..2.0),
            jitter in proptest::collection::vec((-0.2f64..0.2, -0.2f64..0.2), 1..64),
            holes in proptest::collection::vec(proptest::bool::weighted(0.2), 1..40),
        ) {
            let tris = mesh(n, cell, [origin.0, origin.1], &jitter, &holes);
            proptest::prop_assume!(!tris.is_empty());
            let list: Vec<&[Pt]> = tris.iter().map(|t| &t[..]).collect();
            let (plain, cut) = union_area(&polys(&list), 10, 10, |_| true, false);
            let (seamed, fewer) = union_area(&polys(&list), 10, 10, |_| true, true);
            for k in 0..100 {
                proptest::prop_assert!((plain[k] - seamed[k]).abs() < 1e-12, "pixel {}: {} vs {}", k, plain[k], seamed[k]);
            }
            proptest::prop_assert!(fewer.pixel_polygon_pairs <= cut.pixel_polygon_pairs);
        }
    }

    /// A mesh without holes covering the frame: only the pixels its outline and its cells'
    /// edges that do not match bit for bit meet are cut; an edge one rounding off its
    /// neighbour's is kept in the outline.
    #[test]
    fn a_mesh_is_cut_only_along_its_outline() {
        let tris = mesh(8, 1.5, [-1.0, -1.0], &[(0.05, -0.1), (0.0, 0.1), (-0.1, 0.0)], &[false]);
        let list: Vec<&[Pt]> = tris.iter().map(|t| &t[..]).collect();
        let all = polys(&list);
        let (area, work) = union_area(&all, 10, 10, |_| true, true);
        let (plain, _) = union_area(&all, 10, 10, |_| true, false);
        assert!(area.iter().zip(&plain).all(|(a, b)| (a - b).abs() < 1e-12));
        let met = boundary_pixels(&all, 10, 10);
        assert_eq!(
            met.iter().filter(|&&m| m).count(),
            0,
            "the mesh's outline lies outside the frame"
        );
        assert_eq!(work.pixel_polygon_pairs, 0);
        assert!(area.iter().all(|&a| a == 1.0));
        // One corner nudged by a rounding in one of the triangles that hold it: its edges no
        // longer match their neighbours', and the pixels they cross are cut.
        let mut nudged = tris.clone();
        nudged[20][0][0] = f64::from_bits(nudged[20][0][0].to_bits() + 1);
        let list: Vec<&[Pt]> = nudged.iter().map(|t| &t[..]).collect();
        let met = boundary_pixels(&polys(&list), 10, 10);
        assert!(met.iter().any(|&m| m), "the nudged edges are kept");
        let (area, work) = union_area(&polys(&list), 10, 10, |_| true, true);
        let (plain, _) = union_area(&polys(&list), 10, 10, |_| true, false);
        assert!(work.pixel_polygon_pairs > 0);
        assert!(area.iter().zip(&plain).all(|(a, b)| (a - b).abs() < 1e-12));
        // A finer mesh, whose 21,600 edges fill 64 buckets: an edge and its reverse still
        // meet, and a nudged corner is still found.
        let fine = mesh(60, 0.2, [-1.0, -1.0], &[(0.05, -0.1), (0.0, 0.1), (-0.1, 0.0)], &[false]);
        let list: Vec<&[Pt]> = fine.iter().map(|t| &t[..]).collect();
        assert!(!boundary_pixels(&polys(&list), 10, 10).contains(&true));
        let mut nudged = fine.clone();
        nudged[3_661][1][1] = f64::from_bits(nudged[3_661][1][1].to_bits() + 1);
        let list: Vec<&[Pt]> = nudged.iter().map(|t| &t[..]).collect();
        assert!(boundary_pixels(&polys(&list), 10, 10).contains(&true));
    }

    /// Found by `union_areas_are_bounded_and_order_free`: a triangle with two equal corners
    /// (no area) reaching out of the frame, its edge and its reverse in one polygon. Those do
    /// not pair up, and a polygon reaching beyond the frame is swept, not taken as covering
    /// the pixels of its box that its edges miss: it covers nothing.
    #[test]
    fn a_degenerate_polygon_across_the_frame_covers_nothing() {
        let (a, b) =
            ([0.5452327783495148, 8.540564930811412], [-0.5477674107305036, 7.59653507631114]);
        let all = polys(&[&[a, b, a]]);
        let (area, _) = union_area(&all, 8, 8, |_| true, true);
        assert!(area.iter().all(|&v| v == 0.0), "{area:?}");
        // Its edges miss pixel (0, 7), which its box reaches: only the frame tells.
        assert!(!boundary_pixels(&all, 8, 8)[7 * 8]);
    }
}
