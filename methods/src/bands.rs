//! Binning items into bands of rows, in parallel: the camera and light rasterizer's triangles
//! ([`crate::raster`]) and the exact reference's pixel clipper, shadow polygons and caster grid
//! cells bin their items this way before working band by band.

use rayon::prelude::*;

/// Items per run of the parallel binning: each run counts and places its own items.
pub const RUN: usize = 1 << 14;

/// Bins items `0..count` into bands of `band` rows (at least 1): `rows(item)` gives the
/// inclusive row range an item may touch (already clamped to `0..height`). Returns `(offsets,
/// items)` in CSR layout: band `b`'s items are `items[offsets[b]..offsets[b + 1]]`, in
/// ascending order.
///
/// In parallel over runs of [`RUN`] items: each run counts its items per band, and writes them
/// into its own part of every band (the runs' parts follow each other in run order, so each
/// band stays in item order).
pub fn bin_by_band(
    count: usize,
    height: usize,
    band: usize,
    rows: impl Fn(usize) -> Option<(usize, usize)> + Sync,
) -> (Vec<usize>, Vec<u32>) {
    let band = band.max(1);
    let bands = height.div_ceil(band);
    // Each item's bands, `(first, last)` (`first > last`: none).
    let spans: Vec<(u32, u32)> = (0..count)
        .into_par_iter()
        .map(|i| rows(i).map_or((1, 0), |(a, b)| ((a / band) as u32, (b / band) as u32)))
        .collect();
    let counts: Vec<Vec<usize>> = spans
        .par_chunks(RUN)
        .map(|run| {
            let mut n = vec![0usize; bands];
            for &(a, b) in run {
                for band in a..=b {
                    n[band as usize] += 1;
                }
            }
            n
        })
        .collect();
    let mut offsets = vec![0usize; bands + 1];
    for b in 0..bands {
        offsets[b + 1] = offsets[b] + counts.iter().map(|n| n[b]).sum::<usize>();
    }
    let mut items = vec![0u32; offsets[bands]];
    // Run `r`'s part of every band, cut from `items` band by band.
    let mut parts: Vec<Vec<&mut [u32]>> = (0..counts.len()).map(|_| Vec::new()).collect();
    let mut rest = &mut items[..];
    for b in 0..bands {
        for (r, n) in counts.iter().enumerate() {
            let (part, tail) = std::mem::take(&mut rest).split_at_mut(n[b]);
            parts[r].push(part);
            rest = tail;
        }
    }
    spans.par_chunks(RUN).zip(parts).enumerate().for_each(|(r, (run, mut parts))| {
        let mut at = vec![0usize; bands];
        for (k, &(a, b)) in run.iter().enumerate() {
            for band in a as usize..=b as usize {
                parts[band][at[band]] = (r * RUN + k) as u32;
                at[band] += 1;
            }
        }
    });
    (offsets, items)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The parallel binning gives every band its items in ascending order, as binning them
    /// one by one does, across several runs of items and with items in no band.
    #[test]
    fn items_are_binned_in_order() {
        let height = 200;
        let rows = |i: usize| {
            let a = (i * 7919) % 230;
            (a < height).then(|| (a, (a + i % 37).min(height - 1)))
        };
        let count = 3 * (1 << 14) + 5;
        for band in [8, 1, 13, 500] {
            let (offsets, items) = bin_by_band(count, height, band, rows);
            let bands = height.div_ceil(band);
            assert_eq!(offsets.len(), bands + 1);
            for b in 0..bands {
                let expected: Vec<u32> = (0..count)
                    .filter(|&i| rows(i).is_some_and(|(a, z)| a / band <= b && b <= z / band))
                    .map(|i| i as u32)
                    .collect();
                assert_eq!(&items[offsets[b]..offsets[b + 1]], &expected[..], "band {band}: {b}");
            }
        }
    }
}
