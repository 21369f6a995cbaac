//! `vsm`: variance shadow maps (Donnelly and Lauritzen, "Variance Shadow Maps", ACM Symposium
//! on Interactive 3D Graphics and Games 2006), added as a method in one module (with its WGSL
//! beside it, `vsm.wgsl`) and one table entry ([`ENTRY`]); `docs/adding-a-method.md` walks
//! through it.
//!
//! Stages, as the paper's section 3:
//! - **light depth map**: the nearest caster depth at each texel centre ([`crate::depth_map`]),
//!   the shadow map every other technique renders;
//! - **moments** (section 3.1): each texel stores the first two moments of depth, `M1 = z` and
//!   `M2 = z^2`, with `z` the depth normalised to [0, 1] over the scene's light depth range (a
//!   texel without a caster holds 1, as a cleared depth buffer holds the far plane), computed
//!   in `f64` and rounded to the storage precision (`--precision`, section 4: `f32` by
//!   default, the paper's 32-bit floats; `f16`, whose numeric trouble the paper discusses; `f64`,
//!   no rounding), then averaged over a `filter x filter` box of texels (section 3.2: the
//!   moments, unlike depths, can be filtered linearly; the box is
//!   [`crate::filtered_map::box_filter`], shared with the other filtered maps, summing the
//!   stored values in `f64`);
//! - **Chebyshev test** (section 3.1, equation 5): at the pixel centre's receiver depth `t`
//!   (minus the shared bias tolerance, [`crate::depth_test`], with the reach of the filter's
//!   half-width), `mu = M1`, `sigma^2 = max(M2 - M1^2, min_variance)`; lit when `t <= mu`,
//!   else the upper bound `p_max = sigma^2 / (sigma^2 + (t - mu)^2)`, remapped by the
//!   light-bleeding reduction `clamp((p_max - A) / (1 - A), 0, 1)` (`--bleeding-reduction A`,
//!   default 0: off; Lauritzen and McCool, "Layered Variance Shadow Maps", GI 2008, and GPU
//!   Gems 3, chapter 8: the paper shows the bleeding, section 5, the reduction came later).
//!
//! Choices where the paper leaves them open: depths are normalised over the scene's light
//! depth range so that `M2 - M1^2` does not cancel far from the origin; the minimum variance is
//! in those units, a fraction of the squared light depth range; the stages are
//! [`crate::filtered_map::run`]'s. With `filter = 1`, `min_variance = 0` and `f64` storage the
//! test is the standard shadow map's (`sm`), which the tests check pixel for pixel; at `f32`
//! the rounding of `M2` leaves a variance of rounding size (about `2^-25`), under which the
//! bound behind a caster is small but not 0. Casters with opacity below 1 are treated as
//! opaque, as by `sm`.
//!
//! On the GPU (`--device gpu`, [`crate::gpu::filtered`]) the same stages run as compute kernels
//! with `vsm.wgsl`'s `store` and `test`, the twins of this module's, in `f64`.

use super::{gpu, map, Build, Family, MethodEntry, Rates};
use crate::{
    depth_test::MapOptions,
    filtered_map::{
        self, check_bleeding_reduction, check_filter, reduce_bleeding, FilteredMap, Precision,
        BLEEDING_REDUCTION, DEFAULT_FILTER, FILTER, PRECISION,
    },
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    params::{self, Kind, MethodOptions, Param},
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
    params: params::map_and![&FILTER, &PRECISION, &MIN_VARIANCE, &BLEEDING_REDUCTION],
    stores_samples: None,
    cpu: |o| Ok(Box::new(build(o)?)),
    gpu: gpu!(|o| Ok(Box::new(crate::gpu::filtered::GpuFilteredMap::<2, _> { twin: build(o)? }))),
};

/// The map the options give, validated.
fn build(o: &MethodOptions) -> Result<VarianceShadowMap, MethodError> {
    let m = VarianceShadowMap {
        map: map(o)?,
        filter: o.count(FILTER.key, DEFAULT_FILTER),
        precision: Precision::given(o, DEFAULT_PRECISION),
        min_variance: o.real(MIN_VARIANCE.key, DEFAULT_MIN_VARIANCE),
        bleeding_reduction: o.real(BLEEDING_REDUCTION.key, 0.0),
    };
    m.validate()?;
    Ok(m)
}

/// The default minimum variance, as a fraction of the squared light depth range.
pub const DEFAULT_MIN_VARIANCE: f64 = 1e-6;
/// The default storage precision (the paper's 32-bit floats).
pub const DEFAULT_PRECISION: Precision = Precision::F32;
/// The precisions the moments are stored at.
pub const PRECISIONS: [Precision; 3] = [Precision::F16, Precision::F32, Precision::F64];

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
    /// The precision the moments are stored at (f16, f32 or f64).
    pub precision: Precision,
    /// Least variance, as a fraction of the squared light depth range.
    pub min_variance: f64,
    /// The light-bleeding reduction `A` (0: off).
    pub bleeding_reduction: f64,
}

impl FilteredMap<2> for VarianceShadowMap {
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
        [STAGE_MOMENTS, STAGE_CHEBYSHEV]
    }

    fn validate(&self) -> Result<(), MethodError> {
        self.map.validate()?;
        check_filter(self.filter)?;
        self.precision.check(ENTRY.name, &PRECISIONS)?;
        if !(0.0..=1.0).contains(&self.min_variance) {
            return Err(MethodError::InvalidOption {
                option: MIN_VARIANCE.flag,
                message: format!("must be in [0, 1], got {}", self.min_variance),
            });
        }
        check_bleeding_reduction(self.bleeding_reduction)
    }

    fn store(&self, z: f64) -> [f64; 2] {
        [self.precision.round(z), self.precision.round(z * z)]
    }

    fn test(&self, &[mu, m2]: &[f64; 2], z: f64) -> f64 {
        if z <= mu {
            return 1.0;
        }
        let d = m2 - mu * mu;
        let variance = if d > self.min_variance { d } else { self.min_variance };
        if variance.is_nan() || variance <= 0.0 {
            // No spread behind a caster: the bound is 0.
            return 0.0;
        }
        let over = z - mu;
        reduce_bleeding(variance / (variance + over * over), self.bleeding_reduction)
    }

    fn wgsl(&self) -> &'static str {
        include_str!("vsm.wgsl")
    }

    fn wgsl_params(&self) -> [f64; 4] {
        [self.min_variance, self.bleeding_reduction, 0.0, 0.0]
    }
}

impl ShadowMethod for VarianceShadowMap {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = self.map.params();
        m.insert(FILTER.key.into(), self.filter.into());
        m.insert(PRECISION.key.into(), self.precision.name().into());
        m.insert(MIN_VARIANCE.key.into(), self.min_variance.into());
        m.insert(BLEEDING_REDUCTION.key.into(), self.bleeding_reduction.into());
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

    fn at(precision: Precision) -> VarianceShadowMap {
        VarianceShadowMap {
            map: MapOptions::default(),
            filter: 3,
            precision,
            min_variance: 0.0,
            bleeding_reduction: 0.0,
        }
    }

    /// A texel stores the first two moments; at or in front of the mean the pixel is lit,
    /// behind a texel of one depth it is dark, behind a spread of depths it is Chebyshev's
    /// bound.
    #[test]
    fn the_test_is_chebyshevs_bound() {
        let m = at(Precision::F64);
        assert_eq!(m.store(0.5), [0.5, 0.25]);
        assert_eq!(m.test(&[0.5, 0.25], 0.5), 1.0);
        assert_eq!(m.test(&[0.5, 0.25], 0.75), 0.0);
        // Depths 0.25 and 0.75 in equal parts: variance 1/16; at 1, (1/16) / (1/16 + 1/4).
        let two = [0.5, (0.0625 + 0.5625) / 2.0];
        assert!((m.test(&two, 1.0) - 0.2).abs() < 1e-12);
        // With the reduction 0.1: (0.2 - 0.1) / 0.9.
        let reduced = VarianceShadowMap { bleeding_reduction: 0.1, ..m };
        assert!((reduced.test(&two, 1.0) - 0.1 / 0.9).abs() < 1e-12);
        assert_eq!(reduced.test(&two, 0.4), 1.0, "in front of the mean: lit, not remapped");
    }

    /// The moments are rounded to the precision when stored; a third of a unit survives only
    /// in `f64`.
    #[test]
    fn moments_are_stored_at_the_precision() {
        let z = 1.0 / 3.0;
        assert_eq!(at(Precision::F64).store(z), [z, z * z]);
        assert_eq!(at(Precision::F32).store(z), [f64::from(z as f32), f64::from((z * z) as f32)]);
        let [m1, m2] = at(Precision::F16).store(z);
        assert_eq!(m1, Precision::F16.round(z));
        assert!((m1 - z).abs() < 2e-4 && (m2 - z * z).abs() < 1e-4 && m1 != z);
    }

    #[test]
    fn bad_options_name_the_flag() {
        let m = VarianceShadowMap { filter: 4, ..at(Precision::F32) };
        assert!(m.validate().expect_err("even").to_string().starts_with("--filter: "));
        let m = VarianceShadowMap { filter: 3, min_variance: f64::NAN, ..m };
        assert!(m.validate().expect_err("NaN").to_string().starts_with("--min-variance: "));
        let m = VarianceShadowMap { min_variance: 0.0, precision: Precision::U16, ..m };
        assert!(m.validate().expect_err("u16").to_string().starts_with("--precision: "));
        let m = VarianceShadowMap { precision: Precision::F16, bleeding_reduction: 1.0, ..m };
        let e = m.validate().expect_err("1").to_string();
        assert!(e.starts_with("--bleeding-reduction: "), "{e}");
    }
}
