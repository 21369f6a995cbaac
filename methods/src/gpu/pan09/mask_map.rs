//! Stage "silhouette mask map" on the GPU (`mask_map.wgsl`): one invocation per silhouette
//! edge, marking texels with an atomic exchange (which also counts `silhouette_texels`).

use super::{Kernels, Run};
use crate::gpu::{GpuContext, GpuError};
use crate::pan09::STAGE_SILHOUETTE_MASK;
use instrumentation::Recorder;

/// The mask map of the `count` edges in `edges`: one `u32` per texel, 1 where marked.
pub(super) fn run(
    run: &Run<'_>,
    k: &Kernels,
    edges: &wgpu::Buffer,
    count: u32,
    rec: &mut Recorder,
) -> Result<wgpu::Buffer, GpuError> {
    let ctx = run.ctx;
    let res = run.map.res as usize;
    let marks = ctx.zeroed::<u32>("silhouette mask", res * res);
    let n = ctx.upload("edge count", &[count]);
    let map = run.map;
    let bind = ctx.bind(
        &k.mask_map,
        &[
            &run.params,
            edges,
            &n,
            &map.depth,
            &map.triangle,
            &run.frame.corners,
            &marks,
            &run.counters,
        ],
    );
    ctx.stage(rec, STAGE_SILHOUETTE_MASK, |e| {
        GpuContext::dispatch(e, &k.mask_map, &bind, GpuContext::groups_1d(count as usize, 64))
    })?;
    Ok(marks)
}
