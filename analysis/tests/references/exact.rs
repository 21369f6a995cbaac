//! The exact reference against analytic areas (axis-aligned, rotated and arbitrary occluders,
//! spot lights, grazing perspective views) and against brute-force point sampling on the
//! built-in scenes; its applicability; the tiny-skia cross-check; and the pixel classes of a
//! pixel overlapped by more triangles than one word of bits holds.
//!
//! Analytic areas are computed independently here: the shadow of a planar occluder is
//! projected by hand (vertical light: its footprint; spot light: central projection written
//! out below), mapped to the screen (by the orthographic formula or the camera's projector), and
//! clipped against each pixel with this file's own Sutherland–Hodgman clipper.

use analysis::crosscheck::tiny_skia_crosscheck;
use analysis::exact::{shadow_polygons, ExactCoverage};
use analysis::pixel_class::{counts, PixelClass};
use analysis::{Reference, ReferenceError, ReferenceImage};
use glam::{DVec2, DVec3};
use instrumentation::Recorder;
use methods::Frame;
use rayon::prelude::*;
use scenes::{
    generators::PlaneParams,
    scene_file::{ObjectDesc, SceneDesc, Shape, Transform},
    Camera, Light, Material, Mesh, Object, Scene,
};

// ---------------------------------------------------------------------------------------------
// Scene building

fn plane_object(name: &str, size: f64, rotate_deg: DVec3, translate: DVec3) -> ObjectDesc {
    ObjectDesc {
        name: Some(name.into()),
        shape: Shape::Plane(PlaneParams { size, subdivisions: 1 }),
        transform: Transform { rotate_deg, translate, ..Default::default() },
        material: Material::default(),
        casts_shadows: true,
    }
}

fn ground() -> ObjectDesc {
    plane_object("ground", 40.0, DVec3::ZERO, DVec3::ZERO)
}

/// Orthographic camera 6 world units high; `from_below` looks up at the ground's underside, so
/// that occluders above the ground lie behind the receiver and every pixel is evaluated.
///
/// Looking down (64 x 48): screen `x = 32 + 8 wx`, `y = 24 + 8 wz`. Looking up: screen
/// `x = 32 - 8 wx`, `y = 24 + 8 wz`.
fn ortho_camera(from_below: bool) -> Camera {
    let y = if from_below { -10.0 } else { 10.0 };
    Camera::Orthographic {
        eye: DVec3::new(0.0, y, 0.0),
        target: DVec3::ZERO,
        up: DVec3::new(0.0, 0.0, -1.0),
        height: 6.0,
    }
}

fn ortho_screen(p: DVec3, from_below: bool) -> DVec2 {
    let x = if from_below { 32.0 - 8.0 * p.x } else { 32.0 + 8.0 * p.x };
    DVec2::new(x, 24.0 + 8.0 * p.z)
}

const DOWN: Light = Light::Directional { direction: DVec3::new(0.0, -1.0, 0.0) };

fn scene(camera: Camera, light: Light, objects: Vec<ObjectDesc>) -> Scene {
    SceneDesc {
        name: Some("test".into()),
        resolution: [64, 48],
        camera,
        light,
        effects: Default::default(),
        animation: Default::default(),
        objects,
    }
    .resolve("test", std::path::Path::new("test"), std::path::Path::new("."))
    .expect("valid scene")
}

/// A scene with the ground and one free-form caster mesh.
fn scene_with_mesh(camera: Camera, light: Light, mesh: Mesh) -> Scene {
    let mut s = scene(camera, light, vec![ground()]);
    s.objects.push(Object {
        name: "caster".into(),
        mesh,
        material: Material::default(),
        casts_shadows: true,
    });
    s
}

fn exact(scene: &Scene, w: u32, h: u32) -> (Frame<'_>, ReferenceImage, Recorder) {
    let mut rec = Recorder::default();
    let frame = Frame::new(scene, w, h, &mut rec);
    let img = ExactCoverage::default().evaluate(&frame, &mut rec).expect("exact applies");
    assert_eq!(img.lit.len(), (w * h) as usize);
    assert_eq!(img.evaluated.len(), (w * h) as usize);
    assert_finite_in_range(&img);
    (frame, img, rec)
}

fn assert_finite_in_range(img: &ReferenceImage) {
    for (k, &l) in img.lit.iter().enumerate() {
        assert!(l.is_finite() && (0.0..=1.0).contains(&l), "pixel {k}: lit {l}");
    }
}

// ---------------------------------------------------------------------------------------------
// Independent analytic areas: convex polygon ∩ pixel by Sutherland–Hodgman

fn clip_half(poly: &[DVec2], inside: impl Fn(DVec2) -> f64) -> Vec<DVec2> {
    let mut out = Vec::new();
    for k in 0..poly.len() {
        let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
        let (dp, dq) = (inside(p), inside(q));
        if dp >= 0.0 {
            out.push(p);
        }
        if (dp >= 0.0) != (dq >= 0.0) {
            out.push(p + (q - p) * (dp / (dp - dq)));
        }
    }
    out
}

fn polygon_area(poly: &[DVec2]) -> f64 {
    let n = poly.len();
    (0.5 * (0..n).map(|k| poly[k].perp_dot(poly[(k + 1) % n])).sum::<f64>()).abs()
}

/// Area of the convex polygon `poly` inside pixel `(i, j)`.
fn pixel_area(poly: &[DVec2], i: usize, j: usize) -> f64 {
    // Relative to the pixel's corner, where the clipped coordinates are small.
    let corner = DVec2::new(i as f64, j as f64);
    let local: Vec<DVec2> = poly.iter().map(|&p| p - corner).collect();
    let mut p = clip_half(&local, |q| q.x);
    p = clip_half(&p, |q| 1.0 - q.x);
    p = clip_half(&p, |q| q.y);
    p = clip_half(&p, |q| 1.0 - q.y);
    if p.len() < 3 {
        0.0
    } else {
        polygon_area(&p)
    }
}

/// Overlap of the axis-aligned rectangle `[x0, x1] x [y0, y1]` with pixel `(i, j)`.
fn rect_area([x0, x1, y0, y1]: [f64; 4], i: usize, j: usize) -> f64 {
    let (i, j) = (i as f64, j as f64);
    let w = (x1.min(i + 1.0) - x0.max(i)).max(0.0);
    let h = (y1.min(j + 1.0) - y0.max(j)).max(0.0);
    w * h
}

/// The pixels `exact` evaluates as `planar` pixels of the scene's main planar receiver (the
/// object the pixel centre sees).
fn on_receiver(frame: &Frame<'_>, img: &ReferenceImage) -> Vec<bool> {
    let receiver = frame.scene.receiver_plane().expect("a planar receiver").0 as u32;
    let classes = img.classes.as_deref().expect("exact classifies");
    (0..img.lit.len())
        .map(|k| {
            let t = frame.gbuffer.triangle[k];
            img.evaluated[k]
                && classes[k] == PixelClass::Planar
                && t != methods::raster::NO_TRIANGLE
                && frame.geometry.object[t as usize] == receiver
        })
        .collect()
}

/// Asserts `lit == 1 - shadowed(i, j)` within `tol` on every pixel `exact` evaluates on the
/// main receiver ([`on_receiver`]); returns the number of those pixels strictly between 0 and
/// 1.
fn assert_matches(
    frame: &Frame<'_>,
    img: &ReferenceImage,
    tol: f64,
    shadowed: impl Fn(usize, usize) -> f64,
) -> usize {
    let w = img.width as usize;
    let mut partial = 0;
    let mut worst = 0.0f64;
    let mine = on_receiver(frame, img);
    for (k, &l) in img.lit.iter().enumerate() {
        if !mine[k] {
            continue;
        }
        let (i, j) = (k % w, k / w);
        let expect = (1.0 - shadowed(i, j)).clamp(0.0, 1.0);
        let err = (l - expect).abs();
        worst = worst.max(err);
        assert!(err <= tol, "pixel ({i}, {j}): exact {l} vs analytic {expect} (error {err:e})");
        partial += usize::from(expect > 0.0 && expect < 1.0);
    }
    eprintln!("worst error {worst:e} over {} pixels, {partial} partial", img.lit.len());
    partial
}

/// The four world corners of a one-quad plane object, in order around it.
fn quad_corners(scene: &Scene, object: usize) -> [DVec3; 4] {
    let p = &scene.objects[object].mesh.positions;
    assert_eq!(p.len(), 4, "a one-quad plane");
    // Vertex (i, j) of the plane's grid is positions[j * 2 + i].
    [p[0], p[1], p[3], p[2]]
}

// ---------------------------------------------------------------------------------------------
// Analytic cases

#[test]
fn exact_axis_aligned_square_under_a_vertical_light_is_exact() {
    // Square [-0.6875, 1.3125] x [-1.40625, 0.59375] at height 1.5: shadow on screen
    // [26.5, 42.5] x [12.75, 28.75], dyadic, so every step is exact.
    let (tx, tz) = (0.3125, -0.40625);
    for from_below in [false, true] {
        let s = scene(
            ortho_camera(from_below),
            DOWN,
            vec![ground(), plane_object("square", 2.0, DVec3::ZERO, DVec3::new(tx, 1.5, tz))],
        );
        let (frame, img, rec) = exact(&s, 64, 48);
        let (xa, xb) = (
            ortho_screen(DVec3::new(tx - 1.0, 0.0, 0.0), from_below).x,
            ortho_screen(DVec3::new(tx + 1.0, 0.0, 0.0), from_below).x,
        );
        let rect = [xa.min(xb), xa.max(xb), 24.0 + 8.0 * (tz - 1.0), 24.0 + 8.0 * (tz + 1.0)];
        let partial = assert_matches(&frame, &img, 1e-9, |i, j| rect_area(rect, i, j));
        // From above, the square hides its shadow (the light and the camera look straight
        // down); from below, the ground shows all of it.
        assert!(if from_below { partial >= 60 } else { partial == 0 }, "{partial} partial pixels");
        for name in ["pixel classes", "shadow polygons", "pixel unions"] {
            assert!(rec.stages.stages.iter().any(|st| st.name == name), "stage {name} missing");
        }
        // Seen from above, the square hides its own shadow: the pixels whose square overlaps
        // the square's screen image [26.5, 42.5] x [12.75, 28.75] without lying inside it
        // see both objects (`edge`, not evaluated); those inside see the square (`planar`, lit).
        // Seen from below, every pixel sees the ground alone.
        let w = 64;
        let classes = img.classes.as_deref().expect("exact classifies");
        for (k, &e) in img.evaluated.iter().enumerate() {
            let (i, j) = ((k % w) as f64, (k / w) as f64);
            let overlaps = i + 1.0 > rect[0] && i < rect[1] && j + 1.0 > rect[2] && j < rect[3];
            let inside = i >= rect[0] && i + 1.0 <= rect[1] && j >= rect[2] && j + 1.0 <= rect[3];
            let expect = if from_below || !overlaps {
                PixelClass::Planar
            } else if inside {
                assert_eq!(img.lit[k], 1.0, "pixel {k} on the square is lit");
                PixelClass::Planar
            } else {
                PixelClass::Edge
            };
            assert_eq!(classes[k], expect, "pixel {k} from below {from_below}");
            assert_eq!(e, expect == PixelClass::Planar, "pixel {k} from below {from_below}");
        }
    }
}

#[test]
fn exact_rotated_squares_match_clipped_polygons() {
    for (angle, (tx, tz)) in
        [(30.0, (0.1, 0.2)), (17.0, (-0.37, 0.55)), (45.0, (0.0, 0.0)), (-71.3, (1.1, -0.3))]
    {
        let s = scene(
            ortho_camera(true),
            DOWN,
            vec![
                ground(),
                plane_object("square", 2.0, DVec3::new(0.0, angle, 0.0), DVec3::new(tx, 1.5, tz)),
            ],
        );
        let (frame, img, _) = exact(&s, 64, 48);
        let footprint: Vec<DVec2> =
            quad_corners(&s, 1).iter().map(|&p| ortho_screen(p, true)).collect();
        let partial = assert_matches(&frame, &img, 1e-9, |i, j| pixel_area(&footprint, i, j));
        assert!(partial > 50);
        assert!(img.evaluated.iter().all(|&e| e), "seen from below, every pixel sees the ground");
    }
}

#[test]
fn exact_triangle_with_a_vertex_on_a_pixel_corner_and_an_edge_along_a_row() {
    // Screen (20, 10) is a pixel corner, (36, 10) on the same row line, (28.3, 30.55) anywhere.
    let screen = [DVec2::new(20.0, 10.0), DVec2::new(36.0, 10.0), DVec2::new(28.3, 30.55)];
    let world = screen.map(|p| DVec3::new((32.0 - p.x) / 8.0, 1.0, (p.y - 24.0) / 8.0));
    let mesh = Mesh { positions: world.to_vec(), triangles: vec![[0, 1, 2]] };
    let s = scene_with_mesh(ortho_camera(true), DOWN, mesh);
    let (frame, img, _) = exact(&s, 64, 48);
    let partial = assert_matches(&frame, &img, 1e-9, |i, j| pixel_area(&screen, i, j));
    assert!(partial > 20);
    // The row above the edge is untouched; the pixel below the corner is partly covered.
    assert!((0..64).all(|i| img.lit[9 * 64 + i] == 1.0));
}

#[test]
fn exact_overlapping_occluders_count_the_overlap_once() {
    // Two axis-aligned squares at different heights whose shadows, [21.5, 37.5] x
    // [12.75, 28.75] and [28.75, 44.75] x [17.375, 33.375], overlap: the union's area per pixel
    // is A + B - A∩B.
    let a = (0.3125, -0.40625, 1.5);
    let b = (-0.59375, 0.171875, 2.25);
    let s = scene(
        ortho_camera(true),
        DOWN,
        vec![
            ground(),
            plane_object("a", 2.0, DVec3::ZERO, DVec3::new(a.0, a.2, a.1)),
            plane_object("b", 2.0, DVec3::ZERO, DVec3::new(b.0, b.2, b.1)),
        ],
    );
    let (frame, img, _) = exact(&s, 64, 48);
    let rect = |(x, z, _): (f64, f64, f64)| {
        [
            32.0 - 8.0 * (x + 1.0),
            32.0 - 8.0 * (x - 1.0),
            24.0 + 8.0 * (z - 1.0),
            24.0 + 8.0 * (z + 1.0),
        ]
    };
    let (ra, rb) = (rect(a), rect(b));
    let both = [ra[0].max(rb[0]), ra[1].min(rb[1]), ra[2].max(rb[2]), ra[3].min(rb[3])];
    assert!(both[1] > both[0] && both[3] > both[2], "the shadows overlap");
    assert_matches(&frame, &img, 1e-9, |i, j| {
        rect_area(ra, i, j) + rect_area(rb, i, j) - rect_area(both, i, j)
    });
    // Fully shadowed pixels inside the overlap are exactly 0, not negative.
    let (ci, cj) = (((both[0] + both[1]) * 0.5) as usize, ((both[2] + both[3]) * 0.5) as usize);
    assert_eq!(img.lit[cj * 64 + ci], 0.0);
}

#[test]
fn exact_union_keeps_holes_lit() {
    // A square ring of four bars: the hole in the middle of the union stays lit.
    let bars = [
        (DVec3::new(0.0, 1.5, -1.0), DVec3::new(2.5, 1.0, 0.5)),
        (DVec3::new(0.0, 1.5, 1.0), DVec3::new(2.5, 1.0, 0.5)),
        (DVec3::new(-1.0, 1.6, 0.0), DVec3::new(0.5, 1.0, 2.5)),
        (DVec3::new(1.0, 1.6, 0.0), DVec3::new(0.5, 1.0, 2.5)),
    ];
    let mut objects = vec![ground()];
    for (k, (t, scale)) in bars.iter().enumerate() {
        let mut o = plane_object(&format!("bar{k}"), 1.0, DVec3::ZERO, *t);
        o.transform.scale = *scale;
        objects.push(o);
    }
    let s = scene(ortho_camera(true), DOWN, objects);
    let (frame, img, _) = exact(&s, 64, 48);
    let rects: Vec<[f64; 4]> = bars
        .iter()
        .map(|(t, sc)| {
            let (hx, hz) = (0.5 * sc.x, 0.5 * sc.z);
            [
                32.0 - 8.0 * (t.x + hx),
                32.0 - 8.0 * (t.x - hx),
                24.0 + 8.0 * (t.z - hz),
                24.0 + 8.0 * (t.z + hz),
            ]
        })
        .collect();
    // Inclusion-exclusion over four rectangles (intersections of rectangles are rectangles).
    let inter =
        |a: [f64; 4], b: [f64; 4]| [a[0].max(b[0]), a[1].min(b[1]), a[2].max(b[2]), a[3].min(b[3])];
    assert_matches(&frame, &img, 1e-9, |i, j| {
        let mut total = 0.0;
        for mask in 1u32..16 {
            let mut r = [f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY];
            for (b, rb) in rects.iter().enumerate() {
                if mask & (1 << b) != 0 {
                    r = inter(r, *rb);
                }
            }
            let sign = if mask.count_ones() % 2 == 1 { 1.0 } else { -1.0 };
            if r[1] > r[0] && r[3] > r[2] {
                total += sign * rect_area(r, i, j);
            }
        }
        total
    });
    assert_eq!(img.lit[24 * 64 + 32], 1.0, "the hole is lit");
}

#[test]
fn exact_occluder_partly_outside_the_frame() {
    // The square's shadow [-5.5, 10.5] x [28.75, 44.75] leaves the frame on the left.
    let (tx, tz) = (4.6875, 0.59375);
    let s = scene(
        ortho_camera(true),
        DOWN,
        vec![ground(), plane_object("square", 2.0, DVec3::ZERO, DVec3::new(tx, 1.5, tz))],
    );
    let (frame, img, _) = exact(&s, 64, 48);
    let rect = [
        32.0 - 8.0 * (tx + 1.0),
        32.0 - 8.0 * (tx - 1.0),
        24.0 + 8.0 * (tz - 1.0),
        24.0 + 8.0 * (tz + 1.0),
    ];
    assert!(rect[0] < 0.0);
    let partial = assert_matches(&frame, &img, 1e-9, |i, j| rect_area(rect, i, j));
    assert!(partial > 10);
    assert_eq!(img.lit[30 * 64], 0.0);
}

/// Central projection of `p` from `light` onto the ground `y = 0`.
fn spot_project(light: DVec3, p: DVec3) -> DVec3 {
    light + (p - light) * (light.y / (light.y - p.y))
}

#[test]
fn exact_spot_light_matches_the_central_projection() {
    for (pos, rot) in [
        (DVec3::new(0.0, 8.0, 0.0), DVec3::ZERO),
        (DVec3::new(3.0, 7.0, -1.5), DVec3::new(35.0, 20.0, 0.0)),
        (DVec3::new(-2.0, 3.0, 1.0), DVec3::new(-50.0, 0.0, 10.0)),
    ] {
        let light = Light::Spot { position: pos, target: DVec3::ZERO, fov_deg: 90.0 };
        let s = scene(
            ortho_camera(true),
            light,
            vec![ground(), plane_object("square", 1.5, rot, DVec3::new(0.2, 1.5, -0.1))],
        );
        let (frame, img, _) = exact(&s, 64, 48);
        let quad: Vec<DVec2> =
            quad_corners(&s, 1).iter().map(|&p| ortho_screen(spot_project(pos, p), true)).collect();
        let partial = assert_matches(&frame, &img, 1e-9, |i, j| pixel_area(&quad, i, j));
        assert!(partial > 30, "{partial}");
    }
}

#[test]
fn exact_perspective_camera_at_a_grazing_angle() {
    // The eye 0.4 units above the ground, looking along it: the shadow is a thin quadrilateral
    // whose screen image is the camera's projection of the four shadow corners (a homography
    // keeps straight edges straight).
    let camera = Camera::Perspective {
        eye: DVec3::new(0.3, 0.4, 9.0),
        target: DVec3::new(0.0, 0.0, 0.0),
        up: DVec3::Y,
        fov_y_deg: 40.0,
        near: 0.01,
    };
    let light = Light::Directional { direction: DVec3::new(-0.3, -1.0, 0.2) };
    let s = scene(
        camera,
        light.clone(),
        vec![
            ground(),
            plane_object("square", 2.0, DVec3::new(0.0, 25.0, 0.0), DVec3::new(0.5, 0.3, 2.0)),
        ],
    );
    let (frame, img, _) = exact(&s, 96, 64);
    let Light::Directional { direction: l } = light else { unreachable!() };
    let quad: Vec<DVec2> = quad_corners(&s, 1)
        .iter()
        .map(|&p| {
            let q = p + l * (-p.y / l.y);
            frame.camera.project(q).expect("in front").0
        })
        .collect();
    let partial = assert_matches(&frame, &img, 1e-9, |i, j| pixel_area(&quad, i, j));
    assert!(partial > 30, "{partial}");
    assert!(img.evaluated.iter().filter(|&&e| e).count() > 1000);
}

// ---------------------------------------------------------------------------------------------
// Brute-force point sampling

/// Möller–Trumbore: whether the segment `o + t d`, `t in (t_min, t_max)`, hits the triangle.
#[inline]
fn hits(o: DVec3, d: DVec3, [a, b, c]: [DVec3; 3], t_min: f64, t_max: f64) -> bool {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return false;
    }
    let inv = 1.0 / det;
    let s = o - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = e2.dot(q) * inv;
    t > t_min && t < t_max
}

fn hash(mut x: u64) -> u64 {
    x ^= x >> 33;
    x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
    x ^= x >> 33;
    x = x.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    x ^ (x >> 33)
}

/// Lit fraction of each pixel in `pixels` by `n x n` jittered stratified samples: camera ray
/// to the receiver plane, shadow ray to the light tested against the caster triangles that
/// may block it (candidates: triangles whose projection's bounding box along the light meets
/// the pixel's footprint's bounding box on the plane; every caster for spot lights).
fn brute_force(frame: &Frame<'_>, pixels: &[usize], n: usize) -> Vec<f64> {
    let scene = frame.scene;
    let (receiver, normal, offset) = scene.receiver_plane().expect("planar receiver");
    let g = &frame.geometry;
    let casters: Vec<[DVec3; 3]> = (0..g.len())
        .filter(|&t| g.object[t] as usize != receiver && frame.is_caster(t))
        .map(|t| g.corners(t))
        .collect();
    let on_plane = |o: DVec3, d: DVec3| o + d * ((offset - normal.dot(o)) / normal.dot(d));
    let bounds: Option<Vec<(DVec3, DVec3)>> = match scene.light {
        Light::Directional { direction } => Some(
            casters
                .iter()
                .map(|tri| {
                    let p = tri.map(|v| on_plane(v, direction));
                    (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]))
                })
                .collect(),
        ),
        Light::Spot { .. } => None,
    };
    let w = frame.width() as usize;
    let cam = frame.camera;
    let plane_hit = |xy: DVec2| {
        let ray = cam.ray(xy);
        ray.at(ray.intersect_plane(normal, offset).expect("the ray meets the receiver plane"))
    };
    let extent = {
        let (lo, hi) = scene.bounds();
        (hi - lo).length()
    };
    pixels
        .par_iter()
        .map(|&k| {
            let (i, j) = ((k % w) as f64, (k / w) as f64);
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .map(|(a, b)| plane_hit(DVec2::new(i + a, j + b)));
            let lo = corners.iter().fold(DVec3::INFINITY, |a, &b| a.min(b)) - 1e-9 * extent;
            let hi = corners.iter().fold(DVec3::NEG_INFINITY, |a, &b| a.max(b)) + 1e-9 * extent;
            let candidates: Vec<[DVec3; 3]> = match &bounds {
                Some(b) => casters
                    .iter()
                    .zip(b)
                    .filter(|(_, (blo, bhi))| blo.cmple(hi).all() && bhi.cmpge(lo).all())
                    .map(|(t, _)| *t)
                    .collect(),
                None => casters.clone(),
            };
            if candidates.is_empty() {
                return 1.0;
            }
            let mut lit = 0usize;
            for sy in 0..n {
                for sx in 0..n {
                    let r = hash((k as u64) << 24 ^ (sy as u64) << 12 ^ sx as u64);
                    let (u, v) =
                        ((r & 0xffff) as f64 / 65536.0, ((r >> 16) & 0xffff) as f64 / 65536.0);
                    let xy =
                        DVec2::new(i + (sx as f64 + u) / n as f64, j + (sy as f64 + v) / n as f64);
                    let q = plane_hit(xy);
                    let (d, t_max) = match scene.light {
                        Light::Directional { direction } => (-direction, f64::INFINITY),
                        Light::Spot { position, .. } => (position - q, 1.0),
                    };
                    let t_min = 1e-9 * extent / d.length();
                    if !candidates.iter().any(|&tri| hits(q, d, tri, t_min, t_max)) {
                        lit += 1;
                    }
                }
            }
            lit as f64 / (n * n) as f64
        })
        .collect()
}

/// Up to `boundary` pixels evaluated on the main receiver ([`on_receiver`]) strictly between 0
/// and 1 and `others` other such pixels, evenly spaced.
fn pick_pixels(
    frame: &Frame<'_>,
    img: &ReferenceImage,
    boundary: usize,
    others: usize,
) -> Vec<usize> {
    let evenly = |v: Vec<usize>, n: usize| -> Vec<usize> {
        if v.len() <= n {
            v
        } else {
            (0..n).map(|s| v[s * v.len() / n]).collect()
        }
    };
    let mine = on_receiver(frame, img);
    let eval: Vec<usize> = (0..img.lit.len()).filter(|&k| mine[k]).collect();
    let (b, o): (Vec<usize>, Vec<usize>) =
        eval.into_iter().partition(|&k| img.lit[k] > 0.0 && img.lit[k] < 1.0);
    let mut picked = evenly(b, boundary);
    picked.extend(evenly(o, others));
    picked
}

fn check_against_sampling(scene: &Scene, w: u32, h: u32, boundary: usize, others: usize) {
    let (frame, img, _) = exact(scene, w, h);
    let pixels = pick_pixels(&frame, &img, boundary, others);
    let n_boundary = pixels.iter().filter(|&&k| img.lit[k] > 0.0 && img.lit[k] < 1.0).count();
    assert!(n_boundary >= boundary.min(20), "{}: only {n_boundary} boundary pixels", scene.name);
    let sampled = brute_force(&frame, &pixels, 512);
    let mut worst = 0.0f64;
    for (&k, &s) in pixels.iter().zip(&sampled) {
        let err = (img.lit[k] - s).abs();
        worst = worst.max(err);
        assert!(err < 1e-3, "{}: pixel {k}: exact {} vs sampled {s}", scene.name, img.lit[k]);
        // An evaluated pixel's centre sees the receiver.
        let t = frame.gbuffer.triangle[k] as usize;
        let receiver = scene.receiver_plane().expect("plane").0;
        assert_eq!(frame.geometry.object[t] as usize, receiver, "pixel {k} is evaluated");
    }
    eprintln!(
        "{}: {} pixels ({n_boundary} boundary), worst |exact - sampled| = {worst:e}",
        scene.name,
        pixels.len()
    );
}

#[test]
fn exact_agrees_with_point_sampling_on_built_in_scenes() {
    for name in ["plane-square", "cage", "random-1k"] {
        let scene = scenes::load(name).expect("built-in");
        check_against_sampling(&scene, 64, 48, 150, 50);
    }
}

#[test]
fn exact_agrees_with_point_sampling_under_a_spot_light_crossing_its_plane() {
    // A tall wall reaches above the spot light's height: only its part below the light casts
    // a shadow, which runs to the receiver's horizon under the perspective camera.
    let light = Light::Spot {
        position: DVec3::new(0.0, 2.0, 0.0),
        target: DVec3::new(0.0, 0.0, -1.0),
        fov_deg: 120.0,
    };
    let camera = Camera::Perspective {
        eye: DVec3::new(0.0, 3.0, 6.0),
        target: DVec3::new(0.0, 0.0, -2.0),
        up: DVec3::Y,
        fov_y_deg: 60.0,
        near: 0.01,
    };
    let wall = plane_object("wall", 2.0, DVec3::new(90.0, 0.0, 10.0), DVec3::new(0.3, 1.5, -1.5));
    let post = {
        let mut o =
            plane_object("post", 0.4, DVec3::new(90.0, 30.0, 0.0), DVec3::new(-1.2, 0.6, 0.4));
        o.transform.scale = DVec3::new(1.0, 1.0, 3.0);
        o
    };
    let s = scene(camera, light, vec![ground(), wall, post]);
    check_against_sampling(&s, 64, 48, 120, 40);
}

// ---------------------------------------------------------------------------------------------
// An unsnapped union: vertical slabs

/// Area of the union of convex polygons inside pixel `(i, j)`, without any grid: the pixel is
/// cut into vertical slabs at every vertex and every crossing of two edges, inside which each
/// polygon's cross-section is an interval with linear ends and their order is fixed, so the
/// union's length is linear in `x` and the midpoint rule is exact.
fn slab_union_area(polys: &[Vec<DVec2>], i: usize, j: usize) -> f64 {
    let clipped: Vec<Vec<DVec2>> = polys
        .iter()
        .map(|p| {
            // Relative to the pixel's corner.
            let corner = DVec2::new(i as f64, j as f64);
            let local: Vec<DVec2> = p.iter().map(|&q| q - corner).collect();
            let mut c = clip_half(&local, |q| q.x);
            c = clip_half(&c, |q| 1.0 - q.x);
            c = clip_half(&c, |q| q.y);
            clip_half(&c, |q| 1.0 - q.y)
        })
        .filter(|c| c.len() >= 3)
        .collect();
    if clipped.is_empty() {
        return 0.0;
    }
    let edges: Vec<(DVec2, DVec2)> = clipped
        .iter()
        .flat_map(|c| (0..c.len()).map(move |k| (c[k], c[(k + 1) % c.len()])))
        .collect();
    let mut xs: Vec<f64> = vec![0.0, 1.0];
    xs.extend(edges.iter().map(|e| e.0.x));
    for (a, &(p, q)) in edges.iter().enumerate() {
        for &(r, s) in &edges[a + 1..] {
            let (d1, d2) = (q - p, s - r);
            let den = d1.perp_dot(d2);
            if den == 0.0 {
                continue;
            }
            let t = (r - p).perp_dot(d2) / den;
            let u = (r - p).perp_dot(d1) / den;
            if (0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u) {
                xs.push(p.x + t * d1.x);
            }
        }
    }
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let mut area = 0.0;
    let mut spans: Vec<(f64, f64)> = Vec::with_capacity(clipped.len());
    for w in xs.windows(2) {
        let (xa, xb) = (w[0], w[1]);
        if xb <= xa {
            continue;
        }
        let xm = 0.5 * (xa + xb);
        spans.clear();
        for c in &clipped {
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for k in 0..c.len() {
                let (p, q) = (c[k], c[(k + 1) % c.len()]);
                if (p.x - xm) * (q.x - xm) <= 0.0 && p.x != q.x {
                    let y = p.y + (xm - p.x) / (q.x - p.x) * (q.y - p.y);
                    lo = lo.min(y);
                    hi = hi.max(y);
                }
            }
            if hi > lo {
                spans.push((lo, hi));
            }
        }
        spans.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (mut len, mut end) = (0.0, f64::NEG_INFINITY);
        for &(lo, hi) in &spans {
            if hi > end {
                len += hi - lo.max(end);
                end = hi;
            }
        }
        area += (xb - xa) * len;
    }
    area
}

/// The worst per-pixel difference between `exact` and the slab union of the same shadow
/// polygons on `name` at `w x h`.
fn worst_against_slab_union(name: &str, w: u32, h: u32) -> f64 {
    let scene = scenes::load(name).expect("built-in");
    let (frame, img, _) = exact(&scene, w, h);
    let polys: Vec<Vec<DVec2>> = shadow_polygons(&frame)
        .expect("applies")
        .contours()
        .map(|c| c.iter().map(|p| DVec2::new(p[0], p[1])).collect())
        .collect();
    // Bin polygons by pixel so each pixel sees only its own.
    let (w, h) = (w as usize, h as usize);
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); w * h];
    for (k, p) in polys.iter().enumerate() {
        let lo = p.iter().fold(DVec2::INFINITY, |a, &b| a.min(b));
        let hi = p.iter().fold(DVec2::NEG_INFINITY, |a, &b| a.max(b));
        for j in (lo.y.floor().max(0.0) as usize)..(hi.y.ceil() as usize).min(h) {
            for i in (lo.x.floor().max(0.0) as usize)..(hi.x.ceil() as usize).min(w) {
                bins[j * w + i].push(k as u32);
            }
        }
    }
    let mine = on_receiver(&frame, &img);
    let worst = (0..w * h)
        .into_par_iter()
        .filter(|&k| mine[k])
        .map(|k| {
            let mine: Vec<Vec<DVec2>> =
                bins[k].iter().map(|&p| polys[p as usize].clone()).collect();
            let shadowed = slab_union_area(&mine, k % w, k / w);
            (img.lit[k] - (1.0 - shadowed).clamp(0.0, 1.0)).abs()
        })
        .reduce(|| 0.0, f64::max);
    eprintln!(
        "{name} {w}x{h}: {} shadow polygons, worst |exact - slab union| = {worst:e}",
        polys.len()
    );
    worst
}

#[test]
fn exact_matches_an_unsnapped_slab_union_on_built_in_scenes() {
    // Everything after the shadow polygons (the per-pixel cuts) against an independent union
    // by vertical slabs: this measures the bound.
    for name in ["plane-square", "cage", "random-1k", "plant", "grazing", "spot-spheres"] {
        let worst = worst_against_slab_union(name, 64, 48);
        assert!(worst < 1e-12, "{name}: {worst:e}");
    }
    // Large frames: every cut is taken relative to its pixel's corner, so the error does not
    // grow with the coordinates.
    let worst = worst_against_slab_union("cage", 800, 600);
    assert!(worst < 1e-12, "cage at 800 x 600: {worst:e}");
}

// ---------------------------------------------------------------------------------------------
// Applicability, cross-check

#[test]
fn exact_does_not_apply_to_transparency_but_to_curved_receivers() {
    let scene = scenes::load("hairball").expect("built-in");
    let mut rec = Recorder::default();
    let frame = Frame::new(&scene, 32, 24, &mut rec);
    match ExactCoverage::default().evaluate(&frame, &mut rec) {
        Err(ReferenceError::NotApplicable(msg)) => {
            assert!(msg.contains("transparen") && msg.contains("hairball"), "{msg}")
        }
        other => panic!("hairball: expected NotApplicable, got {other:?}"),
    }
    // `bumpy` has no planar receiver: every pixel that sees it is `surface` or `edge`.
    let scene = scenes::load("bumpy").expect("built-in");
    assert!(!scene.effects().planar_receiver);
    let (_, img, _) = exact(&scene, 64, 48);
    let n = counts(img.classes.as_deref().expect("classes"));
    assert_eq!(n[PixelClass::Planar as usize], 0);
    assert!(n[PixelClass::Surface as usize] > 9 * n[PixelClass::Edge as usize], "{n:?}");
}

#[test]
fn exact_tiny_skia_difference_falls_with_resolution() {
    for name in ["plane-square", "cage"] {
        let scene = scenes::load(name).expect("built-in");
        let mut rec = Recorder::default();
        let frame = Frame::new(&scene, 160, 120, &mut rec);
        let checks: Vec<_> = [1, 2, 4, 8]
            .iter()
            .map(|&k| tiny_skia_crosscheck(&frame, k).expect("applies"))
            .collect();
        for c in &checks {
            eprintln!(
                "{name}: k = {}: mean |diff| {:.3e}, max |diff| {:.3e} over {} pixels",
                c.k, c.mean_abs_diff, c.max_abs_diff, c.evaluated_pixels
            );
            assert!(c.evaluated_pixels > 1000);
        }
        for pair in checks.windows(2) {
            assert!(pair[1].mean_abs_diff <= pair[0].mean_abs_diff, "{name}: {pair:?}");
        }
        assert!(checks[0].mean_abs_diff > checks[3].mean_abs_diff, "{name}");
        assert!(checks[3].max_abs_diff < 0.05, "{name}: {:?}", checks[3]);
    }
}

#[test]
fn exact_outputs_are_finite_and_in_range_on_every_applicable_built_in() {
    for name in
        ["plane-square", "random-1k", "cage", "plant", "spheres", "city", "grazing", "spot-spheres"]
    {
        let scene = scenes::load(name).expect("built-in");
        let (_, img, rec) = exact(&scene, 80, 60);
        let evaluated = img.evaluated.iter().filter(|&&e| e).count();
        eprintln!("{name}: {evaluated} evaluated pixels; {:?}", rec.notes);
        assert!(evaluated > 0, "{name}");
        assert!(!rec.notes.iter().any(|n| n.contains("skipped")), "{name}: {:?}", rec.notes);
    }
}

// ---------------------------------------------------------------------------------------------
// Pixel classes with many triangles in one pixel

/// A pixel overlapped by more triangles than one word of the rule's bit sets holds: a flat
/// fan of 100 wedges whose apex lies inside pixel (32, 24), above the ground, looking down.
/// The wedges tile the pixel as one surface, so it is `planar` with all of them as its tiles;
/// the same with 40 wedges (one word). Its light is that of the fan's top, lit from above.
#[test]
fn a_pixel_of_more_triangles_than_a_word_is_tiled_by_all_of_them() {
    for wedges in [40u32, 100] {
        // Screen x = 32 + 8 wx, y = 24 + 8 wz: the apex at (32.4, 24.45).
        let apex = DVec3::new(0.05, 1.0, 0.05625);
        let mut positions = vec![apex];
        for k in 0..wedges {
            let a = std::f64::consts::TAU * f64::from(k) / f64::from(wedges);
            positions.push(apex + 0.3 * DVec3::new(a.cos(), 0.0, a.sin()));
        }
        let triangles = (0..wedges).map(|k| [0, 1 + k, 1 + (k + 1) % wedges]).collect();
        let scene = scene_with_mesh(ortho_camera(false), DOWN, Mesh { positions, triangles });
        let (frame, img, _) = exact(&scene, 64, 48);
        let classes = analysis::exact::classify(&frame);
        let k = 24 * 64 + 32;
        assert_eq!(classes.class[k], PixelClass::Planar, "{wedges} wedges");
        let first = frame.geometry.len() as u32 - wedges;
        let fan: Vec<u32> = (first..first + wedges).collect();
        assert_eq!(classes.tiles_of(k), &fan[..], "{wedges} wedges");
        assert!(img.evaluated[k] && img.lit[k] == 1.0, "{wedges} wedges: {}", img.lit[k]);
    }
}

/// A fold of a mesh wound inconsistently: triangle `B` shares an edge of `A` in the same
/// direction (not reversed, as in a consistently wound mesh) and folds back under it, so that
/// on screen both have one winding and `B` lies on `A`'s side of the shared edge, hidden
/// behind it. `B` tiles no pixel, and `A`'s pixels, open to the light, are lit: were `B`
/// taken as a tile, its area in `A`'s shadow would darken them.
#[test]
fn a_fold_of_an_inconsistently_wound_mesh_hides_the_folded_triangle() {
    let (a, b, c) =
        (DVec3::new(-2.0, 1.0, -2.0), DVec3::new(-2.0, 1.0, 2.0), DVec3::new(2.0, 1.0, -2.0));
    let d = DVec3::new(-1.0, 0.5, 0.0);
    let mesh = Mesh { positions: vec![a, b, c, d], triangles: vec![[0, 1, 2], [0, 1, 3]] };
    let scene = scene_with_mesh(ortho_camera(false), DOWN, mesh);
    let (frame, img, _) = exact(&scene, 64, 48);
    let g = &frame.geometry;
    let caster = (0..g.len()).filter(|&t| g.object[t] == 1).collect::<Vec<_>>();
    let (top, folded) = (caster[0] as u32, caster[1] as u32);
    let classes = analysis::exact::classify(&frame);
    let mut lit = 0;
    for k in 0..img.lit.len() {
        let tiles = classes.tiles_of(k);
        assert!(!tiles.contains(&folded), "pixel {k} takes the hidden triangle");
        if img.evaluated[k] && tiles.contains(&top) {
            assert!(img.lit[k] >= 1.0 - 1e-9, "pixel {k}: {}", img.lit[k]);
            lit += 1;
        }
    }
    assert!(lit > 100, "{lit} pixels of the top triangle");
}
