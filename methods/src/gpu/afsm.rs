//! `afsm` on the GPU: the alias-free shadow map (Aila and Laine 2004, "Alias-Free Shadow
//! Maps", EGSR 2004, sections 3 and 5) as an irregular z-buffer, the
//! form GPU versions of the technique take: the sampling points are binned into a regular
//! grid of light-space cells instead of the paper's 2D BSP, and each caster triangle visits
//! the cells its light-space bounding box covers.
//!
//! Stages (each one GPU submission, timed by [`GpuContext::stage`]):
//!
//! - [`STAGE_TRANSFORMATION`] (`transform.wgsl`): every pixel centre's surface point (on the
//!   camera ray through it at the G-buffer's depth) moved to the light's image plane with its
//!   shadow threshold depth, as [`afsm::samples::transform_samples`] does, in `f64`.
//! - [`STAGE_IZB`] (`izb.wgsl`, `scan.wgsl`): the samples binned into a [`grid_size`] square
//!   grid over the light image: per-cell counts by `atomicAdd` (which also gives each sample
//!   its rank in its cell), an exclusive scan of the counts, and a scatter into one sample
//!   array in which each cell's samples are contiguous.
//! - [`STAGE_RASTERIZATION`] (`setup.wgsl`, `scan.wgsl`, `args.wgsl`, `test.wgsl`): each
//!   caster triangle is set up as [`afsm::blockers::Blocker::new`] does (in `f64`, the same
//!   operations in the same order), the number of cells its bounding box covers is scanned
//!   over the triangles, and one invocation per (triangle, cell) item, dispatched indirectly,
//!   tests the cell's samples with the CPU's predicate
//!   ([`Blocker::shadows`](afsm::blockers::Blocker::shadows)): inside the bounding box,
//!   not the sample's own triangle, the caster's plane depth (clamped to its corners' range)
//!   in front of the sample's threshold, and inside the outline by `orient2d` with the
//!   top-left rule. A covered sample's pixel is marked by `atomicOr`. In `ftizb`'s passes
//!   ([`Izb::shadowed_and_hidden`]) the pixel is also marked hidden when the covering caster
//!   [`hides`] its sub-sample from the camera (`sample.wgsl` gives the camera ray through it).
//! - [`STAGE_UNDECIDED`]: `orient2d` is the robust crate's filter (its first stage, with the
//!   same error bound [`ORIENT2D_FILTER_BOUND`]); where it decides, it returns what the CPU's
//!   `orient2d` returns. The (sample, triangle) pairs it cannot decide (an edge test, or the
//!   triangle's winding) are appended to an undecided list (atomic counter) and resolved on
//!   the CPU by `Blocker::new(..).shadows(..)` itself (and, in `ftizb`'s passes, by
//!   [`hides`] where they shadow). The depth comparison needs no such
//!   care: its operands are computed bit for bit as on the CPU.
//!
//! The result is therefore the CPU `afsm`'s, pixel for pixel.
//!
//! [`Izb`] holds the pipelines and buffers of one frame and runs the stages for one
//! sub-sample of every pixel ([`SampleSurface`]); `afsm` runs it once, at the pixel centres,
//! `afsm-ss` ([`super::afsm_ss`]) once per sub-sample, and `ftizb` ([`super::ftizb`]) once per
//! sub-sample on the pixels' tangent planes. The casters' setup (the first part
//! of the rasterization of blockers) depends on the light only and runs once per frame.
//!
//! # Choices
//!
//! - **Grid.** [`grid_size`]: a square grid over the light image (`LIGHT_IMAGE_RES` square,
//!   to which the light's projector is fitted, so every surface point falls in it; points
//!   outside are clamped to the border cells), about [`PIXELS_PER_CELL`] pixels of the image
//!   per cell (35 x 35 cells at 160 x 120, 222 x 222 at 1024 x 768). The samples fill only
//!   part of the light image, so the cells they occupy hold more than that on average.
//! - **Footprint.** A triangle visits every cell its bounding box touches (conservative);
//!   the per-sample bounding-box test then admits exactly the samples the CPU's leaves test.
//! - **Culling.** Neither of the CPU's cullings runs (they never change a pixel); the
//!   options are accepted and recorded as the CPU's are.
//! - **Counters.** `sampling_points_tested` counts the samples inside a triangle's bounding
//!   box in the cells it visits, as the CPU counts them in its leaves (less the dark samples
//!   the CPU's occlusion culling skips), summed by `atomicAdd` on the GPU. The undecided
//!   pairs are counted in a note of the run record.
//! - **Transparency.** Semi-transparent casters attenuate in triangle order on the CPU; the
//!   GPU path takes opaque casters only and reports scenes with `transparency` as not
//!   applicable.

use super::{
    common::{ProjectorData, COMMON},
    shader::{compose, Part},
    GpuContext, GpuError, GpuFrame,
};
use crate::{
    afsm::{
        self, blockers::Blocker, samples::Sample, AfsmOptions, AliasFreeShadowMap, SHADOW_OFFSET,
        STAGE_RASTERIZATION, STAGE_TRANSFORMATION,
    },
    frame::Frame,
    ftizb::hidden::hides,
    method::{MethodError, ShadowMethod, Visibility},
    raster::NO_TRIANGLE,
};
use bytemuck::{Pod, Zeroable};
use glam::DVec2;
use instrumentation::Recorder;
use scenes::Projector;

/// Name of the stage that bins the samples into the grid.
pub const STAGE_IZB: &str = "IZB construction";
/// Name of the stage that resolves the undecided pairs on the CPU.
pub const STAGE_UNDECIDED: &str = "undecided tests (CPU)";

/// Pixels of the light image per grid cell (see [`grid_size`]).
pub const PIXELS_PER_CELL: u32 = 16;

/// The error bound of the robust crate's `orient2d` filter (its `THETA`): the sign of
/// `det` is certain when `|det| >= THETA * |detleft + detright|`.
pub const ORIENT2D_FILTER_BOUND: f64 = 3.3306690621773722e-16;

/// Cells per side of the grid for an image of `pixels` pixels: `ceil(sqrt(pixels / 16))`,
/// in `1..=4096`.
pub fn grid_size(pixels: usize) -> u32 {
    let cells = (pixels as f64 / f64::from(PIXELS_PER_CELL)).sqrt().ceil();
    cells.clamp(1.0, 4096.0) as u32
}

const WG: u32 = 64;

/// The kernels' WGSL: the grid's cell function is shared by the binning of samples and the
/// casters' setup.
const GRID: Part = Part::file("afsm/grid.wgsl", include_str!("afsm/grid.wgsl"));
/// The per-frame constants and the blocker records, as the kernels read them.
const LAYOUT: Part = Part::file("afsm/layout.wgsl", include_str!("afsm/layout.wgsl"));

/// The kernels' `f64` constants, the WGSL `FParams` of `layout.wgsl`: the shadow offset
/// ratio ([`SHADOW_OFFSET`]), the grid's cells per light-image unit along x and y,
/// `orient2d`'s filter bound, and the offset in its pixel of the sub-sample shaded
/// (written per pass by [`Izb::shadowed`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct FParams {
    offset: f64,
    cell_x: f64,
    cell_y: f64,
    filter_bound: f64,
    sub_x: f64,
    sub_y: f64,
}

/// The kernels' `u32` constants, the WGSL `UParams`: pixels, grid cells a side, triangles,
/// image width, and whether the pass's sample tests mark hidden sub-samples (1 in a pass of
/// [`Izb::shadowed_and_hidden`], else 0; written per pass).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct UParams {
    pixels: u32,
    grid: u32,
    triangles: u32,
    width: u32,
    hidden: u32,
}

/// A blocker's outline (up to four corners, `x` then `y`) and bounding box, the WGSL
/// `BlockerOutline` (outline and plane are apart so that each buffer stays within the
/// adapter's binding size limit).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct BlockerOutline {
    outline: [f64; 8],
    lo: [f64; 2],
    hi: [f64; 2],
}

/// A blocker's plane depth function (numerator and denominator coefficients) and depth
/// range, the WGSL `BlockerPlane`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct BlockerPlane {
    num: [f64; 3],
    den: [f64; 3],
    dmin: f64,
    dmax: f64,
}

/// A blocker's corner count (with a flag when its orientation was left undecided) and its
/// grid cell range, the WGSL `BlockerU`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct BlockerU {
    flags: u32,
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

super::layout::wgsl_mirror!(
    FParams,
    "FParams",
    compose(&[&LAYOUT]),
    [offset, cell_x, cell_y, filter_bound, sub_x, sub_y];
    UParams,
    "UParams",
    compose(&[&LAYOUT]),
    [pixels, grid, triangles, width, hidden];
    BlockerOutline,
    "BlockerOutline",
    compose(&[&LAYOUT]),
    [outline, lo, hi];
    BlockerPlane,
    "BlockerPlane",
    compose(&[&LAYOUT]),
    [num, den, dmin, dmax];
    BlockerU,
    "BlockerU",
    compose(&[&LAYOUT]),
    [flags, x0, y0, x1, y1];
);
/// The camera ray through a pixel's sub-sample and the shadow offset of a point on it.
const SAMPLE: Part = Part {
    name: "afsm/sample.wgsl",
    source: include_str!("afsm/sample.wgsl"),
    needs: &[&COMMON, &LAYOUT],
};
const TRANSFORM: Part = Part {
    name: "afsm/transform.wgsl",
    source: include_str!("afsm/transform.wgsl"),
    needs: &[&COMMON, &LAYOUT, &SAMPLE],
};
const IZB: Part = Part {
    name: "afsm/izb.wgsl",
    source: include_str!("afsm/izb.wgsl"),
    needs: &[&COMMON, &GRID, &LAYOUT],
};
const SETUP: Part = Part {
    name: "afsm/setup.wgsl",
    source: include_str!("afsm/setup.wgsl"),
    needs: &[&COMMON, &GRID, &LAYOUT],
};
const ARGS: Part =
    Part { name: "afsm/args.wgsl", source: include_str!("afsm/args.wgsl"), needs: &[&LAYOUT] };
const TEST: Part = Part {
    name: "afsm/test.wgsl",
    source: include_str!("afsm/test.wgsl"),
    needs: &[&COMMON, &LAYOUT, &SAMPLE],
};

/// The alias-free shadow map on the GPU (`afsm` with `--device gpu`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GpuAfsm {
    /// The CPU `afsm`'s options (rate 1; the culling switches have no effect here).
    pub options: AfsmOptions,
}

/// What [`shade`] returns.
#[derive(Debug, Clone, PartialEq)]
pub struct AfsmGpuOutput {
    /// Per pixel, 1 lit, 0 shadowed.
    pub lit: Vec<f32>,
    /// (Sample, triangle) pairs the GPU's filter could not decide, resolved on the CPU.
    pub undecided: u64,
    /// Cells per side of the grid.
    pub grid: u32,
}

/// The kernels of `afsm` for `frame` with its G-buffer and geometry in `gpu`: the light per
/// pixel; adds `sampling_points_tested` to `rec`'s counters and a note with the grid and the
/// undecided pairs. `frame` supplies the light, the camera (for the samples' shadow offsets)
/// and the triangles for the CPU's resolution of undecided pairs.
pub fn shade(
    ctx: &GpuContext,
    gpu: &GpuFrame,
    frame: &Frame<'_>,
    rec: &mut Recorder,
) -> Result<AfsmGpuOutput, MethodError> {
    let izb = Izb::new(ctx, gpu, frame);
    let surface =
        SampleSurface { triangle: &gpu.triangle, depth: &gpu.depth, offset: DVec2::splat(0.5) };
    let out = izb.shadowed(ctx, surface, rec)?;
    rec.counters.sampling_points_tested += out.tested;
    rec.notes.push(izb.note(out.undecided));
    let lit = out.shadowed.iter().map(|&s| if s == 0 { 1.0 } else { 0.0 }).collect();
    Ok(AfsmGpuOutput { lit, undecided: out.undecided, grid: izb.grid })
}

/// The camera's nearest surface at one sub-sample position of every pixel, on the GPU: what
/// the transformation of samples reads.
#[derive(Debug, Clone, Copy)]
pub struct SampleSurface<'a> {
    /// Triangle id per pixel (`NO_TRIANGLE` where the sub-sample sees no surface).
    pub triangle: &'a wgpu::Buffer,
    /// Depth per pixel: the parameter of the camera ray through `(i, j) + offset` where it
    /// meets the surface, `f64`.
    pub depth: &'a wgpu::Buffer,
    /// The sub-sample's position in its pixel (`(0.5, 0.5)` for the centre).
    pub offset: DVec2,
}

/// What [`Izb::shadowed`] gives for one sub-sample of every pixel.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowedSamples {
    /// Per pixel, 1 where the sub-sample is shadowed, else 0.
    pub shadowed: Vec<u32>,
    /// Per pixel, 1 where some caster that shadows the sub-sample also hides it from the
    /// camera (`ftizb`'s rule, [`hides`]), else 0; all 0 in a pass of [`Izb::shadowed`].
    pub hidden: Vec<u32>,
    /// (Sample, triangle) pairs the GPU's filter could not decide, resolved on the CPU.
    pub undecided: u64,
    /// Samples tested against a triangle (`sampling_points_tested`).
    pub tested: u64,
}

/// The irregular z-buffer of one frame: its pipelines and buffers, made once and used for
/// every sub-sample (`afsm` has one, `afsm-ss` `rate`). The casters' setup depends on the
/// light only, so it runs once, in the first sub-sample's rasterization of blockers.
pub struct Izb<'a> {
    frame: &'a Frame<'a>,
    light: Projector,
    /// Cells per side of the grid.
    pub grid: u32,
    pixels: usize,
    fparams: wgpu::Buffer,
    /// The transformation's inputs but the surface: light, fparams, uparams, then after the
    /// surface's two, the outputs and the camera (bindings 5, 6, 7).
    transform_io: [wgpu::Buffer; 6],
    transform: wgpu::ComputePipeline,
    count: Kernel,
    scatter: Kernel,
    cell_start: wgpu::Buffer,
    cell_scan: super::scan::PreparedScan,
    setup: Kernel,
    items_scan: super::scan::PreparedScan,
    args: Kernel,
    args_buf: wgpu::Buffer,
    test: wgpu::ComputePipeline,
    /// `test.wgsl`'s first ten bindings.
    test_inputs: [wgpu::Buffer; 10],
    /// The triangles' corners, which the hidden test reads.
    corners: wgpu::Buffer,
    /// The tests' counters and undecided list, cleared for every sub-sample.
    pairs: TestBuffers,
    set_up: std::cell::Cell<bool>,
}

/// A pipeline and its bind group.
struct Kernel {
    pipeline: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
}

impl Kernel {
    fn new(ctx: &GpuContext, pipeline: wgpu::ComputePipeline, buffers: &[&wgpu::Buffer]) -> Self {
        let bind = ctx.bind(&pipeline, buffers);
        Self { pipeline, bind }
    }

    fn dispatch(&self, e: &mut wgpu::CommandEncoder, groups: (u32, u32, u32)) {
        GpuContext::dispatch(e, &self.pipeline, &self.bind, groups);
    }
}

impl<'a> Izb<'a> {
    /// Compiles the kernels and allocates the buffers for `frame`, whose geometry is in `gpu`;
    /// the light is [`afsm::light_projector`]'s.
    pub fn new(ctx: &GpuContext, gpu: &GpuFrame, frame: &'a Frame<'a>) -> Self {
        let light = afsm::light_projector(frame);
        let pixels = gpu.pixels();
        let grid = grid_size(pixels);
        let triangles = gpu.triangles as usize;
        let cells = grid as usize * grid as usize;
        let light_buf = ctx.upload("afsm light", &[ProjectorData::new(&light)]);
        // The last two are the sub-sample's offset in its pixel, written by `shadowed`.
        let fparams = ctx.upload(
            "afsm fparams",
            &[FParams {
                offset: SHADOW_OFFSET,
                cell_x: f64::from(grid) / light.width,
                cell_y: f64::from(grid) / light.height,
                filter_bound: ORIENT2D_FILTER_BOUND,
                sub_x: 0.5,
                sub_y: 0.5,
            }],
        );
        let uparams = ctx.upload(
            "afsm uparams",
            &[UParams {
                pixels: pixels as u32,
                grid,
                triangles: gpu.triangles,
                width: frame.width(),
                hidden: 0,
            }],
        );
        let camera = ctx.upload("afsm camera", &[ProjectorData::new(&frame.camera)]);
        let scan = super::scan::Scan::new(ctx);
        let transform = ctx.pipeline("afsm transform", &compose(&[&TRANSFORM]), "transform");
        let sample_f = ctx.zeroed::<f64>("afsm sample xyz", 3 * pixels);
        let sample_tri = ctx.zeroed::<u32>("afsm sample triangle", pixels);

        let izb_src = compose(&[&IZB]);
        let slot = ctx.zeroed::<u32>("afsm slot", 2 * pixels);
        let cell_start = ctx.zeroed::<u32>("afsm cells", cells + 1);
        let samples = ctx.zeroed::<u32>("afsm samples", 1);
        let izb_f = ctx.zeroed::<f64>("afsm izb xyz", 3 * pixels);
        let izb_u = ctx.zeroed::<u32>("afsm izb ids", 2 * pixels);
        let izb_bufs =
            [&fparams, &uparams, &sample_f, &sample_tri, &slot, &cell_start, &izb_f, &izb_u];
        let count = Kernel::new(ctx, ctx.pipeline("afsm count", &izb_src, "count"), &izb_bufs);
        let scatter =
            Kernel::new(ctx, ctx.pipeline("afsm scatter", &izb_src, "scatter"), &izb_bufs);
        let cell_scan = scan.prepare(ctx, &cell_start, cells + 1, &samples);

        let blk_outline = ctx.zeroed::<BlockerOutline>("afsm blocker outlines", triangles);
        let blk_plane = ctx.zeroed::<BlockerPlane>("afsm blocker planes", triangles);
        let blk_u = ctx.zeroed::<BlockerU>("afsm blockers u32", triangles);
        let items = ctx.zeroed::<u32>("afsm items", triangles + 1);
        let items_total = ctx.zeroed::<u32>("afsm items total", 1);
        let setup = Kernel::new(
            ctx,
            ctx.pipeline("afsm setup", &compose(&[&SETUP]), "setup"),
            &[
                &light_buf,
                &fparams,
                &uparams,
                &gpu.corners,
                &gpu.casters,
                &blk_outline,
                &blk_plane,
                &blk_u,
                &items,
            ],
        );
        let items_scan = scan.prepare(ctx, &items, triangles + 1, &items_total);
        let args_buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("afsm test dispatch"),
            size: 12,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
            mapped_at_creation: false,
        });
        let args = Kernel::new(
            ctx,
            ctx.pipeline("afsm args", &compose(&[&ARGS]), "args_main"),
            &[&uparams, &items, &args_buf],
        );
        let test = ctx.pipeline("afsm test", &compose(&[&TEST]), "test");
        let shadow = ctx.zeroed::<u32>("afsm shadow", pixels);
        let test_inputs = [
            fparams.clone(),
            uparams.clone(),
            items,
            blk_outline,
            blk_plane,
            blk_u,
            cell_start.clone(),
            izb_f,
            izb_u,
            shadow,
        ];
        let pairs = TestBuffers::new(ctx, pixels.max(4096));
        Self {
            frame,
            light,
            grid,
            pixels,
            transform_io: [light_buf, fparams.clone(), uparams, sample_f, sample_tri, camera],
            transform,
            count,
            scatter,
            cell_scan,
            setup,
            items_scan,
            args,
            args_buf,
            test,
            test_inputs,
            corners: gpu.corners.clone(),
            pairs,
            cell_start,
            fparams,
            set_up: std::cell::Cell::new(false),
        }
    }

    /// Which pixels' sub-sample on `surface` are shadowed: the transformation of samples, the
    /// IZB construction and the rasterization of blockers on the GPU (one stage each, timed
    /// into `rec`), then the undecided pairs on the CPU ([`STAGE_UNDECIDED`]).
    pub fn shadowed(
        &self,
        ctx: &GpuContext,
        surface: SampleSurface<'_>,
        rec: &mut Recorder,
    ) -> Result<ShadowedSamples, MethodError> {
        self.pass(ctx, surface, false, rec)
    }

    /// As [`Izb::shadowed`], and which of the shadowed sub-samples are hidden from the camera
    /// (`ftizb`'s rule for its sub-samples but the centre): some caster that shadows the
    /// sub-sample (in the GPU's tests or the CPU's undecided ones) [`hides`] it, on the camera
    /// ray through its pixel's corner plus `surface.offset` at `surface.depth`, with its shadow
    /// offset ([`afsm::shadow_offset`]).
    pub fn shadowed_and_hidden(
        &self,
        ctx: &GpuContext,
        surface: SampleSurface<'_>,
        rec: &mut Recorder,
    ) -> Result<ShadowedSamples, MethodError> {
        self.pass(ctx, surface, true, rec)
    }

    /// A pass of [`Izb::shadowed`] (`hidden` false) or [`Izb::shadowed_and_hidden`].
    fn pass(
        &self,
        ctx: &GpuContext,
        surface: SampleSurface<'_>,
        hidden: bool,
        rec: &mut Recorder,
    ) -> Result<ShadowedSamples, MethodError> {
        let pixels = self.pixels;
        let groups = GpuContext::groups_1d(pixels, WG);
        ctx.queue.write_buffer(
            &self.fparams,
            std::mem::offset_of!(FParams, sub_x) as u64,
            bytemuck::cast_slice(&[surface.offset.x, surface.offset.y]),
        );
        let [_, _, uparams_buf, _, _, camera_buf] = &self.transform_io;
        ctx.queue.write_buffer(
            uparams_buf,
            std::mem::offset_of!(UParams, hidden) as u64,
            bytemuck::cast_slice(&[u32::from(hidden)]),
        );
        let camera_side = [camera_buf, &self.corners, surface.depth];

        // Transformation of samples.
        let [light, fparams, uparams, sample_f, sample_tri, camera] = &self.transform_io;
        let bind = ctx.bind(
            &self.transform,
            &[
                light,
                fparams,
                uparams,
                surface.triangle,
                surface.depth,
                sample_f,
                sample_tri,
                camera,
            ],
        );
        ctx.stage(rec, STAGE_TRANSFORMATION, |e| {
            GpuContext::dispatch(e, &self.transform, &bind, groups);
        })?;

        // IZB construction.
        ctx.stage(rec, STAGE_IZB, |e| {
            e.clear_buffer(&self.cell_start, 0, None);
            self.count.dispatch(e, groups);
            self.cell_scan.record(e);
            self.scatter.dispatch(e, groups);
        })?;

        // Rasterization of blockers.
        let set_up = self.set_up.replace(true);
        // `test.wgsl`'s binding 9: per pixel, whether its sample is shadowed.
        let [.., shadow] = &self.test_inputs;
        let triangles = self.frame.geometry.triangles.len();
        let indirect = |e: &mut wgpu::CommandEncoder, bind: &wgpu::BindGroup| {
            let mut pass = e.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: None,
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.test);
            pass.set_bind_group(0, bind, &[]);
            pass.dispatch_workgroups_indirect(&self.args_buf, 0);
        };
        let bind_test = self.pairs.bind(ctx, &self.test, &self.test_inputs, camera_side);
        ctx.stage(rec, STAGE_RASTERIZATION, |e| {
            if !set_up {
                self.setup.dispatch(e, GpuContext::groups_1d(triangles, WG));
                self.items_scan.record(e);
                self.args.dispatch(e, (1, 1, 1));
            }
            e.clear_buffer(shadow, 0, None);
            e.clear_buffer(&self.pairs.counters, 0, None);
            indirect(e, &bind_test);
        })?;
        let (mut tested, mut undecided) = self.pairs.counts(ctx)?;
        let larger;
        let mut pairs = &self.pairs;
        if undecided > pairs.capacity {
            // The list overflowed: the samples are tested again with room for every pair
            // (marking a shadowed pixel twice changes nothing), timed as part of the stage.
            larger = TestBuffers::new(ctx, undecided);
            pairs = &larger;
            let bind = pairs.bind(ctx, &self.test, &self.test_inputs, camera_side);
            ctx.stage(rec, STAGE_RASTERIZATION, |e| indirect(e, &bind))?;
            (tested, undecided) = pairs.counts(ctx)?;
        }
        // Bit 1: shadowed; bit 2: hidden.
        let marks: Vec<u32> = ctx.read(shadow)?;
        let mut shadowed: Vec<u32> = marks.iter().take(pixels).map(|&m| m & 1).collect();
        let mut hidden_out: Vec<u32> = marks.iter().take(pixels).map(|&m| m >> 1 & 1).collect();

        // Undecided tests (CPU).
        let (pf, pu): (Vec<f64>, Vec<u32>) = if undecided > 0 {
            (ctx.read(&pairs.und_f)?, ctx.read(&pairs.und_u)?)
        } else {
            (Vec::new(), Vec::new())
        };
        // The sub-samples' depths, for the hidden test of the pairs found shadowing.
        let depth: Vec<f64> =
            if hidden && undecided > 0 { ctx.read(surface.depth)? } else { Vec::new() };
        let width = self.frame.width() as usize;
        rec.stages.time(STAGE_UNDECIDED, || {
            for k in 0..undecided {
                let (pixel, t) = (pu[3 * k] as usize, pu[3 * k + 2] as usize);
                let s = Sample {
                    x: pf[3 * k],
                    y: pf[3 * k + 1],
                    zt: pf[3 * k + 2],
                    id: pixel as u32,
                    tri: pu[3 * k + 1],
                };
                if Blocker::new(&self.frame.geometry, t, &self.light).is_some_and(|b| b.shadows(&s))
                {
                    shadowed[pixel] = 1;
                    if hidden {
                        let (i, j) = ((pixel % width) as f64, (pixel / width) as f64);
                        let ray = self.frame.camera.ray(DVec2::new(i, j) + surface.offset);
                        let ts = depth[pixel];
                        let offset = afsm::shadow_offset(ray.origin, ray.at(ts));
                        if hides(&ray, ts, offset, self.frame.geometry.corners(t)) {
                            hidden_out[pixel] = 1;
                        }
                    }
                }
            }
        });
        Ok(ShadowedSamples { shadowed, hidden: hidden_out, undecided: undecided as u64, tested })
    }

    /// Leaves every (sample, caster) pair that passes the depth test undecided from now on (the
    /// filter's error bound made infinite, so that no edge test and no caster's winding is
    /// certain), so the CPU resolves them all, hidden test included: for parity tests of the
    /// CPU's resolution against the GPU's decisions. Effective for every caster only when
    /// called before the first pass (which sets the casters up).
    pub fn leave_every_pair_undecided(&self, ctx: &GpuContext) {
        ctx.queue.write_buffer(
            &self.fparams,
            std::mem::offset_of!(FParams, filter_bound) as u64,
            bytemuck::cast_slice(&[f64::INFINITY]),
        );
    }

    /// The samples the last transformation of samples wrote, read back as the CPU's
    /// [`afsm::samples::transform_samples`] gives them for sub-sample `s` of `rate` (ids
    /// `pixel * rate + s`, pixels without a sample left out): for stage-by-stage parity tests.
    pub fn samples(&self, ctx: &GpuContext, s: u32, rate: u32) -> Result<Vec<Sample>, GpuError> {
        let [_, _, _, sample_f, sample_tri, _] = &self.transform_io;
        let f: Vec<f64> = ctx.read(sample_f)?;
        let tri: Vec<u32> = ctx.read(sample_tri)?;
        Ok((0..self.pixels)
            .filter(|&k| tri[k] != NO_TRIANGLE)
            .map(|k| Sample {
                x: f[3 * k],
                y: f[3 * k + 1],
                zt: f[3 * k + 2],
                id: k as u32 * rate + s,
                tri: tri[k],
            })
            .collect())
    }

    /// Per pixel, whether the last transformation of samples gave it a sample: its surface
    /// has a triangle there and the light projects the point to a finite light image point
    /// with a finite threshold depth. These are the samples a pass tests, over which a
    /// supersampled method takes its ratio (`ftizb`'s valid sub-samples).
    pub fn sampled(&self, ctx: &GpuContext) -> Result<Vec<bool>, GpuError> {
        let [_, _, _, _, sample_tri, _] = &self.transform_io;
        let tri: Vec<u32> = ctx.read(sample_tri)?;
        Ok(tri.iter().take(self.pixels).map(|&t| t != NO_TRIANGLE).collect())
    }

    /// The run record's note on the grid and the `undecided` pairs.
    pub fn note(&self, undecided: u64) -> String {
        let grid = self.grid;
        format!(
            "afsm (GPU): {grid} x {grid} grid cells over the light image; {undecided} undecided \
             (sample, triangle) pairs resolved on the CPU"
        )
    }
}

/// Refuses a frame with semi-transparent casters, which `method`'s CPU twin attenuates in
/// triangle order; the GPU kernels take opaque casters only.
pub(super) fn opaque_casters_only(frame: &Frame<'_>, method: &str) -> Result<(), MethodError> {
    if frame.effects.transparency {
        return Err(MethodError::NotApplicable(format!(
            "{method} on the GPU takes opaque casters only: semi-transparent casters attenuate \
             in triangle order (run it with --device cpu)"
        )));
    }
    Ok(())
}

/// The counters and the undecided list of the sample tests.
struct TestBuffers {
    /// Room for this many undecided pairs.
    capacity: usize,
    /// Tests (low and high word) and undecided pairs.
    counters: wgpu::Buffer,
    /// Undecided pairs: light image x, y and threshold depth.
    und_f: wgpu::Buffer,
    /// Undecided pairs: pixel, sample triangle, caster triangle.
    und_u: wgpu::Buffer,
}

impl TestBuffers {
    /// Zeroed counters and a list with room for `capacity` pairs.
    fn new(ctx: &GpuContext, capacity: usize) -> Self {
        Self {
            capacity,
            counters: ctx.zeroed::<u32>("afsm counters", 3),
            und_f: ctx.zeroed::<f64>("afsm undecided xyz", 3 * capacity),
            und_u: ctx.zeroed::<u32>("afsm undecided ids", 3 * capacity),
        }
    }

    /// The bind group of `test.wgsl`: its first ten buffers, then these, then the hidden
    /// test's `camera_side` (camera, corners, the sub-samples' depths).
    fn bind(
        &self,
        ctx: &GpuContext,
        test: &wgpu::ComputePipeline,
        first: &[wgpu::Buffer; 10],
        camera_side: [&wgpu::Buffer; 3],
    ) -> wgpu::BindGroup {
        let mut all: Vec<&wgpu::Buffer> = first.iter().collect();
        all.extend([&self.counters, &self.und_f, &self.und_u]);
        all.extend(camera_side);
        ctx.bind(test, &all)
    }

    /// The tests made and the undecided pairs found.
    fn counts(&self, ctx: &GpuContext) -> Result<(u64, usize), GpuError> {
        let c: Vec<u32> = ctx.read(&self.counters)?;
        Ok((u64::from(c[0]) | u64::from(c[1]) << 32, c[2] as usize))
    }
}

impl GpuAfsm {
    /// The CPU method with the same options.
    fn twin(&self) -> AliasFreeShadowMap {
        AliasFreeShadowMap::pixel_centres(self.options)
    }
}

impl ShadowMethod for GpuAfsm {
    fn name(&self) -> &'static str {
        self.twin().name()
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        super::twin_params(&self.twin())
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        self.twin().validate()?;
        opaque_casters_only(frame, self.name())?;
        let ctx = GpuContext::shared()?;
        ctx.describe(rec);
        let gpu = GpuFrame::for_run(ctx, frame, rec)?;
        let out = shade(ctx, &gpu, frame, rec)?;
        Ok(Visibility {
            width: frame.width(),
            height: frame.height(),
            lit: out.lit,
            transmittance: None,
        })
    }
}
