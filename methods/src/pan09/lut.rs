//! The precomputed lookup table of section 3.4 ("similar to \[ED07\], we precompute a lookup
//! table which takes a half-plane as input and returns a bit pattern corresponding to the
//! covered view samples").
//!
//! # Quantization
//!
//! A screen half-plane `g0 + gx ux + gy uy >= 0` (pixel-local, [`HalfPlane`]) is scaled by
//! `m = max(|gx|, |gy|)`: its normal `(gx, gy) / m` lies on the boundary of the square
//! `[-1, 1]^2` and its offset `r = g0 / m` in `[-1, 1]` whenever the line meets the pixel
//! square (other half-planes never reach the table, see [`HalfPlane::crossing`]). The normal
//! is indexed by its position along the square's boundary, [`SIDE_BINS`] equal bins per side
//! ([`DIRECTION_BINS`] in all; no trigonometry), the offset by [`DISTANCE_BINS`] equal bins
//! over `[-1, 1]` with `r = 0` on a bin boundary. Each entry holds the samples covered by the
//! half-plane of its bins' centres.
//!
//! # The flip bound
//!
//! Within a bin the normal's free coordinate moves by at most `1 / SIDE_BINS` and the offset
//! by at most `1 / DISTANCE_BINS`; samples lie within `1/2` of the centre per axis, so the
//! scaled value at a sample moves by at most [`FLIP_BOUND`] `= 0.5 / SIDE_BINS +
//! 1 / DISTANCE_BINS` (`= 1/128` pixel at the defaults), and since the scaled normal has length
//! at least 1 that is also a bound in pixels: **a sub-sample farther than `FLIP_BOUND` pixels
//! from a half-plane's line always gets its exact side**. The centre sample is exact: the
//! offset bins never straddle `r = 0`. The table has `DIRECTION_BINS x DISTANCE_BINS = 131072`
//! entries of the rate's mask width (512 KB at 32 bits, 2 MB at 128). In practice the table
//! flips between 1e-4 (`plane-square`) and 4e-3 (`random-10k`, many edges per pixel) of the
//! silhouette pixels' sub-samples (see the module documentation of [`super`]).

use super::mask::Mask;
use super::screen::HalfPlane;
use crate::pattern::SamplePattern;
use glam::DVec2;
use rayon::prelude::*;

/// Direction bins per side of the square of normals.
pub const SIDE_BINS: usize = 128;
/// Direction bins in all.
pub const DIRECTION_BINS: usize = 4 * SIDE_BINS;
/// Offset bins over `[-1, 1]` (even, so that `r = 0` is a bin boundary).
pub const DISTANCE_BINS: usize = 256;
/// The largest distance, in pixels, at which a sub-sample can get the wrong side of a
/// half-plane from the table (see the module documentation).
pub const FLIP_BOUND: f64 = 0.5 / SIDE_BINS as f64 + 1.0 / DISTANCE_BINS as f64;

/// The scaled normal at boundary parameter `tau` in `[0, 8)`: right side `(1, tau - 1)`,
/// then top, left and bottom, counter-clockwise.
fn normal_at(tau: f64) -> DVec2 {
    if tau < 2.0 {
        DVec2::new(1.0, tau - 1.0)
    } else if tau < 4.0 {
        DVec2::new(3.0 - tau, 1.0)
    } else if tau < 6.0 {
        DVec2::new(-1.0, 5.0 - tau)
    } else {
        DVec2::new(tau - 7.0, -1.0)
    }
}

/// The table's index of a half-plane whose line meets the pixel square.
#[inline(always)]
pub fn index(h: &HalfPlane) -> usize {
    let (ax, ay) = (h.gx.abs(), h.gy.abs());
    let m = ax.max(ay);
    let inv = 1.0 / m;
    let (dx, dy) = (h.gx * inv, h.gy * inv);
    let tau = if ax >= ay {
        if h.gx > 0.0 {
            1.0 + dy
        } else {
            5.0 - dy
        }
    } else if h.gy > 0.0 {
        3.0 - dx
    } else {
        7.0 + dx
    };
    let a = ((tau * (DIRECTION_BINS as f64 / 8.0)) as usize) % DIRECTION_BINS;
    let r = h.g0 * inv;
    let half = DISTANCE_BINS / 2;
    let scale = half as f64;
    // Signs are exact: negative offsets land below `half`, others at or above it.
    let b = if r < 0.0 {
        half - 1 - ((-r * scale) as usize).min(half - 1)
    } else {
        half + ((r * scale) as usize).min(half - 1)
    };
    a * DISTANCE_BINS + b
}

/// Occlusion bitmasks of every quantized half-plane for one sample pattern.
#[derive(Debug, Clone, PartialEq)]
pub struct LookupTable<M> {
    masks: Vec<M>,
}

impl<M: Mask> LookupTable<M> {
    /// The table of `pattern` (whose rate must fit `M`).
    pub fn new(pattern: &SamplePattern) -> Self {
        let us: Vec<DVec2> = pattern.offsets().iter().map(|o| *o - DVec2::splat(0.5)).collect();
        let masks = (0..DIRECTION_BINS * DISTANCE_BINS)
            .into_par_iter()
            .with_min_len(DISTANCE_BINS)
            .map(|i| {
                let (a, b) = (i / DISTANCE_BINS, i % DISTANCE_BINS);
                let d = normal_at((a as f64 + 0.5) * 8.0 / DIRECTION_BINS as f64);
                let r = (b as f64 + 0.5) * 2.0 / DISTANCE_BINS as f64 - 1.0;
                us.iter()
                    .enumerate()
                    .filter(|(_, u)| d.dot(**u) + r >= 0.0)
                    .fold(M::ZERO, |m, (s, _)| m | M::bit(s))
            })
            .collect();
        Self { masks }
    }

    /// Every entry, in [`index`] order (uploaded as is by the GPU path).
    #[cfg(feature = "gpu")]
    pub(crate) fn masks(&self) -> &[M] {
        &self.masks
    }

    /// The samples covered by a half-plane whose line meets the pixel square.
    #[inline(always)]
    pub fn lookup(&self, h: &HalfPlane) -> M {
        self.masks[index(h)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::PatternKind;
    use proptest::prelude::*;

    #[test]
    fn boundary_parameter_round_trips_through_the_index() {
        for a in 0..DIRECTION_BINS {
            let d = normal_at((a as f64 + 0.5) * 8.0 / DIRECTION_BINS as f64);
            assert!((d.x.abs().max(d.y.abs()) - 1.0).abs() < 1e-15);
            let h = HalfPlane { g0: 0.0, gx: 3.0 * d.x, gy: 3.0 * d.y };
            assert_eq!(index(&h) / DISTANCE_BINS, a);
        }
    }

    proptest! {
        /// Every sample farther than FLIP_BOUND from the line gets its exact side, and the
        /// centre sample is always exact.
        #[test]
        fn flips_stay_within_the_bound(
            rate_i in 0usize..7,
            rotated in any::<bool>(),
            angle in 0.0f64..std::f64::consts::TAU,
            len in 0.01f64..100.0,
            offset in -0.75f64..0.75,
        ) {
            let rate = [1u32, 4, 8, 16, 32, 64, 128][rate_i];
            let kind = if rotated { PatternKind::Rotated } else { PatternKind::Grid };
            let pattern = SamplePattern::new(rate, kind).expect("valid");
            let table = LookupTable::<u128>::new(&pattern);
            let n = DVec2::new(angle.cos(), angle.sin());
            let h = HalfPlane { g0: offset * len, gx: n.x * len, gy: n.y * len };
            prop_assume!(h.crossing() == crate::pan09::screen::Crossing::Split);
            let m = table.lookup(&h);
            for (s, o) in pattern.offsets().iter().enumerate() {
                let u = *o - DVec2::splat(0.5);
                let dist = h.at(u) / len;
                let bit = m >> s & 1 == 1;
                if dist.abs() > FLIP_BOUND || s == pattern.centre_index() {
                    prop_assert_eq!(bit, dist >= 0.0, "sample {} at distance {}", s, dist);
                }
            }
        }
    }
}
