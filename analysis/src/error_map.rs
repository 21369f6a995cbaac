//! False-colour error maps: the absolute error `|value - reference|` of every compared pixel
//! through the magma colormap (perceptually uniform and readable in grey, from the `colorous`
//! crate, a port of d3-scale-chromatic), with a colour bar below the image.
//!
//! The scale runs from 0 (magma's black) to `max_error` (its pale yellow); larger errors take
//! the top colour. Pixels outside the mask (not compared) are a fixed dark grey, [`OUTSIDE`],
//! which magma never takes. The colour bar is a strip as wide as the image: the ramp from 0 to
//! `max_error`, tick marks at 0, `max_error / 2` and `max_error`, and their values written
//! under them with a built-in 3 x 5 pixel font of digits, so the picture carries its own scale
//! ([`bar_height`] gives the strip's height).

use image::{Rgb, RgbImage};
use methods::Visibility;

/// The colour of pixels outside the mask: dark grey (magma has no grey).
pub const OUTSIDE: [u8; 3] = [64, 64, 64];

/// The error at the top of the scale unless told otherwise (`compare --error-scale`).
pub const DEFAULT_MAX_ERROR: f64 = 0.1;

/// The colour bar's background.
const BAR_BACKGROUND: [u8; 3] = [24, 24, 24];

/// The colour of the bar's tick marks and labels.
const INK: [u8; 3] = [235, 235, 235];

/// An error map that cannot be drawn.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ErrorMapError {
    /// The top of the scale is not a finite number above 0.
    #[error("the error scale must be a finite number greater than 0, got {0}")]
    Scale(f64),
}

/// Checks that `max_error` can be the top of the scale (finite, greater than 0).
pub fn check_scale(max_error: f64) -> Result<(), ErrorMapError> {
    if max_error.is_finite() && max_error > 0.0 {
        Ok(())
    } else {
        Err(ErrorMapError::Scale(max_error))
    }
}

/// The colour of an absolute error `error` on a scale whose top is `max_error` (checked by
/// the caller): magma at `error / max_error`, clamped to [0, 1].
pub fn colour(error: f64, max_error: f64) -> [u8; 3] {
    let c = colorous::MAGMA.eval_continuous((error / max_error).clamp(0.0, 1.0));
    [c.r, c.g, c.b]
}

/// Pixels per font pixel of the bar's labels: 2 from 240 pixels of width, else 1.
fn font_scale(width: u32) -> u32 {
    if width >= 240 {
        2
    } else {
        1
    }
}

/// Height of the colour bar under an image `width` pixels wide: a gap, the ramp (8 font
/// pixels), the ticks (2), a gap, the labels (5) and a gap, 20 font pixels in all.
pub fn bar_height(width: u32) -> u32 {
    20 * font_scale(width)
}

/// The 3 x 5 glyphs of the labels, rows top to bottom, bit 2 the left column.
fn glyph(c: char) -> Option<[u8; 5]> {
    Some(match c {
        '0' => [0b111, 0b101, 0b101, 0b101, 0b111],
        '1' => [0b010, 0b110, 0b010, 0b010, 0b111],
        '2' => [0b111, 0b001, 0b111, 0b100, 0b111],
        '3' => [0b111, 0b001, 0b111, 0b001, 0b111],
        '4' => [0b101, 0b101, 0b111, 0b001, 0b001],
        '5' => [0b111, 0b100, 0b111, 0b001, 0b111],
        '6' => [0b111, 0b100, 0b111, 0b101, 0b111],
        '7' => [0b111, 0b001, 0b010, 0b010, 0b010],
        '8' => [0b111, 0b101, 0b111, 0b101, 0b111],
        '9' => [0b111, 0b101, 0b111, 0b001, 0b111],
        '.' => [0b000, 0b000, 0b000, 0b000, 0b010],
        _ => return None,
    })
}

/// The bar's three labels (0, `max_error / 2`, `max_error`), with three significant digits
/// of `max_error` and no trailing zeros: `0`, `0.05`, `0.1` for 0.1.
pub fn labels(max_error: f64) -> [String; 3] {
    let decimals = (2 - max_error.log10().floor() as i32).clamp(0, 12) as usize;
    let text = |v: f64| {
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_owned()
        } else {
            s
        }
    };
    [text(0.0), text(max_error / 2.0), text(max_error)]
}

/// Width in image pixels of `text` at font scale `s` (glyphs 3 wide, 1 apart).
fn text_width(text: &str, s: u32) -> u32 {
    (4 * text.chars().count() as u32).saturating_sub(1) * s
}

/// Draws `text` with its left edge at `x0` and its top at `y0`, clipped to the image.
fn draw_text(img: &mut RgbImage, text: &str, x0: i64, y0: u32, s: u32) {
    for (k, rows) in text.chars().filter_map(glyph).enumerate() {
        for (row, bits) in rows.iter().enumerate() {
            for col in 0..3u32 {
                if bits & (0b100 >> col) == 0 {
                    continue;
                }
                for (dx, dy) in (0..s).flat_map(|dx| (0..s).map(move |dy| (dx, dy))) {
                    let x = x0 + i64::from((4 * k as u32 + col) * s + dx);
                    let y = y0 + row as u32 * s + dy;
                    if (0..i64::from(img.width())).contains(&x) && y < img.height() {
                        img.put_pixel(x as u32, y, Rgb(INK));
                    }
                }
            }
        }
    }
}

/// Draws the colour bar into the rows from `top` down of `img`.
fn draw_bar(img: &mut RgbImage, top: u32, max_error: f64) {
    let (w, s) = (img.width(), font_scale(img.width()));
    for y in top..img.height() {
        for x in 0..w {
            img.put_pixel(x, y, Rgb(BAR_BACKGROUND));
        }
    }
    // The ramp: column x shows the error x / (w - 1) of the way up the scale.
    let ramp_top = top + 2 * s;
    for x in 0..w {
        let t = if w > 1 { f64::from(x) / f64::from(w - 1) } else { 0.0 };
        for y in ramp_top..ramp_top + 8 * s {
            img.put_pixel(x, y, Rgb(colour(t * max_error, max_error)));
        }
    }
    // Ticks under 0, the middle and the top of the ramp; each label aligned to its tick
    // (left, centred, right) and the middle one left out where it would touch the others.
    let tick_top = ramp_top + 8 * s;
    let ticks = [0, (w - 1) / 2, w - 1];
    for x in ticks {
        for (dx, y) in (0..s).flat_map(|dx| (tick_top..tick_top + 2 * s).map(move |y| (dx, y))) {
            let x = (x + dx).min(w - 1);
            img.put_pixel(x, y, Rgb(INK));
        }
    }
    let label_top = tick_top + 3 * s;
    let [low, mid, high] = labels(max_error);
    let low_end = i64::from(text_width(&low, s));
    let high_start = i64::from(w) - i64::from(text_width(&high, s));
    let mid_start = i64::from(ticks[1]) - i64::from(text_width(&mid, s) / 2);
    let mid_end = mid_start + i64::from(text_width(&mid, s));
    draw_text(img, &low, 0, label_top, s);
    draw_text(img, &high, high_start.max(0), label_top, s);
    if mid_start > low_end + i64::from(2 * s) && mid_end + i64::from(2 * s) < high_start {
        draw_text(img, &mid, mid_start, label_top, s);
    }
}

/// The false-colour map of `|result - reference|` over the pixels where `mask` is true, with
/// the colour bar of `max_error` appended below (the image is `result`'s width and its height
/// plus [`bar_height`]).
///
/// # Panics
/// When the buffers differ in size (a caller's bug, not bad input).
pub fn error_map(
    result: &Visibility,
    reference: &[f64],
    mask: &[bool],
    max_error: f64,
) -> Result<RgbImage, ErrorMapError> {
    check_scale(max_error)?;
    assert_eq!(result.lit.len(), reference.len(), "result and reference differ in size");
    assert_eq!(result.lit.len(), mask.len(), "result and mask differ in size");
    let (w, h) = (result.width, result.height);
    let mut img = RgbImage::new(w, h + bar_height(w));
    for (k, ((&v, &r), &m)) in result.lit.iter().zip(reference).zip(mask).enumerate() {
        let c = if m { colour((f64::from(v) - r).abs(), max_error) } else { OUTSIDE };
        img.put_pixel(k as u32 % w, k as u32 / w, Rgb(c));
    }
    if w > 0 {
        draw_bar(&mut img, h, max_error);
    }
    Ok(img)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vis(width: u32, lit: Vec<f32>) -> Visibility {
        Visibility { width, height: lit.len() as u32 / width, lit, transmittance: None }
    }

    #[test]
    fn known_errors_take_magma_colours_and_unmasked_pixels_grey() {
        // Errors 0, 1/16, 1/8 and 1/2 (exact in f32) on a scale of 1/8; the last pixel is
        // not compared.
        let v = vis(5, vec![0.5, 0.5625, 0.375, 1.0, 0.0]);
        let r = [0.5, 0.5, 0.5, 0.5, 1.0];
        let mask = [true, true, true, true, false];
        let img = error_map(&v, &r, &mask, 0.125).expect("a valid scale");
        let at = |x: u32| img.get_pixel(x, 0).0;
        // magma's ends (d3-scale-chromatic): #000004 and #fcfdbf.
        assert_eq!(at(0), [0x00, 0x00, 0x04]);
        assert_eq!(at(2), [0xfc, 0xfd, 0xbf]);
        // Halfway up the scale, magma's middle (#b73779, within rounding).
        let mid = at(1);
        for (c, want) in mid.iter().zip([0xb7u8, 0x37, 0x79]) {
            assert!(c.abs_diff(want) <= 2, "{mid:?}");
        }
        // Beyond the top of the scale: the top colour.
        assert_eq!(at(3), at(2));
        assert_eq!(at(4), OUTSIDE);
        // Errors increase in lightness along magma.
        let luma =
            |c: [u8; 3]| 0.3 * f64::from(c[0]) + 0.59 * f64::from(c[1]) + 0.11 * f64::from(c[2]);
        assert!(luma(at(0)) < luma(mid) && luma(mid) < luma(at(2)));
    }

    #[test]
    fn the_colour_bar_is_appended_below_with_its_ramp_and_labels() {
        for (w, h) in [(96u32, 72u32), (320, 240), (1, 1)] {
            let n = (w * h) as usize;
            let img = error_map(&vis(w, vec![0.0; n]), &vec![0.0; n], &vec![true; n], 0.1)
                .expect("a valid scale");
            assert_eq!(img.dimensions(), (w, h + bar_height(w)), "{w}x{h}");
        }
        assert_eq!((bar_height(96), bar_height(320)), (20, 40));

        let (w, h) = (96u32, 72u32);
        let n = (w * h) as usize;
        let img = error_map(&vis(w, vec![0.0; n]), &vec![0.0; n], &vec![false; n], 0.2)
            .expect("a valid scale");
        // The ramp (two rows below the image, s = 1) runs from magma's bottom to its top.
        let ramp_row = h + 2;
        assert_eq!(img.get_pixel(0, ramp_row).0, colour(0.0, 1.0));
        assert_eq!(img.get_pixel(w - 1, ramp_row).0, colour(1.0, 1.0));
        // Ticks at both ends, and ink in the label rows at the left (`0`) and the right
        // (`0.2`), the middle (`0.1`) too.
        let tick_row = h + 10;
        assert_eq!(img.get_pixel(0, tick_row).0, INK);
        assert_eq!(img.get_pixel(w - 1, tick_row).0, INK);
        let inked = |xs: std::ops::Range<u32>| {
            xs.flat_map(|x| (h + 13..h + 18).map(move |y| (x, y)))
                .filter(|&(x, y)| img.get_pixel(x, y).0 == INK)
                .count()
        };
        // `0` is 12 font pixels; `0.2`: 12 + 1 + 11.
        assert_eq!(inked(0..4), 12);
        assert_eq!(inked(w - 11..w), 12 + 1 + 11);
        assert!(inked(w / 2 - 8..w / 2 + 8) > 0);
    }

    #[test]
    fn labels_carry_three_significant_digits_without_trailing_zeros() {
        assert_eq!(labels(0.1), ["0", "0.05", "0.1"]);
        assert_eq!(labels(1.0), ["0", "0.5", "1"]);
        assert_eq!(labels(0.25), ["0", "0.125", "0.25"]);
        assert_eq!(labels(0.003), ["0", "0.0015", "0.003"]);
        for max in [0.1, 1.0, 0.25, 0.003, 0.5, 2.0] {
            for label in labels(max) {
                assert!(label.chars().all(|c| glyph(c).is_some()), "{label}");
            }
        }
    }

    #[test]
    fn a_scale_that_is_not_a_positive_number_is_refused() {
        let v = vis(1, vec![0.0]);
        for bad in [0.0, -0.1, f64::NAN, f64::INFINITY] {
            let e = error_map(&v, &[0.0], &[true], bad).expect_err("refused");
            assert!(e.to_string().contains("greater than 0"), "{e}");
        }
        assert_eq!(check_scale(1e-6), Ok(()));
    }
}
