//! What a report is made of, the types every part of `reports` shares: the runs ([`Row`]),
//! the scenes' shared work ([`SceneInfo`]), the whole [`Report`] as `runs.json` holds it, the
//! image grids' panels ([`Panel`]), what a sweep leaves for the image outputs ([`Images`]),
//! and the helpers that name a run and its parameters the same way in every output
//! ([`param_label`], [`row_stem`], [`params_of`]).
//!
//! Everything here is data and its formatting; nothing here runs a method or writes a file,
//! so that the sweep, the figures, the pages and the writers depend on the model and never on
//! one another through it.

use crate::cache::CacheStats;
use crate::output::MetricsRecord;
use crate::plan::Shard;
use crate::suite::Suite;
use crate::tables::{Table, TableRun};
use crate::timing::Machine;
use analysis::{metrics::PerClass, pixel_class::PixelClass, Metrics, ReferenceImage};
use image::RgbImage;
use instrumentation::measure::{Clock, Conditions, StageTimes};
use instrumentation::stats::Summary;
use instrumentation::{Counters, Provenance, RunRecord};
use methods::Visibility;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One method with one parameter combination on one scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Scene name.
    pub scene: String,
    /// Method name.
    pub method: String,
    /// The method's parameters, as its run record gives them.
    pub params: serde_json::Map<String, serde_json::Value>,
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Reference measured against (`exact` or `raytrace`).
    pub reference: String,
    /// Rate of the `raytrace` reference (absent for `exact`).
    pub ref_rate: Option<u32>,
    /// Error metrics against the reference, over its shadow-only pixels.
    pub metrics: Metrics,
    /// NVIDIA FLIP mean over the frame (only the shadow-only pixels may differ).
    pub flip_mean: f64,
    /// Pixel match in Lecocq et al.'s sense (`analysis::metrics::lecocq_pixel_match`): binary
    /// results against `raytrace` at one sample per pixel, over the shadow-only pixels;
    /// `None` for a result that is not binary there.
    #[serde(default)]
    pub pixel_match_lecocq: Option<f64>,
    /// The error's distribution: the share of compared pixels whose error exceeds each of
    /// `analysis::metrics::EXCEEDANCE_THRESHOLDS` (empty when no pixel was compared).
    #[serde(default)]
    pub error_exceedance: Vec<f64>,
    /// The metrics of each pixel class (`metrics.json`'s `classes`).
    #[serde(default)]
    pub classes: Option<PerClass>,
    /// The plan's item that ran it ([`crate::plan`]).
    #[serde(default)]
    pub item: usize,
    /// The shard that ran it, in a merged report ([`Report::shards`]); `None` when unsharded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<u32>,
    /// Wall-clock total of the method's stages.
    pub total_ms: Summary,
    /// CPU time of the process's threads over each run; `None` where unmeasured.
    #[serde(default)]
    pub cpu_ms: Option<Summary>,
    /// Whether a timed run was contended (its threads' CPU share below the protocol's
    /// threshold, after a retry): its wall times are not to be compared.
    #[serde(default)]
    pub contended: bool,
    /// The machine's load and the runs' CPU share over the timed runs.
    #[serde(default)]
    pub conditions: Option<Conditions>,
    /// Each stage's time, on both clocks.
    pub stages: Vec<StageTimes>,
    /// Stages the scene did not call for.
    pub skipped_stages: Vec<String>,
    /// Counters of the last run.
    pub counters: Counters,
    /// The method's notes.
    pub notes: Vec<String>,
    /// Whether the row is an outside renderer's result (a suite's `[[external]]`), scored
    /// like a method's run; its time is the one the suite gives, on both clocks.
    #[serde(default)]
    pub external: bool,
    /// A run in motion's temporal metrics (its scene has an animation); `None` for a still
    /// scene.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temporal: Option<analysis::temporal::TemporalMetrics>,
    /// A run in motion's frames, each as `animate` records it (`frames.csv`); empty for a still
    /// scene.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub per_frame: Vec<crate::animation::FrameRecord>,
}

impl Row {
    /// The run's times on `clock` (wall time where CPU time was not measured).
    pub fn time(&self, clock: Clock) -> &Summary {
        match (clock, &self.cpu_ms) {
            (Clock::Cpu, Some(cpu)) => cpu,
            _ => &self.total_ms,
        }
    }

    /// Whether the row has a time: every method's run, an outside result when the suite gives
    /// its time ([`Report::untimed`] holds the others).
    pub fn timed(&self) -> bool {
        self.total_ms.n > 0
    }

    /// Whether the run was on a GPU (its parameters say `"device": "gpu"`).
    pub fn on_gpu(&self) -> bool {
        self.params.get("device").and_then(|d| d.as_str()) == Some("gpu")
    }

    /// A parameter as text, strings without their quotes (empty when the method has no such
    /// parameter).
    pub fn param(&self, key: &str) -> String {
        self.params
            .get(key)
            .map_or_else(String::new, |v| v.to_string().trim_matches('"').to_owned())
    }
}

/// One scene's shared work.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneInfo {
    /// Scene name.
    pub scene: String,
    /// Triangles.
    pub triangles: u64,
    /// Effects.
    pub effects: Vec<String>,
    /// Frame size.
    pub width: u32,
    /// Frame size.
    pub height: u32,
    /// Camera G-buffer wall time (shared by every method).
    pub gbuffer_ms: f64,
    /// Camera G-buffer CPU time.
    #[serde(default)]
    pub gbuffer_cpu_ms: Option<f64>,
    /// Reference used and its time.
    pub reference: String,
    /// Reference time.
    pub reference_ms: f64,
}

/// Everything a report is made of.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// The suite as run.
    pub suite: Suite,
    /// What produced the report (commit, version, command line, time, machine); its adapter
    /// is the GPU's when a method ran on one.
    pub provenance: Provenance,
    /// Where the times were taken.
    pub machine: Machine,
    /// The clock of the report's cost axis (charts, Pareto fronts, budgets, baselines).
    #[serde(default)]
    pub clock: Clock,
    /// Per-scene shared work.
    pub scenes: Vec<SceneInfo>,
    /// Every measured run.
    pub rows: Vec<Row>,
    /// Every run the papers' tables measured (times and counters; [`crate::tables::build`]
    /// makes the tables of them).
    #[serde(default)]
    pub table_runs: Vec<TableRun>,
    /// What could not run, and why.
    pub skipped: Vec<String>,
    /// Outside renderers' results without a time (a suite's `[[external]]` without
    /// `time_ms` for their scene): scored as the rows are, shown in the runs tables, kept
    /// out of everything that takes a time (charts, fronts, budgets, baselines); their
    /// `total_ms` has `n` = 0.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub untimed: Vec<Row>,
    /// Image grids, by title and file.
    pub grids: Vec<GridFile>,
    /// The papers' tables, measured.
    pub tables: Vec<Table>,
    /// What the reference cache did (`None` without a cache).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cache: Option<CacheStats>,
    /// The shards this report was run as: one for a shard's own report, every shard for a
    /// merged one, none for an unsharded one.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shards: Vec<ShardInfo>,
}

impl Report {
    /// The timed runs of `scene`, in report order.
    pub fn scene_rows(&self, scene: &str) -> Vec<&Row> {
        self.rows.iter().filter(|r| r.scene == scene).collect()
    }
}

/// Where and how one shard of a report ran.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShardInfo {
    /// The shard.
    pub shard: Shard,
    /// The plan's items it ran.
    pub items: Vec<usize>,
    /// What produced it.
    pub provenance: Provenance,
    /// Where its times were taken.
    pub machine: Machine,
    /// What its reference cache did.
    pub cache: Option<CacheStats>,
    /// Its wall time, seconds, from the start of the sweep to the last file written.
    pub wall_s: f64,
}

/// An image grid of a report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GridFile {
    /// The plan's item that drew it ([`crate::plan`]).
    #[serde(default)]
    pub item: usize,
    /// Scene.
    pub scene: String,
    /// Title.
    pub title: String,
    /// PNG file, relative to the report folder.
    pub png: String,
}

/// A grid's panels, to be written.
pub struct GridImages {
    /// Index into [`Report::grids`].
    pub grid: usize,
    /// The panels.
    pub panels: Vec<Panel>,
    /// The inset.
    pub inset: Region,
}

/// A visibility buffer a sweep produced, for the image outputs.
pub struct Produced {
    /// Index of its row in [`Report::rows`].
    pub row: usize,
    /// Index of its scene's images in [`Images::scenes`].
    pub scene: usize,
    /// The buffer.
    pub visibility: Visibility,
    /// The run record of its last timed run, as `render` writes it (`run.json`).
    pub record: RunRecord,
    /// Its comparison with the reference, as `compare` writes it (`metrics.json`).
    pub metrics: MetricsRecord,
    /// A run in motion's frames, for its run page's players; `None` for a still scene.
    pub motion: Option<MotionFrames>,
}

/// A run in motion's frames as PNG files' bytes, frame 0 first, one entry per frame in each.
pub struct MotionFrames {
    /// The method's shaded image (`crate::output::shade`).
    pub method: Vec<Vec<u8>>,
    /// The reference's shaded image.
    pub reference: Vec<Vec<u8>>,
    /// The error map over the compared pixels (`analysis::error_map::error_map` at its
    /// default scale).
    pub error: Vec<Vec<u8>>,
    /// How long a player shows each frame, milliseconds.
    pub frame_ms: u16,
}

/// A scene's reference, as the image outputs need it.
pub struct SceneImages {
    /// Index of the scene in [`Report::scenes`].
    pub scene: usize,
    /// The reference.
    pub reference: ReferenceImage,
    /// Each pixel's class (the reference's own, or the camera's view when it computes none).
    pub classes: Vec<PixelClass>,
    /// The pixels the metrics are taken over (the shadow-only pixels the reference evaluated,
    /// [`analysis::metrics::headline_pixels`]).
    pub compared: Vec<bool>,
}

/// What a sweep leaves for the image outputs beside the [`Report`]: every run's visibility
/// buffer, every scene's reference and classes, and the image grids' panels.
#[derive(Default)]
pub struct Images {
    /// Every run's visibility buffer.
    pub runs: Vec<Produced>,
    /// Every scene's reference.
    pub scenes: Vec<SceneImages>,
    /// The grids' panels.
    pub grids: Vec<GridImages>,
}

/// The row's method as charts and tables name it: an outside renderer's result is marked
/// `NAME (external)`.
pub fn method_label(row: &Row) -> String {
    if row.external {
        format!("{} (external)", row.method)
    } else {
        row.method.clone()
    }
}

/// The parameters every label names where a method has them (the ones the published
/// techniques sweep).
pub const LABEL_KEYS: [&str; 4] = ["map_res", "rate", "depth_bits", "pattern"];

/// The row's other parameters whose value is not the one its method takes by default with
/// the row's [`LABEL_KEYS`] (a swept bias, a method's own parameter; not a bias a depth
/// precision implies), as keys, in the record's order; the device aside.
pub fn other_params(row: &Row) -> Vec<&str> {
    let defaults = default_params(row);
    row.params
        .iter()
        .filter(|(k, v)| {
            let named = LABEL_KEYS.contains(&k.as_str()) || *k == "device";
            !named && defaults.as_ref().and_then(|d| d.get(*k)) != Some(*v)
        })
        .map(|(k, _)| k.as_str())
        .collect()
}

/// A short label of the row's parameters, e.g. `map_res=1024 rate=16`: the [`LABEL_KEYS`]
/// the method has, then its [`other_params`], then the device.
pub fn param_label(row: &Row) -> String {
    let mut keys: Vec<&str> =
        LABEL_KEYS.iter().copied().filter(|k| row.params.contains_key(*k)).collect();
    keys.extend(other_params(row));
    if row.params.contains_key("device") {
        keys.push("device");
    }
    keys.iter().map(|k| format!("{k}={}", row.param(k))).collect::<Vec<_>>().join(" ")
}

/// The parameters of the row's method built with the row's [`LABEL_KEYS`] and no other option
/// (the defaults those imply), as its run record holds them; `None` for a name no method or
/// reference has.
fn default_params(row: &Row) -> Option<serde_json::Map<String, serde_json::Value>> {
    type Defaults = BTreeMap<String, Option<serde_json::Map<String, serde_json::Value>>>;
    static DEFAULTS: std::sync::Mutex<Defaults> = std::sync::Mutex::new(BTreeMap::new());
    let params = analysis::registry::params_of(&row.method)?;
    let mut options = methods::MethodOptions::default();
    for key in LABEL_KEYS {
        let (Some(param), Some(v)) =
            (params.iter().find(|p| p.key == key), row.params.get(key).map(value_text))
        else {
            continue;
        };
        if let Ok(v) = param.parse(&v) {
            options.set(param, v);
        }
    }
    let key = format!("{} {:?}", row.method, options.given());
    let mut defaults = DEFAULTS.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    defaults
        .entry(key)
        .or_insert_with(|| {
            analysis::registry::technique(&row.method, &options).ok().map(|t| t.params())
        })
        .clone()
}

/// A scene's name as a file stem: ASCII letters, digits and `-` kept, the rest `_`.
pub fn scene_stem(scene: &str) -> String {
    scene.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' }).collect()
}

/// The file stem of a row's visibility buffer.
pub fn row_stem(row: &Row) -> String {
    let label = param_label(row).replace(['=', ' '], "-");
    let stem = [row.scene.as_str(), &row.method, &label]
        .into_iter()
        .filter(|s| !s.is_empty())
        .collect::<Vec<_>>()
        .join("-");
    stem.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' }).collect()
}

/// A parameter value as text (strings without their quotes).
pub fn value_text(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// A row's parameters as text, with the device (`cpu` or `gpu`) always present.
pub fn params_of(r: &Row) -> BTreeMap<String, String> {
    let mut p: BTreeMap<String, String> =
        r.params.iter().map(|(k, v)| (k.clone(), value_text(v))).collect();
    let device = if r.on_gpu() { "gpu" } else { "cpu" };
    p.insert("device".into(), device.into());
    p
}

/// The inset's region, as fractions of the frame: `[x, y, width, height]`.
pub type Region = [f64; 4];

/// One panel of a grid.
pub struct Panel {
    /// Label drawn above the panel.
    pub label: String,
    /// The image (all panels of a grid have the frame's size).
    pub image: RgbImage,
}
