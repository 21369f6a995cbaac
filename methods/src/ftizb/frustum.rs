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
//! tested against those the texel *owns*, in caster order. A sub-sample is owned by every
//! texel whose closed square (extended beyond the grid at the border) holds its light image
//! point as the facet's projective map places it
//! ([`Approximate`](super::footprints::Approximate), the map the footprint's
//! corners come from, so the point lies in the footprint and its texels list the pixel); only
//! owned sub-samples are placed exactly ([`SubSamples::sample`]). Each (sub-sample, caster)
//! pair is thus tested once however many texels a footprint meets (twice or four times for a
//! point exactly on a texel's side or corner, which changes nothing). The papers test a
//! pixel's whole mask in every texel of its footprint; the owned masks give the same result
//! (ORed) without the repeated tests and placements (on `cage` at 800 x 600 a footprint met
//! 2.4 texels on average). The valid masks, the ratio's denominator, are placed once per pixel
//! with a shadowed sub-sample, after the tests.
//!
//! A caster is skipped in the texel when its nearest corner is not in front of the farthest
//! sample's threshold (`nodes_depth_culled`); else each pixel that is not its own triangle's
//! and still has sub-samples that are not hidden is one `visibility_evaluations`; when the
//! caster may meet the box of the pixel's sub-samples' light image points
//! ([`Blocker::overlaps`]), those sub-samples are each one `sampling_points_tested` and the
//! frustum test decides them (`frustum_mask`), with [`Blocker::shadows`]'s decisions, exact
//! on the `f64` light image point and threshold (see [`super`]). A sub-sample the caster
//! shadows and also hides from the camera is hidden ([`super::hidden`]) instead. A shadowed
//! sub-sample is tested again against later casters, since one of them may hide it: there is
//! no occlusion culling (hidden wins whatever the casters' order, as on the GPU). The texel's
//! masks are ORed into the pixels' (two atomic words of a `u128`), so the result does not
//! depend on the order the texels are run in.
//!
//! Hot loop rules: no allocation per texel (each thread reuses its buffers), one pass over a
//! pixel's sub-samples per caster, visiting only the owned ones not hidden (their bits); a
//! sub-sample's camera ray is formed again only where a caster shadows it.

use super::{
    footprints::SubSamples,
    grid::{Grid, TexelLists},
    hidden::hides,
    FtizbOptions,
};
use crate::{
    afsm::{blockers::Blocker, samples::Sample, shadow_offset},
    method::MethodError,
};
use glam::DVec2;
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
    grid: Grid,
    pixels: &TexelLists,
) -> Result<TexelLists, MethodError> {
    let res = grid.res;
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
                let Some((x0, y0, x1, y1)) = grid.rect(grid.texels(lo), grid.texels(hi)) else {
                    continue;
                };
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
    /// Valid sub-samples per pixel that are not hidden, for the pixels with a shadowed
    /// sub-sample (zero elsewhere).
    pub valid: Vec<u128>,
    /// Hidden sub-samples per pixel ([`super::hidden`]).
    pub hidden: Vec<u128>,
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
    /// The pixels' sub-samples, `rate` per pixel.
    samples: Vec<Sample>,
    /// Their light image coordinates again, for the edge masks.
    xs: Vec<f64>,
    ys: Vec<f64>,
    /// Per pixel: the valid sub-samples the texel owns, the shadowed ones, the hidden ones
    /// ([`super::hidden`]), and the box of the owned ones' light image points.
    valid: Vec<u128>,
    occluded: Vec<u128>,
    hidden: Vec<u128>,
    boxes: Vec<(DVec2, DVec2)>,
}

/// Tests every texel's casters against its pixels' sub-samples.
pub fn frustum_tests(
    geometry: &Geometry,
    grid: Grid,
    subs: &SubSamples<'_>,
    pixels: &TexelLists,
    casters: &TexelLists,
    options: &FtizbOptions,
) -> Tested {
    let count = subs.pixels();
    let occlusion: Vec<AtomicMask> = (0..count).map(|_| AtomicMask::default()).collect();
    let hidden: Vec<AtomicMask> = (0..count).map(|_| AtomicMask::default()).collect();
    let counters = casters
        .texels()
        .par_iter()
        .map_init(Scratch::default, |scratch, &texel| {
            let texel = texel as usize;
            let c = test_texel(
                geometry,
                grid,
                subs,
                pixels.of(texel),
                texel,
                casters.of(texel),
                options,
                scratch,
            );
            for (i, &k) in pixels.of(texel).iter().enumerate() {
                occlusion[k as usize].or(scratch.occluded[i]);
                hidden[k as usize].or(scratch.hidden[i]);
            }
            c
        })
        .reduce(Counters::default, |mut a, b| {
            a.merge(&b);
            a
        });
    // Hidden wins: a sub-sample one caster shadows and another hides is left out.
    let hidden: Vec<u128> = hidden.iter().map(AtomicMask::load).collect();
    let occlusion: Vec<u128> = occlusion.iter().zip(&hidden).map(|(o, &h)| o.load() & !h).collect();
    // The ratio's denominator, for the pixels with a shadowed sub-sample.
    let valid = occlusion
        .par_iter()
        .zip(&hidden)
        .enumerate()
        .map_init(
            || vec![Sample::default(); subs.rate()],
            |out, (k, (&o, &h))| if o == 0 { 0 } else { subs.pixel(k, out) & !h },
        )
        .collect();
    Tested { occlusion, valid, hidden, counters }
}

/// One texel: the sub-samples it owns of its pixels against its casters, the masks left in
/// `scratch`.
#[allow(clippy::too_many_arguments)]
fn test_texel(
    geometry: &Geometry,
    grid: Grid,
    subs: &SubSamples<'_>,
    pixels: &[u32],
    texel: usize,
    casters: &[u32],
    options: &FtizbOptions,
    scratch: &mut Scratch,
) -> Counters {
    let rate = subs.rate();
    let light = subs.light();
    let pattern = subs.pattern();
    let centre = pattern.centre_index();
    let n = pixels.len();
    let mut c = Counters::default();
    scratch.samples.resize(n * rate, Sample::default());
    scratch.xs.resize(n * rate, 0.0);
    scratch.ys.resize(n * rate, 0.0);
    scratch.valid.clear();
    scratch.boxes.clear();
    scratch.occluded.clear();
    scratch.occluded.resize(n, 0);
    scratch.hidden.clear();
    scratch.hidden.resize(n, 0);
    let mut farthest = f64::NEG_INFINITY;
    for (i, &k) in pixels.iter().enumerate() {
        let k = k as usize;
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        let mut own = 0u128;
        // A pixel whose centre is not valid has no valid sub-sample.
        if let Some(middle) = subs.sample(k, centre) {
            let approximate = subs.approximate(k);
            for (s, offset) in pattern.offsets().iter().enumerate() {
                let owned = match &approximate {
                    Some(a) => grid.region_holds(texel, a.at(*offset - DVec2::splat(0.5))),
                    None => s == centre && grid.region_holds(texel, DVec2::new(middle.x, middle.y)),
                };
                let sample = match owned {
                    true if s == centre => Some(middle),
                    true => subs.sample(k, s),
                    false => None,
                };
                let slot = i * rate + s;
                let Some(sample) = sample else {
                    scratch.samples[slot] = Sample { zt: f64::NEG_INFINITY, ..middle };
                    continue;
                };
                scratch.samples[slot] = sample;
                scratch.xs[slot] = sample.x;
                scratch.ys[slot] = sample.y;
                let p = DVec2::new(sample.x, sample.y);
                own |= 1 << s;
                (lo, hi) = (lo.min(p), hi.max(p));
                farthest = farthest.max(sample.zt);
            }
        }
        scratch.valid.push(own);
        scratch.boxes.push((lo, hi));
    }
    let centre_bit = 1u128 << centre;
    for &t in casters {
        let Some(b) = Blocker::new(geometry, t as usize, light) else { continue };
        if options.depth_culling && b.nearest_depth() >= farthest {
            c.nodes_depth_culled += 1;
            continue;
        }
        let mut corners = None;
        for (i, &k) in pixels.iter().enumerate() {
            let k = k as usize;
            // A shadowed sub-sample is tested again: a later caster may hide it.
            let candidates = scratch.valid[i] & !scratch.hidden[i];
            if candidates == 0 || subs.triangle(k) == t {
                continue;
            }
            c.visibility_evaluations += 1;
            let (lo, hi) = scratch.boxes[i];
            if !b.overlaps(lo, hi) {
                continue;
            }
            let span = i * rate..(i + 1) * rate;
            let mut hit = frustum_mask(
                &b,
                candidates,
                &scratch.samples[span.clone()],
                &scratch.xs[span.clone()],
                &scratch.ys[span],
                (lo, hi),
            );
            c.sampling_points_tested += u64::from(candidates.count_ones());
            let mut bits = hit & !centre_bit;
            while bits != 0 {
                let s = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let Some((ray, ts)) = subs.tangent_point(k, s) else { continue };
                let corners = *corners.get_or_insert_with(|| geometry.corners(t as usize));
                if hides(&ray, ts, shadow_offset(ray.origin, ray.at(ts)), corners) {
                    scratch.hidden[i] |= 1 << s;
                    hit &= !(1 << s);
                }
            }
            scratch.occluded[i] |= hit;
        }
    }
    c
}

/// The sub-samples among `lit` that the caster `b` shadows, exactly (the decisions of
/// [`Blocker::shadows`]): the edge masks ([`Blocker::edge_masks`], 64 sub-samples at a time,
/// inside the box `bounds` of the pixel's points) drop those certainly outside the projection
/// and settle the coverage of those certainly inside the caster's bounding box and every
/// edge (their error bound holds in that box); only the rest take the exact predicates.
#[inline]
fn frustum_mask(
    b: &Blocker,
    lit: u128,
    samples: &[Sample],
    xs: &[f64],
    ys: &[f64],
    (lo, hi): (DVec2, DVec2),
) -> u128 {
    let (blo, bhi) = b.bounds();
    let mut hit = 0u128;
    for (chunk, start) in (0..samples.len()).step_by(64).enumerate() {
        let end = (start + 64).min(samples.len());
        let todo = (lit >> (64 * chunk)) as u64 & mask_of(end - start);
        if todo == 0 {
            continue;
        }
        let (maybe, surely) = b.edge_masks(&xs[start..end], &ys[start..end], lo, hi);
        let mut bits = todo & maybe;
        while bits != 0 {
            let s = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let sample = &samples[start + s];
            let boxed =
                sample.x >= blo.x && sample.x <= bhi.x && sample.y >= blo.y && sample.y <= bhi.y;
            let shadowed = boxed
                && if surely >> s & 1 == 1 {
                    b.shadows_covered(sample)
                } else {
                    b.shadows_boxed(sample)
                };
            if shadowed {
                hit |= 1u128 << (start + s);
            }
        }
    }
    hit
}

/// The mask of the first `n` bits (`n <= 64`).
#[inline]
fn mask_of(n: usize) -> u64 {
    if n >= 64 {
        u64::MAX
    } else {
        (1u64 << n) - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use proptest::prelude::*;
    use scenes::projection::{look_basis, ProjectionKind};

    #[test]
    fn atomic_masks_or_both_words() {
        let m = AtomicMask::default();
        m.or(1);
        m.or(1 << 100);
        m.or(0);
        assert_eq!(m.load(), 1 | 1 << 100);
    }

    /// A directional light looking down on the square `[0, 16]^2`, one texel a unit.
    fn light() -> Projector {
        let (right, up, forward) = look_basis(-DVec3::Z, DVec3::Y);
        Projector {
            origin: DVec3::new(8.0, 8.0, 12.0),
            right,
            up,
            forward,
            kind: ProjectionKind::Orthographic { half_width: 8.0, half_height: 8.0 },
            near: f64::NEG_INFINITY,
            width: 16.0,
            height: 16.0,
        }
    }

    proptest! {
        /// The frustum mask equals the exact test of every sub-sample, with corners and
        /// samples on a quarter-unit grid (many exactly on edges and corners) and up to 128
        /// sub-samples (two chunks of edge masks).
        #[test]
        fn frustum_masks_equal_the_exact_test_of_each_sub_sample(
            corners in proptest::collection::vec((0u32..=64, 0u32..=64, 0u32..=8), 3),
            points in proptest::collection::vec((0u32..=64, 0u32..=64, 0u32..=20), 1..=128),
            lit_bits in any::<u128>(),
        ) {
            let mut g = Geometry::default();
            g.positions.extend(corners.iter().map(|&(x, y, z)| {
                DVec3::new(f64::from(x) / 4.0, 16.0 - f64::from(y) / 4.0, f64::from(z) / 2.0)
            }));
            g.triangles.push([0, 1, 2]);
            g.object.push(0);
            let Some(b) = Blocker::new(&g, 0, &light()) else { return Ok(()) };
            let samples: Vec<Sample> = points
                .iter()
                .enumerate()
                .map(|(s, &(x, y, z))| Sample {
                    x: f64::from(x) / 4.0,
                    y: f64::from(y) / 4.0,
                    zt: 12.0 - f64::from(z) / 4.0,
                    id: s as u32,
                    tri: 7,
                })
                .collect();
            let xs: Vec<f64> = samples.iter().map(|s| s.x).collect();
            let ys: Vec<f64> = samples.iter().map(|s| s.y).collect();
            let n = samples.len();
            let lit = if n == 128 { lit_bits } else { lit_bits & ((1u128 << n) - 1) };
            let (lo, hi) = samples.iter().fold(
                (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
                |(lo, hi), s| (lo.min(DVec2::new(s.x, s.y)), hi.max(DVec2::new(s.x, s.y))),
            );
            let got = frustum_mask(&b, lit, &samples, &xs, &ys, (lo, hi));
            for (s, sample) in samples.iter().enumerate() {
                let want = lit >> s & 1 == 1 && b.shadows(sample);
                prop_assert_eq!(got >> s & 1 == 1, want, "sub-sample {}", s);
            }
        }
    }
}
