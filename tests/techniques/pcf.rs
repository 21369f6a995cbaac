//! Percentage-closer filtering: the shadow levels each variant can take, the lookups each
//! makes, and its error against the exact reference as the shadow map grows.

use analysis::{exact::ExactCoverage, Metrics, Reference};
use instrumentation::Recorder;
use methods::{method, Frame, MethodOptions, Visibility};
use std::collections::BTreeSet;

fn run(name: &str, frame: &Frame<'_>, options: MethodOptions) -> (Visibility, Recorder) {
    let mut rec = Recorder::default();
    let v = method(name, &options).expect("valid").run(frame, &mut rec).expect("runs");
    (v, rec)
}

fn levels(v: &Visibility) -> BTreeSet<u32> {
    v.lit.iter().map(|l| l.to_bits()).collect()
}

/// Pixels whose surface point falls inside the light's map frustum (all of them on the
/// built-in directional scenes, whose light frustum is fitted to the scene).
fn receivers(frame: &Frame<'_>) -> u64 {
    (0..frame.gbuffer.triangle.len()).filter(|&k| frame.gbuffer.covered(k)).count() as u64
}

#[test]
fn shadow_levels_are_bounded_as_the_papers_count_them() {
    for scene in ["plane-square", "cage", "random-1k"] {
        let scene = scenes::load(scene).expect("built-in");
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        for (name, map_res, most) in [
            ("sm", 256, 2),
            ("pcf-bs-2x2", 128, 5),
            ("pcf-bs-fast-2x2", 128, 5),
            ("pcf-bs-fast-4x4", 128, 21),
        ] {
            let options = MethodOptions { map_res: Some(map_res), ..Default::default() };
            let (v, _) = run(name, &frame, options);
            let seen = levels(&v);
            assert!(seen.len() <= most, "{}: {name} takes {} levels", scene.name, seen.len());
            // The bound is reached where the map is coarse: the levels are really there.
            assert!(seen.len() >= most.min(5) - 1, "{}: {name}: {seen:?}", scene.name);
            if name == "pcf-bs-fast-4x4" {
                // Sixteen compares: the values are k / 16.
                assert!(v.lit.iter().all(|&l| (l * 16.0).fract() == 0.0));
            }
        }
        // pcf-reeves: multiples of 1 / N.
        let (v, _) =
            run("pcf-reeves", &frame, MethodOptions { rate: Some(8), ..Default::default() });
        assert!(v.lit.iter().all(|&l| (l * 8.0).fract() == 0.0));
    }
}

#[test]
fn gpu_gems_variants_make_sixteen_and_four_bilinear_lookups_per_pixel() {
    let scene = scenes::load("plane-square").expect("built-in");
    let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
    let pixels = receivers(&frame);
    assert!(pixels > 10_000);
    for (name, per_pixel) in [("pcf-gems16", 16), ("pcf-gems4", 4)] {
        let (v, rec) =
            run(name, &frame, MethodOptions { map_res: Some(256), ..Default::default() });
        assert_eq!(rec.counters.bilinear_lookups, per_pixel * pixels, "{name}");
        // Four compares per bilinear lookup (the map covers every lookup here).
        assert_eq!(rec.counters.shadow_map_lookups, 4 * per_pixel * pixels, "{name}");
        // Bilinear weights give more than the 17 levels of a box filter.
        assert!(levels(&v).len() > 17, "{name}: {} levels", levels(&v).len());
    }
    for (name, per_pixel) in
        [("sm", 1), ("pcf-bs-2x2", 4), ("pcf-bs-fast-2x2", 4), ("pcf-bs-fast-4x4", 16)]
    {
        let (_, rec) =
            run(name, &frame, MethodOptions { map_res: Some(256), ..Default::default() });
        assert_eq!(rec.counters.shadow_map_lookups, per_pixel * pixels, "{name}");
        assert_eq!(rec.counters.bilinear_lookups, 0, "{name}");
    }
    let (_, rec) =
        run("pcf-reeves", &frame, MethodOptions { rate: Some(32), ..Default::default() });
    assert_eq!(rec.counters.shadow_map_lookups, 32 * pixels);
}

#[test]
fn stages_name_every_map_pass() {
    let scene = scenes::load("plane-square").expect("built-in");
    let frame = Frame::new(&scene, 64, 48, &mut Recorder::default());
    let names = |m: &str| -> Vec<String> {
        let (_, rec) = run(m, &frame, MethodOptions { map_res: Some(64), ..Default::default() });
        rec.stages.stages.iter().map(|s| s.name.clone()).collect()
    };
    assert_eq!(
        names("pcf-bs-2x2"),
        [
            "light depth map (jitter 1)",
            "light depth map (jitter 2)",
            "light depth map (jitter 3)",
            "light depth map (jitter 4)",
            "texel packing",
            "depth test"
        ]
    );
    let fast4 = names("pcf-bs-fast-4x4");
    assert_eq!(fast4.len(), 10, "{fast4:?}");
    assert_eq!(fast4[1], "depth encoding");
    assert_eq!(fast4[8], "texel packing (pass 4)");
    assert_eq!(fast4[9], "depth test (pass 4)");
    assert_eq!(names("pcf-gems4"), ["light depth map", "percentage-closer filtering"]);
}

#[test]
fn reeves_is_deterministic_for_a_seed_and_varies_with_it() {
    let scene = scenes::load("cage").expect("built-in");
    let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
    let with = |seed| {
        run("pcf-reeves", &frame, MethodOptions { seed: Some(seed), ..Default::default() }).0.lit
    };
    assert_eq!(with(3), with(3));
    assert_ne!(with(3), with(4));
}

#[test]
fn depth_bits_coarsen_the_comparison() {
    // At 8 bits a caster close above its receiver falls within one depth step of it and its
    // shadow is lost where the 32-bit map keeps it.
    let scene = scenes::load("cage").expect("built-in");
    let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
    let shadow = |bits| {
        let options = MethodOptions { depth_bits: Some(bits), ..Default::default() };
        run("pcf-bs-fast-2x2", &frame, options)
            .0
            .lit
            .iter()
            .map(|&l| 1.0 - f64::from(l))
            .sum::<f64>()
    };
    let (coarse, fine) = (shadow(8), shadow(32));
    assert!(fine > 0.0 && coarse <= fine, "8 bits: {coarse}, 32 bits: {fine}");
}

/// Mean absolute error against `exact` of `sm` and every PCF variant on `plane-square` and
/// `cage` for maps of 256 .. 2048 texels: it falls as the map grows. The frame is 1600 x 1200
/// so that even the 2048 map is magnified on screen: once texels are smaller than pixels, a
/// fixed-size texel filter shrinks below the pixel and the error levels off (at 400 x 300,
/// `pcf-bs-2x2` is best at 1024 and slightly worse at 2048).
#[test]
fn exact_pcf_error_falls_as_the_map_grows() {
    // `sm` and the PCF variants: every map method but `pan09`.
    let methods = crate::common::MAP_METHODS.iter().copied().filter(|&m| m != "pan09");
    for scene in ["plane-square", "cage"] {
        let scene = scenes::load(scene).expect("built-in");
        let frame = Frame::new(&scene, 1600, 1200, &mut Recorder::default());
        let reference = ExactCoverage::default()
            .evaluate(&frame, &mut Recorder::default())
            .expect("planar receiver");
        for name in methods.clone() {
            let mut errors = Vec::new();
            for map_res in [256, 512, 1024, 2048] {
                let options = MethodOptions { map_res: Some(map_res), ..Default::default() };
                let (v, rec) = run(name, &frame, options);
                let m = Metrics::compare(&v, &reference.lit, &reference.evaluated);
                eprintln!(
                    "{} {name} map {map_res}: mean {:.5} boundary mean {:.4} rmse {:.4} \
                     ({:.1} ms)",
                    scene.name,
                    m.mean_abs_error,
                    m.boundary_mean_abs_error,
                    m.rmse,
                    rec.stages.total_ms()
                );
                errors.push(m.mean_abs_error);
            }
            for pair in errors.windows(2) {
                assert!(pair[1] < pair[0], "{} {name}: {errors:?}", scene.name);
            }
        }
    }
}
