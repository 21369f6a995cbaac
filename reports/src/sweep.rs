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
//! On an animated scene ([`crate::plan::animation_of`]) the `[[run]]`s run in motion, frame by
//! frame ([`crate::motion`]: one row per run, its metrics pooled over the frames, its times per
//! frame, its temporal metrics); the scene's tables' runs, grids and `[[external]]` entries run
//! on its frame 0 only, which is also the frame of its reference and class images and of its
//! [`SceneInfo`]'s G-buffer time (its reference time is summed over the frames).
//!
//! When standard error is not a terminal (a log, a pipe), the sweep prints a line there as it
//! starts each frame, and when it ends: the runs done of the total, the time elapsed and an
//! estimate of the time left ([`crate::progress`]). On a terminal the caller's progress bar
//! shows the same.

use crate::cache::ReferenceCache;
use crate::model::{
    GridFile, GridImages, Images, Panel, Produced, Report, Row, SceneImages, SceneInfo,
};
use crate::output::shade;
use crate::output::MetricsRecord;
use crate::plan::{Work, WorkItem};
use crate::progress::{run_key, Estimate, Progress, ProgressLog};
use crate::suite::{GridSpec, PanelSpec, ReferenceChoice, Suite};
use crate::tables::TableRun;
use crate::timing::Machine;
use analysis::compare::Truth;
use analysis::metrics::exceedance;
use analysis::{error_image, Metrics, ReferenceImage};
use instrumentation::measure::{measure_all, Measured};
use instrumentation::stats::Summary;
use instrumentation::{Provenance, Recorder, RunIdentity};
use methods::{registry::Device, Frame, MethodOptions, ShadowMethod, Visibility};
use std::time::Duration;

/// The scene's reference on `frame`, from `cache` when it holds it (and stored there when it
/// does not), with its name, rate and the time it took to compute.
fn reference_for(
    suite: &Suite,
    scene: &scenes::Scene,
    frame: &Frame<'_>,
    cache: Option<&mut ReferenceCache>,
    build: &str,
) -> Result<(String, Option<u32>, ReferenceImage, f64, bool), String> {
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
    let (image, ms, cached) = match cache {
        Some(c) => {
            let hits = c.stats.hits;
            let (image, ms) = c.get_or_compute(scene, frame, name, rate, build, compute)?;
            (image, ms, c.stats.hits > hits)
        }
        None => {
            let (image, ms) = compute()?;
            (image, ms, false)
        }
    };
    Ok((name.to_owned(), rate, image, ms, cached))
}

/// A panel of the sub-pixel shadow map's pixel classes (Lecocq et al. Fig. 14).
fn spsm_classes(p: &PanelSpec, frame: &Frame<'_>) -> Result<Panel, String> {
    use methods::spsm::{class_image, Spsm, SpsmOptions, TexelFormat};
    let texel = match p.method.as_str() {
        "spsm" => TexelFormat::Packed,
        "spsm-f32" => TexelFormat::F32,
        _ => return Err("`classes` shows the pixel classes of spsm or spsm-f32 only".into()),
    };
    let (o, d) = (p.options(), SpsmOptions::default());
    let mut map = d.map;
    map.map_res = o.map_res.unwrap_or(map.map_res);
    map.constant_bias = o.constant_bias.unwrap_or(map.constant_bias);
    let options = SpsmOptions {
        map,
        texel,
        rate: o.rate.unwrap_or(d.rate),
        pattern: o.pattern.unwrap_or(d.pattern),
        derivative_power: o.derivative_power.unwrap_or(d.derivative_power),
    };
    options.validate().map_err(|e| e.to_string())?;
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
        let options = p.options();
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
                    let params: Vec<String> = options
                        .given()
                        .into_iter()
                        .map(|(k, v)| {
                            let k = match k {
                                "map_res" => "map",
                                "depth_bits" => "bits",
                                k => k,
                            };
                            format!("{k} {}", v.text())
                        })
                        .collect();
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

/// The report of the suite written as `toml`, for tests of what is made from reports.
#[cfg(test)]
pub(crate) fn report_of(toml: &str) -> Report {
    let suite = Suite::parse(toml, std::path::Path::new("test.toml")).expect("a valid suite");
    run_suite(&suite, |_| {}).0
}

/// Runs `suite`; `progress` is called once per method run with a short label. The report's
/// provenance names this process's command line ([`Provenance::command_line`]). Returns the
/// report and what its image outputs need ([`Images`]).
pub fn run_suite(suite: &Suite, progress: impl FnMut(&Progress<'_>)) -> (Report, Images) {
    let plan = crate::plan::plan(suite);
    let all: Vec<usize> = (0..plan.len()).collect();
    run_items(suite, &plan, &all, None, progress)
}

/// How many method runs the items of `plan` numbered in `items` make; a run in motion counts
/// once per frame ([`WorkItem::frames`]).
pub fn items_run_count(plan: &[WorkItem], items: &[usize]) -> u64 {
    items
        .iter()
        .map(|&k| match &plan[k].work {
            Work::Runs { runs, .. } => runs.len() as u64 * u64::from(plan[k].frames.max(1)),
            Work::Grid { .. } => 0,
            Work::External { .. } => 1,
            Work::Table { runs, .. } => runs.len() as u64,
        })
        .sum()
}

/// What every item of one scene shares: the frame, the reference and the pixel classes.
struct SceneRun<'s> {
    /// The scene's name in the report: its own on its own frame (the suite's size, or the
    /// scene's), `NAME WxH` on a frame size a `[[run]]` gives.
    label: String,
    frame: &'s Frame<'s>,
    effects: Vec<String>,
    ref_name: String,
    ref_rate: Option<u32>,
    reference_ms: f64,
    /// Whether the reference was read from the cache.
    reference_cached: bool,
    /// The reference, the pixel classes and the shadow-only pixels the metrics are taken over.
    truth: Truth,
    /// Index of its images in [`Images::scenes`].
    images: usize,
    /// Index of its shared work in [`Report::scenes`].
    info: usize,
}

/// What a planned run is for.
enum Purpose<'a> {
    /// A combination of a suite's `[[run]]`: a row of the report.
    Suite(&'a crate::suite::RunSpec),
    /// Run `run` of the suite's table `table`: a [`TableRun`].
    Table {
        /// Index into the suite's tables.
        table: usize,
        /// Index into the table's runs on the scene.
        run: usize,
    },
}

/// One run on a frame, built and waiting to be measured.
struct Planned<'a> {
    /// The plan's item.
    item: usize,
    purpose: Purpose<'a>,
    options: MethodOptions,
    technique: Box<dyn ShadowMethod>,
    /// Its share of its item's estimated cost ([`crate::plan`]), for the progress.
    cost: f64,
}

/// Adds the runs of `item`, the `[[run]]` `spec` on an animated scene, to `in_motion`, each
/// priced per frame; a run whose method cannot be built is listed as not run, every frame of
/// it told to `tick`.
fn plan_motion(
    item: &WorkItem,
    spec: &crate::suite::RunSpec,
    in_motion: &mut Vec<crate::motion::Run>,
    report: &mut Report,
    tick: &mut crate::motion::Tick<'_>,
) {
    let scene = item.scene.as_deref().unwrap_or_default();
    let combos = spec.expand();
    let frames = item.frames.max(1);
    // As `item_runs` prices them.
    let cost = item.cost / (combos.len() * frames as usize).max(1) as f64;
    for options in combos {
        let key = key_of(&spec.method, &options);
        match analysis::registry::technique(&spec.method, &options) {
            Ok(technique) => in_motion.push(crate::motion::Run {
                item: item.item,
                method: spec.method.clone(),
                options,
                technique,
                key,
                cost,
            }),
            Err(e) => {
                report.skipped.push(format!("{} on {scene}: {e}", spec.method));
                for _ in 0..frames {
                    tick(&format!("{scene} {}", spec.method), &key, cost, None);
                }
            }
        }
    }
}

/// The key an estimate prices a run of `method` with `options` by.
fn key_of(method: &str, options: &MethodOptions) -> String {
    run_key(method, options.device == Device::Gpu)
}

/// How many method runs `report` measured, counted as [`items_run_count`] counts them (a run in
/// motion once per frame it ran): its rows, untimed outside results and tables' runs.
pub fn measured_run_count(report: &Report) -> u64 {
    let rows: u64 = report.rows.iter().map(|r| r.per_frame.len().max(1) as u64).sum();
    rows + report.untimed.len() as u64 + report.table_runs.len() as u64
}

/// The runs of a plan's item, each with its key and its share of the item's estimated cost; a
/// run in motion once per frame, with its share of one frame.
fn item_runs(suite: &Suite, item: &WorkItem) -> Vec<(String, f64)> {
    let runs: Vec<(String, MethodOptions)> = match &item.work {
        Work::Runs { spec, .. } => {
            let spec = &suite.runs[*spec];
            spec.expand().into_iter().map(|o| (spec.method.clone(), o)).collect()
        }
        Work::Table { table, .. } => {
            let scene = item.scene.as_deref().unwrap_or_default();
            let made = suite.tables[*table].paper.runs(scene);
            made.into_iter().map(|(m, o)| (m.to_owned(), o)).collect()
        }
        Work::Grid { .. } => Vec::new(),
        Work::External { name, .. } => return vec![(external_key(name), item.cost)],
    };
    let frames = item.frames.max(1) as usize;
    let per = item.cost / (runs.len() * frames).max(1) as f64;
    runs.iter().flat_map(|(m, o)| std::iter::repeat_n((key_of(m, o), per), frames)).collect()
}

/// The key an estimate prices the scoring of an outside result by.
fn external_key(name: &str) -> String {
    format!("external {name}")
}

/// Every run of the items of `plan` numbered in `items`, with its key and estimated cost.
fn planned_runs(suite: &Suite, plan: &[WorkItem], items: &[usize]) -> Vec<(String, f64)> {
    items.iter().flat_map(|&k| item_runs(suite, &plan[k])).collect()
}

/// The frame an item runs on: its scene and size.
fn frame_key(item: &WorkItem) -> (Option<&str>, u32, u32) {
    (item.scene.as_deref(), item.width, item.height)
}

/// Runs the items of `plan` numbered in `items` (in plan order; consecutive items on one
/// scene and frame share the frame and its reference, taken from `cache` when it holds them,
/// and their runs are measured together, interleaved); `progress` is called once per method
/// run. Running every item of the plan is running the suite ([`run_suite`]), which also builds
/// the papers' tables from their runs; a shard runs its own ([`crate::plan::Shard::items`]).
pub fn run_items(
    suite: &Suite,
    plan: &[WorkItem],
    items: &[usize],
    mut cache: Option<&mut ReferenceCache>,
    mut progress: impl FnMut(&Progress<'_>),
) -> (Report, Images) {
    let estimate = std::cell::RefCell::new(Estimate::new(planned_runs(suite, plan, items)));
    let log = ProgressLog::new();
    // A run is done: `spent` is its wall time, `None` for one that did not run.
    let mut tick = |label: &str, key: &str, cost: f64, spent: Option<Duration>| {
        let mut e = estimate.borrow_mut();
        e.done(key, cost, spent);
        let (runs_done, runs_total) = e.runs();
        progress(&Progress { label, runs_done, runs_total, time_left: e.time_left() });
    };
    let mut report = Report {
        suite: suite.clone(),
        provenance: Provenance::capture(Provenance::command_line(), None),
        machine: Machine::current(),
        clock: suite.clock,
        scenes: Vec::new(),
        rows: Vec::new(),
        table_runs: Vec::new(),
        skipped: Vec::new(),
        untimed: Vec::new(),
        grids: Vec::new(),
        tables: Vec::new(),
        cache: None,
        shards: Vec::new(),
    };
    let mut images = Images::default();
    let protocol = suite.protocol();
    let mut groups: Vec<Vec<&WorkItem>> = Vec::new();
    for &k in items {
        match groups.last_mut() {
            Some(g) if frame_key(g[0]) == frame_key(&plan[k]) => g.push(&plan[k]),
            _ => groups.push(vec![&plan[k]]),
        }
    }
    // What identifies this build in the cache's keys, worked out when a cache is first used.
    let mut build: Option<String> = None;
    for (n, group) in groups.iter().enumerate() {
        let first = group[0];
        let scene_name = first.scene.as_deref().unwrap_or_default();
        let label = |method: &str| format!("{scene_name} {method}");
        log.print(
            &format!(
                "frame {}/{} {scene_name} {}x{}",
                n + 1,
                groups.len(),
                first.width,
                first.height
            ),
            &estimate.borrow(),
        );
        // Per item, what failing to load the scene leaves undone and how to say it.
        type Tick<'t> = dyn FnMut(&str, &str, f64, Option<Duration>) + 't;
        let not_run = |report: &mut Report, tick: &mut Tick<'_>, why: &str| {
            for item in group {
                for (key, cost) in item_runs(suite, item) {
                    tick(scene_name, &key, cost, None);
                }
                if let Work::Table { paper, .. } = &item.work {
                    report.skipped.push(format!("{paper}: scene {scene_name}: {why}"));
                }
            }
        };
        let loaded = match scenes::load(scene_name) {
            Ok(s) => s,
            Err(e) => {
                if group.iter().any(|i| !matches!(i.work, Work::Table { .. })) {
                    report.skipped.push(format!("scene {scene_name}: {e}"));
                }
                not_run(&mut report, &mut tick, &e.to_string());
                continue;
            }
        };
        // An animated scene's `[[run]]` items run in motion (`crate::motion`); its other items
        // (grids, outside results, tables' runs) run on its frame 0.
        let animation = crate::plan::animation_of(&loaded, suite.frames);
        let posed = animation.as_ref().map(|a| a.pose(&loaded, 0));
        let scene = posed.as_ref().unwrap_or(&loaded);
        let (w, h) = match (first.width, first.height) {
            (0, _) | (_, 0) => (scene.width, scene.height),
            size => size,
        };
        let mut rec = Recorder::default();
        let frame = Frame::new(scene, w, h, &mut rec);
        let gbuffer_ms = rec.stages.total_ms();
        let triangles = frame.geometry.len() as f64;
        // The suite's runs and grids need the scene's reference; a table's own frame does not.
        let mut ctx = None;
        let mut build_id = "";
        if group.iter().any(|i| !matches!(i.work, Work::Table { .. })) {
            build_id = match cache {
                Some(_) => build.get_or_insert_with(|| {
                    crate::cache::build_id(&report.provenance.commit, report.provenance.dirty)
                }),
                None => "",
            };
            match reference_for(suite, scene, &frame, cache.as_deref_mut(), build_id) {
                Ok((ref_name, ref_rate, image, reference_ms, reference_cached)) => {
                    // The metrics are taken over the shadow-only pixels, by the frame's pixel
                    // classes (the reference's own, or the camera's view of the triangles when
                    // it has none), as `compare`'s headline is.
                    let truth = Truth::new(&frame, image, &mut Recorder::default());
                    let effects: Vec<String> =
                        frame.effects.names().into_iter().map(String::from).collect();
                    let own = match suite.width {
                        0 => (scene.width, scene.height),
                        _ => (suite.width, suite.height),
                    };
                    let label = if (w, h) == own {
                        scene.name.clone()
                    } else {
                        format!("{} {w}x{h}", scene.name)
                    };
                    report.scenes.push(SceneInfo {
                        scene: label.clone(),
                        triangles: triangles as u64,
                        effects: effects.clone(),
                        width: w,
                        height: h,
                        gbuffer_ms,
                        gbuffer_cpu_ms: rec.stages.stages.iter().map(|s| s.cpu_ms).sum(),
                        reference: ref_name.clone(),
                        reference_ms,
                    });
                    ctx = Some(SceneRun {
                        info: report.scenes.len() - 1,
                        label,
                        frame: &frame,
                        effects,
                        ref_name,
                        ref_rate,
                        reference_ms,
                        reference_cached,
                        truth,
                        images: images.scenes.len(),
                    });
                }
                Err(e) => report.skipped.push(format!("scene {}: reference: {e}", scene.name)),
            }
        }
        // Every run on the frame is measured together, interleaved round by round; on an
        // animated scene, the `[[run]]`s frame by frame.
        let mut planned = Vec::new();
        let mut in_motion = Vec::new();
        for item in group {
            let runs: Vec<(Purpose<'_>, &str, MethodOptions)> = match &item.work {
                Work::Runs { spec, .. } => {
                    let spec = &suite.runs[*spec];
                    if ctx.is_none() {
                        for (key, cost) in item_runs(suite, item) {
                            tick(&label(&spec.method), &key, cost, None);
                        }
                        continue;
                    }
                    if animation.is_some() {
                        plan_motion(item, spec, &mut in_motion, &mut report, &mut tick);
                        continue;
                    }
                    spec.expand()
                        .into_iter()
                        .map(|o| (Purpose::Suite(spec), spec.method.as_str(), o))
                        .collect()
                }
                Work::Table { table, .. } => {
                    let spec = &suite.tables[*table];
                    let made = spec.paper.runs(scene_name);
                    made.into_iter()
                        .enumerate()
                        .map(|(run, (m, o))| (Purpose::Table { table: *table, run }, m, o))
                        .collect()
                }
                Work::Grid { .. } | Work::External { .. } => continue,
            };
            let cost = item.cost / runs.len().max(1) as f64;
            for (purpose, method, options) in runs {
                match analysis::registry::technique(method, &options) {
                    Ok(technique) => {
                        planned.push(Planned { item: item.item, purpose, options, technique, cost })
                    }
                    Err(e) => {
                        report.skipped.push(not_run_text(suite, &purpose, method, scene_name, &e));
                        tick(&label(method), &key_of(method, &options), cost, None);
                    }
                }
            }
        }
        let mut subjects: Vec<_> = planned
            .iter()
            .map(|p| {
                let frame = &frame;
                move |rec: &mut Recorder| p.technique.run(frame, rec)
            })
            .collect();
        let measured = measure_all(&protocol, &mut subjects, |k, spent| {
            let p = &planned[k];
            let key = key_of(p.technique.name(), &p.options);
            tick(&label(p.technique.name()), &key, p.cost, Some(spent));
        });
        drop(subjects);
        if let (Some(animation), Some(ctx)) = (&animation, &ctx) {
            let animated = crate::motion::Animated {
                suite,
                rest: &loaded,
                animation,
                label: &ctx.label,
                effects: &ctx.effects,
                ref_name: &ctx.ref_name,
                ref_rate: ctx.ref_rate,
                images: ctx.images,
                first: ctx.frame,
                first_truth: &ctx.truth,
                first_reference_ms: ctx.reference_ms,
                first_reference_cached: ctx.reference_cached,
            };
            let mut references = |s: &scenes::Scene, f: &Frame<'_>| {
                reference_for(suite, s, f, cache.as_deref_mut(), build_id).map(
                    |(_, _, image, ms, cached)| crate::motion::FrameReference { image, ms, cached },
                )
            };
            let runs = std::mem::take(&mut in_motion);
            let say = |line: &str| log.print(line, &estimate.borrow());
            let later_ms = crate::motion::run(
                &animated,
                runs,
                &mut references,
                &mut tick,
                &say,
                &mut report,
                &mut images,
            );
            report.scenes[ctx.info].reference_ms += later_ms;
        }
        for (p, m) in planned.iter().zip(measured) {
            let m = match m {
                Ok(m) => m,
                Err(e) => {
                    let why = not_run_text(suite, &p.purpose, p.technique.name(), scene_name, &e);
                    report.skipped.push(why);
                    continue;
                }
            };
            match (&p.purpose, &ctx) {
                (Purpose::Suite(spec), Some(ctx)) => {
                    add_run(suite, ctx, p, spec, m, &mut report, &mut images)
                }
                (Purpose::Table { table, run }, _) => report.table_runs.push(TableRun {
                    table: *table,
                    run: *run,
                    item: p.item,
                    shard: None,
                    scene: scene.name.clone(),
                    width: w,
                    height: h,
                    triangles: triangles as u64,
                    gbuffer_ms,
                    method: p.technique.name().to_owned(),
                    params: p.technique.params(),
                    total_ms: m.wall_ms,
                    cpu_ms: m.cpu_ms,
                    contended: m.contended(),
                    stages: m.stages,
                    counters: m.record.counters,
                }),
                (Purpose::Suite(_), None) => {}
            }
        }
        for item in group {
            let Work::External { external, name } = &item.work else { continue };
            let spent = std::time::Instant::now();
            let scored = match &ctx {
                Some(ctx) => add_external(suite, ctx, item, *external, &mut report, &mut images),
                None => Err("the scene's reference could not be computed".to_owned()),
            };
            match scored {
                Ok(()) => tick(&label(name), &external_key(name), item.cost, Some(spent.elapsed())),
                Err(e) => {
                    report.skipped.push(format!("external {name} on {scene_name}: {e}"));
                    tick(&label(name), &external_key(name), item.cost, None);
                }
            }
        }
        let Some(ctx) = ctx else { continue };
        for item in group {
            let Work::Grid { grid, .. } = &item.work else { continue };
            let g = &suite.grids[*grid];
            let panels = grid_panels(
                g,
                ctx.frame,
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
        let Truth { reference, classes, headline, .. } = ctx.truth;
        images.scenes.push(SceneImages {
            scene: report.scenes.len() - 1,
            reference,
            classes,
            compared: headline,
        });
    }
    log.print("done", &estimate.borrow());
    if items.len() == plan.len() {
        report.tables = crate::tables::build_all(&suite.tables, &report.table_runs);
    }
    report.machine.load_end = instrumentation::clock::Load::now().map(|l| l.loadavg);
    // A scene that cannot be loaded is said once, however many of its items there are.
    let mut seen = std::collections::HashSet::new();
    report.skipped.retain(|s| seen.insert(s.clone()));
    report.provenance.adapter = report.machine.gpu.clone();
    report.cache = cache.map(|c| c.stats);
    (report, images)
}

/// Why a run could not be made, for the report's list of what did not run.
fn not_run_text(
    suite: &Suite,
    purpose: &Purpose<'_>,
    method: &str,
    scene: &str,
    e: &dyn std::fmt::Display,
) -> String {
    match purpose {
        Purpose::Suite(_) => format!("{method} on {scene}: {e}"),
        Purpose::Table { table, .. } => {
            format!("{}: {method} on {scene}: {e}", suite.tables[*table].paper.name())
        }
    }
}

/// Measures the suite's table `spec` alone under `protocol`: its runs planned and swept as a
/// report sweeps them, then the table built from them ([`crate::tables::build`]). What could
/// not run is added to `skipped`; `progress` is called once per run.
pub fn run_table(
    spec: &crate::tables::TableSpec,
    protocol: &instrumentation::measure::Protocol,
    skipped: &mut Vec<String>,
    mut progress: impl FnMut(&str),
) -> crate::tables::Table {
    let suite = Suite {
        name: spec.paper.name().to_owned(),
        description: String::new(),
        width: 0,
        height: 0,
        warmup: protocol.warmup,
        repeats: protocol.min_repeats,
        max_repeats: Some(protocol.max_repeats),
        target: protocol.target_half_width,
        time_cap_s: protocol.time_cap.as_secs_f64(),
        clock: protocol.clock,
        reference: Default::default(),
        ref_rate: 1,
        scenes: Vec::new(),
        runs: Vec::new(),
        grids: Vec::new(),
        tables: vec![spec.clone()],
        externals: Vec::new(),
        frames: None,
    };
    let (report, _) = run_suite(&suite, |p| progress(p.label));
    skipped.extend(report.skipped);
    report.tables.into_iter().next().unwrap_or_else(|| crate::tables::build(spec, 0, &[]))
}

/// Adds the row and images of one measured combination: its comparison with the reference,
/// its times on both clocks and its record; a run whose comparison fails is added to the
/// report's skipped runs.
fn add_run(
    suite: &Suite,
    ctx: &SceneRun<'_>,
    p: &Planned<'_>,
    spec: &crate::suite::RunSpec,
    m: Measured<Visibility>,
    report: &mut Report,
    images: &mut Images,
) {
    let (w, h) = (ctx.frame.width(), ctx.frame.height());
    if p.options.device == Device::Gpu && report.machine.gpu.is_none() {
        report.machine.gpu = methods::registry::gpu_adapter_name();
    }
    let v = &m.output;
    let comparison = match ctx.truth.compare(ctx.frame, v) {
        Ok(c) => c,
        Err(e) => {
            report.skipped.push(format!("{} on {}: {e}", spec.method, ctx.label));
            return;
        }
    };
    let mut record = m.run_record(
        RunIdentity {
            scene: ctx.label.clone(),
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
        scene: ctx.label.clone(),
        method: record.method.clone(),
        params: record.params.clone(),
        width: w,
        height: h,
        method_ms: Some(record.total_ms),
        reference_ms: ctx.reference_ms,
        reference_cached: ctx.reference_cached,
        reference_read_ms: None,
        external: false,
    };
    let truth = &ctx.truth;
    report.rows.push(Row {
        scene: ctx.label.clone(),
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
        external: false,
        temporal: None,
        per_frame: Vec::new(),
    });
    images.runs.push(Produced {
        row: report.rows.len() - 1,
        scene: ctx.images,
        visibility: m.output,
        record,
        metrics,
        motion: None,
    });
}

/// Scores the suite's `[[external]]` entry number `k` on `item`'s scene, `ctx` (its file read
/// and checked against the frame, [`crate::external::read_visibility`]), and adds its row: to
/// the rows, with its record, metrics and images, when the suite gives its time on the scene;
/// else to the untimed results ([`Report::untimed`]). The error says why it could not be
/// scored.
fn add_external(
    suite: &Suite,
    ctx: &SceneRun<'_>,
    item: &WorkItem,
    k: usize,
    report: &mut Report,
    images: &mut Images,
) -> Result<(), String> {
    let spec = &suite.externals[k];
    let scene_key = item.scene.as_deref().unwrap_or_default();
    let file = spec.files.get(scene_key).ok_or("the entry has no file for the scene")?;
    let (w, h) = (ctx.frame.width(), ctx.frame.height());
    let v = crate::external::read_visibility(file, w, h).map_err(|e| e.to_string())?;
    let comparison = ctx.truth.compare(ctx.frame, &v).map_err(|e| e.to_string())?;
    let time = spec.time_on(scene_key);
    let truth = &ctx.truth;
    let untimed = Summary {
        n: 0,
        median: 0.0,
        ci_low: None,
        ci_high: None,
        ci_level: None,
        min: 0.0,
        max: 0.0,
    };
    let notes = vec![format!("an outside renderer's result, read from {}", file.display())];
    let row = Row {
        scene: ctx.label.clone(),
        method: spec.name.clone(),
        params: serde_json::Map::new(),
        width: w,
        height: h,
        reference: ctx.ref_name.clone(),
        ref_rate: ctx.ref_rate,
        metrics: Metrics::compare(&v, &truth.reference.lit, &truth.headline),
        flip_mean: comparison.flip_mean,
        pixel_match_lecocq: comparison.pixel_match_lecocq,
        error_exceedance: exceedance(&v, &truth.reference.lit, &truth.headline).unwrap_or_default(),
        classes: Some(comparison.classes),
        item: item.item,
        shard: None,
        total_ms: time.and_then(|t| Summary::of(&[t])).unwrap_or(untimed),
        cpu_ms: None,
        contended: false,
        conditions: None,
        stages: Vec::new(),
        skipped_stages: Vec::new(),
        counters: Default::default(),
        notes: notes.clone(),
        external: true,
        temporal: None,
        per_frame: Vec::new(),
    };
    let Some(time) = time else {
        report.untimed.push(row);
        return Ok(());
    };
    let metrics = MetricsRecord {
        comparison,
        reference: ctx.ref_name.clone(),
        ref_rate: ctx.ref_rate,
        edge_reference: (ctx.ref_name == "exact").then(|| "none".to_owned()),
        scene: ctx.label.clone(),
        method: spec.name.clone(),
        params: serde_json::Map::new(),
        width: w,
        height: h,
        method_ms: Some(time),
        reference_ms: ctx.reference_ms,
        reference_cached: ctx.reference_cached,
        reference_read_ms: None,
        external: true,
    };
    let record = instrumentation::RunRecord {
        scene: ctx.label.clone(),
        method: spec.name.clone(),
        params: serde_json::Map::new(),
        width: w,
        height: h,
        effects: ctx.effects.clone(),
        counters: Default::default(),
        stages: Vec::new(),
        skipped_stages: Vec::new(),
        notes,
        warnings: Vec::new(),
        total_ms: time,
        cpu_ms: None,
        clocks: "total_ms: the time the suite gives for the outside renderer".to_owned(),
        timing: None,
        pixel_classes: None,
        provenance: Some(report.provenance.clone()),
    };
    report.rows.push(row);
    images.runs.push(Produced {
        row: report.rows.len() - 1,
        scene: ctx.images,
        visibility: v,
        record,
        metrics,
        motion: None,
    });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cost_tables_measure_every_method_against_work_and_draw_it() {
        // Two scenes of different triangle counts at a small frame, planned and swept as a
        // suite's table items are.
        let spec = crate::tables::TableSpec {
            paper: crate::tables::PaperTable::CostAgainstTriangles,
            scenes: vec!["plane-square".into(), "cage".into()],
            width: 48,
            height: 32,
        };
        let mut skipped = Vec::new();
        let t = run_table(
            &spec,
            &instrumentation::measure::Protocol::fixed(0, 1),
            &mut skipped,
            |_| {},
        );
        assert!(skipped.is_empty(), "{skipped:?}");
        assert_eq!(t.header[1..], ["plane-square 48x32", "cage 48x32", "fitted exponent"]);
        let labels: Vec<&str> = t.rows.iter().map(|r| r[0].as_str()).collect();
        assert_eq!(
            labels,
            [
                "triangles",
                "pixels",
                "camera G-buffer (ms)",
                "afsm (ms)",
                "raytrace 1x (ms)",
                "exact (ms)",
                "sm (ms)",
                "pan09 32x (ms)",
                "spsm (ms)",
                "ftizb 1x (ms)",
                "ftizb 32x (ms)",
            ]
        );
        assert_eq!(t.curves.len(), 9, "the G-buffer and eight runs");
        for c in &t.curves {
            let works: Vec<f64> = c.points.iter().map(|p| p.0).collect();
            assert_eq!(works.len(), 2, "{}: a point per scene", c.label);
            assert!(works[0] < works[1], "{}: triangles grow along the row", c.label);
            assert!(c.exponent.is_some_and(f64::is_finite), "{}", c.label);
        }
        let drawn = crate::tables::chart(&t).expect("a cost table has a chart");
        assert_eq!((drawn.x_label.as_str(), drawn.series.len()), ("triangles", 9));
        assert!(drawn.series[2].label.starts_with("raytrace 1x (exponent "), "{:?}", drawn.series);
        assert!(crate::tables::markdown(&t).contains("| fitted exponent |"));
        // The papers' tables draw no chart.
        let paper = crate::tables::Table {
            paper: crate::tables::PaperTable::LecocqTable2,
            curves: vec![],
            ..t
        };
        assert!(crate::tables::chart(&paper).is_none());
        // `cost-against-pixels` runs one scene at every frame unless a frame is given.
        let pixels = crate::tables::TableSpec {
            paper: crate::tables::PaperTable::CostAgainstPixels,
            ..spec
        };
        assert_eq!(crate::tables::frames_of(&pixels), vec![(48, 32)]);
        let pixels = crate::tables::TableSpec { width: 0, height: 0, ..pixels };
        assert_eq!(crate::tables::frames_of(&pixels), crate::tables::COST_FRAMES.to_vec());
    }
}
