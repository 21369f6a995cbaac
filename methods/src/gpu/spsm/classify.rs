//! Stage 3 on the GPU, classification ([`crate::spsm::classify`]; Lecocq et al. 2014,
//! section 4.1, Algorithm 1): one thread a pixel decodes its texel and the 3x3 ring as
//! [`SpsmMap::get`] does (the 16-bit vertices and depth by the CPU's integer codes, the 8-bit
//! derivative codes through the uploaded 256-entry decode and error tables, [`GpuTexels`]; `f32` texels
//! widened to `f64`) and runs [`Lookup::classify`] in `f64` with the CPU's operations in the
//! CPU's order.
//!
//! The receiver's gradient in the coplanar test needs [`crate::spsm::quantize::DerivativeCode::encode`] (an `atan`
//! and a power): the GPU encodes by the uploaded thresholds, the smallest `f64` slope of each
//! code found on the CPU by bisection over the ordered `f64`s, so it returns the CPU's code
//! for every slope ([`DerivativeCode::thresholds`](crate::spsm::quantize::DerivativeCode::thresholds)).
//!
//! The CPU's containment tests use the exact `orient2d` of the `robust` crate. The kernel
//! runs its `f64` filter: where the filter decides, both return the same `f64` determinant;
//! elsewhere the pixel is handed back and classified by the CPU code (returned as
//! [`Classified::handed_back`]).
//!
//! Counters (`u32` atomics): `lit_by_one_lookup`, `shadowed_by_one_lookup`,
//! `shadowed_by_neighbourhood`, `uncertain_pixels`, `shadow_map_lookups`; the handed-back
//! pixels' counts are added by the CPU code that classifies them.

use super::texel::{GpuTexels, Params, ENCODE, TEXEL};
use crate::{
    depth_test::texel_at,
    frame::Frame,
    gpu::{
        common::ProjectorData,
        shader::{compose, Part},
        GpuContext, GpuError, GpuFrame,
    },
    spsm::{
        classify::{Lookup, PixelClass, UncertainPixel},
        texel::SpsmMap,
        STAGE_CLASSIFICATION,
    },
};
use instrumentation::{Counters, Recorder};

/// WGSL of [`Lookup`]: map points, containment, gradient, plane error, `lies_on`.
pub(super) const LOOKUP: Part = Part {
    name: "spsm/lookup.wgsl",
    source: include_str!("lookup.wgsl"),
    needs: &[&TEXEL, &ENCODE],
};

const CLASSIFY: Part =
    Part { name: "spsm/classify.wgsl", source: include_str!("classify.wgsl"), needs: &[&LOOKUP] };

crate::gpu::layout::wgsl_mirror!(
    Params,
    "Params",
    compose(&[&CLASSIFY]),
    [
        constant,
        z_lo,
        depth_step,
        vertex_step,
        half_res,
        half_ulp,
        size_x,
        size_y,
        pixels,
        res,
        perspective,
        packed,
        count,
        pad1,
        pad2,
        pad3
    ]
);

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
    texels: &GpuTexels,
    rec: &mut Recorder,
) -> Result<Classified, GpuError> {
    let map: &SpsmMap = lookup.map;
    let n = gframe.pixels();
    let params = Params { pixels: n as u32, ..texels.params };
    let p = ctx.pipeline("spsm classification", &compose(&[&CLASSIFY]), "main");
    let uniform = ctx.uniform("spsm params", &params);
    let light = ctx.upload("spsm light", &[ProjectorData::new(&lookup.tester.projector)]);
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
            &texels.texels,
            &texels.planes,
            &texels.tables,
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
