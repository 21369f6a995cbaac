//! Every shadow-map method (`sm` and the PCF variants) end to end: no acne on lit planes at the
//! documented valid biases, finite results in [0, 1] on hard cases; `sm`'s binary output.

use crate::common::{self, MAP_METHODS};

use glam::DVec3;
use instrumentation::Recorder;
use methods::{method, Frame, MethodOptions};
use scenes::{Light, Scene};

fn run_method<'s>(
    name: &str,
    frame: &Frame<'s>,
    options: MethodOptions,
) -> (methods::Visibility, Recorder) {
    let mut rec = Recorder::default();
    let v = method(name, &options).expect("valid").run(frame, &mut rec).expect("runs");
    (v, rec)
}

fn run(
    scene: &Scene,
    w: u32,
    h: u32,
    options: MethodOptions,
) -> (Frame<'_>, methods::Visibility, Recorder) {
    let frame = Frame::new(scene, w, h, &mut Recorder::default());
    let (v, rec) = run_method("sm", &frame, options);
    (frame, v, rec)
}

#[test]
fn a_lit_plane_stays_fully_lit_at_every_valid_bias() {
    let lights = [
        Light::Directional { direction: DVec3::new(-0.3, -1.0, -0.2) },
        Light::Directional { direction: DVec3::new(1.0, -0.12, 0.3) }, // about 83° from vertical
        Light::Spot { position: DVec3::new(2.0, 6.0, 1.0), target: DVec3::ZERO, fov_deg: 120.0 },
    ];
    for light in lights {
        let scene = common::lone_plane(light.clone());
        let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
        for &name in MAP_METHODS {
            // Depth precisions: only the depth-as-colour maps quantize.
            let bits: &[Option<u32>] = if name.starts_with("pcf-bs") {
                &[Some(8), Some(12), Some(24), None]
            } else {
                &[None]
            };
            for &depth_bits in bits {
                let least = depth_bits.map_or(0.0, |b| 2f64.powi(1 - b as i32));
                for map_res in [64, 256, 1024] {
                    for slope_bias in [1.0, 4.0] {
                        for constant_bias in [least, 1e-5f64.max(least), 1e-3f64.max(least)] {
                            let options = MethodOptions {
                                map_res: Some(map_res),
                                slope_bias: Some(slope_bias),
                                constant_bias: Some(constant_bias),
                                depth_bits,
                                ..Default::default()
                            };
                            let (v, _) = run_method(name, &frame, options);
                            let dark = v.lit.iter().filter(|&&l| l != 1.0).count();
                            assert_eq!(
                                dark, 0,
                                "{name} {light:?} bits {depth_bits:?} map {map_res} slope \
                                 {slope_bias} constant {constant_bias}"
                            );
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn without_slope_bias_a_tilted_light_shows_acne() {
    // The bias bound is not vacuous: below the valid range, the same plane self-shadows.
    let scene = common::lone_plane(Light::Directional { direction: DVec3::new(1.0, -0.5, 0.3) });
    let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
    for &name in MAP_METHODS {
        let options = MethodOptions {
            map_res: Some(256),
            slope_bias: Some(0.0),
            constant_bias: Some(0.0),
            ..Default::default()
        };
        let (v, _) = run_method(name, &frame, options);
        let dark = v.lit.iter().filter(|&&l| l < 1.0).count();
        assert!(dark > 100, "{name}: {dark} pixels darkened");
    }
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
        let frame = Frame::new(&scene, 120, 90, &mut Recorder::default());
        for &m in MAP_METHODS {
            for map_res in [16, 512] {
                for depth_bits in [None, Some(8)] {
                    let options = MethodOptions {
                        map_res: Some(map_res),
                        depth_bits: depth_bits.filter(|_| m.starts_with("pcf-bs")),
                        ..Default::default()
                    };
                    let (v, rec) = run_method(m, &frame, options);
                    assert!(
                        v.lit.iter().all(|l| l.is_finite() && (0.0..=1.0).contains(l)),
                        "{name} {m} {map_res}"
                    );
                    if name == "hairball" {
                        assert!(
                            rec.notes.iter().any(|n| n.contains("opaque")),
                            "{m}: {:?}",
                            rec.notes
                        );
                    }
                }
            }
        }
    }
}
