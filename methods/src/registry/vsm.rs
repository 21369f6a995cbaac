//! `vsm`: variance shadow maps (Donnelly and Lauritzen, "Variance Shadow Maps", ACM Symposium
//! on Interactive 3D Graphics and Games 2006), added as a method in one module and one table
//! entry ([`ENTRY`]); `docs/adding-a-method.md` walks through it.
//!
//! Stages, as the paper's section 3:
//! - **light depth map**: the nearest caster depth at each texel centre ([`crate::depth_map`]),
//!   the shadow map every other technique renders;
//! - **moments** (section 3.1): each texel stores the first two moments of depth, `M1 = d` and
//!   `M2 = d^2`, with `d` the depth above the scene's nearest light depth (a texel without a
//!   caster holds the scene's farthest depth, as a cleared depth buffer holds the far plane),
//!   then the moments are averaged over a `filter x filter` box of texels (section 3.2: the
//!   moments, unlike depths, can be filtered linearly; the box is
//!   [`crate::filtered_map::box_filter`], shared with the other filtered maps);
//! - **Chebyshev test** (section 3.1, equation 5): at the pixel centre's receiver depth `t`
//!   (minus the shared bias tolerance, [`crate::depth_test`], with the reach of the filter's
//!   half-width), `mu = M1`, `sigma^2 = max(M2 - M1^2, min_variance)`; lit when `t <= mu`,
//!   else the upper bound `p_max = sigma^2 / (sigma^2 + (t - mu)^2)`.
//!
//! Choices where the paper leaves them open: the moments are kept in `f64` (the paper stores
//! 16- or 32-bit floats; their precision is the subject of its section 4), and depths are
//! measured from the scene's nearest light depth so that `M2 - M1^2` does not cancel far from
//! the origin; the minimum variance is a fraction of the squared light depth range (the
//! paper's is an absolute constant of its depth range); no light-bleeding reduction (the paper
//! shows the bleeding, section 5; the reduction came later). With `filter = 1` and
//! `min_variance = 0` the test is the standard shadow map's (`sm`), which the tests check pixel
//! for pixel. Casters with opacity below 1 are treated as opaque, as by `sm`.

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

/// The least variance of the Chebyshev bound.
pub static MIN_VARIANCE: Param = Param {
    key: "min_variance",
    flag: "--min-variance",
    value_name: "V",
    help: "Least variance of `vsm`'s Chebyshev bound, as a fraction of the squared light depth \
           range, 0 to 1; default 1e-6.",
    kind: Kind::Real,
};

/// The method's entry in the registry's table.
pub const ENTRY: MethodEntry = MethodEntry {
    name: "vsm",
    description: "variance shadow map: box-filtered depth moments, Chebyshev's upper bound \
                  (Donnelly & Lauritzen 2006)",
    rates: Rates::None,
    params: &[
        &params::MAP_RES,
        &params::CONSTANT_BIAS,
        &params::SLOPE_BIAS,
        &params::MAX_SLOPE,
        &FILTER,
        &MIN_VARIANCE,
    ],
    stores_samples: None,
    cpu: |o| {
        let m = VarianceShadowMap {
            map: map(o)?,
            filter: o.count(FILTER.key, DEFAULT_FILTER),
            min_variance: o.real(MIN_VARIANCE.key, DEFAULT_MIN_VARIANCE),
        };
        m.validate()?;
        Ok(Box::new(m))
    },
    gpu: None,
};

/// The default minimum variance, as a fraction of the squared light depth range.
pub const DEFAULT_MIN_VARIANCE: f64 = 1e-6;

/// Name of the moments stage.
pub const STAGE_MOMENTS: &str = "moments";
/// Name of the Chebyshev test stage.
pub const STAGE_CHEBYSHEV: &str = "chebyshev test";

/// A variance shadow map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VarianceShadowMap {
    /// Map resolution and bias.
    pub map: MapOptions,
    /// Width of the box filter, in texels (odd).
    pub filter: u32,
    /// Least variance, as a fraction of the squared light depth range.
    pub min_variance: f64,
}

impl VarianceShadowMap {
    /// Checks the options; the error names the flag.
    pub fn validate(&self) -> Result<(), MethodError> {
        self.map.validate()?;
        check_filter(self.filter)?;
        if !(0.0..=1.0).contains(&self.min_variance) {
            return Err(MethodError::InvalidOption {
                option: MIN_VARIANCE.flag,
                message: format!("must be in [0, 1], got {}", self.min_variance),
            });
        }
        Ok(())
    }
}

/// The mean and mean square of depth at each texel, averaged over a `filter`-wide box
/// ([`box_filter`]), depths measured from `near`, texels without a caster at `far`.
fn moments(depth: &[f64], res: usize, filter: usize, near: f64, far: f64) -> Vec<[f64; 2]> {
    let raw: Vec<[f64; 2]> = depth
        .par_iter()
        .map(|&t| {
            let d = if t.is_finite() { t - near } else { far - near };
            [d, d * d]
        })
        .collect();
    box_filter(raw, res, filter)
}

impl ShadowMethod for VarianceShadowMap {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = self.map.params();
        m.insert(FILTER.key.into(), self.filter.into());
        m.insert(MIN_VARIANCE.key.into(), self.min_variance.into());
        m
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        self.validate()?;
        if frame.effects.transparency {
            rec.notes.push("vsm treats semi-transparent casters as opaque".into());
        }
        let map = frame.light_depth_map(self.map.map_res, rec);
        let (near, far) = frame.light_depth_bounds(&map.projector);
        let range = frame.light_depth_range(&map.projector);
        let res = map.res as usize;
        let filtered = rec
            .stages
            .time(STAGE_MOMENTS, || moments(&map.depth, res, self.filter as usize, near, far));
        let tester = DepthTester::new(&self.map, map.projector, range);
        rec.warnings.extend(tester.warnings(self.name(), frame, Sampling::PixelCentre));
        let reach = DVec2::splat(f64::from(self.filter) / 2.0);
        let min_variance = self.min_variance * range * range;
        let (lit, counters) = rec.stages.time(STAGE_CHEBYSHEV, || {
            filter_pixels(frame, &tester, |_, _, r| {
                let Some((x, y)) = texel_at(r.xy, map.res) else {
                    return PixelResult { lit: 1.0, ..Default::default() };
                };
                let [mu, m2] = filtered[y * res + x];
                let t = (r.depth - tester.tolerance(r, reach)) - near;
                let lit = if t <= mu {
                    1.0
                } else {
                    let variance = (m2 - mu * mu).max(min_variance);
                    let over = t - mu;
                    // 0 / 0 cannot arise: `over > 0`.
                    (variance / (variance + over * over)) as f32
                };
                PixelResult { lit, compares: 1, bilinear_lookups: 0 }
            })
        });
        rec.counters.merge(&counters);
        Ok(Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The box filter averages the moments and repeats the border; one texel is no filter.
    #[test]
    fn moments_are_box_filtered() {
        let depth = vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, f64::INFINITY];
        let m = moments(&depth, 3, 1, 1.0, 11.0);
        assert_eq!(m[0], [0.0, 0.0]);
        assert_eq!(m[8], [10.0, 100.0]);
        let f = moments(&depth, 3, 3, 1.0, 11.0);
        // Centre: the mean of all nine.
        let mean = (0.0 + 1.0 + 2.0 + 3.0 + 4.0 + 5.0 + 6.0 + 7.0 + 10.0) / 9.0;
        assert!((f[4][0] - mean).abs() < 1e-12, "{:?}", f[4]);
        // Corner: rows 0,0,1 and columns 0,0,1.
        let corner = (4.0 * 0.0 + 2.0 * 1.0 + 2.0 * 3.0 + 4.0) / 9.0;
        assert!((f[0][0] - corner).abs() < 1e-12, "{:?}", f[0]);
    }

    #[test]
    fn bad_options_name_the_flag() {
        let m = VarianceShadowMap { map: MapOptions::default(), filter: 4, min_variance: 0.0 };
        assert!(m.validate().expect_err("even").to_string().starts_with("--filter: "));
        let m = VarianceShadowMap { filter: 3, min_variance: f64::NAN, ..m };
        assert!(m.validate().expect_err("NaN").to_string().starts_with("--min-variance: "));
    }
}
