//! Percentage-closer filtering on the GPU: `pcf-reeves`, `pcf-bs-2x2`, `pcf-bs-fast-2x2`,
//! `pcf-bs-fast-4x4`, `pcf-gems16` and `pcf-gems4` as compute kernels, each the twin of the
//! CPU method of the same name ([`ReevesPcf`], [`BrabecSeidelPcf`], [`GemsPcf`]), with the
//! same stages and counters.
//!
//! Every kernel mirrors its twin's per-pixel arithmetic in `f64`, operation for operation
//! (see [`super`] on precision), on the receiver of `receiver.wgsl` ([`super::sm`]):
//!
//! - **`pcf-reeves`** (Reeves, Salesin and Cook 1987; [`crate::pcf_reeves`]): one thread per
//!   pixel maps the pixel's corners through its tangent plane into the map (the footprint),
//!   draws the stratified jittered samples and compares each against its nearest texel. The
//!   jitter is the CPU's SplitMix64 hash of (seed, pixel, sample, axis), evaluated on the GPU
//!   with 64-bit integers emulated as pairs of `u32`, so the sample positions are the CPU's
//!   bit for bit without uploading them. Stage `percentage-closer filtering`.
//! - **Brabec and Seidel** (CGI 2001, sections 2 to 4; [`crate::pcf_bs`]): kernels for the
//!   depth-as-colour ramp (`depth encoding`), the two packings (`texel packing`: four jittered
//!   maps into RGBA, section 3; the 2x2 neighbourhood of each texel, section 4) and the shadow
//!   test (`depth test`: four code compares against one packed texel, the lit count added into
//!   a per-pixel accumulator, which `pcf-bs-fast-4x4` fills in four passes). The jittered maps
//!   of `pcf-bs-2x2` come from [`GpuDepthMap::for_run`] at the CPU's shifts
//!   ([`crate::pcf_bs::JITTERS`]).
//! - **GPU Gems** (Bunnell and Pellacini 2004, ch. 11, sections 11.3 and 11.4;
//!   [`crate::pcf_gems`]): one thread per pixel makes the 16 (or 4 dithered) bilinear PCF
//!   lookups in software, with the exact `f64` bilinear weights of the twin rather than the
//!   texture unit's quantized ones. Stage `percentage-closer filtering`.
//!
//! Counters `shadow_map_lookups` and `bilinear_lookups` are counted on the GPU as the twins
//! count them (see [`super::sm`] for how).

use super::{
    shader::Part,
    sm::{counters_buffer, map_pipeline, per_pixel, pipeline, read_counters, Params, WORKGROUP},
    GpuContext, GpuDepthMap, GpuError, GpuFrame,
};
use crate::{
    depth_test::{DepthCode, DepthTester, MapOptions},
    footprint::Sampling,
    frame::{Frame, STAGE_LIGHT_DEPTH_MAP},
    method::{MethodError, ShadowMethod, Visibility},
    pattern::grid_dims,
    pcf_bs::{BrabecSeidelPcf, BsOptions, Variant, JITTERS, QUADRANTS},
    pcf_gems::{GemsPcf, GemsSamples, GEMS_REACH, STAGE_FILTERING},
    pcf_reeves::{ReevesOptions, ReevesPcf},
};
use glam::DVec2;
use instrumentation::{Counters, Recorder};

const JITTER: Part = Part::file("pcf_jitter.wgsl", include_str!("pcf_jitter.wgsl"));
const REEVES: Part =
    Part { name: "pcf_reeves.wgsl", source: include_str!("pcf_reeves.wgsl"), needs: &[&JITTER] };
const GEMS: Part = Part::file("pcf_gems.wgsl", include_str!("pcf_gems.wgsl"));
const BS_ENCODE: Part = Part::file("pcf_bs_encode.wgsl", include_str!("pcf_bs_encode.wgsl"));
const BS_PACK: Part = Part::file("pcf_bs_pack.wgsl", include_str!("pcf_bs_pack.wgsl"));
const BS_PACK_FAST: Part =
    Part::file("pcf_bs_pack_fast.wgsl", include_str!("pcf_bs_pack_fast.wgsl"));
const BS_TEST: Part = Part::file("pcf_bs_test.wgsl", include_str!("pcf_bs_test.wgsl"));

/// The stage `percentage-closer filtering` of `pcf-reeves` on the GPU, as
/// [`crate::pcf_reeves::footprint`] and [`crate::pcf_reeves::filter`] per pixel.
pub fn reeves(
    ctx: &GpuContext,
    frame: &GpuFrame,
    map: &GpuDepthMap,
    tester: &DepthTester,
    options: &ReevesOptions,
    rec: &mut Recorder,
) -> Result<(Vec<f32>, Counters), GpuError> {
    let (grid_x, grid_y) = grid_dims(options.samples).unwrap_or((1, 1));
    let params = Params {
        samples: options.samples,
        grid_x,
        grid_y,
        seed_lo: options.seed as u32,
        seed_hi: (options.seed >> 32) as u32,
        ..Params::new(frame, map, tester)
    };
    let buffers =
        [&map.light, &frame.triangle, &frame.position, &frame.normal, &frame.camera, &map.depth];
    per_pixel(
        ctx,
        frame,
        ("pcf-reeves", &[&REEVES]),
        &params,
        &buffers,
        crate::pcf_reeves::STAGE_FILTERING,
        rec,
    )
}

/// The stage `percentage-closer filtering` of `pcf-gems16` / `pcf-gems4` on the GPU, as
/// [`crate::pcf_gems::filter`] per pixel.
pub fn gems(
    ctx: &GpuContext,
    frame: &GpuFrame,
    map: &GpuDepthMap,
    tester: &DepthTester,
    samples: GemsSamples,
    rec: &mut Recorder,
) -> Result<(Vec<f32>, Counters), GpuError> {
    debug_assert_eq!(GEMS_REACH.x, GEMS_REACH.y);
    let params = Params {
        reach: GEMS_REACH.x,
        dithered: u32::from(samples == GemsSamples::FourDithered),
        ..Params::new(frame, map, tester)
    };
    let buffers = [&map.light, &frame.triangle, &frame.position, &frame.normal, &map.depth];
    per_pixel(ctx, frame, ("pcf-gems", &[&GEMS]), &params, &buffers, STAGE_FILTERING, rec)
}

/// Brabec and Seidel's depth-as-colour ramp as the kernels read it: the
/// [`DepthCode`] of `bits` bits over light depths `near ..= far`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpuDepthCode {
    near: f64,
    span: f64,
    max_code: f64,
}

impl GpuDepthCode {
    /// The ramp `DepthCode::new(bits, near, far - near)` makes (an error for bits it rejects).
    pub fn new(bits: u32, near: f64, far: f64) -> Result<Self, MethodError> {
        let code = DepthCode::new(bits, near, far - near)?;
        Ok(Self {
            near,
            span: (far - near).max(f64::MIN_POSITIVE),
            max_code: f64::from(code.max_code()),
        })
    }
}

/// The shadow-test passes of one Brabec and Seidel run: the pipeline, the per-pixel
/// accumulator, the lit values and the counters they share.
struct ShadowTest<'a> {
    ctx: &'a GpuContext,
    frame: &'a GpuFrame,
    light: &'a wgpu::Buffer,
    pipeline: wgpu::ComputePipeline,
    uniform: wgpu::Buffer,
    accumulator: wgpu::Buffer,
    lit: wgpu::Buffer,
    counters: wgpu::Buffer,
}

impl<'a> ShadowTest<'a> {
    /// Passes for `variant` with `params` (the code, the bias, the map resolution).
    fn new(
        ctx: &'a GpuContext,
        frame: &'a GpuFrame,
        light: &'a wgpu::Buffer,
        variant: Variant,
        params: &Params,
    ) -> Self {
        debug_assert_eq!(variant.reach().x, variant.reach().y);
        let (origin, side, half_offset) = match variant {
            Variant::Stratified2x2 => (0, params.res, 0),
            Variant::Fast2x2 | Variant::Fast4x4 => (-1, params.res + 1, 1),
        };
        let levels = match variant {
            Variant::Fast4x4 => 16,
            Variant::Stratified2x2 | Variant::Fast2x2 => 4,
        };
        let params =
            Params { reach: variant.reach().x, origin, side, half_offset, levels, ..*params };
        let n = frame.pixels();
        Self {
            ctx,
            frame,
            light,
            pipeline: pipeline(ctx, variant.name(), &BS_TEST),
            uniform: ctx.uniform("shadow test", &params),
            accumulator: ctx.zeroed::<u32>("accumulator", n),
            lit: ctx.zeroed::<f32>("lit", n),
            counters: counters_buffer(ctx),
        }
    }

    /// One pass against `packed`, as the stage `stage`.
    fn pass(&self, packed: &wgpu::Buffer, stage: &str, rec: &mut Recorder) -> Result<(), GpuError> {
        let f = self.frame;
        let bind = self.ctx.bind(
            &self.pipeline,
            &[
                &self.uniform,
                self.light,
                &f.triangle,
                &f.position,
                &f.normal,
                packed,
                &self.accumulator,
                &self.lit,
                &self.counters,
            ],
        );
        self.ctx.stage(rec, stage, |e| {
            let groups = GpuContext::groups_1d(f.pixels(), WORKGROUP);
            GpuContext::dispatch(e, &self.pipeline, &bind, groups)
        })
    }

    /// The lit values and counters after the last pass.
    fn finish(self) -> Result<(Vec<f32>, Counters), GpuError> {
        let mut out: Vec<f32> = self.ctx.read(&self.lit)?;
        out.truncate(self.frame.pixels());
        Ok((out, read_counters(self.ctx, &self.counters)?))
    }
}

/// The uniform parameters of the Brabec and Seidel kernels.
fn bs_params(
    frame: &GpuFrame,
    map: &GpuDepthMap,
    tester: &DepthTester,
    code: &GpuDepthCode,
) -> Params {
    Params {
        code_near: code.near,
        code_span: code.span,
        code_max: code.max_code,
        ..Params::new(frame, map, tester)
    }
}

/// Runs a map kernel over `n` elements as the stage `stage`.
fn map_kernel(
    ctx: &GpuContext,
    (label, kernel): (&str, &Part),
    buffers: &[&wgpu::Buffer],
    n: usize,
    stage: &str,
    rec: &mut Recorder,
) -> Result<(), GpuError> {
    let p = map_pipeline(ctx, label, kernel);
    let bind = ctx.bind(&p, buffers);
    ctx.stage(rec, stage, |e| {
        GpuContext::dispatch(e, &p, &bind, GpuContext::groups_1d(n, WORKGROUP))
    })
}

/// `pcf-bs-2x2` after its four jittered maps (in [`JITTERS`] order): the stages
/// `texel packing` and `depth test` on the GPU, as [`crate::pcf_bs::pack_stratified`] and the
/// twin's shadow test.
pub fn bs_stratified(
    ctx: &GpuContext,
    frame: &GpuFrame,
    maps: [&GpuDepthMap; 4],
    tester: &DepthTester,
    code: &GpuDepthCode,
    rec: &mut Recorder,
) -> Result<(Vec<f32>, Counters), GpuError> {
    let res = maps[0].res;
    let texels = res as usize * res as usize;
    let params = Params { side: res, ..bs_params(frame, maps[0], tester, code) };
    let uniform = ctx.uniform("texel packing", &params);
    let packed = ctx.zeroed::<[u32; 4]>("packed", texels);
    let buffers =
        [&uniform, &maps[0].depth, &maps[1].depth, &maps[2].depth, &maps[3].depth, &packed];
    map_kernel(ctx, ("texel packing", &BS_PACK), &buffers, texels, "texel packing", rec)?;
    let test = ShadowTest::new(ctx, frame, &maps[0].light, Variant::Stratified2x2, &params);
    test.pass(&packed, "depth test", rec)?;
    test.finish()
}

/// `pcf-bs-fast-2x2` or `pcf-bs-fast-4x4` after its map: the stages `depth encoding`, then
/// `texel packing` and `depth test` (once, or `texel packing (pass k)` and `depth test (pass
/// k)` for the four quadrants of the 4x4 region) on the GPU, as
/// [`crate::pcf_bs::encode_map`], [`crate::pcf_bs::pack_neighbourhood`] and the twin's shadow
/// test. `pcf-bs-2x2` needs four maps: [`bs_stratified`].
pub fn bs_fast(
    ctx: &GpuContext,
    frame: &GpuFrame,
    map: &GpuDepthMap,
    tester: &DepthTester,
    code: &GpuDepthCode,
    variant: Variant,
    rec: &mut Recorder,
) -> Result<(Vec<f32>, Counters), MethodError> {
    let passes: &[(i64, i64)] = match variant {
        Variant::Stratified2x2 => {
            return Err(MethodError::NotApplicable(
                "pcf-bs-2x2 packs four jittered maps, not the neighbourhood of one".into(),
            ))
        }
        Variant::Fast2x2 => &[(0, 0)],
        Variant::Fast4x4 => &QUADRANTS,
    };
    let res = map.res;
    let texels = res as usize * res as usize;
    let params = bs_params(frame, map, tester, code);
    let uniform = ctx.uniform("depth encoding", &params);
    let codes = ctx.zeroed::<u32>("codes", texels);
    map_kernel(
        ctx,
        ("depth encoding", &BS_ENCODE),
        &[&uniform, &map.depth, &codes],
        texels,
        "depth encoding",
        rec,
    )?;
    let side = res + 1;
    let packed_texels = side as usize * side as usize;
    let packed = ctx.zeroed::<[u32; 4]>("packed", packed_texels);
    let test = ShadowTest::new(ctx, frame, &map.light, variant, &params);
    for (pass, &(ox, oy)) in passes.iter().enumerate() {
        let (packing, testing) = if passes.len() == 1 {
            ("texel packing".to_owned(), "depth test".to_owned())
        } else {
            (
                format!("texel packing (pass {})", pass + 1),
                format!("depth test (pass {})", pass + 1),
            )
        };
        let pack_params = Params { side, offset_x: ox as i32, offset_y: oy as i32, ..params };
        let pack_uniform = ctx.uniform("texel packing", &pack_params);
        map_kernel(
            ctx,
            ("texel packing", &BS_PACK_FAST),
            &[&pack_uniform, &codes, &packed],
            packed_texels,
            &packing,
            rec,
        )?;
        test.pass(&packed, &testing, rec)?;
    }
    Ok(test.finish()?)
}

/// A percentage-closer filtering method on the GPU, built from the same options as its CPU
/// twin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GpuPcf {
    /// `pcf-reeves`, the twin of [`ReevesPcf`].
    Reeves {
        /// Options, as the twin's.
        options: ReevesOptions,
    },
    /// `pcf-bs-2x2`, `pcf-bs-fast-2x2` or `pcf-bs-fast-4x4`, the twin of [`BrabecSeidelPcf`].
    BrabecSeidel {
        /// Options, as the twin's.
        options: BsOptions,
        /// Which method.
        variant: Variant,
    },
    /// `pcf-gems16` or `pcf-gems4`, the twin of [`GemsPcf`].
    Gems {
        /// Options, as the twin's.
        options: MapOptions,
        /// 16 lookups or 4 dithered ones.
        samples: GemsSamples,
    },
}

impl GpuPcf {
    /// The CPU twin.
    fn twin(&self) -> Box<dyn ShadowMethod> {
        match *self {
            GpuPcf::Reeves { options } => Box::new(ReevesPcf { options }),
            GpuPcf::BrabecSeidel { options, variant } => {
                Box::new(BrabecSeidelPcf { options, variant })
            }
            GpuPcf::Gems { options, samples } => Box::new(GemsPcf { options, samples }),
        }
    }

    /// How the method decides a pixel: Reeves et al.'s filter samples its footprint, the
    /// others a fixed region of texels around its centre.
    fn sampling(&self) -> Sampling {
        match self {
            GpuPcf::Reeves { .. } => Sampling::PixelArea,
            GpuPcf::BrabecSeidel { .. } | GpuPcf::Gems { .. } => Sampling::PixelCentre,
        }
    }

    /// The map options.
    fn map_options(&self) -> &MapOptions {
        match self {
            GpuPcf::Reeves { options } => &options.map,
            GpuPcf::BrabecSeidel { options, .. } => &options.map,
            GpuPcf::Gems { options, .. } => options,
        }
    }
}

impl ShadowMethod for GpuPcf {
    fn name(&self) -> &'static str {
        self.twin().name()
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        super::twin_params(&*self.twin())
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        match self {
            GpuPcf::Reeves { options } => options.validate()?,
            GpuPcf::BrabecSeidel { options, .. } => options.validate()?,
            GpuPcf::Gems { options, .. } => options.validate()?,
        }
        if frame.effects.transparency {
            rec.notes.push(format!("{} treats semi-transparent casters as opaque", self.name()));
        }
        let ctx = GpuContext::shared()?;
        ctx.describe(rec);
        let gframe = GpuFrame::for_run(ctx, frame, rec)?;
        let o = *self.map_options();
        let plain_map = |rec: &mut Recorder| {
            let (res, fit) = (o.map_res, o.frustum);
            GpuDepthMap::for_run(ctx, frame, res, fit, DVec2::ZERO, STAGE_LIGHT_DEPTH_MAP, rec)
        };
        let projector = frame.light_projector(o.map_res, o.frustum);
        let tester = DepthTester::new(&o, projector, frame.light_depth_range(&projector));
        rec.warnings.extend(tester.warnings(self.name(), frame, self.sampling()));
        let (lit, counters) = match *self {
            GpuPcf::Reeves { options } => {
                let map = plain_map(rec)?;
                reeves(ctx, &gframe, &map, &tester, &options, rec)?
            }
            GpuPcf::Gems { samples, .. } => {
                let map = plain_map(rec)?;
                gems(ctx, &gframe, &map, &tester, samples, rec)?
            }
            GpuPcf::BrabecSeidel { options, variant } => {
                let (near, far) = frame.light_depth_bounds(&projector);
                let code = GpuDepthCode::new(options.depth_bits, near, far)?;
                if variant == Variant::Stratified2x2 {
                    let mut maps = Vec::with_capacity(4);
                    for (j, &shift) in JITTERS.iter().enumerate() {
                        let stage = format!("light depth map (jitter {})", j + 1);
                        maps.push(GpuDepthMap::for_run(
                            ctx, frame, o.map_res, o.frustum, shift, &stage, rec,
                        )?);
                    }
                    let maps = [&maps[0], &maps[1], &maps[2], &maps[3]];
                    bs_stratified(ctx, &gframe, maps, &tester, &code, rec)?
                } else {
                    let map = plain_map(rec)?;
                    bs_fast(ctx, &gframe, &map, &tester, &code, variant, rec)?
                }
            }
        };
        rec.counters.merge(&counters);
        Ok(Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pcf_reeves::jitter;

    /// The GPU's SplitMix64 on `u32` pairs gives the CPU's jitter bit for bit, over seeds
    /// with both words set, large pixel indices and both axes.
    #[test]
    fn jitter_on_u32_pairs_equals_the_cpu_hash() {
        let ctx = GpuContext::shared().expect("a GPU adapter (install Mesa's Vulkan driver)");
        let probe = r#"
@group(0) @binding(0) var<storage, read> input: array<u32>;
@group(0) @binding(1) var<storage, read_write> output: array<f64>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i < arrayLength(&output) {
        let a = input[5u * i];
        output[i] = jitter(vec2<u32>(a, input[5u * i + 1u]), input[5u * i + 2u],
            input[5u * i + 3u], input[5u * i + 4u]);
    }
}
"#;
        let cases: Vec<(u64, u32, u32, u32)> = (0..4096u32)
            .map(|i| {
                let seed = [0, 7, u64::MAX, 0x1234_5678_9abc_def0][(i % 4) as usize];
                let pixel = i.wrapping_mul(2_654_435_761);
                (seed, pixel, i % 1024, (i / 1024) % 2)
            })
            .collect();
        let input: Vec<u32> = cases
            .iter()
            .flat_map(|&(seed, pixel, s, axis)| [seed as u32, (seed >> 32) as u32, pixel, s, axis])
            .collect();
        let p = ctx.pipeline(
            "jitter probe",
            &format!("{}{probe}", crate::gpu::shader::compose(&[&JITTER])),
            "main",
        );
        let input = ctx.upload("input", &input);
        let output = ctx.zeroed::<f64>("output", cases.len());
        let bind = ctx.bind(&p, &[&input, &output]);
        let mut rec = Recorder::default();
        ctx.stage(&mut rec, "jitter", |e| {
            GpuContext::dispatch(e, &p, &bind, GpuContext::groups_1d(cases.len(), 64))
        })
        .expect("probe runs");
        let got: Vec<f64> = ctx.read(&output).expect("read back");
        for (&(seed, pixel, s, axis), g) in cases.iter().zip(&got) {
            let want = jitter(seed, u64::from(pixel), s, axis);
            assert_eq!(g.to_bits(), want.to_bits(), "{seed} {pixel} {s} {axis}: {g} vs {want}");
        }
    }
}
