//! The shared kernels on whole scenes: the camera G-buffer and the light depth map.

use glam::{DVec2, DVec3};
use instrumentation::Recorder;
use methods::{raster::NO_TRIANGLE, Frame, LightFit};
use scenes::{
    generators::SpheresParams,
    scene_file::{ObjectDesc, SceneDesc, Shape, Transform},
    Camera, Light, Material, Scene,
};

fn centre(k: usize, w: usize) -> DVec2 {
    DVec2::new((k % w) as f64 + 0.5, (k / w) as f64 + 0.5)
}

#[test]
fn exact_gbuffer_positions_reproject_to_their_pixel_centres() {
    for name in ["plane-square", "cage", "spot-spheres", "grazing"] {
        let scene = scenes::load(name).expect("built-in");
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        let g = &frame.gbuffer;
        let mut covered = 0;
        for k in 0..g.triangle.len() {
            if g.triangle[k] == NO_TRIANGLE {
                continue;
            }
            covered += 1;
            let (xy, depth) = frame.camera.project(g.position[k]).expect("in front of the camera");
            assert!((xy - centre(k, 160)).length() < 1e-4, "{name}: pixel {k} reprojects to {xy}");
            assert!((depth - g.depth[k]).abs() <= 1e-9 * depth.abs().max(1.0));
        }
        assert!(covered > 1000, "{name}: {covered} covered pixels");
    }
}

/// Möller-Trumbore in f64: the ray parameter and barycentrics of the hit, if any.
fn ray_triangle(o: DVec3, d: DVec3, [a, b, c]: [DVec3; 3]) -> Option<(f64, f64, f64)> {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let s = o - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    Some((t, u, v))
}

fn spheres_scene(camera: Camera) -> Scene {
    SceneDesc {
        name: Some("closed".into()),
        resolution: [96, 72],
        camera,
        light: Light::Directional { direction: DVec3::new(-0.3, -1.0, -0.2) },
        effects: Default::default(),
        animation: Default::default(),
        objects: vec![ObjectDesc {
            name: None,
            shape: Shape::Spheres(SpheresParams { count: 3, seed: 7, ..Default::default() }),
            transform: Transform { rotate_deg: DVec3::new(13.0, 27.0, 5.0), ..Default::default() },
            material: Material::default(),
            casts_shadows: true,
        }],
    }
    .resolve("closed", std::path::Path::new("test"), std::path::Path::new("."))
    .expect("valid scene")
}

#[test]
fn exact_closed_meshes_leave_no_pixel_empty_inside_their_silhouette() {
    let cameras = [
        Camera::Perspective {
            eye: DVec3::new(1.0, 6.0, 9.0),
            target: DVec3::new(0.0, 1.5, 0.0),
            up: DVec3::Y,
            fov_y_deg: 50.0,
            near: 0.01,
        },
        Camera::Orthographic {
            eye: DVec3::new(0.0, 9.0, 0.1),
            target: DVec3::ZERO,
            up: DVec3::Y,
            height: 12.0,
        },
    ];
    for camera in cameras {
        let scene = spheres_scene(camera);
        let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
        let g = &frame.geometry;
        let (mut inside, mut ambiguous) = (0, 0);
        for k in 0..frame.gbuffer.triangle.len() {
            let ray = frame.camera.ray(centre(k, 96));
            // Classify the centre by brute force: clearly inside some triangle, clearly
            // outside all, or within 1e-9 (barycentric) of an edge.
            let mut state = 0; // 0 outside, 1 inside, 2 ambiguous
            for t in 0..g.len() {
                if let Some((tt, u, v)) = ray_triangle(ray.origin, ray.direction, g.corners(t)) {
                    if tt <= 0.0 {
                        continue;
                    }
                    let m = u.min(v).min(1.0 - u - v);
                    if m > 1e-9 {
                        state = 1;
                        break;
                    } else if m > -1e-9 {
                        state = 2;
                    }
                }
            }
            let covered = frame.gbuffer.triangle[k] != NO_TRIANGLE;
            match state {
                1 => {
                    inside += 1;
                    assert!(covered, "hole at pixel {k}");
                }
                0 => assert!(!covered, "pixel {k} covered outside the silhouette"),
                _ => ambiguous += 1,
            }
        }
        assert!(inside > 100, "{inside} pixels inside");
        assert!(ambiguous < 5, "{ambiguous} ambiguous pixels");
    }
}

#[test]
fn exact_light_depth_map_of_plane_square_matches_the_analytic_depth() {
    let scene = scenes::load("plane-square").expect("built-in");
    let mut rec = Recorder::default();
    let frame = Frame::new(&scene, 64, 48, &mut rec);
    let map = frame.light_depth_map(256, LightFit::Scene, &mut rec);
    // Each object is one planar quad of two triangles: its plane and its corners.
    let quads: Vec<_> =
        scene.objects.iter().map(|o| (o.mesh.plane().expect("planar"), o.mesh.clone())).collect();
    let (mut checked, mut on_square) = (0, 0);
    for k in 0..map.depth.len() {
        let ray = map.projector.ray(centre(k, 256));
        let mut expected = f64::INFINITY;
        let mut near_edge = false;
        for (i, ((n, d), mesh)) in quads.iter().enumerate() {
            let Some(t) = ray.intersect_plane(*n, *d) else { continue };
            for tri in 0..mesh.triangle_count() {
                let Some((_, u, v)) = ray_triangle(ray.origin, ray.direction, mesh.corners(tri))
                else {
                    continue;
                };
                let m = u.min(v).min(1.0 - u - v);
                if m.abs() <= 1e-9 {
                    near_edge = true;
                } else if m > 0.0 && t < expected {
                    expected = t;
                    if i == 1 {
                        on_square += 1;
                    }
                }
            }
        }
        if near_edge {
            continue;
        }
        checked += 1;
        let got = map.depth[k];
        if expected.is_infinite() {
            assert!(got.is_infinite(), "texel {k}: {got} where nothing is");
        } else {
            assert!(
                (got - expected).abs() <= 1e-9 * expected.abs().max(1.0),
                "texel {k}: {got} vs {expected}"
            );
        }
    }
    assert!(
        checked > 60_000 && on_square > 500,
        "{checked} texels checked, {on_square} on the square"
    );
}
