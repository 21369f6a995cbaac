//! Running a suite: every scene, every method, every combination of its swept parameters,
//! timed by the protocol of [`crate::timing`] and measured against the scene's reference.
//!
//! Per scene, the frame (camera G-buffer) and the reference are computed once and shared by
//! every method, so a method's time is its own stages only; the G-buffer's time is reported
//! per scene. The metrics come from the last timed run (every method is deterministic for
//! its parameters, so all runs give the same image) and are taken over the reference's
//! shadow-only pixels (`analysis::metrics::headline_pixels`: the `planar` and `surface` pixels
//! the reference evaluated, by its own classes or, for `raytrace`, by the camera's view of the
//! triangles), as `compare`'s headline is. Each run also keeps its run record and its
//! comparison per pixel class (`compare`'s `metrics.json`), and each scene its reference and
//! classes, for the run pages ([`Images`]).
//!
//! When standard error is not a terminal (a log, a pipe), the sweep prints a line there as it
//! starts each scene and each paper's table, and when it ends: the runs done of the total, the
//! time elapsed and an estimate of the time left from the mean time per run so far
//! ([`ProgressLog`]). On a terminal the caller's progress bar shows the same.

use crate::cache::ReferenceCache;
use crate::model::{
    GridFile, GridImages, Images, Panel, Produced, Report, Row, SceneImages, SceneInfo,
};
use crate::output::shade;
use crate::output::MetricsRecord;
use crate::plan::{Work, WorkItem};
use crate::suite::{GridSpec, PanelSpec, ReferenceChoice, Suite};
use crate::tables::{run_table, table_run_count};
use crate::timing::Machine;
use analysis::compare::Truth;
use analysis::metrics::exceedance;
use analysis::{error_image, Metrics, ReferenceImage};
use instrumentation::measure::{measure_all, Measured};
use instrumentation::{Provenance, Recorder, RunIdentity};
use methods::{registry::Device, Frame, MethodOptions, ShadowMethod, Visibility};
use std::cell::Cell;
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// The scene's reference on `frame`, from `cache` when it holds it (and stored there when it
/// does not), with its name, rate and the time it took to compute.
fn reference_for(
    suite: &Suite,
    scene: &scenes::Scene,
    frame: &Frame<'_>,
    cache: Option<&mut ReferenceCache>,
    build: &str,
) -> Result<(String, Option<u32>, ReferenceImage, f64), String> {
    let use_exact = match suite.reference {
        ReferenceChoice::Auto => !frame.effects.transparency,
        ReferenceChoice::Exact => true,
        ReferenceChoice::Raytrace => false,
    };
    let (name, rate) = if use_exact { ("exact", None) } else { ("raytrace", Some(suite.ref_rate)) };
    // The report measures shadow-only pixels, so `exact`'s edge pixels are not ray traced.
    let r: Box<dyn analysis::Reference> = if use_exact {
        Box::new(analysis::exact::ExactCoverage { edge: None })
    } else {
        analysis::registry::reference(name, suite.ref_rate, Default::default())
            .map_err(|e| e.to_string())?
    };
    let compute = || {
        let t = std::time::Instant::now();
        let image = r.evaluate(frame, &mut Recorder::default()).map_err(|e| e.to_string())?;
        Ok::<_, String>((image, t.elapsed().as_secs_f64() * 1e3))
    };
    let (image, ms) = match cache {
        Some(c) => c.get_or_compute(scene, frame, name, rate, build, compute)?,
        None => compute()?,
    };
    Ok((name.to_owned(), rate, image, ms))
}

/// A panel of the sub-pixel shadow map's pixel classes (Lecocq et al. Fig. 14).
fn spsm_classes(p: &PanelSpec, frame: &Frame<'_>) -> Result<Panel, String> {
    use methods::spsm::{class_image, Spsm, SpsmOptions, TexelFormat};
    let texel = match p.method.as_str() {
        "spsm" => TexelFormat::Packed,
        "spsm-f32" => TexelFormat::F32,
        _ => return Err("`classes` shows the pixel classes of spsm or spsm-f32 only".into()),
    };
    let d = SpsmOptions::default();
    let mut map = d.map;
    map.map_res = p.map_res.unwrap_or(map.map_res);
    let options = SpsmOptions { map, texel, rate: p.rate.unwrap_or(d.rate), ..d };
    let (v, classes) = Spsm { options }
        .run_classified(frame, &mut Recorder::default())
        .map_err(|e| e.to_string())?;
    let rgb = class_image(&classes, &v.lit);
    let image = image::RgbImage::from_fn(v.width, v.height, |x, y| {
        image::Rgb(rgb[(y * v.width + x) as usize])
    });
    let label =
        p.label.clone().unwrap_or_else(|| format!("{} classes, map {}", p.method, map.map_res));
    Ok(Panel { label, image })
}

/// The panels of `grid` on `frame` (untimed runs); panels whose method cannot run are left
/// out with the reason in `skipped`.
fn grid_panels(
    grid: &GridSpec,
    frame: &Frame<'_>,
    truth: &ReferenceImage,
    compared: &[bool],
    ref_name: &str,
    skipped: &mut Vec<String>,
) -> Vec<Panel> {
    let mut panels = Vec::new();
    let mut last = None;
    for p in &grid.panels {
        let options = MethodOptions {
            map_res: p.map_res,
            rate: p.rate,
            depth_bits: p.depth_bits,
            ..Default::default()
        };
        if p.classes {
            match spsm_classes(p, frame) {
                Ok(panel) => panels.push(panel),
                Err(e) => skipped.push(format!("grid `{}`: {}: {e}", grid.title, p.method)),
            }
            continue;
        }
        let run = analysis::registry::technique(&p.method, &options)
            .and_then(|t| t.run(frame, &mut Recorder::default()).map(|v| (t, v)));
        match run {
            Ok((t, v)) => {
                let label = p.label.clone().unwrap_or_else(|| {
                    let given = [("map", p.map_res), ("rate", p.rate), ("bits", p.depth_bits)];
                    let params: Vec<String> =
                        given.iter().filter_map(|(k, v)| v.map(|v| format!("{k} {v}"))).collect();
                    format!("{} {}", t.name(), params.join(", "))
                });
                panels.push(Panel { label, image: shade(frame, &v) });
                last = Some(v);
            }
            Err(e) => skipped.push(format!("grid `{}`: {}: {e}", grid.title, p.method)),
        }
    }
    if grid.reference {
        let lit = truth.lit.iter().map(|&l| l as f32).collect();
        let v = Visibility { width: truth.width, height: truth.height, lit, transmittance: None };
        // Pixels the reference does not evaluate (its value there is not ground truth) are
        // painted dark blue, as in the error image.
        let mut image = shade(frame, &v);
        for (k, px) in image.pixels_mut().enumerate() {
            if !truth.evaluated[k] {
                *px = image::Rgb([0, 0, 64]);
            }
        }
        panels.push(Panel { label: format!("reference ({ref_name}; blue: not evaluated)"), image });
        if let Some(v) = last {
            // Over the pixels the metrics are taken on, as `compare`'s error.png.
            panels.push(Panel {
                label: "10x |error| of the last".into(),
                image: error_image(&v, &truth.lit, compared),
            });
        }
    }
    panels
}

/// `d` as `1h02m03s`, `2m03s` or `3s`.
fn hms(d: Duration) -> String {
    let s = d.as_secs();
    match (s / 3600, s / 60 % 60, s % 60) {
        (0, 0, s) => format!("{s}s"),
        (0, m, s) => format!("{m}m{s:02}s"),
        (h, m, s) => format!("{h}h{m:02}m{s:02}s"),
    }
}

/// Progress lines of a sweep for a log: what starts, the runs done of the total, the time
/// elapsed and the time left at the mean time per run so far.
pub struct ProgressLog {
    start: Instant,
    total: u64,
    /// Printed only when standard error is not a terminal.
    enabled: bool,
}

impl ProgressLog {
    /// A log of `total` runs, starting now; it prints when standard error is not a terminal.
    pub fn new(total: u64) -> Self {
        Self { start: Instant::now(), total, enabled: !std::io::stderr().is_terminal() }
    }

    /// The line for `what` (e.g. `scene 2/5 cage`) after `done` runs in `elapsed`.
    pub fn line(&self, what: &str, done: u64, elapsed: Duration) -> String {
        let left = if done == 0 {
            "time left unknown".to_owned()
        } else {
            let per_run = elapsed.as_secs_f64() / done as f64;
            let left = per_run * self.total.saturating_sub(done) as f64;
            format!("about {} left", hms(Duration::from_secs_f64(left)))
        };
        format!("{what}: {done}/{} runs done, {} elapsed, {left}", self.total, hms(elapsed))
    }

    /// Prints the line for `what` after `done` runs, when enabled.
    pub fn print(&self, what: &str, done: u64) {
        if self.enabled {
            eprintln!("{}", self.line(what, done, self.start.elapsed()));
        }
    }
}

/// The report of the suite written as `toml`, for tests of what is made from reports.
#[cfg(test)]
pub(crate) fn report_of(toml: &str) -> Report {
    let suite = Suite::parse(toml, std::path::Path::new("test.toml")).expect("a valid suite");
    run_suite(&suite, |_| {}).0
}

/// Runs `suite`; `progress` is called once per method run with a short label. The report's
/// provenance names this process's command line ([`Provenance::command_line`]). Returns the
/// report and what its image outputs need ([`Images`]).
pub fn run_suite(suite: &Suite, progress: impl FnMut(&str)) -> (Report, Images) {
    let plan = crate::plan::plan(suite);
    let all: Vec<usize> = (0..plan.len()).collect();
    run_items(suite, &plan, &all, None, progress)
}

/// How many method runs the items of `plan` numbered in `items` make.
pub fn items_run_count(suite: &Suite, plan: &[WorkItem], items: &[usize]) -> u64 {
    items
        .iter()
        .map(|&k| match &plan[k].work {
            Work::Runs { runs, .. } => runs.len() as u64,
            Work::Grid { .. } => 0,
            Work::Table { table, .. } => table_run_count(&suite.tables[*table]),
        })
        .sum()
}

/// What every item of one scene shares: the frame, the reference and the pixel classes.
struct SceneRun<'s> {
    scene: &'s scenes::Scene,
    frame: Frame<'s>,
    effects: Vec<String>,
    ref_name: String,
    ref_rate: Option<u32>,
    reference_ms: f64,
    /// The reference, the pixel classes and the shadow-only pixels the metrics are taken over.
    truth: Truth,
    /// Index of its images in [`Images::scenes`].
    images: usize,
}

/// One combination of a `[[run]]` on a scene, built and waiting to be measured.
struct Planned<'a> {
    /// The plan's item.
    item: usize,
    spec: &'a crate::suite::RunSpec,
    options: MethodOptions,
    technique: Box<dyn ShadowMethod>,
}

/// Runs the items of `plan` numbered in `items` (in plan order; a scene's frame and reference
/// are prepared once for its consecutive items, and taken from `cache` when it holds them);
/// `progress` is called once per method run. Running every item of the plan is running the
/// suite ([`run_suite`]); a shard runs its own ([`crate::plan::Shard::items`]).
pub fn run_items(
    suite: &Suite,
    plan: &[WorkItem],
    items: &[usize],
    mut cache: Option<&mut ReferenceCache>,
    mut progress: impl FnMut(&str),
) -> (Report, Images) {
    let log = ProgressLog::new(items_run_count(suite, plan, items));
    let done = Cell::new(0u64);
    let mut progress = |label: &str| {
        done.set(done.get() + 1);
        progress(label);
    };
    let mut report = Report {
        suite: suite.clone(),
        provenance: Provenance::capture(Provenance::command_line(), None),
        machine: Machine::current(),
        clock: suite.clock,
        scenes: Vec::new(),
        rows: Vec::new(),
        skipped: Vec::new(),
        grids: Vec::new(),
        tables: Vec::new(),
        cache: None,
        shards: Vec::new(),
    };
    let mut images = Images::default();
    let scene_count = items
        .iter()
        .filter_map(|&k| plan[k].scene_index)
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    let table_count = items.iter().filter(|&&k| matches!(plan[k].work, Work::Table { .. })).count();
    let mut tables_started = 0;
    let mut scenes_started = 0;
    // What identifies this build in the cache's keys, worked out when a cache is first used.
    let mut build: Option<String> = None;
    let mut at = 0;
    while at < items.len() {
        let first = &plan[items[at]];
        let Some(scene_index) = first.scene_index else {
            if let Work::Table { table, paper } = &first.work {
                tables_started += 1;
                log.print(&format!("table {tables_started}/{table_count} {paper}"), done.get());
                let spec = &suite.tables[*table];
                let t = run_table(spec, &suite.protocol(), &mut report.skipped, &mut progress);
                report.tables.push(t);
            }
            at += 1;
            continue;
        };
        let end = at
            + items[at..].iter().take_while(|&&k| plan[k].scene_index == Some(scene_index)).count();
        let group: Vec<&WorkItem> = items[at..end].iter().map(|&k| &plan[k]).collect();
        at = end;
        scenes_started += 1;
        let scene_name = &suite.scenes[scene_index];
        log.print(&format!("scene {scenes_started}/{scene_count} {scene_name}"), done.get());
        let runs_in_group = |group: &[&WorkItem]| -> usize {
            group
                .iter()
                .map(|i| if let Work::Runs { runs, .. } = &i.work { runs.len() } else { 0 })
                .sum()
        };
        let scene = match scenes::load(scene_name) {
            Ok(s) => s,
            Err(e) => {
                report.skipped.push(format!("scene {scene_name}: {e}"));
                (0..runs_in_group(&group)).for_each(|_| progress(scene_name));
                continue;
            }
        };
        let (w, h) = if suite.width == 0 {
            (scene.width, scene.height)
        } else {
            (suite.width, suite.height)
        };
        let mut rec = Recorder::default();
        let frame = Frame::new(&scene, w, h, &mut rec);
        let build: &str = match cache {
            Some(_) => build.get_or_insert_with(|| {
                crate::cache::build_id(&report.provenance.commit, report.provenance.dirty)
            }),
            None => "",
        };
        let reference = reference_for(suite, &scene, &frame, cache.as_deref_mut(), build);
        let (ref_name, ref_rate, truth, reference_ms) = match reference {
            Ok(r) => r,
            Err(e) => {
                report.skipped.push(format!("scene {}: reference: {e}", scene.name));
                (0..runs_in_group(&group)).for_each(|_| progress(&scene.name));
                continue;
            }
        };
        // The metrics are taken over the shadow-only pixels, by the frame's pixel classes
        // (the reference's own, or the camera's view of the triangles when it has none), as
        // `compare`'s headline is.
        let truth = Truth::new(&frame, truth, &mut Recorder::default());
        let effects: Vec<String> = frame.effects.names().into_iter().map(String::from).collect();
        report.scenes.push(SceneInfo {
            scene: scene.name.clone(),
            triangles: frame.geometry.len() as u64,
            effects: effects.clone(),
            width: w,
            height: h,
            gbuffer_ms: rec.stages.total_ms(),
            gbuffer_cpu_ms: rec.stages.stages.iter().map(|s| s.cpu_ms).sum(),
            reference: ref_name.clone(),
            reference_ms,
        });
        let ctx = SceneRun {
            scene: &scene,
            frame,
            effects,
            ref_name,
            ref_rate,
            reference_ms,
            truth,
            images: images.scenes.len(),
        };
        // Every run of the scene is measured together, interleaved round by round.
        let mut planned = Vec::new();
        for item in &group {
            if let Work::Runs { spec, .. } = &item.work {
                let spec = &suite.runs[*spec];
                for options in spec.expand() {
                    match analysis::registry::technique(&spec.method, &options) {
                        Ok(technique) => {
                            planned.push(Planned { item: item.item, spec, options, technique })
                        }
                        Err(e) => {
                            report.skipped.push(format!("{} on {}: {e}", spec.method, scene.name));
                            progress(&format!("{} {}", scene.name, spec.method));
                        }
                    }
                }
            }
        }
        let frame = &ctx.frame;
        let mut subjects: Vec<_> =
            planned.iter().map(|p| move |rec: &mut Recorder| p.technique.run(frame, rec)).collect();
        let measured = measure_all(&suite.protocol(), &mut subjects, |k| {
            progress(&format!("{} {}", scene.name, planned[k].spec.method));
        });
        drop(subjects);
        for (p, m) in planned.iter().zip(measured) {
            match m {
                Ok(m) => add_run(suite, &ctx, p, m, &mut report, &mut images),
                Err(e) => report.skipped.push(format!("{} on {}: {e}", p.spec.method, scene.name)),
            }
        }
        for item in &group {
            match &item.work {
                Work::Runs { .. } => {}
                Work::Grid { grid, .. } => {
                    let g = &suite.grids[*grid];
                    let panels = grid_panels(
                        g,
                        &ctx.frame,
                        &ctx.truth.reference,
                        &ctx.truth.headline,
                        &ctx.ref_name,
                        &mut report.skipped,
                    );
                    if !panels.is_empty() {
                        report.grids.push(GridFile {
                            item: item.item,
                            scene: scene.name.clone(),
                            title: g.title.clone(),
                            png: format!("grids/grid-{}.png", grid + 1),
                        });
                        images.grids.push(GridImages {
                            grid: report.grids.len() - 1,
                            panels,
                            inset: g.inset,
                        });
                    }
                }
                Work::Table { .. } => {}
            }
        }
        let Truth { reference, classes, headline, .. } = ctx.truth;
        images.scenes.push(SceneImages {
            scene: report.scenes.len() - 1,
            reference,
            classes,
            compared: headline,
        });
    }
    log.print("done", done.get());
    report.machine.load_end = instrumentation::clock::Load::now().map(|l| l.loadavg);
    // A scene that cannot be loaded is said once, however many of its items there are.
    let mut seen = std::collections::HashSet::new();
    report.skipped.retain(|s| seen.insert(s.clone()));
    report.provenance.adapter = report.machine.gpu.clone();
    report.cache = cache.map(|c| c.stats);
    (report, images)
}

/// Adds the row and images of one measured combination: its comparison with the reference,
/// its times on both clocks and its record; a run whose comparison fails is added to the
/// report's skipped runs.
fn add_run(
    suite: &Suite,
    ctx: &SceneRun<'_>,
    p: &Planned<'_>,
    m: Measured<Visibility>,
    report: &mut Report,
    images: &mut Images,
) {
    let scene = ctx.scene;
    let (w, h) = (ctx.frame.width(), ctx.frame.height());
    if p.options.device == Device::Gpu && report.machine.gpu.is_none() {
        report.machine.gpu = methods::registry::gpu_adapter_name();
    }
    let v = &m.output;
    let comparison = match ctx.truth.compare(&ctx.frame, v) {
        Ok(c) => c,
        Err(e) => {
            report.skipped.push(format!("{} on {}: {e}", p.spec.method, scene.name));
            return;
        }
    };
    let mut record = m.run_record(
        RunIdentity {
            scene: scene.name.clone(),
            method: p.technique.name().to_owned(),
            params: p.technique.params(),
            width: w,
            height: h,
            effects: ctx.effects.clone(),
        },
        suite.warmup,
    );
    record.provenance = Some(report.provenance.clone());
    let metrics = MetricsRecord {
        comparison: comparison.clone(),
        reference: ctx.ref_name.clone(),
        ref_rate: ctx.ref_rate,
        edge_reference: (ctx.ref_name == "exact").then(|| "none".to_owned()),
        scene: scene.name.clone(),
        method: record.method.clone(),
        params: record.params.clone(),
        width: w,
        height: h,
        method_ms: record.total_ms,
        reference_ms: ctx.reference_ms,
    };
    let truth = &ctx.truth;
    report.rows.push(Row {
        scene: scene.name.clone(),
        method: record.method.clone(),
        params: record.params.clone(),
        width: w,
        height: h,
        reference: ctx.ref_name.clone(),
        ref_rate: ctx.ref_rate,
        metrics: Metrics::compare(v, &truth.reference.lit, &truth.headline),
        flip_mean: comparison.flip_mean,
        pixel_match_lecocq: comparison.pixel_match_lecocq,
        error_exceedance: exceedance(v, &truth.reference.lit, &truth.headline).unwrap_or_default(),
        classes: Some(comparison.classes),
        item: p.item,
        shard: None,
        total_ms: m.wall_ms,
        cpu_ms: m.cpu_ms,
        contended: m.contended(),
        conditions: Some(m.conditions),
        stages: m.stages.clone(),
        skipped_stages: record.skipped_stages.clone(),
        counters: record.counters,
        notes: record.notes.clone(),
    });
    images.runs.push(Produced {
        row: report.rows.len() - 1,
        scene: ctx.images,
        visibility: m.output,
        record,
        metrics,
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn progress_lines_estimate_the_time_left_from_the_mean_run() {
        let log = ProgressLog { start: Instant::now(), total: 120, enabled: false };
        assert_eq!(
            log.line("scene 2/5 cage", 40, Duration::from_secs(72)),
            "scene 2/5 cage: 40/120 runs done, 1m12s elapsed, about 2m24s left"
        );
        assert_eq!(
            log.line("scene 1/5 cage", 0, Duration::from_millis(300)),
            "scene 1/5 cage: 0/120 runs done, 0s elapsed, time left unknown"
        );
        assert_eq!(hms(Duration::from_secs(3723)), "1h02m03s");
    }
}
