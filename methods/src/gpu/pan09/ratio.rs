//! Stage "occlusion ratio" on the GPU (`ratio.wgsl`): one invocation per silhouette facet.

use super::{facets::Facets, Kernels, Run};
use crate::gpu::{GpuContext, GpuError};
use crate::pan09::STAGE_OCCLUSION_RATIO;
use instrumentation::Recorder;

/// Writes the facets' lit values into `lit` and their final validity masks into
/// `facets.valid`.
pub(super) fn run(
    run: &Run<'_>,
    k: &Kernels,
    facets: &Facets,
    masks: &wgpu::Buffer,
    lit: &wgpu::Buffer,
    rec: &mut Recorder,
) -> Result<(), GpuError> {
    let ctx = run.ctx;
    let dims = ctx.upload("ratio dims", &[facets.count]);
    let bind = ctx.bind(
        &k.ratio,
        &[
            &run.params,
            &dims,
            &facets.ff,
            &facets.fu,
            &run.lut,
            masks,
            &facets.valid,
            lit,
            &run.counters,
        ],
    );
    ctx.stage(rec, STAGE_OCCLUSION_RATIO, |e| {
        GpuContext::dispatch(e, &k.ratio, &bind, GpuContext::groups_1d(facets.count as usize, 64))
    })
}
