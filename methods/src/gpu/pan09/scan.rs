//! Exclusive prefix sums for the write offsets of the emit passes, the facet numbers and the
//! texel lists' offsets, by the shared scan ([`crate::gpu::scan`]).

use super::Kernels;
use crate::gpu::GpuContext;

/// Records the exclusive scan of `data[..n]` in place; returns a one-word buffer that
/// receives the sum of the `n` values.
pub(super) fn record(
    ctx: &GpuContext,
    k: &Kernels,
    encoder: &mut wgpu::CommandEncoder,
    data: &wgpu::Buffer,
    n: u32,
) -> wgpu::Buffer {
    let total = ctx.zeroed::<u32>("scan total", 1);
    k.scan.prepare(ctx, data, n as usize, &total).record(encoder);
    total
}
