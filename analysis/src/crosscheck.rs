//! An independent cross-check of `exact`: tiny-skia rasterizes the same screen-space shadow
//! polygons ([`crate::exact::shadow_polygons`], all of one orientation) with the non-zero
//! fill rule, which fills their union, with anti-aliasing at `k` times the frame's resolution;
//! the coverage is box-filtered down to the frame, and the result is compared with `exact`
//! over the `planar` pixels of that receiver.
//!
//! tiny-skia works in `f32` and its anti-aliasing takes 4 x 4 sub-samples per pixel (coverage
//! quantised to 8 bits), so the difference is expected near 0.02 per partially covered pixel
//! at `k = 1` and to fall as `k` grows; it measures tiny-skia's error, not `exact`'s, and
//! checks that both read the polygons the same way (orientation, overlaps, holes, frame).

use crate::exact::{shadow_polygons, ExactCoverage, ScreenPolygons};
use crate::pixel_class::PixelClass;
use crate::reference::{Reference, ReferenceError};
use instrumentation::Recorder;
use methods::Frame;
use tiny_skia::{FillRule, Mask, PathBuilder, Transform};

/// Largest side, in pixels, of the high-resolution mask (`k` times the frame's side).
pub const MAX_MASK_SIDE: u64 = 32_768;

/// The difference between tiny-skia's rasterization and `exact`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrossCheck {
    /// Supersampling factor per axis.
    pub k: u32,
    /// Mean of `|tiny-skia - exact|` over the evaluated pixels (0 when there are none).
    pub mean_abs_diff: f64,
    /// Largest `|tiny-skia - exact|` over the evaluated pixels.
    pub max_abs_diff: f64,
    /// Number of evaluated pixels compared.
    pub evaluated_pixels: u64,
}

/// Shadowed fraction of every pixel of a `width x height` frame covered by `polygons`
/// (non-zero fill: their union when all have one orientation), rasterized by tiny-skia with anti-aliasing at `k x k` mask pixels per
/// frame pixel and box-filtered down.
pub fn tiny_skia_coverage(
    polygons: &ScreenPolygons,
    width: u32,
    height: u32,
    k: u32,
) -> Result<Vec<f64>, ReferenceError> {
    let (kw, kh) = (u64::from(width) * u64::from(k), u64::from(height) * u64::from(k));
    if k == 0 || kw > MAX_MASK_SIDE || kh > MAX_MASK_SIDE {
        return Err(ReferenceError::InvalidOption {
            option: "k",
            message: format!(
                "must be at least 1 with k x {width} and k x {height} at most {MAX_MASK_SIDE}, \
                 got {k}"
            ),
        });
    }
    let (w, h) = (width as usize, height as usize);
    let mut out = vec![0.0; w * h];
    if w == 0 || h == 0 {
        return Ok(out);
    }
    let mut mask =
        Mask::new(kw as u32, kh as u32).ok_or_else(|| ReferenceError::InvalidOption {
            option: "k",
            message: format!("cannot allocate a {kw} x {kh} mask"),
        })?;
    let scale = f64::from(k);
    let mut pb = PathBuilder::new();
    for contour in polygons.contours() {
        let Some((first, rest)) = contour.split_first() else { continue };
        pb.move_to((first[0] * scale) as f32, (first[1] * scale) as f32);
        for p in rest {
            pb.line_to((p[0] * scale) as f32, (p[1] * scale) as f32);
        }
        pb.close();
    }
    if let Some(path) = pb.finish() {
        mask.fill_path(&path, FillRule::Winding, true, Transform::identity());
    }
    let data = mask.data();
    let (k, kw) = (k as usize, kw as usize);
    let norm = 1.0 / (255.0 * (k * k) as f64);
    for (j, row) in out.chunks_mut(w).enumerate() {
        for sy in 0..k {
            let line = &data[(j * k + sy) * kw..(j * k + sy + 1) * kw];
            for (i, v) in row.iter_mut().enumerate() {
                *v += line[i * k..(i + 1) * k].iter().map(|&a| f64::from(a)).sum::<f64>();
            }
        }
        row.iter_mut().for_each(|v| *v *= norm);
    }
    Ok(out)
}

/// Rasterizes the frame's shadow polygons with tiny-skia at `k` times the resolution and
/// compares the lit fraction with `exact` over the `planar` pixels of the scene's main planar
/// receiver (`Scene::receiver_plane`) that `exact` evaluates.
pub fn tiny_skia_crosscheck(frame: &Frame<'_>, k: u32) -> Result<CrossCheck, ReferenceError> {
    let exact = ExactCoverage::default().evaluate(frame, &mut Recorder::default())?;
    let polygons = shadow_polygons(frame)?;
    let shadowed = tiny_skia_coverage(&polygons, frame.width(), frame.height(), k)?;
    let receiver = frame.scene.receiver_plane().map(|(o, _, _)| o as u32);
    let classes = exact.classes.as_deref().unwrap_or_default();
    let on_receiver = |p: usize| {
        let t = frame.gbuffer.triangle[p];
        classes.get(p) == Some(&PixelClass::Planar)
            && t != methods::raster::NO_TRIANGLE
            && Some(frame.geometry.object[t as usize]) == receiver
    };
    let (mut n, mut sum, mut max) = (0u64, 0.0, 0.0f64);
    for (p, ((&s, &e), &ev)) in shadowed.iter().zip(&exact.lit).zip(&exact.evaluated).enumerate() {
        if ev && on_receiver(p) {
            let d = ((1.0 - s).clamp(0.0, 1.0) - e).abs();
            n += 1;
            sum += d;
            max = max.max(d);
        }
    }
    Ok(CrossCheck {
        k,
        mean_abs_diff: if n == 0 { 0.0 } else { sum / n as f64 },
        max_abs_diff: max,
        evaluated_pixels: n,
    })
}
