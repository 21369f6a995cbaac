//! `spsm` and `spsm-f32` on the GPU against the CPU twin, pixel for pixel and counter for
//! counter, with the CPU's own G-buffer uploaded, at rate 1 and 16; and one end-to-end run.

use crate::common::load_builtin;
use instrumentation::Recorder;
use methods::{
    gpu::{spsm as gpu_spsm, GpuContext, GpuFrame},
    spsm::{Spsm, SpsmOptions, TexelFormat},
    Frame, LightFit, ShadowMethod,
};

fn options(texel: TexelFormat, rate: u32) -> SpsmOptions {
    let mut o = SpsmOptions { texel, rate, ..SpsmOptions::default() };
    o.map.map_res = 512;
    o
}

/// GPU and CPU `spsm` on `name` at 160 x 120, map 512, both texel formats, rate 1 and 16:
/// the differing pixels, classes and counters summed over the four runs (`None` when the
/// scene's model is missing).
fn compare(name: &str) -> Option<(usize, usize, usize)> {
    let scene = load_builtin(name)?;
    let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
    let ctx = GpuContext::shared().expect("a GPU adapter (Mesa's lavapipe on CI)");
    let gpu = GpuFrame::upload(ctx, &frame, &frame.gbuffer);
    let mut total = (0, 0, 0);
    for texel in [TexelFormat::Packed, TexelFormat::F32] {
        for rate in [1, 16] {
            let o = options(texel, rate);
            let mut cpu_rec = Recorder::default();
            let (cpu, cpu_classes) =
                Spsm { options: o }.run_classified(&frame, &mut cpu_rec).expect("CPU spsm runs");
            let mut rec = Recorder::default();
            let out = gpu_spsm::shade(ctx, &gpu, &frame, &o, &mut rec).expect("GPU spsm runs");
            let lit = &out.visibility.lit;
            assert_eq!(lit.len(), cpu.lit.len());
            let differing = lit.iter().zip(&cpu.lit).filter(|(g, c)| g != c).count();
            let classes = out.classes.iter().zip(&cpu_classes).filter(|(g, c)| g != c).count();
            let counters = usize::from(rec.counters != cpu_rec.counters);
            let shadowed = cpu.lit.iter().filter(|&&l| l < 1.0).count();
            let c = &rec.counters;
            let ms = |name: &str| {
                rec.stages.stages.iter().find(|s| s.name == name).map_or(f64::NAN, |s| s.ms)
            };
            eprintln!(
                "{name} {} rate {rate}: {differing} differing pixels, {classes} differing \
                 classes, counters {}, {} handed back; {shadowed} shadowed; lit {} shadowed \
                 {} neighbourhood {} uncertain {} corrected {} recovered {} lookups {} \
                 antialiased {}; classification {:.2} ms, consistent min depth {:.2} ms",
                texel.name(),
                if counters == 0 { "equal" } else { "DIFFER" },
                out.handed_back,
                c.lit_by_one_lookup,
                c.shadowed_by_one_lookup,
                c.shadowed_by_neighbourhood,
                c.uncertain_pixels,
                c.depth_corrected_texels,
                c.recovered_pixels,
                c.shadow_map_lookups,
                c.antialiased_samples,
                ms(methods::spsm::STAGE_CLASSIFICATION),
                ms(methods::spsm::STAGE_CONSISTENT_DEPTH),
            );
            if counters != 0 {
                eprintln!("GPU {:?}\nCPU {:?}", rec.counters, cpu_rec.counters);
            }
            assert!(shadowed > 0, "{name}: no shadow at all");
            total = (total.0 + differing, total.1 + classes, total.2 + counters);
        }
    }
    Some(total)
}

fn assert_parity(name: &str) {
    match compare(name) {
        Some((differing, classes, counters)) => {
            assert_eq!(
                (differing, classes, counters),
                (0, 0, 0),
                "{name}: differing pixels, classes, counter sets against the CPU spsm"
            );
        }
        None => eprintln!("{name}: skipped (model missing)"),
    }
}

#[test]
fn gpu_parity_plane_square() {
    assert_parity("plane-square");
}

#[test]
fn gpu_parity_cage() {
    assert_parity("cage");
}

#[test]
fn gpu_parity_random_10k() {
    assert_parity("random-10k");
}

#[test]
fn gpu_parity_bumpy() {
    assert_parity("bumpy");
}

#[test]
fn gpu_parity_spot_spheres() {
    assert_parity("spot-spheres");
}

#[test]
fn gpu_spsm_runs_end_to_end() {
    let scene = scenes::load("plane-square").expect("built-in");
    let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
    for texel in [TexelFormat::Packed, TexelFormat::F32] {
        let o = options(texel, 16);
        let m = gpu_spsm::GpuSpsm { options: o };
        let cpu = Spsm { options: o };
        assert_eq!(m.name(), cpu.name());
        let mut want = cpu.params();
        want.insert("device".into(), "gpu".into());
        assert_eq!(m.params(), want);
        let mut rec = Recorder::default();
        let v = m.run(&frame, &mut rec).expect("GPU spsm runs");
        assert_eq!(v.lit.len(), 160 * 120);
        assert!(v.lit.iter().all(|l| l.is_finite() && (0.0..=1.0).contains(l)));
        assert!(v.lit.contains(&0.0) && v.lit.contains(&1.0));
        let stages: Vec<&str> = rec.stages.stages.iter().map(|s| s.name.as_str()).collect();
        for stage in [
            methods::spsm::STAGE_RASTER,
            methods::spsm::STAGE_PACKING,
            methods::spsm::STAGE_CLASSIFICATION,
            methods::spsm::STAGE_CONSISTENT_DEPTH,
            methods::spsm::STAGE_RECOVERY,
            methods::spsm::STAGE_ANTIALIASING,
        ] {
            assert!(stages.contains(&stage), "stage {stage} missing from {stages:?}");
        }
        let c = &rec.counters;
        assert!(c.packed_texels > 0 && c.shadow_map_lookups > 0 && c.uncertain_pixels > 0);
        let cpu_v = cpu.run(&frame, &mut Recorder::default()).expect("CPU spsm runs");
        let differing = v.lit.iter().zip(&cpu_v.lit).filter(|(g, c)| g != c).count();
        eprintln!("end to end {}: {differing} pixels differ from the CPU's run", texel.name());
    }
}

/// Stage 1 on the GPU, conservative rasterization, against the twin's: the same triangle and
/// the same minimum conservative depth (bit for bit) in every texel, and the same counters,
/// at maps 256 and 1024 on the parity scenes (spot-spheres: a spot light, clipped
/// triangles).
#[test]
fn gpu_parity_conservative_rasterization_texel_for_texel() {
    use methods::{gpu::spsm::raster as gpu_raster, spsm::raster, spsm::texel::LightSpace};
    let ctx = GpuContext::shared().expect("a GPU adapter (Mesa's lavapipe on CI)");
    for name in ["plane-square", "cage", "random-10k", "bumpy", "spot-spheres"] {
        let Some(scene) = load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 64, 48, &mut Recorder::default());
        for res in [256, 1024] {
            let light = frame.light_projector(res, LightFit::Scene);
            let space = LightSpace::new(&light, frame.light_depth_bounds(&light));
            let caster = |t| frame.is_caster(t);
            let mut cpu_counters = Default::default();
            let cpu = raster::rasterize_conservative(
                &frame.geometry,
                caster,
                &light,
                &space,
                &mut cpu_counters,
            );
            let mut rec = Recorder::default();
            let (gpu, counts) = gpu_raster::rasterize_conservative(
                ctx,
                &frame.geometry,
                caster,
                &light,
                &space,
                "conservative rasterization",
                &mut rec,
            )
            .expect("GPU conservative rasterization");
            let texels = cpu.texel.iter().zip(&gpu.texel).filter(|(a, b)| a != b).count();
            let depths = cpu
                .depth
                .iter()
                .zip(&gpu.depth)
                .filter(|(a, b)| a.to_bits() != b.to_bits())
                .count();
            let covered = cpu.texel.iter().filter(|&&t| t != raster::NONE).count();
            eprintln!(
                "{name} map {res}: {covered} texels covered, {texels} triangles and {depths} \
                 depths differ, {} undecided",
                counts.undecided
            );
            assert!(covered > 0, "{name}: nothing rasterized");
            assert_eq!((texels, depths), (0, 0), "{name} map {res}: texels differ");
            assert_eq!(gpu.setups, cpu.setups);
            let got = (rec.counters.triangles_rasterized, counts.tested, counts.fragments);
            let want = (
                cpu_counters.triangles_rasterized,
                cpu_counters.raster_samples_tested,
                cpu_counters.conservative_fragments,
            );
            assert_eq!(got, want, "{name} map {res}: triangles, texels tested, fragments");
            assert_eq!(rec.stages.stages.len(), 1, "one stage: {:?}", rec.stages.stages);
        }
    }
}

/// Stage 2 on the GPU, packing, against the twin's: every texel's bits equal, in both
/// formats, with the twin's conservative map as input, at maps 256 and 1024 (spot-spheres:
/// derivative codes taken per texel at the decoded depth).
#[test]
fn gpu_parity_packing_texel_for_texel() {
    use methods::{
        gpu::spsm::pack as gpu_pack,
        spsm::{pack, quantize::DEFAULT_POWER, raster, texel},
    };
    let ctx = GpuContext::shared().expect("a GPU adapter (Mesa's lavapipe on CI)");
    let bits = |m: &texel::SpsmMap| -> Vec<u32> {
        match &m.texels {
            texel::Texels::Packed(w, _) => w.iter().flatten().copied().collect(),
            texel::Texels::F32(t) => t
                .iter()
                .flat_map(|x| {
                    let [a, b, c] = x.v;
                    [a[0], a[1], b[0], b[1], c[0], c[1], x.z, x.dz[0], x.dz[1]].map(f32::to_bits)
                })
                .collect(),
        }
    };
    for name in ["plane-square", "cage", "random-10k", "bumpy", "spot-spheres"] {
        let Some(scene) = load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 64, 48, &mut Recorder::default());
        for res in [256, 1024] {
            let light = frame.light_projector(res, LightFit::Scene);
            let space = texel::LightSpace::new(&light, frame.light_depth_bounds(&light));
            let caster = |t| frame.is_caster(t);
            let map = raster::rasterize_conservative(
                &frame.geometry,
                caster,
                &light,
                &space,
                &mut Default::default(),
            );
            for format in [TexelFormat::Packed, TexelFormat::F32] {
                let cpu = pack::pack_map(&map, space, format, DEFAULT_POWER);
                let mut rec = Recorder::default();
                let gpu = gpu_pack::pack_map(
                    ctx,
                    &map,
                    space,
                    format,
                    DEFAULT_POWER,
                    "packing",
                    &mut rec,
                )
                .expect("GPU packing");
                let (c, g) = (bits(&cpu.0), bits(&gpu.map));
                let differing = c.iter().zip(&g).filter(|(a, b)| a != b).count();
                eprintln!("{name} map {res} {format:?}: {differing} of {} words differ", c.len());
                assert_eq!((g.len(), differing), (c.len(), 0), "{name} map {res} {format:?}");
                assert_eq!((gpu.filled, gpu.clamped), (cpu.1, cpu.2), "filled and clamped texels");
            }
        }
    }
}

/// Stages 4 and 5 on the GPU, consistent min depth and silhouette recovery, against the
/// twin's: the same depth for every texel recovery reads and the same count of corrected
/// texels; the same silhouette (centre texel, kept pattern, facing away) and the same value
/// for every uncertain pixel, and the same counters. Each stage takes the twin's outputs as
/// its input (map, classes, consistent depths), in both formats at maps 512 and 1024
/// (spot-spheres: a spot light).
#[test]
fn gpu_parity_consistent_depth_and_silhouette_recovery() {
    use methods::{
        gpu::spsm::{depth as gpu_depth, recover as gpu_recover, texel::GpuTexels},
        spsm::{self, classify, depth, recover},
    };
    let ctx = GpuContext::shared().expect("a GPU adapter (Mesa's lavapipe on CI)");
    let mut tangents = 0;
    for name in ["plane-square", "cage", "random-10k", "bumpy", "spot-spheres"] {
        let Some(scene) = load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        let gpu_frame = GpuFrame::upload(ctx, &frame, &frame.gbuffer);
        for res in [512, 1024] {
            for texel in [TexelFormat::Packed, TexelFormat::F32] {
                let mut o = options(texel, 1);
                o.map.map_res = res;
                let (map, tester, space) = spsm::build_map(&o, &frame, &mut Recorder::default());
                let lookup = classify::Lookup { map: &map, tester, space };
                let (_, lit, uncertain, _) = classify::classify_pixels(&frame, &lookup);
                let centres: Vec<u32> = uncertain.iter().map(|u| u.texel).collect();
                let (consistent, corrected) = depth::consistent_depths(&map, &centres);
                let texels = GpuTexels::upload(ctx, &lookup);
                let gpu_consistent = gpu_depth::consistent_depths(
                    ctx,
                    &texels,
                    &uncertain,
                    &mut Recorder::default(),
                )
                .expect("GPU consistent min depth");
                assert!(
                    gpu_consistent == (consistent.clone(), corrected),
                    "{name} map {res} {texel:?}: consistent depths differ"
                );
                let mut cpu_lit = lit.clone();
                let (cpu, cpu_counters) =
                    recover::recover_pixels(&frame, &lookup, &consistent, &uncertain, &mut cpu_lit);
                let mut gpu_lit = lit;
                let mut rec = Recorder::default();
                let gpu = gpu_recover::recover_pixels(
                    ctx,
                    &gpu_frame,
                    &frame,
                    &lookup,
                    &texels,
                    &consistent,
                    &uncertain,
                    &mut gpu_lit,
                    &mut rec,
                )
                .expect("GPU silhouette recovery");
                let silhouettes = cpu.iter().zip(&gpu.silhouettes).filter(|(a, b)| a != b).count();
                let values = cpu_lit.iter().zip(&gpu_lit).filter(|(a, b)| a != b).count();
                eprintln!(
                    "{name} map {res} {texel:?}: {} uncertain, {} recovered by tangents, \
                     {silhouettes} silhouettes and {values} values differ, {} handed back",
                    uncertain.len(),
                    cpu_counters.recovered_pixels,
                    gpu.handed_back
                );
                assert_eq!(gpu.silhouettes.len(), cpu.len());
                assert_eq!((silhouettes, values), (0, 0), "{name} map {res} {texel:?}");
                assert_eq!(rec.counters, cpu_counters, "{name} map {res} {texel:?}");
                tangents += cpu_counters.recovered_pixels;
            }
        }
    }
    assert!(tangents > 0, "no pixel was decided by a silhouette function");
}
