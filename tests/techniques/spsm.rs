//! The sub-pixel shadow map (`spsm`, `spsm-f32`; Lecocq et al. 2014) end to end: pixel match
//! against the ray-traced reference beside `sm` (the paper's Fig. 12 measure), the derivative
//! code's precision (section 3.4), what packing costs, antialiasing against the exact
//! reference, stages, counters, the Fig. 14 class image, hard cases and bad options.

use crate::common;

use analysis::{exact::ExactCoverage, raytrace::RayTrace, Metrics, Reference};
use glam::DVec3;
use instrumentation::Recorder;
use methods::{
    method,
    pattern::{PatternKind, SamplePattern},
    spsm::{self, class_image, quantize::DerivativeCode, PixelClass, Spsm, SpsmOptions},
    Frame, MethodError, MethodOptions, Visibility,
};
use scenes::Light;

fn run(name: &str, frame: &Frame<'_>, options: MethodOptions) -> (Visibility, Recorder) {
    let mut rec = Recorder::default();
    let v = method(name, &options).expect("valid").run(frame, &mut rec).expect("runs");
    (v, rec)
}

fn map(map_res: u32) -> MethodOptions {
    MethodOptions { map_res: Some(map_res), ..Default::default() }
}

fn covered(frame: &Frame<'_>) -> u64 {
    (0..frame.gbuffer.triangle.len()).filter(|&k| frame.gbuffer.covered(k)).count() as u64
}

/// Pixel match (DESIGN.md) of `sm`, `spsm` and `spsm-f32` against `raytrace` at rate 1 (the
/// pixel centre, as both maps without antialiasing), at the paper's 1920 x 1080 with 1K and
/// 2K maps. The paper reports 99.63% for SPSM and 97.93% for SM with a 2K map, on shaded
/// images; most of our remaining mismatches are receivers facing away from the light within
/// a texel of the light's silhouette (dark in a shaded image whatever the shadow).
#[test]
fn pixel_match_against_raytrace_beside_sm() {
    for name in ["spheres", "bunny-plane"] {
        let scene = match scenes::load(name) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("skipping {name}: {e} (scripts/fetch-models fetches the models)");
                continue;
            }
        };
        let frame = Frame::new(&scene, 1920, 1080, &mut Recorder::default());
        let pattern = SamplePattern::new(1, PatternKind::Grid).expect("rate 1");
        let reference =
            RayTrace { pattern }.evaluate(&frame, &mut Recorder::default()).expect("ok");
        let score = |v: &Visibility| {
            Metrics::compare(v, &reference.lit, &reference.evaluated).pixel_match * 100.0
        };
        for map_res in [1024, 2048] {
            let sm = score(&run("sm", &frame, map(map_res)).0);
            let packed = score(&run("spsm", &frame, map(map_res)).0);
            let unpacked = score(&run("spsm-f32", &frame, map(map_res)).0);
            eprintln!(
                "{name} 1920x1080 map {map_res}: sm {sm:.3}%  spsm {packed:.3}%  spsm-f32 \
                 {unpacked:.3}%"
            );
            assert!(packed > 99.0 && unpacked > 99.0, "{name} {map_res}: {packed} {unpacked}");
            // The sub-texel silhouette beats the map's texels, on curved casters and on a
            // dense mesh (75K triangles) alike (the paper: 99.63% against 97.93% at 2K).
            assert!(packed > sm + 0.2, "{name} {map_res}: spsm {packed} vs sm {sm}");
            assert!(unpacked > sm + 0.2, "{name} {map_res}: spsm-f32 {unpacked} vs sm {sm}");
            if map_res == 2048 {
                assert!(packed >= 99.6 && unpacked >= 99.6, "{name}: {packed} {unpacked}");
            }
            // Packing costs little: within half a point of the f32 texel.
            assert!((packed - unpacked).abs() < 0.5, "{name} {map_res}");
        }
    }
}

#[test]
fn quantization_near_80_degrees_is_as_the_paper_states() {
    // Section 3.4: x^5 resolves about 0.17 degrees near 80 degrees where the linear code's
    // step is 0.71 degrees. Our x^5 step is 0.23 degrees at 80 and 0.17 at 85; the round trip
    // error (half a step) stays within 0.17 degrees over 75..85 degrees.
    let power5 = DerivativeCode::new(5);
    let linear = DerivativeCode::new(1);
    let round_trip = |c: &DerivativeCode, deg: f64| {
        (c.decode(c.encode(deg.to_radians().tan())).atan().to_degrees() - deg).abs()
    };
    let (mut worst5, mut worst1) = (0.0f64, 0.0f64);
    for k in 0..=1000 {
        let deg = 75.0 + 10.0 * f64::from(k) / 1000.0;
        worst5 = worst5.max(round_trip(&power5, deg));
        worst1 = worst1.max(round_trip(&linear, deg));
    }
    eprintln!("round trip 75..85 degrees: x^5 {worst5:.3}, linear {worst1:.3}");
    assert!(worst5 <= 0.17, "{worst5}");
    assert!(worst1 > 0.34 && worst1 <= 0.36, "{worst1}");
    // Steps between neighbouring codes.
    let step = |c: &DerivativeCode, deg: f64| {
        let q = c.encode(deg.to_radians().tan());
        c.decode_degrees(q + 1) - c.decode_degrees(q)
    };
    assert!((step(&power5, 80.0) - 0.23).abs() < 0.01, "{}", step(&power5, 80.0));
    assert!((step(&power5, 85.0) - 0.17).abs() < 0.01, "{}", step(&power5, 85.0));
    assert!((step(&linear, 80.0) - 180.0 / 254.0).abs() < 1e-9);
    // The price: near 0 degrees the first x^5 code above flat is 34.16 degrees.
    assert!((power5.decode_degrees(128) - 34.16).abs() < 0.01, "{}", power5.decode_degrees(128));
}

#[test]
fn quantization_decode_tables_are_monotone_and_odd() {
    for n in 1..=spsm::quantize::MAX_POWER {
        let c = DerivativeCode::new(n);
        let t = c.table();
        for q in 0..254 {
            assert!(t[q + 1] > t[q], "power {n}: code {q}");
        }
        for q in 0..=254 {
            assert_eq!(t[q], -t[254 - q], "power {n}: code {q}");
        }
        // Encoding is monotone too, and decodes back to its own code.
        let mut last = 0u8;
        for k in -400..=400 {
            let s = (f64::from(k) / 400.0 * 0.999 * std::f64::consts::FRAC_PI_2).tan();
            let q = c.encode(s);
            assert!(q >= last, "power {n}: slope {s}");
            assert_eq!(c.encode(c.decode(q)), q, "power {n}: code {q}");
            last = q;
        }
    }
}

#[test]
fn exact_a_lit_plane_stays_fully_lit_without_slope_bias() {
    // Equation 1 evaluates the stored plane at the point: no slope-scaled bias is needed,
    // at any map size or light angle, for both texels and every derivative code.
    let lights = [
        Light::Directional { direction: DVec3::new(-0.3, -1.0, -0.2) },
        Light::Directional { direction: DVec3::new(1.0, -0.12, 0.3) }, // about 83° from vertical
        Light::Spot { position: DVec3::new(2.0, 6.0, 1.0), target: DVec3::ZERO, fov_deg: 120.0 },
    ];
    for light in lights {
        let scene = common::lone_plane(light.clone());
        let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
        for name in ["spsm", "spsm-f32"] {
            for map_res in [64, 256, 1024] {
                for power in [1, 5] {
                    let options = MethodOptions {
                        map_res: Some(map_res),
                        slope_bias: Some(0.0),
                        derivative_power: Some(power),
                        ..Default::default()
                    };
                    let (v, rec) = run(name, &frame, options);
                    let dark = v.lit.iter().filter(|&&l| l != 1.0).count();
                    assert_eq!(dark, 0, "{name} {light:?} map {map_res} x^{power}");
                    assert_eq!(rec.counters.shadowed_by_one_lookup, 0);
                }
            }
        }
    }
}

#[test]
fn stages_counters_and_the_fig14_class_image() {
    let scene = scenes::load("plane-square").expect("built-in");
    let frame = Frame::new(&scene, 320, 240, &mut Recorder::default());
    let mut rec = Recorder::default();
    let options = SpsmOptions {
        map: methods::depth_test::MapOptions { map_res: 256, ..Default::default() },
        ..Default::default()
    };
    let (v, classes) = Spsm { options }.run_classified(&frame, &mut rec).expect("runs");
    let names: Vec<&str> = rec.stages.stages.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "conservative rasterization",
            "packing",
            "classification",
            "consistent min depth",
            "silhouette recovery"
        ]
    );
    assert_eq!(rec.stages.skipped, ["antialiasing"]);
    let c = &rec.counters;
    // Every covered pixel is classified once (the light's map covers the whole scene).
    assert_eq!(
        c.lit_by_one_lookup
            + c.shadowed_by_one_lookup
            + c.shadowed_by_neighbourhood
            + c.uncertain_pixels,
        covered(&frame)
    );
    assert!(
        c.uncertain_pixels > 0
            && c.recovered_pixels > 0
            && c.recovered_pixels <= c.uncertain_pixels
    );
    assert!(c.shadowed_by_neighbourhood > 0, "{c:?}");
    assert!(c.conservative_fragments >= c.packed_texels && c.packed_texels > 0);
    assert!(c.shadow_map_lookups >= covered(&frame));
    assert_eq!(c.antialiased_samples, 0);
    // Binary at rate 1.
    assert!(v.lit.iter().all(|&l| l == 0.0 || l == 1.0));
    // The class image: red where recovery ran, green where the 3x3 neighbourhood shadowed.
    let count = |class| classes.iter().filter(|&&k| k == class).count() as u64;
    assert_eq!(count(PixelClass::Uncertain), c.uncertain_pixels);
    assert_eq!(count(PixelClass::ShadowedNeighbourhood), c.shadowed_by_neighbourhood);
    let rgb = class_image(&classes, &v.lit);
    assert_eq!(rgb.len(), classes.len());
    for (k, px) in rgb.iter().enumerate() {
        match classes[k] {
            PixelClass::Uncertain => assert_eq!(*px, [220, 0, 0]),
            PixelClass::ShadowedNeighbourhood => assert_eq!(*px, [0, 200, 0]),
            PixelClass::Unmapped => assert_eq!(*px, [0, 0, 0]),
            PixelClass::LitOneLookup => assert_eq!(*px, [240, 240, 240]),
            PixelClass::ShadowedOneLookup => assert_eq!(*px, [90, 90, 90]),
        }
    }
    // Uncertain pixels lie along the square's shadow border (99% of them at least): within
    // a few pixels of a pixel whose exact lit fraction is strictly between 0 and 1.
    let exact = ExactCoverage::default()
        .evaluate(&frame, &mut Recorder::default())
        .expect("planar receiver");
    let (w, h) = (frame.width() as i64, frame.height() as i64);
    let near_border = |k: usize| {
        let (x, y) = (k as i64 % w, k as i64 / w);
        (-6..=6).any(|dy| {
            (-6..=6).any(|dx| {
                let (nx, ny) = (x + dx, y + dy);
                nx >= 0 && ny >= 0 && nx < w && ny < h && {
                    let l = exact.lit[(ny * w + nx) as usize];
                    l > 0.0 && l < 1.0
                }
            })
        })
    };
    let far: Vec<(usize, usize, f64)> = (0..classes.len())
        .filter(|&k| classes[k] == PixelClass::Uncertain && exact.evaluated[k] && !near_border(k))
        .map(|k| (k % w as usize, k / w as usize, exact.lit[k]))
        .collect();
    // (A point on the square's own diagonal is surely in neither of its triangles once the
    // vertex quantization is allowed for; recovery shadows it.)
    assert!(
        far.len() as u64 * 100 <= c.uncertain_pixels,
        "uncertain pixels away from the shadow border: {far:?}"
    );
}

#[test]
fn exact_antialiasing_uncertain_pixels_lowers_the_error() {
    // Section 5: the recovered function evaluated at 16 sub-samples, uncertain pixels only.
    let scene = scenes::load("plane-square").expect("built-in");
    let frame = Frame::new(&scene, 400, 300, &mut Recorder::default());
    let exact = ExactCoverage::default()
        .evaluate(&frame, &mut Recorder::default())
        .expect("planar receiver");
    let error = |v: &Visibility| Metrics::compare(v, &exact.lit, &exact.evaluated);
    let (sm, _) = run("sm", &frame, map(512));
    let (aliased, _) = run("spsm", &frame, map(512));
    let options = MethodOptions { rate: Some(16), ..map(512) };
    let (smooth, rec) = run("spsm", &frame, options);
    let (sm, aliased, smooth) = (error(&sm), error(&aliased), error(&smooth));
    eprintln!(
        "plane-square boundary mean error: sm {:.4}, spsm {:.4}, spsm 16x {:.4}",
        sm.boundary_mean_abs_error, aliased.boundary_mean_abs_error, smooth.boundary_mean_abs_error
    );
    assert!(aliased.mean_abs_error < sm.mean_abs_error);
    assert!(smooth.mean_abs_error < 0.8 * aliased.mean_abs_error);
    assert!(smooth.boundary_mean_abs_error < aliased.boundary_mean_abs_error);
    assert_eq!(rec.counters.antialiased_samples, 16 * rec.counters.recovered_pixels);
    assert!(rec.stages.stages.iter().any(|s| s.name == "antialiasing"));
    assert!(rec.stages.skipped.is_empty());
    assert!(smooth.max_abs_error <= 1.0);
}

#[test]
fn hard_cases_stay_finite_and_in_range() {
    for name in ["cage", "random-100k", "grazing", "spot-spheres", "hairball", "bumpy"] {
        let scene = scenes::load(name).expect("built-in");
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        for m in ["spsm", "spsm-f32"] {
            for map_res in [16, 512] {
                for rate in [1, 16] {
                    let options = MethodOptions { rate: Some(rate), ..map(map_res) };
                    let (v, rec) = run(m, &frame, options);
                    assert!(
                        v.lit.iter().all(|l| l.is_finite() && (0.0..=1.0).contains(l)),
                        "{name} {m} {map_res} {rate}"
                    );
                    assert!(
                        v.lit.iter().all(|&l| (l * rate as f32).fract() == 0.0),
                        "{name} {m}: values are multiples of 1/{rate}"
                    );
                    if name == "hairball" {
                        assert!(rec.notes.iter().any(|n| n.contains("opaque")), "{:?}", rec.notes);
                    }
                }
            }
        }
    }
}

#[test]
fn bad_options_name_their_flag() {
    let cases: [(MethodOptions, &str); 5] = [
        (MethodOptions { derivative_power: Some(0), ..Default::default() }, "--derivative-power"),
        (MethodOptions { derivative_power: Some(10), ..Default::default() }, "--derivative-power"),
        (MethodOptions { rate: Some(3), ..Default::default() }, "--rate"),
        (MethodOptions { rate: Some(256), ..Default::default() }, "--rate"),
        (MethodOptions { map_res: Some(0), ..Default::default() }, "--map-res"),
    ];
    for name in ["spsm", "spsm-f32"] {
        for (options, flag) in &cases {
            match method(name, options) {
                Err(MethodError::InvalidOption { option, .. }) => assert_eq!(option, *flag),
                other => panic!("{name} {options:?}: {:?}", other.map(|m| m.name())),
            }
        }
    }
}

#[test]
fn cli_renders_spsm_and_rejects_a_bad_power() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("run");
    let o = common::shadowbench(&[
        "render",
        "--scene",
        "plane-square",
        "--method",
        "spsm",
        "--width",
        "96",
        "--height",
        "72",
        "--map-res",
        "128",
        "--rate",
        "4",
        "--derivative-power",
        "3",
        "--out",
        out.to_str().expect("utf-8 path"),
        "--json",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let record: serde_json::Value = serde_json::from_slice(&o.stdout).expect("run.json");
    assert_eq!(record["method"], "spsm");
    assert_eq!(record["params"]["derivative_power"], 3);
    assert_eq!(record["params"]["rate"], 4);
    assert!(record["counters"]["uncertain_pixels"].as_u64().expect("counter") > 0);
    let o = common::shadowbench(&[
        "render",
        "--scene",
        "plane-square",
        "--method",
        "spsm",
        "--derivative-power",
        "0",
        "--out",
        out.to_str().expect("utf-8 path"),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(common::stderr(&o).contains("--derivative-power"), "{}", common::stderr(&o));
}
