//! `pan09` on the GPU against its CPU twin: with the CPU's own G-buffer and light depth map
//! uploaded, the occlusion and validity masks of every sub-sample, the pixel classes, the lit
//! values and the counters must equal the CPU's (`Pan09::run_masks`). Fails (does not skip)
//! when there is no GPU adapter; scenes whose models are missing are skipped.

use crate::common::load_builtin;
use instrumentation::Recorder;
use methods::{
    gpu::{pan09::GpuPan09, GpuContext, GpuDepthMap, GpuFrame},
    pan09::{Pan09, Pan09Options, StageOutputs, SubsampleMasks, VisibilityMode},
    pattern::PatternKind,
    Frame, ShadowMethod, Visibility,
};

const COUNTERS: [&str; 8] = [
    "silhouette_texels",
    "silhouette_pixels",
    "shadow_map_lookups",
    "pt_pairs",
    "tt_pairs",
    "visibility_evaluations",
    "boundary_pixels",
    "valid_samples",
];

fn counter(rec: &Recorder, name: &str) -> u64 {
    let c = &rec.counters;
    match name {
        "silhouette_texels" => c.silhouette_texels,
        "silhouette_pixels" => c.silhouette_pixels,
        "shadow_map_lookups" => c.shadow_map_lookups,
        "pt_pairs" => c.pt_pairs,
        "tt_pairs" => c.tt_pairs,
        "visibility_evaluations" => c.visibility_evaluations,
        "boundary_pixels" => c.boundary_pixels,
        "valid_samples" => c.valid_samples,
        _ => unreachable!("a counter of the list"),
    }
}

fn options(rate: u32, map_res: u32, visibility: VisibilityMode) -> Pan09Options {
    let mut o = Pan09Options { rate, pattern: PatternKind::Grid, visibility, ..Default::default() };
    o.map.map_res = map_res;
    o
}

/// Runs both on `scene` at 160 x 120 and compares everything; returns the silhouette pixels.
fn parity(scene: &str, rate: u32, map_res: u32, visibility: VisibilityMode) -> Option<u64> {
    let scene = load_builtin(scene)?;
    let ctx = GpuContext::shared().expect("a GPU adapter with f64 (Mesa's lavapipe on CI)");
    let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
    let o = options(rate, map_res, visibility);
    let mut cpu_rec = Recorder::default();
    let (cpu_v, cpu_m) =
        Pan09::new(o).expect("valid").run_masks(&frame, &mut cpu_rec).expect("cpu runs");
    let map = frame.light_depth_map(map_res, o.map.frustum, &mut Recorder::default());
    let gframe = GpuFrame::upload(ctx, &frame, &frame.gbuffer);
    let gmap = GpuDepthMap::upload(ctx, &map);
    // Stage by stage first, so that a drift shows where it starts.
    let cpu_stages = Pan09::new(o).expect("valid").stage_outputs(&frame, &mut Recorder::default());
    let gpu_stages = GpuPan09::new(o)
        .expect("valid")
        .stage_outputs(ctx, &frame, &gframe, &gmap, &mut Recorder::default())
        .expect("gpu runs");
    compare_stages(&cpu_stages, &gpu_stages);
    let mut gpu_rec = Recorder::default();
    let (gpu_v, gpu_m) = GpuPan09::new(o)
        .expect("valid")
        .run_kernels(ctx, &frame, &gframe, &gmap, &mut gpu_rec)
        .expect("gpu runs");
    compare(&cpu_v, &cpu_m, &gpu_v, &gpu_m);
    let got: Vec<u64> = COUNTERS.iter().map(|n| counter(&gpu_rec, n)).collect();
    let want: Vec<u64> = COUNTERS.iter().map(|n| counter(&cpu_rec, n)).collect();
    assert_eq!(got, want, "counters {COUNTERS:?}");
    let cpu_stages: Vec<&str> = cpu_rec.stages.stages.iter().map(|s| s.name.as_str()).collect();
    for s in &gpu_rec.stages.stages {
        assert!(cpu_stages.contains(&s.name.as_str()), "stage {} is the CPU's", s.name);
    }
    assert_eq!(gpu_rec.stages.skipped, cpu_rec.stages.skipped);
    eprintln!(
        "{}: {} silhouette pixels, {} evaluations; GPU stages {:?}",
        scene.name,
        cpu_rec.counters.silhouette_pixels,
        cpu_rec.counters.visibility_evaluations,
        gpu_rec.stages.stages.iter().map(|s| (s.name.as_str(), s.ms)).collect::<Vec<_>>()
    );
    Some(cpu_rec.counters.silhouette_pixels)
}

/// The stages up to the triangle-texel pairs, in order: the first that differs fails.
fn compare_stages(cpu: &StageOutputs, gpu: &StageOutputs) {
    assert_eq!(gpu.silhouette_edges, cpu.silhouette_edges, "silhouette extraction: edges");
    assert!(cpu.mask.contains(&true), "no texel marked: the mask map is not tested");
    let texels = cpu.mask.iter().zip(&gpu.mask).filter(|(a, b)| a != b).count();
    assert_eq!((gpu.mask.len(), texels), (cpu.mask.len(), 0), "silhouette mask map: texels");
    assert!(gpu.sat == cpu.sat, "summed-area table differs");
    let classes = cpu.class.iter().zip(&gpu.class).filter(|(a, b)| a != b).count();
    assert_eq!((gpu.class.len(), classes), (cpu.class.len(), 0), "pixel facets: classes");
    assert_eq!(gpu.facet_pixels, cpu.facet_pixels, "pixel facets: the facets' pixels");
    let lit = cpu.depth_test_lit.iter().zip(&gpu.depth_test_lit).filter(|(a, b)| a != b).count();
    assert_eq!(lit, 0, "depth test: pixels");
    assert_eq!(gpu.pairs, cpu.pairs, "PT-pairs and TT-pairs");
}

fn compare(cv: &Visibility, cm: &SubsampleMasks, gv: &Visibility, gm: &SubsampleMasks) {
    assert_eq!(gm.rate, cm.rate);
    assert_eq!(gm.class.len(), cm.class.len());
    let diff = |a: &[u128], b: &[u128]| -> (usize, usize) {
        let pixels = a.iter().zip(b).filter(|(x, y)| x != y).count();
        let samples = a.iter().zip(b).map(|(x, y)| (x ^ y).count_ones() as usize).sum();
        (pixels, samples)
    };
    let classes = cm.class.iter().zip(&gm.class).filter(|(a, b)| a != b).count();
    let occ = diff(&cm.occlusion, &gm.occlusion);
    let val = diff(&cm.valid, &gm.valid);
    let lit = cv.lit.iter().zip(&gv.lit).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
    assert_eq!(
        (classes, occ, val, lit),
        (0, (0, 0), (0, 0), 0),
        "differing classes, occlusion (pixels, sub-samples), validity (pixels, sub-samples), lit"
    );
}

#[test]
fn gpu_parity_plane_square_rate_32() {
    let sil = parity("plane-square", 32, 512, VisibilityMode::Table).expect("built in");
    assert!(sil > 0);
}

#[test]
fn gpu_parity_cage_rate_32() {
    parity("cage", 32, 512, VisibilityMode::Table);
}

#[test]
fn gpu_parity_random_10k_rate_32() {
    parity("random-10k", 32, 256, VisibilityMode::Table);
}

#[test]
fn gpu_parity_bumpy_rate_32_with_validity() {
    if let Some(scene) = load_builtin("bumpy") {
        assert!(scene.effects().curved_receivers, "bumpy calls for the validity mask");
    }
    parity("bumpy", 32, 512, VisibilityMode::Table);
}

#[test]
fn gpu_parity_spot_spheres_rate_32() {
    parity("spot-spheres", 32, 512, VisibilityMode::Table).expect("built in");
}

#[test]
fn gpu_parity_cage_rate_128() {
    parity("cage", 128, 512, VisibilityMode::Table);
}

#[test]
fn gpu_parity_plane_square_exact_rate_64() {
    parity("plane-square", 64, 256, VisibilityMode::Exact).expect("built in");
}

#[test]
fn gpu_run_is_the_shadow_method_end_to_end() {
    let scene = load_builtin("plane-square").expect("built in");
    let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
    let o = options(32, 512, VisibilityMode::Table);
    let gpu = GpuPan09::new(o).expect("valid");
    let cpu = Pan09::new(o).expect("valid");
    assert_eq!(gpu.name(), cpu.name());
    let mut want = cpu.params();
    want.insert("device".into(), "gpu".into());
    assert_eq!(gpu.params(), want);
    let mut rec = Recorder::default();
    let v = gpu.run(&frame, &mut rec).expect("runs");
    let c = cpu.run(&frame, &mut Recorder::default()).expect("runs");
    assert_eq!(v.lit, c.lit);
    assert!(rec.notes.iter().any(|n| n.starts_with("GPU: ")));
    for stage in [
        "silhouette extraction",
        "silhouette mask map",
        "summed-area table",
        "pixel facets",
        "depth test",
        "pixel-texel pairs",
        "triangle-texel pairs",
        "visibility evaluation",
        "occlusion ratio",
    ] {
        assert!(rec.stages.stages.iter().any(|s| s.name == stage), "stage {stage}");
    }
}
