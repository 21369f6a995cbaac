//! The papers' tables, measured by a report and printed beside the papers' own figures, each
//! labelled with the hardware the paper measured on.
//!
//! A suite asks for a table with a `[[table]]` entry:
//!
//! ```toml
//! [[table]]
//! paper = "aila-laine-table1"   # or "pan-table1", "lecocq-table1", "lecocq-table2"
//! scenes = ["random-1k", "random-10k"]   # optional: default, the table's own scenes
//! width = 1024                           # optional: default, the paper's frame
//! height = 768
//! ```
//!
//! A table runs its own frames (the papers' frame sizes differ from a suite's) under the suite's
//! timing protocol ([`instrumentation::measure`]); it measures times and counters only, so no
//! reference is computed. Where our scenes stand in for the paper's models, the row names both.
//!
//! - `aila-laine-table1`: Aila and Laine 2004, Table 1: `afsm` on `random-1k` .. `random-1m`
//!   at 1024 x 768; BSP nodes, nodes visited and occlusion culled, sampling points tested, the
//!   three stage times and their total. Paper: 1.6 GHz Mobile Pentium 4.
//! - `lecocq-table1`: Lecocq et al. 2014, Table 1: `sm` and `spsm` with 1K and 2K maps at
//!   1920 x 1080 on three models (Spheres 12K, YeahRight 155K, City 2.3M polygons; our stand-ins
//!   `spheres`, `bunny-plane`, `random-1m`). Paper: NVIDIA GeForce GTX 580.
//! - `pan-table1`: Pan et al. 2009, Table 1: `pan09` (map 512, the paper's sample rates) on
//!   `cage`, `plant`, `spheres`, `bunny-plane`, `bumpy` at 800 x 600: triangles, silhouette
//!   texels and pixels, visibility evaluations, the three stage times and their total, beside
//!   the paper's Cage, Plant and Bunny. Paper: NVIDIA GeForce GTX 280.
//! - `lecocq-table2`: Lecocq et al. 2014, Table 2: `sm` and `spsm` at maps 512 .. 4096 on one
//!   model (YeahRight; our stand-in `bunny-plane`) at 1920 x 1080, with the overhead.
//! - `cost-against-triangles` and `cost-against-pixels`: cost against work, the measure behind
//!   the papers' speed claims (Aila and Laine's scalability with the triangle count, Pan et
//!   al.'s and Lecocq et al.'s with the frame). The time of `afsm`, `raytrace` (1 sample per
//!   pixel), `exact`, `sm`, `pan09` (32x) and `spsm` against the scene's triangles
//!   (`random-1k` .. `random-1m` at 1024 x 768), and against the frame's pixels (`bunny-plane`
//!   at 320 x 240 .. 3840 x 2160, the frames of [`COST_FRAMES`]; a `width` gives one frame
//!   instead), with the camera G-buffer as a row of its own. Each row ends with the exponent `b`
//!   of the power law `ms = a work^b` fitted by least squares to `(ln work, ln ms)` (the
//!   `linreg` crate): 1 is linear, below 1 fixed costs dominate, above 1 the time grows faster
//!   than the work. The report draws each as a log-log chart (`plots/NAME.png`, [`chart`]).
//!   No paper prints these figures, so they have no paper column.
//!
//! The papers' times include rendering the scene; ours give the method's own stages, and the
//! camera G-buffer (our scene rendering) apart, so that both overheads can be read.
//!
//! Each figure of ours and each of the paper's has a column of its own (`SM 1K ms`, `SM 1K
//! paper ms`). A table is built from typed [`Cell`]s and kept twice: as the text the report
//! prints (counts as the papers print them, `32.8K`; the paper's figures as printed) and as
//! the numbers `tables/*.csv` holds (`32768`; an empty cell where a figure is missing).

use instrumentation::measure::StageTimes;
use instrumentation::stats::Summary;
use instrumentation::Counters;
use methods::{pan09::PAPER_TABLE1 as PAN_TABLE1, MethodOptions};
use serde::{Deserialize, Serialize};

/// A paper's table that a report can reproduce.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PaperTable {
    /// Aila and Laine 2004, Table 1 (alias-free shadow maps, scalability).
    AilaLaineTable1,
    /// Lecocq et al. 2014, Table 1 (SM and SPSM times on three models).
    LecocqTable1,
    /// Lecocq et al. 2014, Table 2 (SM and SPSM times against map size).
    LecocqTable2,
    /// Pan et al. 2009, Table 1 (statistics of the test scenes and `pan09`'s stage times).
    PanTable1,
    /// Cost against work: every method's time against the scene's triangle count.
    CostAgainstTriangles,
    /// Cost against work: every method's time against the frame's pixel count.
    CostAgainstPixels,
}

/// The frames of `cost-against-pixels`, smallest first.
pub const COST_FRAMES: [(u32, u32); 5] =
    [(320, 240), (640, 480), (1280, 720), (1920, 1080), (3840, 2160)];

/// The runs of the cost-against-work tables: each method at its default settings, the
/// supersampled ones at the rates the papers compare (`raytrace` at one sample per pixel, the
/// brute force a shadow method replaces; `pan09` at 32x, Pan et al.'s setting; `ftizb` at 1x
/// and 32x, Wyman et al.'s "32 samples at about twice the cost of one", which they measured
/// at 1080p and 2160p, frames of `cost-against-pixels`).
fn cost_runs() -> Vec<(&'static str, MethodOptions)> {
    let rate = |r| MethodOptions { rate: Some(r), ..Default::default() };
    vec![
        ("afsm", MethodOptions::default()),
        ("raytrace", rate(1)),
        ("exact", MethodOptions::default()),
        ("sm", MethodOptions::default()),
        ("pan09", rate(32)),
        ("spsm", MethodOptions::default()),
        ("ftizb", rate(1)),
        ("ftizb", rate(32)),
    ]
}

/// A run's row label: the method, and its rate where one is set (`pan09 32x`).
fn run_label(method: &str, options: &MethodOptions) -> String {
    options.rate.map_or_else(|| method.to_owned(), |r| format!("{method} {r}x"))
}

/// One measured curve of a cost-against-work table: a row's `(work, ms)` points, in the
/// order of the table's columns, and the fitted exponent.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Curve {
    /// The row: a method with its rate, or `camera G-buffer`.
    pub label: String,
    /// `(work, ms)`: triangles or pixels, and the median time.
    pub points: Vec<(f64, f64)>,
    /// Exponent of the power law fitted to the points; `None` for fewer than two works.
    pub exponent: Option<f64>,
}

/// The exponent `b` of the power law `ms = a work^b` that fits `points` `(work, ms)` best in
/// the least-squares sense on logarithms; `None` for fewer than two distinct, positive works.
pub fn fit_exponent(points: &[(f64, f64)]) -> Option<f64> {
    let (x, y): (Vec<f64>, Vec<f64>) = points
        .iter()
        .filter(|(w, t)| *w > 0.0 && *t > 0.0 && w.is_finite() && t.is_finite())
        .map(|(w, t)| (w.ln(), t.ln()))
        .unzip();
    linreg::linear_regression::<f64, f64, f64>(&x, &y).ok().map(|(slope, _)| slope)
}

/// A `[[table]]` entry of a suite.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TableSpec {
    /// Which table.
    pub paper: PaperTable,
    /// Scenes, one per column or row of the paper's in order; empty takes the table's own.
    #[serde(default)]
    pub scenes: Vec<String>,
    /// Frame width; 0 takes the paper's.
    #[serde(default)]
    pub width: u32,
    /// Frame height; 0 takes the paper's.
    #[serde(default)]
    pub height: u32,
}

/// A cell of a table, typed so that it prints as the papers do and writes as a number.
#[derive(Debug, Clone, PartialEq)]
enum Cell {
    /// A name.
    Text(String),
    /// A count, printed with a K or M suffix.
    Count(f64),
    /// An integer printed in full (a map size, a sample rate).
    Int(u64),
    /// A time in milliseconds, printed to 0.1.
    Ms(f64),
    /// A percentage, printed to 1.
    Percent(f64),
    /// A fitted exponent, printed to 0.01.
    Exponent(f64),
    /// A figure of a paper as printed there (`16K`, `2.3M`, `4.2`).
    Paper(&'static str),
    /// No figure (a run that failed, a paper without this scene).
    Missing,
}

impl Cell {
    /// The cell as the report prints it.
    fn text(&self) -> String {
        match self {
            Cell::Text(t) => t.clone(),
            Cell::Count(v) => si(*v),
            Cell::Int(v) => v.to_string(),
            Cell::Ms(v) => format!("{v:.1}"),
            Cell::Percent(v) => format!("{v:.0}"),
            Cell::Exponent(v) => format!("{v:.2}"),
            Cell::Paper(p) => (*p).to_owned(),
            Cell::Missing => "–".to_owned(),
        }
    }

    /// The cell as `tables/*.csv` holds it: a number in full, a name, or empty.
    fn value(&self) -> String {
        match self {
            Cell::Text(t) => t.clone(),
            Cell::Count(v) | Cell::Ms(v) | Cell::Percent(v) | Cell::Exponent(v) => v.to_string(),
            Cell::Int(v) => v.to_string(),
            Cell::Paper(p) => paper_number(p).map_or_else(String::new, |v| v.to_string()),
            Cell::Missing => String::new(),
        }
    }
}

/// A paper's printed figure as a number: `16K` is 16000, `2.3M` 2300000.
fn paper_number(printed: &str) -> Option<f64> {
    let (digits, scale) = match printed.strip_suffix('K') {
        Some(d) => (d, 1e3),
        None => match printed.strip_suffix('M') {
            Some(d) => (d, 1e6),
            None => (printed, 1.0),
        },
    };
    digits.parse::<f64>().ok().map(|v| v * scale)
}

fn ms_or_missing(v: Option<f64>) -> Cell {
    v.map_or(Cell::Missing, Cell::Ms)
}

fn paper_or_missing(v: Option<&&'static str>) -> Cell {
    v.map_or(Cell::Missing, |p| Cell::Paper(p))
}

/// A measured table, ready to print.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Table {
    /// Which table.
    pub paper: PaperTable,
    /// Title, naming the paper and its table.
    pub title: String,
    /// The hardware the paper measured on.
    pub paper_hardware: String,
    /// How our figures were taken, and what differs from the paper's.
    pub notes: Vec<String>,
    /// Column headings; each figure of ours and of the paper has its own column, its unit in
    /// the heading (or, where rows are quantities, in the row's label).
    pub header: Vec<String>,
    /// Rows of cells as printed (counts as `32.8K`, `–` for a missing figure).
    pub rows: Vec<Vec<String>>,
    /// The same rows as numbers in full for `tables/*.csv` (empty for a missing figure).
    pub values: Vec<Vec<String>>,
    /// The curves a cost-against-work table draws ([`chart`]); empty for the papers' tables.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub curves: Vec<Curve>,
}

impl PaperTable {
    /// The name used in suite files.
    pub fn name(self) -> &'static str {
        match self {
            Self::AilaLaineTable1 => "aila-laine-table1",
            Self::LecocqTable1 => "lecocq-table1",
            Self::LecocqTable2 => "lecocq-table2",
            Self::PanTable1 => "pan-table1",
            Self::CostAgainstTriangles => "cost-against-triangles",
            Self::CostAgainstPixels => "cost-against-pixels",
        }
    }

    /// The table's own scenes (ours standing in for the paper's models where needed).
    pub fn default_scenes(self) -> &'static [&'static str] {
        match self {
            Self::AilaLaineTable1 => &["random-1k", "random-10k", "random-100k", "random-1m"],
            Self::LecocqTable1 => &["spheres", "bunny-plane", "random-1m"],
            Self::LecocqTable2 => &["bunny-plane"],
            Self::PanTable1 => &["cage", "plant", "spheres", "bunny-plane", "bumpy"],
            Self::CostAgainstTriangles => &["random-1k", "random-10k", "random-100k", "random-1m"],
            Self::CostAgainstPixels => &["bunny-plane"],
        }
    }

    /// The table's own frames: the paper's frame size, or [`COST_FRAMES`] for
    /// `cost-against-pixels`.
    pub fn frames(self) -> &'static [(u32, u32)] {
        match self {
            Self::AilaLaineTable1 | Self::CostAgainstTriangles => &[(1024, 768)],
            Self::LecocqTable1 | Self::LecocqTable2 => &[(1920, 1080)],
            Self::PanTable1 => &[(800, 600)],
            Self::CostAgainstPixels => &COST_FRAMES,
        }
    }

    /// What a cost-against-work table's columns grow (`None` for a paper's table).
    pub fn work(self) -> Option<&'static str> {
        match self {
            Self::CostAgainstTriangles => Some("triangles"),
            Self::CostAgainstPixels => Some("pixels"),
            _ => None,
        }
    }

    fn hardware(self) -> &'static str {
        match self {
            Self::AilaLaineTable1 => "1.6 GHz Mobile Pentium 4 (CPU)",
            Self::LecocqTable1 | Self::LecocqTable2 => "NVIDIA GeForce GTX 580 (GPU)",
            Self::PanTable1 => "NVIDIA GeForce GTX 280 (GPU) with a 3.0 GHz CPU",
            Self::CostAgainstTriangles | Self::CostAgainstPixels => {
                "none (no paper prints these figures)"
            }
        }
    }

    /// The method runs the table makes on `scene`.
    pub fn runs(self, scene: &str) -> Vec<(&'static str, MethodOptions)> {
        let map =
            |method, res| (method, MethodOptions { map_res: Some(res), ..Default::default() });
        match self {
            Self::PanTable1 => {
                let rate = Some(pan_rate(scene));
                vec![("pan09", MethodOptions { map_res: Some(512), rate, ..Default::default() })]
            }
            Self::AilaLaineTable1 => vec![("afsm", MethodOptions::default())],
            Self::LecocqTable1 => {
                vec![map("sm", 1024), map("sm", 2048), map("spsm", 1024), map("spsm", 2048)]
            }
            Self::LecocqTable2 => [512, 1024, 2048, 4096]
                .into_iter()
                .flat_map(|res| [map("sm", res), map("spsm", res)])
                .collect(),
            Self::CostAgainstTriangles | Self::CostAgainstPixels => cost_runs(),
        }
    }
}

/// The frames a table runs each scene at: the suite's `width` x `height` where given, else
/// the table's own ([`PaperTable::frames`]).
pub fn frames_of(spec: &TableSpec) -> Vec<(u32, u32)> {
    match spec.width {
        0 => spec.paper.frames().to_vec(),
        w => vec![(w, spec.height)],
    }
}

fn scenes_of(spec: &TableSpec) -> Vec<String> {
    if spec.scenes.is_empty() {
        spec.paper.default_scenes().iter().map(|s| (*s).to_owned()).collect()
    } else {
        spec.scenes.clone()
    }
}

/// The scenes of a table at its frames, each with the runs the table makes there: what a
/// suite's plan turns into work items, one per scene and frame.
pub fn table_items(spec: &TableSpec) -> Vec<TableItem> {
    let frames = frames_of(spec);
    scenes_of(spec)
        .into_iter()
        .flat_map(|scene| {
            let runs = spec.paper.runs(&scene);
            frames.iter().map(move |&f| (scene.clone(), f, runs.clone()))
        })
        .collect()
}

/// A scene of a table, at one of its frames, with the runs the table makes there (method and
/// options).
pub type TableItem = (String, (u32, u32), Vec<(&'static str, MethodOptions)>);

/// One run a table measured: a method on a scene at a frame, its times and counters. A
/// report keeps them (`runs.json`'s `table_runs`) and builds its tables from them
/// ([`build`]), so that a table's runs are planned, sharded and merged as any run is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TableRun {
    /// Index of the table in the suite's tables.
    pub table: usize,
    /// Index of the run in the table's runs on the scene ([`table_items`]).
    pub run: usize,
    /// The plan's item that ran it.
    pub item: usize,
    /// The shard that ran it, in a merged report.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<u32>,
    /// Scene.
    pub scene: String,
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Triangles of the frame.
    pub triangles: u64,
    /// The frame's camera G-buffer, wall-clock milliseconds.
    pub gbuffer_ms: f64,
    /// Method.
    pub method: String,
    /// The method's parameters.
    pub params: serde_json::Map<String, serde_json::Value>,
    /// Wall-clock totals of the timed runs.
    pub total_ms: Summary,
    /// CPU totals.
    #[serde(default)]
    pub cpu_ms: Option<Summary>,
    /// Whether a timed run was contended.
    #[serde(default)]
    pub contended: bool,
    /// Each stage.
    pub stages: Vec<StageTimes>,
    /// Counters of the run kept.
    pub counters: Counters,
}

/// One scene's measurements at one frame for a table.
struct SceneRuns<'a> {
    name: String,
    frame: (u32, u32),
    triangles: u64,
    gbuffer_ms: f64,
    /// In the order of [`PaperTable::runs`]; `None` where the run failed.
    runs: Vec<Option<&'a TableRun>>,
}

/// The suite's table number `index`, `spec`, built from the runs measured for it (`runs` may
/// hold other tables' runs too). A pure function of the runs: a scene and frame without runs
/// is left out, a run that is missing shows as "–" (empty in the CSV).
pub fn build(spec: &TableSpec, index: usize, runs: &[TableRun]) -> Table {
    let paper = spec.paper;
    let frames = frames_of(spec);
    let mine: Vec<&TableRun> = runs.iter().filter(|r| r.table == index).collect();
    let mut measured = Vec::new();
    for (name, (w, h), made) in table_items(spec) {
        let here: Vec<&TableRun> = mine
            .iter()
            .copied()
            .filter(|r| r.scene == name && (r.width, r.height) == (w, h))
            .collect();
        let Some(first) = here.first() else { continue };
        measured.push(SceneRuns {
            name: name.clone(),
            frame: (w, h),
            triangles: first.triangles,
            gbuffer_ms: first.gbuffer_ms,
            runs: (0..made.len()).map(|k| here.iter().copied().find(|r| r.run == k)).collect(),
        });
    }
    let counts: Vec<u32> = mine.iter().map(|r| r.total_ms.n).collect();
    let (fewest, most) = (counts.iter().min().copied(), counts.iter().max().copied());
    let frame_text = match &frames[..] {
        [(w, h)] => format!("{w}x{h}"),
        _ => "the frames of the columns".to_owned(),
    };
    let runs_text = match (fewest, most) {
        (Some(a), Some(b)) if a == b => format!("{a}"),
        (Some(a), Some(b)) => format!("{a} to {b}"),
        _ => "no".to_owned(),
    };
    let mut notes = vec![format!(
        "Ours: {frame_text}, wall-clock medians of {runs_text} timed runs after the suite's \
         warm-up (the papers give frame times), on the machine named at the top of the report."
    )];
    let mut curves = Vec::new();
    let (header, rows) = match paper {
        PaperTable::AilaLaineTable1 => aila_laine(&measured, &mut notes),
        PaperTable::LecocqTable1 => lecocq1(&measured, &mut notes),
        PaperTable::LecocqTable2 => lecocq2(&measured, &mut notes),
        PaperTable::PanTable1 => pan1(&measured, &mut notes),
        PaperTable::CostAgainstTriangles | PaperTable::CostAgainstPixels => {
            cost(paper, &measured, &mut notes, &mut curves)
        }
    };
    let title = match paper {
        PaperTable::AilaLaineTable1 => "Aila & Laine 2004, Table 1: alias-free shadow maps",
        PaperTable::LecocqTable1 => "Lecocq et al. 2014, Table 1: SM and SPSM times (ms)",
        PaperTable::LecocqTable2 => "Lecocq et al. 2014, Table 2: SPSM overhead against map size",
        PaperTable::PanTable1 => "Pan et al. 2009, Table 1: statistics of the test scenes",
        PaperTable::CostAgainstTriangles => "Cost against work: time against triangles",
        PaperTable::CostAgainstPixels => "Cost against work: time against pixels",
    };
    Table {
        paper,
        title: title.to_owned(),
        paper_hardware: paper.hardware().to_owned(),
        notes,
        header,
        values: rows.iter().map(|r| r.iter().map(Cell::value).collect()).collect(),
        rows: rows.iter().map(|r| r.iter().map(Cell::text).collect()).collect(),
        curves,
    }
}

/// Every table of a suite (its `[[table]]` entries, `specs`), built from the runs measured
/// for them.
pub fn build_all(specs: &[TableSpec], runs: &[TableRun]) -> Vec<Table> {
    specs.iter().enumerate().map(|(k, spec)| build(spec, k, runs)).collect()
}

/// `1234567` as `1.23M`, as the papers print counts.
pub fn si(v: f64) -> String {
    let a = v.abs();
    if a >= 1e6 {
        format!("{:.2}M", v / 1e6)
    } else if a >= 1e3 {
        format!("{:.1}K", v / 1e3)
    } else {
        format!("{v:.0}")
    }
}

fn counter(t: &TableRun, name: &str) -> Option<u64> {
    t.counters.entries().into_iter().find(|(n, _)| *n == name).map(|(_, v)| v)
}

fn stage_ms(stages: &[StageTimes], name: &str) -> Option<f64> {
    stages.iter().find(|s| s.name == name).map(|s| s.ms.median)
}

fn aila_laine(measured: &[SceneRuns], notes: &mut Vec<String>) -> (Vec<String>, Vec<Vec<Cell>>) {
    use methods::afsm::{PAPER_TABLE1, STAGE_BSP, STAGE_RASTERIZATION, STAGE_TRANSFORMATION};
    notes.push(
        "BSP nodes: ours counts every node (the leaves are about half); the paper's count is of \
         leaves or of all nodes, it does not say. The camera G-buffer is not in the total (the \
         paper starts from the depth buffer too)."
            .into(),
    );
    let mut header = vec!["".to_owned()];
    for (k, s) in measured.iter().enumerate() {
        header.push(format!("{} ours", s.name));
        header.push(format!("paper ({})", PAPER_TABLE1[0].get(k).unwrap_or(&"–")));
    }
    let labels = [
        "triangles",
        "2D BSP nodes",
        "2D BSP nodes visited",
        "nodes occlusion culled",
        "sampling points tested",
        "transformation of samples (ms)",
        "BSP construction (ms)",
        "rasterization of blockers (ms)",
        "total (ms)",
    ];
    let rows = labels
        .iter()
        .enumerate()
        .map(|(row, label)| {
            let mut cells = vec![Cell::Text((*label).to_owned())];
            for (k, s) in measured.iter().enumerate() {
                let t = s.runs.first().copied().flatten();
                let c = |name| {
                    t.and_then(|t| counter(t, name))
                        .map_or(Cell::Missing, |v| Cell::Count(v as f64))
                };
                let st = |name| ms_or_missing(t.and_then(|t| stage_ms(&t.stages, name)));
                cells.push(match row {
                    0 => Cell::Count(s.triangles as f64),
                    1 => c("bsp_nodes"),
                    2 => c("bsp_nodes_visited"),
                    3 => c("nodes_occlusion_culled"),
                    4 => c("sampling_points_tested"),
                    5 => st(STAGE_TRANSFORMATION),
                    6 => st(STAGE_BSP),
                    7 => st(STAGE_RASTERIZATION),
                    _ => ms_or_missing(t.map(|t| t.total_ms.median)),
                });
                cells.push(paper_or_missing(PAPER_TABLE1[row].get(k)));
            }
            cells
        })
        .collect();
    (header, rows)
}

/// The paper's Table 1 (Lecocq et al.): model, polygons, SM 1K, SM 2K, SPSM 1K, SPSM 2K (ms).
const LECOCQ1: [(&str, &str, [&str; 4]); 3] = [
    ("Spheres", "12K", ["5.0", "6.8", "6.8", "8.6"]),
    ("YeahRight", "155K", ["5.8", "7.4", "9.1", "10.7"]),
    ("City", "2.3M", ["31.2", "32.2", "40", "41.6"]),
];

fn lecocq1(measured: &[SceneRuns], notes: &mut Vec<String>) -> (Vec<String>, Vec<Vec<Cell>>) {
    notes.push(
        "The paper's times include the shadow map and the scene's rendering; ours are the \
         method's own stages, with our scene rendering (the camera G-buffer) in its own column."
            .into(),
    );
    let mut header = ["scene", "paper's model", "triangles", "paper triangles", "G-buffer ms"]
        .map(String::from)
        .to_vec();
    for run in ["SM 1K", "SM 2K", "SPSM 1K", "SPSM 2K"] {
        header.push(format!("{run} ms"));
        header.push(format!("{run} paper ms"));
    }
    let rows = measured
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let paper = LECOCQ1.get(k);
            let mut cells = vec![
                Cell::Text(s.name.clone()),
                paper.map_or(Cell::Missing, |p| Cell::Text(p.0.to_owned())),
                Cell::Count(s.triangles as f64),
                paper_or_missing(paper.map(|p| &p.1)),
                Cell::Ms(s.gbuffer_ms),
            ];
            for (j, t) in s.runs.iter().enumerate() {
                cells.push(ms_or_missing(t.map(|t| t.total_ms.median)));
                cells.push(paper_or_missing(paper.map(|p| &p.2[j])));
            }
            cells
        })
        .collect();
    (header, rows)
}

/// The paper's Table 2 (Lecocq et al., YeahRight): map size, SM ms, SPSM ms, overhead %.
const LECOCQ2: [(u32, &str, &str, &str); 4] = [
    (512, "5.5", "10.0", "81"),
    (1024, "5.8", "9.1", "56"),
    (2048, "7.4", "10.7", "44"),
    (4096, "14.2", "18.1", "27"),
];

fn lecocq2(measured: &[SceneRuns], notes: &mut Vec<String>) -> (Vec<String>, Vec<Vec<Cell>>) {
    notes.push(
        "Overhead = SPSM / SM - 1. The paper's times include rendering the scene, so its \
         overhead compares with ours including the G-buffer; without it, ours is the methods' \
         own."
            .into(),
    );
    let header = [
        "scene",
        "paper's model",
        "map_res",
        "SM ms",
        "SM paper ms",
        "SPSM ms",
        "SPSM paper ms",
        "overhead % (methods)",
        "overhead % (with G-buffer)",
        "paper overhead %",
    ]
    .map(String::from)
    .to_vec();
    let mut rows = Vec::new();
    for s in measured {
        for (k, (res, sm_paper, spsm_paper, over_paper)) in LECOCQ2.iter().enumerate() {
            let t = |j: usize| s.runs.get(j).copied().flatten().map(|t| t.total_ms.median);
            let (sm, spsm) = (t(2 * k), t(2 * k + 1));
            let over = |extra: f64| match (sm, spsm) {
                (Some(a), Some(b)) => Cell::Percent(100.0 * ((b + extra) / (a + extra) - 1.0)),
                _ => Cell::Missing,
            };
            rows.push(vec![
                Cell::Text(s.name.clone()),
                Cell::Text("YeahRight".to_owned()),
                Cell::Int(u64::from(*res)),
                ms_or_missing(sm),
                Cell::Paper(sm_paper),
                ms_or_missing(spsm),
                Cell::Paper(spsm_paper),
                over(0.0),
                over(s.gbuffer_ms),
                Cell::Paper(over_paper),
            ]);
        }
    }
    (header, rows)
}

/// The sample rate Pan et al.'s Table 1 runs `scene` at: the paper's for the kinds of scene it
/// lists, 32 elsewhere.
fn pan_rate(scene: &str) -> u32 {
    PAN_TABLE1.iter().find(|(n, ..)| *n == scene).map_or(32, |r| r.1)
}

fn pan1(measured: &[SceneRuns], notes: &mut Vec<String>) -> (Vec<String>, Vec<Vec<Cell>>) {
    use methods::pan09::TABLE1;
    notes.push(
        "pan09 in table mode with a 512x512 map, at the paper's rate for the scenes it lists \
         (our cage, plant and bunny-plane beside its Cage, Plant and Bunny) and 32 elsewhere. \
         The three times group our stages as methods::pan09::TABLE1 does (each the sum of its \
         stages' medians); the camera G-buffer and the per-scene edge adjacency are not in them."
            .into(),
    );
    // The paper's figures follow ours, column by column; `PAN_TABLE1`'s entries 1..=9 are
    // the paper's in the order of these columns.
    let mut quantities: Vec<String> = [
        "triangles",
        "silhouette texels",
        "silhouette pixels",
        "visibility evaluations",
        "sample rate",
    ]
    .map(String::from)
    .to_vec();
    quantities.extend(TABLE1.iter().map(|(name, _)| format!("{name} ms")));
    let mut header = vec!["scene".to_owned(), "paper's scene".to_owned()];
    for q in &quantities {
        header.push(q.clone());
        header.push(format!("paper {q}"));
    }
    header.push("total ms".into());
    header.push("paper total ms".into());
    let rows = measured
        .iter()
        .map(|s| {
            let paper = PAN_TABLE1.iter().find(|(n, ..)| *n == s.name).and_then(|r| r.2);
            let t = s.runs.first().copied().flatten();
            let c = |name| t.and_then(|t| counter(t, name)).map_or(Cell::Missing, Cell::Int);
            let groups: Vec<Option<f64>> = TABLE1
                .iter()
                .map(|(_, names)| {
                    t.map(|t| names.iter().filter_map(|n| stage_ms(&t.stages, n)).sum::<f64>())
                })
                .collect();
            let total = groups.iter().copied().sum::<Option<f64>>();
            let paper_total =
                paper.map(|p| p[6..9].iter().filter_map(|v| paper_number(v)).sum::<f64>());
            let ours = [
                Cell::Int(s.triangles),
                c("silhouette_texels"),
                c("silhouette_pixels"),
                c("visibility_evaluations"),
                Cell::Int(u64::from(pan_rate(&s.name))),
            ]
            .into_iter()
            .chain(groups.iter().map(|g| ms_or_missing(*g)));
            let mut cells = vec![
                Cell::Text(s.name.clone()),
                paper.map_or(Cell::Missing, |p| Cell::Text(p[0].to_owned())),
            ];
            for (k, cell) in ours.enumerate() {
                cells.push(cell);
                cells.push(paper_or_missing(paper.as_ref().map(|p| &p[1 + k])));
            }
            cells.push(ms_or_missing(total));
            cells.push(ms_or_missing(paper_total));
            cells
        })
        .collect();
    (header, rows)
}

/// A cost-against-work table: per column a scene at a frame, per row the work (triangles,
/// pixels), the camera G-buffer and each run, in milliseconds, and the fitted exponent.
fn cost(
    paper: PaperTable,
    measured: &[SceneRuns],
    notes: &mut Vec<String>,
    curves: &mut Vec<Curve>,
) -> (Vec<String>, Vec<Vec<Cell>>) {
    notes.push(
        "A method's time is its own stages; the camera G-buffer, which every method starts \
         from, is a row of its own. The fitted exponent is b of ms = a work^b, by least squares \
         on the logarithms."
            .into(),
    );
    let triangles: fn(&SceneRuns) -> f64 = |s| s.triangles as f64;
    let pixels: fn(&SceneRuns) -> f64 = |s| f64::from(s.frame.0) * f64::from(s.frame.1);
    let work = if paper == PaperTable::CostAgainstPixels { pixels } else { triangles };
    let mut header = vec!["".to_owned()];
    header.extend(measured.iter().map(|s| format!("{} {}x{}", s.name, s.frame.0, s.frame.1)));
    header.push("fitted exponent".into());
    let mut rows = Vec::new();
    for (label, count) in [("triangles", triangles), ("pixels", pixels)] {
        let mut cells = vec![Cell::Text(label.to_owned())];
        cells.extend(measured.iter().map(|s| Cell::Count(count(s))));
        cells.push(Cell::Missing);
        rows.push(cells);
    }
    let mut series: Vec<(String, Vec<Option<f64>>)> =
        vec![("camera G-buffer".into(), measured.iter().map(|s| Some(s.gbuffer_ms)).collect())];
    for (k, (method, options)) in cost_runs().iter().enumerate() {
        let times = measured
            .iter()
            .map(|s| s.runs.get(k).copied().flatten().map(|t| t.total_ms.median))
            .collect();
        series.push((run_label(method, options), times));
    }
    for (label, times) in series {
        let points: Vec<(f64, f64)> =
            measured.iter().zip(&times).filter_map(|(s, t)| t.map(|t| (work(s), t))).collect();
        let exponent = fit_exponent(&points);
        let mut cells = vec![Cell::Text(format!("{label} (ms)"))];
        cells.extend(times.iter().map(|t| ms_or_missing(*t)));
        cells.push(exponent.map_or(Cell::Missing, Cell::Exponent));
        rows.push(cells);
        curves.push(Curve { label, points, exponent });
    }
    (header, rows)
}

/// The log-log chart of a cost-against-work table: one line per row, time against work, the
/// fitted exponent in the legend; `None` for a paper's table.
pub fn chart(t: &Table) -> Option<crate::plots::Chart> {
    use crate::plots::{Chart, Marker, Point, Series};
    let work = t.paper.work()?;
    let series = t
        .curves
        .iter()
        .filter(|c| !c.points.is_empty())
        .map(|c| Series {
            label: match c.exponent {
                Some(b) => format!("{} (exponent {b:.2})", c.label),
                None => c.label.clone(),
            },
            marker: Marker::Circle,
            points: c.points.iter().map(|&(w, ms)| Point::at(w, ms)).collect(),
        })
        .collect::<Vec<_>>();
    (!series.is_empty()).then(|| Chart {
        title: t.title.clone(),
        x_label: work.to_owned(),
        y_label: "time (ms), median".to_owned(),
        series,
        pareto: false,
        linear_x: false,
    })
}

/// The table as Markdown, with its title, the paper's hardware and the notes.
pub fn markdown(t: &Table) -> String {
    let mut s = format!("### {}\n\nPaper's figures measured on: {}.", t.title, t.paper_hardware);
    for n in &t.notes {
        s.push(' ');
        s.push_str(n);
    }
    s.push_str("\n\n| ");
    s.push_str(&t.header.join(" | "));
    s.push_str(" |\n|");
    s.push_str(&"---|".repeat(t.header.len()));
    s.push('\n');
    for r in &t.rows {
        s.push_str("| ");
        s.push_str(&r.join(" | "));
        s.push_str(" |\n");
    }
    s
}

/// The table as CSV: the header, then [`Table::values`] (numbers in full, empty where a
/// figure is missing).
pub fn csv(t: &Table) -> Result<String, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&t.header)?;
    for r in &t.values {
        w.write_record(r)?;
    }
    let bytes = w.into_inner().map_err(|e| csv::Error::from(e.into_error()))?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_print_as_the_papers_do() {
        assert_eq!(si(16_384.0), "16.4K");
        assert_eq!(si(23_000_000.0), "23.00M");
        assert_eq!(si(130.0), "130");
    }

    #[test]
    fn paper_figures_read_as_numbers() {
        assert_eq!(paper_number("16K"), Some(16_000.0));
        assert_eq!(paper_number("2.3M"), Some(2_300_000.0));
        assert_eq!(paper_number("4.2"), Some(4.2));
        assert_eq!(paper_number("–"), None);
        assert_eq!(
            (Cell::Paper("5.3K").text(), Cell::Paper("5.3K").value()),
            ("5.3K".into(), "5300".into())
        );
        assert_eq!(
            (Cell::Count(32_768.0).text(), Cell::Count(32_768.0).value()),
            ("32.8K".into(), "32768".into())
        );
        assert_eq!((Cell::Missing.text(), Cell::Missing.value()), ("–".into(), String::new()));
    }

    #[test]
    fn csv_holds_the_values_and_quotes_cells_with_commas() {
        let cells = [vec![Cell::Text("1, 2".into()), Cell::Count(1500.0), Cell::Missing]];
        let t = Table {
            paper: PaperTable::LecocqTable2,
            title: "t".into(),
            paper_hardware: "h".into(),
            notes: vec![],
            header: vec!["a".into(), "b".into(), "c".into()],
            values: cells.iter().map(|r| r.iter().map(Cell::value).collect()).collect(),
            rows: cells.iter().map(|r| r.iter().map(Cell::text).collect()).collect(),
            curves: vec![],
        };
        assert_eq!(csv(&t).expect("writes"), "a,b,c\n\"1, 2\",1500,\n");
        let md = markdown(&t);
        assert!(md.contains("Paper's figures measured on: h."), "{md}");
        assert!(md.contains("| 1, 2 | 1.5K | – |"), "{md}");
    }

    #[test]
    fn every_table_has_its_scenes_and_runs() {
        for p in [
            PaperTable::AilaLaineTable1,
            PaperTable::PanTable1,
            PaperTable::LecocqTable1,
            PaperTable::LecocqTable2,
            PaperTable::CostAgainstTriangles,
            PaperTable::CostAgainstPixels,
        ] {
            let spec = TableSpec { paper: p, scenes: vec![], width: 0, height: 0 };
            let frames = frames_of(&spec).len();
            let runs: usize = p.default_scenes().iter().map(|s| p.runs(s).len() * frames).sum();
            let planned: usize = table_items(&spec).iter().map(|(_, _, r)| r.len()).sum();
            assert_eq!(planned, runs);
            assert!(!p.hardware().is_empty());
        }
        // Pan et al.'s rates: 128 for the cage, 32 for the plant and elsewhere.
        assert_eq!(PaperTable::PanTable1.runs("cage")[0].1.rate, Some(128));
        assert_eq!(PaperTable::PanTable1.runs("plant")[0].1.rate, Some(32));
        assert_eq!(PaperTable::PanTable1.runs("city")[0].1.rate, Some(32));
        // Lecocq's Table 2 alternates sm and spsm per map size, as its rows read them.
        let runs = PaperTable::LecocqTable2.runs("bunny-plane");
        assert_eq!(runs.len(), 2 * LECOCQ2.len());
        for (k, (res, ..)) in LECOCQ2.iter().enumerate() {
            assert_eq!((runs[2 * k].0, runs[2 * k].1.map_res), ("sm", Some(*res)));
            assert_eq!((runs[2 * k + 1].0, runs[2 * k + 1].1.map_res), ("spsm", Some(*res)));
        }
    }

    #[test]
    fn a_power_law_gives_its_exponent() {
        let pts: Vec<(f64, f64)> =
            [1e3, 1e4, 1e5, 1e6].iter().map(|&w: &f64| (w, 3.0 * w.powf(0.8))).collect();
        let b = fit_exponent(&pts).expect("fits");
        assert!((b - 0.8).abs() < 1e-12, "{b}");
        assert_eq!(fit_exponent(&pts[..1]), None);
        assert_eq!(fit_exponent(&[(1.0, 2.0), (1.0, 3.0)]), None, "one work only");
        assert_eq!(fit_exponent(&[(0.0, 2.0), (10.0, 3.0)]), None, "no log of 0");
        // Noise around a line: the fit lies between the extremes' slopes.
        let noisy = [(1.0, 1.0), (10.0, 12.0), (100.0, 90.0), (1000.0, 1100.0)];
        let b = fit_exponent(&noisy).expect("fits");
        assert!((0.9..1.1).contains(&b), "{b}");
    }
}
