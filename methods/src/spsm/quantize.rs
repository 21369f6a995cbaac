//! The 8-bit depth-derivative code of Lecocq et al. 2014, section 3.4.
//!
//! A derivative `s` (a surface slope: depth change per unit of lateral distance) is stored as
//! its angle `θ = atan(s)`, normalised to `u = 2θ/π ∈ [-1, 1]`, then raised to the power `n`
//! (keeping the sign) and quantized to 8 bits (equation 3):
//!
//! `Q(s) = 127 + sign(u) · round(127 |u|^n)`, codes `0 ..= 254`, `127` for a flat surface
//! (equation 3 with the rounding made symmetric, so `-s` gets the mirrored code).
//!
//! Decoding is the inverse (equation 4), `θ = π/2 · sign(v) |v|^(1/n)` with `v = Q/127 - 1`,
//! precomputed for the 256 codes in a table. `n = 1` is the linear code (a uniform step of
//! `180°/254 ≈ 0.71°`); `n = 5` (the paper's choice) spends the codes near `±90°`, where a
//! small angle change is a large slope change: the step is about 0.23° at 80° and 0.17° at
//! 85°, and correspondingly coarse near 0° (the first code above 0 is about 34°).
//!
//! Choices:
//! - The extreme codes 0 and 254 stand for `|θ|` up to exactly 90°, an infinite slope; they
//!   decode to the finite slope a quarter code inside their rounding interval, and their
//!   error bound is infinite: a texel holding a triangle seen this close to edge-on cannot
//!   prove a shadow nor a consistent depth (see [`DerivativeCode::error`]).
//! - Code 255 is never written; it decodes as 254 so that the table covers every byte.
//! - Encoding compares the slope with a table of thresholds, the smallest `f64` slope of each
//!   code, found once per exponent by bisection over the ordered `f64`s with equation 3
//!   itself: the same code as equation 3 for every slope, without its `atan` and power
//!   (which took a tenth of a `spsm` run), and the table the GPU kernels encode with.

use std::f64::consts::FRAC_PI_2;
use std::sync::OnceLock;

/// Largest encoding exponent accepted (`--derivative-power`).
pub const MAX_POWER: u32 = 9;

/// The default exponent: the paper's `x^5`.
pub const DEFAULT_POWER: u32 = 5;

/// An 8-bit derivative code for one exponent, with its decoding and error tables.
#[derive(Debug, Clone, PartialEq)]
pub struct DerivativeCode {
    power: u32,
    slope: [f64; 256],
    error: [f64; 256],
    threshold: [f64; 256],
}

/// Equation 3 for exponent `power`: the code of slope `s` (not NaN).
fn by_equation(power: u32, s: f64) -> u8 {
    let u = s.atan() / FRAC_PI_2;
    // Rounded as a magnitude, so that -s gets exactly the mirrored code.
    let m = (127.0 * u.abs().powf(f64::from(power))).round().min(127.0);
    (127.0 + u.signum() * m) as u8
}

/// The order-preserving map of the non-NaN `f64`s onto the integers.
fn key(s: f64) -> i128 {
    let b = s.to_bits() as i64;
    i128::from(if b < 0 { b ^ i64::MAX } else { b })
}

/// The inverse of [`key`].
fn from_key(k: i128) -> f64 {
    let k = k as i64;
    f64::from_bits((if k < 0 { k ^ i64::MAX } else { k }) as u64)
}

/// For each code `c` in 1 to 254, the smallest `f64` slope that equation 3 encodes to `c` or
/// above, by bisection over the ordered `f64`s: the code is non-decreasing in the slope, so
/// a slope's code is the number of thresholds at or below it.
fn thresholds(power: u32) -> [f64; 256] {
    let mut t = [f64::NEG_INFINITY; 256];
    t[255] = f64::INFINITY;
    for (c, slot) in t.iter_mut().enumerate().take(255).skip(1) {
        let (mut lo, mut hi) = (key(f64::NEG_INFINITY), key(f64::INFINITY));
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if usize::from(by_equation(power, from_key(mid))) >= c {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        *slot = from_key(hi);
    }
    t
}

/// `sign(v) |v|^e`.
fn signed_pow(v: f64, e: f64) -> f64 {
    v.signum() * v.abs().powf(e)
}

impl DerivativeCode {
    /// The code with exponent `power` (1 = linear). The caller validates `1..=MAX_POWER`;
    /// values outside are clamped into it. Made once per exponent and kept.
    pub fn new(power: u32) -> Self {
        static CODES: [OnceLock<DerivativeCode>; MAX_POWER as usize] =
            [const { OnceLock::new() }; MAX_POWER as usize];
        let power = power.clamp(1, MAX_POWER);
        CODES[power as usize - 1].get_or_init(|| Self::build(power)).clone()
    }

    fn build(power: u32) -> Self {
        let n = f64::from(power);
        // Angle of the (fractional) code q, clamped to the domain.
        let angle = |q: f64| FRAC_PI_2 * signed_pow((q / 127.0 - 1.0).clamp(-1.0, 1.0), 1.0 / n);
        let mut slope = [0.0; 256];
        let mut error = [0.0; 256];
        // The upper half, mirrored onto the lower one so that the table is exactly odd.
        for c in 127..=254usize {
            let q = c as f64;
            let (lo, hi) = (angle(q - 0.5), angle(q + 0.5));
            let (s, e) = if c == 254 {
                (angle(q - 0.25).tan(), f64::INFINITY)
            } else {
                let s = angle(q).tan();
                (s, (lo.tan() - s).abs().max((hi.tan() - s).abs()))
            };
            (slope[c], error[c]) = (s, e);
            (slope[254 - c], error[254 - c]) = (-s, e);
        }
        (slope[255], error[255]) = (slope[254], error[254]);
        Self { power, slope, error, threshold: thresholds(power) }
    }

    /// The code of slope `s` (equation 3), through the thresholds. NaN encodes as 127
    /// (flat).
    #[inline]
    pub fn encode(&self, s: f64) -> u8 {
        if s.is_nan() {
            return 127;
        }
        // The number of thresholds at or below `s`, codes 1 to 254.
        let (mut lo, mut hi) = (0usize, 254usize);
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if s >= self.threshold[mid] {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        lo as u8
    }

    /// For each code `c` in 1 to 254, the smallest slope that encodes to `c` or above
    /// (index 0 holds `-∞`, 255 `+∞`): the table [`Self::encode`] searches.
    pub fn thresholds(&self) -> &[f64; 256] {
        &self.threshold
    }

    /// The exponent `n`, in `1..=MAX_POWER`.
    pub fn power(&self) -> u32 {
        self.power
    }

    /// The slope a code stands for (equation 4, through the 256-entry table).
    #[inline]
    pub fn decode(&self, q: u8) -> f64 {
        self.slope[q as usize]
    }

    /// The largest `|s - decode(q)|` over every slope `s` that encodes to `q`; infinite for
    /// the two extreme codes.
    #[inline]
    pub fn error(&self, q: u8) -> f64 {
        self.error[q as usize]
    }

    /// The angle in degrees a code stands for.
    pub fn decode_degrees(&self, q: u8) -> f64 {
        self.decode(q).atan().to_degrees()
    }

    /// The decoding table: the slope of each of the 256 codes.
    pub fn table(&self) -> &[f64; 256] {
        &self.slope
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_is_the_middle_code_and_signs_are_symmetric() {
        for n in 1..=MAX_POWER {
            let c = DerivativeCode::new(n);
            assert_eq!(c.encode(0.0), 127);
            assert_eq!(c.decode(127), 0.0);
            for s in [0.3, 1.0, 4.0, 57.0] {
                assert_eq!(i32::from(c.encode(s)) - 127, 127 - i32::from(c.encode(-s)));
                assert_eq!(c.decode(c.encode(s)), -c.decode(c.encode(-s)));
            }
        }
    }

    #[test]
    fn every_slope_decodes_within_its_error_bound() {
        for n in [1, 3, 5] {
            let c = DerivativeCode::new(n);
            for k in -2000..=2000 {
                let s = (f64::from(k) / 2000.0 * 1.55).tan();
                let q = c.encode(s);
                assert!((c.decode(q) - s).abs() <= c.error(q) * (1.0 + 1e-12), "n {n} s {s}");
            }
        }
    }

    #[test]
    fn thresholds_encode_as_equation_3_does() {
        let mut rng = 0x9e37_79b9_7f4a_7c15u64;
        for n in 1..=MAX_POWER {
            let c = DerivativeCode::new(n);
            let mut slopes: Vec<f64> =
                (-3000..=3000).map(|k| (f64::from(k) / 1900.0).tan()).collect();
            // The thresholds themselves and their neighbours, where a code changes.
            for &t in &c.thresholds()[1..255] {
                slopes.extend([t, from_key(key(t) - 1), from_key(key(t) + 1)]);
            }
            // Random bit patterns: every magnitude.
            for _ in 0..20_000 {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                slopes.push(f64::from_bits(rng));
            }
            slopes.extend([
                0.0,
                -0.0,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::MAX,
                f64::MIN_POSITIVE,
            ]);
            for s in slopes.into_iter().filter(|s| !s.is_nan()) {
                assert_eq!(c.encode(s), by_equation(n, s), "n {n} s {s:e}");
            }
        }
    }

    #[test]
    fn extreme_codes_are_finite_with_unbounded_error() {
        let c = DerivativeCode::new(5);
        assert_eq!(c.encode(f64::INFINITY), 254);
        assert_eq!(c.encode(f64::NEG_INFINITY), 0);
        assert_eq!(c.encode(f64::NAN), 127);
        for q in [0, 254, 255] {
            assert!(c.decode(q).is_finite());
            assert_eq!(c.error(q), f64::INFINITY);
        }
        assert!(c.error(253).is_finite());
        assert_eq!(c.decode(255), c.decode(254));
    }
}
