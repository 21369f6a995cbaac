//! A scene at one frame of its animation: the light and camera of the frame, and each moving
//! object's rest mesh under its rigid motion (rotated about the centre of its bounding box at
//! rest, then translated). Triangles keep their order and indices, so triangle ids are the
//! same in every frame; only positions change.

use super::interpolate::sample;
use super::timeline::Animation;
use crate::mesh::Mesh;
use crate::scene::{Object, Scene};

impl Animation {
    /// The scene at frame `i` (a frame beyond the last is the last): a still scene (its
    /// `animation` is [`Animation::still`]). Frame `i` of a still animation is `rest` with a
    /// still animation.
    pub fn pose(&self, rest: &Scene, i: u32) -> Scene {
        let time = self.time(i);
        let objects = rest
            .objects
            .iter()
            .enumerate()
            .map(|(index, object)| {
                let motion = self.objects.iter().find(|m| m.object == index);
                match motion.and_then(|m| sample(&m.keys, time)) {
                    Some(rigid) => {
                        let mesh = &object.mesh;
                        let centre =
                            mesh.bounds().map_or(glam::DVec3::ZERO, |(lo, hi)| 0.5 * (lo + hi));
                        Object {
                            name: object.name.clone(),
                            mesh: Mesh {
                                positions: mesh
                                    .positions
                                    .iter()
                                    .map(|&p| rigid.apply(p, centre))
                                    .collect(),
                                triangles: mesh.triangles.clone(),
                            },
                            material: object.material,
                            casts_shadows: object.casts_shadows,
                        }
                    }
                    None => object.clone(),
                }
            })
            .collect();
        Scene {
            name: rest.name.clone(),
            width: rest.width,
            height: rest.height,
            camera: self.camera_at(i).unwrap_or_else(|| rest.camera.clone()),
            light: self.light_at(i).unwrap_or_else(|| rest.light.clone()),
            objects,
            switches: rest.switches,
            animation: Animation::still(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::interpolate::{Key, Rigid};
    use super::super::timeline::Motion;
    use super::*;
    use crate::camera::Camera;
    use crate::light::Light;
    use glam::DVec3;
    use proptest::prelude::*;

    /// A scene of the given meshes under a directional light.
    fn scene(meshes: Vec<Mesh>) -> Scene {
        Scene {
            name: "s".into(),
            width: 64,
            height: 48,
            camera: Camera::Perspective {
                eye: DVec3::new(0.0, 6.0, 8.0),
                target: DVec3::ZERO,
                up: DVec3::Y,
                fov_y_deg: 45.0,
                near: 0.01,
            },
            light: Light::Directional { direction: DVec3::new(-0.3, -1.0, -0.2).normalize() },
            objects: meshes
                .into_iter()
                .enumerate()
                .map(|(i, mesh)| Object {
                    name: format!("o{i}"),
                    mesh,
                    material: Default::default(),
                    casts_shadows: true,
                })
                .collect(),
            switches: Default::default(),
            animation: Animation::still(),
        }
    }

    fn tetrahedron(offset: DVec3) -> Mesh {
        let p = [DVec3::ZERO, DVec3::X, DVec3::new(0.3, 0.9, 0.1), DVec3::new(0.2, 0.3, 1.1)];
        Mesh {
            positions: p.iter().map(|&q| q + offset).collect(),
            triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        }
    }

    /// An animation moving object `object` through `keys` (time, translate, rotate_deg).
    fn moving(object: usize, keys: &[(f64, DVec3, DVec3)], frames: u32) -> Animation {
        let keys = keys.iter().map(|&(time, t, r)| Key { time, value: Rigid::new(t, r) }).collect();
        Animation { frames, objects: vec![Motion { object, keys }], ..Animation::still() }
    }

    #[test]
    fn a_still_animation_poses_to_the_rest_scene() {
        let rest = scene(vec![tetrahedron(DVec3::ZERO), tetrahedron(DVec3::X * 3.0)]);
        let still = Animation::still().with_frames(5).expect("5 frames");
        for i in [0, 2, 4, 99] {
            assert_eq!(still.pose(&rest, i), rest);
        }
        // A rest scene carrying an animation poses to a scene without one.
        let carrying = Scene { animation: moving(0, &[(0.0, DVec3::X, DVec3::ZERO)], 2), ..rest };
        let posed = carrying.animation.pose(&carrying, 1);
        assert!(posed.animation.is_still() && posed.animation.frames() == 1);
    }

    #[test]
    fn a_pose_at_a_key_time_is_the_key_bit_for_bit() {
        let rest = scene(vec![tetrahedron(DVec3::ZERO), tetrahedron(DVec3::new(0.1, 0.7, -3.3))]);
        let keys = [
            (0.0, DVec3::new(0.1, 0.0, 0.0), DVec3::ZERO),
            (1.0, DVec3::new(0.3, 1.0 / 3.0, -0.7), DVec3::new(10.0, 33.3, -71.0)),
            (2.0, DVec3::new(-0.9, 0.2, 0.0), DVec3::ZERO),
        ];
        let mut animation = moving(1, &keys, 3);
        let directions = [DVec3::new(-0.3, -1.0, 0.2), DVec3::new(0.7, -0.9, -0.1)];
        animation.light = directions
            .iter()
            .enumerate()
            .map(|(k, &d)| Key {
                time: 2.0 * k as f64,
                value: Light::Directional { direction: d.normalize() },
            })
            .collect();
        animation.camera = [(0.0, DVec3::new(0.1, 5.3, 7.7)), (1.0, DVec3::new(-2.9, 4.1, 6.3))]
            .map(|(time, eye)| Key {
                time,
                value: Camera::Perspective {
                    eye,
                    target: DVec3::new(0.0, 1.0 / 3.0, 0.0),
                    up: DVec3::new(0.1, 1.0, 0.0),
                    fov_y_deg: 41.3,
                    near: 0.01,
                },
            })
            .into();
        animation.map_scale = vec![Key { time: 1.0, value: 0.3 }, Key { time: 2.0, value: 0.7 }];
        // Frames 0, 1 and 2 are at times 0, 1 and 2.
        let centre = {
            let (lo, hi) = rest.objects[1].mesh.bounds().expect("vertices");
            0.5 * (lo + hi)
        };
        for (i, &(time, _, _)) in keys.iter().enumerate() {
            let i = i as u32;
            assert_eq!(animation.time(i).to_bits(), time.to_bits());
            let posed = animation.pose(&rest, i);
            let rigid = animation.objects[0].keys[i as usize].value;
            let want: Vec<DVec3> =
                rest.objects[1].mesh.positions.iter().map(|&p| rigid.apply(p, centre)).collect();
            assert_eq!(posed.objects[1].mesh.positions, want, "frame {i}");
            assert_eq!(posed.objects[0], rest.objects[0]);
            if let Some(k) = animation.light.iter().find(|k| k.time == time) {
                assert_eq!(posed.light, k.value, "frame {i}");
            }
            if let Some(k) = animation.camera.iter().find(|k| k.time == time) {
                assert_eq!(posed.camera, k.value, "frame {i}");
            }
            if let Some(k) = animation.map_scale.iter().find(|k| k.time == time) {
                assert_eq!(animation.map_scale(i).to_bits(), k.value.to_bits(), "frame {i}");
            }
        }
        // Translation alone is exact: the first key moves every vertex by 0.1 in x.
        let first = animation.pose(&rest, 0);
        for (p, q) in first.objects[1].mesh.positions.iter().zip(&rest.objects[1].mesh.positions) {
            assert_eq!(*p, *q + DVec3::new(0.1, 0.0, 0.0));
        }
        // Before its first key a track holds it; after its last, too.
        assert_eq!(animation.map_scale(0), 0.3);
        assert_eq!(animation.pose(&rest, 2).camera, animation.camera[1].value);
    }

    /// Every edge's length in `mesh`.
    fn edges(mesh: &Mesh) -> Vec<f64> {
        mesh.triangles
            .iter()
            .flat_map(|t| (0..3).map(move |e| (t[e], t[(e + 1) % 3])))
            .map(|(a, b)| (mesh.positions[a as usize] - mesh.positions[b as usize]).length())
            .collect()
    }

    fn vec3(range: f64) -> impl Strategy<Value = DVec3> {
        (-range..range, -range..range, -range..range).prop_map(|(x, y, z)| DVec3::new(x, y, z))
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

        /// Rigid motions, interpolated between keys or not, keep every edge's length to f64
        /// rounding, and keep the triangles as they are.
        #[test]
        fn pose_with_rigid_motions_preserves_edge_lengths(
            points in proptest::collection::vec(vec3(100.0), 3..12),
            keys in proptest::collection::vec((vec3(1e3), vec3(720.0)), 1..5),
            frames in 1u32..9,
        ) {
            let n = points.len() as u32;
            let triangles = (0..n - 2).map(|i| [i, i + 1, i + 2]).collect();
            let rest = scene(vec![Mesh { positions: points, triangles }]);
            let keys: Vec<(f64, DVec3, DVec3)> =
                keys.into_iter().enumerate().map(|(k, (t, r))| (k as f64 * 0.5, t, r)).collect();
            let largest_translation =
                keys.iter().map(|k| k.1.abs().max_element()).fold(0.0, f64::max);
            let animation = moving(0, &keys, frames);
            let before = edges(&rest.objects[0].mesh);
            // Coordinates below 100, so a vertex is within 200 of the centre.
            let tolerance = 64.0 * f64::EPSILON * (400.0 + largest_translation);
            for i in 0..frames {
                let posed = animation.pose(&rest, i);
                prop_assert_eq!(&posed.objects[0].mesh.triangles, &rest.objects[0].mesh.triangles);
                for (a, b) in edges(&posed.objects[0].mesh).iter().zip(&before) {
                    prop_assert!((a - b).abs() <= tolerance, "frame {}: {} vs {}", i, a, b);
                }
            }
        }
    }
}
