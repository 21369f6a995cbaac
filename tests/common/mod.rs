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

/// The machine, as the tests of one binary share it: a test that measures times holds it
/// alone ([`machine_alone`]), every test that runs reports holds it with the others
/// ([`machine_shared`]), so that a timing test's quiet run is not loaded by its neighbours.
static MACHINE: std::sync::RwLock<()> = std::sync::RwLock::new(());

/// Holds the machine with the other tests that share it (see [`MACHINE`]).
pub fn machine_shared() -> std::sync::RwLockReadGuard<'static, ()> {
    MACHINE.read().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Holds the machine alone (see [`MACHINE`]).
pub fn machine_alone() -> std::sync::RwLockWriteGuard<'static, ()> {
    MACHINE.write().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Every method that looks up a light depth map.
pub const MAP_METHODS: &[&str] = &[
    "sm",
    "pcf-reeves",
    "pcf-bs-2x2",
    "pcf-bs-fast-2x2",
    "pcf-bs-fast-4x4",
    "pcf-gems16",
    "pcf-gems4",
    "pan09",
];

/// Runs the `shadowbench` binary with `args`, with `XDG_CACHE_HOME` in a folder of this test
/// process ([`test_cache_home`]), so that `compare`'s default reference cache is the tests' own.
pub fn shadowbench(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_shadowbench"))
        .args(args)
        .env("XDG_CACHE_HOME", test_cache_home())
        .output()
        .expect("the shadowbench binary runs")
}

/// The `XDG_CACHE_HOME` of the binaries this test process runs: a temporary folder of its own.
pub fn test_cache_home() -> &'static Path {
    static HOME: std::sync::OnceLock<tempfile::TempDir> = std::sync::OnceLock::new();
    HOME.get_or_init(|| tempfile::tempdir().expect("a temporary cache folder")).path()
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
        animation: Default::default(),
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

/// A report's `runs.json` without what depends on where and when it ran: its provenance,
/// machine, shards and cache counts, every run's times (both clocks, the timed runs' count,
/// contention and load) and shard, every scene's times, the papers' tables' runs' times and
/// every paper's table (whose cells are times).
pub fn report_without_times(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("runs.json")).expect("runs.json");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("runs.json parses");
    let o = v.as_object_mut().expect("an object");
    for k in ["provenance", "machine", "shards", "cache", "tables"] {
        o.remove(k);
    }
    for row in o["rows"].as_array_mut().expect("rows") {
        let row = row.as_object_mut().expect("a row");
        for k in ["total_ms", "cpu_ms", "contended", "conditions", "stages", "shard"] {
            row.remove(k);
        }
    }
    for run in o["table_runs"].as_array_mut().into_iter().flatten() {
        let run = run.as_object_mut().expect("a table's run");
        for k in ["total_ms", "cpu_ms", "contended", "stages", "shard", "gbuffer_ms"] {
            run.remove(k);
        }
    }
    for scene in o["scenes"].as_array_mut().expect("scenes") {
        let scene = scene.as_object_mut().expect("a scene");
        for k in ["gbuffer_ms", "gbuffer_cpu_ms", "reference_ms"] {
            scene.remove(k);
        }
    }
    v
}

/// Panics, naming the first difference, unless the reports in `a` and `b` are equal on every
/// field but times, machine and provenance ([`report_without_times`]).
pub fn assert_same_report(a: &Path, b: &Path) {
    let (x, y) = (report_without_times(a), report_without_times(b));
    if x == y {
        return;
    }
    let (xr, yr) = (&x["rows"], &y["rows"]);
    assert_eq!(
        xr.as_array().map(Vec::len),
        yr.as_array().map(Vec::len),
        "{} and {}: not as many runs",
        a.display(),
        b.display()
    );
    for (k, (p, q)) in
        xr.as_array().into_iter().flatten().zip(yr.as_array().into_iter().flatten()).enumerate()
    {
        assert_eq!(p, q, "run {k} differs between {} and {}", a.display(), b.display());
    }
    for key in ["suite", "scenes", "skipped", "grids"] {
        assert_eq!(x[key], y[key], "`{key}` differs between {} and {}", a.display(), b.display());
    }
    panic!("{} and {} differ", a.display(), b.display());
}
