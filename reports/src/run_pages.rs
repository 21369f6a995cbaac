//! A page per run of a report, `runs/ID.html` (ID: the run's file stem,
//! [`crate::model::row_stem`]), with the run's files beside it:
//!
//! - `runs/ID.png`: the method's lit fraction as 8-bit grey (black in shadow, white lit);
//! - `runs/ID.error.png`: `|method - reference|` on the compared pixels in false colour
//!   (magma, 0 to [`analysis::error_map::DEFAULT_MAX_ERROR`], with its colour bar; dark grey
//!   where nothing is compared), as `compare` writes `error.png`;
//! - `runs/ID.run.json`: the run record of its last timed run, as `render` writes `run.json`;
//! - `runs/ID.metrics.json`: its comparison with the reference, per pixel class, as `compare`
//!   writes `metrics.json`;
//! - `visibility/ID.exr`: its visibility buffer;
//! - for a run in motion (its scene animated, `crate::motion`): `runs/ID/frames/method-NNNN.png`,
//!   `reference-NNNN.png` and `error-NNNN.png` (NNNN the frame from 0000: the method's shaded
//!   image, the reference's and the error map), `runs/ID.frames.csv` (a row per frame, the
//!   columns of `animate`'s `frames.csv`, `crate::animation::FrameRecord`) and
//!   `runs/ID.temporal.json` (its temporal metrics, `analysis::temporal::TemporalMetrics`);
//!
//! and its scene's, shared by the scene's runs ([`scene_files`]): the reference's lit
//! fraction (`scenes/SCENE.reference.png`, and `.exr`) and the pixel classes
//! (`scenes/SCENE.classes.png`).
//!
//! A page is rendered by the `run.html` template (`reports/templates/`, [`crate::templates`])
//! from a [`RunPage`] built from the report. It shows the run's parameters, metrics (the
//! headline and each pixel class, every count), its times on both clocks (median, interval
//! or "no interval", [min, max]) with the machine's load and whether it was contended, stage
//! times and counters, and a comparison view (plain JavaScript from
//! `reports/assets/report.js`, nothing from the network) over the run's image, the reference,
//! the error map, the class map and the images of the scene's other runs: zoom with the wheel
//! or `+`/`-`, pan by dragging, `0` to fit; step through the views with the buttons, the list,
//! the arrow keys or `n`/`p`; `f` flips between this run and the last other view (the
//! reference at first); `s` swipes between the two (this run left of the pointer, the other
//! right of it). `ID.html#view=N` opens the page on view N (1 the reference, 2 the error
//! map, 3 the class map). Opened as `ID.html#selftest`, the page flips, zooms, pans and swipes itself
//! and writes what it found into `<pre id="selftest">`.

use crate::figures::clock_name;
use crate::html::{anchor, metric_cells, Cell, METRIC_COLUMNS};
use crate::model::{
    param_label, params_of, row_stem, scene_stem, Images, MotionFrames, Report, Row,
};
use crate::output::{write_run_json, write_visibility_exr, OutputError};
use crate::summary::{full_time_text, ms_text};
use crate::templates::{Pages, TemplateError};
use analysis::metrics::PerClass;
use instrumentation::measure::Clock;
use methods::Visibility;
use serde::Serialize;
use std::path::Path;

/// A run's lit fraction as 8-bit grey (0 in shadow, 255 lit).
pub fn lit_image(v: &Visibility) -> image::GrayImage {
    image::GrayImage::from_fn(v.width, v.height, |x, y| {
        let l = v.lit[(y * v.width + x) as usize];
        image::Luma([(l.clamp(0.0, 1.0) * 255.0).round() as u8])
    })
}

/// What a run is called on its page and in the list of views.
fn title(r: &Row) -> String {
    let params = param_label(r);
    if params.is_empty() {
        r.method.clone()
    } else {
        format!("{} {params}", r.method)
    }
}

/// One image of the comparison view.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct View {
    /// The image, relative to the page.
    pub src: String,
    /// What it is.
    pub label: String,
}

/// The views of the run `report.rows[row]`: its image, the reference, its error map, the
/// class map, then the images of the scene's other runs (same scene and frame) in report
/// order.
pub fn views(report: &Report, row: usize) -> Vec<View> {
    let r = &report.rows[row];
    let stem = row_stem(r);
    let scene = scene_stem(&r.scene);
    let mut v = vec![
        View { src: format!("{stem}.png"), label: format!("{} (this run)", title(r)) },
        View {
            src: format!("../scenes/{scene}.reference.png"),
            label: format!("reference ({})", reference_text(r)),
        },
        View {
            src: format!("{stem}.error.png"),
            label: format!(
                "|error| of this run, 0 to {} (magma)",
                analysis::error_map::DEFAULT_MAX_ERROR
            ),
        },
        View {
            src: format!("../scenes/{scene}.classes.png"),
            label: "pixel classes (blue planar, green surface, red edge, black uncovered)".into(),
        },
    ];
    let same = |o: &Row| o.scene == r.scene && (o.width, o.height) == (r.width, r.height);
    v.extend(
        report
            .rows
            .iter()
            .enumerate()
            .filter(|(k, o)| *k != row && same(o))
            .map(|(_, o)| View { src: format!("{}.png", row_stem(o)), label: title(o) }),
    );
    v
}

/// The reference a row was measured against, in words.
fn reference_text(r: &Row) -> String {
    match r.ref_rate {
        Some(rate) => format!("{} at {rate} samples per pixel", r.reference),
        None => r.reference.clone(),
    }
}

/// A row of a table of cells under a name (a pixel class, a stage).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NamedRow {
    /// The row's name.
    pub name: String,
    /// Its cells.
    pub cells: Vec<Cell>,
}

/// Everything a run's page shows, for its template.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunPage {
    /// `run`, for the page's `data-page`.
    pub page: &'static str,
    /// The page's title.
    pub title: String,
    /// Method.
    pub method: String,
    /// Scene.
    pub scene: String,
    /// Its parameters in a line.
    pub params: String,
    /// The anchor of the scene's runs table in `index.html`.
    pub back: String,
    /// The run's file stem.
    pub stem: String,
    /// The scene's file stem.
    pub scene_stem: String,
    /// The images of the comparison view.
    pub views: Vec<View>,
    /// Parameters, frame and reference.
    pub parameters: Vec<(String, Cell)>,
    /// The headline metrics, every count included.
    pub metrics: Vec<(String, Cell)>,
    /// Each pixel class's metrics.
    pub classes: Vec<NamedRow>,
    /// Its times on both clocks and the conditions they were taken under.
    pub timing: Vec<(String, Cell)>,
    /// The stage table's heads after `stage`.
    pub stage_heads: Vec<String>,
    /// Each stage's times, then the total.
    pub stages: Vec<NamedRow>,
    /// Stages the scene did not call for.
    pub skipped_stages: Vec<String>,
    /// The timing protocol, in words.
    pub protocol: String,
    /// Counters of the last timed run that are not zero.
    pub counters: Vec<(String, Cell)>,
    /// The method's notes.
    pub notes: Vec<String>,
}

/// A time in milliseconds as a cell.
fn ms(v: f64) -> Cell {
    Cell::sorted(ms_text(v), v)
}

/// A share as a percentage cell, `n/a` where unknown.
fn percent(v: Option<f64>) -> Cell {
    v.map_or_else(Cell::na, |v| Cell::sorted(format!("{:.1} %", 100.0 * v), v))
}

/// The model of the page of the run `report.rows[row]`.
pub fn run_page_model(report: &Report, row: usize) -> RunPage {
    let r = &report.rows[row];
    let mut parameters: Vec<(String, Cell)> =
        params_of(r).into_iter().map(|(k, v)| (k, Cell::text(v))).collect();
    parameters.push(("frame".into(), Cell::text(format!("{}x{}", r.width, r.height))));
    parameters.push(("reference".into(), Cell::text(reference_text(r))));
    let mut metrics = vec![
        ("compared pixels".to_owned(), Cell::num(r.metrics.evaluated_pixels as f64, 0)),
        (
            "max abs error".to_owned(),
            if r.metrics.evaluated_pixels == 0 {
                Cell::na()
            } else {
                Cell::num(r.metrics.max_abs_error, 5)
            },
        ),
    ];
    metrics.extend(METRIC_COLUMNS.iter().map(|c| c.to_string()).zip(metric_cells(r)));
    let clock = clock_name(report.clock);
    let c = r.conditions.unwrap_or_default();
    let load = match (c.loadavg_before, c.loadavg_after) {
        (Some(a), Some(b)) => Cell::text(format!("{a:.2} -> {b:.2}")),
        _ => Cell::na(),
    };
    let cost = |c: Clock| if c == report.clock { ", the report's cost" } else { "" };
    let timing = vec![
        (
            format!("CPU ms{}", cost(Clock::Cpu)),
            r.cpu_ms.map_or_else(Cell::na, |t| Cell::sorted(full_time_text(&t), t.median)),
        ),
        (
            format!("wall ms{}", cost(Clock::Wall)),
            Cell::sorted(full_time_text(&r.total_ms), r.total_ms.median),
        ),
        ("timed runs".to_owned(), Cell::num(f64::from(r.total_ms.n), 0)),
        ("contended".to_owned(), Cell::text(if r.contended { "yes" } else { "no" })),
        ("lowest CPU share of a kept run".to_owned(), percent(c.min_share)),
        ("cores taken by other processes".to_owned(), percent(c.others_share)),
        ("load average before -> after".to_owned(), load),
    ];
    let any_cpu = r.stages.iter().any(|s| s.cpu_ms.is_some());
    let mut stage_heads: Vec<String> =
        ["wall median", "wall min", "wall max"].iter().map(|s| s.to_string()).collect();
    if any_cpu {
        stage_heads.push("CPU median".into());
    }
    let mut stages: Vec<NamedRow> = r
        .stages
        .iter()
        .map(|st| {
            let mut cells = vec![ms(st.ms.median), ms(st.ms.min), ms(st.ms.max)];
            if any_cpu {
                cells.push(st.cpu_ms.map_or_else(Cell::na, |t| ms(t.median)));
            }
            NamedRow { name: st.name.clone(), cells }
        })
        .collect();
    let t = &r.total_ms;
    let mut total = vec![ms(t.median), ms(t.min), ms(t.max)];
    if any_cpu {
        total.push(r.cpu_ms.map_or_else(Cell::na, |c| ms(c.median)));
    }
    stages.push(NamedRow { name: "total".into(), cells: total });
    let s = &report.suite;
    RunPage {
        page: "run",
        title: format!("{} on {}", title(r), r.scene),
        method: r.method.clone(),
        scene: r.scene.clone(),
        params: param_label(r),
        back: format!("scene-{}-runs", anchor(&r.scene)),
        stem: row_stem(r),
        scene_stem: scene_stem(&r.scene),
        views: views(report, row),
        parameters,
        metrics,
        classes: r.classes.as_ref().map(class_rows).unwrap_or_default(),
        timing,
        stage_heads,
        stages,
        skipped_stages: r.skipped_stages.clone(),
        protocol: format!(
            "Milliseconds, the median of {} timed runs ({} to {} by the suite) after {} warm-up, \
             with minimum and maximum; the report's cost is the {clock} time.",
            r.total_ms.n,
            s.repeats,
            s.protocol().max_repeats,
            s.warmup
        ),
        counters: r
            .counters
            .entries()
            .into_iter()
            .filter(|(_, v)| *v != 0)
            .map(|(k, v)| (k.to_owned(), Cell::num(v as f64, 0)))
            .collect(),
        notes: r.notes.clone(),
    }
}

/// The page of the run `report.rows[row]`, rendered.
pub fn run_page(pages: &Pages, report: &Report, row: usize) -> Result<String, TemplateError> {
    pages.render("run.html", &run_page_model(report, row))
}

/// Each pixel class's metrics (`metrics.json`'s `classes`), `n/a` where a class has no
/// compared pixel: pixels, mean, RMSE, max, p95, boundary pixels, boundary error and its p95.
fn class_rows(classes: &PerClass) -> Vec<NamedRow> {
    [("planar", &classes.planar), ("surface", &classes.surface), ("edge", &classes.edge)]
        .into_iter()
        .map(|(name, m)| {
            let or_na = |v: Option<f64>| v.map_or_else(Cell::na, |v| Cell::num(v, 5));
            NamedRow {
                name: name.to_owned(),
                cells: vec![
                    Cell::num(m.pixels as f64, 0),
                    or_na(m.mean_abs_error),
                    or_na(m.rmse),
                    or_na(m.max_abs_error),
                    or_na(m.p95_abs_error),
                    Cell::num(m.boundary_pixels as f64, 0),
                    or_na(m.boundary_mean_abs_error),
                    or_na(m.boundary_p95_abs_error),
                ],
            }
        })
        .collect()
}

/// Writes every scene's shared images into `dir/scenes/`: `SCENE.reference.png` (the
/// reference's lit fraction in grey), `SCENE.reference.exr` (the same in 32-bit float) and
/// `SCENE.classes.png` (the pixel classes, coloured as `render --method exact` colours them).
pub fn scene_files(dir: &Path, report: &Report, images: &Images) -> Result<(), OutputError> {
    let scenes = dir.join("scenes");
    std::fs::create_dir_all(&scenes).map_err(|e| write_err(&scenes, &e))?;
    for sc in &images.scenes {
        let stem = scene_stem(&report.scenes[sc.scene].scene);
        let lit = sc.reference.to_visibility();
        let path = scenes.join(format!("{stem}.reference.png"));
        lit_image(&lit).save(&path).map_err(|e| write_err(&path, &e))?;
        write_visibility_exr(&scenes.join(format!("{stem}.reference.exr")), &lit)?;
        let (w, h) = (sc.reference.width, sc.reference.height);
        let path = scenes.join(format!("{stem}.classes.png"));
        image::RgbImage::from_fn(w, h, |x, y| {
            image::Rgb(sc.classes[(y * w + x) as usize].colour())
        })
        .save(&path)
        .map_err(|e| write_err(&path, &e))?;
    }
    Ok(())
}

/// Writes, for every produced run, into `dir/runs/`: `ID.png` (its lit fraction),
/// `ID.error.png` (its error map), `ID.run.json` and `ID.metrics.json`; for a run in motion
/// also its frames, `ID.frames.csv` and `ID.temporal.json` ([`motion_files`]).
pub fn run_files(dir: &Path, report: &Report, images: &Images) -> Result<(), OutputError> {
    let runs = dir.join("runs");
    std::fs::create_dir_all(&runs).map_err(|e| write_err(&runs, &e))?;
    for p in &images.runs {
        let stem = row_stem(&report.rows[p.row]);
        let sc = &images.scenes[p.scene];
        let path = runs.join(format!("{stem}.png"));
        lit_image(&p.visibility).save(&path).map_err(|e| write_err(&path, &e))?;
        let path = runs.join(format!("{stem}.error.png"));
        let max = analysis::error_map::DEFAULT_MAX_ERROR;
        analysis::error_map::error_map(&p.visibility, &sc.reference.lit, &sc.compared, max)
            .map_err(|e| write_err(&path, &e))?
            .save(&path)
            .map_err(|e| write_err(&path, &e))?;
        write_run_json(&runs.join(format!("{stem}.run.json")), &p.record)?;
        let path = runs.join(format!("{stem}.metrics.json"));
        let text = serde_json::to_string_pretty(&p.metrics).map_err(|e| write_err(&path, &e))?;
        std::fs::write(&path, text + "\n").map_err(|e| write_err(&path, &e))?;
        if let Some(motion) = &p.motion {
            motion_files(&runs, &stem, &report.rows[p.row], motion)?;
        }
    }
    Ok(())
}

/// Writes a run in motion's files into `runs` (the report's `runs/`): `STEM/frames/KIND-NNNN.png`
/// for each kind (`method`, `reference`, `error`) and frame, `STEM.frames.csv` (the row's
/// frames) and `STEM.temporal.json` (its temporal metrics, `null` for a row without).
fn motion_files(
    runs: &Path,
    stem: &str,
    row: &Row,
    motion: &MotionFrames,
) -> Result<(), OutputError> {
    let frames = runs.join(stem).join("frames");
    std::fs::create_dir_all(&frames).map_err(|e| write_err(&frames, &e))?;
    for (kind, pngs) in
        [("method", &motion.method), ("reference", &motion.reference), ("error", &motion.error)]
    {
        for (i, bytes) in pngs.iter().enumerate() {
            let path = frames.join(format!("{kind}-{i:04}.png"));
            std::fs::write(&path, bytes).map_err(|e| write_err(&path, &e))?;
        }
    }
    let path = runs.join(format!("{stem}.frames.csv"));
    let mut w = csv::Writer::from_writer(Vec::new());
    for f in &row.per_frame {
        w.serialize(f).map_err(|e| write_err(&path, &e))?;
    }
    let bytes = w.into_inner().map_err(|e| write_err(&path, &e))?;
    std::fs::write(&path, bytes).map_err(|e| write_err(&path, &e))?;
    let path = runs.join(format!("{stem}.temporal.json"));
    let text = serde_json::to_string_pretty(&row.temporal).map_err(|e| write_err(&path, &e))?;
    std::fs::write(&path, text + "\n").map_err(|e| write_err(&path, &e))
}

/// Writes every run's page, `dir/runs/ID.html` (its files are to be there or to follow:
/// [`run_files`]). Returns the pages' paths relative to `dir`, in report order.
pub fn write_run_pages(dir: &Path, report: &Report) -> Result<Vec<String>, OutputError> {
    let runs = dir.join("runs");
    std::fs::create_dir_all(&runs).map_err(|e| write_err(&runs, &e))?;
    let templates = Pages::new().map_err(|e| write_err(&runs, &e))?;
    let mut pages = Vec::with_capacity(report.rows.len());
    for row in 0..report.rows.len() {
        let name = format!("runs/{}.html", row_stem(&report.rows[row]));
        let path = dir.join(&name);
        let html = run_page(&templates, report, row).map_err(|e| write_err(&path, &e))?;
        std::fs::write(&path, html).map_err(|e| write_err(&path, &e))?;
        pages.push(name);
    }
    Ok(pages)
}

/// A failure to write `path`.
fn write_err(path: &Path, e: &dyn std::fmt::Display) -> OutputError {
    OutputError::Write { path: path.to_owned(), message: e.to_string() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lit_fraction_is_grey() {
        let v = Visibility { width: 3, height: 1, lit: vec![0.0, 0.5, 1.0], transmittance: None };
        let g = lit_image(&v);
        assert_eq!(g.as_raw(), &[0, 128, 255]);
    }
}
