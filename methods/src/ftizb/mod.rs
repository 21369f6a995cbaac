//! `ftizb`: frustum-traced irregular z-buffers (Wyman, Hoetzlein and Lefohn, "Frustum-Traced
//! Raster Shadows: Revisiting Irregular Z-Buffers", ACM I3D 2015; and "Frustum-Traced Irregular
//! Z-Buffers: Fast, Sub-pixel Accurate Hard Shadows", IEEE TVCG 22(10), 2016).
//!
//! The heir of Aila and Laine's alias-free shadow maps ([`crate::afsm`]): the eye's samples are
//! the shadow map's sampling points, stored in a light-space grid of lists (the irregular
//! z-buffer, I3D 2015 section 3), and the casters are rasterized into it. What the frustum
//! tracing adds (I3D 2015 sections 4 and 5, TVCG 2016 sections 4 to 6): each pixel enters the
//! grid with the *footprint* of the pixel square on its receiver's tangent plane, not only its
//! centre; casters are rasterized *conservatively*, so every texel a caster touches is visited;
//! and each (pixel, caster) pair is a test of the caster's shadow frustum (the light's rays
//! through the triangle) against every sub-sample of the pixel, which the papers write as a
//! 32-bit visibility mask. The papers' 32 sub-samples per pixel are `--rate 32` of the shared
//! [`SamplePattern`] (any of its rates up to 128): the same pattern object as `pan09`,
//! `afsm-ss` and `raytrace`.
//!
//! # Stages, each timed under its own name
//!
//! | stage | constant | module | paper |
//! |---|---|---|---|
//! | camera G-buffer | (the frame's) | [`crate::gbuffer`] | I3D 2015 section 3, step 1 |
//! | sample footprints | [`STAGE_FOOTPRINTS`] | [`mod@footprints`] | I3D 2015 section 4.1; TVCG 2016 section 5.1 |
//! | conservative rasterization | [`STAGE_RASTERIZATION`] | [`frustum`] | I3D 2015 section 4.2 |
//! | frustum tests | [`STAGE_FRUSTUM_TESTS`] | [`frustum`] | I3D 2015 section 4.3; TVCG 2016 section 5.2 |
//!
//! The sample footprints stage begins with the light's frame fitted to the visible points
//! ([`crate::afsm::light_projector`]), which every later stage uses.
//!
//! Counters: `footprint_texels` (grid texels the pixels' footprints were inserted into: the
//! grid's list entries), `caster_texels` (non-empty texels a caster's conservative
//! rasterization reached), `visibility_evaluations` (the (pixel, caster) pairs whose frustum
//! test ran), `sampling_points_tested` (their sub-samples tested), `nodes_depth_culled`
//! ((texel, caster) pairs skipped because the caster lies beyond every sample of the texel).
//!
//! # Invariants
//!
//! - **The shadow predicate is the ray tracer's**, as `afsm`'s ([`crate::afsm`]): a sub-sample
//!   on the pixel's receiver is shadowed by caster triangle `T` iff `T` is not the pixel's own
//!   triangle, the sub-sample's light image point lies inside `T`'s projection (exact
//!   orientation predicates behind a floating-point filter, ties by the top-left rule:
//!   [`crate::afsm::blockers::Blocker`]) and `T` is nearer the light than the sub-sample by more
//!   than its shadow offset. The frustum test is that test in the light's image space, where
//!   the frustum through the triangle from the light is the prism over its projection. Every
//!   decision on `f64` inputs is thus exact, as in `afsm` and `afsm-ss`.
//! - **On a planar receiver `ftizb` at rate N equals `raytrace` at rate N** sub-sample for
//!   sub-sample (same pattern), up to sub-samples within `f64` rounding of a caster's edge:
//!   there the tangent plane is the surface, and the sub-sample's point is where the camera
//!   ray through it meets the plane, which is the ray tracer's hit (tested on both patterns).
//!   On curved receivers the sub-samples lie on the tangent plane of the pixel centre's
//!   triangle, as in the papers, and the error against `exact` is measured per pixel class.
//! - **Hidden sub-samples** ([`hidden`]): where a pixel spans several triangles of a curved
//!   receiver, sub-samples on the centre triangle's tangent plane can lie behind the real
//!   surface, where the receiver's own triangles shadow them. As Pan et al.'s validity mask
//!   (section 3.4), a sub-sample that a caster shadows *and* hides from the camera is left
//!   out of the pixel's ratio; the centre always counts. Measured at 800 x 600 against
//!   `exact`, surface pixels, mean error at 32 sub-samples before the rule: `bunny-plane`
//!   0.0826 (0.0045 at 1), `bumpy` (530,688 triangles, several a pixel) 0.1747 (0.0012 at 1),
//!   `pan09` 0.0140 and 0.0022.
//! - **Culling never changes a pixel**: a depth-culled caster is nearer no sample of the texel
//!   than its nearest corner.
//! - **Deterministic**: masks are combined with OR and the counters are sums; the result does
//!   not depend on threads.
//! - `lit` is `1 - popcount(occluded) / popcount(valid)`, in `[0, 1]`, a multiple of
//!   `1 / popcount(valid)`.
//!
//! # Choices where the papers leave them open
//!
//! - **Grid**: over the light image of `afsm` ([`crate::afsm::light_projector`]: the light's
//!   projector fitted to the scene, in which every sample's coordinates are computed), at
//!   `--izb-res` texels a side; by default the frame's larger side
//!   ([`FtizbOptions::grid_res`]), as the papers match the light-space resolution to the
//!   eye's (a 1024 x 1024 grid for 1024 x 768 frames). The grid only bins the samples, so its
//!   resolution changes the cost, never a decision (the results are equal bit for bit,
//!   tested); a grid much finer than the pixels lists each pixel in many texels (on `cage` at
//!   80 x 60 a 1024 grid listed each pixel in 72). Texels on the
//!   grid's border stand for everything beyond it on their side, so that samples outside the
//!   light image (a spot's points outside its cone, which the ray tracer also shadows) are
//!   kept.
//! - **Footprint of a pixel** ([`mod@footprints`]): the pixel square seen on the tangent plane of
//!   its G-buffer point and face normal, projected to the light: `pan09`'s facet
//!   ([`crate::pan09::facets::project_facet`], Pan et al. 2009 section 3.1), so that the two
//!   methods see the same sub-sample points and differ only in how they decide them. **At
//!   grazing angles** the tangent plane seen nearly edge-on makes that region unbounded; it is
//!   limited as the facet's, to points at most 4 times the centre's camera depth (perspective
//!   cameras) or within 64 pixel widths of it (orthographic ones), and to the spot light's
//!   side of its near plane; sub-samples outside it are not valid and are left out of the
//!   pixel's ratio (the centre always counts). A pixel whose tangent plane the camera sees
//!   exactly edge-on keeps its centre sample alone.
//! - **List layout**: the papers keep a linked list per texel (a head pointer and a next
//!   pointer per entry); here the (texel, pixel) entries are sorted into one array with an
//!   offset per texel (the same lists, read contiguously), pixels in row-major order.
//! - **Conservative rasterization**: every texel whose closed square the caster's projection
//!   may meet ([`crate::afsm::blockers::Blocker::overlaps`], conservative by a rounding
//!   margin), among the texels holding samples.
//! - **Work per texel**: the papers run one fragment per (caster, texel) that walks the
//!   texel's list; here the (texel, caster) pairs are sorted by texel and each texel's
//!   sub-samples are computed once and tested against all its casters, in caster order, in
//!   parallel over texels. A texel tests only the sub-samples whose light image point it holds
//!   ([`frustum`]), so that a pixel whose footprint meets several texels is not tested against
//!   a caster once per texel (the papers' duplicate tests).
//! - **Transparency**: casters are opaque (the run record says so when the scene has
//!   semi-transparent ones), as in `pan09`.
//! - **Memory**: 8 bytes per list entry and per (texel, caster) pair while they are sorted,
//!   4 bytes per texel for each list's offsets, about 80 bytes of masks per pixel
//!   (shadowed, hidden and valid sub-samples, 128 bits each, the first two also as atomic
//!   words while the texels run); each thread keeps one texel's sub-samples (56 bytes each
//!   with their coordinates again for the edge masks).

pub mod footprints;
pub mod frustum;
pub mod grid;
pub mod hidden;

use crate::{
    afsm::samples::Sample,
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    pattern::{PatternKind, SamplePattern},
};
use footprints::{footprints, SubSamples};
use frustum::{bin_casters, frustum_tests};
use grid::Grid;
use instrumentation::{Counters, Recorder};
use scenes::Projector;

/// Name of the stage that inserts the pixels' footprints into the light-space grid.
pub const STAGE_FOOTPRINTS: &str = "sample footprints";
/// Name of the stage that rasterizes the casters conservatively into the grid.
pub const STAGE_RASTERIZATION: &str = "conservative rasterization";
/// Name of the stage that tests each (pixel, caster) pair's sub-samples.
pub const STAGE_FRUSTUM_TESTS: &str = "frustum tests";

/// Largest grid side (the offsets of its lists take 4 bytes a texel: 64 MiB).
pub const MAX_IZB_RES: u32 = 4096;
/// Default sub-samples per pixel (the papers' 32).
pub const DEFAULT_RATE: u32 = 32;

/// Options of `ftizb`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FtizbOptions {
    /// Sub-samples per pixel (`--rate`): a rate of the shared pattern up to
    /// [`MAX_METHOD_RATE`](crate::pattern::MAX_METHOD_RATE). Default [`DEFAULT_RATE`].
    pub rate: u32,
    /// Sub-sample pattern (`--pattern`). Default grid.
    pub pattern: PatternKind,
    /// Texels per side of the light-space grid (`--izb-res`, 1 to [`MAX_IZB_RES`]); 0 (the
    /// default) for the frame's larger side ([`FtizbOptions::grid_res`]).
    pub izb_res: u32,
    /// Skip a caster in a texel when it lies beyond every sample there. Default on.
    pub depth_culling: bool,
}

impl Default for FtizbOptions {
    fn default() -> Self {
        Self { rate: DEFAULT_RATE, pattern: PatternKind::Grid, izb_res: 0, depth_culling: true }
    }
}

impl FtizbOptions {
    /// Checks the options; errors name the command-line flag.
    pub fn validate(&self) -> Result<(), MethodError> {
        if self.izb_res > MAX_IZB_RES {
            return Err(MethodError::InvalidOption {
                option: "--izb-res",
                message: format!(
                    "must be in 1..={MAX_IZB_RES}, or 0 for the frame's larger side; got {}",
                    self.izb_res
                ),
            });
        }
        SamplePattern::for_method(self.rate, self.pattern).map(|_| ())
    }

    /// The grid's side on a `width x height` frame: `izb_res`, or for 0 the larger side of
    /// the frame, at most [`MAX_IZB_RES`].
    pub fn grid_res(&self, width: u32, height: u32) -> u32 {
        match self.izb_res {
            0 => width.max(height).clamp(1, MAX_IZB_RES),
            r => r,
        }
    }
}

/// Per-sub-sample results of a run, for comparisons sample by sample: bit `s` of a pixel's
/// mask is sub-sample `s` of the pattern.
#[derive(Debug, Clone, PartialEq)]
pub struct SubsampleMasks {
    /// Sub-samples per pixel.
    pub rate: u32,
    /// Shadowed sub-samples per pixel.
    pub occlusion: Vec<u128>,
    /// Sub-samples counted in the pixel's ratio: those on the footprint's region that are not
    /// hidden; none for background pixels and pixels whose centre the light cannot project.
    pub valid: Vec<u128>,
    /// Sub-samples left out because a caster that shadows them hides them from the camera
    /// ([`hidden`]).
    pub hidden: Vec<u128>,
}

/// The frustum-traced irregular z-buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ftizb {
    /// Options.
    pub options: FtizbOptions,
}

impl Ftizb {
    /// The run: each pixel's light, occlusion mask and valid mask (the valid masks of the
    /// pixels some caster was tested against).
    fn masks(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Masked, MethodError> {
        self.options.validate()?;
        let pattern = SamplePattern::new(self.options.rate, self.options.pattern)?;
        let grid = Grid::new(self.options.grid_res(frame.width(), frame.height()));
        if frame.effects.transparency {
            rec.notes.push("ftizb treats semi-transparent casters as opaque".into());
        }
        let (light, lists) = rec.stages.time(STAGE_FOOTPRINTS, || {
            let light = crate::afsm::light_projector(frame);
            let lists = footprints(frame, &light, grid);
            (light, lists)
        });
        let lists = lists?;
        let subs = SubSamples::new(frame, &light, &pattern);
        let bins = rec.stages.time(STAGE_RASTERIZATION, || {
            bin_casters(&frame.geometry, |t| frame.is_caster(t), &light, grid, &lists)
        })?;
        let options = self.options;
        let (out, lit) = rec.stages.time(STAGE_FRUSTUM_TESTS, || {
            let out = frustum_tests(&frame.geometry, grid, &subs, &lists, &bins, &options);
            let lit = resolve(&out.occlusion, &out.valid);
            (out, lit)
        });
        rec.counters.merge(&Counters {
            footprint_texels: lists.entries() as u64,
            caster_texels: bins.entries() as u64,
            ..out.counters
        });
        let v =
            Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None };
        Ok(Masked {
            visibility: v,
            pattern,
            light,
            occlusion: out.occlusion,
            valid: out.valid,
            hidden: out.hidden,
        })
    }

    /// Runs `ftizb` and returns, besides the visibility, every pixel's sub-sample masks (the
    /// valid masks of pixels no caster reached are computed after the timed stages).
    pub fn run_masks(
        &self,
        frame: &Frame<'_>,
        rec: &mut Recorder,
    ) -> Result<(Visibility, SubsampleMasks), MethodError> {
        let Masked { visibility, pattern, light, occlusion, mut valid, hidden } =
            self.masks(frame, rec)?;
        let subs = SubSamples::new(frame, &light, &pattern);
        let mut scratch = vec![Sample::default(); pattern.rate() as usize];
        for (k, v) in valid.iter_mut().enumerate() {
            if *v == 0 {
                *v = subs.pixel(k, &mut scratch) & !hidden[k];
            }
        }
        Ok((visibility, SubsampleMasks { rate: pattern.rate(), occlusion, valid, hidden }))
    }
}

/// What [`Ftizb::masks`] gives.
struct Masked {
    visibility: Visibility,
    pattern: SamplePattern,
    light: Projector,
    occlusion: Vec<u128>,
    valid: Vec<u128>,
    hidden: Vec<u128>,
}

/// Per pixel [`lit`] of its shadowed and valid sub-samples.
fn resolve(occlusion: &[u128], valid: &[u128]) -> Vec<f32> {
    occlusion.iter().zip(valid).map(|(&o, &v)| lit((o & v).count_ones(), v.count_ones())).collect()
}

/// A pixel's light from its `shadowed` and `valid` sub-samples: `1 - shadowed / valid` in
/// `f64`, 1 where none is shadowed (on the CPU and, from its counts, the GPU).
pub fn lit(shadowed: u32, valid: u32) -> f32 {
    if shadowed == 0 {
        1.0
    } else {
        (1.0 - f64::from(shadowed) / f64::from(valid)).clamp(0.0, 1.0) as f32
    }
}

impl ShadowMethod for Ftizb {
    fn name(&self) -> &'static str {
        "ftizb"
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let o = &self.options;
        let mut m = serde_json::Map::new();
        m.insert("rate".into(), o.rate.into());
        m.insert("pattern".into(), o.pattern.name().into());
        m.insert("izb_res".into(), if o.izb_res == 0 { "frame".into() } else { o.izb_res.into() });
        m.insert("depth_culling".into(), o.depth_culling.into());
        m
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        Ok(self.masks(frame, rec)?.visibility)
    }
}

#[cfg(test)]
mod tests {
    use super::lit;

    #[test]
    fn lit_is_the_share_of_lit_valid_sub_samples() {
        assert_eq!(lit(0, 0), 1.0);
        assert_eq!(lit(0, 7), 1.0);
        assert_eq!(lit(1, 4), 0.75);
        assert_eq!(lit(4, 4), 0.0);
        assert_eq!(lit(1, 3), (1.0 - 1.0 / 3.0f64) as f32);
    }
}
