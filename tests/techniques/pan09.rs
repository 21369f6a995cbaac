//! `pan09` (Pan et al. 2009) end to end: exact mode against the ray tracer sub-sample for
//! sub-sample on planar receivers, table mode's quantization flips, the depth test of
//! non-silhouette pixels against `sm`, rate 1 against `afsm`, hard cases, stages, counters and
//! options.

use crate::common;

use crate::common::load_builtin;
use crate::planar::{compare_on_plane, samples, Comparison};
use glam::DVec3;
use instrumentation::Recorder;
use methods::{
    method,
    pan09::{facets::PixelClass, Pan09, Pan09Options, SubsampleMasks, VisibilityMode},
    pattern::{PatternKind, SamplePattern},
    Frame, MethodError, MethodOptions, Visibility,
};
use scenes::{
    generators::PlaneParams,
    scene_file::{ObjectDesc, SceneDesc, Shape, Transform},
    Camera, Light, Material, Scene,
};

fn pan09(rate: u32, pattern: PatternKind, visibility: VisibilityMode) -> Pan09 {
    Pan09::new(Pan09Options { rate, pattern, visibility, ..Pan09Options::default() })
        .expect("valid options")
}

fn run_masks(m: &Pan09, frame: &Frame<'_>) -> (Visibility, SubsampleMasks, Recorder) {
    let mut rec = Recorder::default();
    let (v, masks) = m.run_masks(frame, &mut rec).expect("pan09 runs");
    assert_eq!(v.lit.len(), frame.gbuffer.triangle.len());
    assert!(v.lit.iter().all(|l| l.is_finite() && (0.0..=1.0).contains(l)));
    (v, masks, rec)
}

#[test]
fn exact_mode_equals_raytrace_sub_sample_for_sub_sample_on_planar_receivers() {
    for name in ["plane-square", "cage", "random-10k", "plant", "bunny-plane", "spheres"] {
        let Some(scene) = load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        for (rate, kind) in
            [(32, PatternKind::Grid), (32, PatternKind::Rotated), (128, PatternKind::Grid)]
        {
            let (_, masks, rec) = run_masks(&pan09(rate, kind, VisibilityMode::Exact), &frame);
            let truth = samples(&frame, rate, kind);
            let c = compare_on_plane(&frame, &masks.occlusion, &masks.valid, &truth);
            eprintln!(
                "{name} {rate} {kind}: {c:?}, {} silhouette pixels",
                rec.counters.silhouette_pixels
            );
            assert!(c.pixels > 5000 && c.shadowed > 1000, "{name}: {c:?}");
            assert_eq!(c.invalid, 0, "{name} {rate} {kind}");
            assert!(c.mismatches as f64 <= 1e-5 * c.samples as f64, "{name} {rate} {kind}: {c:?}");
        }
    }
}

/// Pixels of each class.
fn classes(masks: &SubsampleMasks) -> (Vec<usize>, Vec<usize>) {
    let (mut depth_test, mut silhouette) = (Vec::new(), Vec::new());
    for (k, c) in masks.class.iter().enumerate() {
        match c {
            PixelClass::DepthTest => depth_test.push(k),
            PixelClass::Silhouette(_) => silhouette.push(k),
            PixelClass::Lit => {}
        }
    }
    (depth_test, silhouette)
}

fn run_named(name: &str, frame: &Frame<'_>, options: MethodOptions) -> Visibility {
    method(name, &options).expect("valid").run(frame, &mut Recorder::default()).expect("runs")
}

#[test]
fn non_silhouette_pixels_are_sm_and_silhouette_pixels_at_rate_1_are_afsm() {
    for name in ["plane-square", "cage", "spheres", "spot-spheres", "grazing", "bunny-plane"] {
        let Some(scene) = load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        let sm =
            run_named("sm", &frame, MethodOptions { map_res: Some(512), ..Default::default() });
        let afsm = run_named("afsm", &frame, MethodOptions::default());
        for (rate, visibility) in
            [(1, VisibilityMode::Table), (1, VisibilityMode::Exact), (32, VisibilityMode::Table)]
        {
            let (v, masks, _) = run_masks(&pan09(rate, PatternKind::Grid, visibility), &frame);
            let (depth_test, silhouette) = classes(&masks);
            assert!(depth_test.len() > 1000 && silhouette.len() > 20, "{name}");
            let off_sm = depth_test.iter().filter(|&&k| v.lit[k] != sm.lit[k]).count();
            assert_eq!(
                off_sm, 0,
                "{name} {rate} {visibility}: non-silhouette pixels differ from sm"
            );
            if rate == 1 {
                let off: Vec<usize> =
                    silhouette.iter().copied().filter(|&k| v.lit[k] != afsm.lit[k]).collect();
                eprintln!(
                    "{name} {visibility}: {} silhouette pixels, {} differ from afsm",
                    silhouette.len(),
                    off.len()
                );
                assert!(off.is_empty(), "{name} {visibility}: pixels {off:?} differ from afsm");
            }
        }
    }
}

#[test]
fn table_mode_flips_only_sub_samples_near_an_edge() {
    for name in ["plane-square", "cage", "random-10k", "plant"] {
        let Some(scene) = load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        for rate in [32, 128] {
            let (exact_v, exact, _) =
                run_masks(&pan09(rate, PatternKind::Grid, VisibilityMode::Exact), &frame);
            let (table_v, table, _) =
                run_masks(&pan09(rate, PatternKind::Grid, VisibilityMode::Table), &frame);
            assert_eq!(exact.class, table.class, "classification does not depend on the mode");
            let (depth_test, silhouette) = classes(&exact);
            assert!(depth_test.iter().all(|&k| exact_v.lit[k] == table_v.lit[k]));
            let centre =
                1u128 << SamplePattern::new(rate, PatternKind::Grid).expect("valid").centre_index();
            let (mut flips, mut samples) = (0u32, 0u64);
            for &k in &silhouette {
                let differ =
                    (exact.occlusion[k] & exact.valid[k]) ^ (table.occlusion[k] & table.valid[k]);
                let differ = differ | (exact.valid[k] ^ table.valid[k]);
                assert_eq!(differ & centre, 0, "{name}: the centre sample is exact");
                flips += differ.count_ones();
                samples += u64::from(rate);
            }
            let fraction = f64::from(flips) / samples as f64;
            eprintln!(
                "{name} {rate}: {flips} of {samples} silhouette sub-samples flipped ({fraction:.2e})"
            );
            assert!(fraction < 1e-2, "{name} {rate}: {fraction}");
        }
    }
}

fn plane(name: &str, size: f64, transform: Transform) -> ObjectDesc {
    ObjectDesc {
        name: Some(name.into()),
        shape: Shape::Plane(PlaneParams { size, subdivisions: 1 }),
        transform,
        material: Material::default(),
        casts_shadows: true,
    }
}

fn scene(camera: Camera, light: Light, objects: Vec<ObjectDesc>, res: [u32; 2]) -> Scene {
    SceneDesc {
        name: Some("hard".into()),
        resolution: res,
        camera,
        light,
        effects: Default::default(),
        animation: Default::default(),
        objects,
    }
    .resolve("hard", std::path::Path::new("test"), std::path::Path::new("."))
    .expect("valid scene")
}

/// Runs both modes and the ray tracer; checks ranges and returns the exact mode's comparison
/// on the receiver plane, the sub-samples where it differs, and the number of pixels with
/// sub-samples outside their facet.
fn hard_case(scene: &Scene, rate: u32) -> (Comparison, Vec<(usize, usize)>, usize) {
    let frame = Frame::new(scene, scene.width, scene.height, &mut Recorder::default());
    for visibility in [VisibilityMode::Table, VisibilityMode::Exact] {
        for kind in [PatternKind::Grid, PatternKind::Rotated] {
            run_masks(&pan09(rate, kind, visibility), &frame);
        }
    }
    let (_, masks, _) = run_masks(&pan09(rate, PatternKind::Grid, VisibilityMode::Exact), &frame);
    let truth = samples(&frame, rate, PatternKind::Grid);
    let c = compare_on_plane(&frame, &masks.occlusion, &masks.valid, &truth);
    let r = rate as usize;
    let differing = (0..truth.light.len())
        .filter(|&i| {
            let (k, s) = (i / r, i % r);
            let on_plane = truth.triangle[k * r..(k + 1) * r].iter().all(|&t| {
                t != methods::raster::NO_TRIANGLE && frame.geometry.object[t as usize] == 0
            });
            on_plane && (masks.occlusion[k] >> s & 1 == 1) != (truth.light[i] == 0.0)
        })
        .map(|i| (i / r, i % r))
        .collect();
    let all = (1u128 << (rate - 1) << 1).wrapping_sub(1);
    let cut = masks.valid.iter().filter(|&&v| v != all).count();
    (c, differing, cut)
}

#[test]
fn exact_hard_case_shadow_edges_on_pixel_rows_and_through_sub_samples() {
    // An orthographic camera straight down, 1/8 world unit per pixel (image x = 8 (X + 4),
    // y = 8 (Z + 3)), and a light that moves a shadow by (X, Z) = (h / 2, h / 4) at height h:
    // 4 and 2 pixels for the square at height 1, whose shadow edges lie on pixel rows and
    // columns, 2 and 1 pixels for the one at height 1/2, whose shadow edges pass through the
    // sub-samples at 3/8 and 1/4 of a pixel (the grid pattern's sub-samples sit at multiples
    // of 1/8 and 1/4 of a pixel).
    let camera = Camera::Orthographic {
        eye: DVec3::new(0.0, 10.0, 0.0),
        target: DVec3::ZERO,
        up: DVec3::new(0.0, 0.0, -1.0),
        height: 6.0,
    };
    let light = Light::Directional { direction: DVec3::new(0.5, -1.0, 0.25) };
    let squares = [
        (DVec3::new(-2.0, 1.0, 0.0), 2.0),
        (DVec3::new(1.0 + 3.0 / 64.0, 0.5, 0.5 + 1.0 / 32.0), 1.5),
    ];
    let mut objects = vec![plane("ground", 12.0, Transform::default())];
    for (i, (at, size)) in squares.iter().enumerate() {
        objects.push(plane(
            &format!("square {i}"),
            *size,
            Transform { translate: *at, ..Default::default() },
        ));
    }
    let (c, differing, _) = hard_case(&scene(camera, light, objects, [64, 48]), 32);
    eprintln!("pixel rows: {c:?}, {} differing sub-samples", differing.len());
    assert!(c.pixels > 2000 && c.shadowed > 2000, "{c:?}");
    // Sub-samples exactly on a shadow edge break the tie by each method's own rule; every
    // other one agrees.
    let pattern = SamplePattern::new(32, PatternKind::Grid).expect("valid");
    for (k, s) in differing {
        let p = pattern.point((k % 64) as u32, (k / 64) as u32, s);
        let (x, z) = (p.x / 8.0 - 4.0, p.y / 8.0 - 3.0);
        let on_edge = squares.iter().any(|(at, size)| {
            let h = size / 2.0;
            let (dx, dz) = ((x - at.x - at.y / 2.0).abs(), (z - at.z - at.y / 4.0).abs());
            (dx == h && dz <= h) || (dz == h && dx <= h)
        });
        assert!(on_edge, "sub-sample {s} of pixel {k} at ({x}, {z}) differs off the edges");
    }
}

#[test]
fn exact_hard_cases_edge_on_facets_intersecting_casters_grazing_light() {
    let camera = |eye: DVec3, target: DVec3| Camera::Perspective {
        eye,
        target,
        up: DVec3::Y,
        fov_y_deg: 45.0,
        near: 0.01,
    };
    let light = Light::Directional { direction: DVec3::new(-0.4, -1.0, -0.25) };
    // A wall the camera sees within a tenth of a degree of edge-on (its plane passes 0.01
    // beside the eye, 7 units away): its facets reach far beyond 4 times their depth within
    // the pixel and are cut by their region.
    let wall = plane(
        "wall",
        3.0,
        Transform {
            rotate_deg: DVec3::new(0.0, 0.0, 88.0),
            translate: DVec3::new(0.0, 1.5, 0.0),
            ..Default::default()
        },
    );
    // A square piercing the ground: its shadow starts at the line where it meets the ground,
    // inside facets that straddle that line.
    let piercing = plane(
        "piercing",
        4.0,
        Transform {
            rotate_deg: DVec3::new(35.0, 20.0, 0.0),
            translate: DVec3::new(0.0, 0.4, 0.0),
            ..Default::default()
        },
    );
    let cases = [
        (
            "edge-on wall",
            scene(
                camera(DVec3::new(0.0, 1.2, 7.0), DVec3::new(0.0, 0.5, 0.0)),
                light.clone(),
                vec![plane("ground", 12.0, Transform::default()), wall],
                [96, 72],
            ),
        ),
        (
            "piercing square",
            scene(
                camera(DVec3::new(-2.0, 4.0, -6.0), DVec3::ZERO),
                light,
                vec![plane("ground", 12.0, Transform::default()), piercing],
                [96, 72],
            ),
        ),
        ("grazing light", scenes::load("grazing").expect("built-in")),
    ];
    for (label, mut s) in cases {
        s.width = 96;
        s.height = 72;
        let (c, differing, cut) = hard_case(&s, 32);
        eprintln!("{label}: {c:?}, {cut} pixels with sub-samples left out (region or validity)");
        if label == "edge-on wall" {
            assert!(cut > 0, "the wall's facets are cut by their region");
        }
        assert!(c.pixels > 1000 && c.shadowed > 500, "{label}: {c:?}");
        assert_eq!(c.invalid, 0, "{label}");
        assert!(differing.len() as f64 <= 1e-5 * c.samples as f64, "{label}: {differing:?}");
    }
}

#[test]
fn stages_counters_and_the_skipped_validity_mask() {
    use methods::pan09::*;
    let planar = load_builtin("plane-square").expect("built-in");
    let frame = Frame::new(&planar, 96, 72, &mut Recorder::default());
    let (v, masks, rec) = run_masks(&Pan09::new(Pan09Options::default()).expect("valid"), &frame);
    let names: Vec<&str> = rec.stages.stages.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        [
            STAGE_LIGHT_DEPTH_MAP,
            STAGE_EDGE_ADJACENCY,
            STAGE_SILHOUETTE_EDGES,
            STAGE_SILHOUETTE_MASK,
            STAGE_SAT,
            STAGE_FACETS,
            STAGE_DEPTH_TEST,
            STAGE_PT_PAIRS,
            STAGE_TT_PAIRS,
            STAGE_VISIBILITY,
            STAGE_OCCLUSION_RATIO,
        ]
    );
    assert_eq!(rec.stages.skipped, [STAGE_VALIDITY]);
    let grouped: f64 = table1_times(&rec.stages).iter().sum();
    let adjacency =
        rec.stages.stages.iter().find(|s| s.name == STAGE_EDGE_ADJACENCY).map_or(0.0, |s| s.ms);
    assert!(
        (grouped + adjacency - rec.stages.total_ms()).abs() < 1e-9,
        "every other stage is in a group"
    );
    let c = rec.counters;
    let (depth_test, silhouette) = classes(&masks);
    assert_eq!(c.silhouette_pixels, silhouette.len() as u64);
    assert_eq!(c.shadow_map_lookups, depth_test.len() as u64);
    assert!(c.silhouette_texels > 0 && c.pt_pairs >= c.silhouette_pixels && c.tt_pairs > 0);
    assert!(c.visibility_evaluations > 0);
    assert_eq!(c.valid_samples, 0, "no validity mask on planar receivers");
    assert_eq!(c.boundary_pixels, v.lit.iter().filter(|&&l| l > 0.0 && l < 1.0).count() as u64);
    assert!(c.boundary_pixels > 10);
    assert!(silhouette.iter().all(|&k| masks.valid[k] == u128::from(u32::MAX)));

    let curved = load_builtin("cage").expect("built-in");
    let frame = Frame::new(&curved, 96, 72, &mut Recorder::default());
    let (_, _, rec) = run_masks(&Pan09::new(Pan09Options::default()).expect("valid"), &frame);
    assert!(rec.stages.stages.iter().any(|s| s.name == STAGE_VALIDITY));
    assert!(rec.stages.skipped.is_empty());
    assert!(rec.counters.valid_samples > 0);
}

#[test]
fn validity_mask_on_the_bumpy_receiver_fig_9() {
    let Some(scene) = load_builtin("bumpy") else { return };
    let frame = Frame::new(&scene, 200, 150, &mut Recorder::default());
    let (v, masks, rec) = run_masks(&pan09(32, PatternKind::Grid, VisibilityMode::Table), &frame);
    let c = rec.counters;
    let mean = c.valid_samples as f64 / c.boundary_pixels as f64;
    let reduced = masks.valid.iter().filter(|&&m| m != u128::from(u32::MAX)).count();
    eprintln!(
        "bumpy: {} boundary pixels, {mean:.1} valid sub-samples each (paper: 18.5 of 32), {reduced} \
         pixels with invalid sub-samples",
        c.boundary_pixels
    );
    assert!(c.boundary_pixels > 100 && reduced > 10);
    assert!(mean > 1.0 && mean <= 32.0, "{mean}");
    // The centre sub-sample is always valid, so every ratio has a denominator.
    let centre = 1u128 << SamplePattern::new(32, PatternKind::Grid).expect("valid").centre_index();
    assert!(masks.valid.iter().all(|&m| m & centre != 0));
    assert!(v.lit.iter().all(|l| l.is_finite() && (0.0..=1.0).contains(l)));
}

#[test]
fn results_and_counters_do_not_depend_on_the_thread_count() {
    for name in ["cage", "spot-spheres"] {
        let scene = load_builtin(name).expect("built-in");
        let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
        let m = pan09(32, PatternKind::Rotated, VisibilityMode::Table);
        let (many, masks_many, rec_many) = run_masks(&m, &frame);
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a pool");
        let (single, masks_single, rec_single) = one.install(|| run_masks(&m, &frame));
        assert_eq!(many, single, "{name}");
        assert_eq!(masks_many, masks_single, "{name}");
        assert_eq!(rec_many.counters, rec_single.counters, "{name}");
    }
}

#[test]
fn registry_builds_pan09_and_rejects_bad_options() {
    assert!(methods::METHODS.iter().any(|m| m.name == "pan09"));
    let m = method("pan09", &MethodOptions::default()).expect("valid");
    assert_eq!(m.name(), "pan09");
    let p = m.params();
    assert_eq!((p["rate"].as_u64(), p["map_res"].as_u64()), (Some(32), Some(512)));
    assert_eq!((p["pattern"].as_str(), p["masks"].as_str()), (Some("grid"), Some("table")));
    let exact = MethodOptions {
        rate: Some(128),
        pattern: Some(PatternKind::Rotated),
        visibility: Some(VisibilityMode::Exact),
        map_res: Some(256),
        ..Default::default()
    };
    let p = method("pan09", &exact).expect("valid").params();
    assert_eq!((p["rate"].as_u64(), p["masks"].as_str()), (Some(128), Some("exact")));
    let error = |o: MethodOptions| method("pan09", &o).err();
    for rate in [0, 2, 256, 1024] {
        assert!(matches!(
            error(MethodOptions { rate: Some(rate), ..Default::default() }),
            Some(MethodError::InvalidOption { option: "--rate", .. })
        ));
    }
    assert!(matches!(
        error(MethodOptions { map_res: Some(0), ..Default::default() }),
        Some(MethodError::InvalidOption { option: "--map-res", .. })
    ));
    assert!(matches!(
        "bitmask".parse::<VisibilityMode>(),
        Err(MethodError::InvalidOption { option: "--masks", .. })
    ));
    for mode in [VisibilityMode::Table, VisibilityMode::Exact] {
        assert_eq!(mode.name().parse::<VisibilityMode>().expect("parses"), mode);
    }
}

#[test]
fn cli_renders_pan09_in_both_modes_and_rejects_a_bad_mode() {
    let dir = tempfile::tempdir().expect("tempdir");
    for mode in ["table", "exact"] {
        let out = dir.path().join(mode);
        let o = common::shadowbench(&[
            "render",
            "--scene",
            "plane-square",
            "--method",
            "pan09",
            "--masks",
            mode,
            "--rate",
            "8",
            "--width",
            "64",
            "--height",
            "48",
            "--json",
            "--out",
            out.to_str().expect("utf-8 path"),
        ]);
        assert!(o.status.success(), "{}", common::stderr(&o));
        let run: serde_json::Value = serde_json::from_slice(&o.stdout).expect("run.json");
        assert_eq!(run["method"], "pan09");
        assert_eq!(run["params"]["masks"], mode);
        assert_eq!(run["params"]["rate"], 8);
        assert!(run["counters"]["silhouette_pixels"].as_u64().expect("count") > 0);
        assert_eq!(run["skipped_stages"][0], "validity mask");
        assert!(out.join("visibility.exr").exists());
    }
    let o = common::shadowbench(&[
        "render",
        "--scene",
        "plane-square",
        "--method",
        "pan09",
        "--masks",
        "lut",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", common::stderr(&o));
    let o = common::shadowbench(&[
        "render",
        "--scene",
        "plane-square",
        "--method",
        "pan09",
        "--rate",
        "3",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(common::stderr(&o).contains("--rate"), "{}", common::stderr(&o));
}
