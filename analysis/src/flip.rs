//! NVIDIA's FLIP perceptual difference (Andersson et al. 2020, through the `nv-flip` crate),
//! as an extra column beside the per-pixel metrics.
//!
//! Both buffers are turned into grey sRGB 8-bit images of the lit fraction. Pixels the
//! reference does not evaluate take the reference's value in both images, so they add no
//! difference; the mean is still taken over the whole frame, as FLIP's pool does, so compare
//! FLIP values only between runs of the same frame. Viewing condition: FLIP's default of
//! 67 pixels per degree.

use methods::Visibility;

fn srgb8(linear: f64) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0).round() as u8
}

/// Mean FLIP error between `result` and `reference` (0 identical, 1 most different).
///
/// # Panics
/// When the buffers differ in size (a caller's bug).
pub fn flip_mean(result: &Visibility, reference: &[f64], evaluated: &[bool]) -> f64 {
    assert_eq!(result.lit.len(), reference.len(), "result and reference differ in size");
    let grey = |v: f64| [srgb8(v); 3];
    let test: Vec<u8> = result
        .lit
        .iter()
        .zip(reference)
        .zip(evaluated)
        .flat_map(|((&v, &r), &e)| grey(if e { f64::from(v) } else { r }))
        .collect();
    let truth: Vec<u8> = reference.iter().flat_map(|&r| grey(r)).collect();
    let (w, h) = (result.width, result.height);
    let reference_image = nv_flip::FlipImageRgb8::with_data(w, h, &truth);
    let test_image = nv_flip::FlipImageRgb8::with_data(w, h, &test);
    let error_map = nv_flip::flip(reference_image, test_image, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    f64::from(nv_flip::FlipPool::from_image(&error_map).mean())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vis(lit: Vec<f32>, w: u32) -> Visibility {
        let h = lit.len() as u32 / w;
        Visibility { width: w, height: h, lit, transmittance: None }
    }

    #[test]
    fn identical_images_have_zero_flip_and_differences_do_not() {
        let reference: Vec<f64> =
            (0..64 * 64).map(|k| if k % 64 < 32 { 0.0 } else { 1.0 }).collect();
        let same = vis(reference.iter().map(|&r| r as f32).collect(), 64);
        let all = vec![true; reference.len()];
        assert_eq!(flip_mean(&same, &reference, &all), 0.0);
        let shifted = vis((0..64 * 64).map(|k| if k % 64 < 36 { 0.0 } else { 1.0 }).collect(), 64);
        let f = flip_mean(&shifted, &reference, &all);
        assert!(f > 0.0 && f <= 1.0, "{f}");
        // Where the reference does not vouch for a pixel, the result is not held against it.
        let masked: Vec<bool> = (0..64 * 64).map(|k| !(32..36).contains(&(k % 64))).collect();
        assert_eq!(flip_mean(&shifted, &reference, &masked), 0.0);
    }
}
