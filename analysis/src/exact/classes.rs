//! Pixel classes: what each pixel's square sees, decided exactly from the camera's view of
//! the triangles.
//!
//! # The rule
//!
//! Every triangle `t` is projected through the camera, clipped at the near plane and to the
//! frame ([`Screen::triangle`]): a convex screen polygon `P_t` with a winding sign (`+1` or
//! `-1`, the orientation its corners have on screen); triangles seen edge-on have no polygon.
//! For the closed square `Q` of a pixel:
//!
//! 1. `F` = the triangles whose polygon overlaps `Q` with an area above [`MIN_OVERLAP`] (the
//!    overlap is clipped exactly against the pixel grid, as `exact`'s areas are).
//!    `F` empty: **`uncovered`**.
//! 2. The seed `s` is the triangle the camera G-buffer holds at the pixel centre (the nearest
//!    triangle there). No seed, or a seed not in `F`: **`edge`**.
//! 3. `C` = the triangles of `F` reachable from `s` through shared edges (two corners at
//!    equal positions) between triangles of `s`'s object with `s`'s winding: one
//!    continuous surface, front-facing as `s` is (a surface is judged by the consistency of
//!    its own winding, whichever way its file winds it, so a visible back face, whose winding
//!    on screen is the other, never joins `C`).
//! 4. `C` tiles `Q` without gap or overlap: the areas of `P_t ∩ Q` over `C` sum to at least
//!    [`MIN_TILE_COVERAGE`], and no two triangles of `C` overlap inside `Q` by more than
//!    [`MAX_TILE_OVERLAP`] (two triangles with one winding sharing an edge that their
//!    corners' orders run in opposite directions, as a consistently wound mesh has it, lie
//!    on its two sides and are not tested; the others by a separating-axis test, then by
//!    their clipped intersection's area: among them a fold of a mesh wound inconsistently,
//!    whose two triangles lie on one side of the edge, the hidden one under the other, and a
//!    triangle repeated). Otherwise: **`edge`**.
//! 5. Nothing of `F \ C` is in front of `C`: for every `u` in `F \ C` and `t` in `C` whose
//!    polygons overlap inside `Q` (by more than [`MIN_OVERLAP`]), `u`'s plane is not nearer
//!    to the camera than `t`'s at any corner of that overlap. The inverse depth of a plane
//!    is affine on the screen, so the corners decide for the whole convex overlap. Depths are
//!    compared along the camera ray through the corner with a tolerance of `1e-9` times the
//!    largest distance of the two triangles' corners from the camera's origin (the magnitude
//!    of the numbers in the comparison). Otherwise: **`edge`**.
//! 6. Then the square sees `C` and nothing else: **`planar`** when `s`'s object is planar
//!    (`Mesh::plane`), else **`surface`**.
//!
//! `exact` evaluates `planar` and `surface` pixels: their visible surface is known triangle by
//! triangle (`C`), and its lit fraction is computed exactly. Everything a square sees beyond
//! one surface (a silhouette, a depth discontinuity, several objects, background) is `edge`.
//!
//! # Cost
//!
//! One exact pixel-grid clip per triangle (the `pixel_triangle_overlaps` counter counts the
//! overlaps found; the columns of a row a triangle covers wholly are taken without a cut),
//! then per pixel a few tests between the triangles overlapping it, in parallel over bands of
//! rows. Those tests grow with the square of the triangles a pixel overlaps: on `bunny-plane`
//! 79,083 of the bunny's pixels overlap 4 to 15 triangles or more (5 to 9 most often), and
//! rule 3 finds which pairs share an edge once for rules 3 and 4. A pixel's first whole cover
//! is kept apart from the list that is grouped by pixel (on `bunny-plane`, 315,077 of 866,761
//! overlaps, mostly the ground's) and put back in contour order where the pixel has other
//! overlaps.

use super::clip::{self, Poly, Pt};
use super::shadow::{plane_depth, Screen};
use super::ScreenPolygons;
use crate::pixel_class::PixelClass;
use glam::DVec3;
use methods::{raster::NO_TRIANGLE, Frame};
use rayon::prelude::*;
use scenes::projection::Ray;

/// Smallest area (pixels) of a triangle's overlap with a square, or of two triangles' overlap,
/// that counts: below it the overlap is the rounding of a shared edge or corner.
pub const MIN_OVERLAP: f64 = 1e-12;

/// Area (pixels) the covering surface must reach in a square to tile it.
pub const MIN_TILE_COVERAGE: f64 = 1.0 - 1e-9;

/// Largest overlap (pixels) two triangles of the covering surface may have in a square.
pub const MAX_TILE_OVERLAP: f64 = 1e-9;

/// Relative tolerance of the depth comparison of rule 5.
const DEPTH_TOLERANCE: f64 = 1e-9;

/// Every pixel's class, and for `planar` and `surface` pixels the triangles that tile their
/// square.
#[derive(Debug, Clone, PartialEq)]
pub struct Classes {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The class of each pixel (row-major).
    pub class: Vec<PixelClass>,
    /// Pixel `k`'s tiling triangles are `tiles[offsets[k]..offsets[k + 1]]` (in triangle
    /// order; empty for `edge` and `uncovered` pixels).
    pub offsets: Vec<u32>,
    /// The tiling triangles of every pixel, pixel after pixel.
    pub tiles: Vec<u32>,
    /// Pixel-triangle overlaps measured.
    pub overlaps: u64,
    /// Every triangle's screen polygon ([`Screen::triangle`]), from which the classes were
    /// decided: triangle `t`'s is contour `t` (empty: none).
    pub(crate) screen: ScreenPolygons,
    /// `(pixel, triangle)` for every triangle whose screen polygon overlaps an `edge` pixel,
    /// however little, pixel by pixel: the only triangles a camera ray through the pixel can
    /// meet.
    pub edge_overlaps: Vec<(u32, u32)>,
}

impl Classes {
    /// The triangles that tile pixel `k`'s square.
    pub fn tiles_of(&self, k: usize) -> &[u32] {
        &self.tiles[self.offsets[k] as usize..self.offsets[k + 1] as usize]
    }

    /// Triangle `t`'s screen polygon, as [`Screen::triangle`] gives it (without the winding);
    /// `None` when it has none.
    pub(crate) fn screen_polygon(&self, t: u32) -> Option<Poly> {
        let range = self.screen.ranges.get(t as usize)?;
        (!range.is_empty()).then(|| Poly::from_slice(&self.screen.points[range.clone()]))
    }
}

/// The screen polygons of every triangle, indexed by triangle: `polys` contour `t` is
/// triangle `t`'s (empty when it has none), with winding `winding[t]`, and its corners
/// `corners[t]` span the camera depths `depth[t]` (smallest, largest). The corners are copied
/// once and read in place by the rule's tests: gathered from the geometry per pixel (626,844
/// times for `bunny-plane`'s 80,867 pixels of several triangles at 800 x 600), with every
/// triangle's normal, the stage took 5 % longer there (one pinned thread, 6 alternating runs).
///
/// Indexed by triangle, every array but the polygons' points is written in place, in
/// parallel over chunks of triangles, into memory zeroed in parallel: numbered by
/// contour, only the triangles with a polygon, they were gathered per chunk and then joined
/// in one serial copy, 24-29 ms of `bumpy`'s pixel classes at one and two threads (530,688
/// triangles, 800 x 600). A triangle without a polygon keeps zeros, which nothing reads.
///
/// `keys[t]` holds a hash of each corner's position ([`corner_key`]): two triangles whose keys
/// have fewer than two in common share no edge, which rule 3 asks of every pair of a pixel's
/// triangles (most of them not neighbours) before it compares their corners: the stage took
/// 46.6 -> 45.3 ms on `bunny-plane` at two threads (8 alternating runs, load 0.7-0.8) and
/// 283.7 -> 270.0 ms on `bumpy` at one (3 runs), 800 x 600.
struct Projected {
    polys: ScreenPolygons,
    winding: Vec<f64>,
    depth: Vec<[f64; 2]>,
    corners: Vec<[DVec3; 3]>,
    keys: Vec<[u32; 3]>,
}

impl Projected {
    fn new(frame: &Frame<'_>, screen: &Screen) -> Self {
        const CHUNK: usize = 4096;
        let g = &frame.geometry;
        let n = g.len();
        let mut winding = methods::parallel::filled(n, 0.0);
        let mut depth = methods::parallel::filled(n, [0.0; 2]);
        let mut corners = methods::parallel::filled(n, [DVec3::ZERO; 3]);
        let mut keys = methods::parallel::filled(n, [0u32; 3]);
        let parts: Vec<ScreenPolygons> = winding
            .par_chunks_mut(CHUNK)
            .zip(depth.par_chunks_mut(CHUNK))
            .zip(corners.par_chunks_mut(CHUNK))
            .zip(keys.par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(c, (((winding, depth), corners), keys))| {
                let mut polys = ScreenPolygons::default();
                for (k, t) in (c * CHUNK..(c + 1) * CHUNK).take(winding.len()).enumerate() {
                    let tri = g.corners(t);
                    let Some((poly, sign)) = screen.triangle(tri) else {
                        polys.push(&[]);
                        continue;
                    };
                    polys.push(poly.points());
                    winding[k] = sign;
                    let d = tri.map(|p| screen.depth(p));
                    depth[k] = [d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2])];
                    corners[k] = tri;
                    keys[k] = tri.map(corner_key);
                }
                polys
            })
            .collect();
        Projected { polys: ScreenPolygons::concat(&parts), winding, depth, corners, keys }
    }

    fn points(&self, k: usize) -> &[Pt] {
        self.polys.contour(k)
    }

    fn poly(&self, k: usize) -> Poly {
        Poly::from_slice(self.points(k))
    }
}

/// No contour (of [`Projected`]).
const NO_CONTOUR: u32 = u32::MAX;

/// One triangle overlapping a pixel: the triangle (its contour in [`Projected`]) and the
/// overlap's area.
#[derive(Clone, Copy)]
struct Overlap {
    contour: u32,
    area: f64,
}

/// Classifies every pixel of `frame` (see the module documentation for the rule).
pub fn classify(frame: &Frame<'_>) -> Classes {
    let screen = Screen::new(frame);
    let (width, height) = (frame.width() as usize, frame.height() as usize);
    let projected = Projected::new(frame, &screen);
    let planar: Vec<bool> = frame.scene.objects.iter().map(|o| o.mesh.plane().is_some()).collect();
    let (binned, items) =
        methods::bands::bin_by_band(frame.geometry.len(), height, clip::BAND, |k| {
            let (lo, hi) = clip::range(projected.points(k), 1);
            clip::overlapped_rows(lo, hi, height)
        });
    let ctx = Context { frame, screen: &screen, projected: &projected, planar: &planar };
    // Each band writes its pixels' classes and tile counts in place (the counts at
    // `offsets[k + 1]`, summed into offsets below); its tiles and edge overlaps are joined
    // after, in parallel.
    let n = width * height;
    let rows = (clip::BAND * width).max(1);
    let mut class = methods::parallel::filled(n, PixelClass::Uncovered);
    let mut offsets = methods::parallel::filled(n + 1, 0u32);
    let results: Vec<Band> = class
        .par_chunks_mut(rows)
        .zip(offsets[1..].par_chunks_mut(rows))
        .enumerate()
        .map(|(band, (class, counts))| {
            let count = class.len();
            let r0 = band * clip::BAND;
            let r1 = r0 + count / width;
            let mut entries: Vec<(u32, Overlap)> = Vec::new();
            // How many overlaps each pixel has, at `starts[local + 1]`.
            let mut starts = vec![0u32; count + 1];
            // The first contour covering each pixel wholly (area exactly 1), kept apart from
            // the entries: on bunny-plane 315,077 of 866,761 overlaps, most of them the
            // ground's, whose pixels need no grouping.
            let mut whole = vec![NO_CONTOUR; count];
            let (mut poly, mut bufs) = (Poly::new(), clip::PixelBufs::new());
            for &k in &items[binned[band]..binned[band + 1]] {
                poly.assign_points(projected.points(k as usize));
                // Every overlap is kept, however small: the rule counts those above
                // `MIN_OVERLAP`, the edge pixels' rays may meet any.
                clip::for_each_pixel_in(&poly, r0, r1, width, &mut bufs, |i, j, area| {
                    let local = (j - r0) * width + i;
                    if area == 1.0 && whole[local] == NO_CONTOUR {
                        whole[local] = k;
                    } else {
                        starts[local + 1] += 1;
                        entries.push((local as u32, Overlap { contour: k, area }));
                    }
                });
            }
            // The overlaps grouped by pixel (a counting sort): the band's contours come in
            // ascending order, so each pixel's stay in contour order.
            for p in 0..count {
                starts[p + 1] += starts[p];
            }
            let mut fill = starts.clone();
            let mut by_pixel = vec![Overlap { contour: 0, area: 0.0 }; entries.len()];
            for &(local, o) in &entries {
                by_pixel[fill[local as usize] as usize] = o;
                fill[local as usize] += 1;
            }
            drop(entries);
            let mut tiles = Vec::new();
            let mut group: Vec<Overlap> = Vec::new();
            let mut scratch = Scratch::default();
            let (mut overlaps, mut edge_overlaps) = (0, Vec::new());
            let mut merged: Vec<Overlap> = Vec::new();
            for local in 0..count {
                let mut all = &by_pixel[starts[local] as usize..starts[local + 1] as usize];
                if whole[local] != NO_CONTOUR {
                    // The whole cover among the others, in contour order.
                    let full = Overlap { contour: whole[local], area: 1.0 };
                    let at = all.partition_point(|o| o.contour < full.contour);
                    merged.clear();
                    merged.extend_from_slice(&all[..at]);
                    merged.push(full);
                    merged.extend_from_slice(&all[at..]);
                    all = &merged;
                }
                group.clear();
                group.extend(all.iter().filter(|o| o.area > MIN_OVERLAP));
                if group.is_empty() {
                    continue;
                }
                overlaps += group.len() as u64;
                let (i, j) = (local % width, r0 + local / width);
                let before = tiles.len();
                class[local] = ctx.classify_pixel(i, j, &group, &mut scratch, &mut tiles);
                counts[local] = (tiles.len() - before) as u32;
                if class[local] == PixelClass::Edge {
                    let k = (j * width + i) as u32;
                    edge_overlaps.extend(all.iter().map(|o| (k, o.contour)));
                }
            }
            Band { tiles, overlaps, edge_overlaps }
        })
        .collect();
    // Each band's counts summed into offsets, from the tiles of the bands before it.
    let mut first = Vec::with_capacity(results.len());
    let mut end = 0u32;
    for band in &results {
        first.push(end);
        end += band.tiles.len() as u32;
    }
    offsets[1..].par_chunks_mut(rows).zip(first).for_each(|(counts, mut end)| {
        for c in counts {
            end += *c;
            *c = end;
        }
    });
    let tiles: Vec<&[u32]> = results.iter().map(|b| &b.tiles[..]).collect();
    let edge_overlaps: Vec<&[(u32, u32)]> = results.iter().map(|b| &b.edge_overlaps[..]).collect();
    Classes {
        width: width as u32,
        height: height as u32,
        class,
        offsets,
        tiles: methods::parallel::concat(&tiles),
        overlaps: results.iter().map(|b| b.overlaps).sum(),
        edge_overlaps: methods::parallel::concat(&edge_overlaps),
        screen: projected.polys,
    }
}

/// Buffers the per-pixel rule reuses from pixel to pixel.
#[derive(Default)]
struct Scratch {
    /// Bit sets over a pixel's triangles, `words` bits apiece (see
    /// [`Context::classify_pixel`]).
    open: Vec<u64>,
    in_c: Vec<u64>,
    adjacent: Vec<u64>,
    stack: Vec<usize>,
    members: Vec<usize>,
}

/// One band of rows' result, beside the classes and tile counts it writes in place.
struct Band {
    /// The tiles, pixel after pixel.
    tiles: Vec<u32>,
    /// Pixel-triangle overlaps measured (above [`MIN_OVERLAP`]).
    overlaps: u64,
    /// `(pixel, triangle)` for every triangle overlapping one of the band's `edge` pixels.
    edge_overlaps: Vec<(u32, u32)>,
}

/// What the per-pixel rule reads.
struct Context<'a> {
    frame: &'a Frame<'a>,
    screen: &'a Screen,
    projected: &'a Projected,
    planar: &'a [bool],
}

impl Context<'_> {
    /// Classifies pixel `(i, j)` from the triangles overlapping it (`group`, in triangle
    /// order); appends its tiling triangles to `tiles` when it is `planar` or `surface`.
    fn classify_pixel(
        &self,
        i: usize,
        j: usize,
        group: &[Overlap],
        scratch: &mut Scratch,
        tiles: &mut Vec<u32>,
    ) -> PixelClass {
        let g = &self.frame.geometry;
        let p = self.projected;
        let k = j * self.frame.width() as usize + i;
        let seed_tri = self.frame.gbuffer.triangle[k];
        if seed_tri == NO_TRIANGLE {
            return PixelClass::Edge;
        }
        let tri = |o: &Overlap| o.contour as usize;
        let Some(seed) = group.iter().position(|o| tri(o) == seed_tri as usize) else {
            return PixelClass::Edge;
        };
        let object = g.object[seed_tri as usize];
        let class =
            if self.planar[object as usize] { PixelClass::Planar } else { PixelClass::Surface };
        // One triangle in the square, the seed: rules 3 to 5 reduce to rule 4's coverage.
        if group.len() == 1 {
            if group[0].area < MIN_TILE_COVERAGE {
                return PixelClass::Edge;
            }
            tiles.push(seed_tri);
            return class;
        }
        let winding = p.winding[group[seed].contour as usize];
        let Scratch { open, in_c, adjacent, stack, members } = scratch;
        let n = group.len();
        let corners = |f: usize| &p.corners[group[f].contour as usize];
        let keys = |f: usize| &p.keys[group[f].contour as usize];
        let normal = |f: usize| {
            let c = corners(f);
            (c[1] - c[0]).cross(c[2] - c[0])
        };
        let mut rays = None;
        // Rule 3: the continuous surface through the seed, found by a flood from it. A
        // triangle of the square may join when it has the seed's object and winding. Each
        // pair of a member and such a triangle is tested once, when the first of the two
        // leaves the stack; `open` holds those not yet off the stack, and a shared edge the
        // two run in opposite directions is kept in `adjacent` (a row of `words` bits per
        // triangle) for rule 4's pairs. The triangles' sets are bits (`words` per set),
        // visited in increasing order as a loop over the triangles with a `bool` each visited
        // them: the stage took 12 % less time on `bunny-plane` and 11 % on `cage` (800 x 600,
        // one pinned thread, 6 alternating runs).
        let words = n.div_ceil(64);
        let (word, bit) = (|f: usize| f / 64, |f: usize| 1u64 << (f % 64));
        open.clear();
        open.resize(words, 0);
        for (f, o) in group.iter().enumerate() {
            if g.object[tri(o)] == object && p.winding[o.contour as usize] == winding {
                open[word(f)] |= bit(f);
            }
        }
        adjacent.clear();
        adjacent.resize(n * words, 0);
        in_c.clear();
        in_c.resize(words, 0);
        in_c[word(seed)] |= bit(seed);
        stack.clear();
        stack.push(seed);
        while let Some(m) = stack.pop() {
            open[word(m)] &= !bit(m);
            for w in 0..words {
                let mut candidates = open[w];
                while candidates != 0 {
                    let f = 64 * w + candidates.trailing_zeros() as usize;
                    candidates &= candidates - 1;
                    let edge = if may_share_edge(keys(m), keys(f)) {
                        shared_edge(corners(m), corners(f))
                    } else {
                        SharedEdge::None
                    };
                    if edge != SharedEdge::None {
                        // Only a reversed edge puts the two on its two sides (rule 4).
                        if edge == SharedEdge::Reversed {
                            adjacent[m * words + word(f)] |= bit(f);
                            adjacent[f * words + word(m)] |= bit(m);
                        }
                        if in_c[w] & bit(f) == 0 {
                            in_c[w] |= bit(f);
                            stack.push(f);
                        }
                    }
                }
            }
        }
        members.clear();
        for (w, &set) in in_c.iter().enumerate() {
            let mut set = set;
            while set != 0 {
                members.push(64 * w + set.trailing_zeros() as usize);
                set &= set - 1;
            }
        }
        // Rule 4: C tiles the square (its areas added in the triangles' order).
        let covered: f64 = members.iter().map(|&f| group[f].area).sum();
        if covered < MIN_TILE_COVERAGE {
            return PixelClass::Edge;
        }
        let points = |f: usize| p.points(group[f].contour as usize);
        let overlap = |a: usize, b: usize| -> Option<Poly> {
            if clip::separated(points(a), points(b)) {
                return None;
            }
            let r = clip::intersect(
                &clip::clip_to_pixel(&p.poly(group[a].contour as usize), i, j),
                &p.poly(group[b].contour as usize),
            );
            (r.n >= 3).then_some(r)
        };
        for (x, &a) in members.iter().enumerate() {
            for &b in &members[x + 1..] {
                if adjacent[a * words + b / 64] >> (b % 64) & 1 == 1 {
                    continue;
                }
                if let Some(r) = overlap(a, b) {
                    if 0.5 * r.area2_rel(i as f64, j as f64) > MAX_TILE_OVERLAP {
                        return PixelClass::Edge;
                    }
                }
            }
        }
        // Rule 5: nothing else in front of C. A triangle whose nearest corner is no nearer
        // than the farthest corner of `t` is behind `t` wherever both are seen (a point's
        // depth along a camera ray is its camera depth, and a triangle's points lie between
        // its corners' depths), so it needs no overlap; one no nearer than the farthest
        // corner of all of C (on `bunny-plane`, the far side of the bunny) is behind each. A
        // NaN depth decides nothing here, as in the comparison tile by tile.
        let depth = |f: usize| p.depth[group[f].contour as usize];
        let far = members.iter().map(|&t| depth(t)[1]).fold(f64::NEG_INFINITY, |far, d| {
            if d.is_nan() {
                f64::INFINITY
            } else {
                far.max(d)
            }
        });
        let nearer = |f: usize| depth(f)[0] < far || depth(f)[0].is_nan();
        for u in (0..n).filter(|&f| in_c[word(f)] & bit(f) == 0 && nearer(f)) {
            for &t in members.iter() {
                if depth(u)[0] >= depth(t)[1]
                    || behind_on_square(
                        (normal(u), corners(u)[0]),
                        (normal(t), corners(t)[0]),
                        rays.get_or_insert_with(|| self.screen.corner_rays(i, j)),
                    )
                {
                    continue;
                }
                let Some(r) = overlap(u, t) else { continue };
                if 0.5 * r.area2_rel(i as f64, j as f64) <= MIN_OVERLAP {
                    continue;
                }
                if r.points().iter().any(|&x| self.in_front(corners(u), corners(t), x)) {
                    return PixelClass::Edge;
                }
            }
        }
        tiles.extend(members.iter().map(|&m| tri(&group[m]) as u32));
        class
    }

    /// Whether the plane of triangle `u` is nearer to the camera than that of `t` along the
    /// camera ray through screen point `x` (beyond the tolerance of rule 5).
    fn in_front(&self, u: &[DVec3; 3], t: &[DVec3; 3], x: [f64; 2]) -> bool {
        let ray = self.screen.ray(x);
        let depth = |c: &[DVec3; 3]| plane_depth(&ray, (c[1] - c[0]).cross(c[2] - c[0]), c[0]);
        let (du, dt) = (depth(u), depth(t));
        if !(du.is_finite() && dt.is_finite()) {
            return false;
        }
        let o = self.screen.origin();
        let magnitude = u.iter().chain(t).map(|&c| (c - o).abs().max_element()).fold(0.0, f64::max);
        du < dt - DEPTH_TOLERANCE * magnitude
    }
}

/// Whether the plane of triangle `u` (normal and a corner) is nowhere nearer to the camera
/// than that of `t` over the square of a pixel, decided along the camera rays through its four
/// corners (`rays`) without tolerance: where both planes lie in front of the camera, the sign
/// of `depth_u - depth_t` is that of `1 / depth_t - 1 / depth_u`, an affine function of the
/// screen point, so the corners of the square decide for the whole square and for every
/// overlap inside it. `u` then passes rule 5 against `t` (a point where `u` is at least as far
/// as `t` is not in front beyond any tolerance) without the overlap being clipped. `false`
/// means the overlap decides.
fn behind_on_square(u: (DVec3, DVec3), t: (DVec3, DVec3), rays: &[Ray; 4]) -> bool {
    let ((nu, cu), (nt, ct)) = (u, t);
    rays.iter().all(|ray| {
        let (du, dt) = (plane_depth(ray, nu, cu), plane_depth(ray, nt, ct));
        dt > 0.0 && dt.is_finite() && du.is_finite() && du >= dt
    })
}

/// How two triangles meet: along an edge (two corners at equal positions) that their corners'
/// orders run in opposite directions, as in a consistently wound mesh, or in the same one
/// (also a triangle repeated), or not along an edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SharedEdge {
    Reversed,
    Same,
    None,
}

/// A hash of a corner's position: equal positions (`==`, so `-0.0` and `0.0` alike) have equal
/// keys.
fn corner_key(p: DVec3) -> u32 {
    // Adding 0.0 turns -0.0 into 0.0 and leaves every other number as it is.
    let [x, y, z] = p.to_array().map(|v| (v + 0.0).to_bits());
    let mixed = (x ^ y.rotate_left(21) ^ z.rotate_left(42)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    (mixed >> 32) as u32
}

/// Whether triangles with corner keys `a` and `b` ([`corner_key`]) may share an edge: two of
/// `a`'s keys are among `b`'s. `false` proves they do not.
#[inline]
fn may_share_edge(a: &[u32; 3], b: &[u32; 3]) -> bool {
    a.iter().filter(|k| b.contains(k)).count() >= 2
}

/// How triangles `a` and `b` meet ([`SharedEdge`]).
#[inline]
fn shared_edge(a: &[DVec3; 3], b: &[DVec3; 3]) -> SharedEdge {
    let at = |p: &DVec3| b.iter().position(|q| q == p);
    let found = [at(&a[0]), at(&a[1]), at(&a[2])];
    for k in 0..3 {
        if let (Some(i), Some(j)) = (found[k], found[(k + 1) % 3]) {
            // `a` runs from `b[i]` to `b[j]`; `b` runs back from `b[j]` to `b[i]` when `i`
            // follows `j`.
            return if i == (j + 1) % 3 { SharedEdge::Reversed } else { SharedEdge::Same };
        }
    }
    SharedEdge::None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The keys never hide a shared edge: on triangles drawn from a few positions (signed
    /// zeros among them), every pair [`shared_edge`] finds meeting along an edge passes
    /// [`may_share_edge`], and pairs without a common position mostly do not.
    #[test]
    fn keys_never_hide_a_shared_edge() {
        let points = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(-0.0, 0.0, -0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(1.0, 1.0, 1e-300),
            DVec3::new(1e6, -1e-6, 3.0),
            DVec3::new(f64::NAN, 0.0, 0.0),
        ];
        let n = points.len();
        let tri = |k: usize| [points[k % n], points[k / n % n], points[k / (n * n) % n]];
        let (mut met, mut apart) = (0, 0);
        for a in (0..n * n * n).map(tri) {
            for b in (0..n * n * n).map(tri) {
                let keys = (a.map(corner_key), b.map(corner_key));
                if shared_edge(&a, &b) != SharedEdge::None {
                    met += 1;
                    assert!(may_share_edge(&keys.0, &keys.1), "{a:?} {b:?}");
                } else if !may_share_edge(&keys.0, &keys.1) {
                    apart += 1;
                }
            }
        }
        assert!(met > 1000 && apart > 10_000, "{met} {apart}");
        assert_eq!(corner_key(points[0]), corner_key(points[1]), "signed zeros");
    }
}
