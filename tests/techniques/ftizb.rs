//! `ftizb` (Wyman et al. 2015, 2016) end to end: sub-sample for sub-sample against the ray
//! tracer on planar receivers (both patterns), rate 1 against `afsm`, hidden sub-samples on
//! curved receivers, culling and the grid's resolution changing only the cost, determinism
//! over thread counts, counters and stages.

use crate::common::load_builtin;
use crate::planar::{compare_on_plane, samples};
use instrumentation::Recorder;
use methods::{
    ftizb::{Ftizb, FtizbOptions, SubsampleMasks},
    method,
    pattern::PatternKind,
    Frame, MethodOptions, Visibility,
};

fn ftizb(rate: u32, pattern: PatternKind) -> Ftizb {
    Ftizb { options: FtizbOptions { rate, pattern, ..FtizbOptions::default() } }
}

fn run_masks(m: &Ftizb, frame: &Frame<'_>) -> (Visibility, SubsampleMasks, Recorder) {
    let mut rec = Recorder::default();
    let (v, masks) = m.run_masks(frame, &mut rec).expect("ftizb runs");
    assert_eq!(v.lit.len(), frame.gbuffer.triangle.len());
    assert!(v.lit.iter().all(|l| l.is_finite() && (0.0..=1.0).contains(l)));
    (v, masks, rec)
}

#[test]
fn ftizb_equals_raytrace_sub_sample_for_sub_sample_on_planar_receivers() {
    let cases = [
        ("plane-square", 32, PatternKind::Grid),
        ("plane-square", 32, PatternKind::Rotated),
        ("cage", 32, PatternKind::Grid),
        ("cage", 8, PatternKind::Rotated),
        ("bunny-plane", 16, PatternKind::Rotated),
        ("spheres", 128, PatternKind::Grid),
        ("spot-spheres", 32, PatternKind::Rotated),
    ];
    for (name, rate, kind) in cases {
        let Some(scene) = load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 120, 90, &mut Recorder::default());
        let (_, masks, rec) = run_masks(&ftizb(rate, kind), &frame);
        let truth = samples(&frame, rate, kind);
        let c = compare_on_plane(&frame, &masks.occlusion, &masks.valid, &truth);
        eprintln!(
            "{name} {rate} {kind}: {c:?}, {} pairs tested",
            rec.counters.visibility_evaluations
        );
        assert!(c.pixels > 2000 && c.shadowed > 500, "{name}: {c:?}");
        assert_eq!(c.invalid, 0, "{name} {rate} {kind}");
        assert!(c.mismatches as f64 <= 1e-5 * c.samples as f64, "{name} {rate} {kind}: {c:?}");
    }
}

#[test]
fn ftizb_at_rate_1_is_afsm() {
    for name in ["plane-square", "cage", "spheres", "spot-spheres", "grazing", "bunny-plane"] {
        let Some(scene) = load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
        let (v, _, _) = run_masks(&ftizb(1, PatternKind::Grid), &frame);
        let afsm = method("afsm", &MethodOptions::default())
            .expect("valid")
            .run(&frame, &mut Recorder::default())
            .expect("runs");
        let off: Vec<usize> = (0..v.lit.len()).filter(|&k| v.lit[k] != afsm.lit[k]).collect();
        assert!(off.is_empty(), "{name}: pixels {off:?} differ from afsm");
    }
}

fn options(depth: bool, izb_res: u32) -> FtizbOptions {
    FtizbOptions { rate: 16, depth_culling: depth, izb_res, ..FtizbOptions::default() }
}

#[test]
fn depth_culling_and_the_grid_size_change_the_cost_never_a_pixel() {
    for name in ["cage", "spheres", "grazing"] {
        let Some(scene) = load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 80, 60, &mut Recorder::default());
        let run = |o: FtizbOptions| run_masks(&Ftizb { options: o }, &frame);
        let (base, masks, rec) = run(options(true, 0));
        let c = &rec.counters;
        assert!(c.nodes_depth_culled > 0, "{name}: {c:?}");
        assert!(c.footprint_texels >= c.caster_texels.min(1), "{name}");
        let (v, m, r) = run(options(false, 0));
        assert_eq!(v.lit, base.lit, "{name}: depth culling off");
        assert_eq!(m, masks, "{name}: depth culling off");
        assert!(
            r.counters.sampling_points_tested > c.sampling_points_tested,
            "{name}: depth culling off does more work"
        );
        // The grid bins the samples; their coordinates and every decision are the same.
        for res in [1, 16, 1024] {
            let (v, m, r) = run(options(true, res));
            assert_eq!(v.lit, base.lit, "{name} at grid {res}");
            assert_eq!(m, masks, "{name} at grid {res}");
            assert_ne!(r.counters.visibility_evaluations, 0, "{name} at grid {res}");
        }
    }
}

#[test]
fn results_and_counters_do_not_depend_on_the_thread_count() {
    let Some(scene) = load_builtin("cage") else { return };
    let frame = Frame::new(&scene, 80, 60, &mut Recorder::default());
    let m = ftizb(32, PatternKind::Rotated);
    let (v, _, rec) = run_masks(&m, &frame);
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a pool");
    let (v1, _, rec1) = one.install(|| run_masks(&m, &frame));
    assert_eq!(v.lit, v1.lit);
    assert_eq!(rec.counters, rec1.counters);
}

#[test]
fn stages_and_counters_are_recorded() {
    let Some(scene) = load_builtin("bunny-plane") else { return };
    let frame = Frame::new(&scene, 64, 48, &mut Recorder::default());
    let (_, _, rec) = run_masks(&ftizb(32, PatternKind::Grid), &frame);
    let names: Vec<&str> = rec.stages.stages.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["sample footprints", "conservative rasterization", "frustum tests"]);
    let c = &rec.counters;
    assert!(c.footprint_texels > 0 && c.caster_texels > 0, "{c:?}");
    assert!(c.visibility_evaluations > 0 && c.sampling_points_tested > 0, "{c:?}");
    // Every pair tests at most 32 sub-samples.
    assert!(c.sampling_points_tested <= 32 * c.visibility_evaluations, "{c:?}");
}

#[test]
fn registry_builds_ftizb_and_names_bad_flags() {
    let m = method("ftizb", &MethodOptions::default()).expect("defaults are valid");
    assert_eq!(m.name(), "ftizb");
    assert_eq!(m.params()["rate"], 32);
    assert_eq!(m.params()["izb_res"], "frame");
    let mut bad = MethodOptions::default();
    bad.set(&methods::registry::IZB_RES, methods::params::Value::Count(5000));
    let e = method("ftizb", &bad).map(|_| ()).expect_err("izb_res 5000");
    assert!(e.to_string().contains("--izb-res"), "{e}");
    let e = method("ftizb", &MethodOptions { rate: Some(256), ..Default::default() })
        .map(|_| ())
        .expect_err("rate 256");
    assert!(e.to_string().contains("--rate"), "{e}");
}

/// On a curved mesh with several triangles a pixel, the sub-samples a caster shadows and hides
/// from the camera are left out (they lie behind the surface on the tangent plane). At 160 x
/// 120 the pixels differ from the ray tracer's at the same rate by 0.0141 on `bunny-plane`
/// (`pan09` 0.0118, `ftizb` at 1 sub-sample 0.0088) and by 0.076 on `bumpy`, whose 530,688
/// triangles put about 20 in a pixel (`pan09` 0.0131, `ftizb` at 1 0.0083); without the rule
/// 41 % of `bumpy`'s sub-samples disagreed with the ray tracer's at 64 x 48.
#[test]
fn hidden_sub_samples_are_left_out_on_curved_receivers() {
    for (name, most) in [("bunny-plane", 0.02), ("bumpy", 0.1)] {
        let Some(scene) = load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        let (v, masks, _) = run_masks(&ftizb(32, PatternKind::Grid), &frame);
        let truth = samples(&frame, 32, PatternKind::Grid);
        let g = &frame.gbuffer;
        let (mut hidden, mut pixels, mut error) = (0u32, 0usize, 0.0f64);
        for k in (0..masks.occlusion.len()).filter(|&k| g.covered(k)) {
            hidden += masks.hidden[k].count_ones();
            assert_eq!(masks.valid[k] & masks.hidden[k], 0, "{name}: hidden and valid");
            assert_eq!(masks.occlusion[k] & masks.hidden[k], 0, "{name}: hidden and shadowed");
            let traced = truth.light[k * 32..(k + 1) * 32].iter().sum::<f64>() / 32.0;
            error += (f64::from(v.lit[k]) - traced).abs();
            pixels += 1;
        }
        let mean = error / pixels as f64;
        eprintln!(
            "{name}: mean difference from raytrace {mean:.4} over {pixels} pixels, {hidden} hidden"
        );
        assert!(hidden > 0, "{name}: nothing hidden");
        assert!(mean < most, "{name}: {mean}");
    }
}
