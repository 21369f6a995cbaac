//! Per-pixel error metrics over chosen pixels, as a whole ([`Metrics`]) and per pixel class
//! ([`ClassMetrics`], [`per_class`]).
//!
//! A pixel is compared when the caller's mask says so: the reference must vouch for it
//! (`ReferenceImage::evaluated`), and `metrics.json`'s headline takes only the shadow-only
//! pixels (`planar` and `surface`, [`crate::ReferenceImage::shadow_only`]), where the error is
//! the shadow's and not the camera's. `pixel_match` is the fraction of compared pixels within
//! half an 8-bit step of the reference; boundary pixels are those whose reference is strictly
//! between 0 and 1.
//!
//! `pixel_match_lecocq` is pixel match in the sense of Lecocq, Marvie, Sourimant and Gautron,
//! "Sub-pixel Shadow Mapping" (I3D 2014, section 6.2, Figure 12), who compare a binary shadow
//! against ray-traced shadows, one ray per pixel: the fraction of compared pixels whose value
//! equals that of `raytrace` at rate 1 (a pixel-centre sample, 0 or 1), see
//! [`lecocq_pixel_match`]. It applies only where both are binary: a result with any compared
//! value other than exactly 0 or 1 (an antialiased method, a supersampled rate) has none, and
//! neither does a frame where the ray-traced value is fractional (semi-transparent casters).
//! For antialiased results the boundary error's percentiles say more.
//!
//! Percentiles (`p95_abs_error`, and `boundary_p50/p95/p99_abs_error` over the boundary
//! pixels) follow the nearest-rank definition: with the `n` errors sorted ascending, the
//! `p`-th percentile is the one of rank `ceil(p n / 100)` (1-based), so it is always one of
//! the measured errors (the largest when `n < 100 / (100 - p)`). A statistic of no pixels is
//! `None` (`null` in JSON, `n/a` when printed), never 0.

use crate::pixel_class::{self, PixelClass};
use crate::reference::ReferenceImage;
use image::RgbImage;
use methods::Visibility;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

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
    /// Mean absolute error over the boundary pixels (0 when there are none: read it through
    /// [`Metrics::boundary_mean`], which says `None` then).
    pub boundary_mean_abs_error: f64,
    /// Median absolute error over the boundary pixels (nearest rank).
    pub boundary_p50_abs_error: Option<f64>,
    /// 95th percentile of the absolute error over the boundary pixels (nearest rank).
    pub boundary_p95_abs_error: Option<f64>,
    /// 99th percentile of the absolute error over the boundary pixels (nearest rank).
    pub boundary_p99_abs_error: Option<f64>,
}

/// The `p`-th percentile (0 < `p` <= 100) of `values` by nearest rank (see the module doc);
/// `None` when there are no values. Reorders `values`.
pub fn nearest_rank(values: &mut [f64], p: usize) -> Option<f64> {
    let index = nearest_rank_index(values.len(), p)?;
    Some(*values.select_nth_unstable_by(index, f64::total_cmp).1)
}

/// The 0-based position, among `n` values sorted ascending, of their `p`-th percentile
/// (0 < `p` <= 100) by nearest rank: rank `ceil(p n / 100)`, computed in integers; `None` when
/// `n` is 0. [`nearest_rank`] and the temporal metrics' `f32` values share it.
pub fn nearest_rank_index(n: usize, p: usize) -> Option<usize> {
    (n > 0).then(|| p.saturating_mul(n).div_ceil(100).clamp(1, n) - 1)
}

/// The 50th, 95th and 99th percentiles of `values` (nearest rank). Reorders `values`.
fn boundary_percentiles(values: &mut [f64]) -> [Option<f64>; 3] {
    [50, 95, 99].map(|p| nearest_rank(values, p))
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
        let mut boundary: Vec<f64> = Vec::new();
        for ((&v, &r), _) in result.lit.iter().zip(reference).zip(evaluated).filter(|(_, &e)| e) {
            let e = (f64::from(v) - r).abs();
            n += 1;
            sum += e;
            sq += e * e;
            max = max.max(e);
            matched += u64::from(e <= MATCH_TOLERANCE);
            if r > 0.0 && r < 1.0 {
                boundary.push(e);
            }
        }
        let mean = |s: f64, n: u64| if n == 0 { 0.0 } else { s / n as f64 };
        let nb = boundary.len() as u64;
        let sum_b = boundary.iter().sum::<f64>();
        let [p50, p95, p99] = boundary_percentiles(&mut boundary);
        Self {
            evaluated_pixels: n,
            mean_abs_error: mean(sum, n),
            rmse: mean(sq, n).sqrt(),
            max_abs_error: max,
            pixel_match: if n == 0 { 1.0 } else { matched as f64 / n as f64 },
            boundary_pixels: nb,
            boundary_mean_abs_error: mean(sum_b, nb),
            boundary_p50_abs_error: p50,
            boundary_p95_abs_error: p95,
            boundary_p99_abs_error: p99,
        }
    }

    /// The mean absolute error over the boundary pixels, `None` when there are none (for
    /// printing `n/a` rather than the field's 0).
    pub fn boundary_mean(&self) -> Option<f64> {
        (self.boundary_pixels > 0).then_some(self.boundary_mean_abs_error)
    }
}

/// Whether every value of `result` where `mask` is true is exactly 0 or 1 (a binary shadow).
///
/// # Panics
/// When the buffers differ in size (a caller's bug, not bad input).
pub fn is_binary(result: &Visibility, mask: &[bool]) -> bool {
    assert_eq!(result.lit.len(), mask.len(), "result and mask differ in size");
    result.lit.iter().zip(mask).all(|(&v, &m)| !m || v == 0.0 || v == 1.0)
}

/// The error thresholds of [`exceedance`]: 1, 2 and 5 times each power of ten from 1e-4 to
/// 0.5, with half an 8-bit step (0.5 / 255, where [`Metrics::pixel_match`] draws its line)
/// between 1e-3 and 2e-3.
pub const EXCEEDANCE_THRESHOLDS: [f64; 14] =
    [1e-4, 2e-4, 5e-4, 1e-3, MATCH_TOLERANCE, 2e-3, 5e-3, 1e-2, 2e-2, 5e-2, 0.1, 0.2, 0.5, 0.9];

/// The error's distribution as the share of compared pixels (`mask` true) whose
/// `|value - reference|` exceeds each of [`EXCEEDANCE_THRESHOLDS`] (the complementary
/// cumulative distribution at those points; at `0.5 / 255` it is one minus the pixel match).
/// `None` when no pixel is compared.
///
/// # Panics
/// When the buffers differ in size (a caller's bug, not bad input).
pub fn exceedance(result: &Visibility, reference: &[f64], mask: &[bool]) -> Option<Vec<f64>> {
    assert_eq!(result.lit.len(), reference.len(), "result and reference differ in size");
    assert_eq!(result.lit.len(), mask.len(), "result and mask differ in size");
    let mut over = [0u64; EXCEEDANCE_THRESHOLDS.len()];
    let mut n = 0u64;
    for ((&v, &r), _) in result.lit.iter().zip(reference).zip(mask).filter(|(_, &m)| m) {
        n += 1;
        let e = (f64::from(v) - r).abs();
        for (c, &t) in over.iter_mut().zip(&EXCEEDANCE_THRESHOLDS) {
            *c += u64::from(e > t);
        }
    }
    (n > 0).then(|| over.iter().map(|&c| c as f64 / n as f64).collect())
}

/// Pixel match as Lecocq et al. define it (see the module doc): the fraction of the pixels
/// where `mask` is true and `raytrace1` (`raytrace` at one sample per pixel on the same frame)
/// evaluated whose value in `result` equals the ray-traced one. `None` when no pixel is
/// compared, when a compared value of `result` is not exactly 0 or 1, or when a compared
/// ray-traced value is not (semi-transparent casters).
///
/// # Panics
/// When the buffers differ in size (a caller's bug, not bad input).
pub fn lecocq_pixel_match(
    result: &Visibility,
    raytrace1: &ReferenceImage,
    mask: &[bool],
) -> Option<f64> {
    assert_eq!(result.lit.len(), raytrace1.lit.len(), "result and reference differ in size");
    assert_eq!(result.lit.len(), mask.len(), "result and mask differ in size");
    let binary = |v: f64| v == 0.0 || v == 1.0;
    let (mut n, mut matched) = (0u64, 0u64);
    for ((&v, &r), _) in result
        .lit
        .iter()
        .zip(&raytrace1.lit)
        .zip(mask.iter().zip(&raytrace1.evaluated))
        .filter(|(_, (&m, &e))| m && e)
    {
        let v = f64::from(v);
        if !binary(v) || !binary(r) {
            return None;
        }
        n += 1;
        matched += u64::from(v == r);
    }
    (n > 0).then(|| matched as f64 / n as f64)
}

/// Error of a result against a reference over one set of pixels (a pixel class), as written
/// under `classes` in `metrics.json`. A statistic of no pixels is `None` (`null`), not 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ClassMetrics {
    /// Pixels compared.
    pub pixels: u64,
    /// Mean of `|value - reference|`.
    pub mean_abs_error: Option<f64>,
    /// Root mean square error.
    pub rmse: Option<f64>,
    /// Largest `|value - reference|`.
    pub max_abs_error: Option<f64>,
    /// 95th percentile of `|value - reference|` (nearest rank, see the module doc).
    pub p95_abs_error: Option<f64>,
    /// Compared pixels whose reference is strictly between 0 and 1.
    pub boundary_pixels: u64,
    /// Mean absolute error over the boundary pixels.
    pub boundary_mean_abs_error: Option<f64>,
    /// Median absolute error over the boundary pixels (nearest rank).
    pub boundary_p50_abs_error: Option<f64>,
    /// 95th percentile of the absolute error over the boundary pixels (nearest rank).
    pub boundary_p95_abs_error: Option<f64>,
    /// 99th percentile of the absolute error over the boundary pixels (nearest rank).
    pub boundary_p99_abs_error: Option<f64>,
}

impl ClassMetrics {
    /// Compares `result` with `reference` on the pixels where `mask` is true.
    ///
    /// # Panics
    /// When the three buffers differ in size (a caller's bug, not bad input).
    pub fn compare(result: &Visibility, reference: &[f64], mask: &[bool]) -> Self {
        assert_eq!(result.lit.len(), reference.len(), "result and reference differ in size");
        assert_eq!(result.lit.len(), mask.len(), "result and mask differ in size");
        let mut errors: Vec<f64> = Vec::new();
        let mut boundary: Vec<f64> = Vec::new();
        for ((&v, &r), _) in result.lit.iter().zip(reference).zip(mask).filter(|(_, &m)| m) {
            let e = (f64::from(v) - r).abs();
            errors.push(e);
            if r > 0.0 && r < 1.0 {
                boundary.push(e);
            }
        }
        let n = errors.len();
        let some = |v: f64| (n > 0).then_some(v);
        let mean = errors.iter().sum::<f64>() / n as f64;
        let rmse = (errors.iter().map(|e| e * e).sum::<f64>() / n as f64).sqrt();
        let max = errors.iter().copied().fold(0.0, f64::max);
        let p95 = nearest_rank(&mut errors, 95);
        let nb = boundary.len();
        let boundary_mean = (nb > 0).then(|| boundary.iter().sum::<f64>() / nb as f64);
        let [p50_b, p95_b, p99_b] = boundary_percentiles(&mut boundary);
        Self {
            pixels: n as u64,
            mean_abs_error: some(mean),
            rmse: some(rmse),
            max_abs_error: some(max),
            p95_abs_error: p95,
            boundary_pixels: nb as u64,
            boundary_mean_abs_error: boundary_mean,
            boundary_p50_abs_error: p50_b,
            boundary_p95_abs_error: p95_b,
            boundary_p99_abs_error: p99_b,
        }
    }
}

/// [`ClassMetrics`] of the three classes whose pixels can be compared (`uncovered` pixels
/// see nothing), as written under `classes` in `metrics.json`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PerClass {
    /// Pixels whose square sees one planar object.
    pub planar: ClassMetrics,
    /// Pixels tiled by one continuous surface.
    pub surface: ClassMetrics,
    /// Silhouettes, depth discontinuities, several objects (against the reference's values
    /// where it evaluated them, e.g. `exact`'s ray-traced edge pixels).
    pub edge: ClassMetrics,
}

/// Compares `result` with `truth` class by class: a pixel counts in its class (`classes[k]`)
/// when `truth` evaluated it.
///
/// # Panics
/// When the buffers differ in size (a caller's bug, not bad input).
pub fn per_class(result: &Visibility, truth: &ReferenceImage, classes: &[PixelClass]) -> PerClass {
    assert_eq!(classes.len(), truth.evaluated.len(), "classes and reference differ in size");
    let of = |class: PixelClass| {
        let mask: Vec<bool> =
            truth.evaluated.iter().zip(classes).map(|(&e, &c)| e && c == class).collect();
        ClassMetrics::compare(result, &truth.lit, &mask)
    };
    PerClass {
        planar: of(PixelClass::Planar),
        surface: of(PixelClass::Surface),
        edge: of(PixelClass::Edge),
    }
}

/// Pixels of each class by name (every class, zeros included), as `metrics.json`'s
/// `class_pixels` and `run.json`'s `pixel_classes` give them.
pub fn class_pixels(classes: &[PixelClass]) -> BTreeMap<String, u64> {
    PixelClass::ALL
        .iter()
        .zip(pixel_class::counts(classes))
        .map(|(c, n)| (c.name().to_owned(), n))
        .collect()
}

/// The pixels of the headline: those `truth` evaluated whose class is `planar` or `surface`
/// (the same as [`ReferenceImage::shadow_only`] when `truth` carries these classes).
///
/// # Panics
/// When the buffers differ in size (a caller's bug, not bad input).
pub fn headline_pixels(truth: &ReferenceImage, classes: &[PixelClass]) -> Vec<bool> {
    assert_eq!(classes.len(), truth.evaluated.len(), "classes and reference differ in size");
    truth.evaluated.iter().zip(classes).map(|(&e, c)| e && c.is_shadow_only()).collect()
}

/// What `metrics.json` reports of a comparison: the shadow-only headline (the
/// [`headline_pixels`]) at the top, then each class and the frame's class counts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// Headline pixels compared.
    pub evaluated_pixels: u64,
    /// Mean of `|value - reference|` over the headline pixels.
    pub mean_abs_error: Option<f64>,
    /// Root mean square error over the headline pixels.
    pub rmse: Option<f64>,
    /// Largest `|value - reference|` over the headline pixels.
    pub max_abs_error: Option<f64>,
    /// Headline pixels whose reference is strictly between 0 and 1.
    pub boundary_pixels: u64,
    /// Mean absolute error over those boundary pixels.
    pub boundary_mean_abs_error: Option<f64>,
    /// Median absolute error over those boundary pixels (nearest rank).
    pub boundary_p50_abs_error: Option<f64>,
    /// 95th percentile of the absolute error over those boundary pixels (nearest rank).
    pub boundary_p95_abs_error: Option<f64>,
    /// 99th percentile of the absolute error over those boundary pixels (nearest rank).
    pub boundary_p99_abs_error: Option<f64>,
    /// NVIDIA FLIP mean ([`crate::flip::flip_mean`]) where only the headline pixels may differ.
    pub flip_mean: f64,
    /// Fraction of headline pixels within half an 8-bit step ([`Metrics::pixel_match`]).
    pub pixel_match: Option<f64>,
    /// Pixel match in Lecocq et al.'s sense over the headline pixels
    /// ([`lecocq_pixel_match`]): binary against `raytrace` at rate 1; `None` (`null`) where it
    /// does not apply.
    pub pixel_match_lecocq: Option<f64>,
    /// Each class.
    pub classes: PerClass,
    /// Pixels of each class in the frame ([`class_pixels`]), evaluated or not.
    pub class_pixels: BTreeMap<String, u64>,
}

impl Comparison {
    /// Compares `result` with `truth`; `classes` are the frame's pixel classes (the
    /// reference's own when it computes them). `raytrace1` is `raytrace` at one sample per
    /// pixel on the same frame, for [`Comparison::pixel_match_lecocq`]; `None` leaves that
    /// null (a caller that knows the result is not binary, [`is_binary`], need not trace it).
    ///
    /// # Panics
    /// When the buffers differ in size (a caller's bug, not bad input).
    pub fn new(
        result: &Visibility,
        truth: &ReferenceImage,
        classes: &[PixelClass],
        raytrace1: Option<&ReferenceImage>,
    ) -> Self {
        let headline = headline_pixels(truth, classes);
        let h = ClassMetrics::compare(result, &truth.lit, &headline);
        let matched = Metrics::compare(result, &truth.lit, &headline).pixel_match;
        Self {
            evaluated_pixels: h.pixels,
            mean_abs_error: h.mean_abs_error,
            rmse: h.rmse,
            max_abs_error: h.max_abs_error,
            boundary_pixels: h.boundary_pixels,
            boundary_mean_abs_error: h.boundary_mean_abs_error,
            boundary_p50_abs_error: h.boundary_p50_abs_error,
            boundary_p95_abs_error: h.boundary_p95_abs_error,
            boundary_p99_abs_error: h.boundary_p99_abs_error,
            flip_mean: crate::flip::flip_mean(result, &truth.lit, &headline),
            pixel_match: (h.pixels > 0).then_some(matched),
            pixel_match_lecocq: raytrace1.and_then(|r| lecocq_pixel_match(result, r, &headline)),
            classes: per_class(result, truth, classes),
            class_pixels: class_pixels(classes),
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

    #[test]
    fn exceedance_counts_the_compared_pixels_over_each_threshold() {
        // Errors 0, 0.001 (not over 1e-3), 0.3 and 1.0 on compared pixels; a fifth pixel with
        // error 1 is not compared.
        let v = vis(vec![0.5, 0.501, 0.2, 1.0, 1.0]);
        let r = [0.5, 0.5, 0.5, 0.0, 0.0];
        let e = exceedance(&v, &r, &[true, true, true, true, false]).expect("compared");
        let at = |t: f64| e[EXCEEDANCE_THRESHOLDS.iter().position(|&x| x == t).expect("t")];
        assert_eq!(at(1e-4), 0.75, "0.001 (as f32) exceeds 1e-4");
        assert_eq!(at(0.5 / 255.0), 0.5);
        assert_eq!(at(0.2), 0.5);
        assert_eq!(at(0.5), 0.25);
        assert_eq!(at(0.9), 0.25);
        assert!(EXCEEDANCE_THRESHOLDS.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(exceedance(&v, &r, &[false; 5]), None);
    }

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
        assert_eq!(m.boundary_mean(), Some(m.boundary_mean_abs_error));
        // Boundary errors 0 and 0.5: ranks ceil(1.0) = 1, ceil(1.9) = 2, ceil(1.98) = 2.
        assert_eq!(
            (m.boundary_p50_abs_error, m.boundary_p95_abs_error, m.boundary_p99_abs_error),
            (Some(0.0), Some(0.5), Some(0.5))
        );

        // No boundary pixel: the mean reads as n/a and the percentiles are null, not 0.
        let flat = Metrics::compare(&vis(vec![1.0, 0.0]), &[1.0, 1.0], &[true, true]);
        assert_eq!((flat.boundary_pixels, flat.boundary_mean()), (0, None));
        assert_eq!(flat.boundary_p50_abs_error, None);
        let json = serde_json::to_value(flat).expect("serializes");
        for f in ["boundary_p50_abs_error", "boundary_p95_abs_error", "boundary_p99_abs_error"] {
            assert!(json[f].is_null(), "{f}");
        }
    }

    #[test]
    fn nearest_rank_percentiles_are_measured_values() {
        // 1, 2, ..., 100 in a scrambled order: the p-th percentile is p.
        let mut values: Vec<f64> = (0..100).map(|k| f64::from((k * 37) % 100 + 1)).collect();
        assert_eq!(boundary_percentiles(&mut values), [Some(50.0), Some(95.0), Some(99.0)]);
        assert_eq!(nearest_rank(&mut values, 100), Some(100.0));
        // Ten values: ranks 5, 10, 10.
        let mut ten: Vec<f64> = (1..=10).rev().map(f64::from).collect();
        assert_eq!(boundary_percentiles(&mut ten), [Some(5.0), Some(10.0), Some(10.0)]);
        assert_eq!(boundary_percentiles(&mut [0.25]), [Some(0.25); 3]);
        assert_eq!(boundary_percentiles(&mut []), [None; 3]);
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

    #[test]
    fn class_metrics_on_a_known_case() {
        // Errors 0.00, 0.05, ..., 0.95 (twenty pixels) against a reference of 0.5 (all on the
        // boundary), and one masked-out pixel with a large error.
        let mut lit: Vec<f32> = (0..20).map(|k| 0.5 + 0.05 * k as f32).collect();
        lit.push(0.0);
        let mut r = vec![0.5; 20];
        r.push(1.0);
        let mut mask = vec![true; 20];
        mask.push(false);
        let errors: Vec<f64> = (0..20).map(|k| f64::from(lit[k]) - 0.5).collect();
        let m = ClassMetrics::compare(&vis(lit), &r, &mask);
        assert_eq!(m.pixels, 20);
        let mean = errors.iter().sum::<f64>() / 20.0;
        let rmse = (errors.iter().map(|e| e * e).sum::<f64>() / 20.0).sqrt();
        assert!((m.mean_abs_error.expect("mean") - mean).abs() < 1e-12);
        assert!((m.rmse.expect("rmse") - rmse).abs() < 1e-12);
        assert_eq!(m.max_abs_error, Some(errors[19]));
        // Nearest rank: ceil(0.95 * 20) = 19th smallest.
        assert_eq!(m.p95_abs_error, Some(errors[18]));
        assert_eq!(m.boundary_pixels, 20);
        assert!((m.boundary_mean_abs_error.expect("boundary") - mean).abs() < 1e-12);
        // Ranks ceil(10) = 10, ceil(19) = 19, ceil(19.8) = 20 of the twenty boundary errors.
        assert_eq!(
            (m.boundary_p50_abs_error, m.boundary_p95_abs_error, m.boundary_p99_abs_error),
            (Some(errors[9]), Some(errors[18]), Some(errors[19]))
        );

        // One pixel: every statistic is its error; no boundary pixel: null, not 0.
        let one = ClassMetrics::compare(&vis(vec![0.25, 0.0]), &[0.0, 0.0], &[true, false]);
        assert_eq!(one.pixels, 1);
        assert_eq!(
            (one.mean_abs_error, one.rmse, one.max_abs_error, one.p95_abs_error),
            (Some(0.25), Some(0.25), Some(0.25), Some(0.25))
        );
        assert_eq!((one.boundary_pixels, one.boundary_mean_abs_error), (0, None));
        assert_eq!(one.boundary_p99_abs_error, None);
        let json = serde_json::to_value(one).expect("serializes");
        assert!(json["boundary_mean_abs_error"].is_null());
        assert!(json["boundary_p50_abs_error"].is_null());

        // No pixel: every statistic null.
        let none = ClassMetrics::compare(&vis(vec![0.25]), &[0.0], &[false]);
        assert_eq!(none.pixels, 0);
        assert!(none.mean_abs_error.is_none() && none.rmse.is_none());
        assert!(none.max_abs_error.is_none() && none.p95_abs_error.is_none());
    }

    #[test]
    fn per_class_counts_each_class_where_the_reference_evaluated_it() {
        use PixelClass::{Edge, Planar, Surface, Uncovered};
        let classes = [Planar, Planar, Surface, Edge, Edge, Uncovered];
        let truth = ReferenceImage {
            width: 6,
            height: 1,
            lit: vec![1.0, 0.5, 0.0, 0.0, 1.0, 1.0],
            evaluated: vec![true, true, true, true, false, false],
            transmittance: None,
            classes: Some(classes.to_vec()),
        };
        let v = vis(vec![1.0, 0.25, 0.125, 0.5, 0.0, 0.0]);
        let m = per_class(&v, &truth, &classes);
        assert_eq!((m.planar.pixels, m.surface.pixels, m.edge.pixels), (2, 1, 1));
        assert_eq!(m.planar.max_abs_error, Some(0.25));
        assert_eq!(m.planar.boundary_pixels, 1);
        assert_eq!(m.surface.mean_abs_error, Some(0.125));
        // The edge pixel the reference left out (error 1) is not counted.
        assert_eq!(m.edge.max_abs_error, Some(0.5));
        let json = serde_json::to_value(m).expect("serializes");
        for class in ["planar", "surface", "edge"] {
            assert!(json[class]["p95_abs_error"].is_number(), "{class}");
        }
        let n = class_pixels(&classes);
        let named = |c: &str| n.get(c).copied();
        assert_eq!(
            (named("uncovered"), named("planar"), named("surface"), named("edge")),
            (Some(1), Some(2), Some(1), Some(2))
        );
        assert_eq!(class_pixels(&[]).values().sum::<u64>(), 0);
        assert_eq!(class_pixels(&[]).len(), 4);

        // The headline: planar and surface pixels the reference evaluated.
        let c = Comparison::new(&v, &truth, &classes, None);
        assert_eq!(headline_pixels(&truth, &classes), truth.shadow_only());
        assert_eq!(c.evaluated_pixels, 3);
        assert_eq!(c.max_abs_error, Some(0.25));
        assert!((c.mean_abs_error.expect("mean") - 0.375 / 3.0).abs() < 1e-12);
        assert_eq!((c.boundary_pixels, c.boundary_mean_abs_error), (1, Some(0.25)));
        assert_eq!(
            (c.boundary_p50_abs_error, c.boundary_p95_abs_error, c.boundary_p99_abs_error),
            (Some(0.25), Some(0.25), Some(0.25))
        );
        assert_eq!(c.pixel_match, Some(1.0 / 3.0));
        assert_eq!(c.pixel_match_lecocq, None, "not measured");
        assert_eq!(c.classes, m);
        assert_eq!(c.class_pixels, n);
        let json = serde_json::to_value(&c).expect("serializes");
        assert_eq!(json["classes"]["edge"]["pixels"], 1);
        assert_eq!(json["class_pixels"]["uncovered"], 1);
    }

    /// A reference image of one row.
    fn row(lit: Vec<f64>, evaluated: Vec<bool>) -> ReferenceImage {
        ReferenceImage {
            width: lit.len() as u32,
            height: 1,
            lit,
            evaluated,
            transmittance: None,
            classes: None,
        }
    }

    #[test]
    fn lecocq_pixel_match_is_binary_against_one_ray_per_pixel() {
        let ray = row(vec![1.0, 0.0, 1.0, 0.0, 1.0], vec![true, true, true, true, false]);
        let all = [true; 5];
        // Three of the four evaluated pixels agree; the unevaluated one is not compared.
        let v = vis(vec![1.0, 0.0, 0.0, 0.0, 0.0]);
        assert!(is_binary(&v, &all));
        assert_eq!(lecocq_pixel_match(&v, &ray, &all), Some(0.75));
        assert_eq!(lecocq_pixel_match(&v, &ray, &[true, false, true, false, true]), Some(0.5));
        // One fractional value among the compared pixels: not a binary method, no match.
        let aa = vis(vec![1.0, 0.0, 0.5, 0.0, 1.0]);
        assert!(!is_binary(&aa, &all));
        assert_eq!(lecocq_pixel_match(&aa, &ray, &all), None);
        // ... unless that pixel is masked out.
        assert_eq!(lecocq_pixel_match(&aa, &ray, &[true, true, false, true, true]), Some(1.0));
        // A fractional ray-traced value (semi-transparent casters): no match either.
        let tinted = row(vec![1.0, 0.4, 1.0, 0.0, 1.0], vec![true; 5]);
        assert_eq!(lecocq_pixel_match(&v, &tinted, &all), None);
        // No pixel compared.
        assert_eq!(lecocq_pixel_match(&v, &ray, &[false; 5]), None);

        // In a comparison, over the headline pixels.
        use PixelClass::{Edge, Planar};
        let classes = [Planar, Planar, Planar, Edge, Planar];
        let truth = row(vec![1.0, 0.0, 0.5, 0.5, 1.0], vec![true; 5]);
        let c = Comparison::new(&v, &truth, &classes, Some(&ray));
        assert_eq!(c.pixel_match_lecocq, Some(2.0 / 3.0));
        assert_eq!(Comparison::new(&aa, &truth, &classes, Some(&ray)).pixel_match_lecocq, None);
        let json = serde_json::to_value(Comparison::new(&aa, &truth, &classes, Some(&ray)))
            .expect("serializes");
        assert!(json["pixel_match_lecocq"].is_null());
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
            proptest::prop_assert_eq!(m.boundary_mean().is_some(), m.boundary_pixels > 0);
            let ps = [m.boundary_p50_abs_error, m.boundary_p95_abs_error, m.boundary_p99_abs_error];
            proptest::prop_assert!(ps.iter().all(|p| p.is_some() == (m.boundary_pixels > 0)));
            if let [Some(p50), Some(p95), Some(p99)] = ps {
                proptest::prop_assert!(0.0 <= p50 && p50 <= p95 && p95 <= p99);
                proptest::prop_assert!(p99 <= m.max_abs_error);
            }
        }

        #[test]
        fn class_metrics_are_ordered(values in proptest::collection::vec((0.0f32..=1.0, 0.0f64..=1.0, proptest::bool::ANY), 1..64)) {
            let v = vis(values.iter().map(|t| t.0).collect());
            let r: Vec<f64> = values.iter().map(|t| t.1).collect();
            let e: Vec<bool> = values.iter().map(|t| t.2).collect();
            let m = ClassMetrics::compare(&v, &r, &e);
            proptest::prop_assert_eq!(m.pixels, e.iter().filter(|&&x| x).count() as u64);
            proptest::prop_assert!(m.boundary_pixels <= m.pixels);
            if m.pixels == 0 {
                proptest::prop_assert!(m.mean_abs_error.is_none() && m.p95_abs_error.is_none());
            } else {
                let (mean, rmse) = (m.mean_abs_error.expect("mean"), m.rmse.expect("rmse"));
                let max = m.max_abs_error.expect("max");
                let p95 = m.p95_abs_error.expect("p95");
                proptest::prop_assert!(mean <= rmse + 1e-12);
                proptest::prop_assert!(rmse <= max + 1e-12);
                proptest::prop_assert!(p95 <= max);
                proptest::prop_assert!(p95 >= 0.0);
            }
            proptest::prop_assert_eq!(m.boundary_mean_abs_error.is_some(), m.boundary_pixels > 0);
            let ps = [m.boundary_p50_abs_error, m.boundary_p95_abs_error, m.boundary_p99_abs_error];
            proptest::prop_assert!(ps.iter().all(|p| p.is_some() == (m.boundary_pixels > 0)));
            if let [Some(p50), Some(p95), Some(p99)] = ps {
                proptest::prop_assert!(0.0 <= p50 && p50 <= p95 && p95 <= p99);
                proptest::prop_assert!(p99 <= m.max_abs_error.expect("max"));
            }
        }
    }
}
