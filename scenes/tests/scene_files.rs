//! Scene files: round trips, errors that name the file and key, derived effects.

use scenes::{registry, SceneDesc, SceneError, BUILTINS};
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
            &registry::models_dir().join("nowhere"),
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
