//! `shadowbench report`: a suite file runs, and its CSV and JSON parse back with every run.

use crate::common::{shadowbench, stderr, write};

const SUITE: &str = r#"
name = "tiny"
width = 64
height = 48
warmup = 1
repeats = 6
ref_rate = 4
scenes = ["plane-square", "hairball"]

[[run]]
method = "sm"
map_res = [64, 128]
device = ["cpu", "gpu"]

[[run]]
method = "pcf-bs-fast-2x2"
map_res = [128]
depth_bits = [8, 32]

[[grid]]
title = "result, reference and error"
scene = "plane-square"
inset = [0.4, 0.4, 0.25, 0.25]
reference = true
panels = [{ method = "sm", map_res = 64 }, { method = "pcf-gems4", map_res = 64 }]

[[table]]
paper = "aila-laine-table1"
scenes = ["random-1k", "plane-square"]
width = 64
height = 48

[[table]]
paper = "cost-against-triangles"
scenes = ["plane-square", "random-1k"]
width = 64
height = 48
"#;

#[test]
fn a_suite_file_writes_tables_that_parse_back() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = write(dir.path(), "tiny.toml", SUITE);
    let out = dir.path().join("out");
    let o = shadowbench(&["report", "--suite", &suite, "--out", out.to_str().expect("utf-8")]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // Standard error is a pipe here: a progress line per frame, and one at the end. The
    // tables' runs on plane-square at the suite's frame join its frame; random-1k's, of both
    // tables, share one.
    let log = stderr(&o);
    let starts = |p: &str| log.lines().filter(|l| l.starts_with(p)).count();
    assert_eq!(starts("frame 1/3 plane-square 64x48: 0/30 runs done, "), 1, "{log}");
    assert_eq!(starts("frame 2/3 hairball 64x48: 15/30 runs done, "), 1, "{log}");
    assert_eq!(starts("frame 3/3 random-1k 64x48: 21/30 runs done, "), 1, "{log}");
    assert_eq!(starts("done: 30/30 runs done, "), 1, "{log}");
    let last = String::from_utf8_lossy(&o.stdout);
    assert!(
        last.contains("30 of 30 planned runs measured") || !methods::registry::HAS_GPU,
        "{last}"
    );

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("runs.json")).expect("runs.json"))
            .expect("valid JSON");
    let rows = json["rows"].as_array().expect("rows");
    // Two of the six combinations are on the GPU, not run by a build without GPU kernels.
    let combos = if methods::registry::HAS_GPU { 6 } else { 4 };
    assert_eq!(rows.len(), 2 * combos, "two scenes, {combos} combinations");
    for r in rows {
        let mean = r["metrics"]["mean_abs_error"].as_f64().expect("metric");
        assert!((0.0..=1.0).contains(&mean));
        let t = &r["total_ms"];
        assert!(t["min"].as_f64() <= t["median"].as_f64());
        assert!(t["median"].as_f64() <= t["max"].as_f64());
        assert!(!r["stages"].as_array().expect("stages").is_empty());
        // Lecocq et al.'s pixel match: a number for binary results (`sm`), null for filtered
        // ones (`pcf-bs-fast-2x2`).
        let lecocq = &r["pixel_match_lecocq"];
        match r["method"].as_str() {
            Some("sm") if r["scene"] == "plane-square" => {
                assert!(lecocq.as_f64().is_some_and(|p| (0.9..=1.0).contains(&p)), "{r}")
            }
            Some("pcf-bs-fast-2x2") => assert!(lecocq.is_null(), "{r}"),
            _ => {}
        }
    }
    let by_scene = |s: &str| rows.iter().filter(|r| r["scene"] == s).count();
    assert_eq!((by_scene("plane-square"), by_scene("hairball")), (combos, combos));
    // Exact where it applies, ray traced where the scene has transparency.
    let reference =
        |s: &str| rows.iter().find(|r| r["scene"] == s).expect("row")["reference"].clone();
    assert_eq!(reference("plane-square"), "exact");
    assert_eq!(reference("hairball"), "raytrace");
    // Against exact, the metrics are taken over its shadow-only pixels (planar and surface),
    // not over the edge pixels it ray traces: as many as `exact` classifies so at 64 x 48.
    let classes = dir.path().join("classes");
    let o = shadowbench(&[
        "render",
        "--scene",
        "plane-square",
        "--method",
        "exact",
        "--width",
        "64",
        "--height",
        "48",
        "--out",
        classes.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let run: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(classes.join("run.json")).expect("read"))
            .expect("JSON");
    let count = |c: &str| run["pixel_classes"][c].as_u64().expect("count");
    assert!(count("edge") > 0, "plane-square's square has silhouettes");
    for r in rows.iter().filter(|r| r["scene"] == "plane-square") {
        let n = r["metrics"]["evaluated_pixels"].as_u64();
        assert_eq!(n, Some(count("planar") + count("surface")), "{}", r["metrics"]);
    }
    assert!(json["machine"]["cores"].as_u64() >= Some(1));
    // Provenance: what produced the report, from which source, when, with which compiler.
    let p = &json["provenance"];
    let commit = p["commit"].as_str().expect("commit");
    assert_eq!(commit.len(), 40, "the tests run in a checkout: {p}");
    assert_eq!(p["version"], env!("CARGO_PKG_VERSION"));
    assert!(p["dirty"].is_boolean() && p["threads"].as_u64() >= Some(1), "{p}");
    assert!(p["rustc"].as_str().is_some_and(|r| r.starts_with("rustc ")), "{p}");
    assert!(p["command"].as_str().is_some_and(|c| c.contains("report --suite")), "{p}");
    assert!(p["timestamp"].as_str().is_some_and(|t| t.ends_with('Z')), "{p}");
    assert_eq!(p["adapter"], json["machine"]["gpu"], "the GPU's adapter: {p}");

    // runs.csv is tidy: unique column names, a line per run, numeric cells under units.
    let mut reader = csv::Reader::from_path(out.join("runs.csv")).expect("runs.csv");
    let header: Vec<String> = reader.headers().expect("header").iter().map(str::to_owned).collect();
    let unique: std::collections::BTreeSet<&String> = header.iter().collect();
    assert_eq!(unique.len(), header.len(), "duplicate column names: {header:?}");
    let col = |name: &str| header.iter().position(|h| h == name).expect(name);
    let lines: Vec<csv::StringRecord> =
        reader.records().map(|r| r.expect("a well-formed CSV line")).collect();
    assert_eq!(lines.len(), rows.len());
    let numeric = |h: &str| {
        h.ends_with("_ms")
            || h.ends_with("_px")
            || h.ends_with("_error")
            || h.starts_with("stage_ms.")
            || ["rmse", "pixel_match", "flip_mean", "evaluated_pixels", "boundary_pixels"]
                .contains(&h)
    };
    assert!(header.iter().filter(|h| h.starts_with("stage_ms.")).count() >= 2, "{header:?}");
    assert!(header.contains(&"counter.boundary_pixels".to_owned()), "{header:?}");
    for l in &lines {
        assert_eq!(l.len(), header.len());
        for (h, cell) in header.iter().zip(l.iter()) {
            if numeric(h) {
                assert!(cell.is_empty() || cell.parse::<f64>().is_ok(), "{h}: `{cell}`");
            }
            if h.starts_with("counter.") {
                let _: u64 = cell.parse().unwrap_or_else(|_| panic!("{h}: `{cell}`"));
            }
        }
        let err: f64 = l[col("mean_abs_error")].parse().expect("number");
        assert!((0.0..=1.0).contains(&err));
        let ms = |c: &str| -> f64 { l[col(c)].parse().expect(c) };
        // Six timed runs at least: the median's 95 % interval is there, on both clocks.
        for clock in ["time", "cpu"] {
            let at = |q: &str| ms(&format!("{clock}_{q}_ms"));
            assert!(at("min") <= at("ci_low") && at("ci_low") <= at("median"), "{clock}");
            assert!(at("median") <= at("ci_high") && at("ci_high") <= at("max"), "{clock}");
        }
        assert!(l[col("timed_runs")].parse::<u32>().is_ok_and(|n| n >= 6));
        assert!(["true", "false"].contains(&&l[col("contended")]));
        // A run without boundary pixels has no boundary error: an empty cell, not 0.
        let boundary: u64 = l[col("boundary_pixels")].parse().expect("count");
        assert_eq!(boundary == 0, l[col("boundary_mean_abs_error")].is_empty());
        assert_eq!((&l[col("commit")], &l[col("version")]), (commit, env!("CARGO_PKG_VERSION")));
    }
    // The error's distribution: a share per threshold, never growing with it, and one minus
    // the pixel match at half an 8-bit step.
    let shares: Vec<usize> =
        (0..header.len()).filter(|&k| header[k].starts_with("share_error_over.")).collect();
    assert_eq!(shares.len(), analysis::metrics::EXCEEDANCE_THRESHOLDS.len(), "{header:?}");
    let at_match = col(&format!("share_error_over.{}", analysis::metrics::MATCH_TOLERANCE));
    for l in &lines {
        let v: Vec<f64> = shares.iter().map(|&k| l[k].parse().expect("a share")).collect();
        assert!(v.windows(2).all(|w| w[0] >= w[1]) && v.iter().all(|s| (0.0..=1.0).contains(s)));
        let matched: f64 = l[col("pixel_match")].parse().expect("pixel match");
        let over: f64 = l[at_match].parse().expect("share");
        assert!((over + matched - 1.0).abs() < 1e-12, "{over} + {matched}");
    }
    let bits: Vec<&str> = lines.iter().map(|l| &l[col("depth_bits")]).collect();
    assert!(bits.contains(&"8") && bits.contains(&"32") && bits.contains(&""));

    let md = std::fs::read_to_string(out.join("report.md")).expect("report.md");
    assert!(md.contains("## plane-square") && md.contains("pcf-bs-fast-2x2"), "{md}");
    assert!(md.contains(&format!("at commit {commit}")), "provenance in the header: {md}");
    // report.md holds what the README says: the Pareto fronts and the sentences per method
    // first, the charts as images (every one a file of the report), the budget table.
    assert!(md.contains("## Pareto fronts: mean error against CPU time"), "{md}");
    assert!(md.contains("## What the runs say of each method"), "{md}");
    assert!(md.contains("## Best error within a time budget"), "{md}");
    assert!(md.contains("| scene | method | <= 10 CPU ms |"), "{md}");
    for chart in ["error-vs-time-plane-square-pcf", "error-vs-time-plane-square-bs"] {
        assert!(md.contains(&format!("](plots/{chart}.png)")), "no {chart} in {md}");
    }
    let images: Vec<&str> = md.split("](").skip(1).filter_map(|s| s.split(')').next()).collect();
    assert!(images.len() >= 5, "{images:?}");
    for png in images {
        assert!(out.join(png).is_file(), "report.md shows {png}, which is missing");
    }
    // CPU and GPU side by side: each sm run on both devices, paired, the adapter named. A
    // build without GPU kernels says it did not run them, and why.
    let devices: Vec<&str> = lines.iter().map(|l| &l[col("device")]).collect();
    if methods::registry::HAS_GPU {
        assert_eq!(devices.iter().filter(|d| **d == "gpu").count(), 4, "{devices:?}");
        assert!(
            json["machine"]["gpu"].as_str().is_some_and(|g| !g.is_empty()),
            "{}",
            json["machine"]
        );
        let side = md.split("## CPU and GPU").nth(1).expect("a CPU and GPU section");
        let pairs: Vec<&str> =
            side.lines().filter(|l| l.starts_with("| plane-square | sm ")).collect();
        assert_eq!(pairs.len(), 2, "{side}");
        for l in pairs {
            let cells: Vec<&str> = l.split(" | ").collect();
            let time_of = |c: &str| -> f64 {
                c.split_whitespace().next().expect("a time").parse().expect("ms")
            };
            // GPU time with its G-buffer, then without it; the ratio sets CPU against the latter.
            let (with, without) = (time_of(cells[4]), time_of(cells[5]));
            assert!(0.0 < without && without <= with, "{l}");
        }
    } else {
        assert!(!devices.contains(&"gpu"), "{devices:?}");
        assert!(json["skipped"].to_string().contains("no GPU kernels"), "{}", json["skipped"]);
    }
    let grids = json["grids"].as_array().expect("grids");
    assert_eq!(grids.len(), 1);
    let grid = image::open(out.join(grids[0]["png"].as_str().expect("path"))).expect("a PNG");
    assert!(grid.width() > 4 * 64, "four panels: two methods, reference, error");
    let exrs = std::fs::read_dir(out.join("visibility")).expect("visibility").count();
    assert_eq!(exrs, rows.len());

    // The paper's table: our figures beside the paper's, its hardware named.
    let tables = json["tables"].as_array().expect("tables");
    assert_eq!(tables.len(), 2);
    let t = &tables[0];
    assert!(t["paper_hardware"].as_str().expect("hardware").contains("Pentium 4"));
    let header: Vec<&str> =
        t["header"].as_array().expect("header").iter().filter_map(|h| h.as_str()).collect();
    assert_eq!(header, ["", "random-1k ours", "paper (1K)", "plane-square ours", "paper (10K)"]);
    let table_rows = t["rows"].as_array().expect("rows");
    assert_eq!(table_rows.len(), 9);
    let cell = |row: usize, col: usize| table_rows[row][col].as_str().expect("cell").to_owned();
    assert_eq!((cell(0, 1), cell(0, 2)), ("1.0K".to_owned(), "1K".to_owned()));
    assert_eq!(cell(0, 3), "4", "plane-square has four triangles");
    let total: f64 = cell(8, 1).parse().expect("total ms");
    assert!(total > 0.0);
    assert_eq!(cell(8, 2), "675");
    assert!(md.contains("Paper's figures measured on: 1.6 GHz Mobile Pentium 4"), "{md}");
    // The table's CSV: the same cells as numbers in full, the paper's in their own columns.
    let mut reader =
        csv::Reader::from_path(out.join("tables/aila-laine-table1.csv")).expect("table CSV");
    let header: Vec<String> = reader.headers().expect("header").iter().map(str::to_owned).collect();
    assert_eq!(header, ["", "random-1k ours", "paper (1K)", "plane-square ours", "paper (10K)"]);
    let records: Vec<csv::StringRecord> = reader.records().map(|r| r.expect("a line")).collect();
    assert_eq!(records.len(), 9);
    for r in &records {
        for cell in r.iter().skip(1) {
            assert!(cell.is_empty() || cell.parse::<f64>().is_ok(), "`{cell}` in {r:?}");
        }
    }
    let triangles: f64 = records[0][1].parse().expect("our triangles");
    assert!((950.0..1050.0).contains(&triangles), "1.0K in full: {triangles}");
    assert_eq!(&records[0][2], "1000", "the paper's 1K in full");
    assert_eq!(&records[0][3], "4");

    // Cost against work: every method's time per scene, the fitted exponent, and its chart
    // under the table on the page.
    let cost = &tables[1];
    let header: Vec<&str> =
        cost["header"].as_array().expect("header").iter().filter_map(|h| h.as_str()).collect();
    assert_eq!(header, ["", "plane-square 64x48", "random-1k 64x48", "fitted exponent"]);
    let rows = cost["rows"].as_array().expect("rows");
    assert_eq!(rows.len(), 11, "triangles, pixels, the G-buffer and eight runs");
    let labels: Vec<&str> = rows.iter().filter_map(|r| r[0].as_str()).collect();
    assert!(labels.contains(&"ftizb 1x (ms)") && labels.contains(&"ftizb 32x (ms)"), "{labels:?}");
    for r in &rows[2..] {
        let exponent: f64 = r[3].as_str().expect("cell").parse().expect("an exponent");
        assert!(exponent.is_finite(), "{r}");
    }
    let chart = image::open(out.join("plots/cost-against-triangles.png")).expect("chart");
    assert!(chart.width() > 400, "a chart, not a stub");
    assert!(out.join("plots/cost-against-triangles.svg").is_file());
    let html = std::fs::read_to_string(out.join("index.html")).expect("index.html");
    assert!(html.contains("<img src=\"plots/cost-against-triangles.png\""), "chart on the page");
    let csv = std::fs::read_to_string(out.join("tables/cost-against-triangles.csv")).expect("csv");
    assert!(csv.starts_with(",plane-square 64x48,random-1k 64x48,fitted exponent\n"), "{csv}");
}

#[test]
fn bad_suites_are_named() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let bad = write(dir.path(), "bad.toml", "name = \"x\"\nscenes = [\"cage\"]\nrepeat = 2\n");
    for (suite, needle) in [(bad.as_str(), "repeat"), ("no-such-suite", "no-such-suite")] {
        let o = shadowbench(&["report", "--suite", suite, "--out", "/tmp/unused"]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{}", stderr(&o));
    }
}

/// A suite whose runs name an unknown method or scene, or a value a method refuses, is
/// refused whole before anything runs (it used to run the rest and report "0 runs"): one
/// message with the file, the line, the key and the allowed values, and no output written.
#[test]
fn suites_with_unknown_names_or_bad_values_are_refused_before_running() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let base = "name = \"x\"\nwidth = 32\nheight = 24\nrepeats = 1\nscenes = [\"cage\"]\n\
                [[run]]\nmethod = \"sm\"\n";
    let cases: Vec<(&str, String, &[&str])> = vec![
        ("method", base.replace("\"sm\"", "\"magic\""), &["line 7", "run[0].method", "pan09"]),
        (
            "scene",
            base.replace("[\"cage\"]", "[\"cage\", \"no-such-scene\"]"),
            &["line 5", "scenes[1]", "no-such-scene", "plane-square"],
        ),
        (
            "rate",
            format!("{base}[[run]]\nmethod = \"spsm\"\nrate = [16, 256]\n"),
            &["line 10", "run[1].rate", "1, 4, 8, 16, 32, 64, 128 samples", "got 256"],
        ),
        (
            "map-res",
            format!("{base}map_res = [64, 0]\n"),
            &["line 8", "run[0].map_res", "1..=16384"],
        ),
    ];
    for (name, text, needles) in cases {
        let file = write(dir.path(), &format!("{name}.toml"), &text);
        let out = dir.path().join(format!("out-{name}"));
        let o = shadowbench(&["report", "--suite", &file, "--out", out.to_str().expect("utf-8")]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(&file), "{name}: the file is not named: {err}");
        for n in needles {
            assert!(err.contains(n), "{name}: `{n}` not in: {err}");
        }
        assert_eq!(err.lines().filter(|l| l.starts_with("error")).count(), 1, "{name}: {err}");
        assert!(!out.join("runs.json").exists(), "{name}: the suite ran");
    }
}

#[test]
fn index_html_shows_only_files_the_report_wrote() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = write(dir.path(), "tiny.toml", SUITE);
    let out = dir.path().join("out");
    let o = shadowbench(&["report", "--suite", &suite, "--out", out.to_str().expect("utf-8")]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let page = std::fs::read_to_string(out.join("index.html")).expect("index.html");
    let images = page.matches("<img ").count();
    assert!(images >= 4, "{images} images in the page");
    for png in page.split("src=\"").skip(1).filter_map(|s| s.split('"').next()) {
        assert!(out.join(png).is_file(), "{png} referenced but missing");
    }
    // Per scene, the error distribution of the Pareto runs; per run, its page and files.
    assert!(page.contains("src=\"plots/error-distribution-plane-square.png\""), "{page}");
    let runs = std::fs::read_dir(out.join("runs")).expect("runs/").count();
    let rows = std::fs::read_to_string(out.join("runs.csv")).expect("csv").lines().count() - 1;
    assert_eq!(runs, 5 * rows, "a page, an image, an error map, run.json and metrics.json each");
}

/// `report --baseline DIR` sets the report against an earlier one: a summary at the top of
/// report.md and index.html, every run in baseline.md, the counts on standard output; a
/// baseline folder without a report, or an output folder holding a foreign file, is bad input.
#[test]
fn a_report_is_set_against_its_baseline_and_foreign_folders_are_refused() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = write(
        dir.path(),
        "base.toml",
        "name = \"base\"\nwidth = 48\nheight = 36\nwarmup = 0\nrepeats = 1\n\
         scenes = [\"plane-square\"]\n[[run]]\nmethod = \"sm\"\nmap_res = [64, 128]\n",
    );
    let first = dir.path().join("first");
    let second = dir.path().join("second");
    let run = |out: &std::path::Path, baseline: Option<&std::path::Path>| {
        let mut args = vec!["report", "--suite", &suite, "--out", out.to_str().expect("utf-8")];
        if let Some(b) = baseline {
            args.extend(["--baseline", b.to_str().expect("utf-8")]);
        }
        shadowbench(&args)
    };
    assert!(run(&first, None).status.success());
    let o = run(&second, Some(&first));
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("2 runs compared (0 new, 0 dropped)"), "{out}");
    let md = std::fs::read_to_string(second.join("report.md")).expect("report.md");
    assert!(md.contains("## Against the baseline"), "{md}");
    assert!(second.join("baseline.md").exists());
    let html = std::fs::read_to_string(second.join("index.html")).expect("index.html");
    assert!(html.contains("id=\"baseline\""));
    // Writing again into a report's folder replaces it; a foreign file is refused.
    assert!(run(&second, Some(&first)).status.success());
    std::fs::write(second.join("notes.txt"), "mine").expect("writes");
    let o = run(&second, None);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("notes.txt"), "{}", stderr(&o));
    // Thresholds that are not numbers of their kind are bad input, named.
    for (flag, value) in [("--baseline-tolerance", "-0.5"), ("--baseline-min-ms", "NaN")] {
        let o = shadowbench(&[
            "report",
            "--suite",
            &suite,
            "--out",
            dir.path().join("fourth").to_str().expect("utf-8"),
            "--baseline",
            first.to_str().expect("utf-8"),
            flag,
            value,
        ]);
        assert_eq!(o.status.code(), Some(2), "{flag} {value}");
        assert!(stderr(&o).contains(flag), "{}", stderr(&o));
    }
    // A baseline whose times are not times, or of a later version, is refused naming the run
    // and the field.
    let edited = dir.path().join("edited");
    std::fs::create_dir_all(&edited).expect("folder");
    let text = std::fs::read_to_string(first.join("runs.json")).expect("runs.json");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
    v["rows"][0]["total_ms"]["median"] = serde_json::json!(-3.0);
    std::fs::write(edited.join("runs.json"), v.to_string()).expect("writes");
    let o = run(&dir.path().join("fifth"), Some(&edited));
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("total_ms.median") && stderr(&o).contains("sm"), "{}", stderr(&o));
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
    v["provenance"]["version"] = serde_json::json!("99.0.0");
    std::fs::write(edited.join("runs.json"), v.to_string()).expect("writes");
    let o = run(&dir.path().join("fifth"), Some(&edited));
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("99.0.0"), "{}", stderr(&o));
    assert!(!dir.path().join("fifth").exists(), "refused before anything is written");
    let o = run(&dir.path().join("third"), Some(&dir.path().join("nowhere")));
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--baseline") && stderr(&o).contains("runs.json"),
        "{}",
        stderr(&o)
    );
}

/// A suite's `[[external]]` entries: an outside renderer's result (here `sm`'s own, from
/// `render`) is planned, scored like the `sm` run, listed in runs.json and the runs table
/// marked external, and merged back from a shard; without a time it is in runs.json's
/// `untimed` and the table only.
#[test]
fn outside_results_of_a_suite_are_scored_planned_and_merged() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let sm = d.join("sm");
    let render = [
        "render",
        "--scene",
        "plane-square",
        "--method",
        "sm",
        "--width",
        "32",
        "--height",
        "24",
        "--out",
        sm.to_str().expect("utf-8"),
    ];
    assert!(shadowbench(&render).status.success());
    let suite = write(
        d,
        "outside.toml",
        "name = \"outside\"\nwidth = 32\nheight = 24\nwarmup = 0\nrepeats = 1\n\
         scenes = [\"plane-square\"]\n[[run]]\nmethod = \"sm\"\n\
         [[external]]\nname = \"mine\"\ntime_ms = 1.5\nfiles = { plane-square = \"sm/visibility.exr\" }\n\
         [[external]]\nname = \"later\"\nfiles = { plane-square = \"sm/visibility.exr\" }\n",
    );
    let o = shadowbench(&["report", "--suite", &suite, "--plan"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let plan = String::from_utf8_lossy(&o.stdout).into_owned();
    assert_eq!(plan.matches("\"kind\":\"external\"").count(), 2, "{plan}");
    assert!(stderr(&o).contains("3 items, 3 runs"), "{}", stderr(&o));

    let out = d.join("out");
    let o = shadowbench(&["report", "--suite", &suite, "--out", out.to_str().expect("utf-8")]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("3 of 3 planned runs measured"));
    let runs = |dir: &std::path::Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join("runs.json")).expect("runs.json"))
            .expect("JSON")
    };
    let json = runs(&out);
    let rows = json["rows"].as_array().expect("rows");
    let by = |m: &str| rows.iter().find(|r| r["method"] == m).unwrap_or_else(|| panic!("{m}"));
    assert_eq!(by("mine")["metrics"], by("sm")["metrics"]);
    assert_eq!((&by("mine")["external"], &by("sm")["external"]), (&true.into(), &false.into()));
    assert_eq!(by("mine")["total_ms"]["median"], 1.5);
    let untimed = json["untimed"].as_array().expect("untimed");
    assert_eq!(untimed.len(), 1);
    assert_eq!(
        (&untimed[0]["method"], &untimed[0]["metrics"]),
        (&"later".into(), &by("sm")["metrics"])
    );
    let page = std::fs::read_to_string(out.join("index.html")).expect("index.html");
    assert!(page.contains("mine (external)") && page.contains("later (external)"), "{page}");
    assert!(page.contains("not given"), "{page}");
    let mut reader = csv::Reader::from_path(out.join("runs.csv")).expect("runs.csv");
    let header = reader.headers().expect("header").clone();
    let at = |name: &str| header.iter().position(|h| h == name).expect(name);
    let lines: Vec<csv::StringRecord> = reader.records().map(|r| r.expect("a line")).collect();
    let marked: Vec<(&str, &str)> =
        lines.iter().map(|l| (&l[at("method")], &l[at("external")])).collect();
    assert_eq!(marked, [("sm", "false"), ("mine", "true")], "timed runs only");
    let md = std::fs::read_to_string(out.join("report.md")).expect("report.md");
    assert!(md.contains("| mine (external) |") && md.contains("| later (external) |"), "{md}");
    assert!(out.join("runs/plane-square-mine.html").is_file());
    assert!(!out.join("runs/plane-square-later.html").exists());

    let shard = d.join("shard");
    let o = shadowbench(&[
        "report",
        "--suite",
        &suite,
        "--shard",
        "0/1",
        "--out",
        shard.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let merged = d.join("merged");
    let o = shadowbench(&[
        "report",
        "merge",
        shard.to_str().expect("utf-8"),
        "--out",
        merged.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m = runs(&merged);
    assert_eq!(m["rows"].as_array().expect("rows").len(), 2);
    assert_eq!(m["untimed"].as_array().expect("untimed").len(), 1);
}
