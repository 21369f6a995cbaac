//! Frames out, results in: `frame` writes what another renderer needs to make the same frame
//! (`reports::frame_export`), and `compare --visibility` scores that renderer's lit
//! fraction against the same reference, pixel classes and metrics as any method
//! (`reports::external` reads it).

use super::{begin_out, commit_out, input, CompareArgs, Failure, RenderArgs, MAX_FRAME_SIDE};
use instrumentation::Recorder;
use methods::Frame;
use reports::publish::Kind;
use std::path::{Path, PathBuf};

/// `frame`'s arguments.
#[derive(clap::Args)]
pub struct FrameArgs {
    /// Scene: a built-in name (see `shadowbench scenes`), a scene file (.toml), or a mesh
    /// file (.obj, .off, .ply) placed over a ground plane with a default light and camera.
    #[arg(long)]
    scene: String,
    /// Image width in pixels, 1 to 16384; default: the scene's.
    #[arg(long, value_name = "W", allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_FRAME_SIDE)))]
    width: Option<u32>,
    /// Image height in pixels, 1 to 16384; default: the scene's.
    #[arg(long, value_name = "H", allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_FRAME_SIDE)))]
    height: Option<u32>,
    /// Output folder (the same rules as `render --out`: empty, or holding an earlier frame,
    /// which the new one replaces once it is whole).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

/// `compare`'s arguments for an outside result.
#[derive(clap::Args)]
pub struct OutsideArgs {
    /// Score an outside renderer's result instead of running a method: an EXR of the
    /// frame's size with one f16 or f32 channel named Y, L, lit or visibility (a workbench
    /// visibility.exr as it is), the lit fraction per pixel in [0, 1], row 0 at the top (see
    /// `shadowbench frame`). Values outside [0, 1] or NaN are refused. Replaces --method.
    #[arg(long = "visibility", value_name = "FILE.exr", conflicts_with = "method")]
    pub visibility_file: Option<PathBuf>,
    /// With --visibility: the result's name in metrics.json and the output folder's
    /// name; default `external`.
    #[arg(long, value_name = "NAME", requires = "visibility_file")]
    name: Option<String>,
    /// With --visibility: the time the outside renderer took, milliseconds, recorded as
    /// metrics.json's method_ms (null when not given).
    #[arg(long, value_name = "T", allow_negative_numbers = true, requires = "visibility_file")]
    time_ms: Option<f64>,
}

/// Refuses `--name` and `--time-ms` without `--visibility` (clap does not require it
/// once `--method`, which conflicts with it, is given).
pub fn refuse_outside_flags(o: &OutsideArgs) -> Result<(), Failure> {
    for (flag, given) in [("--name", o.name.is_some()), ("--time-ms", o.time_ms.is_some())] {
        if given {
            return Err(input(anyhow::anyhow!(
                "{flag} names an outside result: it needs --visibility, not --method"
            )));
        }
    }
    Ok(())
}

/// A scene resolved at a checked frame size.
struct Sized {
    scene: scenes::Scene,
    width: u32,
    height: u32,
}

/// The scene `name` at `width x height` (default: the scene's resolution), checked as `render`
/// checks it, with the memory budget of a single-buffer result compared against
/// `reference`.
fn sized_scene(
    name: &str,
    width: Option<u32>,
    height: Option<u32>,
    max_memory: Option<u64>,
    reference: Option<(&str, u32)>,
) -> Result<Sized, Failure> {
    let described = super::describe_scene(name)?;
    let [scene_width, scene_height] = described.resolution();
    let width = width.unwrap_or(scene_width);
    let height = height.unwrap_or(scene_height);
    reports::suite::check_frame(width, height, 1)
        .map_err(|m| input(anyhow::anyhow!("--width and --height: {m}")))?;
    let budget = |triangles: u64| -> Result<(), Failure> {
        let Some(limit) = analysis::budget::Limit::new(max_memory) else { return Ok(()) };
        // An outside result is one buffer of the frame: `sm`'s cost with a one-texel map.
        let work = analysis::budget::Work {
            triangles,
            width,
            height,
            method: "sm",
            rate: 1,
            map_res: 1,
            reference,
        };
        let what = format!("an outside result on {name} at {width}x{height}");
        analysis::budget::check(&work, &limit, &what).map(|_| ()).map_err(input)
    };
    budget(described.triangles().map_err(super::scene_error)?)?;
    let scene = described.resolve().map_err(super::scene_error)?;
    Ok(Sized { scene, width, height })
}

/// `frame --scene S --out DIR`: frame.json, gbuffer.exr and samples.json.
pub fn frame(a: FrameArgs) -> Result<(), Failure> {
    let s = sized_scene(&a.scene, a.width, a.height, None, None)?;
    let tx = begin_out(&a.out, "--out", Kind::Frame)?;
    let frame = Frame::new(&s.scene, s.width, s.height, &mut Recorder::default());
    reports::frame_export::write_frame(tx.staging(), &frame)?;
    let glb = tx.staging().join("scene.glb");
    scenes::write_glb(&s.scene, &glb)
        .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", glb.display()))?;
    let out = commit_out(tx, "--out")?;
    eprintln!(
        "frame of {} at {}x{}: wrote frame.json, gbuffer.exr, samples.json and scene.glb to {}",
        s.scene.name,
        s.width,
        s.height,
        out.display()
    );
    Ok(())
}

/// Notes for the flags of `a` that only a method uses (every method parameter but the
/// pattern, which the reference's ray-traced pixels take).
fn note_method_flags(a: &RenderArgs) {
    let params = a.params.iter().filter(|(p, _)| p.key != "pattern").map(|(p, _)| (p.flag, true));
    let others = [("--device", a.device != super::DeviceArg::Cpu), ("--repeat", a.repeat != 1)];
    for (flag, given) in params.chain(others) {
        if given {
            eprintln!("note: an outside result does not use {flag}; ignored");
        }
    }
}

/// `compare --visibility FILE`: the outside result scored like a method's run.
pub fn compare(c: &CompareArgs, file: &Path) -> Result<(), Failure> {
    let a = &c.render;
    let o = &c.outside;
    let name = o.name.clone().unwrap_or_else(|| "external".to_owned());
    let plain = |ch: char| ch.is_ascii_alphanumeric() || "-_.".contains(ch);
    if name.is_empty() || !name.chars().all(plain) || name.starts_with('.') {
        return Err(input(anyhow::anyhow!(
            "--name `{name}`: use letters, digits, `-`, `_` and `.` (not first)"
        )));
    }
    if let Some(t) = o.time_ms {
        if !(t.is_finite() && t >= 0.0) {
            return Err(input(anyhow::anyhow!(
                "--time-ms: {t} is not a time (a finite number >= 0)"
            )));
        }
    }
    note_method_flags(a);
    let chosen = super::reference::choose(&c.truth, a.pattern())?;
    let rate = chosen.ref_rate.unwrap_or(analysis::registry::DEFAULT_REF_RATE);
    let s = sized_scene(
        &a.scene,
        a.width,
        a.height,
        a.max_memory,
        Some((chosen.reference.name(), rate)),
    )?;
    let error_scale = super::error_scale(&c.truth)?;
    let visibility = reports::external::read_visibility(file, s.width, s.height)
        .map_err(|e| input(anyhow::anyhow!("--visibility {e}")))?;
    let out = a.out.clone().unwrap_or_else(|| {
        let folder = format!("{}-{name}-vs-{}", s.scene.name, chosen.reference.name());
        Path::new("shadowbench-out").join(folder)
    });
    let flag = if a.out.is_some() { "--out" } else { "--out (default)" };
    let tx = begin_out(&out, flag, Kind::Run)?;
    let mut cache = super::reference::open_cache(&c.truth.cache)?;
    let frame = Frame::new(&s.scene, s.width, s.height, &mut Recorder::default());
    let evaluated =
        super::reference::evaluate(&chosen, &s.scene, &frame, cache.as_mut(), &visibility)?;
    let result = super::reference::Compared {
        method: name,
        params: serde_json::Map::new(),
        method_ms: o.time_ms,
        external: true,
    };
    reports::write_shadow_png(&tx.staging().join("shadow.png"), &frame, &visibility)?;
    let metrics = super::reference::score(
        &frame,
        &visibility,
        &chosen,
        evaluated,
        result,
        error_scale,
        tx.staging(),
    )?;
    let out = commit_out(tx, flag)?;
    let time = o.time_ms.map_or("not given".to_owned(), |t| format!("{t} ms (--time-ms)"));
    super::reference::report(&metrics, a.json, &time, cache.as_ref())?;
    eprintln!("wrote {}", out.display());
    Ok(())
}
