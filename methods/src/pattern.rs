//! Sub-pixel sample patterns shared by every supersampling technique (`pan09`, `afsm-ss`) and
//! by the `raytrace` reference, so that at equal rate and pattern they evaluate visibility at
//! exactly the same image points and can be compared sample for sample.
//!
//! A [`SamplePattern`] is a list of `rate` offsets inside the unit pixel, relative to its
//! top-left corner: sub-sample `s` of pixel `(i, j)` lies at image point
//! `(i + offsets[s].x, j + offsets[s].y)` (image coordinates from the top-left, `y` down, as in
//! [`scenes::projection`]).
//!
//! # Invariants (unit-tested below)
//!
//! - Exactly `rate` distinct offsets, each in `[0, 1)^2`.
//! - Exactly one offset equals the pixel centre `(0.5, 0.5)`, at [`SamplePattern::centre_index`]
//!   (Pan et al. 2009, section 3.4: the validity mask needs a sample at the pixel centre, the
//!   point the camera G-buffer was rasterized at).
//! - Every coordinate is a multiple of `1 / rate` (of `1/2` at rate 1): a dyadic rational, so
//!   every offset, the centre included, is exact in `f64` and `f32`.
//! - Deterministic: the same `(rate, kind)` always gives the same offsets in the same order.
//!
//! # Rates
//!
//! [`RATES`]: 1, 4, 8, 16, 32, 64, 128 (the methods' rates of DESIGN.md) and 256, 512, 1024
//! (reference rates). Any other value is rejected with `MethodError::InvalidOption` naming
//! `--rate`.
//!
//! # Patterns and the choices made
//!
//! A pattern with a sample exactly at the centre cannot also be symmetric about the centre
//! when the rate is even, so both patterns are *centre-aligned lattices on the torus*: the
//! pattern repeated over all pixels is a regular lattice that contains every pixel centre.
//!
//! - [`PatternKind::Grid`]: `rate = nx x ny` cells ([`grid_dims`]: 1x1, 2x2, 4x2, 4x4, 8x4, 8x8,
//!   16x8, 16x16, 32x16, 32x32; `nx >= ny`). Column `a` is at
//!   `x = 0.5 + (a - floor(nx / 2)) / nx`, row `b` at `y = 0.5 + (b - floor(ny / 2)) / ny`:
//!   the cell centres `(a + 0.5) / nx` moved by half a cell along every axis with an even
//!   count. For even `nx` that is `x = a / nx`, a regular grid of spacing `1 / nx` that starts
//!   at the pixel's left edge; spacing stays regular across pixel borders too. Order: row by
//!   row from the top, left to right within a row. The mean offset is `0.5 - 1 / (2 nx)` in
//!   `x` (and likewise in `y`): half a cell up-left of the centre, the price of the exact
//!   centre sample.
//! - [`PatternKind::Rotated`]: an N-rooks pattern (one sample per column and per row of the
//!   `N x N` sub-grid, `N = rate`), `x = k / N` for `k = 0..N`, ordered by `x`.
//!   - `N = 4`: the classic rotated-grid (RGSS) permutation, rows `[3, 0, 2, 1]` for columns
//!     `0..4`, i.e. the well-known offsets `(3,1), (7,3), (1,5), (5,7)` / 8 moved on the torus
//!     by `(1, 3) / 8` so that one lands on the centre. (Every rank-1 lattice with 4 points is
//!     a diagonal line, useless against edges along the other diagonal.)
//!   - `N >= 8`: the rank-1 lattice `(k / N, (k g mod N) / N)`, translated on the torus so that
//!     column `N / 2` sits on the centre: row of column `k` = `(N/2 + (k - N/2) g) mod N`. The
//!     generator `g` (odd, hence coprime to the power-of-two `N`, which makes the rows a
//!     permutation) maximises the minimum toroidal distance between samples; ties go to the
//!     `g` nearest `sqrt(N)`, then the smaller. This gives `g` = 3, 3, 7, 19, 23, 71, 67, 271
//!     for `N` = 8 ... 1024 and a minimum distance within 5 % of the hexagonal optimum for
//!     `N >= 32` (26 % below it at `N = 16`, where no rank-1 lattice does better).
//!     ("Near `sqrt(N)`" alone can pick a poor lattice: for `N = 256`, `g = 15` or 17 gives
//!     samples along nearly parallel lines.)
//!
//!   The mean offset is `0.5 - 1 / (2N)` on both axes.

use crate::method::MethodError;
use glam::DVec2;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// Every accepted sub-pixel sample rate: the methods' rates (up to 128) and the reference
/// rates 256, 512 and 1024.
pub const RATES: &[u32] = &[1, 4, 8, 16, 32, 64, 128, 256, 512, 1024];

/// Highest sample rate of the techniques (DESIGN.md: masks of at most 128 bits); the higher
/// [`RATES`] are the references'.
pub const MAX_METHOD_RATE: u32 = 128;

/// The error for a `rate` that is not one of [`RATES`] up to `max`, listing those.
fn unsupported_rate(rate: u32, max: u32) -> MethodError {
    MethodError::InvalidOption {
        option: "--rate",
        message: format!(
            "unsupported sample rate {rate}; available: {}",
            RATES.iter().filter(|&&r| r <= max).map(u32::to_string).collect::<Vec<_>>().join(", ")
        ),
    }
}

/// The shape of a sample pattern (`--pattern`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PatternKind {
    /// Regular grid of `nx x ny` samples, centre-aligned (the default).
    #[default]
    Grid,
    /// N-rooks rotated grid (RGSS at rate 4, a rank-1 lattice above), centre-aligned.
    Rotated,
}

impl PatternKind {
    /// The name as on the command line: `grid` or `rotated`.
    pub fn name(self) -> &'static str {
        match self {
            PatternKind::Grid => "grid",
            PatternKind::Rotated => "rotated",
        }
    }
}

impl fmt::Display for PatternKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for PatternKind {
    type Err = MethodError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "grid" => Ok(PatternKind::Grid),
            "rotated" => Ok(PatternKind::Rotated),
            _ => Err(MethodError::InvalidOption {
                option: "--pattern",
                message: format!("unknown pattern `{s}`; available: grid, rotated"),
            }),
        }
    }
}

/// The sub-pixel sample positions of one pixel (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct SamplePattern {
    rate: u32,
    kind: PatternKind,
    offsets: Vec<DVec2>,
    centre: usize,
}

/// Columns and rows `(nx, ny)` of the grid pattern at `rate` (`nx >= ny`, `nx * ny = rate`),
/// or `None` when `rate` is not one of [`RATES`].
pub fn grid_dims(rate: u32) -> Option<(u32, u32)> {
    if !RATES.contains(&rate) {
        return None;
    }
    let log2 = rate.trailing_zeros();
    let ny = 1u32 << (log2 / 2);
    Some((rate / ny, ny))
}

/// The generator `g` of the rotated pattern's rank-1 lattice at `n >= 8` samples: the odd `g`
/// that maximises the minimum toroidal distance between samples, ties to the `g` nearest
/// `sqrt(n)`, then the smaller.
fn lattice_generator(n: u32) -> u32 {
    let n = u64::from(n);
    // Squared minimum distance of the lattice, in units of 1/n (integer, exact).
    let min_dist2 = |g: u64| {
        (1..n)
            .map(|k| {
                let dx = k.min(n - k);
                let y = (k * g) % n;
                let dy = y.min(n - y);
                dx * dx + dy * dy
            })
            .min()
            .unwrap_or(0)
    };
    // Distance of g from sqrt(n) (n <= 1024: the f64 values are far apart or equal).
    let from_root = |g: u64| (g as f64 - (n as f64).sqrt()).abs();
    let mut best = (1u64, min_dist2(1));
    for g in (3..n).step_by(2) {
        let d = min_dist2(g);
        let better = d > best.1 || (d == best.1 && from_root(g) < from_root(best.0));
        if better {
            best = (g, d);
        }
    }
    best.0 as u32
}

/// Row permutation of the rotated pattern: the row (in `0..n`) of the sample in column `k`.
fn rotated_rows(n: u32) -> Vec<u32> {
    match n {
        4 => vec![3, 0, 2, 1],
        _ => {
            let g = u64::from(lattice_generator(n));
            let (n, half) = (u64::from(n), u64::from(n / 2));
            (0..n).map(|k| ((half + ((k + n - half) * g) % n) % n) as u32).collect()
        }
    }
}

impl SamplePattern {
    /// The pattern of `rate` samples for a technique: as [`SamplePattern::new`], with `rate` at
    /// most [`MAX_METHOD_RATE`] (otherwise `MethodError::InvalidOption` naming `--rate` and
    /// listing the rates a technique takes).
    pub fn for_method(rate: u32, kind: PatternKind) -> Result<Self, MethodError> {
        if rate > MAX_METHOD_RATE {
            return Err(unsupported_rate(rate, MAX_METHOD_RATE));
        }
        Self::new(rate, kind)
    }

    /// The pattern of `rate` samples of the given kind; `rate` must be one of [`RATES`]
    /// (otherwise `MethodError::InvalidOption` naming `--rate`).
    pub fn new(rate: u32, kind: PatternKind) -> Result<Self, MethodError> {
        let Some((nx, ny)) = grid_dims(rate) else {
            return Err(unsupported_rate(rate, u32::MAX));
        };
        let offsets: Vec<DVec2> = match kind {
            PatternKind::Grid => {
                let axis = |a: u32, n: u32| 0.5 + (f64::from(a) - f64::from(n / 2)) / f64::from(n);
                (0..ny)
                    .flat_map(|b| (0..nx).map(move |a| DVec2::new(axis(a, nx), axis(b, ny))))
                    .collect()
            }
            PatternKind::Rotated => {
                if rate == 1 {
                    vec![DVec2::splat(0.5)]
                } else {
                    let n = f64::from(rate);
                    rotated_rows(rate)
                        .into_iter()
                        .enumerate()
                        .map(|(k, row)| DVec2::new(k as f64 / n, f64::from(row) / n))
                        .collect()
                }
            }
        };
        let centre = offsets.iter().position(|o| *o == DVec2::splat(0.5)).ok_or_else(|| {
            // Unreachable by construction (tested for every rate); kept as a typed error.
            MethodError::NotApplicable(format!("{kind} pattern at rate {rate} has no centre"))
        })?;
        Ok(Self { rate, kind, offsets, centre })
    }

    /// Number of samples per pixel.
    pub fn rate(&self) -> u32 {
        self.rate
    }

    /// The pattern's kind.
    pub fn kind(&self) -> PatternKind {
        self.kind
    }

    /// Sample positions inside the pixel, in `[0, 1)^2`, relative to its top-left corner.
    pub fn offsets(&self) -> &[DVec2] {
        &self.offsets
    }

    /// Index in [`offsets`](Self::offsets) of the sample at the pixel centre `(0.5, 0.5)`.
    pub fn centre_index(&self) -> usize {
        self.centre
    }

    /// Image point of sample `s` of pixel `(i, j)`: `(i, j) + offsets[s]`.
    ///
    /// Panics if `s >= rate` (an index, not data).
    #[inline]
    pub fn point(&self, i: u32, j: u32, s: usize) -> DVec2 {
        DVec2::new(f64::from(i), f64::from(j)) + self.offsets[s]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    fn all() -> Vec<SamplePattern> {
        RATES
            .iter()
            .flat_map(|&r| {
                [PatternKind::Grid, PatternKind::Rotated]
                    .map(|k| SamplePattern::new(r, k).expect("valid rate"))
            })
            .collect()
    }

    fn cells(v: impl Iterator<Item = f64>, n: u32) -> BTreeSet<u64> {
        v.map(|x| (x * f64::from(n)).floor() as u64).collect()
    }

    #[test]
    fn n_distinct_offsets_in_the_unit_square() {
        for p in all() {
            let o = p.offsets();
            assert_eq!(o.len(), p.rate() as usize, "{:?} {}", p.kind(), p.rate());
            assert!(o.iter().all(|v| (0.0..1.0).contains(&v.x) && (0.0..1.0).contains(&v.y)));
            let distinct: BTreeSet<(u64, u64)> =
                o.iter().map(|v| (v.x.to_bits(), v.y.to_bits())).collect();
            assert_eq!(distinct.len(), o.len(), "{:?} {}", p.kind(), p.rate());
        }
    }

    #[test]
    fn exactly_one_sample_at_the_centre() {
        for p in all() {
            let at_centre: Vec<usize> = (0..p.offsets().len())
                .filter(|&s| p.offsets()[s] == DVec2::new(0.5, 0.5))
                .collect();
            assert_eq!(at_centre, vec![p.centre_index()], "{:?} {}", p.kind(), p.rate());
            assert_eq!(p.point(3, 7, p.centre_index()), DVec2::new(3.5, 7.5));
        }
    }

    #[test]
    fn coordinates_are_exact_multiples_of_one_over_rate() {
        for p in all() {
            let n = f64::from(p.rate().max(2));
            for v in p.offsets() {
                for c in [v.x, v.y] {
                    assert_eq!((c * n).fract(), 0.0, "{:?} {}: {c}", p.kind(), p.rate());
                    assert_eq!(f64::from(c as f32), c);
                }
            }
        }
    }

    #[test]
    fn grid_is_regular_with_equal_spacing() {
        for &rate in RATES {
            let p = SamplePattern::new(rate, PatternKind::Grid).expect("valid");
            let (nx, ny) = grid_dims(rate).expect("valid");
            assert_eq!(nx * ny, rate);
            assert!(nx >= ny && nx <= 2 * ny);
            let xs: BTreeSet<u64> = p.offsets().iter().map(|v| v.x.to_bits()).collect();
            let ys: BTreeSet<u64> = p.offsets().iter().map(|v| v.y.to_bits()).collect();
            assert_eq!((xs.len() as u32, ys.len() as u32), (nx, ny));
            for (values, n) in [(xs, nx), (ys, ny)] {
                let v: Vec<f64> = values.into_iter().map(f64::from_bits).collect();
                // Every gap, including the one across the pixel border (on the torus), is 1/n.
                for k in 0..v.len() {
                    let next = if k + 1 < v.len() { v[k + 1] } else { v[0] + 1.0 };
                    assert_eq!(next - v[k], 1.0 / f64::from(n), "rate {rate}");
                }
            }
            // Row-major order from the top-left.
            for (s, v) in p.offsets().iter().enumerate() {
                let (a, b) = ((s as u32 % nx) as usize, (s as u32 / nx) as usize);
                let expected = DVec2::new(p.offsets()[a].x, p.offsets()[b * nx as usize].y);
                assert_eq!(*v, expected);
                assert!(a == 0 || p.offsets()[s - 1].x < v.x);
                assert!(b == 0 || p.offsets()[s - nx as usize].y < v.y);
            }
        }
    }

    #[test]
    fn rotated_is_n_rooks() {
        for &rate in RATES {
            let p = SamplePattern::new(rate, PatternKind::Rotated).expect("valid");
            let o = p.offsets();
            assert_eq!(cells(o.iter().map(|v| v.x), rate).len(), rate as usize, "rate {rate}");
            assert_eq!(cells(o.iter().map(|v| v.y), rate).len(), rate as usize, "rate {rate}");
        }
    }

    #[test]
    fn rotated_four_is_the_classic_rgss_up_to_a_torus_shift() {
        let p = SamplePattern::new(4, PatternKind::Rotated).expect("valid");
        let classic = [(3.0, 1.0), (7.0, 3.0), (1.0, 5.0), (5.0, 7.0)]
            .map(|(x, y)| DVec2::new(((x + 1.0) / 8.0f64).fract(), ((y + 3.0) / 8.0f64).fract()));
        let mine: BTreeSet<_> =
            p.offsets().iter().map(|v| (v.x.to_bits(), v.y.to_bits())).collect();
        let theirs: BTreeSet<_> = classic.iter().map(|v| (v.x.to_bits(), v.y.to_bits())).collect();
        assert_eq!(mine, theirs);
    }

    #[test]
    fn rotated_lattices_are_well_spread() {
        // Minimum toroidal distance against the hexagonal packing bound sqrt(2 / (sqrt 3 N)).
        for &rate in &RATES[2..] {
            let p = SamplePattern::new(rate, PatternKind::Rotated).expect("valid");
            let o = p.offsets();
            let mut dmin = f64::INFINITY;
            for a in 0..o.len() {
                for b in a + 1..o.len() {
                    let d = (o[a] - o[b]).abs();
                    let d = DVec2::new(d.x.min(1.0 - d.x), d.y.min(1.0 - d.y));
                    dmin = dmin.min(d.length());
                }
            }
            let hex = (2.0 / (3f64.sqrt() * f64::from(rate))).sqrt();
            assert!(dmin > 0.7 * hex, "rate {rate}: {dmin} vs {hex}");
        }
        assert_eq!([8, 16, 32, 64].map(lattice_generator), [3, 3, 7, 19]);
    }

    #[test]
    fn mean_offset_is_near_the_centre() {
        for p in all() {
            let mean = p.offsets().iter().copied().sum::<DVec2>() / f64::from(p.rate());
            let bound = match p.kind() {
                PatternKind::Grid => {
                    let (nx, ny) = grid_dims(p.rate()).expect("valid");
                    DVec2::new(0.5 / f64::from(nx), 0.5 / f64::from(ny))
                }
                PatternKind::Rotated => DVec2::splat(0.5 / f64::from(p.rate())),
            };
            let off = (mean - DVec2::splat(0.5)).abs();
            assert!(off.x <= bound.x + 1e-15 && off.y <= bound.y + 1e-15, "{p:?}");
        }
    }

    #[test]
    fn bad_rates_are_rejected_naming_the_flag() {
        for rate in [0, 2, 3, 5, 12, 100, 2048, u32::MAX] {
            for kind in [PatternKind::Grid, PatternKind::Rotated] {
                match SamplePattern::new(rate, kind) {
                    Err(MethodError::InvalidOption { option, message }) => {
                        assert_eq!(option, "--rate");
                        assert!(message.contains(&rate.to_string()), "{message}");
                    }
                    other => panic!("rate {rate}: {other:?}"),
                }
            }
        }
    }

    #[test]
    fn methods_take_rates_up_to_128() {
        assert!(SamplePattern::for_method(MAX_METHOD_RATE, PatternKind::Grid).is_ok());
        for rate in [256, 1024] {
            match SamplePattern::for_method(rate, PatternKind::Rotated) {
                Err(MethodError::InvalidOption { option, message }) => {
                    assert_eq!(option, "--rate");
                    assert!(message.ends_with("available: 1, 4, 8, 16, 32, 64, 128"), "{message}");
                }
                other => panic!("rate {rate}: {other:?}"),
            }
        }
    }

    #[test]
    fn deterministic_and_named() {
        for p in all() {
            assert_eq!(SamplePattern::new(p.rate(), p.kind()).expect("valid"), p);
        }
        for kind in [PatternKind::Grid, PatternKind::Rotated] {
            assert_eq!(kind.to_string().parse::<PatternKind>().expect("parses"), kind);
            let json = serde_json::to_string(&kind).expect("serializes");
            assert_eq!(json, format!("\"{kind}\""));
        }
        assert_eq!(PatternKind::default(), PatternKind::Grid);
        assert!(matches!(
            "jittered".parse::<PatternKind>(),
            Err(MethodError::InvalidOption { option: "--pattern", .. })
        ));
    }
}
