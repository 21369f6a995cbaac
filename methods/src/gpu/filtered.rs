//! The filtered shadow maps on the GPU (variance, exponential and moment shadow maps, the
//! registry's `FilteredMap` methods): [`GpuFilteredMap`], the twin of any
//! [`FilteredMap`], with the stages of [`crate::filtered_map::run`] as compute kernels.
//!
//! - **light depth map**: [`GpuDepthMap::for_run`], as every GPU shadow map;
//! - **stored values, filtered** (the method's first stage, [`store_and_filter`]): one thread
//!   per texel normalises its depth and runs the method's `store` (its WGSL,
//!   [`FilteredMap::wgsl`]), which rounds the values to the storage precision with
//!   `filtered.wgsl`'s `quantize`; then two passes of the separable box filter (rows, then
//!   columns; none for a one-texel filter), each summing its texels in the CPU's order in
//!   `f64`, all in one submission timed as one stage;
//! - **test** (its second stage, [`fn@test`]): one thread per pixel builds the receiver as
//!   [`crate::gpu::sm`] does, finds its texel, normalises its depth after the bias tolerance
//!   with the filter's reach, and runs the method's `test`, written as
//!   [`crate::filtered_map::lit_value`] writes it. Counter `shadow_map_lookups`, one per
//!   pixel whose point falls in the map, as the twin counts.
//!
//! Every value is computed with the twin's operations in the twin's order in `f64` (see
//! [`super`] on precision), so a kernel given the twin's depth map and G-buffer gives the
//! twin's stored values, filtered values and lit values bit for bit. Two things the CPU gets
//! from its libraries are built from exact operations instead: the rounding to `f32`, `f16` and
//! 16-bit unsigned normalized values (`filtered.wgsl`: the binade found by halving or doubling,
//! the steps counted and rounded to nearest, ties to even, each operation exact, which is
//! Rust's `as f32` and [`crate::filtered_map::f16_bits`] by construction; WGSL's own conversion
//! to `f32` rounds as the implementation likes), and the exponential of `esm` (WGSL has none in
//! `f64`: `esm` computes its own, from basic operations, on both paths).
//!
//! One freedom of the GPU's compiler remains: WGSL lets it fuse a multiply and an add into
//! one rounding (naga has no way to forbid it, and llvmpipe does so in some expressions). Where
//! a computation cancels badly enough, that shows in the written `f32`: `msm` without a moment
//! bias, whose Hankel matrix is singular at a texel of one depth, differs from its twin in the
//! last bit of one pixel of the parity scenes; every configuration with the default biases
//! agrees bit for bit (`tests/gpu/filtered.rs`).

use super::{
    common::COMMON,
    shader::{compose, Part},
    sm::{per_pixel, Params, RECEIVER, WORKGROUP},
    GpuContext, GpuDepthMap, GpuError, GpuFrame,
};
use crate::{
    depth_test::DepthTester,
    filtered_map::{filter_reach, FilteredMap},
    footprint::Sampling,
    frame::{Frame, STAGE_LIGHT_DEPTH_MAP},
    method::{MethodError, ShadowMethod, Visibility},
};
use bytemuck::{Pod, Zeroable};
use instrumentation::{Counters, Recorder};

/// WGSL of the kernels' parameters, the rounding to a precision, the bleeding reduction and
/// the lit value.
const FILTERED: Part =
    Part { name: "filtered.wgsl", source: include_str!("filtered.wgsl"), needs: &[&RECEIVER] };
const STORE: Part = Part::file("filtered_store.wgsl", include_str!("filtered_store.wgsl"));
const BLUR: Part = Part::file("filtered_blur.wgsl", include_str!("filtered_blur.wgsl"));
const TEST: Part = Part::file("filtered_test.wgsl", include_str!("filtered_test.wgsl"));

/// The filtered maps' uniform parameters; the WGSL `FParams` of `filtered.wgsl`, field for
/// field ([`super::layout`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, Pod, Zeroable)]
struct FParams {
    near: f64,
    range: f64,
    weight: f64,
    pad0: f64,
    p0: f64,
    p1: f64,
    p2: f64,
    p3: f64,
    texels: u32,
    res: u32,
    n: u32,
    half: u32,
    precision_code: u32,
    along_rows: u32,
    pad1: u32,
    pad2: u32,
}

super::layout::wgsl_mirror!(
    FParams,
    "FParams",
    format!(
        "{}@group(0) @binding(0) var<uniform> fparams: FParams;",
        compose(&[&COMMON, &FILTERED])
    ),
    [
        near,
        range,
        weight,
        pad0,
        p0,
        p1,
        p2,
        p3,
        texels,
        res,
        n,
        half,
        precision_code,
        along_rows,
        pad1,
        pad2
    ]
);

impl FParams {
    /// The parameters of `m`'s kernels over `map`, whose scene's nearest light depth is `near`
    /// and light depth range `range`.
    fn new<const N: usize, M: FilteredMap<N>>(
        m: &M,
        map: &GpuDepthMap,
        near: f64,
        range: f64,
    ) -> Self {
        let [p0, p1, p2, p3] = m.wgsl_params();
        Self {
            near,
            range,
            weight: 1.0 / f64::from(m.filter()),
            p0,
            p1,
            p2,
            p3,
            texels: map.res * map.res,
            res: map.res,
            n: N as u32,
            half: m.filter() / 2,
            precision_code: m.precision().code(),
            ..Default::default()
        }
    }
}

/// The method's WGSL (its `store` and `test`) as a part after `filtered.wgsl`.
fn method_part<const N: usize, M: FilteredMap<N>>(m: &M) -> Part {
    Part { name: "method.wgsl", source: m.wgsl(), needs: &[&FILTERED] }
}

/// A map's filtered values on the GPU, `N` `f64` per texel.
#[derive(Debug)]
pub struct FilteredValues {
    /// The values, texel by texel (row by row), `N` each.
    pub values: wgpu::Buffer,
}

impl FilteredValues {
    /// Reads the values back, `N` per texel.
    pub fn read<const N: usize>(&self, ctx: &GpuContext) -> Result<Vec<[f64; N]>, GpuError> {
        let flat: Vec<f64> = ctx.read(&self.values)?;
        Ok(flat.chunks_exact(N).map(|c| std::array::from_fn(|i| c[i])).collect())
    }
}

/// The method's first stage on the GPU: the stored values of `map` (scene's nearest light
/// depth `near`, depth range `range`), filtered, as [`crate::filtered_map::filtered_values`].
pub fn store_and_filter<const N: usize, M: FilteredMap<N>>(
    ctx: &GpuContext,
    map: &GpuDepthMap,
    near: f64,
    range: f64,
    m: &M,
    rec: &mut Recorder,
) -> Result<FilteredValues, GpuError> {
    let params = FParams::new(m, map, near, range);
    let texels = params.texels as usize;
    let method = method_part(m);
    let store = ctx.pipeline("filtered store", &compose(&[&COMMON, &method, &STORE]), "main");
    let blur = ctx.pipeline("filtered blur", &compose(&[&COMMON, &method, &BLUR]), "main");
    let rows = ctx.uniform("filtered rows", &FParams { along_rows: 1, ..params });
    let columns = ctx.uniform("filtered columns", &params);
    let stored = ctx.zeroed::<f64>("stored values", texels * N);
    let filtered = m.filter() > 1;
    let (across, done) = if filtered {
        (ctx.zeroed::<f64>("filtered rows", texels * N), ctx.zeroed::<f64>("filtered", texels * N))
    } else {
        (ctx.zeroed::<f64>("unused", 1), ctx.zeroed::<f64>("unused", 1))
    };
    let store_bind = ctx.bind(&store, &[&rows, &map.depth, &stored]);
    let rows_bind = ctx.bind(&blur, &[&rows, &stored, &across]);
    let columns_bind = ctx.bind(&blur, &[&columns, &across, &done]);
    let groups = GpuContext::groups_1d(texels, WORKGROUP);
    let [stage, _] = m.stages();
    ctx.stage(rec, stage, |e| {
        GpuContext::dispatch(e, &store, &store_bind, groups);
        if filtered {
            GpuContext::dispatch(e, &blur, &rows_bind, groups);
            GpuContext::dispatch(e, &blur, &columns_bind, groups);
        }
    })?;
    Ok(FilteredValues { values: if filtered { done } else { stored } })
}

/// The method's second stage on the GPU: the test of every pixel of `frame` against the
/// filtered values of `map`, with the bias of `tester` (made for `map`'s projector), as
/// [`crate::filtered_map::run`]'s. Returns the lit values and the counters.
#[allow(clippy::too_many_arguments)]
pub fn test<const N: usize, M: FilteredMap<N>>(
    ctx: &GpuContext,
    frame: &GpuFrame,
    map: &GpuDepthMap,
    tester: &DepthTester,
    (near, range): (f64, f64),
    filtered: &FilteredValues,
    m: &M,
    rec: &mut Recorder,
) -> Result<(Vec<f32>, Counters), GpuError> {
    let reach = filter_reach(m.filter());
    debug_assert_eq!(reach.x, reach.y);
    let params = Params { reach: reach.x, ..Params::new(frame, map, tester) };
    let fparams = FParams::new(m, map, near, range);
    let funiform = ctx.uniform("filtered params", &fparams);
    let method = method_part(m);
    let buffers =
        [&map.light, &frame.triangle, &frame.position, &frame.normal, &funiform, &filtered.values];
    let [_, stage] = m.stages();
    per_pixel(ctx, frame, ("filtered test", &[&method, &TEST]), &params, &buffers, stage, rec)
}

/// A filtered shadow map on the GPU: the twin `twin`'s stages as kernels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpuFilteredMap<const N: usize, M> {
    /// The CPU method whose options, values and test the kernels reproduce.
    pub twin: M,
}

impl<const N: usize, M: FilteredMap<N>> ShadowMethod for GpuFilteredMap<N, M> {
    fn name(&self) -> &'static str {
        self.twin.name()
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        super::twin_params(&self.twin)
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        let m = &self.twin;
        m.validate()?;
        if frame.effects.transparency {
            rec.notes.push(format!("{} treats semi-transparent casters as opaque", m.name()));
        }
        rec.warnings.extend(m.warning());
        let ctx = GpuContext::shared()?;
        ctx.describe(rec);
        let gframe = GpuFrame::for_run(ctx, frame, rec)?;
        let o = m.map();
        let map = GpuDepthMap::for_run(
            ctx,
            frame,
            o.map_res,
            o.frustum,
            glam::DVec2::ZERO,
            STAGE_LIGHT_DEPTH_MAP,
            rec,
        )?;
        let (near, _) = frame.light_depth_bounds(&map.projector);
        let range = frame.light_depth_range(&map.projector);
        let filtered = store_and_filter(ctx, &map, near, range, m, rec)?;
        let tester = DepthTester::new(o, map.projector, range);
        rec.warnings.extend(tester.warnings(m.name(), frame, Sampling::PixelCentre));
        let (lit, counters) = test(ctx, &gframe, &map, &tester, (near, range), &filtered, m, rec)?;
        rec.counters.merge(&counters);
        Ok(Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None })
    }
}

/// Runs `probe(x: f64) -> f64`, defined in `wgsl` after `filtered.wgsl` (with `fparams`'
/// `precision_code` set to `precision`), on every value of `inputs`; returns its results.
#[cfg(test)]
pub(crate) fn probe(
    ctx: &GpuContext,
    wgsl: &str,
    precision: u32,
    inputs: &[f64],
) -> Result<Vec<f64>, GpuError> {
    let main = r#"
@group(0) @binding(0) var<uniform> fparams: FParams;
@group(0) @binding(1) var<storage, read> input: array<f64>;
@group(0) @binding(2) var<storage, read_write> output: array<f64>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = flat_index(gid, groups);
    if i < fparams.texels {
        output[i] = probe(input[i]);
    }
}
"#;
    let source = format!("{}{wgsl}\n{main}", compose(&[&COMMON, &FILTERED]));
    let p = ctx.pipeline("probe", &source, "main");
    let params =
        FParams { texels: inputs.len() as u32, precision_code: precision, ..Default::default() };
    let uniform = ctx.uniform("probe params", &params);
    let input = ctx.upload("input", inputs);
    let output = ctx.zeroed::<f64>("output", inputs.len());
    let bind = ctx.bind(&p, &[&uniform, &input, &output]);
    ctx.stage(&mut Recorder::default(), "probe", |e| {
        GpuContext::dispatch(e, &p, &bind, GpuContext::groups_1d(inputs.len(), WORKGROUP))
    })?;
    let mut out: Vec<f64> = ctx.read(&output)?;
    out.truncate(inputs.len());
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filtered_map::{f16_value, lit_value, reduce_bleeding, Precision};

    /// Values that exercise the rounding: every half and its neighbourhood, ties between
    /// neighbouring halves and their neighbours, f32 ties, subnormal ranges, and a sweep of
    /// [0, 1] in small irregular steps.
    fn hard_values() -> Vec<f64> {
        let mut v = vec![0.0, 1.0, 0.5, 2.0f64.powi(-126), 2.0f64.powi(-149), 2.0f64.powi(-150)];
        for h in 0u16..0x3c00 {
            let (lo, hi) = (f16_value(h), f16_value(h + 1));
            let mid = (lo + hi) / 2.0;
            for x in [lo, mid].into_iter().filter(|&x| x > 0.0) {
                let f = x as f32;
                v.extend([x, x * (1.0 + 1e-12), x * (1.0 - 1e-12)]);
                v.extend(
                    [f32::from_bits(f.to_bits() + 1), f32::from_bits(f.to_bits() - 1)]
                        .map(f64::from),
                );
            }
        }
        for k in 1..20_000u32 {
            let x = f64::from(k) / 20_000.0;
            // An f32 tie: halfway between two neighbouring singles.
            let f = x as f32;
            let next = f32::from_bits(f.to_bits() + 1);
            v.extend([x * 0.999_999_7, (f64::from(f) + f64::from(next)) / 2.0]);
            v.push(f64::from(k) / 65535.0 * (1.0 + 1e-13) - 0.5 / 65535.0);
        }
        v.retain(|x| (0.0..=1.0).contains(x));
        v
    }

    /// The kernels' rounding to each precision, written value and bleeding reduction are the
    /// CPU's, bit for bit, over values chosen to hit every tie.
    #[test]
    fn rounding_equals_the_cpu_bit_for_bit() {
        let ctx = GpuContext::shared().expect("a GPU adapter (scripts/install-gpu-driver)");
        let values = hard_values();
        for p in Precision::ALL {
            let got =
                probe(ctx, "fn probe(x: f64) -> f64 { return quantize(x); }", p.code(), &values)
                    .expect("probe runs");
            for (x, g) in values.iter().zip(&got) {
                let want = p.round(*x);
                assert_eq!(g.to_bits(), want.to_bits(), "{} of {x:e}: {g:e} vs {want:e}", p.name());
            }
        }
        let wgsl = "fn probe(x: f64) -> f64 { return f64(lit_value(x)); }";
        let got = probe(ctx, wgsl, 0, &values).expect("probe runs");
        for (x, g) in values.iter().zip(&got) {
            assert_eq!(g.to_bits(), f64::from(lit_value(*x)).to_bits(), "lit of {x:e}");
        }
        let wgsl = "fn probe(x: f64) -> f64 { return reduce_bleeding(x, 0.3lf); }";
        let got = probe(ctx, wgsl, 0, &values).expect("probe runs");
        for (x, g) in values.iter().zip(&got) {
            assert_eq!(g.to_bits(), reduce_bleeding(*x, 0.3).to_bits(), "reduced {x:e}");
        }
    }
}
