//! Lights: directional (orthographic light frustum fitted to the scene's bounds) and spot
//! (perspective frustum).

use crate::projection::{look_basis, ProjectionKind, Projector};
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
                if !direction.is_finite() || direction.length_squared() == 0.0 {
                    return Err(("direction", "must be finite and non-zero".into()));
                }
            }
            Light::Spot { position, target, fov_deg } => {
                if !position.is_finite() {
                    return Err(("position", "must be finite".into()));
                }
                if !target.is_finite() || (*target - *position).length_squared() == 0.0 {
                    return Err(("target", "must be finite and differ from position".into()));
                }
                if !(*fov_deg > 0.0 && *fov_deg <= 170.0) {
                    return Err(("fov_deg", format!("must be in (0, 170], got {fov_deg}")));
                }
            }
        }
        Ok(())
    }

    /// Unit direction from `p` towards the light.
    pub fn direction_to_light(&self, p: DVec3) -> DVec3 {
        match self {
            Light::Directional { direction } => -direction.normalize(),
            Light::Spot { position, target, .. } => {
                (*position - p).normalize_or((*position - *target).normalize())
            }
        }
    }

    /// The light's projector onto a `res x res` map, fitted to the axis-aligned box
    /// `(lo, hi)` that holds the scene.
    ///
    /// Directional: an orthographic frustum whose image rectangle is the tightest one around
    /// the box seen along the light (texels may be non-square), and whose origin lies in front
    /// of the box so that every depth is positive. Spot: a perspective frustum of the spot's
    /// opening angle; `near` is the nearest depth of the box's corners, clamped to a small
    /// positive fraction of the box's size when the light is inside the box.
    pub fn projector(&self, bounds: (DVec3, DVec3), res: u32) -> Projector {
        let (lo, hi) = bounds;
        let pad = (hi - lo).length().max(1e-9) * FIT_MARGIN;
        let (lo, hi) = (lo - DVec3::splat(pad), hi + DVec3::splat(pad));
        let corners = (0..8).map(move |i| {
            DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        });
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
                let (right, up, forward) = look_basis(target - position, DVec3::Y);
                let nearest =
                    corners.map(|c| (c - position).dot(forward)).fold(f64::INFINITY, f64::min);
                let near = nearest.max(1e-4 * pad / FIT_MARGIN);
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
    fn spot_light_inside_the_box_keeps_a_positive_near() {
        let light = Light::Spot { position: DVec3::ZERO, target: -DVec3::Y, fov_deg: 90.0 };
        let p = light.projector((DVec3::splat(-1.0), DVec3::splat(1.0)), 256);
        assert!(p.near > 0.0);
    }
}
