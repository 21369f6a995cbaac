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

use super::clip::{keep, Poly};
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

/// Margin, in pixels, of the homogeneous frame clip that bounds coordinates before the
/// division; the exact frame clip follows in screen space.
const FRAME_MARGIN: f64 = 1.0;

/// The light as the projection onto the receiver plane needs it.
#[derive(Debug, Clone, Copy)]
enum LightSetup {
    /// Parallel projection along `dir` (the direction light travels); `nl = n·dir != 0`.
    Directional { dir: DVec3, nl: f64 },
    /// Central projection from `pos`, at height `big_h > 0` above the receiver plane.
    Spot { pos: DVec3, big_h: f64 },
}

/// The receiver plane, light and camera of a frame, with the clip functions derived from them.
#[derive(Debug, Clone)]
pub(crate) struct Setup {
    /// Index of the receiver object.
    pub receiver: usize,
    /// Unit normal of the receiver plane.
    n: DVec3,
    /// Offset of the receiver plane (`n·p = d`).
    d: f64,
    /// `+1` or `-1`: the sign of `n·p - d` on the light's side of the plane.
    light_side: f64,
    /// `+1` or `-1`: the sign of `n·p - d` on the camera's side of the plane.
    camera_side: f64,
    /// Tolerance of "on the camera's side" for occluders: `1e-9` of the receiver's extent.
    side_tolerance: f64,
    light: LightSetup,
    camera: Projector,
    /// Image width in pixels.
    pub width: f64,
    /// Image height in pixels.
    pub height: f64,
}

impl Setup {
    /// Checks that `exact` applies to the frame and derives the projection.
    pub fn new(frame: &Frame<'_>) -> Result<Self, ReferenceError> {
        let name = &frame.scene.name;
        if frame.effects.transparency {
            return Err(ReferenceError::NotApplicable(format!(
                "exact does not apply to scene `{name}`: it has semi-transparent casters \
                 (effect `transparency`), and exact handles opaque casters only; use the \
                 `raytrace` reference"
            )));
        }
        let no_plane = || {
            ReferenceError::NotApplicable(format!(
                "exact does not apply to scene `{name}`: no planar receiver is visible (effect \
                 `planar_receiver` is off); use the `raytrace` reference"
            ))
        };
        if !frame.effects.planar_receiver {
            return Err(no_plane());
        }
        let (receiver, n, d) = frame.scene.receiver_plane().ok_or_else(no_plane)?;
        let (light, light_side) = match frame.scene.light {
            Light::Directional { direction } => {
                let dir = direction;
                let nl = n.dot(dir);
                if nl == 0.0 || !nl.is_finite() {
                    return Err(ReferenceError::NotApplicable(format!(
                        "exact does not apply to scene `{name}`: the directional light runs \
                         parallel to the receiver plane"
                    )));
                }
                // Light comes from -dir: the lit side is where n·p - d has the sign of -n·dir.
                (LightSetup::Directional { dir, nl }, -nl.signum())
            }
            Light::Spot { position, .. } => {
                let s = n.dot(position) - d;
                if s == 0.0 || !s.is_finite() {
                    return Err(ReferenceError::NotApplicable(format!(
                        "exact does not apply to scene `{name}`: the spot light lies in the \
                         receiver plane"
                    )));
                }
                (LightSetup::Spot { pos: position, big_h: s.abs() }, s.signum())
            }
        };
        let camera = frame.camera;
        let camera_side = match camera.kind {
            ProjectionKind::Perspective { .. } => n.dot(camera.origin) - d,
            ProjectionKind::Orthographic { .. } => -n.dot(camera.forward),
        };
        let camera_side = if camera_side < 0.0 { -1.0 } else { 1.0 };
        // The receiver's own size: its plane holds its vertices within `1e-9` of it
        // (`Mesh::plane`); the scene's size, which a far-away object sets, plays no part.
        let extent = frame.scene.objects[receiver].mesh.bounds().map_or(0.0, |(lo, hi)| {
            let e = (hi - lo).length();
            if e.is_finite() {
                e
            } else {
                0.0
            }
        });
        let side_tolerance = 1e-9 * extent;
        Ok(Self {
            receiver,
            n,
            d,
            light_side,
            camera_side,
            side_tolerance,
            light,
            camera,
            width: f64::from(frame.width()),
            height: f64::from(frame.height()),
        })
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

    /// Height of `p` above the receiver plane, positive on the light's side.
    #[inline]
    fn light_height(&self, p: DVec3) -> f64 {
        self.light_side * (self.n.dot(p) - self.d)
    }

    /// The shadow of caster triangle `tri` on the receiver plane, in screen space, clipped to
    /// the frame; `None` when empty or degenerate.
    ///
    /// Kept part: `h >= 0` (the light's side of the plane), for spot lights also `h <= H` (not
    /// beyond the plane through the light parallel to the receiver), and, for perspective
    /// cameras, shadow points at `depth >= near`. In homogeneous coordinates a point at the
    /// light's height maps to the receiver's horizon (a point at infinity of the plane), which
    /// the frame clip removes or keeps as a finite screen point: nothing is projected to
    /// infinity.
    pub fn caster(&self, tri: [DVec3; 3]) -> Option<Poly> {
        let h = tri.map(|p| self.light_height(p));
        if h.iter().all(|&x| x <= 0.0) {
            return None;
        }
        let recs = match self.light {
            LightSetup::Directional { dir, nl } => [0, 1, 2].map(|k| {
                let p = tri[k];
                let q = p + ((self.d - self.n.dot(p)) / nl) * dir;
                let [x, y, w, near] = self.camera_h(q, 1.0);
                [x, y, w, h[k], 1.0, near]
            }),
            LightSetup::Spot { pos, big_h } => [0, 1, 2].map(|k| {
                // q = pos + (p - pos) H / (H - h): homogeneous (H p - h pos, H - h).
                let p = tri[k];
                let w = big_h - h[k];
                let [x, y, wt, near] = self.camera_h(big_h * p - h[k] * pos, w);
                [x, y, wt, h[k], w, near]
            }),
        };
        self.finish(recs, true)
    }

    /// Receiver triangle `tri` in screen space, clipped at the camera's near plane and to the
    /// frame; `None` when empty or degenerate.
    pub fn receiver(&self, tri: [DVec3; 3]) -> Option<Poly> {
        let recs = tri.map(|p| {
            let [x, y, w, near] = self.camera_h(p, 1.0);
            [x, y, w, 1.0, 1.0, near]
        });
        self.finish(recs, true)
    }

    /// The part of triangle `tri` on the camera's side of the receiver plane (within
    /// [`Setup::side_tolerance`]) in screen space, clipped at the near plane and to the frame
    /// widened by a pixel (not exactly: for marking touched pixels only).
    pub fn occluder(&self, tri: [DVec3; 3]) -> Option<Poly> {
        let recs = tri.map(|p| {
            let side = self.camera_side * (self.n.dot(p) - self.d) + self.side_tolerance;
            let [x, y, w, near] = self.camera_h(p, 1.0);
            [x, y, w, side, 1.0, near]
        });
        self.finish(recs, false)
    }

    /// Clips the three clip-space vertices, divides, and (with `exact_frame`) clips exactly to
    /// the frame; drops empty or degenerate results and orients the rest with positive
    /// [`Poly::area2_rel`].
    fn finish(&self, recs: [Rec; 3], exact_frame: bool) -> Option<Poly> {
        let (wd, ht, m) = (self.width, self.height, FRAME_MARGIN);
        let planes: [Rec; 7] = [
            [0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            [1.0, 0.0, m, 0.0, 0.0, 0.0],
            [-1.0, 0.0, wd + m, 0.0, 0.0, 0.0],
            [0.0, 1.0, m, 0.0, 0.0, 0.0],
            [0.0, -1.0, ht + m, 0.0, 0.0, 0.0],
        ];
        let eval = |pl: &Rec, r: &Rec| -> f64 { pl.iter().zip(r).map(|(a, b)| a * b).sum() };
        // Trivial reject (culls everything whose shadow misses the frame) and accept.
        let mut inside_all = true;
        for pl in &planes {
            let v = recs.map(|r| eval(pl, &r));
            if v.iter().all(|&x| x < 0.0) {
                return None;
            }
            inside_all &= v.iter().all(|&x| x >= 0.0);
        }
        let mut a = [[0.0; 6]; HCAP];
        let mut na = 3;
        a[..3].copy_from_slice(&recs);
        if !inside_all {
            let mut b = [[0.0; 6]; HCAP];
            for pl in &planes {
                let mut nb = 0;
                for k in 0..na {
                    let p = a[k];
                    let q = a[if k + 1 == na { 0 } else { k + 1 }];
                    let (dp, dq) = (eval(pl, &p), eval(pl, &q));
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
                std::mem::swap(&mut a, &mut b);
                na = nb;
                if na < 3 {
                    return None;
                }
            }
        }
        let mut pts = [[0.0; 2]; HCAP];
        for (k, r) in a[..na].iter().enumerate() {
            let (x, y) = (r[0] / r[2], r[1] / r[2]);
            if r[2].is_nan() || r[2] <= 0.0 || !x.is_finite() || !y.is_finite() {
                return None;
            }
            pts[k] = [x, y];
        }
        let mut poly = Poly::from_slice(&pts[..na]);
        if exact_frame {
            poly = keep(&poly, 0, 0.0, true);
            poly = keep(&poly, 0, wd, false);
            poly = keep(&poly, 1, 0.0, true);
            poly = keep(&poly, 1, ht, false);
        }
        if poly.n < 3 {
            return None;
        }
        let area2 = poly.area2_rel(0.5 * wd, 0.5 * ht);
        if !(area2 != 0.0 && area2.is_finite()) {
            // Degenerate: a segment or a point. Occluders still touch pixels.
            return (!exact_frame).then_some(poly);
        }
        if area2 < 0.0 {
            poly.reverse();
        }
        Some(poly)
    }

    /// Shadow polygons of every caster triangle of `frame` (every triangle of a shadow-casting
    /// object other than the receiver), in triangle order.
    pub fn shadow_polygons(&self, frame: &Frame<'_>) -> ScreenPolygons {
        let g = &frame.geometry;
        collect(g.len(), |t| {
            if g.object[t] as usize != self.receiver && frame.is_caster(t) {
                self.caster(g.corners(t))
            } else {
                None
            }
        })
    }

    /// Screen polygons of the receiver object's triangles.
    pub fn receiver_polygons(&self, frame: &Frame<'_>) -> ScreenPolygons {
        let g = &frame.geometry;
        collect(g.len(), |t| {
            (g.object[t] as usize == self.receiver).then(|| self.receiver(g.corners(t))).flatten()
        })
    }

    /// Screen polygons (frame widened by a pixel) of the parts of other objects' triangles on
    /// the camera's side of the receiver plane.
    pub fn occluder_polygons(&self, frame: &Frame<'_>) -> ScreenPolygons {
        let g = &frame.geometry;
        collect(g.len(), |t| {
            (g.object[t] as usize != self.receiver).then(|| self.occluder(g.corners(t))).flatten()
        })
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
    let mut all = ScreenPolygons {
        points: Vec::with_capacity(parts.iter().map(|p| p.points.len()).sum()),
        ranges: Vec::with_capacity(parts.iter().map(|p| p.ranges.len()).sum()),
    };
    for p in &parts {
        for c in p.contours() {
            all.push(c);
        }
    }
    all
}
