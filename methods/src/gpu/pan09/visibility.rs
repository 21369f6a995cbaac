//! Stage "visibility evaluation" on the GPU (`visibility.wgsl`): one invocation per TT-pair.

use super::{facets::Facets, pairs::TexelLists, Kernels, Run};
use crate::gpu::{GpuContext, GpuError};
use crate::pan09::STAGE_VISIBILITY;
use instrumentation::Recorder;

/// Occlusion masks (`words` per facet) and validity candidates (2 `u32` each, at most
/// `capacity`).
pub(super) fn run(
    run: &Run<'_>,
    k: &Kernels,
    (tt, pairs): (&wgpu::Buffer, u32),
    pt: &TexelLists,
    facets: &Facets,
    capacity: u32,
    rec: &mut Recorder,
) -> Result<(wgpu::Buffer, wgpu::Buffer), GpuError> {
    let ctx = run.ctx;
    let masks = ctx.zeroed::<u32>("occlusion masks", facets.count as usize * run.words as usize);
    let candidates = ctx.zeroed::<u32>("validity candidates", 2 * capacity as usize);
    let dims = ctx.upload("visibility dims", &[pairs, capacity]);
    let bind = ctx.bind(
        &k.visibility,
        &[
            &run.params,
            &dims,
            tt,
            &run.frame.corners,
            &pt.offsets,
            &pt.items,
            &facets.ff,
            &facets.fu,
            &run.lut,
            &masks,
            &candidates,
            &run.counters,
        ],
    );
    ctx.stage(rec, STAGE_VISIBILITY, |e| {
        GpuContext::dispatch(e, &k.visibility, &bind, GpuContext::groups_1d(pairs as usize, 64))
    })?;
    Ok((masks, candidates))
}
