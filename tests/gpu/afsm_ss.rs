//! `afsm-ss` on the GPU (one irregular z-buffer pass per sub-sample) against the CPU
//! `afsm-ss`, pixel for pixel, with the CPU's own G-buffers uploaded; and one end-to-end run.

use crate::common::load_builtin;
use instrumentation::Recorder;
use methods::{
    afsm::{AfsmOptions, AliasFreeShadowMap},
    gpu::{
        afsm_ss::{self, GpuAfsmSs, SubSampleGBuffers},
        GpuContext, GpuFrame,
    },
    pattern::PatternKind,
    Frame, ShadowMethod,
};

/// GPU and CPU `afsm-ss` at `rate` on `name` at 96 x 72: the number of differing pixels
/// (`None` when the scene's model is missing).
fn differing(name: &str, rate: u32, pattern: PatternKind) -> Option<usize> {
    let scene = load_builtin(name)?;
    let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
    let options = AfsmOptions { rate, pattern, ..AfsmOptions::supersampled() };
    let cpu = AliasFreeShadowMap::supersampled(options)
        .run(&frame, &mut Recorder::default())
        .expect("CPU afsm-ss runs");
    let ctx = GpuContext::shared().expect("a GPU adapter (Mesa's lavapipe on CI)");
    let gpu = GpuFrame::upload(ctx, &frame, &frame.gbuffer);
    let mut rec = Recorder::default();
    let out = afsm_ss::shade(ctx, &gpu, &frame, &options, SubSampleGBuffers::Cpu, &mut rec)
        .expect("GPU afsm-ss runs");
    assert_eq!(out.lit.len(), cpu.lit.len());
    let differing = out.lit.iter().zip(&cpu.lit).filter(|(g, c)| g != c).count();
    let partial = cpu.lit.iter().filter(|&&l| 0.0 < l && l < 1.0).count();
    eprintln!(
        "{} at {rate}: {differing} differing pixels, {partial} partly lit, {} undecided",
        scene.name, out.undecided
    );
    assert!(cpu.lit.contains(&0.0), "{name}: no shadow at all");
    assert!(partial > 0, "{name}: no pixel partly lit, so no sub-sample told apart");
    assert!(rec.counters.sampling_points_tested > 0);
    // One entry per stage, the sub-samples' G-buffers each named.
    let stages: Vec<&str> = rec.stages.stages.iter().map(|s| s.name.as_str()).collect();
    for stage in ["transformation of samples", "IZB construction", "rasterization of blockers"] {
        assert_eq!(stages.iter().filter(|s| **s == stage).count(), 1, "{stage}: {stages:?}");
    }
    let gbuffers = stages.iter().filter(|s| s.starts_with("camera G-buffer (sub-sample")).count();
    assert_eq!(gbuffers, rate as usize - 1, "{stages:?}");
    Some(differing)
}

#[test]
fn gpu_parity_afsm_ss_on_the_parity_scenes() {
    for name in ["plane-square", "cage", "random-10k", "bumpy", "spot-spheres"] {
        match differing(name, 4, PatternKind::Grid) {
            Some(d) => assert_eq!(d, 0, "{name}: {d} pixels differ from the CPU afsm-ss"),
            None => eprintln!("{name}: skipped (model missing)"),
        }
    }
}

#[test]
fn gpu_parity_afsm_ss_with_every_pattern_at_rate_8() {
    for pattern in [PatternKind::Grid, PatternKind::Rotated] {
        let d = differing("plane-square", 8, pattern).expect("built-in");
        assert_eq!(d, 0, "{pattern:?}: {d} pixels differ from the CPU afsm-ss");
    }
}

#[test]
fn gpu_afsm_ss_runs_end_to_end() {
    let scene = scenes::load("plane-square").expect("built-in");
    let frame = Frame::new(&scene, 64, 48, &mut Recorder::default());
    let options = AfsmOptions { rate: 4, ..AfsmOptions::supersampled() };
    let m = GpuAfsmSs { options };
    assert_eq!(m.name(), "afsm-ss");
    let mut want = AliasFreeShadowMap::supersampled(options).params();
    want.insert("device".into(), "gpu".into());
    assert_eq!(m.params(), want);
    let mut rec = Recorder::default();
    let v = m.run(&frame, &mut rec).expect("GPU afsm-ss runs");
    assert_eq!(v.lit.len(), 64 * 48);
    assert!(v.lit.iter().all(|l| l.is_finite() && (0.0..=1.0).contains(l)));
    assert!(v.lit.iter().all(|l| (l * 4.0).fract() == 0.0), "values are k / rate");
    assert!(v.lit.contains(&0.0) && v.lit.contains(&1.0));
    assert!(rec.notes.iter().any(|n| n.contains("over 4 sub-samples")), "{:?}", rec.notes);
}

/// The transformation of samples, sub-sample by sub-sample: the GPU's samples (light image
/// point, threshold depth, triangle) equal the CPU's `transform_samples` bit for bit, on the
/// same G-buffers, before any caster is tested.
#[test]
fn gpu_parity_afsm_ss_transformation_per_sub_sample() {
    use glam::DVec2;
    use methods::{
        afsm::samples::{transform_samples, Surface},
        gpu::afsm::{Izb, SampleSurface},
        pattern::SamplePattern,
        raster::rasterize_nearest_at,
    };
    let ctx = GpuContext::shared().expect("a GPU adapter (Mesa's lavapipe on CI)");
    for name in ["plane-square", "spot-spheres", "cage"] {
        let Some(scene) = load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 48, 36, &mut Recorder::default());
        let pattern = SamplePattern::new(4, PatternKind::Rotated).expect("a pattern");
        let extra: Vec<_> = (0..4)
            .map(|s| {
                let shift = pattern.offsets()[s] - DVec2::splat(0.5);
                let geometry = &frame.geometry;
                let mut counters = Default::default();
                rasterize_nearest_at(geometry, |_| true, &frame.camera, shift, &mut counters)
            })
            .collect();
        let centre = pattern.centre_index();
        let surfaces: Vec<Surface<'_>> = (0..4)
            .map(|s| match s == centre {
                true => Surface { triangle: &frame.gbuffer.triangle, depth: &frame.gbuffer.depth },
                false => Surface { triangle: &extra[s].triangle, depth: &extra[s].depth },
            })
            .collect();
        let light = methods::afsm::light_projector(&frame);
        let cpu =
            transform_samples(&frame.camera, &light, &surfaces, &pattern, frame.width()).samples;
        let gpu_frame = GpuFrame::upload(ctx, &frame, &frame.gbuffer);
        let izb = Izb::new(ctx, &gpu_frame, &frame);
        let mut gpu = Vec::new();
        for (s, surface) in surfaces.iter().enumerate() {
            let triangle = ctx.upload("triangle", surface.triangle);
            let depth = ctx.upload("depth", surface.depth);
            let offset = pattern.offsets()[s];
            let at = SampleSurface { triangle: &triangle, depth: &depth, offset };
            izb.shadowed(ctx, at, &mut Recorder::default()).expect("GPU afsm-ss pass");
            gpu.extend(izb.samples(ctx, s as u32, 4).expect("samples read back"));
        }
        gpu.sort_by_key(|s| s.id);
        assert!(!cpu.is_empty(), "{name}: no sample");
        let bits = |s: &methods::afsm::samples::Sample| {
            (s.id, s.tri, s.x.to_bits(), s.y.to_bits(), s.zt.to_bits())
        };
        let differing = cpu.iter().zip(&gpu).filter(|(c, g)| bits(c) != bits(g)).count();
        assert_eq!((gpu.len(), differing), (cpu.len(), 0), "{name}: transformed samples");
    }
}
