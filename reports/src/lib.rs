//! What runs and reports write. A single run: the visibility buffer as EXR, a shaded PNG for
//! looking, and the run record as JSON ([`output`]). A report: a [`suite`] of scenes, methods
//! and parameters, planned as items by [`plan`] (and split into shards there), run by [`sweep`]
//! under the timing protocol of [`timing`] with references from the [`cache`], held in the
//! [`model`], written by [`write`] as JSON, CSV, Markdown, EXR images and HTML pages
//! ([`index`], [`run_pages`], rendered from [`templates`]), leading with the answer that
//! [`summary`] computes (Pareto fronts, what the runs say of each method, the machine and its
//! load), with the charts chosen by [`figures`] and drawn by [`plots`], and the section that
//! sets today's techniques against the seeds ([`today`]);
//! the papers' tables and the cost-against-work tables are measured by [`tables`]; shards are
//! put back together by [`merge`]. A frame for another renderer is written by [`frame_export`],
//! and an outside renderer's result read by [`external`].

pub mod animation;
pub mod baseline;
pub mod cache;
pub mod devices;
pub mod external;
pub mod figures;
pub mod frame_export;
pub mod grids;
pub mod html;
pub mod index;
pub mod merge;
pub mod model;
pub mod motion;
pub mod motion_charts;
pub mod output;
pub mod plan;
pub mod plots;
pub mod progress;
pub mod publish;
pub mod run_pages;
pub mod suite;
pub mod summary;
pub mod sweep;
pub mod tables;
pub mod templates;
pub mod timing;
pub mod today;
pub mod write;

pub use figures::write_plots;
pub use model::{Images, Report, Row};
pub use output::{
    shade, write_class_pngs, write_run_json, write_shadow_png, write_visibility_exr, MetricsRecord,
    OutputError,
};
pub use suite::{Suite, SuiteError, BUILTIN_SUITES};
pub use sweep::run_suite;
pub use write::write_report;
