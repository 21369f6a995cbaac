//! `pcf-reeves`: percentage-closer filtering over the pixel's footprint in the shadow map,
//! sampled stochastically (Reeves, Salesin and Cook, "Rendering antialiased shadows with depth
//! maps", SIGGRAPH 1987, as described by Brabec and Seidel, section 3, and GPU Gems ch. 11,
//! section 11.2).
//!
//! Stages: `light depth map`, then `percentage-closer filtering`, which for every pixel
//! 1. maps the pixel's square into the shadow map ([`footprint`]): the camera rays through its
//!    four corners meet the plane of the surface seen at its centre (G-buffer position and
//!    face normal), the four points are projected to the light, and their bounding box is the
//!    region to filter (Reeves et al. use the bounding box of the projected micropolygon);
//! 2. draws `samples` points in that box, stratified on the cells of the shared pattern's
//!    grid ([`crate::pattern::grid_dims`]: 4 x 4 at 16 samples) and jittered uniformly
//!    within each cell by a seeded hash of (seed, pixel, sample): deterministic for a seed,
//!    independent of thread scheduling;
//! 3. compares the point's light depth against the texel under each sample (nearest texel)
//!    and returns the fraction not shadowed.
//!
//! Counter `shadow_map_lookups`: one per sample that lands inside the map (samples outside
//! are lit without a compare).
//!
//! # Invariants
//!
//! - Values are multiples of `1 / samples` in `[0, 1]`.
//! - A lit plane stays fully lit for `slope_bias >= 1` (below `max_slope`): the tolerance uses
//!   the pixel's own reach, the box's extent from the point plus half a texel on each axis.
//!
//! # Choices where the paper is vague
//!
//! - The footprint's half-extent is limited to [`MAX_FOOTPRINT`] texels around the point,
//!   and a pixel whose corner rays miss the tangent plane (silhouettes seen edge-on, rays
//!   behind the eye) uses that largest box: at grazing views the footprint grows without bound.
//! - No minimum footprint: where the map is magnified (box smaller than a texel) the samples
//!   fall into one or two texels and the result is close to `sm`'s, antialiased along texel
//!   edges only; that is the behaviour GPU Gems' fixed 4x4 region was designed to avoid.
//! - One depth per pixel (the surface point at the pixel centre) for all samples, as in the
//!   original, where the depth is the micropolygon's.

use crate::{
    depth_map::LightDepthMap,
    depth_test::{filter_pixels, texel_at, DepthTester, MapOptions, PixelResult, Receiver},
    footprint::Sampling,
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    pattern::{grid_dims, RATES},
};
use glam::{DVec2, DVec3};
use instrumentation::Recorder;
use scenes::Projector;

/// Name of the filtering stage.
pub const STAGE_FILTERING: &str = "percentage-closer filtering";

/// Largest half-extent of a footprint, in texels.
pub const MAX_FOOTPRINT: f64 = 16.0;

/// Options of `pcf-reeves`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReevesOptions {
    /// Map resolution and bias.
    pub map: MapOptions,
    /// Samples per pixel (`--rate`): 1, 4, 8, 16, 32, 64, 128, 256, 512 or 1024. Default 16.
    pub samples: u32,
    /// Seed of the jitter (`--seed`). Default 0.
    pub seed: u64,
}

impl Default for ReevesOptions {
    fn default() -> Self {
        Self { map: MapOptions::default(), samples: 16, seed: 0 }
    }
}

impl ReevesOptions {
    /// Checks the options; errors name the command-line flag.
    pub fn validate(&self) -> Result<(), MethodError> {
        self.map.validate()?;
        if !RATES.contains(&self.samples) {
            return Err(MethodError::InvalidOption {
                option: "--rate",
                message: format!(
                    "pcf-reeves takes {} samples per pixel, got {}",
                    RATES.iter().map(u32::to_string).collect::<Vec<_>>().join(", "),
                    self.samples
                ),
            });
        }
        Ok(())
    }
}

/// A pixel's footprint in the shadow map: an axis-aligned box in texels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footprint {
    /// Lower corner.
    pub lo: DVec2,
    /// Upper corner.
    pub hi: DVec2,
}

/// The footprint of pixel `(i, j)` whose surface point is `r` (position `p`, unit normal `n`):
/// the bounding box of its corners mapped through the tangent plane into the map, limited to
/// [`MAX_FOOTPRINT`] texels around `r.xy`.
pub fn footprint(
    camera: &Projector,
    light: &Projector,
    (i, j): (u32, u32),
    p: DVec3,
    n: DVec3,
    r: &Receiver,
) -> Footprint {
    let limit = Footprint {
        lo: r.xy - DVec2::splat(MAX_FOOTPRINT),
        hi: r.xy + DVec2::splat(MAX_FOOTPRINT),
    };
    let (mut lo, mut hi) = (r.xy, r.xy);
    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let corner = DVec2::new(f64::from(i + dx), f64::from(j + dy));
        let ray = camera.ray(corner);
        let Some(t) = ray.intersect_plane(n, n.dot(p)) else { return limit };
        if t <= 0.0 || (camera.is_perspective() && t < camera.near) {
            return limit;
        }
        let Some((xy, _)) = light.project(ray.at(t)) else { return limit };
        lo = lo.min(xy);
        hi = hi.max(xy);
    }
    Footprint { lo: lo.max(limit.lo), hi: hi.min(limit.hi) }
}

/// A uniform number in `[0, 1)` from a hash of `(seed, pixel, sample, axis)` (SplitMix64).
#[inline]
pub fn jitter(seed: u64, pixel: u64, sample: u32, axis: u32) -> f64 {
    let mut z = seed
        ^ pixel.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (u64::from(sample) << 32 | u64::from(axis)).wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Filters one pixel: the lit fraction of `samples` jittered samples of `fp`, and the number
/// of compares made.
#[inline]
pub fn filter(
    map: &LightDepthMap,
    tester: &DepthTester,
    r: &Receiver,
    fp: &Footprint,
    options: &ReevesOptions,
    pixel: u64,
) -> (f64, u64) {
    let (nx, ny) = grid_dims(options.samples).unwrap_or((1, 1));
    let reach = (r.xy - fp.lo).max(fp.hi - r.xy) + DVec2::splat(0.5);
    let threshold = r.depth - tester.tolerance(r, reach);
    let size = fp.hi - fp.lo;
    let res = map.res as usize;
    let (mut lit, mut compares) = (0u32, 0u64);
    for s in 0..options.samples {
        let cell = DVec2::new(f64::from(s % nx), f64::from(s / nx));
        let u = DVec2::new(jitter(options.seed, pixel, s, 0), jitter(options.seed, pixel, s, 1));
        let q = fp.lo + (cell + u) / DVec2::new(f64::from(nx), f64::from(ny)) * size;
        match texel_at(q, map.res) {
            Some((x, y)) => {
                compares += 1;
                lit += u32::from(map.depth[y * res + x] >= threshold);
            }
            None => lit += 1,
        }
    }
    (f64::from(lit) / f64::from(options.samples), compares)
}

/// Reeves et al.'s stochastic percentage-closer filtering.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ReevesPcf {
    /// Options.
    pub options: ReevesOptions,
}

impl ShadowMethod for ReevesPcf {
    fn name(&self) -> &'static str {
        "pcf-reeves"
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = self.options.map.params();
        m.insert("rate".into(), self.options.samples.into());
        m.insert("seed".into(), self.options.seed.into());
        m
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        let o = self.options;
        o.validate()?;
        if frame.effects.transparency {
            rec.notes.push("pcf-reeves treats semi-transparent casters as opaque".into());
        }
        let map = frame.light_depth_map(o.map.map_res, o.map.frustum, rec);
        let tester =
            DepthTester::new(&o.map, map.projector, frame.light_depth_range(&map.projector));
        rec.warnings.extend(tester.warnings(self.name(), frame, Sampling::PixelArea));
        let g = &frame.gbuffer;
        let (lit, counters) = rec.stages.time(STAGE_FILTERING, || {
            filter_pixels(frame, &tester, |pixel, k, r| {
                let fp =
                    footprint(&frame.camera, &map.projector, pixel, g.position[k], g.normal[k], r);
                let (v, compares) = filter(&map, &tester, r, &fp, &o, k as u64);
                PixelResult { lit: v as f32, compares, bilinear_lookups: 0 }
            })
        });
        rec.counters.merge(&counters);
        Ok(Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jitter_is_uniform_enough_and_deterministic() {
        let n = 4096;
        let mean = (0..n).map(|s| jitter(7, 3, s, 0)).sum::<f64>() / f64::from(n);
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
        assert_eq!(jitter(7, 3, 5, 1), jitter(7, 3, 5, 1));
        assert_ne!(jitter(7, 3, 5, 1), jitter(8, 3, 5, 1));
        assert!((0..n).all(|s| (0.0..1.0).contains(&jitter(1, 2, s, 1))));
    }
}
