//! The one comparison of a result with the ground truth, shared by `compare` and a report's
//! sweep, so that both give the same metrics for the same result.
//!
//! A [`Truth`] is a frame's reference prepared once: its values, the frame's pixel classes
//! (the reference's own, or the camera's view of the triangles for a reference that computes
//! none, [`crate::exact::classify`]) and the shadow-only headline pixels
//! ([`crate::metrics::headline_pixels`]). [`Truth::compare`] measures a result against it
//! ([`Comparison::new`]); Lecocq et al.'s pixel match needs `raytrace` at one sample per pixel
//! on the same frame, which is traced the first time a binary result asks for it and kept for
//! the others (or given, [`Truth::with_one_ray`]).

use crate::metrics::{headline_pixels, is_binary, Comparison};
use crate::pixel_class::PixelClass;
use crate::reference::{ReferenceError, ReferenceImage};
use instrumentation::Recorder;
use methods::{pattern::PatternKind, Frame, Visibility};
use std::cell::OnceCell;

/// Stage name of the pixel classes computed for a reference that has none.
pub const STAGE_PIXEL_CLASSES: &str = "pixel classes";

/// A frame's ground truth, ready to compare results with.
pub struct Truth {
    /// The reference's values.
    pub reference: ReferenceImage,
    /// Each pixel's class.
    pub classes: Vec<PixelClass>,
    /// The pixels the headline is taken over: `planar` and `surface` pixels the reference
    /// evaluated.
    pub headline: Vec<bool>,
    /// `raytrace` at one sample per pixel (the grid's single sample, the pixel centre), traced
    /// when a binary result is first compared.
    raytrace1: OnceCell<ReferenceImage>,
}

impl Truth {
    /// The truth of `reference` on `frame`; the classes, when the reference has none, are
    /// computed and timed into `rec` (stage [`STAGE_PIXEL_CLASSES`]).
    pub fn new(frame: &Frame<'_>, reference: ReferenceImage, rec: &mut Recorder) -> Self {
        let classes = match &reference.classes {
            Some(c) => c.clone(),
            None => {
                let c = rec.stages.time(STAGE_PIXEL_CLASSES, || crate::exact::classify(frame));
                rec.counters.pixel_triangle_overlaps += c.overlaps;
                c.class
            }
        };
        let headline = headline_pixels(&reference, &classes);
        Self { reference, classes, headline, raytrace1: OnceCell::new() }
    }

    /// Measures `result`, a method's run on `frame` (the frame of the truth), against the
    /// truth: the headline, each class, and Lecocq et al.'s pixel match where the result is
    /// binary on the headline pixels.
    pub fn compare(
        &self,
        frame: &Frame<'_>,
        result: &Visibility,
    ) -> Result<Comparison, ReferenceError> {
        let raytrace1 =
            if is_binary(result, &self.headline) { Some(self.raytrace1(frame)?) } else { None };
        Ok(Comparison::new(result, &self.reference, &self.classes, raytrace1))
    }

    /// The truth with `image` as its `raytrace` at one sample per pixel of the grid pattern on
    /// the same frame (one kept from an earlier run, a reference cache's), so that comparing a
    /// binary result does not trace it again.
    pub fn with_one_ray(self, image: ReferenceImage) -> Self {
        Self { raytrace1: OnceCell::from(image), ..self }
    }

    /// The pixels of the headline whose reference is strictly between 0 and 1.
    pub fn boundary(&self) -> Vec<bool> {
        let lit = &self.reference.lit;
        lit.iter().zip(&self.headline).map(|(&r, &h)| h && r > 0.0 && r < 1.0).collect()
    }

    fn raytrace1(&self, frame: &Frame<'_>) -> Result<&ReferenceImage, ReferenceError> {
        if let Some(r) = self.raytrace1.get() {
            return Ok(r);
        }
        let one_ray = crate::registry::reference("raytrace", 1, PatternKind::Grid)?;
        let image = one_ray.evaluate(frame, &mut Recorder::default())?;
        Ok(self.raytrace1.get_or_init(|| image))
    }
}
