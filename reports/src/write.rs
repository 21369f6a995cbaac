//! A report's files: `runs.json` (everything), `runs.csv` (one line per run: parameters,
//! metrics, times, counters), `report.md` (the tables), and `visibility/*.exr` (every
//! visibility buffer).

use crate::figures::write_plots;
use crate::grids::write_grid;
use crate::output::{write_visibility_exr, OutputError};
use crate::sweep::{GridImages, Produced, Report, Row};
use instrumentation::Counters;
use std::fmt::Write as _;
use std::path::Path;

/// A parameter of a row as text (empty when the method has no such parameter).
fn param(row: &Row, key: &str) -> String {
    row.params.get(key).map_or_else(String::new, |v| v.to_string().trim_matches('"').to_owned())
}

/// A short label of the row's parameters, e.g. `map_res=1024 rate=16`.
pub fn param_label(row: &Row) -> String {
    ["map_res", "rate", "depth_bits", "pattern", "device"]
        .iter()
        .filter(|k| row.params.contains_key(**k))
        .map(|k| format!("{k}={}", param(row, k)))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The file stem of a row's visibility buffer.
pub fn row_stem(row: &Row) -> String {
    let label = param_label(row).replace(['=', ' '], "-");
    let stem = format!("{}-{}-{label}", row.scene, row.method);
    stem.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' }).collect()
}

/// Columns of `runs.csv` before the counters.
pub const CSV_COLUMNS: &[&str] = &[
    "scene",
    "method",
    "map_res",
    "rate",
    "depth_bits",
    "pattern",
    "device",
    "width",
    "height",
    "reference",
    "ref_rate",
    "evaluated_pixels",
    "mean_abs_error",
    "rmse",
    "max_abs_error",
    "pixel_match",
    "boundary_pixels",
    "boundary_mean_abs_error",
    "flip_mean",
    "time_median_ms",
    "time_min_ms",
    "time_max_ms",
    "commit",
    "version",
];

/// `runs.csv`: a header, then one line per row; counters follow the columns of
/// [`CSV_COLUMNS`] under their own names.
pub fn csv(report: &Report) -> String {
    let mut out = CSV_COLUMNS.join(",");
    for name in Counters::NAMES {
        out.push(',');
        out.push_str(name);
    }
    out.push('\n');
    for r in &report.rows {
        let m = &r.metrics;
        let mut cells = vec![
            r.scene.clone(),
            r.method.clone(),
            param(r, "map_res"),
            param(r, "rate"),
            param(r, "depth_bits"),
            param(r, "pattern"),
            if crate::devices::is_gpu(r) { "gpu" } else { "cpu" }.to_owned(),
            r.width.to_string(),
            r.height.to_string(),
            r.reference.clone(),
            r.ref_rate.map_or_else(String::new, |v| v.to_string()),
            m.evaluated_pixels.to_string(),
            m.mean_abs_error.to_string(),
            m.rmse.to_string(),
            m.max_abs_error.to_string(),
            m.pixel_match.to_string(),
            m.boundary_pixels.to_string(),
            m.boundary_mean_abs_error.to_string(),
            r.flip_mean.to_string(),
            r.total_ms.median.to_string(),
            r.total_ms.min.to_string(),
            r.total_ms.max.to_string(),
            report.provenance.commit.clone(),
            report.provenance.version.clone(),
        ];
        cells.extend(r.counters.entries().into_iter().map(|(_, v)| v.to_string()));
        // Scene names and parameters hold no commas or quotes; quote defensively anyway.
        let line: Vec<String> =
            cells
                .into_iter()
                .map(|c| {
                    if c.contains([',', '"']) {
                        format!("\"{}\"", c.replace('"', "\"\""))
                    } else {
                        c
                    }
                })
                .collect();
        out.push_str(&line.join(","));
        out.push('\n');
    }
    out
}

/// Column heads of the per-scene run tables.
pub const RUN_COLUMNS: [&str; 7] = [
    "method",
    "parameters",
    "mean abs error",
    "boundary error",
    "pixel match",
    "FLIP",
    "time ms [min, max]",
];

/// A row's cells in the per-scene run tables, under [`RUN_COLUMNS`].
pub fn run_cells(r: &Row) -> [String; 7] {
    [
        r.method.clone(),
        param_label(r),
        format!("{:.5}", r.metrics.mean_abs_error),
        format!("{:.4}", r.metrics.boundary_mean_abs_error),
        format!("{:.2} %", 100.0 * r.metrics.pixel_match),
        format!("{:.4}", r.flip_mean),
        format!("{:.1} [{:.1}, {:.1}]", r.total_ms.median, r.total_ms.min, r.total_ms.max),
    ]
}

/// `report.md`: the machine, the scenes, and per scene a table of every run.
pub fn markdown(report: &Report) -> String {
    let mut s = String::new();
    let m = &report.machine;
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
        "Machine: {} ({} cores, {} threads, {}); GPU: {}. Times: median of {} runs after {} \
         warm-up, [min, max]; a method's time is its own stages (the camera G-buffer is shared \
         and listed per scene).\n",
        m.cpu,
        m.cores,
        m.threads,
        m.os,
        m.gpu.as_deref().unwrap_or("none used"),
        report.suite.repeats,
        report.suite.warmup
    );
    let _ = writeln!(s, "## Scenes\n");
    let _ = writeln!(
        s,
        "| scene | triangles | effects | frame | G-buffer ms | reference | reference ms |"
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
    for sc in &report.scenes {
        let _ = writeln!(s, "\n## {}\n", sc.scene);
        for g in report.grids.iter().filter(|g| g.scene == sc.scene) {
            let _ = writeln!(s, "![{}]({})\n", g.title, g.png);
        }
        let _ = writeln!(s, "| {} |", RUN_COLUMNS.join(" | "));
        let _ = writeln!(s, "|{}", "---|".repeat(RUN_COLUMNS.len()));
        for r in report.rows.iter().filter(|r| r.scene == sc.scene) {
            let _ = writeln!(s, "| {} |", run_cells(r).join(" | "));
        }
    }
    let side_by_side = crate::devices::markdown(&report.rows);
    if !side_by_side.is_empty() {
        let _ = writeln!(
            s,
            "\n## CPU and GPU\n\nThe same method and parameters on both devices; GPU: {}.\n",
            m.gpu.as_deref().unwrap_or("none")
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

/// Writes `index.html`, `report.md`, `runs.csv`, `runs.json`, `plots/*.png|svg`,
/// `tables/*.csv` (the papers' tables) and `visibility/*.exr` into `dir`.
pub fn write_report(
    dir: &Path,
    report: &Report,
    produced: &[Produced],
    grids: &[GridImages],
) -> Result<(), OutputError> {
    let err = |path: &Path, e: &dyn std::fmt::Display| OutputError::Write {
        path: path.to_owned(),
        message: e.to_string(),
    };
    let images = dir.join("visibility");
    std::fs::create_dir_all(&images).map_err(|e| err(&images, &e))?;
    let grid_dir = dir.join("grids");
    std::fs::create_dir_all(&grid_dir).map_err(|e| err(&grid_dir, &e))?;
    for g in grids {
        write_grid(&dir.join(&report.grids[g.grid].png), &g.panels, g.inset)?;
    }
    let json = serde_json::to_string_pretty(report).map_err(|e| err(dir, &e))?;
    let plots = write_plots(dir, report)?;
    let html = crate::html::index_html(report, &plots);
    for (name, text) in [
        ("runs.json", json),
        ("runs.csv", csv(report)),
        ("report.md", markdown(report)),
        ("index.html", html),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).map_err(|e| err(&path, &e))?;
    }
    if !report.tables.is_empty() {
        let tables = dir.join("tables");
        std::fs::create_dir_all(&tables).map_err(|e| err(&tables, &e))?;
        for t in &report.tables {
            let path = tables.join(format!("{}.csv", t.paper.name()));
            std::fs::write(&path, crate::tables::csv(t)).map_err(|e| err(&path, &e))?;
        }
    }
    for p in produced {
        let path = images.join(format!("{}.exr", row_stem(&report.rows[p.row])));
        write_visibility_exr(&path, &p.visibility)?;
    }
    Ok(())
}
