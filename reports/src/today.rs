//! The section "Against today's techniques": the runs of the techniques today's shadow papers
//! compare against (the filtered maps, variance, exponential and moment shadow maps, and the
//! frustum-traced irregular z-buffer: `methods::registry::Family::Today`) set against those of
//! the 2001-2014 techniques the workbench began with (`Family::Seed`) on the same scenes. A
//! run's family is its method's registry entry's ([`family_of`]); nothing here lists method
//! names, so a method added to the registry's table joins its family's side by itself.
//!
//! A scene takes part when it has a run of each family ([`compares`], [`scenes()`]); the index
//! (`crate::index`) and `report.md` (`crate::write`) show the section when some scene does.
//! The runs are the scene's rows as the rest of the index takes them: a still scene's frame;
//! on an animated scene, its runs with their metrics pooled over the frames and their time per
//! frame (`crate::motion`); an outside result without a time is in no chart and not here.
//!
//! Per scene:
//! - **today's techniques against the seeds** (`today-vs-seeds-SCENE`, [`charts`]): mean
//!   error on the shadow-only pixels against time on the report's clock, log-log. Today's
//!   methods are coloured series, one per method, device and fixed parameters as on the
//!   error-against-time charts (`crate::figures::series`), at most 8 a chart
//!   (`crate::plots::MAX_SERIES`) and more over more charts; the seeds' runs are open
//!   dark-grey rings without lines
//!   (`Marker::Ring`), named where they are on the front; the scene's other runs (a reference
//!   run as a method, an outside result, today's runs of another chart) are grey dots; the
//!   Pareto front over every run of the scene is drawn;
//! - **a table** ([`table`]): per run its method (linked to its page), family, parameters,
//!   mean error, the 95th percentile of the boundary error (as in the runs tables), time on
//!   the report's clock (median and its 95 % interval) and whether it is on the front
//!   ([`on_front`]: no other run of the scene is at least as fast and as accurate and better
//!   in one of the two).

use crate::figures::{packed_series, params_text, point, Measure, Place, PlotFile, SceneChart};
use crate::html::{metric_cells, time_head, Cell, Head, TableView, METRIC_COLUMNS};
use crate::model::{method_label, row_stem, scene_stem, Report, Row, SceneInfo};
use crate::output::OutputError;
use crate::plots::{pareto_front, write_chart, Chart, Marker, Point, Series};
use crate::summary::time_text;
use instrumentation::measure::Clock;
pub use methods::registry::Family;
use std::path::Path;

/// The family of the run's method in the registry's table; `None` for a run of a name the
/// table has not (a reference run as a method) and for an outside result.
pub fn family_of(row: &Row) -> Option<Family> {
    if row.external {
        return None;
    }
    methods::registry::entry(&row.method).map(|e| e.family)
}

/// A family as the table and the legends name it.
pub fn family_name(family: Option<Family>) -> &'static str {
    match family {
        Some(Family::Seed) => "seed (2001-2014)",
        Some(Family::Today) => "today",
        None => "other",
    }
}

/// Whether `rows` set today's techniques against the seeds: a run of each family at least.
pub fn compares(rows: &[&Row]) -> bool {
    let has = |f: Family| rows.iter().any(|r| family_of(r) == Some(f));
    has(Family::Today) && has(Family::Seed)
}

/// The scenes of `report` whose runs [`compares`], in report order.
pub fn scenes(report: &Report) -> Vec<&SceneInfo> {
    report.scenes.iter().filter(|sc| compares(&report.scene_rows(&sc.scene))).collect()
}

/// For each of `rows`, whether it is on their Pareto front of mean error against time on
/// `clock`: no other run is at least as fast and as accurate and better in one of the two
/// (two runs with the same time and error are on it together), the front the charts draw.
pub fn on_front(rows: &[&Row], clock: Clock) -> Vec<bool> {
    let points: Vec<(f64, f64)> = rows.iter().map(|r| point(r, clock)).collect();
    let front = pareto_front(&points);
    points.iter().map(|p| front.contains(p)).collect()
}

/// The charts of `scene` (see the module documentation); none when its runs do not
/// [`compares`].
pub fn charts(report: &Report, scene: &SceneInfo) -> Vec<SceneChart> {
    let rows = report.scene_rows(&scene.scene);
    if !compares(&rows) {
        return Vec::new();
    }
    let clock = report.clock;
    let front = on_front(&rows, clock);
    let today: Vec<&Row> =
        rows.iter().copied().filter(|r| family_of(r) == Some(Family::Today)).collect();
    let seeds: Vec<Point> = rows
        .iter()
        .zip(&front)
        .filter(|(r, _)| family_of(r) == Some(Family::Seed))
        .map(|(r, &on)| {
            let (x, y) = point(r, clock);
            Point { label: if on { method_label(r) } else { String::new() }, ..Point::at(x, y) }
        })
        .collect();
    let rings = Series {
        label: "the 2001-2014 techniques (seeds), named where on the front".into(),
        marker: Marker::Ring,
        points: seeds,
    };
    let name = &scene.scene;
    let time = Measure::Time(clock);
    let parts = packed_series(&today, time, Measure::MeanError, report.machine.gpu.as_deref());
    let n = parts.len();
    parts
        .into_iter()
        .enumerate()
        .map(|(k, lines)| {
            let drawn = |r: &Row| {
                let (x, y) = point(r, clock);
                lines.iter().any(|s| s.points.iter().any(|p| p.x == x && p.y == y))
            };
            let others: Vec<Point> = rows
                .iter()
                .filter(|r| family_of(r) != Some(Family::Seed) && !drawn(r))
                .map(|r| {
                    let (x, y) = point(r, clock);
                    Point::at(x, y)
                })
                .collect();
            let mut series = vec![rings.clone()];
            series.extend(lines);
            if !others.is_empty() {
                series.push(Series {
                    label: "the scene's other runs".into(),
                    marker: Marker::Context,
                    points: others,
                });
            }
            let part = if n > 1 { format!(" ({} of {n})", k + 1) } else { String::new() };
            let suffix = if k > 0 { format!("-{}", k + 1) } else { String::new() };
            SceneChart {
                scene: name.clone(),
                stem: format!("today-vs-seeds-{}{suffix}", scene_stem(name)),
                chart: Chart {
                    title: format!(
                        "{name}{part}: today's techniques against the seeds, mean error against \
                         {} time, against {} at {}x{}",
                        crate::figures::clock_name(clock),
                        scene.reference,
                        scene.width,
                        scene.height
                    ),
                    x_label: time.label(),
                    y_label: Measure::MeanError.label(),
                    series,
                    pareto: true,
                    linear_x: false,
                },
                note: String::new(),
            }
        })
        .collect()
}

/// Writes the charts of every scene that sets today's techniques against the seeds into
/// `dir/plots/`. Returns them, each placed in the section ([`Place::Today`]).
pub fn write_plots(dir: &Path, report: &Report) -> Result<Vec<PlotFile>, OutputError> {
    let plots = dir.join("plots");
    std::fs::create_dir_all(&plots)
        .map_err(|e| OutputError::Write { path: plots.clone(), message: e.to_string() })?;
    let mut files = Vec::new();
    for sc in &report.scenes {
        for c in charts(report, sc) {
            write_chart(&plots.join(&c.stem), &c.chart)?;
            files.push(PlotFile {
                scene: c.scene,
                title: c.chart.title,
                png: format!("plots/{}.png", c.stem),
                place: Place::Today,
            });
        }
    }
    Ok(files)
}

/// The head of the table's column that says whether a run is on the front.
pub const FRONT_HEAD: &str = "on the Pareto front";

/// The table of `rows`, one scene's runs (see the module documentation), in their order; its
/// front is theirs ([`on_front`]).
pub fn table(rows: &[&Row], report: &Report) -> TableView {
    let clock = report.clock;
    let front = on_front(rows, clock);
    let heads = vec![
        Head::text("method"),
        Head::text("family"),
        Head::text("parameters"),
        Head::num(METRIC_COLUMNS[MEAN]),
        Head::num(METRIC_COLUMNS[BOUNDARY_P95]),
        Head::num(time_head(crate::figures::clock_name(clock))),
        Head::text(FRONT_HEAD),
    ];
    let body = rows
        .iter()
        .zip(front)
        .map(|(r, on)| {
            let metrics = metric_cells(r);
            let t = r.time(clock);
            vec![
                Cell::text(method_label(r)).link(format!("runs/{}.html", row_stem(r))),
                Cell::text(family_name(family_of(r))),
                Cell::text(params_text(r)),
                metrics[MEAN].clone(),
                metrics[BOUNDARY_P95].clone(),
                Cell::sorted(time_text(t), t.median),
                Cell::text(if on { "yes" } else { "no" }),
            ]
        })
        .collect();
    TableView::new("today", heads, body)
}

/// The mean error among [`METRIC_COLUMNS`].
const MEAN: usize = 0;

/// The 95th percentile of the boundary error among [`METRIC_COLUMNS`].
const BOUNDARY_P95: usize = 5;

#[cfg(test)]
mod tests {
    use super::*;
    use instrumentation::stats::Summary;

    /// `sm` at two map sizes, `msm` at two map sizes and two filters and `esm` on one scene
    /// at 32 x 24, on the wall clock, with the times given per run.
    fn report(times: &[f64]) -> Report {
        let mut report = crate::sweep::report_of(
            r#"
            name = "today"
            width = 32
            height = 24
            warmup = 0
            repeats = 1
            scenes = ["plane-square"]
            [[run]]
            method = "sm"
            map_res = [64, 128]
            [[run]]
            method = "msm"
            map_res = [64, 128]
            filter = [3, 7]
            [[run]]
            method = "esm"
            map_res = [64]
            "#,
        );
        assert_eq!(report.rows.len(), times.len(), "{:?}", report.skipped);
        report.clock = Clock::Wall;
        for (r, &t) in report.rows.iter_mut().zip(times) {
            r.total_ms = Summary::of(&[t]).expect("a time");
        }
        report
    }

    /// Times of the runs of [`report`], milliseconds.
    const TIMES: [f64; 7] = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];

    /// Whether row `k` of `rows` is on the front by the definition: no other row at least
    /// as fast and as accurate and better in one.
    fn undominated(rows: &[&Row], k: usize) -> bool {
        let (t, e) = point(rows[k], Clock::Wall);
        !rows
            .iter()
            .map(|r| point(r, Clock::Wall))
            .any(|(u, f)| u <= t && f <= e && (u < t || f < e))
    }

    #[test]
    fn families_come_from_the_registry() {
        let report = report(&TIMES);
        let families: Vec<Option<Family>> = report.rows.iter().map(family_of).collect();
        let (seed, today) = (Some(Family::Seed), Some(Family::Today));
        assert_eq!(families, [seed, seed, today, today, today, today, today]);
        let mut outside = report.rows[2].clone();
        outside.external = true;
        assert_eq!(family_of(&outside), None, "an outside result named as a method");
        let mut reference = report.rows[0].clone();
        reference.method = "exact".into();
        assert_eq!(family_of(&reference), None);
        assert_eq!([seed, today, None].map(family_name), ["seed (2001-2014)", "today", "other"]);
        let rows: Vec<&Row> = report.rows.iter().collect();
        assert!(compares(&rows));
        assert!(!compares(&rows[..2]), "seeds alone");
        assert!(!compares(&rows[2..]), "today's alone");
        assert_eq!(scenes(&report).len(), 1);
    }

    #[test]
    fn the_front_flags_the_runs_no_other_run_beats() {
        let report = report(&TIMES);
        let mut rows: Vec<Row> = report.rows[..5].to_vec();
        // Errors by hand: row 1 slower and less accurate than row 0; rows 3 and 4 tie in
        // time, 4 the more accurate; row 2 ties row 4's error, faster.
        for (r, e) in rows.iter_mut().zip([0.1, 0.2, 0.05, 0.07, 0.05]) {
            r.metrics.mean_abs_error = e;
        }
        rows[3].total_ms = rows[4].total_ms;
        // A copy of row 0: on the front with it.
        rows.push(rows[0].clone());
        let refs: Vec<&Row> = rows.iter().collect();
        let front = on_front(&refs, Clock::Wall);
        assert_eq!(front, [true, false, true, false, false, true]);
        for (k, &on) in front.iter().enumerate() {
            assert_eq!(on, undominated(&refs, k), "row {k}");
        }
    }

    #[test]
    fn the_chart_rings_the_seeds_colours_todays_and_draws_every_run() {
        let report = report(&TIMES);
        let charts = charts(&report, &report.scenes[0]);
        let [chart] = &charts[..] else { panic!("{} charts", charts.len()) };
        assert_eq!(chart.stem, "today-vs-seeds-plane-square");
        assert!(chart.chart.pareto && chart.chart.title.contains("wall time"));
        let rings: Vec<&Series> =
            chart.chart.series.iter().filter(|s| s.marker == Marker::Ring).collect();
        assert_eq!(rings.len(), 1);
        assert_eq!(rings[0].points.len(), 2, "both sm runs");
        // msm's two series sweep the map and are named by the filter; esm's one.
        let mut coloured: Vec<&str> = chart
            .chart
            .series
            .iter()
            .filter(|s| matches!(s.marker, Marker::Circle | Marker::Triangle))
            .map(|s| s.label.as_str())
            .collect();
        coloured.sort();
        assert_eq!(coloured, ["esm", "msm filter=3", "msm filter=7"]);
        assert!(chart.chart.series.iter().all(|s| s.marker != Marker::Context), "nothing else");
        // Every run once, and the front drawn is the runs' own.
        let mut drawn: Vec<(f64, f64)> =
            chart.chart.series.iter().flat_map(|s| s.points.iter().map(|p| (p.x, p.y))).collect();
        let rows: Vec<&Row> = report.rows.iter().collect();
        let mut points: Vec<(f64, f64)> = rows.iter().map(|r| point(r, Clock::Wall)).collect();
        drawn.sort_by(|a, b| a.0.total_cmp(&b.0));
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert_eq!(drawn, points);
        let flags = on_front(&rows, Clock::Wall);
        let front = pareto_front(&drawn);
        for (r, &on) in rows.iter().zip(&flags) {
            assert_eq!(front.contains(&point(r, Clock::Wall)), on, "{}", r.method);
        }
        // A seed is named where it is on the front, and only there.
        for ((p, r), &on) in rings[0].points.iter().zip(&rows).zip(&flags) {
            assert_eq!(p.label.is_empty(), !on, "{} {}", r.method, p.label);
        }
        // The seeds alone: no chart.
        let mut seeds = report.clone();
        seeds.rows.truncate(2);
        assert!(super::charts(&seeds, &seeds.scenes[0]).is_empty());
    }

    #[test]
    fn the_table_has_a_row_per_run_with_its_family_and_front() {
        let report = report(&TIMES);
        let rows: Vec<&Row> = report.rows.iter().collect();
        let t = table(&rows, &report);
        let heads: Vec<&str> = t.heads.iter().map(|h| h.text.as_str()).collect();
        assert_eq!(
            heads,
            [
                "method",
                "family",
                "parameters",
                "mean abs error",
                "boundary p95",
                "wall ms (95 % interval)",
                FRONT_HEAD
            ]
        );
        assert_eq!(t.rows.len(), rows.len());
        let flags = on_front(&rows, Clock::Wall);
        for ((cells, r), on) in t.rows.iter().zip(&rows).zip(flags) {
            assert_eq!(cells[0].text, r.method);
            assert_eq!(cells[0].href, Some(format!("runs/{}.html", row_stem(r))));
            assert_eq!(cells[1].text, family_name(family_of(r)));
            assert_eq!(cells[3].value, Some(r.metrics.mean_abs_error));
            assert_eq!(cells[5].value, Some(r.time(Clock::Wall).median));
            assert_eq!(cells[6].text, if on { "yes" } else { "no" });
        }
        let params: Vec<&str> = t.rows.iter().map(|r| r[2].text.as_str()).collect();
        assert!(params.contains(&"map_res=128 filter=7"), "{params:?}");
    }
}
