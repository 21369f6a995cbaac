//! The light-space grid of the irregular z-buffer (Wyman et al., I3D 2015, section 3): `res x
//! res` texels over the light's image, each holding a list (of pixels whose footprint meets
//! it, or of casters rasterized into it).
//!
//! The light image's coordinates are `afsm`'s (a [`LIGHT_IMAGE_RES`] square); the grid scales
//! them to *texel units* ([`Grid::texels`]), in which texel `(x, y)` covers the closed square
//! `[x, x + 1] x [y, y + 1]`. Every decision is made on the light image's coordinates, so the
//! grid's size changes which texels hold what, never a sample's coordinates. The texels of the
//! border also stand for everything beyond the grid on their side ([`Grid::texel_box`]), so
//! that a point outside the light image still has a texel, and both the pixels and the casters
//! reach it.
//!
//! The lists are one array of entries sorted by texel with an offset per texel
//! ([`TexelLists`]): built from `(texel, item)` keys sorted in parallel, read contiguously.

use crate::afsm::LIGHT_IMAGE_RES;
use glam::DVec2;
use rayon::prelude::*;

/// Stand-in for the unbounded side of a border texel: far beyond any light image coordinate
/// the scenes' limits allow, small enough that products with it stay finite.
const BEYOND: f64 = 1e150;

/// A `res x res` grid over the light's image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// Texels per side.
    pub res: u32,
    /// Texels per unit of light image coordinates: `res / LIGHT_IMAGE_RES`.
    scale: f64,
}

impl Grid {
    /// The grid of `res` texels a side (at least 1) over the light image.
    pub fn new(res: u32) -> Self {
        let res = res.max(1);
        Self { res, scale: f64::from(res) / f64::from(LIGHT_IMAGE_RES) }
    }

    /// Light image point `p` in texel units.
    #[inline]
    pub fn texels(&self, p: DVec2) -> DVec2 {
        p * self.scale
    }

    /// The texels `(x0, y0, x1, y1)` (inclusive, clamped to the grid) whose closed squares may
    /// meet the box `lo..=hi` (texel units), widened by a rounding margin; `None` when the box
    /// is not finite or is empty.
    #[inline]
    pub fn rect(&self, lo: DVec2, hi: DVec2) -> Option<(u32, u32, u32, u32)> {
        if !(lo.is_finite() && hi.is_finite() && lo.x <= hi.x && lo.y <= hi.y) {
            return None;
        }
        let last = f64::from(self.res - 1);
        let margin = |v: f64| 1e-9 * (1.0 + v.abs());
        // Texel x covers [x, x + 1]: it meets [lo, hi] when x <= hi and x + 1 >= lo.
        let first = |v: f64| (v - margin(v) - 1.0).ceil().clamp(0.0, last) as u32;
        let end = |v: f64| (v + margin(v)).floor().clamp(0.0, last) as u32;
        Some((first(lo.x), first(lo.y), end(hi.x), end(hi.y)))
    }

    /// Whether the box `lo..=hi` (texel units) lies within the grid `[0, res]^2`.
    #[inline]
    pub fn holds(&self, lo: DVec2, hi: DVec2) -> bool {
        let r = f64::from(self.res);
        lo.x >= 0.0 && lo.y >= 0.0 && hi.x <= r && hi.y <= r
    }

    /// The region texel `(x, y)` stands for, in light image coordinates: its closed square,
    /// extended beyond the grid on the sides where it is a border texel.
    #[inline]
    pub fn texel_box(&self, x: u32, y: u32) -> (DVec2, DVec2) {
        let last = self.res - 1;
        let at = |v: u32| f64::from(v) / self.scale;
        let lo =
            DVec2::new(if x == 0 { -BEYOND } else { at(x) }, if y == 0 { -BEYOND } else { at(y) });
        let hi = DVec2::new(
            if x == last { BEYOND } else { at(x + 1) },
            if y == last { BEYOND } else { at(y + 1) },
        );
        (lo, hi)
    }

    /// Whether light image point `p` lies in the closed region texel `t` (an index) stands
    /// for: its square in texel units, extended beyond the grid where it is a border texel.
    #[inline]
    pub fn region_holds(&self, t: usize, p: DVec2) -> bool {
        let res = self.res as usize;
        let (x, y) = ((t % res) as f64, (t / res) as f64);
        let last = f64::from(self.res - 1);
        let q = self.texels(p);
        (x == 0.0 || q.x >= x)
            && (x == last || q.x <= x + 1.0)
            && (y == 0.0 || q.y >= y)
            && (y == last || q.y <= y + 1.0)
    }

    /// The index of texel `(x, y)`.
    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.res as usize + x as usize
    }

    /// The key of `item` in texel `texel`, sorting by texel then item.
    #[inline]
    pub fn key(texel: usize, item: u32) -> u64 {
        (texel as u64) << 32 | u64::from(item)
    }
}

/// A list of items per texel.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TexelLists {
    /// `offsets[t]..offsets[t + 1]` are texel `t`'s entries.
    offsets: Vec<u32>,
    /// The items, texel after texel, each texel's in increasing order.
    items: Vec<u32>,
    /// The texels holding at least one item, in increasing order.
    texels: Vec<u32>,
}

impl TexelLists {
    /// The lists of the keys ([`Grid::key`]) of a grid of `texels` texels; the keys are sorted
    /// here. More than `u32::MAX` entries cannot be indexed: `None`.
    pub fn from_keys(texels: usize, mut keys: Vec<u64>) -> Option<Self> {
        if keys.len() >= u32::MAX as usize {
            return None;
        }
        keys.par_sort_unstable();
        let mut offsets = vec![0u32; texels + 1];
        let mut used = Vec::new();
        for &k in &keys {
            let t = (k >> 32) as usize;
            if offsets[t + 1] == 0 {
                used.push(t as u32);
            }
            offsets[t + 1] += 1;
        }
        for t in 0..texels {
            offsets[t + 1] += offsets[t];
        }
        let items = keys.par_iter().map(|&k| k as u32).collect();
        Some(Self { offsets, items, texels: used })
    }

    /// Texel `t`'s items.
    #[inline]
    pub fn of(&self, t: usize) -> &[u32] {
        &self.items[self.offsets[t] as usize..self.offsets[t + 1] as usize]
    }

    /// Whether texel `t` holds no item.
    #[inline]
    pub fn is_empty_at(&self, t: usize) -> bool {
        self.offsets[t] == self.offsets[t + 1]
    }

    /// The texels holding at least one item, in increasing order.
    pub fn texels(&self) -> &[u32] {
        &self.texels
    }

    /// Entries over all lists.
    pub fn entries(&self) -> usize {
        self.items.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_hold_their_keys_by_texel_in_item_order() {
        let keys = vec![Grid::key(3, 9), Grid::key(0, 4), Grid::key(3, 1), Grid::key(5, 2)];
        let l = TexelLists::from_keys(6, keys).expect("few keys");
        assert_eq!(l.of(3), &[1, 9]);
        assert_eq!(l.of(0), &[4]);
        assert!(l.of(1).is_empty() && l.is_empty_at(4) && !l.is_empty_at(5));
        assert_eq!(l.texels(), &[0, 3, 5]);
        assert_eq!(l.entries(), 4);
    }

    #[test]
    fn rects_clamp_to_the_grid_and_border_texels_reach_beyond() {
        let g = Grid::new(8);
        assert_eq!(g.rect(DVec2::new(2.5, 3.0), DVec2::new(4.0, 3.5)), Some((2, 2, 4, 3)));
        assert_eq!(g.rect(DVec2::new(-50.0, 9.5), DVec2::new(-40.0, 20.0)), Some((0, 7, 0, 7)));
        assert_eq!(g.rect(DVec2::new(f64::NAN, 0.0), DVec2::ONE), None);
        // 8 texels over 1024 light image units: 128 units a texel.
        assert_eq!(g.texels(DVec2::new(256.0, 64.0)), DVec2::new(2.0, 0.5));
        let (lo, hi) = g.texel_box(0, 7);
        assert!(lo.x < -1e100 && hi.y > 1e100 && hi.x == 128.0 && lo.y == 896.0);
        assert!(g.holds(DVec2::ZERO, DVec2::splat(8.0)));
        assert!(!g.holds(DVec2::ZERO, DVec2::splat(8.5)));
        assert!(g.region_holds(g.index(3, 2), DVec2::new(384.0, 383.9)));
        assert!(g.region_holds(g.index(2, 2), DVec2::new(384.0, 383.9)), "closed squares");
        assert!(!g.region_holds(g.index(4, 2), DVec2::new(384.0, 383.9)));
        assert!(g.region_holds(g.index(0, 7), DVec2::new(-1e30, 1e30)));
    }
}
