//! Stage "silhouette extraction" on the GPU (`silhouette.wgsl`): one invocation per edge of
//! the casters' adjacency (computed once per scene on the CPU, [`EdgeAdjacency`], and
//! uploaded as five `u32` per edge: ends, face count, third corners).

use super::{Kernels, Run};
use crate::{gpu::GpuError, pan09::silhouette::EdgeAdjacency, pan09::STAGE_SILHOUETTE_EDGES};
use instrumentation::Recorder;

/// The adjacency as the kernel reads it.
pub(super) fn adjacency_data(adjacency: &EdgeAdjacency) -> Vec<u32> {
    (0..adjacency.len())
        .flat_map(|e| {
            let [a, b] = adjacency.ends[e];
            let [c1, c2] = adjacency.opposite[e];
            [a, b, adjacency.faces[e], c1, c2]
        })
        .collect()
}

/// Finds the silhouette edges; returns them (6 `f64` each, count in the counters).
pub(super) fn run(
    run: &Run<'_>,
    k: &Kernels,
    positions: &wgpu::Buffer,
    adjacency: &wgpu::Buffer,
    edges: usize,
    rec: &mut Recorder,
) -> Result<wgpu::Buffer, GpuError> {
    let ctx = run.ctx;
    let out = ctx.zeroed::<f64>("silhouette edges", 6 * edges);
    let bind = ctx.bind(&k.silhouette, &[&run.params, positions, adjacency, &out, &run.counters]);
    ctx.stage(rec, STAGE_SILHOUETTE_EDGES, |e| {
        crate::gpu::GpuContext::dispatch(
            e,
            &k.silhouette,
            &bind,
            crate::gpu::GpuContext::groups_1d(edges, 64),
        )
    })?;
    Ok(out)
}
