//! `ftizb` on the GPU: the frustum-traced irregular z-buffer (Wyman, Hoetzlein and Lefohn,
//! "Frustum-Traced Raster Shadows: Revisiting Irregular Z-Buffers", ACM I3D 2015, sections 3
//! to 5; "Frustum-Traced Irregular Z-Buffers: Fast, Sub-pixel Accurate Hard Shadows", IEEE
//! TVCG 22(10), 2016, sections 4 to 6), built on `afsm`'s irregular z-buffer
//! ([`super::afsm::Izb`]). Its CPU twin is [`crate::ftizb`].
//!
//! Stages: [`STAGE_FOOTPRINTS`] (`ftizb/tangent.wgsl`, once per sub-sample but the centre):
//! every pixel's sub-sample placed on the tangent plane of its G-buffer point and face normal,
//! as [`SubSamples::pixel`](crate::ftizb::footprints::SubSamples::pixel) places it (the camera
//! ray through `(i, j) + offset` meets the plane at the parameter `t` of
//! `Ray::intersect_plane`, in `f64` with the CPU's operations in its order; outside the
//! facet's region, or with no intersection, the sub-sample has no point); then, for every
//! sub-sample, `afsm`'s transformation of samples, IZB construction, rasterization of blockers
//! and undecided tests (CPU) on that surface ([`Izb::shadowed`]). Each stage is recorded once,
//! its time summed over the sub-samples.
//!
//! # Choices
//!
//! - **The irregular z-buffer is `afsm`'s, one pass per sub-sample.** A sub-sample's surface
//!   ([`SampleSurface`]) is the pixel's G-buffer triangle and the tangent-plane depth `t`; the
//!   centre sub-sample's is the G-buffer itself (its point is the G-buffer's position, which is
//!   the centre ray at the G-buffer's depth), so it needs no kernel. `Izb`'s per-sample
//!   predicate is the CPU's [`Blocker::shadows`](crate::afsm::blockers::Blocker::shadows),
//!   the one CPU `ftizb`'s frustum tests decide with (pairs the `f64` filter cannot decide go
//!   back to the CPU), and its light is [`afsm::light_projector`](crate::afsm::light_projector),
//!   whose image CPU `ftizb`'s grid only scales: the decisions are the CPU's.
//! - **Binning.** The twin lists each pixel's *footprint* (its sub-samples' region on the
//!   light's image) in the texels of its grid and rasterizes the casters conservatively into
//!   them; here the sub-samples themselves are binned into `Izb`'s grid, one sub-sample of
//!   every pixel per pass, and each caster visits the cells its bounding box covers. Which
//!   sub-samples a caster shadows does not depend on how they are binned, so the result is
//!   the CPU's, pixel for pixel; the counters are not (as GPU `afsm`'s are not): there is no
//!   footprint list, no conservative rasterization and no culling (the `--izb-res` grid and
//!   the depth-culling switch are accepted and recorded, and change nothing).
//! - **Valid sub-samples.** A sub-sample counts in its pixel's ratio when it has a point on
//!   the tangent plane's region and the light projects it to a finite light image point with
//!   a finite threshold, which is exactly when `Izb`'s transformation gives it a sample
//!   ([`Izb::sampled`]); a pixel whose centre has no sample has none (lit), as on the CPU.
//! - **Hidden sub-samples** (the CPU's rule, after Pan et al.'s validity mask): where a pixel
//!   spans several triangles of a curved mesh, tangent-plane points lie behind the real
//!   surface and its own triangles would shadow them. A sub-sample but the centre is hidden
//!   when a caster that shadows it also hides it from the camera (the camera ray through it
//!   meets the caster before its tangent-plane depth, less its shadow offset): every pass but
//!   the centre's is [`Izb::shadowed_and_hidden`], which tests this on the GPU for every
//!   shadowing (sample, caster) pair and on the CPU for the undecided pairs found shadowing,
//!   so hidden wins whatever the order of the casters. A hidden sub-sample leaves the ratio:
//!   `lit = 1 - shadowed / valid` over the valid sub-samples that are not hidden, in `f64`,
//!   1 where none of them is shadowed, as `f32`.
//! - **Counters.** `sampling_points_tested` as GPU `afsm-ss` sums it (the samples inside a
//!   caster's bounding box in the cells it visits); the undecided pairs in a note.
//! - **Transparency** is not applicable, as for `afsm` on the GPU (the twin treats
//!   semi-transparent casters as opaque and says so).

use super::{
    afsm::{opaque_casters_only, Izb, SampleSurface},
    common::COMMON,
    shader::{compose, Part},
    GpuContext, GpuFrame,
};
use crate::{
    frame::Frame,
    ftizb::{self, Ftizb, FtizbOptions, STAGE_FOOTPRINTS},
    method::{MethodError, ShadowMethod, Visibility},
    pan09::{
        facets::{FACET_DEPTH_RATIO, FACET_ORTHO_SPAN},
        screen::CameraBasis,
    },
    pattern::SamplePattern,
};
use bytemuck::{Pod, Zeroable};
use instrumentation::Recorder;

const WG: u32 = 64;

/// The tangent-plane kernel's WGSL.
const TANGENT: Part = Part {
    name: "ftizb/tangent.wgsl",
    source: include_str!("ftizb/tangent.wgsl"),
    needs: &[&COMMON],
};

/// The tangent-plane kernel's constants, the WGSL `TangentParams`: the region's depth ratio
/// ([`FACET_DEPTH_RATIO`]) and reach in depth for orthographic cameras ([`FACET_ORTHO_SPAN`]
/// pixel widths, the pixel width as [`CameraBasis`] gives it), the sub-sample's offset in its
/// pixel (written per pass), pixels and image width.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct TangentParams {
    depth_ratio: f64,
    ortho_span: f64,
    sub_x: f64,
    sub_y: f64,
    pixels: u32,
    width: u32,
}

super::layout::wgsl_mirror!(
    TangentParams,
    "TangentParams",
    compose(&[&TANGENT]),
    [depth_ratio, ortho_span, sub_x, sub_y, pixels, width];
);

/// `ftizb` on the GPU (`ftizb` with `--device gpu`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GpuFtizb {
    /// The CPU `ftizb`'s options (the grid resolution and the depth-culling switch have no
    /// effect here).
    pub options: FtizbOptions,
}

/// What [`shade`] returns.
#[derive(Debug, Clone, PartialEq)]
pub struct FtizbGpuOutput {
    /// Per pixel, `1 - shadowed / valid` over its sub-samples counted (1 where none is
    /// shadowed).
    pub lit: Vec<f32>,
    /// Sub-samples per pixel counted in its ratio: valid and not hidden (0 for background
    /// pixels and pixels whose centre the light cannot project).
    pub valid: Vec<u32>,
    /// Shadowed sub-samples per pixel among those counted.
    pub shadowed: Vec<u32>,
    /// Hidden sub-samples per pixel: valid, and shadowed by a caster that also hides them
    /// from the camera; left out of the pixel's ratio.
    pub hidden: Vec<u32>,
    /// (Sample, triangle) pairs the GPU's filter could not decide, over all sub-samples.
    pub undecided: u64,
}

/// The kernels of `ftizb` with `options` for `frame`, whose geometry and G-buffer (triangle,
/// depth, position and normal) are in `gpu`: the light per pixel; adds
/// `sampling_points_tested` to `rec`'s counters, the stages' times, and a note with the grid
/// and the undecided pairs.
pub fn shade(
    ctx: &GpuContext,
    gpu: &GpuFrame,
    frame: &Frame<'_>,
    options: &FtizbOptions,
    rec: &mut Recorder,
) -> Result<FtizbGpuOutput, MethodError> {
    options.validate()?;
    let pattern = SamplePattern::new(options.rate, options.pattern)?;
    let rate = pattern.rate() as usize;
    let centre = pattern.centre_index();
    let pixels = gpu.pixels();
    let izb = Izb::new(ctx, gpu, frame);

    let basis = CameraBasis::new(&frame.camera);
    let params = ctx.upload(
        "ftizb tangent params",
        &[TangentParams {
            depth_ratio: FACET_DEPTH_RATIO,
            ortho_span: FACET_ORTHO_SPAN * basis.ox.length().max(basis.oy.length()),
            sub_x: 0.5,
            sub_y: 0.5,
            pixels: pixels as u32,
            width: gpu.width,
        }],
    );
    let tangent = ctx.pipeline("ftizb tangent", &compose(&[&TANGENT]), "tangent");
    let s_triangle = ctx.zeroed::<u32>("ftizb sub-sample triangle", pixels);
    let s_depth = ctx.zeroed::<f64>("ftizb sub-sample depth", pixels);
    let bind = ctx.bind(
        &tangent,
        &[
            &params,
            &gpu.camera,
            &gpu.triangle,
            &gpu.depth,
            &gpu.position,
            &gpu.normal,
            &s_triangle,
            &s_depth,
        ],
    );
    let groups = GpuContext::groups_1d(pixels, WG);

    let mut valid = vec![0u32; pixels];
    let mut shadowed = vec![0u32; pixels];
    let mut hidden = vec![0u32; pixels];
    let mut centre_valid = vec![false; pixels];
    let mut passes = Recorder::default();
    let mut undecided = 0;
    if rate == 1 {
        rec.stages.skip(STAGE_FOOTPRINTS);
    }
    for (s, &offset) in pattern.offsets().iter().enumerate() {
        let surface = if s == centre {
            SampleSurface { triangle: &gpu.triangle, depth: &gpu.depth, offset }
        } else {
            ctx.queue.write_buffer(
                &params,
                std::mem::offset_of!(TangentParams, sub_x) as u64,
                bytemuck::cast_slice(&[offset.x, offset.y]),
            );
            ctx.stage(rec, STAGE_FOOTPRINTS, |e| {
                GpuContext::dispatch(e, &tangent, &bind, groups);
            })?;
            SampleSurface { triangle: &s_triangle, depth: &s_depth, offset }
        };
        // The centre sub-sample is never hidden.
        let out = if s == centre {
            izb.shadowed(ctx, surface, &mut passes)?
        } else {
            izb.shadowed_and_hidden(ctx, surface, &mut passes)?
        };
        let sampled = izb.sampled(ctx)?;
        let marks = out.shadowed.iter().zip(&out.hidden);
        for (k, (&has, (&dark, &behind))) in sampled.iter().zip(marks).enumerate() {
            if !has {
                continue;
            }
            // Hidden wins over shadowed.
            if behind != 0 {
                hidden[k] += 1;
            } else {
                valid[k] += 1;
                shadowed[k] += u32::from(dark != 0);
            }
        }
        if s == centre {
            centre_valid = sampled;
        }
        undecided += out.undecided;
        rec.counters.sampling_points_tested += out.tested;
    }
    for stage in &passes.stages.stages {
        rec.stages.add(&stage.name, stage.ms);
    }
    rec.notes.push(format!("{}, over {rate} sub-samples", izb.note(undecided)));
    // A pixel whose centre has no sample has no valid sub-sample (CPU: `SubSamples::pixel`).
    for (k, &has) in centre_valid.iter().enumerate() {
        if !has {
            valid[k] = 0;
            shadowed[k] = 0;
            hidden[k] = 0;
        }
    }
    let lit = valid.iter().zip(&shadowed).map(|(&v, &s)| ftizb::lit(s, v)).collect();
    Ok(FtizbGpuOutput { lit, valid, shadowed, hidden, undecided })
}

impl GpuFtizb {
    /// The CPU method with the same options.
    fn twin(&self) -> Ftizb {
        Ftizb { options: self.options }
    }
}

impl ShadowMethod for GpuFtizb {
    fn name(&self) -> &'static str {
        self.twin().name()
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        super::twin_params(&self.twin())
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        self.options.validate()?;
        opaque_casters_only(frame, self.name())?;
        let ctx = GpuContext::shared()?;
        ctx.describe(rec);
        let gpu = GpuFrame::for_run(ctx, frame, rec)?;
        let out = shade(ctx, &gpu, frame, &self.options, rec)?;
        Ok(Visibility {
            width: frame.width(),
            height: frame.height(),
            lit: out.lit,
            transmittance: None,
        })
    }
}
