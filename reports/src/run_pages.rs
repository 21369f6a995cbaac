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
//!
//! and its scene's, shared by the scene's runs ([`scene_files`]): the reference's lit
//! fraction (`scenes/SCENE.reference.png`, and `.exr`) and the pixel classes
//! (`scenes/SCENE.classes.png`).
//!
//! A run in motion (over an animated scene, [`crate::motion_charts::in_motion`]) also has
//! ([`motion_files`]):
//!
//! - `runs/ID/frames/method-NNNN.png`, `runs/ID/frames/reference-NNNN.png` and
//!   `runs/ID/frames/error-NNNN.png` (NNNN the frame from 0000): each frame's shaded method
//!   image, shaded reference and error map, as the sweep encoded them ([`MotionFrames`]);
//! - `runs/ID.animation.png`: the three side by side, animated (APNG,
//!   [`crate::animation::Apng`]), each frame shown for the sweep's frame delay;
//! - `runs/ID.frames.csv`: a row per frame ([`crate::animation::FrameRecord`]: errors, the
//!   temporal error of the pair ending there, times);
//! - `runs/ID.temporal.json`: its temporal metrics (`analysis::temporal::TemporalMetrics`).
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
//!
//! A run in motion's page has a section "In motion" (`#motion`): three players side by side,
//! the method, the reference and the error map, each an `<img>` showing
//! `ID/frames/KIND-NNNN.png`, driven together by one play/pause button and one frame slider
//! so that all three always show the same frame; playing advances a frame every frame delay
//! (the delay of `ID.animation.png`, read when the page is written; [`DEFAULT_FRAME_MS`]
//! without it) and loops. A counter says `frame i / N` (frames numbered from 0) and the
//! frame's time; its temporal metrics and a table of its frames follow, the frame shown
//! highlighted. The self-test sets the slider and checks that the three images name that
//! frame, then plays and checks that the frame advanced, the three in step, and that playing
//! on from the last frame comes back to the first.

use crate::animation::{frame_delay_ms, side_by_side, write_frames_csv, Apng};
use crate::figures::clock_name;
use crate::html::{anchor, metric_cells, Cell, METRIC_COLUMNS};
use crate::model::{
    param_label, params_of, row_stem, scene_stem, Images, MotionFrames, Report, Row,
};
use crate::motion_charts::{frame_count, in_motion};
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
    /// A run in motion's players, temporal metrics and frames; `None` for a still run.
    pub motion: Option<MotionView>,
}

/// How long a player shows each frame when the run's animation does not say, milliseconds:
/// the sweep's delay.
pub const DEFAULT_FRAME_MS: u16 = crate::motion::FRAME_MS;

/// The kinds of a run in motion's frames, in the order the players show them.
pub const FRAME_KINDS: [&str; 3] = ["method", "reference", "error"];

/// The file of frame `k` of kind `kind` (one of [`FRAME_KINDS`]) of the run `stem`, relative
/// to `runs/`: `ID/frames/KIND-NNNN.png`.
pub fn frame_file(stem: &str, kind: &str, k: usize) -> String {
    format!("{stem}/frames/{kind}-{k:04}.png")
}

/// One player of a run in motion.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Player {
    /// What it shows: `method`, `reference` or `error` ([`FRAME_KINDS`]).
    pub kind: &'static str,
    /// Its first frame, relative to the page.
    pub src: String,
    /// What it is.
    pub label: String,
}

/// A run in motion on its page: the players, the temporal metrics and the frames.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MotionView {
    /// Frames.
    pub frames: usize,
    /// The last frame's number, the slider's maximum.
    pub last: usize,
    /// How long a player shows each frame, milliseconds.
    pub frame_ms: u16,
    /// The frames' folder relative to the page, `ID/frames/`.
    pub base: String,
    /// Method, reference and error map.
    pub players: Vec<Player>,
    /// Each frame's time in the animation, separated by spaces, for the frame counter.
    pub times: String,
    /// The temporal metrics, every count included.
    pub metrics: Vec<(String, Cell)>,
    /// The frame table's heads after `frame`.
    pub heads: Vec<String>,
    /// A row per frame, named with its number.
    pub rows: Vec<NamedRow>,
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
        motion: motion_view(r),
    }
}

/// A number to `decimals` decimals, trailing zeros dropped (`0.125`, `2`).
fn short(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        s
    }
}

/// A run in motion's part of its page ([`DEFAULT_FRAME_MS`] its delay); `None` for a still
/// run or one without frames.
fn motion_view(r: &Row) -> Option<MotionView> {
    let t = r.temporal.as_ref().filter(|_| in_motion(r))?;
    let frames = frame_count(r);
    if frames == 0 {
        return None;
    }
    let stem = row_stem(r);
    let labels = [
        "this run".to_owned(),
        format!("reference ({})", reference_text(r)),
        format!("|error|, 0 to {} (magma)", analysis::error_map::DEFAULT_MAX_ERROR),
    ];
    let players = FRAME_KINDS
        .iter()
        .zip(labels)
        .map(|(&kind, label)| Player { kind, src: frame_file(&stem, kind, 0), label })
        .collect();
    let or_na = |v: Option<f64>| v.map_or_else(Cell::na, |v| Cell::num(v, 5));
    let mut metrics = vec![
        ("frames".to_owned(), Cell::num(frames as f64, 0)),
        ("pixel pairs".to_owned(), Cell::num(t.pixel_pairs as f64, 0)),
        ("temporal error".to_owned(), or_na(t.mean)),
        ("temporal p95".to_owned(), or_na(t.p95)),
        ("boundary pixel pairs".to_owned(), Cell::num(t.boundary_pairs as f64, 0)),
        ("boundary temporal error".to_owned(), or_na(t.boundary_mean)),
        ("boundary temporal p95".to_owned(), or_na(t.boundary_p95)),
    ];
    metrics.extend(t.per_class.iter().map(|(class, c)| {
        let text = c.mean.map_or_else(|| "n/a".to_owned(), |m| format!("{m:.5}"));
        (
            format!("{class} temporal error"),
            Cell { text: format!("{text} over {} pairs", c.pairs), value: c.mean, href: None },
        )
    }));
    metrics.push((
        "pixel pairing".to_owned(),
        Cell::text(if t.reprojected {
            "reprojected (the camera or the geometry moved)"
        } else {
            "each pixel with itself"
        }),
    ));
    let maps: Vec<Option<u32>> = r.per_frame.iter().map(|f| f.map_res).collect();
    let map_varies = maps.iter().any(|m| *m != maps[0]);
    let cpu = r.per_frame.iter().any(|f| f.method_cpu_ms.is_some());
    let mut heads = vec!["time".to_owned()];
    if map_varies {
        heads.push("map_res".into());
    }
    heads.extend(
        ["mean abs error", "boundary error", "temporal error", "pixel pairs", "wall ms"]
            .map(String::from),
    );
    if cpu {
        heads.push("CPU ms".into());
    }
    let rows = r
        .per_frame
        .iter()
        .map(|f| {
            let mut cells = vec![Cell::sorted(short(f.time, 4), f.time)];
            if map_varies {
                cells.push(f.map_res.map_or_else(Cell::na, |m| Cell::num(f64::from(m), 0)));
            }
            cells.extend([
                or_na(f.mean_abs_error),
                or_na(f.boundary_mean_abs_error),
                or_na(f.temporal_error),
                Cell::num(f.temporal_pairs as f64, 0),
                ms(f.method_ms),
            ]);
            if cpu {
                cells.push(f.method_cpu_ms.map_or_else(Cell::na, ms));
            }
            NamedRow { name: f.frame.to_string(), cells }
        })
        .collect();
    Some(MotionView {
        frames,
        last: frames - 1,
        frame_ms: DEFAULT_FRAME_MS,
        base: format!("{stem}/frames/"),
        players,
        times: r.per_frame.iter().map(|f| short(f.time, 4)).collect::<Vec<_>>().join(" "),
        metrics,
        heads,
        rows,
    })
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
/// `ID.error.png` (its error map), `ID.run.json` and `ID.metrics.json`.
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
        if let Some(m) = &p.motion {
            motion_files(&runs, &report.rows[p.row], m)?;
        }
    }
    Ok(())
}

/// Writes a run in motion's files into `runs` (see the module documentation): its frames,
/// its animation, `ID.frames.csv` from the row's per-frame records and `ID.temporal.json`
/// from its temporal metrics (when it has them). The three kinds must have as many frames
/// each, and each kind's frames one size.
pub fn motion_files(runs: &Path, row: &Row, motion: &MotionFrames) -> Result<(), OutputError> {
    let stem = row_stem(row);
    let frames_dir = runs.join(&stem).join("frames");
    let n = motion.method.len();
    if motion.reference.len() != n || motion.error.len() != n {
        return Err(write_err(
            &frames_dir,
            &format!(
                "{n} method frames, {} reference frames and {} error frames: not one of each a \
                 frame",
                motion.reference.len(),
                motion.error.len()
            ),
        ));
    }
    std::fs::create_dir_all(&frames_dir).map_err(|e| write_err(&frames_dir, &e))?;
    let kinds = [&motion.method, &motion.reference, &motion.error];
    let animation = runs.join(format!("{stem}.animation.png"));
    let mut apng: Option<Apng> = None;
    for k in 0..n {
        let mut panels = Vec::with_capacity(kinds.len());
        for (kind, frames) in FRAME_KINDS.iter().zip(kinds) {
            let path = runs.join(frame_file(&stem, kind, k));
            std::fs::write(&path, &frames[k]).map_err(|e| write_err(&path, &e))?;
            let image = image::load_from_memory(&frames[k])
                .map_err(|e| write_err(&path, &format!("not a PNG the sweep encoded: {e}")))?;
            panels.push(image.to_rgb8());
        }
        let frame = side_by_side(&[&panels[0], &panels[1], &panels[2]]);
        if apng.is_none() {
            let (w, h) = frame.dimensions();
            apng = Some(Apng::create(&animation, w, h, n as u32, motion.frame_ms)?);
        }
        if let Some(writer) = apng.as_mut() {
            writer.push(&frame)?;
        }
    }
    if let Some(writer) = apng {
        writer.finish()?;
    }
    write_frames_csv(&runs.join(format!("{stem}.frames.csv")), &row.per_frame)?;
    if let Some(t) = &row.temporal {
        let path = runs.join(format!("{stem}.temporal.json"));
        let text = serde_json::to_string_pretty(t).map_err(|e| write_err(&path, &e))?;
        std::fs::write(&path, text + "\n").map_err(|e| write_err(&path, &e))?;
    }
    Ok(())
}

/// Writes every run's page, `dir/runs/ID.html` (its files are to be there or to follow:
/// [`run_files`]; a run in motion's players take their frame delay from its animation when it
/// is there). Returns the pages' paths relative to `dir`, in report order.
pub fn write_run_pages(dir: &Path, report: &Report) -> Result<Vec<String>, OutputError> {
    let runs = dir.join("runs");
    std::fs::create_dir_all(&runs).map_err(|e| write_err(&runs, &e))?;
    let templates = Pages::new().map_err(|e| write_err(&runs, &e))?;
    let mut pages = Vec::with_capacity(report.rows.len());
    for row in 0..report.rows.len() {
        let stem = row_stem(&report.rows[row]);
        let name = format!("runs/{stem}.html");
        let path = dir.join(&name);
        let mut model = run_page_model(report, row);
        if let Some(m) = model.motion.as_mut() {
            let animation = runs.join(format!("{stem}.animation.png"));
            m.frame_ms = frame_delay_ms(&animation).unwrap_or(DEFAULT_FRAME_MS);
        }
        let html = templates.render("run.html", &model).map_err(|e| write_err(&path, &e))?;
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

    #[test]
    fn a_run_in_motion_has_its_frames_animation_and_records_and_its_page_the_players() {
        use crate::motion_charts::fixture::{report_in_motion, FRAMES, FRAME_MS};
        let (report, images) = report_in_motion();
        let dir = tempfile::tempdir().expect("tempdir");
        run_files(dir.path(), &report, &images).expect("files written");
        write_run_pages(dir.path(), &report).expect("pages written");
        let runs = dir.path().join("runs");
        let stem = row_stem(&report.rows[0]);
        // Each kind's frames as the sweep encoded them, numbered from 0000, and no more.
        for (offset, kind) in FRAME_KINDS.iter().enumerate() {
            for k in 0..FRAMES as usize {
                let path = runs.join(frame_file(&stem, kind, k));
                let image = image::open(&path).expect("a frame").to_rgb8();
                assert_eq!(image.get_pixel(0, 0).0[0] as usize, 10 * k + offset, "{kind} {k}");
            }
            assert!(!runs.join(frame_file(&stem, kind, FRAMES as usize)).exists());
        }
        assert_eq!(frame_file("a", "error", 12), "a/frames/error-0012.png");
        // The animation: the three side by side (the error map a row taller), every frame.
        let animation = runs.join(format!("{stem}.animation.png"));
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(&animation).expect("animation.png"),
        ));
        let mut reader = decoder.read_info().expect("a PNG");
        let control = reader.info().animation_control().copied().expect("animated");
        assert_eq!((control.num_frames, control.num_plays), (FRAMES, 0));
        let (w, h) = (reader.info().width, reader.info().height);
        assert_eq!((w, h), (3 * 32 + 2 * 4, 25));
        let mut buf = vec![0; reader.output_buffer_size().expect("size")];
        let mut firsts = Vec::new();
        for _ in 0..FRAMES {
            reader.next_frame(&mut buf).expect("a frame");
            firsts.push(buf[0]);
        }
        assert_eq!(firsts, [0, 10, 20, 30], "the method's frames in order, leftmost");
        assert_eq!(frame_delay_ms(&animation), Some(FRAME_MS));
        // The records: a CSV row per frame, the temporal metrics as they are.
        let csv = std::fs::read_to_string(runs.join(format!("{stem}.frames.csv"))).expect("csv");
        assert_eq!(csv.lines().count(), 1 + FRAMES as usize, "{csv}");
        assert!(csv.starts_with("frame,time,map_res,mean_abs_error,"), "{csv}");
        let json = std::fs::read_to_string(runs.join(format!("{stem}.temporal.json")))
            .expect("temporal.json");
        let back: analysis::temporal::TemporalMetrics =
            serde_json::from_str(&json).expect("parses");
        assert_eq!(Some(back), report.rows[0].temporal);
        // The still run has none of them.
        let still = row_stem(&report.rows[1]);
        assert!(!runs.join(&still).exists());
        for ext in ["animation.png", "frames.csv", "temporal.json"] {
            assert!(!runs.join(format!("{still}.{ext}")).exists(), "{ext}");
        }

        // The page of the run in motion has the players, on frame 0, at the animation's
        // delay, and a row per frame; the still run's page has none.
        let page = std::fs::read_to_string(runs.join(format!("{stem}.html"))).expect("page");
        assert!(page.contains("<h2 id=\"motion\">In motion</h2>"), "{page}");
        assert!(page.contains(&format!("data-frame-ms=\"{FRAME_MS}\"")), "{page}");
        assert!(page.contains(&format!("data-frames=\"{FRAMES}\"")), "{page}");
        for kind in FRAME_KINDS {
            let img = format!("data-kind=\"{kind}\" src=\"{}\"", frame_file(&stem, kind, 0));
            assert!(page.contains(&img), "{img}");
        }
        assert_eq!(page.matches("<tr data-frame=").count(), FRAMES as usize);
        assert!(page.contains("type=\"range\"") && page.contains("id=\"play\""));
        let still_page =
            std::fs::read_to_string(runs.join(format!("{still}.html"))).expect("still page");
        assert!(!still_page.contains("id=\"motion\"") && !still_page.contains("class=\"players"));
        // Without its animation the page plays at the default delay.
        let mut model = run_page_model(&report, 0);
        let view = model.motion.take().expect("in motion");
        assert_eq!((view.frame_ms, view.frames, view.last), (DEFAULT_FRAME_MS, 4, 3));
        assert_eq!(view.times, "0 0.1 0.2 0.3");
        assert!(run_page_model(&report, 1).motion.is_none());
    }

    #[test]
    fn frames_that_do_not_match_are_refused_naming_the_folder() {
        let (report, mut images) = crate::motion_charts::fixture::report_in_motion();
        let dir = tempfile::tempdir().expect("tempdir");
        let motion = images.runs.iter_mut().find_map(|p| p.motion.as_mut()).expect("motion");
        motion.reference.pop();
        let e = motion_files(dir.path(), &report.rows[0], motion).expect_err("refused");
        let text = e.to_string();
        assert!(text.contains("frames") && text.contains("4 method frames, 3 reference"), "{text}");
        // A frame that is not a PNG is refused naming its file.
        let mut motion = crate::motion_charts::fixture::motion_frames(4, 3, 2, 100);
        motion.error[1] = b"not a png".to_vec();
        let e = motion_files(dir.path(), &report.rows[0], &motion).expect_err("refused");
        assert!(e.to_string().contains("error-0001.png"), "{e}");
    }
}
