//! Projection of triangles to screen space through homogeneous coordinates: casters along light
//! rays onto the receiver plane and then through the camera, receiver triangles and occluding
//! triangles through the camera alone.
//!
//! Every quantity a clip needs is an affine function of the world point `p` on a triangle:
//! the homogeneous screen coordinates `(X, Y, W)` of its shadow (or of itself) and up to three
//! extra functions `f0, f1, f2` that must be `>= 0` on the kept part. A triangle is clipped in
//! this 6-vector space with Sutherland–Hodgman (linear interpolation is exact for affine
//! functions, up to rounding), then `(X / W, Y / W)` is taken, which is a projective map with
//! `W > 0` on the kept part, so convex polygons stay convex and straight edges straight.

use super::clip::{keep_into, Poly};
use super::ScreenPolygons;
use crate::reference::ReferenceError;
use glam::DVec3;
use methods::Frame;
use rayon::prelude::*;
use scenes::{projection::ProjectionKind, Light, Projector};

/// A vertex in the clip space: homogeneous screen `X, Y, W`, then `f0, f1, f2`.
type Rec = [f64; 6];

/// Largest vertex count of a polygon in clip space (3 + one per plane, 7 planes).
const HCAP: usize = 16;

/// Margin, in pixels, of the homogeneous clip to the frame (or a rectangle in it) that bounds
/// coordinates before the division; the exact clip follows in screen space.
const FRAME_MARGIN: f64 = 1.0;

/// The light as the projection onto the receiver plane needs it.
#[derive(Debug, Clone, Copy)]
enum LightSetup {
    /// Parallel projection along `dir` (the direction light travels); `nl = n·dir != 0`.
    Directional { dir: DVec3, nl: f64 },
    /// Central projection from `pos`, at height `big_h > 0` above the receiver plane.
    Spot { pos: DVec3, big_h: f64 },
}

/// The camera's map from world space to the screen, with the homogeneous clips `exact` uses.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Screen {
    camera: Projector,
    /// Image width in pixels.
    pub width: f64,
    /// Image height in pixels.
    pub height: f64,
}

/// The receiver plane and light of a frame, with the clip functions derived from them.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Setup {
    /// Unit normal of the receiver plane.
    n: DVec3,
    /// Offset of the receiver plane (`n·p = d`).
    d: f64,
    /// `+1` or `-1`: the sign of `n·p - d` on the light's side of the plane.
    light_side: f64,
    light: LightSetup,
    /// The camera.
    pub screen: Screen,
}

impl Setup {
    /// Checks that `exact` applies to the frame as a whole (opaque casters only).
    pub fn check(frame: &Frame<'_>) -> Result<(), ReferenceError> {
        if frame.effects.transparency {
            return Err(ReferenceError::NotApplicable(format!(
                "exact does not apply to scene `{}`: it has semi-transparent casters \
                 (effect `transparency`), and exact handles opaque casters only; use the \
                 `raytrace` reference",
                frame.scene.name
            )));
        }
        Ok(())
    }

    /// The setup for the scene's main planar receiver (`Scene::receiver_plane`, the largest
    /// visible planar object): its object index and the setup.
    pub fn main_receiver(frame: &Frame<'_>) -> Result<(usize, Self), ReferenceError> {
        Self::check(frame)?;
        let name = &frame.scene.name;
        let no_plane = || {
            ReferenceError::NotApplicable(format!(
                "scene `{name}` has no visible planar receiver (effect `planar_receiver` is off)"
            ))
        };
        if !frame.effects.planar_receiver {
            return Err(no_plane());
        }
        let (receiver, n, d) = frame.scene.receiver_plane().ok_or_else(no_plane)?;
        let setup = Self::for_plane(frame, n, d).ok_or_else(|| {
            ReferenceError::NotApplicable(format!(
                "the light of scene `{name}` lies in the plane of its receiver (a directional \
                 light parallel to it, or a spot light in it)"
            ))
        })?;
        Ok((receiver, setup))
    }

    /// The setup for the receiver plane `n·p = d` (`n` a unit normal); `None` when the light
    /// runs parallel to the plane (directional) or lies in it (spot): light reaches such a
    /// plane only at grazing incidence and no shadow projects onto it.
    pub fn for_plane(frame: &Frame<'_>, n: DVec3, d: f64) -> Option<Self> {
        let (light, light_side) = match frame.scene.light {
            Light::Directional { direction } => {
                let nl = n.dot(direction);
                if nl == 0.0 || !nl.is_finite() {
                    return None;
                }
                // Light comes from -dir: the lit side is where n·p - d has the sign of -n·dir.
                (LightSetup::Directional { dir: direction, nl }, -nl.signum())
            }
            Light::Spot { position, .. } => {
                let s = n.dot(position) - d;
                if s == 0.0 || !s.is_finite() {
                    return None;
                }
                (LightSetup::Spot { pos: position, big_h: s.abs() }, s.signum())
            }
        };
        Some(Self { n, d, light_side, light, screen: Screen::new(frame) })
    }

    /// Height of `p` above the receiver plane, positive on the light's side.
    #[inline]
    pub fn light_height(&self, p: DVec3) -> f64 {
        self.light_side * (self.n.dot(p) - self.d)
    }

    /// Whether `p` lies on the light's side of the receiver plane or in it, and for a spot
    /// light strictly below the plane through the light parallel to the receiver.
    #[inline]
    pub fn toward_light(&self, p: DVec3) -> bool {
        let h = self.light_height(p);
        match self.light {
            LightSetup::Directional { .. } => h >= 0.0,
            LightSetup::Spot { big_h, .. } => h >= 0.0 && h < big_h,
        }
    }

    /// Whether triangle `tri` faces the light: the normal its corners' order gives it points
    /// to the light's side of its plane (for a spot light, towards the light's position).
    #[inline]
    pub fn faces_light(&self, tri: &[DVec3; 3]) -> bool {
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        match self.light {
            LightSetup::Directional { dir, .. } => n.dot(dir) < 0.0,
            LightSetup::Spot { pos, .. } => n.dot(pos - tri[0]) > 0.0,
        }
    }

    /// The shadow of caster triangle `tri` on the receiver plane, in screen space, clipped to
    /// the frame; `None` when empty or degenerate.
    pub fn caster(&self, tri: [DVec3; 3]) -> Option<Poly> {
        self.caster_in(tri, self.screen.frame())
    }

    /// [`Self::caster`] clipped to the screen rectangle `rect` (`[x0, x1, y0, y1]`, inside
    /// the frame) instead of the frame: a shadow that misses it is rejected before any clip.
    ///
    /// Kept part: `h >= 0` (the light's side of the plane), for spot lights also `h <= H` (not
    /// beyond the plane through the light parallel to the receiver), and, for perspective
    /// cameras, shadow points at `depth >= near`. In homogeneous coordinates a point at the
    /// light's height maps to the receiver's horizon (a point at infinity of the plane), which
    /// the frame clip removes or keeps as a finite screen point: nothing is projected to
    /// infinity.
    pub fn caster_in(&self, tri: [DVec3; 3], rect: [f64; 4]) -> Option<Poly> {
        let h = tri.map(|p| self.light_height(p));
        if h.iter().all(|&x| x <= 0.0) {
            return None;
        }
        let recs = match self.light {
            LightSetup::Directional { dir, nl } => [0, 1, 2].map(|k| {
                // q = p + ((d - n·p) / nl) dir, as the homogeneous point
                // (|nl| p + sign(nl) (d - n·p) dir, |nl|): near grazing incidence (`nl` a few
                // roundings from 0) q runs off to 1e16 and more, and the clips below would
                // interpolate between such coordinates and lose every digit of the points
                // on the plane; homogeneous, nothing grows as `nl` falls.
                let p = tri[k];
                let along = nl.signum() * (self.d - self.n.dot(p));
                let [x, y, w, near] = self.screen.camera_h(nl.abs() * p + along * dir, nl.abs());
                [x, y, w, h[k], 1.0, near]
            }),
            LightSetup::Spot { pos, big_h } => [0, 1, 2].map(|k| {
                // q = pos + (p - pos) H / (H - h): homogeneous (H p - h pos, H - h).
                let p = tri[k];
                let w = big_h - h[k];
                let [x, y, wt, near] = self.screen.camera_h(big_h * p - h[k] * pos, w);
                [x, y, wt, h[k], w, near]
            }),
        };
        self.screen.finish(recs, rect).map(|(poly, _)| poly)
    }

    /// Shadow polygons of every caster triangle of `frame` of an object other than
    /// `receiver` (a plane cannot shadow itself), in triangle order; of an object `o` with
    /// `facing_only[o]`, those of its triangles facing the light only ([`Self::faces_light`];
    /// the caller knows when their union is the whole shadow).
    pub fn shadow_polygons(
        &self,
        frame: &Frame<'_>,
        receiver: usize,
        facing_only: &[bool],
    ) -> ScreenPolygons {
        let g = &frame.geometry;
        collect(g.len(), |t| {
            let o = g.object[t] as usize;
            let corners = g.corners(t);
            let facing =
                !facing_only.get(o).copied().unwrap_or(false) || self.faces_light(&corners);
            if o != receiver && frame.is_caster(t) && facing {
                self.caster(corners)
            } else {
                None
            }
        })
    }
}

impl Screen {
    /// The camera of `frame`.
    pub fn new(frame: &Frame<'_>) -> Self {
        Self {
            camera: frame.camera,
            width: f64::from(frame.width()),
            height: f64::from(frame.height()),
        }
    }

    /// The camera's ray through screen point `xy`, parameterised by depth.
    #[inline]
    pub fn ray(&self, xy: [f64; 2]) -> scenes::projection::Ray {
        self.camera.ray(glam::DVec2::new(xy[0], xy[1]))
    }

    /// The camera rays through the four corners of pixel `(i, j)`'s square: top-left,
    /// top-right, bottom-left, bottom-right.
    pub fn corner_rays(&self, i: usize, j: usize) -> [scenes::projection::Ray; 4] {
        let (x, y) = (i as f64, j as f64);
        [[x, y], [x + 1.0, y], [x, y + 1.0], [x + 1.0, y + 1.0]].map(|c| self.ray(c))
    }

    /// The camera depth of `p` (along the viewing direction from the origin): the parameter
    /// of `p` on the camera ray through it.
    #[inline]
    pub fn depth(&self, p: DVec3) -> f64 {
        (p - self.camera.origin).dot(self.camera.forward)
    }

    /// The camera's origin (eye or image-plane centre).
    #[inline]
    pub fn origin(&self) -> DVec3 {
        self.camera.origin
    }

    /// Homogeneous screen coordinates `(X, Y, W)` of the homogeneous point `(q, w)`, and the
    /// camera's near function (`depth - near` scaled by `w`, or 1 for orthographic cameras).
    #[inline]
    fn camera_h(&self, q: DVec3, w: f64) -> [f64; 4] {
        let c = &self.camera;
        let v = q - w * c.origin;
        let (hw, hh) = (0.5 * self.width, 0.5 * self.height);
        match c.kind {
            ProjectionKind::Perspective { tan_half_x, tan_half_y } => {
                let depth = v.dot(c.forward);
                [
                    (depth + v.dot(c.right) / tan_half_x) * hw,
                    (depth - v.dot(c.up) / tan_half_y) * hh,
                    depth,
                    depth - c.near * w,
                ]
            }
            ProjectionKind::Orthographic { half_width, half_height } => [
                (w + v.dot(c.right) / half_width) * hw,
                (w - v.dot(c.up) / half_height) * hh,
                w,
                1.0,
            ],
        }
    }

    /// Triangle `tri` as the camera sees it: clipped at the near plane and to the frame, and
    /// the sign of its winding on screen (`+1` or `-1`); `None` when empty or degenerate
    /// (seen edge-on).
    pub fn triangle(&self, tri: [DVec3; 3]) -> Option<(Poly, f64)> {
        let recs = tri.map(|p| {
            let [x, y, w, near] = self.camera_h(p, 1.0);
            [x, y, w, 1.0, 1.0, near]
        });
        self.finish(recs, self.frame())
    }

    /// The frame as a rectangle `[x0, x1, y0, y1]`.
    pub fn frame(&self) -> [f64; 4] {
        [0.0, self.width, 0.0, self.height]
    }

    /// Clips the three clip-space vertices, divides, and clips exactly to the rectangle `rect`
    /// (`[x0, x1, y0, y1]`); drops empty or degenerate results, orients the rest with positive
    /// [`Poly::area2_rel`] and returns the sign the winding had.
    fn finish(&self, recs: [Rec; 3], rect: [f64; 4]) -> Option<(Poly, f64)> {
        let [x0, x1, y0, y1] = rect;
        let m = FRAME_MARGIN;
        // The seven clip planes' values at a clip-space vertex: `f0, f1, f2`, then the four
        // sides of the rectangle widened by the margin (each plane has at most three non-zero
        // coefficients; written out, not as six-term dot products).
        let value = |plane: usize, r: &Rec| -> f64 {
            match plane {
                0 => r[3],
                1 => r[4],
                2 => r[5],
                3 => r[0] + (m - x0) * r[2],
                4 => -r[0] + (x1 + m) * r[2],
                5 => r[1] + (m - y0) * r[2],
                _ => -r[1] + (y1 + m) * r[2],
            }
        };
        let values: [[f64; 3]; 7] = std::array::from_fn(|plane| recs.map(|r| value(plane, &r)));
        // Trivial reject (culls everything whose shadow misses the rectangle) and accept; only the
        // planes that cut the triangle clip it (a plane every vertex is inside of leaves a
        // polygon as it is).
        let mut cutting = [false; 7];
        for (v, cuts) in values.iter().zip(&mut cutting) {
            if v.iter().all(|&x| x < 0.0) {
                return None;
            }
            *cuts = !v.iter().all(|&x| x >= 0.0);
        }
        let inside_all = !cutting.contains(&true);
        // Clipped only when some plane cuts the triangle; the polygon is then in `bufs[cur]`
        // and each plane clips it into the other buffer.
        let mut bufs;
        let mut na = 3;
        let a: &[Rec] = if inside_all {
            &recs
        } else {
            bufs = [[[0.0; 6]; HCAP]; 2];
            bufs[0][..3].copy_from_slice(&recs);
            let mut cur = 0;
            for plane in (0..7).filter(|&plane| cutting[plane]) {
                let (first, second) = bufs.split_at_mut(1);
                let (a, b) = if cur == 0 {
                    (&first[0], &mut second[0])
                } else {
                    (&second[0], &mut first[0])
                };
                let mut nb = 0;
                for k in 0..na {
                    let p = a[k];
                    let q = a[if k + 1 == na { 0 } else { k + 1 }];
                    let (dp, dq) = (value(plane, &p), value(plane, &q));
                    if dp >= 0.0 && nb < HCAP {
                        b[nb] = p;
                        nb += 1;
                    }
                    if ((dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0)) && nb < HCAP {
                        let t = dp / (dp - dq);
                        let mut x = [0.0; 6];
                        for (i, xi) in x.iter_mut().enumerate() {
                            *xi = p[i] + t * (q[i] - p[i]);
                        }
                        b[nb] = x;
                        nb += 1;
                    }
                }
                cur = 1 - cur;
                na = nb;
                if na < 3 {
                    return None;
                }
            }
            &bufs[cur]
        };
        let mut poly = Poly::new();
        for r in &a[..na] {
            let (x, y) = (r[0] / r[2], r[1] / r[2]);
            if r[2].is_nan() || r[2] <= 0.0 || !x.is_finite() || !y.is_finite() {
                return None;
            }
            poly.push([x, y]);
        }
        // A side every vertex is inside of leaves the polygon as it is; the others clip it
        // through a second buffer, made only then (a polygon is 392 bytes to zero, and most
        // triangles lie inside the rectangle).
        let ((lx, hx), (ly, hy)) = (poly.range(0), poly.range(1));
        let sides = [
            (lx < x0, 0, x0, true),
            (hx > x1, 0, x1, false),
            (ly < y0, 1, y0, true),
            (hy > y1, 1, y1, false),
        ];
        if sides.iter().any(|side| side.0) {
            let mut other = Poly::new();
            for (cuts, axis, c, above) in sides {
                if cuts {
                    keep_into(&poly, axis, c, above, &mut other);
                    std::mem::swap(&mut poly, &mut other);
                }
            }
        }
        if poly.n < 3 {
            return None;
        }
        let area2 = poly.area2_rel(0.5 * (x0 + x1), 0.5 * (y0 + y1));
        if !(area2 != 0.0 && area2.is_finite()) {
            return None;
        }
        if area2 < 0.0 {
            poly.reverse();
        }
        Some((poly, area2.signum()))
    }
}

/// The polygons `f(0..count)` yields, in index order, built in parallel in fixed chunks (so the
/// result does not depend on the thread count).
fn collect(count: usize, f: impl Fn(usize) -> Option<Poly> + Sync) -> ScreenPolygons {
    const CHUNK: usize = 4096;
    let parts: Vec<ScreenPolygons> = (0..count.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut part = ScreenPolygons::default();
            for t in c * CHUNK..((c + 1) * CHUNK).min(count) {
                if let Some(p) = f(t) {
                    part.push(p.points());
                }
            }
            part
        })
        .collect();
    ScreenPolygons::concat(&parts)
}

/// The depth at which the camera ray `ray` (parameterised by depth) meets the plane through
/// `corner` with normal `n` (any length); infinite or NaN when the ray runs along the plane.
#[inline]
pub(crate) fn plane_depth(ray: &scenes::projection::Ray, n: DVec3, corner: DVec3) -> f64 {
    n.dot(corner - ray.origin) / n.dot(ray.direction)
}
