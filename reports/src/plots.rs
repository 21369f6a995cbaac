//! Plots of a report (plotters, PNG and SVG): log-log charts of one measure against another
//! (or, along frames, a linear x axis against a log y axis: [`Chart::linear_x`]), what to draw
//! given by the caller (the report's charts: `figures`, `motion_charts`). Each series is a line
//! through its points in the order of the parameter it sweeps, each point may carry a label
//! (the parameter's value) and a horizontal bar (the spread of a time), CPU runs are marked
//! with circles and GPU runs with triangles, and a chart may set its series against the
//! scene's other runs, drawn as small grey dots ([`Marker::Context`]), or draw a group of runs
//! as open dark-grey rings without a line, set apart from the coloured series
//! ([`Marker::Ring`]: the seed techniques against today's). The legend sits beside
//! the plot, never over the data, each entry whole (long ones wrapped onto more lines); both
//! log axes label 1, 2 and 5 times each power of ten. The error-against-time charts also draw
//! the Pareto front (the runs no other run beats in both error and time).
//!
//! A chart's series have distinct colours ([`series_colours`]; the figures draw at most
//! [`MAX_SERIES`] a chart). Point labels are placed where they overlap neither another label
//! nor a point ([`place_labels`]); a label that finds no such place is left out.
//!
//! Text is drawn with DejaVu Sans, compiled in (`reports/fonts/`, Bitstream Vera licence), so
//! plots need no installed fonts. Values at or below zero cannot sit on a log axis; they are
//! drawn at [`LOG_FLOOR`] and the chart says so in its caption.

use crate::output::OutputError;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// Smallest value drawn on a log axis.
pub const LOG_FLOOR: f64 = 1e-7;

/// The most coloured series a report's chart holds: more are not told apart by colour at a
/// glance.
pub const MAX_SERIES: usize = 8;

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
    /// A small grey dot without line or label: the scene's other runs, for context; not a
    /// coloured series.
    Context,
    /// An open dark-grey ring without line, its points labelled where they carry a label: a
    /// group of runs set apart from the coloured series (the seed techniques on the chart
    /// against today's); not a coloured series.
    Ring,
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
    /// A linear x axis (frame numbers) instead of a logarithmic one; y is always logarithmic.
    pub linear_x: bool,
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

/// The grey of [`Marker::Context`] points.
pub const CONTEXT_GREY: RGBColor = RGBColor(190, 190, 190);

/// The dark grey of [`Marker::Ring`] points.
pub const RING_GREY: RGBColor = RGBColor(70, 70, 70);

/// The colour of each series of `chart`, in order: the coloured series take [`colour`]`(0)`,
/// `colour(1)`, ... in turn, the context series ([`Marker::Context`]) are grey and the rings
/// ([`Marker::Ring`]) dark grey.
pub fn series_colours(chart: &Chart) -> Vec<RGBAColor> {
    let mut k = 0;
    chart
        .series
        .iter()
        .map(|s| match s.marker {
            Marker::Context => CONTEXT_GREY.to_rgba(),
            Marker::Ring => RING_GREY.to_rgba(),
            _ => {
                k += 1;
                colour(k - 1)
            }
        })
        .collect()
}

/// Width, in pixels, of the legend beside the plotting area.
const LEGEND_WIDTH: u32 = 300;

/// Where a legend's text starts, from the legend's left edge.
const LEGEND_TEXT_X: i32 = 36;

/// Height of one line of legend text.
const LEGEND_LINE: i32 = 15;

/// A rectangle in pixels, `[x0, x1) x [y0, y1)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rect {
    /// Left edge.
    pub x0: i32,
    /// Top edge.
    pub y0: i32,
    /// Right edge (outside).
    pub x1: i32,
    /// Bottom edge (outside).
    pub y1: i32,
}

impl Rect {
    /// Whether the two rectangles share a pixel.
    pub fn intersects(&self, o: &Rect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }

    /// Whether `self` lies within `outer`.
    pub fn inside(&self, outer: &Rect) -> bool {
        self.x0 >= outer.x0 && self.y0 >= outer.y0 && self.x1 <= outer.x1 && self.y1 <= outer.y1
    }
}

/// Half the side of the square a point's marker covers, in pixels.
const MARKER_HALF: i32 = 6;

/// The square a marker at `(x, y)` covers.
fn marker_box(x: i32, y: i32) -> Rect {
    Rect {
        x0: x - MARKER_HALF,
        y0: y - MARKER_HALF,
        x1: x + MARKER_HALF + 1,
        y1: y + MARKER_HALF + 1,
    }
}

/// Places point labels: label `k`, of size `sizes[k]` (width, height), beside its point
/// `anchors[k]`, at the first of six places around it (right above, right below, left above,
/// left below, above, below) that lies within `bounds` and overlaps neither a label placed
/// before it nor any point's marker (`markers`). A label without such a place is left out
/// (`None`): a crowded chart thins its labels rather than print them over one another.
pub fn place_labels(
    anchors: &[(i32, i32)],
    sizes: &[(u32, u32)],
    markers: &[(i32, i32)],
    bounds: Rect,
) -> Vec<Option<Rect>> {
    let obstacles: Vec<Rect> = markers.iter().map(|&(x, y)| marker_box(x, y)).collect();
    let mut placed: Vec<Rect> = Vec::new();
    anchors
        .iter()
        .zip(sizes)
        .map(|(&(x, y), &(w, h))| {
            let (w, h) = (w as i32, h as i32);
            let gap = MARKER_HALF + 2;
            let candidates = [
                (x + gap, y - h - 2),
                (x + gap, y + 2),
                (x - gap - w, y - h - 2),
                (x - gap - w, y + 2),
                (x - w / 2, y - h - gap),
                (x - w / 2, y + gap),
            ];
            let found = candidates
                .iter()
                .map(|&(x0, y0)| Rect { x0, y0, x1: x0 + w, y1: y0 + h })
                .find(|r| {
                    r.inside(&bounds)
                        && !placed.iter().any(|p| p.intersects(r))
                        && !obstacles.iter().any(|o| o.intersects(r))
                });
            if let Some(r) = found {
                placed.push(r);
            }
            found
        })
        .collect()
}

/// Splits `text` into lines no wider than `max` pixels by `width_of`, at spaces; a word wider
/// than a line is split between its characters. No character but the spaces between lines is
/// dropped.
pub fn wrap_text(text: &str, max: u32, width_of: impl Fn(&str) -> u32) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in text.split(' ') {
        let candidate = if line.is_empty() { word.to_owned() } else { format!("{line} {word}") };
        if width_of(&candidate) <= max {
            line = candidate;
            continue;
        }
        if !line.is_empty() {
            lines.push(std::mem::take(&mut line));
        }
        // The word alone, split where it is wider than a line.
        for c in word.chars() {
            line.push(c);
            if width_of(&line) > max && line.chars().count() > 1 {
                line.pop();
                lines.push(std::mem::replace(&mut line, c.to_string()));
            }
        }
    }
    if !line.is_empty() || lines.is_empty() {
        lines.push(line);
    }
    lines
}

/// The width of `text` in `font`, in pixels (an estimate where the font cannot lay it out).
fn text_width(font: &FontDesc<'_>, text: &str) -> u32 {
    font.box_size(text).map_or(7 * text.chars().count() as u32, |(w, _)| w)
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, chart: &Chart) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let points = || chart.series.iter().flat_map(|s| &s.points);
    let xs = || {
        points().flat_map(|p| {
            let (a, b) = p.x_span.unwrap_or((p.x, p.x));
            [p.x, a, b]
        })
    };
    let floored = points().any(|p| (!chart.linear_x && p.x <= 0.0) || p.y <= 0.0);
    let (y0, y1) = log_range(points().map(|p| p.y));
    let caption = if floored {
        format!("{} (values <= 0 drawn at {LOG_FLOOR:e})", chart.title)
    } else {
        chart.title.clone()
    };
    let (w, _) = root.dim_in_pixel();
    let (plot_area, legend_area) = root.split_horizontally(w.saturating_sub(LEGEND_WIDTH));
    let (yb, yl) = log_ticks(y0, y1);
    let y = (y0..y1).log_scale().with_key_points(yb).with_light_points(yl);
    let mut builder = ChartBuilder::on(&plot_area);
    builder
        .margin(12)
        .caption(caption, ("sans-serif", 18))
        .x_label_area_size(50)
        .y_label_area_size(80);
    let areas = Areas { root: &root, legend: &legend_area };
    if chart.linear_x {
        let (x0, x1) = linear_range(xs());
        let c = builder.build_cartesian_2d(x0..x1, y).map_err(e)?;
        plot(&areas, c, chart, |v| v, linear_tick)
    } else {
        let (x0, x1) = log_range(xs());
        let (xb, xl) = log_ticks(x0, x1);
        let x = (x0..x1).log_scale().with_key_points(xb).with_light_points(xl);
        let c = builder.build_cartesian_2d(x, y).map_err(e)?;
        plot(&areas, c, chart, |v| v.max(LOG_FLOOR), |v| tick(*v))
    }
}

/// The range a linear axis gives `values`, with a margin of 3 % of the span on each side
/// (half a unit when all values are equal).
fn linear_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) =
        values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let margin = if hi > lo { 0.03 * (hi - lo) } else { 0.5 };
    (lo - margin, hi + margin)
}

/// A tick label of a linear axis: whole numbers without decimals, others with up to two.
fn linear_tick(v: &f64) -> String {
    if (v - v.round()).abs() < 1e-9 {
        format!("{v:.0}")
    } else {
        let s = format!("{v:.2}");
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    }
}

/// The drawing areas of a chart: the whole image (for the point labels) and the legend's.
struct Areas<'a, DB: DrawingBackend> {
    root: &'a DrawingArea<DB, Shift>,
    legend: &'a DrawingArea<DB, Shift>,
}

/// Draws the mesh, the series, the Pareto front, the point labels and the legend into the
/// chart `c`, its x axis linear or logarithmic: `fx` places an x value on it (the floor of a
/// log axis) and `x_tick` labels its ticks. The y axis is logarithmic.
fn plot<DB, X, Y>(
    areas: &Areas<'_, DB>,
    mut c: ChartContext<'_, DB, Cartesian2d<X, Y>>,
    chart: &Chart,
    fx: fn(f64) -> f64,
    x_tick: fn(&f64) -> String,
) -> Result<(), String>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let fy = |v: f64| v.max(LOG_FLOOR);
    let at = |x: f64, y: f64| (fx(x), fy(y));
    let points = || chart.series.iter().flat_map(|s| &s.points);
    c.configure_mesh()
        .x_desc(chart.x_label.as_str())
        .y_desc(chart.y_label.as_str())
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 15))
        .x_label_formatter(&x_tick)
        .y_label_formatter(&|v| tick(*v))
        .draw()
        .map_err(e)?;
    let colours = series_colours(chart);
    let mut legend: Vec<(String, RGBAColor, Option<Marker>)> = Vec::new();
    // The context first, under the coloured series.
    let order = chart
        .series
        .iter()
        .zip(&colours)
        .filter(|(s, _)| s.marker == Marker::Context)
        .chain(chart.series.iter().zip(&colours).filter(|(s, _)| s.marker != Marker::Context));
    let mut front_drawn = false;
    for (s, &colour) in order {
        let pts: Vec<(f64, f64)> = s.points.iter().map(|p| at(p.x, p.y)).collect();
        if s.marker == Marker::Context {
            c.draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled()))).map_err(e)?;
            legend.push((s.label.clone(), colour, Some(Marker::Context)));
            continue;
        }
        // The front over the context and under the coloured series, whose points stay in view.
        if chart.pareto && !front_drawn {
            let all: Vec<(f64, f64)> = points().map(|p| at(p.x, p.y)).collect();
            c.draw_series(LineSeries::new(pareto_front(&all), BLACK.mix(0.8).stroke_width(3)))
                .map_err(e)?;
            front_drawn = true;
        }
        if s.marker != Marker::Ring {
            c.draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2))).map_err(e)?;
        }
        for p in &s.points {
            if let Some((a, b)) = p.x_span {
                let y = fy(p.y);
                c.draw_series(std::iter::once(PathElement::new(
                    vec![(fx(a), y), (fx(b), y)],
                    colour.stroke_width(1),
                )))
                .map_err(e)?;
            }
        }
        match s.marker {
            Marker::Triangle => {
                c.draw_series(pts.iter().map(|&p| TriangleMarker::new(p, 6, colour.filled())))
                    .map_err(e)?;
            }
            Marker::Ring => {
                c.draw_series(pts.iter().map(|&p| Circle::new(p, 5, colour.stroke_width(2))))
                    .map_err(e)?;
            }
            _ => {
                c.draw_series(pts.iter().map(|&p| Circle::new(p, 4, colour.filled())))
                    .map_err(e)?;
            }
        }
        legend.push((s.label.clone(), colour, Some(s.marker)));
    }
    if chart.pareto && !front_drawn {
        let all: Vec<(f64, f64)> = points().map(|p| at(p.x, p.y)).collect();
        c.draw_series(LineSeries::new(pareto_front(&all), BLACK.mix(0.8).stroke_width(3)))
            .map_err(e)?;
    }
    // Point labels where they overlap neither another label nor a point.
    let font = ("sans-serif", 11).into_font();
    let pixel = |p: &Point| c.backend_coord(&at(p.x, p.y));
    let markers: Vec<(i32, i32)> = points().map(pixel).collect();
    let labelled: Vec<(&Point, RGBAColor)> = chart
        .series
        .iter()
        .zip(&colours)
        .filter(|(s, _)| s.marker != Marker::Context)
        .flat_map(|(s, &colour)| s.points.iter().map(move |p| (p, colour)))
        .filter(|(p, _)| !p.label.is_empty())
        .collect();
    let anchors: Vec<(i32, i32)> = labelled.iter().map(|(p, _)| pixel(p)).collect();
    let sizes: Vec<(u32, u32)> = labelled
        .iter()
        .map(|(p, _)| font.box_size(&p.label).unwrap_or((7 * p.label.len() as u32, 12)))
        .collect();
    let (xr, yr) = c.plotting_area().get_pixel_range();
    let bounds = Rect { x0: xr.start, y0: yr.start, x1: xr.end, y1: yr.end };
    for ((p, colour), place) in
        labelled.iter().zip(place_labels(&anchors, &sizes, &markers, bounds))
    {
        if let Some(r) = place {
            let style = font.clone().color(&colour.mix(0.9));
            areas.root.draw(&Text::new(p.label.clone(), (r.x0, r.y0), style)).map_err(e)?;
        }
    }
    if chart.pareto {
        legend.push(("Pareto front (no run is better on both axes)".into(), BLACK.into(), None));
    }
    draw_legend(areas.legend, &legend).map_err(e)?;
    areas.root.present().map_err(e)
}

/// The legend, one entry per series, in its own area beside the plot (never over the data);
/// a label too long for a line goes on over more lines, whole.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, RGBAColor, Option<Marker>)],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let font = ("sans-serif", 12).into_font();
    let max = LEGEND_WIDTH - LEGEND_TEXT_X as u32 - 6;
    let mut y = 40;
    for (label, colour, marker) in entries {
        if !matches!(marker, Some(Marker::Context | Marker::Ring)) {
            area.draw(&PathElement::new(vec![(6, y), (30, y)], colour.stroke_width(2)))?;
        }
        match marker {
            Some(Marker::Circle) => area.draw(&Circle::new((18, y), 4, colour.filled()))?,
            Some(Marker::Context) => area.draw(&Circle::new((18, y), 3, colour.filled()))?,
            Some(Marker::Ring) => area.draw(&Circle::new((18, y), 5, colour.stroke_width(2)))?,
            Some(Marker::Triangle) => {
                area.draw(&TriangleMarker::new((18, y), 6, colour.filled()))?
            }
            None => {}
        }
        let lines = wrap_text(label, max, |t| text_width(&font, t));
        for (k, line) in lines.iter().enumerate() {
            let top = y - 7 + LEGEND_LINE * k as i32;
            area.draw(&Text::new(line.clone(), (LEGEND_TEXT_X, top), font.clone()))?;
        }
        y += (LEGEND_LINE * lines.len() as i32).max(18) + 3;
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
    fn labels_never_overlap_one_another_or_a_point() {
        // A crowded cluster and a few points apart, in a 300 x 200 plot.
        let mut rng = fastrand::Rng::with_seed(7);
        let mut anchors: Vec<(i32, i32)> =
            (0..40).map(|_| (100 + rng.i32(0..40), 80 + rng.i32(0..30))).collect();
        anchors.extend([(20, 20), (280, 180), (250, 30)]);
        let sizes: Vec<(u32, u32)> = anchors.iter().map(|_| (28, 12)).collect();
        let bounds = Rect { x0: 0, y0: 0, x1: 300, y1: 200 };
        let placed = place_labels(&anchors, &sizes, &anchors, bounds);
        assert_eq!(placed.len(), anchors.len());
        let boxes: Vec<Rect> = placed.iter().flatten().copied().collect();
        for (k, a) in boxes.iter().enumerate() {
            assert!(a.inside(&bounds), "{a:?}");
            for b in &boxes[k + 1..] {
                assert!(!a.intersects(b), "{a:?} and {b:?} overlap");
            }
            for &(x, y) in &anchors {
                assert!(!a.intersects(&marker_box(x, y)), "{a:?} covers the point ({x}, {y})");
            }
        }
        assert!(boxes.len() < anchors.len(), "the crowded cluster is thinned");
        assert!(placed[40..].iter().all(Option::is_some), "the points apart keep their labels");
    }

    #[test]
    fn legend_labels_wrap_whole() {
        let width = |t: &str| 7 * t.chars().count() as u32;
        let label = "Pareto front (no run is both faster and more accurate)";
        let lines = wrap_text(label, 150, width);
        assert!(lines.len() > 1 && lines.iter().all(|l| width(l) <= 150), "{lines:?}");
        assert_eq!(lines.join(" "), label, "nothing is cut");
        let long = wrap_text("abcdefghijklmnopqrstuvwxyz", 70, width);
        assert_eq!(long.concat(), "abcdefghijklmnopqrstuvwxyz");
        assert!(long.iter().all(|l| width(l) <= 70), "{long:?}");
        assert_eq!(wrap_text("sm", 150, width), ["sm"]);
    }

    #[test]
    fn series_have_distinct_colours_and_the_context_is_grey() {
        let series = |label: &str, marker| Series {
            label: label.into(),
            marker,
            points: vec![Point::at(1.0, 1.0)],
        };
        let mut list: Vec<Series> =
            (0..MAX_SERIES).map(|k| series(&format!("s{k}"), Marker::Circle)).collect();
        list.insert(3, series("other runs", Marker::Context));
        list.insert(5, series("seed techniques", Marker::Ring));
        let chart = Chart {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            series: list,
            pareto: true,
            linear_x: false,
        };
        let colours = series_colours(&chart);
        assert_eq!(colours[3], CONTEXT_GREY.to_rgba());
        assert_eq!(colours[5], RING_GREY.to_rgba());
        let mut coloured: Vec<(u8, u8, u8)> = colours
            .iter()
            .enumerate()
            .filter(|(k, _)| *k != 3 && *k != 5)
            .map(|(_, c)| (c.0, c.1, c.2))
            .collect();
        coloured.sort();
        coloured.dedup();
        assert_eq!(coloured.len(), MAX_SERIES, "no colour twice");
        assert!(!coloured.contains(&(190, 190, 190)) && !coloured.contains(&(0, 0, 0)));
        assert!(!coloured.contains(&(RING_GREY.0, RING_GREY.1, RING_GREY.2)));
    }

    #[test]
    fn a_frame_axis_is_linear_and_labelled_with_whole_numbers() {
        assert_eq!(linear_range([1.0, 3.0, 2.0].into_iter()), (0.94, 3.06));
        assert_eq!(linear_range([2.0].into_iter()), (1.5, 2.5));
        assert_eq!(linear_range(std::iter::empty()), (0.0, 1.0));
        assert_eq!(
            (linear_tick(&0.0), linear_tick(&12.0), linear_tick(&2.5)),
            ("0".to_owned(), "12".to_owned(), "2.5".to_owned())
        );
        let dir = tempfile::tempdir().expect("tempdir");
        let chart = Chart {
            title: "per frame".into(),
            x_label: "frame".into(),
            y_label: "temporal error".into(),
            series: vec![Series {
                label: "sm".into(),
                marker: Marker::Circle,
                points: (1..6).map(|k| Point::at(f64::from(k), 0.01 * f64::from(k))).collect(),
            }],
            pareto: false,
            linear_x: true,
        };
        write_chart(&dir.path().join("f"), &chart).expect("writes");
        let svg = std::fs::read_to_string(dir.path().join("f.svg")).expect("an SVG");
        // A log axis labels 1, 2 and 5 only; the frame axis labels every frame.
        let labels: Vec<&str> = svg.lines().map(str::trim).collect();
        assert!(["1", "2", "3", "4", "5"].iter().all(|t| labels.contains(t)), "linear ticks");
        assert!(!svg.contains("drawn at"), "no value is floored");
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
                Series {
                    label: "seed rings".into(),
                    marker: Marker::Ring,
                    points: vec![point(3.0, 0.2, "ring-label")],
                },
            ],
            pareto: true,
            linear_x: false,
        };
        write_chart(&dir.path().join("c"), &chart).expect("writes");
        let png = image::open(dir.path().join("c.png")).expect("a PNG");
        assert_eq!((png.width(), png.height()), (1200, 700));
        let svg = std::fs::read_to_string(dir.path().join("c.svg")).expect("an SVG");
        for text in ["x (ms)", "Pareto", "1024", "software", "seed rings", "ring-label"] {
            assert!(svg.contains(text), "{text}");
        }
    }
}
