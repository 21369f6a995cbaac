//! Exclusive prefix sums on the GPU (`scan.wgsl`), for the write offsets of the emit passes,
//! the facet numbers and the texel lists' offsets.

use super::Kernels;
use crate::gpu::GpuContext;

/// Values scanned by one invocation of the first pass.
const CHUNK: u32 = 256;

/// Records the exclusive scan of `data[..n]` in place; returns the chunk sums, whose entry
/// `n.div_ceil(CHUNK)` is the total.
pub(super) fn record(
    ctx: &GpuContext,
    k: &Kernels,
    encoder: &mut wgpu::CommandEncoder,
    data: &wgpu::Buffer,
    n: u32,
) -> (wgpu::Buffer, u32) {
    let chunks = n.div_ceil(CHUNK);
    let dims = ctx.upload("scan dims", &[n]);
    let sums = ctx.zeroed::<u32>("scan sums", chunks as usize + 1);
    let bind = |p: &wgpu::ComputePipeline| ctx.bind(p, &[&dims, data, &sums]);
    let groups = GpuContext::groups_1d(chunks as usize, 64);
    GpuContext::dispatch(encoder, &k.scan_chunks, &bind(&k.scan_chunks), groups);
    GpuContext::dispatch(encoder, &k.scan_totals, &bind(&k.scan_totals), (1, 1, 1));
    let groups = GpuContext::groups_1d(n as usize, 64);
    GpuContext::dispatch(encoder, &k.scan_add, &bind(&k.scan_add), groups);
    (sums, chunks)
}
