//! `vsm`: variance shadow maps (Donnelly and Lauritzen, "Variance Shadow Maps", ACM Symposium
//! on Interactive 3D Graphics and Games 2006), added as a method in one module and one table
//! entry ([`ENTRY`]); `docs/adding-a-method.md` walks through it.
//!
//! Stages, as the paper's section 3:
//! - **light depth map**: the nearest caster depth at each texel centre ([`crate::depth_map`]),
//!   the shadow map every other technique renders;
//! - **moments** (section 3.1): each texel stores the first two moments of depth, `M1 = z` and
//!   `M2 = z^2`, with `z` the depth normalised to [0, 1] over the scene's light depth range (a
//!   texel without a caster holds 1, as a cleared depth buffer holds the far plane),
//!   then the moments are averaged over a `filter x filter` box of texels (section 3.2: the
//!   moments, unlike depths, can be filtered linearly; the box is
//!   [`crate::filtered_map::box_filter`], shared with the other filtered maps);
//! - **Chebyshev test** (section 3.1, equation 5): at the pixel centre's receiver depth `t`
//!   (minus the shared bias tolerance, [`crate::depth_test`], with the reach of the filter's
//!   half-width), `mu = M1`, `sigma^2 = max(M2 - M1^2, min_variance)`; lit when `t <= mu`,
//!   else the upper bound `p_max = sigma^2 / (sigma^2 + (t - mu)^2)`.
//!
//! Choices where the paper leaves them open: the moments are kept in `f64` (the paper stores
//! 16- or 32-bit floats; their precision is the subject of its section 4), of depths
//! normalised over the scene's light depth range so that `M2 - M1^2` does not cancel far from
//! the origin; the minimum variance is in those units, a fraction of the squared light depth
//! range; the stages are [`crate::filtered_map::run`]'s; no light-bleeding reduction (the paper
//! shows the bleeding, section 5; the reduction came later). With `filter = 1` and
//! `min_variance = 0` the test is the standard shadow map's (`sm`), which the tests check pixel
//! for pixel. Casters with opacity below 1 are treated as opaque, as by `sm`.

use super::{map, Family, MethodEntry, Rates};
use crate::{
    depth_test::MapOptions,
    filtered_map::{self, check_filter, FilteredMap, DEFAULT_FILTER, FILTER},
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    params::{self, Kind, Param},
};
use instrumentation::Recorder;

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
    family: Family::Today,
    rates: Rates::None,
    params: params::map_and![&FILTER, &MIN_VARIANCE],
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

impl FilteredMap<2> for VarianceShadowMap {
    fn map(&self) -> &MapOptions {
        &self.map
    }

    fn filter(&self) -> u32 {
        self.filter
    }

    fn stages(&self) -> [&'static str; 2] {
        [STAGE_MOMENTS, STAGE_CHEBYSHEV]
    }

    fn store(&self, z: f64) -> [f64; 2] {
        [z, z * z]
    }

    fn test(&self, &[mu, m2]: &[f64; 2], z: f64) -> f64 {
        if z <= mu {
            return 1.0;
        }
        let variance = (m2 - mu * mu).max(self.min_variance);
        let over = z - mu;
        // 0 / 0 cannot arise: `over > 0`.
        variance / (variance + over * over)
    }
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
        filtered_map::run(self, frame, rec)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A texel stores the first two moments; at or in front of the mean the pixel is lit,
    /// behind a texel of one depth it is dark, behind a spread of depths it is Chebyshev's
    /// bound.
    #[test]
    fn the_test_is_chebyshevs_bound() {
        let m = VarianceShadowMap { map: MapOptions::default(), filter: 3, min_variance: 0.0 };
        assert_eq!(m.store(0.5), [0.5, 0.25]);
        assert_eq!(m.test(&[0.5, 0.25], 0.5), 1.0);
        assert_eq!(m.test(&[0.5, 0.25], 0.75), 0.0);
        // Depths 0.25 and 0.75 in equal parts: variance 1/16; at 1, (1/16) / (1/16 + 1/4).
        let two = [0.5, (0.0625 + 0.5625) / 2.0];
        assert!((m.test(&two, 1.0) - 0.2).abs() < 1e-12);
    }

    #[test]
    fn bad_options_name_the_flag() {
        let m = VarianceShadowMap { map: MapOptions::default(), filter: 4, min_variance: 0.0 };
        assert!(m.validate().expect_err("even").to_string().starts_with("--filter: "));
        let m = VarianceShadowMap { filter: 3, min_variance: f64::NAN, ..m };
        assert!(m.validate().expect_err("NaN").to_string().starts_with("--min-variance: "));
    }
}
