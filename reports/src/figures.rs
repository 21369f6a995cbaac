//! The figures of a report: which charts are drawn from which runs, written as PNG and SVG
//! into `plots/` by [`crate::plots`].
//!
//! Per scene:
//! - **error against time**: every run; one series per method, device and fixed parameters,
//!   its points joined in the order of the parameter the series sweeps (the one with the
//!   most values among that method's runs) and labelled with its value (`512`, `32x`); a
//!   horizontal bar spans each run's [min, max] time; the Pareto front is drawn and listed
//!   ([`PlotFile::pareto`]);
//! - **error against shadow-map size** and **error against sample rate** (and time against
//!   rate), one series per method, device and other parameters;
//! - **error distribution of the Pareto runs**: for each run on the front, the share of the
//!   shadow-only pixels whose error exceeds x, at the thresholds of
//!   `analysis::metrics::EXCEEDANCE_THRESHOLDS` (log-log: the tail of large errors stays
//!   visible beside the many small ones; at x = 0.5/255 the share is one minus the pixel
//!   match).
//!
//! Across scenes, **best error within a time budget**: per scene a panel, per method the least
//! error among its runs whose median time fits each budget of [`BUDGETS_MS`].
//!
//! Per cost-against-work table (`crate::tables`), its log-log chart of time against work
//! (`plots/cost-against-triangles.png`, `plots/cost-against-pixels.png`), which the page shows
//! under the table.
//!
//! The error is the shadow-only headline (planar and surface pixels, see `analysis::metrics`).
//! GPU runs are separate series marked with triangles, named with the adapter, and a software
//! adapter (llvmpipe, lavapipe) is said to be one.

use crate::model::{Report, Row};
use crate::output::OutputError;
use crate::plots::{pareto_front, write_chart, Chart, Marker, Point, Series};
use analysis::metrics::EXCEEDANCE_THRESHOLDS;
use plotters::prelude::*;
use std::path::Path;

/// The time budgets of the summary figure, in milliseconds.
pub const BUDGETS_MS: [f64; 4] = [10.0, 30.0, 100.0, 300.0];

/// The parameters a series may sweep or hold fixed, in the order they are named.
const PARAMS: [&str; 4] = ["map_res", "rate", "depth_bits", "pattern"];

/// A chart written for a report.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotFile {
    /// Scene it belongs to (empty for a figure across scenes).
    pub scene: String,
    /// Title.
    pub title: String,
    /// File name of the PNG, relative to the report folder (the SVG is beside it).
    pub png: String,
    /// The runs on the Pareto front of an error-against-time chart, fastest first (empty for
    /// other charts).
    pub pareto: Vec<ParetoEntry>,
}

/// A run on the Pareto front.
#[derive(Debug, Clone, PartialEq)]
pub struct ParetoEntry {
    /// Method.
    pub method: String,
    /// Its parameters, as `map_res=1024 rate=16 device=gpu`.
    pub params: String,
    /// Median time, milliseconds.
    pub time_ms: f64,
    /// Shadow-only mean absolute error.
    pub error: f64,
}

/// What a measure of a row is, for the charts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Measure {
    /// Mean absolute error on the shadow-only pixels.
    MeanError,
    /// Median total time of the method's stages.
    Time,
    /// A parameter of the method (`map_res`, `rate`).
    Param(&'static str),
}

impl Measure {
    /// The row's value of this measure.
    pub fn of(self, row: &Row) -> Option<f64> {
        match self {
            Measure::MeanError => Some(row.metrics.mean_abs_error),
            Measure::Time => Some(row.total_ms.median),
            Measure::Param(key) => row.params.get(key).and_then(serde_json::Value::as_f64),
        }
    }

    /// Axis label with unit.
    pub fn label(self) -> String {
        match self {
            Measure::MeanError => "mean absolute error, shadow-only pixels (lit fraction)".into(),
            Measure::Time => "time, median with [min, max] (ms)".into(),
            Measure::Param("map_res") => "shadow map resolution (texels per side)".into(),
            Measure::Param("rate") => "samples per pixel".into(),
            Measure::Param(k) => k.into(),
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
            .filter(|&&k| Some(k) != sweep && !r.param(k).is_empty() && varies(rows, &r.method, k))
            .map(|k| format!("{k}={}", r.param(k)))
            .collect();
        let device = device_label(r, adapter);
        let label = [r.method.clone(), fixed.join(" "), device.clone()]
            .into_iter()
            .filter(|s| !s.is_empty())
            .collect::<Vec<_>>()
            .join(" ");
        let order = sweep.and_then(|k| r.params.get(k)).and_then(serde_json::Value::as_f64);
        let point = Point {
            x: xv,
            y: yv,
            x_span: (x == Measure::Time).then_some((r.total_ms.min, r.total_ms.max)),
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

/// The rows on the Pareto front of error against time, fastest first.
pub fn pareto_rows<'a>(rows: &[&'a Row]) -> Vec<&'a Row> {
    let points: Vec<(f64, f64)> =
        rows.iter().map(|r| (r.total_ms.median, r.metrics.mean_abs_error)).collect();
    pareto_front(&points)
        .into_iter()
        .filter_map(|(t, e)| {
            rows.iter().find(|r| r.total_ms.median == t && r.metrics.mean_abs_error == e).copied()
        })
        .collect()
}

/// A row's swept parameters and device, as `map_res=1024 rate=16 device=gpu`.
fn params_text(r: &Row) -> String {
    PARAMS
        .iter()
        .chain(&["device"])
        .filter(|k| !r.param(k).is_empty())
        .map(|k| format!("{k}={}", r.param(k)))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The runs of `rows` on the Pareto front of error against time, fastest first.
pub fn pareto_runs(rows: &[&Row]) -> Vec<ParetoEntry> {
    pareto_rows(rows)
        .into_iter()
        .map(|r| ParetoEntry {
            method: r.method.clone(),
            params: params_text(r),
            time_ms: r.total_ms.median,
            error: r.metrics.mean_abs_error,
        })
        .collect()
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
            let label = [r.method.clone(), params_text(r)].join(" ").trim().to_owned();
            let marker = if r.on_gpu() { Marker::Triangle } else { Marker::Circle };
            (!points.is_empty()).then_some(Series { label, marker, points })
        })
        .collect()
}

/// The least error of each method's runs (among `rows`) whose median time fits `budget_ms`,
/// per method in first-appearance order; `None` where no run fits.
pub fn best_within(rows: &[&Row], budget_ms: f64) -> Vec<(String, Option<f64>)> {
    let mut out: Vec<(String, Option<f64>)> = Vec::new();
    for r in rows {
        let fits = r.total_ms.median <= budget_ms;
        let e = r.metrics.mean_abs_error;
        match out.iter_mut().find(|(m, _)| *m == r.method) {
            Some((_, best)) if fits => *best = Some(best.map_or(e, |b: f64| b.min(e))),
            Some(_) => {}
            None => out.push((r.method.clone(), fits.then_some(e))),
        }
    }
    out
}

/// Writes the report's charts into `dir/plots/` (see the module documentation).
pub fn write_plots(dir: &Path, report: &Report) -> Result<Vec<PlotFile>, OutputError> {
    let plots = dir.join("plots");
    std::fs::create_dir_all(&plots)
        .map_err(|e| OutputError::Write { path: plots.clone(), message: e.to_string() })?;
    let adapter = report.machine.gpu.as_deref();
    let mut files = Vec::new();
    for sc in &report.scenes {
        let rows: Vec<&Row> = report.rows.iter().filter(|r| r.scene == sc.scene).collect();
        let rate_swept = |m: &str| varies(&rows, m, "rate");
        let rate_rows: Vec<&Row> = rows.iter().copied().filter(|r| rate_swept(&r.method)).collect();
        let reference = format!("against {} at {}x{}", sc.reference, sc.width, sc.height);
        let specs = [
            ("error-vs-time", "error against time", &rows, Measure::Time, Measure::MeanError),
            (
                "error-vs-map",
                "error against shadow map size",
                &rows,
                Measure::Param("map_res"),
                Measure::MeanError,
            ),
            (
                "error-vs-rate",
                "error against sample rate",
                &rate_rows,
                Measure::Param("rate"),
                Measure::MeanError,
            ),
            (
                "time-vs-rate",
                "time against sample rate",
                &rate_rows,
                Measure::Param("rate"),
                Measure::Time,
            ),
        ];
        for (kind, what, subset, x, y) in specs {
            // Every run on one chart against time: there the Pareto front tells what accuracy
            // costs.
            let pareto = x == Measure::Time;
            let title = if y == Measure::MeanError {
                format!("{}: {what}, {reference}", sc.scene)
            } else {
                format!("{}: {what}", sc.scene)
            };
            let lines = series(subset, x, y, adapter);
            if lines.is_empty() || (lines.iter().all(|s| s.points.len() < 2) && !pareto) {
                continue;
            }
            let stem = format!("{kind}-{}", sc.scene);
            let chart = Chart {
                title: title.clone(),
                x_label: x.label(),
                y_label: y.label(),
                series: lines,
                pareto,
            };
            write_chart(&plots.join(&stem), &chart)?;
            files.push(PlotFile {
                scene: sc.scene.clone(),
                title,
                png: format!("plots/{stem}.png"),
                pareto: if pareto { pareto_runs(subset) } else { Vec::new() },
            });
        }
        let lines = exceedance_series(&pareto_rows(&rows));
        if !lines.is_empty() {
            let stem = format!("error-distribution-{}", sc.scene);
            let title = format!("{}: error distribution of the Pareto runs, {reference}", sc.scene);
            let chart = Chart {
                title: title.clone(),
                x_label: "absolute error x (lit fraction)".into(),
                y_label: "share of compared pixels with |error| > x".into(),
                series: lines,
                pareto: false,
            };
            write_chart(&plots.join(&stem), &chart)?;
            files.push(PlotFile {
                scene: sc.scene.clone(),
                title,
                png: format!("plots/{stem}.png"),
                pareto: Vec::new(),
            });
        }
    }
    if !report.scenes.is_empty() && !report.rows.is_empty() {
        let stem = "best-error-within-budget";
        write_budget_figure(&plots.join(stem), report)?;
        files.push(PlotFile {
            scene: String::new(),
            title: "best error within a time budget, per scene and method".into(),
            png: format!("plots/{stem}.png"),
            pareto: Vec::new(),
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

/// The summary figure: one panel per scene, the best error of each method within each budget
/// of [`BUDGETS_MS`] (a method without a run that fits a budget has no point there).
fn write_budget_figure(stem: &Path, report: &Report) -> Result<(), OutputError> {
    crate::plots::register_font();
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    let fail = |path: &Path, message: String| OutputError::Write { path: path.to_owned(), message };
    let n = report.scenes.len() as u32;
    let methods = methods_of(report).len() as u32;
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
    let root = root
        .titled(
            "best mean error (shadow-only pixels) reachable within a time budget",
            ("sans-serif", 20),
        )
        .map_err(e)?;
    let n = report.scenes.len();
    let methods = methods_of(report);
    let (_, h) = root.dim_in_pixel();
    let (grid, legend) =
        root.split_vertically(h.saturating_sub(legend_height(methods.len() as u32)));
    let panels = grid.split_evenly((n.div_ceil(2), 2));
    for (sc, panel) in report.scenes.iter().zip(panels) {
        let rows: Vec<&Row> = report.rows.iter().filter(|r| r.scene == sc.scene).collect();
        let best: Vec<Vec<(String, Option<f64>)>> =
            BUDGETS_MS.iter().map(|&b| best_within(&rows, b)).collect();
        let errors: Vec<f64> = best
            .iter()
            .flatten()
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
            .x_desc("time budget (ms)")
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

/// The methods of a report, in first-appearance order.
fn methods_of(report: &Report) -> Vec<String> {
    let mut m: Vec<String> = Vec::new();
    for r in &report.rows {
        if !m.contains(&r.method) {
            m.push(r.method.clone());
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn series_follow_the_swept_parameter_and_label_its_values() {
        let report = small_report();
        let rows: Vec<&Row> = report.rows.iter().collect();
        let lines = series(&rows, Measure::Time, Measure::MeanError, None);
        let sm = lines.iter().find(|s| s.label == "sm").expect("one sm series");
        let labels: Vec<&str> = sm.points.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(labels, ["256", "512", "1024"]);
        assert!(sm.points.iter().all(|p| p.x_span.is_some_and(|(a, b)| a <= p.x && p.x <= b)));
        // pcf-reeves sweeps map_res and rate equally: one series per value of the other.
        let pcf: Vec<&Series> =
            lines.iter().filter(|s| s.label.starts_with("pcf-reeves")).collect();
        assert_eq!(pcf.len(), 2, "{lines:?}");
        assert!(lines.iter().all(|s| s.marker == Marker::Circle));
        let by_map = series(&rows, Measure::Param("map_res"), Measure::MeanError, None);
        let sm = by_map.iter().find(|s| s.label == "sm").expect("sm");
        assert_eq!(sm.points.iter().map(|p| p.x).collect::<Vec<_>>(), [256.0, 512.0, 1024.0]);
    }

    #[test]
    fn the_pareto_front_and_the_budgets_come_from_the_runs() {
        let report = small_report();
        let rows: Vec<&Row> = report.rows.iter().collect();
        let front = pareto_runs(&rows);
        assert!(!front.is_empty());
        assert!(front.windows(2).all(|w| w[0].time_ms < w[1].time_ms && w[0].error > w[1].error));
        for f in &front {
            assert!(
                !rows
                    .iter()
                    .any(|r| r.total_ms.median < f.time_ms && r.metrics.mean_abs_error < f.error),
                "{f:?} is dominated"
            );
        }
        let all = best_within(&rows, f64::INFINITY);
        for (m, best) in &all {
            let least = rows
                .iter()
                .filter(|r| &r.method == m)
                .map(|r| r.metrics.mean_abs_error)
                .fold(f64::INFINITY, f64::min);
            assert_eq!(*best, Some(least));
        }
        assert!(best_within(&rows, 0.0).iter().all(|(_, b)| b.is_none()));
    }

    #[test]
    fn error_distributions_are_drawn_for_the_pareto_runs_until_no_pixel_is_left() {
        let report = small_report();
        let rows: Vec<&Row> = report.rows.iter().collect();
        let front = pareto_rows(&rows);
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
