//! The figures of a report, per scene: which charts are drawn from which runs (error against
//! time with the Pareto front, error against shadow-map size, error and time against sample
//! rate), written as PNG and SVG into `plots/` by [`crate::plots`].

use crate::output::OutputError;
use crate::plots::{series, write_chart, Chart, Measure};
use crate::sweep::{Report, Row};
use std::path::Path;

/// A chart written for a report.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotFile {
    /// Scene it belongs to.
    pub scene: String,
    /// Title.
    pub title: String,
    /// File name of the PNG, relative to the report folder (the SVG is beside it).
    pub png: String,
}

/// Writes the report's charts into `dir/plots/`, per scene: error against time (every run,
/// with the Pareto front), error against shadow-map resolution, and error and time against
/// sample rate where a method sweeps its rate.
pub fn write_plots(dir: &Path, report: &Report) -> Result<Vec<PlotFile>, OutputError> {
    let plots = dir.join("plots");
    std::fs::create_dir_all(&plots)
        .map_err(|e| OutputError::Write { path: plots.clone(), message: e.to_string() })?;
    let mut files = Vec::new();
    for sc in &report.scenes {
        let rows: Vec<&Row> = report.rows.iter().filter(|r| r.scene == sc.scene).collect();
        let rate_swept = |m: &str| {
            let mut rates: Vec<String> = rows
                .iter()
                .filter(|r| r.method == m)
                .filter_map(|r| r.params.get("rate").map(|v| v.to_string()))
                .collect();
            rates.sort();
            rates.dedup();
            rates.len() > 1
        };
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
            // Every run on one chart, against time: there the Pareto front tells what
            // accuracy costs.
            let pareto = x == Measure::Time;
            let title = if y == Measure::MeanError {
                format!("{}: {what}, {reference}", sc.scene)
            } else {
                format!("{}: {what}", sc.scene)
            };
            let lines = series(subset, x, y, pareto);
            if lines.iter().all(|s| s.points.len() < 2) && !pareto {
                continue;
            }
            if lines.is_empty() {
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
            });
        }
    }
    Ok(files)
}
