//! Per-pixel error metrics over the evaluated pixels.
//!
//! A pixel is evaluated when the caller's mask says so (for the exact reference: the pixels
//! whose whole square sees the receiver plane). `pixel_match` is the fraction of evaluated
//! pixels within half an 8-bit step of the reference; boundary pixels are those whose
//! reference is strictly between 0 and 1.

use image::RgbImage;
use methods::Visibility;
use serde::{Deserialize, Serialize};

/// Largest difference still counted as a match: half of one 8-bit step.
pub const MATCH_TOLERANCE: f64 = 0.5 / 255.0;

/// Error of a result against a reference, as written to `metrics.json`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Pixels compared.
    pub evaluated_pixels: u64,
    /// Mean of `|value - reference|`.
    pub mean_abs_error: f64,
    /// Root mean square error.
    pub rmse: f64,
    /// Largest `|value - reference|`.
    pub max_abs_error: f64,
    /// Fraction of evaluated pixels with `|value - reference| <= 0.5/255`.
    pub pixel_match: f64,
    /// Evaluated pixels whose reference is strictly between 0 and 1.
    pub boundary_pixels: u64,
    /// Mean absolute error over the boundary pixels (0 when there are none).
    pub boundary_mean_abs_error: f64,
}

impl Metrics {
    /// Compares `result` with `reference` on the pixels where `evaluated` is true.
    ///
    /// # Panics
    /// When the three buffers differ in size (a caller's bug, not bad input).
    pub fn compare(result: &Visibility, reference: &[f64], evaluated: &[bool]) -> Self {
        assert_eq!(result.lit.len(), reference.len(), "result and reference differ in size");
        assert_eq!(result.lit.len(), evaluated.len(), "result and mask differ in size");
        let (mut n, mut sum, mut sq, mut max, mut matched) = (0u64, 0.0, 0.0, 0.0f64, 0u64);
        let (mut nb, mut sum_b) = (0u64, 0.0);
        for ((&v, &r), _) in result.lit.iter().zip(reference).zip(evaluated).filter(|(_, &e)| e) {
            let e = (f64::from(v) - r).abs();
            n += 1;
            sum += e;
            sq += e * e;
            max = max.max(e);
            matched += u64::from(e <= MATCH_TOLERANCE);
            if r > 0.0 && r < 1.0 {
                nb += 1;
                sum_b += e;
            }
        }
        let mean = |s: f64, n: u64| if n == 0 { 0.0 } else { s / n as f64 };
        Self {
            evaluated_pixels: n,
            mean_abs_error: mean(sum, n),
            rmse: mean(sq, n).sqrt(),
            max_abs_error: max,
            pixel_match: if n == 0 { 1.0 } else { matched as f64 / n as f64 },
            boundary_pixels: nb,
            boundary_mean_abs_error: mean(sum_b, nb),
        }
    }
}

/// The error image of Pan et al. Fig. 8: `10 x |value - reference|` in grey, clamped to white;
/// pixels not evaluated are dark blue.
pub fn error_image(result: &Visibility, reference: &[f64], evaluated: &[bool]) -> RgbImage {
    RgbImage::from_fn(result.width, result.height, |x, y| {
        let k = (y * result.width + x) as usize;
        if !evaluated[k] {
            return image::Rgb([0, 0, 64]);
        }
        let e = (10.0 * (f64::from(result.lit[k]) - reference[k]).abs()).min(1.0);
        let g = (e * 255.0).round() as u8;
        image::Rgb([g, g, g])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vis(lit: Vec<f32>) -> Visibility {
        Visibility { width: lit.len() as u32, height: 1, lit, transmittance: None }
    }

    #[test]
    fn metrics_on_a_known_case() {
        let v = vis(vec![1.0, 0.0, 0.5, 0.25, 0.9]);
        let r = [1.0, 0.5, 0.5, 0.0, 0.0];
        let m = Metrics::compare(&v, &r, &[true, true, true, true, false]);
        assert_eq!(m.evaluated_pixels, 4);
        assert!((m.mean_abs_error - 0.75 / 4.0).abs() < 1e-12);
        assert!((m.rmse - ((0.25 + 0.0625) / 4.0f64).sqrt()).abs() < 1e-12);
        assert_eq!(m.max_abs_error, 0.5);
        assert_eq!(m.pixel_match, 0.5);
        assert_eq!(m.boundary_pixels, 2);
        assert!((m.boundary_mean_abs_error - 0.25).abs() < 1e-12);
    }

    #[test]
    fn half_a_step_still_matches() {
        let v = vis(vec![0.5 + (0.49 / 255.0) as f32, 0.5 + (0.6 / 255.0) as f32]);
        let m = Metrics::compare(&v, &[0.5, 0.5], &[true, true]);
        assert_eq!(m.pixel_match, 0.5);
    }

    #[test]
    fn error_image_scales_by_ten_and_marks_unevaluated() {
        let v = vis(vec![0.0, 0.0, 0.0]);
        let img = error_image(&v, &[0.05, 0.5, 0.0], &[true, true, false]);
        assert_eq!(img.get_pixel(0, 0).0, [128, 128, 128]);
        assert_eq!(img.get_pixel(1, 0).0, [255, 255, 255]);
        assert_eq!(img.get_pixel(2, 0).0, [0, 0, 64]);
    }

    proptest::proptest! {
        #[test]
        fn metrics_are_bounded(values in proptest::collection::vec((0.0f32..=1.0, 0.0f64..=1.0, proptest::bool::ANY), 1..64)) {
            let v = vis(values.iter().map(|t| t.0).collect());
            let r: Vec<f64> = values.iter().map(|t| t.1).collect();
            let e: Vec<bool> = values.iter().map(|t| t.2).collect();
            let m = Metrics::compare(&v, &r, &e);
            proptest::prop_assert!(m.mean_abs_error <= m.rmse + 1e-12);
            proptest::prop_assert!(m.rmse <= m.max_abs_error + 1e-12);
            proptest::prop_assert!((0.0..=1.0).contains(&m.pixel_match));
            proptest::prop_assert!(m.boundary_pixels <= m.evaluated_pixels);
        }
    }
}
