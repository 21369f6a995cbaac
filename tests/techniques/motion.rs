//! Shadows in motion against the exact truth (the temporal error of `analysis::temporal` over an
//! animated built-in's frames, each against `exact`): a method that converges to the truth
//! flickers less than a shadow map, and the papers' claims of temporal consistency hold.

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
    let exact = analysis::exact::ExactCoverage { edge: None };
    let mut temporal = Temporal::new();
    let mut prev: Option<Kept> = None;
    for i in 0..frames {
        // The scene's map scale multiplies the map's resolution, as `animate` applies it.
        let mut o = options.clone();
        if let Some(m) = o.map_res {
            o.map_res = Some(reports::motion::scaled_map_res(m, animation.map_scale(i)));
        }
        let technique = analysis::registry::technique(method, &o).expect("builds");
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

fn map(map_res: u32) -> MethodOptions {
    MethodOptions { map_res: Some(map_res), ..Default::default() }
}

/// Lecocq et al., "Sub-Pixel Shadow Mapping", I3D 2014, section 6: sub-pixel shadow maps keep
/// "high temporal consistency" when the light moves or the map's resolution varies at run time:
/// `spsm` flickers less than `sm` at the same map size, under the light's sweep over `cage` and
/// under the map-resolution ramp.
#[test]
fn sub_pixel_shadow_maps_flicker_less_than_shadow_maps_of_the_same_size() {
    for scene in ["cage-sweep", "cage-ramp"] {
        let run = |m: &str| temporal(scene, 6, (64, 48), m, &map(512)).expect("built-in");
        let (sm, spsm) = (run("sm"), run("spsm"));
        let (a, b) = (sm.mean.expect("pairs"), spsm.mean.expect("pairs"));
        assert!(b < a, "{scene}: spsm {b}, sm {a}");
    }
}

/// Pan et al., "Fast, Sub-pixel Antialiased Shadow Maps", PG 2009, section 1: pixel-level
/// aliasing, which even alias-free shadow maps keep (one sample per pixel), is "more obvious
/// under dynamic lights": under the light's sweep over `cage`, `afsm` flickers more than
/// `pan09` at 16 sub-samples.
#[test]
fn sub_pixel_antialiasing_flickers_less_than_alias_free_maps_under_a_moving_light() {
    let pan09 = MethodOptions { rate: Some(16), ..map(512) };
    let pan09 = temporal("cage-sweep", 6, (64, 48), "pan09", &pan09).expect("built-in");
    let afsm =
        temporal("cage-sweep", 6, (64, 48), "afsm", &MethodOptions::default()).expect("built-in");
    let (p, a) = (pan09.mean.expect("pairs"), afsm.mean.expect("pairs"));
    assert!(p < a / 2.0, "pan09 {p}, afsm {a}");
}
