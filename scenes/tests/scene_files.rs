//! Scene files: round trips, errors that name the file and key, derived effects.

use glam::DVec3;
use scenes::{registry, Light, SceneDesc, SceneError, BUILTINS};
use std::path::Path;

#[test]
fn every_builtin_round_trips_through_its_scene_file() {
    for (name, _) in BUILTINS {
        let desc = registry::builtin(name).expect("listed built-in exists");
        let text = desc.to_toml();
        let back = SceneDesc::from_toml(&text, Path::new("round-trip.toml"))
            .unwrap_or_else(|e| panic!("{name}: {e}\n{text}"));
        assert_eq!(back, desc, "{name}");
    }
}

#[test]
fn unknown_keys_are_named_with_file_and_line() {
    let text = "resolution = [8, 8]\n[camera.perspective]\neye = [0.0, 1.0, 2.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y_deg = 40.0\nlens = 3\n";
    let err = SceneDesc::from_toml(text, Path::new("dir/file.toml")).expect_err("unknown key");
    let msg = err.to_string();
    assert!(
        msg.contains("dir/file.toml") && msg.contains("lens") && msg.contains("line 6"),
        "{msg}"
    );
}

#[test]
fn generator_parameters_reject_unknown_keys() {
    let text = r#"
[camera.orthographic]
eye = [0.0, 5.0, 0.1]
target = [0.0, 0.0, 0.0]
height = 10.0
[light.directional]
direction = [0.0, -1.0, 0.0]
[[object]]
shape.cage = { bars = 3 }
"#;
    let msg =
        SceneDesc::from_toml(text, Path::new("cage.toml")).expect_err("unknown key").to_string();
    assert!(msg.contains("bars") && msg.contains("line 9"), "{msg}");
}

#[test]
fn effects_follow_the_content() {
    let effects = |name: &str| scenes::load(name).expect("built-in").effects();
    let plane = effects("plane-square");
    assert!(plane.planar_receiver && !plane.curved_receivers && !plane.transparency);
    let hair = effects("hairball");
    assert!(hair.transparency && hair.planar_receiver);
    let bumpy = effects("bumpy");
    assert!(bumpy.curved_receivers && !bumpy.transparency);
    assert!(effects("cage").curved_receivers);
}

#[test]
fn effects_can_be_forced_off() {
    let mut desc = registry::builtin("hairball").expect("built-in");
    desc.effects.transparency = false;
    desc.effects.curved_receivers = false;
    let scene = desc.resolve("hairball", Path::new("test"), Path::new(".")).expect("valid");
    let e = scene.effects();
    assert!(!e.transparency && !e.curved_receivers && e.planar_receiver);
}

#[test]
fn missing_models_say_how_to_get_them() {
    let desc = registry::builtin("bunny-plane").expect("built-in");
    let err = desc
        .resolve("bunny-plane", Path::new("builtin:bunny-plane"), Path::new("/nonexistent-models"))
        .expect_err("no model there");
    assert!(matches!(err, SceneError::ModelMissing { .. }), "{err}");
    let err = desc
        .resolve(
            "bunny-plane",
            Path::new("builtin:bunny-plane"),
            &scenes::models::models_dir().join("nowhere"),
        )
        .expect_err("no model there");
    assert!(err.to_string().contains("scripts/fetch-models"), "{err}");
}

#[test]
fn every_builtin_knows_its_resolution_and_light() {
    for (name, _) in BUILTINS {
        let desc = registry::builtin(name).expect("exists");
        let [w, h] = desc.resolution;
        assert!(w >= 64 && h >= 64, "{name}");
        assert!(desc.light.validate().is_ok() && desc.camera.validate().is_ok(), "{name}");
    }
    assert_eq!(registry::builtin("random-1m").expect("exists").resolution, [1024, 768]);
}

/// Scene files with every fixed-size array the format has, once with a perspective camera and a
/// spot light, once with an orthographic camera and a directional light.
const ARRAYS: [&str; 2] = [
    r#"resolution = [64, 48]
[camera.perspective]
eye = [0.0, 6.0, 8.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y_deg = 45.0
[light.spot]
position = [3.0, 9.0, 2.0]
target = [0.0, 0.0, 0.0]
fov_deg = 75.0
[[object]]
shape.plane = { size = 10.0 }
material = { color = [0.5, 0.5, 0.5] }
transform = { scale = [1.0, 1.0, 1.0], rotate_deg = [0.0, 10.0, 0.0], translate = [0.0, 0.0, 0.0] }
[[object]]
shape.cage = { size = [4.0, 4.0, 4.0] }
[[object]]
shape.random_triangles = { count = 10, extent = [8.0, 3.0, 8.0] }
"#,
    r#"[camera.orthographic]
eye = [0.0, 6.0, 8.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
height = 12.0
[light.directional]
direction = [-0.3, -1.0, -0.2]
[[object]]
shape.plane = { size = 10.0 }
"#,
];

#[test]
fn fixed_size_arrays_refuse_any_other_length_naming_line_and_key() {
    let path = Path::new("arrays.toml");
    let mut checked = 0;
    for text in ARRAYS {
        let desc = SceneDesc::from_toml(text, path).unwrap_or_else(|e| panic!("{e}"));
        desc.resolve("arrays", path, Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
        for (i, line) in text.lines().enumerate() {
            // Every `key = [x, y(, z)]` on the line.
            for (start, _) in line.match_indices(" = [") {
                let key = line[..start].rsplit(['{', ',', ' ']).next().expect("a key");
                let open = start + " = [".len();
                let close = open + line[open..].find(']').expect("closed");
                let values = &line[open..close];
                let (fewer, _) = values.rsplit_once(", ").expect("several values");
                for wrong in
                    [format!("{values}, 7"), format!("{values}, \"seven\""), fewer.to_owned()]
                {
                    let bad_line = format!("{}{wrong}{}", &line[..open], &line[close..]);
                    let mut lines: Vec<&str> = text.lines().collect();
                    lines[i] = &bad_line;
                    let bad = lines.join("\n");
                    let err = SceneDesc::from_toml(&bad, path).expect_err(&bad_line).to_string();
                    assert!(
                        err.contains("arrays.toml")
                            && err.contains(&format!("line {}", i + 1))
                            && err.contains(&format!("{key} = ["))
                            && err.contains("invalid length"),
                        "{bad_line}: {err}"
                    );
                    checked += 1;
                }
            }
        }
    }
    // resolution, eye, target, up, position, target, color, scale, rotate_deg, translate, size,
    // extent; eye, target, up, direction: three wrong lengths each.
    assert_eq!(checked, 3 * 16);
}

/// The unit cube of `tests/data/cube.obj` with every coordinate multiplied by `scale`, as OBJ.
fn scaled_cube(scale: f64) -> String {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cube.obj"))
            .expect("read");
    text.lines()
        .map(|line| match line.strip_prefix("v ") {
            Some(xyz) => {
                let v: Vec<String> = xyz
                    .split_whitespace()
                    .map(|c| format!("{:e}", c.parse::<f64>().expect("number") * scale))
                    .collect();
                format!("v {}\n", v.join(" "))
            }
            None => format!("{line}\n"),
        })
        .collect()
}

/// Resolves `--scene NAME` for a mesh file holding `text`.
fn mesh_scene(name: &str, text: &str) -> Result<scenes::Scene, SceneError> {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join(name);
    std::fs::write(&path, text).expect("write");
    scenes::load(path.to_str().expect("utf-8"))
}

#[test]
fn the_fit_holds_any_finite_mesh_with_an_extent() {
    let plain = mesh_scene("cube.obj", &scaled_cube(1.0)).expect("plain cube");
    assert_eq!(plain.objects[1].mesh.bounds().map(|(lo, hi)| hi - lo), Some(DVec3::splat(4.0)));
    // Powers of two: the fit is exact, from subnormal coordinates to near f64::MAX.
    for k in [-1070, -1030, -500, 500, 1000, 1023] {
        let scale = f64::MIN_POSITIVE * 2f64.powi(1022 + k.min(0)) * 2f64.powi(k.max(0));
        let scene = mesh_scene("cube.obj", &scaled_cube(scale)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.objects[1].mesh, plain.objects[1].mesh, "2^{k}");
    }
    // Others: the same up to rounding.
    for scale in [1e-320, 3e-300, 7e300, 1.7e308, -1.7e308] {
        let scene = mesh_scene("cube.obj", &scaled_cube(scale)).unwrap_or_else(|e| panic!("{e}"));
        let (lo, hi) = scene.objects[1].mesh.bounds().expect("vertices");
        assert!((hi - lo - DVec3::splat(4.0)).abs().max_element() < 1e-12, "{scale}: {lo} {hi}");
        assert!(lo.y == 0.0 && (lo.x + hi.x).abs() < 1e-12, "{scale}: {lo} {hi}");
    }
    // Coordinates from -1.7e308 to 1.7e308: the extent alone would overflow.
    let wide = "v -1.7e308 0 0\nv 1.7e308 0 0\nv 0 1.7e308 0\nv 0 0 1e308\nf 1 2 3\nf 1 2 4\n";
    let scene = mesh_scene("wide.obj", wide).unwrap_or_else(|e| panic!("{e}"));
    let (lo, hi) = scene.objects[1].mesh.bounds().expect("vertices");
    assert!((hi.x - lo.x - 4.0).abs() < 1e-12 && (hi.y - 2.0).abs() < 1e-12, "{lo} {hi}");
    // All one point: nothing to fit.
    let err = mesh_scene("point.obj", "v 1e-320 1 1\nv 1e-320 1 1\nv 1e-320 1 1\nf 1 2 3\n")
        .expect_err("one point");
    assert!(
        matches!(&err, SceneError::Invalid { key, .. } if key == "object[1].transform.fit_size"),
        "{err}"
    );
    assert!(
        err.to_string().contains("point.obj") && err.to_string().contains("one point"),
        "{err}"
    );
}

/// [`ARRAYS`]' second scene with `from` replaced by `to`, resolved.
fn resolve_with(from: &str, to: &str) -> Result<scenes::Scene, SceneError> {
    let text = ARRAYS[1].replace(from, to);
    assert_ne!(text, ARRAYS[1], "{from}");
    let path = Path::new("range.toml");
    SceneDesc::from_toml(&text, path)?.resolve("range", path, Path::new("."))
}

#[test]
fn scenes_beyond_the_supported_range_are_refused_naming_key_and_range() {
    let spot = "[light.spot]\nposition = [3.0, 9.0, 2.0]\ntarget = [0.0, 0.0, 0.0]\nfov_deg = 60.0";
    let light = "[light.directional]\ndirection = [-0.3, -1.0, -0.2]";
    for (from, to, key, reach) in [
        ("eye = [0.0, 6.0, 8.0]", "eye = [0.0, 6.0, 2e15]", "camera.eye", "2e15"),
        ("target = [0.0, 0.0, 0.0]", "target = [-1e300, 0.0, 0.0]", "camera.target", "1e300"),
        (light, &spot.replace("9.0", "1.5e15"), "light.position", "1.5e15"),
        (light, &spot.replace("target = [0.0", "target = [-3e20"), "light.target", "3e20"),
        (
            "size = 10.0 }",
            "size = 10.0 }\ntransform = { translate = [0, 0, 1e16] }",
            "object[0]",
            "1e16",
        ),
        (
            "size = 10.0 }",
            "size = 10.0 }\ntransform = { scale = [3e14, 1, 3e14] }",
            "object[0]",
            "1.5e15",
        ),
        (
            "size = 10.0 }",
            "size = 10.0 }\ntransform = { scale = [1e300, 1e300, 1] }",
            "object[0]",
            "5e300",
        ),
    ] {
        let err = resolve_with(from, to).expect_err(to);
        let msg = err.to_string();
        assert!(matches!(&err, SceneError::OutOfRange { key: k, .. } if k == key), "{msg}");
        assert!(
            msg.contains("range.toml")
                && msg.contains(&format!(
                    "coordinates reach {reach}, beyond the supported range |x| <= 1e15"
                )),
            "{msg}"
        );
    }
    let err =
        resolve_with("size = 10.0 }", "size = 1.0 }\ntransform = { scale = [1e-10, 1, 1e-10] }")
            .expect_err("tiny");
    assert!(matches!(&err, SceneError::OutOfRange { key, .. } if key == "object"), "{err}");
    assert!(err.to_string().contains("below the supported minimum 1e-9"), "{err}");
    // At the limits: accepted.
    resolve_with("size = 10.0 }", "size = 10.0 }\ntransform = { scale = [2e14, 1, 2e14] }")
        .expect("1e15 is in range");
    resolve_with("size = 10.0 }", "size = 1e-9 }").expect("a diagonal of 1.4e-9 is in range");
    let err =
        resolve_with("size = 10.0 }", "size = 10.0 }\ntransform = { scale = [1e308, 1e308, 1] }")
            .expect_err("overflow");
    assert!(err.to_string().contains("overflow"), "{err}");

    // A mesh file placed without a fit: the object is named with its file.
    let dir = tempfile::tempdir().expect("tempdir");
    let huge = "v 0 0 0\nv 1 0 0\nv 0 3.2e20 0\nf 1 2 3\n";
    std::fs::write(dir.path().join("huge.obj"), huge).expect("write");
    let text = ARRAYS[1].replace(
        "shape.plane = { size = 10.0 }",
        "name = \"model\"\nshape.file = { path = \"huge.obj\" }",
    );
    let path = Path::new("range.toml");
    let desc = SceneDesc::from_toml(&text, path).expect("parses");
    let err = desc.resolve("range", path, dir.path()).expect_err("huge");
    assert!(
        err.to_string().contains(
            "range.toml: `object[0]`: object `model` (huge.obj): coordinates reach 3.2e20, \
             beyond the supported range |x| <= 1e15"
        ),
        "{err}"
    );
}

#[test]
fn any_finite_non_zero_light_direction_resolves_to_a_unit_vector() {
    let want = DVec3::new(-0.3, -1.0, -0.2).normalize();
    for d in ["[-0.3e154, -1e154, -0.2e154]", "[-3e-171, -1e-170, -2e-171]", "[-3, -10, -2]"] {
        let scene = resolve_with("[-0.3, -1.0, -0.2]", d).unwrap_or_else(|e| panic!("{d}: {e}"));
        let Light::Directional { direction } = scene.light else { panic!("directional") };
        assert!((direction - want).length() < 1e-15, "{d}: {direction}");
    }
    let err = resolve_with("[-0.3, -1.0, -0.2]", "[0.0, -0.0, 0.0]").expect_err("zero");
    assert!(err.to_string().contains("light.direction"), "{err}");
}

#[test]
fn errors_found_after_parsing_name_the_line_and_the_key_as_written() {
    let dir = tempfile::tempdir().expect("tempdir");
    let head = "[camera.perspective]\neye = [0.0, 6.0, 8.0]\ntarget = [0.0, 0.0, 0.0]\n\
                fov_y_deg = FOV\n[light.directional]\ndirection = [-0.3, -1.0, -0.2]\n";
    for (name, fov, objects, want) in [
        (
            "count.toml",
            "45.0",
            "[[object]]\nshape.plane = { size = 4.0 }\n[[object]]\nname = \"cloud\"\n\
             shape.random_triangles = { count = 0 }\n",
            "line 11: `object[1].shape.random_triangles.count`: ",
        ),
        (
            "fov.toml",
            "180.0",
            "[[object]]\nshape.plane = { size = 4.0 }\n",
            "line 4: `camera.perspective.fov_y_deg`: must be in (0, 180), got 180",
        ),
        (
            "opacity.toml",
            "45.0",
            "[[object]]\nshape.plane = { size = 4.0 }\nmaterial = { opacity = 1.5 }\n",
            "line 9: `object[0].material.opacity`: must be in [0, 1], got 1.5",
        ),
        (
            "model.toml",
            "45.0",
            "[[object]]\n\nshape.file = { path = \"nowhere.obj\" }\n",
            "line 9: `object[0].shape.file.path`: scene `model` needs nowhere.obj, which is missing",
        ),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, format!("{}{objects}", head.replace("FOV", fov))).expect("writes");
        for err in [
            registry::load(path.to_str().expect("utf-8")).expect_err("refused"),
            SceneDesc::load(&path).expect_err("refused"),
        ] {
            let msg = err.to_string();
            assert!(msg.starts_with(&format!("{}: {want}", path.display())), "{msg}");
        }
    }
}

#[test]
fn a_scene_file_named_by_a_relative_path_looks_in_its_absolute_folder() {
    // The working folder is the package's: a relative path to a scene file in `tests/data`.
    let folders = SceneDesc::mesh_folders(Path::new("tests/data/any.toml"));
    let here = std::env::current_dir().expect("a working folder");
    assert_eq!(folders, [here.join("tests/data"), scenes::models::models_dir()]);
}
