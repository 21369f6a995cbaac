//! The GPU kernels of `sm` and the percentage-closer filtering methods against their CPU
//! twins: given the CPU's own G-buffer and depth maps, every pixel and every counter must
//! agree; and each GPU method runs end to end through `ShadowMethod::run`.

use crate::common::load_builtin;
use instrumentation::{Counters, Recorder};
use methods::{
    depth_test::{DepthTester, MapOptions},
    gpu::{
        pcf::{self as gpu_pcf, GpuDepthCode, GpuPcf},
        sm::{self as gpu_sm, GpuShadowMap},
        GpuContext, GpuDepthMap, GpuFrame,
    },
    pcf_bs::{BrabecSeidelPcf, BsOptions, Variant, JITTERS},
    pcf_gems::{GemsPcf, GemsSamples},
    pcf_reeves::{ReevesOptions, ReevesPcf},
    sm::StandardShadowMap,
    Frame, LightFit, ShadowMethod, Visibility,
};

const SCENES: [&str; 5] = ["plane-square", "cage", "random-10k", "bumpy", "spot-spheres"];
const WIDTH: u32 = 160;
const HEIGHT: u32 = 120;

fn ctx() -> &'static GpuContext {
    GpuContext::shared().expect("a GPU adapter with f64 shaders (CI installs Mesa's Vulkan driver)")
}

/// Runs `check` on a 160 x 120 frame of each scene whose models are present.
fn for_each_frame(mut check: impl FnMut(&Frame<'_>)) {
    for name in SCENES {
        let Some(scene) = load_builtin(name) else { continue };
        let frame = Frame::new(&scene, WIDTH, HEIGHT, &mut Recorder::default());
        check(&frame);
    }
}

fn cpu_run(m: &dyn ShadowMethod, frame: &Frame<'_>) -> (Visibility, Counters) {
    let mut rec = Recorder::default();
    let v = m.run(frame, &mut rec).expect("the CPU method runs");
    (v, rec.counters)
}

/// Pixels that differ and the largest difference.
fn compare(cpu: &[f32], gpu: &[f32]) -> (usize, f32) {
    assert_eq!(cpu.len(), gpu.len());
    let differ = cpu.iter().zip(gpu).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
    let max = cpu.iter().zip(gpu).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    (differ, max)
}

fn assert_counters(what: &str, cpu: &Counters, gpu: &Counters) {
    assert_eq!(cpu.shadow_map_lookups, gpu.shadow_map_lookups, "{what}: shadow_map_lookups");
    assert_eq!(cpu.bilinear_lookups, gpu.bilinear_lookups, "{what}: bilinear_lookups");
}

/// A PCF variant's result within 1e-6 of its twin's per pixel, with equal counters.
fn assert_close(what: &str, cpu: (&[f32], &Counters), gpu: (&[f32], &Counters)) {
    let (differ, max) = compare(cpu.0, gpu.0);
    eprintln!(
        "{what}: {differ} pixels differ, max |difference| {max:e}, {} compares, {} bilinear lookups",
        gpu.1.shadow_map_lookups, gpu.1.bilinear_lookups
    );
    assert!(max <= 1e-6, "{what}: max |difference| {max:e}");
    assert_counters(what, cpu.1, gpu.1);
}

fn map_options(map_res: u32) -> MapOptions {
    MapOptions { map_res, ..Default::default() }
}

/// The CPU's map, the tester the CPU method builds for it, and both uploaded.
fn uploaded(frame: &Frame<'_>, options: &MapOptions) -> (GpuFrame, GpuDepthMap, DepthTester) {
    let map = frame.light_depth_map(options.map_res, options.frustum, &mut Recorder::default());
    let tester = DepthTester::new(options, map.projector, frame.light_depth_range(&map.projector));
    (GpuFrame::upload(ctx(), frame, &frame.gbuffer), GpuDepthMap::upload(ctx(), &map), tester)
}

#[test]
fn gpu_parity_sm_equals_the_cpu_per_pixel() {
    for_each_frame(|frame| {
        for (map_res, frustum) in
            [(256, LightFit::Scene), (512, LightFit::Scene), (256, LightFit::ViewSnapped)]
        {
            let options = MapOptions { frustum, ..map_options(map_res) };
            let (cpu, cpu_counters) = cpu_run(&StandardShadowMap { options }, frame);
            let (gframe, map, tester) = uploaded(frame, &options);
            let mut rec = Recorder::default();
            let (lit, counters) =
                gpu_sm::depth_test(ctx(), &gframe, &map, &tester, &mut rec).expect("kernel runs");
            let (differ, _) = compare(&cpu.lit, &lit);
            let what = format!("{} sm map {map_res} {}", frame.scene.name, frustum.as_str());
            eprintln!("{what}: {differ} pixels differ, {} compares", counters.shadow_map_lookups);
            assert_eq!(differ, 0, "{what}");
            assert_counters(&what, &cpu_counters, &counters);
            assert!(counters.shadow_map_lookups > 0, "{what}");
        }
    });
}

#[test]
fn gpu_parity_pcf_reeves_matches_the_cpu_per_pixel() {
    for_each_frame(|frame| {
        for (samples, seed) in [(16, 0), (8, 0x1234_5678_9abc_def0)] {
            let options = ReevesOptions { map: map_options(256), samples, seed };
            let (cpu, cpu_counters) = cpu_run(&ReevesPcf { options }, frame);
            let (gframe, map, tester) = uploaded(frame, &options.map);
            let (lit, counters) =
                gpu_pcf::reeves(ctx(), &gframe, &map, &tester, &options, &mut Recorder::default())
                    .expect("kernel runs");
            let what = format!("{} pcf-reeves rate {samples}", frame.scene.name);
            assert_close(&what, (&cpu.lit, &cpu_counters), (&lit, &counters));
        }
    });
}

#[test]
fn gpu_parity_pcf_gems_matches_the_cpu_per_pixel() {
    for_each_frame(|frame| {
        for samples in [GemsSamples::Sixteen, GemsSamples::FourDithered] {
            let options = map_options(256);
            let twin = GemsPcf { options, samples };
            let (cpu, cpu_counters) = cpu_run(&twin, frame);
            let (gframe, map, tester) = uploaded(frame, &options);
            let (lit, counters) =
                gpu_pcf::gems(ctx(), &gframe, &map, &tester, samples, &mut Recorder::default())
                    .expect("kernel runs");
            let what = format!("{} {}", frame.scene.name, twin.name());
            assert_close(&what, (&cpu.lit, &cpu_counters), (&lit, &counters));
            assert!(counters.bilinear_lookups > 0, "{what}");
        }
    });
}

#[test]
fn gpu_parity_pcf_bs_matches_the_cpu_per_pixel() {
    for_each_frame(|frame| {
        for depth_bits in [8, 32] {
            for variant in [Variant::Stratified2x2, Variant::Fast2x2, Variant::Fast4x4] {
                let mut options = BsOptions::with_depth_bits(depth_bits);
                options.map.map_res = 256;
                let twin = BrabecSeidelPcf { options, variant };
                let (cpu, cpu_counters) = cpu_run(&twin, frame);
                let projector = frame.light_projector(256, options.map.frustum);
                let (near, far) = frame.light_depth_bounds(&projector);
                let code = GpuDepthCode::new(depth_bits, near, far).expect("valid bits");
                let tester =
                    DepthTester::new(&options.map, projector, frame.light_depth_range(&projector));
                let gframe = GpuFrame::upload(ctx(), frame, &frame.gbuffer);
                let mut rec = Recorder::default();
                let (lit, counters) = if variant == Variant::Stratified2x2 {
                    let maps = JITTERS.map(|shift| {
                        let fit = options.map.frustum;
                        let m = frame.jittered_light_depth_map(256, fit, shift, "map", &mut rec);
                        GpuDepthMap::upload(ctx(), &m)
                    });
                    let maps = [&maps[0], &maps[1], &maps[2], &maps[3]];
                    gpu_pcf::bs_stratified(ctx(), &gframe, maps, &tester, &code, &mut rec)
                        .expect("kernels run")
                } else {
                    let m = frame.light_depth_map(256, options.map.frustum, &mut rec);
                    let map = GpuDepthMap::upload(ctx(), &m);
                    gpu_pcf::bs_fast(ctx(), &gframe, &map, &tester, &code, variant, &mut rec)
                        .expect("kernels run")
                };
                let what = format!("{} {} {depth_bits} bits", frame.scene.name, twin.name());
                assert_close(&what, (&cpu.lit, &cpu_counters), (&lit, &counters));
            }
        }
    });
}

/// Every GPU method runs end to end: values in [0, 1], the twin's stages (plus the GPU
/// G-buffer), the adapter note and the twin's parameters plus the device.
#[test]
fn gpu_methods_run_end_to_end_with_the_twins_stages() {
    let scene = load_builtin("plane-square").expect("a built-in scene without models");
    let frame = Frame::new(&scene, WIDTH, HEIGHT, &mut Recorder::default());
    let map = map_options(256);
    type Pair = (Box<dyn ShadowMethod>, Box<dyn ShadowMethod>);
    let reeves = ReevesOptions { map, ..Default::default() };
    let view = MapOptions { frustum: LightFit::View, ..map };
    let mut methods: Vec<Pair> = vec![
        (Box::new(GpuShadowMap { options: map }), Box::new(StandardShadowMap { options: map })),
        (Box::new(GpuShadowMap { options: view }), Box::new(StandardShadowMap { options: view })),
        (Box::new(GpuPcf::Reeves { options: reeves }), Box::new(ReevesPcf { options: reeves })),
    ];
    for samples in [GemsSamples::Sixteen, GemsSamples::FourDithered] {
        methods.push((
            Box::new(GpuPcf::Gems { options: map, samples }),
            Box::new(GemsPcf { options: map, samples }),
        ));
    }
    for variant in [Variant::Stratified2x2, Variant::Fast2x2, Variant::Fast4x4] {
        let options = BsOptions { map, ..Default::default() };
        methods.push((
            Box::new(GpuPcf::BrabecSeidel { options, variant }),
            Box::new(BrabecSeidelPcf { options, variant }),
        ));
    }
    for (gpu, cpu) in &methods {
        assert_eq!(gpu.name(), cpu.name());
        let mut params = cpu.params();
        params.insert("device".into(), "gpu".into());
        assert_eq!(gpu.params(), params, "{}", gpu.name());
        let mut rec = Recorder::default();
        let v = gpu.run(&frame, &mut rec).expect("the GPU method runs");
        assert_eq!((v.width, v.height), (WIDTH, HEIGHT));
        assert_eq!(v.lit.len(), (WIDTH * HEIGHT) as usize);
        assert!(v.lit.iter().all(|l| l.is_finite() && (0.0..=1.0).contains(l)), "{}", gpu.name());
        assert!(
            rec.notes.iter().any(|n| n.starts_with("GPU: ")),
            "{}: {:?}",
            gpu.name(),
            rec.notes
        );
        let mut cpu_rec = Recorder::default();
        cpu.run(&frame, &mut cpu_rec).expect("the CPU method runs");
        let names =
            |r: &Recorder| r.stages.stages.iter().map(|s| s.name.clone()).collect::<Vec<_>>();
        let mut want = vec![methods::frame::STAGE_GPU_GBUFFER.to_owned()];
        want.extend(names(&cpu_rec));
        assert_eq!(names(&rec), want, "{}", gpu.name());
        assert!(rec.stages.stages.iter().all(|s| s.ms.is_finite() && s.ms >= 0.0));
        let times: Vec<String> =
            rec.stages.stages.iter().map(|s| format!("{} {:.2} ms", s.name, s.ms)).collect();
        eprintln!("{} ({}): {}", gpu.name(), ctx().adapter_name(), times.join(", "));
        assert!(rec.counters.shadow_map_lookups > 0, "{}", gpu.name());
    }
}
