//! Accuracy against ground truth: references (the [`reference::Reference`] seam), the metrics
//! of DESIGN.md (`metrics.json`) and error images.

pub mod crosscheck;
pub mod exact;
pub mod flip;
pub mod metrics;
pub mod pixel_class;
pub mod raytrace;
pub mod reference;
pub mod registry;

pub use metrics::{error_image, Metrics};
pub use reference::{Reference, ReferenceError, ReferenceImage};
