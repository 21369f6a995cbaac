//! A suite's runs on an animated scene (its animation not still, [`crate::plan::animation_of`]):
//! every run through every frame, measured, compared with the frame's truth and paired with its
//! previous frame by the temporal error (`analysis::temporal`), as `shadowbench animate` does
//! for one run; one row per run.
//!
//! For each frame `i` the scene is posed (`scenes::Animation::pose`), its frame built and its
//! reference taken as the sweep takes a still scene's, through its reference cache (the
//! cache's keys hash the posed scene, so the runs share each frame's reference and a second
//! report computes none), and its `Truth` prepared; frame 0 is the frame the sweep prepared for
//! the scene's other items. Then every run still going is measured on the frame, all together,
//! interleaved (`instrumentation::measure::measure_all`): a run whose method has a map (its
//! parameters have `map_res`) at its `map_res` times the scene's map scale at the frame,
//! rounded, within 1 to 16384 ([`scaled_map_res`]); compared with the truth; paired with its
//! previous frame; and its frame's images encoded as PNG: the method's shaded image and the
//! reference's (`crate::output::shade`), and the error map over the headline pixels at
//! `analysis::error_map::DEFAULT_MAX_ERROR`. Two frames are held at a time: of the previous
//! frame its camera, geometry, G-buffer and truth, and per run only its lit fraction, beside
//! the run's accumulators and encoded images.
//!
//! Each run gives one [`Row`]:
//!
//! - `metrics` and `error_exceedance`: pooled over the frames, each compared pixel of each
//!   frame counted once (so means are weighted by the frames' pixel counts); the max is the
//!   largest; the boundary percentiles are nearest rank over the boundary errors of every
//!   frame, which are kept for that;
//! - `flip_mean`: the mean over frames; `pixel_match_lecocq`: the mean over frames when every
//!   frame has one, else `None`; `classes`: frame 0's;
//! - `total_ms`, `cpu_ms`: a `Summary` over the frames of each frame's median time, so that
//!   its `n` is the frame count and the cost axis reads per frame; `stages`: each stage the
//!   same way, over the frames that ran it; `contended` when any frame was; `conditions`
//!   pooled (the load before the first frame and after the last, the largest shares other
//!   processes and the hypervisor took, the lowest CPU share);
//! - `counters`, `skipped_stages` and `notes`: frame 0's run, with a note when the map was
//!   scaled; `params`: the run's own, its `map_res` unscaled;
//! - `temporal`: the temporal metrics over every pair of consecutive frames; `per_frame`: a
//!   [`FrameRecord`] per frame, as `animate` writes `frames.csv`.
//!
//! Its [`Produced`] holds frame 0's lit fraction and run record (what the run's page shows
//! beside the scene's reference and class map, which are frame 0's, as are a grid's, an outside
//! result's and a table's runs on the scene), the pooled comparison as its metrics record, and
//! every frame's images ([`MotionFrames`], shown [`FRAME_MS`] each).
//!
//! A run that fails on a frame (the method, its comparison, its images) is left out of the
//! rows and listed among the report's runs not run, naming the frame; a frame whose reference
//! cannot be computed ends every run still going. The progress is told once per run per frame.

use crate::animation::{mean_of, FrameRecord};
use crate::model::{Images, MotionFrames, Produced, Report, Row};
use crate::output::{shade, MetricsRecord};
use crate::suite::Suite;
use analysis::compare::Truth;
use analysis::metrics::{nearest_rank, Comparison, EXCEEDANCE_THRESHOLDS, MATCH_TOLERANCE};
use analysis::temporal::{FrameInput, Temporal, View};
use analysis::{Metrics, ReferenceImage};
use instrumentation::measure::{measure_all, Conditions, Measured, Protocol, StageTimes};
use instrumentation::stats::Summary;
use instrumentation::{Recorder, RunIdentity, RunRecord};
use methods::{registry::Device, Frame, MethodOptions, ShadowMethod, Visibility};
use std::time::Duration;

/// How long a player shows each frame of a run in motion, milliseconds (also `animate`'s
/// default).
pub const FRAME_MS: u16 = 100;

/// The largest map resolution a scaled map takes.
const MAX_MAP_RES: f64 = 16384.0;

/// The map resolution of a frame: the run's `base` times the scene's map `scale` at the frame,
/// rounded to whole texels, within 1 to 16384.
pub fn scaled_map_res(base: u32, scale: f64) -> u32 {
    // A scale that is not a number gives 0 here, hence the last `max`.
    ((f64::from(base) * scale).round().clamp(1.0, MAX_MAP_RES) as u32).max(1)
}

/// A frame's reference as the sweep takes it.
pub struct FrameReference {
    /// The reference.
    pub image: ReferenceImage,
    /// Its time, milliseconds (by the run that computed it when it was read from a cache).
    pub ms: f64,
    /// Whether it was read from a cache.
    pub cached: bool,
}

/// Where the frames' references come from: the posed scene and its frame in, the reference
/// or why there is none out.
pub type References<'r> =
    dyn FnMut(&scenes::Scene, &Frame<'_>) -> Result<FrameReference, String> + 'r;

/// Tells the progress a run's frame is done: label, the run's price key
/// (`crate::progress::run_key`), its estimated cost, its wall time (`None` when it did not
/// run).
pub type Tick<'t> = dyn FnMut(&str, &str, f64, Option<Duration>) + 't;

/// An animated scene as the sweep prepared it, frame 0 included.
pub struct Animated<'a> {
    /// The suite (its timing protocol and warm-up).
    pub suite: &'a Suite,
    /// The scene at rest, posed at every frame.
    pub rest: &'a scenes::Scene,
    /// Its animation, sampled at the frames to run.
    pub animation: &'a scenes::Animation,
    /// The scene's name in the report.
    pub label: &'a str,
    /// The effects it calls for.
    pub effects: &'a [String],
    /// The reference's name (`exact`, `raytrace`).
    pub ref_name: &'a str,
    /// The `raytrace` reference's rate.
    pub ref_rate: Option<u32>,
    /// Index of its images in [`Images::scenes`].
    pub images: usize,
    /// Frame 0.
    pub first: &'a Frame<'a>,
    /// Frame 0's truth.
    pub first_truth: &'a Truth,
    /// Frame 0's reference time, milliseconds.
    pub first_reference_ms: f64,
    /// Whether frame 0's reference was read from a cache.
    pub first_reference_cached: bool,
}

/// One planned run of a `[[run]]` on the animated scene.
pub struct Run {
    /// The plan's item.
    pub item: usize,
    /// The method's name in the registry.
    pub method: String,
    /// Its options (the map resolution unscaled).
    pub options: MethodOptions,
    /// The method built with them.
    pub technique: Box<dyn ShadowMethod>,
    /// The key its progress is priced by.
    pub key: String,
    /// Its estimated cost on one frame.
    pub cost: f64,
}

/// Every compared pixel of every frame, pooled (the same sums as `analysis::Metrics::compare`
/// and `analysis::metrics::exceedance` over one frame).
#[derive(Debug, Default)]
struct Pooled {
    n: u64,
    sum: f64,
    sq: f64,
    max: f64,
    matched: u64,
    /// The boundary pixels' errors, for their percentiles.
    boundary: Vec<f64>,
    /// Pixels whose error exceeds each of [`EXCEEDANCE_THRESHOLDS`].
    over: [u64; EXCEEDANCE_THRESHOLDS.len()],
}

impl Pooled {
    /// Adds the pixels of one frame where `mask` is true.
    fn add(&mut self, result: &Visibility, reference: &[f64], mask: &[bool]) {
        for ((&v, &r), _) in result.lit.iter().zip(reference).zip(mask).filter(|(_, &m)| m) {
            let e = (f64::from(v) - r).abs();
            self.n += 1;
            self.sum += e;
            self.sq += e * e;
            self.max = self.max.max(e);
            self.matched += u64::from(e <= MATCH_TOLERANCE);
            if r > 0.0 && r < 1.0 {
                self.boundary.push(e);
            }
            for (c, &t) in self.over.iter_mut().zip(&EXCEEDANCE_THRESHOLDS) {
                *c += u64::from(e > t);
            }
        }
    }

    /// The pooled metrics and error distribution (`None` when no pixel was compared).
    fn finish(mut self) -> (Metrics, Option<Vec<f64>>) {
        let mean = |s: f64, n: u64| if n == 0 { 0.0 } else { s / n as f64 };
        let nb = self.boundary.len() as u64;
        let sum_b = self.boundary.iter().sum::<f64>();
        let [p50, p95, p99] = [50, 95, 99].map(|p| nearest_rank(&mut self.boundary, p));
        let n = self.n;
        let metrics = Metrics {
            evaluated_pixels: n,
            mean_abs_error: mean(self.sum, n),
            rmse: mean(self.sq, n).sqrt(),
            max_abs_error: self.max,
            pixel_match: if n == 0 { 1.0 } else { self.matched as f64 / n as f64 },
            boundary_pixels: nb,
            boundary_mean_abs_error: mean(sum_b, nb),
            boundary_p50_abs_error: p50,
            boundary_p95_abs_error: p95,
            boundary_p99_abs_error: p99,
        };
        let shares = (n > 0).then(|| self.over.iter().map(|&c| c as f64 / n as f64).collect());
        (metrics, shares)
    }
}

/// The conditions of two stretches of timed runs, the first before the second, as one.
fn pool_conditions(a: Conditions, b: Conditions) -> Conditions {
    let pick = |x: Option<f64>, y: Option<f64>, f: fn(f64, f64) -> f64| match (x, y) {
        (Some(x), Some(y)) => Some(f(x, y)),
        (x, y) => x.or(y),
    };
    Conditions {
        loadavg_before: a.loadavg_before.or(b.loadavg_before),
        loadavg_after: b.loadavg_after.or(a.loadavg_after),
        others_share: pick(a.others_share, b.others_share, f64::max),
        steal_share: pick(a.steal_share, b.steal_share, f64::max),
        min_share: pick(a.min_share, b.min_share, f64::min),
        cores: a.cores.max(b.cores),
    }
}

/// An image as PNG bytes.
fn png(image: &image::RgbImage) -> Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .map_err(|e| format!("cannot encode a frame's image: {e}"))?;
    Ok(bytes)
}

/// What a run keeps of frame 0.
struct First {
    visibility: Visibility,
    record: RunRecord,
    comparison: Comparison,
}

/// One stage's per-frame medians.
struct StageFrames {
    name: String,
    wall: Vec<f64>,
    cpu: Vec<Option<f64>>,
}

/// A run going through the frames: its previous lit fraction and its accumulators.
struct Going {
    run: Run,
    /// Its parameters as its method gives them (the map resolution unscaled).
    params: serde_json::Map<String, serde_json::Value>,
    /// Its map resolution, for a method with a map.
    base_map: Option<u32>,
    failed: bool,
    prev: Option<Visibility>,
    temporal: Temporal,
    pooled: Pooled,
    flip: Vec<f64>,
    lecocq: Vec<Option<f64>>,
    wall: Vec<f64>,
    cpu: Vec<Option<f64>>,
    stages: Vec<StageFrames>,
    contended: bool,
    conditions: Option<Conditions>,
    per_frame: Vec<FrameRecord>,
    frames: MotionFrames,
    first: Option<First>,
}

impl Going {
    fn new(run: Run) -> Self {
        let params = run.technique.params();
        let base_map = params.get("map_res").and_then(serde_json::Value::as_u64).map(|m| m as u32);
        Self {
            run,
            params,
            base_map,
            failed: false,
            prev: None,
            temporal: Temporal::new(),
            pooled: Pooled::default(),
            flip: Vec::new(),
            lecocq: Vec::new(),
            wall: Vec::new(),
            cpu: Vec::new(),
            stages: Vec::new(),
            contended: false,
            conditions: None,
            per_frame: Vec::new(),
            frames: MotionFrames {
                method: Vec::new(),
                reference: Vec::new(),
                error: Vec::new(),
                frame_ms: FRAME_MS,
            },
            first: None,
        }
    }
}

/// What one frame of the animation is, for its runs.
struct FrameAt<'f> {
    i: u32,
    frame: &'f Frame<'f>,
    truth: &'f Truth,
    /// The previous frame's view and truth (none for frame 0).
    prev: Option<(View<'f>, &'f Truth)>,
    reference_ms: f64,
    reference_cached: bool,
    /// The reference's shaded image, once for every run.
    reference_png: Result<Vec<u8>, String>,
}

/// A run on one frame: which run, its method when built again for the frame's map, the
/// frame's map resolution.
struct FrameRun {
    k: usize,
    built: Option<Box<dyn ShadowMethod>>,
    map_res: Option<u32>,
}

/// The runs of one animated scene going through its frames.
struct Runner<'a> {
    scene: &'a Animated<'a>,
    protocol: Protocol,
    frames: u32,
    going: Vec<Going>,
}

impl Runner<'_> {
    /// The label of run `k`'s progress on frame `i`.
    fn label(&self, k: usize, i: u32) -> String {
        let g = &self.going[k];
        format!("{} {} frame {}/{}", self.scene.label, g.run.method, i + 1, self.frames)
    }

    /// Run `k` fails on frame `i` for `why`: listed as not run, its frames from `from` on
    /// told as not run.
    fn fail(
        &mut self,
        k: usize,
        i: u32,
        from: u32,
        why: &str,
        tick: &mut Tick<'_>,
        r: &mut Report,
    ) {
        let label = self.label(k, i);
        let g = &mut self.going[k];
        g.failed = true;
        let name = &g.run.method;
        r.skipped.push(format!("{name} on {}: frame {i}: {why}", self.scene.label));
        for _ in from..self.frames {
            tick(&label, &g.run.key, g.run.cost, None);
        }
    }

    /// Measures every run still going on frame `f.i` and adds what it gives.
    fn frame(&mut self, f: &FrameAt<'_>, tick: &mut Tick<'_>, report: &mut Report) {
        let i = f.i;
        let scale = self.scene.animation.map_scale(i);
        // Each run's method at the frame: built again where the map is scaled.
        let mut runs: Vec<FrameRun> = Vec::new();
        for k in 0..self.going.len() {
            let g = &self.going[k];
            if g.failed {
                continue;
            }
            let map_res = g.base_map.map(|m| scaled_map_res(m, scale));
            let built = match map_res.filter(|&m| Some(m) != g.base_map) {
                Some(m) => {
                    let options = MethodOptions { map_res: Some(m), ..g.run.options.clone() };
                    match analysis::registry::technique(&g.run.method, &options) {
                        Ok(t) => Some(t),
                        Err(e) => {
                            self.fail(k, i, i, &e.to_string(), tick, report);
                            continue;
                        }
                    }
                }
                None => None,
            };
            runs.push(FrameRun { k, built, map_res });
        }
        let going = &self.going;
        let frame = f.frame;
        let mut subjects: Vec<_> = runs
            .iter()
            .map(|r| {
                let technique: &dyn ShadowMethod = match &r.built {
                    Some(t) => t.as_ref(),
                    None => going[r.k].run.technique.as_ref(),
                };
                move |rec: &mut Recorder| technique.run(frame, rec)
            })
            .collect();
        let labels: Vec<String> = runs.iter().map(|r| self.label(r.k, i)).collect();
        let measured = measure_all(&self.protocol, &mut subjects, |j, spent| {
            let g = &going[runs[j].k];
            tick(&labels[j], &g.run.key, g.run.cost, Some(spent));
        });
        drop(subjects);
        for (FrameRun { k, map_res, .. }, m) in runs.into_iter().zip(measured) {
            let added = match m {
                Ok(m) => self.add(k, f, map_res, m, report),
                Err(e) => Err(e.to_string()),
            };
            if let Err(why) = added {
                self.fail(k, i, i + 1, &why, tick, report);
            }
        }
    }

    /// Adds run `k`'s measurement `m` on frame `f` (run at `map_res`): everything that can
    /// fail first, then the accumulators.
    fn add(
        &mut self,
        k: usize,
        f: &FrameAt<'_>,
        map_res: Option<u32>,
        m: Measured<Visibility>,
        report: &Report,
    ) -> Result<(), String> {
        let (frame, truth, i) = (f.frame, f.truth, f.i);
        let v = &m.output;
        let comparison = truth.compare(frame, v).map_err(|e| e.to_string())?;
        let method_png = png(&shade(frame, v))?;
        let max = analysis::error_map::DEFAULT_MAX_ERROR;
        let error = analysis::error_map::error_map(v, &truth.reference.lit, &truth.headline, max)
            .map_err(|e| e.to_string())?;
        let error_png = png(&error)?;
        let reference_png = f.reference_png.clone()?;
        let scene = self.scene;
        let first = (i == 0).then(|| {
            let who = RunIdentity {
                scene: scene.label.to_owned(),
                method: self.going[k].run.technique.name().to_owned(),
                params: frame_params(&self.going[k].params, map_res),
                width: frame.width(),
                height: frame.height(),
                effects: scene.effects.to_vec(),
            };
            let mut record = m.run_record(who, self.scene.suite.warmup);
            record.provenance = Some(report.provenance.clone());
            First { visibility: m.output.clone(), record, comparison: comparison.clone() }
        });
        let g = &mut self.going[k];
        let pair = match (f.prev, &g.prev) {
            (Some((view, prev_truth)), Some(prev)) => {
                let before = FrameInput { view, truth: prev_truth, result: prev };
                Some(g.temporal.add(&before, &FrameInput::of(frame, truth, v)))
            }
            _ => None,
        };
        g.pooled.add(v, &truth.reference.lit, &truth.headline);
        g.flip.push(comparison.flip_mean);
        g.lecocq.push(comparison.pixel_match_lecocq);
        g.wall.push(m.wall_ms.median);
        g.cpu.push(m.cpu_ms.map(|c| c.median));
        for s in &m.stages {
            let at = match g.stages.iter().position(|t| t.name == s.name) {
                Some(at) => at,
                None => {
                    let name = s.name.clone();
                    g.stages.push(StageFrames { name, wall: Vec::new(), cpu: Vec::new() });
                    g.stages.len() - 1
                }
            };
            g.stages[at].wall.push(s.ms.median);
            g.stages[at].cpu.push(s.cpu_ms.map(|c| c.median));
        }
        g.contended |= m.contended();
        g.conditions = Some(match g.conditions {
            Some(c) => pool_conditions(c, m.conditions),
            None => m.conditions,
        });
        g.per_frame.push(FrameRecord {
            frame: i,
            time: scene.animation.time(i),
            map_res,
            mean_abs_error: comparison.mean_abs_error,
            boundary_mean_abs_error: comparison.boundary_mean_abs_error,
            boundary_p95_abs_error: comparison.boundary_p95_abs_error,
            temporal_error: pair.and(g.temporal.last_mean()),
            temporal_pairs: pair.unwrap_or(0),
            method_ms: m.wall_ms.median,
            method_cpu_ms: m.cpu_ms.map(|c| c.median),
            reference_ms: f.reference_ms,
            reference_cached: f.reference_cached,
        });
        g.frames.method.push(method_png);
        g.frames.reference.push(reference_png);
        g.frames.error.push(error_png);
        if first.is_some() {
            g.first = first;
        }
        g.prev = Some(m.output);
        Ok(())
    }
}

/// The parameters of a frame's run: the run's own, its map resolution the frame's.
fn frame_params(
    params: &serde_json::Map<String, serde_json::Value>,
    map_res: Option<u32>,
) -> serde_json::Map<String, serde_json::Value> {
    let mut params = params.clone();
    if let Some(m) = map_res {
        params.insert("map_res".into(), m.into());
    }
    params
}

/// What the previous frame keeps for the temporal pairs: its view and its truth.
struct Kept {
    camera: scenes::Projector,
    geometry: scenes::Geometry,
    gbuffer: methods::gbuffer::GBuffer,
    truth: Truth,
}

impl Kept {
    fn view(&self) -> View<'_> {
        View { camera: &self.camera, geometry: &self.geometry, gbuffer: &self.gbuffer }
    }
}

/// The reference's shaded image on `frame` as PNG bytes.
fn reference_png(frame: &Frame<'_>, truth: &Truth) -> Result<Vec<u8>, String> {
    png(&shade(frame, &truth.reference.to_visibility()))
}

/// Runs `runs` through every frame of `scene` (see the module documentation), taking the
/// frames' references from `references`, telling each run's frames to `tick` and each frame's
/// start to `say` (`cage-sweep in motion, frame 2/24`); adds a row and its images per run that
/// went through every frame, and lists the others as not run. Returns the time of the
/// references of frames 1 and on, milliseconds (frame 0's is the sweep's).
pub fn run(
    scene: &Animated<'_>,
    runs: Vec<Run>,
    references: &mut References<'_>,
    tick: &mut Tick<'_>,
    say: &dyn Fn(&str),
    report: &mut Report,
    images: &mut Images,
) -> f64 {
    let frames = scene.animation.frames();
    let going = runs.into_iter().map(Going::new).collect();
    let mut runner = Runner { scene, protocol: scene.suite.protocol(), frames, going };
    let (w, h) = (scene.first.width(), scene.first.height());
    let mut later_ms = 0.0;
    let mut all_cached = scene.first_reference_cached;
    let mut kept: Option<Kept> = None;
    for i in 0..frames {
        if runner.going.iter().all(|g| g.failed) {
            break;
        }
        say(&format!("{} in motion, frame {}/{frames}", scene.label, i + 1));
        if i == 0 {
            let f = FrameAt {
                i,
                frame: scene.first,
                truth: scene.first_truth,
                prev: None,
                reference_ms: scene.first_reference_ms,
                reference_cached: scene.first_reference_cached,
                reference_png: reference_png(scene.first, scene.first_truth),
            };
            runner.frame(&f, tick, report);
            continue;
        }
        let posed = scene.animation.pose(scene.rest, i);
        let frame = Frame::new(&posed, w, h, &mut Recorder::default());
        let reference = match references(&posed, &frame) {
            Ok(r) => r,
            Err(e) => {
                for k in 0..runner.going.len() {
                    if !runner.going[k].failed {
                        runner.fail(k, i, i, &format!("reference: {e}"), tick, report);
                    }
                }
                break;
            }
        };
        later_ms += reference.ms;
        all_cached &= reference.cached;
        let truth = Truth::new(&frame, reference.image, &mut Recorder::default());
        let prev = match &kept {
            Some(k) => (k.view(), &k.truth),
            None => (View::of(scene.first), scene.first_truth),
        };
        let f = FrameAt {
            i,
            frame: &frame,
            truth: &truth,
            prev: Some(prev),
            reference_ms: reference.ms,
            reference_cached: reference.cached,
            reference_png: reference_png(&frame, &truth),
        };
        runner.frame(&f, tick, report);
        drop(f);
        let Frame { camera, geometry, gbuffer, .. } = frame;
        kept = Some(Kept { camera, geometry, gbuffer, truth });
    }
    let reference_ms = scene.first_reference_ms + later_ms;
    for g in runner.going.into_iter().filter(|g| !g.failed) {
        let method = g.run.method.clone();
        match finish(scene, g, reference_ms, all_cached, report) {
            Some((row, produced)) => {
                report.rows.push(row);
                images.runs.push(Produced { row: report.rows.len() - 1, ..produced });
            }
            None => {
                report.skipped.push(format!("{method} on {}: no frame was measured", scene.label))
            }
        }
    }
    later_ms
}

/// The row and images of a run that went through every frame (see the module documentation);
/// `None` when no frame was measured.
fn finish(
    scene: &Animated<'_>,
    g: Going,
    reference_ms: f64,
    reference_cached: bool,
    report: &mut Report,
) -> Option<(Row, Produced)> {
    let first = g.first?;
    let total_ms = Summary::of(&g.wall)?;
    let cpu_ms = g.cpu.iter().copied().collect::<Option<Vec<f64>>>().and_then(|c| Summary::of(&c));
    let stages: Vec<StageTimes> = g
        .stages
        .iter()
        .filter_map(|s| {
            let cpu = s.cpu.iter().copied().collect::<Option<Vec<f64>>>();
            Summary::of(&s.wall).map(|ms| StageTimes {
                name: s.name.clone(),
                ms,
                cpu_ms: cpu.and_then(|c| Summary::of(&c)),
            })
        })
        .collect();
    let (metrics, exceedance) = g.pooled.finish();
    let flip_mean = mean_of(g.flip.iter().copied().map(Some)).unwrap_or(0.0);
    // The mean only when every frame has one.
    let lecocq =
        g.lecocq.iter().all(Option::is_some).then(|| mean_of(g.lecocq.iter().copied())).flatten();
    let mut notes = first.record.notes.clone();
    let maps: Vec<u32> = g.per_frame.iter().filter_map(|f| f.map_res).collect();
    if let (Some(lo), Some(hi)) = (maps.iter().min(), maps.iter().max()) {
        if lo != hi || Some(*lo) != g.base_map {
            notes.push(format!(
                "map_res scaled frame by frame by the scene's map scale: {lo} to {hi} texels"
            ));
        }
    }
    if g.run.options.device == Device::Gpu && report.machine.gpu.is_none() {
        report.machine.gpu = methods::registry::gpu_adapter_name();
    }
    let c = &first.comparison;
    let some = |v: f64| (metrics.evaluated_pixels > 0).then_some(v);
    let comparison = Comparison {
        evaluated_pixels: metrics.evaluated_pixels,
        mean_abs_error: some(metrics.mean_abs_error),
        rmse: some(metrics.rmse),
        max_abs_error: some(metrics.max_abs_error),
        boundary_pixels: metrics.boundary_pixels,
        boundary_mean_abs_error: metrics.boundary_mean(),
        boundary_p50_abs_error: metrics.boundary_p50_abs_error,
        boundary_p95_abs_error: metrics.boundary_p95_abs_error,
        boundary_p99_abs_error: metrics.boundary_p99_abs_error,
        flip_mean,
        pixel_match: some(metrics.pixel_match),
        pixel_match_lecocq: lecocq,
        classes: c.classes,
        class_pixels: c.class_pixels.clone(),
    };
    let (width, height) = (scene.first.width(), scene.first.height());
    let method = first.record.method.clone();
    let metrics_record = MetricsRecord {
        comparison,
        reference: scene.ref_name.to_owned(),
        ref_rate: scene.ref_rate,
        edge_reference: (scene.ref_name == "exact").then(|| "none".to_owned()),
        scene: scene.label.to_owned(),
        method: method.clone(),
        params: g.params.clone(),
        width,
        height,
        method_ms: Some(total_ms.median),
        reference_ms,
        reference_cached,
        reference_read_ms: None,
        external: false,
    };
    let row = Row {
        scene: scene.label.to_owned(),
        method,
        params: g.params,
        width,
        height,
        reference: scene.ref_name.to_owned(),
        ref_rate: scene.ref_rate,
        metrics,
        flip_mean,
        pixel_match_lecocq: lecocq,
        error_exceedance: exceedance.unwrap_or_default(),
        classes: Some(c.classes),
        item: g.run.item,
        shard: None,
        total_ms,
        cpu_ms,
        contended: g.contended,
        conditions: g.conditions,
        stages,
        skipped_stages: first.record.skipped_stages.clone(),
        counters: first.record.counters,
        notes,
        external: false,
        temporal: Some(g.temporal.finish()),
        per_frame: g.per_frame,
    };
    let produced = Produced {
        row: 0,
        scene: scene.images,
        visibility: first.visibility,
        record: first.record,
        metrics: metrics_record,
        motion: Some(g.frames),
    };
    Some((row, produced))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_map_scale_rounds_and_stays_in_range() {
        assert_eq!(scaled_map_res(512, 0.25), 128);
        assert_eq!(scaled_map_res(512, 1.0), 512);
        assert_eq!(scaled_map_res(3, 0.1), 1);
        assert_eq!(scaled_map_res(16384, 2.0), 16384);
        assert_eq!(scaled_map_res(512, f64::NAN), 1);
    }

    fn vis(lit: &[f32]) -> Visibility {
        Visibility { width: lit.len() as u32, height: 1, lit: lit.to_vec(), transmittance: None }
    }

    /// One frame pooled is the frame's own metrics and distribution, bit for bit; two frames
    /// pool their pixels (means weighted by counts, percentiles over both frames' errors).
    #[test]
    fn pooled_metrics_of_one_frame_are_the_frame_s_and_of_two_their_pixels() {
        let reference = [0.0, 0.25, 0.5, 1.0, 0.75, 0.1];
        let mask = [true, true, true, true, false, true];
        let a = vis(&[0.0, 0.3, 0.45, 0.9, 0.0, 0.1]);
        let mut one = Pooled::default();
        one.add(&a, &reference, &mask);
        let (m, shares) = one.finish();
        assert_eq!(m, Metrics::compare(&a, &reference, &mask));
        assert_eq!(shares, analysis::metrics::exceedance(&a, &reference, &mask));

        let b = vis(&[0.5, 0.25, 0.5, 1.0, 1.0, 0.6]);
        let mut two = Pooled::default();
        two.add(&a, &reference, &mask);
        two.add(&b, &reference, &mask);
        let (m2, _) = two.finish();
        let (ma, mb) =
            (Metrics::compare(&a, &reference, &mask), Metrics::compare(&b, &reference, &mask));
        assert_eq!(m2.evaluated_pixels, 10);
        let weighted = (ma.mean_abs_error * 5.0 + mb.mean_abs_error * 5.0) / 10.0;
        assert!((m2.mean_abs_error - weighted).abs() < 1e-15);
        assert_eq!(m2.max_abs_error, ma.max_abs_error.max(mb.max_abs_error));
        // Boundary pixels: references 0.25, 0.5 and 0.1 in both frames; errors about 0.05,
        // 0.05 and 1.5e-9 in frame a, 0, 0 and 0.5 in frame b; nearest ranks 3 and 6 of 6.
        assert_eq!(m2.boundary_pixels, 6);
        assert_eq!(m2.boundary_p50_abs_error, Some(f64::from(0.1f32) - 0.1));
        assert_eq!(m2.boundary_p99_abs_error, Some(f64::from(0.6f32) - 0.1));
        let empty = Pooled::default().finish();
        assert_eq!(
            (empty.0.pixel_match, empty.0.boundary_p95_abs_error, empty.1),
            (1.0, None, None)
        );
    }

    #[test]
    fn conditions_pool_the_load_at_both_ends_and_the_worst_shares() {
        let a = Conditions {
            loadavg_before: Some(1.0),
            loadavg_after: Some(1.5),
            others_share: Some(0.1),
            steal_share: None,
            min_share: Some(0.9),
            cores: 2,
        };
        let b = Conditions {
            loadavg_before: Some(2.0),
            loadavg_after: Some(2.5),
            others_share: Some(0.3),
            steal_share: Some(0.01),
            min_share: Some(0.95),
            cores: 2,
        };
        let p = pool_conditions(a, b);
        assert_eq!((p.loadavg_before, p.loadavg_after), (Some(1.0), Some(2.5)));
        assert_eq!(
            (p.others_share, p.steal_share, p.min_share),
            (Some(0.3), Some(0.01), Some(0.9))
        );
    }
}
