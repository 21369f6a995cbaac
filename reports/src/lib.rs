//! What runs and reports write. A single run: the visibility buffer as EXR, a shaded PNG for
//! looking, and the run record as JSON ([`output`]). A report: a [`suite`] of scenes, methods
//! and parameters, run by [`sweep`] under the timing protocol of [`timing`], written by
//! [`write`] as JSON, CSV, Markdown tables and EXR images, with the charts chosen by [`figures`]
//! and drawn by [`plots`]; the papers' tables are measured by [`tables`].

pub mod baseline;
pub mod devices;
pub mod figures;
pub mod grids;
pub mod html;
pub mod output;
pub mod plots;
pub mod run_pages;
pub mod suite;
pub mod sweep;
pub mod tables;
pub mod timing;
pub mod write;

pub use figures::write_plots;
pub use output::{
    shade, write_class_pngs, write_run_json, write_shadow_png, write_visibility_exr, MetricsRecord,
    OutputError,
};
pub use suite::{Suite, SuiteError, BUILTIN_SUITES};
pub use sweep::{run_count, run_suite, Report, Row};
pub use write::write_report;
