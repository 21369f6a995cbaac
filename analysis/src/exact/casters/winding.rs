//! A receiver facing away from the light in the shadow of its own closed object, by the
//! winding number just beyond it: the proof for the receivers [`CasterGrid::behind_own_facing`]
//! leaves, where a light line from the receiver meets its object again beyond it.
//!
//! Let the object be closed, with winding number `w` as in [`super::super::closed`]'s module
//! doc (0 far from the object, changed by one where a path crosses a triangle: up when it
//! crosses against the triangle's normal), under a directional light. Let `T` be a receiver
//! of the object facing away from the light.
//!
//! 1. Let no other triangle of the object meet the inside of `T` (its points off its edges).
//!    Then just beyond `T` (on its side away from the light) `w` is one number `w_b`
//!    over all of `T`: it cannot change between two points of `T` without a triangle between
//!    them.
//! 2. Just before `T` (on its side toward the light) `w` is then `w_b + 1`: the path toward
//!    the light crosses `T` against its normal. Where the light comes from, `w = 0`. So where
//!    `w_b + 1 != 0`, the segment from any point of `T` to the light crosses a triangle of
//!    the object: all of `T` is in the object's shadow.
//! 3. `w_b` is counted along one light line through the inside of `T`: from far beyond `T`
//!    (`w = 0`) back to `T`, plus one for each crossing of a triangle whose normal points
//!    away from the light, minus one for each facing it.
//!
//! So `T` is shadowed unless the count is `-1`. On an object whose inside and outside are
//! as its normals say, `w` is 0 outside and 1 inside, so the count is 0 or 1, and every
//! triangle facing away from the light passes, under a bunny's ears too. On a mesh turned
//! inside out, `w` is -1 inside and the count beyond a face the light sees is -1: it fails, as
//! it must (tested).
//!
//! # Every decision exact or beyond its rounding
//!
//! - Light lines are the lines of one light-space image point: `(p·right, p·up)` with the
//!   basis vectors as rounded. Their direction is `±right × up`, within a few roundings of
//!   the light's. The line taken is the one through the centroid `c` of the receiver's
//!   image as computed: a point of the image plane, whichever rounding made it.
//! - Where `c` lies against a triangle's exact image (inside, outside, or too close to tell)
//!   is decided by its three edge functions with the bound of `images_separated`, from the
//!   largest corner coordinate of both triangles (a coordinate `p·right` is within 8
//!   roundings of that, not of its own size). Inside, the edge functions' common sign is the
//!   image's orientation, which says which way the triangle's normal points along the line.
//!   A receiver's `c` must lie inside its own image.
//! - A triangle `X` of the object wholly nearer the light than `T` by light-space depth
//!   (`p·forward`, within the same rounding), or wholly beyond it, does not meet `T`; the
//!   line crosses it, if at all, before `T` or beyond it.
//! - For every other `X` whose image is not apart from `T`'s ([`images_separated`], with the
//!   same bound), a plane must keep the two apart: either every corner of `X` lies on one side
//!   of `T`'s plane but corners of `T` on it, or every corner of `T` lies on one side of
//!   `X`'s plane or on it. Sides are the signs of Shewchuk's `orient3d`, exact for any `f64`
//!   corners (the `robust` crate). Either way `X` does not meet the inside of `T`: what `X`
//!   has on `T`'s plane is a corner or an edge of `T`, or what `T` has on `X`'s plane is a
//!   corner or an edge of its own. Where the line crosses the inside of `X`, the side tells
//!   whether beyond `T`: `X` on `T`'s far side, or `T` on the side of `X`'s plane that the
//!   line leaves toward `X`.
//! - Anything else (coplanar triangles, triangles whose planes cross each other near `T`, a
//!   line too close to an edge, a facing the rounding cannot tell) fails, and the receiver
//!   goes to the casters' shadows as before.
//!
//! Spot lights are not asked (their light lines meet at the light; `behind_own_facing` still
//! is).
//!
//! A triangle meeting the inside of `T` is found by the scan of `T`'s light-space box, as
//! every caster is ([`CasterGrid::query`]): one whose box the rounding put just apart from
//! `T`'s, across a cell's border, could only meet `T` within that rounding of `T`'s box, and
//! change `w_b` on no more than a sliver that wide. A triangle the line crosses is never
//! missed: `c` lies inside `T`'s image by more than the rounding of either box.
//!
//! # Cost
//!
//! One scan of the receiver's light-space box, as `behind_own_facing`'s. A triangle wholly
//! nearer the light than the receiver, or wholly beyond it, by light-space depth, is settled
//! by its depths (it cannot meet the receiver); only the others are tested for a separating
//! plane, with two to six exact orientations. On `bunny-plane` at 800 x 600 it passes 3,982 of
//! the 4,085 receivers facing away from the light, against 1,876 for `behind_own_facing` (the
//! two together 3,984), and the stage `surface shadows` took 102.8 -> 88.1 ms at one thread
//! (4 alternating runs, load 1.2) and 55.3 -> 48.9 at two (6 runs, load 1.0-1.2), with the same
//! image bit for bit; `cage` and `bumpy` are unchanged. Testing every triangle whose image is
//! not apart for a plane, without the depths first, took 95.4 ms.

use super::{corner_magnitude, images_separated, joint_extent, Away, CasterGrid, Space};
use glam::DVec3;
use robust::{orient3d, Coord3D};
use std::cell::Cell;

impl CasterGrid<'_> {
    /// Whether receiver `r`, facing away from a directional light (beyond the rounding of its
    /// normal), is in the shadow of its own object by the count of crossings beyond it (see
    /// the module doc): no other triangle of the object meets its inside, and beyond it the
    /// light line through its image's centroid does not cross one more triangle facing the
    /// light than facing away (a count of -1). `false` under a spot light and wherever a
    /// decision is within its rounding. The object must be closed and cast shadows (the caller's checks): a triangle
    /// of it missing from the grid would go uncounted.
    pub fn behind_own_winding(&self, r: u32) -> bool {
        let Space::Directional { right, up, forward } = self.space else { return false };
        let g = self.geometry;
        let Some(Away { tri, b, z, object, own, magnitude: tri_magnitude }) = self.away(r) else {
            return false;
        };
        let image = self.images[r as usize];
        let at = [
            (image[0][0] + image[1][0] + image[2][0]) / 3.0,
            (image[0][1] + image[1][1] + image[2][1]) / 3.0,
        ];
        let extent = (b[2] - b[0]).max(b[3] - b[1]);
        // The receiver's orientation on the image plane; with `h`, which way the line's
        // direction `right × up` points along the light, it says which side of the
        // receiver's plane is beyond it, and must agree with its facing.
        let Where::Inside(s_t) = locate(&image, at, rounding(tri_magnitude), extent) else {
            return false;
        };
        let h = if right.cross(up).dot(forward) > 0.0 { 1 } else { -1 };
        if h * s_t != 1 {
            return false;
        }
        // Whether every triangle asked so far passed, and the crossings' count beyond `r`.
        let fine = Cell::new(true);
        let count = Cell::new(0i64);
        let ask = |c: u32| -> bool {
            if !fine.get() || c == r || g.object[c as usize] != object {
                return false;
            }
            if !self.boxes_meet(c, &b, own) {
                return false;
            }
            let corners = g.corners(c as usize);
            let m = rounding(tri_magnitude.max(corner_magnitude(&corners)));
            // Depths along the light, each within `m` of its exact value.
            let depth = corners.map(|p| p.dot(forward));
            let (near, far) =
                (depth[0].min(depth[1]).min(depth[2]), depth[0].max(depth[1]).max(depth[2]));
            // Wholly nearer the light than `r`: it neither meets `r` nor lies beyond it (the
            // light line leaves `r` along increasing depth).
            if far < z[0] - 2.0 * m {
                return false;
            }
            let span = joint_extent(&self.boxes[c as usize], &b);
            let other = &self.images[c as usize];
            // Wholly beyond `r` in depth: it does not meet `r`, and crosses the line, if at
            // all, beyond `r`. Otherwise a plane must keep it apart from `r`.
            let apart = if near > z[1] + 2.0 * m {
                None
            } else {
                if images_separated(&image, other, m, span) {
                    return false;
                }
                let Some(apart) = Apart::new(&tri, &corners) else {
                    fine.set(false);
                    return false;
                };
                Some(apart)
            };
            match locate(other, at, m, span) {
                Where::Outside => {}
                Where::Unsure => fine.set(false),
                Where::Inside(s_x) => {
                    let beyond = match apart {
                        None => true,
                        // `X` on the side of `r`'s plane that `h (right × up)` points to.
                        Some(Apart::OtherOnSide(side)) => side == h * s_t,
                        // The line leaves `r` toward `X`'s plane: `r` on the side of it
                        // opposite to where `h (right × up)` points.
                        Some(Apart::ReceiverOnSide(side)) => side == -h * s_x,
                    };
                    if beyond {
                        count.set(count.get() + i64::from(h * s_x));
                    }
                }
            }
            false
        };
        self.scan(&b, &ask, &mut Vec::new());
        fine.get() && count.get() != -1
    }
}

/// The bound on the rounding of a light-space image coordinate `p·right` of points of
/// coordinate magnitude up to `magnitude`, as `images_separated` takes it: a dot product of
/// three terms with a unit vector is within `3 √3` roundings of the magnitude.
fn rounding(magnitude: f64) -> f64 {
    8.0 * f64::EPSILON * magnitude
}

/// Where a point lies against a triangle's exact image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Where {
    /// Inside, off its edges; the image's orientation (`1` counterclockwise, `-1` clockwise).
    Inside(i8),
    /// Outside the closed image.
    Outside,
    /// Within the rounding of an edge's line, or the image has no orientation.
    Unsure,
}

/// Where point `v` lies against the exact image of a triangle whose computed image is `p`,
/// each coordinate within `m` of the exact one, every difference within `extent` of zero:
/// each edge function `e × (v - s)` is within `8 m (|e| + extent)` of its exact value (the
/// bound of [`images_separated`]). Two of them beyond it with opposite signs put `v` outside,
/// all three with one sign inside; anything else is unsure. No orientation is taken from the
/// computed area, whose sign a sliver's rounding can flip.
fn locate(p: &[[f64; 2]; 3], v: [f64; 2], m: f64, extent: f64) -> Where {
    let (mut positive, mut negative, mut unsure) = (false, false, false);
    for k in 0..3 {
        let (s, e) = (p[k], p[(k + 1) % 3]);
        let (ex, ey) = (e[0] - s[0], e[1] - s[1]);
        let tol = 8.0 * m * (ex.abs() + ey.abs() + extent);
        let f = ex * (v[1] - s[1]) - ey * (v[0] - s[0]);
        // NaN is unsure.
        if f > tol {
            positive = true;
        } else if f < -tol {
            negative = true;
        } else {
            unsure = true;
        }
    }
    match (positive, negative, unsure) {
        (true, true, _) => Where::Outside,
        (true, false, false) => Where::Inside(1),
        (false, true, false) => Where::Inside(-1),
        _ => Where::Unsure,
    }
}

/// The exact side of point `d` against the plane of triangle `a`: the sign of
/// `(d - a0)·((a1 - a0) × (a2 - a0))`, `None` for a NaN. Shewchuk's `orient3d` is positive
/// where `d` lies below the plane as seen with `a`'s corners counterclockwise, that is on the
/// side opposite that normal.
fn side(a: &[DVec3; 3], d: DVec3) -> Option<i8> {
    let c = |p: DVec3| Coord3D { x: p.x, y: p.y, z: p.z };
    let o = orient3d(c(a[0]), c(a[1]), c(a[2]), c(d));
    if o > 0.0 {
        Some(-1)
    } else if o < 0.0 {
        Some(1)
    } else if o == 0.0 {
        Some(0)
    } else {
        None
    }
}

/// How two triangles `T` and `X` are kept apart by a plane, so that `X` does not meet the
/// inside of `T`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Apart {
    /// `X` lies on this side of `T`'s plane ([`side`]), except for corners it shares with `T`.
    OtherOnSide(i8),
    /// `T` lies on this side of `X`'s plane, or on it with at most two corners.
    ReceiverOnSide(i8),
}

impl Apart {
    /// How `x` is kept apart from the inside of `t`, or `None` when neither lies on one side
    /// of the other's plane as these need.
    fn new(t: &[DVec3; 3], x: &[DVec3; 3]) -> Option<Self> {
        one_side(t, x, |p| t.contains(p))
            .map(Self::OtherOnSide)
            .or_else(|| one_side(x, t, |_| true).map(Self::ReceiverOnSide))
    }
}

/// The side of `a`'s plane on which every corner of `b` lies that is not on the plane, with
/// one such corner at least, and only corners with `on_plane(p)` on the plane.
///
/// With `b`'s corners on the plane restricted to `a`'s corners, what `b` has on the plane
/// is a corner or an edge of `a`; with `b` the receiver and any corners on the plane, what
/// the receiver has on the other's plane is a corner or an edge of its own. Either way the
/// inside of the receiver is off the other triangle.
fn one_side(a: &[DVec3; 3], b: &[DVec3; 3], on_plane: impl Fn(&DVec3) -> bool) -> Option<i8> {
    let mut found = 0;
    for p in b {
        match side(a, *p)? {
            0 if on_plane(p) => {}
            s if s != 0 && (found == 0 || s == found) => found = s,
            _ => return None,
        }
    }
    (found != 0).then_some(found)
}

#[cfg(test)]
mod tests {
    use super::super::tests::{blocked, cuboid, one_object, two_stars, uniform};
    use super::super::{Facing, LitSide};
    use super::*;
    use instrumentation::Recorder;
    use methods::Frame;
    use scenes::Light;

    /// The side is the sign of the height along the corners' normal, exactly: a point a
    /// rounding above a plane through large coordinates is above it.
    #[test]
    fn sides_are_exact() {
        let a = [DVec3::ZERO, DVec3::X, DVec3::Y];
        assert_eq!(side(&a, DVec3::Z), Some(1));
        assert_eq!(side(&a, -DVec3::Z), Some(-1));
        assert_eq!(side(&a, DVec3::new(5.0, -3.0, 0.0)), Some(0));
        let big = a.map(|p| p * 1e6 + DVec3::new(1e6, 1e6, 1e6));
        let just_above = DVec3::new(1.5e6, 1.5e6, 1e6 + 1e6 * f64::EPSILON);
        assert_eq!(side(&big, just_above), Some(1));
        assert_eq!(side(&a, DVec3::new(0.0, 0.0, f64::NAN)), None);
    }

    /// A neighbour sharing an edge lies on one side beyond it; a triangle through the
    /// receiver is on neither side, nor is a coplanar one; one through the receiver's plane
    /// beyond its edge leaves the receiver on one side of its own plane.
    #[test]
    fn triangles_apart_from_the_receiver() {
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let folded = [DVec3::Y, DVec3::X, DVec3::new(1.0, 1.0, 0.5)];
        assert_eq!(Apart::new(&t, &folded), Some(Apart::OtherOnSide(1)));
        let through =
            [DVec3::new(0.2, 0.2, -1.0), DVec3::new(0.2, 0.2, 1.0), DVec3::new(0.3, 0.1, 0.0)];
        assert_eq!(Apart::new(&t, &through), None);
        let coplanar = [DVec3::X, DVec3::Y, DVec3::new(0.3, 0.3, 0.0)];
        assert_eq!(Apart::new(&t, &coplanar), None);
        let beside =
            [DVec3::new(2.0, 0.0, -1.0), DVec3::new(2.0, 0.0, 1.0), DVec3::new(3.0, 1.0, 0.0)];
        assert!(matches!(Apart::new(&t, &beside), Some(Apart::ReceiverOnSide(_))));
    }

    /// Inside, outside and on an edge, for both orientations; a degenerate image holds
    /// nothing inside.
    #[test]
    fn points_are_located_beyond_the_rounding() {
        let p = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let q = [p[0], p[2], p[1]];
        let m = 1e-15;
        assert_eq!(locate(&p, [0.2, 0.2], m, 1.0), Where::Inside(1));
        assert_eq!(locate(&q, [0.2, 0.2], m, 1.0), Where::Inside(-1));
        assert_eq!(locate(&p, [2.0, 2.0], m, 2.0), Where::Outside);
        assert_eq!(locate(&p, [0.5, 0.0], m, 1.0), Where::Unsure);
        assert_eq!(locate(&p, [0.5, 1e-16], m, 1.0), Where::Unsure);
        let flat = [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]];
        assert_ne!(locate(&flat, [0.5, 0.5], m, 2.0), Where::Inside(1));
        assert_eq!(locate(&p, [f64::NAN, 0.2], m, 1.0), Where::Unsure);
    }

    /// Asks both proofs of every triangle of `frame` (one closed object); checks that every
    /// triangle the count passes is in shadow at its centre and near its corners; returns how
    /// many faced away, passed `behind_own_facing`, and passed the count.
    fn check_winding(frame: &Frame<'_>) -> (usize, usize, usize) {
        let g = &frame.geometry;
        let all: Vec<u32> = (0..g.len() as u32).collect();
        let grid = CasterGrid::new(frame, &all);
        let (mut away, mut facing, mut winding) = (0, 0, 0);
        for t in 0..g.len() {
            let corners = g.corners(t);
            away += usize::from(LitSide::new(&corners, &frame.scene.light).facing == Facing::Away);
            let by_facing = grid.behind_own_facing(t as u32);
            let by_winding = grid.behind_own_winding(t as u32);
            facing += usize::from(by_facing);
            winding += usize::from(by_winding);
            if !by_winding {
                continue;
            }
            for w in [[1.0, 1.0, 1.0], [8.0, 1.0, 1.0], [1.0, 8.0, 1.0], [1.0, 1.0, 8.0]] {
                let p = (corners[0] * w[0] + corners[1] * w[1] + corners[2] * w[2])
                    / (w[0] + w[1] + w[2]);
                assert!(blocked(frame, t, p), "triangle {t} at {p}");
            }
        }
        (away, facing, winding)
    }

    /// In an object of two boxes, one over the other, the upper one's bottom is in its own
    /// shadow, which `behind_own_facing` cannot tell (the lower box's top faces the light
    /// beyond it) and the count can: every face away from the light passes. Turned inside
    /// out, the boxes' faces away from the light by their corners' order are those the light
    /// sees: none passes.
    #[test]
    fn the_count_settles_a_face_over_another_part_of_its_object() {
        let light = Light::Directional { direction: DVec3::new(0.02, -1.0, 0.01) };
        for inverted in [false, true] {
            let (mut positions, mut triangles) = (Vec::new(), Vec::new());
            cuboid(DVec3::new(-1.0, 0.0, -1.0), DVec3::ONE, &mut positions, &mut triangles);
            cuboid(
                DVec3::new(-1.0, 2.0, -1.0),
                DVec3::new(1.0, 3.0, 1.0),
                &mut positions,
                &mut triangles,
            );
            if inverted {
                triangles.iter_mut().for_each(|t| t.swap(1, 2));
            }
            let mesh = scenes::Mesh::new(positions, triangles).expect("valid");
            let scene = one_object(mesh, light.clone());
            let frame = Frame::new(&scene, 16, 12, &mut Recorder::default());
            let (away, facing, winding) = check_winding(&frame);
            if inverted {
                assert_eq!((away, winding), (12, 0));
            } else {
                assert_eq!((away, facing, winding), (12, 10, 12));
            }
        }
    }

    /// Two boxes of one object that pass through each other (the object is closed by its
    /// edges, but not the boundary of a solid): faces of one inside the other are crossed by
    /// the other's faces, and the count is 2 beyond some faces; every face that passes is in
    /// shadow.
    #[test]
    fn boxes_through_each_other() {
        let light = Light::Directional { direction: DVec3::new(0.3, -1.0, 0.2) };
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        cuboid(DVec3::splat(-1.0), DVec3::ONE, &mut positions, &mut triangles);
        cuboid(
            DVec3::new(-0.5, -2.0, -0.5),
            DVec3::new(0.5, 0.5, 0.5),
            &mut positions,
            &mut triangles,
        );
        cuboid(
            DVec3::new(-0.6, -4.0, -0.6),
            DVec3::new(0.6, -3.0, 0.6),
            &mut positions,
            &mut triangles,
        );
        let mesh = scenes::Mesh::new(positions, triangles).expect("valid");
        let scene = one_object(mesh, light);
        let frame = Frame::new(&scene, 16, 12, &mut Recorder::default());
        let (away, _, winding) = check_winding(&frame);
        assert!(winding > 0 && winding < away, "{winding} of {away}");
    }

    /// On random objects of two star-shaped closed meshes, one of them turned inside out in
    /// two cases of three, one over the other with a random shift, under a directional light:
    /// every triangle the count passes is in shadow at every point tried, and it passes more
    /// than `behind_own_facing` (1,327 against 802).
    #[test]
    fn the_count_passes_only_shadowed_triangles() {
        let mut random = uniform(0x9e37_79b9_7f4a_7c15);
        let (mut facing, mut winding) = (0, 0);
        for case in 0..24 {
            let shift = DVec3::new(2.0 * random() - 1.0, 3.0 * random(), 2.0 * random() - 1.0);
            let (mesh, to) = two_stars(&mut random, shift, [case % 3 == 0, case % 3 == 1]);
            let scene = one_object(mesh, Light::Directional { direction: to });
            let frame = Frame::new(&scene, 16, 12, &mut Recorder::default());
            let (_, f, w) = check_winding(&frame);
            (facing, winding) = (facing + f, winding + w);
        }
        assert!(winding > facing, "{winding} against {facing}");
    }
}
