//! The seam between the workbench and a ground truth.

use crate::pixel_class::PixelClass;
use instrumentation::Recorder;
use methods::{Frame, Visibility};

/// A reference's per-pixel lit fraction and which pixels it vouches for.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceImage {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Lit fraction per pixel in [0, 1] (f64: exact where the reference is exact).
    pub lit: Vec<f64>,
    /// Pixels the reference is valid for; metrics are taken over these only.
    pub evaluated: Vec<bool>,
    /// RGB transmittance per pixel, when the reference carries it (scenes with transparency).
    pub transmittance: Option<Vec<[f64; 3]>>,
    /// Each pixel's class (`exact` computes them; see [`crate::pixel_class`]).
    pub classes: Option<Vec<PixelClass>>,
}

impl ReferenceImage {
    /// The reference as a method's result: its lit fraction (and transmittance) rounded to
    /// `f32`.
    pub fn to_visibility(&self) -> Visibility {
        Visibility {
            width: self.width,
            height: self.height,
            lit: self.lit.iter().map(|&v| v as f32).collect(),
            transmittance: self
                .transmittance
                .as_ref()
                .map(|t| t.iter().map(|c| c.map(|v| v as f32)).collect()),
        }
    }

    /// The pixels the reference vouches for whose class is `planar` or `surface` (every
    /// evaluated pixel when there are no classes): the shadow-only pixels, where the error is
    /// the shadow's and not the camera's.
    pub fn shadow_only(&self) -> Vec<bool> {
        match &self.classes {
            Some(c) => {
                self.evaluated.iter().zip(c).map(|(&e, c)| e && c.is_shadow_only()).collect()
            }
            None => self.evaluated.clone(),
        }
    }
}

/// Why a reference could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReferenceError {
    /// The reference does not apply to this scene (bad input), e.g. `exact` without a planar
    /// receiver or with semi-transparent casters.
    #[error("{0}")]
    NotApplicable(String),
    /// An option has a value the reference cannot use (bad input).
    #[error("{option}: {message}")]
    InvalidOption {
        /// The option as the user spells it (e.g. `--ref-rate`).
        option: &'static str,
        /// What is wrong.
        message: String,
    },
}

/// A ground truth: computes the reference image of a frame, recording counters and stages.
pub trait Reference: Sync {
    /// The reference's name, as on the command line (`exact`, `raytrace`).
    fn name(&self) -> &'static str;
    /// The parameters that shape the result, for the run record.
    fn params(&self) -> serde_json::Map<String, serde_json::Value>;
    /// Computes the reference for the frame.
    fn evaluate(
        &self,
        frame: &Frame<'_>,
        rec: &mut Recorder,
    ) -> Result<ReferenceImage, ReferenceError>;
}
