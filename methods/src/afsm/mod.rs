//! `afsm` and `afsm-ss`: alias-free shadow maps (Aila and Laine 2004, "Alias-Free Shadow
//! Maps", Eurographics Symposium on Rendering (EGSR) 2004).
//!
//! The visible samples themselves are the shadow map's sampling points (section 3): each is
//! moved to the light's image plane with its light depth, without discretisation; the samples
//! are organised in an axis-aligned 2D BSP (section 5.1); every caster triangle is rasterized
//! hierarchically into it, with occlusion culling and max-depth culling (section 5.1);
//! semi-transparent casters attenuate an RGB transmittance per sample (section 4). `afsm`
//! samples pixel centres; `afsm-ss` takes `rate` sub-samples per pixel from the shared
//! [`SamplePattern`], each with its own surface point (the brute-force supersampling baseline
//! of Pan et al. 2009, Fig. 10).
//!
//! Stages, each timed on its own: [`STAGE_GBUFFER_SUBSAMPLE`] `(sub-sample s)` (`afsm-ss`
//! only: the camera G-buffer at every non-centre sub-sample position, rendered by
//! [`rasterize_nearest_at`]; the centre sub-sample uses the frame's G-buffer),
//! [`STAGE_TRANSFORMATION`] ([`samples`] in the light's frame fitted to the scene, which
//! also bounds the visible points; made again in the frame [`light_projector`] fits to those
//! points where the scene's is too coarse for them), [`STAGE_BSP`] ([`bsp`]) and
//! [`STAGE_RASTERIZATION`] ([`blockers`]; it also writes the samples' light back to their
//! pixels). Counters: `bsp_nodes`, `bsp_nodes_visited`, `nodes_depth_culled`,
//! `nodes_occlusion_culled`, `sampling_points_tested` (defined in [`blockers`]), plus the
//! G-buffers' `triangles_rasterized` and `raster_samples_tested`.
//!
//! # Invariants
//!
//! - **The shadow predicate is the ray-traced reference's.** A sample on triangle `R` is
//!   shadowed by caster triangle `T` iff `T != R`, the sample's light image point lies inside
//!   `T`'s projection, and `T` is nearer the light than the sample by more than the sample's
//!   [`shadow_offset`] (in world units along the light's ray: the threshold depth of
//!   [`samples::threshold_depth`]). The offset is local: [`SHADOW_OFFSET`] times the magnitude
//!   of the numbers that made the sample's surface point (the camera ray's origin and the
//!   point), the scale of that point's rounding error, so neither the scene's size nor its
//!   position nor a far-away object changes which casters count (an offset in units of the
//!   scene's diagonal lost every shadow near the origin once one triangle lay 1e10 away).
//!   `raytrace`'s shadow rays make the same test (they skip the hit triangle and hits nearer
//!   than the same offset; a spot light's segment ends at the light, and every caster in front
//!   of a sample's depth is on that segment). With the shared pattern at equal rate the two
//!   evaluate the same image points, so they can differ only where a sample lies exactly on a
//!   caster's edge, where each breaks the tie by its own rule, or within `f64` rounding of one.
//! - **Exact coverage.** Point-in-triangle is decided by Shewchuk's exact `orient2d` on the
//!   `f64` light image coordinates, ties on an edge by the rasterizer's top-left rule, so a
//!   sample on an edge shared by two casters is covered by exactly one of them. A
//!   floating-point edge function with a forward error bound answers first where the bound
//!   decides its sign ([`blockers::edge_sign`]), so the answer is always the exact one.
//! - **Culling never changes a pixel** (see [`blockers`]); switching either off (the options)
//!   changes only the counters. The same holds for *facing culling* ([`facing`], not in the
//!   paper): of a closed opaque caster seen from outside only the triangles facing the light
//!   are rasterized, whose shadow is the whole caster's (up to the ties and rounding the
//!   first invariant allows; the built-in scenes' images are the same bit for bit). On
//!   `bunny-plane` at 800 x 600 it halves the BSP nodes visited and takes a sixth off the
//!   rasterization (49-57 -> 41 ms at one thread, its own check of 8-10 ms included, 6.5-9.5
//!   ms since its passes became plain loops), on `cage` a fifth (21-23 -> 16-18 ms).
//! - **Deterministic.** Pixels and counters do not depend on thread scheduling or count.
//! - `lit` is in `[0, 1]`: the mean over a pixel's sub-samples of their light (background
//!   sub-samples, and surface points a spot light cannot project, count as lit, as in
//!   `raytrace`). Without transparency each sub-sample is 0 or 1, so values are `k / rate`.
//!
//! # Choices where the paper is vague
//!
//! - **Light image.** The light's projector fitted to the scene ([`Frame::light_projector`]) at
//!   [`LIGHT_IMAGE_RES`]; the resolution only scales coordinates, nothing is discretised.
//!   `--frustum` is not declared: the light image only bins the samples, so a view-fitted
//!   frustum would change the cost, never the result.
//!   Samples outside that image are kept (the reference ignores the spot's cone). A spot light
//!   projects only points beyond its `near` plane: casters are clipped there, and surface
//!   points nearer than it are lit. The fitted frustum's `near` is the nearest depth of the
//!   scene's padded bounds, but a fixed fraction (1e-4) of the scene's diagonal when the light
//!   is inside them, which a far-away object makes larger than the whole scene near the light
//!   (every shadow was lost). [`light_projector`] keeps the fitted `near` only where it is
//!   smaller than a local one: [`SHADOW_OFFSET`] times the magnitude of the light's position
//!   and of its distance to the farthest visible surface point, so only points within the
//!   shadow offset of the light, which the ray tracer also counts as lit, are left out. For
//!   directional lights it centres the orthographic image on the visible surface points when
//!   the fitted frame's rounding exceeds their shadow offset (a frame fitted to a scene that
//!   holds an object 1e10 away rounds light image coordinates and depths near the origin to
//!   about 1e-6 world units, and flipped pixels near shadow edges).
//! - **Depth.** A caster's depth at a sample is where the light's ray through the sample's
//!   image point meets the caster's plane, clamped to the depth range of its corners (as the
//!   rasterizer does); the sample's own depth is its surface point's light depth.
//! - **BSP.** "Divided in half": the left child takes `floor(n / 2)` samples; the first split
//!   is along `x`; a node of at least `leaf_size` samples is split, so leaves hold fewer
//!   ("less than a predetermined number"). Nodes keep the exact bounding box of their samples,
//!   a tighter region than the split planes, for the overlap test.
//! - **Overlap** of a triangle and a node is tested on bounding boxes and on the triangle's
//!   edge lines against the node's box (conservatively); the exact test decides per sample.
//! - **Leaf tests.** The paper tests a leaf's samples "individually" without saying how. A
//!   leaf first masks, branch-free over its samples, those inside the triangle's bounding box,
//!   then (past a few) those certainly outside an edge or certainly inside all edges by the
//!   bounded floating-point edge functions ([`blockers::Blocker::edge_masks`]); only the rest
//!   reach the exact predicate. On `cage`, whose long thin bars hold many samples in their
//!   bounding boxes but few inside, this halved the rasterization's time.
//! - **Max-depth culling** compares the triangle's nearest corner with the node's farthest
//!   threshold depth (the sample depth less the shadow offset).
//! - **Occlusion culling** also skips dark samples inside a leaf; with transparency a sample
//!   is dark only at zero transmittance (behind an opaque caster).
//! - **Counting.** A node is *visited* when the triangle overlaps it (the paper's "subnodes
//!   that are at least partially covered"); culled nodes are visited nodes that are then
//!   skipped. `bsp_nodes` counts inner nodes and leaves (the paper's 16K at 1024x768 matches
//!   our leaf count).
//! - **Transmittance** is RGB per sample, initially white; opaque casters set it to black,
//!   a semi-transparent one multiplies every channel by `1 - opacity` (materials have one
//!   opacity and no transmission colour, as in `raytrace`, so the channels are equal). A
//!   pixel's transmittance is the mean over its sub-samples, its `lit` the mean of the three
//!   channels. Without the scene's `transparency` effect every caster is opaque and only a
//!   shadowed flag is carried per sample.
//! - **Parallelism** (see [`blockers`]): the BSP's top levels split the samples into up to 64
//!   subtrees, each owned by one task that rasterizes its triangles in triangle order;
//!   nodes above them are depth culled but never occlusion culled.
//! - **Memory.** 32 bytes per covered sub-sample while the samples are transformed (one slot
//!   per sub-sample the G-buffers cover), then 48 per visible sub-sample
//!   (coordinates, threshold depth, ids, and the coordinates again in two flat arrays for the
//!   leaves' vectorised tests), 56 per BSP node, and for `afsm-ss` the `rate - 1` extra
//!   G-buffers (12 bytes per pixel each) until the samples are transformed.
//!
//! [`rasterize_nearest_at`]: crate::raster::rasterize_nearest_at

pub mod blockers;
pub mod bsp;
pub mod facing;
pub mod samples;

use crate::{
    closed::per_object,
    frame::Frame,
    gbuffer::GBuffer,
    light_fit::LightFit,
    method::{MethodError, ShadowMethod, Visibility},
    pattern::{PatternKind, SamplePattern},
    raster::rasterize_nearest_at,
};
use blockers::{rasterize_blockers, Culling, Shade};
use bsp::Bsp;
use glam::{DVec2, DVec3};
use instrumentation::{Counters, Recorder};
use rayon::prelude::*;
use samples::{transform_samples, Sample, Surface};
use scenes::{projection::ProjectionKind, Projector};
use std::sync::atomic::{AtomicU32, Ordering};

/// The paper's Table 1 (measured on a 1.6 GHz Mobile Pentium 4), to print beside ours. Rows:
/// triangles, 2D BSP nodes, nodes visited, nodes occlusion culled, sampling points tested,
/// transformation of samples (ms), BSP construction (ms), rasterization of blockers (ms),
/// total (ms); columns: the 1K, 10K, 100K and 1M triangle scenes.
pub const PAPER_TABLE1: [[&str; 4]; 9] = [
    ["1K", "10K", "100K", "1M"],
    ["16K", "16K", "16K", "16K"],
    ["91K", "471K", "3.2M", "23M"],
    ["5.3K", "5.4K", "5.8K", "6.8K"],
    ["458K", "513K", "506K", "501K"],
    ["130", "130", "130", "130"],
    ["400", "402", "391", "408"],
    ["145", "381", "1568", "8102"],
    ["675", "913", "2089", "8640"],
];

/// Name of the stage that moves the samples to the light's image plane.
pub const STAGE_TRANSFORMATION: &str = "transformation of samples";
/// Name of the stage that builds the 2D BSP.
pub const STAGE_BSP: &str = "BSP construction";
/// Name of the stage that rasterizes the casters into the BSP.
pub const STAGE_RASTERIZATION: &str = "rasterization of blockers";
/// Prefix of the stages that render the camera G-buffer at one sub-sample position
/// (`afsm-ss`); the full name is given by [`gbuffer_stage`].
pub const STAGE_GBUFFER_SUBSAMPLE: &str = "camera G-buffer";

/// Shadow offset as a fraction of the magnitude of the numbers that made a sample's surface
/// point (see [`shadow_offset`]); the ray-traced reference's shadow rays use the same offset.
pub const SHADOW_OFFSET: f64 = 1e-10;

/// The distance below which a caster does not shadow the surface point `p`, the hit of a
/// camera ray from `origin`: [`SHADOW_OFFSET`] times the largest coordinate magnitude of the
/// two points plus their distance (in the max norm), the scale of `p`'s rounding error, as the
/// ray-traced reference's shadow rays measure it. Local: a far-away object, or the scene's
/// position and size, do not change it.
#[inline]
pub fn shadow_offset(origin: DVec3, p: DVec3) -> f64 {
    let magnitude = origin.abs().max(p.abs()).max_element() + (p - origin).abs().max_element();
    SHADOW_OFFSET * magnitude
}

/// Resolution of the light image the samples are expressed in (a scale, not a grid).
pub const LIGHT_IMAGE_RES: u32 = 1024;

/// Default sub-samples per pixel of `afsm-ss`.
pub const DEFAULT_SS_RATE: u32 = 32;

/// Name of the stage that renders the camera G-buffer at sub-sample `s`.
pub fn gbuffer_stage(s: usize) -> String {
    format!("{STAGE_GBUFFER_SUBSAMPLE} (sub-sample {s})")
}

/// Options of the alias-free shadow map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AfsmOptions {
    /// A BSP node with at least this many samples is split, so leaves hold fewer
    /// (`--leaf-size`, at least 2). Default 64, the paper's.
    pub leaf_size: u32,
    /// Sub-samples per pixel (`--rate`): 1 for `afsm`; for `afsm-ss` one of the pattern's
    /// rates up to [`MAX_METHOD_RATE`](crate::pattern::MAX_METHOD_RATE), default [`DEFAULT_SS_RATE`].
    pub rate: u32,
    /// Sub-sample pattern (`--pattern`). Default grid.
    pub pattern: PatternKind,
    /// Occlusion culling: skip nodes (and samples) already fully shadowed. Default on.
    pub occlusion_culling: bool,
    /// Max-depth culling: skip nodes whose samples all lie in front of the triangle.
    /// Default on.
    pub depth_culling: bool,
    /// Rasterize, of a closed opaque caster seen from outside, only the triangles facing the
    /// light, whose shadow is the whole caster's ([`facing`]). Default on.
    pub facing_culling: bool,
}

impl Default for AfsmOptions {
    fn default() -> Self {
        Self {
            leaf_size: 64,
            rate: 1,
            pattern: PatternKind::Grid,
            occlusion_culling: true,
            depth_culling: true,
            facing_culling: true,
        }
    }
}

impl AfsmOptions {
    /// The defaults of `afsm-ss`: those of `afsm` at [`DEFAULT_SS_RATE`].
    pub fn supersampled() -> Self {
        Self { rate: DEFAULT_SS_RATE, ..Self::default() }
    }

    /// Checks the options; errors name the command-line flag.
    pub fn validate(&self) -> Result<(), MethodError> {
        if !(2..=1 << 20).contains(&self.leaf_size) {
            return Err(MethodError::InvalidOption {
                option: "--leaf-size",
                message: format!("must be in 2..=1048576, got {}", self.leaf_size),
            });
        }
        SamplePattern::for_method(self.rate, self.pattern).map(|_| ())
    }
}

/// The alias-free shadow map: `afsm` (pixel centres) or `afsm-ss` (sub-samples).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AliasFreeShadowMap {
    /// Options.
    pub options: AfsmOptions,
    /// `afsm-ss` when true; `afsm` requires rate 1.
    pub supersampled: bool,
}

impl AliasFreeShadowMap {
    /// `afsm` with the given options (their rate must be 1).
    pub fn pixel_centres(options: AfsmOptions) -> Self {
        Self { options, supersampled: false }
    }

    /// `afsm-ss` with the given options.
    pub fn supersampled(options: AfsmOptions) -> Self {
        Self { options, supersampled: true }
    }

    /// Checks the options.
    pub fn validate(&self) -> Result<(), MethodError> {
        if !self.supersampled && self.options.rate != 1 {
            return Err(MethodError::InvalidOption {
                option: "--rate",
                message: format!(
                    "afsm samples pixel centres (rate 1), got {}; afsm-ss takes sub-samples",
                    self.options.rate
                ),
            });
        }
        self.options.validate()
    }
}

/// The light's projector of `afsm` (see "Light image" in the module doc): the fitted one at
/// [`LIGHT_IMAGE_RES`], with its frame taken from the surface points the camera sees at pixel
/// centres where the scene's frame is too coarse for them. Orthographic: when the fitted
/// frame's rounding (`f64::EPSILON` times its half extent or its origin's distance from those
/// points) exceeds [`SHADOW_OFFSET`] times their own magnitude, the origin moves to the centre
/// of their bounding box and the image rectangle shrinks around them, so that light image
/// coordinates and depths keep the precision of the visible scene however far other objects
/// lie. Spot: `near` no larger than [`SHADOW_OFFSET`] times the magnitude of the light's
/// position plus its distance to the farthest of those points (max norm), never zero.
///
/// The points' bounds (or farthest distance) are gathered in parallel over chunks of pixels
/// ([`per_object`], one slot): a minimum or maximum does not depend on the order of
/// reduction, and a zero bound is made `+0`, so that neither does the sign of a zero (the pass
/// over the 480,000 pixels of bunny-plane at 800 x 600 added 1.35 ms to the stage at one
/// thread, 0.6 at two; the methods call this inside a stage). `afsm` on the CPU makes the same
/// frame from the scene's fitted one it already has (`transformed`): under a spot light by the
/// same pass (`near_visible`), under a directional one bounding the points while it makes its
/// samples.
pub fn light_projector(frame: &Frame<'_>) -> Projector {
    let light = frame.light_projector(LIGHT_IMAGE_RES, LightFit::Scene);
    let g = &frame.gbuffer;
    match light.kind {
        ProjectionKind::Orthographic { .. } => {
            let empty = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            let join = |(lo, hi): (DVec3, DVec3), (a, b): (DVec3, DVec3)| (lo.min(a), hi.max(b));
            recentred(light, over_visible(g, empty, |p| (p, p), join))
        }
        ProjectionKind::Perspective { .. } => near_visible(light, g),
    }
}

/// The perspective `light` with its `near` plane no farther than the local one of the surface
/// points the camera sees at pixel centres in `g` ([`light_projector`]).
fn near_visible(mut light: Projector, g: &GBuffer) -> Projector {
    let q = light.origin;
    let reach = over_visible(g, 0.0, |p| (p - q).abs().max_element(), f64::max);
    let local = SHADOW_OFFSET * (q.abs().max_element() + reach);
    if local > 0.0 && local < light.near {
        light.near = local;
    }
    light
}

/// The orthographic `light` with its frame taken from the surface points the camera sees at
/// pixel centres, whose bounds are `(lo, hi)`, where its own frame is too coarse for them
/// ([`light_projector`]); `light` itself otherwise, and for a perspective light.
fn recentred(mut light: Projector, (lo, hi): (DVec3, DVec3)) -> Projector {
    let ProjectionKind::Orthographic { half_width, half_height } = light.kind else {
        return light;
    };
    let (lo, hi) = (lo + DVec3::ZERO, hi + DVec3::ZERO);
    let centre = 0.5 * (lo + hi);
    let (mut hw, mut hh) = (0.0f64, 0.0f64);
    for c in scenes::mesh::box_corners(lo, hi) {
        let c = c - centre;
        hw = hw.max(c.dot(light.right).abs());
        hh = hh.max(c.dot(light.up).abs());
    }
    // The fitted frame rounds light coordinates to about `EPSILON` of its scale; keep it
    // while that stays below the shadow offset of the visible points.
    let fitted = half_width.max(half_height).max((light.origin - centre).abs().max_element());
    let local = hw.max(hh) + centre.abs().max_element();
    let coarse = f64::EPSILON * fitted > SHADOW_OFFSET * local;
    if coarse && centre.is_finite() && hw > 0.0 && hh > 0.0 && hw.max(hh).is_finite() {
        light.origin = centre;
        light.kind = ProjectionKind::Orthographic { half_width: hw, half_height: hh };
    }
    light
}

/// The light's projector ([`light_projector`]) and the visible sub-samples on its image plane
/// ([`transform_samples`]). Under a directional light the samples are first made with the
/// fitted frame, which gathers the bounds of the centre points as it goes, and made again only
/// where those bounds find the frame too coarse (a scene with an object far away). A separate
/// pass over the G-buffer's positions for the bounds cost the stage 2 ms of 9 on
/// `bunny-plane` at 800 x 600 (medians 9.1 -> 7.1 ms, one pinned thread, 6 alternating runs
/// of 5 frames, load 1.0-1.2), 1.9 of 9 on `cage`.
fn transformed(
    frame: &Frame<'_>,
    surfaces: &[Surface<'_>],
    pattern: &SamplePattern,
) -> (Projector, Vec<Sample>) {
    let fitted = frame.light_projector(LIGHT_IMAGE_RES, LightFit::Scene);
    let transform = |light: &Projector| {
        transform_samples(&frame.camera, light, surfaces, pattern, frame.width())
    };
    if fitted.is_perspective() {
        let light = near_visible(fitted, &frame.gbuffer);
        let samples = transform(&light).samples;
        return (light, samples);
    }
    let first = transform(&fitted);
    let light = recentred(fitted, first.centre_bounds);
    if light == fitted {
        return (light, first.samples);
    }
    drop(first);
    let samples = transform(&light).samples;
    (light, samples)
}

/// `f` of the surface point of every covered pixel of `g`, joined by `join` (associative and
/// commutative) from `init`, in parallel over chunks of pixels.
fn over_visible<A: Copy + Send + Sync>(
    g: &GBuffer,
    init: A,
    f: impl Fn(DVec3) -> A + Sync,
    join: impl Fn(A, A) -> A + Sync,
) -> A {
    let step = |acc: &mut [A], k: usize| {
        if g.covered(k) {
            acc[0] = join(acc[0], f(g.position[k]));
        }
    };
    per_object(g.triangle.len(), 1, init, step, &join)[0]
}

/// Per pixel, the mean over its `rate` sub-samples of their light (lit for sub-samples that
/// have no sample), from the light of each sample in BSP order: `lit`, the mean of the three
/// channels, and with `rgb` also the RGB transmittance.
///
/// Light that is all or nothing ([`Shade::ALL_OR_NOTHING`], without `rgb`) is resolved by
/// counting each pixel's dark samples: a pixel's light depends only on how many of its
/// sub-samples are lit, so each count's light is made once by the same arithmetic (the mean of
/// that many lit and dark sub-samples) and looked up. On `bunny-plane` at one sub-sample per
/// pixel the mean per pixel took about 5 ms at one thread. The counts are gathered in
/// parallel over the samples into atomic counters: at one sub-sample per pixel every pixel
/// has one sample, and a dark one is stored as its count (a plain store); otherwise each adds
/// its 1. A serial count was the stage's last serial part (1.2-1.3 ms at two threads on
/// `bunny-plane` and `cage` at 800 x 600).
fn resolve<S: Shade>(
    bsp: &Bsp,
    light: &[S],
    pixels: usize,
    rate: usize,
    rgb: bool,
) -> (Vec<f32>, Option<Vec<[f32; 3]>>) {
    let mean = |subs: &[S]| {
        let mut sum = [0.0f64; 3];
        for sub in subs {
            for (acc, c) in sum.iter_mut().zip(sub.rgb()) {
                *acc += c;
            }
        }
        sum.map(|c| (c / rate as f64).clamp(0.0, 1.0))
    };
    let lit_of = |c: [f64; 3]| ((c[0] + c[1] + c[2]) / 3.0).clamp(0.0, 1.0) as f32;
    if S::ALL_OR_NOTHING && !rgb {
        let mut dark_sample = S::LIT;
        dark_sample.attenuate(&[0.0; 3]);
        // The light of a pixel with `n` dark sub-samples, at `by_dark[n]`.
        let by_dark: Vec<f32> = (0..=rate)
            .map(|n| {
                let subs: Vec<S> =
                    (0..rate).map(|k| if k < n { dark_sample } else { S::LIT }).collect();
                lit_of(mean(&subs))
            })
            .collect();
        let dark: Vec<AtomicU32> =
            (0..pixels).into_par_iter().with_min_len(CHUNK).map(|_| AtomicU32::new(0)).collect();
        // The pattern's rates are powers of two: a shift, not a division per sample.
        if rate == 1 {
            count_dark(bsp, light, |id| dark[id as usize].store(1, Ordering::Relaxed));
        } else if rate.is_power_of_two() {
            let shift = rate.trailing_zeros();
            count_dark(bsp, light, |id| {
                dark[(id >> shift) as usize].fetch_add(1, Ordering::Relaxed);
            });
        } else {
            count_dark(bsp, light, |id| {
                dark[id as usize / rate].fetch_add(1, Ordering::Relaxed);
            });
        }
        let lit = dark
            .into_par_iter()
            .with_min_len(CHUNK)
            .map(|n| by_dark[n.into_inner() as usize])
            .collect();
        return (lit, None);
    }
    let mut per_id = vec![S::LIT; pixels * rate];
    for (s, l) in bsp.samples.iter().zip(light) {
        per_id[s.id as usize] = *l;
    }
    let lit = per_id.par_chunks(rate).map(|subs| lit_of(mean(subs))).collect();
    let transmittance =
        rgb.then(|| per_id.par_chunks(rate).map(|subs| mean(subs).map(|v| v as f32)).collect());
    (lit, transmittance)
}

/// Items per task of [`resolve`]'s parallel passes.
const CHUNK: usize = 1 << 14;

/// Calls `dark(id)` for each dark sample's id, in parallel.
fn count_dark<S: Shade>(bsp: &Bsp, light: &[S], dark: impl Fn(u32) + Sync) {
    bsp.samples.par_iter().zip(light).with_min_len(CHUNK).for_each(|(s, l)| {
        if l.is_dark() {
            dark(s.id);
        }
    });
}

impl AliasFreeShadowMap {
    /// The BSP and rasterization stages with per-sample light `S`; per pixel the light and,
    /// with the scene's transparency, the RGB transmittance.
    fn shade<S: Shade>(
        &self,
        frame: &Frame<'_>,
        samples: Vec<Sample>,
        light: &Projector,
        rate: usize,
        rec: &mut Recorder,
    ) -> (Vec<f32>, Option<Vec<[f32; 3]>>) {
        let leaf_size = self.options.leaf_size as usize;
        let bsp = rec.stages.time(STAGE_BSP, || Bsp::build(samples, leaf_size));
        let transparency = frame.effects.transparency;
        let passes: Vec<[f64; 3]> = frame
            .scene
            .objects
            .iter()
            .map(|o| {
                let pass =
                    if transparency { (1.0 - o.material.opacity).clamp(0.0, 1.0) } else { 0.0 };
                [pass; 3]
            })
            .collect();
        let culling = Culling {
            occlusion: self.options.occlusion_culling,
            depth: self.options.depth_culling,
        };
        let pixels = frame.gbuffer.triangle.len();
        let facing_culling = self.options.facing_culling;
        let (resolved, counters, facing) = rec.stages.time(STAGE_RASTERIZATION, || {
            let opaque = |o: usize| frame.object_casts_shadows(o) && passes[o] == [0.0; 3];
            // At one sub-sample per pixel, the samples lie on the G-buffer's triangles.
            let seen = if rate == 1 {
                facing::Seen::Pixels(&frame.gbuffer.triangle)
            } else {
                facing::Seen::Samples(&bsp.samples)
            };
            let facing = facing_culling.then(|| facing::Needed::new(frame, seen, light, opaque));
            let (light_per_sample, counters) = rasterize_blockers::<S>(
                &frame.geometry,
                |t| frame.is_caster(t) && facing.as_ref().is_none_or(|f| f.needs(frame, t)),
                &passes,
                light,
                &bsp,
                culling,
            );
            (resolve(&bsp, &light_per_sample, pixels, rate, transparency), counters, facing)
        });
        if let Some(objects) = facing.map(|f| f.objects()).filter(|&n| n > 0) {
            let (casters, their) =
                if objects == 1 { ("caster", "its") } else { ("casters", "their") };
            rec.notes.push(format!(
                "{objects} closed {casters} seen from outside: only {their} triangles facing the \
                 light rasterized, whose shadow is the whole caster's"
            ));
        }
        rec.counters.merge(&Counters { bsp_nodes: bsp.nodes.len() as u64, ..counters });
        resolved
    }
}

impl ShadowMethod for AliasFreeShadowMap {
    fn name(&self) -> &'static str {
        if self.supersampled {
            "afsm-ss"
        } else {
            "afsm"
        }
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let o = &self.options;
        let mut m = serde_json::Map::new();
        if self.supersampled {
            m.insert("rate".into(), o.rate.into());
            m.insert("pattern".into(), o.pattern.name().into());
        }
        m.insert("leaf_size".into(), o.leaf_size.into());
        m.insert("occlusion_culling".into(), o.occlusion_culling.into());
        m.insert("depth_culling".into(), o.depth_culling.into());
        m.insert("facing_culling".into(), o.facing_culling.into());
        m
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        self.validate()?;
        let pattern = SamplePattern::new(self.options.rate, self.options.pattern)?;
        let rate = pattern.rate() as usize;
        let g = &frame.gbuffer;
        if (g.triangle.len() as u64) * rate as u64 > u64::from(u32::MAX) {
            return Err(MethodError::NotApplicable(format!(
                "{}: {} x {} pixels at {rate} sub-samples exceed 2^32 samples",
                self.name(),
                frame.width(),
                frame.height()
            )));
        }
        let extra: Vec<Option<crate::raster::NearestSurface>> = (0..rate)
            .map(|s| {
                if s == pattern.centre_index() {
                    return None;
                }
                let shift = pattern.offsets()[s] - DVec2::splat(0.5);
                Some(rec.stages.time(&gbuffer_stage(s), || {
                    rasterize_nearest_at(
                        &frame.geometry,
                        |_| true,
                        &frame.camera,
                        shift,
                        &mut rec.counters,
                    )
                }))
            })
            .collect();
        let surfaces: Vec<Surface<'_>> = extra
            .iter()
            .map(|e| match e {
                Some(n) => Surface { triangle: &n.triangle, depth: &n.depth },
                None => Surface { triangle: &g.triangle, depth: &g.depth },
            })
            .collect();
        let (light, samples) =
            rec.stages.time(STAGE_TRANSFORMATION, || transformed(frame, &surfaces, &pattern));
        drop(surfaces);
        drop(extra);
        let (lit, transmittance) = if frame.effects.transparency {
            self.shade::<[f64; 3]>(frame, samples, &light, rate, rec)
        } else {
            self.shade::<bool>(frame, samples, &light, rate, rec)
        };
        Ok(Visibility { width: frame.width(), height: frame.height(), lit, transmittance })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The samples made with the fitted frame, whose bounds decide whether to make them
    /// again, are those of the light [`light_projector`] fits from the G-buffer, bit for bit:
    /// built-in scenes under directional and spot lights, and `spheres` with one triangle
    /// 1e10 away, whose fitted frame is too coarse for the visible points; at one sub-sample
    /// per pixel and at four.
    #[test]
    fn samples_made_once_equal_those_of_the_light_fitted_from_the_g_buffer() {
        let far = |mut scene: scenes::Scene| {
            let p = DVec3::new(1e10, 3.0, -1e10);
            let mesh = scenes::Mesh::new(vec![p, p + DVec3::X, p + DVec3::Z], vec![[0, 1, 2]])
                .expect("valid mesh");
            let material = scenes::Material::default();
            let far = scenes::Object { name: "far".into(), mesh, material, casts_shadows: true };
            scene.objects.push(far);
            scene
        };
        let mut coarse = 0;
        for (name, far_away) in
            [("spheres", false), ("spot-spheres", false), ("cage", false), ("spheres", true)]
        {
            let Some(Ok(scene)) = scenes::registry::load_builtin(name) else { continue };
            let scene = if far_away { far(scene) } else { scene };
            let frame = Frame::new(&scene, 40, 30, &mut Recorder::default());
            let g = &frame.gbuffer;
            let centre = Surface { triangle: &g.triangle, depth: &g.depth };
            let want_light = light_projector(&frame);
            let fitted = frame.light_projector(LIGHT_IMAGE_RES, LightFit::Scene);
            coarse += usize::from(want_light != fitted);
            for rate in [1, 4] {
                let pattern = SamplePattern::new(rate, PatternKind::Grid).expect("valid rate");
                // Sub-samples other than the centre see the centre's surface (only the
                // centre's points are bounded).
                let surfaces = vec![centre; rate as usize];
                let (light, samples) = transformed(&frame, &surfaces, &pattern);
                assert_eq!(light, want_light, "{name} (far: {far_away}) at rate {rate}");
                let want =
                    transform_samples(&frame.camera, &light, &surfaces, &pattern, frame.width());
                assert_eq!(samples, want.samples, "{name} (far: {far_away}) at rate {rate}");
                assert!(!samples.is_empty());
            }
        }
        assert!(coarse >= 1, "a far triangle makes the fitted frame too coarse");
    }

    /// Counting each pixel's dark samples gives the light the mean of its sub-samples gives,
    /// bit for bit: the same samples resolved as all-or-nothing light and as RGB
    /// transmittance, at rates that are powers of two and one that is not, with sub-samples
    /// that have no sample.
    #[test]
    fn counted_dark_samples_give_the_mean_of_the_sub_samples() {
        let pixels = 50;
        for rate in [1usize, 3, 4, 32] {
            // Every fifth sub-sample has no sample; the others are dark by a pattern.
            let samples: Vec<Sample> = (0..pixels * rate)
                .filter(|id| id % 5 != 0)
                .map(|id| Sample {
                    x: (id * 7 % 13) as f64,
                    y: (id % 11) as f64,
                    id: id as u32,
                    ..Sample::default()
                })
                .collect();
            let bsp = Bsp::build(samples, 4);
            let dark: Vec<bool> = bsp.samples.iter().map(|s| (s.id * 31 % 7) < 3).collect();
            let rgb: Vec<[f64; 3]> =
                dark.iter().map(|&d| if d { [0.0; 3] } else { [1.0; 3] }).collect();
            let (counted, none) = resolve(&bsp, &dark, pixels, rate, false);
            let (mean, _) = resolve(&bsp, &rgb, pixels, rate, false);
            assert!(none.is_none());
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&counted), bits(&mean), "rate {rate}");
            assert!(counted.iter().any(|&l| l > 0.0 && l < 1.0) || rate == 1);
        }
    }
}
