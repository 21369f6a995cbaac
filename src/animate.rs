//! `animate`: one method through every frame of an animated scene, each frame measured against
//! the ground truth as `compare` measures a still one, and the frames compared with each
//! other (`analysis::temporal`: flicker the truth does not have).
//!
//! Each frame is the scene posed at that frame (`scenes::Animation::pose`), run and timed as
//! `render --repeat` runs a still frame, its reference read from or stored in the reference
//! cache (so that a second method over the same animation computes no reference), and compared.
//! A map-scale track multiplies the run's `--map-res` (rounded, at least 1), for the methods
//! that have a map; the others note that it is not used. Two frames are held at a time.
//!
//! Writes into `--out`: `frames/visibility-NNNN.exr` (each frame's lit fraction),
//! `frames.csv` (a row per frame: errors, temporal error of the pair ending there, times),
//! `temporal.json` (`reports::animation::AnimationRecord`) and `animation.png` (an animated
//! PNG: the method, the reference and the error side by side).

use super::reference::{self, TruthArgs};
use super::{input, Failure, RenderArgs};
use analysis::compare::Truth;
use analysis::temporal::{FrameInput, Temporal, View};
use instrumentation::Recorder;
use methods::{Frame, MethodOptions, Visibility};
use reports::animation::{mean_of, AnimationRecord, Apng, FrameRecord};

/// `animate`'s arguments.
#[derive(clap::Args)]
pub struct AnimateArgs {
    #[command(flatten)]
    pub render: RenderArgs,
    #[command(flatten)]
    pub truth: TruthArgs,
    /// Frames to sample the scene's animation at, evenly over the time span of its keys, 1 to
    /// 1000; default: the scene's own count (its `[animation] frames`; 1 for a still scene).
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(scenes::MAX_FRAMES)))]
    pub frames: Option<u32>,
    /// How long animation.png shows each frame, milliseconds, 1 to 10000; default 100.
    #[arg(long, value_name = "MS", default_value_t = reports::motion::FRAME_MS,
          allow_negative_numbers = true,
          value_parser = clap::value_parser!(u16).range(1..=10_000))]
    pub frame_ms: u16,
}

/// What is kept of the previous frame for the temporal comparison.
struct Kept {
    camera: scenes::Projector,
    geometry: scenes::Geometry,
    gbuffer: methods::gbuffer::GBuffer,
    truth: Truth,
    result: Visibility,
}

impl Kept {
    fn input(&self) -> FrameInput<'_> {
        let view = View { camera: &self.camera, geometry: &self.geometry, gbuffer: &self.gbuffer };
        FrameInput { view, truth: &self.truth, result: &self.result }
    }
}

/// Runs `animate`.
pub fn animate(a: AnimateArgs) -> Result<(), Failure> {
    let r = &a.render;
    let rate = a.truth.ref_rate.unwrap_or(analysis::registry::DEFAULT_REF_RATE);
    let budget_reference = match a.truth.reference {
        super::ReferenceName::Exact => ("exact", rate),
        super::ReferenceName::Raytrace => ("raytrace", rate),
    };
    let job = super::job(r, Some(budget_reference))?;
    let frames = a.frames.unwrap_or_else(|| job.scene.animation.frames());
    let animation = job
        .scene
        .animation
        .with_frames(frames)
        .map_err(|e| input(anyhow::anyhow!("--frames: {e}")))?;
    let error_scale = super::error_scale(&a.truth)?;
    let chosen = reference::choose(&a.truth, r.pattern())?;
    let method = job.technique.name().to_owned();
    let params = job.technique.params();
    let base_map = params.get("map_res").and_then(serde_json::Value::as_u64).map(|m| m as u32);
    let scaled = (0..frames).any(|i| animation.map_scale(i) != 1.0);
    if scaled && base_map.is_none() {
        eprintln!("note: {method} has no shadow map; the scene's map scale is not used");
    }
    let tx = super::out_dir(r, &job, "-animated")?;
    let mut cache = reference::open_cache(&a.truth.cache)?;
    let staging = tx.staging().to_owned();
    let frames_dir = staging.join("frames");
    std::fs::create_dir_all(&frames_dir)
        .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", frames_dir.display()))?;

    let options = r.options();
    let mut temporal = Temporal::new();
    let mut prev: Option<Kept> = None;
    let mut apng: Option<Apng> = None;
    let mut per_frame = Vec::with_capacity(frames as usize);
    let mut cpu_all = true;
    for i in 0..frames {
        let map_res = base_map.map(|m| reports::motion::scaled_map_res(m, animation.map_scale(i)));
        let mut o: MethodOptions = options.clone();
        if let Some(m) = map_res {
            o.map_res = Some(m);
        }
        let (technique, reference_run) = super::techniques(&method, &o)?;
        let frame_job = super::Job {
            scene: animation.pose(&job.scene, i),
            technique,
            reference: reference_run,
            width: job.width,
            height: job.height,
        };
        let (frame, ran, _) = super::run_repeated(&frame_job, r.repeat)?;
        let evaluated = reference::evaluate(
            &chosen,
            &frame_job.scene,
            &frame,
            cache.as_mut(),
            &ran.visibility,
        )?;
        let (reference_ms, reference_cached) = (evaluated.computed_ms, evaluated.read_ms.is_some());
        let mut rec = Recorder::default();
        let mut truth = Truth::new(&frame, evaluated.image, &mut rec);
        if let Some(one) = evaluated.one_ray {
            truth = truth.with_one_ray(one);
        }
        let comparison = truth.compare(&frame, &ran.visibility).map_err(input)?;
        let v = &ran.visibility;
        let pair = prev.as_ref().map(|p| {
            let cur = FrameInput::of(&frame, &truth, v);
            temporal.add(&p.input(), &cur)
        });
        let pair_mean = temporal.last_mean();

        reports::write_visibility_exr(&frames_dir.join(format!("visibility-{i:04}.exr")), v)?;
        let panels = [
            reports::output::shade(&frame, v),
            reports::output::shade(&frame, &truth.reference.to_visibility()),
            analysis::error_map::error_map(v, &truth.reference.lit, &truth.headline, error_scale)?,
        ];
        let image = reports::animation::side_by_side(&[&panels[0], &panels[1], &panels[2]]);
        if apng.is_none() {
            let path = staging.join("animation.png");
            apng = Some(Apng::create(&path, image.width(), image.height(), frames, a.frame_ms)?);
        }
        if let Some(apng) = apng.as_mut() {
            apng.push(&image)?;
        }
        cpu_all &= ran.record.cpu_ms.is_some();
        per_frame.push(FrameRecord {
            frame: i,
            time: animation.time(i),
            map_res,
            mean_abs_error: comparison.mean_abs_error,
            boundary_mean_abs_error: comparison.boundary_mean_abs_error,
            boundary_p95_abs_error: comparison.boundary_p95_abs_error,
            temporal_error: pair.and(pair_mean),
            temporal_pairs: pair.unwrap_or(0),
            method_ms: ran.record.total_ms,
            method_cpu_ms: ran.record.cpu_ms,
            reference_ms: reference_ms + rec.stages.total_ms(),
            reference_cached,
        });
        for w in &ran.record.warnings {
            eprintln!("warning: frame {i}: {w}");
        }
        let Frame { camera, geometry, gbuffer, .. } = frame;
        prev = Some(Kept { camera, geometry, gbuffer, truth, result: ran.visibility });
    }
    if let Some(apng) = apng {
        apng.finish()?;
    }
    let n = f64::from(frames);
    let record = AnimationRecord {
        scene: job.scene.name.clone(),
        method,
        params,
        width: job.width,
        height: job.height,
        frames,
        reference: chosen.reference.name().to_owned(),
        ref_rate: chosen.ref_rate,
        mean_abs_error: mean_of(per_frame.iter().map(|f| f.mean_abs_error)),
        boundary_mean_abs_error: mean_of(per_frame.iter().map(|f| f.boundary_mean_abs_error)),
        method_ms: per_frame.iter().map(|f| f.method_ms).sum::<f64>() / n,
        method_cpu_ms: cpu_all
            .then(|| per_frame.iter().filter_map(|f| f.method_cpu_ms).sum::<f64>() / n),
        temporal: temporal.finish(),
        per_frame,
    };
    record.write_frames_csv(&staging.join("frames.csv"))?;
    record.write_json(&staging.join("temporal.json"))?;
    let out = super::commit_out(tx, "--out")?;
    if r.json {
        println!("{}", serde_json::to_string_pretty(&record)?);
    }
    print_summary(&record, cache.is_some());
    eprintln!("wrote {}", out.display());
    Ok(())
}

/// Prints the run's summary: errors, temporal errors and time.
fn print_summary(r: &AnimationRecord, cached: bool) {
    let f = |v: Option<f64>| v.map_or("-".to_owned(), |v| format!("{v:.5}"));
    let t = &r.temporal;
    println!(
        "{} on {} at {}x{}, {} frames, against {}{}",
        r.method,
        r.scene,
        r.width,
        r.height,
        r.frames,
        r.reference,
        if cached { " (reference cache)" } else { "" }
    );
    println!("  mean abs error (mean over frames): {}", f(r.mean_abs_error));
    println!("  boundary mean abs error (mean over frames): {}", f(r.boundary_mean_abs_error));
    println!(
        "  temporal error: mean {}, p95 {} over {} pixel pairs{}",
        f(t.mean),
        f(t.p95),
        t.pixel_pairs,
        if t.reprojected { " (reprojected)" } else { "" }
    );
    println!(
        "  boundary temporal error: mean {}, p95 {} over {} pixel pairs",
        f(t.boundary_mean),
        f(t.boundary_p95),
        t.boundary_pairs
    );
    let cpu = r.method_cpu_ms.map_or(String::new(), |c| format!(", {c:.1} ms CPU"));
    println!("  time: method {:.1} ms wall{cpu} per frame (mean)", r.method_ms);
}
