//! Instrumentation: work counters, stage timers and the run record (`run.json`).
//!
//! [`Counters`] is a plain struct of `u64`: methods keep one copy per thread (or per rayon
//! task) and sum them with [`Counters::merge`]; no string map is touched in a hot loop. A
//! counter a method does not use stays 0. [`Stages`] times each pipeline stage under its own
//! name and lists the stages a scene did not call for as skipped. [`cpu_model`] names the
//! CPU that times were taken on, and [`Provenance`] what a result was produced by.

pub mod clock;
pub mod measure;
pub mod stats;

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;
use std::time::{Instant, SystemTime};

macro_rules! counters {
    ($($(#[doc = $doc:literal])* $name:ident),* $(,)?) => {
        /// Work counted by a run. Every field is a count of real work done.
        #[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct Counters {
            $($(#[doc = $doc])* pub $name: u64,)*
        }

        impl Counters {
            /// Names of all counters, in declaration order.
            pub const NAMES: &'static [&'static str] = &[$(stringify!($name)),*];

            /// Adds every counter of `other` into `self`.
            pub fn merge(&mut self, other: &Counters) {
                $(self.$name += other.$name;)*
            }

            /// `(name, value)` for every counter, in declaration order.
            pub fn entries(&self) -> Vec<(&'static str, u64)> {
                vec![$((stringify!($name), self.$name)),*]
            }
        }
    };
}

counters! {
    /// Shadow-map texels marked as holding a silhouette edge.
    silhouette_texels,
    /// Pixels whose facet touches a silhouette texel.
    silhouette_pixels,
    /// Pixel-texel pairs emitted.
    pt_pairs,
    /// Triangle-texel pairs emitted.
    tt_pairs,
    /// Triangle-against-pixel visibility evaluations.
    visibility_evaluations,
    /// Pixels classified as uncertain.
    uncertain_pixels,
    /// Sub-samples found valid by a validity mask.
    valid_samples,
    /// Pixels on a shadow boundary (value strictly between 0 and 1).
    boundary_pixels,
    /// Nodes of a 2D BSP.
    bsp_nodes,
    /// BSP nodes visited during rasterization.
    bsp_nodes_visited,
    /// BSP nodes (`afsm`) or light-grid texels (`ftizb`, once per caster) skipped because all
    /// their samples were already shadowed.
    nodes_occlusion_culled,
    /// BSP nodes (`afsm`) or light-grid texels (`ftizb`, once per caster) skipped because the
    /// triangle lies beyond their farthest sample.
    nodes_depth_culled,
    /// Light-grid texels the pixels' footprints were listed in (`ftizb`).
    footprint_texels,
    /// Light-grid texels holding pixels that a caster's conservative rasterization reached
    /// (`ftizb`).
    caster_texels,
    /// Sampling points tested against a triangle.
    sampling_points_tested,
    /// Depth comparisons against a shadow map.
    shadow_map_lookups,
    /// Hardware-style bilinear PCF lookups (four depth compares each, interpolated).
    bilinear_lookups,
    /// Rays traced (camera and shadow rays).
    rays_traced,
    /// Triangles sent to a rasterizer (camera G-buffer and light maps).
    triangles_rasterized,
    /// Sample points (pixel or texel centres) tested for coverage by a rasterizer.
    raster_samples_tested,
    /// Texel-triangle overlaps found by conservative rasterization (SPSM).
    conservative_fragments,
    /// Texels holding a triangle after packing (SPSM).
    packed_texels,
    /// Texels whose consistent minimum depth lies above the conservative corner depth (SPSM).
    depth_corrected_texels,
    /// Pixels lit by a single map lookup (SPSM).
    lit_by_one_lookup,
    /// Pixels shadowed by the triangle of their own texel (SPSM).
    shadowed_by_one_lookup,
    /// Pixels shadowed by a triangle of the 3x3 texel neighbourhood (SPSM).
    shadowed_by_neighbourhood,
    /// Uncertain pixels decided by a recovered silhouette function (SPSM).
    recovered_pixels,
    /// Sub-samples evaluated against a recovered silhouette (SPSM antialiasing).
    antialiased_samples,
    /// Pixel-triangle overlaps measured to classify pixels (`exact`).
    pixel_triangle_overlaps,
    /// Receiver triangles whose shadows were computed (`exact`, surface pixels).
    receiver_triangles,
    /// Receiver-caster pairs looked at after the light-space caster grid (`exact`).
    caster_pairs,
    /// Non-empty shadow polygons projected onto a receiver, within the frame (a planar
    /// object) or the receiver triangle's screen box (a surface triangle) (`exact`).
    shadow_polygons,
    /// Pixels (or a receiver's part of one) found wholly inside one shadow polygon, or inside
    /// the union of a mesh's shadow polygons away from its outline, shadowed without a cut
    /// (`exact`).
    covered_pixels,
    /// Pixel-shadow polygon overlaps resolved by cutting the pixel's uncovered pieces
    /// (`exact`).
    pixel_polygon_pairs,
}

impl std::ops::AddAssign<&Counters> for Counters {
    fn add_assign(&mut self, rhs: &Counters) {
        self.merge(rhs);
    }
}

impl std::iter::Sum for Counters {
    fn sum<I: Iterator<Item = Counters>>(iter: I) -> Self {
        iter.fold(Counters::default(), |mut a, b| {
            a.merge(&b);
            a
        })
    }
}

/// One timed stage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stage {
    /// The stage's name.
    pub name: String,
    /// Wall-clock time in milliseconds (for a GPU stage timed by timestamp queries, the GPU's
    /// time).
    pub ms: f64,
    /// CPU time of the process's threads (the rayon pool included) in milliseconds, where the
    /// stage was timed on the CPU ([`Stages::time`]); absent for a stage added from another
    /// clock ([`Stages::add`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpu_ms: Option<f64>,
}

/// Stage times and skipped stages of one run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Stages {
    /// Stages in the order they ran.
    pub stages: Vec<Stage>,
    /// Stages the scene did not call for, in the order they were skipped.
    pub skipped: Vec<String>,
}

impl Stages {
    /// Runs `f` as the stage `name`, recording its wall-clock time and the CPU time of the
    /// process's threads ([`clock::cpu_now`]).
    pub fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let cpu = clock::cpu_now();
        let start = Instant::now();
        let out = f();
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let cpu_ms =
            cpu.zip(clock::cpu_now()).map(|(a, b)| b.saturating_sub(a).as_secs_f64() * 1e3);
        self.stages.push(Stage { name: name.to_owned(), ms, cpu_ms });
        out
    }

    /// Adds `ms` to the latest stage called `name`, or records a new stage when there is
    /// none: one stage run in parts (a pass submitted twice, a sub-sample's pass, CPU work
    /// beside a GPU pass) is one entry, its parts' time summed.
    pub fn add(&mut self, name: &str, ms: f64) {
        match self.stages.iter_mut().rev().find(|s| s.name == name) {
            Some(stage) => {
                // A part from another clock: the stage's CPU time is no longer known whole.
                stage.ms += ms;
                stage.cpu_ms = None;
            }
            None => self.stages.push(Stage { name: name.to_owned(), ms, cpu_ms: None }),
        }
    }

    /// Records that the stage `name` was not run because the scene does not call for it.
    pub fn skip(&mut self, name: &str) {
        self.skipped.push(name.to_owned());
    }

    /// Sum of all stage times in milliseconds.
    pub fn total_ms(&self) -> f64 {
        self.stages.iter().map(|s| s.ms).sum()
    }
}

/// Counters and stages gathered while a method runs.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Recorder {
    /// Work counters.
    pub counters: Counters,
    /// Stage times.
    pub stages: Stages,
    /// Remarks a method makes about the run (e.g. "casters treated as opaque").
    pub notes: Vec<String>,
    /// Conditions under which the result is not to be trusted as usual (e.g. a bias rule
    /// outside its valid range); written to `run.json` and printed by the CLI.
    pub warnings: Vec<String>,
}

/// Who ran, on what: the part of a run record the recorder does not hold.
#[derive(Debug, Clone, PartialEq)]
pub struct RunIdentity {
    /// Scene name.
    pub scene: String,
    /// Method name.
    pub method: String,
    /// Method parameters.
    pub params: serde_json::Map<String, serde_json::Value>,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Effects the scene calls for.
    pub effects: Vec<String>,
}

impl Recorder {
    /// The run record of what this recorder holds, for the run `who`; without pixel classes
    /// or provenance, which the caller adds when it has them.
    pub fn into_record(self, who: RunIdentity) -> RunRecord {
        RunRecord {
            scene: who.scene,
            method: who.method,
            params: who.params,
            width: who.width,
            height: who.height,
            effects: who.effects,
            counters: self.counters,
            total_ms: self.stages.total_ms(),
            cpu_ms: None,
            clocks: CLOCKS.to_owned(),
            timing: None,
            stages: self.stages.stages,
            skipped_stages: self.stages.skipped,
            notes: self.notes,
            warnings: self.warnings,
            pixel_classes: None,
            provenance: None,
        }
    }
}

/// The run record written as `run.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// Scene name.
    pub scene: String,
    /// Method name.
    pub method: String,
    /// Method parameters as given (rate, pattern, map resolution, biases, ...).
    pub params: serde_json::Map<String, serde_json::Value>,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Effects the scene calls for.
    pub effects: Vec<String>,
    /// Work counters.
    pub counters: Counters,
    /// Stages in the order they ran.
    pub stages: Vec<Stage>,
    /// Stages not run because the scene does not call for them.
    pub skipped_stages: Vec<String>,
    /// Remarks about the run.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    /// Conditions under which the result is not to be trusted as usual (empty when none).
    #[serde(default)]
    pub warnings: Vec<String>,
    /// Sum of the stage times, milliseconds.
    pub total_ms: f64,
    /// CPU time of the process's threads over the run, milliseconds; absent where it was not
    /// measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpu_ms: Option<f64>,
    /// Which clock each time of the record is ([`CLOCKS`]).
    #[serde(default = "clocks")]
    pub clocks: String,
    /// How the times were taken: the timed runs, their summaries on both clocks, contention
    /// and the machine's load ([`measure`]); absent where the record is not of a measurement.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timing: Option<measure::Timing>,
    /// Pixels of each class (`uncovered`, `planar`, `surface`, `edge`), for a reference that
    /// classifies pixels (`exact`); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pixel_classes: Option<BTreeMap<String, u64>>,
    /// What produced the run (commit, version, command line, time, machine); absent when not
    /// recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub provenance: Option<Provenance>,
}

/// Which clock each time of a run record is.
pub const CLOCKS: &str = "total_ms and stages[].ms: wall-clock time (a GPU stage timed by \
    timestamp queries: the GPU's time); cpu_ms and stages[].cpu_ms: CPU time of the process's \
    threads, the rayon pool included";

fn clocks() -> String {
    CLOCKS.to_owned()
}

/// The CPU's model name, from `/proc/cpuinfo` where there is one, for labelling times.
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_owned())
        })
        .unwrap_or_else(|| "unknown CPU".to_owned())
}

/// What a run or report was produced by and when, so that a result can be traced to its
/// source and machine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The workbench's crate version.
    pub version: String,
    /// The git commit of the source the binary was built from (`git rev-parse HEAD` in that
    /// source folder at run time), or `unknown` when that folder is not a git checkout.
    pub commit: String,
    /// Whether tracked files of that checkout differ from the commit (`false` when unknown).
    pub dirty: bool,
    /// The compiler the binary was built with (`rustc --version` at build time).
    pub rustc: String,
    /// The command line that produced the result.
    pub command: String,
    /// When the result was produced, RFC 3339 in UTC to the second.
    pub timestamp: String,
    /// CPU model.
    pub cpu: String,
    /// Worker threads of the parallel runtime.
    pub threads: usize,
    /// GPU adapter, when a method ran on the GPU.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adapter: Option<String>,
    /// A report merged from shards of different versions or commits (`report merge
    /// --allow-mixed`): each shard's version and commit, as `shard 1: 0.1.0 abc123`; empty
    /// otherwise.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub mixed: Vec<String>,
}

impl Provenance {
    /// The provenance of a result produced now by `command` (see [`Provenance::command_line`])
    /// on `adapter` (when a GPU was used).
    pub fn capture(command: String, adapter: Option<String>) -> Self {
        let source = Path::new(env!("CARGO_MANIFEST_DIR"));
        let (commit, dirty) = git_state(source).unwrap_or_else(|| ("unknown".to_owned(), false));
        Self {
            version: env!("CARGO_PKG_VERSION").to_owned(),
            commit,
            dirty,
            rustc: env!("SHADOWBENCH_RUSTC").to_owned(),
            command,
            timestamp: humantime::format_rfc3339_seconds(SystemTime::now()).to_string(),
            cpu: cpu_model(),
            threads: rayon::current_num_threads(),
            adapter,
            mixed: Vec::new(),
        }
    }

    /// This process's command line, arguments separated by spaces; an argument that is empty
    /// or holds a character outside `[A-Za-z0-9_./=:,+-]` is single-quoted as a shell would.
    pub fn command_line() -> String {
        std::env::args().map(|a| shell_quote(&a)).collect::<Vec<_>>().join(" ")
    }
}

/// `arg` as a POSIX shell reads it back: as is when plain, else single-quoted.
fn shell_quote(arg: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "_./=:,+-".contains(c);
    if !arg.is_empty() && arg.chars().all(plain) {
        arg.to_owned()
    } else {
        format!("'{}'", arg.replace('\'', "'\\''"))
    }
}

/// The commit checked out in the git repository holding `dir`, and whether tracked files
/// differ from it; `None` when `dir` is in no repository or `git` cannot be run.
fn git_state(dir: &Path) -> Option<(String, bool)> {
    let git = |args: &[&str]| {
        Command::new("git")
            .arg("-C")
            .arg(dir)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .and_then(|o| String::from_utf8(o.stdout).ok())
    };
    let commit = git(&["rev-parse", "HEAD"])?.trim().to_owned();
    let dirty = !git(&["status", "--porcelain", "--untracked-files=no"])?.trim().is_empty();
    Some((commit, dirty))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stage_run_in_parts_is_one_entry() {
        let mut s = Stages::default();
        s.add("map", 1.5);
        s.add("test", 2.0);
        s.add("map", 0.25);
        let got: Vec<(&str, f64)> = s.stages.iter().map(|x| (x.name.as_str(), x.ms)).collect();
        assert_eq!(got, [("map", 1.75), ("test", 2.0)]);
        assert_eq!(s.total_ms(), 3.75);
    }

    #[test]
    fn merge_adds_every_field() {
        let mut a = Counters { pt_pairs: 2, rays_traced: 5, ..Default::default() };
        let b = Counters { pt_pairs: 3, shadow_map_lookups: 7, ..Default::default() };
        a.merge(&b);
        assert_eq!((a.pt_pairs, a.rays_traced, a.shadow_map_lookups), (5, 5, 7));
        let total: Counters = vec![a, b].into_iter().sum();
        assert_eq!(total.pt_pairs, 8);
    }

    #[test]
    fn counters_serialize_every_field_by_name() {
        let json = serde_json::to_value(Counters::default()).expect("serializes");
        let obj = json.as_object().expect("object");
        assert_eq!(obj.len(), Counters::NAMES.len());
        for name in Counters::NAMES {
            assert_eq!(obj[*name], 0, "{name}");
        }
    }

    #[test]
    fn stages_record_names_and_skips() {
        let mut s = Stages::default();
        let v = s.time("light depth map", || 41 + 1);
        s.skip("validity mask");
        assert_eq!(v, 42);
        assert_eq!(s.stages[0].name, "light depth map");
        assert!(s.stages[0].ms >= 0.0);
        assert_eq!(s.skipped, vec!["validity mask".to_string()]);
    }

    #[test]
    fn provenance_names_version_commit_compiler_and_time() {
        let p = Provenance::capture("shadowbench report".into(), None);
        assert_eq!(p.version, env!("CARGO_PKG_VERSION"));
        assert!(p.rustc.starts_with("rustc "), "{}", p.rustc);
        // The tests run inside the checkout: a 40-digit commit.
        assert_eq!(p.commit.len(), 40, "{}", p.commit);
        assert!(p.commit.chars().all(|c| c.is_ascii_hexdigit()), "{}", p.commit);
        // RFC 3339, UTC, to the second: 2026-12-02T02:07:25Z.
        let t = p.timestamp.as_bytes();
        assert_eq!((t.len(), t[4], t[10], t[19]), (20, b'-', b'T', b'Z'), "{}", p.timestamp);
        assert!(p.threads >= 1);
        let json = serde_json::to_value(&p).expect("serializes");
        assert!(json.get("adapter").is_none(), "no adapter key without a GPU: {json}");
        assert_eq!(json["command"], "shadowbench report");
    }

    #[test]
    fn command_lines_quote_what_a_shell_would_split() {
        assert_eq!(shell_quote("--out=dir/a.b"), "--out=dir/a.b");
        assert_eq!(shell_quote("my report"), "'my report'");
        assert_eq!(shell_quote("it's"), "'it'\\''s'");
        assert_eq!(shell_quote(""), "''");
    }
}
