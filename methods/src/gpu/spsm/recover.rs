//! Stage 5 on the GPU, silhouette recovery ([`crate::spsm::recover`]; Lecocq et al. 2014,
//! section 4.2, Figs. 7, 8 and 10): one thread an uncertain pixel builds the depth-test
//! pattern of its 3x3 neighbourhood ([`recover::silhouette`]: the consistent minimum depths of
//! stage 4, the receiver-plane test at the corners of each triangle clipped to its texel,
//! the quantization margins), filters it through the uploaded 4-connectivity table, and
//! evaluates the silhouette function at the pixel's own map point with the uploaded tangent
//! table ([`recover::Resolved::lit`]); in `f64` with the twin's operations in the twin's
//! order.
//!
//! The twin's containment tests and triangle orientations use the exact `orient2d`; the
//! kernel runs its `f64` filter, and a pixel the filter leaves undecided is handed back and
//! recovered by the twin's code ([`recover::recover_pixel`]). The silhouettes come back per
//! pixel (centre texel, kept pattern, facing away) for the antialiasing, and the counters
//! are the twin's ([`recover::record`]).

use super::{
    antialias::SILHOUETTE,
    classify::LOOKUP,
    depth::CLIP,
    texel::{GpuTexels, Params},
};
use crate::{
    frame::Frame,
    gpu::{
        common::ProjectorData,
        shader::{compose, Part},
        GpuContext, GpuError, GpuFrame,
    },
    spsm::{
        classify::{Lookup, UncertainPixel},
        depth::ConsistentDepths,
        recover::{self, connectivity_table, pattern_table, Pattern, Silhouette},
        STAGE_RECOVERY,
    },
};
use instrumentation::Recorder;
use rayon::prelude::*;

const RECOVER: Part = Part {
    name: "spsm/recover.wgsl",
    source: include_str!("recover.wgsl"),
    needs: &[&LOOKUP, &CLIP, &SILHOUETTE],
};

/// The look-up tables as the kernel reads them: the 4-connectivity table and each ring
/// mask's tangent count (`u32`), and the tangents' normals (`f64`, four `(x, y)` a mask).
fn tables() -> (Vec<u32>, Vec<f64>) {
    let mut patterns: Vec<u32> = connectivity_table().iter().map(|&m| u32::from(m)).collect();
    let mut normals = vec![0.0f64; 256 * 8];
    for (ring, p) in pattern_table().iter().enumerate() {
        let count = match *p {
            Pattern::Tangents { count, normals: n } => {
                for (i, v) in n.iter().enumerate() {
                    normals[8 * ring + 2 * i] = v.x;
                    normals[8 * ring + 2 * i + 1] = v.y;
                }
                u32::from(count)
            }
            Pattern::Lit | Pattern::Shadowed => 0,
        };
        patterns.push(count);
    }
    (patterns, normals)
}

/// What the recovery hands on: each uncertain pixel's silhouette (in the order of the
/// pixels) and the pixels the `f64` filter left to the twin's code.
#[derive(Debug, Clone, PartialEq)]
pub struct Recovered {
    /// Each pixel's silhouette, as [`recover::recover_pixels`] returns them.
    pub silhouettes: Vec<Option<Silhouette>>,
    /// Pixels recovered by the twin's code.
    pub handed_back: u64,
}

/// The stage [`STAGE_RECOVERY`] on the GPU: recovers the `uncertain` pixels of `gframe`
/// (whose G-buffer is `frame`'s) against the map in `texels` with stage 4's `consistent`
/// depths, writing their lit values (1 or 0) into `lit`; counters into `rec`.
#[allow(clippy::too_many_arguments)]
pub fn recover_pixels(
    ctx: &GpuContext,
    gframe: &GpuFrame,
    frame: &Frame<'_>,
    lookup: &Lookup<'_>,
    texels: &GpuTexels,
    consistent: &ConsistentDepths,
    uncertain: &[UncertainPixel],
    lit: &mut [f32],
    rec: &mut Recorder,
) -> Result<Recovered, GpuError> {
    let n = uncertain.len();
    if n == 0 {
        rec.stages.add(STAGE_RECOVERY, 0.0);
        return Ok(Recovered { silhouettes: Vec::new(), handed_back: 0 });
    }
    let (patterns, normals) = tables();
    let (index, depth) = consistent.parts();
    let params = Params { count: n as u32, ..texels.params };
    let pixels: Vec<u32> = uncertain.iter().map(|u| u.pixel).collect();
    let pipeline = ctx.pipeline("spsm silhouette recovery", &compose(&[&RECOVER]), "main");
    let result = ctx.zeroed::<u32>("spsm silhouettes", 3 * n);
    let bind = ctx.bind(
        &pipeline,
        &[
            &ctx.uniform("spsm recovery params", &params),
            &ctx.upload("spsm light", &[ProjectorData::new(&lookup.tester.projector)]),
            &gframe.position,
            &gframe.normal,
            &texels.texels,
            &texels.planes,
            &texels.tables,
            &ctx.upload("spsm uncertain pixels", &pixels),
            &ctx.upload("spsm consistent texels", &[index, &[u32::MAX]].concat()),
            &ctx.upload("spsm consistent depths", &[depth, &[f32::INFINITY]].concat()),
            &ctx.upload("spsm patterns", &patterns),
            &ctx.upload("spsm tangents", &normals),
            &result,
        ],
    );
    ctx.stage(rec, STAGE_RECOVERY, |e| {
        GpuContext::dispatch(e, &pipeline, &bind, GpuContext::groups_1d(n, 64));
    })?;
    let result: Vec<u32> = ctx.read(&result)?;
    // The CPU's part of the stage (the handed-back pixels, the records) is timed into it.
    let start = std::time::Instant::now();
    let res = lookup.map.res;
    let out: Vec<(Option<Silhouette>, bool)> = uncertain
        .par_iter()
        .zip(result.par_chunks_exact(3))
        .map(|(u, r)| match r[0] {
            0 => (None, true),
            1 => {
                let s = Silhouette {
                    texel: (r[1] % res, r[1] / res),
                    kept: (r[2] & 0x1ff) as u16,
                    facing_away: r[2] & (1 << 9) != 0,
                };
                (Some(s), r[2] & (1 << 10) != 0)
            }
            _ => recover::recover_pixel(frame, lookup, consistent, u),
        })
        .collect();
    let handed_back = result.chunks_exact(3).filter(|r| r[0] == 2).count() as u64;
    let (silhouettes, counters) = recover::record(uncertain, out, lit);
    rec.stages.add(STAGE_RECOVERY, start.elapsed().as_secs_f64() * 1e3);
    rec.counters.merge(&counters);
    Ok(Recovered { silhouettes, handed_back })
}
