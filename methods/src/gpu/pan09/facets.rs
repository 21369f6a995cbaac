//! Stage "pixel facets" on the GPU (`facets.wgsl`): classification of every pixel, a scan of
//! the silhouette flags into facet numbers (pixel order, as on the CPU), then the silhouette
//! facets' records.

use super::{params::slot, read_counters, Kernels, Run};
use crate::gpu::{common::Xyz, GpuContext, GpuError};
use crate::pan09::STAGE_FACETS;
use bytemuck::{Pod, Zeroable};
use instrumentation::Recorder;

/// A silhouette facet's record, `f64` part: the WGSL `FacetF` of `facet_layout.wgsl` (the
/// facet's plane, its map, its region's planes, its footprint's corners, box and
/// orientation). Written and read on the GPU only.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(super) struct FacetF {
    normal: Xyz,
    offset: f64,
    origin: Xyz,
    dir: Xyz,
    a: Xyz,
    b: [f64; 2],
    k: f64,
    region: [Xyz; 3],
    footprint: [f64; 16],
    lo: [f64; 2],
    hi: [f64; 2],
    orientation: f64,
}

/// A silhouette facet's record, `u32` part: the WGSL `FacetU` (pixel, triangle, region plane
/// count, footprint corner count, texel rectangle `x0, y0, x1, y1`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(super) struct FacetU {
    /// The facet's pixel.
    pub pixel: u32,
    triangle: u32,
    regions: u32,
    corners: u32,
    rect: [u32; 4],
}

crate::gpu::layout::wgsl_mirror!(
    FacetF,
    "FacetF",
    crate::gpu::shader::compose(&[&crate::gpu::pan09::FACET_LAYOUT]),
    [normal, offset, origin, dir, a, b, k, region, footprint, lo, hi, orientation];
    FacetU,
    "FacetU",
    crate::gpu::shader::compose(&[&crate::gpu::pan09::FACET_LAYOUT]),
    [pixel, triangle, regions, corners, rect];
);

/// The facets: class per pixel, records, initial validity masks.
pub(super) struct Facets {
    /// 0 lit, 1 depth test, 2 silhouette, per pixel.
    pub class: wgpu::Buffer,
    /// Records, `f64` part.
    pub ff: wgpu::Buffer,
    /// Records, `u32` part.
    pub fu: wgpu::Buffer,
    /// Validity masks (all sub-samples until the validity mask stage).
    pub valid: wgpu::Buffer,
    /// Number of facets.
    pub count: u32,
}

/// Classifies the pixels with the summed-area table `sat` and builds the silhouette facets.
pub(super) fn run(
    run: &Run<'_>,
    k: &Kernels,
    sat: &wgpu::Buffer,
    rec: &mut Recorder,
) -> Result<Facets, GpuError> {
    let ctx = run.ctx;
    let f = run.frame;
    let pixels = f.pixels();
    let class = ctx.zeroed::<u32>("pixel class", pixels);
    let index = ctx.zeroed::<u32>("facet index", pixels + 1);
    let placeholders =
        [ctx.zeroed::<FacetF>("-", 1), ctx.zeroed::<FacetU>("-", 1), ctx.zeroed::<u32>("-", 1)];
    let bind = ctx.bind(
        &k.facets_classify,
        &[
            &run.params,
            &f.triangle,
            &f.position,
            &f.normal,
            sat,
            &class,
            &index,
            &placeholders[0],
            &placeholders[1],
            &placeholders[2],
            &run.counters,
        ],
    );
    let groups = GpuContext::groups_1d(pixels, 64);
    run.ctx.stage(rec, STAGE_FACETS, |e| {
        GpuContext::dispatch(e, &k.facets_classify, &bind, groups);
        super::scan::record(ctx, k, e, &index, pixels as u32 + 1);
    })?;
    let count = read_counters(ctx, &run.counters)?[slot::SILHOUETTE_PIXELS];
    let n = count as usize;
    let ff = ctx.zeroed::<FacetF>("facets f64", n);
    let fu = ctx.zeroed::<FacetU>("facets u32", n);
    let valid = ctx.zeroed::<u32>("validity masks", n * run.words as usize);
    let bind = ctx.bind(
        &k.facets_build,
        &[
            &run.params,
            &f.triangle,
            &f.position,
            &f.normal,
            sat,
            &class,
            &index,
            &ff,
            &fu,
            &valid,
            &run.counters,
        ],
    );
    run.ctx
        .stage(rec, STAGE_FACETS, |e| GpuContext::dispatch(e, &k.facets_build, &bind, groups))?;
    Ok(Facets { class, ff, fu, valid, count })
}
