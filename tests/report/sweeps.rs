//! Sweeps over anything a method declares: a suite sweeping `pattern`, `slope_bias`, frame
//! sizes and a method's own parameter (`vsm`'s `filter`, a method registered in the table
//! alone) runs, every combination a row of its own with its own files; a parameter the method
//! does not use is refused with its line, and nothing is written.

use crate::common::{shadowbench, stderr, write};

const SUITE: &str = r#"
name = "sweeps"
width = 48
height = 36
warmup = 0
repeats = 1
reference = "exact"
ref_rate = 4
scenes = ["cage"]

[[run]]
method = "pan09"
map_res = 128
rate = 4
pattern = ["grid", "rotated"]

[[run]]
method = "sm"
map_res = 128
slope_bias = [1, 4]
width = [48, 32]
height = [36, 24]

[[run]]
method = "vsm"
map_res = 128
filter = [1, 5]

[[grid]]
title = "a method's own parameter in a panel"
scene = "cage"
inset = [0.4, 0.4, 0.2, 0.2]
panels = [{ method = "vsm", map_res = 128, filter = 5 }, { method = "pan09", pattern = "rotated" }]
"#;

#[test]
fn a_suite_sweeps_patterns_biases_sizes_and_a_methods_own_parameter() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = write(dir.path(), "sweeps.toml", SUITE);
    let out = dir.path().join("out");
    let o = shadowbench(&["report", "--suite", &suite, "--out", out.to_str().expect("utf-8")]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("runs.json")).expect("runs.json"))
            .expect("valid JSON");
    let rows = json["rows"].as_array().expect("rows");
    let got: Vec<(String, String, u64, String)> = rows
        .iter()
        .map(|r| {
            let p = &r["params"];
            let swept = match r["method"].as_str() {
                Some("pan09") => p["pattern"].to_string(),
                Some("sm") => p["slope_bias"].to_string(),
                _ => p["filter"].to_string(),
            };
            (
                r["scene"].as_str().unwrap_or_default().to_owned(),
                r["method"].as_str().unwrap_or_default().to_owned(),
                r["width"].as_u64().unwrap_or_default(),
                swept,
            )
        })
        .collect();
    let row = |scene: &str, method: &str, w: u64, v: &str| {
        (scene.to_owned(), method.to_owned(), w, v.to_owned())
    };
    let expected = vec![
        row("cage", "pan09", 48, "\"grid\""),
        row("cage", "pan09", 48, "\"rotated\""),
        row("cage", "sm", 48, "1.0"),
        row("cage", "sm", 48, "4.0"),
        row("cage", "vsm", 48, "1"),
        row("cage", "vsm", 48, "5"),
        row("cage 32x24", "sm", 32, "1.0"),
        row("cage 32x24", "sm", 32, "4.0"),
    ];
    assert_eq!(got, expected);
    // Every row has a page and a visibility file of its own.
    let files = |dir: &str, ext: &str| {
        std::fs::read_dir(out.join(dir))
            .expect("the report's folder")
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().ends_with(ext))
            .count()
    };
    assert_eq!(files("runs", ".html"), rows.len(), "a page per run");
    assert_eq!(files("visibility", ".exr"), rows.len(), "a visibility buffer per run");
    // The frame sizes are two frames of the scene, each with its reference.
    let scenes: Vec<&str> = json["scenes"]
        .as_array()
        .expect("scenes")
        .iter()
        .filter_map(|s| s["scene"].as_str())
        .collect();
    assert_eq!(scenes, ["cage", "cage 32x24"]);
    assert!(out.join("grids/grid-1.png").exists(), "the grid of panels is drawn");
    assert_eq!(json["skipped"], serde_json::json!([]), "every panel ran");
}

#[test]
fn a_parameter_the_method_does_not_use_is_refused_with_its_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (run, needle) in [
        (
            "method = \"sm\"\nrate = [4]",
            "bad.toml: line 5: `run[0].rate`: `sm` does not use `rate`",
        ),
        ("method = \"vsm\"\nfilter = [3, 4]", "bad.toml: line 5: `run[0].filter`: must be odd"),
    ] {
        let text = format!("name = \"x\"\nscenes = [\"cage\"]\n[[run]]\n{run}\n");
        let suite = write(dir.path(), "bad.toml", &text);
        let out = dir.path().join("out");
        let o = shadowbench(&["report", "--suite", &suite, "--out", out.to_str().expect("utf-8")]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        let e = stderr(&o);
        assert!(e.contains(needle), "{e}");
        assert!(!out.exists(), "a refused suite writes nothing");
    }
}
