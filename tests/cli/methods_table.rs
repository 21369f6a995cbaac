//! The registry's table reaches the command line: a method declared there alone (`vsm`) runs
//! through `render` and `compare` with its own flags, which `--help` lists with the methods
//! that use them; its bad values exit 2 naming the flag, and a flag it does not declare is
//! noted and ignored. The shared `--frustum` reaches every shadow-map method and its run record.

use crate::common::{shadowbench, stderr};

fn small(args: &[&str], out: &std::path::Path) -> std::process::Output {
    let mut all: Vec<&str> = args.to_vec();
    all.extend(["--scene", "plane-square", "--width", "48", "--height", "36", "--out"]);
    all.push(out.to_str().expect("utf-8"));
    shadowbench(&all)
}

#[test]
fn a_method_of_the_table_runs_through_render_and_compare_with_its_own_flags() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("render");
    let o = small(&["render", "--method", "vsm", "--filter", "5", "--map-res", "256"], &out);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let run: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).expect("run.json"))
            .expect("JSON");
    assert_eq!(run["method"], "vsm");
    assert_eq!(
        (run["params"]["filter"].as_u64(), run["params"]["map_res"].as_u64()),
        (Some(5), Some(256))
    );
    let stages: Vec<&str> = run["stages"]
        .as_array()
        .expect("stages")
        .iter()
        .filter_map(|s| s["name"].as_str())
        .collect();
    assert!(stages.contains(&"moments") && stages.contains(&"chebyshev test"), "{stages:?}");

    let out = dir.path().join("compare");
    let o = small(&["compare", "--method", "vsm", "--filter", "3", "--ref-rate", "4"], &out);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).expect("metrics"))
            .expect("JSON");
    assert_eq!((m["method"].as_str(), m["params"]["filter"].as_u64()), (Some("vsm"), Some(3)));
    assert!(m["mean_abs_error"].as_f64().is_some_and(|e| (0.0..=1.0).contains(&e)));
}

#[test]
fn its_flags_are_checked_listed_and_noted() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("bad");
    let o = small(&["render", "--method", "vsm", "--filter", "4"], &out);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("error: --filter: must be odd"), "{}", stderr(&o));
    assert!(!out.exists(), "a refused run writes nothing");
    let o = small(&["render", "--method", "vsm", "--min-variance", "x"], &out);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--min-variance"), "{}", stderr(&o));

    let out = dir.path().join("sm");
    let o = small(&["render", "--method", "sm", "--filter", "3"], &out);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("note: sm does not use --filter; ignored"), "{}", stderr(&o));

    let help = shadowbench(&["render", "--help"]);
    let text = String::from_utf8_lossy(&help.stdout);
    assert!(text.contains("vsm: variance shadow map"), "{text}");
    assert!(text.contains("--filter <K>") && text.contains("Used by: vsm."), "{text}");
    let compare = shadowbench(&["compare", "--help"]);
    assert!(String::from_utf8_lossy(&compare.stdout).contains("--min-variance <V>"));
}

/// `--frustum`, a parameter every shadow-map method declares: listed by `--help` with its
/// choices, recorded by the run, and a value outside its choices exits 2 naming it.
#[test]
fn the_light_frustum_is_a_flag_recorded_by_the_run() {
    let help = shadowbench(&["render", "--help"]);
    let text = String::from_utf8_lossy(&help.stdout);
    assert!(text.contains("--frustum <FIT>") && text.contains("view-snapped"), "{text}");

    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("view");
    let o = shadowbench(&[
        "render",
        "--scene",
        "cage",
        "--method",
        "sm",
        "--frustum",
        "view",
        "--width",
        "64",
        "--height",
        "48",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let run: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).expect("run.json"))
            .expect("JSON");
    assert_eq!(run["params"]["frustum"], "view");

    let out = dir.path().join("bad");
    let o = small(&["render", "--method", "sm", "--frustum", "tight"], &out);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--frustum"), "{}", stderr(&o));
    assert!(!out.exists(), "a refused run writes nothing");
}
