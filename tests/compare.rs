//! `compare` and references run through `render`: the CLI contract of DESIGN.md.

mod common;
use common::{shadowbench, stderr};

const METRIC_FIELDS: &[&str] = &[
    "reference",
    "ref_rate",
    "evaluated_pixels",
    "mean_abs_error",
    "rmse",
    "max_abs_error",
    "pixel_match",
    "boundary_pixels",
    "boundary_mean_abs_error",
    "flip_mean",
];

fn compare(args: &[&str]) -> (std::process::Output, tempfile::TempDir) {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("cmp");
    let mut all =
        vec!["compare", "--width", "64", "--height", "48", "--out", out.to_str().expect("utf-8")];
    all.extend_from_slice(args);
    (shadowbench(&all), dir)
}

#[test]
fn compare_against_exact_writes_metrics_and_error_images() {
    let (o, dir) =
        compare(&["--scene", "plane-square", "--method", "sm", "--map-res", "256", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = dir.path().join("cmp");
    for f in ["metrics.json", "error.png", "error_boundary.png", "visibility.exr", "run.json"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).expect("read"))
            .expect("JSON");
    let printed: serde_json::Value = serde_json::from_slice(&o.stdout).expect("stdout JSON");
    assert_eq!(m, printed);
    for f in METRIC_FIELDS {
        assert!(m.get(*f).is_some(), "{f} missing from metrics.json");
    }
    assert_eq!(m["reference"], "exact");
    assert!(m["ref_rate"].is_null());
    let evaluated = m["evaluated_pixels"].as_u64().expect("count");
    assert!(evaluated > 1000, "{evaluated}");
    let mean = m["mean_abs_error"].as_f64().expect("number");
    assert!(mean > 0.0 && mean < 0.1, "sm has some error, but not much: {mean}");
    assert!(m["boundary_pixels"].as_u64().expect("count") > 10);
    let flip = m["flip_mean"].as_f64().expect("number");
    assert!(flip > 0.0 && flip < 1.0, "{flip}");
}

#[test]
fn compare_against_raytrace_names_its_rate() {
    let (o, dir) = compare(&[
        "--scene",
        "cage",
        "--method",
        "sm",
        "--reference",
        "raytrace",
        "--ref-rate",
        "16",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("cmp/metrics.json")).expect("read"),
    )
    .expect("JSON");
    assert_eq!(m["reference"], "raytrace");
    assert_eq!(m["ref_rate"], 16);
}

#[test]
fn references_render_like_methods() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (method, rate) in [("exact", None), ("raytrace", Some("4"))] {
        let out = dir.path().join(method);
        let mut args = vec![
            "render",
            "--scene",
            "plane-square",
            "--method",
            method,
            "--width",
            "48",
            "--height",
            "32",
            "--out",
            out.to_str().expect("utf-8"),
        ];
        if let Some(r) = rate {
            args.extend_from_slice(&["--rate", r]);
        }
        let o = shadowbench(&args);
        assert!(o.status.success(), "{method}: {}", stderr(&o));
        let run: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).expect("read"))
                .expect("JSON");
        assert_eq!(run["method"], method);
        if method == "raytrace" {
            assert_eq!(run["params"]["rate"], 4);
            assert!(run["counters"]["rays_traced"].as_u64().expect("count") >= 48 * 32 * 4);
        }
    }
}

#[test]
fn references_that_do_not_apply_or_bad_rates_are_bad_input() {
    let cases: &[(&[&str], &str)] = &[
        (&["--scene", "hairball", "--method", "sm"], "exact"),
        (
            &[
                "--scene",
                "plane-square",
                "--method",
                "sm",
                "--reference",
                "raytrace",
                "--ref-rate",
                "3",
            ],
            "--ref-rate",
        ),
        (&["--scene", "plane-square", "--method", "raytrace", "--rate", "5"], "--rate"),
    ];
    for (args, needle) in cases {
        let (o, _dir) = compare(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{args:?}: expected `{needle}` in {}", stderr(&o));
    }
}
