//! Stage 2, packing (Lecocq et al. 2014, sections 3.3 and 3.4): the conservatively rasterized
//! map ([`super::raster`]) stored texel by texel in the texel layout of [`super::texel`],
//! 128-bit packed or `f32`. A module of its own above both, so that the texel layout needs
//! nothing of the rasterizer, which hands its texels over in that layout
//! ([`TexelData`](super::texel::TexelData)). Its GPU twin is `gpu::spsm::pack`.

use super::quantize::DerivativeCode;
use super::raster::{ConservativeMap, NONE};
use super::texel::{
    F32Texel, LightSpace, PackedTriangle, Packer, SpsmMap, TexelFormat, Texels, EMPTY_PACKED,
};
use glam::DVec2;
use rayon::prelude::*;

/// Stage 2, packing: stores every texel of the conservatively rasterized map in `format`
/// (with the derivative exponent `power` for packed texels). Returns the map, the number of
/// texels holding a triangle, and the number of packed texels whose vertices were clamped.
pub fn pack_map(
    raster: &ConservativeMap,
    space: LightSpace,
    format: TexelFormat,
    power: u32,
) -> (SpsmMap, u64, u64) {
    let r = raster.res as usize;
    // One pass per row: (filled, clamped) texels.
    let count = |row: &[u32], clamped: &dyn Fn(u32) -> bool| {
        row.iter()
            .filter(|&&s| s != NONE)
            .fold((0u64, 0u64), |(f, c), &s| (f + 1, c + u64::from(clamped(s))))
    };
    let (texels, (filled, clamped)) = match format {
        TexelFormat::Packed => {
            let packer = Packer { space, code: DerivativeCode::new(power) };
            let tris: Vec<PackedTriangle> =
                raster.setups.par_iter().map(|s| packer.pack_triangle(&s.v, s.dz)).collect();
            let mut words = vec![EMPTY_PACKED; r * r];
            let counts = words
                .par_chunks_mut(r.max(1))
                .zip(raster.texel.par_chunks(r.max(1)))
                .enumerate()
                .map(|(j, (out, row))| {
                    for (i, (w, &s)) in out.iter_mut().zip(row).enumerate() {
                        if s != NONE {
                            let setup = &raster.setups[s as usize];
                            let centre = DVec2::new(i as f64 + 0.5, j as f64 + 0.5);
                            *w =
                                packer.pack_texel(&tris[s as usize], setup.plane(centre), setup.dz);
                        }
                    }
                    count(row, &|s| tris[s as usize].clamped)
                })
                .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
            (Texels::Packed(words, Box::new(packer)), counts)
        }
        TexelFormat::F32 => {
            let mut t = vec![F32Texel::EMPTY; r * r];
            let counts = t
                .par_chunks_mut(r.max(1))
                .zip(raster.texel.par_chunks(r.max(1)))
                .enumerate()
                .map(|(j, (out, row))| {
                    for (i, (texel, &s)) in out.iter_mut().zip(row).enumerate() {
                        if s != NONE {
                            *texel = F32Texel::new(&raster.setups[s as usize].texel_data(i, j));
                        }
                    }
                    count(row, &|_| false)
                })
                .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
            (Texels::F32(t), counts)
        }
    };
    (SpsmMap { res: raster.res, space, texels }, filled, clamped)
}
