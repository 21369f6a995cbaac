//! A closed mesh's shadow on a receiver plane is the shadow of its triangles facing the light;
//! its triangles facing away from the light lie in its shadow when nothing of it that faces
//! the light lies beyond them.
//!
//! A plane point `p` is in the shadow of a mesh when the segment from `p` to the light meets
//! one of its triangles. Let the mesh be closed: every edge is used as often in one
//! direction as in the other by its triangles (corners compared by position), so the mesh
//! has no boundary and a winding number `w(x)` around every point off it, constant between
//! its triangles and changed by one, up or down with the triangle's orientation, where a
//! path crosses a triangle (up where it crosses against the triangle's normal).
//!
//! Let every corner lie on the light's side of the plane or in it, and, for a spot light,
//! below the plane through the light ([`Setup::toward_light`]). A ray from the light away
//! from the plane then meets no triangle (for a directional light, the light is at
//! infinity), so `w(light) = 0`. A plane point `p` off the mesh has `w(p) = 0` (a ray from it
//! away from the light meets nothing). Along the segment from `p` to the light the
//! crossings' signed count is `w(light) - w(p) = 0`: a segment that crosses the mesh crosses
//! it both ways, so it crosses a triangle facing the light ([`Setup::faces_light`]), whose
//! normal the segment runs along when it leaves the closed surface. A plane point on a
//! triangle lying in the plane (a base the mesh stands on) is one more case: let no such
//! triangle face the light; just above `p`, `w` is then at least 1 (each triangle of the
//! plane there is crossed against its normal by a path going up), so the segment leaves the
//! surface through a triangle facing the light again. Only the segments through an edge, a
//! corner or along a triangle's plane escape these counts, and they cover no area of the
//! plane. So the union of the shadows of the triangles facing the light is the union of all
//! the mesh's shadows, up to the rounding of their projections; no other property of the
//! mesh (one sheet, no self-intersection, outward normals) is needed.
//!
//! # A closed mesh's shadow on itself
//!
//! Let `T` be a triangle of the closed mesh facing away from the light, `p` a point of it,
//! and let `w(light) = 0` (a directional light; a spot light outside the mesh's box):
//! [`self_shadowing`]. Along the light's line through `p`, `w` is 0 far beyond `p` (away from
//! the light), and moving toward the light it goes up by one across each triangle facing
//! away from the light and down by one across each facing it. If no triangle facing the
//! light is crossed beyond `p`, then just beyond `p` `w >= 0`; across `T` (facing away) it
//! goes up to `w >= 1` just before `p` on the light's side, so the segment from `p` to the
//! light, where `w` must come back to 0, crosses a triangle of the mesh: `p` is in its
//! shadow. [`CasterGrid::behind_own_facing`] checks that no triangle facing the light lies
//! beyond `T` on a light line through both (each is wholly nearer the light, or `T` lies on
//! its dark side), and that the facing of `T` and of each triangle it asks is beyond the
//! rounding of their normals; then `T` is shadowed over its whole area, and the surface
//! receiver takes it so without asking the grid for casters or projecting any
//! ([`super::surface`]). The check asks for no orientation: on a mesh turned inside out,
//! whose side facing away from the light by its corners' order is the side the light sees,
//! the far side faces the light and lies beyond, and the check fails (tested).
//!
//! It fails too where a line from `T` meets the mesh again beyond it, as under a bunny's ear,
//! whose light reaches its body: there the crossings beyond `p` pair up without the check
//! seeing it. On `bunny-plane` at 800 x 600 it passes 1,876 of the 4,085 receivers facing
//! away from the light. Under a directional light, a receiver is first asked of
//! [`CasterGrid::behind_own_winding`], which counts the crossings beyond `T` along one light
//! line, having checked that no other triangle meets the inside of `T` (so that `w` just
//! beyond `T` is one number): `T` is shadowed unless the count is -1. It passes those under
//! the ears too: with it, 3,984 of the 4,085 pass, and the stage `surface shadows` takes
//! 14 % less time (102.8 -> 88.1 ms at one thread, 4 alternating runs, load 1.2, the same
//! image bit for bit). What neither passes is left to the casters' shadows.
//!
//! # Cost
//!
//! On `bunny-plane` at 800 x 600 the ground's shadow polygons go from 75,408 to 35,672 and
//! the cuts of their union from 138,872 to 67,974 (stage `pixel unions` 30 -> 18 ms); on
//! `cage` from 1,584 to 792 polygons. Whether an object is closed is decided once per frame
//! ([`ClosedCasters`]), in the first stage that asks (the planar receivers' `shadow
//! polygons`, else `surface shadows`): one parallel pass sums a hash of the directed edges
//! (non-zero proves an object open), then only an object that may be closed has its edges
//! sorted ([`methods::closed`]).
//!
//! [`CasterGrid::behind_own_facing`]: super::casters::CasterGrid::behind_own_facing
//! [`CasterGrid::behind_own_winding`]: super::casters::CasterGrid::behind_own_winding

use super::shadow::Setup;
use super::ScreenPolygons;
use methods::closed::{closed_objects, per_object, Corners};
use methods::Frame;
use scenes::Light;

/// Which objects of a frame are closed casters ([`closed_objects`], corners compared by number
/// or else by position), each decided once per frame, when a stage first asks for it: the
/// planar receivers' casters toward the light ([`facing_suffices`]) and the surface
/// receivers' own objects ([`self_shadowing`]) are often the same (on `bunny-plane`, the
/// bunny: 3.4-4.5 ms a decision).
#[derive(Debug)]
pub(crate) struct ClosedCasters {
    known: Vec<Option<bool>>,
}

impl ClosedCasters {
    /// Nothing decided yet for the objects of `frame`.
    pub fn new(frame: &Frame<'_>) -> Self {
        Self { known: vec![None; frame.scene.objects.len()] }
    }

    /// Per object of `frame`: whether it is a closed caster, for the objects `ask(o)` names
    /// (those not decided yet are decided together, in one pass over the triangles), `false`
    /// for the others.
    pub fn ask(&mut self, frame: &Frame<'_>, ask: impl Fn(usize) -> bool) -> Vec<bool> {
        let objects = self.known.len();
        let asked: Vec<bool> = (0..objects).map(ask).collect();
        let new: Vec<bool> = (0..objects).map(|o| asked[o] && self.known[o].is_none()).collect();
        if new.contains(&true) {
            let casts = |o: usize| new[o] && frame.object_casts_shadows(o);
            let closed =
                closed_objects(&frame.geometry, objects, casts, Corners::ByNumberOrPosition);
            for o in (0..objects).filter(|&o| new[o]) {
                self.known[o] = Some(closed[o]);
            }
        }
        (0..objects).map(|o| asked[o] && self.known[o] == Some(true)).collect()
    }
}

/// The shadow polygons of the casters of `frame` on the plane of `setup`, that of object
/// `receiver` ([`Setup::shadow_polygons`]): of a closed object toward the light, those of its
/// triangles facing the light only ([`facing_suffices`]); and whether there is such an object,
/// whose neighbouring triangles' shadows share their edges, so that the union's outline is
/// worth finding first (`seams` of [`super::coverage::union_area`]).
pub(crate) fn shadow_polygons(
    frame: &Frame<'_>,
    setup: &Setup,
    receiver: usize,
    closed: &mut ClosedCasters,
) -> (ScreenPolygons, bool) {
    let casters: Vec<bool> = (0..frame.scene.objects.len())
        .map(|o| o != receiver && frame.object_casts_shadows(o))
        .collect();
    let facing = facing_suffices(frame, setup, &casters, closed);
    (setup.shadow_polygons(frame, receiver, &facing), facing.contains(&true))
}

/// For each object of `frame`: whether its shadow on the plane of `setup` is that of its
/// triangles facing the light alone. It must be one of the `casters` (others are not looked
/// at), closed (asked of `closed`), with every corner toward the light from the plane, and no
/// triangle lying in the plane facing the light.
pub(crate) fn facing_suffices(
    frame: &Frame<'_>,
    setup: &Setup,
    casters: &[bool],
    closed: &mut ClosedCasters,
) -> Vec<bool> {
    let g = &frame.geometry;
    let objects = casters.len();
    // One parallel pass over the triangles: per object, whether every triangle lies toward
    // the light (none in the plane facing it).
    let toward = per_object(
        g.len(),
        objects,
        true,
        |acc, t| {
            let o = g.object[t] as usize;
            if casters.get(o).copied().unwrap_or(false) && acc[o] {
                let c = g.corners(t);
                let in_plane = c.iter().all(|&p| setup.light_height(p) == 0.0);
                let toward = c.iter().all(|&p| setup.toward_light(p));
                acc[o] = toward && !(in_plane && setup.faces_light(&c));
            }
        },
        |x, y| x && y,
    );
    closed.ask(frame, |o| casters[o] && toward[o])
}

/// An object's own shadow on its triangles facing away from the light is looked for only where
/// they are at least `1 / MIN_AWAY_SHARE` of its triangles among the surface receivers:
/// deciding whether an object is closed costs 25-60 ns per triangle at one thread (13 ms for
/// `bumpy`'s open heightfield of 520,000), and the proofs save about 7 us per receiver facing
/// away from the light that they pass (on `bunny-plane`, 98 % of them).
const MIN_AWAY_SHARE: usize = 80;

/// For each object of `frame`: whether its triangles facing away from the light among
/// `receivers` may be found in its own shadow ([`behind_own_winding`], [`behind_own_facing`],
/// see the module doc): it is closed (asked of `closed`, for objects with enough such
/// receivers, [`MIN_AWAY_SHARE`]) and, under a spot light, its box does not hold the light, so
/// that the light's winding number around it is 0 (a directional light's always is).
///
/// [`behind_own_winding`]: super::casters::CasterGrid::behind_own_winding
/// [`behind_own_facing`]: super::casters::CasterGrid::behind_own_facing
pub(crate) fn self_shadowing(
    frame: &Frame<'_>,
    receivers: &[u32],
    closed: &mut ClosedCasters,
) -> Vec<bool> {
    let g = &frame.geometry;
    let objects = frame.scene.objects.len();
    // The receivers facing away from the light, by object (by the sign of their normal alone:
    // the proof decides beyond its rounding).
    let away = per_object(
        receivers.len(),
        objects,
        0usize,
        |acc, k| {
            let t = receivers[k] as usize;
            let c = g.corners(t);
            let n = (c[1] - c[0]).cross(c[2] - c[0]);
            let away = match frame.scene.light {
                Light::Directional { direction } => n.dot(direction) > 0.0,
                Light::Spot { position, .. } => n.dot(position - c[0]) < 0.0,
            };
            acc[g.object[t] as usize] += usize::from(away);
        },
        |x, y| x + y,
    );
    let triangles = |o: usize| frame.scene.objects[o].mesh.triangle_count();
    let closed = closed.ask(frame, |o| away[o] > 0 && away[o] * MIN_AWAY_SHARE >= triangles(o));
    match frame.scene.light {
        Light::Directional { .. } => closed,
        Light::Spot { position, .. } => {
            // The box of the object's vertices, used or not, holds that of its triangles.
            let holds = |o: usize| {
                frame.scene.objects[o].mesh.bounds().is_some_and(|(lo, hi)| {
                    (0..3).all(|k| lo[k] <= position[k] && position[k] <= hi[k])
                })
            };
            closed.iter().enumerate().map(|(o, &c)| c && !holds(o)).collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact::coverage;
    use glam::DVec3;
    use instrumentation::Recorder;

    /// On bunny-plane, cage and spheres the ground's shadow polygons of the closed casters'
    /// triangles facing the light cover, in every pixel, what those of all their triangles
    /// cover, to 1e-12; and they are fewer.
    #[test]
    fn the_triangles_facing_the_light_cast_the_whole_shadow() {
        for name in ["bunny-plane", "cage", "spheres"] {
            let Ok(scene) = scenes::load(name) else {
                eprintln!("{name}: model not available, skipped");
                continue;
            };
            let frame = Frame::new(&scene, 200, 150, &mut Recorder::default());
            let (receiver, setup) = Setup::main_receiver(&frame).expect("planar receiver");
            let (facing, seams) =
                shadow_polygons(&frame, &setup, receiver, &mut ClosedCasters::new(&frame));
            assert!(seams, "{name}: a closed caster");
            let g = &frame.geometry;
            let mut all = crate::exact::ScreenPolygons::default();
            for t in (0..g.len()).filter(|&t| g.object[t] as usize != receiver) {
                if let Some(p) = setup.caster(g.corners(t)).filter(|_| frame.is_caster(t)) {
                    all.push(p.points());
                }
            }
            assert!(facing.len() < all.len(), "{name}: {} of {}", facing.len(), all.len());
            let (a, _) = coverage::union_area(&facing, 200, 150, |_| true, true);
            let (b, _) = coverage::union_area(&all, 200, 150, |_| true, false);
            let worst = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
            assert!(worst <= 1e-12, "{name}: {worst}");
            assert!(b.iter().filter(|&&v| v > 0.5).count() > 100, "{name}: a shadow");
        }
    }

    /// Each object is answered for only when asked, and answered the same however it is
    /// asked: on `spheres`, the ground is open and the spheres closed.
    #[test]
    fn closed_casters_answer_what_is_asked() {
        let scene = scenes::load("spheres").expect("built-in");
        let frame = Frame::new(&scene, 40, 30, &mut Recorder::default());
        let objects = scene.objects.len();
        let ground = (0..objects).find(|&o| scene.objects[o].mesh.plane().is_some());
        let ground = ground.expect("a ground plane");
        let mut closed = ClosedCasters::new(&frame);
        let spheres = closed.ask(&frame, |o| o != ground);
        assert!(!spheres[ground] && spheres.iter().filter(|&&c| c).count() == objects - 1);
        assert_eq!(closed.ask(&frame, |o| o == ground), vec![false; objects]);
        let all = closed.ask(&frame, |_| true);
        assert_eq!(all, spheres);
        assert_eq!(all, ClosedCasters::new(&frame).ask(&frame, |_| true), "as when asked at once");
    }

    /// A box on the light's side of the plane qualifies, one reaching through the plane does
    /// not (its closedness is [`methods::closed`]'s business).
    #[test]
    fn boxes_through_the_plane_do_not_qualify() {
        let corners = |lift: f64| -> Vec<DVec3> {
            (0..8)
                .map(|k| DVec3::new((k & 1) as f64, (k >> 1 & 1) as f64 + lift, (k >> 2) as f64))
                .collect()
        };
        // On the ground of plane-square's frame, under its light.
        let scene = scenes::load("plane-square").expect("built-in");
        let frame = Frame::new(&scene, 40, 30, &mut Recorder::default());
        let (_, setup) = Setup::main_receiver(&frame).expect("planar receiver");
        let above = corners(0.5).iter().all(|&p| setup.toward_light(p));
        let through = corners(-0.5).iter().all(|&p| setup.toward_light(p));
        assert!(above && !through, "the cube above the ground qualifies, through it not");
    }
}
