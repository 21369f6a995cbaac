//! `shadowbench`: the command line of the shadow-map antialiasing workbench.
//!
//! Argument parsing and wiring only; the algorithms live in the workspace's crates. Exit
//! codes: 0 success, 2 bad input (one message naming the file, line, key, flag or environment
//! variable), 1 internal failure.
//!
//! Every input is checked before any computation, in this order: the flags and the scene
//! ([`job`]: method options, frame size), the GPU environment for `--device gpu` (the adapter
//! is opened, so `SHADOWBENCH_GPU_*` errors come first), then the output folder
//! ([`begin_out`]: opened as a transaction of `reports::publish`, locked, its contents checked;
//! the outputs are written into its staging folder and published whole at the end). A method
//! error is bad input, except a GPU device failure, which is internal ([`method_failure`]).

use analysis::{pixel_class::PixelClass, Reference};
use anyhow::Context;
use clap::builder::TypedValueParser;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand, ValueEnum};
use instrumentation::measure::{measure, Protocol};
use instrumentation::stats::Summary;
use instrumentation::{Recorder, RunRecord};
#[cfg(feature = "gpu")]
use methods::gpu::GpuError;
use methods::{
    params::{self, Param},
    pattern::PatternKind,
    registry::Device,
    Frame, MethodError, MethodOptions, ShadowMethod, Visibility,
};
use reports::publish::{Kind, PublishError, Transaction};
use reports::suite::{check_frame, MAX_FRAME_SIDE};
use reports::write::summary_text;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

mod animate;
mod external;
mod reference;

/// Research workbench for shadow-map antialiasing: runs the published techniques on the same
/// scenes, counts their work, times every stage and writes what they compute.
#[derive(Parser)]
#[command(name = "shadowbench", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the built-in scenes: name, triangle count, effects, default resolution.
    Scenes {
        /// Print the list as JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Print the scene file (TOML) of one built-in scene, to copy and edit.
        #[arg(long, value_name = "NAME", conflicts_with = "json")]
        toml: Option<String>,
    },
    /// Run one method (or a reference: `exact`, `raytrace`) on one scene; write
    /// visibility.exr, shadow.png and run.json (`exact` also writes its pixel classes:
    /// classes.png and class_ids.png).
    Render(RenderArgs),
    /// Run one method and a reference on the same frame; print the error metrics (the
    /// shadow-only headline over planar and surface pixels, then per pixel class) and write
    /// error.png (the absolute error in false colour with its colour bar, see
    /// --error-scale), error_boundary.png, metrics.json and the method's visibility.exr,
    /// shadow.png and run.json.
    Compare(CompareArgs),
    /// Write what another renderer needs to make the same frame into --out: frame.json (the
    /// camera and light with their matrices, the shadow-map light frustum, the conventions),
    /// gbuffer.exr (position, normal, depth, triangle id per pixel centre) and samples.json
    /// (the sub-sample offsets of every rate of the shared patterns). Score its result with
    /// `compare --visibility`.
    Frame(external::FrameArgs),
    /// Run one method through every frame of an animated scene (a scene file's [animation],
    /// or a built-in such as bumpy-orbit; see `shadowbench scenes`), each frame compared with
    /// the reference as `compare` does, and the frames with each other (temporal error: the
    /// flicker the truth does not have); write frames/visibility-NNNN.exr, frames.csv,
    /// temporal.json and animation.png (the method, the reference and the error, animated).
    Animate(animate::AnimateArgs),
    /// Run a suite (scenes x methods x parameters) under the timing protocol and write
    /// index.html, report.md, runs.csv, runs.json, a page per run and every visibility buffer
    /// as EXR into --out; or plan it (--plan), run one shard of it (--shard K/N), or merge
    /// shards (`report merge`).
    Report(ReportArgs),
}

#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
struct ReportArgs {
    /// Merge shards instead of running a suite.
    #[command(subcommand)]
    action: Option<ReportAction>,
    /// A built-in suite (`quick`: every method on small frames, a few minutes; `papers`: the
    /// papers' frame and map sizes; `full`: every scene and parameter; `temporal`: the
    /// animated scenes in motion) or a suite file (.toml; copy one from reports/suites/ and
    /// edit it).
    #[arg(long, default_value = "quick", value_name = "SUITE")]
    suite: String,
    /// Output folder; default `shadowbench-out/report-SUITE`. It must be empty or hold an
    /// earlier report, which the new one replaces once it is whole; a folder holding other
    /// files, or being written by another command, is refused.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// An earlier report's folder: every run present in both is compared (error change, time
    /// ratio on the report's clock, CPU time by default, with its interval; wall-time ratio
    /// beside where neither run was contended) and regressions are flagged at the top of
    /// report.md and index.html, and in baseline.md. Read before anything is computed.
    #[arg(long, value_name = "DIR")]
    baseline: Option<PathBuf>,
    /// With --baseline: the relative slow-down the whole interval of a run's time ratio must
    /// exceed for the run to be flagged slower; default 0.2 (CPU times of unchanged code, one
    /// report quiet and one with a core busy, stay within it).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    baseline_tolerance: Option<f64>,
    /// With --baseline: milliseconds by which a run's time interval must lie above the
    /// baseline's for the run to be flagged slower (or below, faster); default 1 (0 compares
    /// ratios alone).
    #[arg(long, value_name = "MS", allow_negative_numbers = true)]
    baseline_min_ms: Option<f64>,
    /// Print the suite's work list and stop: one JSON line per item (scene, frame, reference,
    /// runs, estimated cost), in the order a report runs them, then a summary on standard
    /// error (with --shard K/N, of that shard's items).
    #[arg(long)]
    plan: bool,
    /// Run only share K of N of the work (K from 0, as Slurm's array task id: `--shard
    /// $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`), into a shard folder for `report
    /// merge` (runs.json and the runs' images and records; the merge writes the pages and
    /// charts). Shards are balanced by the items' estimated cost; the same suite and N always
    /// give the same shares.
    #[arg(long, value_name = "K/N")]
    shard: Option<reports::plan::Shard>,
    /// Reference cache folder, shared by shards and reports (content-addressed, verified on
    /// read, safe for several writers); default `cache/` in the output folder.
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// The most memory one run of the suite may use with its reference, such as 8G (units of
    /// 1024 bytes); default: the memory available now. Every item's heaviest run is estimated
    /// before anything runs, and a suite with one above the limit is refused, naming it.
    #[arg(long, value_name = "SIZE", value_parser = size_arg)]
    max_memory: Option<u64>,
    /// The clock of the report's cost axis (charts, Pareto fronts, budgets, --baseline):
    /// `cpu`, the CPU time of the process's threads, which other work on the machine moves
    /// little, or `wall`, the wall-clock time a user waits; the other is given beside. Default:
    /// the suite's `clock` (cpu in the built-in suites).
    #[arg(long, value_enum)]
    clock: Option<ClockArg>,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ClockArg {
    /// CPU time of the process's threads.
    Cpu,
    /// Wall-clock time.
    Wall,
}

impl From<ClockArg> for instrumentation::measure::Clock {
    fn from(c: ClockArg) -> Self {
        match c {
            ClockArg::Cpu => Self::Cpu,
            ClockArg::Wall => Self::Wall,
        }
    }
}

#[derive(clap::Subcommand)]
enum ReportAction {
    /// Merge the shard folders of one suite (`report --shard K/N`, every K of one N) into
    /// the report an unsharded run writes; refuses, naming them, when shards are missing or
    /// did not finish.
    Merge(MergeArgs),
}

#[derive(clap::Args)]
struct MergeArgs {
    /// The shards' folders.
    #[arg(required = true, value_name = "DIR")]
    dirs: Vec<PathBuf>,
    /// Output folder (the same rules as `report --out`).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Merge shards written by different versions or commits of shadowbench (refused
    /// otherwise); the merged report's provenance lists each shard's build.
    #[arg(long)]
    allow_mixed: bool,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum DeviceArg {
    /// The CPU methods.
    Cpu,
    /// The GPU kernels (wgpu; a real GPU first, Mesa's llvmpipe when there is none;
    /// SHADOWBENCH_GPU_BACKEND=vulkan|gl|metal|dx12 restricts the backends,
    /// SHADOWBENCH_GPU_ADAPTER=TEXT picks an adapter by name).
    Gpu,
}

impl From<DeviceArg> for Device {
    fn from(d: DeviceArg) -> Self {
        match d {
            DeviceArg::Cpu => Device::Cpu,
            DeviceArg::Gpu => Device::Gpu,
        }
    }
}

/// The ground truth of a comparison (`--reference`).
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ReferenceName {
    /// Exact lit area per pixel on every visible surface (planar and surface pixels); edge
    /// pixels as --edge-reference says.
    Exact,
    /// Ray-traced supersampling at --ref-rate sub-samples per pixel.
    Raytrace,
}

/// The reference of `exact`'s edge pixels (`--edge-reference`).
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum EdgeReference {
    /// Ray traced at --ref-rate sub-samples per pixel; their error is reported under
    /// `classes.edge`.
    Raytrace,
    /// Left out: not evaluated, `classes.edge` has no pixels (--ref-rate is not used).
    None,
}

#[derive(clap::Args)]
struct CompareArgs {
    #[command(flatten)]
    render: RenderArgs,
    #[command(flatten)]
    truth: reference::TruthArgs,
    #[command(flatten)]
    outside: external::OutsideArgs,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Scene: a built-in name (see `shadowbench scenes`), a scene file (.toml), or a mesh
    /// file (.obj, .off, .ply) placed over a ground plane with a default light and camera.
    #[arg(long)]
    scene: String,
    /// Method: a name of the registry's table or a reference (the list, with each method's
    /// parameters, is in `--help`). Required, except by `compare --visibility`.
    #[arg(long)]
    method: Option<String>,
    /// Where the method runs: `cpu` (default) or `gpu` (kernels for sm, the pcf-* methods,
    /// afsm, pan09, and spsm's classification and depth stages; the run record names the
    /// adapter and how stage times were taken).
    #[arg(long, value_enum, default_value_t = DeviceArg::Cpu)]
    device: DeviceArg,
    /// The most memory the run may use, such as 8G or 512M (units of 1024 bytes); default:
    /// the memory available now. The run's need is estimated from the scene's triangles, the
    /// frame, the method and the reference before anything is built, and a run that would
    /// need more is refused, naming the estimate.
    #[arg(long, value_name = "SIZE", value_parser = size_arg)]
    max_memory: Option<u64>,
    /// Image width in pixels, 1 to 16384; default: the scene's.
    #[arg(long, value_name = "W", allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_FRAME_SIDE)))]
    width: Option<u32>,
    /// Image height in pixels, 1 to 16384; default: the scene's.
    #[arg(long, value_name = "H", allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_FRAME_SIDE)))]
    height: Option<u32>,
    /// Timed runs of the method (1 to 1000): with N > 1 it runs N + 1 times, G-buffer
    /// included, the first as an untimed warm-up; run.json (and metrics.json's method_ms) then
    /// holds the run of median CPU time (the lower middle one for even N) with every run's wall
    /// and CPU times in its `timing`, and the printed line the medians of both clocks with
    /// their 95 % intervals (from 6 runs on) and ranges; a run another process starved of CPU
    /// is run again once and counted as contended. Default 1 (one cold run).
    #[arg(long, value_name = "N", default_value_t = 1, allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=1000))]
    repeat: u32,
    /// Output folder; default `shadowbench-out/SCENE-METHOD`.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Also print the record written to the output folder to standard output (run.json;
    /// metrics.json for `compare`).
    #[arg(long)]
    json: bool,
    /// The method parameters given, by the flags the registry's table declares
    /// ([`with_params`]).
    #[arg(skip)]
    params: Vec<(&'static Param, params::Value)>,
}

impl RenderArgs {
    /// The method options given: the parameters' flags and `--device`.
    fn options(&self) -> MethodOptions {
        let mut options = MethodOptions { device: self.device.into(), ..Default::default() };
        for (p, v) in &self.params {
            options.set(p, *v);
        }
        options
    }

    /// The sub-sample pattern given (`--pattern`), default grid.
    fn pattern(&self) -> PatternKind {
        self.options().pattern.unwrap_or_default()
    }
}

/// The method flags: one per parameter some method declares (`methods::params`), with its
/// help and the methods that use it, and `--method`'s help listing every method with its
/// parameters; added to `render` and `compare`.
fn with_params(cmd: clap::Command) -> clap::Command {
    let mut lines = vec!["Method (or a reference run as a method):".to_owned()];
    let methods = methods::registry::METHODS.iter().map(|m| (m.name, m.description, m.params));
    let references = analysis::registry::REFERENCES
        .iter()
        .map(|(n, d)| (*n, *d, analysis::registry::REFERENCE_PARAMS));
    for (name, description, params) in methods.chain(references) {
        let flags: Vec<&str> = params.iter().map(|p| p.flag).collect();
        let flags = if flags.is_empty() { "no parameters".into() } else { flags.join(", ") };
        lines.push(format!("  {name}: {description} [{flags}]"));
    }
    let mut cmd = cmd.mut_arg("method", |a| a.long_help(lines.join("\n")));
    for p in methods::registry::all_params() {
        let mut users: Vec<&str> = methods::registry::METHODS
            .iter()
            .filter(|m| m.params.iter().any(|q| q.key == p.key))
            .map(|m| m.name)
            .collect();
        if analysis::registry::REFERENCE_PARAMS.iter().any(|q| q.key == p.key) {
            users.extend(analysis::registry::REFERENCES.iter().map(|(n, _)| *n));
        }
        let arg = clap::Arg::new(p.key)
            .long(&p.flag[2..])
            .value_name(p.value_name)
            .help(format!("{} Used by: {}.", p.help, users.join(", ")))
            .allow_negative_numbers(true);
        let arg = match p.kind {
            params::Kind::Choice(names) => arg.value_parser(
                clap::builder::PossibleValuesParser::new(
                    names.iter().map(|(n, h)| clap::builder::PossibleValue::new(*n).help(*h)),
                )
                .try_map(move |text: String| p.parse(&text)),
            ),
            _ => arg.value_parser(move |text: &str| p.parse(text)),
        };
        cmd = cmd.arg(arg);
    }
    cmd
}

/// The command line, with the method flags of the registry's table ([`with_params`]).
fn command() -> clap::Command {
    Cli::command()
        .mut_subcommand("render", with_params)
        .mut_subcommand("compare", with_params)
        .mut_subcommand("animate", with_params)
}

/// The method parameters given on the command line `m` (of `render` or `compare`).
fn given_params(m: &clap::ArgMatches) -> Vec<(&'static Param, params::Value)> {
    methods::registry::all_params()
        .into_iter()
        .filter_map(|p| m.get_one::<params::Value>(p.key).map(|v| (p, *v)))
        .collect()
}

/// A failure and the exit code it maps to.
enum Failure {
    /// Bad input: exit code 2.
    Input(anyhow::Error),
    /// Internal failure: exit code 1.
    Internal(anyhow::Error),
}

impl<E: Into<anyhow::Error>> From<E> for Failure {
    fn from(e: E) -> Self {
        Failure::Internal(e.into())
    }
}

fn input(e: impl Into<anyhow::Error>) -> Failure {
    Failure::Input(e.into())
}

/// A GPU error: the device failing is internal; no adapter, an adapter without what the
/// kernels need, a bad `SHADOWBENCH_GPU_*` variable (the environment) or an input beyond the
/// adapter's limits is bad input.
#[cfg(feature = "gpu")]
fn gpu_failure(e: GpuError) -> Failure {
    match e {
        GpuError::Device(_) => Failure::Internal(e.into()),
        _ => input(e),
    }
}

/// A method's error: bad input (an option, a scene it does not apply to), except GPU device
/// failures, which are internal.
fn method_failure(e: MethodError) -> Failure {
    match e {
        #[cfg(feature = "gpu")]
        MethodError::Gpu(g) => gpu_failure(g),
        _ => input(e),
    }
}

/// Opens the output folder `out` as a transaction for an output of `kind`, after every other
/// input has been checked and before any computation: a folder that cannot be used (a file or
/// a dangling link in the way, another command writing it, files no command of ours wrote, or
/// another kind of output) is bad input naming `flag` and the path.
fn begin_out(out: &Path, flag: &str, kind: Kind) -> Result<Transaction, Failure> {
    Transaction::begin(out, kind)
        .map_err(|e| publish_failure(e, &format!("{flag} {}", out.display())))
}

/// Publishes the transaction's staged output (`reports::publish`); a failure names `flag` and
/// the folder. Returns the folder.
fn commit_out(tx: Transaction, flag: &str) -> Result<PathBuf, Failure> {
    let out = tx.dir().to_owned();
    tx.commit().map_err(|e| publish_failure(e, &format!("{flag} {}", out.display())))?;
    Ok(out)
}

/// A failure of an output folder's transaction, named by `what` (the flag and the path).
fn publish_failure(e: PublishError, what: &str) -> Failure {
    let input_error = e.is_input();
    let e = anyhow::anyhow!("{what}: {e}");
    if input_error {
        Failure::Input(e)
    } else {
        Failure::Internal(e)
    }
}

/// Checks, without creating anything, that `path` can be a folder: it is one, or it does not
/// exist and its nearest existing ancestor is a folder. A file in the way is bad input naming
/// `flag`.
fn check_folder_path(path: &Path, flag: &str) -> Result<(), Failure> {
    let blocked = path.ancestors().find(|a| a.exists() && !a.is_dir());
    match blocked {
        Some(file) => Err(input(anyhow::anyhow!(
            "{flag} {}: {} is a file, not a folder",
            path.display(),
            file.display()
        ))),
        None => Ok(()),
    }
}

/// Whether folders `a` and `b` are the same or one holds the other, by their absolute paths
/// with symbolic links resolved (as far as they exist).
fn overlaps(a: &Path, b: &Path) -> bool {
    /// `p` resolved: itself where it exists, else its parent's resolution and its name.
    fn real(p: &Path) -> PathBuf {
        if let Ok(r) = p.canonicalize() {
            return r;
        }
        match (p.parent(), p.file_name()) {
            (Some(parent), Some(name)) if parent.as_os_str().is_empty() => {
                real(Path::new(".")).join(name)
            }
            (Some(parent), Some(name)) => real(parent).join(name),
            _ => p.to_path_buf(),
        }
    }
    let (a, b) = (real(a), real(b));
    a.starts_with(&b) || b.starts_with(&a)
}

fn scenes(json: bool, toml: Option<String>) -> Result<(), Failure> {
    if let Some(name) = toml {
        let desc = scenes::registry::builtin(&name).ok_or_else(|| {
            input(anyhow::anyhow!(
                "--toml: unknown built-in scene `{name}`; known: {}",
                scenes::BUILTINS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
            ))
        })?;
        print!("{}", desc.to_toml());
        return Ok(());
    }
    let mut rows = Vec::new();
    for (name, description) in scenes::BUILTINS {
        let row = match scenes::registry::load_builtin(name) {
            Some(Ok(s)) => serde_json::json!({
                "name": name,
                "description": description,
                "available": true,
                "triangles": s.triangle_count(),
                "effects": s.effects().names(),
                "resolution": [s.width, s.height],
            }),
            Some(Err(e)) => serde_json::json!({
                "name": name,
                "description": description,
                "available": false,
                "triangles": null,
                "effects": [],
                "missing": e.to_string(),
            }),
            None => continue,
        };
        rows.push(row);
    }
    if json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    } else {
        println!(
            "{:<14} {:>10}  {:<11} {:<44} description",
            "scene", "triangles", "resolution", "effects"
        );
        for r in &rows {
            let tris = r["triangles"].as_u64().map_or("missing".to_string(), |t| t.to_string());
            let res = r["resolution"]
                .as_array()
                .map_or(String::from("-"), |a| format!("{}x{}", a[0], a[1]));
            let effects: Vec<&str> =
                r["effects"].as_array().into_iter().flatten().filter_map(|e| e.as_str()).collect();
            println!(
                "{:<14} {:>10}  {:<11} {:<44} {}",
                r["name"].as_str().unwrap_or_default(),
                tris,
                res,
                effects.join(","),
                r["description"].as_str().unwrap_or_default()
            );
        }
    }
    Ok(())
}

/// A scene, a technique and the frame size, checked.
struct Job {
    scene: scenes::Scene,
    technique: Box<dyn ShadowMethod>,
    /// The technique when it is a reference (`exact`, `raytrace`), run as a reference so that
    /// its pixel classes come with its values.
    reference: Option<Box<dyn Reference>>,
    width: u32,
    height: u32,
}

/// `--max-memory`'s value.
fn size_arg(text: &str) -> Result<u64, String> {
    analysis::budget::parse_size(text).map_err(|e| e.to_string())
}

/// Refuses a run whose estimated memory ([`analysis::budget`]) exceeds `--max-memory` or what
/// the machine has available.
fn check_budget(
    a: &RenderArgs,
    method: &str,
    triangles: u64,
    (width, height): (u32, u32),
    options: &MethodOptions,
    params: &serde_json::Map<String, serde_json::Value>,
    reference: Option<(&str, u32)>,
) -> Result<(), Failure> {
    let Some(limit) = analysis::budget::Limit::new(a.max_memory) else { return Ok(()) };
    let int = |key: &str, default: u32| {
        params.get(key).and_then(serde_json::Value::as_u64).map_or(default, |v| v as u32)
    };
    let work = analysis::budget::Work {
        triangles,
        width,
        height,
        method,
        rate: methods::registry::stored_samples(method, options).max(int("rate", 1)),
        map_res: int("map_res", 1024),
        reference,
    };
    let what = format!("{method} on {} at {width}x{height}", a.scene);
    analysis::budget::check(&work, &limit, &what).map(|_| ()).map_err(input)
}

/// A `--scene` error: bad input naming the flag.
fn scene_error(e: scenes::SceneError) -> Failure {
    input(anyhow::anyhow!("--scene: {e}"))
}

/// The scene `--scene` names, described (not built), with the notes of what it leaves out
/// (a glTF scene's textures, extra lights, ...) printed.
fn describe_scene(name: &str) -> Result<scenes::Described, Failure> {
    let described = scenes::describe(name).map_err(scene_error)?;
    for note in described.notes() {
        eprintln!("note: --scene {name}: {note}");
    }
    Ok(described)
}

/// A technique, and the reference it wraps when it is one.
type Techniques = (Box<dyn ShadowMethod>, Option<Box<dyn Reference>>);

/// The technique `method` with `options`, and the reference it wraps when it is one (with
/// `registry::technique`'s rate and pattern), so that its pixel classes come with its values.
fn techniques(method: &str, options: &MethodOptions) -> Result<Techniques, Failure> {
    let technique = analysis::registry::technique(method, options).map_err(method_failure)?;
    let reference = if analysis::registry::REFERENCES.iter().any(|(n, _)| *n == method) {
        let rate = options.rate.unwrap_or(1);
        let pattern = options.pattern.unwrap_or_default();
        Some(analysis::registry::reference(method, rate, pattern).map_err(input)?)
    } else {
        None
    };
    Ok((technique, reference))
}

fn job(a: &RenderArgs, compared_with: Option<(&str, u32)>) -> Result<Job, Failure> {
    let method = a.method.as_deref().ok_or_else(|| {
        input(anyhow::anyhow!("--method is required (by compare, unless --visibility is given)"))
    })?;
    let described = describe_scene(&a.scene)?;
    let options = a.options();
    let (technique, reference) = techniques(method, &options)?;
    let params = technique.params();
    let declared = analysis::registry::params_of(method).unwrap_or_default();
    for (p, _) in &a.params {
        if !declared.iter().any(|q| q.key == p.key) {
            eprintln!("note: {} does not use {}; ignored", technique.name(), p.flag);
        }
    }
    let [scene_width, scene_height] = described.resolution();
    let width = a.width.unwrap_or(scene_width);
    let height = a.height.unwrap_or(scene_height);
    for (flag, v) in [("--width", width), ("--height", height)] {
        if !(1..=MAX_FRAME_SIDE).contains(&v) {
            return Err(input(anyhow::anyhow!(
                "{flag}: must be in 1..={MAX_FRAME_SIDE}, got {v} (the scene's resolution when \
                 not given)"
            )));
        }
    }
    let samples = methods::registry::stored_samples(method, &options);
    let flags = if samples > 1 { "--width, --height and --rate" } else { "--width and --height" };
    check_frame(width, height, samples).map_err(|m| input(anyhow::anyhow!("{flags}: {m}")))?;
    // The memory budget, before anything is built: from the scene's triangle bound, exact for
    // generated objects; a mesh file's bound can be loose, so a scene with one that the bound
    // refuses is loaded and checked again by its real count before the frame is built.
    let budget = |triangles: u64| {
        check_budget(a, method, triangles, (width, height), &options, &params, compared_with)
    };
    let scene = match budget(described.triangles().map_err(scene_error)?) {
        Ok(()) => described.resolve().map_err(scene_error)?,
        Err(refused) if described.triangles_exact() => return Err(refused),
        Err(_) => {
            let scene = described.resolve().map_err(scene_error)?;
            budget(scene.triangle_count() as u64)?;
            scene
        }
    };
    #[cfg(feature = "gpu")]
    if a.device == DeviceArg::Gpu {
        methods::gpu::GpuContext::shared().map_err(gpu_failure)?;
    }
    Ok(Job { scene, technique, reference, width, height })
}

fn report(a: ReportArgs) -> Result<(), Failure> {
    if let Some(ReportAction::Merge(m)) = a.action {
        return report_merge(m);
    }
    let mut suite =
        reports::Suite::load(&a.suite).map_err(|e| input(anyhow::anyhow!("--suite: {e}")))?;
    if let Some(clock) = a.clock {
        suite.clock = clock.into();
    }
    if a.plan {
        return print_plan(&suite, a.shard);
    }
    let (out, flag) = match (a.out, a.shard) {
        (Some(out), _) => (out, "--out"),
        (None, None) => {
            (PathBuf::from(format!("shadowbench-out/report-{}", suite.name)), "--out (default)")
        }
        (None, Some(s)) => (
            PathBuf::from(format!("shadowbench-out/report-{}/shards/{}", suite.name, s.index)),
            "--out (default)",
        ),
    };
    let mut options = reports::baseline::BaselineOptions::default();
    // A threshold of the baseline comparison: a finite number >= 0, given with --baseline.
    let threshold = |value: Option<f64>, flag: &str, what: &str, into: &mut f64| {
        let Some(v) = value else { return Ok(()) };
        if !(v.is_finite() && v >= 0.0) {
            return Err(input(anyhow::anyhow!("{flag}: {v} is not {what} (a finite number >= 0)")));
        }
        if a.baseline.is_none() {
            eprintln!("note: {flag} applies only with --baseline; ignored");
        }
        *into = v;
        Ok(())
    };
    threshold(
        a.baseline_tolerance,
        "--baseline-tolerance",
        "a relative tolerance",
        &mut options.time_tolerance,
    )?;
    threshold(
        a.baseline_min_ms,
        "--baseline-min-ms",
        "a time in milliseconds",
        &mut options.min_change_ms,
    )?;
    let before = match &a.baseline {
        Some(dir) => Some(reports::baseline::load_baseline(dir).map_err(input)?),
        None => None,
    };
    let cache_dir = a.cache.clone().unwrap_or_else(|| out.join(reports::write::CACHE_DIR));
    let plan = reports::plan::plan(&suite);
    let items = match a.shard {
        Some(s) => s.items(&plan),
        None => (0..plan.len()).collect(),
    };
    if let (Some(limit), Some(heaviest)) = (
        analysis::budget::Limit::new(a.max_memory),
        items.iter().map(|&k| &plan[k]).max_by_key(|i| i.memory),
    ) {
        if heaviest.memory > limit.bytes {
            return Err(input(analysis::budget::OverBudget {
                what: format!(
                    "--suite {}: item {} ({} at {}x{})",
                    suite.name,
                    heaviest.item,
                    heaviest.scene.as_deref().unwrap_or("a table's scene"),
                    heaviest.width,
                    heaviest.height
                ),
                estimate: analysis::budget::Estimate { bytes: heaviest.memory, parts: Vec::new() },
                limit,
                lower: "its frame, rate, map size or the scene's triangles".into(),
            }));
        }
    }
    // The output folder is opened (its earlier report stays until the new one replaces it
    // whole), then the cache's path checked: a refusal drops the transaction, which leaves
    // the folder as it was.
    let kind = if a.shard.is_some() { Kind::Shard } else { Kind::Report };
    let tx = begin_out(&out, flag, kind)?;
    check_folder_path(&cache_dir, "--cache")?;
    let mut cache = reports::cache::ReferenceCache::open(&cache_dir).map_err(|e| {
        input(anyhow::anyhow!("--cache {}: cannot create the folder: {e}", cache_dir.display()))
    })?;
    if let Some(shard) = a.shard {
        let start = reports::merge::ShardStart {
            suite: suite.name.clone(),
            shard,
            started: instrumentation::Provenance::capture(String::new(), None).timestamp,
        };
        let path = tx.staging().join(reports::merge::SHARD_START);
        std::fs::write(&path, serde_json::to_string_pretty(&start)? + "\n")
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    let started = std::time::Instant::now();
    let runs_planned = reports::sweep::items_run_count(&plan, &items);
    let bar = indicatif::ProgressBar::new(runs_planned);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} runs, {elapsed} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let (mut report, images) =
        reports::sweep::run_items(&suite, &plan, &items, Some(&mut cache), |p| {
            // The time left from the plan's cost model, corrected by the runs done so far.
            let left = p.time_left.map_or_else(
                || "time left unknown".to_owned(),
                |d| format!("about {} left", reports::progress::hms(d)),
            );
            bar.set_message(format!("{left}; {}", p.label));
            bar.set_position(p.runs_done);
        });
    bar.finish_and_clear();
    if let Some(shard) = a.shard {
        for r in &mut report.rows {
            r.shard = Some(shard.index);
        }
        report.shards = vec![reports::model::ShardInfo {
            shard,
            items: items.clone(),
            provenance: report.provenance.clone(),
            machine: report.machine.clone(),
            cache: report.cache,
            wall_s: started.elapsed().as_secs_f64(),
        }];
    }
    let comparison = match (&before, &a.baseline) {
        (Some(b), Some(dir)) => Some(reports::baseline::compare(&report, b, dir, options)),
        _ => None,
    };
    if a.shard.is_some() {
        // The merge writes the report's pages and charts; a shard leaves what it measured.
        reports::write::write_shard(tx.staging(), &report, &images)?;
    } else {
        reports::write_report(tx.staging(), &report, &images, comparison.as_ref())?;
    }
    commit_out(tx, flag)?;
    if let Some(c) = &comparison {
        println!("{}", reports::baseline::summary_line(c));
        if let Some(ratios) = reports::baseline::ratio_summary(c) {
            println!("{ratios}");
        }
        for r in c.regressions() {
            println!(
                "  regression: {} {} on {}: {}",
                r.method,
                r.params,
                r.scene,
                reports::baseline::flags(r)
            );
        }
    }
    for skipped in &report.skipped {
        eprintln!("note: not run: {skipped}");
    }
    let what = match a.shard {
        Some(s) => {
            format!("shard {s} of suite {} ({} of {} items)", suite.name, items.len(), plan.len())
        }
        None => format!("suite {}", suite.name),
    };
    let measured = reports::sweep::measured_run_count(&report);
    let not_run = match runs_planned.saturating_sub(measured) {
        0 => String::new(),
        n => format!(" ({n} not run, see the notes above)"),
    };
    println!(
        "{what}: {measured} of {runs_planned} planned runs measured{not_run} on {} scenes; {}; \
         wrote {}",
        report.scenes.len(),
        cache_line(cache.dir(), cache.stats),
        out.display()
    );
    Ok(())
}

/// What a reference cache did, in words.
fn cache_line(dir: &Path, s: reports::cache::CacheStats) -> String {
    let mut line =
        format!("reference cache {}: {} hits, {} misses", dir.display(), s.hits, s.misses);
    if s.invalid > 0 {
        line += &format!(", {} entries failed verification and were recomputed", s.invalid);
    }
    if s.write_failures > 0 {
        line += &format!(", {} entries could not be written", s.write_failures);
    }
    line
}

/// `report --plan`: the work list as JSON lines, and a summary on standard error.
fn print_plan(suite: &reports::Suite, shard: Option<reports::plan::Shard>) -> Result<(), Failure> {
    let plan = reports::plan::plan(suite);
    let items = match shard {
        Some(s) => s.items(&plan),
        None => (0..plan.len()).collect(),
    };
    let mut out = String::new();
    for &k in &items {
        out += &serde_json::to_string(&plan[k])?;
        out.push('\n');
    }
    print!("{out}");
    let cost: f64 = items.iter().map(|&k| plan[k].cost).sum();
    let total: f64 = plan.iter().map(|i| i.cost).sum();
    let runs = reports::sweep::items_run_count(&plan, &items);
    let whose = shard.map_or_else(String::new, |s| format!("shard {s}: "));
    eprintln!(
        "{whose}{} items, {runs} runs, {:.1} % of the suite's estimated cost",
        items.len(),
        if total > 0.0 { 100.0 * cost / total } else { 100.0 }
    );
    Ok(())
}

/// `report merge DIR... --out OUT`.
fn report_merge(m: MergeArgs) -> Result<(), Failure> {
    let out = m.out;
    // The shards are read and checked, and the output folder is none of them, before the
    // output folder's earlier report is removed.
    let (report, dirs) = reports::merge::merge(&m.dirs, m.allow_mixed).map_err(input)?;
    for dir in &dirs {
        if overlaps(dir, &out) {
            return Err(input(anyhow::anyhow!(
                "--out {}: the merge would write over the shard {} (give a folder of its own)",
                out.display(),
                dir.display()
            )));
        }
    }
    let tx = begin_out(&out, "--out", Kind::Report)?;
    reports::merge::copy_shard_files(&dirs, tx.staging())
        .with_context(|| format!("cannot copy the shards' files into {}", out.display()))?;
    reports::write::write_summary(tx.staging(), &report, None)?;
    commit_out(tx, "--out")?;
    for skipped in &report.skipped {
        eprintln!("note: not run: {skipped}");
    }
    let walls: Vec<String> =
        report.shards.iter().map(|s| format!("{} {:.1} s", s.shard, s.wall_s)).collect();
    let cache = report.cache.unwrap_or_default();
    println!(
        "merged {} shards of suite {}: {} runs on {} scenes; shards' wall times: {}; \
         reference caches: {} hits, {} misses; wrote {}",
        report.shards.len(),
        report.suite.name,
        report.rows.len(),
        report.scenes.len(),
        walls.join(", "),
        cache.hits,
        cache.misses,
        out.display()
    );
    Ok(())
}

/// A method's result: its visibility, its run record, and its pixel classes when it is a
/// reference that computes them (`exact`).
struct Ran {
    visibility: Visibility,
    record: RunRecord,
    classes: Option<Vec<PixelClass>>,
}

/// Runs the job's technique on `frame`, recording into `rec`. A reference is evaluated as
/// such (keeping its pixel classes), and its values are rounded to `f32`
/// ([`ReferenceImage::to_visibility`]).
fn run(
    job: &Job,
    frame: &Frame<'_>,
    rec: &mut Recorder,
) -> Result<(Visibility, Option<Vec<PixelClass>>), Failure> {
    match &job.reference {
        Some(r) => {
            let image = r.evaluate(frame, rec).map_err(input)?;
            Ok((image.to_visibility(), image.classes))
        }
        None => Ok((job.technique.run(frame, rec).map_err(method_failure)?, None)),
    }
}

/// Who ran on `frame`: the job's scene, technique and frame size.
fn identity(job: &Job, frame: &Frame<'_>) -> instrumentation::RunIdentity {
    instrumentation::RunIdentity {
        scene: job.scene.name.clone(),
        method: job.technique.name().to_owned(),
        params: job.technique.params(),
        width: job.width,
        height: job.height,
        effects: frame.effects.names().into_iter().map(String::from).collect(),
    }
}

/// The GPU adapter a job ran on (`--device gpu`), for its provenance.
fn gpu_adapter(job: &Job) -> Option<String> {
    let on_gpu = job.technique.params().get("device").and_then(|d| d.as_str()) == Some("gpu");
    on_gpu.then(methods::registry::gpu_adapter_name).flatten()
}

/// The spread of the total times of repeated runs (`--repeat`).
struct Spread {
    /// Wall-clock totals.
    wall: Summary,
    /// CPU totals, where measured.
    cpu: Option<Summary>,
    /// Timed runs whose CPU share was below the protocol's threshold.
    contended: usize,
}

impl Spread {
    /// The times of the repeated runs: both clocks' medians with their intervals and ranges,
    /// and how many runs were contended.
    fn describe(&self) -> String {
        let cpu = self.cpu.map_or(String::new(), |c| format!("CPU {} ms, ", summary_text(&c)));
        let contended = match self.contended {
            0 => String::new(),
            n => format!("; {n} contended (another process took the cores)"),
        };
        format!(
            "{cpu}wall {} ms, median of {} runs after a warm-up{contended}",
            summary_text(&self.wall),
            self.wall.n
        )
    }
}

/// The time of a run, on both clocks: the record's own for one run, the spread of repeated
/// runs.
fn time_text(record: &RunRecord, spread: Option<&Spread>) -> String {
    match spread {
        Some(s) => s.describe(),
        None => {
            let cpu = record.cpu_ms.map_or(String::new(), |c| format!(", {c:.1} ms CPU"));
            format!("{:.1} ms wall{cpu}", record.total_ms)
        }
    }
}

/// Runs the job's technique `repeat` times (see `--repeat`) under the measurement engine's
/// protocol, each on a frame of its own so that the G-buffer is timed too: once, cold, for 1;
/// else after an untimed warm-up. Gives the last frame, the result with the record of the run
/// of median CPU time, and the spread of the totals when there was more than one timed run.
/// Prints the record's warnings.
fn run_repeated(job: &Job, repeat: u32) -> Result<(Frame<'_>, Ran, Option<Spread>), Failure> {
    let warmup = u32::from(repeat > 1);
    let protocol = Protocol::fixed(warmup, repeat);
    let measured = measure(&protocol, |rec: &mut Recorder| {
        let frame = Frame::new(&job.scene, job.width, job.height, rec);
        run(job, &frame, rec).map(|(v, classes)| (frame, v, classes))
    })?;
    // The record kept is the median run's; every run computes the same values.
    let mut record = measured.run_record(identity(job, &measured.output.0), warmup);
    let (frame, visibility, classes) = measured.output;
    record.pixel_classes = classes.as_deref().map(analysis::metrics::class_pixels);
    record.provenance = Some(instrumentation::Provenance::capture(
        instrumentation::Provenance::command_line(),
        gpu_adapter(job),
    ));
    let spread = (measured.samples.len() > 1).then(|| Spread {
        wall: measured.wall_ms,
        cpu: measured.cpu_ms,
        contended: measured.samples.iter().filter(|s| s.contended).count(),
    });
    let ran = Ran { visibility, record, classes };
    for w in &ran.record.warnings {
        eprintln!("warning: {w}");
    }
    Ok((frame, ran, spread))
}

/// The output folder (`--out`, or `shadowbench-out/SCENE-METHOD{suffix}`), opened as a run's
/// transaction ([`begin_out`]).
fn out_dir(a: &RenderArgs, job: &Job, suffix: &str) -> Result<Transaction, Failure> {
    let (out, flag) = match &a.out {
        Some(out) => (out.clone(), "--out"),
        None => {
            let name = format!("{}-{}{suffix}", job.scene.name, job.technique.name());
            (Path::new("shadowbench-out").join(name), "--out (default)")
        }
    };
    begin_out(&out, flag, Kind::Run)
}

/// Writes a run's files: visibility.exr, shadow.png, run.json, and classes.png and
/// class_ids.png when it has pixel classes.
fn write_run(out: &Path, frame: &Frame<'_>, ran: &Ran) -> Result<(), Failure> {
    let v = &ran.visibility;
    reports::write_visibility_exr(&out.join("visibility.exr"), v)?;
    reports::write_shadow_png(&out.join("shadow.png"), frame, v)?;
    reports::write_run_json(&out.join("run.json"), &ran.record)?;
    if let Some(classes) = &ran.classes {
        reports::write_class_pngs(out, v.width, v.height, classes)?;
    }
    Ok(())
}

fn render(a: RenderArgs) -> Result<(), Failure> {
    let job = job(&a, None)?;
    let tx = out_dir(&a, &job, "")?;
    let (frame, ran, spread) = run_repeated(&job, a.repeat)?;
    write_run(tx.staging(), &frame, &ran)?;
    let out = commit_out(tx, "--out")?;
    let record = &ran.record;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&record)?);
    }
    eprintln!(
        "{} on {} at {}x{}: {}; wrote {}",
        record.method,
        record.scene,
        job.width,
        job.height,
        time_text(record, spread.as_ref()),
        out.display()
    );
    Ok(())
}

/// `--error-scale`, checked.
fn error_scale(c: &reference::TruthArgs) -> Result<f64, Failure> {
    let error_scale = c.error_scale.unwrap_or(analysis::error_map::DEFAULT_MAX_ERROR);
    analysis::error_map::check_scale(error_scale)
        .map_err(|e| input(anyhow::anyhow!("--error-scale: {e}")))?;
    Ok(error_scale)
}

fn compare(c: CompareArgs) -> Result<(), Failure> {
    if let Some(file) = &c.outside.visibility_file {
        return external::compare(&c, file);
    }
    external::refuse_outside_flags(&c.outside)?;
    let a = &c.render;
    let rate = c.truth.ref_rate.unwrap_or(analysis::registry::DEFAULT_REF_RATE);
    let budget_reference = match c.truth.reference {
        ReferenceName::Exact => ("exact", rate),
        ReferenceName::Raytrace => ("raytrace", rate),
    };
    let job = job(a, Some(budget_reference))?;
    let error_scale = error_scale(&c.truth)?;
    let chosen = reference::choose(&c.truth, a.pattern())?;
    let tx = out_dir(a, &job, &format!("-vs-{}", chosen.reference.name()))?;
    let mut cache = reference::open_cache(&c.truth.cache)?;
    let staging = tx.staging().to_owned();

    let (frame, ran, spread) = run_repeated(&job, a.repeat)?;
    let evaluated =
        reference::evaluate(&chosen, &job.scene, &frame, cache.as_mut(), &ran.visibility)?;
    write_run(&staging, &frame, &ran)?;
    let record = &ran.record;
    let compared = reference::Compared {
        method: record.method.clone(),
        params: record.params.clone(),
        method_ms: Some(record.total_ms),
        external: false,
    };
    let metrics = reference::score(
        &frame,
        &ran.visibility,
        &chosen,
        evaluated,
        compared,
        error_scale,
        &staging,
    )?;
    let out = commit_out(tx, "--out")?;
    reference::report(&metrics, a.json, &time_text(record, spread.as_ref()), cache.as_ref())?;
    eprintln!("wrote {}", out.display());
    Ok(())
}

/// Prints a comparison: the shadow-only headline, then one line per class, then the method's
/// time (`time`, on both clocks) and the reference's.
fn print_metrics(m: &reports::MetricsRecord, time: &str) {
    let c = &m.comparison;
    let rate = |r: Option<u32>| r.map_or(String::new(), |r| format!(" at {r} samples/pixel"));
    let against = match m.edge_reference.as_deref() {
        Some("none") => format!("{} (edge pixels left out)", m.reference),
        Some(_) => format!("{} (edge pixels ray traced{})", m.reference, rate(m.ref_rate)),
        None => format!("{}{}", m.reference, rate(m.ref_rate)),
    };
    // A statistic that does not apply (no pixels to take it over) is `n/a`, never 0.
    let num = |v: Option<f64>, digits: usize| v.map_or("n/a".into(), |v| format!("{v:.digits$}"));
    println!("{} on {} at {}x{} against {against}", m.method, m.scene, m.width, m.height);
    println!("shadow-only pixels (planar + surface the reference evaluated):");
    println!("  evaluated pixels        {}", c.evaluated_pixels);
    println!("  mean abs error          {}", num(c.mean_abs_error, 6));
    println!("  rmse                    {}", num(c.rmse, 6));
    println!("  max abs error           {}", num(c.max_abs_error, 6));
    println!("  pixel match (0.5/255)   {}", num(c.pixel_match, 4));
    println!("  pixel match (Lecocq)    {}", num(c.pixel_match_lecocq, 4));
    println!("  boundary pixels         {}", c.boundary_pixels);
    println!("  boundary mean abs error {}", num(c.boundary_mean_abs_error, 6));
    println!(
        "  boundary abs error p50/p95/p99  {} / {} / {}",
        num(c.boundary_p50_abs_error, 6),
        num(c.boundary_p95_abs_error, 6),
        num(c.boundary_p99_abs_error, 6)
    );
    println!("  FLIP mean (whole frame) {:.6}", c.flip_mean);
    println!(
        "  {:<9} {:>15} {:>10} {:>10} {:>10} {:>10} {:>9} {:>13} {:>13}",
        "class",
        "pixels",
        "mean abs",
        "rmse",
        "max abs",
        "p95 abs",
        "boundary",
        "boundary mean",
        "boundary p95"
    );
    for (name, k) in
        [("planar", &c.classes.planar), ("surface", &c.classes.surface), ("edge", &c.classes.edge)]
    {
        let total = c.class_pixels.get(name).copied().unwrap_or(0);
        println!(
            "  {:<9} {:>15} {:>10} {:>10} {:>10} {:>10} {:>9} {:>13} {:>13}",
            name,
            format!("{}/{total}", k.pixels),
            num(k.mean_abs_error, 6),
            num(k.rmse, 6),
            num(k.max_abs_error, 6),
            num(k.p95_abs_error, 6),
            k.boundary_pixels,
            num(k.boundary_mean_abs_error, 6),
            num(k.boundary_p95_abs_error, 6)
        );
    }
    println!(
        "  (pixels: compared/in the frame; {} uncovered)",
        c.class_pixels.get("uncovered").copied().unwrap_or(0)
    );
    match m.reference_read_ms {
        Some(read) => println!(
            "  time: method {time}; reference read from the cache in {read:.1} ms (computed in \
             {:.1} ms wall by an earlier run)",
            m.reference_ms
        ),
        None => println!("  time: method {time}; reference {:.1} ms wall", m.reference_ms),
    }
}

fn main() -> ExitCode {
    let matches = command().get_matches();
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    let sub = matches.subcommand().map(|(_, m)| m);
    let result = match cli.command {
        Command::Scenes { json, toml } => scenes(json, toml),
        Command::Render(mut a) => {
            a.params = sub.map(given_params).unwrap_or_default();
            render(a)
        }
        Command::Compare(mut c) => {
            c.render.params = sub.map(given_params).unwrap_or_default();
            compare(c)
        }
        Command::Frame(f) => external::frame(f),
        Command::Animate(mut a) => {
            a.render.params = sub.map(given_params).unwrap_or_default();
            animate::animate(a)
        }
        Command::Report(r) => report(r),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Input(e)) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
        Err(Failure::Internal(e)) => {
            eprintln!("internal error: {e:#}");
            ExitCode::from(1)
        }
    }
}

#[cfg(all(test, feature = "gpu"))]
mod tests {
    use super::*;

    /// GPU errors: the environment (variables, no adapter, no 64-bit floats) is bad input,
    /// exit 2; the device failing is internal, exit 1.
    #[test]
    fn gpu_device_failures_are_internal_and_the_environment_is_input() {
        let internal = |e: MethodError| matches!(method_failure(e), Failure::Internal(_));
        assert!(internal(MethodError::Gpu(GpuError::Device("lost".into()))));
        for env in [
            GpuError::BadBackend("warp".into()),
            GpuError::NoAdapter { backends: "VULKAN".into() },
            GpuError::NoF64Adapter { adapters: "llvmpipe".into() },
            GpuError::NoMatchingAdapter { wanted: "h200".into(), adapters: "llvmpipe".into() },
            GpuError::Limit("binding of 268435456 bytes".into()),
        ] {
            assert!(!internal(MethodError::Gpu(env)));
        }
        assert!(!internal(MethodError::NotApplicable("exact".into())));
    }
}
