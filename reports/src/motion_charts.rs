//! The charts of a report's runs in motion: the runs of a scene with an animation, each
//! carrying its temporal metrics ([`Row::temporal`], `analysis::temporal`: the flicker the
//! method shows from frame to frame that the exact truth does not have) and its per-frame
//! records ([`Row::per_frame`]). Written as PNG and SVG into `plots/` by [`crate::plots`],
//! beside the still charts of [`crate::figures`], and shown in the scene's "In motion"
//! section of the index ([`crate::index`]).
//!
//! Per animated scene:
//! - **temporal error against time** (`temporal-vs-time-SCENE`): the runs' mean temporal error
//!   against their time per frame on the report's clock, one series per method, device and
//!   fixed parameters (the light-frustum policy among them) as the still error-against-time
//!   charts have them ([`crate::figures::series`]), with the Pareto front of temporal error and
//!   time ([`temporal_pareto_rows`]) and the scene's runs in motion that a chart of
//!   [`MAX_SERIES`] series leaves out as grey dots;
//! - **temporal error against mean error** (`temporal-vs-error-SCENE`): whether the runs that
//!   are accurate on each frame are also steady from one frame to the next;
//! - **temporal error per frame** (`temporal-per-frame-SCENE`): for each frame from 1 on, the
//!   mean temporal error of the pair (previous frame, this frame), one line per run, at most
//!   [`MAX_SERIES`] (the first in report order), the runs left out named in the figure's
//!   caption; its frame axis is linear.
//!
//! A temporal error of 0 (an exact method, a frame pair where nothing changed) is drawn at the
//! log axis' floor and the chart says so.

use crate::figures::{
    clock_name, packed_series, params_text, Measure, Place, PlotFile, SceneChart,
};
use crate::model::{method_label, Report, Row, SceneInfo};
use crate::output::OutputError;
use crate::plots::{pareto_front, write_chart, Chart, Marker, Point, Series, MAX_SERIES};
use instrumentation::measure::Clock;
use std::path::Path;

/// Whether a run was in motion: its scene has an animation, and it has temporal metrics.
pub fn in_motion(row: &Row) -> bool {
    row.temporal.is_some()
}

/// The runs of `scene` in motion, in report order.
pub fn motion_rows<'a>(report: &'a Report, scene: &str) -> Vec<&'a Row> {
    report.rows.iter().filter(|r| r.scene == scene && in_motion(r)).collect()
}

/// A run's mean temporal error, where it has one.
pub fn temporal_error(row: &Row) -> Option<f64> {
    row.temporal.as_ref().and_then(|t| t.mean)
}

/// How many frames a run in motion has: its per-frame records, or its temporal metrics'
/// frame count where it has no record; 0 for a still run.
pub fn frame_count(row: &Row) -> usize {
    if row.per_frame.is_empty() {
        row.temporal.as_ref().map_or(0, |t| t.frames as usize)
    } else {
        row.per_frame.len()
    }
}

/// The rows on the Pareto front of temporal error against time on `clock` (no other row is
/// both faster and steadier), fastest first; rows without a temporal error are left out.
pub fn temporal_pareto_rows<'a>(rows: &[&'a Row], clock: Clock) -> Vec<&'a Row> {
    let measured: Vec<(&Row, (f64, f64))> = rows
        .iter()
        .filter_map(|r| temporal_error(r).map(|e| (*r, (r.time(clock).median, e))))
        .collect();
    let points: Vec<(f64, f64)> = measured.iter().map(|(_, p)| *p).collect();
    pareto_front(&points)
        .into_iter()
        .filter_map(|p| measured.iter().find(|(_, q)| *q == p).map(|(r, _)| *r))
        .collect()
}

/// A run's name on a chart: its method, then its parameters (`sm map_res=512 frustum=view`).
pub fn run_label(row: &Row) -> String {
    [method_label(row), params_text(row)].join(" ").trim().to_owned()
}

/// The per-frame temporal errors of `rows` as series, one per run with a value on some frame
/// (frame number against the temporal error of the pair ending there), the first
/// [`MAX_SERIES`] in the order of `rows`; and the names of the runs with values that are left
/// out.
pub fn per_frame_series(rows: &[&Row]) -> (Vec<Series>, Vec<String>) {
    let all: Vec<Series> = rows
        .iter()
        .filter_map(|r| {
            let points: Vec<Point> = r
                .per_frame
                .iter()
                .filter_map(|f| f.temporal_error.map(|e| Point::at(f64::from(f.frame), e)))
                .collect();
            let marker = if r.on_gpu() { Marker::Triangle } else { Marker::Circle };
            (!points.is_empty()).then(|| Series { label: run_label(r), marker, points })
        })
        .collect();
    let left_out = all.iter().skip(MAX_SERIES).map(|s| s.label.clone()).collect();
    (all.into_iter().take(MAX_SERIES).collect(), left_out)
}

/// The runs of `rows` that `lines` do not draw, as grey points of `x` against `y`.
fn context(rows: &[&Row], lines: &[Series], x: Measure, y: Measure) -> Vec<Point> {
    rows.iter()
        .filter_map(|r| Some((x.of(r)?, y.of(r)?)))
        .filter(|&(px, py)| !lines.iter().any(|s| s.points.iter().any(|p| p.x == px && p.y == py)))
        .map(|(px, py)| Point::at(px, py))
        .collect()
}

/// What a chart says of its scene: reference and frame.
fn against(sc: &SceneInfo) -> String {
    format!("against {} at {}x{}", sc.reference, sc.width, sc.height)
}

/// The charts of the runs in motion of `scene` (see the module documentation); none for a
/// scene without such runs.
pub fn charts(report: &Report, scene: &SceneInfo) -> Vec<SceneChart> {
    let rows = motion_rows(report, &scene.scene);
    if rows.iter().all(|r| temporal_error(r).is_none()) {
        return Vec::new();
    }
    let adapter = report.machine.gpu.as_deref();
    let clock = report.clock;
    let time = Measure::Time(clock);
    let name = &scene.scene;
    let chart = |title: String, x_label: String, series, pareto, linear_x| Chart {
        title,
        x_label,
        y_label: Measure::TemporalError.label(),
        series,
        pareto,
        linear_x,
    };
    let mut out = Vec::new();
    let kinds = [
        (
            "temporal-vs-time",
            format!("temporal error against {} time per frame", clock_name(clock)),
            time,
            format!(
                "{} time per frame, median over the frames with [min, max] (ms)",
                clock_name(clock)
            ),
        ),
        (
            "temporal-vs-error",
            "temporal error against mean error".to_owned(),
            Measure::MeanError,
            Measure::MeanError.label(),
        ),
    ];
    for (kind, what, x, x_label) in kinds {
        let pareto = x == time;
        let parts = packed_series(&rows, x, Measure::TemporalError, adapter);
        let n = parts.len();
        for (k, mut lines) in parts.into_iter().enumerate() {
            let part = if n > 1 { format!(" ({} of {n})", k + 1) } else { String::new() };
            let others = context(&rows, &lines, x, Measure::TemporalError);
            if !others.is_empty() {
                lines.push(Series {
                    label: "the scene's other runs in motion".into(),
                    marker: Marker::Context,
                    points: others,
                });
            }
            let suffix = if k > 0 { format!("-{}", k + 1) } else { String::new() };
            out.push(SceneChart {
                scene: name.clone(),
                stem: format!("{kind}-{name}{suffix}"),
                chart: chart(
                    format!("{name}{part}: {what}, {}", against(scene)),
                    x_label.clone(),
                    lines,
                    pareto,
                    false,
                ),
                note: String::new(),
            });
        }
    }
    let (lines, left_out) = per_frame_series(&rows);
    if !lines.is_empty() {
        out.push(SceneChart {
            scene: name.clone(),
            stem: format!("temporal-per-frame-{name}"),
            chart: chart(
                format!("{name}: temporal error per frame, {}", against(scene)),
                "frame (the pair of it and the frame before it)".into(),
                lines,
                false,
                true,
            ),
            note: if left_out.is_empty() {
                String::new()
            } else {
                format!("not drawn (at most {MAX_SERIES} lines): {}", left_out.join(", "))
            },
        });
    }
    out
}

/// Writes the charts of every scene's runs in motion into `dir/plots/` (the folder
/// [`crate::figures::write_plots`] writes, which must exist). Returns them, each placed in
/// the "In motion" section ([`Place::Motion`]), its title followed by its note.
pub fn write_plots(dir: &Path, report: &Report) -> Result<Vec<PlotFile>, OutputError> {
    let plots = dir.join("plots");
    std::fs::create_dir_all(&plots)
        .map_err(|e| OutputError::Write { path: plots.clone(), message: e.to_string() })?;
    let mut files = Vec::new();
    for sc in &report.scenes {
        for c in charts(report, sc) {
            write_chart(&plots.join(&c.stem), &c.chart)?;
            let title = if c.note.is_empty() {
                c.chart.title.clone()
            } else {
                format!("{}; {}", c.chart.title, c.note)
            };
            files.push(PlotFile {
                scene: c.scene,
                title,
                png: format!("plots/{}.png", c.stem),
                place: Place::Motion,
            });
        }
    }
    Ok(files)
}

/// Runs in motion made by hand, for the tests of what shows them (charts, files, pages).
#[cfg(test)]
pub(crate) mod fixture {
    use crate::animation::FrameRecord;
    use crate::model::{MotionFrames, Row};
    use analysis::temporal::{ClassTemporal, TemporalMetrics};

    /// Temporal metrics of mean `mean` over `frames` frames: p95 twice the mean, boundary
    /// mean three times it, 100 pixel pairs a frame pair.
    pub fn metrics(mean: f64, frames: u32) -> TemporalMetrics {
        let pairs = 100 * u64::from(frames.saturating_sub(1));
        let class = ClassTemporal { pairs, mean: Some(mean) };
        TemporalMetrics {
            frames,
            reprojected: false,
            pixel_pairs: pairs,
            mean: Some(mean),
            p95: Some(2.0 * mean),
            boundary_pairs: pairs / 4,
            boundary_mean: Some(3.0 * mean),
            boundary_p95: Some(4.0 * mean),
            per_class: [("planar".to_owned(), class), ("surface".to_owned(), class)]
                .into_iter()
                .collect(),
            per_frame: (1..frames).map(|_| Some(mean)).collect(),
        }
    }

    /// Puts `row` in motion over `frames` frames with temporal error `mean`: its metrics, and
    /// a record per frame (frame k at time k / 10, temporal error `mean` from frame 1 on).
    pub fn put_in_motion(row: &mut Row, mean: f64, frames: u32) {
        row.temporal = Some(metrics(mean, frames));
        row.per_frame = (0..frames)
            .map(|k| FrameRecord {
                frame: k,
                time: f64::from(k) / 10.0,
                map_res: None,
                mean_abs_error: Some(row.metrics.mean_abs_error),
                boundary_mean_abs_error: None,
                boundary_p95_abs_error: None,
                temporal_error: (k > 0).then_some(mean),
                temporal_pairs: if k > 0 { 100 } else { 0 },
                method_ms: 1.0,
                method_cpu_ms: Some(1.0),
                reference_ms: 2.0,
                reference_cached: false,
            })
            .collect();
    }

    /// Frames of the report of [`report_in_motion`].
    pub const FRAMES: u32 = 4;

    /// Frame delay of the report of [`report_in_motion`], milliseconds.
    pub const FRAME_MS: u16 = 80;

    /// A report of `sm` at two map sizes on `plane-square` at 32 x 24, its first run put in
    /// motion over [`FRAMES`] frames with temporal error 0.01 and its frames given
    /// ([`motion_frames`], each shown [`FRAME_MS`]); the other run still.
    pub fn report_in_motion() -> (crate::model::Report, crate::model::Images) {
        let suite = crate::suite::Suite::parse(
            "name = \"motion\"\nwidth = 32\nheight = 24\nwarmup = 0\nrepeats = 1\n\
             scenes = [\"plane-square\"]\n[[run]]\nmethod = \"sm\"\nmap_res = [64, 128]\n",
            std::path::Path::new("motion.toml"),
        )
        .expect("a valid suite");
        let (mut report, mut images) = crate::sweep::run_suite(&suite, |_| {});
        assert_eq!(report.rows.len(), 2, "{:?}", report.skipped);
        put_in_motion(&mut report.rows[0], 0.01, FRAMES);
        let produced = images.runs.iter_mut().find(|p| p.row == 0).expect("the first run's");
        produced.motion = Some(motion_frames(32, 24, FRAMES, FRAME_MS));
        (report, images)
    }

    /// `frames` frames of `w x h` as PNG bytes: the method's frame k all grey level 10 k,
    /// the reference's 10 k + 1, the error map's 10 k + 2 and one row taller (as an error map
    /// is, with its colour bar).
    pub fn motion_frames(w: u32, h: u32, frames: u32, frame_ms: u16) -> MotionFrames {
        let png = |w: u32, h: u32, v: u32| {
            let img = image::RgbImage::from_pixel(w, h, image::Rgb([(v % 256) as u8; 3]));
            let mut bytes = Vec::new();
            img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
                .expect("encodes");
            bytes
        };
        MotionFrames {
            method: (0..frames).map(|k| png(w, h, 10 * k)).collect(),
            reference: (0..frames).map(|k| png(w, h, 10 * k + 1)).collect(),
            error: (0..frames).map(|k| png(w, h + 1, 10 * k + 2)).collect(),
            frame_ms,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `sm` at three map sizes and `pcf-reeves` at two rates on one scene, each put in motion
    /// with the temporal error given per run, and the times given per run.
    fn report(errors: &[f64], times: &[f64]) -> Report {
        let mut report = crate::sweep::report_of(
            r#"
            name = "motion"
            width = 32
            height = 24
            warmup = 0
            repeats = 1
            scenes = ["plane-square"]
            [[run]]
            method = "sm"
            map_res = [256, 512, 1024]
            [[run]]
            method = "pcf-reeves"
            map_res = [256]
            rate = [4, 16]
            "#,
        );
        assert_eq!(report.rows.len(), errors.len());
        report.clock = Clock::Wall;
        for ((r, &e), &t) in report.rows.iter_mut().zip(errors).zip(times) {
            fixture::put_in_motion(r, e, 4);
            r.total_ms = instrumentation::stats::Summary::of(&[t]).expect("a time");
        }
        report
    }

    #[test]
    fn the_temporal_pareto_front_keeps_the_runs_no_run_beats_in_both() {
        // Run 1 is slower and less steady than run 0; run 3 ties run 2's time but is steadier;
        // run 4 is the slowest and the steadiest.
        let report = report(&[0.02, 0.03, 0.01, 0.005, 0.001], &[1.0, 2.0, 3.0, 3.0, 9.0]);
        let rows: Vec<&Row> = report.rows.iter().collect();
        let front = temporal_pareto_rows(&rows, Clock::Wall);
        let picked: Vec<usize> = front
            .iter()
            .map(|f| rows.iter().position(|r| std::ptr::eq(*r, *f)).expect("a row"))
            .collect();
        assert_eq!(picked, [0, 3, 4]);
        // A row without a temporal error is on no front; nor is a still run.
        let mut still = report.rows.clone();
        still[0].temporal = None;
        still[3].temporal.as_mut().expect("in motion").mean = None;
        let rows: Vec<&Row> = still.iter().collect();
        let front = temporal_pareto_rows(&rows, Clock::Wall);
        assert_eq!(
            front.iter().map(|r| temporal_error(r)).collect::<Vec<_>>(),
            [Some(0.03), Some(0.01), Some(0.001)]
        );
        assert!(!in_motion(&still[0]) && in_motion(&still[1]));
        assert_eq!((frame_count(&still[0]), frame_count(&still[1])), (4, 4));
    }

    #[test]
    fn the_charts_draw_every_run_in_motion() {
        let report = report(&[0.02, 0.03, 0.01, 0.005, 0.001], &[1.0, 2.0, 3.0, 3.0, 9.0]);
        let charts = charts(&report, &report.scenes[0]);
        let stems: Vec<&str> = charts.iter().map(|c| c.stem.as_str()).collect();
        assert_eq!(
            stems,
            [
                "temporal-vs-time-plane-square",
                "temporal-vs-error-plane-square",
                "temporal-per-frame-plane-square"
            ]
        );
        let [time, error, frames] = &charts[..] else { panic!("{stems:?}") };
        assert!(time.chart.pareto && !error.chart.pareto && !frames.chart.pareto);
        assert!(frames.chart.linear_x && !time.chart.linear_x);
        for c in [time, error] {
            let mut ys: Vec<f64> =
                c.chart.series.iter().flat_map(|s| s.points.iter().map(|p| p.y)).collect();
            ys.sort_by(f64::total_cmp);
            assert_eq!(ys, [0.001, 0.005, 0.01, 0.02, 0.03], "{}", c.stem);
        }
        // The front of the points drawn is the front of the rows.
        let points: Vec<(f64, f64)> =
            time.chart.series.iter().flat_map(|s| s.points.iter().map(|p| (p.x, p.y))).collect();
        assert_eq!(pareto_front(&points), [(1.0, 0.02), (3.0, 0.005), (9.0, 0.001)]);
        // One line per run over frames 1 to 3, named with its parameters.
        assert_eq!(frames.chart.series.len(), 5);
        assert!(frames
            .chart
            .series
            .iter()
            .all(|s| { s.points.iter().map(|p| p.x).collect::<Vec<_>>() == [1.0, 2.0, 3.0] }));
        assert_eq!(frames.chart.series[0].label, "sm map_res=256");
        assert!(frames.note.is_empty());
        // A still report has none.
        let mut still = report.clone();
        still.rows.iter_mut().for_each(|r| r.temporal = None);
        assert!(super::charts(&still, &still.scenes[0]).is_empty());
    }

    #[test]
    fn the_per_frame_chart_names_the_runs_it_leaves_out() {
        let report = report(&[0.02, 0.03, 0.01, 0.005, 0.001], &[1.0, 2.0, 3.0, 3.0, 9.0]);
        let many: Vec<Row> = (0..MAX_SERIES + 2)
            .map(|k| {
                let mut r = report.rows[0].clone();
                // Sizes a map can have (up to 16384), so that the labels name no default.
                r.params.insert("map_res".into(), (16 << k).into());
                r
            })
            .collect();
        let rows: Vec<&Row> = many.iter().collect();
        let (lines, left_out) = per_frame_series(&rows);
        assert_eq!(lines.len(), MAX_SERIES);
        assert_eq!(
            left_out,
            [
                format!("sm map_res={}", 16 << MAX_SERIES),
                format!("sm map_res={}", 16 << (MAX_SERIES + 1))
            ]
        );
        // Written, the caption names them; the chart files are there.
        let mut big = report.clone();
        big.rows = many;
        let dir = tempfile::tempdir().expect("tempdir");
        let files = write_plots(dir.path(), &big).expect("written");
        let per_frame = files.iter().find(|f| f.png.contains("per-frame")).expect("drawn");
        assert!(per_frame.title.ends_with(&left_out.join(", ")), "{}", per_frame.title);
        for f in &files {
            assert_eq!(f.place, Place::Motion);
            assert!(dir.path().join(&f.png).is_file() && dir.path().join(f.svg()).is_file());
        }
    }
}
