//! Bad input: every malformed scene file, mesh file and flag gives exit code 2 and one message
//! naming the file and line, the key, or the flag.

mod common;
use common::{shadowbench, stderr, write};

/// Renders `scene` with `sm` and returns (exit code, stderr).
fn render(scene: &str, extra: &[&str]) -> (Option<i32>, String) {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let mut args =
        vec!["render", "--scene", scene, "--method", "sm", "--width", "32", "--height", "24"];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--out", out.to_str().expect("utf-8")]);
    let o = shadowbench(&args);
    (o.status.code(), stderr(&o))
}

const VALID: &str = r#"
resolution = [64, 48]
[camera.perspective]
eye = [0.0, 6.0, 8.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 45.0
[light.directional]
direction = [-0.3, -1.0, -0.2]
[[object]]
shape.plane = { size = 10.0 }
"#;

#[test]
fn a_valid_scene_file_renders() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = write(dir.path(), "ok.toml", VALID);
    let (code, err) = render(&path, &[]);
    assert_eq!(code, Some(0), "{err}");
}

#[test]
fn scene_file_errors_name_the_file_and_the_line_or_key() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cases: &[(&str, String, &[&str])] = &[
        (
            "unknown-key.toml",
            VALID.replace("fov_y_deg = 45.0", "fov_y_deg = 45.0\nzoom = 2"),
            &["zoom", "line 7"],
        ),
        (
            "bad-type.toml",
            VALID.replace("fov_y_deg = 45.0", "fov_y_deg = \"wide\""),
            &["fov_y_deg", "line 6"],
        ),
        (
            "bad-fov.toml",
            VALID.replace("fov_y_deg = 45.0", "fov_y_deg = 190.0"),
            &["camera.fov_y_deg"],
        ),
        (
            "bad-opacity.toml",
            format!("{VALID}material = {{ opacity = 2.0 }}\n"),
            &["object[0].material.opacity"],
        ),
        (
            "bad-generator.toml",
            VALID.replace("size = 10.0", "size = -1.0"),
            &["object[0].shape.size"],
        ),
        (
            "unknown-shape.toml",
            VALID.replace("shape.plane", "shape.teapot"),
            &["teapot", "line 10"],
        ),
        (
            "unknown-param.toml",
            VALID.replace("size = 10.0", "size = 10.0, colour = 1"),
            &["colour", "line 10"],
        ),
        (
            "bad-param-type.toml",
            VALID.replace("size = 10.0", "size = \"big\""),
            &["size = \"big\"", "line 10"],
        ),
        (
            "no-objects.toml",
            VALID.replace("[[object]]\nshape.plane = { size = 10.0 }\n", "object = []\n"),
            &["object"],
        ),
        (
            "zero-light.toml",
            VALID.replace("[-0.3, -1.0, -0.2]", "[0.0, 0.0, 0.0]"),
            &["light.direction"],
        ),
        (
            "missing-mesh.toml",
            VALID.replace(
                "shape.plane = { size = 10.0 }",
                "shape.file = { path = \"nowhere.obj\" }",
            ),
            &["nowhere.obj", "missing"],
        ),
        ("not-toml.toml", "this is = = not toml".to_string(), &["line 1"]),
    ];
    for (name, text, needles) in cases {
        let path = write(dir.path(), name, text);
        let (code, err) = render(&path, &[]);
        assert_eq!(code, Some(2), "{name}: {err}");
        assert!(err.contains(name), "{name}: message does not name the file: {err}");
        for n in *needles {
            assert!(err.contains(n), "{name}: message lacks `{n}`: {err}");
        }
        assert_eq!(err.lines().filter(|l| l.starts_with("error")).count(), 1, "{name}: {err}");
    }
}

#[test]
fn malformed_mesh_files_name_the_file_and_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cases: &[(&str, &str, &str)] = &[
        ("nan.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", "line 4"),
        ("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n", "line 3"),
        ("index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4"),
        ("index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "line 6"),
        ("truncated.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n", "line"),
        ("word.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n", "line 11"),
        ("empty.obj", "", "empty.obj"),
    ];
    for (name, text, needle) in cases {
        let path = write(dir.path(), name, text);
        let (code, err) = render(&path, &[]);
        assert_eq!(code, Some(2), "{name}: {err}");
        assert!(
            err.contains(name) && err.contains(needle),
            "{name}: expected `{needle}` in: {err}"
        );
    }
}

#[test]
fn bad_flags_and_names_are_named() {
    let cases: &[(&[&str], &str)] = &[
        (&["render", "--scene", "no-such-scene", "--method", "sm"], "no-such-scene"),
        (&["render", "--scene", "plane-square", "--method", "magic"], "--method"),
        (&["render", "--scene", "plane-square", "--method", "sm", "--map-res", "0"], "--map-res"),
        (
            &["render", "--scene", "plane-square", "--method", "sm", "--slope-bias=-1"],
            "--slope-bias",
        ),
        (&["render", "--scene", "plane-square", "--method", "sm", "--width", "0"], "--width"),
        (
            &["render", "--scene", "plane-square", "--method", "sm", "--map-res", "many"],
            "--map-res",
        ),
        (&["render", "--scene", "/no/such/file.obj", "--method", "sm"], "/no/such/file.obj"),
        (&["scenes", "--toml", "no-such-scene"], "no-such-scene"),
        (
            &["render", "--scene", "plane-square", "--method", "pcf-bs-2x2", "--depth-bits", "16"],
            "--depth-bits",
        ),
        (&["render", "--scene", "plane-square", "--method", "pcf-reeves", "--rate", "3"], "--rate"),
        (
            &["render", "--scene", "plane-square", "--method", "pcf-gems4", "--max-slope", "nan"],
            "--max-slope",
        ),
    ];
    for (args, needle) in cases {
        let o = shadowbench(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{args:?}: expected `{needle}` in {}", stderr(&o));
    }
}
