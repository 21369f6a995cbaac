//! Stage "packing" of `spsm` on the GPU (`pack.wgsl`), equal to
//! [`spsm::pack::pack_map`](crate::spsm::pack::pack_map) texel for texel, in both texel formats.
//!
//! What depends on the triangle only (its three vertex words, whether a vertex was clamped,
//! and, under an orthographic light, its derivative codes) is computed per prepared triangle
//! by the twin's own [`Packer::pack_triangle`]; everything per texel runs on the GPU: the depth
//! at the texel's centre and its 16-bit code (rounded half away from zero, as `f64::round`),
//! the derivative codes at the decoded depth under a spot light (through the code's
//! thresholds, `encode.wgsl`), or the `f32` texel. The texels stay on the GPU for the later
//! stages and are read back for the twin's code (handed-back pixels, antialiasing records).

use super::{
    raster::{setup_data, SETUP},
    texel::{code_tables, ENCODE},
};
use crate::{
    gpu::{
        shader::{compose, Part},
        GpuContext, GpuError,
    },
    spsm::{
        quantize::DerivativeCode,
        raster::{ConservativeMap, NONE},
        texel::{F32Texel, LightSpace, Packer, SpsmMap, TexelFormat, Texels},
    },
};
use bytemuck::{Pod, Zeroable};
use instrumentation::Recorder;

const PACK: Part =
    Part { name: "spsm/pack.wgsl", source: include_str!("pack.wgsl"), needs: &[&ENCODE, &SETUP] };

/// The packing's parameters, the WGSL `PackParams` of `pack.wgsl`: the light space's depth
/// origin and step, and its texel's world size at unit depth (`LightSpace::slope_scale`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct PackParams {
    z_lo: f64,
    depth_step: f64,
    size_x: f64,
    size_y: f64,
}

crate::gpu::layout::wgsl_mirror!(
    PackParams,
    "PackParams",
    compose(&[&PACK]),
    [z_lo, depth_step, size_x, size_y]
);

/// What [`pack_map`] gives: the twin's map, read back, and its texels as they stay on the
/// GPU for the later stages.
#[derive(Debug)]
pub struct Packed {
    /// The map, as the twin's `pack_map` gives it.
    pub map: SpsmMap,
    /// Texels filled.
    pub filled: u64,
    /// Filled texels holding a clamped vertex.
    pub clamped: u64,
    /// The texels' words on the GPU (the layout of [`super::texel::GpuTexels::texels`]).
    pub words: wgpu::Buffer,
    /// The `f32` texels' planes on the GPU ([`super::texel::GpuTexels::planes`]).
    pub planes: wgpu::Buffer,
}

/// The map of `raster` in `format` with derivative exponent `power`, as the twin's
/// `pack_map` gives it, with the texels filled and those holding a clamped vertex. The GPU
/// pass is recorded as the stage `stage`.
pub fn pack_map(
    ctx: &GpuContext,
    raster: &ConservativeMap,
    space: LightSpace,
    format: TexelFormat,
    power: u32,
    stage: &str,
    rec: &mut Recorder,
) -> Result<Packed, GpuError> {
    let texels = raster.texel.len();
    let packer = Packer { space, code: DerivativeCode::new(power) };
    let packed = format == TexelFormat::Packed;
    // The CPU's part of the stage (per triangle) is timed into it beside the GPU pass.
    let start = std::time::Instant::now();
    // Per triangle: its words and codes (packed texels), and whether a vertex was clamped.
    let (tri_words, clamped): (Vec<u32>, Vec<bool>) = if packed {
        raster
            .setups
            .iter()
            .map(|s| {
                let t = packer.pack_triangle(&s.v, s.dz);
                let codes = t.codes.map_or(u32::MAX, |(x, y)| u32::from(x) << 8 | u32::from(y));
                let [a, b, c] = t.words;
                ([a, b, c, codes], t.clamped)
            })
            .fold((Vec::new(), Vec::new()), |(mut w, mut c), (words, clamped)| {
                w.extend_from_slice(&words);
                c.push(clamped);
                (w, c)
            })
    } else {
        (vec![0], vec![false; raster.setups.len()])
    };
    let cpu_ms = start.elapsed().as_secs_f64() * 1e3;
    let size = space.slope_scale(-1.0);
    let tables = code_tables(&packer.code);
    let source = compose(&[&PACK]);
    let entry = if packed { "pack_packed" } else { "pack_f32" };
    let pipeline = ctx.pipeline("spsm pack", &source, entry);
    let words_per = if packed { 4 } else { 6 };
    let out_words = ctx.zeroed::<u32>("spsm packed words", words_per * texels);
    let out_planes = ctx.zeroed::<u32>("spsm f32 planes", if packed { 1 } else { 3 * texels });
    let bind = ctx.bind(
        &pipeline,
        &[
            &ctx.upload("spsm pack dims", &[raster.res]),
            &ctx.upload(
                "spsm pack params",
                &[PackParams {
                    z_lo: space.z_lo,
                    depth_step: space.depth_step(),
                    size_x: size.x,
                    size_y: size.y,
                }],
            ),
            &ctx.upload("spsm setups", &setup_data(&raster.setups)),
            &ctx.upload("spsm triangle words", &tri_words),
            &ctx.upload("spsm texel triangles", &raster.texel),
            &ctx.upload("spsm code tables", &tables),
            &out_words,
            &out_planes,
        ],
    );
    ctx.stage(rec, stage, |e| {
        GpuContext::dispatch(e, &pipeline, &bind, GpuContext::groups_1d(texels, 64));
    })?;
    rec.stages.add(stage, cpu_ms);
    let words: Vec<u32> = ctx.read(&out_words)?;
    let filled = raster.texel.iter().filter(|&&s| s != NONE).count() as u64;
    let clamped = raster.texel.iter().filter(|&&s| s != NONE && clamped[s as usize]).count() as u64;
    let texels = if packed {
        let words = words[..4 * texels].chunks_exact(4).map(|w| [w[0], w[1], w[2], w[3]]).collect();
        Texels::Packed(words, Box::new(packer))
    } else {
        let planes: Vec<u32> = ctx.read(&out_planes)?;
        let f = f32::from_bits;
        Texels::F32(
            (0..texels)
                .map(|k| {
                    let (w, p) = (&words[6 * k..6 * k + 6], &planes[3 * k..3 * k + 3]);
                    F32Texel {
                        v: [[f(w[0]), f(w[1])], [f(w[2]), f(w[3])], [f(w[4]), f(w[5])]],
                        z: f(p[0]),
                        dz: [f(p[1]), f(p[2])],
                    }
                })
                .collect(),
        )
    };
    let map = SpsmMap { res: raster.res, space, texels };
    Ok(Packed { map, filled, clamped, words: out_words, planes: out_planes })
}
