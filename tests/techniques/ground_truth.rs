//! The two references agree: ray-traced supersampling converges to the exact coverage.

use crate::common;

use analysis::{
    exact::ExactCoverage, pixel_class::PixelClass, registry::reference, Metrics, Reference,
};
use instrumentation::Recorder;
use methods::{pattern::PatternKind, Frame, Visibility};

fn as_visibility(r: &analysis::ReferenceImage) -> Visibility {
    Visibility {
        width: r.width,
        height: r.height,
        lit: r.lit.iter().map(|&v| v as f32).collect(),
        transmittance: None,
    }
}

/// Mean absolute difference of raytrace at `rate` to exact, over the pixels exact evaluates.
///
/// The rotated (N-rooks) pattern: a regular 32 x 32 grid resolves edges close to an axis only
/// to 1/32 of a pixel, and the cage's bars give many such edges (grid at 1024 on `cage` at
/// 48 x 36: mean 1.5e-3; rotated: 4.6e-4).
fn raytrace_error(frame: &Frame<'_>, exact: &analysis::ReferenceImage, rate: u32) -> Metrics {
    let rt = reference("raytrace", rate, PatternKind::Rotated).expect("valid rate");
    let img = rt.evaluate(frame, &mut Recorder::default()).expect("applies");
    // Compare only where both references vouch for the pixel.
    let both: Vec<bool> =
        exact.shadow_only().iter().zip(&img.evaluated).map(|(a, b)| *a && *b).collect();
    Metrics::compare(&as_visibility(&img), &exact.lit, &both)
}

#[test]
fn exact_raytrace_at_1024_agrees_with_exact_and_converges() {
    for name in ["plane-square", "cage", "random-10k"] {
        let scene = scenes::load(name).expect("built-in");
        let frame = Frame::new(&scene, 48, 36, &mut Recorder::default());
        let exact = reference("exact", 1, PatternKind::Grid)
            .expect("exists")
            .evaluate(&frame, &mut Recorder::default())
            .expect("planar receiver");
        let m = raytrace_error(&frame, &exact, 1024);
        eprintln!(
            "{name}: raytrace@1024 vs exact: mean {:.2e}, max {:.2e}, {} px",
            m.mean_abs_error, m.max_abs_error, m.evaluated_pixels
        );
        assert!(m.evaluated_pixels > 200, "{name}: {} pixels", m.evaluated_pixels);
        assert!(m.mean_abs_error < 1e-3, "{name}: {}", m.mean_abs_error);
        let errors: Vec<f64> = [4, 16, 64, 256]
            .iter()
            .map(|&r| raytrace_error(&frame, &exact, r).mean_abs_error)
            .collect();
        eprintln!("{name}: mean error at 4, 16, 64, 256: {errors:?}");
        assert!(errors.windows(2).all(|w| w[1] < w[0]), "{name}: {errors:?}");
    }
}

/// `exact` on `planar` and `surface` pixels against `raytrace` at 1024 sub-samples (rotated
/// pattern) on the curved-receiver scenes: mean difference at most 1e-3, and every pixel
/// within [`sampling_bound`].
#[test]
fn exact_on_every_surface_agrees_with_raytrace_at_1024() {
    for name in ["bumpy", "spheres", "bunny-plane"] {
        let Some(scene) = common::load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        let exact = ExactCoverage::default()
            .evaluate(&frame, &mut Recorder::default())
            .expect("exact applies");
        let classes = exact.classes.as_deref().expect("exact classifies");
        let surface = classes.iter().filter(|&&c| c == PixelClass::Surface).count();
        assert!(surface > 1000, "{name}: {surface} surface pixels");
        let rt = reference("raytrace", 1024, PatternKind::Rotated).expect("valid rate");
        let img = rt.evaluate(&frame, &mut Recorder::default()).expect("applies");
        let mut worst = (0.0f64, 0usize);
        let (mut n, mut sum) = (0usize, 0.0);
        for (k, &e) in exact.shadow_only().iter().enumerate() {
            if e && img.evaluated[k] {
                let d = (exact.lit[k] - img.lit[k]).abs();
                n += 1;
                sum += d;
                if d > worst.0 {
                    worst = (d, k);
                }
            }
        }
        let mean = sum / n as f64;
        eprintln!("{name}: exact vs raytrace@1024 on {n} shadow-only pixels: mean {mean:.2e}, max {:.2e} at pixel {}", worst.0, worst.1);
        assert!(n > 5000, "{name}: {n} pixels");
        assert!(mean <= 1e-3, "{name}: mean {mean}");
        assert!(
            worst.0 <= sampling_bound(1024),
            "{name}: pixel {} differs by {}",
            worst.1,
            worst.0
        );
    }
}

/// The largest difference `raytrace` at `rate` sub-samples may have from a pixel's exact lit
/// fraction: a straight shadow edge crossing the pixel misplaces at most one column of the
/// `sqrt(rate) x sqrt(rate)` pattern, `1 / sqrt(rate)` of its area; two edges are allowed (a
/// shadow's corner).
fn sampling_bound(rate: u32) -> f64 {
    2.0 / f64::from(rate).sqrt()
}
