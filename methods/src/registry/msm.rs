//! `msm`: moment shadow maps (Peters and Klein, "Moment Shadow Mapping", ACM I3D 2015), a
//! method of the registry's table in one module, with the Hamburger four-moment
//! reconstruction.
//!
//! Stages, as the paper's sections 3 and 4:
//! - **light depth map**: the nearest caster depth at each texel centre ([`crate::depth_map`]);
//! - **moments**: each texel stores `b = (z, z^2, z^3, z^4)`, `z` the caster's depth normalised
//!   to [0, 1] over the scene's light depth range (1 without a caster), averaged over a
//!   `filter x filter` box ([`crate::filtered_map::box_filter`]);
//! - **Hamburger 4MSM**: at the pixel centre's receiver depth `z_f` (normalised the same way,
//!   minus the shared bias tolerance of [`crate::depth_test`] with the reach of the filter's
//!   half-width): the moments are pulled towards those of a uniform-ish distribution,
//!   `b' = (1 - alpha) b + alpha (0.5, 0.5, 0.5, 0.5)` (the moment bias); `c` solves
//!   `B c = (1, z_f, z_f^2)` for the Hankel matrix `B = [[1, b1, b2], [b1, b2, b3], [b2, b3, b4]]`
//!   by its Cholesky factors; the roots `z2 <= z3` of `c3 z^2 + c2 z + c1` with `z_f` are the
//!   support of the distribution that bounds the shadow from below, and the shadow intensity is
//!   0 for `z_f <= z2`, `(z_f z3 - b1 (z_f + z3) + b2) / ((z3 - z2) (z_f - z2))` for
//!   `z_f <= z3`, else `1 - (z2 z3 - b1 (z2 + z3) + b2) / ((z_f - z2) (z_f - z3))`; lit is one
//!   minus it, clamped to [0, 1] (the stages are [`crate::filtered_map::run`]'s).
//!
//! Choices where the paper leaves them open: the moments are kept in `f64` (the paper
//! quantizes them to 16 or 32 bits with an optimized basis, section 4, and tunes `alpha` to
//! that precision; `--moment-bias` defaults to 3e-5); where the reconstruction is not finite
//! (a degenerate quadratic the bias did not lift), the pixel takes the standard shadow map's
//! test against the mean depth `b1`, so every value is finite. With a one-texel filter the
//! result approaches the standard shadow map's: the tests check how close. Casters with
//! opacity below 1 are treated as opaque.

use super::{map, Family, MethodEntry, Rates};
use crate::{
    depth_test::MapOptions,
    filtered_map::{self, check_filter, FilteredMap, DEFAULT_FILTER, FILTER},
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    params::{self, Kind, Param},
};
use instrumentation::Recorder;

/// The moment bias `alpha`.
pub static MOMENT_BIAS: Param = Param {
    key: "moment_bias",
    flag: "--moment-bias",
    value_name: "A",
    help: "The moment bias alpha of moment shadow maps (`msm`): the stored moments are pulled \
           by alpha towards (0.5, 0.5, 0.5, 0.5) before the reconstruction, 0 to 1; default 3e-5.",
    kind: Kind::Real,
};

/// The method's entry in the registry's table.
pub const ENTRY: MethodEntry = MethodEntry {
    name: "msm",
    description: "moment shadow map: four box-filtered depth moments, Hamburger reconstruction \
                  (Peters & Klein 2015)",
    family: Family::Today,
    rates: Rates::None,
    params: params::map_and![&FILTER, &MOMENT_BIAS],
    stores_samples: None,
    cpu: |o| {
        let m = MomentShadowMap {
            map: map(o)?,
            filter: o.count(FILTER.key, DEFAULT_FILTER),
            moment_bias: o.real(MOMENT_BIAS.key, DEFAULT_MOMENT_BIAS),
        };
        m.validate()?;
        Ok(Box::new(m))
    },
    gpu: None,
};

/// The default moment bias.
pub const DEFAULT_MOMENT_BIAS: f64 = 3e-5;

/// Name of the moments stage.
pub const STAGE_MOMENTS: &str = "moments";
/// Name of the reconstruction stage.
pub const STAGE_HAMBURGER: &str = "hamburger reconstruction";

/// A moment shadow map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MomentShadowMap {
    /// Map resolution and bias.
    pub map: MapOptions,
    /// Width of the box filter, in texels (odd).
    pub filter: u32,
    /// The moment bias `alpha`.
    pub moment_bias: f64,
}

impl MomentShadowMap {
    /// Checks the options; the error names the flag.
    pub fn validate(&self) -> Result<(), MethodError> {
        self.map.validate()?;
        check_filter(self.filter)?;
        if !(0.0..=1.0).contains(&self.moment_bias) {
            return Err(MethodError::InvalidOption {
                option: MOMENT_BIAS.flag,
                message: format!("must be in [0, 1], got {}", self.moment_bias),
            });
        }
        Ok(())
    }
}

/// The shadow intensity of the Hamburger four-moment reconstruction (see the module
/// documentation) of the moments `b` at depth `zf` with moment bias `alpha`; `None` where it
/// is not finite.
fn hamburger(b: [f64; 4], zf: f64, alpha: f64) -> Option<f64> {
    let b = b.map(|m| (1.0 - alpha) * m + alpha * 0.5);
    // Cholesky factors of B = [[1, b1, b2], [b1, b2, b3], [b2, b3, b4]] (L with unit diagonal
    // scaled: B = L D L^T), then B c = (1, zf, zf^2) by forward and back substitution.
    let (l21, l31) = (b[0], b[1]);
    let d22 = b[1] - b[0] * b[0];
    let l32 = (b[2] - b[0] * b[1]) / d22;
    let d33 = b[3] - b[1] * b[1] - l32 * l32 * d22;
    let y1 = 1.0;
    let y2 = zf - l21 * y1;
    let y3 = zf * zf - l31 * y1 - l32 * y2;
    let c3 = y3 / d33;
    let c2 = y2 / d22 - l32 * c3;
    let c1 = y1 - l21 * c2 - l31 * c3;
    // The roots of c3 z^2 + c2 z + c1.
    let disc = (c2 * c2 - 4.0 * c3 * c1).max(0.0).sqrt();
    let (r1, r2) = ((-c2 - disc) / (2.0 * c3), (-c2 + disc) / (2.0 * c3));
    let (z2, z3) = if r1 <= r2 { (r1, r2) } else { (r2, r1) };
    let g = if zf <= z2 {
        0.0
    } else if zf <= z3 {
        (zf * z3 - b[0] * (zf + z3) + b[1]) / ((z3 - z2) * (zf - z2))
    } else {
        1.0 - (z2 * z3 - b[0] * (z2 + z3) + b[1]) / ((zf - z2) * (zf - z3))
    };
    g.is_finite().then_some(g)
}

impl FilteredMap<4> for MomentShadowMap {
    fn map(&self) -> &MapOptions {
        &self.map
    }

    fn filter(&self) -> u32 {
        self.filter
    }

    fn stages(&self) -> [&'static str; 2] {
        [STAGE_MOMENTS, STAGE_HAMBURGER]
    }

    fn store(&self, z: f64) -> [f64; 4] {
        let z2 = z * z;
        [z, z2, z2 * z, z2 * z2]
    }

    fn test(&self, b: &[f64; 4], z: f64) -> f64 {
        let shadow = hamburger(*b, z, self.moment_bias).unwrap_or(if z > b[0] { 1.0 } else { 0.0 });
        1.0 - shadow
    }
}

impl ShadowMethod for MomentShadowMap {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = self.map.params();
        m.insert(FILTER.key.into(), self.filter.into());
        m.insert(MOMENT_BIAS.key.into(), self.moment_bias.into());
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

    fn of(depths: &[f64]) -> [f64; 4] {
        let n = depths.len() as f64;
        let mut b = [0.0; 4];
        for &z in depths {
            for (k, m) in b.iter_mut().enumerate() {
                *m += z.powi(k as i32 + 1) / n;
            }
        }
        b
    }

    /// In front of every caster the shadow is 0; far behind all of them it is nearly 1; behind
    /// half of two casters it lies between, bounded by the half the casters cover.
    #[test]
    fn the_reconstruction_bounds_the_shadow() {
        let alpha = DEFAULT_MOMENT_BIAS;
        let one = of(&[0.5]);
        assert_eq!(hamburger(one, 0.2, alpha), Some(0.0));
        let behind = hamburger(one, 0.9, alpha).expect("finite");
        assert!(behind > 0.99 && behind <= 1.0, "{behind}");
        let two = of(&[0.3, 0.7]);
        let between = hamburger(two, 0.5, alpha).expect("finite");
        assert!((0.0..=0.5 + 1e-9).contains(&between), "{between}");
        assert!(hamburger(two, 0.95, alpha).expect("finite") > between);
    }

    #[test]
    fn bad_options_name_the_flag() {
        let m = MomentShadowMap { map: MapOptions::default(), filter: 3, moment_bias: -1.0 };
        assert!(m.validate().expect_err("negative").to_string().starts_with("--moment-bias: "));
        let m = MomentShadowMap { moment_bias: 1e-5, filter: 0, ..m };
        assert!(m.validate().expect_err("even").to_string().starts_with("--filter: "));
    }
}
