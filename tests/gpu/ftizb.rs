//! `ftizb` on the GPU (sub-samples on the tangent planes, one irregular z-buffer pass per
//! sub-sample) against the CPU `ftizb`, pixel for pixel and in each pixel's valid, shadowed
//! and hidden sub-sample counts, with the CPU's own G-buffer uploaded; and one end-to-end run
//! through the registry.

use crate::common::load_builtin;
use glam::DVec3;
use instrumentation::Recorder;
use methods::{
    ftizb::{Ftizb, FtizbOptions},
    gpu::{ftizb, GpuContext, GpuFrame},
    params::Device,
    pattern::PatternKind,
    Frame, MethodOptions,
};
use scenes::{Camera, Scene};

/// GPU and CPU `ftizb` at `rate` on `scene` at 96 x 72: the number of pixels whose light,
/// valid count, shadowed count or hidden count differ, the number of pixels with some
/// sub-samples outside their tangent plane's region or hidden (counted, but fewer than
/// `rate`), and the number of hidden sub-samples.
fn differing(scene: &Scene, rate: u32, pattern: PatternKind) -> (usize, usize, u64) {
    let frame = Frame::new(scene, 96, 72, &mut Recorder::default());
    let options = FtizbOptions { rate, pattern, ..FtizbOptions::default() };
    let (cpu, masks) =
        Ftizb { options }.run_masks(&frame, &mut Recorder::default()).expect("CPU ftizb runs");
    let ctx = GpuContext::shared().expect("a GPU adapter (Mesa's lavapipe on CI)");
    let gpu = GpuFrame::upload(ctx, &frame, &frame.gbuffer);
    let mut rec = Recorder::default();
    let out = ftizb::shade(ctx, &gpu, &frame, &options, &mut rec).expect("GPU ftizb runs");
    assert_eq!(out.lit.len(), cpu.lit.len());
    let mut differing = 0;
    for k in 0..cpu.lit.len() {
        let (o, v, h) = (masks.occlusion[k], masks.valid[k], masks.hidden[k]);
        let want = (cpu.lit[k], v.count_ones(), (o & v).count_ones(), h.count_ones());
        let got = (out.lit[k], out.valid[k], out.shadowed[k], out.hidden[k]);
        if want != got {
            if differing < 5 {
                eprintln!(
                    "{}: pixel {k}: CPU (lit, valid, shadowed, hidden) {want:?}, GPU {got:?}",
                    scene.name
                );
            }
            differing += 1;
        }
    }
    let partial = cpu.lit.iter().filter(|&&l| 0.0 < l && l < 1.0).count();
    let thinned = masks.valid.iter().filter(|v| (1..rate).contains(&v.count_ones())).count();
    let hidden: u64 = masks.hidden.iter().map(|h| u64::from(h.count_ones())).sum();
    eprintln!(
        "{} at {rate} {pattern:?}: {differing} differing pixels, {partial} partly lit, {thinned} \
         with sub-samples not counted, {hidden} hidden sub-samples, {} undecided",
        scene.name, out.undecided
    );
    assert!(cpu.lit.contains(&0.0), "{}: no shadow at all", scene.name);
    assert!(partial > 0, "{}: no pixel partly lit, so no sub-sample told apart", scene.name);
    assert!(rec.counters.sampling_points_tested > 0);
    // One entry per stage, summed over the sub-samples.
    let stages: Vec<&str> = rec.stages.stages.iter().map(|s| s.name.as_str()).collect();
    for stage in [
        "sample footprints",
        "transformation of samples",
        "IZB construction",
        "rasterization of blockers",
    ] {
        assert_eq!(stages.iter().filter(|s| **s == stage).count(), 1, "{stage}: {stages:?}");
    }
    assert!(rec.notes.iter().any(|n| n.contains(&format!("over {rate} sub-samples"))));
    (differing, thinned, hidden)
}

#[test]
fn gpu_parity_ftizb_on_the_parity_scenes() {
    for name in ["plane-square", "cage", "random-10k", "bumpy", "spot-spheres", "bunny-plane"] {
        match load_builtin(name) {
            Some(scene) => {
                let (d, _, hidden) = differing(&scene, 4, PatternKind::Grid);
                assert_eq!(d, 0, "{name}: {d} pixels differ from the CPU ftizb");
                if name == "bumpy" {
                    assert!(hidden > 0, "bumpy: no hidden sub-sample, so the rule is untested");
                }
            }
            None => eprintln!("{name}: skipped (model missing)"),
        }
    }
}

#[test]
fn gpu_parity_ftizb_rotated_at_rate_8() {
    for name in ["plane-square", "spot-spheres"] {
        let scene = load_builtin(name).expect("built-in");
        let (d, _, _) = differing(&scene, 8, PatternKind::Rotated);
        assert_eq!(d, 0, "{name}: {d} pixels differ from the CPU ftizb");
    }
}

/// A curved mesh with several triangles a pixel: tangent-plane sub-samples behind its surface
/// are hidden by the triangles in front of them, in the CPU's undecided pairs as on the GPU.
#[test]
fn gpu_parity_ftizb_hidden_sub_samples_on_bumpy_at_rate_8() {
    let scene = load_builtin("bumpy").expect("built-in");
    let (d, thinned, hidden) = differing(&scene, 8, PatternKind::Rotated);
    assert_eq!(d, 0, "bumpy: {d} pixels differ from the CPU ftizb");
    assert!(hidden > 0 && thinned > 0, "bumpy: no hidden sub-sample");
}

/// A camera just above the ground, looking along it (rolled a little, so that the horizon
/// crosses the pixels at every height): just below the horizon, the sub-samples above a
/// pixel's centre meet the ground's plane behind the camera or beyond 4 times the centre's
/// depth, so they are not valid and the pixel's ratio is over the others.
#[test]
fn gpu_parity_ftizb_with_sub_samples_beyond_the_region() {
    let mut scene = load_builtin("spot-spheres").expect("built-in");
    scene.camera = Camera::Perspective {
        eye: DVec3::new(0.0, 0.05, 7.9),
        target: DVec3::new(0.0, 0.05, 0.0),
        up: DVec3::new(0.1, 1.0, 0.0),
        fov_y_deg: 45.0,
        near: 0.01,
    };
    let (d, thinned, _) = differing(&scene, 8, PatternKind::Rotated);
    assert_eq!(d, 0, "{d} pixels differ from the CPU ftizb");
    assert!(thinned > 0, "no pixel with sub-samples beyond the region");
}

/// An orthographic camera nearly edge-on to the ground: the region is a span of 64 pixel
/// widths in depth, not a depth ratio, and the sub-samples beyond it are not valid.
#[test]
fn gpu_parity_ftizb_with_an_orthographic_camera() {
    let mut scene = load_builtin("spot-spheres").expect("built-in");
    scene.camera = Camera::Orthographic {
        eye: DVec3::new(0.0, 0.05, 7.9),
        target: DVec3::ZERO,
        up: DVec3::Y,
        height: 4.0,
    };
    let (d, thinned, _) = differing(&scene, 8, PatternKind::Rotated);
    assert_eq!(d, 0, "orthographic: {d} pixels differ from the CPU ftizb");
    assert!(thinned > 0, "orthographic: no pixel with sub-samples beyond the region");
}

#[test]
fn gpu_ftizb_runs_end_to_end_through_the_registry() {
    let scene = scenes::load("plane-square").expect("built-in");
    let frame = Frame::new(&scene, 64, 48, &mut Recorder::default());
    let options = MethodOptions { rate: Some(4), device: Device::Gpu, ..Default::default() };
    let m = methods::method("ftizb", &options).expect("ftizb has GPU kernels");
    assert_eq!(m.name(), "ftizb");
    let cpu = methods::method("ftizb", &MethodOptions { device: Device::Cpu, ..options.clone() })
        .expect("CPU ftizb");
    let mut want = cpu.params();
    want.insert("device".into(), "gpu".into());
    assert_eq!(m.params(), want);
    let mut rec = Recorder::default();
    let v = m.run(&frame, &mut rec).expect("GPU ftizb runs");
    assert_eq!(v.lit.len(), 64 * 48);
    assert!(v.lit.iter().all(|l| l.is_finite() && (0.0..=1.0).contains(l)));
    assert!(v.lit.contains(&0.0) && v.lit.contains(&1.0));
    assert!(v.lit.iter().any(|&l| 0.0 < l && l < 1.0), "no pixel partly lit");
    assert!(rec.notes.iter().any(|n| n.contains("over 4 sub-samples")), "{:?}", rec.notes);
    assert!(rec.stages.stages.iter().any(|s| s.name == "sample footprints"));
    // Its own G-buffer may keep another triangle than the CPU's where the hardware's coverage
    // differs: nearly every pixel is the CPU's.
    let c = cpu.run(&frame, &mut Recorder::default()).expect("CPU ftizb runs");
    let differing = v.lit.iter().zip(&c.lit).filter(|(g, c)| g != c).count();
    assert!(differing * 100 <= v.lit.len(), "{differing} pixels differ from the CPU's");
}

/// The CPU's resolution of undecided pairs, hidden test included, against the GPU's decisions:
/// one pass on `bumpy`'s sub-samples at one offset on their tangent planes, once decided on
/// the GPU and once with every pair that passes the depth test left to the CPU.
#[test]
fn gpu_parity_ftizb_hidden_sub_samples_decided_on_the_cpu() {
    use glam::DVec2;
    use methods::{
        gpu::afsm::{Izb, SampleSurface},
        raster::NO_TRIANGLE,
    };
    let scene = load_builtin("bumpy").expect("built-in");
    let frame = Frame::new(&scene, 48, 36, &mut Recorder::default());
    let g = &frame.gbuffer;
    let offset = DVec2::new(0.125, 0.875);
    // Each pixel's sub-sample at `offset` on its tangent plane (Ray::intersect_plane).
    let w = frame.width() as usize;
    let (mut triangle, mut depth) = (g.triangle.clone(), vec![0.0; g.triangle.len()]);
    for k in 0..g.triangle.len() {
        let ray = frame.camera.ray(DVec2::new((k % w) as f64, (k / w) as f64) + offset);
        let (n, p) = (g.normal[k], g.position[k]);
        match ray.intersect_plane(n, n.dot(p)) {
            Some(t) if g.covered(k) => depth[k] = t,
            _ => triangle[k] = NO_TRIANGLE,
        }
    }
    let ctx = GpuContext::shared().expect("a GPU adapter (Mesa's lavapipe on CI)");
    let gpu = GpuFrame::upload(ctx, &frame, g);
    let (triangle, depth) = (ctx.upload("triangle", &triangle), ctx.upload("depth", &depth));
    let surface = SampleSurface { triangle: &triangle, depth: &depth, offset };
    let pass = |all_on_the_cpu: bool| {
        let izb = Izb::new(ctx, &gpu, &frame);
        if all_on_the_cpu {
            izb.leave_every_pair_undecided(ctx);
        }
        izb.shadowed_and_hidden(ctx, surface, &mut Recorder::default()).expect("GPU pass")
    };
    let (on_gpu, on_cpu) = (pass(false), pass(true));
    let count = |v: &[u32]| v.iter().filter(|&&m| m != 0).count();
    let (shadowed, hidden) = (count(&on_gpu.shadowed), count(&on_gpu.hidden));
    eprintln!(
        "bumpy: {shadowed} shadowed and {hidden} hidden sub-samples; {} and {} undecided pairs",
        on_gpu.undecided, on_cpu.undecided
    );
    assert!(hidden > 0, "no hidden sub-sample");
    assert!(on_cpu.undecided as usize >= shadowed, "the pairs were not left to the CPU");
    assert_eq!(count(&on_cpu.shadowed), shadowed, "shadowed sub-samples");
    assert_eq!(on_cpu.shadowed, on_gpu.shadowed);
    assert_eq!(count(&on_cpu.hidden), hidden, "hidden sub-samples");
    assert_eq!(on_cpu.hidden, on_gpu.hidden);
}
