//! Plots of a report (plotters, PNG and SVG): log-log charts of one measure against another,
//! what to draw given by the caller (the report's charts: `figures`). Each series is a line through its points in the
//! order of the parameter it sweeps, each point may carry a label (the parameter's value) and
//! a horizontal bar (the spread of a time), CPU runs are marked with circles and GPU runs
//! with triangles, the legend sits beside the plot, never over the data, and both log axes
//! label 1, 2 and 5 times each power of ten. The error-against-time chart also draws the
//! Pareto front (the runs no other run beats in both error and time).
//!
//! Text is drawn with DejaVu Sans, compiled in (`reports/fonts/`, Bitstream Vera licence), so
//! plots need no installed fonts. Values at or below zero cannot sit on a log axis; they are
//! drawn at [`LOG_FLOOR`] and the chart says so in its caption.

use crate::output::OutputError;
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

/// How a series marks its points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// A filled circle (runs on the CPU).
    Circle,
    /// A filled triangle (runs on a GPU adapter).
    Triangle,
}

/// One point of a series.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Position along x.
    pub x: f64,
    /// Position along y.
    pub y: f64,
    /// `[min, max]` along x, drawn as a horizontal bar (the spread of a time).
    pub x_span: Option<(f64, f64)>,
    /// Text drawn beside the point (the swept parameter's value, e.g. `512`, `32x`); empty for
    /// none.
    pub label: String,
}

impl Point {
    /// A point without a bar or a label.
    pub fn at(x: f64, y: f64) -> Self {
        Self { x, y, x_span: None, label: String::new() }
    }
}

/// One line of a chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// How its points are marked.
    pub marker: Marker,
    /// Points, in the order the line joins them (the swept parameter's order).
    pub points: Vec<Point>,
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

/// A tick label: scientific notation from 100,000 up (`2e6`, the triangle and pixel counts of
/// the cost charts) and below 1 (`5e-3`), whole numbers from 100, and up to two significant
/// digits from 1.
fn tick(v: f64) -> String {
    if (100.0..1e5).contains(&v) {
        format!("{v:.0}")
    } else if (1.0..100.0).contains(&v) {
        let s = format!("{v:.1}");
        s.trim_end_matches(".0").to_owned()
    } else {
        let e = v.log10().floor();
        let m = v / 10f64.powf(e);
        if (m - m.round()).abs() < 1e-6 {
            format!("{}e{}", m.round(), e)
        } else {
            format!("{m:.1}e{e}")
        }
    }
}

/// Labelled ticks of a log axis over `[lo, hi]`: 1, 2 and 5 times each power of ten (every
/// power of ten alone when the range spans more than three decades), and the light grid
/// lines, 1 to 9 times each power of ten.
pub fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    let (e0, e1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let steps: &[f64] = if e1 - e0 > 3 { &[1.0] } else { &[1.0, 2.0, 5.0] };
    let mut bold = Vec::new();
    let mut light = Vec::new();
    for e in e0..=e1 {
        let p = 10f64.powi(e);
        for m in 1..10 {
            let v = f64::from(m) * p;
            if v >= lo && v <= hi {
                light.push(v);
                if steps.contains(&f64::from(m)) {
                    bold.push(v);
                }
            }
        }
    }
    (bold, light)
}

/// The range a log axis gives `values` (floored at [`LOG_FLOOR`]), with a margin.
fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .map(|v| v.max(LOG_FLOOR))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
    if lo.is_finite() {
        (lo / 1.6, hi * 1.6)
    } else {
        (1.0, 10.0)
    }
}

/// The colour of series `k`: Tableau's ten colours, then ColorBrewer's Dark2 (colorous), none
/// of them too pale to read on white; after 18 series the colours repeat.
pub fn colour(k: usize) -> RGBAColor {
    let c = if k % 18 < 10 { colorous::TABLEAU10[k % 18] } else { colorous::DARK2[k % 18 - 10] };
    RGBColor(c.r, c.g, c.b).to_rgba()
}

/// Width, in pixels, of the legend beside the plotting area.
const LEGEND_WIDTH: u32 = 300;

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, chart: &Chart) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let floor = |v: f64| v.max(LOG_FLOOR);
    let points = || chart.series.iter().flat_map(|s| &s.points);
    let floored = points().any(|p| p.x <= 0.0 || p.y <= 0.0);
    let (x0, x1) = log_range(points().flat_map(|p| {
        let (a, b) = p.x_span.unwrap_or((p.x, p.x));
        [p.x, a, b]
    }));
    let (y0, y1) = log_range(points().map(|p| p.y));
    let caption = if floored {
        format!("{} (values <= 0 drawn at {LOG_FLOOR:e})", chart.title)
    } else {
        chart.title.clone()
    };
    let (w, _) = root.dim_in_pixel();
    let (plot_area, legend_area) = root.split_horizontally(w.saturating_sub(LEGEND_WIDTH));
    let (xb, xl) = log_ticks(x0, x1);
    let (yb, yl) = log_ticks(y0, y1);
    let mut c = ChartBuilder::on(&plot_area)
        .margin(12)
        .caption(caption, ("sans-serif", 20))
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(
            (x0..x1).log_scale().with_key_points(xb).with_light_points(xl),
            (y0..y1).log_scale().with_key_points(yb).with_light_points(yl),
        )
        .map_err(e)?;
    c.configure_mesh()
        .x_desc(chart.x_label.as_str())
        .y_desc(chart.y_label.as_str())
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 15))
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .draw()
        .map_err(e)?;
    let mut legend: Vec<(String, RGBAColor, Option<Marker>)> = Vec::new();
    for (k, s) in chart.series.iter().enumerate() {
        let colour = colour(k);
        let pts: Vec<(f64, f64)> = s.points.iter().map(|p| (floor(p.x), floor(p.y))).collect();
        c.draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2))).map_err(e)?;
        for p in &s.points {
            if let Some((a, b)) = p.x_span {
                let y = floor(p.y);
                c.draw_series(std::iter::once(PathElement::new(
                    vec![(floor(a), y), (floor(b), y)],
                    colour.stroke_width(1),
                )))
                .map_err(e)?;
            }
        }
        match s.marker {
            Marker::Circle => {
                c.draw_series(pts.iter().map(|&p| Circle::new(p, 4, colour.filled())))
                    .map_err(e)?;
            }
            Marker::Triangle => {
                c.draw_series(pts.iter().map(|&p| TriangleMarker::new(p, 6, colour.filled())))
                    .map_err(e)?;
            }
        }
        let text = ("sans-serif", 11).into_font().color(&colour.mix(0.9));
        c.draw_series(s.points.iter().filter(|p| !p.label.is_empty()).map(|p| {
            EmptyElement::at((floor(p.x), floor(p.y)))
                + Text::new(p.label.clone(), (5, -14), text.clone())
        }))
        .map_err(e)?;
        legend.push((s.label.clone(), colour, Some(s.marker)));
    }
    if chart.pareto {
        let all: Vec<(f64, f64)> = points().map(|p| (floor(p.x), floor(p.y))).collect();
        let front = pareto_front(&all);
        c.draw_series(LineSeries::new(front, BLACK.stroke_width(3))).map_err(e)?;
        legend.push((
            "Pareto front (no run is both faster and more accurate)".into(),
            BLACK.into(),
            None,
        ));
    }
    draw_legend(&legend_area, &legend).map_err(e)?;
    root.present().map_err(e)
}

/// The legend, one line per series, in its own area beside the plot (never over the data).
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, RGBAColor, Option<Marker>)],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let font = ("sans-serif", 12).into_font();
    let line = 18;
    for (k, (label, colour, marker)) in entries.iter().enumerate() {
        let y = 40 + line * k as i32;
        area.draw(&PathElement::new(vec![(6, y), (30, y)], colour.stroke_width(2)))?;
        match marker {
            Some(Marker::Circle) => area.draw(&Circle::new((18, y), 4, colour.filled()))?,
            Some(Marker::Triangle) => {
                area.draw(&TriangleMarker::new((18, y), 6, colour.filled()))?
            }
            None => {}
        }
        // Long labels are cut so that they stay inside the legend.
        let text: String = if label.chars().count() > 42 {
            label.chars().take(41).chain(std::iter::once('…')).collect()
        } else {
            label.clone()
        };
        area.draw(&Text::new(text, (36, y - 7), font.clone()))?;
    }
    Ok(())
}

/// Draws `chart` to `stem.png` (1200 x 700) and `stem.svg`.
pub fn write_chart(stem: &Path, chart: &Chart) -> Result<(), OutputError> {
    register_font();
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    let fail = |path: &Path, message: String| OutputError::Write { path: path.to_owned(), message };
    draw(BitMapBackend::new(&png, (1200, 700)).into_drawing_area(), chart)
        .map_err(|m| fail(&png, m))?;
    draw(SVGBackend::new(&svg, (1200, 700)).into_drawing_area(), chart)
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
    fn log_ticks_label_one_two_five() {
        let (bold, light) = log_ticks(3e-3, 0.2);
        assert_eq!(bold, [5e-3, 1e-2, 2e-2, 5e-2, 0.1, 0.2]);
        assert_eq!(light.len(), 7 + 9 + 2);
        let (bold, _) = log_ticks(0.5, 5e4);
        assert_eq!(bold, [1.0, 10.0, 100.0, 1000.0, 1e4]);
        assert_eq!(tick(5e-3), "5e-3");
        assert_eq!(tick(2.0), "2");
        assert_eq!(tick(300.0), "300");
        assert_eq!(tick(50_000.0), "50000");
        assert_eq!(
            (tick(1e5), tick(2e6), tick(8.3e6)),
            ("1e5".into(), "2e6".into(), "8.3e6".into())
        );
    }

    #[test]
    fn charts_are_written_as_png_and_svg() {
        let dir = tempfile::tempdir().expect("tempdir");
        let point = |x, y, label: &str| Point {
            x,
            y,
            x_span: Some((0.8 * x, 1.2 * x)),
            label: label.into(),
        };
        let chart = Chart {
            title: "test".into(),
            x_label: "x (ms)".into(),
            y_label: "y".into(),
            series: vec![
                Series {
                    label: "a".into(),
                    marker: Marker::Circle,
                    points: vec![point(1.0, 0.5, "512"), point(10.0, 0.0, "1024")],
                },
                Series {
                    label: "a gpu (llvmpipe, software)".into(),
                    marker: Marker::Triangle,
                    points: vec![Point::at(2.0, 0.4)],
                },
            ],
            pareto: true,
        };
        write_chart(&dir.path().join("c"), &chart).expect("writes");
        let png = image::open(dir.path().join("c.png")).expect("a PNG");
        assert_eq!((png.width(), png.height()), (1200, 700));
        let svg = std::fs::read_to_string(dir.path().join("c.svg")).expect("an SVG");
        for text in ["x (ms)", "Pareto", "1024", "software"] {
            assert!(svg.contains(text), "{text}");
        }
    }
}
