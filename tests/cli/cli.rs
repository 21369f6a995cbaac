//! The CLI contract of DESIGN.md: `scenes` and `render`.

use crate::common;
use crate::common::{shadowbench, stderr};

#[test]
fn scenes_json_lists_at_least_twelve_scenes_with_counts_and_effects() {
    let o = shadowbench(&["scenes", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let list: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let list = list.as_array().expect("array");
    let available: Vec<_> = list.iter().filter(|s| s["available"] == true).collect();
    assert!(available.len() >= 12, "{} available scenes", available.len());
    for s in available {
        assert!(s["triangles"].as_u64().expect("count") > 0, "{s}");
        assert!(s["effects"].is_array(), "{s}");
    }
    let names: Vec<&str> = list.iter().filter_map(|s| s["name"].as_str()).collect();
    for required in [
        "plane-square",
        "random-1k",
        "random-10k",
        "random-100k",
        "random-1m",
        "cage",
        "plant",
        "spheres",
        "city",
        "bumpy",
        "hairball",
        "grazing",
        "bunny-plane",
    ] {
        assert!(names.contains(&required), "{required} missing from {names:?}");
    }
}

#[test]
fn scenes_toml_prints_a_scene_file_that_loads() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = shadowbench(&["scenes", "--toml", "cage"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let path = common::write(dir.path(), "cage-copy.toml", &String::from_utf8_lossy(&o.stdout));
    let scene = scenes::scene_file::SceneDesc::load(std::path::Path::new(&path)).expect("loads");
    let builtin = scenes::load("cage").expect("built-in");
    assert_eq!(scene.objects, builtin.objects);
}

#[test]
fn render_writes_the_three_files_with_every_counter_and_named_stages() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("run");
    let o = shadowbench(&[
        "render",
        "--scene",
        "plane-square",
        "--method",
        "sm",
        "--width",
        "160",
        "--height",
        "120",
        "--map-res",
        "256",
        "--out",
        out.to_str().expect("utf-8"),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["visibility.exr", "shadow.png", "run.json"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let printed: serde_json::Value = serde_json::from_slice(&o.stdout).expect("stdout is run.json");
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).expect("read"))
            .expect("JSON");
    assert_eq!(printed, written);
    assert_eq!(written["scene"], "plane-square");
    assert_eq!(written["method"], "sm");
    assert_eq!(written["params"]["map_res"], 256);
    assert_eq!((written["width"].as_u64(), written["height"].as_u64()), (Some(160), Some(120)));
    assert!(written["effects"].as_array().expect("effects").contains(&"planar_receiver".into()));
    let counters = written["counters"].as_object().expect("counters");
    for name in instrumentation::Counters::NAMES {
        assert!(counters.contains_key(*name), "counter {name} missing");
    }
    // One lookup per pixel that sees a surface (tests/techniques/shadow_maps.rs checks the exact count).
    let lookups = counters["shadow_map_lookups"].as_u64().expect("count");
    assert!(lookups > 1000 && lookups <= 160 * 120, "{lookups} lookups");
    let stages: Vec<&str> = written["stages"]
        .as_array()
        .expect("stages")
        .iter()
        .map(|s| {
            assert!(s["ms"].as_f64().expect("ms") >= 0.0);
            s["name"].as_str().expect("name")
        })
        .collect();
    assert_eq!(stages, ["camera G-buffer", "light depth map", "depth test"]);
    let total = written["total_ms"].as_f64().expect("total_ms");
    let sum: f64 = written["stages"]
        .as_array()
        .expect("stages")
        .iter()
        .map(|s| s["ms"].as_f64().unwrap_or(0.0))
        .sum();
    assert!((total - sum).abs() < 1e-6);

    let exr = exr::prelude::read_first_flat_layer_from_file(out.join("visibility.exr"))
        .expect("EXR reads");
    assert_eq!(exr.layer_data.size.width(), 160);
    assert_eq!(exr.layer_data.size.height(), 120);
    let png = image::open(out.join("shadow.png")).expect("PNG reads");
    assert_eq!((png.width(), png.height()), (160, 120));
}

/// `exact` writes its pixel classes: `classes.png` (a colour per class), `class_ids.png`
/// (grey, the class's code) and the count per class in `run.json`; other methods do not.
#[test]
fn render_exact_writes_its_pixel_classes() {
    use analysis::pixel_class::PixelClass;
    let dir = tempfile::tempdir().expect("tempdir");
    let (w, h) = (160u32, 120u32);
    let render = |method: &str| {
        let out = dir.path().join(method);
        let o = shadowbench(&[
            "render",
            "--scene",
            "cage",
            "--method",
            method,
            "--width",
            &w.to_string(),
            "--height",
            &h.to_string(),
            "--out",
            out.to_str().expect("utf-8"),
        ]);
        assert!(o.status.success(), "{method}: {}", stderr(&o));
        let run: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).expect("read"))
                .expect("JSON");
        (out, run)
    };
    let (out, run) = render("exact");
    let counts = run["pixel_classes"].as_object().expect("pixel_classes in run.json");
    let count = |c: PixelClass| counts[c.name()].as_u64().expect("count");
    assert_eq!(PixelClass::ALL.iter().map(|&c| count(c)).sum::<u64>(), u64::from(w * h));
    assert!(count(PixelClass::Planar) > 0 && count(PixelClass::Edge) > 0, "{counts:?}");

    let ids = image::open(out.join("class_ids.png")).expect("class_ids.png reads");
    assert_eq!(ids.color(), image::ColorType::L8);
    let ids = ids.to_luma8();
    let rgb = image::open(out.join("classes.png")).expect("classes.png reads").to_rgb8();
    assert_eq!((ids.dimensions(), rgb.dimensions()), ((w, h), (w, h)));
    let mut seen = [0u64; 4];
    for (id, colour) in ids.pixels().zip(rgb.pixels()) {
        let class = PixelClass::ALL
            .get(usize::from(id.0[0]))
            .unwrap_or_else(|| panic!("class id {} out of 0..=3", id.0[0]));
        assert_eq!(colour.0, class.colour());
        seen[usize::from(id.0[0])] += 1;
    }
    for c in PixelClass::ALL {
        assert_eq!(seen[usize::from(c.code())], count(c), "{}", c.name());
    }

    let (out, run) = render("sm");
    assert!(run.get("pixel_classes").is_none(), "{run}");
    assert!(!out.join("classes.png").exists() && !out.join("class_ids.png").exists());
}

#[test]
fn render_takes_a_mesh_file_as_scene() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tetra = common::write(
        dir.path(),
        "tetra.off",
        "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
    );
    let out = dir.path().join("out");
    let o = shadowbench(&[
        "render",
        "--scene",
        &tetra,
        "--method",
        "sm",
        "--width",
        "64",
        "--height",
        "48",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let run: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).expect("read"))
            .expect("JSON");
    assert_eq!(run["scene"], "tetra");
}

#[cfg(feature = "gpu")]
#[test]
fn render_on_the_gpu_names_the_adapter_and_the_timing_in_run_json() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("gpu");
    let o = shadowbench(&[
        "render",
        "--scene",
        "cage",
        "--method",
        "afsm",
        "--device",
        "gpu",
        "--width",
        "64",
        "--height",
        "48",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let run: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).expect("read"))
            .expect("JSON");
    assert_eq!(run["params"]["device"], "gpu");
    let notes = run["notes"].to_string();
    assert!(notes.contains("GPU: ") && notes.contains("stage times by"), "{notes}");
    let stages: Vec<&str> = run["stages"]
        .as_array()
        .expect("stages")
        .iter()
        .filter_map(|s| s["name"].as_str())
        .collect();
    assert!(stages.contains(&"G-buffer (GPU)") && stages.contains(&"rasterization of blockers"));
}

/// `render --device gpu` runs every technique with GPU kernels in the registry's table (every
/// method has them); the references, and a method without kernels, are refused, named.
#[cfg(feature = "gpu")]
#[test]
fn gpu_device_runs_every_method_but_the_references() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cpu_only = ["exact", "raytrace"];
    let no_kernels: Vec<&str> =
        methods::registry::METHODS.iter().filter(|m| m.gpu.is_none()).map(|m| m.name).collect();
    assert_eq!(no_kernels, Vec::<&str>::new());
    for name in methods::registry::METHODS.iter().map(|m| m.name).chain(cpu_only) {
        let out = dir.path().join(name);
        let mut args = vec!["render", "--scene", "plane-square", "--method", name];
        args.extend(["--device", "gpu", "--width", "16", "--height", "12"]);
        if name == "afsm-ss" || name == "pan09" || name == "ftizb" {
            args.extend(["--rate", "4"]);
        }
        args.extend(["--out", out.to_str().expect("utf-8")]);
        let o = shadowbench(&args);
        if cpu_only.contains(&name) {
            assert_eq!(o.status.code(), Some(2), "{name}: {}", stderr(&o));
            assert!(stderr(&o).contains("runs on the CPU only"), "{name}: {}", stderr(&o));
        } else if no_kernels.contains(&name) {
            assert_eq!(o.status.code(), Some(2), "{name}: {}", stderr(&o));
            let e = stderr(&o);
            assert!(e.contains(&format!("--device: `{name}` on the GPU: it has no GPU kernels")));
        } else {
            assert!(o.status.success(), "{name} on the GPU: {}", stderr(&o));
        }
    }
}

/// A scene whose objects cast no shadow leaves the GPU kernels empty inputs (no caster, no
/// silhouette edge, no uncertain pixel): every method still runs (once, pan09 and spsm failed
/// to bind their empty buffers), and the image is lit everywhere (msm to within 1e-4).
#[test]
fn gpu_device_runs_every_method_on_a_scene_without_casters() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = shadowbench(&["scenes", "--toml", "plane-square"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let toml =
        String::from_utf8_lossy(&o.stdout).replace("casts_shadows = true", "casts_shadows = false");
    assert!(!toml.contains("casts_shadows = true"));
    let scene = dir.path().join("no-casters.toml");
    std::fs::write(&scene, toml).expect("scene file written");
    let with_kernels = methods::registry::METHODS.iter().filter(|m| m.gpu.is_some());
    for name in with_kernels.map(|m| m.name) {
        let out = dir.path().join(name);
        let mut args = vec!["render", "--scene", scene.to_str().expect("utf-8"), "--method", name];
        args.extend(["--device", "gpu", "--width", "16", "--height", "12"]);
        if ["afsm-ss", "pan09", "spsm", "spsm-f32"].contains(&name) {
            args.extend(["--rate", "4"]);
        }
        args.extend(["--out", out.to_str().expect("utf-8"), "--json"]);
        let o = shadowbench(&args);
        assert!(o.status.success(), "{name} on the GPU without casters: {}", stderr(&o));
        let exr = exr::prelude::read_first_flat_layer_from_file(out.join("visibility.exr"))
            .expect("EXR reads");
        // msm's default 16-bit moments in the optimized basis cannot hold the far plane's
        // exactly: a texel without a caster dims its receivers by about 4e-5.
        let least = if name == "msm" { 1.0 - 1e-4 } else { 1.0 };
        for c in &exr.layer_data.channel_data.list {
            let lit = c.sample_data.values_as_f32().all(|v| (least..=1.0).contains(&v));
            assert!(lit, "{name}: not lit everywhere");
        }
    }
}

#[test]
fn help_explains_every_render_flag() {
    let o = shadowbench(&["render", "--help"]);
    let help = String::from_utf8_lossy(&o.stdout);
    let lines: Vec<&str> = help.lines().collect();
    for flag in [
        "--scene",
        "--method",
        "--map-res",
        "--constant-bias",
        "--slope-bias",
        "--max-slope",
        "--width",
        "--height",
        "--device",
        "--repeat",
        "--out",
        "--json",
    ] {
        let i = lines
            .iter()
            .position(|l| l.trim_start().starts_with(flag))
            .unwrap_or_else(|| panic!("{flag} not in help:\n{help}"));
        // Long help puts the explanation on the next line; short help after the flag.
        let same_line = lines[i].trim_start()[flag.len()..].split("  ").last().unwrap_or("");
        let explanation = if same_line.split_whitespace().count() >= 3 {
            same_line
        } else {
            lines.get(i + 1).copied().unwrap_or("")
        };
        assert!(
            explanation.split_whitespace().count() >= 3,
            "{flag} is not explained: {explanation:?}"
        );
    }
}

/// `--repeat N` times N runs after a warm-up: run.json keeps its shape and holds the run of
/// median total, whose counters are one run's; the printed line gives the median with the
/// min and max. N must be 1 to 1000.
#[test]
fn render_repeat_reports_the_median_run_with_its_spread() {
    let dir = tempfile::tempdir().expect("tempdir");
    let render = |name: &str, repeat: &str| {
        let out = dir.path().join(name);
        let o = shadowbench(&[
            "render",
            "--scene",
            "cage",
            "--method",
            "sm",
            "--width",
            "96",
            "--height",
            "72",
            "--repeat",
            repeat,
            "--out",
            out.to_str().expect("utf-8"),
        ]);
        let text = std::fs::read_to_string(out.join("run.json")).unwrap_or_default();
        (o, serde_json::from_str::<serde_json::Value>(&text).ok())
    };
    let (o, once) = render("once", "1");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("median"), "{}", stderr(&o));
    let (o, thrice) = render("thrice", "3");
    assert!(o.status.success(), "{}", stderr(&o));
    let (once, thrice) = (once.expect("run.json"), thrice.expect("run.json"));
    let keys =
        |v: &serde_json::Value| v.as_object().expect("object").keys().cloned().collect::<Vec<_>>();
    assert_eq!(keys(&once), keys(&thrice));
    assert_eq!(once["counters"], thrice["counters"], "one run's counters");
    let names = |v: &serde_json::Value| {
        v["stages"]
            .as_array()
            .expect("stages")
            .iter()
            .map(|s| s["name"].clone())
            .collect::<Vec<_>>()
    };
    assert_eq!(names(&once), names(&thrice));
    // `sm on cage at 96x72: CPU T (no interval) [A, B] ms, wall W (no interval) [C, D] ms,
    // median of 3 runs after a warm-up; wrote ...`: the record kept is the run of median CPU
    // time, and its `timing` holds every run's.
    let err = stderr(&o);
    let after = |key: &str| -> &str {
        &err[err.find(key).unwrap_or_else(|| panic!("no `{key}` in {err}")) + key.len()..]
    };
    let number = |t: &str| -> f64 { t.trim().parse().unwrap_or_else(|_| panic!("`{t}` in {err}")) };
    assert!(err.contains("median of 3 runs after a warm-up"), "{err}");
    let cpu = after("96x72: CPU ");
    let median = number(cpu.split(' ').next().expect("a median"));
    let range = &cpu[cpu.find('[').expect("a range") + 1..cpu.find(']').expect("a range")];
    let (min, max) = range.split_once(", ").map(|(a, b)| (number(a), number(b))).expect("a range");
    let recorded = thrice["cpu_ms"].as_f64().expect("CPU time");
    assert!((median - recorded).abs() < 0.06, "printed {median}, run.json {recorded}");
    assert!(min <= median && median <= max, "{err}");
    assert!(after("no interval").contains("wall "), "three runs have no 95 % interval: {err}");
    let samples = thrice["timing"]["samples"].as_array().expect("the timed runs");
    assert_eq!(samples.len(), 3);
    assert!(samples.iter().all(|s| s["wall_ms"].as_f64().is_some_and(|w| w > 0.0)), "{samples:?}");

    for bad in ["0", "-1", "1001", "many"] {
        let (o, _) = render(&format!("bad{bad}"), bad);
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", stderr(&o));
        assert!(stderr(&o).contains("--repeat"), "{bad}: {}", stderr(&o));
    }
    let help = String::from_utf8_lossy(&shadowbench(&["render", "--help"]).stdout).into_owned();
    assert!(help.contains("warm-up") && help.contains("median"), "{help}");
}

/// Two identical runs write the same bytes (the EXR's blocks used to come in the order their
/// parallel compression finished), so checksums can compare runs; in `run.json` only the
/// times may differ.
#[test]
fn identical_renders_write_identical_files() {
    let dir = tempfile::tempdir().expect("tempdir");
    let render = |name: &str| {
        let out = dir.path().join(name);
        let o = shadowbench(&[
            "render",
            "--scene",
            "spheres",
            "--method",
            "pcf-gems16",
            "--width",
            "640",
            "--height",
            "480",
            "--map-res",
            "512",
            "--out",
            out.to_str().expect("utf-8"),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        out
    };
    let (a, b) = (render("a"), render("b"));
    for f in ["visibility.exr", "shadow.png"] {
        let bytes = |d: &std::path::Path| std::fs::read(d.join(f)).expect("the file");
        assert!(bytes(&a) == bytes(&b), "{f} differs between identical runs");
    }
    let record = |d: &std::path::Path| {
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("run.json")).expect("run.json"))
                .expect("JSON");
        // Times: both clocks, and how they were taken (the timed runs, contention, load).
        for key in ["total_ms", "cpu_ms", "timing"] {
            v[key] = serde_json::Value::Null;
        }
        // The provenance names the command (its output folder) and the time of the run.
        for key in ["command", "timestamp"] {
            assert!(v["provenance"][key].is_string(), "provenance.{key}");
            v["provenance"][key] = serde_json::Value::Null;
        }
        for s in v["stages"].as_array_mut().expect("stages") {
            s["ms"] = serde_json::Value::Null;
            s["cpu_ms"] = serde_json::Value::Null;
        }
        v
    };
    assert_eq!(record(&a), record(&b));
}

/// A successful GPU run prints nothing about `XDG_RUNTIME_DIR` when the variable is unset
/// (Mesa's Vulkan driver used to print `error: XDG_RUNTIME_DIR is invalid` twice).
#[cfg(feature = "gpu")]
#[test]
fn gpu_render_without_a_runtime_dir_prints_no_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_shadowbench"))
        .args(["render", "--scene", "cage", "--method", "sm", "--device", "gpu"])
        .args(["--width", "64", "--height", "48", "--out"])
        .arg(dir.path().join("gpu"))
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .expect("the shadowbench binary runs");
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("XDG_RUNTIME_DIR"), "{}", stderr(&o));
    assert!(!stderr(&o).contains("error"), "{}", stderr(&o));
}
