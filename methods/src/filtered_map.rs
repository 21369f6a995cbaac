//! What the filtered shadow maps share (variance, exponential and moment shadow maps, in the
//! registry's table): the width of the box filter over their stored values ([`FILTER`]), the
//! filter itself ([`box_filter`]) and their stages ([`run`]).
//!
//! Each stores `N` values per texel that are a function of the caster's depth `z`, normalised
//! to [0, 1] over the scene's light depth range (1 where the texel holds no caster, as a
//! cleared depth buffer holds the far plane), filters them, and tests each pixel centre's
//! receiver depth, normalised the same way after the shared bias tolerance of
//! [`crate::depth_test`] (with the reach of the filter's half-width), against its texel's
//! filtered values. Stages: the light depth map, the stored values filtered (timed under the
//! method's first stage name), the test (its second).
//!
//! The filter is a box of `filter x filter` texels, separable (rows, then columns), in `f64`;
//! texels beyond the map's border repeat the border (clamp to edge). It runs over any number of
//! values per texel (`N`: two moments, one exponential). Hot path: one pass per axis over rows
//! in parallel, no allocation inside a row.

use crate::{
    depth_test::{filter_pixels, texel_at, DepthTester, MapOptions, PixelResult},
    footprint::Sampling,
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    params::{Kind, Param},
};
use glam::DVec2;
use instrumentation::Recorder;
use rayon::prelude::*;

/// Width of the box filter over a filtered shadow map's stored values.
pub static FILTER: Param = Param {
    key: "filter",
    flag: "--filter",
    value_name: "K",
    help: "Width in texels of the box filter over a filtered shadow map's stored values: odd, 1 \
           to 63; default 3 (1: no filtering).",
    kind: Kind::Count,
};

/// The default filter width, in texels.
pub const DEFAULT_FILTER: u32 = 3;
/// The widest filter.
pub const MAX_FILTER: u32 = 63;

/// Checks a filter width; the error names the flag.
pub fn check_filter(filter: u32) -> Result<(), MethodError> {
    if filter.is_multiple_of(2) || filter > MAX_FILTER {
        return Err(MethodError::InvalidOption {
            option: FILTER.flag,
            message: format!("must be odd, 1 to {MAX_FILTER}, got {filter}"),
        });
    }
    Ok(())
}

/// `values` (a `res x res` map, row by row, `N` values per texel) averaged over a
/// `filter`-wide box; `filter = 1` gives them back unchanged.
pub fn box_filter<const N: usize>(
    values: Vec<[f64; N]>,
    res: usize,
    filter: usize,
) -> Vec<[f64; N]> {
    if filter <= 1 {
        return values;
    }
    let half = (filter / 2) as isize;
    let last = res as isize - 1;
    let weight = 1.0 / filter as f64;
    let blur = |src: &[[f64; N]], along_rows: bool| -> Vec<[f64; N]> {
        let mut out = vec![[0.0; N]; res * res];
        out.par_chunks_mut(res).enumerate().for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let mut sum = [0.0; N];
                for k in -half..=half {
                    let (sx, sy) = if along_rows {
                        ((x as isize + k).clamp(0, last) as usize, y)
                    } else {
                        (x, (y as isize + k).clamp(0, last) as usize)
                    };
                    for (s, v) in sum.iter_mut().zip(src[sy * res + sx]) {
                        *s += v;
                    }
                }
                *o = sum.map(|s| s * weight);
            }
        });
        out
    };
    let rows = blur(&values, true);
    blur(&rows, false)
}

/// A filtered shadow map's values and test: what [`run`] needs of it.
pub trait FilteredMap<const N: usize>: ShadowMethod {
    /// Map resolution and bias.
    fn map(&self) -> &MapOptions;
    /// Width of the box filter, in texels (odd).
    fn filter(&self) -> u32;
    /// The names of its two stages: the filtered values, the test.
    fn stages(&self) -> [&'static str; 2];
    /// What a texel stores for the normalised caster depth `z`.
    fn store(&self, z: f64) -> [f64; N];
    /// The lit fraction, in [0, 1], at the normalised receiver depth `z` of a pixel whose
    /// texel holds the filtered values `filtered`.
    fn test(&self, filtered: &[f64; N], z: f64) -> f64;
}

/// Runs the filtered shadow map `m` on `frame` (see the module documentation).
pub fn run<const N: usize, M: FilteredMap<N>>(
    m: &M,
    frame: &Frame<'_>,
    rec: &mut Recorder,
) -> Result<Visibility, MethodError> {
    if frame.effects.transparency {
        rec.notes.push(format!("{} treats semi-transparent casters as opaque", m.name()));
    }
    let map = frame.light_depth_map(m.map().map_res, m.map().frustum, rec);
    let (near, _) = frame.light_depth_bounds(&map.projector);
    let range = frame.light_depth_range(&map.projector);
    let res = map.res as usize;
    let [store_stage, test_stage] = m.stages();
    let filtered = rec.stages.time(store_stage, || {
        let raw: Vec<[f64; N]> = map
            .depth
            .par_iter()
            .map(|&t| {
                m.store(if t.is_finite() { ((t - near) / range).clamp(0.0, 1.0) } else { 1.0 })
            })
            .collect();
        box_filter(raw, res, m.filter() as usize)
    });
    let tester = DepthTester::new(m.map(), map.projector, range);
    rec.warnings.extend(tester.warnings(m.name(), frame, Sampling::PixelCentre));
    let reach = DVec2::splat(f64::from(m.filter()) / 2.0);
    let (lit, counters) = rec.stages.time(test_stage, || {
        filter_pixels(frame, &tester, |_, _, r| {
            let Some((x, y)) = texel_at(r.xy, map.res) else {
                return PixelResult { lit: 1.0, ..Default::default() };
            };
            let z = (r.depth - tester.tolerance(r, reach) - near) / range;
            let lit = m.test(&filtered[y * res + x], z).clamp(0.0, 1.0);
            PixelResult { lit: lit as f32, compares: 1, bilinear_lookups: 0 }
        })
    });
    rec.counters.merge(&counters);
    Ok(Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The box averages its texels and repeats the border; one texel is no filter.
    #[test]
    fn boxes_average_and_repeat_the_border() {
        let values: Vec<[f64; 1]> = (0..9).map(|v| [f64::from(v)]).collect();
        assert_eq!(box_filter(values.clone(), 3, 1), values);
        let f = box_filter(values, 3, 3);
        assert!((f[4][0] - 4.0).abs() < 1e-12, "{:?}", f[4]);
        // Corner: rows 0, 0, 1 and columns 0, 0, 1 of 0 1 2 / 3 4 5.
        let corner = (4.0 * 0.0 + 2.0 * 1.0 + 2.0 * 3.0 + 4.0) / 9.0;
        assert!((f[0][0] - corner).abs() < 1e-12, "{:?}", f[0]);
    }

    #[test]
    fn even_or_wide_filters_name_the_flag() {
        assert!(check_filter(1).is_ok() && check_filter(63).is_ok());
        for bad in [0, 2, 64, 65] {
            assert!(check_filter(bad).expect_err("refused").to_string().starts_with("--filter: "));
        }
    }
}
