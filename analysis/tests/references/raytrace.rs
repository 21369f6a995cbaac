//! The ray-traced reference end to end: binary values at rate 1 with exact ray counts, lit
//! planes without self-shadowing, closed meshes without light leaks, quantised values and
//! convergence with the rate, multiplied transmittance through stacked semi-transparent quads,
//! finite results on the hard scenes, and packets that change no pixel whatever the mask or the
//! thread count.

use analysis::raytrace::{RayTrace, STAGE_BVH_BUILD, STAGE_RAY_TRACING};
use analysis::{Reference, ReferenceImage};
use glam::DVec3;
use instrumentation::Recorder;
use methods::pattern::{PatternKind, SamplePattern};
use methods::Frame;
use scenes::{
    generators::{PlaneParams, SpheresParams},
    scene::EffectSwitches,
    scene_file::{ObjectDesc, SceneDesc, Shape, Transform},
    Camera, Light, Material, Scene,
};

const W: u32 = 64;
const H: u32 = 48;

fn tracer(rate: u32, kind: PatternKind) -> RayTrace {
    RayTrace { pattern: SamplePattern::new(rate, kind).expect("valid rate") }
}

fn trace(scene: &Scene, rate: u32, kind: PatternKind) -> (Frame<'_>, ReferenceImage, Recorder) {
    let mut rec = Recorder::default();
    let frame = Frame::new(scene, W, H, &mut rec);
    let image = tracer(rate, kind).evaluate(&frame, &mut rec).expect("raytrace runs");
    assert_eq!((image.width, image.height), (W, H));
    assert_eq!(image.lit.len(), (W * H) as usize);
    assert_eq!(image.evaluated.len(), (W * H) as usize);
    assert!(image.lit.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)), "{}", scene.name);
    (frame, image, rec)
}

fn object(name: &str, shape: Shape, transform: Transform, opacity: f64) -> ObjectDesc {
    ObjectDesc {
        name: Some(name.into()),
        shape,
        transform,
        material: Material { opacity, ..Material::default() },
        casts_shadows: true,
    }
}

fn plane(name: &str, size: f64, subdivisions: u32, translate: DVec3, opacity: f64) -> ObjectDesc {
    object(
        name,
        Shape::Plane(PlaneParams { size, subdivisions }),
        Transform { translate, ..Default::default() },
        opacity,
    )
}

fn scene(camera: Camera, light: Light, effects: EffectSwitches, objects: Vec<ObjectDesc>) -> Scene {
    SceneDesc {
        name: Some("test".into()),
        resolution: [W, H],
        camera,
        light,
        effects,
        objects,
        animation: Default::default(),
    }
    .resolve("test", std::path::Path::new("test"), std::path::Path::new("."))
    .expect("valid scene")
}

fn perspective(eye: DVec3, target: DVec3, fov_y_deg: f64) -> Camera {
    Camera::Perspective { eye, target, up: DVec3::Y, fov_y_deg, near: 0.01 }
}

fn mean_abs_error(a: &ReferenceImage, reference: &ReferenceImage) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for k in 0..a.lit.len() {
        if reference.evaluated[k] {
            sum += (a.lit[k] - reference.lit[k]).abs();
            n += 1;
        }
    }
    sum / n.max(1) as f64
}

#[test]
fn rate_one_on_plane_square_is_binary_casts_the_shadow_and_counts_every_ray() {
    let scene = scenes::load("plane-square").expect("built-in");
    let (frame, image, rec) = trace(&scene, 1, PatternKind::Grid);
    assert!(image.lit.iter().all(|&v| v == 0.0 || v == 1.0));
    assert!(image.transmittance.is_none());
    let shadowed = image.lit.iter().filter(|&&v| v == 0.0).count();
    assert!(shadowed > 20, "{shadowed} shadowed pixels");

    // The shadow lies where the square's shadow is: below the square along the light.
    let Light::Directional { direction } = scene.light else { panic!("directional") };
    let square = &scene.objects[1].mesh;
    let (lo, hi) = square.bounds().expect("square");
    let centre = 0.5 * (lo + hi);
    let foot = centre + direction * (centre.y / -direction.y);
    for k in 0..image.lit.len() {
        if image.lit[k] == 0.0 {
            let t = frame.gbuffer.triangle[k] as usize;
            assert_eq!(frame.geometry.object[t], 0, "only the ground is shadowed");
            let p = frame.gbuffer.position[k];
            assert!((p - foot).length() < 2.0, "shadowed point {p} far from {foot}");
        }
    }

    // Rays: one camera ray per sub-sample, one shadow ray per sub-sample that hit a surface.
    // At rate 1 the sub-sample is the pixel centre, which the G-buffer rasterized independently.
    let covered = (0..image.lit.len()).filter(|&k| frame.gbuffer.covered(k)).count() as u64;
    let evaluated = image.evaluated.iter().filter(|&&e| e).count() as u64;
    assert_eq!(evaluated, covered);
    assert_eq!(rec.counters.rays_traced, u64::from(W * H) + covered);
    let names: Vec<&str> = rec.stages.stages.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["camera G-buffer", STAGE_BVH_BUILD, STAGE_RAY_TRACING]);

    // At rate 4 every evaluated pixel traced 4 shadow rays, others between 0 and 3.
    let (_, image4, rec4) = trace(&scene, 4, PatternKind::Rotated);
    let ev4 = image4.evaluated.iter().filter(|&&e| e).count() as u64;
    let camera_rays = u64::from(W * H) * 4;
    let r = rec4.counters.rays_traced;
    assert!(
        r >= camera_rays + 4 * ev4 && r <= camera_rays + 4 * ev4 + 3 * (u64::from(W * H) - ev4)
    );
}

#[test]
fn name_and_params() {
    let t = tracer(64, PatternKind::Rotated);
    assert_eq!(t.name(), "raytrace");
    let p = t.params();
    assert_eq!(p["rate"], 64);
    assert_eq!(p["pattern"], "rotated");
}

#[test]
fn a_lit_plane_stays_lit_under_every_light() {
    let lights = [
        Light::Directional { direction: DVec3::new(-0.3, -1.0, -0.2) },
        // 85 degrees from the vertical, two azimuths.
        Light::Directional {
            direction: DVec3::new(85f64.to_radians().sin(), -85f64.to_radians().cos(), 0.0),
        },
        Light::Directional {
            direction: DVec3::new(
                -0.6 * 85f64.to_radians().sin(),
                -85f64.to_radians().cos(),
                0.8 * 85f64.to_radians().sin(),
            ),
        },
        Light::Spot { position: DVec3::new(2.0, 6.0, 1.0), target: DVec3::ZERO, fov_deg: 120.0 },
        Light::Spot { position: DVec3::new(9.0, 0.5, -3.0), target: DVec3::ZERO, fov_deg: 90.0 },
    ];
    let cameras = [
        perspective(DVec3::new(0.0, 5.0, 9.0), DVec3::ZERO, 50.0),
        perspective(DVec3::new(1.0, 0.4, 9.0), DVec3::ZERO, 40.0), // grazing view
    ];
    for light in lights {
        for camera in &cameras {
            let s = scene(
                camera.clone(),
                light.clone(),
                EffectSwitches::default(),
                vec![plane("ground", 12.0, 7, DVec3::ZERO, 1.0)],
            );
            let (_, image, _) = trace(&s, 4, PatternKind::Rotated);
            let dark = image.lit.iter().filter(|&&v| v != 1.0).count();
            assert_eq!(dark, 0, "{light:?} {camera:?}");
            assert!(image.evaluated.iter().any(|&e| e));
        }
    }
}

/// A unit sphere (icosphere) over the ground at `centre`; returns the scene and the sphere's
/// inscribed radius.
fn sphere_scene(camera: Camera, light: Light, centre: DVec3) -> (Scene, f64) {
    let sphere = object(
        "sphere",
        Shape::Spheres(SpheresParams { count: 1, subdivisions: 3, ..Default::default() }),
        Transform { fit_size: Some(2.0), translate: centre, ..Default::default() },
        1.0,
    );
    let s = scene(
        camera,
        light,
        EffectSwitches::default(),
        vec![plane("ground", 40.0, 4, DVec3::ZERO, 1.0), sphere],
    );
    let mesh = &s.objects[1].mesh;
    let r_in = (0..mesh.triangles.len())
        .map(|t| {
            let [a, b, c] = mesh.triangles[t].map(|v| mesh.positions[v as usize]);
            (b - a).cross(c - a).normalize().dot(a - centre).abs()
        })
        .fold(f64::INFINITY, f64::min);
    assert!(r_in > 0.95 && r_in < 1.0, "{r_in}");
    (s, r_in)
}

#[test]
fn a_closed_sphere_lets_no_light_through() {
    // Orthographic camera under the ground looking up at its underside: every pixel sees the
    // ground, 8 pixels per world unit; the sphere's shadow core under a vertical light is dark.
    let camera = Camera::Orthographic {
        eye: DVec3::new(0.0, -10.0, 0.0),
        target: DVec3::ZERO,
        up: DVec3::new(0.0, 0.0, -1.0),
        height: 6.0,
    };
    let centre = DVec3::new(0.3, 2.5, -0.2);
    let down = Light::Directional { direction: DVec3::new(0.0, -1.0, 0.0) };
    let (s, r_in) = sphere_scene(camera, down, centre);
    let (frame, image, _) = trace(&s, 16, PatternKind::Grid);
    assert!(image.evaluated.iter().all(|&e| e));
    let half_diagonal = 0.5 * 2f64.sqrt() / 8.0;
    let (mut core, mut outside) = (0, 0);
    for k in 0..image.lit.len() {
        let p = frame.gbuffer.position[k];
        let d = ((p.x - centre.x).powi(2) + (p.z - centre.z).powi(2)).sqrt();
        if d + half_diagonal < r_in {
            core += 1;
            assert_eq!(image.lit[k], 0.0, "light leaks at {p}");
        } else if d - half_diagonal > 1.0 {
            outside += 1;
            assert_eq!(image.lit[k], 1.0, "false shadow at {p}");
        }
    }
    assert!(core > 150 && outside > 1000, "{core} {outside}");

    // Seen from the side under a slanted light: every point of the sphere that faces away from
    // the light is dark, every point of the ground far from the shadow is lit.
    let light = Light::Directional { direction: DVec3::new(-0.5, -1.0, -0.3) };
    let camera = perspective(DVec3::new(0.0, 3.0, 7.0), centre, 30.0);
    let (s, _) = sphere_scene(camera, light.clone(), centre);
    let (frame, image, _) = trace(&s, 1, PatternKind::Grid);
    let to_light = light.direction_to_light(DVec3::ZERO);
    let mut dark_side = 0;
    for k in 0..image.lit.len() {
        if !frame.gbuffer.covered(k) {
            continue;
        }
        let t = frame.gbuffer.triangle[k] as usize;
        let p = frame.gbuffer.position[k];
        if frame.geometry.object[t] == 1 && (p - centre).normalize().dot(to_light) < -0.05 {
            dark_side += 1;
            assert_eq!(image.lit[k], 0.0, "light leaks through the sphere at {p}");
        }
    }
    assert!(dark_side > 100, "{dark_side}");
}

#[test]
fn rates_quantise_and_the_error_shrinks_with_the_rate() {
    let scene = scenes::load("plane-square").expect("built-in");
    let (_, reference, _) = trace(&scene, 1024, PatternKind::Grid);
    for kind in [PatternKind::Grid, PatternKind::Rotated] {
        let mut errors = Vec::new();
        for rate in [4, 16, 64] {
            let (_, image, _) = trace(&scene, rate, kind);
            let n = f64::from(rate);
            assert!(image.lit.iter().all(|v| (v * n).fract() == 0.0), "{kind} {rate}");
            let boundary = image.lit.iter().filter(|&&v| v > 0.0 && v < 1.0).count();
            let e = mean_abs_error(&image, &reference);
            println!("plane-square {W}x{H} {kind} rate {rate}: mean abs error {e:.6} vs rate 1024 ({boundary} boundary pixels)");
            errors.push(e);
        }
        assert!(errors[0] > errors[1] && errors[1] > errors[2], "{kind}: {errors:?}");
        assert!(errors[2] > 0.0 && errors[2] < 0.01, "{kind}: {errors:?}");
    }
}

#[test]
fn stacked_semi_transparent_quads_multiply_the_transmittance() {
    // Two quads of opacity 0.1 at heights 1 and 2 overlapping over |x| < 1; a vertical light;
    // the camera below the quads looks at the floor under them.
    let objects = || {
        vec![
            plane("ground", 12.0, 1, DVec3::ZERO, 1.0),
            plane("low", 4.0, 1, DVec3::new(-1.0, 1.0, 0.0), 0.1),
            plane("high", 4.0, 1, DVec3::new(1.0, 2.0, 0.0), 0.1),
        ]
    };
    let camera = perspective(DVec3::new(0.0, 0.7, 4.0), DVec3::new(0.0, 0.0, -0.5), 75.0);
    let down = Light::Directional { direction: DVec3::new(0.0, -1.0, 0.0) };
    let s = scene(camera.clone(), down.clone(), EffectSwitches::default(), objects());
    assert!(s.effects().transparency);
    let (frame, image, _) = trace(&s, 1, PatternKind::Grid);
    let trans = image.transmittance.as_ref().expect("transmittance with transparency");
    assert_eq!(trans.len(), image.lit.len());

    let (mut once, mut twice, mut open) = (0, 0, 0);
    for (k, &[r, g, b]) in trans.iter().enumerate() {
        assert!(r == g && g == b && r == image.lit[k], "grey transmittance, lit = its mean");
        if !frame.gbuffer.covered(k)
            || frame.geometry.object[frame.gbuffer.triangle[k] as usize] != 0
        {
            continue;
        }
        let p = frame.gbuffer.position[k];
        let inside_z = p.z.abs() < 1.8;
        let expected = if inside_z && ((-2.8..-1.2).contains(&p.x) || (1.2..2.8).contains(&p.x)) {
            once += 1;
            0.9
        } else if inside_z && p.x.abs() < 0.8 {
            twice += 1;
            0.81
        } else if p.z.abs() > 2.2 || p.x.abs() > 3.2 {
            open += 1;
            1.0
        } else {
            continue;
        };
        assert!((image.lit[k] - expected).abs() < 1e-9, "{p}: {} vs {expected}", image.lit[k]);
    }
    println!("floor pixels behind one quad {once}, two quads {twice}, none {open}");
    assert!(once > 50 && twice > 20 && open > 50, "{once} {twice} {open}");

    // With transparency forced off the quads are opaque and there is no transmittance.
    let no_transparency = EffectSwitches { transparency: false, ..Default::default() };
    let s = scene(camera, down, no_transparency, objects());
    let (frame, opaque, _) = trace(&s, 1, PatternKind::Grid);
    assert!(opaque.transmittance.is_none());
    assert!(opaque.lit.iter().all(|&v| v == 0.0 || v == 1.0));
    for k in 0..opaque.lit.len() {
        let p = frame.gbuffer.position[k];
        if frame.gbuffer.covered(k) && image.lit[k] < 1.0 && p.y.abs() < 1e-9 {
            assert_eq!(opaque.lit[k], 0.0, "{p}");
        }
    }
}

#[test]
fn hairball_carries_transmittance() {
    let scene = scenes::load("hairball").expect("built-in");
    let (_, image, rec) = trace(&scene, 1, PatternKind::Grid);
    let trans = image.transmittance.as_ref().expect("transmittance");
    assert!(trans.iter().flatten().all(|v| v.is_finite() && (0.0..=1.0).contains(v)));
    let partial = image.lit.iter().filter(|&&v| v > 0.0 && v < 1.0).count();
    assert!(partial > 20, "{partial} partially transmitted pixels");
    assert!(rec.counters.rays_traced > u64::from(W * H));
}

#[test]
fn hard_scenes_stay_finite_and_in_range() {
    for name in ["grazing", "bumpy", "random-10k", "spot-spheres", "cage"] {
        let scene = scenes::load(name).expect("built-in");
        let (_, image, _) = trace(&scene, 4, PatternKind::Rotated);
        assert!(image.evaluated.iter().any(|&e| e), "{name}");
        assert!(image.lit.iter().any(|&v| v < 1.0), "{name} has shadows");
    }
}

#[test]
fn rate_one_sees_what_the_g_buffer_sees() {
    // Perspective, and an orthographic camera whose image plane cuts through the scene (the
    // G-buffer sees every depth; so must the camera rays).
    let scene = scenes::load("plane-square").expect("built-in");
    let inside = Scene {
        camera: Camera::Orthographic {
            eye: DVec3::new(0.0, 1.0, 3.0),
            target: DVec3::new(0.0, 0.0, 0.0),
            up: DVec3::Y,
            height: 8.0,
        },
        ..scene.clone()
    };
    for s in [&scene, &inside] {
        let (frame, image, _) = trace(s, 1, PatternKind::Grid);
        let mismatches = (0..image.lit.len())
            .filter(|&k| image.evaluated[k] != frame.gbuffer.covered(k))
            .count();
        assert_eq!(mismatches, 0, "{:?}", s.camera);
    }
}

/// Packets are formed from the pixels traced, a tile at a time: a sparse mask (as `exact`
/// passes for its edge pixels) leaves each traced pixel's value as in the full image, so does
/// the number of threads, and `sample_image` agrees with `evaluate` sub-sample by sub-sample.
#[test]
fn packets_change_no_pixel_whatever_the_mask_or_the_threads() {
    for (name, rate) in [("cage", 1), ("spot-spheres", 4), ("random-10k", 16), ("grazing", 64)] {
        let scene = scenes::load(name).expect("built-in");
        let mut rec = Recorder::default();
        let frame = Frame::new(&scene, W, H, &mut rec);
        let rt = tracer(rate, PatternKind::Rotated);
        let full = rt.evaluate(&frame, &mut rec).expect("raytrace runs");
        let mask: Vec<bool> = (0..W * H).map(|k| k.is_multiple_of(7) || k % 11 == 3).collect();
        let sparse = rt.evaluate_pixels(&frame, Some(&mask), &mut rec).expect("raytrace runs");
        for (k, &traced) in mask.iter().enumerate() {
            if traced {
                assert_eq!(sparse.lit[k], full.lit[k], "{name}, pixel {k}");
                assert_eq!(sparse.evaluated[k], full.evaluated[k], "{name}, pixel {k}");
            } else {
                assert_eq!((sparse.lit[k], sparse.evaluated[k]), (1.0, false), "{name}");
            }
        }
        let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().expect("a pool");
        let threaded = pool.install(|| rt.evaluate(&frame, &mut Recorder::default()));
        assert_eq!(threaded.expect("raytrace runs").lit, full.lit, "{name}");
        let samples = rt.sample_image(&frame, &mut Recorder::default()).expect("raytrace runs");
        let n = rate as usize;
        for (k, &lit) in full.lit.iter().enumerate() {
            let mean = samples.light[k * n..(k + 1) * n].iter().sum::<f64>() / f64::from(rate);
            assert_eq!(mean.clamp(0.0, 1.0), lit, "{name}, pixel {k}");
        }
    }
}
