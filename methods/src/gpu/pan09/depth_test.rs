//! Stage "depth test" of the non-silhouette pixels on the GPU (`depth_test.wgsl`).

use super::{Kernels, Run};
use crate::gpu::{GpuContext, GpuError};
use crate::pan09::STAGE_DEPTH_TEST;
use instrumentation::Recorder;

/// Every pixel's lit value (`f32`): the depth test's, 1 elsewhere.
pub(super) fn run(
    run: &Run<'_>,
    k: &Kernels,
    class: &wgpu::Buffer,
    rec: &mut Recorder,
) -> Result<wgpu::Buffer, GpuError> {
    let ctx = run.ctx;
    let f = run.frame;
    let lit = ctx.zeroed::<f32>("lit", f.pixels());
    let bind = ctx.bind(
        &k.depth_test,
        &[&run.params, &f.position, &f.normal, class, &run.map.depth, &lit, &run.counters],
    );
    ctx.stage(rec, STAGE_DEPTH_TEST, |e| {
        GpuContext::dispatch(e, &k.depth_test, &bind, GpuContext::groups_1d(f.pixels(), 64))
    })?;
    Ok(lit)
}
