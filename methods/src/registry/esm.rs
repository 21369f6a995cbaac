//! `esm`: exponential shadow maps (Annen, Mertens, Seidel and Kautz, "Exponential Shadow Maps",
//! Graphics Interface 2008), a method of the registry's table in one module (its WGSL beside
//! it, `esm.wgsl`).
//!
//! Stages, as the paper's section 3:
//! - **light depth map**: the nearest caster depth at each texel centre ([`crate::depth_map`]);
//! - **exponentials**: each texel stores `exp(c * (z - 1))`, with `z` the caster's depth
//!   normalised to [0, 1] over the scene's light depth range (a texel without a caster holds
//!   `z = 1`), rounded to the storage precision (`--precision`: `f32` by default, the paper's
//!   32-bit floats; `f16`; `f64`, no rounding) and averaged over a `filter x filter` box
//!   ([`crate::filtered_map::box_filter`], summing the stored values in `f64`): the shadow test
//!   `exp(-c (d - z))` is separable in `d` and `z`, so the map is filtered before the test, the
//!   paper's point;
//! - **exponential test**: at the pixel centre's receiver depth `d` (normalised the same way,
//!   minus the shared bias tolerance of [`crate::depth_test`] with the reach of the filter's
//!   half-width), lit `= min(1, F / exp(c (d - 1)))` with `F` the filtered texel (the stages
//!   are [`crate::filtered_map::run`]'s).
//!
//! The paper has no light-bleeding reduction (its light leaks where a receiver lies close
//! behind its caster, which `c` trades against sharpness), so `esm` takes no
//! `--bleeding-reduction`.
//!
//! Choices where the paper leaves them open: the exponentials are offset by `-c`
//! (`exp(c (z - 1))`, at most 1), so that `c` up to 700 stays finite in `f64` (the paper stores
//! `exp(c z)` in 32-bit floats, which bounds `c` near 88; it uses `c = 80`, the default here);
//! at `f32` or `f16` the stored values of near casters round to 0 once `c (1 - z)` exceeds
//! about 104 or 17 (the run records a warning naming the depth), and a receiver in front of
//! such casters is then shadowed; the test is evaluated as `1` where `F >= exp(c (d - 1))`,
//! else the quotient, which is finite for every `d`; the paper's fall-back to
//! percentage-closer filtering where a receiver lies in front of its own filtered casters (the
//! test exceeding 1) is not implemented: such pixels are lit, which is what the clamp gives.
//! `exp` is this module's [`exp`], built from additions, multiplications and one division (as
//! fdlibm's), since WGSL has no `f64` exponential: the GPU kernels run the same operations
//! (`esm.wgsl`), so both paths agree bit for bit; it is within one unit in the last place of
//! the correctly rounded value. With a one-texel filter and `f64` storage the result tends to
//! the standard shadow map's as `c` grows (a shadowed pixel is `exp(-c (d - z))`, not 0), which
//! the tests check. Casters with opacity below 1 are treated as opaque.

use super::{gpu, map, Build, Family, MethodEntry, Rates};
use crate::{
    depth_test::MapOptions,
    filtered_map::{self, check_filter, FilteredMap, Precision, DEFAULT_FILTER, FILTER, PRECISION},
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    params::{self, Kind, MethodOptions, Param},
};
use instrumentation::Recorder;

/// The exponent `c`.
pub static EXPONENT: Param = Param {
    key: "exponent",
    flag: "--exponent",
    value_name: "C",
    help: "The exponent c of exponential shadow maps (`esm`), over depths normalised to [0, 1]: \
           above 0, at most 700; default 80 (the paper's). Larger is sharper, closer to the \
           standard shadow map; at f32 storage c above 104 (f16: above 17) rounds near \
           casters' values to 0.",
    kind: Kind::Real,
};

/// The method's entry in the registry's table.
pub const ENTRY: MethodEntry = MethodEntry {
    name: "esm",
    description: "exponential shadow map: box-filtered exp(c z), the test exp(-c (d - z)) \
                  (Annen et al. 2008)",
    family: Family::Today,
    rates: Rates::None,
    params: params::map_and![&FILTER, &PRECISION, &EXPONENT],
    stores_samples: None,
    cpu: |o| Ok(Box::new(build(o)?)),
    gpu: gpu!(|o| Ok(Box::new(crate::gpu::filtered::GpuFilteredMap::<1, _> { twin: build(o)? }))),
};

/// The map the options give, validated.
fn build(o: &MethodOptions) -> Result<ExponentialShadowMap, MethodError> {
    let m = ExponentialShadowMap {
        map: map(o)?,
        filter: o.count(FILTER.key, DEFAULT_FILTER),
        precision: Precision::given(o, DEFAULT_PRECISION),
        exponent: o.real(EXPONENT.key, DEFAULT_EXPONENT),
    };
    m.validate()?;
    Ok(m)
}

/// The default exponent (the paper's).
pub const DEFAULT_EXPONENT: f64 = 80.0;
/// The largest exponent: `exp(-700)` is still a normal `f64`.
pub const MAX_EXPONENT: f64 = 700.0;
/// The default storage precision (the paper's 32-bit floats).
pub const DEFAULT_PRECISION: Precision = Precision::F32;
/// The precisions the exponentials are stored at.
pub const PRECISIONS: [Precision; 3] = [Precision::F16, Precision::F32, Precision::F64];

/// Name of the exponentials stage.
pub const STAGE_EXPONENTIALS: &str = "exponentials";
/// Name of the exponential test stage.
pub const STAGE_TEST: &str = "exponential test";

/// An exponential shadow map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExponentialShadowMap {
    /// Map resolution and bias.
    pub map: MapOptions,
    /// Width of the box filter, in texels (odd).
    pub filter: u32,
    /// The precision the exponentials are stored at (f16, f32 or f64).
    pub precision: Precision,
    /// The exponent `c`.
    pub exponent: f64,
}

// fdlibm's reduction and polynomial (e_exp.c): ln 2 in two parts, 1 / ln 2, and the
// coefficients of the rational approximation on [-ln 2 / 2, ln 2 / 2].
const LN2_HI: f64 = 0.6931471803691238;
const LN2_LO: f64 = 1.9082149292705877e-10;
const INV_LN2: f64 = std::f64::consts::LOG2_E;
const P1: f64 = 0.16666666666666602;
const P2: f64 = -0.0027777777777015593;
const P3: f64 = 6.613756321437934e-05;
const P4: f64 = -1.6533902205465252e-06;
const P5: f64 = 4.1381367970572385e-08;
/// Below this, [`exp`] gives 0 (its value would not be a normal `f64`).
pub const EXP_MIN: f64 = -708.0;
/// Above this, [`exp`] gives `exp(EXP_MAX)`.
pub const EXP_MAX: f64 = 709.0;
/// 2^(2^i) and 2^-(2^i), i = 0 to 9: `2^k` for `|k| < 1024` as a product of them.
const POW2_UP: [f64; 10] = [
    2.0,
    4.0,
    16.0,
    256.0,
    65536.0,
    4294967296.0,
    1.8446744073709552e19,
    3.402823669209385e38,
    1.157920892373162e77,
    1.3407807929942597e154,
];
const POW2_DOWN: [f64; 10] = [
    0.5,
    0.25,
    0.0625,
    0.00390625,
    1.52587890625e-5,
    2.3283064365386963e-10,
    5.421010862427522e-20,
    2.938735877055719e-39,
    8.636168555094445e-78,
    7.458340731200207e-155,
];

/// `e^x` from basic operations in a fixed order, as fdlibm computes it (`k = round(x / ln 2)`,
/// `r = x - k ln 2` in two parts, a rational approximation of `e^r`, times `2^k` as a product of
/// powers of two), so that `esm.wgsl`'s `exp64` gives the same bits: within one unit in the
/// last place for `x` in [`EXP_MIN`], [`EXP_MAX`]; 0 below (and for NaN), `exp(EXP_MAX)` above.
pub fn exp(x: f64) -> f64 {
    if x.is_nan() || x < EXP_MIN {
        return 0.0;
    }
    let x = if x > EXP_MAX { EXP_MAX } else { x };
    let k = (x * INV_LN2 + 0.5).floor();
    let hi = x - k * LN2_HI;
    let lo = k * LN2_LO;
    let r = hi - lo;
    let t = r * r;
    let c = r - t * (P1 + t * (P2 + t * (P3 + t * (P4 + t * P5))));
    let mut y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi);
    // |k| <= 1023: ten bits, each an exact scaling (the result is a normal f64).
    let n = k.abs() as u32;
    let powers = if k < 0.0 { &POW2_DOWN } else { &POW2_UP };
    for (i, p) in powers.iter().enumerate() {
        if n & (1 << i) != 0 {
            y *= p;
        }
    }
    y
}

impl ExponentialShadowMap {
    /// The largest `c (1 - z)` whose exponential the precision stores above 0 (half its least
    /// subnormal); `None` at `f64`, where [`MAX_EXPONENT`] keeps every value normal.
    fn storable_exponent(&self) -> Option<f64> {
        match self.precision {
            Precision::F32 => Some(150.0 * std::f64::consts::LN_2),
            Precision::F16 => Some(25.0 * std::f64::consts::LN_2),
            Precision::F64 | Precision::U16 => None,
        }
    }
}

impl FilteredMap<1> for ExponentialShadowMap {
    fn map(&self) -> &MapOptions {
        &self.map
    }

    fn filter(&self) -> u32 {
        self.filter
    }

    fn precision(&self) -> Precision {
        self.precision
    }

    fn stages(&self) -> [&'static str; 2] {
        [STAGE_EXPONENTIALS, STAGE_TEST]
    }

    fn validate(&self) -> Result<(), MethodError> {
        self.map.validate()?;
        check_filter(self.filter)?;
        self.precision.check(ENTRY.name, &PRECISIONS)?;
        if !(self.exponent > 0.0 && self.exponent <= MAX_EXPONENT) {
            return Err(MethodError::InvalidOption {
                option: EXPONENT.flag,
                message: format!(
                    "must be above 0 and at most {MAX_EXPONENT}, got {}",
                    self.exponent
                ),
            });
        }
        Ok(())
    }

    fn store(&self, z: f64) -> [f64; 1] {
        [self.precision.round(exp(self.exponent * (z - 1.0)))]
    }

    fn test(&self, &[f]: &[f64; 1], z: f64) -> f64 {
        let e = exp(self.exponent * (z - 1.0));
        if f >= e {
            1.0
        } else {
            // `e > f >= 0`: a quotient in [0, 1).
            f / e
        }
    }

    fn warning(&self) -> Option<String> {
        let most = self.storable_exponent()?;
        (self.exponent > most).then(|| {
            format!(
                "{}: at {} storage exp(c (z - 1)) with c = {} rounds to 0 for casters nearer \
                 than {:.3} of the light depth range, which shadow every receiver in their \
                 texels; c at most {most:.1} keeps them (or --precision f64)",
                ENTRY.name,
                self.precision.name(),
                self.exponent,
                1.0 - most / self.exponent
            )
        })
    }

    fn wgsl(&self) -> &'static str {
        include_str!("esm.wgsl")
    }

    fn wgsl_params(&self) -> [f64; 4] {
        [self.exponent, 0.0, 0.0, 0.0]
    }
}

impl ShadowMethod for ExponentialShadowMap {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = self.map.params();
        m.insert(FILTER.key.into(), self.filter.into());
        m.insert(PRECISION.key.into(), self.precision.name().into());
        m.insert(EXPONENT.key.into(), self.exponent.into());
        m
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        self.validate()?;
        filtered_map::run(self, frame, rec)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(precision: Precision, exponent: f64) -> ExponentialShadowMap {
        ExponentialShadowMap { map: MapOptions::default(), filter: 1, precision, exponent }
    }

    /// The constants are fdlibm's bits, and `exp` is within one unit in the last place of the
    /// platform's over its range; 0 below it.
    #[test]
    fn exp_is_within_one_unit_in_the_last_place() {
        let bits = [
            (LN2_HI, 0x3fe6_2e42_fee0_0000u64),
            (LN2_LO, 0x3dea_39ef_3579_3c76),
            (INV_LN2, 0x3ff7_1547_652b_82fe),
            (P1, 0x3fc5_5555_5555_553e),
            (P2, 0xbf66_c16c_16be_bd93),
            (P3, 0x3f11_566a_af25_de2c),
            (P4, 0xbebb_bd41_c5d2_6bf1),
            (P5, 0x3e66_3769_72be_a4d0),
        ];
        for (v, b) in bits {
            assert_eq!(v.to_bits(), b, "{v:e}");
        }
        for (i, (up, down)) in POW2_UP.iter().zip(POW2_DOWN).enumerate() {
            assert_eq!(*up, (2.0f64).powi(1 << i));
            assert_eq!(down, (2.0f64).powi(-(1 << i)));
        }
        let mut worst = 0.0f64;
        for k in 0..=200_000 {
            let x = EXP_MIN + (EXP_MAX - EXP_MIN) * f64::from(k) / 200_000.0;
            for x in [x, x / 1000.0] {
                let (got, want) = (exp(x), x.exp());
                let ulp = f64::from_bits(want.to_bits() + 1) - want;
                worst = worst.max((got - want).abs() / ulp);
            }
        }
        assert!(worst <= 1.0, "{worst} units in the last place");
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-708.5), 0.0);
        assert_eq!(exp(f64::NAN), 0.0);
        assert_eq!(exp(1e6), exp(EXP_MAX));
        assert!(exp(EXP_MIN).is_normal() && exp(EXP_MAX).is_finite());
    }

    /// Texels hold `exp(c (z - 1))`, at most 1 (`exp(-c)` at the nearest depth, a normal
    /// `f64` up to the largest `c`); behind a texel's one depth the test is `exp(-c (d - z))`.
    #[test]
    fn exponentials_are_offset_to_at_most_one() {
        let m = at(Precision::F64, 80.0);
        assert_eq!(m.store(0.0), [exp(-80.0)]);
        assert_eq!(m.store(1.0), [1.0]);
        assert_eq!(m.test(&m.store(0.5), 0.25), 1.0);
        assert!((m.test(&m.store(0.5), 0.75) - (-20.0f64).exp()).abs() < 1e-15);
        let m = at(Precision::F64, MAX_EXPONENT);
        assert!(m.store(0.0)[0].is_normal() && m.test(&m.store(0.0), 1.0).is_finite());
        assert_eq!(m.test(&[0.0], -1.0), 1.0, "far in front of every caster: lit");
        assert_eq!(m.test(&[0.0], 0.5), 0.0);
    }

    /// At `f32` and `f16` the exponentials are rounded when stored; the paper's `c` keeps every
    /// caster above 0 at `f32`, not at `f16`, which the run's warning says.
    #[test]
    fn exponentials_are_rounded_and_underflow_is_warned() {
        let m = at(Precision::F32, 80.0);
        assert_eq!(m.store(0.5), [f64::from(exp(-40.0) as f32)]);
        assert!(m.store(0.0)[0] > 0.0 && m.warning().is_none());
        let m = at(Precision::F16, 80.0);
        assert_eq!(m.store(0.5), [0.0]);
        let w = m.warning().expect("warned");
        assert!(w.contains("f16") && w.contains("0.783") && w.contains("17.3"), "{w}");
        assert!(at(Precision::F32, 700.0).warning().is_some_and(|w| w.contains("104.0")));
        assert!(at(Precision::F64, 700.0).warning().is_none());
    }

    /// `esm.wgsl`'s `exp64` gives this module's `exp` bit for bit, over its whole range and
    /// beyond both ends.
    #[cfg(feature = "gpu")]
    #[test]
    fn the_kernels_exp_equals_the_cpus_bit_for_bit() {
        let ctx = crate::gpu::GpuContext::shared().expect("a GPU adapter");
        let mut x: Vec<f64> = (0..=100_000)
            .map(|k| EXP_MIN - 1.0 + (EXP_MAX - EXP_MIN + 2.0) * f64::from(k) / 100_000.0)
            .collect();
        x.extend((0..10_000).map(|k| -f64::from(k) * 1e-4 - 1e-9));
        x.extend([0.0, -0.0, EXP_MIN, EXP_MAX, -745.0, 1e6, -1e6, f64::NAN]);
        let wgsl = format!(
            "{}\nfn probe(x: f64) -> f64 {{ return exp64(x); }}",
            at(Precision::F64, 80.0).wgsl()
        );
        let got = crate::gpu::filtered::probe(ctx, &wgsl, 0, &x).expect("probe runs");
        for (x, g) in x.iter().zip(got) {
            assert_eq!(g.to_bits(), exp(*x).to_bits(), "exp({x:e}): {g:e} vs {:e}", exp(*x));
        }
    }

    #[test]
    fn bad_options_name_the_flag() {
        let m = ExponentialShadowMap { filter: 3, ..at(Precision::F32, 0.0) };
        assert!(m.validate().expect_err("zero").to_string().starts_with("--exponent: "));
        for bad in [f64::NAN, 701.0, -1.0] {
            let m = ExponentialShadowMap { exponent: bad, ..m };
            assert!(m.validate().is_err(), "{bad}");
        }
        let m = ExponentialShadowMap { filter: 2, exponent: 80.0, ..m };
        assert!(m.validate().expect_err("even").to_string().starts_with("--filter: "));
        let m = ExponentialShadowMap { filter: 3, precision: Precision::U16, ..m };
        assert!(m.validate().expect_err("u16").to_string().starts_with("--precision: "));
    }
}
