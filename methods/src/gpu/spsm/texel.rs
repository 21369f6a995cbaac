//! The twin's map on the GPU: its texels as stored (four words a packed texel; an `f32`
//! texel's nine `f32` bits in two buffers, each within the binding size limit), the
//! derivative code's decode, error and encode tables, and the parameters the kernels decode
//! them with (`texel.wgsl`, the twin of [`SpsmMap::get`]).

use crate::{
    gpu::{common::COMMON, shader::Part, GpuContext},
    spsm::{
        classify::Lookup,
        quantize::DerivativeCode,
        texel::{SpsmMap, Texels},
    },
};
use bytemuck::{Pod, Zeroable};

/// WGSL of `DerivativeCode::encode` through the code's thresholds.
pub(super) const ENCODE: Part = Part::file("spsm/encode.wgsl", include_str!("encode.wgsl"));

/// A derivative code's tables as the kernels read them: decode `[0, 256)`, error
/// `[256, 512)`, encode thresholds `[512, 768)` (the code keeps its thresholds; this only
/// lays the three out side by side).
pub(super) fn code_tables(code: &DerivativeCode) -> Vec<f64> {
    let mut tables = vec![0.0f64; 768];
    for q in 0..=255u8 {
        tables[usize::from(q)] = code.decode(q);
        tables[256 + usize::from(q)] = code.error(q);
    }
    tables[512..].copy_from_slice(code.thresholds());
    tables
}

/// WGSL of the texel decoding.
pub(super) const TEXEL: Part =
    Part { name: "spsm/texel.wgsl", source: include_str!("texel.wgsl"), needs: &[&COMMON] };

/// The kernels' uniform parameters; the WGSL `Params` of `texel.wgsl`, field for field
/// (checked with the classification's shader, in `classify.rs`; see `gpu::layout`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, Pod, Zeroable)]
pub(super) struct Params {
    pub constant: f64,
    pub z_lo: f64,
    pub depth_step: f64,
    pub vertex_step: f64,
    pub half_res: f64,
    pub half_ulp: f64,
    pub size_x: f64,
    pub size_y: f64,
    pub pixels: u32,
    pub res: u32,
    pub perspective: u32,
    pub packed: u32,
    pub count: u32,
    pub pad1: u32,
    pub pad2: u32,
    pub pad3: u32,
}

/// The map's texels and tables on the GPU.
#[derive(Debug)]
pub struct GpuTexels {
    /// The kernels' parameters (`pixels` and `count` set per kernel).
    pub(super) params: Params,
    /// The texels as stored: four words a packed texel, or the six `f32` vertex
    /// coordinates of an `f32` texel.
    pub texels: wgpu::Buffer,
    /// The depth and derivatives of each `f32` texel (three `f32`); one unused word for
    /// packed texels.
    pub planes: wgpu::Buffer,
    /// Decode `[0, 256)`, error `[256, 512)` and encode thresholds `[512, 768)` of the
    /// derivative code (zeros for `f32` texels).
    pub tables: wgpu::Buffer,
}

impl GpuTexels {
    /// The kernels' parameters for `lookup`'s map, and the derivative code's tables.
    fn params(lookup: &Lookup<'_>) -> (Params, Vec<f64>) {
        let map: &SpsmMap = lookup.map;
        let space = map.space;
        let size = space.texel_world_size(1.0);
        let mut params = Params {
            constant: lookup.tester.constant,
            z_lo: space.z_lo,
            depth_step: space.depth_step(),
            vertex_step: space.vertex_step(),
            half_res: 0.5 * f64::from(space.res),
            half_ulp: f64::from(f32::EPSILON) * 0.5,
            size_x: size.x,
            size_y: size.y,
            res: map.res,
            perspective: u32::from(space.perspective),
            ..Default::default()
        };
        let mut tables = vec![0.0; 768];
        if let Texels::Packed(_, p) = &map.texels {
            params.packed = 1;
            params.z_lo = p.space.z_lo;
            params.depth_step = p.space.depth_step();
            params.vertex_step = p.space.vertex_step();
            params.half_res = 0.5 * f64::from(p.space.res);
            tables = code_tables(&p.code);
        }
        (params, tables)
    }

    /// Uploads `lookup`'s map.
    pub fn upload(ctx: &GpuContext, lookup: &Lookup<'_>) -> Self {
        let (words, planes): (Vec<u32>, Vec<u32>) = match &lookup.map.texels {
            Texels::Packed(t, _) => (t.iter().flatten().copied().collect(), vec![0]),
            Texels::F32(t) => (
                t.iter()
                    .flat_map(|x| {
                        let [a, b, c] = x.v;
                        [a[0], a[1], b[0], b[1], c[0], c[1]].map(f32::to_bits)
                    })
                    .collect(),
                t.iter().flat_map(|x| [x.z, x.dz[0], x.dz[1]].map(f32::to_bits)).collect(),
            ),
        };
        Self::keep(
            ctx,
            lookup,
            ctx.upload("spsm texels", &words),
            ctx.upload("spsm texel planes", &planes),
        )
    }

    /// `lookup`'s map from buffers already on the GPU, laid out as [`Self::texels`] and
    /// [`Self::planes`] (the packing kernel's output).
    pub fn keep(
        ctx: &GpuContext,
        lookup: &Lookup<'_>,
        texels: wgpu::Buffer,
        planes: wgpu::Buffer,
    ) -> Self {
        let (params, tables) = Self::params(lookup);
        Self { params, texels, planes, tables: ctx.upload("spsm tables", &tables) }
    }
}
