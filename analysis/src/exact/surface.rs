//! Shadows on the triangles of `surface` pixels: every such triangle is a planar receiver of
//! its own.
//!
//! For receiver triangle `T` with plane `n·p = d` (`n` its unit normal): the casters the
//! light-space grid ([`CasterGrid`]) returns for `T` (any caster triangle but `T` itself, its
//! own mesh included: self-shadowing) are cut to their part between the plane and the light
//! and projected along light rays onto the plane and through the camera ([`Setup::caster`],
//! the machinery of the planar receiver); each shadow polygon is intersected with `T`'s own
//! screen polygon (both convex), and the pieces are unioned on the exact grid and
//! triangulated (see [`union`](super::union)). Three cases need no union: no piece (`T` is
//! lit), one piece (it is convex: fanned), and a shadow polygon containing `T`'s whole
//! screen polygon (`T` is in shadow: fanned). The triangles are then clipped exactly against
//! the pixel grid, and each pixel takes the areas of the receivers that tile it (and of no
//! other: a triangle hidden behind the surface in one pixel is that pixel's business only
//! where it is visible).
//!
//! A receiver whose plane holds the light (a directional light parallel to it, a spot light in
//! it) receives light only at grazing incidence and has no projection: its pixels are not
//! evaluated, and the run says how many.
//!
//! Receivers are processed in parallel, results kept in receiver order, so the output does not
//! depend on the thread count.

use super::casters::CasterGrid;
use super::clip::{self, Poly, Pt};
use super::shadow::{Screen, Setup};
use super::{union, ScreenPolygons};
use methods::Frame;
use rayon::prelude::*;

/// The shadows on a set of receiver triangles, in screen space.
#[derive(Debug, Default)]
pub(crate) struct SurfaceShadows {
    /// Shadow triangles; `tag[k]` is the receiver triangle `tris[k]` lies on.
    pub tris: Vec<[Pt; 3]>,
    /// The receiver of each shadow triangle.
    pub tag: Vec<u32>,
    /// Receivers whose plane holds the light (sorted).
    pub grazing: Vec<u32>,
    /// Receiver-caster pairs looked at.
    pub pairs: u64,
    /// Non-empty shadow polygons projected.
    pub polygons: u64,
    /// Constraint edges spade skipped (0 for valid unions).
    pub conflicts: usize,
}

/// One receiver's result.
#[derive(Default)]
struct Receiver {
    tris: Vec<[Pt; 3]>,
    grazing: bool,
    pairs: u64,
    polygons: u64,
    conflicts: usize,
}

/// The shadows on the receiver triangles `receivers` (sorted triangle ids).
pub(crate) fn shadows(frame: &Frame<'_>, grid: &CasterGrid, receivers: &[u32]) -> SurfaceShadows {
    let screen = Screen::new(frame);
    let step = union::grid_step(screen.width, screen.height);
    let per: Vec<Receiver> = receivers
        .par_iter()
        .map_init(Scratch::default, |scratch, &r| receiver(frame, &screen, grid, step, r, scratch))
        .collect();
    let mut out = SurfaceShadows::default();
    for (&r, res) in receivers.iter().zip(per) {
        if res.grazing {
            out.grazing.push(r);
        }
        out.tag.extend(std::iter::repeat_n(r, res.tris.len()));
        out.tris.extend(res.tris);
        out.pairs += res.pairs;
        out.polygons += res.polygons;
        out.conflicts += res.conflicts;
    }
    out
}

/// Buffers a worker reuses from receiver to receiver.
#[derive(Default)]
struct Scratch {
    candidates: Vec<u32>,
    pieces: ScreenPolygons,
}

/// The shadow on receiver triangle `r`.
fn receiver(
    frame: &Frame<'_>,
    screen: &Screen,
    grid: &CasterGrid,
    step: f64,
    r: u32,
    scratch: &mut Scratch,
) -> Receiver {
    let Scratch { candidates, pieces } = scratch;
    let g = &frame.geometry;
    let corners = g.corners(r as usize);
    let mut out = Receiver::default();
    let Some((own, _)) = screen.triangle(corners) else { return out };
    let Some(n) = scenes::direction::unit((corners[1] - corners[0]).cross(corners[2] - corners[0]))
    else {
        return out;
    };
    let Some(setup) = Setup::for_plane(frame, n, n.dot(corners[0])) else {
        out.grazing = true;
        return out;
    };
    grid.query(&corners, candidates);
    let (x0, x1) = own.range(0);
    let (y0, y1) = own.range(1);
    pieces.points.clear();
    pieces.ranges.clear();
    let mut full = false;
    for &c in candidates.iter() {
        if c == r {
            continue;
        }
        out.pairs += 1;
        let Some(shadow) = setup.caster(g.corners(c as usize)) else { continue };
        out.polygons += 1;
        if contains(&shadow, &own) {
            full = true;
            break;
        }
        // The part over the receiver's box (axis-parallel cuts, so pieces share the box's
        // sides exactly), kept only if it meets the receiver.
        let piece = clip::keep(&clip::keep(&shadow, 0, x0, true), 0, x1, false);
        let piece = clip::keep(&clip::keep(&piece, 1, y0, true), 1, y1, false);
        if piece.n >= 3 && !clip::separated(&piece, &own) && clip::intersect(&piece, &own).n >= 3 {
            pieces.push(piece.points());
        }
    }
    if full {
        fan(&own, &mut out.tris);
    } else if pieces.len() == 1 {
        fan(&clip::intersect(&Poly::from_slice(&pieces.points), &own), &mut out.tris);
    } else if pieces.len() > 1 {
        let (tris, conflicts) =
            union::triangulate(&union::union_within(pieces, own.points(), step));
        out.tris = tris;
        out.conflicts = conflicts;
    }
    out
}

/// Whether the convex polygon `outer` contains every vertex of `inner` (both with positive
/// [`Poly::area2_rel`]).
fn contains(outer: &Poly, inner: &Poly) -> bool {
    (0..outer.n).all(|k| {
        let (s, e) = (outer.v[k], outer.v[if k + 1 == outer.n { 0 } else { k + 1 }]);
        let (ex, ey) = (e[0] - s[0], e[1] - s[1]);
        inner.points().iter().all(|v| ex * (v[1] - s[1]) - ey * (v[0] - s[0]) >= 0.0)
    })
}

/// Appends the fan triangulation of the convex polygon `poly`.
fn fan(poly: &Poly, out: &mut Vec<[Pt; 3]>) {
    for k in 1..poly.n.saturating_sub(1) {
        out.push([poly.v[0], poly.v[k], poly.v[k + 1]]);
    }
}
