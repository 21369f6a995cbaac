//! Stage 4 on the GPU, consistent min depth ([`crate::spsm::depth`]; Lecocq et al. 2014,
//! section 4, Fig. 9): a first pass marks the 3x3 neighbourhoods of the uncertain pixels'
//! texels (the set the twin builds by sorting), a second computes, one thread a marked texel,
//! the decoded triangle clipped to the texel square as [`consistent_min_depth`] does, in `f64`
//! with the twin's operations in the twin's order, and counts `depth_corrected_texels` with
//! an atomic. The depths come back in `f64` and are stored as the twin stores them (`f32`).
//!
//! [`consistent_min_depth`]: crate::spsm::depth::consistent_min_depth

use super::texel::{GpuTexels, Params, TEXEL};
use crate::{
    gpu::{
        shader::{compose, Part},
        GpuContext, GpuError,
    },
    spsm::{classify::UncertainPixel, depth::ConsistentDepths, STAGE_CONSISTENT_DEPTH},
};
use instrumentation::Recorder;

const MARK: Part = Part {
    name: "spsm/depth_mark.wgsl",
    source: include_str!("depth_mark.wgsl"),
    needs: &[&TEXEL],
};
/// WGSL of a triangle clipped to a texel and its consistent and conservative depths.
pub(super) const CLIP: Part =
    Part { name: "spsm/clip.wgsl", source: include_str!("clip.wgsl"), needs: &[&TEXEL] };
const DEPTH: Part =
    Part { name: "spsm/depth.wgsl", source: include_str!("depth.wgsl"), needs: &[&CLIP] };

/// The stage [`STAGE_CONSISTENT_DEPTH`] on the GPU: the consistent minimum depths of the
/// texels around the `uncertain` pixels of the map in `texels`, and the number of texels the
/// correction raises (`depth_corrected_texels`).
pub fn consistent_depths(
    ctx: &GpuContext,
    texels: &GpuTexels,
    uncertain: &[UncertainPixel],
    rec: &mut Recorder,
) -> Result<(ConsistentDepths, u64), GpuError> {
    let res = texels.params.res as usize;
    let n = res * res;
    let centres: Vec<u32> = uncertain.iter().map(|u| u.texel).collect();
    let params = Params { count: centres.len() as u32, ..texels.params };
    let mark = ctx.pipeline("spsm consistent depth marks", &compose(&[&MARK]), "main");
    let depth = ctx.pipeline("spsm consistent depth", &compose(&[&DEPTH]), "main");
    let uniform = ctx.uniform("spsm depth params", &params);
    let centre_buf = ctx.upload("spsm centres", &[centres.as_slice(), &[0]].concat());
    let marks = ctx.zeroed::<u32>("spsm texel marks", n);
    let depths = ctx.zeroed::<f64>("spsm consistent depths", n);
    let counters = ctx.zeroed::<u32>("spsm depth counters", 8);
    let mark_bind = ctx.bind(&mark, &[&uniform, &centre_buf, &marks]);
    let depth_bind = ctx.bind(
        &depth,
        &[&uniform, &texels.texels, &texels.planes, &texels.tables, &marks, &depths, &counters],
    );
    ctx.stage(rec, STAGE_CONSISTENT_DEPTH, |e| {
        if !centres.is_empty() {
            GpuContext::dispatch(e, &mark, &mark_bind, GpuContext::groups_1d(centres.len(), 64));
        }
        GpuContext::dispatch(e, &depth, &depth_bind, GpuContext::groups_1d(n, 64));
    })?;
    let marks: Vec<u32> = ctx.read(&marks)?;
    let values: Vec<f64> = ctx.read(&depths)?;
    let corrected: Vec<u32> = ctx.read(&counters)?;
    let (mut index, mut depth) = (Vec::new(), Vec::new());
    for (k, (&m, &d)) in marks.iter().zip(&values).enumerate().take(n) {
        match m {
            0 => {}
            1 => {
                index.push(k as u32);
                depth.push(d as f32);
            }
            _ => {
                index.push(k as u32);
                depth.push(f32::INFINITY);
            }
        }
    }
    Ok((ConsistentDepths::from_parts(index, depth), u64::from(corrected[0])))
}
