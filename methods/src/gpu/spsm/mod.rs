//! `spsm`, `spsm-f32` on the GPU: sub-pixel shadow maps (Lecocq, Marvie, Sourimant and
//! Gautron, "Sub-Pixel Shadow Mapping", ACM i3D 2014; the CPU twin is [`Spsm`], whose module
//! doc lists every choice where the paper is vague; they are the same here).
//!
//! Stages, named as the twin's:
//!
//! 1. **conservative rasterization** (section 3.2): on the GPU ([`raster`]), texel for texel
//!    the twin's map (triangle and minimum conservative depth), the triangles prepared by the
//!    twin's code; overlaps the `f64` filter cannot decide are handed back to it.
//! 2. **packing** (sections 3.3 and 3.4): on the GPU ([`pack`]), texel for texel the twin's
//!    bits in both formats; kept on the GPU for the later stages, and read back for the
//!    twin's code (the pixels handed back, the antialiasing's records).
//! 3. **classification** (section 4.1, Algorithm 1): on the GPU ([`classify`]), one thread a
//!    pixel, decoding the packed or `f32` texels in `f64` as the twin does; pixels whose exact
//!    containment test the `f64` filter cannot decide are handed back to the twin's code.
//! 4. **consistent min depth** (section 4, Fig. 9): on the GPU ([`depth`]), for the texels
//!    around the uncertain pixels, as the twin.
//! 5. **silhouette recovery** (section 4.2): on the GPU ([`recover`]), one thread an
//!    uncertain pixel, the look-up tables uploaded; pixels whose exact tests the `f64` filter
//!    cannot decide are handed back to the twin's code.
//! 6. **antialiasing** (section 5): on the GPU ([`antialias`]), the recovered silhouettes'
//!    occluders uploaded per pixel and every sub-sample evaluated there.
//!
//! The texels reach the kernels as stored ([`texel`]).
//!
//! The run's G-buffer is the GPU's ([`GpuFrame::for_run`]), read back for the CPU stages.
//! Counters as the twin's; those of classification and consistent min depth are counted on the
//! GPU with atomics.

pub mod antialias;
pub mod classify;
pub mod depth;
pub mod pack;
pub mod raster;
pub mod recover;
pub mod texel;

use crate::{
    frame::Frame,
    gpu::{GpuContext, GpuFrame},
    method::{MethodError, ShadowMethod, Visibility},
    spsm::{self, PixelClass, Spsm, SpsmOptions},
};
use instrumentation::Recorder;

/// The output of [`shade`].
#[derive(Debug, Clone)]
pub struct Shaded {
    /// The lit values, as the twin's.
    pub visibility: Visibility,
    /// Each pixel's class (Fig. 14).
    pub classes: Vec<PixelClass>,
    /// Pixels classified by the CPU code (containment undecided by the `f64` filter).
    pub handed_back: u64,
}

/// Every stage after the G-buffer for `gframe`, whose G-buffer is `frame`'s (the CPU's, for
/// parity; or one read back): the twin's map, classification on the GPU, and the stages of
/// the uncertain pixels.
pub fn shade(
    ctx: &GpuContext,
    gframe: &GpuFrame,
    frame: &Frame<'_>,
    options: &SpsmOptions,
    rec: &mut Recorder,
) -> Result<Shaded, MethodError> {
    let sample_pattern = options.validate()?;
    let (projector, space, tester) = spsm::map_frame(options, frame);
    let (raster, counts) = raster::rasterize_conservative(
        ctx,
        &frame.geometry,
        |t| frame.is_caster(t),
        &projector,
        &space,
        spsm::STAGE_RASTER,
        rec,
    )?;
    rec.counters.raster_samples_tested += counts.tested;
    rec.counters.conservative_fragments += counts.fragments;
    if counts.undecided > 0 {
        rec.notes.push(format!(
            "{} texel-triangle pairs of the conservative rasterization decided by the CPU code \
             (overlap undecided by the f64 filter)",
            counts.undecided
        ));
    }
    let packed = pack::pack_map(
        ctx,
        &raster,
        space,
        options.texel,
        options.derivative_power,
        spsm::STAGE_PACKING,
        rec,
    )?;
    drop(raster);
    spsm::record_packing(packed.filled, packed.clamped, rec);
    let lookup = spsm::classify::Lookup { map: &packed.map, tester, space };
    let texels = texel::GpuTexels::keep(ctx, &lookup, packed.words, packed.planes);
    let mut c = classify::classify(ctx, gframe, frame, &lookup, &texels, rec)?;
    rec.counters.merge(&c.counters);
    if c.handed_back > 0 {
        rec.notes.push(format!(
            "{} pixels classified by the CPU code (containment undecided by the f64 filter)",
            c.handed_back
        ));
    }
    let (consistent, corrected) = depth::consistent_depths(ctx, &texels, &c.uncertain, rec)?;
    rec.counters.depth_corrected_texels += corrected;
    let recovered = recover::recover_pixels(
        ctx,
        gframe,
        frame,
        &lookup,
        &texels,
        &consistent,
        &c.uncertain,
        &mut c.lit,
        rec,
    )?;
    if recovered.handed_back > 0 {
        rec.notes.push(format!(
            "{} pixels recovered by the CPU code (containment or orientation undecided by the \
             f64 filter)",
            recovered.handed_back
        ));
    }
    let silhouettes = recovered.silhouettes;
    if options.rate > 1 {
        let counters = antialias::antialias_pixels(
            ctx,
            frame,
            &lookup,
            &sample_pattern,
            &c.uncertain,
            &silhouettes,
            &mut c.lit,
            spsm::STAGE_ANTIALIASING,
            rec,
        )?;
        rec.counters.merge(&counters);
    } else {
        rec.stages.skip(spsm::STAGE_ANTIALIASING);
    }
    let visibility = Visibility {
        width: frame.width(),
        height: frame.height(),
        lit: c.lit,
        transmittance: None,
    };
    Ok(Shaded { visibility, classes: c.classes, handed_back: c.handed_back })
}

/// The sub-pixel shadow map with conservative rasterization, classification and consistent
/// min depth on the GPU; the twin of [`Spsm`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GpuSpsm {
    /// Options, as the twin's.
    pub options: SpsmOptions,
}

impl ShadowMethod for GpuSpsm {
    fn name(&self) -> &'static str {
        Spsm { options: self.options }.name()
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        super::twin_params(&Spsm { options: self.options })
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        self.options.validate()?;
        if frame.effects.transparency {
            rec.notes.push(format!("{} treats semi-transparent casters as opaque", self.name()));
        }
        let ctx = GpuContext::shared()?;
        ctx.describe(rec);
        let gframe = GpuFrame::for_run(ctx, frame, rec)?;
        let mut frame = frame.clone();
        frame.gbuffer = gframe.read_gbuffer(ctx)?;
        shade(ctx, &gframe, &frame, &self.options, rec).map(|s| s.visibility)
    }
}
