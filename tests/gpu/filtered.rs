//! The filtered shadow maps' kernels (`vsm`, `esm`, `msm`) against their CPU twins: given the
//! CPU's own light depth map and G-buffer, every stored and filtered value, every pixel and
//! every counter agree bit for bit, at every precision each method stores, with filters of 1,
//! 3 and 9 texels and the light-bleeding reduction on; and each GPU method runs end to end
//! through `ShadowMethod::run` with its twin's stages.

use crate::common::load_builtin;
use instrumentation::Recorder;
use methods::{
    depth_test::{DepthTester, MapOptions},
    filtered_map::{filtered_values, FilteredMap, Precision},
    gpu::{filtered as gpu_filtered, GpuContext, GpuDepthMap, GpuFrame},
    registry::{
        esm::{self, ExponentialShadowMap},
        msm::{self, MomentShadowMap},
        vsm::{self, VarianceShadowMap},
    },
    Frame, LightFit, MethodOptions,
};

const SCENES: [&str; 5] = ["plane-square", "cage", "random-10k", "bumpy", "spot-spheres"];
const WIDTH: u32 = 160;
const HEIGHT: u32 = 120;
const FILTERS: [u32; 3] = [1, 3, 9];

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

fn map_options(frustum: LightFit) -> MapOptions {
    MapOptions { map_res: 256, frustum, ..Default::default() }
}

/// `m`'s kernels on the CPU's map and G-buffer of `frame` against `m` itself: the filtered
/// values and the counters bit for bit, the lit values bit for bit (`tolerance` 0) or within
/// `tolerance`.
fn assert_parity<const N: usize, M: FilteredMap<N>>(
    frame: &Frame<'_>,
    m: &M,
    what: &str,
    tolerance: f32,
) {
    let what = format!("{} {what}", frame.scene.name);
    let o = m.map();
    let map = frame.light_depth_map(o.map_res, o.frustum, &mut Recorder::default());
    let (near, _) = frame.light_depth_bounds(&map.projector);
    let range = frame.light_depth_range(&map.projector);
    let cpu_values = filtered_values(m, &map, near, range);
    let gmap = GpuDepthMap::upload(ctx(), &map);
    let gframe = GpuFrame::upload(ctx(), frame, &frame.gbuffer);
    let mut rec = Recorder::default();
    let values = gpu_filtered::store_and_filter(ctx(), &gmap, near, range, m, &mut rec)
        .expect("the store and filter kernels run");
    let gpu_values = values.read::<N>(ctx()).expect("read back");
    assert_eq!(gpu_values.len(), cpu_values.len(), "{what}");
    let differ = cpu_values
        .iter()
        .zip(&gpu_values)
        .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.to_bits() != y.to_bits()))
        .count();
    let first = cpu_values.iter().zip(&gpu_values).find(|(a, b)| a != b);
    assert_eq!(differ, 0, "{what}: {differ} texels differ, first {first:?}");
    let tester = DepthTester::new(o, map.projector, range);
    let (lit, counters) =
        gpu_filtered::test(ctx(), &gframe, &gmap, &tester, (near, range), &values, m, &mut rec)
            .expect("the test kernel runs");
    let mut cpu_rec = Recorder::default();
    let cpu = m.run(frame, &mut cpu_rec).expect("the CPU method runs");
    let differ = cpu.lit.iter().zip(&lit).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
    let worst = cpu.lit.iter().zip(&lit).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
    let partial = lit.iter().filter(|&&l| l > 0.0 && l < 1.0).count();
    eprintln!("{what}: {differ} pixels differ (at most {worst:e}), {partial} partly lit");
    if tolerance == 0.0 {
        assert_eq!(differ, 0, "{what}");
    } else {
        assert!(worst <= tolerance, "{what}: {worst:e}");
    }
    assert_eq!(cpu_rec.counters.shadow_map_lookups, counters.shadow_map_lookups, "{what}");
    assert_eq!(cpu_rec.counters.bilinear_lookups, counters.bilinear_lookups, "{what}");
    assert!(counters.shadow_map_lookups > 0, "{what}");
}

#[test]
fn gpu_parity_vsm_equals_the_cpu_bit_for_bit() {
    for_each_frame(|frame| {
        for precision in vsm::PRECISIONS {
            for filter in FILTERS {
                let m = VarianceShadowMap {
                    map: map_options(LightFit::Scene),
                    filter,
                    precision,
                    min_variance: vsm::DEFAULT_MIN_VARIANCE,
                    bleeding_reduction: 0.2,
                };
                let what = format!("vsm {} filter {filter}", precision.name());
                assert_parity(frame, &m, &what, 0.0);
            }
        }
        // No least variance: the bound falls to 0 behind a caster at f64.
        let m = VarianceShadowMap {
            map: map_options(LightFit::ViewSnapped),
            filter: 1,
            precision: Precision::F64,
            min_variance: 0.0,
            bleeding_reduction: 0.0,
        };
        assert_parity(frame, &m, "vsm f64 filter 1 no least variance, view-snapped", 0.0);
    });
}

#[test]
fn gpu_parity_esm_equals_the_cpu_bit_for_bit() {
    for_each_frame(|frame| {
        for precision in esm::PRECISIONS {
            for filter in FILTERS {
                let m = ExponentialShadowMap {
                    map: map_options(LightFit::Scene),
                    filter,
                    precision,
                    exponent: esm::DEFAULT_EXPONENT,
                };
                let what = format!("esm {} filter {filter}", precision.name());
                assert_parity(frame, &m, &what, 0.0);
            }
        }
        let m = ExponentialShadowMap {
            map: map_options(LightFit::View),
            filter: 5,
            precision: Precision::F64,
            exponent: esm::MAX_EXPONENT,
        };
        assert_parity(frame, &m, "esm f64 filter 5 c 700, view", 0.0);
    });
}

#[test]
fn gpu_parity_msm_equals_the_cpu_bit_for_bit() {
    for_each_frame(|frame| {
        for precision in msm::PRECISIONS {
            for filter in FILTERS {
                let m = MomentShadowMap {
                    map: map_options(LightFit::Scene),
                    filter,
                    precision,
                    moment_bias: msm::default_moment_bias(precision),
                    bleeding_reduction: 0.2,
                };
                let what = format!("msm {} filter {filter}", precision.name());
                assert_parity(frame, &m, &what, 0.0);
            }
        }
        // No bias: a texel of one depth makes the Hankel matrix singular, and where the
        // reconstruction cancels that badly the last bits show the driver's freedom to fuse a
        // multiply and an add (llvmpipe does in some expressions; WGSL allows it): one pixel
        // of spot-spheres differs in its last f32 bit. Within 1e-6 there.
        let m = MomentShadowMap {
            map: map_options(LightFit::Scene),
            filter: 3,
            precision: Precision::U16,
            moment_bias: 0.0,
            bleeding_reduction: 0.0,
        };
        assert_parity(frame, &m, "msm u16 filter 3 no bias", 1e-6);
    });
}

/// Every filtered map runs end to end on the GPU from the registry: values in [0, 1], the
/// twin's stages (after the GPU G-buffer), the adapter note, the twin's parameters plus the
/// device, and the twin's warnings about its options.
#[test]
fn gpu_filtered_maps_run_end_to_end_with_the_twins_stages() {
    for scene in ["plane-square", "spot-spheres"] {
        let Some(scene) = load_builtin(scene) else { continue };
        let frame = Frame::new(&scene, WIDTH, HEIGHT, &mut Recorder::default());
        for name in ["vsm", "esm", "msm"] {
            let cpu_options = MethodOptions { map_res: Some(256), ..Default::default() };
            let gpu_options =
                MethodOptions { device: methods::registry::Device::Gpu, ..cpu_options.clone() };
            let cpu = methods::method(name, &cpu_options).expect("builds");
            let gpu = methods::method(name, &gpu_options).expect("builds on the GPU");
            let mut params = cpu.params();
            params.insert("device".into(), "gpu".into());
            assert_eq!(gpu.params(), params, "{name}");
            let mut rec = Recorder::default();
            let v = gpu.run(&frame, &mut rec).expect("the GPU method runs");
            assert_eq!(v.lit.len(), (WIDTH * HEIGHT) as usize);
            assert!(v.lit.iter().all(|l| (0.0..=1.0).contains(l)), "{name}");
            assert!(v.lit.iter().any(|&l| l < 0.5), "{name}: no shadow on {}", scene.name);
            assert!(rec.notes.iter().any(|n| n.starts_with("GPU: ")), "{name}: {:?}", rec.notes);
            let mut cpu_rec = Recorder::default();
            cpu.run(&frame, &mut cpu_rec).expect("the CPU method runs");
            let names =
                |r: &Recorder| r.stages.stages.iter().map(|s| s.name.clone()).collect::<Vec<_>>();
            let mut want = vec![methods::frame::STAGE_GPU_GBUFFER.to_owned()];
            want.extend(names(&cpu_rec));
            assert_eq!(names(&rec), want, "{name}");
            assert_eq!(rec.warnings, cpu_rec.warnings, "{name}");
            assert!(rec.counters.shadow_map_lookups > 0, "{name}");
            let times: Vec<String> =
                rec.stages.stages.iter().map(|s| format!("{} {:.2} ms", s.name, s.ms)).collect();
            eprintln!("{name} ({}): {}", ctx().adapter_name(), times.join(", "));
        }
    }
}
