//! The standard shadow map end to end: binary output, no acne on lit planes at the documented
//! valid biases, finite results on hard cases.

use glam::DVec3;
use instrumentation::Recorder;
use methods::{method, Frame, MethodOptions};
use scenes::{
    generators::PlaneParams,
    scene_file::{ObjectDesc, SceneDesc, Shape},
    Camera, Light, Material, Scene,
};

fn run(
    scene: &Scene,
    w: u32,
    h: u32,
    options: MethodOptions,
) -> (Frame<'_>, methods::Visibility, Recorder) {
    let mut rec = Recorder::default();
    let frame = Frame::new(scene, w, h, &mut rec);
    let v = method("sm", &options).expect("valid").run(&frame, &mut rec).expect("runs");
    (frame, v, rec)
}

fn lone_plane(light: Light) -> Scene {
    SceneDesc {
        name: Some("lone-plane".into()),
        resolution: [96, 72],
        camera: Camera::Perspective {
            eye: DVec3::new(0.0, 5.0, 9.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_deg: 50.0,
            near: 0.01,
        },
        light,
        effects: Default::default(),
        objects: vec![ObjectDesc {
            name: None,
            shape: Shape::Plane(PlaneParams { size: 12.0, subdivisions: 7 }),
            transform: Default::default(),
            material: Material::default(),
            casts_shadows: true,
        }],
    }
    .resolve("lone-plane", std::path::Path::new("test"), std::path::Path::new("."))
    .expect("valid scene")
}

#[test]
fn a_lit_plane_stays_fully_lit_at_every_valid_bias() {
    let lights = [
        Light::Directional { direction: DVec3::new(-0.3, -1.0, -0.2) },
        Light::Directional { direction: DVec3::new(1.0, -0.12, 0.3) }, // about 83° from vertical
        Light::Spot { position: DVec3::new(2.0, 6.0, 1.0), target: DVec3::ZERO, fov_deg: 120.0 },
    ];
    for light in lights {
        let scene = lone_plane(light.clone());
        for map_res in [64, 256, 1024] {
            for slope_bias in [1.0, 2.0, 4.0] {
                for constant_bias in [0.0, 1e-5, 1e-3] {
                    let options = MethodOptions {
                        map_res: Some(map_res),
                        slope_bias: Some(slope_bias),
                        constant_bias: Some(constant_bias),
                        ..Default::default()
                    };
                    let (_, v, _) = run(&scene, 96, 72, options);
                    let dark = v.lit.iter().filter(|&&l| l != 1.0).count();
                    assert_eq!(
                        dark, 0,
                        "{light:?} map {map_res} slope {slope_bias} constant {constant_bias}"
                    );
                }
            }
        }
    }
}

#[test]
fn without_slope_bias_a_tilted_light_shows_acne() {
    // The bias bound is not vacuous: below the valid range, the same plane self-shadows.
    let scene = lone_plane(Light::Directional { direction: DVec3::new(1.0, -0.5, 0.3) });
    let options = MethodOptions {
        map_res: Some(256),
        slope_bias: Some(0.0),
        constant_bias: Some(0.0),
        ..Default::default()
    };
    let (_, v, _) = run(&scene, 96, 72, options);
    assert!(v.lit.iter().filter(|&&l| l == 0.0).count() > 100);
}

#[test]
fn sm_is_binary_and_casts_the_square_shadow() {
    let scene = scenes::load("plane-square").expect("built-in");
    let (frame, v, rec) = run(&scene, 160, 120, MethodOptions::default());
    assert!(v.lit.iter().all(|&l| l == 0.0 || l == 1.0));
    let shadowed = v.lit.iter().filter(|&&l| l == 0.0).count();
    assert!(shadowed > 100, "{shadowed} shadowed pixels");
    let covered = (0..v.lit.len()).filter(|&k| frame.gbuffer.covered(k)).count() as u64;
    assert_eq!(rec.counters.shadow_map_lookups, covered);
    assert!(rec.stages.skipped.is_empty());
}

#[test]
fn hard_cases_stay_finite_and_in_range() {
    for name in ["grazing", "bumpy", "cage", "hairball", "spot-spheres"] {
        let scene = scenes::load(name).expect("built-in");
        for map_res in [16, 512] {
            let (_, v, rec) = run(
                &scene,
                120,
                90,
                MethodOptions { map_res: Some(map_res), ..Default::default() },
            );
            assert!(v.lit.iter().all(|l| l.is_finite() && (0.0..=1.0).contains(l)), "{name}");
            if name == "hairball" {
                assert!(rec.notes.iter().any(|n| n.contains("opaque")), "{name}: {:?}", rec.notes);
            }
        }
    }
}
