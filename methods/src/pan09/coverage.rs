//! The two ways a screen half-plane becomes a mask of covered sub-samples: the paper's
//! lookup table ([`TableCoverage`], section 3.4) and the exact test of every sub-sample in
//! `f64` ([`ExactCoverage`]). Both settle half-planes whose line misses the pixel square
//! without any quantization ([`HalfPlane::crossing`]); only half-planes that cut the pixel go
//! to the table or the per-sample loop.

use super::lut::LookupTable;
use super::mask::Mask;
use super::screen::{Crossing, HalfPlane};
use crate::pattern::SamplePattern;

/// Sub-samples covered by screen half-planes.
pub trait Coverage<M: Mask>: Sync {
    /// Every sub-sample of the pattern.
    fn all(&self) -> M;
    /// The centre sub-sample.
    fn centre(&self) -> M;
    /// Sub-samples with `g >= 0` (ties inside; the table ignores ties).
    fn closed(&self, h: &HalfPlane) -> M;
    /// Sub-samples with `g > 0` (ties outside; the table ignores ties).
    fn open(&self, h: &HalfPlane) -> M;
}

/// Each half-plane tested at each sub-sample in `f64`.
#[derive(Debug, Clone, PartialEq)]
pub struct ExactCoverage<M> {
    xs: Vec<f64>,
    ys: Vec<f64>,
    all: M,
    centre: M,
}

impl<M: Mask> ExactCoverage<M> {
    /// The sub-samples of `pattern` (whose rate must fit `M`), relative to the pixel centre.
    pub fn new(pattern: &SamplePattern) -> Self {
        Self {
            xs: pattern.offsets().iter().map(|o| o.x - 0.5).collect(),
            ys: pattern.offsets().iter().map(|o| o.y - 0.5).collect(),
            all: M::first(pattern.rate()),
            centre: M::bit(pattern.centre_index()),
        }
    }

    #[inline(always)]
    fn split(&self, h: &HalfPlane, strict: bool) -> M {
        let mut m = M::ZERO;
        for (s, (x, y)) in self.xs.iter().zip(&self.ys).enumerate() {
            let g = h.g0 + h.gx * x + h.gy * y;
            if g > 0.0 || (!strict && g == 0.0) {
                m |= M::bit(s);
            }
        }
        m
    }
}

impl<M: Mask> Coverage<M> for ExactCoverage<M> {
    fn all(&self) -> M {
        self.all
    }

    fn centre(&self) -> M {
        self.centre
    }

    #[inline(always)]
    fn closed(&self, h: &HalfPlane) -> M {
        match h.crossing() {
            Crossing::All => self.all,
            Crossing::None => M::ZERO,
            Crossing::Split => self.split(h, false),
        }
    }

    #[inline(always)]
    fn open(&self, h: &HalfPlane) -> M {
        match h.crossing() {
            Crossing::All => self.all,
            Crossing::None => M::ZERO,
            Crossing::Split => self.split(h, true),
        }
    }
}

/// Half-planes quantized and looked up in the precomputed table.
#[derive(Debug, Clone, Copy)]
pub struct TableCoverage<'a, M> {
    table: &'a LookupTable<M>,
    all: M,
    centre: M,
}

impl<'a, M: Mask> TableCoverage<'a, M> {
    /// Lookups in `table`, built for `pattern`.
    pub fn new(table: &'a LookupTable<M>, pattern: &SamplePattern) -> Self {
        Self { table, all: M::first(pattern.rate()), centre: M::bit(pattern.centre_index()) }
    }

    #[inline(always)]
    fn get(&self, h: &HalfPlane) -> M {
        match h.crossing() {
            Crossing::All => self.all,
            Crossing::None => M::ZERO,
            Crossing::Split => self.table.lookup(h),
        }
    }
}

impl<M: Mask> Coverage<M> for TableCoverage<'_, M> {
    fn all(&self) -> M {
        self.all
    }

    fn centre(&self) -> M {
        self.centre
    }

    #[inline(always)]
    fn closed(&self, h: &HalfPlane) -> M {
        self.get(h)
    }

    #[inline(always)]
    fn open(&self, h: &HalfPlane) -> M {
        self.get(h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::PatternKind;

    #[test]
    fn exact_coverage_counts_ties_by_the_rule_asked() {
        let pattern = SamplePattern::new(4, PatternKind::Grid).expect("valid");
        let exact = ExactCoverage::<u32>::new(&pattern);
        // The vertical line through the centre: two samples on it (x = 0), two left of it.
        let h = HalfPlane { g0: 0.0, gx: 1.0, gy: 0.0 };
        assert_eq!(exact.closed(&h).count(), 2);
        assert_eq!(exact.open(&h).count(), 0);
        let flipped = |h: HalfPlane| HalfPlane { g0: -h.g0, gx: -h.gx, gy: -h.gy };
        assert_eq!(exact.closed(&flipped(h)).count(), 4);
        assert_eq!(exact.centre() & exact.closed(&h), exact.centre());
        let far = HalfPlane { g0: 5.0, gx: 1.0, gy: 1.0 };
        assert_eq!(exact.open(&far), exact.all());
        assert_eq!(exact.closed(&flipped(far)), 0);
    }

    #[test]
    fn table_agrees_with_exact_far_from_the_line() {
        let pattern = SamplePattern::new(32, PatternKind::Rotated).expect("valid");
        let table = LookupTable::<u32>::new(&pattern);
        let (t, e) = (TableCoverage::new(&table, &pattern), ExactCoverage::<u32>::new(&pattern));
        // Lines at a generic angle and offset keep every sample farther than the bound.
        for k in 0..200 {
            let a = 0.1 + 0.031 * f64::from(k);
            let h = HalfPlane { g0: 0.013 * f64::from(k % 37) - 0.23, gx: a.cos(), gy: a.sin() };
            let near = pattern.offsets().iter().any(|o| {
                (h.at(*o - glam::DVec2::splat(0.5))).abs() <= super::super::lut::FLIP_BOUND
            });
            if !near {
                assert_eq!(t.closed(&h), e.closed(&h), "{h:?}");
            }
        }
    }
}
