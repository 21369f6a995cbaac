//! `spsm`, `spsm-f32`: sub-pixel shadow maps (Lecocq, Marvie, Sourimant and Gautron,
//! "Sub-Pixel Shadow Mapping", ACM SIGGRAPH Symposium on Interactive 3D Graphics and Games
//! (I3D) 2014).
//!
//! The map stores, per texel, the closest triangle touching it instead of a depth, and each
//! pixel's shadow is decided from that partial geometry with sub-pixel precision.
//!
//! # Stages (each timed under its name, see the `STAGE_*` constants)
//!
//! 1. **conservative rasterization** ([`raster`], section 3.2): every caster triangle gives a
//!    fragment to every texel its projection touches; the texel keeps the fragment of smallest
//!    minimum conservative depth (Hasselgren et al. 2005). Counters `triangles_rasterized`,
//!    `raster_samples_tested` (texels tested exactly), `conservative_fragments`.
//! 2. **packing** ([`pack`](mod@pack), in the texel layout of [`texel`], sections 3.3 and
//!    3.4): the kept triangle as a 128-bit texel (three 16-bit 2D vertices, 16-bit depth at
//!    the texel centre, two 8-bit derivative codes [`quantize`]) for `spsm`, or as `f32` for
//!    `spsm-f32`. Counter `packed_texels`.
//! 3. **classification** ([`classify`], section 4.1, Algorithm 1): lit by one lookup,
//!    shadowed by one lookup, shadowed by the 3x3 neighbourhood, or uncertain. Counters
//!    `lit_by_one_lookup`, `shadowed_by_one_lookup`, `shadowed_by_neighbourhood`,
//!    `uncertain_pixels`, `shadow_map_lookups`.
//! 4. **consistent min depth** ([`depth`], section 4, Fig. 9): the smallest depth the decoded
//!    triangle spawns inside its texel, for the texels around uncertain pixels (the only ones
//!    the tangent estimate reads). Counter `depth_corrected_texels` (those where it lies above
//!    the conservative corner depth).
//! 5. **silhouette recovery** ([`recover`], section 4.2, Figs. 7, 8, 10): uncertain pixels
//!    from the 3x3 depth-test pattern, a tangent look-up table and the piecewise linear
//!    silhouette function. Counters `recovered_pixels`, `shadow_map_lookups`.
//! 6. **antialiasing** ([`antialias`], section 5): the recovered function at the shared
//!    sample pattern's sub-samples, uncertain pixels only. Runs when `rate > 1`; recorded as
//!    skipped at rate 1. Counter `antialiased_samples`.
//!
//! [`Spsm::run_classified`] also returns each pixel's [`PixelClass`], and [`class_image`]
//! colours them as Fig. 14 does.
//!
//! # Invariants
//!
//! - Output values are in `[0, 1]`: 0 or 1 at rate 1, multiples of `1 / rate` above.
//! - Deterministic: ties in the map go to the lower triangle id; every per-pixel decision
//!   depends only on the map and the pixel.
//! - Pixels with no surface, or whose point falls outside the map, are lit (as in `sm`).
//! - The lit and shadowed classifications add the decoded texel's own error bounds (depth,
//!   derivatives, vertices: [`texel::Tri`]) to the constant bias, so packing never makes a
//!   lit plane dark by itself; a lit plane stays lit at every map size and light angle.
//!
//! # Choices where the paper is vague
//!
//! - **Map depth** is the light depth for directional lights and `-1/depth` for spot lights
//!   (affine in the map, as equation 1 needs); derivative angles are taken against the world
//!   size of a texel at the texel's depth ([`texel`]).
//! - **16-bit vertices** are absolute fixed point over `[-R/2, 3R/2]` texels (so shared
//!   vertices decode identically in every texel); **16-bit depth** is linear over the scene's
//!   light depth range. A vertex outside the range is clamped, and the run record says so.
//! - **Extreme derivative codes** (surfaces within about 0.07° of edge-on for `x^5`) have an
//!   unbounded error: such a texel cannot prove a shadow by itself ([`quantize`]); the
//!   recovery pattern caps the margin it allows ([`recover`]).
//! - **Algorithm 1** as printed returns `true` on both branches; we read it as "the stored
//!   triangle occludes `p` iff its plane passes in front of `p` and `p` lies in its 2D
//!   triangle".
//! - **Minimum conservative depth** is Hasselgren et al.'s: the plane at the texel corner
//!   where it is smallest, clamped to the triangle's vertex depths ([`raster`]). Measured
//!   without the clamp, steep silhouette triangles win more texels (Fig. 3's intent) and
//!   the `f32` texel gains on ground shadow edges, but the packed texel loses more on those
//!   nearly edge-on triangles than the `f32` one gains. With the facing-away rule below,
//!   unclamped / clamped, `spsm` bunny-plane 512 99.013 / 99.513, 1024 99.443 / 99.767,
//!   spheres 1024 99.607 / 99.946: edge-on back faces win texels and light themselves; not
//!   lighting back faces by one lookup fixes that (`spsm-f32` spheres 1024 100.000, bunny-plane
//!   1024 99.775) but darkens open surfaces (see below).
//! - **Receivers facing away from the light** (face normal away from it) whose recovery
//!   pattern holds an occluded texel are shadowed, whatever the tangents say ([`recover`]):
//!   light reaches them only through their own surface (`raytrace`'s shadow ray crosses the
//!   closed caster; `sm`'s depth test finds its front side). On bunny-plane at 1024, 6762 of
//!   `spsm`'s 9800 wrong pixels were such receivers. Pixel match at 1920x1080 against
//!   `raytrace`, `spsm` before / after (`sm`): bunny-plane 512 98.716 / 99.513 (98.967), 1024
//!   99.239 / 99.767 (99.316), 2048 99.602 / 99.895 (99.550); spheres 512 99.059 / 99.847
//!   (98.761), 1024 99.537 / 99.946 (99.145). Without the occluder condition (every uncertain
//!   receiver facing away shadowed) the numbers are the same to 0.003, and open single-sided
//!   surfaces seen from behind are not darkened. Tried and dropped: never lighting a
//!   receiver facing away by one lookup (random-1k at 960x540, map 1024: 93.2 against 99.3,
//!   `sm` 98.8, its open triangles go dark).
//! - **Tolerances**: the constant term of the shared bias rule ([`crate::depth_test`],
//!   `--constant-bias`) plus each decoded texel's own error bound. `slope_bias` and
//!   `max_slope` are validated but not used: equation 1 evaluates each stored plane at the
//!   point itself, and the recovery pattern compares against the receiver's own plane
//!   exactly ([`classify`], [`recover`]); the run record lists only what is used.
//! - **Consistent minimum depth** is computed exactly by clipping, once per texel read
//!   ([`depth`]);
//!   the recovery pattern also checks each neighbour against the receiver's own plane.
//! - **Tangent patterns** are derived, not drawn: one tangent per run of free neighbours
//!   around the ring, perpendicular to the run's mean direction; **4-connectivity** keeps the
//!   occluded texels linked to the centre; **vertex selection** keeps the vertices of the
//!   edges facing the tangent axis; **φ** is the nearest facing edge, linked across gaps,
//!   `+∞` beyond the outermost vertex ([`recover`]).
//! - **Antialiasing** positions each sub-sample on the plane of the pixel's surface
//!   ([`antialias`]).
//! - Casters with opacity < 1 are treated as opaque (the run record says so).

pub mod antialias;
pub mod classify;
pub mod depth;
pub mod neighbourhood;
pub mod pack;
pub mod quantize;
pub mod raster;
pub mod recover;
pub mod texel;

pub use classify::PixelClass;
pub use texel::TexelFormat;

use crate::{
    depth_test::{DepthTester, MapOptions},
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    pattern::{PatternKind, SamplePattern},
};
use instrumentation::Recorder;

/// Name of stage 1.
pub const STAGE_RASTER: &str = "conservative rasterization";
/// Name of stage 2.
pub const STAGE_PACKING: &str = "packing";
/// Name of stage 3.
pub const STAGE_CLASSIFICATION: &str = "classification";
/// Name of stage 4.
pub const STAGE_CONSISTENT_DEPTH: &str = "consistent min depth";
/// Name of stage 5.
pub const STAGE_RECOVERY: &str = "silhouette recovery";
/// Name of stage 6.
pub const STAGE_ANTIALIASING: &str = "antialiasing";

/// Options of the sub-pixel shadow map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpsmOptions {
    /// Map resolution and constant bias (`--map-res`, `--constant-bias`); defaults as
    /// [`MapOptions::default`]. The slope-scaled terms are validated but not used.
    pub map: MapOptions,
    /// Texel storage: [`TexelFormat::Packed`] (128 bits, `spsm`, the default) or
    /// [`TexelFormat::F32`] (`spsm-f32`).
    pub texel: TexelFormat,
    /// Exponent `n` of the derivative code `x^n` (`--derivative-power`), 1 (linear) to
    /// [`quantize::MAX_POWER`]; default 5 (the paper's). Packed texels only.
    pub derivative_power: u32,
    /// Sub-samples per uncertain pixel (`--rate`): 1 (no antialiasing, the default), 4, 8,
    /// 16, 32, 64 or 128.
    pub rate: u32,
    /// Sub-sample pattern (`--pattern`); default grid.
    pub pattern: PatternKind,
}

impl Default for SpsmOptions {
    fn default() -> Self {
        Self {
            map: MapOptions::default(),
            texel: TexelFormat::Packed,
            derivative_power: quantize::DEFAULT_POWER,
            rate: 1,
            pattern: PatternKind::Grid,
        }
    }
}

impl SpsmOptions {
    /// Checks the options; errors name the command-line flag.
    pub fn validate(&self) -> Result<SamplePattern, MethodError> {
        self.map.validate()?;
        if !(1..=quantize::MAX_POWER).contains(&self.derivative_power) {
            return Err(MethodError::InvalidOption {
                option: "--derivative-power",
                message: format!(
                    "must be in 1..={} (1 is the linear code), got {}",
                    quantize::MAX_POWER,
                    self.derivative_power
                ),
            });
        }
        SamplePattern::for_method(self.rate, self.pattern)
    }
}

/// The sub-pixel shadow map.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Spsm {
    /// Options.
    pub options: SpsmOptions,
}

/// Colours the classes as Fig. 14 does, over a grey rendering of `lit`: green where the
/// 3x3 neighbourhood shadowed the pixel, red where silhouette recovery ran; elsewhere
/// light grey for lit and dark grey for shadowed pixels, black where no surface is mapped.
/// Row by row, RGB.
pub fn class_image(classes: &[PixelClass], lit: &[f32]) -> Vec<[u8; 3]> {
    classes
        .iter()
        .zip(lit)
        .map(|(&c, &l)| match (c.fig14_colour(), c) {
            (Some(rgb), _) => rgb,
            (None, PixelClass::Unmapped) => [0, 0, 0],
            (None, _) => {
                let g = (90.0 + 150.0 * l.clamp(0.0, 1.0)).round() as u8;
                [g, g, g]
            }
        })
        .collect()
}

/// Stages 1 and 2: the map of `frame` under options `o`, the bias rule and the map's space.
pub fn build_map(
    o: &SpsmOptions,
    frame: &Frame<'_>,
    rec: &mut Recorder,
) -> (texel::SpsmMap, DepthTester, texel::LightSpace) {
    let (projector, space, tester) = map_frame(o, frame);
    let raster = rec.stages.time(STAGE_RASTER, || {
        raster::rasterize_conservative(
            &frame.geometry,
            |t| frame.is_caster(t),
            &projector,
            &space,
            &mut rec.counters,
        )
    });
    (pack(o, raster, space, rec), tester, space)
}

/// The map's light projector, its light space and the depth tester of `o` on `frame`.
pub(crate) fn map_frame(
    o: &SpsmOptions,
    frame: &Frame<'_>,
) -> (scenes::Projector, texel::LightSpace, DepthTester) {
    let projector = frame.light_projector(o.map.map_res, o.map.frustum);
    let space = texel::LightSpace::new(&projector, frame.light_depth_bounds(&projector));
    let tester = DepthTester::new(&o.map, projector, frame.light_depth_range(&projector));
    (projector, space, tester)
}

/// Stage 2, packing of the conservatively rasterized map `raster`.
pub(crate) fn pack(
    o: &SpsmOptions,
    raster: raster::ConservativeMap,
    space: texel::LightSpace,
    rec: &mut Recorder,
) -> texel::SpsmMap {
    let (map, packed, clamped) = rec
        .stages
        .time(STAGE_PACKING, || pack::pack_map(&raster, space, o.texel, o.derivative_power));
    drop(raster);
    record_packing(packed, clamped, rec);
    map
}

/// The packing's counter (`packed` texels filled) and its note on the `clamped` ones.
pub(crate) fn record_packing(packed: u64, clamped: u64, rec: &mut Recorder) {
    rec.counters.packed_texels += packed;
    if clamped > 0 {
        rec.notes.push(format!(
            "{clamped} packed texels hold a vertex outside the 16-bit range [-R/2, 3R/2] \
             (clamped)"
        ));
    }
}

/// Stages 4 to 6 after classification: consistent min depth, silhouette recovery and
/// antialiasing of the `uncertain` pixels, deciding their values in `lit`.
pub(crate) fn finish(
    o: &SpsmOptions,
    frame: &Frame<'_>,
    lookup: &classify::Lookup<'_>,
    sample_pattern: &SamplePattern,
    uncertain: &[classify::UncertainPixel],
    lit: &mut [f32],
    rec: &mut Recorder,
) {
    let (consistent, corrected) = rec.stages.time(STAGE_CONSISTENT_DEPTH, || {
        let centres: Vec<u32> = uncertain.iter().map(|u| u.texel).collect();
        depth::consistent_depths(lookup.map, &centres)
    });
    rec.counters.depth_corrected_texels += corrected;
    recover_and_antialias(o, frame, lookup, sample_pattern, uncertain, &consistent, lit, rec);
}

/// Stages 5 and 6: silhouette recovery and antialiasing of the `uncertain` pixels, with the
/// consistent minimum depths of stage 4.
#[allow(clippy::too_many_arguments)]
pub(crate) fn recover_and_antialias(
    o: &SpsmOptions,
    frame: &Frame<'_>,
    lookup: &classify::Lookup<'_>,
    sample_pattern: &SamplePattern,
    uncertain: &[classify::UncertainPixel],
    consistent: &depth::ConsistentDepths,
    lit: &mut [f32],
    rec: &mut Recorder,
) {
    let silhouettes = recover(frame, lookup, consistent, uncertain, lit, rec);
    if o.rate > 1 {
        let counters = rec.stages.time(STAGE_ANTIALIASING, || {
            antialias::antialias_pixels(frame, lookup, sample_pattern, uncertain, &silhouettes, lit)
        });
        rec.counters.merge(&counters);
    } else {
        rec.stages.skip(STAGE_ANTIALIASING);
    }
}

/// Stage 5: silhouette recovery of the `uncertain` pixels, deciding their binary values in
/// `lit`; their silhouettes, for the antialiasing.
pub(crate) fn recover(
    frame: &Frame<'_>,
    lookup: &classify::Lookup<'_>,
    consistent: &depth::ConsistentDepths,
    uncertain: &[classify::UncertainPixel],
    lit: &mut [f32],
    rec: &mut Recorder,
) -> Vec<Option<recover::Silhouette>> {
    let (silhouettes, counters) = rec.stages.time(STAGE_RECOVERY, || {
        recover::recover_pixels(frame, lookup, consistent, uncertain, lit)
    });
    rec.counters.merge(&counters);
    silhouettes
}

impl Spsm {
    /// Runs the method and also returns each pixel's class (Fig. 14).
    pub fn run_classified(
        &self,
        frame: &Frame<'_>,
        rec: &mut Recorder,
    ) -> Result<(Visibility, Vec<PixelClass>), MethodError> {
        let sample_pattern = self.options.validate()?;
        if frame.effects.transparency {
            rec.notes.push(format!("{} treats semi-transparent casters as opaque", self.name()));
        }
        let o = &self.options;
        let (map, tester, space) = build_map(o, frame, rec);
        let lookup = classify::Lookup { map: &map, tester, space };
        let (classes, mut lit, uncertain, counters) =
            rec.stages.time(STAGE_CLASSIFICATION, || classify::classify_pixels(frame, &lookup));
        rec.counters.merge(&counters);
        finish(o, frame, &lookup, &sample_pattern, &uncertain, &mut lit, rec);
        let vis =
            Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None };
        Ok((vis, classes))
    }
}

impl ShadowMethod for Spsm {
    fn name(&self) -> &'static str {
        match self.options.texel {
            TexelFormat::Packed => "spsm",
            TexelFormat::F32 => "spsm-f32",
        }
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let o = &self.options;
        let mut m = serde_json::Map::new();
        m.insert("map_res".into(), o.map.map_res.into());
        m.insert("constant_bias".into(), o.map.constant_bias.into());
        m.insert("frustum".into(), o.map.frustum.as_str().into());
        m.insert("texel".into(), o.texel.name().into());
        if o.texel == TexelFormat::Packed {
            m.insert("derivative_power".into(), o.derivative_power.into());
        }
        m.insert("rate".into(), o.rate.into());
        m.insert("pattern".into(), o.pattern.name().into());
        m
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        self.run_classified(frame, rec).map(|(v, _)| v)
    }
}
