//! Frames out, results in: `frame` writes what another renderer needs, `compare
//! --visibility` scores that renderer's result exactly as a method's, and `compare`'s
//! reference cache computes a scene's reference once.

use crate::common::{shadowbench, stderr};
use std::path::Path;

fn path(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn metrics(dir: &Path) -> reports::MetricsRecord {
    let text = std::fs::read_to_string(dir.join("metrics.json")).expect("metrics.json");
    serde_json::from_str(&text).expect("a metrics record")
}

/// The channels of the EXR at `p` by name, as f64 (u32 channels converted).
fn exr_channels(p: &Path) -> (usize, usize, std::collections::BTreeMap<String, Vec<f64>>) {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(p)
        .expect("reads the EXR");
    let layer = &image.layer_data[0];
    let channels = layer
        .channel_data
        .list
        .iter()
        .map(|c| {
            let values = match &c.sample_data {
                FlatSamples::U32(v) => v.iter().map(|&x| f64::from(x)).collect(),
                other => other.values_as_f32().map(f64::from).collect(),
            };
            (c.name.to_string(), values)
        })
        .collect();
    (layer.size.width(), layer.size.height(), channels)
}

/// `m` (row-major) times the column vector `v`.
fn mul(m: &serde_json::Value, v: [f64; 4]) -> [f64; 4] {
    let row = |r: usize| (0..4).map(|c| m[r][c].as_f64().expect("number") * v[c]).sum::<f64>();
    [row(0), row(1), row(2), row(3)]
}

/// The done-when of the outside results: `frame`, then `compare --visibility` on `sm`'s
/// own visibility.exr gives exactly the comparison `compare --method sm` gives. The frame's
/// matrices take every G-buffer position to its pixel centre and its depth.
#[test]
fn an_outside_result_scores_exactly_as_the_method_that_made_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let size = ["--width", "64", "--height", "48"];
    let scene = ["--scene", "city"];
    let frame = d.join("frame");
    let o = shadowbench(&[&["frame"][..], &scene, &size, &["--out", path(&frame)]].concat());
    assert!(o.status.success(), "{}", stderr(&o));

    let f: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(frame.join("frame.json")).expect("read"))
            .expect("frame.json");
    assert_eq!((f["width"].as_u64(), f["height"].as_u64()), (Some(64), Some(48)));
    assert_eq!(f["light"]["kind"], "directional");
    assert!(f["conventions"]["matrices"].as_str().expect("text").contains("row-major"));
    let (w, h, g) = exr_channels(&frame.join("gbuffer.exr"));
    assert_eq!((w, h), (64, 48));
    let projection = &f["camera"]["projection"];
    let (mut covered, mut background) = (0, 0);
    for (k, &triangle) in g["triangle"].iter().enumerate() {
        if triangle == f64::from(u32::MAX) {
            assert_eq!(g["depth"][k], f64::INFINITY, "pixel {k}");
            background += 1;
            continue;
        }
        covered += 1;
        let p = [g["position.x"][k], g["position.y"][k], g["position.z"][k], 1.0];
        let view = mul(&projection["world_to_view"], p);
        let clip = mul(&projection["projection"], view);
        let (x, y) =
            ((1.0 + clip[0] / clip[3]) * 0.5 * 64.0, (1.0 - clip[1] / clip[3]) * 0.5 * 48.0);
        let centre = ((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
        // Positions are stored as f32: a thousandth of a pixel.
        assert!((x - centre.0).abs() < 1e-3 && (y - centre.1).abs() < 1e-3, "{k}: {x} {y}");
        let depth = g["depth"][k];
        assert!((view[2] - depth).abs() <= 1e-5 * depth, "{k}: {} vs {depth}", view[2]);
    }
    assert!(covered > 1000 && background < w * h, "{covered} covered");
    let samples: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(frame.join("samples.json")).expect("read"))
            .expect("samples.json");
    for kind in ["grid", "rotated"] {
        let rates: Vec<u64> = samples[kind]
            .as_array()
            .expect("rates")
            .iter()
            .map(|r| {
                let n = r["rate"].as_u64().expect("rate");
                assert_eq!(r["offsets"].as_array().expect("offsets").len() as u64, n);
                let c = &r["offsets"][r["centre_index"].as_u64().expect("index") as usize];
                assert_eq!((c[0].as_f64(), c[1].as_f64()), (Some(0.5), Some(0.5)));
                n
            })
            .collect();
        assert_eq!(
            rates,
            methods::pattern::RATES.iter().map(|&r| u64::from(r)).collect::<Vec<_>>()
        );
    }

    let run = d.join("sm");
    let render =
        [&["render"][..], &scene, &size, &["--method", "sm", "--out", path(&run)]].concat();
    assert!(shadowbench(&render).status.success());
    let cache = d.join("cache");
    let by_method = d.join("by-method");
    let o = shadowbench(
        &[
            &["compare"][..],
            &scene,
            &size,
            &["--method", "sm", "--cache", path(&cache), "--out", path(&by_method)],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let outside = d.join("outside");
    let o = shadowbench(
        &[
            &["compare"][..],
            &scene,
            &size,
            &["--visibility", path(&run.join("visibility.exr")), "--no-cache"],
            &["--name", "my-renderer", "--time-ms", "3.5", "--out", path(&outside)],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (m, e) = (metrics(&by_method), metrics(&outside));
    assert_eq!(e.comparison, m.comparison, "the same comparison object");
    assert!(m.comparison.evaluated_pixels > 1000);
    assert_eq!(
        (&e.reference, e.ref_rate, &e.edge_reference, &e.scene, e.width, e.height),
        (&m.reference, m.ref_rate, &m.edge_reference, &m.scene, m.width, m.height)
    );
    assert_eq!((e.method.as_str(), e.method_ms, e.external), ("my-renderer", Some(3.5), true));
    assert!(!m.external && m.method_ms.is_some());
    for f in ["error.png", "error_boundary.png", "shadow.png", "metrics.json"] {
        assert!(outside.join(f).is_file(), "{f}");
    }
    // Without --time-ms, method_ms is null (not 0) and the name is `external`.
    let untimed = d.join("untimed");
    let o = shadowbench(
        &[
            &["compare"][..],
            &scene,
            &size,
            &["--visibility", path(&run.join("visibility.exr"))],
            &["--cache", path(&cache), "--out", path(&untimed)],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(untimed.join("metrics.json")).expect("read");
    let v: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!((&v["method"], &v["method_ms"]), (&"external".into(), &serde_json::Value::Null));
}

/// Bad outside results and flags are refused with exit code 2, one message naming the file
/// or the flags, and no output folder written.
#[test]
fn bad_outside_results_and_flags_are_refused_naming_the_cause() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let run = d.join("sm");
    let size = ["--width", "32", "--height", "24"];
    let render = [
        &["render", "--scene", "plane-square", "--method", "sm"][..],
        &size,
        &["--out", path(&run)],
    ]
    .concat();
    assert!(shadowbench(&render).status.success());
    let exr = run.join("visibility.exr");
    let out = d.join("out");
    let refused = |args: &[&str], words: &[&str]| {
        let all = [&["compare", "--scene", "plane-square", "--out", path(&out)][..], args].concat();
        let o = shadowbench(&all);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        let e = stderr(&o);
        for w in words {
            assert!(e.contains(w), "{args:?}: `{w}` not in {e}");
        }
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    };
    refused(
        &[&["--visibility", path(&exr), "--method", "sm"][..], &size].concat(),
        &["--visibility", "--method"],
    );
    refused(&size, &["--method"]);
    refused(&[&["--method", "sm", "--name", "x"][..], &size].concat(), &["--name"]);
    refused(&[&["--method", "sm", "--time-ms", "2"][..], &size].concat(), &["--time-ms"]);
    refused(
        &["--visibility", path(&exr), "--width", "33", "--height", "24"],
        &["visibility.exr", "32x24", "33x24"],
    );
    refused(
        &[&["--visibility", path(&exr), "--time-ms", "-1"][..], &size].concat(),
        &["--time-ms"],
    );
    refused(&[&["--visibility", path(&exr), "--name", "a/b"][..], &size].concat(), &["--name"]);
    let missing = d.join("missing.exr");
    refused(&[&["--visibility", path(&missing)][..], &size].concat(), &["missing.exr"]);
    // Out of range: refused, not clamped.
    let bright = d.join("bright.exr");
    let lit = vec![1.25f32; 32 * 24];
    let v = methods::Visibility { width: 32, height: 24, lit, transmittance: None };
    reports::write_visibility_exr(&bright, &v).expect("writes");
    refused(
        &[&["--visibility", path(&bright)][..], &size].concat(),
        &["bright.exr", "1.25", "[0, 1]"],
    );
    // Three channels (a visibility with transmittance) are not a lit fraction.
    let rgb = d.join("rgb.exr");
    let t = methods::Visibility { transmittance: Some(vec![[1.0; 3]; 32 * 24]), ..v };
    reports::write_visibility_exr(&rgb, &t).expect("writes");
    refused(&[&["--visibility", path(&rgb)][..], &size].concat(), &["rgb.exr", "channel"]);
}

/// Three `compare`s of one scene and frame, three methods: the reference is computed by the
/// first and read from the cache by the second and the third, which say so, and keep the
/// first's computation time; `--no-cache` computes it again.
#[test]
fn compare_computes_a_scene_reference_once() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let cache = d.join("cache");
    let mut first_ms = None;
    for (k, method) in ["sm", "pcf-gems4", "afsm"].into_iter().enumerate() {
        let out = d.join(method);
        let o = shadowbench(&[
            "compare",
            "--scene",
            "city",
            "--method",
            method,
            "--width",
            "64",
            "--height",
            "48",
            "--cache",
            path(&cache),
            "--out",
            path(&out),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let m = metrics(&out);
        let printed = String::from_utf8_lossy(&o.stdout).into_owned();
        assert_eq!(m.reference_cached, k > 0, "{method}");
        assert_eq!(m.reference_read_ms.is_some(), k > 0, "{method}");
        assert_eq!(printed.contains("read from the cache"), k > 0, "{method}: {printed}");
        match first_ms {
            None => first_ms = Some(m.reference_ms),
            Some(ms) => assert_eq!(m.reference_ms, ms, "{method}: the computation's time kept"),
        }
    }
    // The reference, and the one-ray image the binary results' pixel match takes (sm's,
    // read back by afsm's).
    let entries = std::fs::read_dir(&cache).expect("cache").count();
    assert_eq!(entries, 2, "one reference and one one-ray image stored");
    // Another pattern, rate or edge reference is another reference.
    let out = d.join("other-rate");
    let o = shadowbench(&[
        "compare",
        "--scene",
        "city",
        "--method",
        "sm",
        "--width",
        "64",
        "--height",
        "48",
        "--ref-rate",
        "16",
        "--cache",
        path(&cache),
        "--out",
        path(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!metrics(&out).reference_cached);
    // A --cache that cannot be a folder is bad input; a default one that cannot be made
    // leaves the reference uncached, with a note.
    let file = d.join("file");
    std::fs::write(&file, "not a folder").expect("writes");
    let o = shadowbench(&[
        "compare",
        "--scene",
        "city",
        "--method",
        "sm",
        "--width",
        "64",
        "--height",
        "48",
        "--cache",
        path(&file),
        "--out",
        path(&d.join("refused")),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--cache") && !d.join("refused").exists(), "{}", stderr(&o));
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_shadowbench"))
        .args(["compare", "--scene", "city", "--method", "sm", "--width", "64", "--height", "48"])
        .args(["--out", path(&d.join("unwritable"))])
        .env("XDG_CACHE_HOME", &file)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("not cached"), "{}", stderr(&o));
    assert!(!metrics(&d.join("unwritable")).reference_cached);
    let out = d.join("no-cache");
    let o = shadowbench(&[
        "compare",
        "--scene",
        "city",
        "--method",
        "sm",
        "--width",
        "64",
        "--height",
        "48",
        "--no-cache",
        "--out",
        path(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!metrics(&out).reference_cached);
}

/// `frame`'s folder is a transaction: one holding a file no manifest lists, or a run's
/// output, is refused (exit 2, naming it) and left as it was; an earlier frame is replaced.
#[test]
fn frame_writes_whole_outputs_or_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let frame = |out: &Path| {
        shadowbench(&[
            "frame",
            "--scene",
            "plane-square",
            "--width",
            "16",
            "--height",
            "12",
            "--out",
            path(out),
        ])
    };
    let foreign = d.join("foreign");
    std::fs::create_dir(&foreign).expect("mkdir");
    std::fs::write(foreign.join("notes.txt"), "mine").expect("writes");
    let o = frame(&foreign);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("notes.txt"), "{}", stderr(&o));
    let left: Vec<_> = std::fs::read_dir(&foreign).expect("list").collect();
    assert_eq!(left.len(), 1, "the folder as it was");

    let run = d.join("run");
    let render = [
        "render",
        "--scene",
        "plane-square",
        "--method",
        "sm",
        "--width",
        "16",
        "--height",
        "12",
        "--out",
        path(&run),
    ];
    assert!(shadowbench(&render).status.success());
    let before = std::fs::read(run.join("run.json")).expect("run.json");
    let o = frame(&run);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(!run.join("frame.json").exists());
    assert_eq!(std::fs::read(run.join("run.json")).expect("run.json"), before);

    let out = d.join("frame");
    assert!(frame(&out).status.success());
    let o = frame(&out);
    assert!(o.status.success(), "an earlier frame is replaced: {}", stderr(&o));
    for f in ["frame.json", "gbuffer.exr", "samples.json"] {
        assert!(out.join(f).is_file(), "{f}");
    }
}
