//! Timing that holds under load: a small suite measured twice on the same code, the second
//! time with another process keeping one core busy, is set against itself by `--baseline`
//! and no regression is flagged; with one method made three times as slow (`SHADOWBENCH_SLOWDOWN`, the
//! test build's `methods::slowdown`), that method is flagged and no other.
//!
//! The comparison is of CPU time, the report's default clock: the load generator takes a core
//! and moves wall times, not the CPU time the work takes. The test holds the machine alone
//! (`common::machine_alone`): the other tests of this binary, which run reports, wait.

use crate::common::{stderr, write};
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};

/// Frames and maps large enough that each run takes milliseconds of CPU time (the baseline's
/// floor is 1 ms), small enough for a test.
const SUITE: &str = r#"
name = "load"
width = 320
height = 240
warmup = 1
repeats = 6
max_repeats = 12
target = 0.05
time_cap_s = 10
scenes = ["cage", "spheres"]

[[run]]
method = "sm"
map_res = [2048]

[[run]]
method = "pcf-gems16"
map_res = [1024]

[[run]]
method = "pcf-bs-fast-4x4"
map_res = [1024]

[[run]]
method = "afsm"
"#;

/// A process that keeps one core busy (pinned to core 0 where `taskset` exists) until it is
/// killed, when dropped.
struct Load(Child);

impl Load {
    fn start() -> Self {
        let spin = "while :; do :; done";
        let pinned = Command::new("taskset")
            .args(["-c", "0", "sh", "-c", spin])
            .stdout(Stdio::null())
            .spawn();
        let child = pinned.unwrap_or_else(|_| {
            Command::new("sh").args(["-c", spin]).spawn().expect("sh runs a busy loop")
        });
        // Let it take its core before the report starts.
        std::thread::sleep(std::time::Duration::from_millis(300));
        Self(child)
    }
}

impl Drop for Load {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// The relative slow-down a run's whole interval must exceed to be flagged here. On this
/// project's 2-core machines a busy core raised the CPU time of every method on `spheres` by
/// 1.3-1.8 times (intervals' lower ends up to 1.45) in some runs and not in others, beyond the
/// default 0.2; CPU time is not free of other work where cores share a physical one's caches.
const TOLERANCE: &str = "0.6";

/// `report --suite SUITE --out OUT [--baseline BASE --baseline-tolerance TOLERANCE]`, with
/// `env` set.
fn report(suite: &str, out: &Path, baseline: Option<&Path>, env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_shadowbench"));
    c.args(["report", "--suite", suite, "--out", out.to_str().expect("utf-8")]);
    if let Some(b) = baseline {
        c.args(["--baseline", b.to_str().expect("utf-8"), "--baseline-tolerance", TOLERANCE]);
    }
    c.env_remove("SHADOWBENCH_SLOWDOWN");
    for (k, v) in env {
        c.env(k, v);
    }
    let o = c.output().expect("the shadowbench binary runs");
    assert!(o.status.success(), "{}", stderr(&o));
    o
}

/// The lines `report --baseline` prints: the summary and one per regression.
fn baseline_lines(o: &Output) -> (String, Vec<String>) {
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let summary = out.lines().find(|l| l.starts_with("Against the baseline")).unwrap_or_default();
    let flagged = out.lines().filter(|l| l.contains("regression:")).map(String::from).collect();
    (summary.to_owned(), flagged)
}

#[test]
fn a_loaded_machine_flags_nothing_and_a_slower_method_alone_is_flagged() {
    // The quiet report is quiet but for this machine's other work: no other test of this
    // binary runs beside it.
    let _machine = crate::common::machine_alone();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = write(dir.path(), "load.toml", SUITE);
    let quiet = dir.path().join("quiet");
    report(&suite, &quiet, None, &[]);

    let runs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(quiet.join("runs.json")).expect("runs.json"))
            .expect("json");
    let rows = runs["rows"].as_array().expect("rows");
    assert_eq!(rows.len(), 8);
    for r in rows {
        assert!(r["cpu_ms"]["median"].as_f64().is_some_and(|c| c > 0.0), "{r}");
        assert!(r["total_ms"]["n"].as_u64().is_some_and(|n| (6..=12).contains(&n)), "{r}");
        assert!(r["conditions"]["cores"].as_u64().is_some_and(|c| c >= 1), "{r}");
    }

    let load = Load::start();
    let loaded = dir.path().join("loaded");
    let o = report(&suite, &loaded, Some(&quiet), &[]);
    let (summary, flagged) = baseline_lines(&o);
    // The ratios, for the log of a failure.
    eprintln!("{}", std::fs::read_to_string(loaded.join("baseline.md")).unwrap_or_default());
    assert!(summary.contains("8 runs compared"), "{summary}");
    // No regression is flagged. A parallel method's CPU time can come out lower under load
    // (the rayon pool's idle threads spin less while another process holds a core), so a run
    // may be flagged faster; slower it must not be.
    assert!(summary.contains("0 slower, 0 less accurate"), "{summary}\n{flagged:?}");
    assert!(flagged.is_empty(), "{flagged:?}");

    // The same under load, with pcf-gems16 doing three times its work, well beyond the
    // tolerance and the load's own effect.
    let slowed = dir.path().join("slowed");
    let o = report(&suite, &slowed, Some(&quiet), &[("SHADOWBENCH_SLOWDOWN", "pcf-gems16=3")]);
    drop(load);
    let (summary, flagged) = baseline_lines(&o);
    assert!(summary.contains("2 slower, 0 less accurate"), "{summary}\n{flagged:?}");
    assert!(flagged.iter().all(|l| l.contains("pcf-gems16")), "{flagged:?}");
    let md = std::fs::read_to_string(slowed.join("baseline.md")).expect("baseline.md");
    eprintln!("{md}");
    assert!(md.contains("**pcf-gems16**") && md.contains("| cpu "), "{md}");
}
