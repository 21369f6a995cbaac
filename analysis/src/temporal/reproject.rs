//! Reprojection of a pixel into the previous frame through the known geometry, for the
//! temporal metrics ([`crate::temporal`]).
//!
//! Pixel `k` of frame `t` sees triangle `T` at the G-buffer's point `p` (the world position
//! where the pixel centre's ray meets `T`). The point is carried with its triangle: its
//! barycentric coordinates in `T` at frame `t` give the same point of `T` at frame `t-1`
//! (triangles keep their ids and topology from frame to frame, only positions change), which is
//! projected through frame `t-1`'s camera ([`scenes::Projector::project`]). Its partner is the
//! pixel that contains the image point (`floor` of the image coordinates, see
//! `scenes::projection`), when that pixel is inside the image and frame `t-1`'s G-buffer sees
//! the same triangle `T` there: a point hidden in frame `t-1` (behind another triangle, or
//! behind a face of its own object) or off its image has no partner.
//!
//! With neither the camera nor the geometry moving, every covered pixel maps to itself: the
//! G-buffer's points reproject to their pixel centres up to `f64` rounding
//! (`methods::gbuffer`), half a pixel from any pixel border.

use glam::DVec3;
use methods::{gbuffer::GBuffer, raster::NO_TRIANGLE, Frame};
use scenes::{Geometry, Projector};

/// What the temporal metrics read of a frame: its camera, its triangles and its G-buffer; a
/// frame's own ([`View::of`]), or parts kept from a frame after its scene is gone, so that a
/// caller holds the previous frame without its scene.
#[derive(Debug, Clone, Copy)]
pub struct View<'a> {
    /// The camera's projector at the frame's size.
    pub camera: &'a Projector,
    /// Every triangle, posed at the frame.
    pub geometry: &'a Geometry,
    /// The camera G-buffer.
    pub gbuffer: &'a GBuffer,
}

impl<'a> View<'a> {
    /// The view of `frame`.
    pub fn of(frame: &'a Frame<'_>) -> Self {
        Self { camera: &frame.camera, geometry: &frame.geometry, gbuffer: &frame.gbuffer }
    }
}

/// The pixel of `prev` paired with pixel `k` of `cur` (see the module doc), or `None` when
/// `k` sees no triangle (or is not a pixel of `cur`), when the point it sees projects outside
/// `prev`'s image (or not at all: behind a perspective camera's near plane) or when `prev`'s
/// G-buffer sees another triangle there. A triangle id that `prev` lacks, or a triangle of zero
/// area, pairs nothing.
pub fn reproject(prev: &View<'_>, cur: &View<'_>, k: usize) -> Option<usize> {
    let t = *cur.gbuffer.triangle.get(k)?;
    if t == NO_TRIANGLE {
        return None;
    }
    let (v, w) = barycentric(corners(cur.geometry, t)?, *cur.gbuffer.position.get(k)?)?;
    let [a, b, c] = corners(prev.geometry, t)?;
    let p = a + v * (b - a) + w * (c - a);
    let (xy, _) = prev.camera.project(p)?;
    let (x, y) = (xy.x.floor(), xy.y.floor());
    let (width, height) = (prev.gbuffer.width, prev.gbuffer.height);
    if !(x >= 0.0 && y >= 0.0 && x < f64::from(width) && y < f64::from(height)) {
        return None;
    }
    // In range: both are whole numbers in [0, width) and [0, height).
    let q = y as usize * width as usize + x as usize;
    (prev.gbuffer.triangle.get(q) == Some(&t)).then_some(q)
}

/// The corners of triangle `t` of `geometry`, or `None` when it has no such triangle.
fn corners(geometry: &Geometry, t: u32) -> Option<[DVec3; 3]> {
    let [a, b, c] = *geometry.triangles.get(t as usize)?;
    let at = |v: u32| geometry.positions.get(v as usize).copied();
    Some([at(a)?, at(b)?, at(c)?])
}

/// The barycentric coordinates `(v, w)` of `p` in the triangle `[a, b, c]`, with
/// `p = a + v (b - a) + w (c - a)` for a point of its plane (the nearest point of the plane
/// otherwise); `None` for a triangle of zero area or coordinates that are not finite.
fn barycentric([a, b, c]: [DVec3; 3], p: DVec3) -> Option<(f64, f64)> {
    let (e1, e2, d) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let denom = d11 * d22 - d12 * d12;
    let v = (d22 * d1 - d12 * d2) / denom;
    let w = (d11 * d2 - d12 * d1) / denom;
    (denom > 0.0 && v.is_finite() && w.is_finite()).then_some((v, w))
}

#[cfg(test)]
mod tests {
    use super::*;
    use instrumentation::Recorder;
    use scenes::scene::EffectSwitches;
    use scenes::{Camera, Light, Material, Mesh, Object, Scene};

    /// A square of side `2 half` centred on `(x, height, z)`, facing up.
    fn square(half: f64, x: f64, height: f64, z: f64) -> Mesh {
        let p = |dx: f64, dz: f64| DVec3::new(x + dx, height, z + dz);
        let positions = vec![p(-half, -half), p(-half, half), p(half, half), p(half, -half)];
        Mesh::new(positions, vec![[0, 1, 2], [0, 2, 3]]).expect("valid square")
    }

    fn object(name: &str, mesh: Mesh) -> Object {
        Object { name: name.into(), mesh, material: Material::default(), casts_shadows: true }
    }

    /// An orthographic camera looking straight down at `(x, 0, 0)` from above, 48 world units
    /// high: at 64 x 48 pixels a pixel is one world unit square, `+x` to the right of the image.
    fn down(x: f64) -> Camera {
        Camera::Orthographic {
            eye: DVec3::new(x, 10.0, 0.0),
            target: DVec3::new(x, 0.0, 0.0),
            up: DVec3::NEG_Z,
            height: 48.0,
        }
    }

    fn scene(camera: Camera, objects: Vec<Object>) -> Scene {
        Scene {
            name: "test".into(),
            width: 64,
            height: 48,
            camera,
            light: Light::Directional { direction: DVec3::NEG_Y },
            objects,
            switches: EffectSwitches::default(),
            animation: scenes::Animation::still(),
        }
    }

    fn frame(scene: &Scene) -> Frame<'_> {
        Frame::new(scene, 64, 48, &mut Recorder::default())
    }

    /// The ground (100 units square) and a 10 x 10 square at `x` floating over it.
    fn ground_and_square(camera: Camera, x: f64) -> Scene {
        let objects = vec![
            object("ground", square(50.0, 0.0, 0.0, 0.0)),
            object("square", square(5.0, x, 2.0, 0.0)),
        ];
        scene(camera, objects)
    }

    #[test]
    fn a_still_frame_maps_every_covered_pixel_to_itself() {
        let perspective = Camera::Perspective {
            eye: DVec3::new(3.0, 20.0, 30.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_deg: 50.0,
            near: 0.01,
        };
        for camera in [down(0.0), down(0.3), perspective] {
            let s = ground_and_square(camera, 1.25);
            let f = frame(&s);
            let covered = (0..f.gbuffer.triangle.len()).filter(|&k| f.gbuffer.covered(k));
            assert!(covered.clone().count() > 1000, "the test sees the ground");
            for k in covered {
                assert_eq!(reproject(&View::of(&f), &View::of(&f), k), Some(k), "pixel {k}");
            }
            let uncovered = (0..f.gbuffer.triangle.len()).find(|&k| !f.gbuffer.covered(k));
            assert!(uncovered.is_none_or(|k| reproject(&View::of(&f), &View::of(&f), k).is_none()));
        }
    }

    #[test]
    fn a_camera_moved_sideways_by_whole_pixels_shifts_every_pixel_by_as_many() {
        for shift in [1usize, 3, 10] {
            let (before, after) =
                (ground_and_square(down(0.0), 0.0), ground_and_square(down(shift as f64), 0.0));
            let (prev, cur) = (frame(&before), frame(&after));
            assert_ne!(prev.camera, cur.camera);
            for k in 0..64 * 48 {
                let i = k % 64;
                // Pixel i of the moved camera sees what pixel i + shift saw.
                let want = (i + shift < 64).then_some(k + shift);
                assert_eq!(
                    reproject(&View::of(&prev), &View::of(&cur), k),
                    want,
                    "pixel ({i}, {}), shift {shift}",
                    k / 64
                );
            }
        }
    }

    #[test]
    fn points_hidden_in_the_previous_frame_are_not_paired() {
        // The square (triangles 2 and 3, over the ground's 0 and 1) moves 4 units, 4 pixels,
        // to the right under a still camera.
        let (before, after) =
            (ground_and_square(down(0.0), -2.0), ground_and_square(down(0.0), 2.0));
        let (prev, cur) = (frame(&before), frame(&after));
        assert_eq!(prev.camera, cur.camera);
        let on_square = |f: &Frame<'_>, k: usize| matches!(f.gbuffer.triangle[k], 2 | 3);
        let (mut moved, mut hidden) = (0, 0);
        for k in 0..64 * 48 {
            let got = reproject(&View::of(&prev), &View::of(&cur), k);
            assert!(cur.gbuffer.covered(k), "the ground fills the view");
            if on_square(&cur, k) {
                // A point of the square comes from 4 pixels to the left.
                assert_eq!(got, Some(k - 4), "square pixel {k}");
                moved += 1;
            } else if on_square(&prev, k) {
                // Ground the square covered a frame ago: hidden then.
                assert_eq!(got, None, "ground pixel {k}, uncovered by the square");
                hidden += 1;
            } else {
                assert_eq!(got, Some(k), "ground pixel {k}");
            }
        }
        // 10 x 10 pixels of square; the 4 columns it left, 10 rows each.
        assert_eq!((moved, hidden), (100, 40));
    }

    #[test]
    fn points_off_the_previous_image_or_of_unknown_triangles_are_not_paired() {
        let s = ground_and_square(down(0.0), 0.0);
        let f = frame(&s);
        let mut lacking = f.clone();
        lacking.geometry.triangles.truncate(2);
        let k = (0..64 * 48).find(|&k| f.gbuffer.triangle[k] >= 2).expect("the square is seen");
        assert_eq!(reproject(&View::of(&lacking), &View::of(&f), k), None);
        assert_eq!(reproject(&View::of(&f), &View::of(&f), 64 * 48), None);
        // A triangle of zero area.
        let mut flat = f.clone();
        let [a, b, _] = flat.geometry.triangles[0];
        flat.geometry.triangles[0] = [a, b, b];
        let k0 = (0..64 * 48).find(|&k| f.gbuffer.triangle[k] == 0).expect("seen");
        assert_eq!(reproject(&View::of(&f), &View::of(&flat), k0), None);
        // Far to the side: the previous camera sees none of it.
        let away = ground_and_square(down(200.0), 0.0);
        assert!(
            (0..64 * 48).all(|k| reproject(&View::of(&frame(&away)), &View::of(&f), k).is_none())
        );
    }
}
