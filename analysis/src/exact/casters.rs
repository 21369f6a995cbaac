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
//! both for every caster it returns. The boxes of the casters are binned into a uniform grid
//! over the receivers' region, about one cell per caster; a caster spanning many cells (a ground plane) and, under a spot light, a
//! caster reaching behind the light's plane are kept in a list every receiver scans.
//! Receivers reaching behind the spot's plane scan every caster. The test is conservative: it
//! only skips casters whose shadow cannot fall on the receiver.

use glam::DVec3;
use methods::Frame;
use scenes::{projection::look_basis, Light};

/// Largest number of cells of the grid.
const MAX_CELLS: usize = 1 << 22;

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

    /// Light-space box `[x0, y0, x1, y1]` and depth span `[near, far]` of a triangle; `None`
    /// when, under a spot light, the triangle reaches the light's plane or behind it (its
    /// image is unbounded).
    fn bounds(&self, tri: &[DVec3; 3]) -> Option<([f64; 4], [f64; 2])> {
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
pub(crate) struct CasterGrid {
    space: Space,
    /// Lower corner of the grid.
    origin: [f64; 2],
    /// Upper corner of the grid.
    end: [f64; 2],
    /// Cells per unit along x and y.
    scale: [f64; 2],
    /// Cells along x and y.
    cells: [usize; 2],
    /// CSR: cell `c`'s casters are `items[offsets[c]..offsets[c + 1]]`.
    offsets: Vec<u32>,
    items: Vec<u32>,
    /// Casters every receiver scans.
    global: Vec<u32>,
    /// Nearest light-space depth of every caster (`-inf` for those in `global`).
    near: Vec<f64>,
    /// Light-space box of every caster (unbounded for those without a bounded image).
    boxes: Vec<[f64; 4]>,
    /// Every caster, for receivers without bounded light-space image.
    all: Vec<u32>,
}

impl CasterGrid {
    /// The grid over the casters of `frame` (`is_caster` triangles), covering the light-space
    /// boxes of the triangles `receivers`.
    pub fn new(frame: &Frame<'_>, receivers: &[u32]) -> Self {
        let space = Space::new(&frame.scene.light);
        let g = &frame.geometry;
        let mut region = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
        for &r in receivers {
            if let Some((b, _)) = space.bounds(&g.corners(r as usize)) {
                region = [
                    region[0].min(b[0]),
                    region[1].min(b[1]),
                    region[2].max(b[2]),
                    region[3].max(b[3]),
                ];
            }
        }
        let all: Vec<u32> = (0..g.len() as u32).filter(|&t| frame.is_caster(t as usize)).collect();
        let boxes: Vec<Option<([f64; 4], [f64; 2])>> =
            all.iter().map(|&t| space.bounds(&g.corners(t as usize))).collect();
        let mut near = vec![f64::NEG_INFINITY; g.len()];
        let (ex, ey) = (region[2] - region[0], region[3] - region[1]);
        let valid = ex.is_finite() && ey.is_finite() && ex >= 0.0 && ey >= 0.0;
        let target = all.len().clamp(1, MAX_CELLS) as f64;
        let (nx, ny) = if !valid {
            (1, 1)
        } else if ex <= 0.0 || ey <= 0.0 {
            // A degenerate region (a receiver seen edge-on by the light): one row of cells.
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
        };
        let scale = [
            if ex > 0.0 { nx as f64 / ex } else { 0.0 },
            if ey > 0.0 { ny as f64 / ey } else { 0.0 },
        ];
        let mut grid = Self {
            space,
            origin: [region[0], region[1]],
            end: [region[2], region[3]],
            scale,
            cells: [nx, ny],
            offsets: vec![0; nx * ny + 1],
            items: Vec::new(),
            global: Vec::new(),
            near: Vec::new(),
            boxes: Vec::new(),
            all: Vec::new(),
        };
        let unbounded = [f64::NEG_INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::INFINITY];
        let mut caster_boxes = vec![unbounded; g.len()];
        let max_span = MAX_SPAN.max(nx * ny / 16);
        let mut spans = Vec::with_capacity(all.len());
        for (&t, b) in all.iter().zip(&boxes) {
            let span = match b {
                None => Some(None),
                Some((b, z)) => {
                    near[t as usize] = z[0];
                    caster_boxes[t as usize] = *b;
                    if !valid {
                        Some(None)
                    } else {
                        grid.cell_range(b).map(|r| {
                            let n = (r[2] - r[0] + 1) * (r[3] - r[1] + 1);
                            (n <= max_span).then_some(r)
                        })
                    }
                }
            };
            match span {
                // Outside the receivers' region: it shadows no receiver.
                None => {}
                Some(None) => grid.global.push(t),
                Some(Some(r)) => {
                    for y in r[1]..=r[3] {
                        for x in r[0]..=r[2] {
                            grid.offsets[y * nx + x + 1] += 1;
                        }
                    }
                }
            }
            spans.push(span);
        }
        for c in 0..nx * ny {
            grid.offsets[c + 1] += grid.offsets[c];
        }
        let mut fill: Vec<u32> = grid.offsets.clone();
        grid.items = vec![0; grid.offsets[nx * ny] as usize];
        for (&t, span) in all.iter().zip(&spans) {
            if let Some(Some(r)) = span {
                for y in r[1]..=r[3] {
                    for x in r[0]..=r[2] {
                        let c = y * nx + x;
                        grid.items[fill[c] as usize] = t;
                        fill[c] += 1;
                    }
                }
            }
        }
        grid.near = near;
        grid.boxes = caster_boxes;
        grid.all = all;
        grid
    }

    /// The cells `[x0, y0, x1, y1]` (inclusive) a light-space box overlaps; `None` when it
    /// misses the grid's region.
    fn cell_range(&self, b: &[f64; 4]) -> Option<[usize; 4]> {
        let (lo, hi) = (self.origin, self.end);
        if b[2] < lo[0] || b[0] > hi[0] || b[3] < lo[1] || b[1] > hi[1] {
            return None;
        }
        let cell = |v: f64, axis: usize| -> usize {
            let n = self.cells[axis];
            ((v - lo[axis]) * self.scale[axis]).floor().clamp(0.0, (n - 1) as f64) as usize
        };
        Some([cell(b[0], 0), cell(b[1], 1), cell(b[2], 0), cell(b[3], 1)])
    }

    /// The casters that can shadow receiver triangle `tri`, sorted, without duplicates, into
    /// `out` (cleared first).
    pub fn query(&self, tri: &[DVec3; 3], out: &mut Vec<u32>) {
        out.clear();
        let Some((b, z)) = self.space.bounds(tri) else {
            out.extend_from_slice(&self.all);
            return;
        };
        let far = z[1];
        // The boxes must overlap; both are within a few roundings of the true boxes, so they
        // are compared with a margin of that size.
        let reach = |c: u32| {
            let cb = &self.boxes[c as usize];
            let magnitude = b.iter().chain(cb).map(|v| v.abs()).filter(|v| v.is_finite());
            let m = 8.0 * f64::EPSILON * magnitude.fold(1.0, f64::max);
            self.near[c as usize] <= far
                && cb[0] <= b[2] + m
                && b[0] <= cb[2] + m
                && cb[1] <= b[3] + m
                && b[1] <= cb[3] + m
        };
        out.extend(self.global.iter().copied().filter(|&c| reach(c)));
        if let Some(r) = self.cell_range(&b) {
            let nx = self.cells[0];
            for y in r[1]..=r[3] {
                for x in r[0]..=r[2] {
                    let c = y * nx + x;
                    let cell = &self.items[self.offsets[c] as usize..self.offsets[c + 1] as usize];
                    out.extend(cell.iter().copied().filter(|&c| reach(c)));
                }
            }
        }
        out.sort_unstable();
        out.dedup();
    }
}
