//! Stage "validity mask" on the GPU (`validity.wgsl`): one invocation per candidate the
//! visibility evaluation noted; run only with curved receivers.

use super::{facets::Facets, Kernels, Run};
use crate::gpu::{GpuContext, GpuError};
use crate::pan09::STAGE_VALIDITY;
use instrumentation::Recorder;

/// ANDs the hidden sub-samples out of `facets.valid`.
pub(super) fn run(
    run: &Run<'_>,
    k: &Kernels,
    candidates: &wgpu::Buffer,
    count: u32,
    facets: &Facets,
    rec: &mut Recorder,
) -> Result<(), GpuError> {
    let ctx = run.ctx;
    let dims = ctx.upload("validity dims", &[count]);
    let bind = ctx.bind(
        &k.validity,
        &[
            &run.params,
            &dims,
            candidates,
            &run.frame.corners,
            &facets.ff,
            &facets.fu,
            &run.lut,
            &facets.valid,
        ],
    );
    ctx.stage(rec, STAGE_VALIDITY, |e| {
        GpuContext::dispatch(e, &k.validity, &bind, GpuContext::groups_1d(count as usize, 64))
    })
}
