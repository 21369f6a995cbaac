//! Writers for a render's three files: `visibility.exr`, `shadow.png`, `run.json`; for the
//! pixel classes of a reference that computes them (`classes.png`, `class_ids.png`); and the
//! record of a comparison, `metrics.json` ([`MetricsRecord`]).
//!
//! The same run writes the same bytes: the EXR's blocks are compressed in parallel but written
//! in increasing order ([`ENCODING`]: without a line order the `exr` crate writes them as they
//! finish), the PNG encoder is sequential, and the JSON's fields come in a fixed order; only
//! the measured fields of `run.json` (the stage times and their total) differ between runs.

use analysis::metrics::Comparison;
use analysis::pixel_class::PixelClass;
use glam::DVec3;
use image::{GrayImage, RgbImage};
use instrumentation::RunRecord;
use methods::{Frame, Visibility};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Writing `path` failed.
    #[error("cannot write {path}: {message}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

fn write_err(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError::Write { path: path.to_owned(), message: e.to_string() }
}

/// The EXR encoding: the `exr` crate's default (RLE, 64 x 64 tiles) with the blocks in
/// increasing order, so that the file's bytes do not depend on which block finished first.
const ENCODING: exr::image::Encoding = exr::image::Encoding {
    line_order: exr::meta::attribute::LineOrder::Increasing,
    ..exr::image::Encoding::FAST_LOSSLESS
};

/// Writes the lit fraction as a 32-bit float EXR: one channel `Y`, or `R`, `G`, `B` when the
/// visibility carries RGB transmittance.
pub fn write_visibility_exr(path: &Path, v: &Visibility) -> Result<(), OutputError> {
    use exr::prelude::*;
    let (w, h) = (v.width as usize, v.height as usize);
    let result = match &v.transmittance {
        None => {
            let pixels = SpecificChannels::build()
                .with_channel("Y")
                .with_pixel_fn(|p: Vec2<usize>| (v.lit[p.y() * w + p.x()],));
            Image::from_encoded_channels((w, h), ENCODING, pixels).write().to_file(path)
        }
        Some(rgb) => {
            let pixels = SpecificChannels::rgb(|p: Vec2<usize>| {
                let [r, g, b] = rgb[p.y() * w + p.x()];
                (r, g, b)
            });
            Image::from_encoded_channels((w, h), ENCODING, pixels).write().to_file(path)
        }
    };
    result.map_err(|e| write_err(path, e))
}

fn srgb8(linear: f64) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0).round() as u8
}

/// Ambient share of the Lambert image, so that shadowed surfaces stay visible.
const AMBIENT: f64 = 0.25;

/// A Lambert image for looking at: `albedo * (ambient + (1 - ambient) * max(0, n·l) * lit)`,
/// with the normal turned towards the camera; background dark grey. Not a renderer: only the
/// shadow term comes from the method.
pub fn shade(frame: &Frame<'_>, v: &Visibility) -> RgbImage {
    let g = &frame.gbuffer;
    let w = g.width;
    RgbImage::from_fn(g.width, g.height, |x, y| {
        let k = (y * w + x) as usize;
        if !g.covered(k) {
            return image::Rgb([40, 40, 48]);
        }
        let p = g.position[k];
        let mut n = g.normal[k];
        if n.dot(frame.camera.direction_to(p)) < 0.0 {
            n = -n;
        }
        let l = frame.scene.light.direction_to_light(p);
        let object = frame.geometry.object[g.triangle[k] as usize] as usize;
        let albedo = DVec3::from(frame.scene.objects[object].material.color);
        let lit = match &v.transmittance {
            Some(t) => DVec3::new(f64::from(t[k][0]), f64::from(t[k][1]), f64::from(t[k][2])),
            None => DVec3::splat(f64::from(v.lit[k])),
        };
        let c = albedo * (DVec3::splat(AMBIENT) + (1.0 - AMBIENT) * n.dot(l).max(0.0) * lit);
        image::Rgb([srgb8(c.x), srgb8(c.y), srgb8(c.z)])
    })
}

/// Writes the Lambert image as PNG.
pub fn write_shadow_png(path: &Path, frame: &Frame<'_>, v: &Visibility) -> Result<(), OutputError> {
    shade(frame, v).save(path).map_err(|e| write_err(path, e))
}

/// Writes a frame's pixel classes into `dir`: `classes.png` (RGB, one colour per class,
/// [`PixelClass::colour`]) for looking, and `class_ids.png` (8-bit grey, the value is
/// [`PixelClass::code`]: 0 uncovered, 1 planar, 2 surface, 3 edge) for tools.
///
/// # Panics
/// When `classes` does not hold `width * height` pixels (a caller's bug).
pub fn write_class_pngs(
    dir: &Path,
    width: u32,
    height: u32,
    classes: &[PixelClass],
) -> Result<(), OutputError> {
    assert_eq!(classes.len(), width as usize * height as usize, "classes and frame differ");
    let at = |x: u32, y: u32| classes[(y * width + x) as usize];
    let path = dir.join("classes.png");
    RgbImage::from_fn(width, height, |x, y| image::Rgb(at(x, y).colour()))
        .save(&path)
        .map_err(|e| write_err(&path, e))?;
    let path = dir.join("class_ids.png");
    GrayImage::from_fn(width, height, |x, y| image::Luma([at(x, y).code()]))
        .save(&path)
        .map_err(|e| write_err(&path, e))
}

/// The record of a comparison, written as `metrics.json`: the metrics first (the shadow-only
/// headline, then each class, [`Comparison`]), then what was compared.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MetricsRecord {
    /// The metrics.
    #[serde(flatten)]
    pub comparison: Comparison,
    /// The reference's name (`exact`, `raytrace`).
    pub reference: String,
    /// Sub-samples per pixel of the ray-traced part of the reference: every pixel for
    /// `raytrace`, the `edge` pixels for `exact` (`None` when nothing is ray traced).
    pub ref_rate: Option<u32>,
    /// How `exact`'s `edge` pixels are referenced (`raytrace`, `none`); `None` for `raytrace`.
    pub edge_reference: Option<String>,
    /// Scene name.
    pub scene: String,
    /// Method name.
    pub method: String,
    /// The method's parameters, as its run record gives them.
    pub params: serde_json::Map<String, serde_json::Value>,
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// The method's total stage time, milliseconds; for an outside result, the time its
    /// renderer reported (`--time-ms`), `None` when not given.
    pub method_ms: Option<f64>,
    /// The reference's total stage time (pixel classes included), milliseconds: the time of
    /// its computation, by the run that computed it when it was read from a cache.
    pub reference_ms: f64,
    /// Whether the reference was read from a cache instead of computed.
    #[serde(default)]
    pub reference_cached: bool,
    /// The time this run took to read the reference from the cache, milliseconds (`None`
    /// when it was computed).
    #[serde(default)]
    pub reference_read_ms: Option<f64>,
    /// Whether the result is an outside renderer's (`compare --visibility`, a suite's
    /// `[[external]]` entry) rather than a method's run.
    #[serde(default)]
    pub external: bool,
}

/// Writes the run record as pretty JSON.
pub fn write_run_json(path: &Path, record: &RunRecord) -> Result<(), OutputError> {
    let text = serde_json::to_string_pretty(record).map_err(|e| write_err(path, e))?;
    std::fs::write(path, text + "\n").map_err(|e| write_err(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn class_pngs_hold_each_class_colour_and_code() {
        let dir = tempfile::tempdir().expect("tempdir");
        let classes = [PixelClass::Uncovered, PixelClass::Planar, PixelClass::Surface]
            .into_iter()
            .chain([PixelClass::Edge, PixelClass::Edge, PixelClass::Planar])
            .collect::<Vec<_>>();
        write_class_pngs(dir.path(), 3, 2, &classes).expect("writes");
        let rgb = image::open(dir.path().join("classes.png")).expect("reads").to_rgb8();
        let ids = image::open(dir.path().join("class_ids.png")).expect("reads");
        assert_eq!(ids.color(), image::ColorType::L8);
        let ids = ids.to_luma8();
        for (k, c) in classes.iter().enumerate() {
            let (x, y) = (k as u32 % 3, k as u32 / 3);
            assert_eq!(rgb.get_pixel(x, y).0, c.colour());
            assert_eq!(ids.get_pixel(x, y).0, [c.code()]);
        }
    }

    /// The EXR is written with its blocks in increasing order, so that writing the same
    /// buffer twice gives the same bytes however the parallel compression finishes.
    #[test]
    fn the_same_visibility_writes_the_same_exr_bytes() {
        let dir = tempfile::tempdir().expect("tempdir");
        let (width, height) = (1000u32, 700u32);
        // Varied content, so that blocks take different times to compress.
        let lit: Vec<f32> = (0..width * height)
            .map(|k| if (k.wrapping_mul(2_654_435_761) >> 7) % 5 < 2 { 1.0 } else { 0.25 })
            .collect();
        let v = Visibility { width, height, lit, transmittance: None };
        let mut files = Vec::new();
        for k in 0..3 {
            let path = dir.path().join(format!("v{k}.exr"));
            write_visibility_exr(&path, &v).expect("writes");
            let meta = exr::meta::MetaData::read_from_file(&path, false).expect("reads back");
            assert_eq!(meta.headers[0].line_order, exr::meta::attribute::LineOrder::Increasing);
            files.push(std::fs::read(&path).expect("bytes"));
        }
        assert!(files.windows(2).all(|w| w[0] == w[1]), "the files differ");
    }
}
