//! Stage "summed-area table" (section 3.3, Fig. 4b): prefix sums of a texel mask, so that the
//! marked texels of any rectangle are counted from four references.
//!
//! Convention: `sum(x, y)` is the number of marked texels in `[0, x) x [0, y)`, for
//! `0 <= x, y <= res`, so the table has `(res + 1)^2` entries with a zero first row and
//! column, and the count of the inclusive texel rectangle `x0..=x1, y0..=y1` is
//! `sum(x1+1, y1+1) - sum(x0, y1+1) - sum(x1+1, y0) + sum(x0, y0)`. `u32` counts: a map has at
//! most `16384^2 < 2^32` texels.

use rayon::prelude::*;

/// Prefix sums of a `res x res` texel mask.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SummedAreaTable {
    res: usize,
    sums: Vec<u32>,
}

impl SummedAreaTable {
    /// The table of `mask` (row by row, `res x res`).
    pub fn new(mask: &[bool], res: u32) -> Self {
        let res = res as usize;
        let stride = res + 1;
        let mut sums = vec![0u32; stride * stride];
        // Row prefix sums in parallel, then a running sum down the columns.
        sums[stride..].par_chunks_mut(stride).zip(mask.par_chunks(res.max(1))).for_each(
            |(row, m)| {
                let mut acc = 0;
                for (x, &on) in m.iter().enumerate() {
                    acc += u32::from(on);
                    row[x + 1] = acc;
                }
            },
        );
        for y in 1..=res {
            let (above, row) = sums.split_at_mut(y * stride);
            let above = &above[(y - 1) * stride..];
            for (v, a) in row[..stride].iter_mut().zip(above) {
                *v += a;
            }
        }
        Self { res, sums }
    }

    /// Number of marked texels in `x0..=x1, y0..=y1` (inclusive; requires
    /// `x0 <= x1 < res` and `y0 <= y1 < res`).
    #[inline]
    pub fn count(&self, x0: usize, y0: usize, x1: usize, y1: usize) -> u32 {
        let s = self.res + 1;
        let at = |x: usize, y: usize| self.sums[y * s + x];
        at(x1 + 1, y1 + 1) + at(x0, y0) - at(x0, y1 + 1) - at(x1 + 1, y0)
    }

    /// The table itself: `sum(x, y)` at `y * (res + 1) + x`.
    pub fn sums(&self) -> &[u32] {
        &self.sums
    }

    /// Marked texels in the whole map.
    pub fn total(&self) -> u32 {
        self.sums[self.sums.len() - 1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Every rectangle's count equals the brute-force count.
        #[test]
        fn counts_equal_brute_force(
            res in 1u32..12,
            bits in proptest::collection::vec(any::<bool>(), 144),
            r in (0usize..12, 0usize..12, 0usize..12, 0usize..12),
        ) {
            let n = res as usize;
            let mask = &bits[..n * n];
            let sat = SummedAreaTable::new(mask, res);
            let (x0, x1) = ((r.0 % n).min(r.1 % n), (r.0 % n).max(r.1 % n));
            let (y0, y1) = ((r.2 % n).min(r.3 % n), (r.2 % n).max(r.3 % n));
            let brute = (y0..=y1)
                .flat_map(|y| (x0..=x1).map(move |x| (x, y)))
                .filter(|&(x, y)| mask[y * n + x])
                .count() as u32;
            prop_assert_eq!(sat.count(x0, y0, x1, y1), brute);
            prop_assert_eq!(sat.total(), mask.iter().filter(|&&b| b).count() as u32);
        }
    }
}
