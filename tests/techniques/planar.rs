//! Sub-sample comparisons with the ray tracer on planar receivers, shared by the methods that
//! place sub-samples on a pixel's tangent plane (`pan09`, `ftizb`): there the plane is the
//! surface, so each sub-sample must equal the ray tracer's at the same rate and pattern.

use analysis::raytrace::{RayTrace, SampleImage};
use instrumentation::Recorder;
use methods::{
    pattern::{PatternKind, SamplePattern},
    Frame,
};

/// The ray tracer's sub-samples of `frame` at `rate` sub-samples of pattern `kind`.
pub fn samples(frame: &Frame<'_>, rate: u32, kind: PatternKind) -> SampleImage {
    let pattern = SamplePattern::new(rate, kind).expect("valid rate");
    RayTrace { pattern }.sample_image(frame, &mut Recorder::default()).expect("raytrace applies")
}

/// Sub-sample comparison over the pixels whose sub-samples all see the receiver plane.
#[derive(Debug, Default)]
pub struct Comparison {
    pub pixels: usize,
    pub samples: usize,
    /// Sub-samples whose shadow differs.
    pub mismatches: usize,
    /// Sub-samples left out of the pixel's ratio (there should be none on the plane).
    pub invalid: usize,
    /// Sub-samples in shadow, for the test to be meaningful.
    pub shadowed: usize,
}

/// Each pixel's occlusion and valid masks (bit `s`: sub-sample `s`) against `truth`, over the
/// pixels whose sub-samples all hit the scene's receiver plane.
pub fn compare_on_plane(
    frame: &Frame<'_>,
    occlusion: &[u128],
    valid: &[u128],
    truth: &SampleImage,
) -> Comparison {
    let (plane, _, _) = frame.scene.receiver_plane().expect("a planar receiver");
    let rate = truth.rate as usize;
    let mut c = Comparison::default();
    for k in 0..occlusion.len() {
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
            let occluded = occlusion[k] >> s & 1 == 1;
            let shadowed = truth.light[k * rate + s] == 0.0;
            c.mismatches += usize::from(occluded != shadowed);
            c.invalid += usize::from(valid[k] >> s & 1 == 0);
            c.shadowed += usize::from(shadowed);
        }
    }
    c
}
