//! The two-step projection of section 3.4: a world-space plane test seen on a pixel's facet,
//! written as a half-plane of the screen.
//!
//! A camera ray through image point `p` is `origin(p) + t dir(p)`; both are affine in `p`
//! and, for each kind of camera, one of them is constant (perspective: the eye; orthographic:
//! the forward direction). The facet's tangent plane `n·X = d` meets the ray at
//! `t(p) = (d - n·origin(p)) / (n·dir(p))`, so for any world plane `N·X = c`
//!
//! `N·X(p) - c = [(N·origin(p) - c)(n·dir(p)) + (d - n·origin(p))(N·dir(p))] / (n·dir(p))`.
//!
//! The numerator is affine in `p` (the product of two affine terms loses its quadratic part
//! because one factor's gradient is zero), and the denominator keeps the sign of its value at
//! the pixel centre over every point where the ray meets the plane in front of the camera
//! (the facet's region, see [`super::facets`]). A world-space half-space is therefore a screen
//! half-plane ([`HalfPlane`], in pixel-local coordinates `u = p - centre`). This is the
//! paper's "projection of these half-planes onto the tangent plane ... then to the screen
//! plane", and its side rule (Fig. 6b) is the sign of the denominator: the side is decided in
//! world space, where the occluding side of each plane is known, and carried to the screen by
//! that sign.

use glam::{DVec2, DVec3};
use scenes::projection::{ProjectionKind, Projector};

/// A screen half-plane `g0 + gx ux + gy uy >= 0` in pixel-local coordinates
/// `u = p - pixel centre`, in pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfPlane {
    /// Value at the pixel centre.
    pub g0: f64,
    /// Change per pixel along x.
    pub gx: f64,
    /// Change per pixel along y.
    pub gy: f64,
}

/// Where a half-plane's line lies relative to the pixel square `[-1/2, 1/2]^2`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Crossing {
    /// The whole closed square is strictly inside (`g > 0`).
    All,
    /// The whole closed square is strictly outside (`g < 0`).
    None,
    /// The line meets the closed square.
    Split,
}

impl HalfPlane {
    /// The value at pixel-local point `u`.
    #[inline(always)]
    pub fn at(&self, u: DVec2) -> f64 {
        self.g0 + self.gx * u.x + self.gy * u.y
    }

    /// Where the line lies relative to the pixel square, from the value at its farthest
    /// corners (exact up to the rounding of one fused sum).
    #[inline(always)]
    pub fn crossing(&self) -> Crossing {
        let reach = 0.5 * (self.gx.abs() + self.gy.abs());
        if self.g0 - reach > 0.0 {
            Crossing::All
        } else if self.g0 + reach < 0.0 {
            Crossing::None
        } else {
            Crossing::Split
        }
    }
}

/// The affine camera ray `origin(p) + t dir(p)` of a projector, with `p` in image
/// coordinates: `origin(p) = o0 + ox p.x + oy p.y`, `dir(p) = d0 + dx p.x + dy p.y`
/// (see [`Projector::ray`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraBasis {
    /// Origin at image point `(0, 0)`.
    pub o0: DVec3,
    /// Origin change per pixel along x (zero for perspective cameras).
    pub ox: DVec3,
    /// Origin change per pixel along y (zero for perspective cameras).
    pub oy: DVec3,
    /// Direction at image point `(0, 0)`.
    pub d0: DVec3,
    /// Direction change per pixel along x (zero for orthographic cameras).
    pub dx: DVec3,
    /// Direction change per pixel along y (zero for orthographic cameras).
    pub dy: DVec3,
    /// Whether rays share one origin (a perspective camera).
    pub perspective: bool,
}

impl CameraBasis {
    /// The basis of `camera`'s rays.
    pub fn new(camera: &Projector) -> Self {
        let (w, h) = (camera.width, camera.height);
        let (r, up, f) = (camera.right, camera.up, camera.forward);
        match camera.kind {
            ProjectionKind::Perspective { tan_half_x: tx, tan_half_y: ty } => Self {
                o0: camera.origin,
                ox: DVec3::ZERO,
                oy: DVec3::ZERO,
                d0: f - r * tx + up * ty,
                dx: r * (2.0 * tx / w),
                dy: -up * (2.0 * ty / h),
                perspective: true,
            },
            ProjectionKind::Orthographic { half_width: hw, half_height: hh } => Self {
                o0: camera.origin - r * hw + up * hh,
                ox: r * (2.0 * hw / w),
                oy: -up * (2.0 * hh / h),
                d0: f,
                dx: DVec3::ZERO,
                dy: DVec3::ZERO,
                perspective: false,
            },
        }
    }

    /// The ray origin at image point `p`.
    #[inline]
    pub fn origin(&self, p: DVec2) -> DVec3 {
        self.o0 + self.ox * p.x + self.oy * p.y
    }

    /// The ray direction at image point `p`.
    #[inline]
    pub fn dir(&self, p: DVec2) -> DVec3 {
        self.d0 + self.dx * p.x + self.dy * p.y
    }
}

/// A world plane `N·X - c` with its products with the camera's per-pixel gradients, computed
/// once per plane and reused for every facet.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WorldPlane {
    /// Normal `N` (any length).
    pub n: DVec3,
    /// Offset `c`.
    pub c: f64,
    pub(crate) n_ox: f64,
    pub(crate) n_oy: f64,
    pub(crate) n_dx: f64,
    pub(crate) n_dy: f64,
}

impl WorldPlane {
    /// The plane `n·X = c` seen by `camera`.
    #[inline]
    pub fn new(n: DVec3, c: f64, camera: &CameraBasis) -> Self {
        Self {
            n,
            c,
            n_ox: n.dot(camera.ox),
            n_oy: n.dot(camera.oy),
            n_dx: n.dot(camera.dx),
            n_dy: n.dot(camera.dy),
        }
    }

    /// The signed value `N·X - c` at world point `x`.
    #[cfg(test)]
    pub fn value(&self, x: DVec3) -> f64 {
        self.n.dot(x) - self.c
    }
}

/// The screen mapping of one pixel's facet: the camera ray at the pixel centre and the
/// tangent plane, in the form [`WorldPlane`]s are mapped with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FacetMap {
    /// Ray origin at the pixel centre.
    pub origin: DVec3,
    /// Ray direction at the pixel centre.
    pub dir: DVec3,
    /// `s n·dir` (positive), `s n·dx`, `s n·dy`, with `s = sign(n·dir)`.
    pub a: [f64; 3],
    /// `s n·ox`, `s n·oy`.
    pub b: [f64; 2],
    /// `s (d - n·origin)`: the ray parameter at the centre times `a[0]`.
    pub k: f64,
}

impl FacetMap {
    /// The mapping of the facet on the tangent plane `normal·X = offset` seen through the
    /// pixel centred at image point `centre`; `None` when the centre ray is parallel to the
    /// plane, meets it behind a perspective camera's eye, or the values are not finite.
    /// (Orthographic rays see every depth, as the G-buffer does.)
    pub fn new(camera: &CameraBasis, centre: DVec2, normal: DVec3, offset: f64) -> Option<Self> {
        let origin = camera.origin(centre);
        let dir = camera.dir(centre);
        let nd = normal.dot(dir);
        let s = if nd > 0.0 {
            1.0
        } else if nd < 0.0 {
            -1.0
        } else {
            return None;
        };
        let k = s * (offset - normal.dot(origin));
        let map = Self {
            origin,
            dir,
            a: [s * nd, s * normal.dot(camera.dx), s * normal.dot(camera.dy)],
            b: [s * normal.dot(camera.ox), s * normal.dot(camera.oy)],
            k,
        };
        let finite = origin.is_finite() && dir.is_finite() && map.a.iter().all(|v| v.is_finite());
        let in_front = k > 0.0 || !camera.perspective;
        (finite && in_front && k.is_finite() && map.b.iter().all(|v| v.is_finite())).then_some(map)
    }

    /// The screen half-plane where `plane`'s value on the facet is `>= 0`.
    #[inline(always)]
    pub fn half_plane(&self, plane: &WorldPlane) -> HalfPlane {
        let p0 = plane.n.dot(self.origin) - plane.c;
        let q = plane.n.dot(self.dir);
        let [a0, ax, ay] = self.a;
        let [bx, by] = self.b;
        HalfPlane {
            g0: p0 * a0 + self.k * q,
            gx: plane.n_ox * a0 + p0 * ax - bx * q + self.k * plane.n_dx,
            gy: plane.n_oy * a0 + p0 * ay - by * q + self.k * plane.n_dy,
        }
    }

    /// The ray parameter (the camera depth) where the ray through pixel-local point `u` meets
    /// the tangent plane.
    #[cfg(test)]
    pub fn depth_at(&self, u: DVec2) -> f64 {
        let [a0, ax, ay] = self.a;
        let [bx, by] = self.b;
        (self.k - bx * u.x - by * u.y) / (a0 + ax * u.x + ay * u.y)
    }

    /// The world point of the facet seen through pixel-local point `u`.
    #[cfg(test)]
    pub fn point_at(&self, camera: &CameraBasis, u: DVec2) -> DVec3 {
        let origin = self.origin + camera.ox * u.x + camera.oy * u.y;
        let dir = self.dir + camera.dx * u.x + camera.dy * u.y;
        origin + dir * self.depth_at(u)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use scenes::projection::look_basis;

    fn camera(perspective: bool) -> Projector {
        let (right, up, forward) = look_basis(DVec3::new(0.2, -0.6, -1.0), DVec3::Y);
        Projector {
            origin: DVec3::new(0.5, 4.0, 6.0),
            right,
            up,
            forward,
            kind: if perspective {
                ProjectionKind::Perspective { tan_half_x: 0.55, tan_half_y: 0.4 }
            } else {
                ProjectionKind::Orthographic { half_width: 3.0, half_height: 2.25 }
            },
            near: if perspective { 0.01 } else { f64::NEG_INFINITY },
            width: 64.0,
            height: 48.0,
        }
    }

    #[test]
    fn basis_reproduces_the_projector_rays() {
        for perspective in [true, false] {
            let cam = camera(perspective);
            let basis = CameraBasis::new(&cam);
            for p in [DVec2::new(0.0, 0.0), DVec2::new(13.25, 40.5), DVec2::new(64.0, 48.0)] {
                let ray = cam.ray(p);
                assert!((basis.origin(p) - ray.origin).length() < 1e-12);
                assert!((basis.dir(p) - ray.direction).length() < 1e-12);
            }
        }
    }

    proptest! {
        /// The sign of the screen half-plane at any point of the facet equals the sign of the
        /// world plane at the facet point seen there.
        #[test]
        fn half_plane_sign_is_the_world_plane_sign(
            perspective in any::<bool>(),
            px in 4u32..60, py in 4u32..44,
            nrm in (-1.0f64..1.0, 0.2f64..1.0, -1.0f64..1.0),
            plane in ((-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0), -2.0f64..2.0),
            u in (-0.5f64..0.5, -0.5f64..0.5),
        ) {
            let cam = camera(perspective);
            let basis = CameraBasis::new(&cam);
            let centre = DVec2::new(f64::from(px) + 0.5, f64::from(py) + 0.5);
            let normal = DVec3::new(nrm.0, nrm.1, nrm.2).normalize();
            // The tangent plane through the point 5 units along the centre ray.
            let x0 = cam.ray(centre).at(5.0);
            let Some(map) = FacetMap::new(&basis, centre, normal, normal.dot(x0)) else {
                return Ok(());
            };
            let u = DVec2::new(u.0, u.1);
            prop_assume!(map.depth_at(u) > 0.0);
            let n = DVec3::new((plane.0).0, (plane.0).1, (plane.0).2);
            let wp = WorldPlane::new(n, plane.1, &basis);
            let x = map.point_at(&basis, u);
            // The facet point lies on the tangent plane and on the ray through u.
            prop_assert!((normal.dot(x) - normal.dot(x0)).abs() < 1e-9);
            let (back, _) = cam.project(x).expect("in front");
            prop_assert!((back - (centre + u)).length() < 1e-7);
            let world = wp.value(x);
            let screen = map.half_plane(&wp).at(u);
            prop_assume!(world.abs() > 1e-9);
            prop_assert_eq!(world > 0.0, screen > 0.0, "world {} screen {}", world, screen);
        }
    }
}
