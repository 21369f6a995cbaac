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
//!   half-width), lit `= min(1, F * exp(c * (1 - d)))` with `F` the filtered texel.
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

use super::{map, MethodEntry, Rates};
use crate::{
    depth_test::{filter_pixels, texel_at, DepthTester, MapOptions, PixelResult},
    filtered_map::{box_filter, check_filter, DEFAULT_FILTER, FILTER},
    footprint::Sampling,
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    params::{self, Kind, Param},
};
use glam::DVec2;
use instrumentation::Recorder;
use rayon::prelude::*;

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
    rates: Rates::None,
    params: &[
        &params::MAP_RES,
        &params::CONSTANT_BIAS,
        &params::SLOPE_BIAS,
        &params::MAX_SLOPE,
        &FILTER,
        &EXPONENT,
    ],
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

/// `exp(c (z - 1))` at each texel, `z` the depth normalised over `[near, near + range]` (1
/// without a caster), averaged over a `filter`-wide box.
fn exponentials(
    depth: &[f64],
    res: usize,
    filter: usize,
    c: f64,
    near: f64,
    range: f64,
) -> Vec<[f64; 1]> {
    let raw: Vec<[f64; 1]> = depth
        .par_iter()
        .map(|&t| {
            let z = if t.is_finite() { ((t - near) / range).clamp(0.0, 1.0) } else { 1.0 };
            [(c * (z - 1.0)).exp()]
        })
        .collect();
    box_filter(raw, res, filter)
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
        if frame.effects.transparency {
            rec.notes.push("esm treats semi-transparent casters as opaque".into());
        }
        let map = frame.light_depth_map(self.map.map_res, rec);
        let (near, _) = frame.light_depth_bounds(&map.projector);
        let range = frame.light_depth_range(&map.projector);
        let res = map.res as usize;
        let c = self.exponent;
        let filtered = rec.stages.time(STAGE_EXPONENTIALS, || {
            exponentials(&map.depth, res, self.filter as usize, c, near, range)
        });
        let tester = DepthTester::new(&self.map, map.projector, range);
        rec.warnings.extend(tester.warnings(self.name(), frame, Sampling::PixelCentre));
        let reach = DVec2::splat(f64::from(self.filter) / 2.0);
        let (lit, counters) = rec.stages.time(STAGE_TEST, || {
            filter_pixels(frame, &tester, |_, _, r| {
                let Some((x, y)) = texel_at(r.xy, map.res) else {
                    return PixelResult { lit: 1.0, ..Default::default() };
                };
                let [f] = filtered[y * res + x];
                let d = (r.depth - tester.tolerance(r, reach) - near) / range;
                // `f >= exp(-c) > 0`: the logarithm is finite.
                let lit = (f.ln() + c * (1.0 - d)).exp().min(1.0);
                PixelResult { lit: lit as f32, compares: 1, bilinear_lookups: 0 }
            })
        });
        rec.counters.merge(&counters);
        Ok(Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Texels hold `exp(c (z - 1))`: 1 without a caster, `exp(-c)` at the nearest depth.
    #[test]
    fn exponentials_are_offset_to_at_most_one() {
        let depth = vec![2.0, 4.0, f64::INFINITY, 3.0];
        let e = exponentials(&depth, 2, 1, 80.0, 2.0, 2.0);
        assert_eq!(e[0][0], (-80.0f64).exp());
        assert_eq!((e[1][0], e[2][0]), (1.0, 1.0));
        assert!((e[3][0] - (-40.0f64).exp()).abs() < 1e-30);
        let e = exponentials(&[0.0], 1, 1, MAX_EXPONENT, 0.0, 1.0);
        assert!(e[0][0].is_normal() && e[0][0].ln().is_finite());
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
