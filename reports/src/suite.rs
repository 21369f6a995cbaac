//! Suites: which scenes, methods, parameters and frame size a report sweeps, read from a TOML
//! file that a user can copy and edit (`shadowbench report --suite FILE`). The built-in suites
//! live in `reports/suites/` and are compiled in.
//!
//! ```toml
//! name = "quick"
//! description = "every method on small frames"
//! width = 320
//! height = 240
//! warmup = 1        # untimed runs before the timed ones
//! repeats = 6       # timed runs at least (6: the fewest whose median has a 95 % interval)
//! max_repeats = 30  # timed runs at most (default: repeats): more are run while the interval
//! target = 0.05     # is wider than this share of the median (its half-width), until
//! time_cap_s = 20   # this many seconds of timed runs per frame have passed
//! clock = "cpu"     # the cost axis of charts, Pareto fronts, budgets and baselines: "cpu" or "wall"
//! reference = "auto" # exact where it applies (opaque casters), else raytrace at ref_rate; or "exact", "raytrace"
//! ref_rate = 64
//! scenes = ["plane-square", "cage"]
//! frames = 12       # resample every animated scene at this many frames (1..=1000); default:
//!                   # each scene's own count; still scenes ignore it
//!
//! [[run]]
//! method = "pcf-reeves"
//! map_res = [512, 1024]   # each list is swept; a run is every combination
//! rate = [4, 16]
//!
//! [[run]]
//! method = "pan09"
//! pattern = ["grid", "rotated"] # any parameter the method declares (`render --help`)
//! slope_bias = 2                # a single value is a list of one
//! width = [320, 640]            # frame sizes of this run: widths and heights paired,
//! height = [240, 480]           # each a frame of its own (default: the suite's)
//! device = ["cpu", "gpu"]
//!
//! [[table]]                  # a paper's table, see `tables`
//! paper = "lecocq-table2"
//!
//! [[external]]                # an outside renderer's results, scored like a method's runs
//! name = "my-renderer"        # its rows' method name (not a method of the workbench)
//! time_ms = 12.5              # its time on every scene, or a table: { cage = 12.5 }; absent:
//!                             # untimed (in the runs tables only, not in the cost charts)
//! [external.files]            # scene -> EXR of the suite's frame (one channel, the lit fraction,
//! plane-square = "out/plane-square.exr"  # see `shadowbench frame`); relative to this file
//! ```
//!
//! Unknown keys and bad values are errors that name the file and the key (and the line,
//! through the TOML parser).
//!
//! A scene whose animation is not still runs each `[[run]]` through every frame of its
//! animation (`crate::motion`); `frames` samples every such scene at that many frames.
//!
//! A `[[run]]` takes `method`, `device`, `width` and `height`, and the parameters its method
//! declares in the registry's table (`methods::registry::METHODS`, `methods::params`): a key
//! the method does not declare is refused with its line and the method's parameters, as the
//! command line notes it, so that no value of a suite is silently dropped.
//!
//! A suite is checked whole before anything runs ([`Suite::parse`]): every run's method with
//! every combination of its values is built as the sweep will build it (so a value the method
//! refuses is refused here, with the values it takes), every grid panel likewise, every scene
//! must be a built-in name or a scene file that loads, and the reference rate must suit
//! `raytrace`. Errors name the file, the key (`run[2].rate`) and, where the value is in the
//! file, its line; the line comes from a second pass of the TOML parser that keeps spans
//! ([`Spans`]), so the suite's own types stay plain. A built-in scene whose optional model
//! has not been fetched is the one thing left to the run, which lists it as not run.
//! An `[[external]]` entry's files must exist and be of the suite's scenes (their size is
//! checked when they are scored, a file of another size is listed as not run).

use crate::tables::TableSpec;
use instrumentation::measure::{Clock, Protocol};
use methods::{
    params::{Param, Value},
    registry::Device,
    MethodOptions,
};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// A suite could not be read.
#[derive(Debug, thiserror::Error)]
pub enum SuiteError {
    /// The file could not be read.
    #[error("cannot read suite {path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The file is not a valid suite (TOML syntax, unknown key, wrong type).
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// The parser's message, with line and key.
        message: String,
    },
    /// A value is out of range, or names a method or scene that does not exist.
    #[error("{path}: {}`{key}`: {message}", line.map_or(String::new(), |l| format!("line {l}: ")))]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The line of the value, when it is in the file.
        line: Option<usize>,
        /// The key.
        key: String,
        /// What is wrong.
        message: String,
    },
}

/// The largest frame width or height a suite (and the command line) takes.
pub const MAX_FRAME_SIDE: u32 = 16384;

/// The most pixels a frame may have: the G-buffer alone takes 60 bytes a pixel, and methods
/// and references keep a few buffers of the frame's size besides, so 2^25 pixels (8192 x
/// 4096) keep a run within a few GB.
pub const MAX_FRAME_PIXELS: u64 = 1 << 25;

/// The most sub-samples a method may keep in memory for one frame (pixels times
/// [`methods::registry::stored_samples`]): 2^27, about 5 GB of `afsm-ss` sampling points
/// (1920 x 1080 at 64 sub-samples fits, at 128 it does not).
pub const MAX_FRAME_SAMPLES: u64 = 1 << 27;

/// Checks a frame size against [`MAX_FRAME_SIDE`] and [`MAX_FRAME_PIXELS`], and the frame's
/// stored sub-samples (`samples` per pixel) against [`MAX_FRAME_SAMPLES`]; the error says
/// which limit and the values.
pub fn check_frame(width: u32, height: u32, samples: u32) -> Result<(), String> {
    for (what, v) in [("width", width), ("height", height)] {
        if !(1..=MAX_FRAME_SIDE).contains(&v) {
            return Err(format!("{what} must be in 1..={MAX_FRAME_SIDE}, got {v}"));
        }
    }
    let pixels = u64::from(width) * u64::from(height);
    if pixels > MAX_FRAME_PIXELS {
        return Err(format!(
            "a {width} x {height} frame has {pixels} pixels, more than the {MAX_FRAME_PIXELS} \
             (8192 x 4096) a run can hold in memory"
        ));
    }
    let stored = pixels * u64::from(samples);
    if stored > MAX_FRAME_SAMPLES {
        return Err(format!(
            "a {width} x {height} frame at {samples} stored sub-samples per pixel has {stored} \
             sub-samples, more than the {MAX_FRAME_SAMPLES} a run can hold in memory"
        ));
    }
    Ok(())
}

/// A span of bytes in a suite file.
type Span = std::ops::Range<usize>;

/// Makes the error for the value at a span of the file (none when the value is not in it),
/// under a key.
type ErrorAt<'a> = dyn Fn(Option<Span>, &str, String) -> SuiteError + 'a;

/// Where the values of a suite are in its file: the suite's keys with their spans, read by a
/// second pass of the TOML parser (keys not listed here are ignored by this pass).
#[derive(Debug, Default, Deserialize)]
struct Spans {
    #[serde(default)]
    scenes: Vec<Spanned<String>>,
    ref_rate: Option<Spanned<u32>>,
    frames: Option<Spanned<u32>>,
    #[serde(default, rename = "run")]
    runs: Vec<BTreeMap<String, Spanned<toml::Value>>>,
    #[serde(default, rename = "grid")]
    grids: Vec<GridSpans>,
    #[serde(default, rename = "table")]
    tables: Vec<TableSpans>,
    #[serde(default, rename = "external")]
    externals: Vec<ExternalSpans>,
}

/// The spans of an `[[external]]`.
#[derive(Debug, Default, Deserialize)]
struct ExternalSpans {
    name: Option<Spanned<String>>,
    #[serde(default)]
    files: std::collections::BTreeMap<String, Spanned<toml::Value>>,
    time_ms: Option<Spanned<toml::Value>>,
}

/// The spans of a `[[grid]]`.
#[derive(Debug, Default, Deserialize)]
struct GridSpans {
    #[serde(default)]
    panels: Vec<BTreeMap<String, Spanned<toml::Value>>>,
}

/// The spans of a `[[table]]`.
#[derive(Debug, Default, Deserialize)]
struct TableSpans {
    #[serde(default)]
    scenes: Vec<Spanned<String>>,
}

/// The suite key of a method option (`--map-res` -> `map_res`), `device` for `--device`, or
/// `method` for the others.
fn key_of(option: &str) -> &'static str {
    if option == "--device" {
        return "device";
    }
    methods::registry::all_params()
        .into_iter()
        .chain(analysis::registry::REFERENCE_PARAMS.iter().copied())
        .find(|p| p.flag == option)
        .map_or("method", |p| p.key)
}

/// Builds `method` with `options` as a sweep will. Building a GPU method opens no device, so
/// this checks `device = ["gpu"]` runs on machines without one too (they are then not run).
/// A build without GPU kernels (no `gpu` feature) checks a GPU run's CPU twin instead.
/// The error is the option at fault (`--method` when it is not an option) and what is wrong.
fn check_method(method: &str, options: &MethodOptions) -> Result<(), (&'static str, String)> {
    // A build without GPU kernels checks a GPU run's CPU twin: the run itself is reported as
    // not run, with the reason, and the suite's other runs go on.
    let cpu = MethodOptions { device: Device::Cpu, ..options.clone() };
    let options = if methods::registry::HAS_GPU { options } else { &cpu };
    match analysis::registry::technique(method, options) {
        Ok(_) => Ok(()),
        Err(methods::MethodError::InvalidOption { option, message }) => Err((option, message)),
        Err(e) => Err(("--method", e.to_string())),
    }
}

/// Whether `name` is a built-in scene or a scene file that loads; the error otherwise.
fn check_scene(name: &str) -> Result<(), String> {
    if scenes::registry::builtin(name).is_some() {
        return Ok(());
    }
    scenes::load(name).map(|_| ()).map_err(|e| e.to_string())
}

/// Which reference each scene is measured against.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ReferenceChoice {
    /// `exact` where the scene has no transparency (opaque casters), else `raytrace`.
    #[default]
    Auto,
    /// Always `exact` (scenes where it does not apply are reported as skipped).
    Exact,
    /// Always `raytrace` at `ref_rate`.
    Raytrace,
}

/// One method and the values to sweep: `device`, the frame sizes and any parameter the method
/// declares, each a value or a list; absent ones take the method's default (the suite's frame).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunSpec {
    /// Method name (see `shadowbench render --help`).
    pub method: String,
    /// Devices to run on (`cpu`, `gpu`); default the CPU only. With both, the report shows
    /// CPU and GPU times side by side.
    #[serde(default, deserialize_with = "one_or_many")]
    pub device: Vec<methods::registry::Device>,
    /// Frame widths, paired with `height`; default the suite's.
    #[serde(default, deserialize_with = "one_or_many")]
    pub width: Vec<u32>,
    /// Frame heights, paired with `width`.
    #[serde(default, deserialize_with = "one_or_many")]
    pub height: Vec<u32>,
    /// The method's parameters by key, each a value or a list of values (checked against the
    /// method's declared parameters by [`Suite::parse`]).
    #[serde(flatten)]
    pub params: BTreeMap<String, toml::Value>,
}

/// A value or a list of values, as a list.
fn one_or_many<'de, D, T>(d: D) -> Result<Vec<T>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum OneOrMany<T> {
        One(T),
        Many(Vec<T>),
    }
    Ok(match OneOrMany::deserialize(d)? {
        OneOrMany::One(v) => vec![v],
        OneOrMany::Many(v) => v,
    })
}

/// The values of the parameter `param` from a suite's `value` (a value or a list of values);
/// the error says what the parameter takes.
fn param_values(param: &'static Param, value: &toml::Value) -> Result<Vec<Value>, String> {
    let one = |v: &toml::Value| match v {
        toml::Value::Integer(i) => param.from_integer(*i),
        toml::Value::Float(f) => param.from_float(*f),
        toml::Value::String(s) => param.parse(s),
        other => Err(format!("{other} is not {}", param.expected())),
    };
    match value {
        toml::Value::Array(list) => list.iter().map(one).collect(),
        v => one(v).map(|v| vec![v]),
    }
}

/// The parameter called `key` that `method` declares.
fn declared(method: &str, key: &str) -> Option<&'static Param> {
    analysis::registry::params_of(method)?.iter().copied().find(|p| p.key == key)
}

/// Checks `params` (a run's or a panel's) against the parameters `method` declares and their
/// kinds: the key at fault and what is wrong. A method that does not exist passes: it is
/// refused itself, with the known ones.
fn check_declared(
    method: &str,
    params: &BTreeMap<String, toml::Value>,
) -> Result<(), (String, String)> {
    let Some(known) = analysis::registry::params_of(method) else { return Ok(()) };
    for (key, value) in params {
        let Some(param) = declared(method, key) else {
            let known: Vec<&str> = known.iter().map(|p| p.key).collect();
            let known = if known.is_empty() { "none".into() } else { known.join(", ") };
            let any = methods::registry::all_params().iter().any(|p| p.key == key);
            let what = if any { "does not use" } else { "has no parameter" };
            return Err((
                key.clone(),
                format!("`{method}` {what} `{key}`; its parameters: {known}"),
            ));
        };
        param_values(param, value).map_err(|m| (key.clone(), m))?;
    }
    Ok(())
}

/// Every combination of the values of `params` (each a value or a list) for `method`, in the
/// order of the keys, the last varying fastest; keys it does not declare are left out
/// ([`check_declared`] refuses them first).
fn combinations(method: &str, params: &BTreeMap<String, toml::Value>) -> Vec<MethodOptions> {
    let mut out = vec![MethodOptions::default()];
    for (key, value) in params {
        let Some(param) = declared(method, key) else { continue };
        let values = param_values(param, value).unwrap_or_default();
        if values.is_empty() {
            continue;
        }
        out = out
            .into_iter()
            .flat_map(|o| {
                values.iter().map(move |v| {
                    let mut o = o.clone();
                    o.set(param, *v);
                    o
                })
            })
            .collect();
    }
    out
}

impl RunSpec {
    /// Checks the keys against the method's declared parameters and the values against their
    /// kinds, and the frame sizes: the key at fault and what is wrong. [`Suite::parse`] runs it
    /// on every run.
    fn check_params(&self) -> Result<(), (String, String)> {
        check_declared(&self.method, &self.params)?;
        if self.width.len() != self.height.len() {
            return Err((
                "width".into(),
                format!(
                    "give as many heights as widths (paired into frame sizes), got {} and {}",
                    self.width.len(),
                    self.height.len()
                ),
            ));
        }
        Ok(())
    }

    /// The frame sizes of the run: `width` and `height` paired, or `None` (the suite's frame)
    /// when not given.
    pub fn sizes(&self) -> Vec<Option<(u32, u32)>> {
        if self.width.is_empty() {
            return vec![None];
        }
        self.width.iter().zip(&self.height).map(|(&w, &h)| Some((w, h))).collect()
    }

    /// The parameter combinations of one run spec (on each of its frame sizes), in the order of
    /// the keys, the last varying fastest, then the device. Values [`Suite::parse`] refused
    /// cannot arise; a key the method does not declare is left out.
    pub fn expand(&self) -> Vec<MethodOptions> {
        let out = combinations(&self.method, &self.params);
        let devices = if self.device.is_empty() { &[Device::Cpu][..] } else { &self.device };
        out.into_iter()
            .flat_map(|o| devices.iter().map(move |&device| MethodOptions { device, ..o.clone() }))
            .collect()
    }
}

/// One panel of an image grid: a method and its parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PanelSpec {
    /// Method name.
    pub method: String,
    /// Label; default: the method and its parameters.
    #[serde(default)]
    pub label: Option<String>,
    /// Show the pixel classes of `spsm` / `spsm-f32` in Lecocq et al.'s Fig. 14 colours
    /// (green: shadowed by the 3x3 neighbourhood, red: silhouette recovery) instead of the
    /// shaded result.
    #[serde(default)]
    pub classes: bool,
    /// The method's parameters by key (any it declares, as in a `[[run]]`), one value each.
    #[serde(flatten)]
    pub params: BTreeMap<String, toml::Value>,
}

impl PanelSpec {
    /// Checks the keys against the method's declared parameters, one value each.
    fn check_params(&self) -> Result<(), (String, String)> {
        if let Some((key, _)) = self.params.iter().find(|(_, v)| v.is_array()) {
            return Err((key.clone(), "a panel takes one value, not a list".into()));
        }
        check_declared(&self.method, &self.params)
    }

    /// The panel's options.
    pub fn options(&self) -> MethodOptions {
        combinations(&self.method, &self.params).pop().unwrap_or_default()
    }
}

/// An outside renderer's results on the suite's scenes (`[[external]]`), each scored against
/// its scene's reference like a method's run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExternalSpec {
    /// The renderer's name: its rows' method (letters, digits, `-`, `_`, `.`; not the name
    /// of one of the workbench's methods).
    pub name: String,
    /// For each scene of the suite it rendered, its EXR (one channel named `Y`, `L`, `lit` or
    /// `visibility`, the lit fraction in [0, 1], the suite's frame size,
    /// [`crate::external::read_visibility`]); relative paths are resolved against the suite
    /// file's folder when the suite is read.
    pub files: std::collections::BTreeMap<String, PathBuf>,
    /// Its time, milliseconds: one for every scene, or per scene; absent: untimed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_ms: Option<ExternalTime>,
}

/// An outside renderer's time (`[[external]]`'s `time_ms`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum ExternalTime {
    /// The same on every scene.
    All(f64),
    /// Per scene (scenes not listed are untimed).
    PerScene(std::collections::BTreeMap<String, f64>),
}

impl ExternalSpec {
    /// Its time on `scene`, milliseconds, when given.
    pub fn time_on(&self, scene: &str) -> Option<f64> {
        match &self.time_ms {
            Some(ExternalTime::All(t)) => Some(*t),
            Some(ExternalTime::PerScene(m)) => m.get(scene).copied(),
            None => None,
        }
    }
}

/// An image grid with a zoomed inset, like the papers' comparison figures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// Title (name the figure it reproduces).
    pub title: String,
    /// Scene (one of the suite's scenes).
    pub scene: String,
    /// The inset's region as fractions of the frame: `[x, y, width, height]`.
    pub inset: [f64; 4],
    /// The panels, left to right.
    pub panels: Vec<PanelSpec>,
    /// Also show the reference and the last panel's 10x error image (Pan et al. Fig. 8).
    #[serde(default)]
    pub reference: bool,
}

/// A suite.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Suite {
    /// Name, shown in the report.
    pub name: String,
    /// One line on what the suite is for.
    #[serde(default)]
    pub description: String,
    /// Frame width; 0 takes each scene's own.
    #[serde(default)]
    pub width: u32,
    /// Frame height; 0 takes each scene's own.
    #[serde(default)]
    pub height: u32,
    /// Untimed runs before the timed ones. Default 1.
    #[serde(default = "one")]
    pub warmup: u32,
    /// Timed runs at least. Default 6.
    #[serde(default = "six")]
    pub repeats: u32,
    /// Timed runs at most; default `repeats` (a fixed count). Above `repeats`, runs are timed
    /// again while their interval is wider than `target`, until `time_cap_s`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_repeats: Option<u32>,
    /// The half-width of a run's interval, relative to its median, at which it is timed
    /// enough. Default 0.05.
    #[serde(default = "target")]
    pub target: f64,
    /// Seconds of timed runs per scene after which runs with `repeats` timed runs stop.
    /// Default 20.
    #[serde(default = "time_cap_s")]
    pub time_cap_s: f64,
    /// The clock of the report's cost axis. Default CPU time.
    #[serde(default)]
    pub clock: Clock,
    /// Reference choice. Default `auto`.
    #[serde(default)]
    pub reference: ReferenceChoice,
    /// Sub-samples per pixel of the `raytrace` reference. Default 256.
    #[serde(default = "ref_rate")]
    pub ref_rate: u32,
    /// Built-in scene names or scene file paths.
    pub scenes: Vec<String>,
    /// The frames every animated scene is sampled at (`scenes::Animation::with_frames`), 1 to
    /// `scenes::MAX_FRAMES`; default each scene's own count. Still scenes ignore it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frames: Option<u32>,
    /// Methods and their sweeps.
    #[serde(rename = "run")]
    pub runs: Vec<RunSpec>,
    /// Image grids.
    #[serde(default, rename = "grid")]
    pub grids: Vec<GridSpec>,
    /// The papers' tables ([`crate::tables`]).
    #[serde(default, rename = "table")]
    pub tables: Vec<TableSpec>,
    /// Outside renderers' results ([`ExternalSpec`]).
    #[serde(default, rename = "external", skip_serializing_if = "Vec::is_empty")]
    pub externals: Vec<ExternalSpec>,
}

fn one() -> u32 {
    1
}
fn six() -> u32 {
    6
}
fn target() -> f64 {
    0.05
}
fn time_cap_s() -> f64 {
    20.0
}
fn ref_rate() -> u32 {
    256
}

/// The most timed runs a suite may ask for.
pub const MAX_REPEATS: u32 = 1000;

impl Suite {
    /// The timing protocol of the suite's runs ([`instrumentation::measure`]).
    pub fn protocol(&self) -> Protocol {
        Protocol {
            warmup: self.warmup,
            min_repeats: self.repeats,
            max_repeats: self.max_repeats.unwrap_or(self.repeats),
            target_half_width: self.target,
            clock: self.clock,
            time_cap: std::time::Duration::from_secs_f64(self.time_cap_s),
            ..Protocol::default()
        }
    }
}

/// The built-in suites: name and TOML text.
pub const BUILTIN_SUITES: &[(&str, &str)] = &[
    ("quick", include_str!("../suites/quick.toml")),
    ("papers", include_str!("../suites/papers.toml")),
    ("full", include_str!("../suites/full.toml")),
    ("temporal", include_str!("../suites/temporal.toml")),
];

impl Suite {
    /// Parses and checks suite `text`, naming `path` in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, SuiteError> {
        let mut suite: Suite = toml::from_str(text)
            .map_err(|e| SuiteError::Parse { path: path.to_owned(), message: e.to_string() })?;
        let spans: Spans = toml::from_str(text).unwrap_or_default();
        let line = |span: Option<Span>| {
            span.map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1)
        };
        let at = |span: Option<Span>, key: &str, message: String| SuiteError::Invalid {
            path: path.to_owned(),
            line: line(span),
            key: key.to_owned(),
            message,
        };
        let invalid = |key: &str, message: String| at(None, key, message);
        if suite.repeats == 0 {
            return Err(invalid("repeats", "must be at least 1".into()));
        }
        if suite.max_repeats.is_some_and(|m| m < suite.repeats || m > MAX_REPEATS) {
            return Err(invalid(
                "max_repeats",
                format!("must be in repeats..={MAX_REPEATS} ({}..={MAX_REPEATS})", suite.repeats),
            ));
        }
        if !(suite.target.is_finite() && suite.target > 0.0) {
            return Err(invalid("target", "must be a finite number > 0 (0.05 is 5 %)".into()));
        }
        if !(suite.time_cap_s.is_finite() && suite.time_cap_s >= 0.0) {
            return Err(invalid("time_cap_s", "must be a finite number of seconds >= 0".into()));
        }
        if (suite.width == 0) != (suite.height == 0) {
            return Err(invalid("width", "give both width and height, or neither".into()));
        }
        if suite.width != 0 {
            check_frame(suite.width, suite.height, 1).map_err(|m| invalid("width", m))?;
        }
        if suite.scenes.is_empty() {
            return Err(invalid("scenes", "must name at least one scene".into()));
        }
        if let Some(n) = suite.frames.filter(|n| !(1..=scenes::MAX_FRAMES).contains(n)) {
            return Err(at(
                spans.frames.as_ref().map(Spanned::span),
                "frames",
                format!("must be in 1..={}, got {n}", scenes::MAX_FRAMES),
            ));
        }
        if suite.runs.is_empty() {
            return Err(invalid("run", "must list at least one [[run]]".into()));
        }
        for (k, g) in suite.grids.iter().enumerate() {
            if !suite.scenes.contains(&g.scene) {
                return Err(invalid(
                    &format!("grid[{k}].scene"),
                    format!("`{}` is not one of the suite's scenes", g.scene),
                ));
            }
            if g.panels.is_empty() {
                return Err(invalid(&format!("grid[{k}].panels"), "must not be empty".into()));
            }
            let [x, y, w, h] = g.inset;
            if !((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y) && w > 0.0 && h > 0.0) {
                return Err(invalid(
                    &format!("grid[{k}].inset"),
                    "x and y in [0, 1), width and height > 0 (fractions of the frame)".into(),
                ));
            }
        }
        for (k, t) in suite.tables.iter().enumerate() {
            if (t.width == 0) != (t.height == 0)
                || (t.width != 0 && check_frame(t.width, t.height, 1).is_err())
            {
                return Err(invalid(
                    &format!("table[{k}].width"),
                    format!(
                        "give both width and height (at most {MAX_FRAME_SIDE} each, \
                         {MAX_FRAME_PIXELS} pixels), or neither"
                    ),
                ));
            }
        }
        suite.check_values(&spans, &at)?;
        let base = path.parent().unwrap_or(Path::new(""));
        for e in &mut suite.externals {
            for file in e.files.values_mut() {
                if file.is_relative() {
                    *file = base.join(&*file);
                }
            }
        }
        suite.check_externals(&spans, &at)?;
        Ok(suite)
    }

    /// Checks the `[[external]]` entries: names, scenes, files (their paths resolved from the
    /// suite file's folder) and times, as the module doc says.
    fn check_externals(&self, spans: &Spans, at: &ErrorAt<'_>) -> Result<(), SuiteError> {
        let plain = |c: char| c.is_ascii_alphanumeric() || "-_.".contains(c);
        for (k, e) in self.externals.iter().enumerate() {
            let span = spans.externals.get(k);
            let name_span = span.and_then(|s| s.name.as_ref().map(Spanned::span));
            let key = |sub: &str| format!("external[{k}].{sub}");
            if e.name.is_empty() || !e.name.chars().all(plain) || e.name.starts_with('.') {
                let message = "use letters, digits, `-`, `_` and `.` (not first)".to_owned();
                return Err(at(name_span, &key("name"), message));
            }
            let taken = methods::registry::METHODS.iter().any(|m| m.name == e.name)
                || analysis::registry::REFERENCES.iter().any(|(m, _)| *m == e.name)
                || self.externals[..k].iter().any(|o| o.name == e.name);
            if taken {
                let message = format!("`{}` is already the name of a method or entry", e.name);
                return Err(at(name_span, &key("name"), message));
            }
            if e.files.is_empty() {
                return Err(at(name_span, &key("files"), "must name at least one scene".into()));
            }
            for (scene, file) in &e.files {
                let file_span = span.and_then(|s| s.files.get(scene).map(Spanned::span));
                let key = key(&format!("files.{scene}"));
                if !self.scenes.contains(scene) {
                    let message = format!("`{scene}` is not one of the suite's scenes");
                    return Err(at(file_span, &key, message));
                }
                if !file.is_file() {
                    let message = format!(
                        "{} is not a file (relative paths are taken from the suite file's folder)",
                        file.display()
                    );
                    return Err(at(file_span, &key, message));
                }
            }
            let time_span = span.and_then(|s| s.time_ms.as_ref().map(Spanned::span));
            let times: Vec<(Option<&String>, f64)> = match &e.time_ms {
                Some(ExternalTime::All(t)) => vec![(None, *t)],
                Some(ExternalTime::PerScene(m)) => m.iter().map(|(s, t)| (Some(s), *t)).collect(),
                None => Vec::new(),
            };
            for (scene, t) in times {
                if !(t.is_finite() && t >= 0.0) {
                    let message = format!("{t} is not a time (a finite number >= 0)");
                    return Err(at(time_span, &key("time_ms"), message));
                }
                if let Some(scene) = scene.filter(|s| !e.files.contains_key(*s)) {
                    let message = format!("`{scene}` has no file in `files`");
                    return Err(at(time_span, &key("time_ms"), message));
                }
            }
        }
        Ok(())
    }

    /// Checks what the runs take: methods and their values, grid panels, scenes and the
    /// reference rate, as the module doc says.
    fn check_values(&self, spans: &Spans, at: &ErrorAt<'_>) -> Result<(), SuiteError> {
        if self.reference != ReferenceChoice::Exact {
            analysis::registry::reference("raytrace", self.ref_rate, Default::default()).map_err(
                |e| {
                    let message = match e {
                        analysis::reference::ReferenceError::InvalidOption { message, .. } => {
                            message
                        }
                        other => other.to_string(),
                    };
                    at(spans.ref_rate.as_ref().map(Spanned::span), "ref_rate", message)
                },
            )?;
        }
        for (k, spec) in self.runs.iter().enumerate() {
            let span = spans.runs.get(k);
            let span_of = |key: &str| span.and_then(|s| s.get(key)).map(Spanned::span);
            // The method, then its keys, then every combination built as the sweep builds it.
            let method_span = span_of("method");
            check_method(&spec.method, &MethodOptions::default()).map_err(|(option, m)| {
                let key = key_of(option);
                let span = if key == "method" { method_span.clone() } else { span_of(key) };
                at(span, &format!("run[{k}].{key}"), m)
            })?;
            spec.check_params()
                .map_err(|(key, m)| at(span_of(&key), &format!("run[{k}].{key}"), m))?;
            for options in spec.expand() {
                if let Err((option, message)) = check_method(&spec.method, &options) {
                    let key = key_of(option);
                    let span = span_of(key).or_else(|| method_span.clone());
                    return Err(at(span, &format!("run[{k}].{key}"), message));
                }
                let samples = methods::registry::stored_samples(&spec.method, &options);
                for size in spec.sizes() {
                    let (key, (w, h)) = match size {
                        Some(size) => ("width", size),
                        None if self.width != 0 => ("rate", (self.width, self.height)),
                        None => continue,
                    };
                    check_frame(w, h, samples)
                        .map_err(|m| at(span_of(key), &format!("run[{k}].{key}"), m))?;
                }
            }
        }
        for (k, grid) in self.grids.iter().enumerate() {
            for (j, p) in grid.panels.iter().enumerate() {
                let span = spans.grids.get(k).and_then(|g| g.panels.get(j));
                let span_of = |key: &str| span.and_then(|s| s.get(key)).map(Spanned::span);
                let prefix = format!("grid[{k}].panels[{j}]");
                p.check_params()
                    .map_err(|(key, m)| at(span_of(&key), &format!("{prefix}.{key}"), m))?;
                let checked = if p.classes && !matches!(p.method.as_str(), "spsm" | "spsm-f32") {
                    Err((
                        "--method",
                        "`classes` shows the pixel classes of spsm or spsm-f32 only".to_owned(),
                    ))
                } else {
                    check_method(&p.method, &p.options())
                };
                if let Err((option, message)) = checked {
                    let key = key_of(option);
                    let span = span_of(key).or_else(|| span_of("method"));
                    return Err(at(span, &format!("{prefix}.{key}"), message));
                }
            }
        }
        let scene_lists = std::iter::once(("scenes".to_owned(), &self.scenes, &spans.scenes[..]))
            .chain(self.tables.iter().enumerate().map(|(k, t)| {
                let spans = spans.tables.get(k).map_or(&[][..], |t| &t.scenes[..]);
                (format!("table[{k}].scenes"), &t.scenes, spans)
            }));
        for (key, names, spans) in scene_lists {
            for (j, name) in names.iter().enumerate() {
                check_scene(name).map_err(|m| {
                    let span = spans.get(j).map(Spanned::span);
                    at(span, &format!("{key}[{j}]"), m)
                })?;
            }
        }
        Ok(())
    }

    /// A built-in suite by name, or a suite file by path.
    pub fn load(name_or_path: &str) -> Result<Self, SuiteError> {
        if let Some((name, text)) = BUILTIN_SUITES.iter().find(|(n, _)| *n == name_or_path) {
            return Self::parse(text, Path::new(&format!("built-in suite `{name}`")));
        }
        let path = Path::new(name_or_path);
        let text = std::fs::read_to_string(path).map_err(|e| SuiteError::Io {
            path: path.to_owned(),
            message: if e.kind() == std::io::ErrorKind::NotFound {
                format!(
                    "no such file, and not a built-in suite ({})",
                    BUILTIN_SUITES.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
                )
            } else {
                e.to_string()
            },
        })?;
        Self::parse(&text, path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_expand_to_every_combination() {
        let spec: RunSpec = toml::from_str(
            "method = \"pcf-bs-fast-2x2\"\nmap_res = [256, 512]\ndepth_bits = [8, 12, 32]\n",
        )
        .expect("parses");
        let all = spec.expand();
        assert_eq!(all.len(), 6);
        assert!(all.iter().all(|o| o.rate.is_none() && o.device == Device::Cpu));
        assert_eq!(all[5].map_res, Some(512));
        assert_eq!(all[5].depth_bits, Some(32));
        let both = RunSpec { device: vec![Device::Cpu, Device::Gpu], ..spec }.expand();
        assert_eq!(both.len(), 12);
        assert_eq!((both[0].device, both[1].device), (Device::Cpu, Device::Gpu));
        assert_eq!(both[0].depth_bits, both[1].depth_bits);
    }

    #[test]
    fn builtin_suites_parse() {
        for (name, _) in BUILTIN_SUITES {
            let s = Suite::load(name).expect("built-in parses");
            assert_eq!(&s.name, name);
        }
    }

    #[test]
    fn errors_name_the_key() {
        let p = Path::new("s.toml");
        let base = "name = \"x\"\nscenes = [\"cage\"]\n[[run]]\nmethod = \"sm\"\n";
        let e = Suite::parse(&format!("{base}colour = 3\n"), p).expect_err("unknown key");
        assert!(e.to_string().contains("colour"), "{e}");
        let e = Suite::parse(&format!("repeats = 0\n{base}"), p).expect_err("zero repeats");
        assert!(e.to_string().contains("repeats"), "{e}");
        let e = Suite::parse(&format!("{base}map_res = \"big\"\n"), p).expect_err("bad type");
        assert!(e.to_string().contains("map_res"), "{e}");
        assert!(Suite::parse(base, p).is_ok());
        let grid = "[[grid]]\ntitle = \"g\"\nscene = \"spheres\"\ninset = [0.1, 0.1, 0.2, 0.2]\n\
                    panels = [{ method = \"sm\" }]\n";
        let e = Suite::parse(&format!("{base}{grid}"), p).expect_err("scene not in the suite");
        assert!(e.to_string().contains("grid[0].scene"), "{e}");
        let grid = grid.replace("spheres", "cage").replace("[0.1, 0.1", "[1.5, 0.1");
        let e = Suite::parse(&format!("{base}{grid}"), p).expect_err("inset outside");
        assert!(e.to_string().contains("grid[0].inset"), "{e}");
        let e = Suite::parse(&format!("{base}[[table]]\npaper = \"table-9\"\n"), p)
            .expect_err("unknown table");
        assert!(e.to_string().contains("table-9"), "{e}");
        let e =
            Suite::parse(&format!("{base}[[table]]\npaper = \"lecocq-table2\"\nwidth = 64\n"), p)
                .expect_err("width without height");
        assert!(e.to_string().contains("table[0].width"), "{e}");
        let e = Suite::load("/no/such/suite.toml").expect_err("missing");
        assert!(e.to_string().contains("quick"), "{e}");
    }

    /// What the runs take is checked before anything runs: every error names the file, the
    /// line of the value, the key and what is allowed.
    #[test]
    fn methods_values_and_scenes_are_checked_with_their_line() {
        let p = Path::new("s.toml");
        let suite = |scenes: &str, run: &str, rest: &str| {
            format!("name = \"x\"\nscenes = {scenes}\n[[run]]\n{run}\n{rest}")
        };
        let ok = suite("[\"cage\"]", "method = \"pan09\"\nrate = [4, 32]", "");
        assert!(Suite::parse(&ok, p).is_ok());
        let panel = "[[grid]]\ntitle = \"g\"\nscene = \"cage\"\ninset = [0.1, 0.1, 0.2, 0.2]\n\
                     panels = [{ method = \"sm\" }, { method = \"sm\", map_res = 0 }]\n";
        let table = "[[table]]\npaper = \"aila-laine-table1\"\nscenes = [\"cage\", \"nowhere\"]\n";
        let cases: &[(String, &str, &[&str])] = &[
            (suite("[\"cage\"]", "method = \"magic\"", ""), "line 4: `run[0].method`", &["pan09"]),
            (
                suite("[\"cage\"]", "method = \"pan09\"\nrate = [4, 0]", ""),
                "line 5: `run[0].rate`",
                &["takes 1, 4, 8, 16, 32, 64, 128 samples", "got 0"],
            ),
            (
                suite("[\"cage\"]", "method = \"sm\"\nmap_res = [0]", ""),
                "line 5: `run[0].map_res`",
                &["1..=16384"],
            ),
            (
                suite("[\"cage\", \"no-such-scene\"]", "method = \"sm\"", ""),
                "line 2: `scenes[1]`",
                &["no-such-scene", "plane-square"],
            ),
            (
                suite("[\"cage\"]", "method = \"sm\"", panel),
                "line 9: `grid[0].panels[1].map_res`",
                &["1..=16384"],
            ),
            (
                suite("[\"cage\"]", "method = \"sm\"", table),
                "line 7: `table[0].scenes[1]`",
                &["nowhere"],
            ),
            (
                format!("ref_rate = 3\n{}", suite("[\"cage\"]", "method = \"sm\"", "")),
                "line 1: `ref_rate`",
                &["1, 4, 8"],
            ),
        ];
        // Every technique has GPU kernels; a build without any checks the CPU twin, and the
        // run is reported as not run.
        let gpu = suite("[\"cage\"]", "method = \"afsm-ss\"\ndevice = [\"gpu\"]", "");
        assert!(Suite::parse(&gpu, p).is_ok());
        for (text, at, needles) in cases {
            let e = Suite::parse(text, p).expect_err(at).to_string();
            assert!(e.starts_with("s.toml: ") && e.contains(at), "{at}: {e}");
            for n in *needles {
                assert!(e.contains(n), "{at}: `{n}` not in {e}");
            }
        }
    }

    /// Any declared parameter sweeps, as a value or a list, and frame sizes pair widths with
    /// heights; a parameter the method does not declare is refused with its line.
    #[test]
    fn any_declared_parameter_sweeps_and_others_are_refused_with_their_line() {
        let p = Path::new("s.toml");
        let base = "name = \"x\"\nscenes = [\"cage\"]\n[[run]]\n";
        let run = "method = \"pan09\"\npattern = [\"grid\", \"rotated\"]\nslope_bias = [1, 2.5]\n\
                   masks = \"exact\"\nwidth = [64, 32]\nheight = [48, 24]\n";
        let s = Suite::parse(&format!("{base}{run}"), p).expect("parses");
        let spec = &s.runs[0];
        assert_eq!(spec.sizes(), vec![Some((64, 48)), Some((32, 24))]);
        let all = spec.expand();
        assert_eq!(all.len(), 4);
        assert!(all.iter().all(|o| o.visibility == Some(methods::pan09::VisibilityMode::Exact)));
        let combos: Vec<(Option<_>, Option<f64>)> =
            all.iter().map(|o| (o.pattern, o.slope_bias)).collect();
        use methods::pattern::PatternKind::{Grid, Rotated};
        assert_eq!(
            combos,
            vec![
                (Some(Grid), Some(1.0)),
                (Some(Grid), Some(2.5)),
                (Some(Rotated), Some(1.0)),
                (Some(Rotated), Some(2.5))
            ]
        );
        let cases: &[(&str, &str, &[&str])] = &[
            ("method = \"sm\"\nrate = [4]", "line 5: `run[0].rate`", &["`sm` does not use `rate`"]),
            ("method = \"sm\"\ncolour = 3", "line 5: `run[0].colour`", &["has no parameter"]),
            (
                "method = \"sm\"\npattern = \"spiral\"",
                "line 5: `run[0].pattern`",
                &["does not use"],
            ),
            (
                "method = \"pan09\"\npattern = \"spiral\"",
                "line 5: `run[0].pattern`",
                &["grid, rotated"],
            ),
            (
                "method = \"sm\"\nwidth = [64, 32]\nheight = [48]",
                "`run[0].width`",
                &["as many heights as widths"],
            ),
            ("method = \"sm\"\nwidth = 0\nheight = 8", "line 5: `run[0].width`", &["1..="]),
        ];
        for (run, at, needles) in cases {
            let e = Suite::parse(&format!("{base}{run}\n"), p).expect_err(at).to_string();
            assert!(e.contains(at), "{at}: {e}");
            for n in *needles {
                assert!(e.contains(n), "{at}: `{n}` not in {e}");
            }
        }
    }

    /// A grid's panels take any parameter their method declares, one value each.
    #[test]
    fn panels_take_declared_parameters_one_value_each() {
        let p = Path::new("s.toml");
        let suite = |panel: &str| {
            format!(
                "name = \"x\"\nscenes = [\"cage\"]\n[[run]]\nmethod = \"sm\"\n[[grid]]\n\
                 title = \"g\"\nscene = \"cage\"\ninset = [0.1, 0.1, 0.2, 0.2]\n\
                 panels = [\n{panel},\n]\n"
            )
        };
        let ok = Suite::parse(&suite("{ method = \"pan09\", pattern = \"rotated\", rate = 8 }"), p)
            .expect("parses");
        let o = ok.grids[0].panels[0].options();
        assert_eq!((o.pattern, o.rate), (Some(methods::pattern::PatternKind::Rotated), Some(8)));
        for (panel, at, needle) in [
            ("{ method = \"sm\", rate = 4 }", "line 10: `grid[0].panels[0].rate`", "does not use"),
            (
                "{ method = \"pan09\", pattern = [\"grid\"] }",
                "line 10: `grid[0].panels[0].pattern`",
                "one value",
            ),
        ] {
            let e = Suite::parse(&suite(panel), p).expect_err(at).to_string();
            assert!(e.contains(at) && e.contains(needle), "{at}: {e}");
        }
    }

    /// `[[external]]` entries: files relative to the suite's folder, times per scene or one;
    /// every error names the file, the line and the key.
    #[test]
    fn external_entries_are_checked_with_their_line() {
        let dir = tempfile::tempdir().expect("tempdir");
        std::fs::write(dir.path().join("cage.exr"), b"").expect("writes");
        let p = dir.path().join("s.toml");
        let suite = |external: &str| {
            format!(
                "name = \"x\"\nscenes = [\"cage\", \"plane-square\"]\n[[run]]\nmethod = \"sm\"\n\
                 [[external]]\n{external}\n"
            )
        };
        let ok = Suite::parse(
            &suite("name = \"mine\"\ntime_ms = { cage = 3 }\nfiles = { cage = \"cage.exr\" }"),
            &p,
        )
        .expect("parses");
        let e = &ok.externals[0];
        assert_eq!(e.files["cage"], dir.path().join("cage.exr"), "resolved beside the suite");
        assert_eq!((e.time_on("cage"), e.time_on("plane-square")), (Some(3.0), None));
        let one = suite("name = \"mine\"\ntime_ms = 4.5\nfiles = { cage = \"cage.exr\" }");
        assert_eq!(Suite::parse(&one, &p).expect("parses").externals[0].time_on("cage"), Some(4.5));
        let cases: &[(&str, &str, &[&str])] = &[
            (
                "name = \"sm\"\nfiles = { cage = \"cage.exr\" }",
                "line 6: `external[0].name`",
                &["`sm`"],
            ),
            (
                "name = \"a b\"\nfiles = { cage = \"cage.exr\" }",
                "line 6: `external[0].name`",
                &["letters"],
            ),
            (
                "name = \"mine\"\nfiles = { spheres = \"cage.exr\" }",
                "line 7: `external[0].files.spheres`",
                &["not one of the suite's scenes"],
            ),
            (
                "name = \"mine\"\nfiles = { cage = \"missing.exr\" }",
                "line 7: `external[0].files.cage`",
                &["missing.exr", "is not a file"],
            ),
            (
                "name = \"mine\"\ntime_ms = -1\nfiles = { cage = \"cage.exr\" }",
                "line 7: `external[0].time_ms`",
                &["-1"],
            ),
            (
                "name = \"mine\"\ntime_ms = { plane-square = 1 }\nfiles = { cage = \"cage.exr\" }",
                "line 7: `external[0].time_ms`",
                &["plane-square", "no file"],
            ),
        ];
        for (entry, at, needles) in cases {
            let e = Suite::parse(&suite(entry), &p).expect_err(at).to_string();
            assert!(e.starts_with(&format!("{}: ", p.display())) && e.contains(at), "{at}: {e}");
            for n in *needles {
                assert!(e.contains(n), "{at}: `{n}` not in {e}");
            }
        }
    }

    /// `frames` resamples the animated scenes; outside 1..=MAX_FRAMES it is refused with its
    /// line.
    #[test]
    fn frames_are_checked_with_their_line() {
        let p = Path::new("s.toml");
        let text = |frames: &str| {
            format!("name = \"x\"\nscenes = [\"cage-sweep\"]\n{frames}\n[[run]]\nmethod = \"sm\"\n")
        };
        assert_eq!(Suite::parse(&text("frames = 4"), p).expect("parses").frames, Some(4));
        assert_eq!(Suite::parse(&text(""), p).expect("parses").frames, None);
        for bad in ["frames = 0", "frames = 1001"] {
            let e = Suite::parse(&text(bad), p).expect_err(bad).to_string();
            assert!(e.contains("line 3: `frames`") && e.contains("1..=1000"), "{bad}: {e}");
        }
        let e = Suite::parse(&text("frames = -2"), p).expect_err("negative").to_string();
        assert!(e.contains("frames") && e.contains("line 3"), "{e}");
    }

    #[test]
    fn frames_beyond_the_limits_are_refused_with_the_limit() {
        assert!(check_frame(8192, 4096, 1).is_ok());
        assert!(check_frame(16384, 1, 1).is_ok());
        assert!(check_frame(1920, 1080, 64).is_ok());
        let e = check_frame(16384, 16384, 1).expect_err("too many pixels");
        assert!(e.contains(&MAX_FRAME_PIXELS.to_string()), "{e}");
        let e = check_frame(1920, 1080, 128).expect_err("too many sub-samples");
        assert!(e.contains(&MAX_FRAME_SAMPLES.to_string()) && e.contains("128"), "{e}");
        let e = check_frame(0, 10, 1).expect_err("empty");
        assert!(e.contains("width") && e.contains("16384"), "{e}");
    }
}
