//! Stage "pixel facets" on the GPU (`facets.wgsl`): classification of every pixel, a scan of
//! the silhouette flags into facet numbers (pixel order, as on the CPU), then the silhouette
//! facets' records.

use super::{params::slot, read_counters, Kernels, Run};
use crate::gpu::{GpuContext, GpuError};
use crate::pan09::STAGE_FACETS;
use instrumentation::Recorder;

/// `f64` per facet record (`facet_record.wgsl`).
pub(super) const FACET_F: usize = 48;
/// `u32` per facet record.
pub(super) const FACET_U: usize = 8;

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
        [ctx.zeroed::<f64>("-", 1), ctx.zeroed::<u32>("-", 1), ctx.zeroed::<u32>("-", 1)];
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
    let ff = ctx.zeroed::<f64>("facets f64", n * FACET_F);
    let fu = ctx.zeroed::<u32>("facets u32", n * FACET_U);
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
