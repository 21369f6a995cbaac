//! `esm`: exponential shadow maps (Annen, Mertens, Seidel and Kautz, "Exponential Shadow Maps",
//! Graphics Interface 2008), a method of the registry's table in one module.
//!
//! Stages, as the paper's section 3:
//! - **light depth map**: the nearest caster depth at each texel centre ([`crate::depth_map`]);
//! - **exponentials**: each texel stores `exp(c * (z - 1))`, with `z` the caster's depth
//!   normalised to [0, 1] over the scene's light depth range (a texel without a caster holds
//!   `z = 1`), averaged over a `filter x filter` box ([`crate::filtered_map::box_filter`]):
//!   the shadow test `exp(-c (d - z))` is separable in `d` and `z`, so the map is filtered
//!   before the test, the paper's point;
//! - **exponential test**: at the pixel centre's receiver depth `d` (normalised the same way,
//!   minus the shared bias tolerance of [`crate::depth_test`] with the reach of the filter's
//!   half-width), lit `= min(1, F * exp(c * (1 - d)))` with `F` the filtered texel (the stages
//!   are [`crate::filtered_map::run`]'s).
//!
//! Choices where the paper leaves them open: the exponentials are kept in `f64` and offset by
//! `-c` (`exp(c (z - 1))`, at most 1), so that `c` up to 700 neither overflows nor underflows
//! (the paper stores `exp(c z)` in 32-bit floats, which bounds `c` near 88; it uses `c = 80`, the
//! default here); the test is evaluated as `exp(ln F + c (1 - d))`; the paper's fall-back to
//! percentage-closer filtering where a receiver lies in front of its own filtered casters (the
//! test exceeding 1) is not implemented: such pixels are lit, which is what the clamp gives.
//! With a one-texel filter the result tends to the standard shadow map's as `c` grows (a
//! shadowed pixel is `exp(-c (d - z))`, not 0), which the tests check. Casters with opacity
//! below 1 are treated as opaque.

use super::{map, Family, MethodEntry, Rates};
use crate::{
    depth_test::MapOptions,
    filtered_map::{self, check_filter, FilteredMap, DEFAULT_FILTER, FILTER},
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    params::{self, Kind, Param},
};
use instrumentation::Recorder;

/// The exponent `c`.
pub static EXPONENT: Param = Param {
    key: "exponent",
    flag: "--exponent",
    value_name: "C",
    help: "The exponent c of exponential shadow maps (`esm`), over depths normalised to [0, 1]: \
           above 0, at most 700; default 80 (the paper's). Larger is sharper, closer to the \
           standard shadow map.",
    kind: Kind::Real,
};

/// The method's entry in the registry's table.
pub const ENTRY: MethodEntry = MethodEntry {
    name: "esm",
    description: "exponential shadow map: box-filtered exp(c z), the test exp(-c (d - z)) \
                  (Annen et al. 2008)",
    family: Family::Today,
    rates: Rates::None,
    params: params::map_and![&FILTER, &EXPONENT],
    stores_samples: None,
    cpu: |o| {
        let m = ExponentialShadowMap {
            map: map(o)?,
            filter: o.count(FILTER.key, DEFAULT_FILTER),
            exponent: o.real(EXPONENT.key, DEFAULT_EXPONENT),
        };
        m.validate()?;
        Ok(Box::new(m))
    },
    gpu: None,
};

/// The default exponent (the paper's).
pub const DEFAULT_EXPONENT: f64 = 80.0;
/// The largest exponent: `exp(-700)` is still a normal `f64`.
pub const MAX_EXPONENT: f64 = 700.0;

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
    /// The exponent `c`.
    pub exponent: f64,
}

impl ExponentialShadowMap {
    /// Checks the options; the error names the flag.
    pub fn validate(&self) -> Result<(), MethodError> {
        self.map.validate()?;
        check_filter(self.filter)?;
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
}

impl FilteredMap<1> for ExponentialShadowMap {
    fn map(&self) -> &MapOptions {
        &self.map
    }

    fn filter(&self) -> u32 {
        self.filter
    }

    fn stages(&self) -> [&'static str; 2] {
        [STAGE_EXPONENTIALS, STAGE_TEST]
    }

    fn store(&self, z: f64) -> [f64; 1] {
        [(self.exponent * (z - 1.0)).exp()]
    }

    fn test(&self, &[f]: &[f64; 1], z: f64) -> f64 {
        // `f >= exp(-c) > 0`: the logarithm is finite.
        (f.ln() + self.exponent * (1.0 - z)).exp().min(1.0)
    }
}

impl ShadowMethod for ExponentialShadowMap {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = self.map.params();
        m.insert(FILTER.key.into(), self.filter.into());
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

    /// Texels hold `exp(c (z - 1))`, at most 1 (`exp(-c)` at the nearest depth, a normal
    /// `f64` up to the largest `c`); behind a texel's one depth the test is `exp(-c (d - z))`.
    #[test]
    fn exponentials_are_offset_to_at_most_one() {
        let m = ExponentialShadowMap { map: MapOptions::default(), filter: 1, exponent: 80.0 };
        assert_eq!(m.store(0.0), [(-80.0f64).exp()]);
        assert_eq!(m.store(1.0), [1.0]);
        assert_eq!(m.test(&m.store(0.5), 0.25), 1.0);
        assert!((m.test(&m.store(0.5), 0.75) - (-20.0f64).exp()).abs() < 1e-15);
        let m = ExponentialShadowMap { exponent: MAX_EXPONENT, ..m };
        assert!(m.store(0.0)[0].is_normal() && m.test(&m.store(0.0), 1.0).is_finite());
    }

    #[test]
    fn bad_options_name_the_flag() {
        let m = ExponentialShadowMap { map: MapOptions::default(), filter: 3, exponent: 0.0 };
        assert!(m.validate().expect_err("zero").to_string().starts_with("--exponent: "));
        for bad in [f64::NAN, 701.0, -1.0] {
            let m = ExponentialShadowMap { exponent: bad, ..m };
            assert!(m.validate().is_err(), "{bad}");
        }
        let m = ExponentialShadowMap { filter: 2, exponent: 80.0, ..m };
        assert!(m.validate().expect_err("even").to_string().starts_with("--filter: "));
    }
}
