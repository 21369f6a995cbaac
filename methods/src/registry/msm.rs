//! `msm`: moment shadow maps (Peters and Klein, "Moment Shadow Mapping", ACM I3D 2015), a
//! method of the registry's table in one module (its WGSL beside it, `msm.wgsl`), with the
//! Hamburger four-moment reconstruction.
//!
//! Stages, as the paper's sections 3 and 4:
//! - **light depth map**: the nearest caster depth at each texel centre ([`crate::depth_map`]);
//! - **moments**: each texel stores `b = (z, z^2, z^3, z^4)`, `z` the caster's depth normalised
//!   to [0, 1] over the scene's light depth range (1 without a caster), computed in `f64` and
//!   stored at the precision of `--precision`: `u16` by default, the paper's 64 bits per texel
//!   (section 4.3, optimized moment quantization): `b` taken to the optimized basis by the
//!   paper's 4x4 matrix and offset ([`FORWARD`], [`OFFSET`]), each of the four rounded to a
//!   16-bit unsigned normalized value; `f32`, four 32-bit floats of `b` (128 bits, no basis
//!   change); `f64`, no rounding. The stored values are averaged over a `filter x filter` box
//!   ([`crate::filtered_map::box_filter`], summing them in `f64`), and at `u16` the basis
//!   change is undone after the filter by the paper's inverse matrix ([`INVERSE`]), before
//!   the reconstruction;
//! - **Hamburger 4MSM** (section 4.1): at the pixel centre's receiver depth
//!   `z_f` (normalised the same way, minus the shared bias tolerance of [`crate::depth_test`]
//!   with the reach of the filter's half-width): the moments are pulled towards those of a
//!   uniform-ish distribution, `b' = (1 - alpha) b + alpha (0.5, 0.5, 0.5, 0.5)` (the moment
//!   bias); `c` solves `B c = (1, z_f, z_f^2)` for the Hankel matrix
//!   `B = [[1, b1, b2], [b1, b2, b3], [b2, b3, b4]]` by its Cholesky factors; the roots
//!   `z2 <= z3` of `c3 z^2 + c2 z + c1` with `z_f` are the support of the distribution that
//!   bounds the shadow from below, and the shadow intensity is 0 for `z_f <= z2`,
//!   `(z_f z3 - b1 (z_f + z3) + b2) / ((z3 - z2) (z_f - z2))` for `z_f <= z3`, else
//!   `1 - (z2 z3 - b1 (z2 + z3) + b2) / ((z_f - z2) (z_f - z3))`; lit is one minus it, remapped
//!   by the light-bleeding reduction `clamp((lit - A) / (1 - A), 0, 1)` (`--bleeding-reduction
//!   A`, default 0: off; the paper's remap of the lower bound, after Lauritzen and McCool), and
//!   clamped to [0, 1] (the stages are [`crate::filtered_map::run`]'s).
//!
//! The moment bias `alpha` must cover the rounding of the stored moments, so its default
//! follows the precision when `--moment-bias` is not given: 6e-5 at `u16` and 3e-7 at `f32`,
//! the paper's values for its 64-bit optimized quantization and for 32-bit floats, and 3e-5 at
//! `f64` (this module's default before the precision was a parameter, so that earlier runs are
//! those at `f64`; without rounding the bias only keeps the Hankel matrix of a single depth
//! invertible, which far smaller values do too).
//!
//! Choices where the paper leaves them open: where the reconstruction is not finite (a
//! degenerate quadratic the bias did not lift), the pixel takes the standard shadow map's test
//! against the mean depth `b1`, so every value is finite. With a one-texel filter the result
//! approaches the standard shadow map's: the tests check how close. Casters with opacity
//! below 1 are treated as opaque.

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

/// The moment bias `alpha`.
pub static MOMENT_BIAS: Param = Param {
    key: "moment_bias",
    flag: "--moment-bias",
    value_name: "A",
    help: "The moment bias alpha of moment shadow maps (`msm`): the stored moments are pulled \
           by alpha towards (0.5, 0.5, 0.5, 0.5) before the reconstruction, 0 to 1; default by \
           --precision: 6e-5 at u16, 3e-7 at f32 (the paper's), 3e-5 at f64.",
    kind: Kind::Real,
};

/// The method's entry in the registry's table.
pub const ENTRY: MethodEntry = MethodEntry {
    name: "msm",
    description: "moment shadow map: four box-filtered depth moments, Hamburger reconstruction \
                  (Peters & Klein 2015)",
    family: Family::Today,
    rates: Rates::None,
    params: params::map_and![&FILTER, &PRECISION, &MOMENT_BIAS, &BLEEDING_REDUCTION],
    stores_samples: None,
    cpu: |o| Ok(Box::new(build(o)?)),
    gpu: gpu!(|o| Ok(Box::new(crate::gpu::filtered::GpuFilteredMap::<4, _> { twin: build(o)? }))),
};

/// The map the options give, validated.
fn build(o: &MethodOptions) -> Result<MomentShadowMap, MethodError> {
    let precision = Precision::given(o, DEFAULT_PRECISION);
    let m = MomentShadowMap {
        map: map(o)?,
        filter: o.count(FILTER.key, DEFAULT_FILTER),
        precision,
        moment_bias: o.real(MOMENT_BIAS.key, default_moment_bias(precision)),
        bleeding_reduction: o.real(BLEEDING_REDUCTION.key, 0.0),
    };
    m.validate()?;
    Ok(m)
}

/// The default storage precision (the paper's 64 bits per texel).
pub const DEFAULT_PRECISION: Precision = Precision::U16;
/// The precisions the moments are stored at.
pub const PRECISIONS: [Precision; 3] = [Precision::U16, Precision::F32, Precision::F64];

/// The default moment bias at `precision` (see the module documentation).
pub fn default_moment_bias(precision: Precision) -> f64 {
    match precision {
        Precision::U16 => 6e-5,
        Precision::F32 | Precision::F16 => 3e-7,
        Precision::F64 => 3e-5,
    }
}

/// The optimized moment basis (Peters and Klein 2015, section 4.3): stored `o = b M + OFFSET`
/// for the row vector `b = (z, z^2, z^3, z^4)`, `M[i][j]` row `i`, column `j`.
pub const FORWARD: [[f64; 4]; 4] = [
    [-2.07224649, 13.7948857237, 0.105877704, 9.7924062118],
    [32.23703778, -59.4683975703, -1.9077466311, -33.7652110555],
    [-68.571074599, 82.0359750338, 9.3496555107, 47.9456096605],
    [39.3703274134, -35.364903257, -6.6543490743, -23.9728048165],
];
/// The offset of the optimized basis's first value.
pub const OFFSET: f64 = 0.035955884801;
/// The paper's inverse of [`FORWARD`] (to the rounding of its ten digits): `b = (o - OFFSET) M'`.
pub const INVERSE: [[f64; 4]; 4] = [
    [0.2227744146, 0.1549679261, 0.1451988946, 0.163127443],
    [0.0771972861, 0.1394629426, 0.2120202157, 0.2591432266],
    [0.7926986636, 0.7963415838, 0.7258694464, 0.6539092497],
    [0.0319417555, -0.1722823173, -0.2758014811, -0.3376131734],
];

/// The row vector `v` times the matrix `m`, each column summed in row order.
fn times(v: [f64; 4], m: &[[f64; 4]; 4]) -> [f64; 4] {
    std::array::from_fn(|j| v[0] * m[0][j] + v[1] * m[1][j] + v[2] * m[2][j] + v[3] * m[3][j])
}

/// The moments `b` in the optimized basis.
pub fn to_optimized(b: [f64; 4]) -> [f64; 4] {
    let mut o = times(b, &FORWARD);
    o[0] += OFFSET;
    o
}

/// The moments of values `o` in the optimized basis.
pub fn from_optimized(o: [f64; 4]) -> [f64; 4] {
    times([o[0] - OFFSET, o[1], o[2], o[3]], &INVERSE)
}

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
    /// The precision the moments are stored at (u16 in the optimized basis, f32 or f64).
    pub precision: Precision,
    /// The moment bias `alpha`.
    pub moment_bias: f64,
    /// The light-bleeding reduction `A` (0: off).
    pub bleeding_reduction: f64,
}

/// The shadow intensity of the Hamburger four-moment reconstruction (see the module
/// documentation) of the moments `b` at depth `zf` with moment bias `alpha`; `None` where it
/// is not finite. Every operation is written out in the order `msm.wgsl` repeats.
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
    // The roots of c3 z^2 + c2 z + c1 (a negative or NaN discriminant as 0).
    let q = c2 * c2 - 4.0 * c3 * c1;
    let disc = if q > 0.0 { q.sqrt() } else { 0.0 };
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

    fn precision(&self) -> Precision {
        self.precision
    }

    fn stages(&self) -> [&'static str; 2] {
        [STAGE_MOMENTS, STAGE_HAMBURGER]
    }

    fn validate(&self) -> Result<(), MethodError> {
        self.map.validate()?;
        check_filter(self.filter)?;
        self.precision.check(ENTRY.name, &PRECISIONS)?;
        if !(0.0..=1.0).contains(&self.moment_bias) {
            return Err(MethodError::InvalidOption {
                option: MOMENT_BIAS.flag,
                message: format!("must be in [0, 1], got {}", self.moment_bias),
            });
        }
        check_bleeding_reduction(self.bleeding_reduction)
    }

    fn store(&self, z: f64) -> [f64; 4] {
        let z2 = z * z;
        let b = [z, z2, z2 * z, z2 * z2];
        match self.precision {
            Precision::U16 => to_optimized(b).map(|v| self.precision.round(v)),
            _ => b.map(|v| self.precision.round(v)),
        }
    }

    fn test(&self, v: &[f64; 4], z: f64) -> f64 {
        let b = match self.precision {
            Precision::U16 => from_optimized(*v),
            _ => *v,
        };
        let shadow = hamburger(b, z, self.moment_bias).unwrap_or(if z > b[0] { 1.0 } else { 0.0 });
        reduce_bleeding(1.0 - shadow, self.bleeding_reduction)
    }

    fn wgsl(&self) -> &'static str {
        include_str!("msm.wgsl")
    }

    fn wgsl_params(&self) -> [f64; 4] {
        [self.moment_bias, self.bleeding_reduction, 0.0, 0.0]
    }
}

impl ShadowMethod for MomentShadowMap {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = self.map.params();
        m.insert(FILTER.key.into(), self.filter.into());
        m.insert(PRECISION.key.into(), self.precision.name().into());
        m.insert(MOMENT_BIAS.key.into(), self.moment_bias.into());
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

    fn at(precision: Precision) -> MomentShadowMap {
        MomentShadowMap {
            map: MapOptions::default(),
            filter: 3,
            precision,
            moment_bias: default_moment_bias(precision),
            bleeding_reduction: 0.0,
        }
    }

    /// In front of every caster the shadow is 0; far behind all of them it is nearly 1; behind
    /// half of two casters it lies between, bounded by the half the casters cover.
    #[test]
    fn the_reconstruction_bounds_the_shadow() {
        let alpha = default_moment_bias(Precision::F64);
        let one = of(&[0.5]);
        assert_eq!(hamburger(one, 0.2, alpha), Some(0.0));
        let behind = hamburger(one, 0.9, alpha).expect("finite");
        assert!(behind > 0.99 && behind <= 1.0, "{behind}");
        let two = of(&[0.3, 0.7]);
        let between = hamburger(two, 0.5, alpha).expect("finite");
        assert!((0.0..=0.5 + 1e-9).contains(&between), "{between}");
        assert!(hamburger(two, 0.95, alpha).expect("finite") > between);
    }

    /// The paper's inverse undoes its basis to the rounding of its ten digits, the basis takes
    /// the moments of every depth in [0, 1] into [0, 1] (so 16-bit unsigned normalized values
    /// hold them), and the offset puts depth 0 at the origin.
    #[test]
    fn the_optimized_basis_is_inverted_to_rounding() {
        let mut worst = 0.0f64;
        for k in 0..=1000 {
            let z = f64::from(k) / 1000.0;
            let b = [z, z * z, z.powi(3), z.powi(4)];
            let o = to_optimized(b);
            assert!(o.iter().all(|v| (-1e-9..=1.0 + 1e-9).contains(v)), "z {z}: {o:?}");
            let back = from_optimized(o);
            for (x, y) in back.iter().zip(b) {
                worst = worst.max((x - y).abs());
            }
        }
        assert!(worst < 1e-8, "{worst}");
        assert_eq!(to_optimized([0.0; 4]), [OFFSET, 0.0, 0.0, 0.0]);
        assert_eq!(from_optimized([OFFSET, 0.0, 0.0, 0.0]), [0.0; 4]);
    }

    /// At `u16` a texel stores the optimized values rounded to 1/65535, which the test maps
    /// back to moments within the rounding's reach; at `f32` it stores the moments rounded.
    #[test]
    fn moments_are_stored_at_the_precision() {
        let z = 0.3;
        let b = [z, z * z, z * z * z, z * z * (z * z)];
        let stored = at(Precision::U16).store(z);
        for v in stored {
            let k = v * 65535.0;
            assert!((k - k.round()).abs() < 1e-6, "{v} is not a 16-bit code");
        }
        let back = from_optimized(stored);
        for (x, y) in back.iter().zip(b) {
            // Half a code through the inverse's largest row sum, about 1.6 / 65535.
            assert!((x - y).abs() < 2e-5, "{back:?} vs {b:?}");
        }
        assert_eq!(at(Precision::F32).store(z), b.map(|v| f64::from(v as f32)));
        assert_eq!(at(Precision::F64).store(z), b);
        // One depth behind, at each precision: dark; in front: lit.
        for p in PRECISIONS {
            let m = at(p);
            assert!(m.test(&m.store(0.3), 0.8) < 0.01, "{}", p.name());
            assert!(m.test(&m.store(0.6), 0.2) > 0.99, "{}", p.name());
        }
    }

    /// The bleeding reduction remaps the lit value of the lower bound: between two casters it
    /// darkens; in front of both it stays lit.
    #[test]
    fn bleeding_reduction_remaps_the_lit_value() {
        let m = at(Precision::F64);
        let two = of(&[0.3, 0.7]);
        let lit = m.test(&two, 0.5);
        let reduced = MomentShadowMap { bleeding_reduction: 0.25, ..m };
        assert!((reduced.test(&two, 0.5) - (lit - 0.25) / 0.75).abs() < 1e-12, "{lit}");
        assert_eq!(reduced.test(&two, 0.1), 1.0);
    }

    #[test]
    fn the_default_bias_follows_the_precision() {
        let o = MethodOptions::default();
        assert_eq!(build(&o).expect("builds").moment_bias, 6e-5);
        let mut o = MethodOptions::default();
        o.set(&PRECISION, PRECISION.parse("f32").expect("listed"));
        assert_eq!(build(&o).expect("builds").moment_bias, 3e-7);
        o.set(&MOMENT_BIAS, params::Value::Real(1e-4));
        assert_eq!(build(&o).expect("builds").moment_bias, 1e-4);
    }

    #[test]
    fn bad_options_name_the_flag() {
        let m = MomentShadowMap { moment_bias: -1.0, ..at(Precision::U16) };
        assert!(m.validate().expect_err("negative").to_string().starts_with("--moment-bias: "));
        let m = MomentShadowMap { moment_bias: 1e-5, filter: 0, ..m };
        assert!(m.validate().expect_err("even").to_string().starts_with("--filter: "));
        let m = MomentShadowMap { filter: 3, precision: Precision::F16, ..m };
        assert!(m.validate().expect_err("f16").to_string().starts_with("--precision: "));
        let m = MomentShadowMap { precision: Precision::F32, bleeding_reduction: -0.5, ..m };
        let e = m.validate().expect_err("negative").to_string();
        assert!(e.starts_with("--bleeding-reduction: "), "{e}");
    }
}
