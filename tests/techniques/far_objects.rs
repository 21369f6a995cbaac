//! A far object costs the ray-traced reference nothing: `cage` with one small triangle added
//! 1e4 to 1e12 away, behind the camera and above every shadow ray (so it is neither seen nor
//! casts anything), gives the same sub-samples as `cage` alone (hit triangle and light) for
//! about the same number of ray-triangle tests. A far triangle once stretched the BVH's frame
//! and its box padding to its own distance, which made every ray test a large part of the
//! scene (60 times the time without it at 1e6).

use crate::common;

use analysis::raytrace::{RayTrace, SampleImage};
use glam::DVec3;
use instrumentation::Recorder;
use methods::{
    pattern::{PatternKind, SamplePattern},
    Frame,
};
use scenes::{Material, Mesh, Object, Scene};

const WIDTH: u32 = 64;
const HEIGHT: u32 = 48;

/// Every sub-sample of `scene` at rate 4.
fn samples(scene: &Scene) -> SampleImage {
    let mut rec = Recorder::default();
    let frame = Frame::new(scene, WIDTH, HEIGHT, &mut rec);
    let pattern = SamplePattern::new(4, PatternKind::Grid).expect("valid rate");
    RayTrace { pattern }.sample_image(&frame, &mut rec).expect("raytrace runs")
}

/// `scene` with one triangle of size 1 at distance `d` behind its camera (which looks
/// towards -z from z = 10), 3 above the ground.
fn with_far_triangle(scene: &Scene, d: f64) -> Scene {
    let p = DVec3::new(0.3 * d, 3.0, d);
    let mesh = Mesh::new(vec![p, p + DVec3::X, p + DVec3::new(0.0, 0.5, 1.0)], vec![[0, 1, 2]])
        .expect("valid mesh");
    let mut s = scene.clone();
    s.objects.push(Object {
        name: "far".into(),
        mesh,
        material: Material::default(),
        casts_shadows: true,
    });
    s
}

#[test]
fn a_far_triangle_changes_neither_the_samples_nor_the_work() {
    let Some(cage) = common::load_builtin("cage") else { return };
    let base = samples(&cage);
    let rays = base.triangle.len() as u64 * 2;
    assert!(base.triangle_tests > rays / 2, "{} tests", base.triangle_tests);
    let mut failures = Vec::new();
    for d in [1e4, 1e6, 1e8, 1e12] {
        let far = samples(&with_far_triangle(&cage, d));
        if (&far.triangle, &far.light) != (&base.triangle, &base.light) {
            failures.push(format!("{d:e}: the sub-samples differ from cage's"));
        }
        eprintln!(
            "far triangle at {d:e}: {} ray-triangle tests, {} without it",
            far.triangle_tests, base.triangle_tests
        );
        if far.triangle_tests > base.triangle_tests + base.triangle_tests / 10 {
            failures.push(format!(
                "{d:e}: {} ray-triangle tests, {} without the far triangle",
                far.triangle_tests, base.triangle_tests
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
