//! The one median and the one interval of every time the workbench reports.
//!
//! A [`Summary`] of repeated measurements holds their median and, where the count allows, a
//! distribution-free confidence interval of that median from order statistics (Conover,
//! *Practical Nonparametric Statistics*, 3rd ed., Wiley 1999, section 3.2; Hahn and Meeker,
//! *Statistical Intervals*, Wiley 1991, section 5.2): with the `n` values sorted, the interval
//! `[x_(k), x_(n+1-k)]` holds the true median with probability
//! `1 - 2 P(B <= k - 1)`, `B ~ Binomial(n, 1/2)`, whatever the distribution of the times. `k`
//! is the largest rank whose coverage is at least [`CONFIDENCE`]; the coverage reached is kept
//! beside the interval ([`Summary::ci_level`]).
//!
//! Below six values no pair of order statistics covers the median with 95 %
//! (`n = 5` reaches 93.75 % with the whole range), so a summary of fewer values has no interval,
//! and the report says "no interval" rather than presenting the range as one. Timing noise is
//! skewed (a run is delayed, never sped up), which is why the interval assumes nothing about the
//! distribution, unlike a t-interval, and why the median, not the mean, is the figure.
//!
//! Own code rather than a statistics crate: the interval is ten lines of binomial sums, and
//! the crates that offer quantiles (`statrs`, `hdrhistogram`) give no interval of the median.

use serde::{Deserialize, Serialize};

/// The confidence an interval of the median must reach.
pub const CONFIDENCE: f64 = 0.95;

/// The fewest values whose median has an interval at [`CONFIDENCE`].
pub const MIN_VALUES_FOR_INTERVAL: usize = 6;

/// Median of sorted values (mean of the two middle values for an even count); `None` when
/// empty. The only median of the workbench's times.
pub fn median_of_sorted(v: &[f64]) -> Option<f64> {
    let n = v.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(v[n / 2]),
        _ => Some(0.5 * (v[n / 2 - 1] + v[n / 2])),
    }
}

/// Median of `values`' finite ones, in any order; `None` when there are none.
pub fn median(values: &[f64]) -> Option<f64> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    median_of_sorted(&v)
}

/// The largest rank `k` (from 1) whose order statistics `[x_(k), x_(n+1-k)]` cover the median
/// of `n` values with at least [`CONFIDENCE`], and that coverage; `None` when no rank does.
pub fn median_interval_rank(n: usize) -> Option<(usize, f64)> {
    if n < MIN_VALUES_FOR_INTERVAL {
        return None;
    }
    // P(B = i) for B ~ Binomial(n, 1/2), summed from i = 0 while the coverage holds. 0.5^n
    // stays a normal f64 up to n = 1022; the suites' repeats are capped far below.
    let mut p = 0.5f64.powi(n as i32);
    let mut tail = 0.0;
    let mut best = None;
    for k in 1..=n / 2 {
        // tail = P(B <= k - 1).
        tail += p;
        p *= (n - (k - 1)) as f64 / k as f64;
        let coverage = 1.0 - 2.0 * tail;
        if coverage < CONFIDENCE {
            break;
        }
        best = Some((k, coverage));
    }
    best
}

/// Median, its distribution-free confidence interval, minimum and maximum of repeated
/// measurements, in milliseconds (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// How many measurements.
    #[serde(default)]
    pub n: u32,
    /// Median (mean of the two middle values for an even count).
    pub median: f64,
    /// Lower end of the median's confidence interval; `None` below
    /// [`MIN_VALUES_FOR_INTERVAL`] values.
    pub ci_low: Option<f64>,
    /// Upper end of the median's confidence interval.
    pub ci_high: Option<f64>,
    /// The interval's coverage (at least [`CONFIDENCE`]); `None` without an interval.
    #[serde(default)]
    pub ci_level: Option<f64>,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

impl Summary {
    /// Summarises the finite ones of `values`; `None` when there are none.
    pub fn of(values: &[f64]) -> Option<Self> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        v.sort_by(f64::total_cmp);
        let median = median_of_sorted(&v)?;
        let n = v.len();
        let interval = median_interval_rank(n).map(|(k, level)| (v[k - 1], v[n - k], level));
        Some(Self {
            n: n as u32,
            median,
            ci_low: interval.map(|i| i.0),
            ci_high: interval.map(|i| i.1),
            ci_level: interval.map(|i| i.2),
            min: v[0],
            max: v[n - 1],
        })
    }

    /// The interval's half-width relative to the median, `(high - low) / (2 median)`; `None`
    /// without an interval or with a median that is not positive.
    pub fn relative_half_width(&self) -> Option<f64> {
        let (lo, hi) = (self.ci_low?, self.ci_high?);
        (self.median > 0.0).then(|| (hi - lo) / (2.0 * self.median))
    }

    /// The interval where there is one, else the range `[min, max]`, with whether it is the
    /// interval: the bounds a comparison of two summaries must stay within.
    pub fn bounds(&self) -> ((f64, f64), bool) {
        match (self.ci_low, self.ci_high) {
            (Some(lo), Some(hi)) => ((lo, hi), true),
            _ => ((self.min, self.max), false),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_min_max() {
        let s = Summary::of(&[3.0, 1.0, 2.0]).expect("values");
        assert_eq!((s.n, s.median, s.min, s.max), (3, 2.0, 1.0, 3.0));
        assert_eq!(Summary::of(&[4.0, 1.0, 2.0, 3.0]).expect("values").median, 2.5);
        assert_eq!(Summary::of(&[]), None);
        assert_eq!(Summary::of(&[f64::NAN]), None);
        assert_eq!(median(&[5.0, f64::INFINITY, 1.0]), Some(3.0));
    }

    #[test]
    fn few_values_have_no_interval() {
        for n in 1..MIN_VALUES_FOR_INTERVAL {
            let v: Vec<f64> = (0..n).map(|k| k as f64).collect();
            let s = Summary::of(&v).expect("values");
            assert_eq!((s.ci_low, s.ci_high, s.ci_level), (None, None, None), "n = {n}");
            assert_eq!(s.relative_half_width(), None);
            assert_eq!(s.bounds(), ((0.0, (n - 1) as f64), false));
        }
    }

    /// The ranks and coverages of the binomial tables (Conover, Table A3): n = 6 takes the
    /// range at 96.9 %, n = 9 the second values at 96.1 %, n = 20 the sixth at 95.9 %.
    #[test]
    fn interval_ranks_match_the_binomial_tables() {
        let rank = |n| median_interval_rank(n).map(|(k, c)| (k, (c * 1000.0).round() / 1000.0));
        assert_eq!(rank(5), None);
        assert_eq!(rank(6), Some((1, 0.969)));
        assert_eq!(rank(8), Some((1, 0.992)));
        assert_eq!(rank(9), Some((2, 0.961)));
        assert_eq!(rank(20), Some((6, 0.959)));
        assert_eq!(rank(100), Some((40, 0.965)));
        for n in 6..600 {
            let (k, c) = median_interval_rank(n).expect("an interval");
            assert!((CONFIDENCE..=1.0).contains(&c), "n = {n}: {c}");
            assert!(2 * k <= n, "n = {n}: rank {k}");
        }
    }

    #[test]
    fn the_interval_is_of_order_statistics_and_narrows_with_more_values() {
        let values: Vec<f64> = (0..20).map(|k| 10.0 + ((k * 7) % 20) as f64).collect();
        let s = Summary::of(&values).expect("values");
        // Sorted, the values are 10..=29; rank 6 from each end.
        assert_eq!((s.ci_low, s.ci_high), (Some(15.0), Some(24.0)));
        assert!(s.ci_high.expect("high") - s.ci_low.expect("low") < s.max - s.min);
        assert!(s.bounds().1, "an interval, not the range");
        let half = s.relative_half_width().expect("a width");
        assert!((half - 4.5 / 19.5).abs() < 1e-12, "{half}");
        let same = Summary::of(&[3.0; 9]).expect("values");
        assert_eq!((same.ci_low, same.ci_high), (Some(3.0), Some(3.0)));
    }
}
