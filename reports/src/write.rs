//! A report's files: `runs.json` (everything), `runs.csv` (one line per run: parameters,
//! metrics, times, counters), `report.md` (the report in Markdown: the machine and the load,
//! per scene its Pareto front and what the runs say of each method, the scenes, the budget
//! figure and table, today's techniques against the seeds (the index's section of that name),
//! per scene its grids and charts as images, its table of runs and, for an
//! animated scene, its runs in motion (the index's "In motion" table and charts), CPU and GPU
//! side by side, the papers' tables), the pages (`index.html`, `runs/ID.html`), the
//! charts (`plots/`), and `visibility/*.exr` (every visibility buffer).
//!
//! Every function here writes into the folder it is given, which is the staging folder of
//! the output's transaction (`crate::publish`): the report appears under its final names, with
//! its manifest, only when it is whole.

use crate::figures::{clock_name, write_plots, Place, PlotFile};
use crate::grids::write_grid;
use crate::model::{param_label, row_stem, Images, Report, Row};
use crate::output::{write_visibility_exr, OutputError};
use crate::summary::{budget_table, error_text, fronts, measured, ms_text, time_text, verdicts};
use analysis::metrics::EXCEEDANCE_THRESHOLDS;
use instrumentation::Counters;
use std::fmt::Write as _;
use std::path::Path;

/// Columns of `runs.csv` before the stage times and the counters: parameters, frame size,
/// reference, metrics (over the reference's shadow-only pixels), total time, provenance, and a
/// run in motion's temporal metrics and frame count (empty for a still scene's run).
pub const CSV_COLUMNS: &[&str] = &[
    "scene",
    "method",
    "map_res",
    "rate",
    "depth_bits",
    "pattern",
    "device",
    "width_px",
    "height_px",
    "reference",
    "ref_rate",
    "evaluated_pixels",
    "mean_abs_error",
    "rmse",
    "max_abs_error",
    "pixel_match",
    "pixel_match_lecocq",
    "boundary_pixels",
    "boundary_mean_abs_error",
    "boundary_p50_abs_error",
    "boundary_p95_abs_error",
    "boundary_p99_abs_error",
    "flip_mean",
    "time_median_ms",
    "time_ci_low_ms",
    "time_ci_high_ms",
    "time_min_ms",
    "time_max_ms",
    "cpu_median_ms",
    "cpu_ci_low_ms",
    "cpu_ci_high_ms",
    "cpu_min_ms",
    "cpu_max_ms",
    "timed_runs",
    "contended",
    "min_cpu_share",
    "loadavg_before",
    "loadavg_after",
    "commit",
    "version",
    "external",
    "temporal_error",
    "temporal_p95",
    "boundary_temporal_error",
    "boundary_temporal_p95",
    "temporal_pairs",
    "frames",
];

/// Stage names over every row of `report`, in the order they first appear.
fn stage_names(report: &Report) -> Vec<&str> {
    let mut names: Vec<&str> = Vec::new();
    for s in report.rows.iter().flat_map(|r| &r.stages) {
        if !names.contains(&s.name.as_str()) {
            names.push(&s.name);
        }
    }
    names
}

/// `runs.csv`, tidy: a header, then one line per run (outside results with a time included,
/// `external` true), one column per quantity. Cells are
/// numbers (or text for names), with no thousands suffix; an empty cell is a quantity that
/// does not apply (a parameter the method has not, the boundary error of a run without
/// boundary pixels, a stage the run did not have, the temporal metrics of a still scene's run).
/// A run in motion's metrics and times are pooled over its frames, its times per frame
/// (`crate::motion`); `frames` is its frame count. After [`CSV_COLUMNS`], the error's
/// distribution as `share_error_over.X` (the share of compared pixels whose absolute error
/// exceeds X, for each X of `analysis::metrics::EXCEEDANCE_THRESHOLDS`), the median time of
/// every stage of the report as `stage_ms.NAME` and every counter as `counter.NAME`.
pub fn csv(report: &Report) -> Result<String, OutputError> {
    let fail = |e: &dyn std::fmt::Display| OutputError::Write {
        path: "runs.csv".into(),
        message: e.to_string(),
    };
    let stages = stage_names(report);
    let mut w = csv::Writer::from_writer(Vec::new());
    let header = CSV_COLUMNS
        .iter()
        .map(|c| (*c).to_owned())
        .chain(EXCEEDANCE_THRESHOLDS.iter().map(|t| format!("share_error_over.{t}")))
        .chain(stages.iter().map(|s| format!("stage_ms.{s}")))
        .chain(Counters::NAMES.iter().map(|c| format!("counter.{c}")));
    w.write_record(header).map_err(|e| fail(&e))?;
    let opt = |v: Option<f64>| v.map_or_else(String::new, |v| v.to_string());
    for r in &report.rows {
        let m = &r.metrics;
        let boundary = m.boundary_pixels > 0;
        let mut cells = vec![
            r.scene.clone(),
            r.method.clone(),
            r.param("map_res"),
            r.param("rate"),
            r.param("depth_bits"),
            r.param("pattern"),
            if r.on_gpu() { "gpu" } else { "cpu" }.to_owned(),
            r.width.to_string(),
            r.height.to_string(),
            r.reference.clone(),
            r.ref_rate.map_or_else(String::new, |v| v.to_string()),
            m.evaluated_pixels.to_string(),
            m.mean_abs_error.to_string(),
            m.rmse.to_string(),
            m.max_abs_error.to_string(),
            m.pixel_match.to_string(),
            opt(r.pixel_match_lecocq),
            m.boundary_pixels.to_string(),
            opt(boundary.then_some(m.boundary_mean_abs_error)),
            opt(m.boundary_p50_abs_error),
            opt(m.boundary_p95_abs_error),
            opt(m.boundary_p99_abs_error),
            r.flip_mean.to_string(),
            r.total_ms.median.to_string(),
            opt(r.total_ms.ci_low),
            opt(r.total_ms.ci_high),
            r.total_ms.min.to_string(),
            r.total_ms.max.to_string(),
            opt(r.cpu_ms.map(|c| c.median)),
            opt(r.cpu_ms.and_then(|c| c.ci_low)),
            opt(r.cpu_ms.and_then(|c| c.ci_high)),
            opt(r.cpu_ms.map(|c| c.min)),
            opt(r.cpu_ms.map(|c| c.max)),
            r.total_ms.n.to_string(),
            r.contended.to_string(),
            opt(r.conditions.and_then(|c| c.min_share)),
            opt(r.conditions.and_then(|c| c.loadavg_before)),
            opt(r.conditions.and_then(|c| c.loadavg_after)),
            report.provenance.commit.clone(),
            report.provenance.version.clone(),
            r.external.to_string(),
        ];
        let t = r.temporal.as_ref();
        cells.extend([
            opt(t.and_then(|t| t.mean)),
            opt(t.and_then(|t| t.p95)),
            opt(t.and_then(|t| t.boundary_mean)),
            opt(t.and_then(|t| t.boundary_p95)),
            t.map_or_else(String::new, |t| t.pixel_pairs.to_string()),
            t.map_or_else(String::new, |_| r.per_frame.len().to_string()),
        ]);
        let shares = r.error_exceedance.iter().map(|v| Some(*v)).chain(std::iter::repeat(None));
        cells.extend(shares.take(EXCEEDANCE_THRESHOLDS.len()).map(opt));
        cells.extend(
            stages
                .iter()
                .map(|name| opt(r.stages.iter().find(|s| s.name == *name).map(|s| s.ms.median))),
        );
        cells.extend(r.counters.entries().into_iter().map(|(_, v)| v.to_string()));
        w.write_record(&cells).map_err(|e| fail(&e))?;
    }
    let bytes = w.into_inner().map_err(|e| fail(&e))?;
    String::from_utf8(bytes).map_err(|e| fail(&e))
}

/// Column heads of the per-scene run tables after the time on the report's clock's head.
pub const RUN_COLUMNS: [&str; 6] =
    ["method", "parameters", "mean abs error", "boundary error", "pixel match", "FLIP"];

/// A summary as `12.3 (11.9–12.8) [11.5, 14.0]`, or `12.3 (no interval) [11.5, 14.0]` with
/// too few timed runs for a confidence interval.
pub fn summary_text(t: &instrumentation::stats::Summary) -> String {
    let ci = match (t.ci_low, t.ci_high) {
        (Some(lo), Some(hi)) => format!("{lo:.1}–{hi:.1}"),
        _ => "no interval".to_owned(),
    };
    format!("{:.1} ({ci}) [{:.1}, {:.1}]", t.median, t.min, t.max)
}

/// A row's cells in the per-scene run tables: [`RUN_COLUMNS`], the time on `clock` (median
/// with its interval), the wall time and whether it was contended. An outside result's method
/// is marked `(external)`; one without a time has its times `not given`.
pub fn run_cells(r: &Row, clock: instrumentation::measure::Clock) -> [String; 9] {
    let given = |text: String| if r.timed() { text } else { "not given".to_owned() };
    [
        crate::model::method_label(r),
        param_label(r),
        format!("{:.5}", r.metrics.mean_abs_error),
        if r.metrics.boundary_pixels == 0 {
            "n/a".to_owned()
        } else {
            format!("{:.4}", r.metrics.boundary_mean_abs_error)
        },
        format!("{:.2} %", 100.0 * r.metrics.pixel_match),
        format!("{:.4}", r.flip_mean),
        given(time_text(r.time(clock))),
        given(ms_text(r.total_ms.median)),
        if r.contended { "yes" } else { "no" }.to_owned(),
    ]
}

/// A page's table in Markdown: the lines stated above it, then its heads and cells as text.
fn md_table_view(s: &mut String, t: &crate::html::TableView) {
    for n in &t.notes {
        match &n.code {
            Some(code) => {
                let _ = writeln!(s, "`{code}`: {}\n", n.text);
            }
            None => {
                let _ = writeln!(s, "{}\n", n.text);
            }
        }
    }
    let heads: Vec<String> = t.heads.iter().map(|h| h.text.clone()).collect();
    let rows: Vec<Vec<String>> =
        t.rows.iter().map(|r| r.iter().map(|c| c.text.clone()).collect()).collect();
    md_table(s, &heads, &rows);
}

/// A Markdown table of `heads` and `rows`.
fn md_table(s: &mut String, heads: &[String], rows: &[Vec<String>]) {
    let _ = writeln!(s, "| {} |", heads.join(" | "));
    let _ = writeln!(s, "|{}", "---|".repeat(heads.len()));
    for r in rows {
        let _ = writeln!(s, "| {} |", r.join(" | "));
    }
}

/// `report.md`: the machine and the load; per scene its Pareto front and, per method, what
/// the runs say of it; the scenes; the best error within each time budget (the figure and
/// the table); today's techniques against the seeds where some scene has runs of both
/// (sentences, charts and per scene the table of `crate::today`); per scene its grids and
/// charts as images (`plots/*.png`) and a table of every run, and for an animated scene its
/// runs in motion (sentence, charts, table); CPU and GPU side by side; the papers' tables;
/// what did not run. `plots` are the charts [`write_plots`],
/// [`crate::motion_charts::write_plots`] and [`crate::today::write_plots`] wrote.
pub fn markdown(report: &Report, plots: &[PlotFile]) -> String {
    let mut s = String::new();
    let clock = clock_name(report.clock);
    let _ = writeln!(s, "# shadowbench report: suite `{}`\n", report.suite.name);
    if !report.suite.description.is_empty() {
        let _ = writeln!(s, "{}\n", report.suite.description);
    }
    let p = &report.provenance;
    let _ = writeln!(
        s,
        "Produced {} by shadowbench {} at commit {}{}, built with {}: `{}`.\n",
        p.timestamp,
        p.version,
        p.commit,
        if p.dirty { " (with uncommitted changes)" } else { "" },
        p.rustc,
        p.command
    );
    let _ = writeln!(
        s,
        "{} A method's time is its own stages (the camera G-buffer is shared and listed per \
         scene).\n",
        measured(report).text()
    );
    let _ = writeln!(s, "## Pareto fronts: mean error against {clock} time\n");
    for f in fronts(report) {
        let _ = writeln!(
            s,
            "### {} ({} against {}; {} of {} runs on the front)\n",
            f.scene,
            f.frame,
            f.reference,
            f.runs.len(),
            f.runs_total
        );
        let heads: Vec<String> = [
            "method",
            "parameters",
            "mean abs error",
            &format!("{clock} ms (95 % interval)"),
            "wall ms",
            "contended",
        ]
        .iter()
        .map(|h| h.to_string())
        .collect();
        let rows: Vec<Vec<String>> = f
            .runs
            .iter()
            .map(|r| {
                vec![
                    r.method.clone(),
                    r.params.clone(),
                    r.error_text.clone(),
                    format!("{} ({})", r.time_text, r.interval_text),
                    r.wall_text.clone(),
                    if r.contended { "yes" } else { "no" }.to_owned(),
                ]
            })
            .collect();
        md_table(&mut s, &heads, &rows);
        s.push('\n');
    }
    let (verdicts, nowhere) = verdicts(report);
    if !verdicts.is_empty() || !nowhere.is_empty() {
        let _ = writeln!(s, "## What the runs say of each method\n");
        for v in &verdicts {
            let _ = writeln!(s, "- `{}`: {}.", v.method, v.sentences.join("; "));
        }
        if !nowhere.is_empty() {
            let names: Vec<String> = nowhere.iter().map(|m| format!("`{m}`")).collect();
            let _ = writeln!(
                s,
                "- On no Pareto front, and neither the most accurate nor the fastest anywhere: \
                 {}.",
                names.join(", ")
            );
        }
        s.push('\n');
    }
    let _ = writeln!(s, "## Scenes\n");
    let _ = writeln!(
        s,
        "| scene | triangles | effects | frame | G-buffer wall ms | reference | reference wall ms |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    for sc in &report.scenes {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {}x{} | {:.1} | {} | {:.1} |",
            sc.scene,
            sc.triangles,
            sc.effects.join(", "),
            sc.width,
            sc.height,
            sc.gbuffer_ms,
            sc.reference,
            sc.reference_ms
        );
    }
    if !report.rows.is_empty() {
        let _ = writeln!(s, "\n## Best error within a time budget\n");
        let _ = writeln!(
            s,
            "Per scene and method, the least mean error of its runs whose median {clock} time \
             fits each budget; **bold** is the least of the scene's methods within it.\n"
        );
        for p in plots.iter().filter(|p| p.scene.is_empty() && p.place == Place::Scene) {
            let _ = writeln!(s, "![{}]({})\n", p.title, p.png);
        }
        let t = budget_table(report);
        let mut heads = vec!["scene".to_owned(), "method".to_owned()];
        heads.extend(t.heads.iter().cloned());
        let rows: Vec<Vec<String>> = t
            .rows
            .iter()
            .map(|r| {
                let mut cells = vec![r.scene.clone(), r.method.clone()];
                cells.extend(r.best.iter().zip(&r.winner).map(|(b, &w)| match b {
                    Some(e) if w => format!("**{}**", error_text(*e)),
                    Some(e) => error_text(*e),
                    None => "no run fits".to_owned(),
                }));
                cells
            })
            .collect();
        md_table(&mut s, &heads, &rows);
    }
    if let Some(t) = crate::index::today_section(report, plots) {
        let _ = writeln!(s, "\n## Against today's techniques\n\n{}", t.about);
        for sc in &t.scenes {
            let _ = writeln!(
                s,
                "\n### {}: today's techniques against the seeds\n\n{}\n",
                sc.name, sc.about
            );
            for p in &sc.plots {
                let _ = writeln!(s, "![{}]({})\n", p.title, p.png);
            }
            md_table_view(&mut s, &sc.table);
        }
    }
    for sc in &report.scenes {
        let _ = writeln!(s, "\n## {}\n", sc.scene);
        for g in report.grids.iter().filter(|g| g.scene == sc.scene) {
            let _ = writeln!(s, "![{}]({})\n", g.title, g.png);
        }
        for p in plots.iter().filter(|p| p.scene == sc.scene && p.place == Place::Scene) {
            let _ = writeln!(s, "![{}]({})\n", p.title, p.png);
        }
        let _ = writeln!(s, "### Runs on {}\n", sc.scene);
        let mut heads: Vec<String> = RUN_COLUMNS.iter().map(|c| c.to_string()).collect();
        heads.extend([format!("{clock} ms (95 % interval)"), "wall ms".into(), "contended".into()]);
        let rows: Vec<Vec<String>> = report
            .rows
            .iter()
            .chain(&report.untimed)
            .filter(|r| r.scene == sc.scene)
            .map(|r| run_cells(r, report.clock).to_vec())
            .collect();
        md_table(&mut s, &heads, &rows);
        let id = format!("scene-{}", crate::html::anchor(&sc.scene));
        if let Some(m) = crate::index::motion_section(report, sc, &id, plots) {
            let _ = writeln!(s, "\n### In motion on {}\n\n{}\n", sc.scene, m.about);
            for p in &m.plots {
                let _ = writeln!(s, "![{}]({})\n", p.title, p.png);
            }
            md_table_view(&mut s, &m.table);
        }
    }
    let side_by_side = crate::devices::markdown(&report.rows);
    if !side_by_side.is_empty() {
        let _ = writeln!(
            s,
            "\n## CPU and GPU\n\nThe same method and parameters on both devices, in wall-clock \
             time; GPU: {}.\n",
            report.machine.gpu.as_deref().unwrap_or("none")
        );
        s.push_str(&side_by_side);
    }
    if !report.tables.is_empty() {
        let _ = writeln!(s, "\n## The papers' tables\n");
        for t in &report.tables {
            let _ = writeln!(s, "{}", crate::tables::markdown(t));
        }
    }
    if !report.skipped.is_empty() {
        let _ = writeln!(s, "\n## Not run\n");
        for k in &report.skipped {
            let _ = writeln!(s, "- {k}");
        }
    }
    s
}

/// The default reference cache's folder in a report folder (`report --cache`).
pub use crate::publish::CACHE_DIR;

/// Writes `index.html`, `report.md`, `runs.csv`, `runs.json`, `plots/*.png|svg`,
/// `tables/*.csv` (the papers' tables), `visibility/*.exr`, the grids, the scenes' and runs'
/// images and records, and every run's page into `dir`.
pub fn write_report(
    dir: &Path,
    report: &Report,
    images: &Images,
    baseline: Option<&crate::baseline::Comparison>,
) -> Result<(), OutputError> {
    write_run_files(dir, report, images)?;
    write_summary(dir, report, baseline)
}

/// A shard's folder: what [`write_run_files`] writes and `runs.json`; the
/// pages, charts and tables are the merge's (`report merge`).
pub fn write_shard(dir: &Path, report: &Report, images: &Images) -> Result<(), OutputError> {
    write_run_files(dir, report, images)?;
    let path = dir.join("runs.json");
    let json = serde_json::to_string_pretty(report)
        .map_err(|e| OutputError::Write { path: path.clone(), message: e.to_string() })?;
    std::fs::write(&path, json)
        .map_err(|e| OutputError::Write { path: path.clone(), message: e.to_string() })
}

/// The files made from a sweep's images: `visibility/ID.exr`, `grids/*.png`, `scenes/*` and
/// `runs/ID.{png,error.png,run.json,metrics.json}`, and for a run in motion `runs/ID/frames/*`
/// and `runs/ID.{animation.png,frames.csv,temporal.json}` (a merged report copies them from
/// its shards).
pub fn write_run_files(dir: &Path, report: &Report, images: &Images) -> Result<(), OutputError> {
    let err = |path: &Path, e: &dyn std::fmt::Display| OutputError::Write {
        path: path.to_owned(),
        message: e.to_string(),
    };
    let exr_dir = dir.join("visibility");
    std::fs::create_dir_all(&exr_dir).map_err(|e| err(&exr_dir, &e))?;
    let grid_dir = dir.join("grids");
    std::fs::create_dir_all(&grid_dir).map_err(|e| err(&grid_dir, &e))?;
    for g in &images.grids {
        write_grid(&dir.join(&report.grids[g.grid].png), &g.panels, g.inset)?;
    }
    for p in &images.runs {
        let path = exr_dir.join(format!("{}.exr", row_stem(&report.rows[p.row])));
        write_visibility_exr(&path, &p.visibility)?;
    }
    crate::run_pages::scene_files(dir, report, images)?;
    crate::run_pages::run_files(dir, report, images)
}

/// The files made from the report alone: `runs.json`, `runs.csv`, `report.md`, `index.html`,
/// `plots/*`, `tables/*.csv`, `baseline.md`, and every run's page.
pub fn write_summary(
    dir: &Path,
    report: &Report,
    baseline: Option<&crate::baseline::Comparison>,
) -> Result<(), OutputError> {
    let err = |path: &Path, e: &dyn std::fmt::Display| OutputError::Write {
        path: path.to_owned(),
        message: e.to_string(),
    };
    let json = serde_json::to_string_pretty(report).map_err(|e| err(dir, &e))?;
    let mut plots = write_plots(dir, report)?;
    plots.extend(crate::motion_charts::write_plots(dir, report)?);
    plots.extend(crate::today::write_plots(dir, report)?);
    let pages = crate::templates::Pages::new().map_err(|e| err(dir, &e))?;
    let index = dir.join("index.html");
    let html =
        crate::index::index_html(&pages, report, &plots, baseline).map_err(|e| err(&index, &e))?;
    let mut md = markdown(report, &plots);
    if let Some(c) = baseline {
        // The comparison's summary first, under the title; the whole of it in baseline.md.
        let summary = format!(
            "## Against the baseline\n\n{}.\n\nRegressions: {}. Run by run: `baseline.md`.\n\n",
            crate::baseline::summary_line(c),
            c.regressions().count()
        );
        let at = md.find("\n\n").map_or(md.len(), |k| k + 2);
        md.insert_str(at, &summary);
        let path = dir.join("baseline.md");
        std::fs::write(&path, crate::baseline::markdown(c)).map_err(|e| err(&path, &e))?;
    }
    for (name, text) in
        [("runs.json", json), ("runs.csv", csv(report)?), ("report.md", md), ("index.html", html)]
    {
        let path = dir.join(name);
        std::fs::write(&path, text).map_err(|e| err(&path, &e))?;
    }
    if !report.tables.is_empty() {
        let tables = dir.join("tables");
        std::fs::create_dir_all(&tables).map_err(|e| err(&tables, &e))?;
        for t in &report.tables {
            let path = tables.join(format!("{}.csv", t.paper.name()));
            let text = crate::tables::csv(t).map_err(|e| err(&path, &e))?;
            std::fs::write(&path, text).map_err(|e| err(&path, &e))?;
        }
    }
    crate::run_pages::write_run_pages(dir, report).map(|_| ())
}

#[cfg(test)]
mod tests {
    use crate::model::{Report, Row};
    use crate::plan::{Work, WorkItem};
    use crate::suite::Suite;
    use instrumentation::Recorder;
    use methods::{Frame, MethodOptions};

    /// A suite's `[[external]]` results: `sm`'s own lit fraction, read back from an EXR, is
    /// scored exactly as the `sm` run it came from; with a time it is a row, in the runs
    /// table and on the error-against-time (Pareto) chart, marked external; without one, in
    /// the runs table only, its time not given.
    #[test]
    fn outside_results_are_scored_as_rows_and_drawn_only_with_a_time() {
        let dir = tempfile::tempdir().expect("tempdir");
        let scene = scenes::load("plane-square").expect("built in");
        let (w, h) = (48, 36);
        let frame = Frame::new(&scene, w, h, &mut Recorder::default());
        let sm = analysis::registry::technique("sm", &MethodOptions::default()).expect("sm");
        let v = sm.run(&frame, &mut Recorder::default()).expect("runs");
        crate::output::write_visibility_exr(&dir.path().join("sm.exr"), &v).expect("writes");
        let text = format!(
            "name = \"outside\"\nwidth = {w}\nheight = {h}\nwarmup = 0\nrepeats = 1\n\
             scenes = [\"plane-square\"]\n[[run]]\nmethod = \"sm\"\n\
             [[external]]\nname = \"mine\"\ntime_ms = 2.5\nfiles = {{ plane-square = \"sm.exr\" }}\n\
             [[external]]\nname = \"untimed\"\nfiles = {{ plane-square = \"sm.exr\" }}\n"
        );
        let suite = Suite::parse(&text, &dir.path().join("suite.toml")).expect("parses");
        let plan = crate::plan::plan(&suite);
        let externals: Vec<&WorkItem> =
            plan.iter().filter(|i| matches!(i.work, Work::External { .. })).collect();
        assert_eq!(externals.len(), 2, "one item per entry and scene");
        let all: Vec<usize> = (0..plan.len()).collect();
        assert_eq!(crate::sweep::items_run_count(&plan, &all), 3);
        let (report, images) = crate::sweep::run_suite(&suite, |_| {});
        assert!(report.skipped.is_empty(), "{:?}", report.skipped);
        let by = |m: &str| report.rows.iter().find(|r| r.method == m).expect(m);
        let (method, mine) = (by("sm"), by("mine"));
        assert!(mine.external && !method.external);
        assert_eq!(mine.metrics, method.metrics, "the same lit fraction, the same metrics");
        assert_eq!(mine.classes, method.classes);
        assert_eq!((mine.total_ms.median, mine.total_ms.n), (2.5, 1));
        assert!(report.rows.iter().all(|r| r.method != "untimed"));
        let [untimed] = report.untimed.as_slice() else { panic!("{:?}", report.untimed) };
        assert!(untimed.external && !untimed.timed());
        assert_eq!(untimed.metrics, method.metrics);
        assert_eq!(images.runs.len(), 2, "pages and images for the timed rows");
        let produced = images.runs.iter().find(|p| p.row == 1).expect("the outside row's");
        assert_eq!((produced.metrics.method_ms, produced.metrics.external), (Some(2.5), true));

        // runs.json keeps both, and reads back.
        let json = serde_json::to_string(&report).expect("serialises");
        let back: Report = serde_json::from_str(&json).expect("reads back");
        assert_eq!(back.untimed, report.untimed);
        assert!(back.rows.iter().any(|r| r.external));
        // The runs table: both, marked; the untimed one's time not given and no page.
        let rows: Vec<&Row> = report.rows.iter().chain(&report.untimed).collect();
        let table =
            serde_json::to_string(&crate::index::runs_table(&rows, &report)).expect("serialises");
        assert!(table.contains("mine (external)") && table.contains("untimed (external)"));
        assert!(table.contains("not given"), "{table}");
        assert!(!table.contains("runs/plane-square-untimed.html"), "{table}");
        let cells = super::run_cells(untimed, report.clock);
        assert_eq!((cells[0].as_str(), cells[6].as_str()), ("untimed (external)", "not given"));
        // The error-against-time chart has the timed one, at its time, and not the other.
        let charts = crate::figures::charts(&report);
        let pareto: Vec<_> = charts.iter().filter(|c| c.chart.pareto).collect();
        let series: Vec<&crate::plots::Series> =
            pareto.iter().flat_map(|c| &c.chart.series).collect();
        let outside = series.iter().find(|s| s.label == "mine (external)").expect("drawn");
        assert_eq!(outside.points[0].x, 2.5);
        assert!(series.iter().all(|s| !s.label.contains("untimed")));
    }

    /// The index and report.md of a report with a run in motion: the scene's section "In
    /// motion" with its table and charts; the same report still has none.
    #[test]
    fn only_a_scene_with_runs_in_motion_has_an_in_motion_section() {
        let (report, images) = crate::motion_charts::fixture::report_in_motion();
        let dir = tempfile::tempdir().expect("tempdir");
        super::write_report(dir.path(), &report, &images, None).expect("written");
        let html = std::fs::read_to_string(dir.path().join("index.html")).expect("index");
        assert_eq!(html.matches("id=\"scene-plane-square-motion\"").count(), 1);
        assert!(html.contains("href=\"#scene-plane-square-motion\""), "in the contents");
        // Its table has the run in motion only, linked to its players.
        let stem = crate::model::row_stem(&report.rows[0]);
        assert!(html.contains(&format!("runs/{stem}.html#motion")), "{html}");
        assert!(!html
            .contains(&format!("runs/{}.html#motion", crate::model::row_stem(&report.rows[1]))));
        assert!(html.contains("<th class=\"num\">temporal error</th>"), "{html}");
        // Its three charts, there and nowhere else.
        for kind in ["temporal-vs-time", "temporal-vs-error", "temporal-per-frame"] {
            let png = format!("plots/{kind}-plane-square.png");
            assert_eq!(html.matches(&format!("src=\"{png}\"")).count(), 1, "{png}");
            assert!(dir.path().join(&png).is_file(), "{png}");
        }
        for term in ["temporal error", "boundary temporal error", "pixel pairs", "reprojection"] {
            assert!(html.contains(&format!("<dt>{term}</dt>")), "glossary lacks {term}");
        }
        assert!(html.contains("<dt>light-frustum policy</dt>"));
        let md = std::fs::read_to_string(dir.path().join("report.md")).expect("report.md");
        assert_eq!(md.matches("### In motion on plane-square").count(), 1, "{md}");
        assert!(md.contains("| temporal error |"), "{md}");
        assert!(md.contains("![plane-square: temporal error per frame"), "{md}");

        // The same report still: no section, no chart.
        let mut still = report.clone();
        still.rows.iter_mut().for_each(|r| {
            r.temporal = None;
            r.per_frame.clear();
        });
        let plots = crate::motion_charts::write_plots(dir.path(), &still).expect("none");
        assert!(plots.is_empty());
        let page = crate::index::index_page(&still, &plots, None);
        assert!(page.scenes.iter().all(|s| s.motion.is_none()));
        assert!(!super::markdown(&still, &plots).contains("In motion"));
    }
}
