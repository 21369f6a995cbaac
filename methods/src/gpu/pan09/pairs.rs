//! Stages "pixel-texel pairs" and "triangle-texel pairs" on the GPU (`pt_pairs.wgsl`,
//! `tt_pairs.wgsl`): count, exclusive scan, emit, test, compact, as the module doc of
//! [`crate::pan09::pairs`] describes; each stage is submitted in two parts around the read
//! of the number of keys emitted (which sizes the key buffers), timed together.

use super::{facets::Facets, params::slot, read_counters, read_total, scan, Kernels, Run};
use crate::gpu::{GpuContext, GpuError};
use crate::pan09::{STAGE_PT_PAIRS, STAGE_TT_PAIRS};
use instrumentation::Recorder;

/// Texel lists: `offsets` (`res^2 + 1`) into `items` (facet numbers).
pub(super) struct TexelLists {
    /// Offsets per texel.
    pub offsets: wgpu::Buffer,
    /// Facets, texel by texel.
    pub items: wgpu::Buffer,
}

/// The PT-pairs of the facets.
pub(super) fn pixel_texel_pairs(
    run: &Run<'_>,
    k: &Kernels,
    facets: &Facets,
    rec: &mut Recorder,
) -> Result<TexelLists, GpuError> {
    let ctx = run.ctx;
    let res = run.map.res;
    let texels = res as usize * res as usize;
    let n = facets.count;
    let counts = ctx.zeroed::<u32>("pt counts", n as usize + 1);
    let dims = ctx.upload("pt dims", &[n, res]);
    let ph: Vec<wgpu::Buffer> = (0..6).map(|_| ctx.zeroed::<u32>("-", 1)).collect();
    let bind = ctx.bind(
        &k.pt_count,
        &[&dims, &facets.ff, &facets.fu, &counts, &ph[0], &ph[1], &ph[2], &ph[3], &ph[4], &ph[5]],
    );
    let total = run.ctx.stage(rec, STAGE_PT_PAIRS, |e| {
        GpuContext::dispatch(e, &k.pt_count, &bind, GpuContext::groups_1d(n as usize, 64));
        scan::record(ctx, k, e, &counts, n + 1)
    })?;
    let emitted = read_total(ctx, &total)?;
    let keys = ctx.zeroed::<u32>("pt keys", 2 * emitted as usize);
    let flags = ctx.zeroed::<u32>("pt flags", emitted as usize);
    let offsets = ctx.zeroed::<u32>("pt offsets", texels + 1);
    let cursor = ctx.zeroed::<u32>("pt cursor", texels);
    let items = ctx.zeroed::<u32>("pt items", emitted as usize);
    let bufs = |d| {
        [
            d,
            &facets.ff,
            &facets.fu,
            &counts,
            &keys,
            &flags,
            &offsets,
            &cursor,
            &items,
            &run.counters,
        ]
    };
    let by_facet = ctx.upload("pt dims", &[n, res]);
    let by_key = ctx.upload("pt dims", &[emitted, res]);
    let emit = ctx.bind(&k.pt_emit, &bufs(&by_facet));
    let test = ctx.bind(&k.pt_test, &bufs(&by_key));
    let scatter = ctx.bind(&k.pt_scatter, &bufs(&by_key));
    run.ctx.stage(rec, STAGE_PT_PAIRS, |e| {
        GpuContext::dispatch(e, &k.pt_emit, &emit, GpuContext::groups_1d(n as usize, 64));
        let g = GpuContext::groups_1d(emitted as usize, 64);
        GpuContext::dispatch(e, &k.pt_test, &test, g);
        scan::record(ctx, k, e, &offsets, texels as u32 + 1);
        GpuContext::dispatch(e, &k.pt_scatter, &scatter, g);
    })?;
    Ok(TexelLists { offsets, items })
}

/// The TT-pairs (texel, triangle), 2 `u32` each, and their number.
pub(super) fn triangle_texel_pairs(
    run: &Run<'_>,
    k: &Kernels,
    pt: &TexelLists,
    rec: &mut Recorder,
) -> Result<(wgpu::Buffer, u32), GpuError> {
    let ctx = run.ctx;
    let res = run.map.res;
    let texels = res as usize * res as usize;
    let triangles = run.frame.triangles;
    let f = run.frame;
    let busy = ctx.zeroed::<u32>("busy texels", texels);
    let counts = ctx.zeroed::<u32>("tt counts", triangles as usize + 1);
    let by_texel = ctx.upload("tt dims", &[texels as u32, res]);
    let by_triangle = ctx.upload("tt dims", &[triangles, res]);
    let rows = ctx.zeroed::<u32>("tt rows", triangles as usize);
    let row_off = ctx.zeroed::<u32>("tt row items", triangles as usize + 1);
    let ph: Vec<wgpu::Buffer> = (0..5).map(|_| ctx.zeroed::<u32>("-", 1)).collect();
    let part1 = |d: &wgpu::Buffer, bsat: &wgpu::Buffer, pipeline: &wgpu::ComputePipeline| {
        ctx.bind(
            pipeline,
            &[
                &run.params,
                d,
                &f.corners,
                &f.casters,
                &pt.offsets,
                &busy,
                bsat,
                &counts,
                &ph[0],
                &ph[1],
                &ph[2],
                &run.counters,
                &rows,
                &row_off,
                &ph[4],
            ],
        )
    };
    let mark = part1(&by_texel, &ph[3], &k.tt_busy);
    let (keys_total, rows_total, bsat) = run.ctx.stage(rec, STAGE_TT_PAIRS, |e| {
        GpuContext::dispatch(e, &k.tt_busy, &mark, GpuContext::groups_1d(texels, 64));
        let bsat = super::sat::record(ctx, k, e, &busy, res);
        let count = part1(&by_triangle, &bsat, &k.tt_count);
        GpuContext::dispatch(e, &k.tt_count, &count, GpuContext::groups_1d(triangles as usize, 64));
        let keys = scan::record(ctx, k, e, &counts, triangles + 1);
        (keys, scan::record(ctx, k, e, &row_off, triangles + 1), bsat)
    })?;
    let emitted = read_total(ctx, &keys_total)?;
    let items = read_total(ctx, &rows_total)?;
    let row_keys = ctx.zeroed::<u32>("tt row keys", items as usize + 1);
    let by_item = ctx.upload("tt dims", &[items, triangles.max(1)]);
    let keys = ctx.zeroed::<u32>("tt keys", 2 * emitted as usize);
    let flags = ctx.zeroed::<u32>("tt flags", emitted as usize + 1);
    let tt = ctx.zeroed::<u32>("tt pairs", 2 * emitted as usize);
    let by_key = ctx.upload("tt dims", &[emitted, res]);
    let part2 = |d: &wgpu::Buffer, pipeline: &wgpu::ComputePipeline| {
        ctx.bind(
            pipeline,
            &[
                &run.params,
                d,
                &f.corners,
                &f.casters,
                &pt.offsets,
                &busy,
                &bsat,
                &counts,
                &keys,
                &flags,
                &tt,
                &run.counters,
                &rows,
                &row_off,
                &row_keys,
            ],
        )
    };
    let count_rows = part2(&by_item, &k.tt_count_rows);
    let emit = part2(&by_item, &k.tt_emit);
    let test = part2(&by_key, &k.tt_test);
    let compact = part2(&by_key, &k.tt_compact);
    run.ctx.stage(rec, STAGE_TT_PAIRS, |e| {
        let per_item = GpuContext::groups_1d(items as usize, 64);
        GpuContext::dispatch(e, &k.tt_count_rows, &count_rows, per_item);
        scan::record(ctx, k, e, &row_keys, items + 1);
        GpuContext::dispatch(e, &k.tt_emit, &emit, per_item);
        let g = GpuContext::groups_1d(emitted as usize, 64);
        GpuContext::dispatch(e, &k.tt_test, &test, g);
        scan::record(ctx, k, e, &flags, emitted + 1);
        GpuContext::dispatch(e, &k.tt_compact, &compact, g);
    })?;
    let kept = read_counters(ctx, &run.counters)?[slot::TT_PAIRS];
    Ok((tt, kept))
}
