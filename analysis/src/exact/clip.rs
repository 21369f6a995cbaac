//! Exact clipping of convex polygons against axis-aligned lines in `f64`: the per-pixel area
//! of polygons on the pixel grid; and clipping of convex polygons against lines and each other.
//!
//! A convex polygon is split at a line `x = c` (or `y = c`) into the part on each side; the
//! crossing points are computed once, with the split coordinate set to `c` exactly, so the two
//! parts share them bit for bit and their areas add up to the whole up to the rounding of the
//! shoelace sums. Areas are taken relative to the pixel's corner, where coordinates are small
//! and exact (`x - i` is exact for `x` in `[i, i + 1]`).

/// A point in screen space (pixels, y down).
pub(crate) type Pt = [f64; 2];

/// Vertex capacity of [`Poly`]: a triangle clipped by the homogeneous planes (7) and the four
/// frame sides stays below 16 vertices; the pixel clipper needs at most 7.
pub(crate) const CAP: usize = 24;

/// Most vertices of a projected triangle ([`super::shadow`]: three corners, one more per
/// homogeneous plane (seven) and per side of the rectangle it is clipped to (four)).
pub(crate) const MAX_PROJECTED: usize = 14;

/// Rows per band of the parallel pixel clipper.
pub(crate) const BAND: usize = 8;

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
        p.assign_points(points);
        p
    }

    /// The valid vertices.
    pub fn points(&self) -> &[Pt] {
        &self.v[..self.n]
    }

    #[inline]
    pub fn push(&mut self, p: Pt) {
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

    /// Makes `self` a copy of `other`, copying only its valid vertices (a whole `Poly` is
    /// [`CAP`] vertices; the hot loops copy the few they hold).
    #[inline]
    pub fn assign(&mut self, other: &Poly) {
        self.n = other.n;
        self.v[..other.n].copy_from_slice(other.points());
    }

    /// Makes `self` the polygon with the given vertices (at most [`CAP`]; extra vertices are
    /// dropped), without a new polygon.
    #[inline]
    pub fn assign_points(&mut self, points: &[Pt]) {
        let n = points.len().min(CAP);
        self.n = n;
        self.v[..n].copy_from_slice(&points[..n]);
    }

    /// Reverses the vertex order.
    pub fn reverse(&mut self) {
        self.v[..self.n].reverse();
    }

    /// Smallest and largest coordinate along `axis`.
    #[inline]
    pub fn range(&self, axis: usize) -> (f64, f64) {
        range(self.points(), axis)
    }
}

/// Smallest and largest coordinate of `points` along `axis`.
#[inline]
pub(crate) fn range(points: &[Pt], axis: usize) -> (f64, f64) {
    points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p[axis]), b.max(p[axis])))
}

/// Splits the convex polygon `poly` at the line `coordinate[axis] = c` into the part with
/// `coordinate <= c` (`lo`) and the part with `coordinate >= c` (`hi`). Vertices on the line go
/// to both; crossing points get the coordinate `c` exactly.
#[inline]
pub(crate) fn split(poly: &Poly, axis: usize, c: f64, lo: &mut Poly, hi: &mut Poly) {
    lo.n = 0;
    hi.n = 0;
    split_into(poly, axis, c, Some(lo), Some(hi));
}

/// Keeps the part of `poly` with `coordinate[axis] >= c` (when `keep_above`) or `<= c`: the
/// same vertices and crossing points as that side of [`split`], built alone.
#[inline]
pub(crate) fn keep(poly: &Poly, axis: usize, c: f64, keep_above: bool) -> Poly {
    let mut out = Poly::new();
    keep_into(poly, axis, c, keep_above, &mut out);
    out
}

/// [`keep`] into `out` (its vertices replaced), without a new polygon.
#[inline]
pub(crate) fn keep_into(poly: &Poly, axis: usize, c: f64, keep_above: bool, out: &mut Poly) {
    out.n = 0;
    if keep_above {
        split_into(poly, axis, c, None, Some(out));
    } else {
        split_into(poly, axis, c, Some(out), None);
    }
}

/// Appends the parts of [`split`] to the sides given (inlined, so a side not asked for costs
/// nothing).
#[inline(always)]
fn split_into(
    poly: &Poly,
    axis: usize,
    c: f64,
    mut lo: Option<&mut Poly>,
    mut hi: Option<&mut Poly>,
) {
    let n = poly.n;
    for k in 0..n {
        let p = poly.v[k];
        let q = poly.v[if k + 1 == n { 0 } else { k + 1 }];
        let dp = p[axis] - c;
        let dq = q[axis] - c;
        if dp <= 0.0 {
            if let Some(lo) = lo.as_deref_mut() {
                lo.push(p);
            }
        }
        if dp >= 0.0 {
            if let Some(hi) = hi.as_deref_mut() {
                hi.push(p);
            }
        }
        if (dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0) {
            let t = dp / (dp - dq);
            let mut x = [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])];
            x[axis] = c;
            if let Some(lo) = lo.as_deref_mut() {
                lo.push(x);
            }
            if let Some(hi) = hi.as_deref_mut() {
                hi.push(x);
            }
        }
    }
}

/// Rows `[floor(lo), ceil(hi) - 1]` a span `[lo, hi]` of positive length overlaps, clamped
/// to `0..height`; `None` when outside or empty.
#[inline]
pub(crate) fn overlapped_rows(lo: f64, hi: f64, height: usize) -> Option<(usize, usize)> {
    if hi.is_nan() || lo.is_nan() || hi <= lo || hi <= 0.0 || lo >= height as f64 {
        return None;
    }
    let a = lo.floor().max(0.0) as usize;
    let b = ((hi.ceil() as usize).max(1) - 1).min(height - 1);
    (a <= b).then_some((a, b))
}

/// Calls `f(i, j, area)` for every pixel `(i, j)` of rows `r0..r1` (and columns
/// `0..width`) that the convex polygon `poly` (positive [`Poly::area2_rel`]) overlaps, with
/// the area of the overlap, clipping it exactly against the pixel grid: row strips, then
/// columns. Every overlapped pixel is visited once, in row-major order.
#[inline]
pub(crate) fn for_each_pixel(
    poly: &Poly,
    r0: usize,
    r1: usize,
    width: usize,
    f: impl FnMut(usize, usize, f64),
) {
    for_each_pixel_in(poly, r0, r1, width, &mut PixelBufs::new(), f);
}

/// The polygons [`for_each_pixel_in`] clips into, reused from call to call: making six
/// polygons zeroes 2.3 KB, which on `bumpy`'s 530,688 sub-pixel triangles cost more than
/// clipping them.
pub(crate) struct PixelBufs {
    rows: [Poly; 3],
    columns: [Poly; 3],
}

impl PixelBufs {
    pub fn new() -> Self {
        Self { rows: [Poly::new(); 3], columns: [Poly::new(); 3] }
    }
}

/// [`for_each_pixel`] with the clipper's polygons in `bufs`.
pub(crate) fn for_each_pixel_in(
    poly: &Poly,
    r0: usize,
    r1: usize,
    width: usize,
    bufs: &mut PixelBufs,
    mut f: impl FnMut(usize, usize, f64),
) {
    let (ymin, ymax) = poly.range(1);
    if ymax.is_nan() || ymin.is_nan() || ymax <= r0 as f64 || ymin >= r1 as f64 {
        return;
    }
    // The polygon left below the rows swept so far, a row strip and a spare: the references
    // rotate, the polygons are not copied.
    let PixelBufs { rows, columns } = bufs;
    let [cur, row, spare] = rows;
    let (mut cur, mut spare) = (cur, spare);
    if ymin < r0 as f64 {
        split(poly, 1, r0 as f64, row, cur);
    } else {
        cur.assign(poly);
    }
    let j_start = (ymin.floor().max(r0 as f64)) as usize;
    let j_end = (ymax.ceil().max(0.0) as usize).min(r1);
    for j in j_start..j_end {
        if cur.n < 3 {
            break;
        }
        if ymax > (j + 1) as f64 {
            split(cur, 1, (j + 1) as f64, row, spare);
            std::mem::swap(&mut cur, &mut spare);
            sweep_row(row, j, width, columns, &mut f);
        } else {
            sweep_row(cur, j, width, columns, &mut f);
            cur.n = 0;
        }
    }
}

/// Calls `f(i, j, area)` for every column `i` the convex polygon `row` (inside the row strip
/// at `y = j`) overlaps, splitting it at every column line (into `bufs`, whose references
/// rotate as in [`for_each_pixel`]).
#[inline]
fn sweep_row(
    row: &Poly,
    j: usize,
    width: usize,
    bufs: &mut [Poly; 3],
    f: &mut impl FnMut(usize, usize, f64),
) {
    if row.n < 3 {
        return;
    }
    let (xmin, xmax) = row.range(0);
    if xmax.is_nan() || xmin.is_nan() || xmax <= 0.0 || xmin >= width as f64 {
        return;
    }
    let fj = j as f64;
    let [cur, piece, spare] = bufs;
    let (mut cur, mut spare) = (cur, spare);
    if xmin < 0.0 {
        split(row, 0, 0.0, piece, cur);
    } else {
        cur.assign(row);
    }
    let i_start = xmin.floor().max(0.0) as usize;
    let i_end = (xmax.ceil() as usize).min(width);
    // The columns wholly inside `row` (both cross-sections span them): their pieces would be
    // the pixel square exactly (corners set to the row and column lines), so their area is
    // exactly 1 without a cut, and the part right of them is one cut away.
    let (inner_from, inner_to) = interior_columns(row, fj, width).unwrap_or((usize::MAX, 0));
    let mut i = i_start;
    while i < i_end {
        if cur.n < 3 {
            break;
        }
        if i == inner_from && inner_to > i {
            for k in i..inner_to {
                f(k, j, 1.0);
            }
            i = inner_to;
            if xmax <= i as f64 {
                break;
            }
            keep_into(cur, 0, i as f64, true, spare);
            std::mem::swap(&mut cur, &mut spare);
            continue;
        }
        let fi = i as f64;
        if xmax > fi + 1.0 {
            split(cur, 0, fi + 1.0, piece, spare);
            f(i, j, 0.5 * piece.area2_rel(fi, fj));
            std::mem::swap(&mut cur, &mut spare);
        } else {
            f(i, j, 0.5 * cur.area2_rel(fi, fj));
            break;
        }
        i += 1;
    }
}

/// The columns `[from, to)` of `0..width` that the convex polygon `row` (inside the row strip
/// at `y = fj`) covers wholly: those within the cross-sections of both its top and bottom
/// lines (its vertices on them, whose `y` the strip's cuts set exactly); `None` when there are
/// none.
#[inline]
fn interior_columns(row: &Poly, fj: f64, width: usize) -> Option<(usize, usize)> {
    let (mut a, mut b) = (f64::NEG_INFINITY, f64::INFINITY);
    for c in [fj, fj + 1.0] {
        let (lo, hi) = row
            .points()
            .iter()
            .filter(|p| p[1] == c)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[0]), hi.max(p[0])));
        (a, b) = (a.max(lo), b.min(hi));
    }
    if (b - a).is_nan() || b - a < 1.0 {
        return None;
    }
    let from = a.ceil().max(0.0) as usize;
    let to = (b.floor().min(width as f64)) as usize;
    (to > from).then_some((from, to))
}

/// The part of the convex polygon `poly` on the left of the directed line `a -> b` (the
/// inside of a counter-clockwise polygon, in a y-up frame, of which `a -> b` is an edge).
#[inline]
pub(crate) fn keep_left(poly: &Poly, a: Pt, b: Pt) -> Poly {
    let (mut left, mut right) = (Poly::new(), Poly::new());
    split_left(poly, a, b, &mut left, &mut right);
    left
}

/// Splits the convex polygon `poly` at the directed line `a -> b` into the part on its left
/// (`left`, see [`keep_left`]) and the part on its right (`right`). Vertices on the line go to
/// both; crossing points are interpolated along `poly`'s edges once and shared by both parts,
/// so the parts tile `poly` up to the rounding of their area sums.
#[inline]
pub(crate) fn split_left(poly: &Poly, a: Pt, b: Pt, left: &mut Poly, right: &mut Poly) {
    left.n = 0;
    right.n = 0;
    let n = poly.n;
    let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
    let side = |p: Pt| ex * (p[1] - a[1]) - ey * (p[0] - a[0]);
    for k in 0..n {
        let p = poly.v[k];
        let q = poly.v[if k + 1 == n { 0 } else { k + 1 }];
        let (dp, dq) = (side(p), side(q));
        if dp >= 0.0 {
            left.push(p);
        }
        if dp <= 0.0 {
            right.push(p);
        }
        if (dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0) {
            let t = dp / (dp - dq);
            let x = [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])];
            left.push(x);
            right.push(x);
        }
    }
}

/// Whether the edge `s -> e` has a direction: a clip can leave two vertices a few roundings
/// apart, and the line through them points anywhere. Edges shorter than `1e-9` of their
/// coordinates' magnitude (and of a pixel) are skipped as clip lines and separating axes;
/// the neighbouring edges of the convex polygon bound it there.
#[inline]
pub(crate) fn has_direction(s: Pt, e: Pt) -> bool {
    let magnitude = s[0].abs().max(s[1].abs()).max(1.0);
    (e[0] - s[0]).abs().max((e[1] - s[1]).abs()) > 1e-9 * magnitude
}

/// The intersection of the convex polygons `a` and `b` (both with positive
/// [`Poly::area2_rel`]).
pub(crate) fn intersect(a: &Poly, b: &Poly) -> Poly {
    let mut cur = *a;
    for k in 0..b.n {
        if cur.n < 3 {
            cur.n = 0;
            break;
        }
        let (s, e) = (b.v[k], b.v[if k + 1 == b.n { 0 } else { k + 1 }]);
        if has_direction(s, e) {
            cur = keep_left(&cur, s, e);
        }
    }
    cur
}

/// Whether the convex polygon `points` (positive [`Poly::area2_rel`]) holds `q`, on or inside
/// every edge, in floating point (a filter: a point within a rounding of an edge may come out
/// either way).
pub(crate) fn holds(points: &[Pt], q: Pt) -> bool {
    (0..points.len()).all(|k| {
        let (s, e) = (points[k], points[if k + 1 == points.len() { 0 } else { k + 1 }]);
        (e[0] - s[0]) * (q[1] - s[1]) - (e[1] - s[1]) * (q[0] - s[0]) >= 0.0
    })
}

/// Whether the convex polygons `a` and `b` (vertex lists with positive [`Poly::area2_rel`])
/// have disjoint interiors by a separating line through an edge of one of them (the separating
/// axis test; touching counts as disjoint). `false` means they may overlap.
pub(crate) fn separated(a: &[Pt], b: &[Pt]) -> bool {
    let outside = |p: &[Pt], q: &[Pt]| {
        (0..p.len()).any(|k| {
            let (s, e) = (p[k], p[if k + 1 == p.len() { 0 } else { k + 1 }]);
            let (ex, ey) = (e[0] - s[0], e[1] - s[1]);
            has_direction(s, e) && q.iter().all(|v| ex * (v[1] - s[1]) - ey * (v[0] - s[0]) <= 0.0)
        })
    };
    outside(a, b) || outside(b, a)
}

/// The convex polygon `poly` clipped to the pixel square `(i, j)`.
#[inline]
pub(crate) fn clip_to_pixel(poly: &Poly, i: usize, j: usize) -> Poly {
    let (x, y) = (i as f64, j as f64);
    let (mut a, mut b) = (Poly::new(), Poly::new());
    keep_into(poly, 0, x, true, &mut a);
    keep_into(&a, 0, x + 1.0, false, &mut b);
    keep_into(&b, 1, y, true, &mut a);
    keep_into(&a, 1, y + 1.0, false, &mut b);
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Per-pixel areas of convex polygons added up over a `width x height` frame.
    fn accumulate(polys: &[&[Pt]], width: usize, height: usize) -> Vec<f64> {
        let mut acc = vec![0.0; width * height];
        for p in polys {
            let mut poly = Poly::from_slice(p);
            if poly.area2_rel(0.0, 0.0) < 0.0 {
                poly.reverse();
            }
            for_each_pixel(&poly, 0, height, width, |i, j, a| acc[j * width + i] += a);
        }
        acc
    }

    #[test]
    fn a_square_on_the_grid_covers_its_pixels_exactly() {
        let tris: [&[Pt]; 2] =
            [&[[1.25, 0.5], [3.75, 0.5], [3.75, 2.0]], &[[1.25, 0.5], [3.75, 2.0], [1.25, 2.0]]];
        let acc = accumulate(&tris, 5, 3);
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
        let acc = accumulate(&[&tri], 20, 20);
        let area = 0.5 * Poly::from_slice(&tri).area2_rel(0.0, 0.0).abs();
        let sum: f64 = acc.iter().sum();
        assert!((sum - area).abs() < 1e-12, "{sum} vs {area}");
        assert!(acc.iter().all(|&a| (-1e-15..=1.0 + 1e-15).contains(&a)));
    }

    /// Large polygons, whose rows have columns wholly inside (taken without a cut), give
    /// every pixel once, with the area of the polygon clipped to that pixel alone, and their
    /// wholly covered pixels exactly 1: triangles and a quadrilateral with corners on the
    /// grid lines, off the frame and at fractions.
    #[test]
    fn wholly_covered_columns_take_the_area_of_their_pixel() {
        let shapes: [&[Pt]; 4] = [
            &[[0.3, 0.7], [57.9, 3.2], [25.5, 41.6]],
            &[[-10.0, -5.0], [70.0, 2.0], [3.0, 60.0]],
            &[[2.0, 3.0], [40.0, 3.0], [40.0, 30.0], [2.0, 30.0]],
            &[[5.25, 1.0], [50.0, 20.5], [30.0, 44.0], [1.0, 17.0]],
        ];
        let (width, height) = (48, 40);
        for shape in shapes {
            let poly = oriented(shape);
            let mut seen = vec![0u32; width * height];
            let mut whole = 0;
            for_each_pixel(&poly, 0, height, width, |i, j, a| {
                seen[j * width + i] += 1;
                let alone = clip_to_pixel(&poly, i, j);
                let expect =
                    if alone.n >= 3 { 0.5 * alone.area2_rel(i as f64, j as f64) } else { 0.0 };
                assert!((a - expect).abs() <= 1e-13, "pixel ({i}, {j}): {a} vs {expect}");
                if expect == 1.0 {
                    assert_eq!(a, 1.0, "pixel ({i}, {j})");
                    whole += 1;
                }
            });
            assert!(seen.iter().all(|&n| n <= 1), "every pixel at most once");
            assert!(whole > 100, "{whole} pixels wholly covered");
        }
    }

    fn oriented(points: &[Pt]) -> Poly {
        let mut p = Poly::from_slice(points);
        if p.area2_rel(0.0, 0.0) < 0.0 {
            p.reverse();
        }
        p
    }

    #[test]
    fn convex_intersection_and_separation() {
        let a = oriented(&[[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]]);
        let b = oriented(&[[1.0, 1.0], [3.0, 1.0], [3.0, 3.0]]);
        let c = oriented(&[[2.0, 0.0], [4.0, 0.0], [2.0, 2.0]]);
        assert!(!separated(a.points(), b.points()));
        assert_eq!(0.5 * intersect(&a, &b).area2_rel(0.0, 0.0), 0.5);
        // Sharing the edge x = 2: touching counts as separated.
        assert!(separated(a.points(), c.points()));
        assert!(intersect(&a, &c).area2_rel(0.0, 0.0).abs() < 1e-15);
        let px = clip_to_pixel(&b, 1, 1);
        assert_eq!(0.5 * px.area2_rel(0.0, 0.0), 0.5);
    }

    /// A shadow polygon whose clip left two vertices 1e-14 apart: the line through them points
    /// anywhere (here it had every vertex of the receiver on its outside), so it is neither a
    /// separating axis nor a clip line. Found on `bumpy`, where it dropped a caster's shadow.
    #[test]
    fn a_tiny_edge_is_no_separating_axis() {
        let shadow = oriented(&[
            [104.59985017771307, 28.683719257967283],
            [98.9302473923912, 37.52843801645953],
            [97.38153350541533, 36.40702573351719],
            [104.59985017771307, 28.683719257967272],
        ]);
        let own = oriented(&[
            [102.92349580664977, 29.270161290279535],
            [104.59985017771305, 28.68371925796729],
            [104.55764574761162, 30.452236836286936],
        ]);
        assert!(!separated(shadow.points(), own.points()));
        let overlap = 0.5 * intersect(&own, &shadow).area2_rel(100.0, 30.0);
        assert!(overlap > 0.1, "{overlap}");
        assert!(!has_direction(shadow.v[0], [shadow.v[0][0], shadow.v[0][1] + 1e-14]));
        assert!(has_direction([0.0, 0.0], [0.0, 1e-6]));
    }
}
