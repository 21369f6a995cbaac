//! Stage 3 on the GPU, classification ([`crate::spsm::classify`]; Lecocq et al. 2014,
//! section 4.1, Algorithm 1): one thread a pixel decodes its texel and the 3x3 ring as
//! [`SpsmMap::get`] does (the 16-bit vertices and depth by the CPU's integer codes, the 8-bit
//! derivative codes through the uploaded 256-entry decode and error tables; `f32` texels
//! widened to `f64`) and runs [`Lookup::classify`] in `f64` with the CPU's operations in the
//! CPU's order.
//!
//! The receiver's gradient in the coplanar test needs [`DerivativeCode::encode`] (an `atan`
//! and a power): the GPU encodes by the uploaded thresholds, the smallest `f64` slope of each
//! code found on the CPU by bisection over the ordered `f64`s, so it returns the CPU's code
//! for every slope ([`encode_thresholds`]).
//!
//! The CPU's containment tests use the exact `orient2d` of the `robust` crate. The kernel
//! runs its `f64` filter: where the filter decides, both return the same `f64` determinant;
//! elsewhere the pixel is handed back and classified by the CPU code (returned as
//! [`Classified::handed_back`]).
//!
//! Counters (`u32` atomics): `lit_by_one_lookup`, `shadowed_by_one_lookup`,
//! `shadowed_by_neighbourhood`, `uncertain_pixels`, `shadow_map_lookups`; the handed-back
//! pixels' counts are added by the CPU code that classifies them.

use crate::{
    depth_test::texel_at,
    frame::Frame,
    gpu::{frame::projector_data, GpuContext, GpuError, GpuFrame, COMMON_WGSL},
    spsm::{
        classify::{Lookup, PixelClass, UncertainPixel},
        quantize::DerivativeCode,
        texel::{SpsmMap, Texels},
        STAGE_CLASSIFICATION,
    },
};
use bytemuck::{Pod, Zeroable};
use instrumentation::{Counters, Recorder};

const CLASSIFY_WGSL: &str = include_str!("classify.wgsl");

/// The kernel's uniform parameters; the WGSL `Params`, field for field.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, Pod, Zeroable)]
struct Params {
    constant: f64,
    z_lo: f64,
    depth_step: f64,
    vertex_step: f64,
    half_res: f64,
    half_ulp: f64,
    size_x: f64,
    size_y: f64,
    pixels: u32,
    res: u32,
    perspective: u32,
    packed: u32,
    pad: [u32; 4],
}

/// The order-preserving map of the non-NaN `f64`s onto the integers.
fn key(s: f64) -> i128 {
    let b = s.to_bits() as i64;
    i128::from(if b < 0 { b ^ i64::MAX } else { b })
}

/// The inverse of [`key`].
fn from_key(k: i128) -> f64 {
    let k = k as i64;
    f64::from_bits((if k < 0 { k ^ i64::MAX } else { k }) as u64)
}

/// For each code `c` in 1 to 254, the smallest `f64` slope `code` encodes to `c` or above
/// (index 0 and 255 are unused): [`DerivativeCode::encode`] is non-decreasing, so a slope's
/// code is the number of thresholds at or below it.
pub fn encode_thresholds(code: &DerivativeCode) -> [f64; 256] {
    let mut t = [f64::NEG_INFINITY; 256];
    t[255] = f64::INFINITY;
    for (c, slot) in t.iter_mut().enumerate().take(255).skip(1) {
        let (mut lo, mut hi) = (key(f64::NEG_INFINITY), key(f64::INFINITY));
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if usize::from(code.encode(from_key(mid))) >= c {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        *slot = from_key(hi);
    }
    t
}

/// What classification hands to the next stages, as
/// [`crate::spsm::classify::classify_pixels`] returns it.
#[derive(Debug, Clone, PartialEq)]
pub struct Classified {
    /// Each pixel's class, row by row.
    pub classes: Vec<PixelClass>,
    /// Lit values: 1 or 0 (0 for uncertain pixels until recovery decides).
    pub lit: Vec<f32>,
    /// The uncertain pixels in pixel order, with their texels.
    pub uncertain: Vec<UncertainPixel>,
    /// The stage's counters.
    pub counters: Counters,
    /// Pixels whose containment tests the `f64` filter left undecided, classified by the
    /// CPU code.
    pub handed_back: u64,
}

/// The stage [`STAGE_CLASSIFICATION`] on the GPU: classifies every pixel of `gframe` (whose
/// G-buffer is `frame`'s) against `lookup`'s map.
pub fn classify(
    ctx: &GpuContext,
    gframe: &GpuFrame,
    frame: &Frame<'_>,
    lookup: &Lookup<'_>,
    rec: &mut Recorder,
) -> Result<Classified, GpuError> {
    let map: &SpsmMap = lookup.map;
    let space = map.space;
    let size = space.texel_world_size(1.0);
    let n = gframe.pixels();
    let mut params = Params {
        constant: lookup.tester.constant,
        z_lo: space.z_lo,
        depth_step: space.depth_step(),
        vertex_step: space.vertex_step(),
        half_res: 0.5 * f64::from(space.res),
        half_ulp: f64::from(f32::EPSILON) * 0.5,
        size_x: size.x,
        size_y: size.y,
        pixels: n as u32,
        res: map.res,
        perspective: u32::from(space.perspective),
        ..Default::default()
    };
    let mut tables = vec![0.0f64; 768];
    let words: Vec<u32> = match &map.texels {
        Texels::Packed(t, p) => {
            params.packed = 1;
            params.z_lo = p.space.z_lo;
            params.depth_step = p.space.depth_step();
            params.vertex_step = p.space.vertex_step();
            params.half_res = 0.5 * f64::from(p.space.res);
            for q in 0..=255u8 {
                tables[usize::from(q)] = p.code.decode(q);
                tables[256 + usize::from(q)] = p.code.error(q);
            }
            tables[512..].copy_from_slice(&encode_thresholds(&p.code));
            t.iter().flatten().copied().collect()
        }
        Texels::F32(t) => t
            .iter()
            .flat_map(|x| {
                let [a, b, c] = x.v;
                [a[0], a[1], b[0], b[1], c[0], c[1], x.z, x.dz[0], x.dz[1]].map(f32::to_bits)
            })
            .collect(),
    };
    let p = ctx.pipeline("spsm classification", &format!("{COMMON_WGSL}{CLASSIFY_WGSL}"), "main");
    let uniform = ctx.uniform("spsm params", &params);
    let light = ctx.upload("spsm light", &projector_data(&lookup.tester.projector));
    let texels = ctx.upload("spsm texels", &words);
    let tables = ctx.upload("spsm tables", &tables);
    let result = ctx.zeroed::<u32>("spsm classes", 2 * n.max(1));
    let counters = ctx.zeroed::<u32>("spsm counters", 8);
    let bind = ctx.bind(
        &p,
        &[
            &uniform,
            &light,
            &gframe.triangle,
            &gframe.position,
            &gframe.normal,
            &texels,
            &tables,
            &result,
            &counters,
        ],
    );
    ctx.stage(rec, STAGE_CLASSIFICATION, |e| {
        GpuContext::dispatch(e, &p, &bind, GpuContext::groups_1d(n, 64))
    })?;
    let result: Vec<u32> = ctx.read(&result)?;
    let w: Vec<u32> = ctx.read(&counters)?;
    let mut c = Counters {
        lit_by_one_lookup: u64::from(w[0]),
        shadowed_by_one_lookup: u64::from(w[1]),
        shadowed_by_neighbourhood: u64::from(w[2]),
        uncertain_pixels: u64::from(w[3]),
        shadow_map_lookups: u64::from(w[4]),
        ..Default::default()
    };
    let handed_back = u64::from(w[5]);
    let g = &frame.gbuffer;
    let res = map.res;
    let mut out = Classified {
        classes: Vec::with_capacity(n),
        lit: Vec::with_capacity(n),
        uncertain: Vec::new(),
        counters: Counters::default(),
        handed_back,
    };
    for k in 0..n {
        let (class, texel) = match result[2 * k] {
            0 => (PixelClass::Unmapped, 0),
            1 => (PixelClass::LitOneLookup, 0),
            2 => (PixelClass::ShadowedOneLookup, 0),
            3 => (PixelClass::ShadowedNeighbourhood, 0),
            4 => (PixelClass::Uncertain, result[2 * k + 1]),
            _ => match lookup.point(g.position[k], g.normal[k]) {
                Some(p) => {
                    let (class, lookups) = lookup.classify(&p);
                    c.shadow_map_lookups += lookups;
                    match class {
                        PixelClass::LitOneLookup => c.lit_by_one_lookup += 1,
                        PixelClass::ShadowedOneLookup => c.shadowed_by_one_lookup += 1,
                        PixelClass::ShadowedNeighbourhood => c.shadowed_by_neighbourhood += 1,
                        PixelClass::Uncertain => c.uncertain_pixels += 1,
                        PixelClass::Unmapped => {}
                    }
                    let texel =
                        texel_at(p.xy, res).map_or(0, |(x, y)| (y * res as usize + x) as u32);
                    (class, texel)
                }
                None => (PixelClass::Unmapped, 0),
            },
        };
        out.lit.push(match class {
            PixelClass::Unmapped | PixelClass::LitOneLookup => 1.0,
            _ => 0.0,
        });
        if class == PixelClass::Uncertain {
            out.uncertain.push(UncertainPixel { pixel: k as u32, texel });
        }
        out.classes.push(class);
    }
    out.counters = c;
    Ok(out)
}
