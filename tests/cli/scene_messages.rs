//! Scene messages that name the real cause: a folder named as a mesh, a coordinate just beyond
//! the supported range, a PLY with more vertex lines than it declares, an empty mesh path, a
//! mesh missing from every place looked in (scene files look beside themselves, then in the
//! models folder), a mesh file given as the scene; and a scene of too many triangles, refused
//! before anything is built.

use crate::common::{stderr, write};
use std::path::Path;
use std::process::{Command, Output};

/// A scene file's camera and light, without objects.
const VIEW: &str = r#"resolution = [64, 48]
[camera.perspective]
eye = [0.0, 6.0, 8.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 45.0
[light.directional]
direction = [-0.3, -1.0, -0.2]
"#;

/// A scene file with [`VIEW`] and one object made of a mesh file at `path`.
fn with_mesh(path: &str) -> String {
    format!("{VIEW}[[object]]\nshape.file = {{ path = \"{path}\" }}\n")
}

/// A triangle in OFF.
const TRIANGLE_OFF: &str = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

/// Renders `scene` with `sm` at 32 x 24 into `dir/out`, with `$SHADOWBENCH_MODELS` set to
/// `models` when given.
fn render(dir: &Path, scene: &str, models: Option<&Path>) -> Output {
    let out = dir.join("out");
    let mut command = Command::new(env!("CARGO_BIN_EXE_shadowbench"));
    command.args(["render", "--scene", scene, "--method", "sm", "--width", "32", "--height", "24"]);
    command.arg("--out").arg(&out);
    if let Some(models) = models {
        command.env("SHADOWBENCH_MODELS", models);
    }
    command.output().expect("the shadowbench binary runs")
}

/// The message of a refused render: exit code 2 and one error line.
fn refused(dir: &Path, scene: &str, models: Option<&Path>) -> String {
    let o = render(dir, scene, models);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{scene}: {err}");
    assert_eq!(err.lines().filter(|l| l.starts_with("error")).count(), 1, "{err}");
    err
}

#[test]
fn a_folder_named_as_a_mesh_is_a_folder_not_missing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let folder = dir.path().join("dir.obj");
    std::fs::create_dir(&folder).expect("mkdir");
    let err = refused(dir.path(), folder.to_str().expect("utf-8"), None);
    assert!(err.contains("dir.obj: is a folder, not a mesh file"), "{err}");
    let scene = write(dir.path(), "folder.toml", &with_mesh("dir.obj"));
    let err = refused(dir.path(), &scene, None);
    assert!(
        err.contains("folder.toml: line 9: `object[0].shape.file.path`: ")
            && err.contains("dir.obj: is a folder, not a mesh file")
            && !err.contains("missing"),
        "{err}"
    );
}

#[test]
fn a_coordinate_just_beyond_the_range_reads_apart_from_its_bound() {
    let dir = tempfile::tempdir().expect("tempdir");
    // A plane of side 2 moved 1e15 along x: its far edge is at 1e15 + 1.
    let text = format!(
        "{VIEW}[[object]]\nshape.plane = {{ size = 2.0 }}\n\
         transform = {{ translate = [1e15, 0.0, 0.0] }}\n"
    );
    let err = refused(dir.path(), &write(dir.path(), "far.toml", &text), None);
    assert!(
        err.contains(
            "coordinates reach 1.000000000000001e15, beyond the supported range |x| <= 1e15"
        ),
        "{err}"
    );
}

#[test]
fn a_ply_with_more_vertex_lines_than_declared_says_so() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cube = include_str!("../../scenes/tests/data/cube.ply");
    let ply = cube.replace("element vertex 8", "element vertex 7");
    let err = refused(dir.path(), &write(dir.path(), "seven.ply", &ply), None);
    // The eighth vertex is on the line where the first face was expected.
    let line = 1 + ply.lines().position(|l| l == "end_header").expect("a header") + 8;
    assert!(
        err.contains(&format!(
            "seven.ply: line {line}: line 4 declares 7 `vertex` records, but more follow: this \
             line reads as one, not as `face` 0"
        )),
        "{err}"
    );
}

#[test]
fn an_empty_mesh_path_is_named_as_empty() {
    let dir = tempfile::tempdir().expect("tempdir");
    let err = refused(dir.path(), &write(dir.path(), "empty.toml", &with_mesh("")), None);
    assert!(
        err.contains("empty.toml: line 9: `object[0].shape.file.path`: the path is empty")
            && !err.contains("unsupported")
            && !err.contains("missing"),
        "{err}"
    );
}

#[test]
fn scene_files_find_their_meshes_beside_them_then_in_the_models_folder() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (scenes, models) = (dir.path().join("scenes"), dir.path().join("models"));
    for folder in [&scenes, &models] {
        std::fs::create_dir(folder).expect("mkdir");
    }
    write(&models, "m.off", TRIANGLE_OFF);
    let found = write(&scenes, "found.toml", &with_mesh("m.off"));
    let o = render(dir.path(), &found, Some(&models));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));

    let lost = write(&scenes, "lost.toml", &with_mesh("gone.off"));
    let err = refused(dir.path(), &lost, Some(&models));
    let (beside, in_models) = (scenes.join("gone.off"), models.join("gone.off"));
    assert!(
        err.contains(&format!(
            "needs gone.off, which is missing (looked for {} and {})",
            beside.display(),
            in_models.display()
        )),
        "{err}"
    );

    // A built-in's model is looked for in the models folder, which the message names.
    let err = refused(dir.path(), "bunny-plane", Some(&models));
    assert!(
        err.contains(&format!(
            "needs bunny00.off, which is missing (looked for {})",
            models.join("bunny00.off").display()
        )) && err.contains("scripts/fetch-models"),
        "{err}"
    );
}

#[test]
fn a_bad_mesh_given_as_the_scene_is_named_by_its_file_and_line_alone() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = write(dir.path(), "bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    let err = refused(dir.path(), &path, None);
    assert!(
        err.contains(&format!("{path}: line 4: vertex index 4 out of range"))
            && !err.contains("object[")
            && !err.contains("shape.file"),
        "{err}"
    );
}

#[test]
fn ten_objects_of_19m_triangles_are_refused_before_anything_is_built() {
    let dir = tempfile::tempdir().expect("tempdir");
    // The first object's mesh has a sound header and a broken body, so that building anything
    // would fail on it before the limit is checked.
    write(dir.path(), "broken.off", &TRIANGLE_OFF.replace("1 0 0", "1 x 0"));
    let big = "[[object]]\nshape.random_triangles = { count = 19000000 }\n".repeat(10);
    let text = format!("{}{big}", with_mesh("broken.off"));
    let err = refused(dir.path(), &write(dir.path(), "ten.toml", &text), None);
    assert!(
        err.contains("ten.toml: the scene has 19000")
            && err.contains("triangles, more than the limit of 40000000")
            && err.contains("`object[1]`, has 19000000"),
        "{err}"
    );
}
