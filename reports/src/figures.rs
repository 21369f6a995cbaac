//! The figures of a report: which charts are drawn from which runs ([`charts`]), written as
//! PNG and SVG into `plots/` by [`crate::plots`].
//!
//! Cost is a run's time on the report's clock ([`Report::clock`]: CPU time by default,
//! [`Row::time`]), and every axis, table and sentence says which clock it is.
//!
//! A chart holds at most [`MAX_SERIES`] coloured series. Methods are drawn by family
//! ([`family_of`]: shadow maps and PCF, Brabec & Seidel's packed PCF, alias-free and sub-pixel
//! maps), each family on charts of its own (small multiples), a family with more series over
//! more charts, a method's series kept together where they fit on one.
//!
//! Per scene and family:
//! - **error against time**: one series per method, device and fixed parameters (the
//!   light-frustum policy `frustum` among them where it varies, never swept), its points
//!   joined in the order of the parameter the series sweeps (the one with the most values
//!   among that method's runs) and labelled with its value (`512`, `32x`; labels that would
//!   collide are left out); a horizontal bar spans each run's [min, max] time; the scene's
//!   other runs are grey dots behind them, and the scene's Pareto front, over all its runs, is
//!   drawn;
//! - **error against shadow-map size** and **error against sample rate** (and time against
//!   rate), one series per method, device and other parameters, where a series has two points
//!   or more.
//!
//! Per scene, the **error distribution of the Pareto runs**: for each run on the front (at most
//! [`MAX_SERIES`], evenly spread along it from the fastest to the most accurate), the share of
//! the shadow-only pixels whose error exceeds x, at the thresholds of
//! `analysis::metrics::EXCEEDANCE_THRESHOLDS` (log-log: the tail of large errors stays visible
//! beside the many small ones; at x = 0.5/255 the share is one minus the pixel match).
//!
//! Across scenes, **best error within a time budget**: per scene a panel, per method the least
//! error among its runs whose median time fits each budget of [`BUDGETS_MS`]; the figure draws
//! the methods that are best within some budget on some scene ([`budget_methods`], at most
//! [`MAX_SERIES`]), and the report's tables give every method.
//!
//! Per cost-against-work table (`crate::tables`), its log-log chart of time against work
//! (`plots/cost-against-triangles.png`, `plots/cost-against-pixels.png`), which the page shows
//! under the table.
//!
//! The error is the shadow-only headline (planar and surface pixels, see `analysis::metrics`).
//! GPU runs are separate series marked with triangles, named with the adapter, and a software
//! adapter (llvmpipe, lavapipe) is said to be one.

use crate::model::{method_label, Report, Row};
use crate::output::OutputError;
pub use crate::plots::MAX_SERIES;
use crate::plots::{pareto_front, write_chart, Chart, Marker, Point, Series};
use analysis::metrics::EXCEEDANCE_THRESHOLDS;
use instrumentation::measure::Clock;
use instrumentation::stats::Summary;
use plotters::prelude::*;
use std::path::Path;

/// The time budgets of the summary figure, in milliseconds.
pub const BUDGETS_MS: [f64; 4] = [10.0, 30.0, 100.0, 300.0];

/// The parameters a series may sweep or hold fixed, in the order they are named (`filter`:
/// the filtered maps' box filter width).
const PARAMS: [&str; 5] = ["map_res", "rate", "depth_bits", "pattern", "filter"];

/// Parameters that name a series (and a run in [`params_text`]) where they vary but are never
/// swept along one, their values having no order: the light-frustum policy of the shadow-map
/// methods.
const NAMING: [&str; 1] = ["frustum"];

/// A clock's name in an axis, a column or a sentence: `CPU` or `wall`.
pub fn clock_name(clock: Clock) -> &'static str {
    match clock {
        Clock::Cpu => "CPU",
        Clock::Wall => "wall",
    }
}

/// A family of methods, drawn on charts of its own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Family {
    /// The family in a file name (`error-vs-time-cage-pcf`).
    pub slug: &'static str,
    /// The family in a title.
    pub name: &'static str,
}

/// The families, in the order their charts come.
pub const FAMILIES: [Family; 4] = [
    Family { slug: "pcf", name: "shadow maps and PCF" },
    Family { slug: "bs", name: "Brabec & Seidel's packed PCF" },
    Family { slug: "subpixel", name: "alias-free and sub-pixel maps" },
    Family { slug: "other", name: "other methods" },
];

/// The family of a method: `sm` and the filters that sample the map (`pcf-reeves`,
/// `pcf-gems*`), Brabec & Seidel's depth-as-colour filters (`pcf-bs-*`), the alias-free and
/// sub-pixel methods (`afsm*`, `spsm*`, `pan09`), and the rest (a reference run as a method).
pub fn family_of(method: &str) -> Family {
    let k = if method.starts_with("pcf-bs") {
        1
    } else if method == "sm" || method.starts_with("pcf") {
        0
    } else if method.starts_with("afsm") || method.starts_with("spsm") || method == "pan09" {
        2
    } else {
        3
    };
    FAMILIES[k]
}

/// A chart written for a report.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotFile {
    /// Scene it belongs to (empty for a figure across scenes).
    pub scene: String,
    /// Title.
    pub title: String,
    /// File name of the PNG, relative to the report folder (the SVG is beside it).
    pub png: String,
    /// Where the index and `report.md` show it.
    pub place: Place,
}

/// Where the index and `report.md` show a chart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Place {
    /// With its scene's other charts (a figure across scenes: under the budgets).
    Scene,
    /// In its scene's "In motion" section: the runs in motion (`crate::motion_charts`).
    Motion,
    /// In the section "Against today's techniques" (`crate::today`).
    Today,
}

impl PlotFile {
    /// The SVG beside the PNG.
    pub fn svg(&self) -> String {
        self.png.trim_end_matches(".png").to_owned() + ".svg"
    }
}

/// One chart of a scene, to be drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneChart {
    /// The scene.
    pub scene: String,
    /// File stem in `plots/`.
    pub stem: String,
    /// What to draw.
    pub chart: Chart,
    /// Said after the title in the figure's caption (the runs a chart leaves out); empty for
    /// nothing.
    pub note: String,
}

/// A run on the Pareto front.
#[derive(Debug, Clone, PartialEq)]
pub struct ParetoEntry {
    /// Method.
    pub method: String,
    /// Its parameters, as `map_res=1024 rate=16 device=gpu`.
    pub params: String,
    /// Its times on the report's clock.
    pub time: Summary,
    /// Median wall time, milliseconds.
    pub wall_ms: f64,
    /// Shadow-only mean absolute error.
    pub error: f64,
    /// Whether a timed run was contended.
    pub contended: bool,
}

/// What a measure of a row is, for the charts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Measure {
    /// Mean absolute error on the shadow-only pixels.
    MeanError,
    /// Median total time of the method's stages on a clock.
    Time(Clock),
    /// A parameter of the method (`map_res`, `rate`).
    Param(&'static str),
    /// A run in motion's temporal error: the mean over its pixel pairs
    /// (`analysis::temporal`); none for a still scene's run.
    TemporalError,
}

impl Measure {
    /// The row's value of this measure.
    pub fn of(self, row: &Row) -> Option<f64> {
        match self {
            Measure::MeanError => Some(row.metrics.mean_abs_error),
            Measure::Time(clock) => Some(row.time(clock).median),
            Measure::Param(key) => row.params.get(key).and_then(serde_json::Value::as_f64),
            Measure::TemporalError => row.temporal.as_ref().and_then(|t| t.mean),
        }
    }

    /// Axis label with unit.
    pub fn label(self) -> String {
        match self {
            Measure::MeanError => "mean absolute error, shadow-only pixels (lit fraction)".into(),
            Measure::Time(clock) => {
                format!("{} time, median with [min, max] (ms)", clock_name(clock))
            }
            Measure::Param("map_res") => "shadow map resolution (texels per side)".into(),
            Measure::Param("rate") => "samples per pixel".into(),
            Measure::Param(k) => k.into(),
            Measure::TemporalError => {
                "temporal error, mean over pixel pairs (change of lit fraction)".into()
            }
        }
    }
}

/// A point's label: the value of the parameter its series sweeps (`32x` for a rate).
fn point_label(row: &Row, key: &str) -> String {
    match (key, row.param(key)) {
        (_, v) if v.is_empty() => String::new(),
        ("rate", v) => format!("{v}x"),
        ("depth_bits", v) => format!("{v} bits"),
        (_, v) => v,
    }
}

/// The device part of a series' name: empty on the CPU, `gpu (ADAPTER)` on a GPU, with
/// `software` when the adapter is one.
fn device_label(row: &Row, adapter: Option<&str>) -> String {
    if row.param("device") != "gpu" {
        return String::new();
    }
    // The adapter's name without its details in parentheses (`llvmpipe (LLVM 15.0.6, 256
    // bits)` is `llvmpipe`); the report's header gives the whole name.
    match adapter.map(|a| (a, a.split(" (").next().unwrap_or(a).trim())) {
        Some((a, short)) if crate::devices::is_software_adapter(a) => {
            format!("gpu ({short}, software)")
        }
        Some((_, short)) => format!("gpu ({short})"),
        None => "gpu".into(),
    }
}

/// How many values parameter `key` takes over the runs of `method`.
fn values_of(rows: &[&Row], method: &str, key: &str) -> usize {
    let mut v: Vec<String> =
        rows.iter().filter(|r| r.method == method).map(|r| r.param(key)).collect();
    v.sort();
    v.dedup();
    v.len()
}

/// Whether parameter `key` takes more than one value over the runs of `method`.
fn varies(rows: &[&Row], method: &str, key: &str) -> bool {
    values_of(rows, method, key) > 1
}

/// The parameter the runs of `method` sweep most: the one with the most distinct values (the
/// first of [`PARAMS`] on a tie).
fn swept(rows: &[&Row], method: &str) -> Option<&'static str> {
    let mut best: Option<(&'static str, usize)> = None;
    for &k in &PARAMS {
        let n = values_of(rows, method, k);
        if n > 1 && best.is_none_or(|(_, m)| n > m) {
            best = Some((k, n));
        }
    }
    best.map(|(k, _)| k)
}

/// The series of `y` against `x`: rows grouped by method, device and every parameter but the
/// one the series sweeps (`x` itself when it is a parameter, else the method's most swept
/// one), points in that parameter's order. Rows without `x` or `y` are left out.
pub fn series(rows: &[&Row], x: Measure, y: Measure, adapter: Option<&str>) -> Vec<Series> {
    let mut out: Vec<(Series, Vec<f64>)> = Vec::new();
    for r in rows {
        let (Some(xv), Some(yv)) = (x.of(r), y.of(r)) else { continue };
        let sweep = match x {
            Measure::Param(k) => Some(k),
            _ => swept(rows, &r.method),
        };
        // Parameters with one value over the method's runs are left out of the name.
        let fixed: Vec<String> = PARAMS
            .iter()
            .chain(&NAMING)
            .filter(|&&k| Some(k) != sweep && !r.param(k).is_empty() && varies(rows, &r.method, k))
            .map(|k| format!("{k}={}", r.param(k)))
            .collect();
        let device = device_label(r, adapter);
        let label = [method_label(r), fixed.join(" "), device.clone()]
            .into_iter()
            .filter(|s| !s.is_empty())
            .collect::<Vec<_>>()
            .join(" ");
        let order = sweep.and_then(|k| r.params.get(k)).and_then(serde_json::Value::as_f64);
        let point = Point {
            x: xv,
            y: yv,
            x_span: match x {
                Measure::Time(clock) => Some((r.time(clock).min, r.time(clock).max)),
                _ => None,
            },
            label: match (x, sweep) {
                (Measure::Param(_), _) | (_, None) => String::new(),
                (_, Some(k)) => point_label(r, k),
            },
        };
        let key = order.unwrap_or(xv);
        match out.iter_mut().find(|(s, _)| s.label == label) {
            Some((s, keys)) => {
                s.points.push(point);
                keys.push(key);
            }
            None => {
                let marker = if device.is_empty() { Marker::Circle } else { Marker::Triangle };
                out.push((Series { label, marker, points: vec![point] }, vec![key]));
            }
        }
    }
    out.into_iter()
        .map(|(mut s, keys)| {
            let mut idx: Vec<usize> = (0..keys.len()).collect();
            idx.sort_by(|&a, &b| keys[a].total_cmp(&keys[b]));
            s.points = idx.into_iter().map(|i| s.points[i].clone()).collect();
            s
        })
        .collect()
}

/// The methods of `rows`, in first-appearance order.
pub fn methods_in(rows: &[&Row]) -> Vec<String> {
    let mut m: Vec<String> = Vec::new();
    for r in rows {
        if !m.contains(&r.method) {
            m.push(r.method.clone());
        }
    }
    m
}

/// The series of `y` against `x` of each method of `rows` in turn (as [`series`]), packed
/// into charts of at most [`MAX_SERIES`]: a method's series go on the chart being filled when
/// they fit, else on a new one; a method with more series than a chart holds fills charts of
/// its own.
pub fn packed_series(
    rows: &[&Row],
    x: Measure,
    y: Measure,
    adapter: Option<&str>,
) -> Vec<Vec<Series>> {
    let mut charts: Vec<Vec<Series>> = Vec::new();
    for m in methods_in(rows) {
        let mine: Vec<&Row> = rows.iter().copied().filter(|r| r.method == m).collect();
        let lines = series(&mine, x, y, adapter);
        for part in lines.chunks(MAX_SERIES) {
            match charts.last_mut() {
                Some(c) if c.len() + part.len() <= MAX_SERIES => c.extend_from_slice(part),
                _ => charts.push(part.to_vec()),
            }
        }
    }
    charts
}

/// A run's point on the error-against-time charts: its median time on `clock` and its mean
/// error.
pub fn point(r: &Row, clock: Clock) -> (f64, f64) {
    (r.time(clock).median, r.metrics.mean_abs_error)
}

/// The rows on the Pareto front of error against time on `clock`, fastest first.
pub fn pareto_rows<'a>(rows: &[&'a Row], clock: Clock) -> Vec<&'a Row> {
    let points: Vec<(f64, f64)> = rows.iter().map(|r| point(r, clock)).collect();
    pareto_front(&points)
        .into_iter()
        .filter_map(|(t, e)| rows.iter().find(|r| point(r, clock) == (t, e)).copied())
        .collect()
}

/// A row's swept parameters, its light-frustum policy where it is not the method's default,
/// and its device, as `map_res=1024 rate=16 frustum=view device=gpu`.
pub fn params_text(r: &Row) -> String {
    let others = crate::model::other_params(r);
    let naming = NAMING.iter().filter(|k| others.contains(*k));
    PARAMS
        .iter()
        .chain(naming)
        .chain(&["device"])
        .filter(|k| !r.param(k).is_empty())
        .map(|k| format!("{k}={}", r.param(k)))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The runs of `rows` on the Pareto front of error against time on `clock`, fastest first.
pub fn pareto_runs(rows: &[&Row], clock: Clock) -> Vec<ParetoEntry> {
    pareto_rows(rows, clock)
        .into_iter()
        .map(|r| ParetoEntry {
            method: r.method.clone(),
            params: params_text(r),
            time: *r.time(clock),
            wall_ms: r.total_ms.median,
            error: r.metrics.mean_abs_error,
            contended: r.contended,
        })
        .collect()
}

/// At most `n` of `items`, evenly spread from the first to the last (all of them when there
/// are no more than `n`).
pub fn spread<T: Clone>(items: &[T], n: usize) -> Vec<T> {
    match n {
        _ if items.len() <= n => items.to_vec(),
        0 => Vec::new(),
        1 => vec![items[0].clone()],
        _ => {
            // Rounded positions k (len - 1) / (n - 1): strictly increasing, first and last
            // included.
            let last = items.len() - 1;
            (0..n).map(|k| items[(k * last + (n - 1) / 2) / (n - 1)].clone()).collect()
        }
    }
}

/// The error distributions of `rows` (their [`Row::error_exceedance`]) as series of the share
/// of compared pixels over each threshold, a series per row named with its method and
/// parameters. A series stops before its first threshold no pixel exceeds, since a log axis
/// has no place for zero; a row without compared pixels has no series.
pub fn exceedance_series(rows: &[&Row]) -> Vec<Series> {
    rows.iter()
        .filter(|r| r.error_exceedance.len() == EXCEEDANCE_THRESHOLDS.len())
        .filter_map(|r| {
            let points: Vec<Point> = EXCEEDANCE_THRESHOLDS
                .iter()
                .zip(&r.error_exceedance)
                .take_while(|(_, &share)| share > 0.0)
                .map(|(&t, &share)| Point::at(t, share))
                .collect();
            let label = [method_label(r), params_text(r)].join(" ").trim().to_owned();
            let marker = if r.on_gpu() { Marker::Triangle } else { Marker::Circle };
            (!points.is_empty()).then_some(Series { label, marker, points })
        })
        .collect()
}

/// The least error of each method's runs (among `rows`) whose median time on `clock` fits
/// `budget_ms`, per method in first-appearance order; `None` where no run fits.
pub fn best_within(rows: &[&Row], budget_ms: f64, clock: Clock) -> Vec<(String, Option<f64>)> {
    let mut out: Vec<(String, Option<f64>)> = Vec::new();
    for r in rows {
        let fits = r.time(clock).median <= budget_ms;
        let e = r.metrics.mean_abs_error;
        match out.iter_mut().find(|(m, _)| *m == r.method) {
            Some((_, best)) if fits => *best = Some(best.map_or(e, |b: f64| b.min(e))),
            Some(_) => {}
            None => out.push((r.method.clone(), fits.then_some(e))),
        }
    }
    out
}

/// The methods with the least error within a budget of [`BUDGETS_MS`] on a scene (ties
/// count for each), those best the most often first, then in report order; at most
/// [`MAX_SERIES`]: the lines of the budget figure.
pub fn budget_methods(report: &Report) -> Vec<String> {
    let all: Vec<&Row> = report.rows.iter().collect();
    let order = methods_in(&all);
    let mut wins: Vec<usize> = vec![0; order.len()];
    for sc in &report.scenes {
        let rows = report.scene_rows(&sc.scene);
        for &b in &BUDGETS_MS {
            let best = best_within(&rows, b, report.clock);
            let least = best.iter().filter_map(|(_, e)| *e).fold(f64::INFINITY, f64::min);
            for (m, e) in &best {
                if *e == Some(least) {
                    if let Some(k) = order.iter().position(|o| o == m) {
                        wins[k] += 1;
                    }
                }
            }
        }
    }
    let mut ranked: Vec<usize> = (0..order.len()).filter(|&k| wins[k] > 0).collect();
    ranked.sort_by(|&a, &b| wins[b].cmp(&wins[a]).then(a.cmp(&b)));
    ranked.into_iter().take(MAX_SERIES).map(|k| order[k].clone()).collect()
}

/// Every chart of every scene of `report`, in the order the page shows them (see the module
/// documentation).
pub fn charts(report: &Report) -> Vec<SceneChart> {
    let adapter = report.machine.gpu.as_deref();
    let clock = report.clock;
    let time = Measure::Time(clock);
    let mut out = Vec::new();
    for sc in &report.scenes {
        let rows = report.scene_rows(&sc.scene);
        let reference = format!("against {} at {}x{}", sc.reference, sc.width, sc.height);
        let families: Vec<Family> = FAMILIES
            .into_iter()
            .filter(|f| rows.iter().any(|r| family_of(&r.method) == *f))
            .collect();
        let kinds = [
            (
                "error-vs-time",
                format!("error against {} time", clock_name(clock)),
                time,
                Measure::MeanError,
            ),
            (
                "error-vs-map",
                "error against shadow map size".into(),
                Measure::Param("map_res"),
                Measure::MeanError,
            ),
            (
                "error-vs-rate",
                "error against sample rate".into(),
                Measure::Param("rate"),
                Measure::MeanError,
            ),
            (
                "time-vs-rate",
                format!("{} time against sample rate", clock_name(clock)),
                Measure::Param("rate"),
                time,
            ),
        ];
        for (kind, what, x, y) in kinds {
            // Every run against time, with the scene's Pareto front: there it shows what
            // accuracy costs.
            let pareto = x == time;
            for f in &families {
                let mine: Vec<&Row> =
                    rows.iter().copied().filter(|r| family_of(&r.method) == *f).collect();
                let subset: Vec<&Row> = match x {
                    Measure::Param("rate") => {
                        mine.iter().copied().filter(|r| varies(&mine, &r.method, "rate")).collect()
                    }
                    _ => mine,
                };
                let mut parts = packed_series(&subset, x, y, adapter);
                if !pareto {
                    parts.retain(|p| p.iter().any(|s| s.points.len() >= 2));
                }
                let n = parts.len();
                for (k, mut lines) in parts.into_iter().enumerate() {
                    let part = if n > 1 { format!(" ({} of {n})", k + 1) } else { String::new() };
                    let title = if y == Measure::MeanError {
                        format!("{}, {}{part}: {what}, {reference}", sc.scene, f.name)
                    } else {
                        format!("{}, {}{part}: {what}", sc.scene, f.name)
                    };
                    if pareto {
                        let context = context_points(&rows, &lines, clock);
                        if !context.is_empty() {
                            lines.push(Series {
                                label: "the scene's other runs".into(),
                                marker: Marker::Context,
                                points: context,
                            });
                        }
                    }
                    let suffix = if k > 0 { format!("-{}", k + 1) } else { String::new() };
                    out.push(SceneChart {
                        scene: sc.scene.clone(),
                        stem: format!("{kind}-{}-{}{suffix}", sc.scene, f.slug),
                        chart: Chart {
                            title,
                            x_label: x.label(),
                            y_label: y.label(),
                            series: lines,
                            pareto,
                            linear_x: false,
                        },
                        note: String::new(),
                    });
                }
            }
        }
    }
    out
}

/// The scene's runs not drawn by `lines` (error against time on `clock`), as points.
fn context_points(rows: &[&Row], lines: &[Series], clock: Clock) -> Vec<Point> {
    let drawn = |r: &Row| {
        let (x, y) = point(r, clock);
        lines.iter().any(|s| s.points.iter().any(|p| p.x == x && p.y == y))
    };
    rows.iter()
        .filter(|r| !drawn(r))
        .map(|r| {
            let (x, y) = point(r, clock);
            Point::at(x, y)
        })
        .collect()
}

/// The chart of the error distribution of a scene's Pareto runs (at most [`MAX_SERIES`],
/// evenly spread along the front); `None` when none compared a pixel.
pub fn distribution_chart(report: &Report, scene: &str) -> Option<SceneChart> {
    let sc = report.scenes.iter().find(|s| s.scene == scene)?;
    let rows = report.scene_rows(scene);
    let front = pareto_rows(&rows, report.clock);
    let shown = spread(&front, MAX_SERIES);
    let lines = exceedance_series(&shown);
    if lines.is_empty() {
        return None;
    }
    let of = if shown.len() < front.len() {
        format!(" ({} of the {} runs on the front)", shown.len(), front.len())
    } else {
        String::new()
    };
    Some(SceneChart {
        scene: scene.to_owned(),
        stem: format!("error-distribution-{scene}"),
        chart: Chart {
            title: format!(
                "{scene}: error distribution of the Pareto runs{of}, against {} at {}x{}",
                sc.reference, sc.width, sc.height
            ),
            x_label: "absolute error x (lit fraction)".into(),
            y_label: "share of compared pixels with |error| > x".into(),
            series: lines,
            pareto: false,
            linear_x: false,
        },
        note: String::new(),
    })
}

/// The file and title of the budget figure.
pub const BUDGET_STEM: &str = "best-error-within-budget";

/// Writes the report's charts into `dir/plots/` (see the module documentation).
pub fn write_plots(dir: &Path, report: &Report) -> Result<Vec<PlotFile>, OutputError> {
    let plots = dir.join("plots");
    std::fs::create_dir_all(&plots)
        .map_err(|e| OutputError::Write { path: plots.clone(), message: e.to_string() })?;
    let mut files = Vec::new();
    let all = charts(report);
    for sc in &report.scenes {
        let mine = all.iter().filter(|c| c.scene == sc.scene);
        for c in mine.chain(distribution_chart(report, &sc.scene).as_ref()) {
            write_chart(&plots.join(&c.stem), &c.chart)?;
            files.push(PlotFile {
                scene: c.scene.clone(),
                title: c.chart.title.clone(),
                png: format!("plots/{}.png", c.stem),
                place: Place::Scene,
            });
        }
    }
    if !report.scenes.is_empty() && !report.rows.is_empty() {
        write_budget_figure(&plots.join(BUDGET_STEM), report)?;
        files.push(PlotFile {
            scene: String::new(),
            title: format!(
                "best error within a {} time budget, per scene, of the methods best within one",
                clock_name(report.clock)
            ),
            png: format!("plots/{BUDGET_STEM}.png"),
            place: Place::Scene,
        });
    }
    // The cost-against-work tables' charts, shown under their tables.
    for t in &report.tables {
        if let Some(chart) = crate::tables::chart(t) {
            write_chart(&plots.join(t.paper.name()), &chart)?;
        }
    }
    Ok(files)
}

/// The summary figure: one panel per scene, the best error of each of [`budget_methods`]
/// within each budget of [`BUDGETS_MS`] (a method without a run that fits a budget has no
/// point there).
fn write_budget_figure(stem: &Path, report: &Report) -> Result<(), OutputError> {
    crate::plots::register_font();
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    let fail = |path: &Path, message: String| OutputError::Write { path: path.to_owned(), message };
    let n = report.scenes.len() as u32;
    let methods = budget_methods(report).len() as u32;
    let size = (1200, 60 + 320 * n.div_ceil(2) + legend_height(methods));
    draw_budgets(BitMapBackend::new(&png, size).into_drawing_area(), report)
        .map_err(|m| fail(&png, m))?;
    draw_budgets(SVGBackend::new(&svg, size).into_drawing_area(), report)
        .map_err(|m| fail(&svg, m))?;
    Ok(())
}

fn draw_budgets<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    report: &Report,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let clock = report.clock;
    let root = root
        .titled(
            &format!(
                "best mean error (shadow-only pixels) reachable within a {} time budget",
                clock_name(clock)
            ),
            ("sans-serif", 20),
        )
        .map_err(e)?;
    let n = report.scenes.len();
    let methods = budget_methods(report);
    let (_, h) = root.dim_in_pixel();
    let (grid, legend) =
        root.split_vertically(h.saturating_sub(legend_height(methods.len() as u32)));
    let panels = grid.split_evenly((n.div_ceil(2), 2));
    for (sc, panel) in report.scenes.iter().zip(panels) {
        let rows = report.scene_rows(&sc.scene);
        let best: Vec<Vec<(String, Option<f64>)>> =
            BUDGETS_MS.iter().map(|&b| best_within(&rows, b, clock)).collect();
        let errors: Vec<f64> = best
            .iter()
            .flatten()
            .filter(|(m, _)| methods.contains(m))
            .filter_map(|(_, e)| *e)
            .map(|v| v.max(crate::plots::LOG_FLOOR))
            .collect();
        let (lo, hi) = errors
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
        let (lo, hi) = if lo.is_finite() { (lo / 1.6, hi * 1.6) } else { (1e-3, 1.0) };
        let (yb, yl) = crate::plots::log_ticks(lo, hi);
        let mut c = ChartBuilder::on(&panel)
            .margin(10)
            .caption(sc.scene.as_str(), ("sans-serif", 15))
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d(
                (6.0..500.0).log_scale().with_key_points(BUDGETS_MS.to_vec()),
                (lo..hi).log_scale().with_key_points(yb).with_light_points(yl),
            )
            .map_err(e)?;
        c.configure_mesh()
            .x_desc(format!("{} time budget (ms)", clock_name(clock)))
            .label_style(("sans-serif", 11))
            .axis_desc_style(("sans-serif", 12))
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(e)?;
        for (k, m) in methods.iter().enumerate() {
            let colour = crate::plots::colour(k);
            let pts: Vec<(f64, f64)> = BUDGETS_MS
                .iter()
                .zip(&best)
                .filter_map(|(&b, per)| {
                    per.iter().find(|(n, _)| n == m).and_then(|(_, e)| e.map(|v| (b, v.max(lo))))
                })
                .collect();
            if pts.is_empty() {
                continue;
            }
            c.draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2))).map_err(e)?;
            c.draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled()))).map_err(e)?;
        }
    }
    // One legend for every panel, below them: a method has the same colour everywhere.
    let font = ("sans-serif", 12).into_font();
    for (k, m) in methods.iter().enumerate() {
        let colour = crate::plots::colour(k);
        let (x, y) =
            (20 + 290 * (k % LEGEND_COLUMNS) as i32, 15 + 18 * (k / LEGEND_COLUMNS) as i32);
        legend
            .draw(&PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)))
            .map_err(e)?;
        legend.draw(&Circle::new((x + 10, y), 3, colour.filled())).map_err(e)?;
        legend.draw(&Text::new(m.clone(), (x + 26, y - 7), font.clone())).map_err(e)?;
    }
    root.present().map_err(e)
}

/// Columns of the summary figure's legend.
const LEGEND_COLUMNS: usize = 4;

/// Height in pixels of a legend of `n` methods in [`LEGEND_COLUMNS`] columns.
fn legend_height(n: u32) -> u32 {
    20 + 18 * n.div_ceil(LEGEND_COLUMNS as u32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::SceneInfo;

    /// A small report: `sm` at three map sizes and `pcf-reeves` at two rates and two map sizes
    /// on one scene.
    fn small_report() -> Report {
        let toml = r#"
            name = "figures"
            width = 48
            height = 36
            warmup = 0
            repeats = 1
            scenes = ["plane-square"]
            [[run]]
            method = "sm"
            map_res = [256, 512, 1024]
            [[run]]
            method = "pcf-reeves"
            map_res = [256, 512]
            rate = [4, 16]
        "#;
        crate::sweep::report_of(toml)
    }

    /// The report the `quick` suite would make, its rows made up: every run of every scene,
    /// with the parameters the suite gives, errors and times drawn at random.
    fn quick_report() -> Report {
        let (_, text) =
            crate::suite::BUILTIN_SUITES.iter().find(|(n, _)| *n == "quick").expect("quick");
        let suite =
            crate::suite::Suite::parse(text, Path::new("quick.toml")).expect("quick parses");
        let mut report = small_report();
        let template = report.rows[0].clone();
        let mut rng = fastrand::Rng::with_seed(3);
        report.rows.clear();
        report.scenes.clear();
        for scene in &suite.scenes {
            report.scenes.push(SceneInfo { scene: scene.clone(), ..report_scene(&template) });
            for spec in &suite.runs {
                for o in spec.expand() {
                    let mut params = serde_json::Map::new();
                    for (k, v) in
                        [("map_res", o.map_res), ("rate", o.rate), ("depth_bits", o.depth_bits)]
                    {
                        if let Some(v) = v {
                            params.insert(k.into(), v.into());
                        }
                    }
                    if o.device == methods::registry::Device::Gpu {
                        params.insert("device".into(), "gpu".into());
                    }
                    let mut r = template.clone();
                    r.scene = scene.clone();
                    r.method = spec.method.clone();
                    r.params = params;
                    r.metrics.mean_abs_error = 10f64.powf(-1.0 - 3.0 * rng.f64());
                    let ms = 10f64.powf(3.0 * rng.f64());
                    r.total_ms = Summary::of(&[ms, 1.1 * ms]).expect("times");
                    r.cpu_ms = Summary::of(&[0.9 * ms, ms]);
                    report.rows.push(r);
                }
            }
        }
        report
    }

    fn report_scene(r: &Row) -> SceneInfo {
        SceneInfo {
            scene: r.scene.clone(),
            triangles: 4,
            effects: Vec::new(),
            width: r.width,
            height: r.height,
            gbuffer_ms: 1.0,
            gbuffer_cpu_ms: None,
            reference: "exact".into(),
            reference_ms: 1.0,
        }
    }

    #[test]
    fn every_chart_of_the_quick_suite_has_at_most_eight_series_of_distinct_colours() {
        let report = quick_report();
        assert_eq!(report.scenes.len(), 5);
        let mut all = charts(&report);
        all.extend(report.scenes.iter().filter_map(|s| distribution_chart(&report, &s.scene)));
        assert!(all.len() >= 5 * 4, "a chart per family and scene at least: {}", all.len());
        for c in &all {
            let coloured = c.chart.series.iter().filter(|s| s.marker != Marker::Context).count();
            assert!(coloured <= MAX_SERIES, "{}: {coloured} series", c.stem);
            let colours: Vec<(u8, u8, u8)> = crate::plots::series_colours(&c.chart)
                .iter()
                .zip(&c.chart.series)
                .filter(|(_, s)| s.marker != Marker::Context)
                .map(|(c, _)| (c.0, c.1, c.2))
                .collect();
            let mut distinct = colours.clone();
            distinct.sort();
            distinct.dedup();
            assert_eq!(distinct.len(), colours.len(), "{}: a colour twice", c.stem);
            let mut labels: Vec<&str> = c.chart.series.iter().map(|s| s.label.as_str()).collect();
            labels.sort();
            labels.dedup();
            assert_eq!(labels.len(), c.chart.series.len(), "{}: a legend entry twice", c.stem);
        }
        // Every run of a scene is on each of its error-against-time charts, coloured or grey.
        let cage = report.rows.iter().filter(|r| r.scene == "cage").count();
        for c in all.iter().filter(|c| c.scene == "cage" && c.stem.starts_with("error-vs-time")) {
            let n: usize = c.chart.series.iter().map(|s| s.points.len()).sum();
            assert_eq!(n, cage, "{}", c.stem);
            assert!(c.chart.pareto);
        }
        // The budget figure draws as many methods at most.
        let lines = budget_methods(&report);
        assert!(!lines.is_empty() && lines.len() <= MAX_SERIES, "{lines:?}");
        // A family with more series than a chart holds goes on over more charts.
        let many: Vec<Row> = (0..11)
            .map(|k| {
                let mut r = report.rows[0].clone();
                r.method = "pcf-reeves".into();
                r.params = serde_json::json!({"map_res": 256, "rate": 4 + k})
                    .as_object()
                    .expect("object")
                    .clone();
                r
            })
            .chain((0..3).map(|k| {
                let mut r = report.rows[0].clone();
                r.method = "sm".into();
                r.params =
                    serde_json::json!({"map_res": 256 << k}).as_object().expect("object").clone();
                r
            }))
            .collect();
        let refs: Vec<&Row> = many.iter().collect();
        // pcf-reeves: a series per rate against the map size, over two charts; sm's one series
        // fits on the second.
        let parts = packed_series(&refs, Measure::Param("map_res"), Measure::MeanError, None);
        assert_eq!(parts.iter().map(Vec::len).collect::<Vec<_>>(), [8, 4]);
        assert!(parts[1].last().is_some_and(|s| s.label == "sm"), "{:?}", parts[1]);
    }

    #[test]
    fn families_group_the_methods() {
        assert_eq!(family_of("sm").slug, "pcf");
        assert_eq!(family_of("pcf-gems16").slug, "pcf");
        assert_eq!(family_of("pcf-bs-fast-2x2").slug, "bs");
        for m in ["afsm", "afsm-ss", "spsm", "spsm-f32", "pan09"] {
            assert_eq!(family_of(m).slug, "subpixel", "{m}");
        }
        assert_eq!(family_of("raytrace").slug, "other");
    }

    #[test]
    fn spread_keeps_the_ends_and_no_item_twice() {
        let v: Vec<u32> = (0..11).collect();
        assert_eq!(spread(&v, 8), [0, 1, 3, 4, 6, 7, 9, 10]);
        assert_eq!(spread(&v[..5], 8), [0, 1, 2, 3, 4]);
        assert_eq!(spread(&v, 2), [0, 10]);
        assert_eq!(spread(&v, 1), [0]);
    }

    #[test]
    fn series_follow_the_swept_parameter_and_label_its_values() {
        let report = small_report();
        let rows: Vec<&Row> = report.rows.iter().collect();
        let lines = series(&rows, Measure::Time(Clock::Cpu), Measure::MeanError, None);
        let sm = lines.iter().find(|s| s.label == "sm").expect("one sm series");
        let labels: Vec<&str> = sm.points.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(labels, ["256", "512", "1024"]);
        assert!(sm.points.iter().all(|p| p.x_span.is_some_and(|(a, b)| a <= p.x && p.x <= b)));
        // On the CPU clock, the points are the CPU times.
        let cpu: Vec<f64> = rows
            .iter()
            .filter(|r| r.method == "sm")
            .map(|r| r.cpu_ms.expect("CPU time measured").median)
            .collect();
        assert!(sm.points.iter().all(|p| cpu.contains(&p.x)), "{cpu:?}");
        // pcf-reeves sweeps map_res and rate equally: one series per value of the other.
        let pcf: Vec<&Series> =
            lines.iter().filter(|s| s.label.starts_with("pcf-reeves")).collect();
        assert_eq!(pcf.len(), 2, "{lines:?}");
        assert!(lines.iter().all(|s| s.marker == Marker::Circle));
        let by_map = series(&rows, Measure::Param("map_res"), Measure::MeanError, None);
        let sm = by_map.iter().find(|s| s.label == "sm").expect("sm");
        assert_eq!(sm.points.iter().map(|p| p.x).collect::<Vec<_>>(), [256.0, 512.0, 1024.0]);
        assert!(Measure::Time(Clock::Cpu).label().starts_with("CPU time"));
        assert!(Measure::Time(Clock::Wall).label().starts_with("wall time"));
    }

    #[test]
    fn the_pareto_front_and_the_budgets_come_from_the_runs() {
        let report = small_report();
        let rows: Vec<&Row> = report.rows.iter().collect();
        for clock in [Clock::Cpu, Clock::Wall] {
            let front = pareto_runs(&rows, clock);
            assert!(!front.is_empty());
            assert!(front
                .windows(2)
                .all(|w| w[0].time.median < w[1].time.median && w[0].error > w[1].error));
            for f in &front {
                assert!(
                    !rows.iter().any(|r| r.time(clock).median < f.time.median
                        && r.metrics.mean_abs_error < f.error),
                    "{f:?} is dominated"
                );
            }
            let all = best_within(&rows, f64::INFINITY, clock);
            for (m, best) in &all {
                let least = rows
                    .iter()
                    .filter(|r| &r.method == m)
                    .map(|r| r.metrics.mean_abs_error)
                    .fold(f64::INFINITY, f64::min);
                assert_eq!(*best, Some(least));
            }
            assert!(best_within(&rows, 0.0, clock).iter().all(|(_, b)| b.is_none()));
        }
    }

    #[test]
    fn error_distributions_are_drawn_for_the_pareto_runs_until_no_pixel_is_left() {
        let report = small_report();
        let rows: Vec<&Row> = report.rows.iter().collect();
        let front = pareto_rows(&rows, report.clock);
        let lines = exceedance_series(&front);
        assert_eq!(lines.len(), front.len(), "every run compared pixels");
        for (s, r) in lines.iter().zip(&front) {
            assert!(s.label.starts_with(&r.method), "{}", s.label);
            let n = s.points.len();
            assert!(n >= 1 && n <= EXCEEDANCE_THRESHOLDS.len());
            assert!(s.points.iter().all(|p| p.y > 0.0), "no zero on a log axis");
            assert!(s.points.windows(2).all(|w| w[0].x < w[1].x && w[0].y >= w[1].y));
            // The series ends where the share first reaches zero.
            assert!(n == EXCEEDANCE_THRESHOLDS.len() || r.error_exceedance[n] == 0.0);
        }
        // A run with a single compared pixel off by 0.01 is over the thresholds up to 5e-3.
        let mut one = report.rows[0].clone();
        one.error_exceedance = EXCEEDANCE_THRESHOLDS.iter().map(|&t| f64::from(0.01 > t)).collect();
        let s = exceedance_series(&[&one]);
        assert_eq!(s[0].points.last().map(|p| p.x), Some(5e-3));
        one.error_exceedance.clear();
        assert!(exceedance_series(&[&one]).is_empty(), "nothing compared, nothing drawn");
    }
}
