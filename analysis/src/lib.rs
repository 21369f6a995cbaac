//! Accuracy against ground truth: references (the [`reference::Reference`] seam), the metrics
//! of DESIGN.md (`metrics.json`) and error images (the false-colour [`error_map`]).

pub mod budget;
pub mod compare;
pub mod crosscheck;
pub mod error_map;
pub mod exact;
pub mod flip;
pub mod metrics;
pub mod pixel_class;
pub mod raytrace;
pub mod reference;
pub mod registry;
pub mod temporal;

pub use metrics::{error_image, Metrics};
pub use reference::{Reference, ReferenceError, ReferenceImage};
