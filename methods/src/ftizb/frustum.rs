//! Stages "conservative rasterization" (Wyman et al., I3D 2015, section 4.2) and "frustum
//! tests" (I3D 2015 section 4.3; TVCG 2016 section 5.2).
//!
//! **Conservative rasterization** ([`bin_casters`]): every caster triangle, projected to the
//! light's image plane as `afsm`'s [`Blocker`] (clipped at a spot light's near plane), is
//! listed in each texel holding pixels whose region it may meet ([`Blocker::overlaps`], which
//! answers `false` only beyond a rounding margin, so no texel holding a covered sample is
//! missed). The (texel, caster) pairs are sorted by texel, each texel's casters in triangle
//! order.
//!
//! **Frustum tests** ([`frustum_tests`]), in parallel over the texels holding casters: the
//! texel's pixels' sub-samples are placed once ([`SubSamples::pixel`]), then each caster is
//! tested against them in caster order. A caster is skipped in the texel when its nearest
//! corner is not in front of the farthest sample's threshold (`nodes_depth_culled`) or when
//! every valid sub-sample of the texel is already shadowed (`nodes_occlusion_culled`); else
//! each pixel that is not its own triangle's and still has lit sub-samples is one
//! `visibility_evaluations`, each of its lit valid sub-samples one `sampling_points_tested`,
//! and [`Blocker::shadows`] decides it: the frustum test, exact on the `f64` light image point
//! and threshold (see [`super`]). The texel's masks are ORed into the pixels' (two atomic
//! words of a `u128`), so the result does not depend on the order the texels are run in.
//!
//! Hot loop rules: no allocation per texel (each thread reuses its buffers), one pass over a
//! pixel's sub-samples per caster, visiting only the lit valid ones (their bits).

use super::{
    footprints::SubSamples,
    grid::{Grid, TexelLists},
    FtizbOptions,
};
use crate::{
    afsm::{blockers::Blocker, samples::Sample},
    method::MethodError,
};
use instrumentation::Counters;
use rayon::prelude::*;
use scenes::{Geometry, Projector};
use std::sync::atomic::{AtomicU64, Ordering};

/// Triangles per parallel task of the rasterization.
const TRIANGLES_PER_TASK: usize = 1024;

/// The casters' lists: for every texel that holds pixels, the caster triangles whose
/// projection may meet it, in triangle order; an error when they would hold `u32::MAX`
/// entries or more.
pub fn bin_casters(
    geometry: &Geometry,
    is_caster: impl Fn(usize) -> bool + Sync,
    light: &Projector,
    pixels: &TexelLists,
) -> Result<TexelLists, MethodError> {
    let res = light.width as u32;
    let grid = Grid { res };
    let n = geometry.triangles.len();
    let keys: Vec<Vec<u64>> = (0..n.div_ceil(TRIANGLES_PER_TASK))
        .into_par_iter()
        .map(|chunk| {
            let mut keys = Vec::new();
            for t in chunk * TRIANGLES_PER_TASK..((chunk + 1) * TRIANGLES_PER_TASK).min(n) {
                if !is_caster(t) {
                    continue;
                }
                let Some(b) = Blocker::new(geometry, t, light) else { continue };
                let (lo, hi) = b.bounds();
                let Some((x0, y0, x1, y1)) = grid.rect(lo, hi) else { continue };
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        let texel = grid.index(x, y);
                        if pixels.is_empty_at(texel) {
                            continue;
                        }
                        let (clo, chi) = grid.texel_box(x, y);
                        if b.overlaps(clo, chi) {
                            keys.push(Grid::key(texel, t as u32));
                        }
                    }
                }
            }
            keys
        })
        .collect();
    let keys = keys.concat();
    let entries = keys.len();
    TexelLists::from_keys(res as usize * res as usize, keys).ok_or_else(|| {
        MethodError::NotApplicable(format!(
            "ftizb: the casters meet {entries} texels of the {res} x {res} grid, more than its \
             lists can index (2^32); lower --izb-res"
        ))
    })
}

/// What the frustum tests give.
#[derive(Debug, Clone, PartialEq)]
pub struct Tested {
    /// Shadowed sub-samples per pixel.
    pub occlusion: Vec<u128>,
    /// Valid sub-samples per pixel, for the pixels of texels holding casters (zero elsewhere).
    pub valid: Vec<u128>,
    /// `visibility_evaluations`, `sampling_points_tested` and the culling counters.
    pub counters: Counters,
}

/// A `u128` mask as two atomic words.
#[derive(Debug, Default)]
struct AtomicMask([AtomicU64; 2]);

impl AtomicMask {
    #[inline]
    fn or(&self, m: u128) {
        let (lo, hi) = (m as u64, (m >> 64) as u64);
        if lo != 0 {
            self.0[0].fetch_or(lo, Ordering::Relaxed);
        }
        if hi != 0 {
            self.0[1].fetch_or(hi, Ordering::Relaxed);
        }
    }

    fn load(&self) -> u128 {
        u128::from(self.0[0].load(Ordering::Relaxed))
            | u128::from(self.0[1].load(Ordering::Relaxed)) << 64
    }
}

/// One thread's buffers for a texel.
#[derive(Debug, Default)]
struct Scratch {
    samples: Vec<Sample>,
    valid: Vec<u128>,
    occluded: Vec<u128>,
}

/// Tests every texel's casters against its pixels' sub-samples.
pub fn frustum_tests(
    geometry: &Geometry,
    subs: &SubSamples<'_>,
    pixels: &TexelLists,
    casters: &TexelLists,
    options: &FtizbOptions,
) -> Tested {
    let count = subs.pixels();
    let occlusion: Vec<AtomicMask> = (0..count).map(|_| AtomicMask::default()).collect();
    let valid: Vec<AtomicMask> = (0..count).map(|_| AtomicMask::default()).collect();
    let light = subs.light();
    let counters = casters
        .texels()
        .par_iter()
        .map_init(Scratch::default, |scratch, &texel| {
            let texel = texel as usize;
            let c = test_texel(
                geometry,
                light,
                subs,
                pixels.of(texel),
                casters.of(texel),
                options,
                scratch,
            );
            for (i, &k) in pixels.of(texel).iter().enumerate() {
                valid[k as usize].or(scratch.valid[i]);
                occlusion[k as usize].or(scratch.occluded[i]);
            }
            c
        })
        .reduce(Counters::default, |mut a, b| {
            a.merge(&b);
            a
        });
    Tested {
        occlusion: occlusion.iter().map(AtomicMask::load).collect(),
        valid: valid.iter().map(AtomicMask::load).collect(),
        counters,
    }
}

/// One texel: its pixels' sub-samples against its casters, the masks left in `scratch`.
fn test_texel(
    geometry: &Geometry,
    light: &Projector,
    subs: &SubSamples<'_>,
    pixels: &[u32],
    casters: &[u32],
    options: &FtizbOptions,
    scratch: &mut Scratch,
) -> Counters {
    let rate = subs.rate();
    let n = pixels.len();
    let mut c = Counters::default();
    scratch.samples.resize(n * rate, Sample::default());
    scratch.valid.clear();
    scratch.occluded.clear();
    scratch.occluded.resize(n, 0);
    let mut farthest = f64::NEG_INFINITY;
    for (i, &k) in pixels.iter().enumerate() {
        let samples = &mut scratch.samples[i * rate..(i + 1) * rate];
        let v = subs.pixel(k as usize, samples);
        let mut bits = v;
        while bits != 0 {
            farthest = farthest.max(samples[bits.trailing_zeros() as usize].zt);
            bits &= bits - 1;
        }
        scratch.valid.push(v);
    }
    // Pixels with every valid sub-sample shadowed (at first, those with none valid).
    let mut dark = scratch.valid.iter().filter(|&&v| v == 0).count();
    for &t in casters {
        if options.occlusion_culling && dark == n {
            c.nodes_occlusion_culled += 1;
            continue;
        }
        let Some(b) = Blocker::new(geometry, t as usize, light) else { continue };
        if options.depth_culling && b.nearest_depth() >= farthest {
            c.nodes_depth_culled += 1;
            continue;
        }
        for (i, &k) in pixels.iter().enumerate() {
            let v = scratch.valid[i];
            let lit = if options.occlusion_culling { v & !scratch.occluded[i] } else { v };
            if lit == 0 || subs.triangle(k as usize) == t {
                continue;
            }
            c.visibility_evaluations += 1;
            let samples = &scratch.samples[i * rate..(i + 1) * rate];
            let mut bits = lit;
            let mut hit = 0u128;
            while bits != 0 {
                let s = bits.trailing_zeros();
                bits &= bits - 1;
                c.sampling_points_tested += 1;
                if b.shadows(&samples[s as usize]) {
                    hit |= 1 << s;
                }
            }
            if hit & !scratch.occluded[i] != 0 {
                scratch.occluded[i] |= hit;
                dark += usize::from(scratch.occluded[i] == v);
            }
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_masks_or_both_words() {
        let m = AtomicMask::default();
        m.or(1);
        m.or(1 << 100);
        m.or(0);
        assert_eq!(m.load(), 1 | 1 << 100);
    }
}
