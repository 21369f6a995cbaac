//! Stage "summed-area table" on the GPU (`sat.wgsl`): one invocation per row, then one per
//! column; also used for the TT-pairs' table of busy texels.

use super::Kernels;
use crate::gpu::GpuContext;

/// Records the `(res + 1)^2` table of the `res x res` mask `mask` into a new buffer.
pub(super) fn record(
    ctx: &GpuContext,
    k: &Kernels,
    encoder: &mut wgpu::CommandEncoder,
    mask: &wgpu::Buffer,
    res: u32,
) -> wgpu::Buffer {
    let stride = res as usize + 1;
    let sums = ctx.zeroed::<u32>("summed-area table", stride * stride);
    let dims = ctx.upload("sat dims", &[res]);
    let rows = ctx.bind(&k.sat_rows, &[&dims, mask, &sums]);
    let cols = ctx.bind(&k.sat_cols, &[&dims, mask, &sums]);
    GpuContext::dispatch(encoder, &k.sat_rows, &rows, GpuContext::groups_1d(res as usize, 64));
    GpuContext::dispatch(encoder, &k.sat_cols, &cols, GpuContext::groups_1d(stride, 64));
    sums
}
