//! Which sub-samples the camera does not see: the validity rule of `ftizb`'s sub-samples on
//! curved receivers (Pan et al. 2009, section 3.4, "validity mask", in the form of
//! [`crate::pan09::validity`]: a triangle nearer the light than the facet hides the facet's
//! points behind it from the camera).
//!
//! A pixel's sub-samples lie on the tangent plane of its centre's triangle. Where the pixel
//! spans several triangles of a curved mesh, some of those points lie behind the real surface:
//! the camera sees another triangle there, and that triangle, between the point and the light,
//! would shadow it (on `bumpy`, 530,688 triangles, several a pixel, 41 % of the sub-samples at
//! 32 a pixel disagreed with the ray tracer, every one where the ray tracer's hit was another
//! triangle). The rule: a sub-sample other than the centre is **hidden** when a caster that
//! shadows it also [`hides`] it from the camera; a hidden sub-sample is left out of the pixel's
//! ratio, whatever other casters do (hidden wins). The centre is the G-buffer's visible point
//! and is never hidden. On a planar receiver whose sub-samples all see the plane, no caster
//! hides one (a caster in front of one would be the camera's hit there), so the rule changes
//! nothing there (tested against the ray tracer).

use glam::DVec3;
use scenes::projection::Ray;

/// Whether the triangle `corners` hides the point at parameter `t` of `ray` from the camera:
/// the ray meets the closed triangle (Möller and Trumbore's test, in `f64`) at a parameter
/// `hit` with `0 < hit < t - offset / |direction|`, `offset` the point's shadow offset in world
/// units ([`crate::afsm::shadow_offset`]), so that a triangle through the point itself (a
/// coplanar neighbour, or one meeting the tangent plane there) does not hide it.
pub fn hides(ray: &Ray, t: f64, offset: f64, corners: [DVec3; 3]) -> bool {
    let [a, b, c] = corners;
    let (e1, e2) = (b - a, c - a);
    let p = ray.direction.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return false;
    }
    let inv = 1.0 / det;
    let tv = ray.origin - a;
    let u = tv.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = tv.cross(e1);
    let v = ray.direction.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let hit = e2.dot(q) * inv;
    hit > 0.0 && hit < t - offset / ray.direction.length()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray() -> Ray {
        Ray { origin: DVec3::new(0.2, 0.3, 10.0), direction: DVec3::new(0.0, 0.0, -2.0) }
    }

    const TRI: [DVec3; 3] =
        [DVec3::new(-1.0, -1.0, 2.0), DVec3::new(1.0, -1.0, 2.0), DVec3::new(0.0, 1.0, 2.0)];

    #[test]
    fn a_triangle_in_front_of_the_point_hides_it_and_one_behind_or_beside_does_not() {
        // The triangle at z = 2 is met at t = 4; the point at t = 4.5 (z = 1) is behind it.
        assert!(hides(&ray(), 4.5, 1e-9, TRI));
        assert!(!hides(&ray(), 3.5, 1e-9, TRI), "the point is in front of the triangle");
        let beside = TRI.map(|c| c + DVec3::new(5.0, 0.0, 0.0));
        assert!(!hides(&ray(), 4.5, 1e-9, beside));
        let behind_camera = TRI.map(|c| c + DVec3::new(0.0, 0.0, 20.0));
        assert!(!hides(&ray(), 4.5, 1e-9, behind_camera));
    }

    #[test]
    fn a_triangle_through_the_point_does_not_hide_it() {
        // The point on the triangle's plane (t = 4), within its offset: not hidden.
        assert!(!hides(&ray(), 4.0, 1e-9, TRI));
        assert!(!hides(&ray(), 4.0 + 1e-12, 1e-9, TRI));
        assert!(hides(&ray(), 4.0 + 1e-6, 1e-9, TRI));
    }

    #[test]
    fn degenerate_and_edge_on_triangles_hide_nothing() {
        let sliver = [TRI[0], TRI[1], (TRI[0] + TRI[1]) * 0.5];
        assert!(!hides(&ray(), 9.0, 1e-9, sliver));
        let edge_on =
            [DVec3::new(0.2, -1.0, 0.0), DVec3::new(0.2, 1.0, 0.0), DVec3::new(0.2, 0.0, 5.0)];
        assert!(!hides(&ray(), 9.0, 1e-9, edge_on));
    }
}
