//! Projections from world space to an image plane, shared by cameras and lights.
//!
//! A [`Projector`] maps a world point to image coordinates `(x, y)` in pixels (or texels) and a
//! depth, and maps an image point back to a ray. Image coordinates run from the top-left
//! corner: pixel `(i, j)` covers `[i, i+1] x [j, j+1]` and its centre is `(i + 0.5, j + 0.5)`;
//! `y` grows downwards. Depth is the distance along the forward axis from the projector's
//! origin (perspective) or from its image plane (orthographic); it is linear in world space, so
//! a depth computed by intersecting a ray with a triangle's plane is exact up to `f64` rounding.
//!
//! Everything is `f64`: the projector is the one place where world and image meet, and the
//! exact reference and the rasterizer both rely on it agreeing with itself.

use crate::direction::unit;
use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

/// Perspective or orthographic projection.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum ProjectionKind {
    /// Central projection through the origin.
    Perspective {
        /// `tan` of half the horizontal field of view.
        tan_half_x: f64,
        /// `tan` of half the vertical field of view.
        tan_half_y: f64,
    },
    /// Parallel projection along the forward axis.
    Orthographic {
        /// Half the width of the view volume, in world units.
        half_width: f64,
        /// Half the height of the view volume, in world units.
        half_height: f64,
    },
}

/// A projection onto a `width x height` image.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Projector {
    /// Eye (perspective) or centre of the image plane (orthographic).
    pub origin: DVec3,
    /// Unit vector along the image's `+x`.
    pub right: DVec3,
    /// Unit vector along the image's `-y` (up on screen).
    pub up: DVec3,
    /// Unit viewing direction.
    pub forward: DVec3,
    /// The projection.
    pub kind: ProjectionKind,
    /// Points nearer than this depth are not projected (perspective only; must be > 0 there).
    pub near: f64,
    /// Image width in pixels.
    pub width: f64,
    /// Image height in pixels.
    pub height: f64,
}

/// The parts of a projector's rays through a grid of points, each computed once per column
/// and once per row ([`Projector::grid_rays`]), not two divisions per ray.
#[derive(Debug, Clone, PartialEq)]
pub struct GridRays {
    /// [`Projector::column`] of offset `s` in column `x`, at `s * width + x`.
    columns: Vec<DVec3>,
    /// [`Projector::row`] of offset `s` in row `y`, at `s * height + y`.
    rows: Vec<DVec3>,
    width: usize,
    height: usize,
}

impl GridRays {
    /// The ray of `projector` (the one that made these parts) through column `x`, row `y`
    /// and offset `s`: `projector.ray` of that point, the same numbers.
    #[inline]
    pub fn ray(&self, projector: &Projector, x: usize, y: usize, s: usize) -> Ray {
        projector.ray_from(self.columns[s * self.width + x], self.rows[s * self.height + y])
    }
}

/// A ray `origin + t * direction`; for a projector's ray, `t` is the depth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: DVec3,
    /// Direction, scaled so that the ray parameter equals depth.
    pub direction: DVec3,
}

impl Ray {
    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + t * self.direction
    }

    /// The parameter where the ray meets the plane `n·p = d`, or `None` when the ray is parallel
    /// to it (or the result is not finite).
    #[inline]
    pub fn intersect_plane(&self, n: DVec3, d: f64) -> Option<f64> {
        let denom = n.dot(self.direction);
        let t = (d - n.dot(self.origin)) / denom;
        (denom != 0.0 && t.is_finite()).then_some(t)
    }
}

/// The unit vector from point `from` towards point `to`, or `None` when they coincide or one is
/// not finite. The difference of two finite points may exceed `f64::MAX`; it is then taken
/// between the halved points (exact at such magnitudes), so that it never overflows.
pub fn direction_between(from: DVec3, to: DVec3) -> Option<DVec3> {
    if !(from.is_finite() && to.is_finite()) {
        return None;
    }
    let d = to - from;
    unit(if d.is_finite() { d } else { 0.5 * to - 0.5 * from })
}

/// An orthonormal basis `(right, up, forward)` looking along `forward`, with `up` as close to
/// `up_hint` as possible. Falls back to another hint when the two are parallel or the hint is
/// zero. Both vectors are normalised with [`unit()`], so that any finite non-zero magnitude
/// works; a `forward` without a direction (zero or not finite) gives a basis of NaN.
pub fn look_basis(forward: DVec3, up_hint: DVec3) -> (DVec3, DVec3, DVec3) {
    let Some(f) = unit(forward) else {
        return (DVec3::NAN, DVec3::NAN, DVec3::NAN);
    };
    let mut r = f.cross(unit(up_hint).unwrap_or(DVec3::ZERO));
    if r.length_squared() < 1e-20 {
        let alt = if f.x.abs() < 0.9 { DVec3::X } else { DVec3::Z };
        r = f.cross(alt);
    }
    let r = r.normalize();
    let u = r.cross(f);
    (r, u, f)
}

impl Projector {
    /// Image coordinates and depth of `p`; `None` for a perspective projector when `p` lies
    /// nearer than `near` (or behind the eye).
    #[inline]
    pub fn project(&self, p: DVec3) -> Option<(DVec2, f64)> {
        let depth = self.depth_of(p);
        if self.is_perspective() && (depth < self.near || depth.is_nan()) {
            return None;
        }
        let (xy, depth) = self.project_unclipped(p);
        xy.is_finite().then_some((xy, depth))
    }

    /// Image coordinates and depth of `p` without the near test; the caller guarantees a
    /// positive depth for perspective projectors (e.g. after clipping at `near`).
    #[inline]
    pub fn project_unclipped(&self, p: DVec3) -> (DVec2, f64) {
        let v = p - self.origin;
        let depth = v.dot(self.forward);
        let (sx, sy) = match self.kind {
            ProjectionKind::Perspective { tan_half_x, tan_half_y } => {
                (v.dot(self.right) / (depth * tan_half_x), v.dot(self.up) / (depth * tan_half_y))
            }
            ProjectionKind::Orthographic { half_width, half_height } => {
                (v.dot(self.right) / half_width, v.dot(self.up) / half_height)
            }
        };
        (DVec2::new((1.0 + sx) * 0.5 * self.width, (1.0 - sy) * 0.5 * self.height), depth)
    }

    /// The ray through image point `xy`, parameterised by depth: [`Self::ray_from`] its
    /// column's and its row's parts.
    #[inline]
    pub fn ray(&self, xy: DVec2) -> Ray {
        self.ray_from(self.column(xy.x), self.row(xy.y))
    }

    /// The part of [`Self::ray`] that depends on the image point's `x` only: for a perspective
    /// projection, the direction's `forward` and `right` terms, for an orthographic one, the
    /// origin's `origin` and `right` terms (the first two terms of the sum, added first).
    #[inline]
    pub fn column(&self, x: f64) -> DVec3 {
        let sx = 2.0 * x / self.width - 1.0;
        match self.kind {
            ProjectionKind::Perspective { tan_half_x, .. } => {
                self.forward + self.right * (sx * tan_half_x)
            }
            ProjectionKind::Orthographic { half_width, .. } => {
                self.origin + self.right * (sx * half_width)
            }
        }
    }

    /// The part of [`Self::ray`] that depends on the image point's `y` only: the `up` term.
    #[inline]
    pub fn row(&self, y: f64) -> DVec3 {
        let sy = 1.0 - 2.0 * y / self.height;
        match self.kind {
            ProjectionKind::Perspective { tan_half_y, .. } => self.up * (sy * tan_half_y),
            ProjectionKind::Orthographic { half_height, .. } => self.up * (sy * half_height),
        }
    }

    /// The ray through the image point of column part `column` ([`Self::column`]) and row part
    /// `row` ([`Self::row`]): the same numbers as [`Self::ray`] (rays through a grid of points
    /// take each part once per column and once per row).
    #[inline]
    pub fn ray_from(&self, column: DVec3, row: DVec3) -> Ray {
        match self.kind {
            ProjectionKind::Perspective { .. } => {
                Ray { origin: self.origin, direction: column + row }
            }
            ProjectionKind::Orthographic { .. } => {
                Ray { origin: column + row, direction: self.forward }
            }
        }
    }

    /// The parts of the rays through the points `(x + offsets[s].x, y + offsets[s].y)` for
    /// columns `x < width` and rows `y < height`: [`GridRays::ray`] makes each of those rays
    /// from them, with the numbers of [`Self::ray`].
    pub fn grid_rays(&self, (width, height): (usize, usize), offsets: &[DVec2]) -> GridRays {
        let columns = offsets
            .iter()
            .flat_map(|o| (0..width).map(move |x| self.column(x as f64 + o.x)))
            .collect();
        let rows = offsets
            .iter()
            .flat_map(|o| (0..height).map(move |y| self.row(y as f64 + o.y)))
            .collect();
        GridRays { columns, rows, width, height }
    }

    /// Depth of `p` along the forward axis (no near test).
    #[inline]
    pub fn depth_of(&self, p: DVec3) -> f64 {
        (p - self.origin).dot(self.forward)
    }

    /// Whether this is a perspective projection.
    pub fn is_perspective(&self) -> bool {
        matches!(self.kind, ProjectionKind::Perspective { .. })
    }

    /// Unit direction from `p` towards the projector (towards the eye, or against `forward`).
    #[inline]
    pub fn direction_to(&self, p: DVec3) -> DVec3 {
        match self.kind {
            ProjectionKind::Perspective { .. } => (self.origin - p).normalize_or(-self.forward),
            ProjectionKind::Orthographic { .. } => -self.forward,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn persp() -> Projector {
        let (right, up, forward) = look_basis(DVec3::new(0.3, -1.0, -2.0), DVec3::Y);
        Projector {
            origin: DVec3::new(1.0, 5.0, 9.0),
            right,
            up,
            forward,
            kind: ProjectionKind::Perspective { tan_half_x: 0.7, tan_half_y: 0.5 },
            near: 0.01,
            width: 800.0,
            height: 600.0,
        }
    }

    #[test]
    fn ray_and_project_are_inverse() {
        for p in [
            persp(),
            Projector {
                kind: ProjectionKind::Orthographic { half_width: 4.0, half_height: 3.0 },
                ..persp()
            },
        ] {
            for xy in [DVec2::new(0.5, 0.5), DVec2::new(400.25, 17.0), DVec2::new(799.5, 599.5)] {
                let ray = p.ray(xy);
                let (back, depth) = p.project(ray.at(7.25)).expect("in front");
                assert!((back - xy).length() < 1e-9, "{back} vs {xy}");
                assert!((depth - 7.25).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn points_behind_a_perspective_eye_do_not_project() {
        let p = persp();
        assert!(p.project(p.origin - p.forward).is_none());
        assert!(p.project(p.origin).is_none());
    }

    #[test]
    fn basis_and_directions_take_any_finite_non_zero_magnitude() {
        // Components exact at every scale, subnormal (2^-1070) included.
        let forward = DVec3::new(0.5, -1.0, -2.0);
        let want = look_basis(forward, DVec3::Y);
        for scale in [f64::MIN_POSITIVE * 2f64.powi(-48), 1e-170, 1e154, 1e300, f64::MAX / 2.0] {
            let (r, u, f) = look_basis(forward * scale, DVec3::Y * scale);
            for (got, want) in [(r, want.0), (u, want.1), (f, want.2)] {
                assert!((got - want).length() < 1e-12, "scale {scale}: {got} vs {want}");
            }
        }
        let far = DVec3::new(f64::MAX, 0.0, 0.0);
        assert_eq!(direction_between(-far, far), Some(DVec3::X));
        assert_eq!(direction_between(DVec3::ZERO, DVec3::splat(1e-320)), unit(DVec3::ONE));
        assert_eq!(direction_between(DVec3::ONE, DVec3::ONE), None);
        assert_eq!(direction_between(DVec3::ONE, DVec3::INFINITY), None);
        assert!(look_basis(DVec3::ZERO, DVec3::Y).0.is_nan());
    }

    #[test]
    fn basis_is_orthonormal_even_looking_straight_down() {
        let (r, u, f) = look_basis(-DVec3::Y, DVec3::Y);
        assert!((r.length() - 1.0).abs() < 1e-15 && (u.length() - 1.0).abs() < 1e-15);
        assert!(r.dot(u).abs() < 1e-15 && r.dot(f).abs() < 1e-15 && u.dot(f).abs() < 1e-15);
    }
}
