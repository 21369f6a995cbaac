//! The animation of a run in motion: each frame the method's shaded image, the reference's and
//! the error map side by side ([`side_by_side`]), written as one animated PNG (APNG, which every
//! current browser plays in an `<img>`) by [`Apng`], frame by frame, so that an animation of
//! many frames never holds more than one in memory.
//!
//! The records of a run in motion: [`FrameRecord`], one per frame (`frames.csv`,
//! [`write_frames_csv`]), and [`AnimationRecord`], the whole run with its temporal metrics
//! (`temporal.json`), written by `animate` and by a report's runs over animated scenes.
//! [`frame_delay_ms`] reads an animation's frame delay back, for the players of a run's page.
//!
//! APNG through the `png` crate (the encoder `image` uses for still PNGs): its `fcTL`/`fdAT`
//! chunks are written by the crate; the frame count is declared up front, and a writer that
//! is finished with fewer frames than declared is an error, not a short file.

use analysis::temporal::TemporalMetrics;
use image::RgbImage;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// Grey of the gap between the three panels.
const GAP_GREY: u8 = 24;
/// Width of the gap between panels, pixels.
const GAP: u32 = 4;

/// An animated image could not be written.
#[derive(Debug, thiserror::Error)]
pub enum AnimationError {
    /// Writing `path` failed.
    #[error("cannot write {path}: {message}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// A frame of the wrong size, or more or fewer frames than declared (a caller's bug).
    #[error("{path}: {message}")]
    Frames {
        /// The file.
        path: PathBuf,
        /// What was wrong.
        message: String,
    },
}

impl From<AnimationError> for crate::output::OutputError {
    /// The same file and message, as the writers of a report's files give them.
    fn from(e: AnimationError) -> Self {
        match e {
            AnimationError::Write { path, message } | AnimationError::Frames { path, message } => {
                Self::Write { path, message }
            }
        }
    }
}

/// The panels of one frame placed left to right on a dark background, top-aligned, with a
/// gap of [`GAP`] pixels between them; the height is the tallest panel's (the error map
/// carries its colour bar below the image).
pub fn side_by_side(panels: &[&RgbImage]) -> RgbImage {
    let width = panels.iter().map(|p| p.width()).sum::<u32>()
        + GAP * (panels.len().saturating_sub(1) as u32);
    let height = panels.iter().map(|p| p.height()).max().unwrap_or(0);
    let mut out = RgbImage::from_pixel(width, height, image::Rgb([GAP_GREY; 3]));
    let mut x0 = 0;
    for p in panels {
        image::imageops::replace(&mut out, *p, i64::from(x0), 0);
        x0 += p.width() + GAP;
    }
    out
}

/// An APNG being written: created with its size, frame count and frame delay, then given
/// every frame in order ([`Apng::push`]) and finished ([`Apng::finish`]).
pub struct Apng {
    path: PathBuf,
    writer: png::Writer<BufWriter<File>>,
    width: u32,
    height: u32,
    declared: u32,
    written: u32,
}

impl Apng {
    /// Starts `path`: `frames` frames of `width x height` RGB, each shown `delay_ms`
    /// milliseconds, looping forever.
    pub fn create(
        path: &Path,
        width: u32,
        height: u32,
        frames: u32,
        delay_ms: u16,
    ) -> Result<Self, AnimationError> {
        let err = |e: &dyn std::fmt::Display| AnimationError::Write {
            path: path.to_owned(),
            message: e.to_string(),
        };
        let file = File::create(path).map_err(|e| err(&e))?;
        let mut encoder = png::Encoder::new(BufWriter::new(file), width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_animated(frames, 0).map_err(|e| err(&e))?;
        encoder.set_frame_delay(delay_ms, 1000).map_err(|e| err(&e))?;
        let writer = encoder.write_header().map_err(|e| err(&e))?;
        Ok(Self { path: path.to_owned(), writer, width, height, declared: frames, written: 0 })
    }

    /// Writes the next frame.
    pub fn push(&mut self, frame: &RgbImage) -> Result<(), AnimationError> {
        if frame.dimensions() != (self.width, self.height) || self.written == self.declared {
            return Err(AnimationError::Frames {
                path: self.path.clone(),
                message: format!(
                    "frame {} of {} is {}x{}, the animation is {}x{}",
                    self.written + 1,
                    self.declared,
                    frame.width(),
                    frame.height(),
                    self.width,
                    self.height
                ),
            });
        }
        self.writer.write_image_data(frame.as_raw()).map_err(|e| AnimationError::Write {
            path: self.path.clone(),
            message: e.to_string(),
        })?;
        self.written += 1;
        Ok(())
    }

    /// Ends the file; every declared frame must have been written.
    pub fn finish(self) -> Result<(), AnimationError> {
        if self.written != self.declared {
            return Err(AnimationError::Frames {
                path: self.path,
                message: format!("{} frames written, {} declared", self.written, self.declared),
            });
        }
        let path = self.path;
        self.writer
            .finish()
            .map_err(|e| AnimationError::Write { path: path.clone(), message: e.to_string() })
    }
}

/// One frame of a run in motion: a row of `frames.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    /// Frame index, from 0.
    pub frame: u32,
    /// The animation's time at this frame (the keys' time unit).
    pub time: f64,
    /// The shadow-map resolution this frame ran at (the run's, times the scene's map scale);
    /// `None` for a method without a map.
    pub map_res: Option<u32>,
    /// Shadow-only mean absolute error against the reference (the headline of `compare`).
    pub mean_abs_error: Option<f64>,
    /// Mean absolute error over the boundary pixels.
    pub boundary_mean_abs_error: Option<f64>,
    /// 95th percentile of the absolute error over the boundary pixels.
    pub boundary_p95_abs_error: Option<f64>,
    /// Temporal error of the pair (previous frame, this frame): the mean over its pixel pairs
    /// (`analysis::temporal`); `None` for frame 0 or a pair with no pixel pair.
    pub temporal_error: Option<f64>,
    /// Pixel pairs compared for `temporal_error`.
    pub temporal_pairs: u64,
    /// The method's time on this frame (the median run's total stage time), milliseconds,
    /// wall clock.
    pub method_ms: f64,
    /// The same run's CPU time, milliseconds, where measured.
    pub method_cpu_ms: Option<f64>,
    /// The reference's time (by the run that computed it when it came from a cache),
    /// milliseconds, wall clock.
    pub reference_ms: f64,
    /// Whether the reference was read from a cache.
    pub reference_cached: bool,
}

/// A run in motion: who ran, on what, and its errors over time (`temporal.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AnimationRecord {
    /// Scene name.
    pub scene: String,
    /// Method name.
    pub method: String,
    /// The method's parameters (frame 0's run record; `map_res` is the unscaled one).
    pub params: serde_json::Map<String, serde_json::Value>,
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Frames sampled.
    pub frames: u32,
    /// The reference (`exact`, `raytrace`).
    pub reference: String,
    /// Sub-samples per pixel of its ray-traced part.
    pub ref_rate: Option<u32>,
    /// Mean over frames of the shadow-only mean absolute error.
    pub mean_abs_error: Option<f64>,
    /// Mean over frames of the boundary mean absolute error.
    pub boundary_mean_abs_error: Option<f64>,
    /// Mean over frames of the method's time, milliseconds, wall clock.
    pub method_ms: f64,
    /// Mean over frames of the method's CPU time, milliseconds, where measured.
    pub method_cpu_ms: Option<f64>,
    /// The temporal metrics over every frame pair.
    pub temporal: TemporalMetrics,
    /// Every frame.
    pub per_frame: Vec<FrameRecord>,
}

impl AnimationRecord {
    /// Writes `per_frame` as CSV ([`write_frames_csv`]).
    pub fn write_frames_csv(&self, path: &Path) -> Result<(), AnimationError> {
        write_frames_csv(path, &self.per_frame)
    }

    /// Writes the record as pretty JSON.
    pub fn write_json(&self, path: &Path) -> Result<(), AnimationError> {
        let err = |e: &dyn std::fmt::Display| AnimationError::Write {
            path: path.to_owned(),
            message: e.to_string(),
        };
        let text = serde_json::to_string_pretty(self).map_err(|e| err(&e))?;
        std::fs::write(path, format!("{text}\n")).map_err(|e| err(&e))
    }
}

/// Writes `frames` as CSV (`frames.csv`), a header and a row per frame, the columns the
/// fields of [`FrameRecord`] (empty cells for `None`); no frame, an empty file.
pub fn write_frames_csv(path: &Path, frames: &[FrameRecord]) -> Result<(), AnimationError> {
    let err = |e: &dyn std::fmt::Display| AnimationError::Write {
        path: path.to_owned(),
        message: e.to_string(),
    };
    let mut w = csv::Writer::from_path(path).map_err(|e| err(&e))?;
    for r in frames {
        w.serialize(r).map_err(|e| err(&e))?;
    }
    w.flush().map_err(|e| err(&e))
}

/// How long the animated PNG at `path` shows its first frame, in milliseconds (rounded; a
/// zero denominator is 1/100 s, as the APNG specification has it); `None` for a file that
/// cannot be read, a still PNG or a delay beyond `u16`.
pub fn frame_delay_ms(path: &Path) -> Option<u16> {
    let file = File::open(path).ok()?;
    let reader = png::Decoder::new(std::io::BufReader::new(file)).read_info().ok()?;
    let control = reader.info().frame_control?;
    let den = if control.delay_den == 0 { 100 } else { u32::from(control.delay_den) };
    let ms = (1000 * u32::from(control.delay_num) + den / 2) / den;
    u16::try_from(ms).ok()
}

/// The mean of the values that are there; `None` when none is.
pub fn mean_of(values: impl IntoIterator<Item = Option<f64>>) -> Option<f64> {
    let (sum, n) = values.into_iter().flatten().fold((0.0, 0u32), |(s, n), v| (s + v, n + 1));
    (n > 0).then(|| sum / f64::from(n))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plain(w: u32, h: u32, v: u8) -> RgbImage {
        RgbImage::from_pixel(w, h, image::Rgb([v; 3]))
    }

    #[test]
    fn panels_are_placed_left_to_right_with_gaps() {
        let (a, b) = (plain(3, 2, 10), plain(2, 4, 200));
        let out = side_by_side(&[&a, &b]);
        assert_eq!(out.dimensions(), (3 + GAP + 2, 4));
        assert_eq!(out.get_pixel(0, 0).0, [10; 3]);
        assert_eq!(out.get_pixel(3, 0).0, [GAP_GREY; 3]);
        assert_eq!(out.get_pixel(3 + GAP, 3).0, [200; 3]);
        assert_eq!(out.get_pixel(0, 3).0, [GAP_GREY; 3], "below the shorter panel");
    }

    #[test]
    fn an_apng_holds_its_frames_and_reads_back() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("a.png");
        let mut apng = Apng::create(&path, 4, 3, 3, 100).expect("created");
        for v in [0, 128, 255] {
            apng.push(&plain(4, 3, v)).expect("frame");
        }
        assert!(apng.push(&plain(4, 3, 1)).is_err(), "a fourth frame is refused");
        apng.finish().expect("finished");
        let decoder = png::Decoder::new(std::io::BufReader::new(File::open(&path).expect("open")));
        let mut reader = decoder.read_info().expect("header");
        let control = reader.info().animation_control().copied().expect("animated");
        assert_eq!((control.num_frames, control.num_plays), (3, 0));
        let mut buf = vec![0; reader.output_buffer_size().expect("size")];
        let mut firsts = Vec::new();
        for _ in 0..3 {
            reader.next_frame(&mut buf).expect("frame");
            firsts.push(buf[0]);
        }
        assert_eq!(firsts, [0, 128, 255]);
        assert_eq!(frame_delay_ms(&path), Some(100), "the delay reads back");
        assert_eq!(frame_delay_ms(&dir.path().join("none.png")), None);
        let still = dir.path().join("still.png");
        plain(2, 2, 0).save(&still).expect("a still PNG");
        assert_eq!(frame_delay_ms(&still), None);
    }

    #[test]
    fn too_few_frames_or_a_wrong_size_are_errors() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("a.png");
        let mut apng = Apng::create(&path, 4, 3, 2, 100).expect("created");
        assert!(apng.push(&plain(3, 3, 0)).is_err());
        apng.push(&plain(4, 3, 0)).expect("frame");
        assert!(apng.finish().is_err());
    }
}
