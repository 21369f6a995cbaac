//! Temporal metrics against exact truth: the flicker a method shows from frame to frame that
//! the truth does not have, over a run of frames in which the light, the camera or rigid
//! objects move (triangles keep their ids and topology, only positions change).
//!
//! # Glossary
//!
//! For frames `t-1` and `t`, a method's lit fraction `m` and the exact reference `e`:
//!
//! - **Pixel pair**: with the camera (its projector) and the geometry's positions identical
//!   in both frames, each pixel is paired with itself. Otherwise pixel `k` of frame `t`, whose
//!   G-buffer sees triangle `T` at point `p`, is paired with the pixel `q` of frame `t-1` where
//!   the point of `T` with the same barycentric coordinates at frame `t-1` projects through
//!   frame `t-1`'s camera (pixel = `floor` of the image coordinates), only where `q` is inside
//!   the image and frame `t-1`'s G-buffer sees the same triangle `T` there (visibility through
//!   the known geometry; [`reproject()`]). With nothing moving the reprojection maps every
//!   covered pixel to itself, so both pairings agree.
//! - A pair **counts** only when both pixels are headline pixels of their frame's truth
//!   (`planar` or `surface`, evaluated by the reference: [`crate::compare::Truth::headline`]).
//! - **Temporal error** of a pair: `|(m_t - m_{t-1}) - (e_t - e_{t-1})|`, the change of the
//!   method's value that the truth does not have, in [0, 2]. It is 0 for the truth against
//!   itself, for any method on a still scene (all frames equal: the method and the truth are
//!   then the same in both) and for a method that is exact. `e` is taken at the precision of a
//!   result (rounded to `f32`, as [`crate::ReferenceImage::to_visibility`] does), so that a
//!   result equal to the truth, the closest a `f32` result can be, has error exactly 0; this
//!   moves an error by at most 2^-24. The differences are taken in `f64`.
//! - **Boundary pair**: a counted pair whose pixel is a boundary pixel
//!   ([`crate::compare::Truth::boundary`]: reference strictly between 0 and 1) in either frame.
//! - Over all frame pairs: `pixel_pairs` (pairs compared), `mean` and `p95` of the temporal
//!   error; `boundary_pairs`, `boundary_mean`, `boundary_p95` over the boundary pairs;
//!   `per_class`: for the class of the frame-`t` pixel (`planar`, `surface`), its pairs and
//!   mean; `per_frame`: for each frame `t >= 1`, in order, the mean over its pairs. A mean or
//!   percentile of no pairs is `None`.
//! - **Percentiles** are nearest rank as in [`crate::metrics`] (rank `ceil(p n / 100)` of the
//!   `n` values sorted ascending, [`crate::metrics::nearest_rank_index`]), over the errors
//!   stored as `f32`: 4 bytes a pair, and 4 more a boundary pair, half of what `f64` takes
//!   (800 x 600 pixels over 120 frames: at most 229 MB, 458 when every pair is a boundary
//!   pair). Rounding to the nearest `f32` never reverses the order of two values, so the
//!   percentile of the stored values is the `f32` rounding of the `f64` errors' own: within
//!   2^-24 of it relative, 2^-23 absolute on [0, 2]. Means are sums of the `f64` errors.
//!
//! [`Temporal`] accumulates frame pairs one at a time and holds no frame, only the pairs'
//! errors, so a caller keeps two frames at a time. Each pair costs O(pixels), its rows in
//! parallel.

mod reproject;

pub use reproject::{reproject, View};

use crate::compare::Truth;
use crate::metrics::nearest_rank_index;
use crate::pixel_class::PixelClass;
use methods::{Frame, Visibility};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The percentile reported by `p95` and `boundary_p95`.
const PERCENTILE: usize = 95;

/// One frame of a run: what is read of the frame (camera, geometry, G-buffer), its truth, the
/// method's result.
pub struct FrameInput<'a> {
    /// The frame's camera, geometry and G-buffer.
    pub view: View<'a>,
    /// Its truth.
    pub truth: &'a Truth,
    /// The method's result on it.
    pub result: &'a Visibility,
}

impl<'a> FrameInput<'a> {
    /// The input of `result` on `frame` against `truth`.
    pub fn of(frame: &'a Frame<'_>, truth: &'a Truth, result: &'a Visibility) -> Self {
        Self { view: View::of(frame), truth, result }
    }
}

/// The temporal error over the pairs whose frame-`t` pixel is of one class.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ClassTemporal {
    /// Pairs compared.
    pub pairs: u64,
    /// Mean temporal error (`None` without pairs).
    pub mean: Option<f64>,
}

/// The temporal metrics of a run (see the module doc's glossary).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TemporalMetrics {
    /// Frames seen: one more than the frame pairs added, 0 when none was.
    pub frames: u32,
    /// Whether some pair needed reprojection (the camera or the geometry moved).
    pub reprojected: bool,
    /// Pixel pairs compared.
    pub pixel_pairs: u64,
    /// Mean temporal error.
    pub mean: Option<f64>,
    /// 95th percentile of the temporal error (nearest rank).
    pub p95: Option<f64>,
    /// Boundary pairs compared.
    pub boundary_pairs: u64,
    /// Mean temporal error over the boundary pairs.
    pub boundary_mean: Option<f64>,
    /// 95th percentile of the temporal error over the boundary pairs (nearest rank).
    pub boundary_p95: Option<f64>,
    /// Per class of the frame-`t` pixel (`planar`, `surface`, both always present).
    pub per_class: BTreeMap<String, ClassTemporal>,
    /// For each frame `t >= 1`, in order (entry `t - 1`), the mean temporal error over its
    /// pairs; `None` when it has none.
    pub per_frame: Vec<Option<f64>>,
}

/// Accumulates frame pairs; holds no frame, only the pairs' values, so a caller keeps two
/// frames at a time.
#[derive(Debug, Default)]
pub struct Temporal {
    reprojected: bool,
    /// Every pair added.
    pairs: Pairs,
    per_frame: Vec<Option<f64>>,
}

/// A count and a sum of errors.
#[derive(Debug, Default, Clone, Copy)]
struct Sum {
    n: u64,
    total: f64,
}

impl Sum {
    fn add(&mut self, e: f64) {
        self.n += 1;
        self.total += e;
    }

    fn merge(&mut self, other: Sum) {
        self.n += other.n;
        self.total += other.total;
    }

    fn mean(self) -> Option<f64> {
        (self.n > 0).then(|| self.total / self.n as f64)
    }
}

/// Pairs' sums and errors: of one image row while a frame pair is compared, then of every
/// pair added.
#[derive(Debug, Default)]
struct Pairs {
    all: Sum,
    boundary: Sum,
    planar: Sum,
    surface: Sum,
    /// Every pair's error, for the percentile.
    values: Vec<f32>,
    /// Every boundary pair's error, for its percentile.
    boundary_values: Vec<f32>,
}

impl Pairs {
    fn merge(&mut self, other: Pairs) {
        self.all.merge(other.all);
        self.boundary.merge(other.boundary);
        self.planar.merge(other.planar);
        self.surface.merge(other.surface);
        self.values.extend_from_slice(&other.values);
        self.boundary_values.extend_from_slice(&other.boundary_values);
    }
}

impl Temporal {
    /// No pairs yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the pair (prev, cur) of consecutive frames; returns how many pixel pairs it
    /// compared. A pair of frames whose triangles differ (ids or topology), or a frame whose
    /// truth or result is not of its frame's size, compares none (its `per_frame` entry is
    /// `None`).
    pub fn add(&mut self, prev: &FrameInput<'_>, cur: &FrameInput<'_>) -> u64 {
        let moved = prev.view.camera != cur.view.camera
            || prev.view.geometry.positions != cur.view.geometry.positions;
        self.add_pairs(prev, cur, moved)
    }

    /// [`Temporal::add`] with the pairing chosen: by reprojection or each pixel with itself.
    fn add_pairs(&mut self, prev: &FrameInput<'_>, cur: &FrameInput<'_>, moved: bool) -> u64 {
        self.reprojected |= moved;
        let (prev_pixels, cur_pixels) = (pixels(prev), pixels(cur));
        let comparable = prev_pixels.is_some()
            && cur_pixels.is_some()
            && (moved || prev_pixels == cur_pixels)
            && prev.view.geometry.triangles == cur.view.geometry.triangles;
        if !comparable {
            self.per_frame.push(None);
            return 0;
        }
        let (prev, cur) = (Side::of(prev), Side::of(cur));
        let width = cur.view.gbuffer.width as usize;
        let rows: Vec<Pairs> = (0..cur.view.gbuffer.height as usize)
            .into_par_iter()
            .map(|j| {
                let mut row = Pairs::default();
                for k in j * width..(j + 1) * width {
                    if !cur.headline[k] {
                        continue;
                    }
                    let partner = if moved { reproject(&prev.view, &cur.view, k) } else { Some(k) };
                    let Some(q) = partner.filter(|&q| prev.headline[q]) else {
                        continue;
                    };
                    let e = pair_error(
                        [prev.result[q], cur.result[k]],
                        [prev.reference[q], cur.reference[k]],
                    );
                    row.all.add(e);
                    row.values.push(e as f32);
                    if prev.boundary[q] || cur.boundary[k] {
                        row.boundary.add(e);
                        row.boundary_values.push(e as f32);
                    }
                    match cur.classes[k] {
                        PixelClass::Planar => row.planar.add(e),
                        PixelClass::Surface => row.surface.add(e),
                        // Headline pixels are planar or surface.
                        PixelClass::Edge | PixelClass::Uncovered => {}
                    }
                }
                row
            })
            .collect();
        let mut frame = Sum::default();
        for row in rows {
            frame.merge(row.all);
            self.pairs.merge(row);
        }
        self.per_frame.push(frame.mean());
        frame.n
    }

    /// The mean temporal error of the last pair added (`None` before any pair, or for a pair
    /// with no pixel pair).
    pub fn last_mean(&self) -> Option<f64> {
        self.per_frame.last().copied().flatten()
    }

    /// The metrics of the pairs added.
    pub fn finish(mut self) -> TemporalMetrics {
        let class = |s: Sum| ClassTemporal { pairs: s.n, mean: s.mean() };
        let p = &mut self.pairs;
        let per_class = [(PixelClass::Planar, p.planar), (PixelClass::Surface, p.surface)]
            .into_iter()
            .map(|(c, s)| (c.name().to_string(), class(s)))
            .collect();
        let frames = match self.per_frame.len() {
            0 => 0,
            n => u32::try_from(n).map_or(u32::MAX, |n| n.saturating_add(1)),
        };
        TemporalMetrics {
            frames,
            reprojected: self.reprojected,
            pixel_pairs: p.all.n,
            mean: p.all.mean(),
            p95: percentile(&mut p.values),
            boundary_pairs: p.boundary.n,
            boundary_mean: p.boundary.mean(),
            boundary_p95: percentile(&mut p.boundary_values),
            per_class,
            per_frame: self.per_frame,
        }
    }
}

/// What a pair reads of one frame, shared by the rows.
struct Side<'a> {
    view: View<'a>,
    headline: &'a [bool],
    boundary: Vec<bool>,
    classes: &'a [PixelClass],
    reference: &'a [f64],
    result: &'a [f32],
}

impl<'a> Side<'a> {
    fn of(input: &FrameInput<'a>) -> Self {
        let truth = input.truth;
        Self {
            view: input.view,
            headline: &truth.headline,
            boundary: truth.boundary(),
            classes: &truth.classes,
            reference: &truth.reference.lit,
            result: &input.result.lit,
        }
    }
}

/// The pixel count of the frame when its G-buffer, truth and result all have one value per
/// pixel, `None` otherwise.
fn pixels(input: &FrameInput<'_>) -> Option<usize> {
    let gbuffer = input.view.gbuffer;
    let n = gbuffer.width as usize * gbuffer.height as usize;
    let truth = input.truth;
    [
        gbuffer.triangle.len(),
        gbuffer.position.len(),
        truth.reference.lit.len(),
        truth.classes.len(),
        truth.headline.len(),
        input.result.lit.len(),
    ]
    .iter()
    .all(|&len| len == n)
    .then_some(n)
}

/// The temporal error of a pair: the method's values `m` and the reference's `e` at frames
/// `t-1` and `t`, the reference rounded to `f32` (see the module doc).
fn pair_error(m: [f32; 2], e: [f64; 2]) -> f64 {
    let dm = f64::from(m[1]) - f64::from(m[0]);
    let de = f64::from(e[1] as f32) - f64::from(e[0] as f32);
    (dm - de).abs()
}

/// The nearest-rank [`PERCENTILE`] of `values`; `None` when there are none. Reorders them.
fn percentile(values: &mut [f32]) -> Option<f64> {
    let index = nearest_rank_index(values.len(), PERCENTILE)?;
    Some(f64::from(*values.select_nth_unstable_by(index, f32::total_cmp).1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::ReferenceImage;
    use glam::DVec3;
    use instrumentation::Recorder;
    use methods::pattern::PatternKind;
    use scenes::{Camera, Light, Scene};

    fn scene(name: &str) -> Scene {
        scenes::registry::load_builtin(name).expect("built in").expect("builds")
    }

    fn frame(scene: &Scene) -> Frame<'_> {
        Frame::new(scene, 64, 48, &mut Recorder::default())
    }

    fn exact(frame: &Frame<'_>) -> Truth {
        let mut rec = Recorder::default();
        let reference = crate::registry::reference("exact", 16, PatternKind::Grid)
            .expect("exact")
            .evaluate(frame, &mut rec)
            .expect("exact applies");
        Truth::new(frame, reference, &mut rec)
    }

    fn input<'a>(frame: &'a Frame<'a>, truth: &'a Truth, result: &'a Visibility) -> FrameInput<'a> {
        FrameInput::of(frame, truth, result)
    }

    fn visibility(lit: Vec<f32>, width: u32, height: u32) -> Visibility {
        Visibility { width, height, lit, transmittance: None }
    }

    /// The metrics of the frames `inputs`, taken in order.
    fn run(inputs: &[FrameInput<'_>]) -> TemporalMetrics {
        let mut t = Temporal::new();
        for pair in inputs.windows(2) {
            t.add(&pair[0], &pair[1]);
        }
        t.finish()
    }

    /// The cage under its light and under a light turned a little.
    fn cage_with_moving_light() -> (Scene, Scene) {
        let first = scene("cage");
        let mut second = first.clone();
        second.light = Light::Directional { direction: DVec3::new(-0.5, -1.0, -0.45) }.normalized();
        assert_ne!(first.light, second.light);
        (first, second)
    }

    fn shadow_map(frame: &Frame<'_>) -> Visibility {
        methods::method("sm", &methods::MethodOptions::default())
            .expect("sm")
            .run(frame, &mut Recorder::default())
            .expect("sm runs")
    }

    #[test]
    fn hand_made_pairs_give_their_numbers() {
        use PixelClass::{Edge, Planar, Surface, Uncovered};
        let s = scene("plane-square");
        let f = Frame::new(&s, 4, 3, &mut Recorder::default());
        let classes = vec![
            Planar, Planar, Planar, Planar, Planar, Planar, Surface, Surface, Surface, Surface,
            Edge, Uncovered,
        ];
        let truth = |lit: Vec<f64>| {
            let mut evaluated = vec![true; 12];
            evaluated[9] = false;
            let image = ReferenceImage {
                width: 4,
                height: 3,
                lit,
                evaluated,
                transmittance: None,
                classes: Some(classes.clone()),
            };
            Truth::new(&f, image, &mut Recorder::default())
        };
        // Pixel 0: m flips 0 -> 1 where e stays 0.5 (error 1, boundary); 1: both flip 0 -> 1
        // (0, no boundary); 2: m drops by 0.25 where e stays 1 (0.25, no boundary); 6: e rises
        // by 0.25 and m stays (0.25, boundary); 9 (not evaluated), 10 (edge) and 11
        // (uncovered) flicker but do not count.
        let e0 = vec![0.5, 0.0, 1.0, 0.5, 0.5, 0.5, 0.25, 0.5, 0.5, 0.5, 0.5, 0.5];
        let e1 = vec![0.5, 1.0, 1.0, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5];
        let m0 = vec![0.0, 0.0, 1.0, 0.5, 0.5, 0.5, 0.25, 0.5, 0.5, 0.0, 0.0, 0.0];
        let m1 = vec![1.0, 1.0, 0.75, 0.5, 0.5, 0.5, 0.25, 0.5, 0.5, 1.0, 1.0, 1.0];
        let (t0, t1) = (truth(e0), truth(e1));
        let (r0, r1) = (visibility(m0, 4, 3), visibility(m1, 4, 3));
        let mut t = Temporal::new();
        assert_eq!(t.add(&input(&f, &t0, &r0), &input(&f, &t1, &r1)), 9);
        // A frame whose truth evaluates nothing: no pairs.
        let none = Truth::new(
            &f,
            ReferenceImage {
                width: 4,
                height: 3,
                lit: vec![0.5; 12],
                evaluated: vec![false; 12],
                transmittance: None,
                classes: Some(classes.clone()),
            },
            &mut Recorder::default(),
        );
        assert_eq!(t.add(&input(&f, &t1, &r1), &input(&f, &none, &r0)), 0);
        let m = t.finish();
        let class = |pairs, mean| ClassTemporal { pairs, mean: Some(mean) };
        let want = TemporalMetrics {
            frames: 3,
            reprojected: false,
            pixel_pairs: 9,
            mean: Some(1.5 / 9.0),
            p95: Some(1.0),
            boundary_pairs: 7,
            boundary_mean: Some(1.25 / 7.0),
            boundary_p95: Some(1.0),
            per_class: BTreeMap::from([
                ("planar".to_string(), class(6, 1.25 / 6.0)),
                ("surface".to_string(), class(3, 0.25 / 3.0)),
            ]),
            per_frame: vec![Some(1.5 / 9.0), None],
        };
        assert_eq!(m, want);
        let json = serde_json::to_value(&m).expect("serialises");
        assert_eq!(json["per_frame"][1], serde_json::Value::Null);
        assert_eq!(serde_json::from_value::<TemporalMetrics>(json).expect("reads back"), want);
    }

    #[test]
    fn no_pairs_give_no_statistics() {
        let none = ClassTemporal { pairs: 0, mean: None };
        let want = TemporalMetrics {
            frames: 0,
            reprojected: false,
            pixel_pairs: 0,
            mean: None,
            p95: None,
            boundary_pairs: 0,
            boundary_mean: None,
            boundary_p95: None,
            per_class: BTreeMap::from([("planar".into(), none), ("surface".into(), none)]),
            per_frame: vec![],
        };
        assert_eq!(Temporal::new().finish(), want);
    }

    #[test]
    fn frames_that_do_not_fit_together_compare_nothing() {
        let s = scene("plane-square");
        let f = frame(&s);
        let truth = exact(&f);
        let result = truth.reference.to_visibility();
        let short = visibility(vec![0.5; 10], 64, 48);
        let mut other_mesh = f.clone();
        other_mesh.geometry.triangles.swap(0, 1);
        let mut t = Temporal::new();
        assert_eq!(t.add(&input(&f, &truth, &result), &input(&f, &truth, &short)), 0);
        assert_eq!(t.add(&input(&f, &truth, &result), &input(&other_mesh, &truth, &result)), 0);
        assert!(t.add(&input(&f, &truth, &result), &input(&f, &truth, &result)) > 0);
        let m = t.finish();
        assert_eq!((m.frames, m.per_frame.len()), (4, 3));
        assert_eq!(&m.per_frame[..2], &[None, None]);
    }

    #[test]
    fn the_truth_against_itself_has_no_temporal_error() {
        let (a, b) = cage_with_moving_light();
        let (fa, fb) = (frame(&a), frame(&b));
        let (ta, tb) = (exact(&fa), exact(&fb));
        let (ra, rb) = (ta.reference.to_visibility(), tb.reference.to_visibility());
        assert_ne!(ta.reference.lit, tb.reference.lit, "the shadow moves");
        let m = run(&[input(&fa, &ta, &ra), input(&fb, &tb, &rb), input(&fa, &ta, &ra)]);
        assert!(!m.reprojected);
        assert!(m.pixel_pairs > 1000 && m.boundary_pairs > 0, "{m:?}");
        assert_eq!((m.mean, m.p95), (Some(0.0), Some(0.0)));
        assert_eq!((m.boundary_mean, m.boundary_p95), (Some(0.0), Some(0.0)));
        assert_eq!(m.per_frame, vec![Some(0.0); 2]);
        // A result that does not move sees all the truth's flicker: |e_t - e_{t-1}|.
        let lit = visibility(vec![1.0; 64 * 48], 64, 48);
        let m = run(&[input(&fa, &ta, &lit), input(&fb, &tb, &lit)]);
        let flicker: Vec<f64> = (0..64 * 48)
            .filter(|&k| ta.headline[k] && tb.headline[k])
            .map(|k| (f64::from(rb.lit[k]) - f64::from(ra.lit[k])).abs())
            .collect();
        assert_eq!(m.pixel_pairs, flicker.len() as u64);
        let mean = flicker.iter().sum::<f64>() / flicker.len() as f64;
        assert!(mean > 0.0 && (m.mean.expect("pairs") - mean).abs() < 1e-12, "{m:?} vs {mean}");
    }

    #[test]
    fn any_method_on_a_still_scene_has_no_temporal_error() {
        let s = scene("cage");
        let f = frame(&s);
        let truth = exact(&f);
        let sm = shadow_map(&f);
        let m = run(&[input(&f, &truth, &sm), input(&f, &truth, &sm), input(&f, &truth, &sm)]);
        assert!(m.pixel_pairs > 1000);
        assert_eq!((m.mean, m.p95, m.boundary_mean), (Some(0.0), Some(0.0), Some(0.0)));
        assert_eq!(m.per_class["planar"].mean, Some(0.0));
    }

    #[test]
    fn pairing_a_still_frame_with_itself_equals_reprojecting_it() {
        let (a, b) = cage_with_moving_light();
        let (fa, fb) = (frame(&a), frame(&b));
        let (ta, tb) = (exact(&fa), exact(&fb));
        let (ra, rb) = (shadow_map(&fa), shadow_map(&fb));
        let (pa, pb) = (input(&fa, &ta, &ra), input(&fb, &tb, &rb));
        let mut still = Temporal::new();
        let mut reprojected = Temporal::new();
        assert_eq!(still.add(&pa, &pb), reprojected.add_pairs(&pa, &pb, true));
        let (still, reprojected) = (still.finish(), reprojected.finish());
        assert!(still.mean.expect("pairs") > 0.0, "sm flickers under a moving light");
        assert!(!still.reprojected && reprojected.reprojected);
        assert_eq!(TemporalMetrics { reprojected: true, ..still }, reprojected);
    }

    #[test]
    fn a_moving_camera_reprojects_and_the_truth_still_has_no_temporal_error() {
        let a = scene("cage");
        let mut b = a.clone();
        let Camera::Perspective { eye, target, up, fov_y_deg, near } = a.camera else {
            panic!("the cage's camera is perspective");
        };
        b.camera = Camera::Perspective {
            eye: eye + DVec3::new(0.4, 0.1, 0.0),
            target,
            up,
            fov_y_deg,
            near,
        };
        let (fa, fb) = (frame(&a), frame(&b));
        let (ta, tb) = (exact(&fa), exact(&fb));
        let (ra, rb) = (ta.reference.to_visibility(), tb.reference.to_visibility());
        let m = run(&[input(&fa, &ta, &ra), input(&fb, &tb, &rb)]);
        assert!(m.reprojected);
        let headline = tb.headline.iter().filter(|&&h| h).count() as u64;
        assert!(m.pixel_pairs > headline / 2 && m.pixel_pairs < headline, "{m:?}");
        assert_eq!((m.mean, m.p95), (Some(0.0), Some(0.0)));
        // A method that does not follow the camera flickers.
        let sm = [shadow_map(&fa), shadow_map(&fb)];
        let m = run(&[input(&fa, &ta, &sm[0]), input(&fb, &tb, &sm[1])]);
        assert!(m.mean.expect("pairs") > 0.0);
    }
}
