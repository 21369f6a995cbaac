//! Tracks of keys and how they are interpolated: piecewise between consecutive keys, the first
//! value held before the first key and the last after the last; at a key's time the key's own
//! value, bit for bit. Points and scalars by linear interpolation, directions by spherical
//! linear interpolation (slerp) of unit vectors, rotations by slerp of unit quaternions.

use crate::camera::Camera;
use crate::direction::unit;
use crate::light::Light;
use glam::{DQuat, DVec3};
use std::f64::consts::PI;

/// Two unit directions whose angle is within this many radians of pi are taken as opposite:
/// the turn between them has no unique path (exactly opposite), or one that rounding decides
/// (nearly so: slerp divides by the sine of the angle). Consecutive keys of a direction, and
/// consecutive views of a camera or a spot light, must turn by less.
pub const OPPOSITE_TOLERANCE: f64 = 1e-6;

/// Below this angle (radians) two directions are interpolated linearly and normalised, which
/// agrees with slerp to rounding there and never divides by a vanishing sine.
const SMALL_ANGLE: f64 = 1e-6;

/// One key of a track: a time and the value the track has then.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Key<T> {
    /// The key's time.
    pub(crate) time: f64,
    /// The value at that time.
    pub(crate) value: T,
}

/// A value that can be interpolated between two keys.
pub(crate) trait Blend: Clone {
    /// The value a fraction `s` in (0, 1) of the way from `a` to `b`.
    fn blend(a: &Self, b: &Self, s: f64) -> Self;
}

/// The value of the track `keys` (strictly increasing in time) at time `t`: the first key's
/// value up to its time, the last key's from its time on, the key's own value at a key's time
/// exactly, and between two keys their blend; `None` for an empty track.
pub(crate) fn sample<T: Blend>(keys: &[Key<T>], t: f64) -> Option<T> {
    let first = keys.first()?;
    // The keys at or before `t`; a NaN time counts as before the first key.
    let after = keys.partition_point(|k| k.time <= t);
    if after == 0 {
        return Some(first.value.clone());
    }
    let before = &keys[after - 1];
    let Some(next) = keys.get(after).filter(|_| before.time != t) else {
        return Some(before.value.clone());
    };
    Some(T::blend(&before.value, &next.value, fraction(before.time, next.time, t)))
}

/// How far `t` is from `a` to `b` (`a < t < b`), in [0, 1]; times so far apart that their
/// difference overflows are halved first.
fn fraction(a: f64, b: f64, t: f64) -> f64 {
    let span = b - a;
    let s =
        if span.is_finite() { (t - a) / span } else { (0.5 * t - 0.5 * a) / (0.5 * b - 0.5 * a) };
    s.clamp(0.0, 1.0)
}

/// `a + (b - a) s`, as a weighted sum that cannot overflow between finite values, kept
/// between `a` and `b` despite rounding: a value interpolated between keys within a range
/// (the coordinate limits, a field of view's interval) stays within it.
fn lerp(a: f64, b: f64, s: f64) -> f64 {
    (a * (1.0 - s) + b * s).max(a.min(b)).min(a.max(b))
}

/// [`lerp`] of each coordinate.
fn lerp3(a: DVec3, b: DVec3, s: f64) -> DVec3 {
    (a * (1.0 - s) + b * s).max(a.min(b)).min(a.max(b))
}

/// The angle between the unit vectors `a` and `b`, in [0, pi], from its sine and cosine
/// (accurate at every angle, unlike the arc cosine of the dot product near 0 and pi).
pub(crate) fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// Whether the unit vectors `a` and `b` are opposite within [`OPPOSITE_TOLERANCE`].
pub(crate) fn opposite(a: DVec3, b: DVec3) -> bool {
    angle(a, b) > PI - OPPOSITE_TOLERANCE
}

/// The unit direction a fraction `s` of the way from `a` to `b` along the great circle through
/// both (unit vectors that are not [`opposite`]): at a constant angular rate, unit to rounding.
/// Any direction without a unit vector gives `a`.
pub(crate) fn slerp(a: DVec3, b: DVec3, s: f64) -> DVec3 {
    let (Some(a), Some(b)) = (unit(a), unit(b)) else { return a };
    let theta = angle(a, b);
    let v = if theta < SMALL_ANGLE {
        lerp3(a, b, s)
    } else {
        let sine = theta.sin();
        a * (((1.0 - s) * theta).sin() / sine) + b * ((s * theta).sin() / sine)
    };
    unit(v).unwrap_or(a)
}

impl Blend for f64 {
    fn blend(a: &Self, b: &Self, s: f64) -> Self {
        lerp(*a, *b, s)
    }
}

impl Blend for Light {
    /// Directions by [`slerp`]; a spot's position, target and opening by [`lerp`]. Keys of
    /// different kinds (which a checked track never has) give `a`.
    fn blend(a: &Self, b: &Self, s: f64) -> Self {
        match (a, b) {
            (Light::Directional { direction: da }, Light::Directional { direction: db }) => {
                Light::Directional { direction: slerp(*da, *db, s) }
            }
            (
                Light::Spot { position: pa, target: ta, fov_deg: fa },
                Light::Spot { position: pb, target: tb, fov_deg: fb },
            ) => Light::Spot {
                position: lerp3(*pa, *pb, s),
                target: lerp3(*ta, *tb, s),
                fov_deg: lerp(*fa, *fb, s),
            },
            _ => a.clone(),
        }
    }
}

impl Blend for Camera {
    /// Eye, target, field of view and height by [`lerp`], the up hint by [`slerp`]; `near`
    /// is `a`'s (every key has the scene camera's). Keys of different kinds give `a`.
    fn blend(a: &Self, b: &Self, s: f64) -> Self {
        match (a, b) {
            (
                Camera::Perspective { eye: ea, target: ta, up: ua, fov_y_deg: fa, near },
                Camera::Perspective { eye: eb, target: tb, up: ub, fov_y_deg: fb, .. },
            ) => Camera::Perspective {
                eye: lerp3(*ea, *eb, s),
                target: lerp3(*ta, *tb, s),
                up: slerp(*ua, *ub, s),
                fov_y_deg: lerp(*fa, *fb, s),
                near: *near,
            },
            (
                Camera::Orthographic { eye: ea, target: ta, up: ua, height: ha },
                Camera::Orthographic { eye: eb, target: tb, up: ub, height: hb },
            ) => Camera::Orthographic {
                eye: lerp3(*ea, *eb, s),
                target: lerp3(*ta, *tb, s),
                up: slerp(*ua, *ub, s),
                height: lerp(*ha, *hb, s),
            },
            _ => a.clone(),
        }
    }
}

/// A rigid motion: a rotation about a centre, then a translation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Rigid {
    /// Added after the rotation.
    pub(crate) translate: DVec3,
    /// Unit quaternion of the rotation.
    pub(crate) rotation: DQuat,
}

impl Rigid {
    /// The motion of an object key: `rotate_deg` in the convention of an object's transform
    /// (about x, then y, then z) as a unit quaternion.
    pub(crate) fn new(translate: DVec3, rotate_deg: DVec3) -> Self {
        let r = rotate_deg;
        let rotation = DQuat::from_euler(
            glam::EulerRot::ZYX,
            r.z.to_radians(),
            r.y.to_radians(),
            r.x.to_radians(),
        );
        Self { translate, rotation }
    }

    /// `p` rotated about `centre`, then translated; without rotation, `p + translate` exactly.
    pub(crate) fn apply(&self, p: DVec3, centre: DVec3) -> DVec3 {
        if self.rotation == DQuat::IDENTITY {
            p + self.translate
        } else {
            self.rotation * (p - centre) + centre + self.translate
        }
    }
}

impl Blend for Rigid {
    /// The translation by [`lerp`], the rotation by quaternion slerp (the shorter way round,
    /// at most half a turn), renormalised so that the motion stays rigid to rounding.
    fn blend(a: &Self, b: &Self, s: f64) -> Self {
        Rigid {
            translate: lerp3(a.translate, b.translate, s),
            rotation: a.rotation.slerp(b.rotation, s).normalize(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track(values: &[(f64, f64)]) -> Vec<Key<f64>> {
        values.iter().map(|&(time, value)| Key { time, value }).collect()
    }

    #[test]
    fn a_track_holds_its_ends_and_is_linear_between_keys() {
        let keys = track(&[(1.0, 10.0), (2.0, 20.0), (4.0, 0.0)]);
        assert_eq!(sample::<f64>(&[], 0.0), None);
        assert_eq!(sample(&keys, -5.0), Some(10.0));
        assert_eq!(sample(&keys, f64::NAN), Some(10.0));
        assert_eq!(sample(&keys, 1.5), Some(15.0));
        assert_eq!(sample(&keys, 3.0), Some(10.0));
        assert_eq!(sample(&keys, 9.0), Some(0.0));
        // Times whose difference overflows.
        let far = track(&[(-f64::MAX, 0.0), (f64::MAX, 2.0)]);
        assert_eq!(sample(&far, 0.0), Some(1.0));
    }

    #[test]
    fn a_track_at_a_key_time_is_the_key_bit_for_bit() {
        // Values a blend would round (0.1 * (1 - s) + 0.7 * s is not 0.7 at every s that
        // rounds to 1): at a key's time the track is the key itself.
        let keys = track(&[(0.1, 0.1), (0.3, 0.7), (0.7, 1.0 / 3.0)]);
        for k in &keys {
            assert_eq!(sample(&keys, k.time).map(f64::to_bits), Some(k.value.to_bits()));
        }
        let dirs = [DVec3::new(-0.3, -1.0, 0.2), DVec3::new(0.7, -0.2, -0.1)];
        let lights: Vec<Key<Light>> = dirs
            .iter()
            .enumerate()
            .map(|(i, &d)| Key {
                time: i as f64 * 0.1,
                value: Light::Directional { direction: unit(d).unwrap_or(d) },
            })
            .collect();
        for k in &lights {
            assert_eq!(sample(&lights, k.time).as_ref(), Some(&k.value));
        }
    }

    #[test]
    fn slerp_midway_is_unit_and_bisects() {
        let cases = [
            (DVec3::new(-0.5, -1.0, -0.4), DVec3::new(0.3, -0.8, 0.5)),
            (DVec3::X, DVec3::Y),
            (DVec3::new(1.0, 0.0, 0.0), DVec3::new(-1.0, 1e-3, 0.0)),
            (DVec3::new(0.2, -1.0, 0.0), DVec3::new(0.2 + 1e-9, -1.0, 0.0)),
        ];
        for (a, b) in cases {
            let (ua, ub) = (unit(a).expect("a"), unit(b).expect("b"));
            let m = slerp(a, b, 0.5);
            assert!((m.length() - 1.0).abs() < 4.0 * f64::EPSILON, "{a} {b}: |m| = {}", m.length());
            let (am, mb, ab) = (angle(ua, m), angle(m, ub), angle(ua, ub));
            // Rounding, and near opposite directions its growth as 1 / sin(angle).
            let tolerance = 2e-15 * (1.0 + 1.0 / (PI - ab));
            assert!((am - mb).abs() < tolerance, "{a} {b}: {am} vs {mb}");
            assert!((am + mb - ab).abs() < tolerance, "{a} {b}: off the great circle");
            // At a constant rate: a quarter of the way is a quarter of the angle.
            let q = slerp(a, b, 0.25);
            assert!((angle(ua, q) - 0.25 * ab).abs() < tolerance, "{a} {b}");
        }
        assert!(opposite(DVec3::X, -DVec3::X));
        assert!(!opposite(DVec3::X, DVec3::new(-1.0, 1e-3, 0.0)));
    }

    #[test]
    fn a_rigid_motion_without_rotation_only_translates() {
        let r = Rigid::new(DVec3::new(0.1, 0.2, 0.3), DVec3::ZERO);
        assert_eq!(r.rotation, DQuat::IDENTITY);
        let p = DVec3::new(1.0, 1.0 / 3.0, -7.0);
        assert_eq!(r.apply(p, DVec3::splat(0.7)), p + r.translate);
        // A quarter turn about y takes x to -z about the centre.
        let r = Rigid::new(DVec3::ZERO, DVec3::new(0.0, 90.0, 0.0));
        let c = DVec3::new(1.0, 2.0, 3.0);
        assert!((r.apply(c + DVec3::X, c) - (c - DVec3::Z)).length() < 1e-15);
        let half = Rigid::blend(&Rigid::new(DVec3::ZERO, DVec3::ZERO), &r, 0.5);
        let want = Rigid::new(DVec3::ZERO, DVec3::new(0.0, 45.0, 0.0));
        assert!((half.rotation - want.rotation).length() < 1e-15);
    }
}
