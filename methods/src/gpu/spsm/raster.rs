//! Stage "conservative rasterization" of `spsm` on the GPU (`raster.wgsl`), equal to
//! [`spsm::raster::rasterize_conservative`] texel for texel.
//!
//! The triangles are prepared on the CPU by the twin's own code ([`spsm::raster::prepare`]:
//! projection, near clipping, orientation, depth plane, texel rectangle; per triangle), and
//! cut into items, one per row of each rectangle. Everything per texel runs on the GPU:
//! `count` (the row's columns as the twin's `strip_columns` gives them, the exact overlap test
//! through `orient2d`'s filter, tests and fragments counted, touching triangles counted per
//! texel), a scan of those counts, `scatter` (each texel's list of touching triangles) and
//! `resolve` (per texel, the triangle of least minimum conservative depth, ties to the lower
//! index, as the twin's in-order `<`). The (triangle, texel) pairs the filter cannot decide
//! are listed and decided on the CPU by `TriSetup::touches` itself, then merged into the map
//! by the same rule; the run record's note says how many.

use crate::{
    gpu::{
        scan::Scan,
        shader::{compose, Part},
        GpuContext, GpuError,
    },
    spsm::raster::{prepare, ConservativeMap, TriSetup},
    spsm::texel::LightSpace,
};
use bytemuck::{Pod, Zeroable};
use instrumentation::Recorder;
use scenes::{Geometry, Projector};

/// WGSL of a prepared triangle as the kernels read it.
pub(super) const SETUP: Part = Part::file("spsm/setup.wgsl", include_str!("setup.wgsl"));
const RASTER: Part =
    Part { name: "spsm/raster.wgsl", source: include_str!("raster.wgsl"), needs: &[&SETUP] };

/// A prepared triangle ([`TriSetup`]) as the kernels read it, the WGSL `SetupData` of
/// `setup.wgsl`: the vertices (`x, y`), their depths, the depth gradient, the least and
/// largest vertex depth.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(super) struct SetupData {
    v: [f64; 6],
    z: [f64; 3],
    dz: [f64; 2],
    z_min: f64,
    z_max: f64,
}

/// The kernels' sizes, the WGSL `Dims` of `raster.wgsl`: the map's resolution, the items,
/// and the capacity of the list of undecided pairs.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct Dims {
    res: u32,
    items: u32,
    capacity: u32,
}

crate::gpu::layout::wgsl_mirror!(
    SetupData,
    "SetupData",
    compose(&[&SETUP]),
    [v, z, dz, z_min, z_max];
    Dims,
    "Dims",
    compose(&[&RASTER]),
    [res, items, capacity];
);

/// The prepared triangles as the kernels read them.
pub(super) fn setup_data(setups: &[TriSetup]) -> Vec<SetupData> {
    setups
        .iter()
        .map(|s| SetupData {
            v: [s.v[0].x, s.v[0].y, s.v[1].x, s.v[1].y, s.v[2].x, s.v[2].y],
            z: s.z,
            dz: s.dz.to_array(),
            z_min: s.z_min,
            z_max: s.z_max,
        })
        .collect()
}

/// What [`rasterize_conservative`] gives beside the map.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RasterCounts {
    /// Texels tested exactly (`raster_samples_tested`).
    pub tested: u64,
    /// Texel-triangle overlaps (`conservative_fragments`).
    pub fragments: u64,
    /// Pairs the GPU's filter could not decide, decided on the CPU.
    pub undecided: u64,
}

/// The conservative map of the triangles `include` selects through `proj` (square, its
/// width the resolution), as the twin's; adds `triangles_rasterized` to `rec`'s counters and
/// records the GPU passes as the stage `stage`.
pub fn rasterize_conservative(
    ctx: &GpuContext,
    geometry: &Geometry,
    include: impl Fn(usize) -> bool + Sync,
    proj: &Projector,
    space: &LightSpace,
    stage: &str,
    rec: &mut Recorder,
) -> Result<(ConservativeMap, RasterCounts), GpuError> {
    let res = proj.width as usize;
    // The CPU's part of the stage (preparing the triangles and cutting the items, then
    // deciding the undecided pairs) is timed into it beside the GPU passes.
    let start = std::time::Instant::now();
    let (setups, bounds) = prepare(geometry, include, proj, space, &mut rec.counters);
    let setup_f = setup_data(&setups);
    let mut cols = Vec::with_capacity(2 * setups.len());
    let mut items: Vec<u32> = Vec::new();
    for (i, b) in bounds.iter().enumerate() {
        let [x0, x1, y0, y1] = b.map_or([1, 0, 1, 0], |b| b.map(|v| v as u32));
        cols.extend_from_slice(&[x0, x1]);
        for y in y0..=y1 {
            items.extend_from_slice(&[i as u32, y]);
        }
    }
    let n_items = items.len() / 2;
    let mut cpu_ms = start.elapsed().as_secs_f64() * 1e3;
    let texels = res * res;
    let source = compose(&[&RASTER]);
    let count = ctx.pipeline("spsm raster count", &source, "count");
    let scatter = ctx.pipeline("spsm raster scatter", &source, "scatter");
    let resolve = ctx.pipeline("spsm raster resolve", &source, "resolve");
    let scan = Scan::new(ctx);
    let setups_buf = ctx.upload("spsm setups", &setup_f);
    let cols_buf = ctx.upload("spsm setup columns", &cols);
    let items_buf = ctx.upload("spsm raster items", &items);
    let texel_count = ctx.zeroed::<u32>("spsm texel counts", texels + 1);
    let cursor = ctx.zeroed::<u32>("spsm texel cursors", texels);
    let out_texel = ctx.zeroed::<u32>("spsm texel triangle", texels);
    let out_depth = ctx.upload("spsm texel depth", &vec![f64::INFINITY; texels]);
    let fragments_total = ctx.zeroed::<u32>("spsm fragments", 1);
    let texel_scan = scan.prepare(ctx, &texel_count, texels + 1, &fragments_total);
    let counters = ctx.zeroed::<u32>("spsm raster counters", 5);
    // The kernels' bindings, in `raster.wgsl`'s order.
    let buffers = |dims: &wgpu::Buffer, list: &wgpu::Buffer, undecided: &wgpu::Buffer| {
        [
            dims.clone(),
            setups_buf.clone(),
            cols_buf.clone(),
            items_buf.clone(),
            texel_count.clone(),
            cursor.clone(),
            list.clone(),
            counters.clone(),
            undecided.clone(),
            out_texel.clone(),
            out_depth.clone(),
        ]
    };
    // Counting, with room for `capacity` undecided pairs; again with room for all of them
    // when they overflow (rare: the filter fails only within rounding of an edge).
    let count_pass = |capacity: usize, rec: &mut Recorder| -> Result<_, GpuError> {
        let dims = ctx.upload(
            "spsm raster dims",
            &[Dims { res: res as u32, items: n_items as u32, capacity: capacity as u32 }],
        );
        let undecided = ctx.zeroed::<u32>("spsm undecided", 3 * capacity);
        let no_list = ctx.zeroed::<u32>("spsm texel lists (not yet)", 1);
        let bind = ctx.bind(&count, &buffers(&dims, &no_list, &undecided).each_ref());
        ctx.stage(rec, stage, |e| {
            e.clear_buffer(&texel_count, 0, None);
            e.clear_buffer(&counters, 0, None);
            GpuContext::dispatch(e, &count, &bind, GpuContext::groups_1d(n_items, 64));
            texel_scan.record(e);
        })?;
        Ok((ctx.read::<u32>(&counters)?, undecided))
    };
    let (mut c, mut undecided) = count_pass(4096, rec)?;
    if c[4] as usize > 4096 {
        (c, undecided) = count_pass(c[4] as usize, rec)?;
    }
    let word = |lo: usize| u64::from(c[lo]) | u64::from(c[lo + 1]) << 32;
    let total = ctx.read::<u32>(&fragments_total)?[0] as usize;
    let list = ctx.zeroed::<u32>("spsm texel lists", total.max(1));
    let dims = ctx.upload(
        "spsm raster dims",
        &[Dims { res: res as u32, items: n_items as u32, capacity: 0 }],
    );
    let buffers = buffers(&dims, &list, &undecided);
    let bind_scatter = ctx.bind(&scatter, &buffers.each_ref());
    let bind_resolve = ctx.bind(&resolve, &buffers.each_ref());
    ctx.stage(rec, stage, |e| {
        GpuContext::dispatch(e, &scatter, &bind_scatter, GpuContext::groups_1d(n_items, 64));
        GpuContext::dispatch(e, &resolve, &bind_resolve, GpuContext::groups_1d(texels, 64));
    })?;
    let mut texel: Vec<u32> = ctx.read(&out_texel)?;
    let mut depth: Vec<f64> = ctx.read(&out_depth)?;
    texel.truncate(texels);
    depth.truncate(texels);
    let mut counts =
        RasterCounts { tested: word(0), fragments: word(2), undecided: u64::from(c[4]) };
    // The pairs the filter could not decide, on the CPU; the map keeps the least
    // (depth, index) of all touching triangles, whatever order they come in.
    let pairs: Vec<u32> = if c[4] > 0 { ctx.read(&undecided)? } else { Vec::new() };
    let start = std::time::Instant::now();
    for p in pairs.chunks_exact(3).take(c[4] as usize) {
        let (i, x, y) = (p[0], p[1] as usize, p[2] as usize);
        let s: &TriSetup = &setups[i as usize];
        if !s.touches(x, y) {
            continue;
        }
        counts.fragments += 1;
        let d = s.conservative_depth(x, y);
        let k = y * res + x;
        if d < depth[k] || (d == depth[k] && i < texel[k]) {
            depth[k] = d;
            texel[k] = i;
        }
    }
    cpu_ms += start.elapsed().as_secs_f64() * 1e3;
    rec.stages.add(stage, cpu_ms);
    Ok((ConservativeMap { res: res as u32, setups, texel, depth }, counts))
}
