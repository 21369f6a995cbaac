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

use crate::model::{
    GridFile, GridImages, Images, Panel, Produced, Report, Row, SceneImages, SceneInfo,
};
use crate::output::shade;
use crate::output::MetricsRecord;
use crate::suite::{GridSpec, PanelSpec, ReferenceChoice, Suite};
use crate::tables::{run_table, table_run_count};
use crate::timing::{time_method, Machine};
use analysis::metrics::{exceedance, Comparison};
use analysis::{error_image, Metrics, ReferenceImage};
use instrumentation::{Provenance, Recorder, RunRecord};
use methods::{registry::Device, Frame, MethodOptions, Visibility};
use std::cell::Cell;
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// Number of method runs a suite makes (scenes times combinations), for progress bars.
pub fn run_count(suite: &Suite) -> u64 {
    (suite.scenes.len() * suite.runs.iter().map(|r| r.expand().len()).sum::<usize>()) as u64
        + suite.tables.iter().map(table_run_count).sum::<u64>()
}

fn reference_for(
    suite: &Suite,
    frame: &Frame<'_>,
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
    let t = std::time::Instant::now();
    let image = r.evaluate(frame, &mut Recorder::default()).map_err(|e| e.to_string())?;
    Ok((name.to_owned(), rate, image, t.elapsed().as_secs_f64() * 1e3))
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
pub fn run_suite(suite: &Suite, mut progress: impl FnMut(&str)) -> (Report, Images) {
    let log = ProgressLog::new(run_count(suite));
    let done = Cell::new(0u64);
    let mut progress = |label: &str| {
        done.set(done.get() + 1);
        progress(label);
    };
    let mut report = Report {
        suite: suite.clone(),
        provenance: Provenance::capture(Provenance::command_line(), None),
        machine: Machine::current(),
        scenes: Vec::new(),
        rows: Vec::new(),
        skipped: Vec::new(),
        grids: Vec::new(),
        tables: Vec::new(),
    };
    let mut images = Images::default();
    let combos: usize = suite.runs.iter().map(|r| r.expand().len()).sum();
    for (k, scene_name) in suite.scenes.iter().enumerate() {
        log.print(&format!("scene {}/{} {scene_name}", k + 1, suite.scenes.len()), done.get());
        let scene = match scenes::load(scene_name) {
            Ok(s) => s,
            Err(e) => {
                report.skipped.push(format!("scene {scene_name}: {e}"));
                (0..combos).for_each(|_| progress(scene_name));
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
        let (ref_name, ref_rate, truth, reference_ms) = match reference_for(suite, &frame) {
            Ok(r) => r,
            Err(e) => {
                report.skipped.push(format!("scene {}: reference: {e}", scene.name));
                (0..combos).for_each(|_| progress(&scene.name));
                continue;
            }
        };
        // The metrics are taken over the shadow-only pixels, by the frame's pixel classes
        // (the reference's own, or the camera's view of the triangles when it has none), as
        // `compare`'s headline is.
        let classes = match &truth.classes {
            Some(c) => c.clone(),
            None => analysis::exact::classify(&frame).class,
        };
        let shadow_only = analysis::metrics::headline_pixels(&truth, &classes);
        let scene_images = images.scenes.len();
        let effects: Vec<String> = frame.effects.names().into_iter().map(String::from).collect();
        // `raytrace` at one sample per pixel, traced the first time a binary result needs it.
        let mut raytrace1: Option<Option<ReferenceImage>> = None;
        report.scenes.push(SceneInfo {
            scene: scene.name.clone(),
            triangles: frame.geometry.len() as u64,
            effects: effects.clone(),
            width: w,
            height: h,
            gbuffer_ms: rec.stages.total_ms(),
            reference: ref_name.clone(),
            reference_ms,
        });
        for spec in &suite.runs {
            for options in spec.expand() {
                progress(&format!("{} {}", scene.name, spec.method));
                let technique = match analysis::registry::technique(&spec.method, &options) {
                    Ok(t) => t,
                    Err(e) => {
                        report.skipped.push(format!("{} on {}: {e}", spec.method, scene.name));
                        continue;
                    }
                };
                let timed =
                    match time_method(technique.as_ref(), &frame, suite.warmup, suite.repeats) {
                        Ok(t) => t,
                        Err(why) => {
                            report
                                .skipped
                                .push(format!("{} on {}: {why}", spec.method, scene.name));
                            continue;
                        }
                    };
                let v = timed.visibility;
                if options.device == Device::Gpu && report.machine.gpu.is_none() {
                    report.machine.gpu =
                        methods::gpu::GpuContext::shared().ok().map(|c| c.adapter_name());
                }
                let rt1 = if analysis::metrics::is_binary(&v, &shadow_only) {
                    raytrace1
                        .get_or_insert_with(|| {
                            analysis::registry::reference("raytrace", 1, Default::default())
                                .ok()?
                                .evaluate(&frame, &mut Recorder::default())
                                .ok()
                        })
                        .as_ref()
                } else {
                    None
                };
                let comparison = Comparison::new(&v, &truth, &classes, rt1);
                let rec = timed.record;
                let record = RunRecord {
                    scene: scene.name.clone(),
                    method: technique.name().to_owned(),
                    params: technique.params(),
                    width: w,
                    height: h,
                    effects: effects.clone(),
                    counters: rec.counters,
                    total_ms: rec.stages.total_ms(),
                    stages: rec.stages.stages,
                    skipped_stages: rec.stages.skipped,
                    notes: rec.notes,
                    warnings: rec.warnings,
                    pixel_classes: None,
                    provenance: Some(report.provenance.clone()),
                };
                let metrics = MetricsRecord {
                    comparison: comparison.clone(),
                    reference: ref_name.clone(),
                    ref_rate,
                    edge_reference: (ref_name == "exact").then(|| "none".to_owned()),
                    scene: scene.name.clone(),
                    method: record.method.clone(),
                    params: record.params.clone(),
                    width: w,
                    height: h,
                    method_ms: record.total_ms,
                    reference_ms,
                };
                report.rows.push(Row {
                    scene: scene.name.clone(),
                    method: record.method.clone(),
                    params: record.params.clone(),
                    width: w,
                    height: h,
                    reference: ref_name.clone(),
                    ref_rate,
                    metrics: Metrics::compare(&v, &truth.lit, &shadow_only),
                    flip_mean: comparison.flip_mean,
                    pixel_match_lecocq: comparison.pixel_match_lecocq,
                    error_exceedance: exceedance(&v, &truth.lit, &shadow_only).unwrap_or_default(),
                    total_ms: timed.total_ms,
                    stages: timed.stages,
                    skipped_stages: record.skipped_stages.clone(),
                    counters: record.counters,
                    notes: record.notes.clone(),
                });
                images.runs.push(Produced {
                    row: report.rows.len() - 1,
                    scene: scene_images,
                    visibility: v,
                    record,
                    metrics,
                });
            }
        }
        for grid in suite.grids.iter().filter(|g| g.scene == *scene_name) {
            let panels =
                grid_panels(grid, &frame, &truth, &shadow_only, &ref_name, &mut report.skipped);
            if panels.is_empty() {
                continue;
            }
            report.grids.push(GridFile {
                scene: scene.name.clone(),
                title: grid.title.clone(),
                png: format!("grids/grid-{}.png", report.grids.len() + 1),
            });
            images.grids.push(GridImages {
                grid: report.grids.len() - 1,
                panels,
                inset: grid.inset,
            });
        }
        images.scenes.push(SceneImages {
            scene: report.scenes.len() - 1,
            reference: truth,
            classes,
            compared: shadow_only,
        });
    }
    for (k, spec) in suite.tables.iter().enumerate() {
        let name = spec.paper.name();
        log.print(&format!("table {}/{} {name}", k + 1, suite.tables.len()), done.get());
        let table =
            run_table(spec, suite.warmup, suite.repeats, &mut report.skipped, &mut progress);
        report.tables.push(table);
    }
    log.print("done", done.get());
    report.provenance.adapter = report.machine.gpu.clone();
    (report, images)
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
