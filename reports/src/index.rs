//! `index.html`: the report as one page that opens in any browser from the file system (no
//! server, no script from elsewhere), rendered by the `index.html` template
//! (`reports/templates/`, [`crate::templates`]) from an [`IndexPage`] built from the
//! [`Report`].
//!
//! The page leads with the answer. Its first screen (1400 x 1000 pixels) holds the machine and
//! the load the times were taken under (the clock of the cost axis, how many runs were
//! contended), per scene its Pareto front (mean error against time on the report's clock) as
//! a compact table, and what the runs say of each method ([`crate::summary`]). Below it: the
//! provenance, the contents list, the comparison with a baseline, the scenes, the best error
//! within each time budget (figure and table), the section "Against today's techniques" when
//! some scene has runs of today's techniques and of the seeds ([`today_section`]: per such
//! scene its chart and its table, [`crate::today`]), per scene its image grids, its whole
//! front, its charts and its table of runs (each run linked to its page, `runs/ID.html`,
//! [`crate::run_pages`]) and, for a scene with an animation, its section "In motion"
//! ([`motion_table`], the charts of [`crate::motion_charts`]), CPU and GPU side by side, the
//! papers' tables, a glossary of the metrics, and what did not run. Images are files beside the page (`plots/*.png`, with the
//! SVG linked).
//!
//! A runs table fits a 1400-pixel window with its time column in view: parameters and columns
//! that are the same over the whole table are stated once above it, a method's fixed
//! parameters once per method; the columns are the method, the parameters that vary, a few
//! error metrics, the time on the report's clock (median and its interval, or "no interval"),
//! the wall time and whether the run was contended. Counts and the other metrics are on the
//! run pages.
//!
//! An "In motion" table has a row per run over the animated scene: the method (linked to the
//! players of its page), the parameters as in a runs table (the light-frustum policy
//! `frustum` a column of its own where it varies within a method), the mean error over the
//! frames, the temporal error, its boundary mean and 95th percentile, the time per frame on
//! the report's clock and the pixel pairs compared; a column that reads the same in every row
//! is stated once above the table.
//!
//! The style and the script are embedded in the page (`reports/assets/report.css` and
//! `report.js`): tables sort by clicking a header (numbers as numbers, `n/a` last) and filter
//! by a text box. The script marks every image `data-loaded="yes"` or `"no"` once the page has
//! loaded, and the page opened as `index.html#selftest` checks its own layout (the first
//! screen holds the Pareto summary and the machine line; no runs table is wider than the
//! window), sorts and filters its first run table, sorts every other sortable table (the one
//! against today's techniques among them) and writes what it found into
//! `<pre id="selftest">`, for a headless browser to check.

use crate::baseline::Comparison;
use crate::figures::{clock_name, Place, PlotFile};
use crate::html::{
    anchor, metric_cells, time_head, Cell, Head, Note, ParamSplit, TableView, METRIC_COLUMNS,
    RUN_TABLE_METRICS,
};
use crate::model::{method_label, params_of, row_stem, Report, Row};
use crate::motion_charts::{frame_count, motion_rows};
use crate::summary::{
    budget_table, error_text, fronts, measured, ms_text, time_text, verdicts, Front, Measured,
    Verdict,
};
use crate::templates::{Pages, TemplateError};
use serde::Serialize;

/// A link of the contents list, with the links under it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Link {
    /// Anchor, `#scene-cage`.
    pub href: String,
    /// What it says.
    pub text: String,
    /// The links under it.
    pub children: Vec<Link>,
}

impl Link {
    fn to(id: &str, text: &str) -> Self {
        Self { href: format!("#{id}"), text: text.to_owned(), children: Vec::new() }
    }
}

/// A chart or an image on the page.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Figure {
    /// Its anchor.
    pub id: String,
    /// The PNG, relative to the page.
    pub png: String,
    /// The SVG beside it, for a chart.
    pub svg: Option<String>,
    /// Caption.
    pub title: String,
    /// Drawn smaller than the page's width.
    pub small: bool,
}

/// The comparison with an earlier report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BaselineView {
    /// The counts, in a sentence.
    pub summary: String,
    /// Each regression, in a line.
    pub regressions: Vec<String>,
}

/// What produced the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProvenanceView {
    /// Crate version.
    pub version: String,
    /// Commit.
    pub commit: String,
    /// Whether the checkout had uncommitted changes.
    pub dirty: bool,
    /// Compiler.
    pub rustc: String,
    /// When (UTC).
    pub timestamp: String,
    /// Command line.
    pub command: String,
}

/// A scene's section.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneSection {
    /// Anchor stem, `scene-cage`.
    pub id: String,
    /// Scene.
    pub name: String,
    /// Its image grids.
    pub grids: Vec<Figure>,
    /// Its whole Pareto front, with intervals and wall times.
    pub front: Option<TableView>,
    /// Its charts.
    pub plots: Vec<Figure>,
    /// What holds for its runs table: frame, reference, where the metrics are taken, clock.
    pub runs_about: String,
    /// Its runs.
    pub runs: Option<TableView>,
    /// Its runs in motion, for a scene with an animation.
    pub motion: Option<MotionSection>,
}

/// The section "In motion" of an animated scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MotionSection {
    /// Its anchor, `scene-cage-motion`.
    pub id: String,
    /// What holds for its table: frames, reference, what the columns measure.
    pub about: String,
    /// A row per run in motion.
    pub table: TableView,
    /// Its charts.
    pub plots: Vec<Figure>,
}

/// The section "Against today's techniques" ([`crate::today`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TodaySection {
    /// Its anchor, `today`.
    pub id: String,
    /// What it holds: which of today's techniques, against which seeds, on how many scenes.
    pub about: String,
    /// A part per scene that has runs of both.
    pub scenes: Vec<TodayScene>,
}

/// A scene's part of the section "Against today's techniques".
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TodayScene {
    /// Its anchor, `today-cage`.
    pub id: String,
    /// Scene.
    pub name: String,
    /// What holds for its chart and table: frame, reference, clock, the front.
    pub about: String,
    /// Its charts.
    pub plots: Vec<Figure>,
    /// A row per run of the scene.
    pub table: TableView,
}

/// CPU and GPU side by side.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DevicesView {
    /// The adapter.
    pub gpu: Option<String>,
    /// Whether it is a software rasterizer.
    pub gpu_software: bool,
    /// The pairs.
    pub table: TableView,
}

/// One of the papers' tables.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PaperTableView {
    /// Anchor stem and CSV name.
    pub id: String,
    /// Title.
    pub title: String,
    /// The paper's hardware.
    pub hardware: String,
    /// Notes.
    pub notes: String,
    /// Header.
    pub header: Vec<String>,
    /// Rows.
    pub rows: Vec<Vec<String>>,
    /// Its chart, for a cost-against-work table.
    pub chart: Option<Figure>,
}

/// Everything `index.html` shows, for its template.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IndexPage {
    /// `index`, for the page's `data-page`.
    pub page: &'static str,
    /// The page's title.
    pub title: String,
    /// Suite name.
    pub suite: String,
    /// Suite description.
    pub description: String,
    /// The machine, the clock and the load.
    pub measured: Measured,
    /// Contended runs, in a sentence.
    pub contended_text: String,
    /// The clock's name, `CPU` or `wall`.
    pub clock: String,
    /// Per scene, its Pareto front.
    pub fronts: Vec<Front>,
    /// Rows of a front shown on the first screen; the rest are in the scene's section.
    pub front_rows: usize,
    /// Per method, what the runs say of it.
    pub verdicts: Vec<Verdict>,
    /// The methods on no front and best nowhere.
    pub off_front: Vec<String>,
    /// What produced the report.
    pub provenance: ProvenanceView,
    /// The contents list.
    pub contents: Vec<Link>,
    /// The comparison with a baseline.
    pub baseline: Option<BaselineView>,
    /// The scenes.
    pub scenes_table: TableView,
    /// Figures across scenes.
    pub summary_figures: Vec<Figure>,
    /// The best error of every method within each budget.
    pub budget: Option<TableView>,
    /// Today's techniques against the seeds, when some scene has runs of both.
    pub today: Option<TodaySection>,
    /// Per scene, its section.
    pub scenes: Vec<SceneSection>,
    /// CPU and GPU side by side.
    pub devices: Option<DevicesView>,
    /// The papers' tables.
    pub papers: Vec<PaperTableView>,
    /// What did not run, and why.
    pub skipped: Vec<String>,
}

/// Rows of a front on the first screen.
const FRONT_ROWS: usize = 6;

/// The metric and time columns a runs table may state above it when they are the same in
/// every row.
fn constant_candidates() -> Vec<&'static str> {
    let mut c: Vec<&'static str> = RUN_TABLE_METRICS.iter().map(|&k| METRIC_COLUMNS[k]).collect();
    c.push("contended");
    c
}

/// The table of one scene's runs (see the module documentation).
pub fn runs_table(rows: &[&Row], report: &Report) -> TableView {
    let clock = report.clock;
    let split = ParamSplit::of(rows);
    let mut heads = vec![Head::text("method")];
    heads.extend(split.heads());
    heads.extend(RUN_TABLE_METRICS.iter().map(|&k| Head::num(METRIC_COLUMNS[k])));
    heads.push(Head::num(time_head(clock_name(clock))));
    heads.push(Head::num("wall ms"));
    heads.push(Head::text("contended"));
    let body: Vec<Vec<Cell>> = rows
        .iter()
        .map(|r| {
            let method = Cell::text(method_label(r));
            let mut cells = vec![if r.timed() {
                method.link(format!("runs/{}.html", row_stem(r)))
            } else {
                method
            }];
            cells.extend(split.cells(r));
            let metrics = metric_cells(r);
            cells.extend(RUN_TABLE_METRICS.iter().map(|&k| metrics[k].clone()));
            if r.timed() {
                let t = r.time(clock);
                cells.push(Cell::sorted(time_text(t), t.median));
                cells.push(Cell::sorted(ms_text(r.total_ms.median), r.total_ms.median));
            } else {
                cells.extend([Cell::text("not given"), Cell::text("not given")]);
            }
            cells.push(Cell::text(if r.contended { "yes" } else { "no" }));
            cells
        })
        .collect();
    let mut table = TableView::new("runs", heads, body);
    table.notes = split.notes();
    table.state_constant_columns(&constant_candidates());
    table
}

/// Heads of an "In motion" table's errors, after the parameters; the time per frame
/// ([`motion_time_head`]) and `pixel pairs` follow them.
pub const MOTION_COLUMNS: [&str; 4] =
    ["mean abs error", "temporal error", "boundary temporal error", "temporal p95"];

/// The head of an "In motion" table's time column on `clock`.
pub fn motion_time_head(clock: &str) -> String {
    format!("{clock} ms per frame")
}

/// The table of one scene's runs in motion (see the module documentation).
pub fn motion_table(rows: &[&Row], report: &Report) -> TableView {
    let clock = report.clock;
    let split = ParamSplit::of(rows);
    let mut heads = vec![Head::text("method")];
    heads.extend(split.heads());
    heads.extend(MOTION_COLUMNS.iter().map(|&c| Head::num(c)));
    heads.push(Head::num(motion_time_head(clock_name(clock))));
    heads.push(Head::num("pixel pairs"));
    let body: Vec<Vec<Cell>> = rows
        .iter()
        .map(|r| {
            let mut cells =
                vec![Cell::text(method_label(r)).link(format!("runs/{}.html#motion", row_stem(r)))];
            cells.extend(split.cells(r));
            let or_na = |v: Option<f64>| v.map_or_else(Cell::na, |v| Cell::num(v, 5));
            let t = r.temporal.as_ref();
            let t_of = |f: fn(&analysis::temporal::TemporalMetrics) -> Option<f64>| t.and_then(f);
            cells.push(if r.metrics.evaluated_pixels == 0 {
                Cell::na()
            } else {
                Cell::num(r.metrics.mean_abs_error, 5)
            });
            cells.push(or_na(t_of(|t| t.mean)));
            cells.push(or_na(t_of(|t| t.boundary_mean)));
            cells.push(or_na(t_of(|t| t.p95)));
            let tm = r.time(clock);
            cells.push(Cell::sorted(time_text(tm), tm.median));
            cells.push(t.map_or_else(Cell::na, |t| Cell::num(t.pixel_pairs as f64, 0)));
            cells
        })
        .collect();
    let mut table = TableView::new("runs motion", heads, body);
    table.notes = split.notes();
    // The time stays in its column even where the runs tie.
    let mut constant = MOTION_COLUMNS.to_vec();
    constant.push("pixel pairs");
    table.state_constant_columns(&constant);
    table
}

/// The section "In motion" of the scene `sc`, whose anchors start with `id`, when it has runs
/// in motion: its sentence, its table and its charts among `plots`.
pub fn motion_section(
    report: &Report,
    sc: &crate::model::SceneInfo,
    id: &str,
    plots: &[PlotFile],
) -> Option<MotionSection> {
    let rows = motion_rows(report, &sc.scene);
    let frames = rows.iter().map(|r| frame_count(r)).max()?;
    let clock = clock_name(report.clock);
    let id = format!("{id}-motion");
    Some(MotionSection {
        about: format!(
            "{frames} frames at {}x{} against {}. Mean abs error: over the shadow-only pixels of \
             every frame; temporal error: the change from one frame to the next that the \
             reference does not have, |(m_t - m_t-1) - (e_t - e_t-1)|, mean over the pixel \
             pairs of every pair of consecutive frames, on the boundary pairs, and its 95th \
             percentile (see the glossary); time: the method's own stages per frame on the \
             {clock} clock, the median over the frames. Each method links to its run's page, \
             which plays the run, the reference and the error map frame by frame.",
            sc.width, sc.height, sc.reference
        ),
        table: motion_table(&rows, report),
        plots: plots
            .iter()
            .filter(|p| p.place == Place::Motion && p.scene == sc.scene)
            .enumerate()
            .map(|(k, p)| figure(format!("{id}-plot-{k}"), p))
            .collect(),
        id,
    })
}

/// The section "Against today's techniques" when some scene has runs of both families
/// ([`crate::today::scenes`]): per such scene its sentence, its charts among `plots` and its
/// table.
pub fn today_section(report: &Report, plots: &[PlotFile]) -> Option<TodaySection> {
    let scenes = crate::today::scenes(report);
    if scenes.is_empty() {
        return None;
    }
    let clock = clock_name(report.clock);
    let names = |family: crate::today::Family| {
        let rows: Vec<&Row> =
            report.rows.iter().filter(|r| crate::today::family_of(r) == Some(family)).collect();
        crate::figures::methods_in(&rows).join(", ")
    };
    let about = format!(
        "Today's techniques, the ones today's shadow papers compare against ({}), against \
         the 2001-2014 techniques the workbench began with, the seeds ({}), on the {} scene{} \
         with runs of both. Per scene: mean error on the shadow-only pixels against the \
         method's own time on the {clock} clock (per frame for a run in motion), today's \
         methods in colour, the seeds as dark rings (named where they are on the front), the \
         scene's other runs as grey dots, and the Pareto front over every run of the scene; \
         then a row per run with its family and whether it is on the front.",
        names(crate::today::Family::Today),
        names(crate::today::Family::Seed),
        scenes.len(),
        if scenes.len() == 1 { "" } else { "s" }
    );
    let parts = scenes
        .into_iter()
        .map(|sc| {
            let id = format!("today-{}", anchor(&sc.scene));
            let rows = report.scene_rows(&sc.scene);
            let on = crate::today::on_front(&rows, report.clock).iter().filter(|&&f| f).count();
            TodayScene {
                about: format!(
                    "Frame {}x{} against {}; {on} of its {} runs on the Pareto front (no \
                     other run of the scene is at least as fast and as accurate and better in \
                     one).",
                    sc.width,
                    sc.height,
                    sc.reference,
                    rows.len()
                ),
                plots: plots
                    .iter()
                    .filter(|p| p.place == Place::Today && p.scene == sc.scene)
                    .enumerate()
                    .map(|(k, p)| figure(format!("{id}-plot-{k}"), p))
                    .collect(),
                table: crate::today::table(&rows, report),
                name: sc.scene.clone(),
                id,
            }
        })
        .collect();
    Some(TodaySection { id: "today".into(), about, scenes: parts })
}

/// A scene's whole Pareto front as a table: method, parameters, error, time on the clock with
/// its interval, wall time.
fn front_table(f: &Front, clock: &str) -> TableView {
    let heads = vec![
        Head::text("method"),
        Head::text("parameters"),
        Head::num("mean abs error"),
        Head::num(time_head(clock)),
        Head::num("wall ms"),
        Head::text("contended"),
    ];
    let rows = f
        .runs
        .iter()
        .map(|r| {
            vec![
                Cell::text(&r.method).link(&r.page),
                Cell::text(&r.params),
                Cell::sorted(&r.error_text, r.error),
                Cell::text(format!("{} ({})", r.time_text, r.interval_text)),
                Cell::text(&r.wall_text),
                Cell::text(if r.contended { "yes" } else { "no" }),
            ]
        })
        .collect();
    let mut t = TableView::new("front", heads, rows);
    t.state_constant_columns(&["contended"]);
    t
}

/// A chart of the page.
fn figure(id: String, p: &PlotFile) -> Figure {
    Figure { id, png: p.png.clone(), svg: Some(p.svg()), title: p.title.clone(), small: false }
}

/// The page's model.
pub fn index_page(report: &Report, plots: &[PlotFile], baseline: Option<&Comparison>) -> IndexPage {
    let clock = clock_name(report.clock).to_owned();
    let measured = measured(report);
    let (verdicts, off_front) = verdicts(report);
    let fronts = fronts(report);
    let p = &report.provenance;
    let scenes_table = TableView::new(
        "scenes",
        vec![
            Head::text("scene"),
            Head::num("triangles"),
            Head::text("effects"),
            Head::text("frame"),
            Head::num("G-buffer wall ms"),
            Head::text("reference"),
            Head::num("reference wall ms"),
        ],
        report
            .scenes
            .iter()
            .map(|sc| {
                vec![
                    Cell::text(&sc.scene).link(format!("#scene-{}", anchor(&sc.scene))),
                    Cell::num(sc.triangles as f64, 0),
                    Cell::text(sc.effects.join(", ")),
                    Cell::text(format!("{}x{}", sc.width, sc.height)),
                    Cell::num(sc.gbuffer_ms, 1),
                    Cell::text(&sc.reference),
                    Cell::num(sc.reference_ms, 1),
                ]
            })
            .collect(),
    );
    let summary_figures: Vec<Figure> = plots
        .iter()
        .filter(|p| p.scene.is_empty() && p.place == Place::Scene)
        .enumerate()
        .map(|(k, p)| figure(format!("summary-plot-{k}"), p))
        .collect();
    let budget = (!report.rows.is_empty()).then(|| {
        let t = budget_table(report);
        let mut heads = vec![Head::text("scene"), Head::text("method")];
        heads.extend(t.heads.iter().map(Head::num));
        let rows = t
            .rows
            .iter()
            .map(|r| {
                let mut cells = vec![Cell::text(&r.scene), Cell::text(&r.method)];
                cells.extend(r.best.iter().zip(&r.winner).map(|(b, &w)| match b {
                    Some(e) if w => Cell::sorted(format!("{} (best)", error_text(*e)), *e),
                    Some(e) => Cell::sorted(error_text(*e), *e),
                    None => Cell::text("no run fits"),
                }));
                cells
            })
            .collect();
        TableView::new("budgets", heads, rows)
    });
    let scenes: Vec<SceneSection> = report
        .scenes
        .iter()
        .map(|sc| {
            let id = format!("scene-{}", anchor(&sc.scene));
            let rows: Vec<&Row> =
                report.rows.iter().chain(&report.untimed).filter(|r| r.scene == sc.scene).collect();
            let untimed = rows.iter().any(|r| !r.timed());
            let ref_rate = rows.first().and_then(|r| r.ref_rate);
            SceneSection {
                grids: report
                    .grids
                    .iter()
                    .filter(|g| g.scene == sc.scene)
                    .enumerate()
                    .map(|(k, g)| Figure {
                        id: format!("{id}-grid-{k}"),
                        png: g.png.clone(),
                        svg: None,
                        title: g.title.clone(),
                        small: false,
                    })
                    .collect(),
                front: fronts.iter().find(|f| f.scene == sc.scene).map(|f| front_table(f, &clock)),
                plots: plots
                    .iter()
                    .filter(|p| p.scene == sc.scene && p.place == Place::Scene)
                    .enumerate()
                    .map(|(k, p)| figure(format!("{id}-plot-{k}"), p))
                    .collect(),
                runs_about: format!(
                    "Frame {}x{}; reference {}{}; metrics over the shadow-only pixels (see the \
                     glossary); time: the method's own stages on the {clock} clock, median of \
                     the timed runs with the 95 % interval of the median, wall time beside it. \
                     Each method links to its run's page, with every metric, stage and counter.{}",
                    sc.width,
                    sc.height,
                    sc.reference,
                    ref_rate.map_or_else(String::new, |r| format!(" at {r} samples per pixel")),
                    if untimed {
                        " Outside results without a time (marked external, time not given) are \
                         in this table only, not in the charts, fronts or budgets, and have no \
                         page."
                    } else {
                        ""
                    },
                ),
                runs: (!rows.is_empty()).then(|| runs_table(&rows, report)),
                motion: motion_section(report, sc, &id, plots),
                name: sc.scene.clone(),
                id,
            }
        })
        .collect();
    let today = today_section(report, plots);
    IndexPage {
        page: "index",
        title: format!("shadowbench report: {}", report.suite.name),
        suite: report.suite.name.clone(),
        description: report.suite.description.clone(),
        contended_text: measured.contended_text(),
        measured,
        clock,
        fronts,
        front_rows: FRONT_ROWS,
        verdicts,
        off_front,
        provenance: ProvenanceView {
            version: p.version.clone(),
            commit: p.commit.clone(),
            dirty: p.dirty,
            rustc: p.rustc.clone(),
            timestamp: p.timestamp.clone(),
            command: p.command.clone(),
        },
        contents: contents(report, &summary_figures, today.as_ref(), &scenes, baseline.is_some()),
        baseline: baseline.map(baseline_view),
        scenes_table,
        summary_figures,
        budget,
        today,
        scenes,
        devices: devices_view(report),
        papers: report
            .tables
            .iter()
            .map(|t| {
                let id = t.paper.name().to_owned();
                PaperTableView {
                    title: t.title.clone(),
                    hardware: t.paper_hardware.clone(),
                    notes: t.notes.join(" "),
                    header: t.header.clone(),
                    rows: t.rows.clone(),
                    chart: crate::tables::chart(t).map(|_| Figure {
                        id: format!("table-{id}-chart"),
                        png: format!("plots/{id}.png"),
                        svg: Some(format!("plots/{id}.svg")),
                        title: format!("{}, log-log", t.title),
                        small: false,
                    }),
                    id,
                }
            })
            .collect(),
        skipped: report.skipped.clone(),
    }
}

/// The page, rendered.
pub fn index_html(
    pages: &Pages,
    report: &Report,
    plots: &[PlotFile],
    baseline: Option<&Comparison>,
) -> Result<String, TemplateError> {
    pages.render("index.html", &index_page(report, plots, baseline))
}

/// The contents list: every section, and under each scene its figures and its tables.
fn contents(
    report: &Report,
    summary: &[Figure],
    today: Option<&TodaySection>,
    scenes: &[SceneSection],
    baseline: bool,
) -> Vec<Link> {
    let mut c = vec![Link::to("summary", "Pareto fronts and what the runs say of each method")];
    if baseline {
        c.push(Link::to("baseline", "Against the baseline"));
    }
    c.push(Link::to("scenes", "Scenes"));
    if !report.rows.is_empty() {
        c.push(Link::to("budgets", "Best error within a time budget"));
    }
    c.extend(summary.iter().map(|f| Link::to(&f.id, &f.title)));
    if let Some(t) = today {
        let mut l = Link::to(&t.id, "Against today's techniques");
        l.children.extend(t.scenes.iter().map(|s| Link::to(&s.id, &s.name)));
        c.push(l);
    }
    for s in scenes {
        let mut l = Link::to(&s.id, &s.name);
        l.children.extend(s.grids.iter().map(|g| Link::to(&g.id, &g.title)));
        if s.front.is_some() {
            l.children.push(Link::to(&format!("{}-front", s.id), "Pareto front"));
        }
        l.children.extend(s.plots.iter().map(|p| Link::to(&p.id, &p.title)));
        l.children.push(Link::to(&format!("{}-runs", s.id), "runs"));
        if let Some(m) = &s.motion {
            l.children.push(Link::to(&m.id, "In motion"));
            l.children.extend(m.plots.iter().map(|p| Link::to(&p.id, &p.title)));
        }
        c.push(l);
    }
    if !crate::devices::pairs(&report.rows).is_empty() {
        c.push(Link::to("devices", "CPU and GPU"));
    }
    if !report.tables.is_empty() {
        let mut l = Link::to("tables", "The papers' tables");
        l.children.extend(
            report.tables.iter().map(|t| Link::to(&format!("table-{}", t.paper.name()), &t.title)),
        );
        c.push(l);
    }
    c.push(Link::to("glossary", "Glossary"));
    if !report.skipped.is_empty() {
        c.push(Link::to("skipped", "Not run"));
    }
    c
}

/// The comparison with an earlier report: counts and every regression.
fn baseline_view(c: &Comparison) -> BaselineView {
    BaselineView {
        summary: crate::baseline::summary_line(c),
        regressions: c
            .regressions()
            .map(|r| {
                format!(
                    "{} {} on {}: {} (time x{:.2} [{:.2}, {:.2}], error {:.6} -> {:.6})",
                    r.method,
                    r.params,
                    r.scene,
                    crate::baseline::flags(r),
                    r.time_ratio,
                    r.time_ratio_ci.0,
                    r.time_ratio_ci.1,
                    r.error.0,
                    r.error.1
                )
            })
            .collect(),
    }
}

/// CPU and GPU side by side (wall-clock times: a GPU's work is not the CPU time of the
/// process's threads), the parameters common to every pair stated once.
fn devices_view(report: &Report) -> Option<DevicesView> {
    let pairs = crate::devices::pairs(&report.rows);
    if pairs.is_empty() {
        return None;
    }
    let cpu_rows: Vec<&Row> = pairs.iter().map(|p| p.cpu).collect();
    let split = ParamSplit::of(&cpu_rows);
    let heads: Vec<Head> = crate::devices::COLUMNS
        .iter()
        .enumerate()
        .map(|(k, c)| if k >= 3 { Head::num(*c) } else { Head::text(*c) })
        .collect();
    let rows: Vec<Vec<Cell>> = pairs
        .iter()
        .map(|p| {
            let mut cells = crate::devices::cells(p);
            cells[2] = params_of(p.cpu)
                .into_iter()
                .filter(|(k, _)| k != "device" && !split.constant.contains_key(k))
                .map(|(k, v)| format!("{k}={v}"))
                .collect::<Vec<_>>()
                .join(" ");
            cells.into_iter().map(Cell::parsed).collect()
        })
        .collect();
    let mut table = TableView::new("devices", heads, rows);
    let kv: Vec<String> = split
        .constant
        .iter()
        .filter(|(k, _)| *k != "device")
        .map(|(k, v)| format!("{k}={v}"))
        .collect();
    if !kv.is_empty() {
        table.notes.push(Note { code: None, text: format!("Every pair: {}.", kv.join(", ")) });
    }
    Some(DevicesView {
        gpu: report.machine.gpu.clone(),
        gpu_software: report
            .machine
            .gpu
            .as_deref()
            .is_some_and(crate::devices::is_software_adapter),
        table,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion_charts::fixture::report_in_motion;

    #[test]
    fn the_motion_table_gives_the_frustum_policy_a_column_only_where_it_varies() {
        let (report, _) = report_in_motion();
        // A run whose temporal error, mean error and pixel pairs follow `error` (pixel pairs
        // 300 at 0.01).
        let run = |method: &str, frustum: Option<&str>, error: f64| {
            let mut r = report.rows[0].clone();
            r.method = method.into();
            r.params.remove("frustum");
            if let Some(f) = frustum {
                r.params.insert("frustum".into(), f.into());
            }
            r.metrics.mean_abs_error = 0.1 + error;
            crate::motion_charts::fixture::put_in_motion(&mut r, error, 4);
            if let Some(t) = r.temporal.as_mut() {
                t.pixel_pairs = (30_000.0 * error).round() as u64;
            }
            r
        };
        let heads = |t: &TableView| t.heads.iter().map(|h| h.text.clone()).collect::<Vec<_>>();
        let rows = [
            run("sm", Some("scene"), 0.01),
            run("sm", Some("view"), 0.03),
            run("sm", Some("view-snapped"), 0.02),
            run("pcf-gems4", Some("scene"), 0.005),
            run("afsm", None, 0.0),
        ];
        let refs: Vec<&Row> = rows.iter().collect();
        let t = motion_table(&refs, &report);
        let h = heads(&t);
        assert_eq!(h[..2], ["method", "frustum"], "{h:?}");
        assert_eq!(
            h[h.len() - 6..],
            [
                "mean abs error",
                "temporal error",
                "boundary temporal error",
                "temporal p95",
                "CPU ms per frame",
                "pixel pairs"
            ]
            .map(String::from),
            "{h:?}"
        );
        let column: Vec<&str> = t.rows.iter().map(|r| r[1].text.as_str()).collect();
        assert_eq!(column, ["scene", "view", "view-snapped", "scene", ""]);
        let temporal: Vec<Option<f64>> = t.rows.iter().map(|r| r[h.len() - 5].value).collect();
        assert_eq!(temporal, [Some(0.01), Some(0.03), Some(0.02), Some(0.005), Some(0.0)]);
        assert!(t.rows[1][0].href.as_deref().is_some_and(|h| h.ends_with(".html#motion")));
        // One policy for sm, none elsewhere: no column, sm's policy stated above the table.
        let same = [run("sm", Some("scene"), 0.01), run("afsm", None, 0.0)];
        let refs: Vec<&Row> = same.iter().collect();
        let t = motion_table(&refs, &report);
        assert!(!heads(&t).contains(&"frustum".to_owned()), "{:?}", heads(&t));
        assert!(t
            .notes
            .iter()
            .any(|n| n.code.as_deref() == Some("sm") && n.text.contains("frustum=scene")));
        // No policy anywhere: no column, no mention.
        let none = [run("sm", None, 0.01), run("sm", None, 0.01)];
        let refs: Vec<&Row> = none.iter().collect();
        let t = motion_table(&refs, &report);
        assert!(!heads(&t).contains(&"frustum".to_owned()));
        assert!(t.notes.iter().all(|n| !n.text.contains("frustum")));
        // The pixel pairs, the same for every run, are stated once above the table.
        assert!(!heads(&t).contains(&"pixel pairs".to_owned()));
        assert!(t.notes.iter().any(|n| n.text.contains("pixel pairs: 300")), "{:?}", t.notes);
    }
}
