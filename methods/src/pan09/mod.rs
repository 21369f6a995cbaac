//! `pan09`: fast sub-pixel antialiased shadow maps (Pan, Wang, Chen, Zhou and Bao 2009, "Fast,
//! Sub-pixel Antialiased Shadow Maps", Computer Graphics Forum 28(7), Pacific Graphics 2009).
//!
//! Alias-free shadows at the pixel centres, extended to `rate` sub-samples per pixel without
//! supersampling the screen: each pixel is approximated by a *facet* on its tangent plane
//! (section 3.1); a *silhouette mask map* and its summed-area table (section 3.2) single out
//! the few pixels near a shadow boundary; only those are rasterized into pixel-texel and
//! triangle-texel pairs (section 3.3) and evaluated against their candidate blockers, each
//! blocker as half-planes whose sub-sample bitmasks come from a precomputed lookup table
//! (section 3.4). Every other pixel takes the standard depth test.
//!
//! # Stages (Fig. 2), each timed under its own name
//!
//! | stage | constant | module |
//! |---|---|---|
//! | light depth map | [`STAGE_LIGHT_DEPTH_MAP`] | [`crate::depth_map`] |
//! | edge adjacency (per scene) | [`STAGE_EDGE_ADJACENCY`] | [`silhouette`] |
//! | silhouette extraction | [`STAGE_SILHOUETTE_EDGES`] | [`silhouette`] |
//! | silhouette mask map | [`STAGE_SILHOUETTE_MASK`] | [`mask_map`] |
//! | summed-area table | [`STAGE_SAT`] | [`sat`] |
//! | pixel facets (projection, classification) | [`STAGE_FACETS`] | [`facets`] |
//! | depth test (non-silhouette pixels) | [`STAGE_DEPTH_TEST`] | [`crate::sm::depth_test`] |
//! | pixel-texel pairs | [`STAGE_PT_PAIRS`] | [`pairs`] |
//! | triangle-texel pairs | [`STAGE_TT_PAIRS`] | [`pairs`] |
//! | visibility evaluation | [`STAGE_VISIBILITY`] | [`visibility`] |
//! | validity mask (curved receivers only, else skipped) | [`STAGE_VALIDITY`] | [`validity`] |
//! | occlusion ratio | [`STAGE_OCCLUSION_RATIO`] | here |
//!
//! Table 1's three times are sums of these ([`TABLE1`], [`table1_times`]): "Create silhouette
//! mask map" (section 3.2: depth map, silhouette extraction, mask map, SAT), "Create
//! PT-pairs and TT-pairs" (section 3.3: facets, PT-pairs, TT-pairs) and "Shadow calculation"
//! (section 3.4: depth test, visibility evaluation, validity mask, occlusion ratio). The camera
//! G-buffer (the frame's) and the edge adjacency (a per-scene precomputation) are not part of
//! them. The lookup table is precomputed when the method is built ([`Pan09::new`]), as the
//! paper precomputes it, and is not a stage.
//!
//! Counters: `silhouette_texels` (marked texels of the mask map), `silhouette_pixels`
//! (silhouette facets), `pt_pairs` and `tt_pairs` (after the intersection test),
//! `visibility_evaluations` (triangle-pixel tests: the pairs of each TT-pair's triangle with
//! its texel's PT list, less the pixel's own triangle), `boundary_pixels` (pixels with a
//! value strictly between 0 and 1), `valid_samples` (only when the validity mask runs: the
//! valid sub-samples summed over the boundary pixels, so `valid_samples / boundary_pixels` is
//! Fig. 9's "average number of valid samples per pixel on the shadow boundary"),
//! `shadow_map_lookups` (depth tests), and the depth maps' `triangles_rasterized` and
//! `raster_samples_tested`.
//!
//! # Invariants
//!
//! - **Non-silhouette pixels are `sm`'s.** They run [`crate::sm::depth_test`] on the same map
//!   (resolution and bias options), so they equal `sm` with those options.
//! - **The shadow predicate is the ray tracer's** (as `afsm`'s, see [`crate::afsm`]): a facet
//!   point is shadowed by a caster triangle other than the pixel's own G-buffer triangle when
//!   the light's ray from it crosses the triangle more than the triangle's local shadow
//!   offset away ([`visibility::occluder_offset`]). Hence at rate 1 a silhouette pixel
//!   (whose only sub-sample is the G-buffer's point) equals `afsm`, and on a planar receiver,
//!   where the facet *is* the surface, exact mode equals `raytrace` at the same rate and
//!   pattern, sub-sample for sub-sample, up to samples within `f64` rounding of a blocker's
//!   edge (where each breaks ties its own way).
//! - **Table mode** differs from exact mode only for sub-samples within [`lut::FLIP_BOUND`]
//!   (1/128 pixel) of a half-plane's line: every other sub-sample gets its exact side, and the
//!   centre sample is always exact. Measured on 160 x 120 frames with the grid pattern, the
//!   share of silhouette pixels' sub-samples the table flips (occlusion or validity) at 32 and
//!   128 sub-samples: `plane-square` 1.2e-4 and 2.4e-4, `plant` 2.0e-3 and 2.2e-3, `cage`
//!   3.5e-3 and 2.4e-3, `random-10k` 4.1e-3 and 4.1e-3 (`tests/techniques/pan09.rs`). Pixels off the
//!   silhouette are identical in both modes.
//! - **Values** are finite and in `[0, 1]`: a silhouette pixel's value is
//!   `1 - popcount(occlusion & valid) / popcount(valid)`, and the centre sample is always
//!   valid. Without transparency, values are multiples of `1 / popcount(valid)`.
//! - **Deterministic**: masks are combined with atomic OR and AND (commutative), pairs sorted
//!   with total orders; the result and the counters do not depend on threads.
//!
//! # Choices where the paper is vague
//!
//! - **Defaults**: map 512 x 512 (Table 1's), rate 32 (the paper's usual rate), `grid` pattern
//!   (the paper's; `rotated` works unchanged, section 5.1), lookup-table visibility; the shared
//!   bias options of [`crate::depth_test`] (constant `1e-5`, slope 1, max slope 10).
//! - **Masks** are `u32` up to rate 32, `u64` at 64, `u128` at 128 ([`mask`]).
//! - **Silhouette edges** ([`silhouette`]): faces adjacent by position, front and back decided
//!   without the winding (the third corners on opposite sides of the plane through the edge
//!   and the light); non-manifold edges and edges of faces seen edge-on are silhouettes.
//! - **Conservative rasterization** of silhouette edges ([`mask_map`]): every texel whose
//!   closed square meets the edge, widened by `1e-7` texel.
//! - **Hidden silhouettes** ([`mask_map`]): compared against the depth map's nine samples
//!   around the texel (its centre and its neighbours'), not the centre alone, with the shared
//!   depth tolerance over 1.5 texels; an edge is hidden only when all nine surfaces lie in
//!   front of its nearest point in the texel.
//! - **SAT** ([`sat`]): `(R + 1)^2` `u32` sums with a zero first row and column; rectangles
//!   inclusive.
//! - **Facets** ([`facets`]): the pixel square seen on the tangent plane of the G-buffer's
//!   point and face normal, limited to a region (at most 4 times the centre's depth for
//!   perspective cameras, 64 pixel widths for orthographic ones, the spot light's side of its
//!   near plane) so that a facet seen edge-on stays bounded; sub-samples outside it are not
//!   valid. The classification rectangle holds every texel whose closed square meets the
//!   footprint's bounding box.
//! - **PT-pairs** are made with every texel the facet touches, not only silhouette texels
//!   ([`pairs`] measures the light leaks the paper's rule allows), so a silhouette facet's
//!   list is sized by its rectangle (the SAT count only classifies). TT-pairs with the texels
//!   that have a PT list, counted with a second SAT over each row's span of the triangle's
//!   footprint. Triangles seen edge-on by the light shadow nothing and get no pairs.
//! - **Half-planes** ([`screen`], [`visibility`]): each of the triangle's edges with the light
//!   spans a world plane; the fourth is the triangle's plane (its intersection line with the
//!   facet), always used when it cuts the pixel. The paper's side rule (Fig. 6b) becomes the
//!   sign of the ray-plane denominator, constant over the facet's region.
//! - **Lookup table** ([`lut`]): normals indexed along the boundary of the unit square (128
//!   bins per side), offsets in 256 bins over `[-1, 1]`; the flip bound is 1/128 pixel.
//!   Half-planes whose line misses the pixel square are settled without the table.
//! - **Validity mask** ([`validity`]): a triangle takes part when it meets the facet inside
//!   the pixel and lies nearer the light than the facet beyond their intersection line (the
//!   paper's concave case); it invalidates the sub-samples it hides from the camera (the
//!   paper masks the line's whole far side, which also drops sub-samples that see the facet);
//!   the centre is always valid. The visibility evaluation notes the candidates; the validity
//!   stage tests them.
//! - **Spot lights**: the shadow offset is measured perpendicular to the caster's plane.
//! - **Transparency**: casters are opaque (the run record says so when the scene has
//!   semi-transparent ones).
//! - **Memory**: about 400 bytes per silhouette pixel (facet, footprint, rectangle, masks),
//!   8 bytes per PT- and TT-pair (16 while they are built), `(R + 1)^2` words per SAT, the
//!   depth map, the mask map and the memos of hidden depths (`R^2` each), and the lookup
//!   table (131 072 masks).

pub mod coverage;
pub mod facets;
pub mod footprint;
pub mod lut;
pub mod mask;
pub mod mask_map;
pub mod pairs;
pub mod sat;
pub mod screen;
pub mod silhouette;
pub mod validity;
pub mod visibility;

pub use crate::frame::STAGE_LIGHT_DEPTH_MAP;
pub use crate::sm::STAGE_DEPTH_TEST;

use crate::{
    depth_test::{DepthTester, MapOptions},
    footprint::Sampling,
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    pattern::{PatternKind, SamplePattern},
};
use coverage::{Coverage, ExactCoverage, TableCoverage};
use facets::{Facets, PixelClass};
use instrumentation::{Counters, Recorder, Stages};
use lut::LookupTable;
use mask::Mask;
use pairs::{TexelLists, TtPair};
use rayon::prelude::*;
use screen::CameraBasis;
use serde::{Deserialize, Serialize};
use silhouette::{EdgeAdjacency, LightModel};
use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

/// Name of the stage that builds the casters' edge adjacency.
pub const STAGE_EDGE_ADJACENCY: &str = "edge adjacency";
/// Name of the stage that finds the silhouette edges.
pub const STAGE_SILHOUETTE_EDGES: &str = "silhouette extraction";
/// Name of the stage that rasterizes the silhouette mask map.
pub const STAGE_SILHOUETTE_MASK: &str = "silhouette mask map";
/// Name of the stage that builds the summed-area table.
pub const STAGE_SAT: &str = "summed-area table";
/// Name of the stage that builds, projects and classifies the pixel facets.
pub const STAGE_FACETS: &str = "pixel facets";
/// Name of the stage that creates the pixel-texel pairs.
pub const STAGE_PT_PAIRS: &str = "pixel-texel pairs";
/// Name of the stage that creates the triangle-texel pairs.
pub const STAGE_TT_PAIRS: &str = "triangle-texel pairs";
/// Name of the visibility evaluation stage.
pub const STAGE_VISIBILITY: &str = "visibility evaluation";
/// Name of the validity mask stage (run only with curved receivers).
pub const STAGE_VALIDITY: &str = "validity mask";
/// Name of the stage that turns masks into occlusion ratios.
pub const STAGE_OCCLUSION_RATIO: &str = "occlusion ratio";

/// Table 1's three time columns (the paper's names) and the stages each sums.
pub const TABLE1: [(&str, &[&str]); 3] = [
    (
        "Create silhouette mask map",
        &[STAGE_LIGHT_DEPTH_MAP, STAGE_SILHOUETTE_EDGES, STAGE_SILHOUETTE_MASK, STAGE_SAT],
    ),
    ("Create PT-pairs and TT-pairs", &[STAGE_FACETS, STAGE_PT_PAIRS, STAGE_TT_PAIRS]),
    (
        "Shadow calculation",
        &[STAGE_DEPTH_TEST, STAGE_VISIBILITY, STAGE_VALIDITY, STAGE_OCCLUSION_RATIO],
    ),
];

/// The paper's Table 1 (NVIDIA GTX 280 with a 3.0 GHz CPU; 800 x 600, map 512), to print
/// beside ours: our scene, the sample rate the table runs it at (the paper's for the scenes it
/// lists, 32 elsewhere), and the paper's row for the same kind of scene where it has one: name,
/// triangles, silhouette texels, silhouette pixels, visibility evaluations, sample rate, the
/// three times of [`TABLE1`] in ms, and frames per second (whole frame).
pub const PAPER_TABLE1: [(&str, u32, Option<[&str; 10]>); 5] = [
    (
        "cage",
        128,
        Some(["Cage", "59780", "37646", "53576", "2915995", "128", "4.2", "10.0", "18.9", "28"]),
    ),
    (
        "plant",
        32,
        Some(["Plant", "20926", "15263", "59692", "1446287", "32", "2.1", "6.2", "10.8", "50"]),
    ),
    ("spheres", 32, None),
    (
        "bunny-plane",
        32,
        Some(["Bunny", "69473", "3254", "18523", "609901", "32", "2.1", "6.3", "6.8", "61"]),
    ),
    ("bumpy", 32, None),
];

/// Table 1's three times of a run, in milliseconds (see [`TABLE1`]).
pub fn table1_times(stages: &Stages) -> [f64; 3] {
    TABLE1.map(|(_, names)| {
        stages.stages.iter().filter(|s| names.contains(&s.name.as_str())).map(|s| s.ms).sum()
    })
}

/// Default sub-samples per pixel.
pub const DEFAULT_RATE: u32 = 32;
/// Default map resolution (the paper's, Table 1).
pub const DEFAULT_MAP_RES: u32 = 512;

/// How half-planes become sub-sample masks (`--masks`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum VisibilityMode {
    /// The paper's precomputed lookup table of quantized half-planes (the default).
    #[default]
    Table,
    /// Each half-plane tested against each sub-sample in `f64`.
    Exact,
}

impl VisibilityMode {
    /// The name as on the command line: `table` or `exact`.
    pub fn name(self) -> &'static str {
        match self {
            VisibilityMode::Table => "table",
            VisibilityMode::Exact => "exact",
        }
    }
}

impl fmt::Display for VisibilityMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for VisibilityMode {
    type Err = MethodError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "table" => Ok(VisibilityMode::Table),
            "exact" => Ok(VisibilityMode::Exact),
            _ => Err(MethodError::InvalidOption {
                option: "--masks",
                message: format!("unknown visibility mode `{s}`; available: table, exact"),
            }),
        }
    }
}

/// Options of `pan09`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pan09Options {
    /// The light depth map and the depth test of non-silhouette pixels (`--map-res`, biases).
    /// Default: [`DEFAULT_MAP_RES`] and the shared bias defaults.
    pub map: MapOptions,
    /// Sub-samples per pixel (`--rate`): 1, 4, 8, 16, 32, 64 or 128. Default 32.
    pub rate: u32,
    /// Sub-sample pattern (`--pattern`). Default grid.
    pub pattern: PatternKind,
    /// Visibility evaluation (`--masks`). Default table.
    pub visibility: VisibilityMode,
}

impl Default for Pan09Options {
    fn default() -> Self {
        Self {
            map: MapOptions { map_res: DEFAULT_MAP_RES, ..MapOptions::default() },
            rate: DEFAULT_RATE,
            pattern: PatternKind::Grid,
            visibility: VisibilityMode::Table,
        }
    }
}

impl Pan09Options {
    /// Checks the options; errors name the command-line flag.
    pub fn validate(&self) -> Result<(), MethodError> {
        self.map.validate()?;
        SamplePattern::for_method(self.rate, self.pattern).map(|_| ())
    }
}

/// The lookup table at the mask width of the rate.
enum Tables {
    W32(LookupTable<u32>),
    W64(LookupTable<u64>),
    W128(LookupTable<u128>),
}

impl fmt::Debug for Tables {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let bits = match self {
            Tables::W32(_) => 32,
            Tables::W64(_) => 64,
            Tables::W128(_) => 128,
        };
        write!(f, "LookupTable<u{bits}>({} x {} masks)", lut::DIRECTION_BINS, lut::DISTANCE_BINS)
    }
}

/// Per-sub-sample results of a run, for comparisons sample by sample: bit `s` of a pixel's
/// mask is sub-sample `s` of the pattern.
#[derive(Debug, Clone, PartialEq)]
pub struct SubsampleMasks {
    /// Sub-samples per pixel.
    pub rate: u32,
    /// Occluded sub-samples per pixel: the occlusion mask of silhouette pixels; all or none
    /// for the depth test's pixels; none for lit ones (no surface, or not projected).
    pub occlusion: Vec<u128>,
    /// Sub-samples counted in the pixel's ratio: the region and validity masks of silhouette
    /// pixels, all sub-samples elsewhere.
    pub valid: Vec<u128>,
    /// Class of each pixel.
    pub class: Vec<PixelClass>,
}

/// `pan09`.
#[derive(Debug, Clone)]
pub struct Pan09 {
    options: Pan09Options,
    pattern: SamplePattern,
    tables: Option<Arc<Tables>>,
}

/// Everything the mask-width-independent stages produce.
/// What the stages up to the triangle-texel pairs give, for comparing the GPU kernels with
/// the CPU stage by stage (`Pan09::stage_outputs`, and the GPU's twin of it).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StageOutputs {
    /// Silhouette edges found (silhouette extraction).
    pub silhouette_edges: usize,
    /// Silhouette mask map: per texel, row by row, whether it is marked.
    pub mask: Vec<bool>,
    /// Its summed-area table ([`sat::SummedAreaTable::sums`]).
    pub sat: Vec<u32>,
    /// Per pixel: 0 lit, 1 depth test, 2 silhouette (pixel facets).
    pub class: Vec<u8>,
    /// The silhouette facets' pixels, in facet order.
    pub facet_pixels: Vec<u32>,
    /// Per pixel, the depth test's light (1 outside its class).
    pub depth_test_lit: Vec<f32>,
    /// PT-pairs and TT-pairs kept.
    pub pairs: (u64, u64),
}

impl StageOutputs {
    /// The code of `class` in [`StageOutputs::class`].
    pub fn class_code(class: PixelClass) -> u8 {
        match class {
            PixelClass::Lit => 0,
            PixelClass::DepthTest => 1,
            PixelClass::Silhouette(_) => 2,
        }
    }
}

struct Prepared {
    facets: Facets,
    pt: TexelLists,
    tt: Vec<TtPair>,
    /// Lit values of the depth test's pixels (1 elsewhere).
    lit: Vec<f32>,
}

impl Pan09 {
    /// `pan09` with `options`, validated; in table mode the lookup table is precomputed here.
    pub fn new(options: Pan09Options) -> Result<Self, MethodError> {
        options.validate()?;
        let pattern = SamplePattern::new(options.rate, options.pattern)?;
        let tables = (options.visibility == VisibilityMode::Table).then(|| {
            Arc::new(match options.rate {
                0..=32 => Tables::W32(LookupTable::new(&pattern)),
                33..=64 => Tables::W64(LookupTable::new(&pattern)),
                _ => Tables::W128(LookupTable::new(&pattern)),
            })
        });
        Ok(Self { options, pattern, tables })
    }

    /// Runs the method and also returns every pixel's sub-sample masks.
    pub fn run_masks(
        &self,
        frame: &Frame<'_>,
        rec: &mut Recorder,
    ) -> Result<(Visibility, SubsampleMasks), MethodError> {
        let (v, masks) = self.dispatch(frame, rec, true)?;
        let masks = masks.ok_or_else(|| {
            MethodError::NotApplicable("pan09: sub-sample masks were not kept".into())
        })?;
        Ok((v, masks))
    }

    fn dispatch(
        &self,
        frame: &Frame<'_>,
        rec: &mut Recorder,
        keep: bool,
    ) -> Result<(Visibility, Option<SubsampleMasks>), MethodError> {
        self.options.validate()?;
        if frame.effects.transparency {
            rec.notes.push("pan09 treats semi-transparent casters as opaque".into());
        }
        let prepared = self.prepare(frame, rec, None);
        Ok(match (self.tables.as_deref(), self.options.rate) {
            (Some(Tables::W32(t)), _) => {
                self.shade(frame, rec, prepared, &TableCoverage::new(t, &self.pattern), keep)
            }
            (Some(Tables::W64(t)), _) => {
                self.shade(frame, rec, prepared, &TableCoverage::new(t, &self.pattern), keep)
            }
            (Some(Tables::W128(t)), _) => {
                self.shade(frame, rec, prepared, &TableCoverage::new(t, &self.pattern), keep)
            }
            (None, 0..=32) => {
                self.shade(frame, rec, prepared, &ExactCoverage::<u32>::new(&self.pattern), keep)
            }
            (None, 33..=64) => {
                self.shade(frame, rec, prepared, &ExactCoverage::<u64>::new(&self.pattern), keep)
            }
            (None, _) => {
                self.shade(frame, rec, prepared, &ExactCoverage::<u128>::new(&self.pattern), keep)
            }
        })
    }

    /// The stages that do not depend on the mask width: depth map, silhouettes, mask map,
    /// SAT, facets, depth test, PT- and TT-pairs.
    /// The outputs of the stages up to the triangle-texel pairs on `frame`.
    pub fn stage_outputs(&self, frame: &Frame<'_>, rec: &mut Recorder) -> StageOutputs {
        let mut out = StageOutputs::default();
        let p = self.prepare(frame, rec, Some(&mut out));
        out.class = p.facets.class.iter().map(|&c| StageOutputs::class_code(c)).collect();
        out.facet_pixels = p.facets.facets.iter().map(|f| f.pixel).collect();
        out.depth_test_lit = p.lit;
        out.pairs = (p.pt.len() as u64, p.tt.len() as u64);
        out
    }

    /// The stages up to the triangle-texel pairs; `probe` receives the silhouette edges, the
    /// mask map and its table, which are not kept otherwise.
    fn prepare(
        &self,
        frame: &Frame<'_>,
        rec: &mut Recorder,
        probe: Option<&mut StageOutputs>,
    ) -> Prepared {
        let res = self.options.map.map_res;
        let map = frame.light_depth_map(res, self.options.map.frustum, rec);
        let light = map.projector;
        let tester = DepthTester::new(&self.options.map, light, frame.light_depth_range(&light));
        rec.warnings.extend(tester.warnings("pan09", frame, Sampling::PixelArea));
        let geometry = &frame.geometry;
        let adjacency = rec
            .stages
            .time(STAGE_EDGE_ADJACENCY, || EdgeAdjacency::new(geometry, |t| frame.is_caster(t)));
        let model = LightModel::of(&light);
        let edges = rec.stages.time(STAGE_SILHOUETTE_EDGES, || {
            silhouette::silhouette_edges(geometry, &adjacency, model)
        });
        let mask = rec.stages.time(STAGE_SILHOUETTE_MASK, || {
            let hidden = mask_map::HiddenDepths::new(geometry, &map, &tester);
            mask_map::silhouette_mask(&edges, &light, res, |k| hidden.get(k))
        });
        let sat = rec.stages.time(STAGE_SAT, || sat::SummedAreaTable::new(&mask, res));
        rec.counters.silhouette_texels += u64::from(sat.total());
        if let Some(probe) = probe {
            probe.silhouette_edges = edges.len();
            probe.sat = sat.sums().to_vec();
            probe.mask = mask;
        }
        let facets =
            rec.stages.time(STAGE_FACETS, || facets::classify_facets(frame, &light, res, &sat));
        rec.counters.silhouette_pixels += facets.facets.len() as u64;

        let g = &frame.gbuffer;
        let (lit, lookups) = rec.stages.time(STAGE_DEPTH_TEST, || {
            let out: Vec<(f32, u64)> = facets
                .class
                .par_iter()
                .enumerate()
                .with_min_len(1024)
                .map(|(k, class)| {
                    if *class != PixelClass::DepthTest {
                        return (1.0, 0);
                    }
                    match tester.receiver(g.position[k], g.normal[k]) {
                        Some(r) => {
                            let p = crate::sm::depth_test(&map, &tester, &r);
                            (p.lit, p.compares)
                        }
                        None => (1.0, 0),
                    }
                })
                .collect();
            let lookups = out.iter().map(|o| o.1).sum::<u64>();
            (out.into_iter().map(|o| o.0).collect::<Vec<f32>>(), lookups)
        });
        rec.counters.shadow_map_lookups += lookups;

        let (pt, _) = rec.stages.time(STAGE_PT_PAIRS, || {
            pairs::pixel_texel_pairs(&facets.footprints, &facets.rects, res)
        });
        rec.counters.pt_pairs += pt.len() as u64;
        let (tt, _) = rec.stages.time(STAGE_TT_PAIRS, || {
            pairs::triangle_texel_pairs(geometry, |t| frame.is_caster(t), &light, res, &pt)
        });
        rec.counters.tt_pairs += tt.len() as u64;
        Prepared { facets, pt, tt, lit }
    }

    /// Visibility evaluation, validity mask and occlusion ratios with masks `M`.
    fn shade<M: Mask, C: Coverage<M>>(
        &self,
        frame: &Frame<'_>,
        rec: &mut Recorder,
        prepared: Prepared,
        coverage: &C,
        keep: bool,
    ) -> (Visibility, Option<SubsampleMasks>) {
        let Prepared { facets, pt, tt, mut lit } = prepared;
        let light = frame.light_projector(self.options.map.map_res, self.options.map.frustum);
        let camera = CameraBasis::new(&frame.camera);
        let scene = visibility::Scene {
            geometry: &frame.geometry,
            light: LightModel::of(&light),
            eye: frame.camera.origin,
            camera: &camera,
        };
        let fs = &facets.facets;
        let curved = frame.effects.curved_receivers;
        let evaluated = rec.stages.time(STAGE_VISIBILITY, || {
            visibility::occlusion_masks(&scene, &tt, &pt, fs, coverage, curved)
        });
        rec.counters.visibility_evaluations += evaluated.evaluations;
        let occlusion = evaluated.masks;
        let candidates = evaluated.validity_candidates;
        let validity: Option<Vec<M>> = if curved {
            Some(rec.stages.time(STAGE_VALIDITY, || {
                let camera = &frame.camera;
                validity::validity_masks(&scene, camera, frame.width(), &candidates, fs, coverage)
            }))
        } else {
            rec.stages.skip(STAGE_VALIDITY);
            None
        };
        let (valid, counters) = rec.stages.time(STAGE_OCCLUSION_RATIO, || {
            let valid: Vec<M> = fs
                .par_iter()
                .enumerate()
                .map(|(i, f)| {
                    let region =
                        f.region().iter().fold(coverage.all(), |m, h| m & coverage.closed(h));
                    let v = validity.as_ref().map_or(region, |v| region & v[i]);
                    v | coverage.centre()
                })
                .collect();
            let ratios: Vec<f32> = valid
                .par_iter()
                .zip(&occlusion)
                .map(|(&v, &o)| {
                    let dark = f64::from((o & v).count()) / f64::from(v.count());
                    (1.0 - dark).clamp(0.0, 1.0) as f32
                })
                .collect();
            let mut counters = Counters::default();
            for (i, f) in fs.iter().enumerate() {
                lit[f.pixel as usize] = ratios[i];
                if ratios[i] > 0.0 && ratios[i] < 1.0 && validity.is_some() {
                    counters.valid_samples += u64::from(valid[i].count());
                }
            }
            counters.boundary_pixels = lit.iter().filter(|&&l| l > 0.0 && l < 1.0).count() as u64;
            (valid, counters)
        });
        rec.counters.merge(&counters);
        let masks = keep.then(|| {
            let all = coverage.all().to_u128();
            let mut occ = vec![0u128; lit.len()];
            let mut val = vec![all; lit.len()];
            for (k, class) in facets.class.iter().enumerate() {
                match *class {
                    PixelClass::Silhouette(i) => {
                        occ[k] = occlusion[i as usize].to_u128();
                        val[k] = valid[i as usize].to_u128();
                    }
                    PixelClass::DepthTest if lit[k] == 0.0 => occ[k] = all,
                    _ => {}
                }
            }
            SubsampleMasks {
                rate: self.pattern.rate(),
                occlusion: occ,
                valid: val,
                class: facets.class,
            }
        });
        (
            Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None },
            masks,
        )
    }
}

impl ShadowMethod for Pan09 {
    fn name(&self) -> &'static str {
        "pan09"
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = self.options.map.params();
        m.insert("rate".into(), self.options.rate.into());
        m.insert("pattern".into(), self.options.pattern.name().into());
        m.insert("masks".into(), self.options.visibility.name().into());
        m
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        Ok(self.dispatch(frame, rec, false)?.0)
    }
}
