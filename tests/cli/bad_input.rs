//! Bad input: every malformed scene file, mesh file and flag gives exit code 2 and one message
//! naming the file and line, the key, or the flag.

use crate::common::{shadowbench, stderr, write};
use std::process::Output;

/// Renders `scene` with `method` at 32 x 24 and the `extra` flags into the folder `out`.
fn render_into(out: &std::path::Path, scene: &str, method: &str, extra: &[&str]) -> Output {
    let mut args =
        vec!["render", "--scene", scene, "--method", method, "--width", "32", "--height", "24"];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--out", out.to_str().expect("utf-8")]);
    shadowbench(&args)
}

/// Renders `scene` with `sm` and returns (exit code, stderr).
fn render(scene: &str, extra: &[&str]) -> (Option<i32>, String) {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = render_into(&dir.path().join("out"), scene, "sm", extra);
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

// Mesh and scene inputs: byte-order marks and line ends, PLY elements that end early,
// fixed-size arrays, directions of any magnitude, extents and the supported range.

/// The unit cube of the loader tests, in each text format.
const CUBE_OBJ: &str = include_str!("../../scenes/tests/data/cube.obj");
const CUBE_OFF: &str = include_str!("../../scenes/tests/data/cube.off");
const CUBE_PLY: &str = include_str!("../../scenes/tests/data/cube.ply");

/// Renders `scene` with `sm` at 32 x 24 and returns the bytes of `visibility.exr`, or the exit
/// code and stderr of a failed run.
fn visibility(scene: &str) -> Result<Vec<u8>, (Option<i32>, String)> {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let o = render_into(&out, scene, "sm", &[]);
    match o.status.code() {
        Some(0) => Ok(std::fs::read(out.join("visibility.exr")).expect("visibility.exr")),
        code => Err((code, stderr(&o))),
    }
}

/// Writes `bytes` to `dir/name` and returns the path as a string.
fn write_bytes(dir: &std::path::Path, name: &str, bytes: &[u8]) -> String {
    let p = dir.join(name);
    std::fs::write(&p, bytes).expect("writes the test file");
    p.to_string_lossy().into_owned()
}

#[test]
fn mesh_files_with_a_byte_order_mark_or_old_line_ends_render_like_plain_ones() {
    let dir = tempfile::tempdir().expect("tempdir");
    // The OBJ starts with a vertex, which a byte-order mark used to hide.
    let obj: String =
        CUBE_OBJ.lines().filter(|l| l.starts_with(['v', 'f'])).map(|l| format!("{l}\n")).collect();
    for (ext, text) in [("obj", obj.as_str()), ("off", CUBE_OFF), ("ply", CUBE_PLY)] {
        let plain = visibility(&write(dir.path(), &format!("plain.{ext}"), text))
            .unwrap_or_else(|e| panic!("plain {ext}: {e:?}"));
        for (name, bom, end) in
            [("bom", true, "\n"), ("cr", false, "\r"), ("bom-crlf", true, "\r\n")]
        {
            let mut bytes = if bom { b"\xEF\xBB\xBF".to_vec() } else { Vec::new() };
            bytes.extend(text.replace('\n', end).into_bytes());
            let path = write_bytes(dir.path(), &format!("{name}.{ext}"), &bytes);
            let got = visibility(&path).unwrap_or_else(|e| panic!("{path}: {e:?}"));
            assert!(got == plain, "{path} renders differently from plain.{ext}");
        }
    }
}

#[test]
fn a_ply_declaring_more_vertices_than_it_holds_names_the_vertex_element() {
    let dir = tempfile::tempdir().expect("tempdir");
    let ply = CUBE_PLY.replace("element vertex 8", "element vertex 10");
    let path = write(dir.path(), "ten.ply", &ply);
    let (code, err) = visibility(&path).expect_err("10 vertices declared, 8 present");
    assert_eq!(code, Some(2), "{err}");
    let face_line = 1 + ply.lines().position(|l| l == "end_header").expect("header") + 9;
    assert!(
        err.contains("ten.ply")
            && err.contains(&format!("line {face_line}:"))
            && err.contains("element `vertex` ends early, after 8 of the 10 records"),
        "{err}"
    );
}

#[test]
fn fixed_size_arrays_of_another_length_are_refused_with_key_and_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (name, from, to, line) in [
        ("resolution.toml", "[64, 48]", "[160, 120, 7]", "line 2"),
        ("eye.toml", "[0.0, 6.0, 8.0]", "[0.0, 6.0, 8.0, \"far\"]", "line 4"),
        ("direction.toml", "[-0.3, -1.0, -0.2]", "[-0.3, -1.0]", "line 8"),
    ] {
        let path = write(dir.path(), name, &VALID.replace(from, to));
        let (code, err) = visibility(&path).expect_err(name);
        assert_eq!(code, Some(2), "{name}: {err}");
        // The message quotes the line, which holds the key.
        let key = name.trim_end_matches(".toml");
        assert!(
            err.contains(name) && err.contains(line) && err.contains(&format!("{key} = {to}")),
            "{name}: {err}"
        );
    }
}

/// [`VALID`] with a cage casting a shadow on the plane.
fn with_caster() -> String {
    format!("{VALID}[[object]]\nshape.cage = {{}}\n")
}

#[test]
fn light_directions_of_any_finite_magnitude_cast_the_same_shadows() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = with_caster();
    let plain = visibility(&write(dir.path(), "plain.toml", &scene)).expect("renders");
    // Powers of two about 1e154 and 1e-170, whose squared lengths overflow and underflow: the
    // direction is exactly the same.
    for k in [512, -560] {
        let s = 2f64.powi(k);
        let d = format!("[{:e}, {:e}, {:e}]", -0.3 * s, -s, -0.2 * s);
        let name = format!("direction-2^{k}.toml");
        let path = write(dir.path(), &name, &scene.replace("[-0.3, -1.0, -0.2]", &d));
        let got = visibility(&path).unwrap_or_else(|e| panic!("{name}: {e:?}"));
        assert!(got == plain, "{name} casts other shadows");
    }
}

#[test]
fn meshes_near_the_ends_of_f64_fit_like_any_other() {
    let dir = tempfile::tempdir().expect("tempdir");
    let plain = visibility(&write(dir.path(), "plain.obj", CUBE_OBJ)).expect("renders");
    // The cube's 0 and 1 mapped to -2^1023 and 2^1023 (its extent overflows), or to 0 and
    // 2^-1070 (subnormal).
    for (name, map) in [
        ("huge.obj", (|c: f64| (2.0 * c - 1.0) * 2f64.powi(1023)) as fn(f64) -> f64),
        ("subnormal.obj", |c: f64| c * f64::MIN_POSITIVE * 2f64.powi(-48)),
    ] {
        let text: String = CUBE_OBJ
            .lines()
            .map(|line| match line.strip_prefix("v ") {
                Some(xyz) => {
                    let xyz: Vec<String> = xyz
                        .split_whitespace()
                        .map(|c| format!("{:e}", map(c.parse().expect("number"))))
                        .collect();
                    format!("v {}\n", xyz.join(" "))
                }
                None => format!("{line}\n"),
            })
            .collect();
        let got =
            visibility(&write(dir.path(), name, &text)).unwrap_or_else(|e| panic!("{name}: {e:?}"));
        assert!(got == plain, "{name} renders differently from plain.obj");
    }
}

#[test]
fn scenes_beyond_the_supported_range_are_refused_naming_the_range() {
    let dir = tempfile::tempdir().expect("tempdir");
    write(dir.path(), "model.obj", "v 0 0 0\nv 1 0 0\nv 0 3.2e20 0\nf 1 2 3\n");
    let model = format!("{VALID}[[object]]\nshape.file = {{ path = \"model.obj\" }}\n");
    let far_eye = VALID.replace("eye = [0.0, 6.0, 8.0]", "eye = [0.0, 6.0, 2e15]");
    for (name, text, needles) in [
        ("model.toml", model, &["`object[1]`", "(model.obj)", "coordinates reach 3.2e20"][..]),
        ("eye.toml", far_eye, &["`camera.perspective.eye`", "coordinates reach 2e15"][..]),
    ] {
        let path = write(dir.path(), name, &text);
        let (code, err) = visibility(&path).expect_err(name);
        assert_eq!(code, Some(2), "{name}: {err}");
        assert!(
            err.contains(name) && err.contains("beyond the supported range |x| <= 1e15"),
            "{err}"
        );
        for n in needles {
            assert!(err.contains(n), "{name}: message lacks `{n}`: {err}");
        }
    }
}

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
            &["camera.perspective.fov_y_deg"],
        ),
        (
            "bad-opacity.toml",
            format!("{VALID}material = {{ opacity = 2.0 }}\n"),
            &["object[0].material.opacity"],
        ),
        (
            "bad-generator.toml",
            VALID.replace("size = 10.0", "size = -1.0"),
            &["object[0].shape.plane.size"],
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

/// The filtered maps' storage precision and light-bleeding reduction: a precision the method
/// does not store (named with those it does), a name that is no precision, and reductions
/// outside [0, 1) exit 2 naming the flag.
#[test]
fn bad_precisions_and_bleeding_reductions_are_named() {
    let cases: &[(&str, &[&str], &[&str])] = &[
        ("vsm", &["--precision", "u16"], &["--precision: `vsm` stores f16, f32, f64, got u16"]),
        ("esm", &["--precision", "u16"], &["--precision: `esm` stores f16, f32, f64, got u16"]),
        ("msm", &["--precision", "f16"], &["--precision: `msm` stores u16, f32, f64, got f16"]),
        ("msm", &["--precision", "f8"], &["--precision", "f8", "f16, f32, f64, u16"]),
        ("vsm", &["--bleeding-reduction", "1"], &["--bleeding-reduction", "below 1"]),
        ("msm", &["--bleeding-reduction=-0.1"], &["--bleeding-reduction", "at least 0"]),
        ("vsm", &["--bleeding-reduction", "nan"], &["--bleeding-reduction"]),
        ("msm", &["--bleeding-reduction", "half"], &["--bleeding-reduction"]),
    ];
    for (method, extra, needles) in cases {
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("out");
        let o = render_into(&out, "cage", method, extra);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{method} {extra:?}: {err}");
        for n in *needles {
            assert!(err.contains(n), "{method} {extra:?}: `{n}` not in {err}");
        }
        assert!(!out.join("visibility.exr").exists(), "{method} {extra:?}: ran");
    }
}

/// `--out` that cannot take the files is refused before anything is computed, for every
/// command that writes (it used to fail with "internal error" after the whole run).
#[test]
fn an_out_folder_that_cannot_be_written_is_named_before_computing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = write(dir.path(), "a-file", "not a folder");
    let under_file = format!("{file}/out");
    let render = ["render", "--scene", "cage", "--method", "sm", "--width", "32", "--height", "24"];
    let compare = [&["compare"][..], &render[1..], &["--reference", "exact"]].concat();
    let report = ["report", "--suite", "quick"];
    for command in [&render[..], &compare[..], &report[..]] {
        for (out, why) in [
            (file.as_str(), "a file is in the way"),
            (&under_file, "a-file is a file, not a folder"),
        ] {
            let o = shadowbench(&[command, &["--out", out]].concat());
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{command:?} --out {out}: {err}");
            assert!(err.contains(&format!("--out {out}")) && err.contains(why), "{err}");
        }
    }
}

/// A rate a method refuses is named with exactly the rates that method takes (`pan09`,
/// `afsm-ss` and `spsm` used to list the references' rates up to 1024, which they refuse).
#[test]
fn bad_rates_list_exactly_the_rates_of_the_method() {
    for (method, rate, takes) in [
        ("pan09", "0", "1, 4, 8, 16, 32, 64, 128 samples"),
        ("afsm-ss", "0", "1, 4, 8, 16, 32, 64, 128 samples"),
        ("spsm", "0", "1, 4, 8, 16, 32, 64, 128 samples"),
        ("spsm-f32", "256", "1, 4, 8, 16, 32, 64, 128 samples"),
        ("pcf-reeves", "3", "1, 4, 8, 16, 32, 64, 128, 256, 512, 1024 samples"),
    ] {
        let dir = tempfile::tempdir().expect("tempdir");
        let o = render_into(&dir.path().join("out"), "cage", method, &["--rate", rate]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{method} --rate {rate}: {err}");
        assert!(err.contains("--rate") && err.contains(&format!("takes {takes}")), "{err}");
    }
}

/// Extreme and malformed flag values: exit 2 naming the flag (or both frame flags and the
/// limit), never a panic, an abort or a misleading name.
#[test]
fn extreme_flag_values_are_named() {
    let sm = ["--method", "sm"];
    let frame = ["--width", "32", "--height", "24"];
    let cases: &[(Vec<&str>, &[&str])] = &[
        (
            [&sm[..], &["--width", "16384", "--height", "16384"]].concat(),
            &["--width and --height", "33554432"],
        ),
        ([&sm[..], &["--width", "4000000000"]].concat(), &["--width", "16384"]),
        (
            vec!["--method", "afsm-ss", "--rate", "128", "--width", "1920", "--height", "1080"],
            &["--width, --height and --rate", "134217728"],
        ),
        ([&sm[..], &["--width", "100000", "--height", "1"]].concat(), &["--width"]),
        ([&sm[..], &["--width", "-5"]].concat(), &["--width"]),
        ([&sm[..], &["--width", "wide"]].concat(), &["--width"]),
        ([&sm[..], &frame, &["--map-res", "1000000"]].concat(), &["--map-res"]),
        ([&sm[..], &frame, &["--seed", "-1"]].concat(), &["--seed"]),
        ([&sm[..], &frame, &["--slope-bias", "-1"]].concat(), &["--slope-bias"]),
        (
            [&["--method", "pcf-bs-2x2"][..], &frame, &["--depth-bits", "2147483648"]].concat(),
            &["--depth-bits"],
        ),
        (
            [&["--method", "pcf-bs-2x2"][..], &frame, &["--depth-bits", "4000000000"]].concat(),
            &["--depth-bits", "8, 12, 24, 32"],
        ),
    ];
    for (extra, needles) in cases {
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("out");
        let args =
            [&["render", "--scene", "cage"][..], extra, &["--out", out.to_str().expect("utf-8")]]
                .concat();
        let o = shadowbench(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        for n in *needles {
            assert!(err.contains(n), "{args:?}: `{n}` not in {err}");
        }
        assert!(!out.join("visibility.exr").exists(), "{args:?}: ran");
    }
}

#[cfg(feature = "gpu")]
/// Renders `cage` with `sm` on the GPU with the environment variable `key` set to `value`;
/// returns (exit code, stderr).
fn gpu_render_with(key: &str, value: &str) -> (Option<i32>, String) {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_shadowbench"))
        .args(["render", "--scene", "cage", "--method", "sm", "--device", "gpu"])
        .args(["--width", "32", "--height", "24", "--out"])
        .arg(tempfile::tempdir().expect("tempdir").path().join("out"))
        .env(key, value)
        .output()
        .expect("the shadowbench binary runs");
    (o.status.code(), stderr(&o))
}

/// The GPU environment variables are bad input named as such, before any computation.
#[cfg(feature = "gpu")]
#[test]
fn a_bad_gpu_backend_variable_is_named_with_the_allowed_values() {
    let (code, err) = gpu_render_with("SHADOWBENCH_GPU_BACKEND", "warp-drive");
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("SHADOWBENCH_GPU_BACKEND") && err.contains("warp-drive"), "{err}");
    assert!(err.contains("vulkan, gl, metal, dx12"), "{err}");
}

/// `SHADOWBENCH_GPU_ADAPTER` that matches no adapter is named, with the adapters found (it was
/// reported as "no adapter with 64-bit floats"). Without any adapter the message says so
/// instead; both are bad input.
#[cfg(feature = "gpu")]
#[test]
fn a_gpu_adapter_variable_matching_nothing_is_named_with_the_adapters_found() {
    let (code, err) = gpu_render_with("SHADOWBENCH_GPU_ADAPTER", "no-such-adapter-name");
    assert_eq!(code, Some(2), "{err}");
    if err.contains("no GPU adapter found") {
        eprintln!("no adapter on this machine: {err}");
        return;
    }
    assert!(
        err.contains("SHADOWBENCH_GPU_ADAPTER") && err.contains("no-such-adapter-name"),
        "{err}"
    );
    assert!(err.contains("adapters found:") && !err.contains("64-bit"), "{err}");
}

/// A map larger than the GPU adapter's binding limit (llvmpipe takes 128 MiB) is bad input
/// naming `--map-res`, not a device failure; an adapter with larger limits renders it.
#[cfg(feature = "gpu")]
#[test]
fn a_map_beyond_the_gpu_limits_is_bad_input_naming_the_flag() {
    let (code, err) = render("cage", &["--device", "gpu", "--map-res", "8192"]);
    if err.contains("no GPU adapter found") {
        eprintln!("no adapter on this machine: {err}");
        return;
    }
    assert!(code == Some(0) || code == Some(2), "{code:?}: {err}");
    if code == Some(2) {
        assert!(err.contains("GPU adapter's limits") && err.contains("--map-res"), "{err}");
    }
}

/// A run whose estimated memory (`analysis::budget`) exceeds `--max-memory` is refused (exit
/// 2) before anything is built or written, naming the estimate, the limit and what to lower;
/// `report` refuses a suite by its heaviest item the same way; a size that is not one is named.
#[test]
fn runs_over_the_memory_budget_are_refused_before_anything_is_built() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    for (method, extra) in [("sm", &[][..]), ("raytrace", &["--rate", "16"][..])] {
        let args = [&["--max-memory", "16M"][..], extra].concat();
        let o = render_into(&out, "cage", method, &args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{method}: {err}");
        assert!(
            err.contains(&format!("{method} on cage at 32x24 needs about"))
                && err.contains("more than the 16 MB of --max-memory")
                && err.contains("lower"),
            "{err}"
        );
        assert!(!out.exists(), "nothing written");
    }
    let o = render_into(&out, "cage", "sm", &["--max-memory", "1G"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = shadowbench(&["compare", "--scene", "cage", "--method", "sm", "--max-memory", "16M"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("needs about"), "{}", stderr(&o));
    let report = dir.path().join("report");
    let o = shadowbench(&[
        "report",
        "--suite",
        "quick",
        "--max-memory",
        "16M",
        "--out",
        report.to_str().expect("utf-8"),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--suite quick: item") && stderr(&o).contains("needs about"));
    assert!(!report.exists(), "nothing written");
    let (code, err) = render("cage", &["--max-memory", "lots"]);
    assert_eq!(code, Some(2));
    assert!(err.contains("--max-memory") && err.contains("`lots` is not a size"), "{err}");
}

/// `ftizb`'s grid size and rates: a grid beyond 4096 texels, a rate its masks cannot hold and
/// a grid that is no number exit 2 naming the flag, and nothing is written.
#[test]
fn bad_ftizb_grids_and_rates_are_named() {
    let cases: &[(&[&str], &[&str])] = &[
        (&["--izb-res", "5000"], &["--izb-res", "1..=4096"]),
        (&["--izb-res", "big"], &["--izb-res"]),
        (&["--rate", "256"], &["--rate"]),
        (&["--rate", "3"], &["--rate"]),
    ];
    for (extra, needles) in cases {
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("out");
        let o = render_into(&out, "cage", "ftizb", extra);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        for n in *needles {
            assert!(err.contains(n), "{extra:?}: `{n}` not in {err}");
        }
        assert!(!out.exists() || !out.join("visibility.exr").exists(), "{extra:?}: ran");
    }
}
