//! Plots of a report (plotters, PNG and SVG): log-log line charts of one measure against
//! another, one series per method and fixed parameters, with axis labels that carry units and
//! a legend; the error-against-time chart also draws the Pareto front (the runs no other run
//! beats in both error and time).
//!
//! Text is drawn with DejaVu Sans, compiled in (`reports/fonts/`, Bitstream Vera licence), so
//! plots need no installed fonts. Values at or below zero cannot sit on a log axis; they are
//! drawn at [`LOG_FLOOR`] and the chart says so in its caption.

use crate::output::OutputError;
use crate::sweep::Row;
use crate::write::param_label;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// Smallest value drawn on a log axis.
pub const LOG_FLOOR: f64 = 1e-7;

static FONT: &[u8] = include_bytes!("../fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Registers the compiled-in font as `sans-serif` (once).
pub(crate) fn register_font() {
    REGISTER.call_once(|| {
        // The font is compiled in and known to parse (unit-tested below).
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// One line of a chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Points, sorted by x.
    pub points: Vec<(f64, f64)>,
}

/// What to draw.
#[derive(Debug, Clone, PartialEq)]
pub struct Chart {
    /// Title.
    pub title: String,
    /// X axis label, with its unit.
    pub x_label: String,
    /// Y axis label, with its unit.
    pub y_label: String,
    /// The lines.
    pub series: Vec<Series>,
    /// Draw the Pareto front of all points (minimise both x and y).
    pub pareto: bool,
}

/// What a measure of a row is, for the charts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Measure {
    /// Mean absolute error against the reference.
    MeanError,
    /// Median total time of the method's stages.
    Time,
    /// A parameter of the method (`map_res`, `rate`).
    Param(&'static str),
}

impl Measure {
    /// The row's value of this measure.
    pub fn of(self, row: &Row) -> Option<f64> {
        match self {
            Measure::MeanError => Some(row.metrics.mean_abs_error),
            Measure::Time => Some(row.total_ms.median),
            Measure::Param(key) => row.params.get(key).and_then(serde_json::Value::as_f64),
        }
    }

    /// Axis label with unit.
    pub fn label(self) -> String {
        match self {
            Measure::MeanError => "mean absolute error against the reference (lit fraction)".into(),
            Measure::Time => "time, median (ms)".into(),
            Measure::Param("map_res") => "shadow map resolution (texels per side)".into(),
            Measure::Param("rate") => "samples per pixel".into(),
            Measure::Param(k) => k.into(),
        }
    }
}

/// The series of `y` against `x` on one scene: rows grouped by method and every parameter
/// other than `x` (or by method alone when `by_method`), each group one series sorted by `x`.
/// Rows without `x` are left out.
pub fn series(rows: &[&Row], x: Measure, y: Measure, by_method: bool) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    for r in rows {
        let (Some(xv), Some(yv)) = (x.of(r), y.of(r)) else { continue };
        let others: Vec<String> = param_label(r)
            .split(' ')
            .filter(|p| match x {
                Measure::Param(key) => !p.starts_with(&format!("{key}=")),
                _ => true,
            })
            .filter(|p| !p.is_empty())
            .map(String::from)
            .collect();
        let label = if others.is_empty() || by_method {
            r.method.clone()
        } else {
            format!("{} {}", r.method, others.join(" "))
        };
        match out.iter_mut().find(|s| s.label == label) {
            Some(s) => s.points.push((xv, yv)),
            None => out.push(Series { label, points: vec![(xv, yv)] }),
        }
    }
    for s in &mut out {
        s.points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    out
}

/// The Pareto front of `points` (minimising both coordinates), sorted by x.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> = points.to_vec();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut front: Vec<(f64, f64)> = Vec::new();
    for q in p {
        if front.last().is_none_or(|l| q.1 < l.1) {
            front.push(q);
        }
    }
    front
}

/// A tick label: whole numbers from 100 up, one decimal from 1, scientific below.
fn tick(v: f64) -> String {
    if v >= 100.0 {
        format!("{v:.0}")
    } else if v >= 1.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.1e}")
    }
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, chart: &Chart) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let all: Vec<(f64, f64)> = chart
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|&(x, y)| (x.max(LOG_FLOOR), y.max(LOG_FLOOR))))
        .collect();
    let floored = chart.series.iter().flat_map(|s| &s.points).any(|&(x, y)| x <= 0.0 || y <= 0.0);
    let range = |v: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
        if lo.is_finite() {
            (lo / 1.5, hi * 1.5)
        } else {
            (1.0, 10.0)
        }
    };
    let (x0, x1) = range(&mut all.iter().map(|p| p.0));
    let (y0, y1) = range(&mut all.iter().map(|p| p.1));
    let caption = if floored {
        format!("{} (values <= 0 drawn at {LOG_FLOOR:e})", chart.title)
    } else {
        chart.title.clone()
    };
    let mut c = ChartBuilder::on(&root)
        .margin(12)
        .caption(caption, ("sans-serif", 22))
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(e)?;
    c.configure_mesh()
        .x_desc(chart.x_label.as_str())
        .y_desc(chart.y_label.as_str())
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .draw()
        .map_err(e)?;
    for (k, s) in chart.series.iter().enumerate() {
        let colour = Palette99::pick(k).to_rgba();
        let pts: Vec<(f64, f64)> =
            s.points.iter().map(|&(x, y)| (x.max(LOG_FLOOR), y.max(LOG_FLOOR))).collect();
        c.draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
            .map_err(e)?
            .label(s.label.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        c.draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled()))).map_err(e)?;
    }
    if chart.pareto {
        let front = pareto_front(&all);
        c.draw_series(LineSeries::new(front, BLACK.stroke_width(3)))
            .map_err(e)?
            .label("Pareto front (no run is both faster and more accurate)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(3)));
    }
    c.configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(e)?;
    root.present().map_err(e)
}

/// Draws `chart` to `stem.png` (1000 x 700) and `stem.svg`.
pub fn write_chart(stem: &Path, chart: &Chart) -> Result<(), OutputError> {
    register_font();
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    let fail = |path: &Path, message: String| OutputError::Write { path: path.to_owned(), message };
    draw(BitMapBackend::new(&png, (1000, 700)).into_drawing_area(), chart)
        .map_err(|m| fail(&png, m))?;
    draw(SVGBackend::new(&svg, (1000, 700)).into_drawing_area(), chart)
        .map_err(|m| fail(&svg, m))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_font_parses() {
        assert!(plotters::style::register_font("test-font", FontStyle::Normal, FONT).is_ok());
    }

    #[test]
    fn pareto_front_keeps_the_undominated_points() {
        let pts = [(1.0, 5.0), (2.0, 3.0), (3.0, 4.0), (4.0, 1.0), (2.5, 3.0), (0.5, 9.0)];
        assert_eq!(pareto_front(&pts), vec![(0.5, 9.0), (1.0, 5.0), (2.0, 3.0), (4.0, 1.0)]);
    }

    #[test]
    fn charts_are_written_as_png_and_svg() {
        let dir = tempfile::tempdir().expect("tempdir");
        let chart = Chart {
            title: "test".into(),
            x_label: "x (ms)".into(),
            y_label: "y".into(),
            series: vec![Series { label: "a".into(), points: vec![(1.0, 0.5), (10.0, 0.0)] }],
            pareto: true,
        };
        write_chart(&dir.path().join("c"), &chart).expect("writes");
        let png = image::open(dir.path().join("c.png")).expect("a PNG");
        assert_eq!((png.width(), png.height()), (1000, 700));
        let svg = std::fs::read_to_string(dir.path().join("c.svg")).expect("an SVG");
        assert!(svg.contains("<svg") && svg.contains("x (ms)") && svg.contains("Pareto"));
    }
}
