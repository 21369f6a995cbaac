//! A light-space grid over the caster triangles, so that each receiver triangle looks only at
//! the casters that can reach it.
//!
//! A caster can shadow a point `p` only where it meets the segment from `p` to the light. In
//! light space (directional light: coordinates across the light direction and depth along
//! it; spot light: central projection from the light onto the plane one unit along its aim,
//! and distance from the light) that segment is one point of the image with depths up to
//! `p`'s. So a caster matters to a receiver triangle only if the boxes of their light-space
//! images overlap (compared with a margin of a few roundings of their coordinates) and the
//! caster's nearest depth is not beyond the receiver's farthest; [`CasterGrid::query`] checks
//! both for every caster it returns. Two finer tests follow, once per caster: under a
//! directional light the caster's image must meet the receiver's (a separating edge line
//! with a margin of the coordinates' rounding, see `images_separated`), and some corner of
//! the receiver must lie beyond the caster's plane as the light sees it ([`LitSide`]: a point
//! on the lit side of a caster's plane, or within the rounding of it, as a shared corner is,
//! cannot be shadowed by it). On `bumpy` they cut the pairs projected from 3.16 million to
//! 71,531 (and the non-empty shadow polygons from 1.01 million to 71,531), with the same image
//! bit for bit. The boxes of the casters are binned into a uniform grid over the receivers'
//! region, about one cell per caster; a caster spanning many cells (a ground plane) and, under
//! a spot light, a caster reaching behind the light's plane are kept in a list every receiver
//! scans. Boxes are clamped to the grid's cells, casters' and queries' alike: clamping is
//! monotone, so two overlapping boxes keep a cell in common even outside the region (a
//! caster beyond it, within a cell of it, is listed in the border cells; a query for a point
//! outside it, as the rays of `exact`'s edge pixels make, scans the border cell it clamps
//! to). A caster farther out is kept apart, on a grid of its own made when a query first
//! reaches that far (on `bumpy`, the heightfield beyond the receivers' region, listed in the
//! border cells, made the cells of the receivers there crowded; on `bunny-plane`, the edge
//! pixels' points on the ground far from the bunny, scanning those casters one by one, took
//! 6.5 ms of tracing instead of 3.1).
//! Receivers reaching behind the spot's plane scan every caster. The test is conservative: it
//! only skips casters whose shadow cannot fall on the receiver.

use glam::DVec3;
use methods::Frame;
use rayon::prelude::*;
use scenes::{projection::look_basis, Geometry, Light};
use std::sync::OnceLock;

mod winding;

/// Largest number of cells of the grid.
const MAX_CELLS: usize = 1 << 22;

/// The span of a caster in [`CasterGrid`]'s `global`, which every receiver scans: one
/// without a bounded image, or whose box covers more cells than the most a caster is listed in
/// ([`MAX_SPAN`], or a sixteenth of the grid).
const GLOBAL: [u32; 4] = [u32::MAX; 4];

/// The span of a caster in [`CasterGrid`]'s `outside`: more than a cell beyond the region.
const OUTER: [u32; 4] = [u32::MAX - 1; 4];

// A cell's coordinate is below `MAX_CELLS`, so no span of cells reads as `GLOBAL` or `OUTER`.
const _: () = assert!(MAX_CELLS < OUTER[0] as usize);

/// Bands of cell rows the cells' lists are filled by, in parallel.
const BANDS: usize = 64;

/// A caster spanning more cells than this (and more than the grid's cells / 16) goes to the
/// list every receiver scans.
const MAX_SPAN: usize = 64;

/// Light space of a frame's light.
#[derive(Debug, Clone, Copy)]
enum Space {
    /// Orthographic along `forward` (the direction light travels).
    Directional { right: DVec3, up: DVec3, forward: DVec3 },
    /// Central from `pos`, onto the plane at unit distance along `forward`.
    Spot { pos: DVec3, right: DVec3, up: DVec3, forward: DVec3 },
}

impl Space {
    fn new(light: &Light) -> Self {
        match *light {
            Light::Directional { direction } => {
                let (right, up, forward) = look_basis(direction, DVec3::Y);
                Self::Directional { right, up, forward }
            }
            Light::Spot { position, target, .. } => {
                let aim =
                    scenes::projection::direction_between(position, target).unwrap_or(DVec3::NEG_Y);
                let (right, up, forward) = look_basis(aim, DVec3::Y);
                Self::Spot { pos: position, right, up, forward }
            }
        }
    }

    /// The light-space image of a triangle's corners under a directional light (`x, y`
    /// across the light direction); unused for spot lights.
    fn image(&self, tri: &[DVec3; 3]) -> [[f64; 2]; 3] {
        match *self {
            Self::Directional { right, up, .. } => tri.map(|p| [p.dot(right), p.dot(up)]),
            Self::Spot { .. } => [[0.0; 2]; 3],
        }
    }

    /// Light-space box `[x0, y0, x1, y1]` and depth span `[near, far]` of a set of points (a
    /// triangle's corners); `None` when, under a spot light, a point lies on the light's plane
    /// or behind it (the image is unbounded).
    fn bounds(&self, tri: &[DVec3]) -> Option<([f64; 4], [f64; 2])> {
        let mut b = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
        let mut z = [f64::INFINITY, f64::NEG_INFINITY];
        for &p in tri {
            let (x, y, depth) = match *self {
                Self::Directional { right, up, forward } => {
                    (p.dot(right), p.dot(up), p.dot(forward))
                }
                Self::Spot { pos, right, up, forward } => {
                    let v = p - pos;
                    let w = v.dot(forward);
                    // At or behind the light's plane (or NaN): no bounded image.
                    if w.is_nan() || w <= 0.0 {
                        return None;
                    }
                    (v.dot(right) / w, v.dot(up) / w, v.length())
                }
            };
            if !(x.is_finite() && y.is_finite() && depth.is_finite()) {
                return None;
            }
            b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
            z = [z[0].min(depth), z[1].max(depth)];
        }
        Some((b, z))
    }
}

/// The grid.
#[derive(Debug, Clone)]
pub(crate) struct CasterGrid<'a> {
    /// The frame's triangles (the casters' planes are taken from their corners when asked).
    geometry: &'a Geometry,
    /// The frame's light.
    light: &'a Light,
    space: Space,
    /// The cells over the receivers' region.
    grid: Cells,
    /// Upper corner of the region.
    end: [f64; 2],
    /// Casters every receiver scans.
    global: Vec<u32>,
    /// Casters more than a cell beyond the region, which only queries reaching there scan,
    /// and their grid, made when the first such query comes (`bumpy`'s 149,703 are never
    /// asked for).
    outside: Vec<u32>,
    outer: OnceLock<Outer>,
    /// Nearest light-space depth of every caster (`-inf` for those without a bounded image, and
    /// for triangles that cast no shadow).
    near: Vec<f64>,
    /// Light-space box of every caster (unbounded for those without a bounded image).
    boxes: Vec<[f64; 4]>,
    /// Largest magnitude of every caster's light-space box coordinates (0 for unbounded ones).
    magnitude: Vec<f64>,
    /// Directional lights: the light-space image of every caster (its corners' `x, y`).
    images: Vec<[[f64; 2]; 3]>,
    /// Every caster, for receivers without bounded light-space image.
    all: Vec<u32>,
}

impl<'a> CasterGrid<'a> {
    /// The grid over the casters of `frame` (`is_caster` triangles), covering the light-space
    /// boxes of the triangles `receivers`.
    ///
    /// Everything is made in parallel straight into its place: every triangle's box, nearest
    /// depth, magnitude and image in one pass over its corners (on `bumpy`, 530,688 triangles,
    /// the build touches over 100 MB of fresh memory, whose page faults were most of its time),
    /// and the cells' lists by bands of cell rows ([`BANDS`]): the casters are binned to the
    /// bands their boxes reach, then each band counts and fills its own cells, whose lists are
    /// one contiguous run, in caster order, as one pass over every caster would. A caster's
    /// plane ([`LitSide`]) is taken from its corners when a query asks, which is only for the
    /// casters whose image meets the receiver's.
    pub fn new(frame: &'a Frame<'a>, receivers: &[u32]) -> Self {
        let space = Space::new(&frame.scene.light);
        let g = &frame.geometry;
        // Minima and maxima: the same region in any order of reduction.
        let region = receivers
            .par_iter()
            .filter_map(|&r| space.bounds(&g.corners(r as usize)).map(|(b, _)| b))
            .reduce(|| EMPTY_BOX, join_boxes);
        let all: Vec<u32> =
            (0..g.len() as u32).into_par_iter().filter(|&t| frame.is_caster(t as usize)).collect();
        let PerTriangle { boxes, near, magnitude, images } = PerTriangle::new(frame, &space);
        let (ex, ey) = (region[2] - region[0], region[3] - region[1]);
        let valid = ex.is_finite() && ey.is_finite() && ex >= 0.0 && ey >= 0.0;
        let (nx, ny) = if valid { dims(ex, ey, all.len()) } else { (1, 1) };
        let scale = scales([ex, ey], [nx, ny]);
        let mut grid = Self {
            geometry: g,
            light: &frame.scene.light,
            space,
            grid: Cells {
                origin: [region[0], region[1]],
                scale,
                cells: [nx, ny],
                offsets: Vec::new(),
                items: Vec::new(),
                firsts: Vec::new(),
            },
            end: [region[2], region[3]],
            global: Vec::new(),
            outside: Vec::new(),
            outer: OnceLock::new(),
            near,
            boxes,
            magnitude,
            images,
            all: Vec::new(),
        };
        let max_span = MAX_SPAN.max(nx * ny / 16);
        // Where caster `t` goes: the cells it is listed in, `[x0, y0, x1, y1]` (below
        // `MAX_CELLS`, so `u32`), or `GLOBAL` or `OUTER`. 16 bytes a caster, where an
        // `Option<Option<[usize; 4]>>` took 40 (21 MB on bumpy, written and read twice).
        let span = |t: u32| -> [u32; 4] {
            if !valid || grid.near[t as usize] == f64::NEG_INFINITY {
                return GLOBAL;
            }
            let b = &grid.boxes[t as usize];
            if !grid.near_region(b, grid.magnitude[t as usize]) {
                return OUTER;
            }
            let r = grid.grid.range(b);
            let n = (r[2] - r[0] + 1) * (r[3] - r[1] + 1);
            if n <= max_span {
                r.map(|v| v as u32)
            } else {
                GLOBAL
            }
        };
        let spans: Vec<[u32; 4]> = all.par_iter().map(|&t| span(t)).collect();
        // In the order of `all` (rayon's collect keeps it).
        let pick = |kind: [u32; 4]| -> Vec<u32> {
            all.par_iter().zip(&spans).filter(|(_, s)| **s == kind).map(|(&t, _)| t).collect()
        };
        let global = pick(GLOBAL);
        let outside = pick(OUTER);
        let listed = |k: usize| {
            let s = spans[k];
            (s[0] < OUTER[0]).then(|| s.map(|v| v as usize))
        };
        let (offsets, items, firsts) = fill_cells(&all, listed, [nx, ny]);
        (grid.grid.offsets, grid.grid.items, grid.grid.firsts) = (offsets, items, firsts);
        (grid.global, grid.outside, grid.all) = (global, outside, all);
        grid
    }

    /// The grid's region widened by a cell and by `margin` on every side.
    fn widened(&self, margin: f64) -> [f64; 4] {
        let (lo, hi) = (self.grid.origin, self.end);
        let cell = |axis: usize| {
            if self.grid.scale[axis] > 0.0 {
                1.0 / self.grid.scale[axis]
            } else {
                0.0
            }
        };
        let (cx, cy) = (cell(0) + margin, cell(1) + margin);
        [lo[0] - cx, lo[1] - cy, hi[0] + cx, hi[1] + cy]
    }

    /// Whether caster box `b` (of coordinate magnitude `magnitude`) reaches the grid's region
    /// widened by a cell and by 64 roundings of both magnitudes: a query box within the region
    /// widened by a cell (its magnitude at most three times the region's) then compares with
    /// a margin smaller than the gap to any caster that does not.
    fn near_region(&self, b: &[f64; 4], magnitude: f64) -> bool {
        let region = self.grid.origin.iter().chain(&self.end).map(|v| v.abs()).fold(0.0, f64::max);
        let w = self.widened(64.0 * f64::EPSILON * (magnitude + region));
        b[2] >= w[0] && b[0] <= w[2] && b[3] >= w[1] && b[1] <= w[3]
    }

    /// Whether the query box `b` lies within the grid's region widened by a cell.
    fn within_reach(&self, b: &[f64; 4]) -> bool {
        let w = self.widened(0.0);
        b[0] >= w[0] && b[1] >= w[1] && b[2] <= w[2] && b[3] <= w[3]
    }

    /// The grid cell `[x, y]` holding the centre of triangle `t`'s light-space box (the
    /// first cell for a triangle that casts no shadow or has no bounded light-space image).
    pub fn cell_of(&self, t: u32) -> [usize; 2] {
        let b = &self.boxes[t as usize];
        let (x, y) = (0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3]));
        let r = self.grid.range(&[x, y, x, y]);
        [r[0], r[1]]
    }

    /// A key that orders triangles by where their light-space boxes lie: the Z order (Morton
    /// code, the low 16 bits of each coordinate interleaved) of [`Self::cell_of`] in the high
    /// 32 bits and `t` in the low 32, so that keys are distinct and sort by cell, then by
    /// triangle.
    pub fn order_key(&self, t: u32) -> u64 {
        let [x, y] = self.cell_of(t);
        // `as u32` keeps the low 32 bits, of which the code reads the low 16.
        (u64::from(scenes::morton::code(x as u32, y as u32)) << 32) | u64::from(t)
    }

    /// The casters that can shadow receiver triangle `tri`, sorted, without duplicates, into
    /// `found.casters` (cleared first).
    pub fn query(&self, tri: &[DVec3; 3], found: &mut Candidates) {
        self.query_part(tri, None, found);
    }

    /// [`Self::query`] for the part of triangle `tri` inside the convex hull of `part`
    /// (points of its plane, e.g. where a pixel's corner rays meet it): the casters that can
    /// shadow a point of `tri` within `part`. The light-space box is that of both, the depths
    /// the nearer of their farthest, and the lit-side test asks `part`'s points.
    pub fn query_part(&self, tri: &[DVec3; 3], part: Option<&[DVec3; 4]>, found: &mut Candidates) {
        let out = &mut found.casters;
        out.clear();
        let Some((mut b, z)) = self.space.bounds(tri) else {
            out.extend_from_slice(&self.all);
            return;
        };
        let mut far = z[1];
        if let Some((pb, pz)) = part.and_then(|p| self.space.bounds(p)) {
            b = [b[0].max(pb[0]), b[1].max(pb[1]), b[2].min(pb[2]), b[3].min(pb[3])];
            far = far.min(pz[1]);
        }
        let own = b.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let reach = |c: u32| self.near[c as usize] <= far && self.boxes_meet(c, &b, own);
        self.scan(&b, &reach, out);
        // Then, once per caster: the receiver must reach beyond the caster's lit side, and under
        // a directional light the images must overlap (see `images_separated`).
        let image = (!self.images.is_empty()).then(|| self.space.image(tri));
        let tri_magnitude = corner_magnitude(tri);
        let lit_points: &[DVec3] = part.map_or(tri, |p| p);
        let lit_magnitude = match part {
            Some(p) => p.iter().map(|p| p.abs().max_element()).fold(tri_magnitude, f64::max),
            None => tri_magnitude,
        };
        // The image test first: it rules out most candidates (the receiver's neighbours in
        // its mesh) before their planes are made.
        out.retain(|&c| {
            !image.is_some_and(|r| self.images_apart(c, &b, own, &r))
                && !LitSide::new(&self.geometry.corners(c as usize), self.light)
                    .holds(lit_points, lit_magnitude)
        });
        out.sort_unstable();
    }

    /// Appends to `out` every caster `c` whose listing the light-space box `b` reaches with
    /// `keep(c)`, each once: those every query scans, those beyond the region when `b` reaches
    /// there, then those of the cells `b` covers ([`Cells::scan`]).
    #[inline]
    fn scan(&self, b: &[f64; 4], keep: &impl Fn(u32) -> bool, out: &mut Vec<u32>) {
        out.extend(self.global.iter().copied().filter(|&c| keep(c)));
        // A box within a cell of the region reaches no caster of `outer` (see
        // `near_region`).
        if !self.within_reach(b) && !self.outside.is_empty() {
            let o = self.outer.get_or_init(|| Outer::new(&self.outside, &self.boxes));
            out.extend(o.wide.iter().copied().filter(|&c| keep(c)));
            o.grid.scan(b, keep, out);
        }
        self.grid.scan(b, keep, out);
    }

    /// The margin to which caster `c`'s box and a query box `b` of coordinate magnitude
    /// `own` are compared: both are within a few roundings of the true boxes.
    #[inline]
    fn margin(&self, c: u32, own: f64) -> f64 {
        8.0 * f64::EPSILON * own.max(self.magnitude[c as usize])
    }

    /// Whether caster `c`'s light-space box meets the box `b` (of coordinate magnitude
    /// `own`), within [`Self::margin`].
    #[inline]
    fn boxes_meet(&self, c: u32, b: &[f64; 4], own: f64) -> bool {
        let cb = &self.boxes[c as usize];
        let m = self.margin(c, own);
        cb[0] <= b[2] + m && b[0] <= cb[2] + m && cb[1] <= b[3] + m && b[1] <= cb[3] + m
    }

    /// Under a directional light: whether caster `c`'s image is apart from `image`, whose
    /// box is `b` (of coordinate magnitude `own`), beyond the rounding of both
    /// ([`images_separated`]).
    #[inline]
    fn images_apart(&self, c: u32, b: &[f64; 4], own: f64, image: &[[f64; 2]; 3]) -> bool {
        let cb = &self.boxes[c as usize];
        images_separated(image, &self.images[c as usize], self.margin(c, own), joint_extent(cb, b))
    }
}

/// A receiver facing away from the light, as both proofs of its own object's shadow take it
/// ([`CasterGrid::behind_own_facing`], [`CasterGrid::behind_own_winding`]).
struct Away {
    /// Its corners.
    tri: [DVec3; 3],
    /// Its light-space box and depth span ([`Space::bounds`]).
    b: [f64; 4],
    z: [f64; 2],
    /// Its object.
    object: u32,
    /// The largest magnitude of its box's coordinates, and of its corners' coordinates.
    own: f64,
    magnitude: f64,
}

/// Largest coordinate magnitude of a triangle's corners.
fn corner_magnitude(c: &[DVec3; 3]) -> f64 {
    c.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max)
}

/// The larger side of the box holding the light-space boxes `a` and `b` (`[x0, y0, x1, y1]`):
/// a bound on every coordinate difference between points of the two.
fn joint_extent(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    (a[2].max(b[2]) - a[0].min(b[0])).max(a[3].max(b[3]) - a[1].min(b[1]))
}

impl CasterGrid<'_> {
    /// Receiver `r` when it faces away from the light beyond the rounding of its normal and
    /// has a bounded light-space image.
    fn away(&self, r: u32) -> Option<Away> {
        let tri = self.geometry.corners(r as usize);
        if LitSide::new(&tri, self.light).facing != Facing::Away {
            return None;
        }
        let (b, z) = self.space.bounds(&tri)?;
        let object = self.geometry.object[r as usize];
        let own = b.iter().map(|v| v.abs()).fold(0.0, f64::max);
        Some(Away { tri, b, z, object, own, magnitude: corner_magnitude(&tri) })
    }

    /// Whether receiver `r` faces away from the light (beyond the rounding of its normal)
    /// and every other triangle of its object that may face the light lies nearer the light
    /// than `r` on every light ray through both: wholly nearer in light-space depth, or with
    /// `r` on the dark side of its plane ([`LitSide::behind`]). Triangles facing away from
    /// the light are not asked; one whose facing the rounding cannot tell answers `false`.
    /// On a closed object this puts `r` in the object's shadow ([`super::closed`]).
    ///
    /// The triangles asked are those whose light-space boxes meet `r`'s (with the margin of
    /// [`Self::query`]) at any depth, less, under a directional light, those whose images
    /// are apart from `r`'s (`images_separated`): what shares no light ray with `r` does not
    /// matter. A triangle of the object that casts no shadow is not in the grid, so the
    /// object must cast shadows (the caller's check).
    pub fn behind_own_facing(&self, r: u32) -> bool {
        let g = self.geometry;
        let Some(Away { tri, b, z, object, own, magnitude: tri_magnitude }) = self.away(r) else {
            return false;
        };
        let light_magnitude = match *self.light {
            Light::Directional { .. } => 0.0,
            Light::Spot { position, .. } => position.abs().max_element(),
        };
        let image = (!self.images.is_empty()).then(|| self.space.image(&tri));
        // Whether every triangle asked so far lies nearer the light; `ask` records it for
        // triangle `c` and takes nothing into a scan's list.
        let fine = std::cell::Cell::new(true);
        let ask = |c: u32| -> bool {
            if !fine.get() || c == r || g.object[c as usize] != object {
                return false;
            }
            if !self.boxes_meet(c, &b, own)
                || image.as_ref().is_some_and(|image| self.images_apart(c, &b, own, image))
            {
                return false;
            }
            let corners = g.corners(c as usize);
            let side = LitSide::new(&corners, self.light);
            let nearer = || {
                // Depths are coordinates along the light (directional) or distances from it
                // (spot) of points of magnitude up to that of the corners and the light, each
                // within 16 roundings of that magnitude.
                self.space.bounds(&corners).is_some_and(|(_, cz)| {
                    let scale = tri_magnitude.max(side.magnitude) + light_magnitude;
                    cz[1] < z[0] - 32.0 * f64::EPSILON * scale
                })
            };
            let ok = match side.facing {
                Facing::Away => true,
                Facing::Unsure => false,
                Facing::Toward => nearer() || side.behind(&tri, tri_magnitude),
            };
            fine.set(ok);
            false
        };
        self.scan(&b, &ask, &mut Vec::new());
        fine.get()
    }
}

/// The casters beyond a cell of a grid's region, on a grid of their own over their boxes'
/// extent (about one cell per caster, boxes clamped as in the main grid); a caster spanning
/// more than [`MAX_SPAN`] of its cells is in `wide`, which every query reaching there scans.
#[derive(Debug, Clone, Default)]
struct Outer {
    grid: Cells,
    wide: Vec<u32>,
}

impl Outer {
    /// The grid of the casters `outside`, whose light-space boxes are in `boxes`.
    fn new(outside: &[u32], boxes: &[[f64; 4]]) -> Self {
        // Minima and maxima: the same region in any order of reduction.
        let region =
            outside.par_iter().map(|&t| boxes[t as usize]).reduce(|| EMPTY_BOX, join_boxes);
        let (ex, ey) = (region[2] - region[0], region[3] - region[1]);
        if outside.is_empty() || !(ex.is_finite() && ey.is_finite()) {
            return Self { wide: outside.to_vec(), ..Self::default() };
        }
        let cells = dims(ex, ey, outside.len());
        let (origin, scale) = ([region[0], region[1]], scales([ex, ey], [cells.0, cells.1]));
        let cells = [cells.0, cells.1];
        let spans: Vec<Option<[usize; 4]>> = outside
            .par_iter()
            .map(|&t| {
                let r = Cells::clamped(origin, scale, cells, &boxes[t as usize]);
                ((r[2] - r[0] + 1) * (r[3] - r[1] + 1) <= MAX_SPAN).then_some(r)
            })
            .collect();
        let wide =
            outside.iter().zip(&spans).filter(|(_, s)| s.is_none()).map(|(&t, _)| t).collect();
        let (offsets, items, firsts) = fill_cells(outside, |k| spans[k], cells);
        Self { grid: Cells { origin, scale, cells, offsets, items, firsts }, wide }
    }
}

/// The light-space box `[x0, y0, x1, y1]` that holds nothing.
const EMPTY_BOX: [f64; 4] = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];

/// The smallest box holding the light-space boxes `a` and `b`.
fn join_boxes(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [a[0].min(b[0]), a[1].min(b[1]), a[2].max(b[2]), a[3].max(b[3])]
}

/// Cells along x and y for about `count` cells over a region `ex` by `ey` (one row when it
/// is degenerate: a receiver seen edge-on by the light).
fn dims(ex: f64, ey: f64, count: usize) -> (usize, usize) {
    let target = count.clamp(1, MAX_CELLS) as f64;
    if ex <= 0.0 || ey <= 0.0 {
        let n = target as usize;
        if ex > 0.0 {
            (n, 1)
        } else if ey > 0.0 {
            (1, n)
        } else {
            (1, 1)
        }
    } else {
        let nx = (target * ex / ey).sqrt().ceil().clamp(1.0, target);
        let ny = (target / nx).ceil().clamp(1.0, target);
        (nx as usize, ny as usize)
    }
}

/// Cells per unit along x and y of `cells` over extents `e` (0 along a degenerate one).
fn scales(e: [f64; 2], cells: [usize; 2]) -> [f64; 2] {
    [0, 1].map(|k| if e[k] > 0.0 { cells[k] as f64 / e[k] } else { 0.0 })
}

/// A uniform grid of cells over a light-space region, each listing casters.
#[derive(Debug, Clone, Default)]
struct Cells {
    /// Lower corner of the region.
    origin: [f64; 2],
    /// Cells per unit along x and y.
    scale: [f64; 2],
    /// Cells along x and y.
    cells: [usize; 2],
    /// CSR: cell `c`'s casters are `items[offsets[c]..offsets[c + 1]]`.
    offsets: Vec<u32>,
    items: Vec<u32>,
    /// For each listing in `items`, whether its cell is the first column ([`FIRST_COLUMN`])
    /// and the first row ([`FIRST_ROW`]) of the cells its caster is listed in.
    firsts: Vec<u8>,
}

impl Cells {
    /// The cells `[x0, y0, x1, y1]` (inclusive) of a grid (`origin`, `scale`, `cells`) the box
    /// `b` overlaps, the box clamped to the grid (clamping is monotone, so two overlapping
    /// boxes keep a cell in common).
    fn clamped(origin: [f64; 2], scale: [f64; 2], cells: [usize; 2], b: &[f64; 4]) -> [usize; 4] {
        let cell = |v: f64, axis: usize| -> usize {
            let n = cells[axis];
            ((v - origin[axis]) * scale[axis]).floor().clamp(0.0, (n - 1) as f64) as usize
        };
        [cell(b[0], 0), cell(b[1], 1), cell(b[2], 0), cell(b[3], 1)]
    }

    /// [`Self::clamped`] on this grid.
    fn range(&self, b: &[f64; 4]) -> [usize; 4] {
        Self::clamped(self.origin, self.scale, self.cells, b)
    }

    /// Appends to `out` the casters `c` of the cells the box `b` covers with `keep(c)`, each
    /// once: a caster listed in several of them is taken in the first column and the first
    /// row the box's cells and its own have in common, the one cell where each of those is
    /// the first column or row of the box's cells or of its own (its listing's
    /// [`Cells::firsts`]). The listings carry that, so no caster's data is read for the
    /// repeats (a bunny receiver's cells list about 134 casters, 20 of them distinct), and a
    /// query marks nothing that the next one would have to clear.
    fn scan(&self, b: &[f64; 4], keep: &impl Fn(u32) -> bool, out: &mut Vec<u32>) {
        if self.items.is_empty() || !(b[0] <= b[2] && b[1] <= b[3]) {
            return;
        }
        let r = self.range(b);
        for y in r[1]..=r[3] {
            // The listings that must be their caster's first column (row) to be taken here.
            let row = if y == r[1] { 0 } else { FIRST_ROW };
            for x in r[0]..=r[2] {
                let wanted = row | if x == r[0] { 0 } else { FIRST_COLUMN };
                let c = y * self.cells[0] + x;
                let span = self.offsets[c] as usize..self.offsets[c + 1] as usize;
                let listings = self.items[span.clone()].iter().zip(&self.firsts[span]);
                out.extend(
                    listings
                        .filter(|&(&c, &firsts)| firsts & wanted == wanted && keep(c))
                        .map(|(&c, _)| c),
                );
            }
        }
    }
}

/// [`Cells::firsts`]: the listing's cell is the first column of its caster's cells.
const FIRST_COLUMN: u8 = 1;

/// [`Cells::firsts`]: the listing's cell is the first row of its caster's cells.
const FIRST_ROW: u8 = 2;

/// What a grid query reuses from call to call: the list of the casters it found.
#[derive(Debug, Default)]
pub(crate) struct Candidates {
    /// The casters found by the last query, sorted.
    pub casters: Vec<u32>,
}

/// A caster's plane, oriented so that the light is on its positive side: a point strictly on
/// that side cannot be shadowed by the caster (the segment from it to the light stays on that
/// side and never meets the plane).
#[derive(Debug, Clone, Copy)]
struct LitSide {
    /// Unit normal towards the light (NaN where the light is in the plane or the triangle has
    /// no normal: such a caster is never ruled out this way).
    n: DVec3,
    /// A corner of the caster.
    corner: DVec3,
    /// Largest corner coordinate magnitude.
    magnitude: f64,
    /// `|e1| |e2| / |e1 × e2|` (at least 1): how much the rounding of the edges turns the
    /// normal of a sliver.
    skew: f64,
    /// Which way the normal its corners' order gives the triangle points, beyond the
    /// rounding of that normal.
    facing: Facing,
}

/// Which way a triangle's normal (by its corners' order) points: to the light's side of its
/// plane, away from it, or too close to the plane for its rounding to tell (a triangle seen
/// edge-on by the light, or without a normal).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Facing {
    Toward,
    Away,
    Unsure,
}

impl LitSide {
    /// The lit side of triangle `c`'s plane.
    ///
    /// Its facing: the unit normal is within `8 ε skew` of the true one (the edges are
    /// exact differences of the corners within `ε` of their length, their cross product
    /// within `4 ε |e1| |e2|`), so its cosine with the unit direction to the light is
    /// within `16 ε skew` of the true cosine (for a spot light, plus the rounding of the
    /// direction from the corner to the light, `ε (|light| + |corner|) / |light - corner|`
    /// relative); a cosine within twice that of 0 is [`Facing::Unsure`].
    fn new(c: &[DVec3; 3], light: &Light) -> Self {
        let (e1, e2) = (c[1] - c[0], c[2] - c[0]);
        let cross = e1.cross(e2);
        let length = cross.length();
        let mut n = cross / length;
        let skew = e1.length() * e2.length() / length;
        let (towards, tol) = match *light {
            Light::Directional { direction } => {
                (-n.dot(direction) / direction.length(), 32.0 * f64::EPSILON * skew)
            }
            Light::Spot { position, .. } => {
                let to = position - c[0];
                let far = to.length();
                let reach = (position.abs().max_element() + c[0].abs().max_element()) / far;
                (n.dot(to) / far, 32.0 * f64::EPSILON * (skew + reach))
            }
        };
        // NaN (no normal, an infinite skew) is unsure.
        let facing = if towards > tol {
            Facing::Toward
        } else if towards < -tol {
            Facing::Away
        } else {
            Facing::Unsure
        };
        n = if towards > 0.0 {
            n
        } else if towards < 0.0 {
            -n
        } else {
            DVec3::NAN
        };
        let magnitude = corner_magnitude(c);
        Self { n, corner: c[0], magnitude, skew, facing }
    }

    /// The rounding bound of a height `n·(p - corner)` for points of magnitude up to
    /// `magnitude` (see [`Self::holds`]).
    fn tolerance(&self, magnitude: f64) -> f64 {
        64.0 * f64::EPSILON * self.magnitude.max(magnitude) * self.skew
    }

    /// Whether every corner of `tri` (of largest coordinate magnitude `magnitude`) lies on
    /// the light's side of the plane or within the rounding of it, so that the caster casts
    /// no shadow on it. A corner on the plane (a corner the two triangles share) has an exact
    /// height of 0, which its computed height meets within the rounding bound: `n` is within
    /// a few roundings times [`Self::skew`] of the true unit normal, so a height
    /// `n·(p - corner)` is within `64 ε M skew` of the true one (`M` the larger magnitude of
    /// both triangles' coordinates, which bounds `|p - corner|` by `2 √3 M`).
    fn holds(&self, tri: &[DVec3], magnitude: f64) -> bool {
        let tol = self.tolerance(magnitude);
        // NaN (no lit side, or an infinite skew) never holds.
        tri.iter().all(|&p| self.n.dot(p - self.corner) >= -tol)
    }

    /// Whether every corner of `tri` (of largest coordinate magnitude `magnitude`) lies on
    /// the dark side of the plane or within the rounding of it ([`Self::holds`]'s bound), so
    /// that the segment from any point of `tri` to the light meets the plane, if at all,
    /// nearer the light than that point.
    fn behind(&self, tri: &[DVec3], magnitude: f64) -> bool {
        let tol = self.tolerance(magnitude);
        // NaN never holds.
        tri.iter().all(|&p| self.n.dot(p - self.corner) <= tol)
    }
}

/// The grid's per-triangle arrays (see [`CasterGrid`]'s fields of the same names).
struct PerTriangle {
    boxes: Vec<[f64; 4]>,
    near: Vec<f64>,
    magnitude: Vec<f64>,
    images: Vec<[[f64; 2]; 3]>,
}

impl PerTriangle {
    /// Every triangle's light-space box, nearest depth and the largest magnitude of its box's
    /// coordinates, and under a directional light its image, in one parallel pass over its
    /// corners: the box and depth of its image for a caster with a bounded one; unbounded,
    /// `-inf` and 0 otherwise (a caster without a bounded image goes to the list every
    /// receiver scans, the other triangles are never listed).
    fn new(frame: &Frame<'_>, space: &Space) -> Self {
        const CHUNK: usize = 1 << 12;
        let g = &frame.geometry;
        let n = g.len();
        let directional = matches!(space, Space::Directional { .. });
        let mut boxes = methods::parallel::filled(n, [0.0; 4]);
        let mut near = methods::parallel::filled(n, 0.0);
        let mut magnitude = methods::parallel::filled(n, 0.0);
        let mut images = methods::parallel::filled(if directional { n } else { 0 }, [[0.0; 2]; 3]);
        let image_chunks: Vec<Option<&mut [[[f64; 2]; 3]]>> = if directional {
            images.chunks_mut(CHUNK).map(Some).collect()
        } else {
            (0..n.div_ceil(CHUNK)).map(|_| None).collect()
        };
        let unbounded = [f64::NEG_INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::INFINITY];
        boxes
            .par_chunks_mut(CHUNK)
            .zip(near.par_chunks_mut(CHUNK))
            .zip(magnitude.par_chunks_mut(CHUNK))
            .zip(image_chunks)
            .enumerate()
            .for_each(|(k, (((b, z), m), mut im))| {
                for i in 0..b.len() {
                    let t = k * CHUNK + i;
                    let corners = g.corners(t);
                    if let Some(im) = im.as_deref_mut() {
                        im[i] = space.image(&corners);
                    }
                    (b[i], z[i], m[i]) = match frame.is_caster(t).then(|| space.bounds(&corners)) {
                        Some(Some((cb, cz))) => {
                            let mag = cb.iter().map(|v| v.abs()).filter(|v| v.is_finite());
                            (cb, cz[0], mag.fold(0.0, f64::max))
                        }
                        _ => (unbounded, f64::NEG_INFINITY, 0.0),
                    };
                }
            });
        Self { boxes, near, magnitude, images }
    }
}

/// The grid's cells' lists in CSR layout (`offsets`, `items`, `firsts`) over `cells = [nx,
/// ny]`: caster `all[k]` is listed in every cell of `listed(k)` (`[x0, y0, x1, y1]`,
/// inclusive), with [`FIRST_COLUMN`] where the cell's column is `x0` and [`FIRST_ROW`] where
/// its row is `y0`, and each cell's list is in the order of `all`. The casters are binned to
/// bands of cell rows, then each band, in parallel, counts its cells' listings and fills them
/// into its own contiguous part of `items` and `firsts`.
fn fill_cells(
    all: &[u32],
    listed: impl Fn(usize) -> Option<[usize; 4]> + Sync,
    [nx, ny]: [usize; 2],
) -> (Vec<u32>, Vec<u32>, Vec<u8>) {
    let rows = ny.div_ceil(BANDS);
    let band_cells = rows * nx;
    let (band_offsets, band_items) =
        methods::bands::bin_by_band(all.len(), ny, rows, |k| listed(k).map(|r| (r[1], r[3])));
    let listed = &listed;
    let in_band = |b: usize| {
        band_items[band_offsets[b]..band_offsets[b + 1]]
            .iter()
            .filter_map(move |&k| listed(k as usize).map(|r| (k as usize, r)))
    };
    // Per band: the running count of its cells' listings (cell `c` of the band ends at
    // `ends[c]`, counted from the band's start).
    let mut offsets = methods::parallel::filled(nx * ny + 1, 0u32);
    offsets[1..].par_chunks_mut(band_cells).enumerate().for_each(|(b, ends)| {
        for (_, r) in in_band(b) {
            for (c, _) in cells_in_band(r, b, rows, nx) {
                ends[c] += 1;
            }
        }
        for c in 1..ends.len() {
            ends[c] += ends[c - 1];
        }
    });
    // Each band's first listing: the listings of the bands before it.
    let mut starts = Vec::with_capacity(BANDS);
    let mut total = 0u32;
    for ends in offsets[1..].chunks(band_cells) {
        starts.push(total);
        total += ends.last().copied().unwrap_or(0);
    }
    offsets[1..].par_chunks_mut(band_cells).zip(&starts).for_each(|(ends, &start)| {
        ends.iter_mut().for_each(|e| *e += start);
    });
    let mut items = methods::parallel::filled(total as usize, 0u32);
    let mut firsts = methods::parallel::filled(total as usize, 0u8);
    let lens = || {
        let ends = starts.iter().skip(1).copied().chain([total]);
        starts.iter().zip(ends).map(|(&start, end)| (end - start) as usize)
    };
    let parts = methods::parallel::cut(&mut items, lens());
    let parts =
        parts.into_iter().zip(methods::parallel::cut(&mut firsts, lens())).collect::<Vec<_>>();
    let offsets_ref = &offsets;
    parts.into_par_iter().zip(&starts).enumerate().for_each(
        |(b, ((part, part_firsts), &start))| {
            // The next free slot of each of the band's cells, from the band's start.
            let first = b * band_cells;
            let last = (first + band_cells).min(nx * ny);
            let mut next: Vec<u32> = offsets_ref[first..last].iter().map(|&o| o - start).collect();
            for (k, r) in in_band(b) {
                for (c, flags) in cells_in_band(r, b, rows, nx) {
                    part[next[c] as usize] = all[k];
                    part_firsts[next[c] as usize] = flags;
                    next[c] += 1;
                }
            }
        },
    );
    (offsets, items, firsts)
}

/// The cells of the cell range `r` (`[x0, y0, x1, y1]`, inclusive) in band `b` of `rows` cell
/// rows, numbered from the band's first cell, each with its [`Cells::firsts`] flags in `r`.
#[inline]
fn cells_in_band(
    r: [usize; 4],
    b: usize,
    rows: usize,
    nx: usize,
) -> impl Iterator<Item = (usize, u8)> {
    let (y0, y1) = (r[1].max(b * rows), r[3].min((b + 1) * rows - 1));
    (y0..=y1).flat_map(move |y| {
        let row = if y == r[1] { FIRST_ROW } else { 0 };
        (r[0]..=r[2]).map(move |x| {
            let column = if x == r[0] { FIRST_COLUMN } else { 0 };
            ((y - b * rows) * nx + x, row | column)
        })
    })
}

/// Whether the light-space images `a` and `b` of two triangles are apart by more than the
/// rounding of their coordinates, by a separating line through an edge of one of them.
///
/// Under a directional light, the shadow a caster casts on a receiver's plane, seen along the
/// light, is (part of) the caster's image, and the receiver is its own image: a caster whose
/// image misses the receiver's casts no shadow on it. Each coordinate is within `m` (8
/// roundings of the largest magnitude involved) of its exact value and every difference of
/// two within `extent` (the span of both boxes) of zero, so the edge function
/// `e × (v - s)` is within `4 m (|e| + extent)` of its exact value, plus its own rounding
/// (a few `f64` epsilons of `|e| extent`, far below): a vertex counts as outside only
/// beyond `8 m (|e| + extent)`. A corner of `q` equal to an end of the edge (a corner both
/// triangles share: the same point gives the same numbers) lies on the exact line and counts as
/// outside too, so neighbours in a mesh whose images only touch along a shared edge or at a
/// shared corner are apart: on `bumpy` this rules out 1.83 of its 1.90 million receiver-caster
/// pairs, whose shadows had no area. Degenerate images (an edge of zero length) give no axis.
fn images_separated(a: &[[f64; 2]; 3], b: &[[f64; 2]; 3], m: f64, extent: f64) -> bool {
    let apart = |p: &[[f64; 2]; 3], q: &[[f64; 2]; 3]| {
        // The image's orientation: its inside is on the side of its edges the third corner
        // is on.
        let (s, e, o) = (p[0], p[1], p[2]);
        let area = (e[0] - s[0]) * (o[1] - s[1]) - (e[1] - s[1]) * (o[0] - s[0]);
        let sign = if area > 0.0 {
            1.0
        } else if area < 0.0 {
            -1.0
        } else {
            return false;
        };
        (0..3).any(|k| {
            let (s, e) = (p[k], p[(k + 1) % 3]);
            let (ex, ey) = (e[0] - s[0], e[1] - s[1]);
            let tol = 8.0 * m * (ex.abs() + ey.abs() + extent);
            q.iter().all(|v| {
                *v == s || *v == e || sign * (ex * (v[1] - s[1]) - ey * (v[0] - s[0])) < -tol
            })
        })
    };
    apart(a, b) || apart(b, a)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact::clip::{self, Poly};
    use instrumentation::Recorder;

    /// The cells' lists filled by bands in parallel equal those of one pass over the casters:
    /// every cell lists its casters in their order, across bands of cell rows, with casters
    /// reaching over several bands or none, on grids narrower and taller than [`BANDS`] rows.
    #[test]
    fn cells_are_filled_as_one_pass_over_the_casters_would() {
        for [nx, ny] in [[1, 1], [7, 3], [5, 64], [13, 200], [300, 2]] {
            let all: Vec<u32> = (0..20_000u32).map(|k| 3 * k + 1).collect();
            let listed = |k: usize| {
                let (x0, y0) = ((k * 7919) % (nx + 2), (k * 104_729) % (ny + 3));
                let r = [x0, y0, (x0 + k % 3).min(nx - 1), (y0 + k % 9).min(ny - 1)];
                (x0 < nx && y0 < ny && !k.is_multiple_of(11)).then_some(r)
            };
            let (offsets, items, firsts) = fill_cells(&all, listed, [nx, ny]);
            let mut expected = vec![Vec::new(); nx * ny];
            for (k, &t) in all.iter().enumerate() {
                if let Some(r) = listed(k) {
                    for y in r[1]..=r[3] {
                        for x in r[0]..=r[2] {
                            let row = if y == r[1] { FIRST_ROW } else { 0 };
                            let column = if x == r[0] { FIRST_COLUMN } else { 0 };
                            expected[y * nx + x].push((t, row | column));
                        }
                    }
                }
            }
            assert_eq!(offsets.len(), nx * ny + 1);
            for (c, cell) in expected.iter().enumerate() {
                let span = offsets[c] as usize..offsets[c + 1] as usize;
                let got: Vec<(u32, u8)> =
                    items[span.clone()].iter().copied().zip(firsts[span].iter().copied()).collect();
                assert_eq!(got, &cell[..], "{nx} x {ny}: cell {c}");
            }
            assert_eq!(items.len(), expected.iter().map(Vec::len).sum::<usize>());
            assert_eq!(firsts.len(), items.len());
        }
    }

    /// The area of the shadow caster `c` casts on receiver `r` under a directional light
    /// along `dir`, seen along the light (computed independently of the grid's tests: the
    /// part of `c` above `r`'s plane on the light's side, imaged, intersected with `r`'s
    /// image).
    fn shadow_area(r: &[DVec3; 3], c: &[DVec3; 3], dir: DVec3) -> f64 {
        let (right, up, _) = look_basis(dir, DVec3::Y);
        let n = (r[1] - r[0]).cross(r[2] - r[0]);
        let side = -n.dot(dir).signum();
        let h = |p: DVec3| side * n.dot(p - r[0]);
        let mut above: Vec<DVec3> = Vec::new();
        for k in 0..3 {
            let (p, q) = (c[k], c[(k + 1) % 3]);
            let (hp, hq) = (h(p), h(q));
            if hp > 0.0 {
                above.push(p);
            }
            if (hp > 0.0) != (hq > 0.0) && hp != hq {
                above.push(p + (q - p) * (hp / (hp - hq)));
            }
        }
        let image = |pts: &[DVec3]| {
            let mut p = Poly::from_slice(
                &pts.iter().map(|p| [p.dot(right), p.dot(up)]).collect::<Vec<_>>(),
            );
            if p.area2_rel(0.0, 0.0) < 0.0 {
                p.reverse();
            }
            p
        };
        if above.len() < 3 {
            return 0.0;
        }
        let (a, b) = (image(&above), image(r));
        if a.area2_rel(0.0, 0.0) == 0.0 || b.area2_rel(0.0, 0.0) == 0.0 {
            return 0.0;
        }
        0.5 * clip::intersect(&a, &b).area2_rel(0.0, 0.0)
    }

    fn point() -> impl proptest::strategy::Strategy<Value = DVec3> {
        (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0).prop_map(|(x, y, z)| DVec3::new(x, y, z))
    }

    use proptest::prelude::*;

    /// A grid of `nx` x `ny` unit cells from the origin listing caster `k` in the cells of
    /// `ranges[k]` (clamped to the grid).
    fn unit_cells(nx: usize, ny: usize, ranges: &[[usize; 4]]) -> Cells {
        let clamp = |r: &[usize; 4]| {
            let (x0, y0) = (r[0].min(nx - 1), r[1].min(ny - 1));
            [x0, y0, r[2].clamp(x0, nx - 1), r[3].clamp(y0, ny - 1)]
        };
        let all: Vec<u32> = (0..ranges.len() as u32).collect();
        let (offsets, items, firsts) = fill_cells(&all, |k| Some(clamp(&ranges[k])), [nx, ny]);
        Cells { origin: [0.0; 2], scale: [1.0; 2], cells: [nx, ny], offsets, items, firsts }
    }

    proptest! {
        /// A scan takes every caster listed in the cells its box covers exactly once, and only
        /// those that `keep` keeps, whatever the casters' cells and the box.
        #[test]
        fn a_scan_takes_each_caster_of_its_cells_once(
            nx in 1usize..12,
            ny in 1usize..12,
            ranges in proptest::collection::vec([0usize..14, 0..14, 0..14, 0..14], 0..60),
            query in [-2.0f64..14.0, -2.0..14.0, 0.0..8.0, 0.0..8.0],
            odd in any::<bool>(),
        ) {
            let cells = unit_cells(nx, ny, &ranges);
            let b = [query[0], query[1], query[0] + query[2], query[1] + query[3]];
            let keep = |c: u32| odd || c.is_multiple_of(2);
            let mut got = Vec::new();
            cells.scan(&b, &keep, &mut got);
            let r = cells.range(&b);
            let mut want: Vec<u32> = (r[1]..=r[3])
                .flat_map(|y| (r[0]..=r[2]).map(move |x| y * nx + x))
                .flat_map(|c| {
                    cells.items[cells.offsets[c] as usize..cells.offsets[c + 1] as usize].to_vec()
                })
                .filter(|&c| keep(c))
                .collect();
            want.sort_unstable();
            want.dedup();
            got.sort_unstable();
            prop_assert_eq!(got, want);
        }

        /// The image and lit-side tests rule out only casters whose shadow misses the
        /// receiver: random pairs, pairs sharing an edge or a corner, at scales from 1e-6 to
        /// 1e6 and far from the origin.
        #[test]
        fn ruled_out_casters_cast_no_shadow(
            r in [point(), point(), point()],
            c in [point(), point(), point()],
            share in 0usize..3,
            dir in point(),
            scale in -6i32..7,
            shift in point(),
        ) {
            prop_assume!(dir.length() > 0.1);
            let dir = dir.normalize();
            let s = 10f64.powi(scale);
            let place = |p: DVec3| p * s + shift * 1e3 * s;
            let r = r.map(place);
            let mut c = c.map(place);
            // share = 1: a corner in common; share = 2: an edge.
            c[..share].copy_from_slice(&r[..share]);
            let light = Light::Directional { direction: dir };
            let space = Space::new(&light);
            let Some((b, _)) = space.bounds(&r) else { return Err(TestCaseError::fail("no bounds")) };
            let Some((cb, _)) = space.bounds(&c) else { return Err(TestCaseError::fail("no bounds")) };
            let magnitude = b.iter().chain(&cb).map(|v| v.abs()).fold(0.0, f64::max);
            let m = 8.0 * f64::EPSILON * magnitude;
            let separated = images_separated(&space.image(&r), &space.image(&c), m, joint_extent(&cb, &b));
            let r_magnitude = corner_magnitude(&r);
            let lit = LitSide::new(&c, &light).holds(&r, r_magnitude);
            if separated || lit {
                let area = shadow_area(&r, &c, dir);
                prop_assert!(area <= 1e-9 * s * s, "{} (separated {}, lit side {})", area, separated, lit);
            }
        }
    }

    /// A query's casters do not depend on the queries made before it with the same
    /// [`Candidates`].
    #[test]
    fn a_query_does_not_depend_on_the_queries_before_it() {
        let scene = scenes::load("bumpy").expect("built-in");
        let frame = Frame::new(&scene, 80, 60, &mut Recorder::default());
        let receivers: Vec<u32> = (0..frame.geometry.len() as u32).step_by(97).collect();
        let grid = CasterGrid::new(&frame, &receivers);
        let mut shared = Candidates::default();
        let (mut found, mut queried) = (0, 0);
        for &r in &receivers {
            let tri = frame.geometry.corners(r as usize);
            let mut fresh = Candidates::default();
            grid.query(&tri, &mut fresh);
            grid.query(&tri, &mut shared);
            assert_eq!(shared.casters, fresh.casters, "receiver {r}");
            assert!(fresh.casters.windows(2).all(|w| w[0] < w[1]), "sorted, without duplicates");
            found += fresh.casters.len();
            queried += 1;
        }
        assert!(queried > 1000 && found > 100, "{queried} queries, {found} casters");
    }

    /// A grid over a corner of the scene answers queries outside its region (triangles and
    /// single points, as the edge pixels' shadow rays ask) with the casters a grid over the
    /// whole scene returns: the boxes of both are clamped to the cells.
    #[test]
    fn queries_outside_the_region_find_what_a_covering_grid_finds() {
        for name in ["bumpy", "spot-spheres"] {
            let scene = scenes::load(name).expect("built-in");
            let frame = Frame::new(&scene, 80, 60, &mut Recorder::default());
            let g = &frame.geometry;
            let n = g.len() as u32;
            let corner: Vec<u32> = (0..n / 50).collect();
            let all: Vec<u32> = (0..n).collect();
            let (small, whole) = (CasterGrid::new(&frame, &corner), CasterGrid::new(&frame, &all));
            let (mut a, mut b) = (Candidates::default(), Candidates::default());
            let mut found = 0;
            for t in (n / 2..n).step_by(61) {
                let tri = g.corners(t as usize);
                let point = [(tri[0] + tri[1] + tri[2]) / 3.0; 4];
                for part in [None, Some(&point)] {
                    small.query_part(&tri, part, &mut a);
                    whole.query_part(&tri, part, &mut b);
                    assert_eq!(a.casters, b.casters, "{name}: triangle {t}");
                    found += a.casters.len();
                }
            }
            assert!(found > 100, "{name}: {found} casters found");
        }
    }

    /// A scene of the one object `mesh` under `light`, seen from above.
    pub(super) fn one_object(mesh: scenes::Mesh, light: Light) -> scenes::Scene {
        let object = scenes::Object {
            name: "object".into(),
            mesh,
            material: scenes::Material::default(),
            casts_shadows: true,
        };
        scenes::Scene {
            name: "test".into(),
            width: 16,
            height: 12,
            camera: scenes::Camera::Orthographic {
                eye: DVec3::new(0.0, 10.0, 0.0),
                target: DVec3::ZERO,
                up: DVec3::NEG_Z,
                height: 8.0,
            },
            light,
            objects: vec![object],
            switches: scenes::scene::EffectSwitches::default(),
            animation: scenes::Animation::still(),
        }
    }

    /// Appends the box from `lo` to `hi`, its triangles' normals outward.
    pub(super) fn cuboid(
        lo: DVec3,
        hi: DVec3,
        positions: &mut Vec<DVec3>,
        triangles: &mut Vec<[u32; 3]>,
    ) {
        // Corner k: x from bit 0, y from bit 1, z from bit 2; faces wound outward.
        const FACES: [[u32; 4]; 6] =
            [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let base = positions.len() as u32;
        positions.extend((0..8).map(|k| {
            let pick = |bit: u32, l: f64, h: f64| if k >> bit & 1 == 1 { h } else { l };
            DVec3::new(pick(0, lo.x, hi.x), pick(1, lo.y, hi.y), pick(2, lo.z, hi.z))
        }));
        for f in FACES {
            let f = f.map(|v| v + base);
            triangles.extend([[f[0], f[1], f[2]], [f[0], f[2], f[3]]]);
        }
    }

    /// Whether the segment from `p` to the light of `frame` meets a triangle of its geometry
    /// other than `own` (Möller and Trumbore's test, in `f64`, away from its ends).
    pub(super) fn blocked(frame: &Frame<'_>, own: usize, p: DVec3) -> bool {
        let (dir, reach) = match frame.scene.light {
            Light::Directional { direction } => (-direction.normalize(), f64::INFINITY),
            Light::Spot { position, .. } => ((position - p).normalize(), (position - p).length()),
        };
        let g = &frame.geometry;
        (0..g.len()).filter(|&t| t != own).any(|t| {
            let [a, b, c] = g.corners(t);
            let (e1, e2) = (b - a, c - a);
            let q = dir.cross(e2);
            let det = e1.dot(q);
            if det.abs() < 1e-14 {
                return false;
            }
            let s = p - a;
            let u = s.dot(q) / det;
            let r = s.cross(e1);
            let v = dir.dot(r) / det;
            let d = e2.dot(r) / det;
            u >= 0.0 && v >= 0.0 && u + v <= 1.0 && d > 1e-9 && d < reach - 1e-9
        })
    }

    /// Asks [`CasterGrid::behind_own_facing`] of every triangle of `frame` (one object);
    /// checks that no triangle facing the light or edge-on passes, and that points of every
    /// one that passes (its centre and points near its corners) are in shadow; returns how
    /// many faced away and how many of those passed.
    fn check_behind(frame: &Frame<'_>) -> (usize, usize) {
        let g = &frame.geometry;
        let all: Vec<u32> = (0..g.len() as u32).collect();
        let grid = CasterGrid::new(frame, &all);
        let (mut away, mut passed) = (0, 0);
        for t in 0..g.len() {
            let corners = g.corners(t);
            let facing = LitSide::new(&corners, &frame.scene.light).facing;
            let behind = grid.behind_own_facing(t as u32);
            away += usize::from(facing == Facing::Away);
            if !behind {
                continue;
            }
            assert_eq!(facing, Facing::Away, "triangle {t}");
            passed += 1;
            for w in [[1.0, 1.0, 1.0], [8.0, 1.0, 1.0], [1.0, 8.0, 1.0], [1.0, 1.0, 8.0]] {
                let p = (corners[0] * w[0] + corners[1] * w[1] + corners[2] * w[2])
                    / (w[0] + w[1] + w[2]);
                assert!(blocked(frame, t, p), "triangle {t} at {p}");
            }
        }
        (away, passed)
    }

    /// A box under an oblique light lies behind its own faces toward the light wherever it
    /// faces away; in an object of two boxes, one over the other, the upper one's bottom does
    /// not (the lower one's top faces the light farther from it), the lower one's does.
    #[test]
    fn the_far_side_of_a_closed_object_is_behind_its_near_side() {
        let direction = DVec3::new(0.3, -1.0, 0.2);
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        cuboid(DVec3::splat(-1.0), DVec3::ONE, &mut positions, &mut triangles);
        let mesh = scenes::Mesh::new(positions, triangles).expect("valid");
        let scene = one_object(mesh, Light::Directional { direction });
        let frame = Frame::new(&scene, 16, 12, &mut Recorder::default());
        assert_eq!(check_behind(&frame), (6, 6), "every face away from the light");

        let direction = DVec3::new(0.02, -1.0, 0.01);
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        cuboid(
            DVec3::new(-1.0, 0.0, -1.0),
            DVec3::new(1.0, 1.0, 1.0),
            &mut positions,
            &mut triangles,
        );
        cuboid(
            DVec3::new(-1.0, 2.0, -1.0),
            DVec3::new(1.0, 3.0, 1.0),
            &mut positions,
            &mut triangles,
        );
        let mesh = scenes::Mesh::new(positions, triangles).expect("valid");
        let scene = one_object(mesh, Light::Directional { direction });
        let frame = Frame::new(&scene, 16, 12, &mut Recorder::default());
        let all: Vec<u32> = (0..frame.geometry.len() as u32).collect();
        let grid = CasterGrid::new(&frame, &all);
        // Each box's bottom (y = lo, its third face) is its triangles 4 and 5.
        let bottom = |b: u32| [4, 5].map(|f| grid.behind_own_facing(12 * b + f));
        assert_eq!(bottom(0), [true, true], "the lower box's bottom");
        assert_eq!(bottom(1), [false, false], "the upper box's bottom, over the lower box");
        check_behind(&frame);
    }

    /// Numbers uniform in `[0, 1)` from a xorshift generator seeded with `state` (not zero).
    pub(super) fn uniform(mut state: u64) -> impl FnMut() -> f64 {
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Appends a star-shaped closed mesh around `centre`: a sphere's rings with a radius from
    /// `radius` at every corner, its triangles' normals outward, or inward when `inverted`.
    pub(super) fn star(
        centre: DVec3,
        inverted: bool,
        mut radius: impl FnMut() -> f64,
        positions: &mut Vec<DVec3>,
        triangles: &mut Vec<[u32; 3]>,
    ) {
        let (rings, segments) = (7u32, 9u32);
        let base = positions.len() as u32;
        positions.push(centre + DVec3::Y * radius());
        for i in 1..rings {
            let theta = std::f64::consts::PI * f64::from(i) / f64::from(rings);
            for j in 0..segments {
                let phi = std::f64::consts::TAU * f64::from(j) / f64::from(segments);
                let d = DVec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
                positions.push(centre + d * radius());
            }
        }
        positions.push(centre + DVec3::NEG_Y * radius());
        let ring = |i: u32, j: u32| base + 1 + (i - 1) * segments + j % segments;
        let south = positions.len() as u32 - 1;
        let mut push = |t: [u32; 3]| triangles.push(if inverted { [t[0], t[2], t[1]] } else { t });
        for j in 0..segments {
            push([base, ring(1, j + 1), ring(1, j)]);
            push([south, ring(rings - 1, j), ring(rings - 1, j + 1)]);
            for i in 1..rings - 1 {
                let (a, b) = (ring(i, j), ring(i, j + 1));
                let (c, d) = (ring(i + 1, j), ring(i + 1, j + 1));
                push([a, b, d]);
                push([a, d, c]);
            }
        }
    }

    /// Two star-shaped closed meshes ([`star`]) as one, around the origin and around `shift`,
    /// each turned inside out as `inverted` says, their radii drawn from `random` (0.6 to 1.4);
    /// and, drawn after them, a direction down toward them for the light.
    pub(super) fn two_stars(
        random: &mut impl FnMut() -> f64,
        shift: DVec3,
        inverted: [bool; 2],
    ) -> (scenes::Mesh, DVec3) {
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        let mut radii: Vec<f64> = (0..200).map(|_| 0.6 + 0.8 * random()).collect();
        let mut radius = || radii.pop().unwrap_or(1.0);
        star(DVec3::ZERO, inverted[0], &mut radius, &mut positions, &mut triangles);
        star(shift, inverted[1], &mut radius, &mut positions, &mut triangles);
        let to = DVec3::new(random() - 0.5, -1.0, random() - 0.5);
        (scenes::Mesh::new(positions, triangles).expect("valid"), to)
    }

    /// On random objects of two star-shaped closed meshes, one of them turned inside out (its
    /// side facing away from the light by its corners' order is the one the light sees), one
    /// over the other with a random shift, under directional and spot lights: every triangle
    /// the check passes is in shadow at every point tried, and the check passes more than a
    /// fifth of those facing away (626 of 2,637).
    #[test]
    fn triangles_behind_their_own_object_are_in_its_shadow() {
        let mut random = uniform(0x2545_f491_4f6c_dd1d);
        let (mut away, mut passed) = (0, 0);
        for case in 0..24 {
            let shift = DVec3::new(2.0 * random() - 1.0, 3.0, 2.0 * random() - 1.0);
            let inverted_above = case % 4 < 2;
            let (mesh, to) = two_stars(&mut random, shift, [!inverted_above, inverted_above]);
            let light = if case % 2 == 0 {
                Light::Directional { direction: to }
            } else {
                Light::Spot { position: -8.0 * to, target: DVec3::ZERO, fov_deg: 60.0 }
            };
            let scene = one_object(mesh, light);
            let frame = Frame::new(&scene, 16, 12, &mut Recorder::default());
            let (a, p) = check_behind(&frame);
            (away, passed) = (away + a, passed + p);
        }
        assert!(5 * passed > away, "{passed} of {away} facing away passed");
    }

    /// A caster whose image is apart from the receiver's, and one the receiver lies on the lit
    /// side of, are ruled out; a caster over the receiver is ruled out by neither test.
    #[test]
    fn the_tests_rule_out_what_casts_nothing() {
        let down = DVec3::new(0.1, -1.0, 0.2).normalize();
        let light = Light::Directional { direction: down };
        let space = Space::new(&light);
        let ground = [DVec3::ZERO, DVec3::X, DVec3::Z];
        let over =
            [DVec3::new(0.1, 1.0, 0.1), DVec3::new(0.3, 1.0, 0.1), DVec3::new(0.1, 1.0, 0.3)];
        let far = over.map(|p| p + DVec3::new(5.0, 0.0, 0.0));
        let sep = |a: &[DVec3; 3], b: &[DVec3; 3]| {
            images_separated(&space.image(a), &space.image(b), 1e-15, 10.0)
        };
        assert!(!sep(&ground, &over));
        assert!(sep(&ground, &far));
        // Neighbours sharing an edge or a corner, their images on the other side of it, touch
        // without overlapping (the shared corners' images are the same numbers): ruled out.
        let square = [DVec3::X, DVec3::new(1.0, 0.0, 1.0), DVec3::Z];
        assert!(sep(&ground, &square) && sep(&square, &ground));
        let corner = [DVec3::X, DVec3::new(2.0, 0.0, -0.5), DVec3::new(1.5, 0.0, -1.0)];
        assert!(sep(&ground, &corner) && sep(&corner, &ground));
        // A neighbour folded over the receiver (its image on the receiver's side of the shared
        // edge) is not, nor one sharing a corner whose image reaches into the receiver's.
        let folded = [DVec3::X, DVec3::Z, DVec3::new(0.2, 0.5, 0.2)];
        assert!(!sep(&ground, &folded));
        let reaching = [DVec3::X, DVec3::new(0.5, 0.0, 0.25), DVec3::new(1.5, 0.0, -1.0)];
        assert!(!sep(&ground, &reaching));
        assert!(!LitSide::new(&over, &light).holds(&ground, 1.0));
        // The ground lies on the lit side of a copy of itself one unit below, which therefore
        // casts nothing on it.
        let below = ground.map(|p| p - DVec3::Y);
        assert!(LitSide::new(&below, &light).holds(&ground, 1.0));
    }
}
