//! `afsm` on the GPU (an irregular z-buffer) against the CPU `afsm`, pixel for pixel, with the
//! CPU's own G-buffer uploaded; and one end-to-end run.

use crate::common::{load_builtin, write};
use glam::DVec3;
use instrumentation::Recorder;
use methods::{
    afsm::{AfsmOptions, AliasFreeShadowMap},
    gpu::{afsm as gpu_afsm, GpuContext, GpuFrame},
    Frame, ShadowMethod,
};
use scenes::{
    generators::PlaneParams,
    scene_file::{FileShape, ObjectDesc, SceneDesc, Shape},
    Camera, Light, Material, Scene,
};
use std::path::Path;

/// GPU and CPU `afsm` on `name` at 160 x 120: the number of differing pixels and of pairs
/// the GPU handed to the CPU (`None` when the scene's model is missing).
fn compare(name: &str) -> Option<(usize, u64)> {
    let scene = load_builtin(name)?;
    Some(compare_scene(&scene, 160, 120))
}

/// GPU and CPU `afsm` on `scene` at `width x height`: the number of differing pixels and of
/// pairs the GPU handed to the CPU.
fn compare_scene(scene: &Scene, width: u32, height: u32) -> (usize, u64) {
    let name = &scene.name;
    let frame = Frame::new(scene, width, height, &mut Recorder::default());
    let cpu = AliasFreeShadowMap::pixel_centres(AfsmOptions::default())
        .run(&frame, &mut Recorder::default())
        .expect("CPU afsm runs");
    let ctx = GpuContext::shared().expect("a GPU adapter (Mesa's lavapipe on CI)");
    let gpu = GpuFrame::upload(ctx, &frame, &frame.gbuffer);
    let mut rec = Recorder::default();
    let out = gpu_afsm::shade(ctx, &gpu, &frame, &mut rec).expect("GPU afsm runs");
    assert_eq!(out.lit.len(), cpu.lit.len());
    let differing = out.lit.iter().zip(&cpu.lit).filter(|(g, c)| g != c).count();
    let shadowed = cpu.lit.iter().filter(|&&l| l == 0.0).count();
    let times: Vec<String> =
        rec.stages.stages.iter().map(|s| format!("{} {:.2} ms", s.name, s.ms)).collect();
    eprintln!(
        "{name}: {differing} differing pixels, {} undecided pairs, {shadowed} shadowed, grid {}, \
         {} tests; {}",
        out.undecided,
        out.grid,
        rec.counters.sampling_points_tested,
        times.join(", ")
    );
    assert!(shadowed > 0, "{name}: no shadow at all");
    assert!(rec.counters.sampling_points_tested > 0);
    (differing, out.undecided)
}

fn assert_parity(name: &str) -> u64 {
    match compare(name) {
        Some((differing, undecided)) => {
            assert_eq!(differing, 0, "{name}: {differing} pixels differ from the CPU afsm");
            undecided
        }
        None => {
            eprintln!("{name}: skipped (model missing)");
            0
        }
    }
}

#[test]
fn gpu_parity_plane_square() {
    assert_parity("plane-square");
}

#[test]
fn gpu_parity_cage() {
    assert_parity("cage");
}

#[test]
fn gpu_parity_random_10k() {
    assert_parity("random-10k");
}

#[test]
fn gpu_parity_bumpy() {
    assert_parity("bumpy");
}

#[test]
fn gpu_parity_spot_spheres() {
    assert_parity("spot-spheres");
}

#[test]
fn gpu_parity_grazing() {
    assert_parity("grazing");
}

/// A 12 x 12 ground plane and one caster triangle whose edge runs along the light image's
/// diagonal, under a light straight down and a camera straight down at 64 x 64: the pixels on
/// the camera's anti-diagonal have surface points with `z == -x` exactly, which the light
/// maps exactly onto that diagonal, so `orient2d` of the edge and those samples is exactly
/// zero with non-zero terms: undecided for the filter, decided by the top-left rule on the
/// CPU.
fn edge_through_samples(dir: &Path) -> Scene {
    let obj = write(dir, "diagonal.obj", "v -2 1 2\nv 2 1 -2\nv 2 1 2\nf 1 2 3\n");
    let object = |shape| ObjectDesc {
        name: None,
        shape,
        transform: Default::default(),
        material: Material::default(),
        casts_shadows: true,
    };
    SceneDesc {
        name: Some("edge-through-samples".into()),
        resolution: [64, 64],
        camera: Camera::Perspective {
            eye: DVec3::new(0.0, 10.0, 0.0),
            target: DVec3::ZERO,
            up: DVec3::new(0.0, 0.0, -1.0),
            fov_y_deg: 60.0,
            near: 0.01,
        },
        light: Light::Directional { direction: DVec3::new(0.0, -1.0, 0.0) },
        effects: Default::default(),
        animation: Default::default(),
        objects: vec![
            object(Shape::Plane(PlaneParams { size: 12.0, subdivisions: 1 })),
            object(Shape::File(FileShape { path: obj.into() })),
        ],
    }
    .resolve("edge-through-samples", Path::new("test"), dir)
    .expect("valid scene")
}

#[test]
fn gpu_parity_edge_through_samples_goes_to_the_cpu() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = edge_through_samples(dir.path());
    let (differing, undecided) = compare_scene(&scene, 64, 64);
    assert_eq!(differing, 0, "{differing} pixels differ from the CPU afsm");
    assert!(undecided > 0, "no pair was handed to the CPU");
}

#[test]
fn gpu_afsm_runs_end_to_end() {
    let scene = scenes::load("plane-square").expect("built-in");
    let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
    let m = gpu_afsm::GpuAfsm { options: AfsmOptions::default() };
    assert_eq!(m.name(), "afsm");
    let cpu = AliasFreeShadowMap::pixel_centres(AfsmOptions::default());
    let mut want = cpu.params();
    want.insert("device".into(), "gpu".into());
    assert_eq!(m.params(), want);
    let mut rec = Recorder::default();
    let v = m.run(&frame, &mut rec).expect("GPU afsm runs");
    assert_eq!(v.lit.len(), 160 * 120);
    assert!(v.lit.iter().all(|l| l.is_finite() && (0.0..=1.0).contains(l)));
    assert!(v.lit.contains(&0.0) && v.lit.contains(&1.0));
    let stages: Vec<&str> = rec.stages.stages.iter().map(|s| s.name.as_str()).collect();
    for stage in [
        "transformation of samples",
        "IZB construction",
        "rasterization of blockers",
        "undecided tests (CPU)",
    ] {
        assert!(stages.contains(&stage), "stage {stage} missing from {stages:?}");
    }
    assert!(rec.counters.sampling_points_tested > 0);
    assert!(rec.notes.iter().any(|n| n.contains("undecided")), "{:?}", rec.notes);
}

#[test]
fn gpu_afsm_refuses_semi_transparent_casters() {
    let scene = scenes::load("plane-square").expect("built-in");
    let mut frame = Frame::new(&scene, 32, 24, &mut Recorder::default());
    frame.effects.transparency = true;
    let m = gpu_afsm::GpuAfsm { options: AfsmOptions::default() };
    let err = m.run(&frame, &mut Recorder::default()).expect_err("not applicable");
    assert!(matches!(err, methods::MethodError::NotApplicable(_)), "{err}");
}
