//! Lights: directional (orthographic light frustum fitted to the scene's bounds) and spot
//! (perspective frustum).
//!
//! Any finite non-zero direction is valid, however large or small: directions are normalised
//! with [`crate::direction::unit`] (never overflowing or underflowing), and a resolved scene
//! carries a directional light's direction as a unit vector ([`Light::normalized`]), so that no
//! consumer normalises a user's vector again.

use crate::direction::unit;
use crate::mesh::box_corners;
use crate::projection::{direction_between, look_basis, ProjectionKind, Projector};
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A light. In scene files: a `[light.directional]` or `[light.spot]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum Light {
    /// Parallel light travelling along `direction`.
    Directional {
        /// Direction the light travels (from the light towards the scene); need not be unit.
        #[serde(deserialize_with = "crate::arrays::dvec3")]
        direction: DVec3,
    },
    /// Point light with a cone, seen as a perspective projection.
    Spot {
        /// Light position.
        #[serde(deserialize_with = "crate::arrays::dvec3")]
        position: DVec3,
        /// Point the spot is aimed at.
        #[serde(deserialize_with = "crate::arrays::dvec3")]
        target: DVec3,
        /// Full opening angle of the frustum in degrees, in (0, 170].
        fov_deg: f64,
    },
}

/// Relative margin added around the scene bounds when fitting a light frustum, so that no
/// geometry lies exactly on the border of the light's image.
pub const FIT_MARGIN: f64 = 0.01;

impl Light {
    /// Checks the light; the error names the bad key.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        match self {
            Light::Directional { direction } => {
                if unit(*direction).is_none() {
                    return Err(("direction", "must be finite and non-zero".into()));
                }
            }
            Light::Spot { position, target, fov_deg } => {
                if !position.is_finite() {
                    return Err(("position", "must be finite".into()));
                }
                if direction_between(*position, *target).is_none() {
                    return Err(("target", "must be finite and differ from position".into()));
                }
                if !(*fov_deg > 0.0 && *fov_deg <= 170.0) {
                    return Err(("fov_deg", format!("must be in (0, 170], got {fov_deg}")));
                }
            }
        }
        Ok(())
    }

    /// The light as a resolved scene carries it: a directional light's `direction` as a unit
    /// vector; a spot light, or a direction that does not validate, unchanged.
    pub fn normalized(&self) -> Self {
        match *self {
            Light::Directional { direction } => {
                Light::Directional { direction: unit(direction).unwrap_or(direction) }
            }
            Light::Spot { .. } => self.clone(),
        }
    }

    /// Unit direction from `p` towards the light (for a spot light at `p`, its axis reversed);
    /// NaN for a light that does not validate.
    pub fn direction_to_light(&self, p: DVec3) -> DVec3 {
        let towards = match *self {
            Light::Directional { direction } => unit(-direction),
            Light::Spot { position, target, .. } => {
                direction_between(p, position).or_else(|| direction_between(target, position))
            }
        };
        towards.unwrap_or(DVec3::NAN)
    }

    /// The light's projector onto a `res x res` map, fitted to the axis-aligned box
    /// `(lo, hi)` that holds the scene.
    ///
    /// Directional: an orthographic frustum whose image rectangle is the tightest one around
    /// the box seen along the light (texels may be non-square), and whose origin lies in front
    /// of the box so that every depth is positive. Spot: a perspective frustum of the spot's
    /// opening angle; `near` is the nearest depth of the box's corners, clamped to a small
    /// positive distance when the light is inside the box: 1e-4 of the spot's aim distance
    /// (position to target) or of the box's diagonal, whichever is smaller. The aim distance
    /// is the scale the spot lights; a far-away object, which stretches the box, does not push
    /// the near plane past the geometry around the light.
    pub fn projector(&self, bounds: (DVec3, DVec3), res: u32) -> Projector {
        let (lo, hi) = bounds;
        let pad = (hi - lo).length().max(1e-9) * FIT_MARGIN;
        let (lo, hi) = (lo - DVec3::splat(pad), hi + DVec3::splat(pad));
        let corners = box_corners(lo, hi);
        let size = f64::from(res);
        match *self {
            Light::Directional { direction } => {
                let (right, up, forward) = look_basis(direction, DVec3::Y);
                let centre = 0.5 * (lo + hi);
                let (mut hw, mut hh, mut dmin) = (0.0f64, 0.0f64, f64::INFINITY);
                for c in corners {
                    let v = c - centre;
                    hw = hw.max(v.dot(right).abs());
                    hh = hh.max(v.dot(up).abs());
                    dmin = dmin.min(v.dot(forward));
                }
                Projector {
                    origin: centre + forward * (dmin - pad),
                    right,
                    up,
                    forward,
                    kind: ProjectionKind::Orthographic {
                        half_width: hw.max(1e-9),
                        half_height: hh.max(1e-9),
                    },
                    near: f64::NEG_INFINITY,
                    width: size,
                    height: size,
                }
            }
            Light::Spot { position, target, fov_deg } => {
                let axis = direction_between(position, target).unwrap_or(DVec3::NAN);
                let (right, up, forward) = look_basis(axis, DVec3::Y);
                let nearest = corners
                    .iter()
                    .map(|&c| (c - position).dot(forward))
                    .fold(f64::INFINITY, f64::min);
                let aim = (target - position).length();
                let near = nearest.max(1e-4 * aim.min(pad / FIT_MARGIN));
                let t = (fov_deg.to_radians() * 0.5).tan();
                Projector {
                    origin: position,
                    right,
                    up,
                    forward,
                    kind: ProjectionKind::Perspective { tan_half_x: t, tan_half_y: t },
                    near,
                    width: size,
                    height: size,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directional_fit_holds_the_box_with_positive_depths() {
        let light = Light::Directional { direction: DVec3::new(-1.0, -2.0, 0.5) };
        let bounds = (DVec3::new(-5.0, 0.0, -5.0), DVec3::new(5.0, 3.0, 5.0));
        let p = light.projector(bounds, 512);
        for i in 0..8 {
            let c = DVec3::new(
                if i & 1 == 0 { -5.0 } else { 5.0 },
                if i & 2 == 0 { 0.0 } else { 3.0 },
                if i & 4 == 0 { -5.0 } else { 5.0 },
            );
            let (xy, depth) = p.project(c).expect("projects");
            assert!(depth > 0.0);
            assert!(xy.x > 0.0 && xy.x < 512.0 && xy.y > 0.0 && xy.y < 512.0, "{xy}");
        }
    }

    #[test]
    fn any_finite_non_zero_direction_is_valid_and_normalized() {
        let d = DVec3::new(-0.5, -1.0, -0.25);
        let bounds = (DVec3::new(-5.0, 0.0, -5.0), DVec3::new(5.0, 3.0, 5.0));
        let want = Light::Directional { direction: d }.projector(bounds, 64);
        for scale in [1e-170, 1e-300, 1.0, 1e154, 1e300] {
            let light = Light::Directional { direction: d * scale };
            assert_eq!(light.validate(), Ok(()), "scale {scale}");
            let Light::Directional { direction } = light.normalized() else { unreachable!() };
            assert!((direction - d.normalize()).length() < 1e-15, "scale {scale}: {direction}");
            let towards = light.direction_to_light(DVec3::ZERO);
            assert!((towards + d.normalize()).length() < 1e-15, "scale {scale}: {towards}");
            let p = light.projector(bounds, 64);
            assert!((p.forward - want.forward).length() < 1e-15, "scale {scale}");
            assert!((p.origin - want.origin).length() < 1e-12, "scale {scale}");
        }
        for bad in [DVec3::ZERO, DVec3::new(f64::NAN, -1.0, 0.0), DVec3::NEG_INFINITY] {
            let light = Light::Directional { direction: bad };
            assert!(light.validate().is_err(), "{bad}");
            let Light::Directional { direction } = light.normalized() else { unreachable!() };
            assert_eq!(direction.to_array().map(f64::to_bits), bad.to_array().map(f64::to_bits));
        }
        // A spot whose position and target are so far apart that their difference overflows.
        let far = DVec3::new(0.0, f64::MAX, 0.0);
        let spot = Light::Spot { position: far, target: -far, fov_deg: 60.0 };
        assert_eq!(spot.validate(), Ok(()));
        assert_eq!(spot.normalized(), spot);
        assert_eq!(spot.direction_to_light(-far), DVec3::Y);
        let spot = Light::Spot { position: DVec3::ONE, target: DVec3::ONE, fov_deg: 60.0 };
        assert_eq!(spot.validate().map_err(|(key, _)| key), Err("target"));
    }

    #[test]
    fn spot_near_plane_is_not_pushed_out_by_a_far_object() {
        let light =
            Light::Spot { position: DVec3::new(0.0, 3.0, 0.0), target: DVec3::ZERO, fov_deg: 60.0 };
        let near_box = (DVec3::new(-5.0, 0.0, -5.0), DVec3::new(5.0, 4.0, 5.0));
        let far_box = (near_box.0, DVec3::splat(1e12));
        let (a, b) = (light.projector(near_box, 64), light.projector(far_box, 64));
        assert!(a.near > 0.0 && a.near <= 3.0001e-4, "{}", a.near);
        assert_eq!(a.near, b.near);
    }

    #[test]
    fn spot_light_inside_the_box_keeps_a_positive_near() {
        let light = Light::Spot { position: DVec3::ZERO, target: -DVec3::Y, fov_deg: 90.0 };
        let p = light.projector((DVec3::splat(-1.0), DVec3::splat(1.0)), 256);
        assert!(p.near > 0.0);
    }
}
