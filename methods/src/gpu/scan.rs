//! Exclusive prefix sum of a `u32` buffer on the GPU (`scan.wgsl`): per block of 256, over
//! the block sums in one workgroup, then each block's offset added. Shared by the kernels
//! that build lists by count, scan and scatter (afsm's irregular z-buffer, pan09's pairs).

use crate::gpu::GpuContext;

/// Elements per block (the kernels' workgroup size).
const BLOCK: u32 = 256;

/// The three scan pipelines (cheap to clone: wgpu's handles are shared).
#[derive(Debug, Clone)]
pub(crate) struct Scan {
    blocks: wgpu::ComputePipeline,
    sums: wgpu::ComputePipeline,
    add: wgpu::ComputePipeline,
}

/// A scan of one buffer, bound and ready to record.
pub(crate) struct PreparedScan {
    scan: Scan,
    groups: (u32, u32, u32),
    /// One bind group per kernel (auto layouts are not shared between pipelines).
    binds: [wgpu::BindGroup; 3],
}

impl Scan {
    /// Compiles the kernels.
    pub(crate) fn new(ctx: &GpuContext) -> Self {
        let src = include_str!("scan.wgsl");
        Self {
            blocks: ctx.pipeline("scan blocks", src, "scan_blocks"),
            sums: ctx.pipeline("scan sums", src, "scan_sums"),
            add: ctx.pipeline("scan add", src, "scan_add"),
        }
    }

    /// Binds the scan of the first `n` elements of `data` in place; `total` (one `u32`)
    /// receives their sum.
    pub(crate) fn prepare(
        &self,
        ctx: &GpuContext,
        data: &wgpu::Buffer,
        n: usize,
        total: &wgpu::Buffer,
    ) -> PreparedScan {
        let groups = GpuContext::groups_1d(n, BLOCK);
        let params = ctx.upload("scan params", &[n as u32]);
        let sums = ctx.zeroed::<u32>("scan sums", groups.0 as usize * groups.1 as usize);
        let buffers = [&params, data, &sums, total];
        let binds = [&self.blocks, &self.sums, &self.add].map(|p| ctx.bind(p, &buffers));
        PreparedScan { scan: self.clone(), groups, binds }
    }
}

impl PreparedScan {
    /// Records the three passes.
    pub(crate) fn record(&self, encoder: &mut wgpu::CommandEncoder) {
        let [blocks, sums, add] = &self.binds;
        GpuContext::dispatch(encoder, &self.scan.blocks, blocks, self.groups);
        GpuContext::dispatch(encoder, &self.scan.sums, sums, (1, 1, 1));
        GpuContext::dispatch(encoder, &self.scan.add, add, self.groups);
    }
}
