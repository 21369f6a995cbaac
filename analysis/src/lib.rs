//! Accuracy of a method's visibility against a reference: the metrics of DESIGN.md
//! (`metrics.json`) and error images.

pub mod metrics;

pub use metrics::{error_image, Metrics};
