//! What a run writes: the visibility buffer as EXR, a shaded PNG for looking, and the run
//! record as JSON.

pub mod output;

pub use output::{shade, write_run_json, write_shadow_png, write_visibility_exr, OutputError};
