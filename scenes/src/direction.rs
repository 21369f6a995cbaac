//! One robust normalisation of directions, used wherever a direction given by a user (a light's
//! `direction`, a camera's `target - eye`) or computed from geometry becomes a unit vector.
//!
//! `glam`'s `normalize` squares the components: a direction of magnitude 1e154 overflows to
//! infinity and one of 1e-170 underflows to zero, so a light that is perfectly well defined
//! would be refused by one path and turned into NaN by another. [`unit()`] first divides by the
//! largest component's magnitude (exact up to one rounding per component, never overflowing),
//! then normalises a vector whose largest component is 1.

use glam::DVec3;

/// The unit vector along `v`, or `None` when `v` is zero or has a non-finite component.
/// Any finite non-zero `v`, however large or small (subnormal included), has one.
pub fn unit(v: DVec3) -> Option<DVec3> {
    if !v.is_finite() {
        return None;
    }
    let m = v.abs().max_element();
    if m == 0.0 {
        return None;
    }
    let u = v / m;
    // `u` has a component of magnitude 1, so its length is in [1, sqrt(3)].
    Some(u / u.length())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_finite_non_zero_magnitude_has_a_direction() {
        let d = DVec3::new(-0.3, -1.0, -0.2);
        let want = d.normalize();
        for scale in [1e-300, 1e-170, 1e-20, 1.0, 1e20, 1e154, 1e300, f64::MAX / 2.0] {
            let got = unit(d * scale).expect("a direction");
            assert!((got - want).length() < 1e-15, "scale {scale}: {got}");
        }
        // Subnormal: components exact in a few bits, scaled by powers of two.
        let d = DVec3::new(-0.5, -1.0, -0.25);
        for k in [-1070, -1060, -1030] {
            let got = unit(d * 2f64.powi(k)).expect("a direction");
            assert!((got - d.normalize()).length() < 1e-15, "2^{k}: {got}");
        }
        assert_eq!(unit(DVec3::new(0.0, -f64::MAX, 0.0)), Some(DVec3::NEG_Y));
    }

    #[test]
    fn zero_and_non_finite_have_none() {
        assert_eq!(unit(DVec3::ZERO), None);
        assert_eq!(unit(DVec3::new(f64::NAN, 1.0, 0.0)), None);
        assert_eq!(unit(DVec3::new(f64::INFINITY, 1.0, 0.0)), None);
    }
}
