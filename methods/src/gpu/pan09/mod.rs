//! `pan09` on the GPU: Pan, Wang, Chen, Zhou and Bao 2009, "Fast, Sub-pixel Antialiased
//! Shadow Maps", Computer Graphics Forum 28(7), Pacific Graphics 2009), the
//! pipeline of its Fig. 2 as compute passes, stage by stage the CPU twin's
//! ([`crate::pan09`], whose module doc lists every choice), in `f64` with the CPU's
//! operations in the CPU's order.
//!
//! # Stages (same names as the CPU's)
//!
//! | stage | GPU formulation | files |
//! |---|---|---|
//! | edge adjacency (per scene) | on the CPU ([`crate::pan09::silhouette::EdgeAdjacency`]), uploaded | [`silhouette`] |
//! | silhouette extraction | one invocation per edge, silhouettes appended with an atomic counter | `silhouette.wgsl` |
//! | silhouette mask map | one invocation per silhouette edge: conservative rasterization, the nine-sample hidden-depth test, marks by atomic exchange | `mask_map.wgsl` |
//! | summed-area table | one invocation per row (scan), then per column | `sat.wgsl` |
//! | pixel facets | per pixel: facet, footprint, SAT count; scan of the silhouette flags into facet numbers; per silhouette pixel: its record | `facets.wgsl` |
//! | depth test | per pixel of the depth test's class | `depth_test.wgsl` |
//! | pixel-texel pairs | count, scan, emit, test, count per texel, scan, scatter | `pt_pairs.wgsl` |
//! | triangle-texel pairs | busy texels and their SAT, count, scan, emit, test, scan, compact | `tt_pairs.wgsl` |
//! | visibility evaluation | per TT-pair, lookup table in a storage buffer, `atomicOr` into `u32` mask words | `visibility.wgsl` |
//! | validity mask (curved receivers only, else skipped) | per candidate, `atomicAnd` | `validity.wgsl` |
//! | occlusion ratio | per facet | `ratio.wgsl` |
//!
//! Masks are `u32` words: 1 at rate 32 (and below), 2 at 64, 4 at 128. The geometry shared by
//! the stages is in `pan09.wgsl`; `params.wgsl` reads the per-frame constants ([`params`]),
//! `coverage.wgsl` the table (or, in exact mode, the sub-samples one by one).
//!
//! # Choices
//!
//! - **Per-frame constants from the CPU.** The camera's screen basis and the light's planes
//!   seen by it (a few dozen numbers per frame, like the projectors) are computed by the CPU
//!   twin's own code and uploaded; everything per pixel, texel, edge, triangle or pair runs on
//!   the GPU.
//! - **Orders.** The CPU sorts the keys of the PT lists by texel then facet and the TT-pairs
//!   by PT-list length for load balance. Here the lists are filled by a counting sort on the
//!   texel (the order inside one texel's list is the atomics'), and the TT-pairs stay in the
//!   order they were emitted (triangle by triangle). Neither order changes a result: every
//!   evaluation ORs into an occlusion mask, every validity candidate ANDs into a validity
//!   mask, and both are commutative and idempotent; the counters are sums.
//! - **Sizes read back.** The number of silhouette edges, facets and keys emitted are read
//!   back between the parts of a stage to size the next buffers; a stage submitted in two
//!   parts is timed as the sum of both. The validity candidates are bounded by the
//!   TT-pairs' PT-list lengths summed (counted in the TT stage).
//! - **Hidden depths** are computed where an edge needs them instead of remembered (same
//!   values as the CPU's memo).
//! - **Exact predicates.** The CPU's `pan09` makes every decision in plain `f64` (no adaptive
//!   predicate), so nothing is handed back to the CPU.
//! - **Counters** are `u32` atomics, read back into the run's `u64` counters.

mod depth_test;
mod facets;
mod mask_map;
mod pairs;
mod params;
mod ratio;
mod sat;
mod scan;
mod silhouette;
mod validity;
mod visibility;

use super::{
    common::COMMON,
    shader::{compose, Part},
    GpuContext, GpuDepthMap, GpuError, GpuFrame,
};
use crate::{
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    pan09::{
        facets::PixelClass, lut::LookupTable, mask::Mask, silhouette::EdgeAdjacency, Pan09Options,
        StageOutputs, SubsampleMasks, VisibilityMode, STAGE_EDGE_ADJACENCY, STAGE_LIGHT_DEPTH_MAP,
        STAGE_VALIDITY,
    },
    pattern::SamplePattern,
};
use instrumentation::Recorder;
use params::slot;
use std::sync::{Arc, OnceLock};

/// The geometry shared by the stages, first in every stage's shader.
const LIB: Part =
    Part { name: "pan09/pan09.wgsl", source: include_str!("pan09.wgsl"), needs: &[&COMMON] };
const PARAMS: Part = Part::file("pan09/params.wgsl", include_str!("params.wgsl"));
const COVERAGE: Part = Part::file("pan09/coverage.wgsl", include_str!("coverage.wgsl"));
const FACET_LAYOUT: Part = Part {
    name: "pan09/facet_layout.wgsl",
    source: include_str!("facet_layout.wgsl"),
    needs: &[&COMMON],
};
const FACET_RECORD: Part = Part {
    name: "pan09/facet_record.wgsl",
    source: include_str!("facet_record.wgsl"),
    needs: &[&FACET_LAYOUT],
};

/// The compiled kernels.
#[derive(Debug)]
struct Kernels {
    scan: crate::gpu::scan::Scan,
    silhouette: wgpu::ComputePipeline,
    mask_map: wgpu::ComputePipeline,
    sat_rows: wgpu::ComputePipeline,
    sat_cols: wgpu::ComputePipeline,
    facets_classify: wgpu::ComputePipeline,
    facets_build: wgpu::ComputePipeline,
    depth_test: wgpu::ComputePipeline,
    pt_count: wgpu::ComputePipeline,
    pt_emit: wgpu::ComputePipeline,
    pt_test: wgpu::ComputePipeline,
    pt_scatter: wgpu::ComputePipeline,
    tt_busy: wgpu::ComputePipeline,
    tt_count: wgpu::ComputePipeline,
    tt_count_rows: wgpu::ComputePipeline,
    tt_emit: wgpu::ComputePipeline,
    tt_test: wgpu::ComputePipeline,
    tt_compact: wgpu::ComputePipeline,
    visibility: wgpu::ComputePipeline,
    validity: wgpu::ComputePipeline,
    ratio: wgpu::ComputePipeline,
}

impl Kernels {
    fn new(ctx: &GpuContext) -> Self {
        // A stage's shader: the shared geometry, the parts it needs, then its own file.
        let with = |needs: &[&Part], name: &'static str, source: &'static str| -> String {
            let own = Part::file(name, source);
            let mut parts = vec![&LIB];
            parts.extend_from_slice(needs);
            parts.push(&own);
            compose(&parts)
        };
        let evaluation: &[&Part] = &[&PARAMS, &COVERAGE, &FACET_RECORD];
        let sat = with(&[], "pan09/sat.wgsl", include_str!("sat.wgsl"));
        let silhouette = with(&[&PARAMS], "pan09/silhouette.wgsl", include_str!("silhouette.wgsl"));
        let mask_map = with(&[&PARAMS], "pan09/mask_map.wgsl", include_str!("mask_map.wgsl"));
        let facets =
            with(&[&PARAMS, &FACET_LAYOUT], "pan09/facets.wgsl", include_str!("facets.wgsl"));
        let depth_test = with(&[&PARAMS], "pan09/depth_test.wgsl", include_str!("depth_test.wgsl"));
        let pt = with(&[&FACET_RECORD], "pan09/pt_pairs.wgsl", include_str!("pt_pairs.wgsl"));
        let tt = with(&[&PARAMS], "pan09/tt_pairs.wgsl", include_str!("tt_pairs.wgsl"));
        let visibility = with(evaluation, "pan09/visibility.wgsl", include_str!("visibility.wgsl"));
        let validity = with(evaluation, "pan09/validity.wgsl", include_str!("validity.wgsl"));
        let ratio = with(evaluation, "pan09/ratio.wgsl", include_str!("ratio.wgsl"));
        let p = |label: &str, src: &str, entry: &str| ctx.pipeline(label, src, entry);
        Self {
            scan: crate::gpu::scan::Scan::new(ctx),
            silhouette: p("pan09 silhouette", &silhouette, "main"),
            mask_map: p("pan09 mask map", &mask_map, "main"),
            sat_rows: p("pan09 sat rows", &sat, "rows"),
            sat_cols: p("pan09 sat cols", &sat, "cols"),
            facets_classify: p("pan09 facets classify", &facets, "classify"),
            facets_build: p("pan09 facets build", &facets, "build"),
            depth_test: p("pan09 depth test", &depth_test, "main"),
            pt_count: p("pan09 pt count", &pt, "count"),
            pt_emit: p("pan09 pt emit", &pt, "emit"),
            pt_test: p("pan09 pt test", &pt, "test"),
            pt_scatter: p("pan09 pt scatter", &pt, "scatter"),
            tt_busy: p("pan09 tt busy", &tt, "mark_busy"),
            tt_count: p("pan09 tt count", &tt, "count"),
            tt_count_rows: p("pan09 tt count rows", &tt, "count_rows"),
            tt_emit: p("pan09 tt emit", &tt, "emit"),
            tt_test: p("pan09 tt test", &tt, "test"),
            tt_compact: p("pan09 tt compact", &tt, "compact"),
            visibility: p("pan09 visibility", &visibility, "main"),
            validity: p("pan09 validity", &validity, "main"),
            ratio: p("pan09 ratio", &ratio, "main"),
        }
    }
}

/// What every stage of one run reads.
struct Run<'a> {
    ctx: &'a GpuContext,
    frame: &'a GpuFrame,
    map: &'a GpuDepthMap,
    /// The run's constants, one [`params::Params`] (`params.wgsl`).
    params: wgpu::Buffer,
    /// Counter slots ([`params::slot`]).
    counters: wgpu::Buffer,
    /// Lookup table, `words` per entry (one placeholder word in exact mode).
    lut: wgpu::Buffer,
    /// Mask words per pixel.
    words: u32,
}

/// The counters buffer read back.
fn read_counters(ctx: &GpuContext, counters: &wgpu::Buffer) -> Result<Vec<u32>, GpuError> {
    ctx.read(counters)
}

/// The one word of a scan's total.
fn read_total(ctx: &GpuContext, total: &wgpu::Buffer) -> Result<u32, GpuError> {
    Ok(ctx.read::<u32>(total)?[0])
}

/// `pan09` on the GPU (`--device gpu`); see the module doc.
#[derive(Debug, Clone)]
pub struct GpuPan09 {
    options: Pan09Options,
    pattern: SamplePattern,
    /// The lookup table as `u32` words (table mode).
    table: Option<Arc<Vec<u32>>>,
    kernels: Arc<OnceLock<Kernels>>,
}

impl GpuPan09 {
    /// `pan09` on the GPU with `options`, validated as [`crate::pan09::Pan09::new`] does; in
    /// table mode the lookup table is precomputed here (by the CPU twin's code).
    pub fn new(options: Pan09Options) -> Result<Self, MethodError> {
        options.validate()?;
        let pattern = SamplePattern::new(options.rate, options.pattern)?;
        let words = params::words(options.rate) as usize;
        let table = (options.visibility == VisibilityMode::Table).then(|| {
            let t = LookupTable::<u128>::new(&pattern);
            Arc::new(
                t.masks().iter().flat_map(|&m| params::to_words(m)[..words].to_vec()).collect(),
            )
        });
        Ok(Self { options, pattern, table, kernels: Arc::new(OnceLock::new()) })
    }

    /// The options.
    pub fn options(&self) -> &Pan09Options {
        &self.options
    }

    /// Runs the method and also returns every pixel's sub-sample masks (as
    /// [`crate::pan09::Pan09::run_masks`]).
    pub fn run_masks(
        &self,
        frame: &Frame<'_>,
        rec: &mut Recorder,
    ) -> Result<(Visibility, SubsampleMasks), MethodError> {
        self.options.validate()?;
        let ctx = GpuContext::shared()?;
        ctx.describe(rec);
        let gframe = GpuFrame::for_run(ctx, frame, rec)?;
        let res = self.options.map.map_res;
        let fit = self.options.map.frustum;
        let map = GpuDepthMap::for_run(
            ctx,
            frame,
            res,
            fit,
            glam::DVec2::ZERO,
            STAGE_LIGHT_DEPTH_MAP,
            rec,
        )?;
        self.run_kernels(ctx, frame, &gframe, &map, rec)
    }

    /// The stages after the light depth map, on `gframe` (the frame's G-buffer) and `map` (the
    /// light depth map at the options' resolution): what [`GpuPan09::run_masks`] runs, for
    /// parity tests to feed the CPU's own G-buffer and map.
    pub fn run_kernels(
        &self,
        ctx: &GpuContext,
        frame: &Frame<'_>,
        gframe: &GpuFrame,
        map: &GpuDepthMap,
        rec: &mut Recorder,
    ) -> Result<(Visibility, SubsampleMasks), MethodError> {
        self.run_probed(ctx, frame, gframe, map, rec, None)
    }

    /// What the stages up to the triangle-texel pairs wrote, read back: the twin of
    /// [`crate::pan09::Pan09::stage_outputs`], on the same inputs as [`Self::run_kernels`].
    pub fn stage_outputs(
        &self,
        ctx: &GpuContext,
        frame: &Frame<'_>,
        gframe: &GpuFrame,
        map: &GpuDepthMap,
        rec: &mut Recorder,
    ) -> Result<StageOutputs, MethodError> {
        let mut out = StageOutputs::default();
        self.run_probed(ctx, frame, gframe, map, rec, Some(&mut out))?;
        Ok(out)
    }

    /// [`Self::run_kernels`], reading the early stages' outputs back into `probe` when given.
    fn run_probed(
        &self,
        ctx: &GpuContext,
        frame: &Frame<'_>,
        gframe: &GpuFrame,
        map: &GpuDepthMap,
        rec: &mut Recorder,
        mut probe: Option<&mut StageOutputs>,
    ) -> Result<(Visibility, SubsampleMasks), MethodError> {
        if map.res != self.options.map.map_res {
            return Err(MethodError::NotApplicable(format!(
                "pan09 on the GPU: a {0} x {0} map given for --map-res {1}",
                map.res, self.options.map.map_res
            )));
        }
        if frame.effects.transparency {
            rec.notes.push("pan09 treats semi-transparent casters as opaque".into());
        }
        let k = self.kernels.get_or_init(|| Kernels::new(ctx));
        let words = params::words(self.options.rate);
        let params = params::Params::new(frame, &map.projector, &self.options, &self.pattern);
        let tester = crate::depth_test::DepthTester::new(
            &self.options.map,
            map.projector,
            frame.light_depth_range(&map.projector),
        );
        rec.warnings.extend(tester.warnings("pan09", frame, crate::footprint::Sampling::PixelArea));
        let run = Run {
            ctx,
            frame: gframe,
            map,
            params: ctx.upload("pan09 params", &[params]),
            counters: ctx.zeroed::<u32>("pan09 counters", slot::COUNT),
            lut: match &self.table {
                Some(t) => ctx.upload("lookup table", t),
                None => ctx.zeroed::<u32>("no lookup table", 1),
            },
            words,
        };
        let geometry = &frame.geometry;
        let adjacency = rec
            .stages
            .time(STAGE_EDGE_ADJACENCY, || EdgeAdjacency::new(geometry, |t| frame.is_caster(t)));
        let positions: Vec<f64> = geometry.positions.iter().flat_map(|p| p.to_array()).collect();
        let positions = ctx.upload("positions", &positions);
        let adjacency_buf = ctx.upload("edge adjacency", &silhouette::adjacency_data(&adjacency));
        let edges = silhouette::run(&run, k, &positions, &adjacency_buf, adjacency.len(), rec)?;
        let edge_count = read_counters(ctx, &run.counters)?[slot::EDGES];
        let marks = mask_map::run(&run, k, &edges, edge_count, rec)?;
        let sat = run
            .ctx
            .stage(rec, crate::pan09::STAGE_SAT, |e| sat::record(ctx, k, e, &marks, map.res))?;
        let facets = facets::run(&run, k, &sat, rec)?;
        let lit = depth_test::run(&run, k, &facets.class, rec)?;
        if let Some(probe) = probe.as_deref_mut() {
            let res = map.res as usize;
            probe.silhouette_edges = edge_count as usize;
            probe.mask = ctx.read::<u32>(&marks)?[..res * res].iter().map(|&m| m != 0).collect();
            probe.sat = ctx.read::<u32>(&sat)?[..(res + 1) * (res + 1)].to_vec();
            let pixels = gframe.pixels();
            probe.class =
                ctx.read::<u32>(&facets.class)?[..pixels].iter().map(|&c| c as u8).collect();
            let fu: Vec<facets::FacetU> = ctx.read(&facets.fu)?;
            probe.facet_pixels = fu[..facets.count as usize].iter().map(|r| r.pixel).collect();
            probe.depth_test_lit = ctx.read::<f32>(&lit)?[..pixels].to_vec();
        }
        let pt = pairs::pixel_texel_pairs(&run, k, &facets, rec)?;
        let tt = pairs::triangle_texel_pairs(&run, k, &pt, rec)?;
        if let Some(probe) = probe {
            let c = read_counters(ctx, &run.counters)?;
            probe.pairs = (u64::from(c[slot::PT_PAIRS]), u64::from(c[slot::TT_PAIRS]));
        }
        let curved = frame.effects.curved_receivers;
        let capacity =
            if curved { read_counters(ctx, &run.counters)?[slot::EVALUATION_BOUND] } else { 0 };
        let (masks, candidates) =
            visibility::run(&run, k, (&tt.0, tt.1), &pt, &facets, capacity, rec)?;
        if curved {
            let noted = read_counters(ctx, &run.counters)?[slot::CANDIDATES].min(capacity);
            validity::run(&run, k, &candidates, noted, &facets, rec)?;
        } else {
            rec.stages.skip(STAGE_VALIDITY);
        }
        ratio::run(&run, k, &facets, &masks, &lit, rec)?;

        let c = read_counters(ctx, &run.counters)?;
        let counters = &mut rec.counters;
        counters.silhouette_texels += u64::from(c[slot::SILHOUETTE_TEXELS]);
        counters.silhouette_pixels += u64::from(c[slot::SILHOUETTE_PIXELS]);
        counters.shadow_map_lookups += u64::from(c[slot::LOOKUPS]);
        counters.pt_pairs += u64::from(c[slot::PT_PAIRS]);
        counters.tt_pairs += u64::from(c[slot::TT_PAIRS]);
        counters.visibility_evaluations += u64::from(c[slot::EVALUATIONS]);
        counters.boundary_pixels += u64::from(c[slot::BOUNDARY]);
        if curved {
            counters.valid_samples += u64::from(c[slot::VALID_SAMPLES]);
        }

        let lit: Vec<f32> = ctx.read(&lit)?;
        let class: Vec<u32> = ctx.read(&facets.class)?;
        let fu: Vec<facets::FacetU> = ctx.read(&facets.fu)?;
        let occ: Vec<u32> = ctx.read(&masks)?;
        let val: Vec<u32> = ctx.read(&facets.valid)?;
        let all = <u128 as Mask>::first(self.pattern.rate());
        let w = words as usize;
        let mask_of = |v: &[u32], f: usize| {
            (0..w).fold(0u128, |m, i| m | (u128::from(v[f * w + i]) << (32 * i)))
        };
        let n = class.len();
        let mut out = SubsampleMasks {
            rate: self.pattern.rate(),
            occlusion: vec![0; n],
            valid: vec![all; n],
            class: class
                .iter()
                .map(|&c| if c == 1 { PixelClass::DepthTest } else { PixelClass::Lit })
                .collect(),
        };
        for (f, record) in fu[..facets.count as usize].iter().enumerate() {
            let pixel = record.pixel as usize;
            out.class[pixel] = PixelClass::Silhouette(f as u32);
            out.occlusion[pixel] = mask_of(&occ, f);
            out.valid[pixel] = mask_of(&val, f);
        }
        for (k, c) in out.class.iter().enumerate() {
            if *c == PixelClass::DepthTest && lit[k] == 0.0 {
                out.occlusion[k] = all;
            }
        }
        let v =
            Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None };
        Ok((v, out))
    }
}

impl ShadowMethod for GpuPan09 {
    fn name(&self) -> &'static str {
        "pan09"
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = self.options.map.params();
        m.insert("rate".into(), self.options.rate.into());
        m.insert("pattern".into(), self.options.pattern.name().into());
        m.insert("masks".into(), self.options.visibility.name().into());
        m.insert("device".into(), "gpu".into());
        m
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        Ok(self.run_masks(frame, rec)?.0)
    }
}
