//! The GPU path's rasterizer against the CPU's exact one: where the hardware keeps the same
//! triangle, position and normal (and a map's depth) are bit-identical; where it keeps another (its
//! fixed-point coverage near edges), the samples are few, and counted.

use crate::common::load_builtin;
use glam::DVec2;
use instrumentation::Recorder;
use methods::gpu::{GpuContext, GpuDepthMap, GpuFrame};
use methods::{Frame, LightFit};

/// Differing ids, and bitwise mismatches among equal ids, of two rasterizations.
fn compare(cpu_tri: &[u32], gpu_tri: &[u32], same_bits: impl Fn(usize) -> bool) -> (usize, usize) {
    let mut other = 0;
    let mut mismatched = 0;
    for k in 0..cpu_tri.len() {
        if cpu_tri[k] != gpu_tri[k] {
            other += 1;
        } else if !same_bits(k) {
            mismatched += 1;
        }
    }
    (other, mismatched)
}

#[test]
fn gpu_parity_raster_gbuffer_and_depth_map_equal_the_cpu_where_the_triangle_is_the_same() {
    let ctx = GpuContext::shared().expect("a GPU adapter (scripts/install-gpu-driver)");
    for name in ["plane-square", "cage", "random-10k", "bumpy", "spot-spheres", "grazing"] {
        let Some(scene) = load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        let mut rec = Recorder::default();
        let g = GpuFrame::for_run(ctx, &frame, &mut rec)
            .and_then(|g| g.read_gbuffer(ctx))
            .expect("G-buffer on the GPU");
        let c = &frame.gbuffer;
        let (other, mismatched) = compare(&c.triangle, &g.triangle, |k| {
            c.depth[k].to_bits() == g.depth[k].to_bits()
                && c.position[k].to_array().map(f64::to_bits)
                    == g.position[k].to_array().map(f64::to_bits)
                && c.normal[k].to_array().map(f64::to_bits)
                    == g.normal[k].to_array().map(f64::to_bits)
        });
        let n = c.triangle.len();
        eprintln!("{name}: G-buffer: {other} of {n} pixels keep another triangle");
        assert_eq!(mismatched, 0, "{name}: G-buffer attributes differ for the same triangle");
        assert!(other * 100 < n, "{name}: {other} of {n} pixels keep another triangle");

        for (res, fit, shift) in [
            (256, LightFit::Scene, DVec2::ZERO),
            (512, LightFit::Scene, DVec2::new(0.25, -0.25)),
            (256, LightFit::ViewSnapped, DVec2::ZERO),
        ] {
            let cpu =
                frame.jittered_light_depth_map(res, fit, shift, "map", &mut Recorder::default());
            let gpu = GpuDepthMap::for_run(ctx, &frame, res, fit, shift, "map", &mut rec)
                .and_then(|m| m.read(ctx))
                .expect("depth map on the GPU");
            let (other, mismatched) = compare(&cpu.triangle, &gpu.triangle, |k| {
                cpu.depth[k].to_bits() == gpu.depth[k].to_bits()
            });
            let n = cpu.triangle.len();
            let fit = fit.as_str();
            eprintln!(
                "{name}: map {res} {fit} shift {shift}: {other} of {n} texels keep another \
                 triangle"
            );
            assert_eq!(mismatched, 0, "{name}: map depth differs for the same triangle");
            assert!(other * 100 < n, "{name}: {other} of {n} texels keep another triangle");
        }
        assert!(rec.stages.stages.iter().all(|s| s.ms.is_finite() && s.ms >= 0.0));
    }
}
