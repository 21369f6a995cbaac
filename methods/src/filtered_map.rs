//! What the filtered shadow maps share (variance, exponential and moment shadow maps, in the
//! registry's table): the width of the box filter over their stored values ([`FILTER`]), the
//! precision those values are stored at ([`PRECISION`], [`Precision`]), the light-bleeding
//! reduction of the maps that bound the shadow ([`BLEEDING_REDUCTION`], [`reduce_bleeding`]),
//! the filter itself ([`box_filter`]) and their stages ([`run`]).
//!
//! Each stores `N` values per texel that are a function of the caster's depth `z`, normalised
//! to [0, 1] over the scene's light depth range (1 where the texel holds no caster, as a
//! cleared depth buffer holds the far plane), filters them, and tests each pixel centre's
//! receiver depth, normalised the same way after the shared bias tolerance of
//! [`crate::depth_test`] (with the reach of the filter's half-width), against its texel's
//! filtered values. Stages: the light depth map, the stored values filtered (timed under the
//! method's first stage name), the test (its second).
//!
//! # Storage precision
//!
//! The values are computed in `f64` and rounded when they are stored, before the filter, as a
//! shader writes them into a texture of that format: `f32` (IEEE single, to nearest, ties to
//! even), `f16` (the `f32` value rounded again to IEEE half, to nearest, ties to even, as a
//! half-float texture write rounds the shader's `f32`), `u16` (16-bit unsigned normalized:
//! clamped to [0, 1], times 65535, rounded half up; the moment map's optimized basis makes its
//! values fit) or `f64` (no rounding). The filter reads the stored values, as a GPU's texture
//! filter reads the texture, and sums them in `f64`. The rounding is deterministic code
//! ([`Precision::round`]: Rust's `as f32`, and [`f16_bits`] by integer operations on the
//! `f32`'s bits) that the GPU kernels reproduce bit for bit (`gpu::filtered`).
//!
//! # Light-bleeding reduction
//!
//! Where several casters overlap in a filter's footprint, the variance map's upper bound and
//! the moment map's lower shadow bound let light through behind the nearer one ("light
//! bleeding"). Lauritzen and McCool ("Layered Variance Shadow Maps", Graphics Interface 2008;
//! Lauritzen, GPU Gems 3, chapter 8) cut those tails off by remapping the lit value,
//! `lit' = clamp((lit - A) / (1 - A), 0, 1)`; Peters and Klein (2015) apply the same remap to
//! the moment map's lit value. [`BLEEDING_REDUCTION`] is `A`, 0 (off) by default.
//!
//! The filter is a box of `filter x filter` texels, separable (rows, then columns), in `f64`;
//! texels beyond the map's border repeat the border (clamp to edge). It runs over any number of
//! values per texel (`N`: two moments, one exponential, four moments). Hot path: one pass per
//! axis over rows in parallel, no allocation inside a row.
//!
//! A pixel's lit value is written as `f32` by [`lit_value`]: clamped to [0, 1], values below
//! the least normal `f32` written as 0 (GPUs may flush `f32` subnormals, so both paths do).

use crate::{
    depth_map::LightDepthMap,
    depth_test::{filter_pixels, texel_at, DepthTester, MapOptions, PixelResult},
    footprint::Sampling,
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    params::{Kind, MethodOptions, Param},
};
use glam::DVec2;
use instrumentation::Recorder;
use rayon::prelude::*;

/// Width of the box filter over a filtered shadow map's stored values.
pub static FILTER: Param = Param {
    key: "filter",
    flag: "--filter",
    value_name: "K",
    help: "Width in texels of the box filter over a filtered shadow map's stored values: odd, 1 \
           to 63; default 3 (1: no filtering).",
    kind: Kind::Count,
};

/// The default filter width, in texels.
pub const DEFAULT_FILTER: u32 = 3;
/// The widest filter.
pub const MAX_FILTER: u32 = 63;

/// Checks a filter width; the error names the flag.
pub fn check_filter(filter: u32) -> Result<(), MethodError> {
    if filter.is_multiple_of(2) || filter > MAX_FILTER {
        return Err(MethodError::InvalidOption {
            option: FILTER.flag,
            message: format!("must be odd, 1 to {MAX_FILTER}, got {filter}"),
        });
    }
    Ok(())
}

/// The precision a filtered shadow map stores its values at.
pub static PRECISION: Param = Param {
    key: "precision",
    flag: "--precision",
    value_name: "P",
    help: "Precision of a filtered shadow map's stored values, rounded when stored, before the \
           filter (which sums in f64): the variance and exponential maps take f16, f32 or f64 \
           (default f32, their papers'), the moment map u16, f32 or f64 (default u16, its \
           paper's 64 bits per texel).",
    kind: Kind::Choice(&[
        ("f16", "IEEE half floats: the f32 value rounded to the nearest half, ties to even."),
        ("f32", "IEEE single floats: rounded to the nearest, ties to even."),
        ("f64", "No rounding."),
        (
            "u16",
            "16-bit unsigned normalized integers, after the moment map's optimized moment \
             basis (Peters & Klein 2015, section 4).",
        ),
    ]),
};

/// A storage precision (`--precision`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Precision {
    /// IEEE half floats (the `f32` value rounded again).
    F16,
    /// IEEE single floats.
    F32,
    /// No rounding.
    F64,
    /// 16-bit unsigned normalized integers: `round(clamp(v, 0, 1) * 65535) / 65535`.
    U16,
}

impl Precision {
    /// Every precision, in [`PRECISION`]'s order.
    pub const ALL: [Precision; 4] =
        [Precision::F16, Precision::F32, Precision::F64, Precision::U16];

    /// The name, as on the command line and in run records.
    pub fn name(self) -> &'static str {
        match self {
            Precision::F16 => "f16",
            Precision::F32 => "f32",
            Precision::F64 => "f64",
            Precision::U16 => "u16",
        }
    }

    /// The precision called `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The precision given (`--precision`), or `default`.
    pub fn given(options: &MethodOptions, default: Precision) -> Precision {
        Self::from_name(options.choice(PRECISION.key, default.name())).unwrap_or(default)
    }

    /// `v` as stored at this precision (see the module documentation).
    pub fn round(self, v: f64) -> f64 {
        match self {
            Precision::F64 => v,
            Precision::F32 => f64::from(v as f32),
            Precision::F16 => f16_value(f16_bits(v as f32)),
            Precision::U16 => unorm16_value(unorm16(v)),
        }
    }

    /// The code of this precision in the GPU kernels' parameters (`filtered.wgsl`).
    pub fn code(self) -> u32 {
        match self {
            Precision::F64 => 0,
            Precision::F32 => 1,
            Precision::F16 => 2,
            Precision::U16 => 3,
        }
    }

    /// Checks that `method` stores at this precision, one of `stored`; the error names the
    /// flag and the precisions it takes.
    pub fn check(self, method: &str, stored: &[Precision]) -> Result<(), MethodError> {
        if stored.contains(&self) {
            return Ok(());
        }
        let names: Vec<&str> = stored.iter().map(|p| p.name()).collect();
        Err(MethodError::InvalidOption {
            option: PRECISION.flag,
            message: format!("`{method}` stores {}, got {}", names.join(", "), self.name()),
        })
    }
}

/// The IEEE half float nearest to `x` (ties to even), as its bits: integer operations on the
/// bits of `x`, overflow to infinity, NaN kept a NaN.
pub fn f16_bits(x: f32) -> u16 {
    let b = x.to_bits();
    let sign = ((b >> 16) & 0x8000) as u16;
    let exponent = ((b >> 23) & 0xff) as i32;
    let mantissa = b & 0x7f_ffff;
    if exponent == 0xff {
        return sign | 0x7c00 | if mantissa != 0 { 0x200 } else { 0 };
    }
    // The half's biased exponent.
    let e = exponent - 127 + 15;
    if e >= 31 {
        return sign | 0x7c00;
    }
    // `kept` of `bits` low bits dropped, rounded to nearest, ties to even.
    let round = |bits: u32, dropped: u32| -> u32 {
        let kept = bits >> dropped;
        let rest = bits & ((1 << dropped) - 1);
        let half = 1 << (dropped - 1);
        kept + u32::from(rest > half || (rest == half && kept & 1 == 1))
    };
    if e <= 0 {
        // A half subnormal (or zero): units of 2^-24. Below 2^-25 it rounds to zero (an f32
        // subnormal is far below).
        if e < -10 {
            return sign;
        }
        return sign | round(mantissa | 0x80_0000, (14 - e) as u32) as u16;
    }
    // A carry out of the mantissa moves into the exponent, up to infinity: still the nearest.
    sign | round(((e as u32) << 23) | mantissa, 13) as u16
}

/// The value of the IEEE half float of bits `h`.
pub fn f16_value(h: u16) -> f64 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let e = i32::from((h >> 10) & 0x1f);
    let m = f64::from(h & 0x3ff);
    let magnitude = match e {
        0 => m * (2.0f64).powi(-24),
        31 if m == 0.0 => f64::INFINITY,
        31 => f64::NAN,
        _ => (1024.0 + m) * (2.0f64).powi(e - 25),
    };
    sign * magnitude
}

/// The 16-bit unsigned normalized code of `v`: clamped to [0, 1] (NaN to 0), times 65535,
/// rounded half up.
pub fn unorm16(v: f64) -> u16 {
    let c = if v > 0.0 {
        if v < 1.0 {
            v
        } else {
            1.0
        }
    } else {
        0.0
    };
    (c * 65535.0).round() as u16
}

/// The value of the 16-bit unsigned normalized code `k`.
pub fn unorm16_value(k: u16) -> f64 {
    f64::from(k) / 65535.0
}

/// The light-bleeding reduction of a filtered map's lit value.
pub static BLEEDING_REDUCTION: Param = Param {
    key: "bleeding_reduction",
    flag: "--bleeding-reduction",
    value_name: "A",
    help: "Light-bleeding reduction of the variance and moment maps: their lit value is \
           remapped to clamp((lit - A) / (1 - A), 0, 1), which darkens the light that leaks \
           behind overlapping casters (Lauritzen & McCool 2008; Peters & Klein 2015); 0 <= A < \
           1, default 0 (off).",
    kind: Kind::Real,
};

/// Checks a light-bleeding reduction; the error names the flag.
pub fn check_bleeding_reduction(a: f64) -> Result<(), MethodError> {
    if !(0.0..1.0).contains(&a) {
        return Err(MethodError::InvalidOption {
            option: BLEEDING_REDUCTION.flag,
            message: format!("must be at least 0 and below 1, got {a}"),
        });
    }
    Ok(())
}

/// `lit` remapped to `clamp((lit - a) / (1 - a), 0, 1)` (`a` below 1); `a = 0` leaves a value in
/// [0, 1] as it is.
pub fn reduce_bleeding(lit: f64, a: f64) -> f64 {
    ((lit - a) / (1.0 - a)).clamp(0.0, 1.0)
}

/// A pixel's lit value `v` as written: clamped to [0, 1] (NaN to 0), values below the least
/// normal `f32` as 0, the rest rounded to the nearest `f32`.
pub fn lit_value(v: f64) -> f32 {
    if v >= f64::from(f32::MIN_POSITIVE) {
        if v < 1.0 {
            v as f32
        } else {
            1.0
        }
    } else {
        0.0
    }
}

/// `values` (a `res x res` map, row by row, `N` values per texel) averaged over a
/// `filter`-wide box; `filter = 1` gives them back unchanged.
pub fn box_filter<const N: usize>(
    values: Vec<[f64; N]>,
    res: usize,
    filter: usize,
) -> Vec<[f64; N]> {
    if filter <= 1 {
        return values;
    }
    let half = (filter / 2) as isize;
    let last = res as isize - 1;
    let weight = 1.0 / filter as f64;
    let blur = |src: &[[f64; N]], along_rows: bool| -> Vec<[f64; N]> {
        let mut out = vec![[0.0; N]; res * res];
        out.par_chunks_mut(res).enumerate().for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let mut sum = [0.0; N];
                for k in -half..=half {
                    let (sx, sy) = if along_rows {
                        ((x as isize + k).clamp(0, last) as usize, y)
                    } else {
                        (x, (y as isize + k).clamp(0, last) as usize)
                    };
                    for (s, v) in sum.iter_mut().zip(src[sy * res + sx]) {
                        *s += v;
                    }
                }
                *o = sum.map(|s| s * weight);
            }
        });
        out
    };
    let rows = blur(&values, true);
    blur(&rows, false)
}

/// A filtered shadow map's values and test: what [`run`] and the GPU kernels need of it.
pub trait FilteredMap<const N: usize>: ShadowMethod {
    /// Map resolution and bias.
    fn map(&self) -> &MapOptions;
    /// Width of the box filter, in texels (odd).
    fn filter(&self) -> u32;
    /// The precision its values are stored at.
    fn precision(&self) -> Precision;
    /// The names of its two stages: the filtered values, the test.
    fn stages(&self) -> [&'static str; 2];
    /// Checks the options; the error names the flag.
    fn validate(&self) -> Result<(), MethodError>;
    /// What a texel stores for the normalised caster depth `z`, rounded to the precision.
    fn store(&self, z: f64) -> [f64; N];
    /// The lit fraction at the normalised receiver depth `z` of a pixel whose texel holds the
    /// filtered values `filtered` (clamped to [0, 1] by [`lit_value`]).
    fn test(&self, filtered: &[f64; N], z: f64) -> f64;
    /// A warning about the options, which a run records (none by default).
    fn warning(&self) -> Option<String> {
        None
    }
    /// The WGSL twin of [`FilteredMap::store`] and [`FilteredMap::test`] for the GPU kernels:
    /// `fn store(z: f64) -> array<f64, 4>` (its `N` values first) and
    /// `fn test(v: array<f64, 4>, z: f64) -> f64`, with the CPU's operations in the CPU's
    /// order, reading their parameters from `fparams.p0` to `fparams.p3`
    /// ([`FilteredMap::wgsl_params`]) and rounding with `quantize` (`gpu/filtered.wgsl`).
    fn wgsl(&self) -> &'static str;
    /// The values of `fparams.p0` to `fparams.p3` for [`FilteredMap::wgsl`].
    fn wgsl_params(&self) -> [f64; 4];
}

/// The normalised depth `z` of a texel of light depth `t` (1 where no caster).
pub fn normalised_depth(t: f64, near: f64, range: f64) -> f64 {
    if t.is_finite() {
        ((t - near) / range).clamp(0.0, 1.0)
    } else {
        1.0
    }
}

/// The stored values of `map` (nearest light depth `near`, depth range `range`), filtered:
/// what the first stage of [`run`] computes.
pub fn filtered_values<const N: usize, M: FilteredMap<N>>(
    m: &M,
    map: &LightDepthMap,
    near: f64,
    range: f64,
) -> Vec<[f64; N]> {
    let raw: Vec<[f64; N]> =
        map.depth.par_iter().map(|&t| m.store(normalised_depth(t, near, range))).collect();
    box_filter(raw, map.res as usize, m.filter() as usize)
}

/// Runs the filtered shadow map `m` on `frame` (see the module documentation).
pub fn run<const N: usize, M: FilteredMap<N>>(
    m: &M,
    frame: &Frame<'_>,
    rec: &mut Recorder,
) -> Result<Visibility, MethodError> {
    if frame.effects.transparency {
        rec.notes.push(format!("{} treats semi-transparent casters as opaque", m.name()));
    }
    rec.warnings.extend(m.warning());
    let map = frame.light_depth_map(m.map().map_res, m.map().frustum, rec);
    let (near, _) = frame.light_depth_bounds(&map.projector);
    let range = frame.light_depth_range(&map.projector);
    let res = map.res as usize;
    let [store_stage, test_stage] = m.stages();
    let filtered = rec.stages.time(store_stage, || filtered_values(m, &map, near, range));
    let tester = DepthTester::new(m.map(), map.projector, range);
    rec.warnings.extend(tester.warnings(m.name(), frame, Sampling::PixelCentre));
    let reach = filter_reach(m.filter());
    let (lit, counters) = rec.stages.time(test_stage, || {
        filter_pixels(frame, &tester, |_, _, r| {
            let Some((x, y)) = texel_at(r.xy, map.res) else {
                return PixelResult { lit: 1.0, ..Default::default() };
            };
            let z = (r.depth - tester.tolerance(r, reach) - near) / range;
            let lit = lit_value(m.test(&filtered[y * res + x], z));
            PixelResult { lit, compares: 1, bilinear_lookups: 0 }
        })
    });
    rec.counters.merge(&counters);
    Ok(Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None })
}

/// The reach of the bias tolerance for a `filter`-wide box: its half-width, texels per axis.
pub fn filter_reach(filter: u32) -> DVec2 {
    DVec2::splat(f64::from(filter) / 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The box averages its texels and repeats the border; one texel is no filter.
    #[test]
    fn boxes_average_and_repeat_the_border() {
        let values: Vec<[f64; 1]> = (0..9).map(|v| [f64::from(v)]).collect();
        assert_eq!(box_filter(values.clone(), 3, 1), values);
        let f = box_filter(values, 3, 3);
        assert!((f[4][0] - 4.0).abs() < 1e-12, "{:?}", f[4]);
        // Corner: rows 0, 0, 1 and columns 0, 0, 1 of 0 1 2 / 3 4 5.
        let corner = (4.0 * 0.0 + 2.0 * 1.0 + 2.0 * 3.0 + 4.0) / 9.0;
        assert!((f[0][0] - corner).abs() < 1e-12, "{:?}", f[0]);
    }

    #[test]
    fn even_or_wide_filters_name_the_flag() {
        assert!(check_filter(1).is_ok() && check_filter(63).is_ok());
        for bad in [0, 2, 64, 65] {
            assert!(check_filter(bad).expect_err("refused").to_string().starts_with("--filter: "));
        }
    }

    /// Every finite half float comes back from its value unchanged, and its value is exactly
    /// an `f32` (the half's 11 significant bits fit in the single's 24).
    #[test]
    fn every_half_round_trips() {
        for h in (0..=u16::MAX).filter(|h| h & 0x7c00 != 0x7c00) {
            let v = f16_value(h);
            assert_eq!(f64::from(v as f32), v, "{h:#06x}");
            assert_eq!(f16_bits(v as f32), h, "{h:#06x}: {v:e}");
        }
        assert_eq!(f16_value(0x7c00), f64::INFINITY);
        assert!(f16_value(0x7e00).is_nan() && f16_value(f16_bits(f32::NAN)).is_nan());
    }

    /// Halfway between two neighbouring halves goes to the one with an even mantissa; a hair
    /// off halfway goes to the nearer one; beyond the largest half is infinity, below half the
    /// least subnormal zero.
    #[test]
    fn halves_round_to_nearest_ties_to_even() {
        for h in (0u16..0x7bff).step_by(7).chain([0, 1, 0x3ff, 0x400, 0x3bff, 0x3c00]) {
            let (lo, hi) = (f16_value(h), f16_value(h + 1));
            let mid = (lo + hi) / 2.0;
            let even = if h % 2 == 0 { h } else { h + 1 };
            assert_eq!(f16_bits(mid as f32), even, "tie between {h:#06x} and the next");
            let below = f32::from_bits((mid as f32).to_bits() - 1);
            let above = f32::from_bits((mid as f32).to_bits() + 1);
            assert_eq!(f16_bits(below), h, "below the tie after {h:#06x}");
            assert_eq!(f16_bits(above), h + 1, "above the tie after {h:#06x}");
            assert_eq!(f16_bits(-(mid as f32)), even | 0x8000, "negative tie after {h:#06x}");
        }
        assert_eq!(f16_bits(65504.0), 0x7bff);
        assert_eq!(f16_bits(65519.0), 0x7bff);
        assert_eq!(f16_bits(65520.0), 0x7c00);
        assert_eq!(f16_bits(1e9), 0x7c00);
        assert_eq!(f16_bits(2.0f32.powi(-25)), 0, "half the least subnormal, a tie to even 0");
        assert_eq!(f16_bits(2.0f32.powi(-25) * 1.000_001), 1);
        assert_eq!(f16_bits(1e-30), 0);
    }

    /// Rounding stays within half a unit of the last place of each format, is the identity
    /// at `f64`, and keeps [0, 1] inside [0, 1].
    #[test]
    fn precisions_round_within_half_a_unit() {
        for k in 0..=10_000 {
            let v = f64::from(k) / 10_000.0 * (1.0 + 1e-9 * f64::from(k % 7));
            let v = v.min(1.0);
            assert_eq!(Precision::F64.round(v), v);
            for (p, unit) in [
                (Precision::F32, (2.0f64).powi(-24)),
                (Precision::F16, (2.0f64).powi(-11)),
                (Precision::U16, 1.0 / 65535.0),
            ] {
                let r = p.round(v);
                let bound = match p {
                    Precision::U16 => unit / 2.0,
                    // Relative to the value, and at most a subnormal's step near zero.
                    // f16 rounds the f32 value: at most a hair beyond its half unit.
                    _ => (unit * v * 1.001).max((2.0f64).powi(-25)),
                };
                assert!((r - v).abs() <= bound, "{} of {v:e}: {r:e}", p.name());
                assert!((0.0..=1.0).contains(&r), "{} of {v:e}: {r:e}", p.name());
            }
        }
        assert_eq!(unorm16(-1.0), 0);
        assert_eq!(unorm16(f64::NAN), 0);
        assert_eq!(unorm16(2.0), u16::MAX);
        assert_eq!(unorm16(0.5), 32768, "32767.5 rounds half up");
        for k in [0, 1, 32767, 65535] {
            assert_eq!(unorm16(unorm16_value(k)), k);
        }
    }

    #[test]
    fn precisions_have_their_names_and_methods_refuse_others() {
        let Kind::Choice(names) = PRECISION.kind else { panic!("a choice") };
        let listed: Vec<&str> = names.iter().map(|(n, _)| *n).collect();
        let all: Vec<&str> = Precision::ALL.iter().map(|p| p.name()).collect();
        assert_eq!(listed, all);
        for p in Precision::ALL {
            assert_eq!(Precision::from_name(p.name()), Some(p));
        }
        let mut codes: Vec<u32> = Precision::ALL.iter().map(|p| p.code()).collect();
        codes.sort_unstable();
        assert_eq!(codes, [0, 1, 2, 3]);
        let e = Precision::U16.check("m", &[Precision::F32, Precision::F64]).expect_err("refused");
        assert_eq!(e.to_string(), "--precision: `m` stores f32, f64, got u16");
    }

    /// The remap leaves [0, 1] alone at 0, cuts the tail below `a` to 0 and keeps 1 at 1.
    #[test]
    fn bleeding_reduction_cuts_the_tail() {
        for lit in [0.0, 0.1, 0.5, 1.0] {
            assert_eq!(reduce_bleeding(lit, 0.0), lit);
        }
        assert_eq!(reduce_bleeding(0.2, 0.3), 0.0);
        assert_eq!(reduce_bleeding(1.0, 0.3), 1.0);
        assert!((reduce_bleeding(0.65, 0.3) - 0.5).abs() < 1e-15);
        assert!(check_bleeding_reduction(0.0).is_ok() && check_bleeding_reduction(0.99).is_ok());
        for bad in [1.0, -0.1, f64::NAN, f64::INFINITY] {
            let e = check_bleeding_reduction(bad).expect_err("refused").to_string();
            assert!(e.starts_with("--bleeding-reduction: "), "{e}");
        }
    }

    #[test]
    fn lit_values_are_clamped_and_flush_below_the_least_normal() {
        assert_eq!(lit_value(-0.5), 0.0);
        assert_eq!(lit_value(f64::NAN), 0.0);
        assert_eq!(lit_value(1e-40), 0.0);
        assert_eq!(lit_value(f64::from(f32::MIN_POSITIVE)), f32::MIN_POSITIVE);
        assert_eq!(lit_value(2.0), 1.0);
        assert_eq!(lit_value(0.1), 0.1f32);
    }
}
