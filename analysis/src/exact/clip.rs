//! Exact clipping of convex polygons against axis-aligned lines in `f64`: the per-pixel area
//! of triangles on the pixel grid, and the pixels whose closed squares a polygon touches.
//!
//! A convex polygon is split at a line `x = c` (or `y = c`) into the part on each side; the
//! crossing points are computed once, with the split coordinate set to `c` exactly, so the two
//! parts share them bit for bit and their areas add up to the whole up to the rounding of the
//! shoelace sums. Areas are taken relative to the pixel's corner, where coordinates are small
//! and exact (`x - i` is exact for `x` in `[i, i + 1]`).

use super::ScreenPolygons;
use rayon::prelude::*;

/// A point in screen space (pixels, y down).
pub(crate) type Pt = [f64; 2];

/// Vertex capacity of [`Poly`]: a triangle clipped by the homogeneous planes (7) and the four
/// frame sides stays below 16 vertices; the pixel clipper needs at most 7.
const CAP: usize = 24;

/// Rows per band of the parallel pixel clipper.
const BAND: usize = 8;

/// A convex polygon of at most [`CAP`] vertices, on the stack.
#[derive(Clone, Copy)]
pub(crate) struct Poly {
    /// Number of vertices.
    pub n: usize,
    /// Vertices (the first `n` are valid).
    pub v: [Pt; CAP],
}

impl Poly {
    /// An empty polygon.
    pub fn new() -> Self {
        Self { n: 0, v: [[0.0; 2]; CAP] }
    }

    /// The polygon with the given vertices (at most [`CAP`]; extra vertices are dropped, which
    /// the callers rule out by construction).
    pub fn from_slice(points: &[Pt]) -> Self {
        let mut p = Self::new();
        for &q in points.iter().take(CAP) {
            p.push(q);
        }
        p
    }

    /// The valid vertices.
    pub fn points(&self) -> &[Pt] {
        &self.v[..self.n]
    }

    #[inline]
    fn push(&mut self, p: Pt) {
        if self.n < CAP {
            self.v[self.n] = p;
            self.n += 1;
        }
    }

    /// Twice the signed area relative to the origin `(ox, oy)` (positive for counter-clockwise
    /// in a y-up frame, i.e. clockwise on screen).
    #[inline]
    pub fn area2_rel(&self, ox: f64, oy: f64) -> f64 {
        let mut s = 0.0;
        for k in 0..self.n {
            let p = self.v[k];
            let q = self.v[if k + 1 == self.n { 0 } else { k + 1 }];
            s += (p[0] - ox) * (q[1] - oy) - (q[0] - ox) * (p[1] - oy);
        }
        s
    }

    /// Reverses the vertex order.
    pub fn reverse(&mut self) {
        self.v[..self.n].reverse();
    }

    /// Smallest and largest coordinate along `axis`.
    #[inline]
    pub fn range(&self, axis: usize) -> (f64, f64) {
        self.points()
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p[axis]), b.max(p[axis])))
    }
}

/// Splits the convex polygon `poly` at the line `coordinate[axis] = c` into the part with
/// `coordinate <= c` (`lo`) and the part with `coordinate >= c` (`hi`). Vertices on the line go
/// to both; crossing points get the coordinate `c` exactly.
#[inline]
pub(crate) fn split(poly: &Poly, axis: usize, c: f64, lo: &mut Poly, hi: &mut Poly) {
    lo.n = 0;
    hi.n = 0;
    let n = poly.n;
    for k in 0..n {
        let p = poly.v[k];
        let q = poly.v[if k + 1 == n { 0 } else { k + 1 }];
        let dp = p[axis] - c;
        let dq = q[axis] - c;
        if dp <= 0.0 {
            lo.push(p);
        }
        if dp >= 0.0 {
            hi.push(p);
        }
        if (dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0) {
            let t = dp / (dp - dq);
            let mut x = [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])];
            x[axis] = c;
            lo.push(x);
            hi.push(x);
        }
    }
}

/// Keeps the part of `poly` with `coordinate[axis] >= c` (when `keep_above`) or `<= c`.
pub(crate) fn keep(poly: &Poly, axis: usize, c: f64, keep_above: bool) -> Poly {
    let (mut lo, mut hi) = (Poly::new(), Poly::new());
    split(poly, axis, c, &mut lo, &mut hi);
    if keep_above {
        hi
    } else {
        lo
    }
}

/// Bins items into bands of [`BAND`] rows: `rows(item)` gives the inclusive row range an item
/// may touch (already clamped to the image). Returns `(offsets, items)` in CSR layout: band
/// `b`'s items are `items[offsets[b]..offsets[b + 1]]`.
fn bin_by_band(
    count: usize,
    height: usize,
    rows: impl Fn(usize) -> Option<(usize, usize)>,
) -> (Vec<usize>, Vec<u32>) {
    let bands = height.div_ceil(BAND);
    let mut offsets = vec![0usize; bands + 1];
    let ranges: Vec<Option<(usize, usize)>> = (0..count).map(&rows).collect();
    for &(a, b) in ranges.iter().flatten() {
        for band in a / BAND..=b / BAND {
            offsets[band + 1] += 1;
        }
    }
    for b in 0..bands {
        offsets[b + 1] += offsets[b];
    }
    let mut fill = offsets.clone();
    let mut items = vec![0u32; offsets[bands]];
    for (i, r) in ranges.iter().enumerate() {
        if let Some((a, b)) = *r {
            for band in a / BAND..=b / BAND {
                items[fill[band]] = i as u32;
                fill[band] += 1;
            }
        }
    }
    (offsets, items)
}

/// Rows `[floor(lo), ceil(hi) - 1]` a span `[lo, hi]` of positive length overlaps, clamped
/// to `0..height`; `None` when outside or empty.
#[inline]
fn overlapped_rows(lo: f64, hi: f64, height: usize) -> Option<(usize, usize)> {
    if hi.is_nan() || lo.is_nan() || hi <= lo || hi <= 0.0 || lo >= height as f64 {
        return None;
    }
    let a = lo.floor().max(0.0) as usize;
    let b = ((hi.ceil() as usize).max(1) - 1).min(height - 1);
    (a <= b).then_some((a, b))
}

/// Area of every pixel covered by the triangles (`width x height` image, row-major), each
/// triangle clipped exactly against the pixel grid. Triangles must lie in the frame
/// `[0, width] x [0, height]` (parts outside are dropped); overlapping triangles add up.
pub(crate) fn accumulate_area(tris: &[[Pt; 3]], width: usize, height: usize) -> Vec<f64> {
    let mut acc = vec![0.0; width * height];
    if width == 0 || height == 0 {
        return acc;
    }
    let (offsets, items) = bin_by_band(tris.len(), height, |t| {
        let (lo, hi) = tris[t]
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p[1]), b.max(p[1])));
        overlapped_rows(lo, hi, height)
    });
    acc.par_chunks_mut(BAND * width).enumerate().for_each(|(band, chunk)| {
        let r0 = band * BAND;
        let r1 = (r0 + BAND).min(height);
        let (mut lo, mut hi) = (Poly::new(), Poly::new());
        for &t in &items[offsets[band]..offsets[band + 1]] {
            let mut cur = Poly::from_slice(&tris[t as usize]);
            if cur.area2_rel(0.0, 0.0) < 0.0 {
                cur.reverse();
            }
            let (ymin, ymax) = cur.range(1);
            if ymin < r0 as f64 {
                split(&cur, 1, r0 as f64, &mut lo, &mut hi);
                cur = hi;
            }
            let j_start = (ymin.floor().max(r0 as f64)) as usize;
            let j_end = (ymax.ceil().max(0.0) as usize).min(r1);
            for j in j_start..j_end {
                if cur.n < 3 {
                    break;
                }
                let row = if ymax > (j + 1) as f64 {
                    split(&cur, 1, (j + 1) as f64, &mut lo, &mut hi);
                    cur = hi;
                    lo
                } else {
                    let row = cur;
                    cur.n = 0;
                    row
                };
                let base = (j - r0) * width;
                sweep_row(&row, j as f64, &mut chunk[base..base + width]);
            }
        }
    });
    acc
}

/// Adds the area of the convex polygon `row` (inside the row strip at `y = j`) to the pixels of
/// `out` (one row), splitting it at every column line.
#[inline]
fn sweep_row(row: &Poly, j: f64, out: &mut [f64]) {
    if row.n < 3 {
        return;
    }
    let width = out.len();
    let (xmin, xmax) = row.range(0);
    if xmax.is_nan() || xmin.is_nan() || xmax <= 0.0 || xmin >= width as f64 {
        return;
    }
    let mut cur = *row;
    let (mut lo, mut hi) = (Poly::new(), Poly::new());
    if xmin < 0.0 {
        split(&cur, 0, 0.0, &mut lo, &mut hi);
        cur = hi;
    }
    let i_start = xmin.floor().max(0.0) as usize;
    let i_end = (xmax.ceil() as usize).min(width);
    for (i, slot) in out.iter_mut().enumerate().take(i_end).skip(i_start) {
        if cur.n < 3 {
            break;
        }
        let fi = i as f64;
        if xmax > fi + 1.0 {
            split(&cur, 0, fi + 1.0, &mut lo, &mut hi);
            *slot += 0.5 * lo.area2_rel(fi, j);
            cur = hi;
        } else {
            *slot += 0.5 * cur.area2_rel(fi, j);
            break;
        }
    }
}

/// Marks in `mask` (row-major `width x height`) every pixel whose closed square the convex
/// polygon touches, widened by `eps` pixels on every side (conservative).
pub(crate) fn mark_touched(
    polys: &ScreenPolygons,
    width: usize,
    height: usize,
    eps: f64,
    mask: &mut [bool],
) {
    if width == 0 || height == 0 {
        return;
    }
    let touched_range = |lo: f64, hi: f64, size: usize| -> Option<(usize, usize)> {
        // Pixel `i`'s closed span [i, i + 1] meets [lo - eps, hi + eps].
        let (lo, hi) = (lo - eps, hi + eps);
        if hi.is_nan() || lo.is_nan() || hi < 0.0 || lo > size as f64 || hi < lo {
            return None;
        }
        let a = (lo.ceil() - 1.0).max(0.0) as usize;
        let b = (hi.floor().max(0.0) as usize).min(size - 1);
        (a <= b).then_some((a, b))
    };
    let (offsets, items) = bin_by_band(polys.len(), height, |k| {
        let p = Poly::from_slice(&polys.points[polys.ranges[k].clone()]);
        if p.n == 0 {
            return None;
        }
        let (lo, hi) = p.range(1);
        touched_range(lo, hi, height)
    });
    mask.par_chunks_mut(BAND * width).enumerate().for_each(|(band, chunk)| {
        let r0 = band * BAND;
        let r1 = (r0 + BAND).min(height);
        for &k in &items[offsets[band]..offsets[band + 1]] {
            let p = &Poly::from_slice(&polys.points[polys.ranges[k as usize].clone()]);
            let (ylo, yhi) = p.range(1);
            let Some((a, b)) = touched_range(ylo, yhi, height) else { continue };
            for j in a.max(r0)..=b.min(r1 - 1) {
                let strip = keep(&keep(p, 1, j as f64 - eps, true), 1, (j + 1) as f64 + eps, false);
                if strip.n == 0 {
                    continue;
                }
                let (xlo, xhi) = strip.range(0);
                if let Some((ia, ib)) = touched_range(xlo, xhi, width) {
                    let base = (j - r0) * width;
                    chunk[base + ia..=base + ib].iter_mut().for_each(|m| *m = true);
                }
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_on_the_grid_covers_its_pixels_exactly() {
        let tris =
            [[[1.25, 0.5], [3.75, 0.5], [3.75, 2.0]], [[1.25, 0.5], [3.75, 2.0], [1.25, 2.0]]];
        let acc = accumulate_area(&tris, 5, 3);
        let expect = [
            0.0, 0.375, 0.5, 0.375, 0.0, //
            0.0, 0.75, 1.0, 0.75, 0.0, //
            0.0, 0.0, 0.0, 0.0, 0.0,
        ];
        for (k, (a, e)) in acc.iter().zip(expect).enumerate() {
            assert!((a - e).abs() < 1e-15, "pixel {k}: {a} vs {e}");
        }
    }

    #[test]
    fn areas_sum_to_the_triangle_area() {
        let tri = [[0.3, 0.7], [17.9, 3.2], [5.5, 11.6]];
        let acc = accumulate_area(&[tri], 20, 20);
        let area = 0.5 * Poly::from_slice(&tri).area2_rel(0.0, 0.0).abs();
        let sum: f64 = acc.iter().sum();
        assert!((sum - area).abs() < 1e-12, "{sum} vs {area}");
        assert!(acc.iter().all(|&a| (-1e-15..=1.0 + 1e-15).contains(&a)));
    }

    #[test]
    fn touching_a_corner_marks_the_four_pixels_around_it() {
        let mut tri = ScreenPolygons::default();
        tri.push(&[[2.0, 2.0], [1.5, 3.0], [1.0, 2.5]]);
        let mut mask = vec![false; 16];
        mark_touched(&tri, 4, 4, 0.0, &mut mask);
        let marked: Vec<usize> = (0..16).filter(|&k| mask[k]).collect();
        // The corner (2, 2) touches pixels (1, 1), (2, 1), (1, 2), (2, 2); the vertex on
        // x = 1 touches (0, 2), the one on y = 3 touches (1, 3).
        assert_eq!(marked, vec![5, 6, 8, 9, 10, 13]);
    }
}
