//! Part of stage "rasterization of blockers": the caster triangles that need not be
//! rasterized, because the shadow of a closed caster seen from outside is that of its
//! triangles facing the light. Not in the paper, which rasterizes every caster; the option
//! [`AfsmOptions::facing_culling`](super::AfsmOptions::facing_culling) turns it off.
//!
//! # Why the rest is enough
//!
//! Let object `O` be closed ([`crate::closed`]: every edge used as often in one direction as in
//! the other, corners compared by vertex number; a mesh split for its normals is rasterized
//! whole, since comparing positions cost `random-1m`'s million separate triangles 30 ms at
//! one thread, more than culling saves on the other scenes), so that it has a winding number
//! `w(x)` around every point off it, constant between its triangles and changed by one where
//! a path crosses a triangle: up where it crosses against the triangle's normal (its corners'
//! order), down where it crosses along it. A sample `p` is shadowed by `O` when the segment
//! `S` from `p` (past the sample's shadow offset) to the light crosses a triangle of `O` other
//! than the sample's own. Along `S` the crossings' signed count is `w(light) - w(p')`, `p'`
//! the start of `S`.
//!
//! - `w(light) = 0`: a directional light is at infinity, and a spot light's every caster
//!   lies beyond the light's `near` plane, where casters are cut (asked: every corner of
//!   `O`'s bounding box at light depth `>= near`), so the light and the part of `S` the
//!   casters do not reach are outside `O`'s box.
//! - `w(p⁻) = 0` for the point `p⁻` just before `p` on its camera ray: the ray meets no
//!   triangle before `p` (the G-buffer's nearest), and it comes from outside `O`'s box (an
//!   orthographic camera's from infinity; a perspective one's from its eye, with every corner
//!   of the box at camera depth `>= near`, so that nothing of `O` is cut away in front of
//!   `p`).
//! - `p'` is `p⁻` unless `p` lies on a triangle `R` of `O` with the camera and the light on
//!   the two sides of its plane (an attached shadow). Then `w(p') = 1` when the camera sees
//!   `R`'s front (its normal toward the eye: the path from `p⁻` to `p'` crosses `R` against
//!   its normal), and this is asked of every sample on `O` (a mesh seen from its back, as an
//!   inward-wound room is, keeps all its triangles).
//!
//! So the crossings' count along `S` is 0 or -1: a segment that crosses `O` crosses it down
//! at least once, along a triangle's normal, which then points toward the light (`n · L > 0`,
//! `L` toward the light). Rasterizing only those triangles shadows the same samples. Only
//! samples whose segment runs through an edge, a corner or along a triangle's plane, or whose
//! shadow offset reaches another triangle of `O`, escape the count: ties that `afsm` already
//! breaks by its own rule, and rounding. Transmittance counts every crossing, so only opaque
//! casters qualify.
//!
//! On `bunny-plane` at 800 x 600 the rasterization visits half the BSP nodes (1,161,070 ->
//! 605,905) with the same image. The check costs [`closed_objects`] (at one thread 4-5 ms
//! for the bunny, most of it bucketing and checking its edges), then, when an object
//! qualifies, a pass over the triangles (about 1 ms) and one over what the camera sees
//! ([`Seen`]): at one sub-sample per pixel the G-buffer's triangle per pixel (4 bytes each)
//! stands for the samples (32 bytes each), which lie on those triangles, or on fewer when a
//! spot light drops some; asking of more pixels only keeps more triangles. That last pass
//! took 3.3-3.7 ms over the samples, 0.6-1 ms over the G-buffer.

use super::samples::Sample;
use crate::closed::{closed_objects, per_object, Corners};
use crate::frame::Frame;
use glam::DVec3;
use rayon::prelude::*;
use scenes::{Light, Projector};

/// What the camera sees, for the check that no sample of an object is seen from the back of
/// its triangle.
#[derive(Debug, Clone, Copy)]
pub enum Seen<'a> {
    /// The nearest triangle per pixel, [`NO_TRIANGLE`](crate::raster::NO_TRIANGLE) for
    /// background: every sample lies on one of them (the frame's G-buffer, at one sub-sample
    /// per pixel).
    Pixels(&'a [u32]),
    /// The samples themselves.
    Samples(&'a [Sample]),
}

/// Which triangles to rasterize: per object, whether only its triangles facing the light
/// are needed (`facing_only`), and the light.
pub struct Needed {
    facing_only: Vec<bool>,
    light: Toward,
}

/// Where the light is seen from a point.
#[derive(Clone, Copy)]
enum Toward {
    /// Along this direction (a directional light's reversed).
    Direction(DVec3),
    /// At this point (a spot light's position).
    Point(DVec3),
}

impl Toward {
    fn new(light: &Light) -> Self {
        match *light {
            Light::Directional { direction } => Self::Direction(-direction),
            Light::Spot { position, .. } => Self::Point(position),
        }
    }
}

impl Needed {
    /// Decides, for `frame` with casters `is_opaque_caster(o)` (objects that cast shadows and
    /// let no light through), what its camera sees (`seen`) and the light projector `light`
    /// the casters are cut by, which objects qualify (see the module doc).
    pub fn new(
        frame: &Frame<'_>,
        seen: Seen<'_>,
        light: &Projector,
        is_opaque_caster: impl Fn(usize) -> bool + Sync,
    ) -> Self {
        let g = &frame.geometry;
        let objects = frame.scene.objects.len();
        let camera = &frame.camera;
        // Closed by vertex number (see the module doc), and beyond both near planes (the
        // mesh's box holds every corner of its triangles).
        let closed = closed_objects(g, objects, &is_opaque_caster, Corners::ByNumber);
        let beyond_near = |p: &Projector, (lo, hi): (DVec3, DVec3)| {
            !p.is_perspective()
                || scenes::mesh::box_corners(lo, hi).iter().all(|&c| p.depth_of(c) >= p.near)
        };
        let outside: Vec<bool> = (0..objects)
            .map(|o| {
                closed[o]
                    && frame.scene.objects[o].mesh.bounds().is_some_and(|b| {
                        b.0.is_finite()
                            && b.1.is_finite()
                            && beyond_near(camera, b)
                            && beyond_near(light, b)
                    })
            })
            .collect();
        if !outside.contains(&true) {
            return Self { facing_only: outside, light: Toward::new(&frame.scene.light) };
        }
        // The closed objects some sample sees from the back of its triangle: each triangle of
        // a closed object asked once (`1 + its object` when it is seen from its back, else 0),
        // then each sample reads its triangle's answer and marks that slot (slot 0 for none),
        // no object looked up per sample.
        let eye =
            |p: DVec3| if camera.is_perspective() { camera.origin - p } else { -camera.forward };
        let back: Vec<u32> = (0..g.len())
            .into_par_iter()
            .map(|t| {
                let o = g.object[t] as usize;
                if !outside[o] {
                    return 0;
                }
                let c = g.corners(t);
                let front = (c[1] - c[0]).cross(c[2] - c[0]).dot(eye(c[0]));
                if front <= 0.0 || front.is_nan() {
                    o as u32 + 1
                } else {
                    0
                }
            })
            .collect();
        let seen_from_back = match seen {
            Seen::Pixels(tris) => from_back(tris, |&t| t, objects, &back),
            Seen::Samples(samples) => from_back(samples, |s| s.tri, objects, &back),
        };
        let facing_only = (0..objects).map(|o| outside[o] && !seen_from_back[o]).collect();
        Self { facing_only, light: Toward::new(&frame.scene.light) }
    }

    /// Whether caster triangle `t` of `frame` must be rasterized: always, unless its object
    /// qualifies and the triangle faces away from the light (`n · L < 0`; a triangle edge-on
    /// to the light, which covers no area of the light's image, is kept).
    #[inline]
    pub fn needs(&self, frame: &Frame<'_>, t: usize) -> bool {
        let g = &frame.geometry;
        if !self.facing_only.get(g.object[t] as usize).copied().unwrap_or(false) {
            return true;
        }
        let c = g.corners(t);
        let n = (c[1] - c[0]).cross(c[2] - c[0]);
        let towards = match self.light {
            Toward::Direction(d) => d,
            Toward::Point(q) => q - c[0],
        };
        let facing = n.dot(towards);
        facing >= 0.0 || facing.is_nan()
    }

    /// How many objects have only their triangles facing the light rasterized.
    pub fn objects(&self) -> usize {
        self.facing_only.iter().filter(|&&f| f).count()
    }
}

/// Per object of the `objects`: whether the triangle `tri(item)` of one of the `items`
/// ([`NO_TRIANGLE`](crate::raster::NO_TRIANGLE) for none) has `back[t]`, which is 0 or 1 + the
/// object's index.
fn from_back<T: Sync>(
    items: &[T],
    tri: impl Fn(&T) -> u32 + Sync,
    objects: usize,
    back: &[u32],
) -> Vec<bool> {
    let seen = per_object(
        items.len(),
        objects + 1,
        false,
        |seen, i| seen[back.get(tri(&items[i]) as usize).map_or(0, |&b| b as usize)] = true,
        |x, y| x || y,
    );
    seen[1..].to_vec()
}
