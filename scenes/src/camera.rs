//! Cameras: perspective or orthographic, placed with a look-at. The view direction `target -
//! eye` and the up hint are normalised robustly ([`crate::direction::unit`]), so that any finite
//! non-zero magnitude is valid.

use crate::direction::unit;
use crate::projection::{direction_between, look_basis, ProjectionKind, Projector};
use glam::DVec3;
use serde::{Deserialize, Serialize};

fn default_up() -> DVec3 {
    DVec3::Y
}

fn default_near() -> f64 {
    0.01
}

/// A look-at camera. In scene files: a `[camera.perspective]` or `[camera.orthographic]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum Camera {
    /// Central projection.
    Perspective {
        /// Eye position.
        #[serde(deserialize_with = "crate::arrays::dvec3")]
        eye: DVec3,
        /// Point looked at.
        #[serde(deserialize_with = "crate::arrays::dvec3")]
        target: DVec3,
        /// Up hint (default `[0, 1, 0]`).
        #[serde(default = "default_up", deserialize_with = "crate::arrays::dvec3")]
        up: DVec3,
        /// Vertical field of view in degrees, in (0, 180).
        fov_y_deg: f64,
        /// Near clipping distance, world units (default 0.01).
        #[serde(default = "default_near")]
        near: f64,
    },
    /// Parallel projection.
    Orthographic {
        /// Centre of the image plane.
        #[serde(deserialize_with = "crate::arrays::dvec3")]
        eye: DVec3,
        /// Point looked at (gives the direction).
        #[serde(deserialize_with = "crate::arrays::dvec3")]
        target: DVec3,
        /// Up hint (default `[0, 1, 0]`).
        #[serde(default = "default_up", deserialize_with = "crate::arrays::dvec3")]
        up: DVec3,
        /// Height of the view volume in world units; the width follows the aspect ratio.
        height: f64,
    },
}

impl Camera {
    /// Checks the camera; the error names the bad key.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        let (eye, target, up) = match self {
            Camera::Perspective { eye, target, up, fov_y_deg, near } => {
                if !(*fov_y_deg > 0.0 && *fov_y_deg < 180.0) {
                    return Err(("fov_y_deg", format!("must be in (0, 180), got {fov_y_deg}")));
                }
                if !(*near > 0.0 && near.is_finite()) {
                    return Err(("near", format!("must be positive and finite, got {near}")));
                }
                (eye, target, up)
            }
            Camera::Orthographic { eye, target, up, height } => {
                if !(*height > 0.0 && height.is_finite()) {
                    return Err(("height", format!("must be positive and finite, got {height}")));
                }
                (eye, target, up)
            }
        };
        for (key, v) in [("eye", eye), ("target", target), ("up", up)] {
            if !v.is_finite() {
                return Err((key, "must be finite".into()));
            }
        }
        if direction_between(*eye, *target).is_none() {
            return Err(("target", "must differ from eye".into()));
        }
        if unit(*up).is_none() {
            return Err(("up", "must not be zero".into()));
        }
        Ok(())
    }

    /// Eye position.
    pub fn eye(&self) -> DVec3 {
        match self {
            Camera::Perspective { eye, .. } | Camera::Orthographic { eye, .. } => *eye,
        }
    }

    /// Point looked at.
    pub fn target(&self) -> DVec3 {
        match self {
            Camera::Perspective { target, .. } | Camera::Orthographic { target, .. } => *target,
        }
    }

    /// The projector onto a `width x height` image (square pixels).
    pub fn projector(&self, width: u32, height: u32) -> Projector {
        let (w, h) = (f64::from(width), f64::from(height));
        let aspect = w / h;
        let (eye, target, up, kind, near) = match *self {
            Camera::Perspective { eye, target, up, fov_y_deg, near } => {
                let tan_half_y = (fov_y_deg.to_radians() * 0.5).tan();
                let kind =
                    ProjectionKind::Perspective { tan_half_x: tan_half_y * aspect, tan_half_y };
                (eye, target, up, kind, near)
            }
            Camera::Orthographic { eye, target, up, height } => {
                let kind = ProjectionKind::Orthographic {
                    half_width: 0.5 * height * aspect,
                    half_height: 0.5 * height,
                };
                (eye, target, up, kind, f64::NEG_INFINITY)
            }
        };
        // A camera that validates has a direction; one that does not gets a basis of NaN.
        let view = direction_between(eye, target).unwrap_or(DVec3::NAN);
        let (right, up, forward) = look_basis(view, up);
        Projector { origin: eye, right, up, forward, kind, near, width: w, height: h }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(eye: DVec3, target: DVec3, up: DVec3) -> Camera {
        Camera::Perspective { eye, target, up, fov_y_deg: 45.0, near: 0.01 }
    }

    #[test]
    fn any_finite_non_zero_view_and_up_are_valid() {
        let want = camera(DVec3::new(0.0, 6.0, 8.0), DVec3::ZERO, DVec3::Y).projector(64, 48);
        for (eye, up) in [
            (DVec3::new(0.0, 6.0, 8.0) * 1e-170, DVec3::Y * 1e-170),
            (DVec3::new(0.0, 6.0, 8.0) * 1e154, DVec3::Y * 1e300),
        ] {
            let c = camera(eye, DVec3::ZERO, up);
            assert_eq!(c.validate(), Ok(()), "{eye} {up}");
            let p = c.projector(64, 48);
            for (got, want) in [(p.right, want.right), (p.up, want.up), (p.forward, want.forward)] {
                assert!((got - want).length() < 1e-15, "{eye}: {got} vs {want}");
            }
        }
        // Points so far apart that their difference overflows still have a direction.
        let far = camera(DVec3::new(0.0, f64::MAX, 0.0), DVec3::new(0.0, -f64::MAX, 0.0), DVec3::Z);
        assert_eq!(far.validate(), Ok(()));
        assert_eq!(far.projector(8, 8).forward, DVec3::NEG_Y);
        let same = camera(DVec3::ONE, DVec3::ONE, DVec3::Y).validate();
        assert_eq!(same.map_err(|(key, _)| key), Err("target"));
        let flat = camera(DVec3::ONE, DVec3::ZERO, DVec3::ZERO).validate();
        assert_eq!(flat.map_err(|(key, _)| key), Err("up"));
    }
}
