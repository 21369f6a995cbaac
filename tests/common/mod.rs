//! Helpers shared by the workspace tests.
#![allow(dead_code)]

use glam::DVec3;
use scenes::{
    generators::PlaneParams,
    scene_file::{ObjectDesc, SceneDesc, Shape},
    Camera, Light, Material, Scene, SceneError,
};
use std::path::Path;
use std::process::{Command, Output};

/// Runs the `shadowbench` binary with `args`.
pub fn shadowbench(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_shadowbench"))
        .args(args)
        .output()
        .expect("the shadowbench binary runs")
}

/// Standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Writes `text` to `dir/name` and returns the path as a string.
pub fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("writes the test file");
    p.to_string_lossy().into_owned()
}

/// The built-in scene `name`, or `None` (with the reason printed) when its model is missing.
pub fn load_builtin(name: &str) -> Option<Scene> {
    match scenes::load(name) {
        Ok(scene) => Some(scene),
        Err(e @ SceneError::ModelMissing { .. }) => {
            eprintln!("skipping {name}: {e}");
            None
        }
        Err(e) => panic!("{name}: {e}"),
    }
}

/// A 12 x 12 plane alone under `light`, seen from above at 96 x 72: nothing shadows it, so
/// every pixel must come out lit.
pub fn lone_plane(light: Light) -> Scene {
    SceneDesc {
        name: Some("lone-plane".into()),
        resolution: [96, 72],
        camera: Camera::Perspective {
            eye: DVec3::new(0.0, 5.0, 9.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_deg: 50.0,
            near: 0.01,
        },
        light,
        effects: Default::default(),
        objects: vec![ObjectDesc {
            name: None,
            shape: Shape::Plane(PlaneParams { size: 12.0, subdivisions: 7 }),
            transform: Default::default(),
            material: Material::default(),
            casts_shadows: true,
        }],
    }
    .resolve("lone-plane", Path::new("test"), Path::new("."))
    .expect("valid scene")
}
