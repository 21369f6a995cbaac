//! Shadows in motion against the exact truth: a method that converges to the truth flickers
//! less than a shadow map, frame after frame (the temporal error of `analysis::temporal` over an
//! animated built-in's frames, each against `exact`).

use crate::common;
use analysis::compare::Truth;
use analysis::temporal::{FrameInput, Temporal, TemporalMetrics, View};
use instrumentation::Recorder;
use methods::{gbuffer::GBuffer, Frame, MethodOptions, Visibility};
use scenes::{Geometry, Projector};

/// What is kept of the previous frame.
struct Kept {
    camera: Projector,
    geometry: Geometry,
    gbuffer: GBuffer,
    truth: Truth,
    result: Visibility,
}

/// The temporal metrics of `method` with `options` over `frames` frames of the animated
/// built-in `scene` at `w x h`, each frame against `exact` (edge pixels left out: the metrics
/// are taken over planar and surface pixels).
fn temporal(
    scene: &str,
    frames: u32,
    (w, h): (u32, u32),
    method: &str,
    options: &MethodOptions,
) -> Option<TemporalMetrics> {
    let rest = common::load_builtin(scene)?;
    let animation = rest.animation.with_frames(frames).expect("a frame count in range");
    let technique = analysis::registry::technique(method, options).expect("builds");
    let exact = analysis::exact::ExactCoverage { edge: None };
    let mut temporal = Temporal::new();
    let mut prev: Option<Kept> = None;
    for i in 0..frames {
        let scene = animation.pose(&rest, i);
        let frame = Frame::new(&scene, w, h, &mut Recorder::default());
        let reference =
            analysis::Reference::evaluate(&exact, &frame, &mut Recorder::default()).expect("exact");
        let truth = Truth::new(&frame, reference, &mut Recorder::default());
        let result = technique.run(&frame, &mut Recorder::default()).expect("runs");
        if let Some(p) = &prev {
            let view = View { camera: &p.camera, geometry: &p.geometry, gbuffer: &p.gbuffer };
            let before = FrameInput { view, truth: &p.truth, result: &p.result };
            temporal.add(&before, &FrameInput::of(&frame, &truth, &result));
        }
        let Frame { camera, geometry, gbuffer, .. } = frame;
        prev = Some(Kept { camera, geometry, gbuffer, truth, result });
    }
    Some(temporal.finish())
}

/// On the light's orbit over `bumpy` (a curved, self-shadowing receiver), ray-traced
/// supersampling at 256 samples per pixel flickers less than a tenth as much as a 512 shadow map
/// does, against the exact truth, frame after frame.
#[test]
fn supersampling_flickers_a_tenth_of_a_shadow_map_under_an_orbiting_light() {
    let size = (64, 48);
    let sm = MethodOptions { map_res: Some(512), ..Default::default() };
    let Some(sm) = temporal("bumpy-orbit", 4, size, "sm", &sm) else { return };
    let rt = MethodOptions { rate: Some(256), ..Default::default() };
    let rt = temporal("bumpy-orbit", 4, size, "raytrace", &rt).expect("built-in");
    assert_eq!((sm.frames, rt.frames), (4, 4));
    assert!(sm.pixel_pairs > 1000 && sm.pixel_pairs == rt.pixel_pairs, "{sm:?}\n{rt:?}");
    let (s, r) = (sm.mean.expect("pairs"), rt.mean.expect("pairs"));
    assert!(s > 0.0, "the shadow map flickers: {sm:?}");
    assert!(r < s / 10.0, "raytrace 256: {r}, sm 512: {s}");
}
