//! A report on a real Slurm cluster: `scripts/slurm/local-cluster start` brings up a
//! single-node cluster from Debian's packages (installing them where missing; root is
//! needed), `scripts/slurm/submit` runs a small suite as a 3-task array and a merge job, and
//! the merged report equals the unsharded one on every field but times, machine and
//! provenance. Then one array task is cancelled: the merge refuses, naming the shard, and
//! `submit --only` completes the report. The cluster is stopped whatever the outcome.

use crate::common::{assert_same_report, shadowbench, stderr, write};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const SUITE: &str = r#"
name = "cluster"
width = 96
height = 72
warmup = 0
repeats = 1
scenes = ["plane-square", "cage", "spheres"]

[[run]]
method = "sm"
map_res = [64, 128]

[[run]]
method = "pcf-gems4"
map_res = [64]
"#;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs `scripts/slurm/NAME args`, with the test's binary as the one the jobs run.
fn script(name: &str, args: &[&str], env: &[(&str, &str)]) -> Output {
    Command::new(repo().join("scripts/slurm").join(name))
        .args(args)
        .envs(env.iter().copied())
        .env("SHADOWBENCH_BIN", env!("CARGO_BIN_EXE_shadowbench"))
        .current_dir(repo())
        .output()
        .unwrap_or_else(|e| panic!("scripts/slurm/{name} runs: {e}"))
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), stderr(o))
}

/// The cluster, stopped when dropped (the test passing or not).
struct Cluster;

impl Cluster {
    fn start() -> Self {
        let o = script("local-cluster", &["start"], &[]);
        assert!(o.status.success(), "local-cluster start: {}", text(&o));
        Cluster
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let o = script("local-cluster", &["stop"], &[]);
        if !o.status.success() {
            eprintln!("local-cluster stop: {}", text(&o));
        }
    }
}

/// `submit --no-build --shards 3 [--only K] --work WORK SUITE`: the array's and the merge's
/// job ids.
fn submit(suite: &str, work: &Path, only: Option<&str>) -> (String, String) {
    let mut args = vec!["--no-build", "--shards", "3", "--work", work.to_str().expect("utf-8")];
    if let Some(k) = only {
        args.extend(["--only", k]);
    }
    args.push(suite);
    let o = script("submit", &args, &[]);
    assert!(o.status.success(), "submit: {}", text(&o));
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let id = |what: &str| {
        out.lines()
            .find_map(|l| l.strip_prefix(what))
            .map(|s| s.trim().to_owned())
            .unwrap_or_else(|| panic!("no `{what}` id: {out}"))
    };
    (id("array "), id("merge "))
}

/// Waits for the jobs; whether all completed, and what `wait` printed.
fn wait(ids: &[&str]) -> (bool, String) {
    let mut args = vec!["--timeout", "600", "--interval", "1"];
    args.extend(ids);
    let o = script("wait", &args, &[]);
    assert_ne!(o.status.code(), Some(124), "the jobs did not end in 10 minutes: {}", text(&o));
    (o.status.success(), text(&o))
}

#[test]
fn a_suite_runs_as_a_slurm_array_and_merges_into_the_unsharded_report() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = write(dir.path(), "cluster.toml", SUITE);
    let whole = dir.path().join("whole");
    let o = shadowbench(&["report", "--suite", &suite, "--out", whole.to_str().expect("utf-8")]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));

    let _cluster = Cluster::start();

    // The whole array, then the merge after it.
    let work = dir.path().join("work");
    let (array, merge) = submit(&suite, &work, None);
    let (ok, states) = wait(&[&array, &merge]);
    assert!(ok, "{states}");
    assert_same_report(&whole, &work.join("report"));
    let runs = std::fs::read_to_string(work.join("report/runs.json")).expect("runs.json");
    let json: serde_json::Value = serde_json::from_str(&runs).expect("parses");
    assert_eq!(json["shards"].as_array().map(Vec::len), Some(3), "every shard's provenance");
    // Five (shard, scene) pairs over three scenes: each reference computed at least once, the
    // rest read from the shared cache (all of it when the tasks run one after the other).
    let cache = &json["cache"];
    let count = |k: &str| cache[k].as_u64().unwrap_or_else(|| panic!("no {k}: {cache}"));
    assert_eq!(count("hits") + count("misses"), 5, "{cache}");
    assert!(count("misses") >= 3, "{cache}");

    // One task cancelled: the merge job cannot run, a merge by hand names the shard, and
    // submitting that shard again completes the report.
    let work = dir.path().join("killed");
    let (array, merge) = submit(&suite, &work, None);
    let o = Command::new("scancel").arg(format!("{array}_1")).output().expect("scancel runs");
    assert!(o.status.success(), "scancel: {}", text(&o));
    let (ok, states) = wait(&[&array, &merge]);
    assert!(!ok, "a cancelled task, yet everything completed: {states}");
    let env = [("SHADOWBENCH_WORK", work.to_str().expect("utf-8")), ("SHADOWBENCH_SHARDS", "3")];
    let o = script("merge.sbatch", &[], &env);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("shard 1 of 3 is missing"), "{}", text(&o));
    assert!(!work.join("report/runs.json").exists());
    let (array, merge) = submit(&suite, &work, Some("1"));
    let (ok, states) = wait(&[&array, &merge]);
    assert!(ok, "{states}");
    assert_same_report(&whole, &work.join("report"));
}
