//! `animate`: a method through every frame of an animated scene, its files, the temporal
//! error's floors (the truth against itself, any method on a still scene), the reference
//! cache shared by every method over one animation, and bad input.

use crate::common::{shadowbench, stderr};
use reports::animation::AnimationRecord;
use std::path::Path;

fn path(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn record(dir: &Path) -> AnimationRecord {
    let text = std::fs::read_to_string(dir.join("temporal.json")).expect("temporal.json");
    serde_json::from_str(&text).expect("an animation record")
}

/// Runs `animate` with `args` at 48x36 into `out`, asserting success.
fn animate(out: &Path, cache: &Path, args: &[&str]) -> AnimationRecord {
    let mut all = vec!["animate", "--width", "48", "--height", "36", "--cache", path(cache)];
    all.extend_from_slice(&["--out", path(out)]);
    all.extend_from_slice(args);
    let o = shadowbench(&all);
    assert!(o.status.success(), "{all:?}: {}", stderr(&o));
    record(out)
}

#[test]
fn a_run_in_motion_writes_every_frame_its_table_its_metrics_and_one_animation() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("slide");
    let r = animate(
        &out,
        &dir.path().join("cache"),
        &["--scene", "square-slide", "--method", "sm", "--frames", "4", "--map-res", "256"],
    );
    assert_eq!((r.frames, r.per_frame.len(), r.temporal.frames), (4, 4, 4));
    assert!(r.temporal.reprojected, "the square moves: pixels are paired through the geometry");
    assert!(r.temporal.pixel_pairs > 0 && r.temporal.mean.is_some_and(|m| m > 0.0));
    assert_eq!(r.per_frame[0].temporal_error, None, "frame 0 ends no pair");
    assert!(r.per_frame[1..].iter().all(|f| f.temporal_pairs > 0));
    assert_eq!(r.per_frame.iter().map(|f| f.map_res).collect::<Vec<_>>(), [Some(256); 4]);
    for i in 0..4 {
        assert!(out.join(format!("frames/visibility-{i:04}.exr")).is_file(), "frame {i}");
    }
    let csv = std::fs::read_to_string(out.join("frames.csv")).expect("frames.csv");
    assert_eq!(csv.lines().count(), 5, "a header and a row per frame:\n{csv}");
    assert!(csv.starts_with("frame,time,map_res,mean_abs_error,"), "{csv}");
    let file = std::fs::File::open(out.join("animation.png")).expect("animation.png");
    let reader = png::Decoder::new(std::io::BufReader::new(file)).read_info().expect("a PNG");
    let control = reader.info().animation_control().copied().expect("animated");
    assert_eq!(control.num_frames, 4);
    assert_eq!(reader.info().height, 36 + analysis::error_map::bar_height(48));
}

#[test]
fn the_truth_against_itself_and_a_still_scene_have_no_temporal_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cache = dir.path().join("cache");
    // The truth as a method (`exact` run through the table of references) against itself.
    let exact = animate(
        &dir.path().join("exact"),
        &cache,
        &[
            "--scene",
            "cage-sweep",
            "--method",
            "exact",
            "--frames",
            "3",
            "--edge-reference",
            "none",
        ],
    );
    assert!(exact.temporal.pixel_pairs > 0);
    assert_eq!(exact.temporal.mean, Some(0.0));
    assert_eq!(exact.temporal.p95, Some(0.0));
    assert!(exact.temporal.boundary_mean.is_none_or(|m| m == 0.0));
    // Any method on a still scene: every frame is the same frame.
    let still = animate(
        &dir.path().join("still"),
        &cache,
        &["--scene", "cage", "--method", "pcf-gems4", "--frames", "3", "--map-res", "128"],
    );
    assert!(!still.temporal.reprojected);
    assert!(still.temporal.pixel_pairs > 0);
    assert_eq!((still.temporal.mean, still.temporal.boundary_mean), (Some(0.0), Some(0.0)));
    assert!(still.mean_abs_error.is_some_and(|e| e > 0.0), "the method is not exact");
}

#[test]
fn every_method_over_one_animation_reads_the_references_the_first_computed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cache = dir.path().join("cache");
    let args = |scene: &'static str, m: &'static str| {
        ["--scene", scene, "--method", m, "--frames", "3", "--edge-reference", "none"]
    };
    let first = animate(&dir.path().join("a"), &cache, &args("cage-sweep", "sm"));
    assert!(first.per_frame.iter().all(|f| !f.reference_cached), "the light moves");
    let second = animate(&dir.path().join("b"), &cache, &args("cage-sweep", "afsm"));
    assert!(second.per_frame.iter().all(|f| f.reference_cached), "{:?}", second.per_frame);
    // The map-scale ramp from 0.25 to 1 scales sm's map and leaves afsm's (it has none); the
    // scene itself does not move, so its one reference is computed once.
    let ramp = animate(&dir.path().join("c"), &cache, &args("cage-ramp", "sm"));
    let maps: Vec<_> = ramp.per_frame.iter().map(|f| f.map_res).collect();
    assert_eq!(maps, [Some(256), Some(640), Some(1024)]);
    let cached: Vec<_> = ramp.per_frame.iter().map(|f| f.reference_cached).collect();
    assert_eq!(cached, [false, true, true]);
    let afsm = animate(&dir.path().join("d"), &cache, &args("cage-ramp", "afsm"));
    assert!(afsm.per_frame.iter().all(|f| f.map_res.is_none() && f.reference_cached));
}

#[test]
fn bad_frame_counts_are_refused_naming_the_flag_and_nothing_is_written() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    for n in ["0", "1001", "-3"] {
        let o = shadowbench(&[
            "animate",
            "--scene",
            "cage-sweep",
            "--method",
            "sm",
            "--frames",
            n,
            "--out",
            path(&out),
        ]);
        assert_eq!(o.status.code(), Some(2), "--frames {n}: {}", stderr(&o));
        assert!(stderr(&o).contains("--frames"), "--frames {n}: {}", stderr(&o));
        assert!(!out.exists(), "a refused command writes nothing");
    }
}

#[test]
fn a_bad_animation_is_refused_naming_its_key_and_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = r#"
[camera.perspective]
eye = [0.0, 5.0, 8.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 45.0

[light.directional]
direction = [-0.5, -1.0, -0.4]

[[object]]
shape.plane = { size = 8.0 }

[animation]
frames = 4

[[animation.light]]
time = 1.0
direction = [-0.5, -1.0, -0.4]

[[animation.light]]
time = 0.5
direction = [0.5, -1.0, -0.4]
"#;
    let file = crate::common::write(dir.path(), "bad.toml", scene);
    let out = dir.path().join("out");
    let o = shadowbench(&["animate", "--scene", &file, "--method", "sm", "--out", path(&out)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("line 21") && err.contains("animation.light[1].time"), "{err}");
    assert!(!out.exists());
}
