//! `pcf-gems16` and `pcf-gems4`: percentage-closer filtering over a fixed 4x4-texel region
//! with hardware bilinear PCF lookups (Bunnell and Pellacini, "Shadow Map Antialiasing",
//! GPU Gems, chapter 11, Addison-Wesley 2004).
//!
//! - **Bilinear PCF lookup** (section 11.3, Fig. 11-3): the hardware compares the point's depth
//!   against the four texels around the lookup point and interpolates the four results
//!   bilinearly by the lookup point's fractional texel position ([`bilinear_pcf`]).
//! - **`pcf-gems16`** (section 11.3): 16 lookups at offsets `-1.5, -0.5, 0.5, 1.5` texels in x
//!   and y from the point, averaged: the shadowed fraction of a 4x4-texel region that is not
//!   aligned to texel boundaries.
//! - **`pcf-gems4`** (section 11.4, Fig. 11-4): four of those 16 lookups, chosen by screen
//!   position: `offset = (x mod 2, (y mod 2) xor (x mod 2))`, lookups at `offset + (-1.5, 0.5)`,
//!   `(0.5, 0.5)`, `(-1.5, -1.5)`, `(0.5, -1.5)`. Every 2x2 block of pixels uses all four
//!   patterns, so together they cover the 16 positions (a dither).
//!
//! Stages: `light depth map`, `percentage-closer filtering`. Counters: `bilinear_lookups`
//! (16 or 4 per pixel whose point falls in the map's frustum) and `shadow_map_lookups` (the
//! depth compares: 4 per bilinear lookup, less where texels lie outside the map).
//!
//! # Invariants
//!
//! - Values in `[0, 1]`; a pixel far from any shadow edge is exactly 0 or 1.
//! - A lit plane stays fully lit for `slope_bias >= 1` (below `max_slope`): the tolerance uses
//!   the reach [`GEMS_REACH`] = 2.5 texels per axis, the farthest texel centre any lookup
//!   compares against (offset 1.5 plus the bilinear footprint's 1).
//!
//! # Choices where the chapter is vague
//!
//! - Screen position: `(x, y)` is the pixel's column and row from the image's top-left (the
//!   shader's window position counts rows from the bottom; the choice mirrors the dither
//!   pattern vertically and changes nothing else). Offsets are in the map's own axes (`y`
//!   down).
//! - Bilinear weights are exact `f64` (the hardware quantizes them to 8 bits; that rounding
//!   is not emulated). Texels outside the map count as lit without a compare (a border of
//!   far depth).
//! - The depth compared is the G-buffer point's light depth at the pixel centre; the same
//!   tolerance serves all 16 lookups.

use crate::{
    depth_map::LightDepthMap,
    depth_test::{filter_pixels, DepthTester, MapOptions, PixelResult, Receiver},
    footprint::Sampling,
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
};
use glam::DVec2;
use instrumentation::Recorder;

/// Name of the filtering stage.
pub const STAGE_FILTERING: &str = "percentage-closer filtering";

/// Farthest texel centre, in texels per axis, that a lookup of either pattern compares against.
pub const GEMS_REACH: DVec2 = DVec2::splat(2.5);

/// The 16 lookup offsets of `pcf-gems16`, in texels, row by row.
pub const OFFSETS_16: [DVec2; 16] = {
    let mut o = [DVec2::ZERO; 16];
    let mut k = 0;
    while k < 16 {
        o[k] = DVec2::new(-1.5 + (k % 4) as f64, -1.5 + (k / 4) as f64);
        k += 1;
    }
    o
};

/// The four lookups of `pcf-gems4` before the per-pixel offset.
pub const OFFSETS_4: [DVec2; 4] =
    [DVec2::new(-1.5, 0.5), DVec2::new(0.5, 0.5), DVec2::new(-1.5, -1.5), DVec2::new(0.5, -1.5)];

/// The dither offset of pixel `(x, y)` for `pcf-gems4` (section 11.4).
#[inline]
pub fn dither_offset(x: u32, y: u32) -> DVec2 {
    let ox = x % 2;
    DVec2::new(f64::from(ox), f64::from((y % 2) ^ ox))
}

/// Which lookups a variant makes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GemsSamples {
    /// All 16 lookups of the 4x4 region.
    Sixteen,
    /// Four lookups chosen by screen position.
    FourDithered,
}

/// One hardware-style bilinear PCF lookup at map point `q` (texels) for a point at light
/// depth `depth` with tolerance `tolerance`: the lit fraction and the number of depth
/// compares made.
#[inline]
pub fn bilinear_pcf(map: &LightDepthMap, q: DVec2, depth: f64, tolerance: f64) -> (f64, u64) {
    let u = q - DVec2::splat(0.5);
    let (x0, y0) = (u.x.floor(), u.y.floor());
    let (fx, fy) = (u.x - x0, u.y - y0);
    let r = i64::from(map.res);
    let mut compares = 0;
    let mut lit = [[1.0f64; 2]; 2];
    for (dy, row) in lit.iter_mut().enumerate() {
        for (dx, v) in row.iter_mut().enumerate() {
            let (x, y) = (x0 as i64 + dx as i64, y0 as i64 + dy as i64);
            if x >= 0 && y >= 0 && x < r && y < r {
                compares += 1;
                if map.depth[(y * r + x) as usize] < depth - tolerance {
                    *v = 0.0;
                }
            }
        }
    }
    let top = lit[0][0] + fx * (lit[0][1] - lit[0][0]);
    let bottom = lit[1][0] + fx * (lit[1][1] - lit[1][0]);
    ((top + fy * (bottom - top)).clamp(0.0, 1.0), compares)
}

/// The filtered lit fraction of one receiver at pixel `(x, y)`, with its compare count.
#[inline]
pub fn filter(
    map: &LightDepthMap,
    tester: &DepthTester,
    r: &Receiver,
    samples: GemsSamples,
    (x, y): (u32, u32),
) -> (f64, u64) {
    let tolerance = tester.tolerance(r, GEMS_REACH);
    let mut sum = 0.0;
    let mut compares = 0;
    let mut lookup = |o: DVec2| {
        let (v, c) = bilinear_pcf(map, r.xy + o, r.depth, tolerance);
        sum += v;
        compares += c;
    };
    match samples {
        GemsSamples::Sixteen => {
            OFFSETS_16.iter().for_each(|&o| lookup(o));
            (sum / 16.0, compares)
        }
        GemsSamples::FourDithered => {
            let d = dither_offset(x, y);
            OFFSETS_4.iter().for_each(|&o| lookup(o + d));
            (sum / 4.0, compares)
        }
    }
}

/// GPU Gems' 4x4-region PCF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GemsPcf {
    /// Map and bias options.
    pub options: MapOptions,
    /// 16 lookups or 4 dithered ones.
    pub samples: GemsSamples,
}

impl ShadowMethod for GemsPcf {
    fn name(&self) -> &'static str {
        match self.samples {
            GemsSamples::Sixteen => "pcf-gems16",
            GemsSamples::FourDithered => "pcf-gems4",
        }
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        self.options.params()
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        self.options.validate()?;
        if frame.effects.transparency {
            rec.notes.push(format!("{} treats semi-transparent casters as opaque", self.name()));
        }
        let map = frame.light_depth_map(self.options.map_res, self.options.frustum, rec);
        let tester =
            DepthTester::new(&self.options, map.projector, frame.light_depth_range(&map.projector));
        rec.warnings.extend(tester.warnings(self.name(), frame, Sampling::PixelCentre));
        let per_pixel = match self.samples {
            GemsSamples::Sixteen => 16,
            GemsSamples::FourDithered => 4,
        };
        let (lit, counters) = rec.stages.time(STAGE_FILTERING, || {
            filter_pixels(frame, &tester, |pixel, _, r| {
                let (v, compares) = filter(&map, &tester, r, self.samples, pixel);
                PixelResult { lit: v as f32, compares, bilinear_lookups: per_pixel }
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
    fn dither_covers_the_sixteen_offsets_in_every_2x2_block() {
        for (bx, by) in [(0, 0), (6, 3), (1, 1)] {
            let mut seen: Vec<DVec2> = (0..4)
                .flat_map(|p| OFFSETS_4.map(|o| o + dither_offset(bx + p % 2, by + p / 2)))
                .collect();
            seen.sort_by(|a, b| (a.y, a.x).partial_cmp(&(b.y, b.x)).expect("finite"));
            assert_eq!(seen, OFFSETS_16.to_vec());
        }
    }

    #[test]
    fn bilinear_lookup_interpolates_the_four_compares() {
        // Left column occludes (depth 0), right column is far.
        let m = LightDepthMap::from_depths(vec![0.0, 9.0, 0.0, 9.0], 2);
        let (v, c) = bilinear_pcf(&m, DVec2::new(0.75, 1.0), 1.0, 0.0);
        assert_eq!(c, 4);
        assert!((v - 0.25).abs() < 1e-15, "{v}");
        // At a texel centre only that texel's compare weighs.
        assert_eq!(bilinear_pcf(&m, DVec2::new(1.5, 0.5), 1.0, 0.0).0, 1.0);
        assert_eq!(bilinear_pcf(&m, DVec2::new(0.5, 1.5), 1.0, 0.0).0, 0.0);
        // Outside the map: lit, no compare.
        assert_eq!(bilinear_pcf(&m, DVec2::new(-3.0, 0.5), 1.0, 0.0), (1.0, 0));
    }
}
