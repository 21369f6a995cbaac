//! `sm` on the GPU: the standard shadow map's depth test (Williams 1978; the CPU twin is
//! [`crate::sm::StandardShadowMap`]) as one compute kernel, one thread per G-buffer pixel.
//!
//! Each thread builds the pixel's receiver as [`DepthTester::receiver`] does (the light
//! projection of `common.wgsl`, [`crate::depth_test::depth_slope`] in `receiver.wgsl`), finds
//! its texel as [`crate::depth_test::texel_at`] and compares once as [`crate::sm::depth_test`],
//! all in `f64` with the CPU's operations in the CPU's order, so the result equals the twin's
//! pixel for pixel. The tolerance's constant part (`constant_bias * depth_range`) is computed on
//! the CPU, as the twin computes it once per run.
//!
//! Stages: `light depth map` ([`GpuDepthMap::for_run`]) and `depth test` (the kernel), as the
//! twin's. Counter `shadow_map_lookups`: one per pixel whose point falls in the map, summed
//! per workgroup and added into a 64-bit total (two `u32` words) on the GPU.
//!
//! The WGSL shared with the percentage-closer filtering kernels ([`super::pcf`]) is
//! [`RECEIVER`] (receiver, texel lookup, depth codes) and [`COUNTERS`].

use super::{
    common::COMMON,
    shader::{compose, Part},
    GpuContext, GpuDepthMap, GpuError, GpuFrame,
};
use crate::{
    depth_test::{DepthTester, MapOptions},
    footprint::Sampling,
    frame::{Frame, STAGE_LIGHT_DEPTH_MAP},
    method::{MethodError, ShadowMethod, Visibility},
    sm::{StandardShadowMap, NEAREST_REACH, STAGE_DEPTH_TEST},
};
use bytemuck::{Pod, Zeroable};
use instrumentation::{Counters, Recorder};

/// WGSL of the receiver, the nearest-texel lookup and the depth codes.
pub(super) const RECEIVER: Part =
    Part { name: "receiver.wgsl", source: include_str!("receiver.wgsl"), needs: &[&COMMON] };

/// WGSL of the workgroup-summed 64-bit counters (`count(local, lookups, bilinear)`).
pub(super) const COUNTERS: Part = Part::file("counters.wgsl", include_str!("counters.wgsl"));

/// WGSL of the per-pixel kernels' first bindings (0 to 4: parameters, light, G-buffer) and
/// their receiver, shared by `sm` and the PCF filters.
pub(super) const PIXEL: Part =
    Part { name: "pixel.wgsl", source: include_str!("pixel.wgsl"), needs: &[&RECEIVER] };

const SM: Part = Part::file("sm.wgsl", include_str!("sm.wgsl"));

/// Threads per workgroup of the per-pixel kernels (`counters.wgsl` sums over one workgroup).
pub(super) const WORKGROUP: u32 = 64;

/// The kernels' uniform parameters; the WGSL `Params` of `receiver.wgsl`, field for field
/// ([`super::layout`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, Pod, Zeroable)]
pub(super) struct Params {
    pub constant: f64,
    pub slope_bias: f64,
    pub max_slope: f64,
    pub reach: f64,
    pub code_near: f64,
    pub code_span: f64,
    pub code_max: f64,
    pub pad0: f64,
    pub width: u32,
    pub pixels: u32,
    pub res: u32,
    pub samples: u32,
    pub grid_x: u32,
    pub grid_y: u32,
    pub seed_lo: u32,
    pub seed_hi: u32,
    pub offset_x: i32,
    pub offset_y: i32,
    pub origin: i32,
    pub side: u32,
    pub half_offset: u32,
    pub levels: u32,
    pub dithered: u32,
    pub pad1: u32,
}

super::layout::wgsl_mirror!(
    Params,
    "Params",
    compose(&[&RECEIVER]),
    [
        constant,
        slope_bias,
        max_slope,
        reach,
        code_near,
        code_span,
        code_max,
        pad0,
        width,
        pixels,
        res,
        samples,
        grid_x,
        grid_y,
        seed_lo,
        seed_hi,
        offset_x,
        offset_y,
        origin,
        side,
        half_offset,
        levels,
        dithered,
        pad1
    ]
);

impl Params {
    /// The parameters every per-pixel kernel shares: the tester's bias, the frame's size and
    /// the map's resolution.
    pub(super) fn new(frame: &GpuFrame, map: &GpuDepthMap, tester: &DepthTester) -> Self {
        Self {
            constant: tester.constant,
            slope_bias: tester.slope_bias,
            max_slope: tester.max_slope,
            width: frame.width,
            pixels: frame.width * frame.height,
            res: map.res,
            ..Default::default()
        }
    }
}

/// A compute pipeline of the per-pixel kernel `kernel` after the shared prologue
/// (`pixel.wgsl`) and the counters.
pub(super) fn pipeline(ctx: &GpuContext, label: &str, kernel: &Part) -> wgpu::ComputePipeline {
    ctx.pipeline(label, &compose(&[&PIXEL, &COUNTERS, kernel]), "main")
}

/// A compute pipeline of the map kernel `kernel` (no counters) after the shared WGSL.
pub(super) fn map_pipeline(ctx: &GpuContext, label: &str, kernel: &Part) -> wgpu::ComputePipeline {
    ctx.pipeline(label, &compose(&[&RECEIVER, kernel]), "main")
}

/// The counters buffer the kernels add into: two 64-bit totals as `u32` words.
pub(super) fn counters_buffer(ctx: &GpuContext) -> wgpu::Buffer {
    ctx.zeroed::<u32>("counters", 4)
}

/// Reads the kernels' counters back.
pub(super) fn read_counters(ctx: &GpuContext, buf: &wgpu::Buffer) -> Result<Counters, GpuError> {
    let w: Vec<u32> = ctx.read(buf)?;
    let word = |i: usize| u64::from(w[i]) | u64::from(w[i + 1]) << 32;
    Ok(Counters { shadow_map_lookups: word(0), bilinear_lookups: word(2), ..Default::default() })
}

/// The stage [`STAGE_DEPTH_TEST`] on the GPU: the standard depth test of every pixel of
/// `frame` against `map`, with the bias of `tester` (made for `map`'s projector). Returns the
/// lit values (1 or 0) and the counters.
pub fn depth_test(
    ctx: &GpuContext,
    frame: &GpuFrame,
    map: &GpuDepthMap,
    tester: &DepthTester,
    rec: &mut Recorder,
) -> Result<(Vec<f32>, Counters), GpuError> {
    debug_assert_eq!(NEAREST_REACH.x, NEAREST_REACH.y);
    let params = Params { reach: NEAREST_REACH.x, ..Params::new(frame, map, tester) };
    let buffers = [&map.light, &frame.triangle, &frame.position, &frame.normal, &map.depth];
    per_pixel(ctx, frame, ("sm depth test", &[&SM]), &params, &buffers, STAGE_DEPTH_TEST, rec)
}

/// Runs a per-pixel kernel (the parts `kernel`, after `pixel.wgsl` and `counters.wgsl`) over
/// `frame` with `buffers` bound after the uniform `params`, as the stage `stage`; returns the
/// lit values and the counters. The kernel's last two bindings are the lit values and the
/// counters, which this makes. `sm`, the percentage-closer filters and the filtered maps'
/// tests run this way.
pub(super) fn per_pixel(
    ctx: &GpuContext,
    frame: &GpuFrame,
    (label, kernel): (&str, &[&Part]),
    params: &Params,
    buffers: &[&wgpu::Buffer],
    stage: &str,
    rec: &mut Recorder,
) -> Result<(Vec<f32>, Counters), GpuError> {
    let n = frame.pixels();
    let mut parts = vec![&PIXEL, &COUNTERS];
    parts.extend_from_slice(kernel);
    let p = ctx.pipeline(label, &compose(&parts), "main");
    let uniform = ctx.uniform(label, params);
    let lit = ctx.zeroed::<f32>("lit", n);
    let counters = counters_buffer(ctx);
    let mut all = vec![&uniform];
    all.extend_from_slice(buffers);
    all.extend([&lit, &counters]);
    let bind = ctx.bind(&p, &all);
    ctx.stage(rec, stage, |e| {
        GpuContext::dispatch(e, &p, &bind, GpuContext::groups_1d(n, WORKGROUP))
    })?;
    let mut out: Vec<f32> = ctx.read(&lit)?;
    out.truncate(n);
    Ok((out, read_counters(ctx, &counters)?))
}

/// The standard shadow map on the GPU; the twin of [`StandardShadowMap`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GpuShadowMap {
    /// Options, as the twin's.
    pub options: MapOptions,
}

impl ShadowMethod for GpuShadowMap {
    fn name(&self) -> &'static str {
        "sm"
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        super::twin_params(&StandardShadowMap { options: self.options })
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        self.options.validate()?;
        if frame.effects.transparency {
            rec.notes.push("sm treats semi-transparent casters as opaque".into());
        }
        let ctx = GpuContext::shared()?;
        ctx.describe(rec);
        let gframe = GpuFrame::for_run(ctx, frame, rec)?;
        let map = GpuDepthMap::for_run(
            ctx,
            frame,
            self.options.map_res,
            self.options.frustum,
            glam::DVec2::ZERO,
            STAGE_LIGHT_DEPTH_MAP,
            rec,
        )?;
        let tester =
            DepthTester::new(&self.options, map.projector, frame.light_depth_range(&map.projector));
        rec.warnings.extend(tester.warnings(self.name(), frame, Sampling::PixelCentre));
        let (lit, counters) = depth_test(ctx, &gframe, &map, &tester, rec)?;
        rec.counters.merge(&counters);
        Ok(Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None })
    }
}
