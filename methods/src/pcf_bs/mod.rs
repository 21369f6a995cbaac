//! `pcf-bs-2x2`, `pcf-bs-fast-2x2`, `pcf-bs-fast-4x4`: Brabec and Seidel's percentage-closer
//! filtering with packed multi-component shadow maps ("Hardware-accelerated rendering of
//! antialiased shadows with shadow maps", Computer Graphics International (CGI) 2001).
//!
//! Depth is stored as colour through a linear ramp (section 2), quantized to `depth_bits`
//! bits (`--depth-bits 8|12|24|32`, default 32; the paper's workstations had 8 bits per
//! channel, 12 on the best ones, section 6), see [`crate::depth_test::DepthCode`]. Each packed
//! texel holds four depth codes (RGBA); a shadow-test pass compares the point's code against
//! all four and counts the lit ones.
//!
//! - **`pcf-bs-2x2`** (section 3, Fig. 3): the scene is rendered into four maps, the image
//!   plane jittered by half a texel between them (stratified: the four samples sit at the
//!   centres of the four quadrants of each texel, offsets `(±1/4, ±1/4)`). Stages
//!   `light depth map (jitter 1..4)`, then `texel packing` (the four maps into one RGBA map,
//!   the effective resolution doubled per axis), then `depth test` (one lookup of the texel
//!   the point falls in): 5 shadow levels.
//! - **`pcf-bs-fast-2x2`** (section 4, Fig. 5, 6): one map, turned into colour once
//!   (`depth encoding`, the ramp of section 2); `texel packing` is the 3x3
//!   convolution that gathers each texel's 2x2 neighbourhood into its channels, and the lookup
//!   is offset by half a texel (Fig. 6) so that the packed texel holds the four texels whose
//!   centres surround the point: 5 levels at the map's own resolution.
//! - **`pcf-bs-fast-4x4`** (section 4): the 4x4 texels around the point in four passes, each
//!   packing one 2x2 quadrant of the region (upper left, upper right, lower left, lower right)
//!   and adding its count into an accumulation buffer: stages `depth encoding` (once: the
//!   map is rendered once), then `texel packing (pass k)` and `depth test (pass k)` for
//!   `k = 1..4`. The sum takes the values `0..=16` (the paper
//!   counts `4 * 5 = 20` levels, the passes' levels summed).
//!
//! Counter `shadow_map_lookups`: the depth compares, four per packed lookup inside the packed
//! map. Pixels whose point falls outside the map (or behind a spot light) are lit.
//!
//! # Invariants
//!
//! - Values are `count / 4` (2x2 methods) or `count / 16` (4x4): at most 5 or 17 distinct.
//! - A lit plane stays fully lit for `slope_bias >= 1` and, with quantization,
//!   `constant_bias >= 2^(1 - depth_bits)` ([`crate::depth_test`]): the reach of each variant
//!   is the farthest sample it compares against, [`Variant::reach`].
//!
//! # Choices where the paper is vague
//!
//! - The jitter of section 3 is `(±1/4, ±1/4)` texel, so the four samples stratify the texel
//!   the point falls in; with a nearest-texel lookup the footprint is that texel.
//! - The default constant bias is `max(1e-5, 2^(1 - depth_bits))`, the smallest valid one at
//!   the precision (the paper does not give its bias).
//! - Packed texels beyond the map's edge hold the far code (a cleared depth buffer), so points
//!   near the edge are filtered against "lit" texels rather than dropped.

use crate::{
    depth_map::LightDepthMap,
    depth_test::{DepthCode, DepthTester, MapOptions, Receiver},
    footprint::Sampling,
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
};
use glam::DVec2;
use instrumentation::{Counters, Recorder};
use rayon::prelude::*;

/// Default depth precision in bits.
pub const DEFAULT_DEPTH_BITS: u32 = 32;

/// The image-plane jitters of the four maps of `pcf-bs-2x2`, in texels.
pub const JITTERS: [DVec2; 4] = [
    DVec2::new(-0.25, -0.25),
    DVec2::new(0.25, -0.25),
    DVec2::new(-0.25, 0.25),
    DVec2::new(0.25, 0.25),
];

/// The 2x2 quadrants of `pcf-bs-fast-4x4`'s region, as the offset of their upper-left texel
/// from the fast 2x2 lookup's: upper left, upper right, lower left, lower right.
pub const QUADRANTS: [(i64, i64); 4] = [(-1, -1), (1, -1), (-1, 1), (1, 1)];

/// Which of Brabec and Seidel's methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variant {
    /// Four jittered maps packed into RGBA, one lookup (section 3).
    Stratified2x2,
    /// One map, each texel packed with its 2x2 neighbourhood (section 4).
    Fast2x2,
    /// Four passes of the fast packing over a 4x4 region, accumulated (section 4).
    Fast4x4,
}

impl Variant {
    /// The method's name.
    pub fn name(self) -> &'static str {
        match self {
            Variant::Stratified2x2 => "pcf-bs-2x2",
            Variant::Fast2x2 => "pcf-bs-fast-2x2",
            Variant::Fast4x4 => "pcf-bs-fast-4x4",
        }
    }

    /// The farthest sample, in texels per axis, that a point is compared against: a quadrant
    /// centre of its texel (0.75), a texel centre around it (1), or of the 4x4 region (2).
    pub fn reach(self) -> DVec2 {
        DVec2::splat(match self {
            Variant::Stratified2x2 => 0.75,
            Variant::Fast2x2 => 1.0,
            Variant::Fast4x4 => 2.0,
        })
    }
}

/// Options of Brabec and Seidel's methods.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BsOptions {
    /// Map resolution and bias. The default constant bias is `max(1e-5, 2^(1 - depth_bits))`.
    pub map: MapOptions,
    /// Bits per stored depth (8, 12, 24 or 32). Default 32.
    pub depth_bits: u32,
}

impl Default for BsOptions {
    fn default() -> Self {
        Self::with_depth_bits(DEFAULT_DEPTH_BITS)
    }
}

impl BsOptions {
    /// Checks the options; errors name the command-line flag.
    pub fn validate(&self) -> Result<(), MethodError> {
        self.map.validate()?;
        DepthCode::new(self.depth_bits, 0.0, 1.0).map(|_| ())
    }

    /// The default options at `depth_bits` bits, with the smallest valid constant bias.
    pub fn with_depth_bits(depth_bits: u32) -> Self {
        let mut map = MapOptions::default();
        map.constant_bias = map.constant_bias.max(DepthCode::min_constant_bias(depth_bits));
        Self { map, depth_bits }
    }
}

/// A map of packed texels: four depth codes each. Packed texel `k` (for `k` in
/// `origin..origin + side` on both axes) is at `texels[(k.y - origin) * side + k.x - origin]`.
#[derive(Debug, Clone, PartialEq)]
pub struct PackedMap {
    /// First packed index on each axis.
    pub origin: i64,
    /// Packed texels per axis.
    pub side: usize,
    /// RGBA depth codes.
    pub texels: Vec<[u32; 4]>,
}

impl PackedMap {
    /// The packed texel at index `(x, y)`, `None` outside.
    #[inline]
    pub fn get(&self, x: i64, y: i64) -> Option<&[u32; 4]> {
        let (x, y) = (x - self.origin, y - self.origin);
        let s = self.side as i64;
        (x >= 0 && y >= 0 && x < s && y < s).then(|| &self.texels[(y * s + x) as usize])
    }
}

/// Texel packing of section 3: the four jittered maps (in [`JITTERS`] order) into the RGBA
/// channels of one map.
pub fn pack_stratified(maps: &[LightDepthMap; 4], code: &DepthCode) -> PackedMap {
    let side = maps[0].res as usize;
    let texels = (0..side * side)
        .into_par_iter()
        .map(|k| [0, 1, 2, 3].map(|c| code.encode(maps[c].depth[k])))
        .collect();
    PackedMap { origin: 0, side, texels }
}

/// Depth as colour (section 2): the map's depths through the linear ramp, one code per texel.
pub fn encode_map(map: &LightDepthMap, code: &DepthCode) -> Vec<u32> {
    map.depth.par_iter().map(|&d| code.encode(d)).collect()
}

/// Texel packing of section 4 (the 3x3 convolution of Fig. 5) of a `res x res` map of depth
/// codes: packed texel `k` holds the 2x2 texels from `k + offset` to `k + offset + (1, 1)`
/// (channels: upper left, upper right, lower left, lower right); texels beyond the map give
/// the `far` code. Indices run over `-1..res`, one more than the map, so every point inside
/// the map finds its packed texel.
pub fn pack_neighbourhood(codes: &[u32], res: u32, far: u32, offset: (i64, i64)) -> PackedMap {
    let r = i64::from(res);
    let side = res as usize + 1;
    let texel = |x: i64, y: i64| {
        if x >= 0 && y >= 0 && x < r && y < r {
            codes[(y * r + x) as usize]
        } else {
            far
        }
    };
    let texels = (0..side * side)
        .into_par_iter()
        .map(|k| {
            let (x, y) = ((k % side) as i64 - 1 + offset.0, (k / side) as i64 - 1 + offset.1);
            [texel(x, y), texel(x + 1, y), texel(x, y + 1), texel(x + 1, y + 1)]
        })
        .collect();
    PackedMap { origin: -1, side, texels }
}

/// The packed index a receiver looks up: the texel it falls in (section 3) or, with the
/// half-texel offset of Fig. 6, the one whose 2x2 block's centres surround it (section 4).
#[inline]
pub fn lookup_index(variant: Variant, xy: DVec2) -> (i64, i64) {
    let p = match variant {
        Variant::Stratified2x2 => xy,
        Variant::Fast2x2 | Variant::Fast4x4 => xy - DVec2::splat(0.5),
    };
    (p.x.floor() as i64, p.y.floor() as i64)
}

/// Per-pixel receivers of one shadow-test pass: light point, point code and tolerance in codes.
#[derive(Debug, Clone, Copy)]
struct Point {
    xy: DVec2,
    code: f64,
    tolerance: f64,
}

/// One shadow-test pass: for every pixel with a receiver, the number of the packed texel's
/// four codes that do not shadow it, added into `accumulator`; returns the compares made.
fn shadow_test(
    frame: &Frame<'_>,
    tester: &DepthTester,
    code: &DepthCode,
    variant: Variant,
    packed: &PackedMap,
    accumulator: &mut [u8],
) -> u64 {
    accumulator
        .par_iter_mut()
        .enumerate()
        .map(|(k, acc)| {
            let Some(p) = receiver_point(frame, tester, code, variant, k) else {
                *acc += 4;
                return 0;
            };
            let (x, y) = lookup_index(variant, p.xy);
            let Some(texel) = packed.get(x, y) else {
                *acc += 4;
                return 0;
            };
            let threshold = p.code - p.tolerance;
            *acc += texel.iter().filter(|&&c| f64::from(c) >= threshold).count() as u8;
            4
        })
        .sum()
}

#[inline]
fn receiver_point(
    frame: &Frame<'_>,
    tester: &DepthTester,
    code: &DepthCode,
    variant: Variant,
    k: usize,
) -> Option<Point> {
    let g = &frame.gbuffer;
    if !g.covered(k) {
        return None;
    }
    let r: Receiver = tester.receiver(g.position[k], g.normal[k])?;
    Some(Point {
        xy: r.xy,
        code: f64::from(code.encode(r.depth)),
        tolerance: code.tolerance(tester.tolerance(&r, variant.reach())),
    })
}

/// One of Brabec and Seidel's PCF methods.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrabecSeidelPcf {
    /// Options.
    pub options: BsOptions,
    /// Which method.
    pub variant: Variant,
}

impl ShadowMethod for BrabecSeidelPcf {
    fn name(&self) -> &'static str {
        self.variant.name()
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = self.options.map.params();
        m.insert("depth_bits".into(), self.options.depth_bits.into());
        m
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        let o = &self.options;
        o.validate()?;
        if frame.effects.transparency {
            rec.notes.push(format!("{} treats semi-transparent casters as opaque", self.name()));
        }
        let projector = frame.light_projector(o.map.map_res, o.map.frustum);
        let (near, far) = frame.light_depth_bounds(&projector);
        let code = DepthCode::new(o.depth_bits, near, far - near)?;
        let tester = DepthTester::new(&o.map, projector, frame.light_depth_range(&projector));
        rec.warnings.extend(tester.warnings(self.name(), frame, Sampling::PixelCentre));
        let mut counts = vec![0u8; frame.gbuffer.triangle.len()];
        let mut compares = 0;
        match self.variant {
            Variant::Stratified2x2 => {
                let maps = [0, 1, 2, 3].map(|j| {
                    let stage = format!("light depth map (jitter {})", j + 1);
                    frame.jittered_light_depth_map(
                        o.map.map_res,
                        o.map.frustum,
                        JITTERS[j],
                        &stage,
                        rec,
                    )
                });
                let packed = rec.stages.time("texel packing", || pack_stratified(&maps, &code));
                compares += rec.stages.time("depth test", || {
                    shadow_test(frame, &tester, &code, self.variant, &packed, &mut counts)
                });
            }
            Variant::Fast2x2 => {
                let map = frame.light_depth_map(o.map.map_res, o.map.frustum, rec);
                let codes = rec.stages.time("depth encoding", || encode_map(&map, &code));
                let packed = rec.stages.time("texel packing", || {
                    pack_neighbourhood(&codes, map.res, code.max_code(), (0, 0))
                });
                compares += rec.stages.time("depth test", || {
                    shadow_test(frame, &tester, &code, self.variant, &packed, &mut counts)
                });
            }
            Variant::Fast4x4 => {
                let map = frame.light_depth_map(o.map.map_res, o.map.frustum, rec);
                let codes = rec.stages.time("depth encoding", || encode_map(&map, &code));
                for (pass, &quadrant) in QUADRANTS.iter().enumerate() {
                    let packed =
                        rec.stages.time(&format!("texel packing (pass {})", pass + 1), || {
                            pack_neighbourhood(&codes, map.res, code.max_code(), quadrant)
                        });
                    compares += rec.stages.time(&format!("depth test (pass {})", pass + 1), || {
                        shadow_test(frame, &tester, &code, self.variant, &packed, &mut counts)
                    });
                }
            }
        }
        rec.counters.merge(&Counters { shadow_map_lookups: compares, ..Default::default() });
        let levels = match self.variant {
            Variant::Fast4x4 => 16.0,
            Variant::Stratified2x2 | Variant::Fast2x2 => 4.0,
        };
        let lit = counts.iter().map(|&c| (f32::from(c) / levels).clamp(0.0, 1.0)).collect();
        Ok(Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neighbourhood_packing_gathers_the_2x2_block_and_pads_with_far() {
        let m = LightDepthMap::from_depths((0..9).map(f64::from).collect(), 3);
        let code = DepthCode::new(8, 0.0, 255.0).expect("valid");
        let codes = encode_map(&m, &code);
        let p = pack_neighbourhood(&codes, 3, code.max_code(), (0, 0));
        assert_eq!(p.side, 4);
        assert_eq!(p.get(0, 0), Some(&[0, 1, 3, 4]));
        assert_eq!(p.get(1, 1), Some(&[4, 5, 7, 8]));
        assert_eq!(p.get(-1, -1), Some(&[255, 255, 255, 0]));
        assert_eq!(p.get(2, 2), Some(&[8, 255, 255, 255]));
        assert_eq!(p.get(3, 0), None);
        // Quadrant offsets move the block.
        let q = pack_neighbourhood(&codes, 3, code.max_code(), (1, -1));
        assert_eq!(q.get(0, 1), Some(&[1, 2, 4, 5]));
    }

    #[test]
    fn fast_lookup_finds_the_block_whose_centres_surround_the_point() {
        // Point in texel (1, 1), lower right quarter: the block of texels (1..=2, 1..=2).
        assert_eq!(lookup_index(Variant::Fast2x2, DVec2::new(1.75, 1.9)), (1, 1));
        // Upper left quarter: the block (0..=1, 0..=1).
        assert_eq!(lookup_index(Variant::Fast2x2, DVec2::new(1.25, 1.1)), (0, 0));
        assert_eq!(lookup_index(Variant::Stratified2x2, DVec2::new(1.25, 1.1)), (1, 1));
    }

    #[test]
    fn quadrants_tile_the_4x4_region_once() {
        let mut cells = Vec::new();
        for (ox, oy) in QUADRANTS {
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                cells.push((ox + dx, oy + dy));
            }
        }
        cells.sort_unstable();
        let mut expected: Vec<(i64, i64)> =
            (-1..=2).flat_map(|x| (-1..=2).map(move |y| (x, y))).collect();
        expected.sort_unstable();
        assert_eq!(cells, expected);
    }
}
