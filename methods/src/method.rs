//! The seam between the workbench and a shadow technique.

use crate::frame::Frame;
use instrumentation::Recorder;

/// Per-pixel result of a method.
#[derive(Debug, Clone, PartialEq)]
pub struct Visibility {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Lit fraction per pixel in [0, 1]; 1 where no surface is seen.
    pub lit: Vec<f32>,
    /// RGB transmittance per pixel, when the method carries it (scenes with transparency).
    pub transmittance: Option<Vec<[f32; 3]>>,
}

/// Why a method could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MethodError {
    /// An option has a value the method cannot use (bad input).
    #[error("{option}: {message}")]
    InvalidOption {
        /// The option, as the user spells it (e.g. `--map-res`).
        option: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The method does not apply to this scene (bad input).
    #[error("{0}")]
    NotApplicable(String),
    /// The GPU path could not run (no adapter, or a device failure).
    #[error(transparent)]
    #[cfg(feature = "gpu")]
    Gpu(#[from] crate::gpu::GpuError),
}

/// A shadow technique.
pub trait ShadowMethod: Sync {
    /// The method's name, as on the command line.
    fn name(&self) -> &'static str;
    /// The parameters that shape the result, for the run record.
    fn params(&self) -> serde_json::Map<String, serde_json::Value>;
    /// Computes visibility for the frame, recording counters and stage times.
    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError>;
}
