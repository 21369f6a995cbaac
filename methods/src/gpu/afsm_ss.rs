//! `afsm-ss` on the GPU: the alias-free shadow map at `rate` sub-samples per pixel (Aila and
//! Laine 2004, "Alias-Free Shadow Maps", EGSR 2004, sections 3 and 5; as brute-force
//! supersampling, the baseline of Pan et al. 2009, "Fast, Sub-pixel Antialiased Shadow Maps",
//! Computer Graphics Forum 28(7), Fig. 10), built on `afsm`'s irregular z-buffer
//! ([`super::afsm::Izb`]).
//!
//! Stages, as the CPU twin's ([`crate::afsm`]): the camera G-buffer at every sub-sample but
//! the centre ([`afsm::gbuffer_stage`]`(s)`, each a hardware rasterization at the
//! sub-sample's shift, [`super::raster`]; the centre's is the frame's), then for every
//! sub-sample the transformation of samples, the IZB construction, the rasterization of
//! blockers and the undecided tests (CPU). Each of these four is recorded once, its time
//! summed over the sub-samples.
//!
//! # Choices
//!
//! - **One pass per sub-sample.** The CPU builds one BSP over all `rate x pixels` samples; here
//!   the irregular z-buffer holds one sub-sample of every pixel at a time, and each pass marks
//!   the shadowed pixels of its sub-sample. Memory stays that of `afsm` (1920 x 1080 at 32
//!   sub-samples would be 66 M samples, 2 GB, beyond a storage binding's size on most
//!   adapters), and the casters' setup runs once. Which samples a caster shadows does not
//!   depend on how the samples are organised, so the result is the CPU's.
//! - **G-buffers.** [`SubSampleGBuffers::Gpu`] (what `--device gpu` runs) rasterizes them on
//!   the GPU, which may keep another triangle than the CPU where the hardware's fixed-point
//!   coverage differs (see [`super`]); [`SubSampleGBuffers::Cpu`] renders them with the CPU's
//!   exact rasterizer and uploads them, for the parity tests, which then require the CPU's
//!   answer exactly.
//! - **Resolve.** A pixel's light is the mean over its sub-samples, computed on the CPU as the
//!   twin computes it (the `f64` mean, then the mean of three equal channels, as `f32`).
//! - **Transparency** is not applicable, as for `afsm` on the GPU.

use super::{
    afsm::{Izb, SampleSurface},
    raster::{rasterize, RasterJob},
    GpuContext, GpuFrame,
};
use crate::{
    afsm::{self, AfsmOptions, AliasFreeShadowMap},
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    pattern::SamplePattern,
    raster::rasterize_nearest_at,
};
use glam::DVec2;
use instrumentation::Recorder;

/// Where the sub-samples' camera G-buffers come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SubSampleGBuffers {
    /// Rasterized on the GPU (`--device gpu`).
    Gpu,
    /// The CPU's exact rasterizer, uploaded (parity tests).
    Cpu,
}

/// `afsm-ss` on the GPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GpuAfsmSs {
    /// The CPU `afsm-ss`'s options (the culling switches have no effect here).
    pub options: AfsmOptions,
}

/// What [`shade`] returns.
#[derive(Debug, Clone, PartialEq)]
pub struct AfsmSsGpuOutput {
    /// Per pixel, the share of its sub-samples that are lit.
    pub lit: Vec<f32>,
    /// (Sample, triangle) pairs the GPU's filter could not decide, over all sub-samples.
    pub undecided: u64,
}

/// The kernels of `afsm-ss` with `options` for `frame`, whose geometry (and centre G-buffer)
/// is in `gpu`, the other sub-samples' G-buffers made as `gbuffers` says: the light per
/// pixel; adds `sampling_points_tested` (and, for G-buffers rasterized on the CPU, its raster
/// counters) to `rec`, and a note with the grid and the undecided pairs.
pub fn shade(
    ctx: &GpuContext,
    gpu: &GpuFrame,
    frame: &Frame<'_>,
    options: &AfsmOptions,
    gbuffers: SubSampleGBuffers,
    rec: &mut Recorder,
) -> Result<AfsmSsGpuOutput, MethodError> {
    let pattern = SamplePattern::new(options.rate, options.pattern)?;
    let rate = pattern.rate() as usize;
    let pixels = gpu.pixels();
    let izb = Izb::new(ctx, gpu, frame);
    let mut lit_count = vec![0u32; pixels];
    let mut passes = Recorder::default();
    let mut undecided = 0;
    for s in 0..rate {
        let offset = pattern.offsets()[s];
        let extra = if s == pattern.centre_index() {
            None
        } else {
            Some(sub_sample_gbuffer(ctx, gpu, frame, offset, s, gbuffers, rec)?)
        };
        let (triangle, depth) = match &extra {
            Some((t, d)) => (t, d),
            None => (&gpu.triangle, &gpu.depth),
        };
        let out = izb.shadowed(ctx, SampleSurface { triangle, depth, offset }, &mut passes)?;
        for (count, &shadowed) in lit_count.iter_mut().zip(&out.shadowed) {
            *count += u32::from(shadowed == 0);
        }
        undecided += out.undecided;
        rec.counters.sampling_points_tested += out.tested;
    }
    for stage in &passes.stages.stages {
        rec.stages.add(&stage.name, stage.ms);
    }
    rec.notes.push(format!("{}, over {rate} sub-samples", izb.note(undecided)));
    let lit = lit_count
        .iter()
        .map(|&n| {
            let c = (f64::from(n) / rate as f64).clamp(0.0, 1.0);
            ((c + c + c) / 3.0).clamp(0.0, 1.0) as f32
        })
        .collect();
    Ok(AfsmSsGpuOutput { lit, undecided })
}

/// The camera G-buffer's triangle and depth buffers at sub-sample `s` (offset `offset` in its
/// pixel), timed as the stage [`afsm::gbuffer_stage`]`(s)`.
fn sub_sample_gbuffer(
    ctx: &GpuContext,
    gpu: &GpuFrame,
    frame: &Frame<'_>,
    offset: DVec2,
    s: usize,
    gbuffers: SubSampleGBuffers,
    rec: &mut Recorder,
) -> Result<(wgpu::Buffer, wgpu::Buffer), MethodError> {
    let shift = offset - DVec2::splat(0.5);
    let stage = afsm::gbuffer_stage(s);
    match gbuffers {
        SubSampleGBuffers::Gpu => {
            let job =
                RasterJob { projector: &frame.camera, casters_only: false, shift, gbuffer: false };
            let r = rasterize(ctx, frame, &gpu.corners, &gpu.casters, job, &stage, rec)?;
            Ok((r.triangle, r.depth))
        }
        SubSampleGBuffers::Cpu => {
            let n = rec.stages.time(&stage, || {
                rasterize_nearest_at(
                    &frame.geometry,
                    |_| true,
                    &frame.camera,
                    shift,
                    &mut rec.counters,
                )
            });
            Ok((ctx.upload("afsm-ss triangle", &n.triangle), ctx.upload("afsm-ss depth", &n.depth)))
        }
    }
}

impl GpuAfsmSs {
    /// The CPU method with the same options.
    fn twin(&self) -> AliasFreeShadowMap {
        AliasFreeShadowMap::supersampled(self.options)
    }
}

impl ShadowMethod for GpuAfsmSs {
    fn name(&self) -> &'static str {
        self.twin().name()
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        super::twin_params(&self.twin())
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        self.twin().validate()?;
        super::afsm::opaque_casters_only(frame, self.name())?;
        let ctx = GpuContext::shared()?;
        ctx.describe(rec);
        let gpu = GpuFrame::for_run(ctx, frame, rec)?;
        let out = shade(ctx, &gpu, frame, &self.options, SubSampleGBuffers::Gpu, rec)?;
        Ok(Visibility {
            width: frame.width(),
            height: frame.height(),
            lit: out.lit,
            transmittance: None,
        })
    }
}
