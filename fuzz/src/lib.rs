//! Fuzz targets: one function per parser, each taking the fuzzer's bytes and panicking only
//! when the code under test breaks its contract.
//!
//! The same functions run under AFL++ (the binary of `src/main.rs`, built by `cargo afl build`)
//! and in the workspace test `tests/cli/fuzz_regressions.rs`, which includes this file by `#[path]`
//! and replays every input saved in `tests/data/fuzz/<target>/`. That is why this file uses
//! only `std`, `glam`, `scenes` and `reports`, which both builds have.
//!
//! A target passes when the call returns `Ok` or `Err` without panicking. On top of that:
//!
//! - `obj`, `off`, `ply` (the mesh loaders): an `Ok` mesh has at least one triangle, only
//!   finite coordinates and only indices in range, checked here independently of
//!   `Mesh::validate`.
//! - `scene` (the scene-file parser): when the text parses, the description is resolved, and an
//!   `Ok` scene is checked against what resolution promises: meshes checked the same way, every
//!   vertex, camera point and spot-light point within `limits::MAX_COORDINATE`, a bounding-box
//!   diagonal of at least `limits::MIN_EXTENT`, a directional light of unit direction; the
//!   same of the scene posed at its first, middle and last frames (an animation is checked for
//!   every time it may be sampled at), each pose still and with the rest scene's triangles.
//!   Shapes that name a mesh file are resolved
//!   against [`NO_MESH_FOLDER`], a folder that does not exist, and only when the path is
//!   relative and made of plain names, so no input reads the disk (every such file is then
//!   missing); a description whose file paths are anything else is parsed but not resolved.
//!   The mesh loaders themselves are the other targets.
//! - `suite` (the report-suite parser): `Suite::parse`. It checks that every scene a suite
//!   names is a built-in or a scene or mesh file that loads, so a fuzzed suite can make it
//!   read a file (one with a `.toml`, `.obj`, `.off` or `.ply` extension, never written); a
//!   mutated name is seldom the path of a real file.
//!
//! The text parsers read their bytes lossily as UTF-8 (invalid sequences become U+FFFD), so
//! that a stray byte does not hide the rest of the input from them.
//!
//! Each function returns whether the input was accepted (the mesh loaded, the scene parsed and
//! resolved or failed only on its missing mesh file, the suite parsed), so that the regression
//! test can check that the seeds are valid files.

use scenes::io::{load_mesh_from_bytes, MeshFormat};
use scenes::limits::{MAX_COORDINATE, MIN_EXTENT};
use scenes::scene_file::Shape;
use scenes::{Camera, Light, Mesh, Scene, SceneDesc, SceneError};
use std::path::{Component, Path};

/// A fuzz target: runs the fuzzer's bytes through one parser and returns whether they were
/// accepted; panics when the parser breaks its contract.
pub type Target = fn(&[u8]) -> bool;

/// The targets, by the names `scripts/fuzz` and `tests/data/fuzz/` use.
pub const TARGETS: &[(&str, Target)] =
    &[("obj", obj), ("off", off), ("ply", ply), ("scene", scene), ("suite", suite)];

/// The folder that mesh files named by fuzzed scene files are looked up in: one that does not
/// exist, so that every such file is missing.
pub const NO_MESH_FOLDER: &str = "/nonexistent/shadowbench-fuzz";

/// The OBJ loader.
pub fn obj(data: &[u8]) -> bool {
    mesh(data, MeshFormat::Obj, "fuzz.obj")
}

/// The OFF loader.
pub fn off(data: &[u8]) -> bool {
    mesh(data, MeshFormat::Off, "fuzz.off")
}

/// The PLY loader (ASCII and binary).
pub fn ply(data: &[u8]) -> bool {
    mesh(data, MeshFormat::Ply, "fuzz.ply")
}

/// The scene-file parser, then resolution of what parses.
pub fn scene(data: &[u8]) -> bool {
    let text = String::from_utf8_lossy(data);
    let origin = Path::new("fuzz.toml");
    let Ok(desc) = SceneDesc::from_toml(&text, origin) else { return false };
    let base = Path::new(NO_MESH_FOLDER);
    if base.exists() || !desc.objects.iter().all(|o| stays_in_base(&o.shape)) {
        return true;
    }
    match desc.resolve("fuzz", origin, base) {
        Ok(scene) => {
            check_scene(&scene);
            let animation = &scene.animation;
            let last = animation.frames().saturating_sub(1);
            for i in [0, last / 2, last] {
                let posed = animation.pose(&scene, i);
                assert!(posed.animation.is_still(), "frame {i}: a pose that moves");
                assert_eq!(posed.geometry().triangles, scene.geometry().triangles, "frame {i}");
                check_scene(&posed);
            }
            true
        }
        Err(SceneError::ModelMissing { .. }) => true,
        Err(_) => false,
    }
}

/// The report-suite parser.
pub fn suite(data: &[u8]) -> bool {
    let text = String::from_utf8_lossy(data);
    reports::suite::Suite::parse(&text, Path::new("fuzz.toml")).is_ok()
}

fn mesh(data: &[u8], format: MeshFormat, name: &str) -> bool {
    let Ok(mesh) = load_mesh_from_bytes(data, format, Path::new(name)) else { return false };
    check_mesh(&mesh, name);
    true
}

/// Whether `shape` reads no file, or a file whose path stays inside the folder it is joined to.
fn stays_in_base(shape: &Shape) -> bool {
    match shape {
        Shape::File(file) => {
            !file.path.as_os_str().is_empty()
                && file.path.components().all(|c| matches!(c, Component::Normal(_)))
        }
        _ => true,
    }
}

/// Panics unless `scene` is what `SceneDesc::resolve` promises (see the module documentation).
fn check_scene(scene: &Scene) {
    let within = |p: glam::DVec3| p.abs().max_element() <= MAX_COORDINATE;
    for object in &scene.objects {
        let what = format!("scene object `{}`", object.name);
        check_mesh(&object.mesh, &what);
        if let Some(p) = object.mesh.positions.iter().find(|&&p| !within(p)) {
            panic!("{what}: accepted vertex {p} beyond {MAX_COORDINATE:e}");
        }
    }
    let (Camera::Perspective { eye, target, .. } | Camera::Orthographic { eye, target, .. }) =
        &scene.camera;
    assert!(within(*eye) && within(*target), "accepted camera {eye} -> {target}");
    match &scene.light {
        Light::Directional { direction } => {
            assert!((direction.length() - 1.0).abs() < 1e-12, "light direction {direction}");
        }
        Light::Spot { position, target, .. } => {
            assert!(within(*position) && within(*target), "accepted spot {position} -> {target}");
        }
    }
    let (lo, hi) = scene.bounds();
    let diagonal = (hi - lo).length();
    assert!(diagonal >= MIN_EXTENT, "accepted geometry of diagonal {diagonal:e}");
}

/// Panics unless `mesh` is what every consumer may assume of a loaded mesh.
fn check_mesh(mesh: &Mesh, what: &str) {
    assert!(!mesh.triangles.is_empty(), "{what}: accepted a mesh without triangles");
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        panic!("{what}: accepted vertex {i} at {}", mesh.positions[i]);
    }
    let count = mesh.positions.len();
    if let Some(t) = mesh.triangles.iter().position(|t| t.iter().any(|&v| v as usize >= count)) {
        panic!("{what}: triangle {t} is {:?} with {count} vertices", mesh.triangles[t]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scenes::scene_file::FileShape;

    fn file(path: &str) -> Shape {
        Shape::File(FileShape { path: path.into() })
    }

    #[test]
    fn only_plain_relative_mesh_paths_are_resolved() {
        assert!(stays_in_base(&file("models/bunny.off")));
        for path in ["", "/etc/passwd", "../x.obj", "a/../../x.obj", "./x.obj"] {
            assert!(!stays_in_base(&file(path)), "{path}");
        }
        assert!(!Path::new(NO_MESH_FOLDER).exists());
    }

    #[test]
    #[should_panic(expected = "light direction")]
    fn a_light_of_non_unit_direction_fails_the_scene_check() {
        let text = "[camera.orthographic]\neye = [0.0, 5.0, 0.1]\ntarget = [0.0, 0.0, 0.0]\n\
                    height = 10.0\n[light.directional]\ndirection = [0.0, -2.0, 0.0]\n\
                    [[object]]\nshape.plane = { size = 2.0 }\n";
        let desc = SceneDesc::from_toml(text, Path::new("t.toml")).expect("parses");
        let mut scene = desc.resolve("t", Path::new("t.toml"), Path::new(".")).expect("resolves");
        check_scene(&scene);
        scene.light = Light::Directional { direction: glam::DVec3::new(0.0, -2.0, 0.0) };
        check_scene(&scene);
    }

    #[test]
    #[should_panic(expected = "accepted vertex 1")]
    fn a_non_finite_vertex_fails_the_check() {
        let positions = vec![glam::DVec3::ZERO, glam::DVec3::new(f64::NAN, 0.0, 0.0)];
        check_mesh(&Mesh { positions, triangles: vec![[0, 1, 0]] }, "test");
    }

    #[test]
    #[should_panic(expected = "triangle 0 is [0, 1, 2] with 2 vertices")]
    fn an_index_out_of_range_fails_the_check() {
        let positions = vec![glam::DVec3::ZERO, glam::DVec3::X];
        check_mesh(&Mesh { positions, triangles: vec![[0, 1, 2]] }, "test");
    }
}
