//! Portable randomness and trigonometry for the generators.
//!
//! A generator must build the bit-identical mesh from the same parameters on every platform, so
//! it draws from [`Rng`] (SplitMix64, no `rand` crate) and takes sines and cosines from
//! [`sin_cos`], a polynomial built only from IEEE-754 additions, multiplications and
//! `round`, instead of the platform's `libm` (whose last bit differs between C libraries).
//! Square roots (`f64::sqrt`) are correctly rounded everywhere and are used freely.

use glam::DVec3;
use std::f64::consts::TAU;

/// SplitMix64 (Steele, Lea & Flood 2014): a tiny, fast generator that passes BigCrush, with a
/// 64-bit state and full period 2^64. Every draw depends only on the seed and the number of
/// earlier draws.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rng {
    state: u64,
}

impl Rng {
    /// A generator seeded with `seed`; every seed, 0 included, is fine.
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A uniform `f64` in `[0, 1)` from the top 53 bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// A uniform `f64` in `[lo, hi)` (exactly `lo` when `lo == hi`).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }

    /// A uniform integer in `[0, n)`; 0 when `n` is 0. (Multiply-shift: the bias is below
    /// `n / 2^64`, far below anything a scene can show.)
    pub fn below(&mut self, n: u32) -> u32 {
        (((self.next_u64() >> 32) * u64::from(n)) >> 32) as u32
    }

    /// A uniformly distributed direction on the unit sphere (Archimedes: uniform height, uniform
    /// azimuth).
    pub fn unit_vector(&mut self) -> DVec3 {
        let z = self.range(-1.0, 1.0);
        let (s, c) = sin_cos(self.range(0.0, TAU));
        let r = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(r * c, r * s, z)
    }
}

/// `(sin x, cos x)`, portable to the last bit: Cody–Waite reduction by π/2, then Taylor
/// polynomials on `[-π/4, π/4]`. Accurate to about 1e-15 absolute for `|x|` up to about 1e6,
/// which covers every angle the generators use; beyond 1e9 the argument is first reduced by an
/// exact `x % TAU` (still finite and deterministic, no longer accurate). Non-finite `x` gives
/// NaNs.
pub fn sin_cos(x: f64) -> (f64, f64) {
    if !x.is_finite() {
        return (f64::NAN, f64::NAN);
    }
    let x = if x.abs() > 1e9 { x % TAU } else { x };
    // π/2 split into a head with 33 significant bits (so that `k * HI` is exact for the
    // quadrant numbers we meet) and the rest (fdlibm's pio2_1 and pio2_1t).
    const PIO2_HI: f64 = 1.570_796_326_734_125_6;
    const PIO2_LO: f64 = 6.077_100_506_506_192e-11;
    let k = (x * std::f64::consts::FRAC_2_PI).round();
    let r = (x - k * PIO2_HI) - k * PIO2_LO;
    let r2 = r * r;
    let sin = r
        * (1.0
            + r2 * (-1.0 / 6.0
                + r2 * (1.0 / 120.0
                    + r2 * (-1.0 / 5_040.0
                        + r2 * (1.0 / 362_880.0
                            + r2 * (-1.0 / 39_916_800.0
                                + r2 * (1.0 / 6_227_020_800.0
                                    + r2 * (-1.0 / 1_307_674_368_000.0
                                        + r2 * (1.0 / 355_687_428_096_000.0)))))))));
    let cos = 1.0
        + r2 * (-0.5
            + r2 * (1.0 / 24.0
                + r2 * (-1.0 / 720.0
                    + r2 * (1.0 / 40_320.0
                        + r2 * (-1.0 / 3_628_800.0
                            + r2 * (1.0 / 479_001_600.0
                                + r2 * (-1.0 / 87_178_291_200.0
                                    + r2 * (1.0 / 20_922_789_888_000.0))))))));
    // `as` saturates for huge k; the quadrant is then meaningless but still finite.
    match (k as i64) & 3 {
        0 => (sin, cos),
        1 => (cos, -sin),
        2 => (-sin, -cos),
        _ => (-cos, sin),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix_matches_the_reference_sequence() {
        // First outputs of SplitMix64 seeded with 1234567 (reference C implementation).
        let mut rng = Rng::new(1_234_567);
        let expected =
            [6_457_827_717_110_365_317, 3_203_168_211_198_807_973, 9_817_491_932_198_370_423];
        for e in expected {
            assert_eq!(rng.next_u64(), e);
        }
    }

    #[test]
    fn floats_are_in_the_unit_interval() {
        let mut rng = Rng::new(7);
        for _ in 0..10_000 {
            let f = rng.next_f64();
            assert!((0.0..1.0).contains(&f));
            assert!(rng.below(5) < 5);
        }
        assert_eq!(rng.below(0), 0);
        assert_eq!(rng.range(2.0, 2.0), 2.0);
    }

    #[test]
    fn unit_vectors_are_unit_and_spread() {
        let mut rng = Rng::new(3);
        let mut mean = DVec3::ZERO;
        for _ in 0..20_000 {
            let v = rng.unit_vector();
            assert!((v.length() - 1.0).abs() < 1e-12);
            mean += v / 20_000.0;
        }
        assert!(mean.length() < 0.03, "{mean}");
    }

    #[test]
    fn sin_cos_matches_std() {
        let mut x = -200.0;
        while x < 200.0 {
            let (s, c) = sin_cos(x);
            assert!((s - x.sin()).abs() < 1e-14, "sin {x}");
            assert!((c - x.cos()).abs() < 1e-14, "cos {x}");
            x += 0.0137;
        }
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        assert!(sin_cos(f64::NAN).0.is_nan() && sin_cos(f64::INFINITY).1.is_nan());
        for huge in [1e12, -3e200, f64::MAX] {
            let (s, c) = sin_cos(huge);
            assert!(s.abs() <= 1.0 + 1e-12 && c.abs() <= 1.0 + 1e-12, "{huge}");
        }
    }
}
