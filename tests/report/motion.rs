//! A report over animated scenes: each run on an animated scene runs through every frame and
//! gives one row with its temporal metrics and a record per frame, its frames written as
//! images beside its page, its temporal columns filled in `runs.csv`; a still scene of the same
//! suite gives rows without. The exact reference run as a method has no error and no temporal
//! error. A second report with the same cache computes no reference, and a sharded report
//! merged has the same temporal numbers as the unsharded one.

use crate::common::{shadowbench, stderr, write};
use std::path::Path;

/// Frames every animated scene is sampled at.
const FRAMES: usize = 4;

/// Two animated scenes (an object sliding, a light sweeping) and a still one.
const SUITE: &str = r#"
name = "motion"
width = 48
height = 36
warmup = 0
repeats = 1
frames = 4
scenes = ["square-slide", "cage-sweep", "plane-square"]

[[run]]
method = "sm"
map_res = 128

[[run]]
method = "afsm"

[[run]]
method = "exact"
"#;

const ANIMATED: [&str; 2] = ["square-slide", "cage-sweep"];
const METHODS: [&str; 3] = ["sm", "afsm", "exact"];

fn path(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Runs `args` (a `report` command line), which must succeed; returns its standard output.
fn report(args: &[&str]) -> String {
    let o = shadowbench(args);
    assert_eq!(o.status.code(), Some(0), "{args:?}: {}", stderr(&o));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// A row's file stem, as the report names its files.
fn stem_of(row: &serde_json::Value) -> String {
    let row: reports::Row = serde_json::from_value(row.clone()).expect("a row");
    reports::model::row_stem(&row)
}

fn runs_json(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("runs.json")).expect("runs.json");
    serde_json::from_str(&text).expect("runs.json parses")
}

/// The rows' stems, temporal metrics and per-frame errors (not the times), by scene and
/// method.
fn temporal_numbers(dir: &Path) -> Vec<(String, serde_json::Value, Vec<serde_json::Value>)> {
    let json = runs_json(dir);
    let mut rows: Vec<_> = json["rows"]
        .as_array()
        .expect("rows")
        .iter()
        .map(|r| {
            let frames = r["per_frame"].as_array().cloned().unwrap_or_default();
            let errors = frames
                .iter()
                .map(|f| {
                    serde_json::json!([
                        f["frame"],
                        f["map_res"],
                        f["mean_abs_error"],
                        f["boundary_mean_abs_error"],
                        f["temporal_error"],
                        f["temporal_pairs"],
                    ])
                })
                .collect();
            let key = format!("{} {}", r["scene"], r["method"]);
            (key, r["temporal"].clone(), errors)
        })
        .collect();
    rows.sort_by(|a, b| a.0.cmp(&b.0));
    rows
}

/// The hits and misses of the cache line a report prints.
fn cache_counts(stdout: &str) -> (u64, u64) {
    let number_before = |word: &str| {
        let before = stdout.split(word).next().expect("text");
        let n = before.trim_end().rsplit(' ').next().expect("a number");
        n.parse::<u64>().unwrap_or_else(|_| panic!("no count before `{word}`: {stdout}"))
    };
    (number_before(" hits"), number_before(" misses"))
}

#[test]
fn runs_in_motion_give_one_row_each_with_temporal_metrics_frames_and_cached_references() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = write(dir.path(), "motion.toml", SUITE);
    let cache = dir.path().join("cache");
    let whole = dir.path().join("whole");

    // The plan counts every frame of a run in motion.
    let o = shadowbench(&["report", "--suite", &suite, "--plan"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let planned = 2 * METHODS.len() * FRAMES + METHODS.len();
    assert!(
        stderr(&o).contains(&format!("{} items, {planned} runs", 3 * METHODS.len())),
        "{}",
        stderr(&o)
    );

    let first =
        report(&["report", "--suite", &suite, "--out", path(&whole), "--cache", path(&cache)]);
    assert!(first.contains(&format!("{planned} of {planned} planned runs measured")), "{first}");
    let references = ANIMATED.len() * FRAMES + 1;
    assert_eq!(cache_counts(&first), (0, references as u64), "one reference per frame");

    let json = runs_json(&whole);
    let rows = json["rows"].as_array().expect("rows");
    assert_eq!(rows.len(), 3 * METHODS.len(), "one row per run: {:?}", json["skipped"]);
    let csv_text = std::fs::read_to_string(whole.join("runs.csv")).expect("runs.csv");
    let mut csv = csv::Reader::from_reader(csv_text.as_bytes());
    let header = csv.headers().expect("header").clone();
    let column = |name: &str| header.iter().position(|h| h == name).expect(name);
    let lines: Vec<csv::StringRecord> = csv.records().map(|r| r.expect("a line")).collect();
    assert_eq!(lines.len(), rows.len());
    for (r, line) in rows.iter().zip(&lines) {
        let (scene, method) =
            (r["scene"].as_str().expect("scene"), r["method"].as_str().expect("m"));
        let animated = ANIMATED.contains(&scene);
        let temporal_cells: Vec<&str> = [
            "temporal_error",
            "temporal_p95",
            "boundary_temporal_error",
            "boundary_temporal_p95",
            "temporal_pairs",
            "frames",
        ]
        .iter()
        .map(|c| &line[column(c)])
        .collect();
        if !animated {
            assert!(r.get("temporal").is_none() && r.get("per_frame").is_none(), "{r}");
            assert!(temporal_cells.iter().all(|c| c.is_empty()), "{scene} {method}: {line:?}");
            continue;
        }
        let t = &r["temporal"];
        assert_eq!(t["frames"], FRAMES as u64, "{scene} {method}: {t}");
        assert_eq!(t["per_frame"].as_array().map(Vec::len), Some(FRAMES - 1));
        assert!(t["pixel_pairs"].as_u64().is_some_and(|n| n > 0), "{scene} {method}: {t}");
        assert_eq!(t["reprojected"], scene == "square-slide", "{scene}: the square moves");
        let frames = r["per_frame"].as_array().expect("per_frame");
        assert_eq!(frames.len(), FRAMES);
        assert!(frames[0]["temporal_error"].is_null() && frames[1]["temporal_error"].is_number());
        assert_eq!(r["total_ms"]["n"], FRAMES as u64, "a time per frame");
        assert_eq!(temporal_cells[5], FRAMES.to_string());
        assert_eq!(temporal_cells[4], t["pixel_pairs"].to_string());
        let mean: f64 = temporal_cells[0].parse().expect("temporal_error is a number");
        assert_eq!(Some(mean), t["mean"].as_f64());
        if method == "exact" {
            // The truth against itself: no error but the lit fraction's rounding to f32, and
            // no flicker (the temporal error takes the truth at f32).
            let error = r["metrics"]["mean_abs_error"].as_f64().expect("a number");
            assert!(error < 1e-7, "{scene}: {error}");
            assert_eq!((t["mean"].as_f64(), t["p95"].as_f64()), (Some(0.0), Some(0.0)), "{scene}");
        }

        // The run's frames, its per-frame records and temporal metrics beside its page.
        let stem = stem_of(r);
        let runs = whole.join("runs");
        for kind in ["method", "reference", "error"] {
            for i in 0..FRAMES {
                let file = runs.join(&stem).join("frames").join(format!("{kind}-{i:04}.png"));
                let image =
                    image::open(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
                assert_eq!(image.width(), 48, "{}", file.display());
            }
            let extra = runs.join(&stem).join("frames").join(format!("{kind}-{FRAMES:04}.png"));
            assert!(!extra.exists(), "{}", extra.display());
        }
        let frames_csv =
            std::fs::read_to_string(runs.join(format!("{stem}.frames.csv"))).expect("frames.csv");
        assert_eq!(frames_csv.lines().count(), FRAMES + 1, "a header and a line per frame");
        assert!(frames_csv.starts_with("frame,time,map_res,"), "{frames_csv}");
        let temporal: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(runs.join(format!("{stem}.temporal.json")))
                .expect("temporal.json"),
        )
        .expect("parses");
        assert_eq!(&temporal, t);
    }

    // The same suite again with the same cache: every frame's reference is read, none computed.
    let again = dir.path().join("again");
    let second =
        report(&["report", "--suite", &suite, "--out", path(&again), "--cache", path(&cache)]);
    assert_eq!(cache_counts(&second), (references as u64, 0), "{second}");
    assert_eq!(temporal_numbers(&again), temporal_numbers(&whole));

    // In two shards, merged: the same temporal numbers, and the frames carried over.
    let shards: Vec<std::path::PathBuf> =
        (0..2).map(|k| dir.path().join("shards").join(k.to_string())).collect();
    for (k, out) in shards.iter().enumerate() {
        report(&[
            "report",
            "--suite",
            &suite,
            "--shard",
            &format!("{k}/2"),
            "--out",
            path(out),
            "--cache",
            path(&cache),
        ]);
    }
    let merged = dir.path().join("merged");
    let mut args = vec!["report", "merge"];
    args.extend(shards.iter().map(|s| path(s)));
    args.extend(["--out", path(&merged)]);
    report(&args);
    assert_eq!(temporal_numbers(&merged), temporal_numbers(&whole));
    for r in rows.iter().filter(|r| r.get("temporal").is_some()) {
        let stem = stem_of(r);
        let frame = merged.join(format!("runs/{stem}/frames/error-{:04}.png", FRAMES - 1));
        assert!(frame.is_file(), "{}", frame.display());
        assert!(merged.join(format!("runs/{stem}.temporal.json")).is_file(), "{stem}");
    }
    let merged_csv = std::fs::read_to_string(merged.join("runs.csv")).expect("runs.csv");
    assert!(merged_csv.lines().next().is_some_and(|h| h.contains("temporal_error")));
}
