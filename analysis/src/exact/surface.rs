//! Shadows on the triangles of `surface` pixels: every such triangle is a planar receiver of
//! its own.
//!
//! For receiver triangle `T` with plane `n·p = d` (`n` its unit normal): the casters the
//! light-space grid ([`CasterGrid`]) returns for `T` (any caster triangle but `T` itself, its
//! own mesh included: self-shadowing) are cut to their part between the plane and the light
//! and projected along light rays onto the plane and through the camera ([`Setup::caster`],
//! the machinery of the planar receiver); each shadow polygon is cut to the bounding box of
//! `T`'s own screen polygon and kept when it meets that polygon, and the area their union
//! covers within `T`'s screen polygon is computed in each pixel `T` tiles ([`coverage`]), so
//! a pixel takes the areas of the receivers that tile it (and of no other: a triangle hidden
//! behind the surface in one pixel is that pixel's business only where it is visible). A
//! shadow polygon containing the receiver's whole screen polygon shadows it without a cut,
//! and so do a few that cover it together (the receiver's polygon cut by each in turn leaves
//! nothing: [`coverage::Scratch::covers`]), as on a closed mesh's side away from the light,
//! whose shadow is cast by the several triangles of the other side (on `bunny-plane` 5,837 of
//! the 29,904 receivers; the stage's CPU time fell by a tenth). Only for the union are the
//! polygons cut to the receiver's polygon (both convex), which keeps its sweep to the polygon:
//! the check takes them as they are, since polygons cover the receiver's polygon exactly
//! when their parts inside it do. Cut before the check, as they were, the receivers the check
//! settles paid for cuts they did not need: at 800 x 600, one thread, 3 alternating runs,
//! the stage took 121.9 -> 106.1 ms on `bunny-plane`, 235.9 -> 217.6 on `bumpy` and 63.1
//! -> 60.7 on `cage`, with the same images.
//! Before any of that, a receiver facing away from the light on a closed object is asked
//! whether it is in the object's shadow by a count of the crossings beyond it, along one light
//! line ([`CasterGrid::behind_own_winding`], directional lights), else along every light line
//! through it ([`CasterGrid::behind_own_facing`]; [`closed`]'s module doc): if so, its whole
//! polygon is shadowed without a caster query or a projection (on `bunny-plane`, 3,984 of its
//! 4,085 receivers facing away from the light).
//!
//! A receiver whose plane holds the light (a directional light parallel to it, a spot light in
//! it) receives light only at grazing incidence and has no projection: its pixels are not
//! evaluated, and the run says how many.
//!
//! Receivers are processed in parallel, results kept in the order they are processed in, so
//! the output does not depend on the thread count. That order is the Z order of the grid cells
//! holding the centres of their light-space boxes ([`CasterGrid::order_key`]), so that
//! consecutive receivers ask for the same casters and find them in cache, unless their own
//! order already is local (a heightfield's rows; see `light_order`). On `bunny-plane`, whose
//! triangles' order is not (77 % of consecutive receivers lie in cells apart), the stage went
//! from 159 to 136 ms of CPU time at one thread (800 x 600, medians of 5 interleaved runs);
//! `bumpy` keeps its order. Each pixel adds the areas of the receivers that tile it in that
//! order; the images came out the same bit for bit on the built-in scenes.

use super::casters::{Candidates, CasterGrid};
use super::clip::{self, Poly};
use super::closed;
use super::coverage::{self, Want, Work};
use super::shadow::{Screen, Setup};
use super::ScreenPolygons;
use methods::Frame;
use rayon::prelude::*;

/// Most shadow polygons for which [`coverage::Scratch::covers`] is asked whether they cover
/// their receiver together.
const COVER_CHECK_POLYGONS: usize = 32;

/// The shadows on a set of receiver triangles, as shadowed areas of the pixels they tile.
#[derive(Debug, Default)]
pub(crate) struct SurfaceShadows {
    /// `(pixel, shadowed area)` of every wanted pixel a receiver's shadow reaches, receiver
    /// by receiver.
    pub areas: Vec<(u32, f64)>,
    /// Receivers whose plane holds the light (sorted).
    pub grazing: Vec<u32>,
    /// Receivers found in the shadow of their own object without a caster query.
    pub behind: u64,
    /// Receiver-caster pairs looked at.
    pub pairs: u64,
    /// Non-empty shadow polygons projected (over their receiver's screen box).
    pub polygons: u64,
    /// Work of the per-pixel unions.
    pub work: Work,
}

/// The shadows on a set of receiver triangles (sorted triangle ids, with their screen polygons
/// `polygon(r)` as [`Screen::triangle`] gives them), over the pixels `k` each receiver `r` is
/// wanted at (`wanted(r, k)`); `closed` decides which objects are closed casters.
pub(crate) fn shadows(
    frame: &Frame<'_>,
    grid: &CasterGrid<'_>,
    closed: &mut closed::ClosedCasters,
    receivers: &[u32],
    polygon: impl Fn(u32) -> Option<Poly> + Sync,
    wanted: impl Fn(u32, usize) -> bool + Sync,
) -> SurfaceShadows {
    // Receivers in small runs: one result per run rather than per receiver, and runs small
    // enough that a receiver with many pixels does not hold a thread while the other waits.
    const RUN: usize = 16;
    let behind = closed::self_shadowing(frame, receivers, closed);
    let shared = Shared { frame, screen: Screen::new(frame), grid, behind };
    // The receivers in the Z order of their light-space cells, where their own order is not
    // local (see the module doc).
    let ordered = light_order(grid, receivers);
    let receivers = ordered.as_deref().unwrap_or(receivers);
    let runs: Vec<SurfaceShadows> = receivers
        .par_chunks(RUN)
        .map_init(Scratch::default, |scratch, run| {
            let mut out = SurfaceShadows::default();
            for &r in run {
                let own = polygon(r);
                receiver(&shared, r, own, |k| wanted(r, k), scratch, &mut out);
            }
            out
        })
        .collect();
    let mut out = SurfaceShadows::default();
    for run in runs {
        out.grazing.extend(run.grazing);
        out.areas.extend(run.areas);
        out.behind += run.behind;
        out.pairs += run.pairs;
        out.polygons += run.polygons;
        out.work += run.work;
    }
    out
}

/// Consecutive pairs of receivers sampled by [`light_order`].
const ORDER_SAMPLES: usize = 1024;

/// The receivers in the Z order of their light-space cells ([`CasterGrid::order_key`]), or
/// `None` to keep their own order: when at most a quarter of [`ORDER_SAMPLES`] pairs of
/// consecutive receivers, evenly spaced, lie in cells that are not neighbours (a heightfield's
/// triangles, numbered row by row: 3 % of all pairs on `bumpy`, against 77 % on `bunny-plane`).
fn light_order(grid: &CasterGrid<'_>, receivers: &[u32]) -> Option<Vec<u32>> {
    let step = (receivers.len() / ORDER_SAMPLES).max(1);
    let pairs = receivers.windows(2).step_by(step);
    let far = pairs.clone().filter(|p| {
        let ([ax, ay], [bx, by]) = (grid.cell_of(p[0]), grid.cell_of(p[1]));
        ax.abs_diff(bx) > 1 || ay.abs_diff(by) > 1
    });
    if 4 * far.count() <= pairs.count() {
        return None;
    }
    let mut keys: Vec<u64> = receivers.par_iter().map(|&r| grid.order_key(r)).collect();
    keys.par_sort_unstable();
    Some(keys.iter().map(|&k| k as u32).collect())
}

/// Buffers a worker reuses from receiver to receiver.
#[derive(Default)]
struct Scratch {
    candidates: Candidates,
    pieces: ScreenPolygons,
    /// The pieces cut to the receiver's polygon, for the union.
    inside: ScreenPolygons,
    coverage: coverage::Scratch,
}

/// What every receiver reads.
struct Shared<'a> {
    frame: &'a Frame<'a>,
    screen: Screen,
    grid: &'a CasterGrid<'a>,
    /// Per object: whether its triangles facing away from the light may be found in its own
    /// shadow ([`closed::self_shadowing`]).
    behind: Vec<bool>,
}

/// The shadow on receiver triangle `r` (screen polygon `own`), over the pixels `k` with
/// `wanted(k)`, added to `out`.
fn receiver(
    shared: &Shared<'_>,
    r: u32,
    own: Option<Poly>,
    wanted: impl Fn(usize) -> bool,
    scratch: &mut Scratch,
    out: &mut SurfaceShadows,
) {
    let Shared { frame, screen, grid, behind } = shared;
    let Scratch { candidates, pieces, inside, coverage } = scratch;
    let g = &frame.geometry;
    let corners = g.corners(r as usize);
    let Some(own) = own else { return };
    let Some(n) = scenes::direction::unit((corners[1] - corners[0]).cross(corners[2] - corners[0]))
    else {
        return;
    };
    let Some(setup) = Setup::for_plane(frame, n, n.dot(corners[0])) else {
        out.grazing.push(r);
        return;
    };
    let (x0, x1) = own.range(0);
    let (y0, y1) = own.range(1);
    pieces.points.clear();
    pieces.ranges.clear();
    // A triangle facing away from the light behind the rest of its closed object: in its
    // object's shadow (see the module doc), without a caster query. The count along one line
    // comes first: it passes nearly every receiver the other passes, and more.
    let mut full = behind[g.object[r as usize] as usize]
        && (grid.behind_own_winding(r) || grid.behind_own_facing(r));
    let casters: &[u32] = if full {
        out.behind += 1;
        &[]
    } else {
        grid.query(&corners, candidates);
        &candidates.casters
    };
    for &c in casters {
        if c == r {
            continue;
        }
        out.pairs += 1;
        // The part over the receiver's box, kept only if it meets the receiver.
        let Some(piece) = setup.caster_in(g.corners(c as usize), [x0, x1, y0, y1]) else {
            continue;
        };
        out.polygons += 1;
        if contains(&piece, &own) {
            full = true;
            break;
        }
        if clip::separated(piece.points(), own.points()) {
            continue;
        }
        pieces.push(piece.points());
    }
    // Several shadow polygons covering the receiver together (its side away from the light on
    // a closed mesh, a part of one in another's shadow): no pixel needs a cut. Tried only for
    // a few polygons: the check's cuts multiply with their number, and on `cage`, whose bars
    // receive 80-100 polygons each, most checks failed after 4-60 us each.
    if !full && (1..=COVER_CHECK_POLYGONS).contains(&pieces.len()) && coverage.covers(&own, pieces)
    {
        full = true;
    }
    let width = screen.width as usize;
    let Some((r0, r1)) = clip::overlapped_rows(y0, y1, screen.height as usize) else { return };
    if full {
        let before = out.areas.len();
        clip::for_each_pixel(&own, r0, r1 + 1, width, |i, j, a| {
            let k = j * width + i;
            if wanted(k) {
                out.areas.push((k as u32, a));
            }
        });
        out.work.covered_pixels += (out.areas.len() - before) as u64;
    } else if !pieces.is_empty() {
        // The union is swept over the receiver's pixels within its polygon, of the pieces cut
        // to it: that keeps the sweep to the polygon (a bar of `cage` seen aslant fills a
        // small part of its box).
        inside.points.clear();
        inside.ranges.clear();
        for piece in pieces.contours() {
            let piece = Poly::from_slice(piece);
            let cut = clip::intersect(&piece, &own);
            if cut.n >= 3 {
                // The intersection of two convex polygons can have as many vertices as both
                // together; beyond what a shadow polygon can have, the piece itself is kept,
                // so that the union's clips stay within `clip::CAP`.
                inside.push(if cut.n <= clip::MAX_PROJECTED {
                    cut.points()
                } else {
                    piece.points()
                });
            }
        }
        if inside.is_empty() {
            return;
        }
        let cols = (x0.floor().max(0.0) as usize)..(x1.ceil().max(0.0) as usize).min(width);
        out.work += coverage::rows_areas(
            inside.contours(),
            r0..r1 + 1,
            cols,
            Some(&own),
            |i, j| if wanted(j * width + i) { Want::Yes } else { Want::No },
            coverage,
            |i, j, a| out.areas.push(((j * width + i) as u32, a)),
        );
    }
}

/// Whether the convex polygon `outer` contains every vertex of `inner` (both with positive
/// [`Poly::area2_rel`]).
fn contains(outer: &Poly, inner: &Poly) -> bool {
    inner.points().iter().all(|&v| clip::holds(outer.points(), v))
}

#[cfg(test)]
mod tests {
    use super::*;
    use instrumentation::Recorder;

    /// A heightfield's triangles, numbered row by row, keep their order; every 97th of them
    /// (consecutive ones far apart) are put in the Z order of their light-space cells, a
    /// permutation of them.
    #[test]
    fn receivers_are_reordered_only_when_their_order_is_not_local() {
        let scene = scenes::load("bumpy").expect("built-in");
        let frame = Frame::new(&scene, 80, 60, &mut Recorder::default());
        let all: Vec<u32> = (0..frame.geometry.len() as u32).collect();
        let grid = CasterGrid::new(&frame, &all);
        assert_eq!(light_order(&grid, &all), None);
        let spaced: Vec<u32> = all.iter().copied().step_by(97).collect();
        let ordered = light_order(&grid, &spaced).expect("reordered");
        let keys: Vec<u64> = ordered.iter().map(|&r| grid.order_key(r)).collect();
        assert!(keys.windows(2).all(|k| k[0] < k[1]), "in the order of their keys");
        let mut sorted = ordered.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, spaced, "a permutation");
        assert_ne!(ordered, spaced);
    }
}
