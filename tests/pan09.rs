//! `pan09` (Pan et al. 2009) end to end: exact mode against the ray tracer sub-sample for
//! sub-sample on planar receivers, table mode's quantization flips, the depth test of
//! non-silhouette pixels against `sm`, rate 1 against `afsm`, hard cases, stages, counters and
//! options.

use analysis::raytrace::{RayTrace, SampleImage};
use instrumentation::Recorder;
use methods::{
    pan09::{Pan09, Pan09Options, SubsampleMasks, VisibilityMode},
    pattern::{PatternKind, SamplePattern},
    Frame, Visibility,
};
use scenes::{Scene, SceneError};

/// The built-in scene `name`, or `None` (with the reason printed) when its model is missing.
fn load(name: &str) -> Option<Scene> {
    match scenes::load(name) {
        Ok(scene) => Some(scene),
        Err(e @ SceneError::ModelMissing { .. }) => {
            eprintln!("skipping {name}: {e}");
            None
        }
        Err(e) => panic!("{name}: {e}"),
    }
}

fn pan09(rate: u32, pattern: PatternKind, visibility: VisibilityMode) -> Pan09 {
    Pan09::new(Pan09Options { rate, pattern, visibility, ..Pan09Options::default() })
        .expect("valid options")
}

fn run_masks(m: &Pan09, frame: &Frame<'_>) -> (Visibility, SubsampleMasks, Recorder) {
    let mut rec = Recorder::default();
    let (v, masks) = m.run_masks(frame, &mut rec).expect("pan09 runs");
    assert_eq!(v.lit.len(), frame.gbuffer.triangle.len());
    assert!(v.lit.iter().all(|l| l.is_finite() && (0.0..=1.0).contains(l)));
    (v, masks, rec)
}

fn samples(frame: &Frame<'_>, rate: u32, kind: PatternKind) -> SampleImage {
    let pattern = SamplePattern::new(rate, kind).expect("valid rate");
    RayTrace { pattern }.sample_image(frame, &mut Recorder::default()).expect("raytrace applies")
}

/// Sub-sample comparison over the pixels whose sub-samples all see the receiver plane.
#[derive(Debug, Default)]
struct Comparison {
    pixels: usize,
    samples: usize,
    /// Sub-samples whose shadow differs.
    mismatches: usize,
    /// Sub-samples left out of the pixel's ratio (there should be none on the plane).
    invalid: usize,
    /// Sub-samples in shadow and lit, for the test to be meaningful.
    shadowed: usize,
}

fn compare_on_plane(frame: &Frame<'_>, masks: &SubsampleMasks, truth: &SampleImage) -> Comparison {
    let (plane, _, _) = frame.scene.receiver_plane().expect("a planar receiver");
    let rate = truth.rate as usize;
    let mut c = Comparison::default();
    for k in 0..masks.occlusion.len() {
        let hits = &truth.triangle[k * rate..(k + 1) * rate];
        let on_plane = hits.iter().all(|&t| {
            t != methods::raster::NO_TRIANGLE && frame.geometry.object[t as usize] as usize == plane
        });
        if !on_plane {
            continue;
        }
        c.pixels += 1;
        for s in 0..rate {
            c.samples += 1;
            let occluded = masks.occlusion[k] >> s & 1 == 1;
            let shadowed = truth.light[k * rate + s] == 0.0;
            c.mismatches += usize::from(occluded != shadowed);
            c.invalid += usize::from(masks.valid[k] >> s & 1 == 0);
            c.shadowed += usize::from(shadowed);
        }
    }
    c
}

#[test]
fn exact_mode_equals_raytrace_sub_sample_for_sub_sample_on_planar_receivers() {
    for name in ["plane-square", "cage", "random-10k", "plant", "bunny-plane", "spheres"] {
        let Some(scene) = load(name) else { continue };
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        for (rate, kind) in
            [(32, PatternKind::Grid), (32, PatternKind::Rotated), (128, PatternKind::Grid)]
        {
            let (_, masks, rec) = run_masks(&pan09(rate, kind, VisibilityMode::Exact), &frame);
            let truth = samples(&frame, rate, kind);
            let c = compare_on_plane(&frame, &masks, &truth);
            eprintln!(
                "{name} {rate} {kind}: {c:?}, {} silhouette pixels",
                rec.counters.silhouette_pixels
            );
            assert!(c.pixels > 5000 && c.shadowed > 1000, "{name}: {c:?}");
            assert_eq!(c.invalid, 0, "{name} {rate} {kind}");
            assert!(c.mismatches as f64 <= 1e-5 * c.samples as f64, "{name} {rate} {kind}: {c:?}");
        }
    }
}
