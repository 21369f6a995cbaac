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
//! timing protocol ([`crate::timing::time_method`]); it measures times and counters only, so no
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
//!
//! The papers' times include rendering the scene; ours give the method's own stages, and the
//! camera G-buffer (our scene rendering) apart, so that both overheads can be read.

use crate::timing::{time_method, StageTimes, Timed};
use instrumentation::Recorder;
use methods::{pan09::PAPER_TABLE1 as PAN_TABLE1, Frame, MethodOptions};
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
    /// Column headings.
    pub header: Vec<String>,
    /// Rows of cells.
    pub rows: Vec<Vec<String>>,
}

impl PaperTable {
    /// The name used in suite files.
    pub fn name(self) -> &'static str {
        match self {
            Self::AilaLaineTable1 => "aila-laine-table1",
            Self::LecocqTable1 => "lecocq-table1",
            Self::LecocqTable2 => "lecocq-table2",
            Self::PanTable1 => "pan-table1",
        }
    }

    /// The table's own scenes (ours standing in for the paper's models where needed).
    pub fn default_scenes(self) -> &'static [&'static str] {
        match self {
            Self::AilaLaineTable1 => &["random-1k", "random-10k", "random-100k", "random-1m"],
            Self::LecocqTable1 => &["spheres", "bunny-plane", "random-1m"],
            Self::LecocqTable2 => &["bunny-plane"],
            Self::PanTable1 => &["cage", "plant", "spheres", "bunny-plane", "bumpy"],
        }
    }

    /// The paper's frame size.
    pub fn paper_frame(self) -> (u32, u32) {
        match self {
            Self::AilaLaineTable1 => (1024, 768),
            Self::LecocqTable1 | Self::LecocqTable2 => (1920, 1080),
            Self::PanTable1 => (800, 600),
        }
    }

    fn hardware(self) -> &'static str {
        match self {
            Self::AilaLaineTable1 => "1.6 GHz Mobile Pentium 4 (CPU)",
            Self::LecocqTable1 | Self::LecocqTable2 => "NVIDIA GeForce GTX 580 (GPU)",
            Self::PanTable1 => "NVIDIA GeForce GTX 280 (GPU) with a 3.0 GHz CPU",
        }
    }

    /// The method runs the table makes on `scene`.
    fn runs(self, scene: &str) -> Vec<(&'static str, MethodOptions)> {
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
        }
    }
}

/// Method runs a table makes, for progress bars.
pub fn table_run_count(spec: &TableSpec) -> u64 {
    scenes_of(spec).iter().map(|s| spec.paper.runs(s).len() as u64).sum()
}

fn scenes_of(spec: &TableSpec) -> Vec<String> {
    if spec.scenes.is_empty() {
        spec.paper.default_scenes().iter().map(|s| (*s).to_owned()).collect()
    } else {
        spec.scenes.clone()
    }
}

/// One scene's measurements for a table.
struct SceneRuns {
    name: String,
    triangles: usize,
    gbuffer_ms: f64,
    /// In the order of [`PaperTable::runs`]; `None` where the run failed.
    runs: Vec<Option<Timed>>,
}

/// Measures the table: every scene of `spec`, every run the table needs, `warmup` untimed and
/// `repeats` timed runs each. Runs that cannot be made are listed in `skipped` and shown as
/// "–".
pub fn run_table(
    spec: &TableSpec,
    warmup: u32,
    repeats: u32,
    skipped: &mut Vec<String>,
    mut progress: impl FnMut(&str),
) -> Table {
    let paper = spec.paper;
    let (pw, ph) = paper.paper_frame();
    let (w, h) = if spec.width == 0 { (pw, ph) } else { (spec.width, spec.height) };
    let mut measured = Vec::new();
    for name in scenes_of(spec) {
        let runs = paper.runs(&name);
        let scene = match scenes::load(&name) {
            Ok(s) => s,
            Err(e) => {
                skipped.push(format!("{}: scene {name}: {e}", paper.name()));
                runs.iter().for_each(|_| progress(&name));
                continue;
            }
        };
        let mut rec = Recorder::default();
        let frame = Frame::new(&scene, w, h, &mut rec);
        let mut out = Vec::new();
        for (method, options) in &runs {
            progress(&format!("{} {name} {method}", paper.name()));
            let timed = analysis::registry::technique(method, options)
                .map_err(|e| e.to_string())
                .and_then(|t| time_method(t.as_ref(), &frame, warmup, repeats));
            match timed {
                Ok(t) => out.push(Some(t)),
                Err(e) => {
                    skipped.push(format!("{}: {method} on {name}: {e}", paper.name()));
                    out.push(None);
                }
            }
        }
        measured.push(SceneRuns {
            name,
            triangles: frame.geometry.len(),
            gbuffer_ms: rec.stages.total_ms(),
            runs: out,
        });
    }
    let mut notes = vec![format!(
        "Ours: {w}x{h}, median of {} timed runs after {warmup} warm-up, on the machine named \
         at the top of the report.",
        repeats.max(1)
    )];
    let (header, rows) = match paper {
        PaperTable::AilaLaineTable1 => aila_laine(&measured, &mut notes),
        PaperTable::LecocqTable1 => lecocq1(&measured, &mut notes),
        PaperTable::LecocqTable2 => lecocq2(&measured, &mut notes),
        PaperTable::PanTable1 => pan1(&measured, &mut notes),
    };
    let title = match paper {
        PaperTable::AilaLaineTable1 => "Aila & Laine 2004, Table 1: alias-free shadow maps",
        PaperTable::LecocqTable1 => "Lecocq et al. 2014, Table 1: SM and SPSM times (ms)",
        PaperTable::LecocqTable2 => "Lecocq et al. 2014, Table 2: SPSM overhead against map size",
        PaperTable::PanTable1 => "Pan et al. 2009, Table 1: statistics of the test scenes",
    };
    Table {
        paper,
        title: title.to_owned(),
        paper_hardware: paper.hardware().to_owned(),
        notes,
        header,
        rows,
    }
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

fn counter(t: &Timed, name: &str) -> Option<u64> {
    t.record.counters.entries().into_iter().find(|(n, _)| *n == name).map(|(_, v)| v)
}

fn stage_ms(stages: &[StageTimes], name: &str) -> Option<f64> {
    stages.iter().find(|s| s.name == name).map(|s| s.ms.median)
}

fn ms(v: Option<f64>) -> String {
    v.map_or_else(|| "–".to_owned(), |v| format!("{v:.1}"))
}

fn aila_laine(measured: &[SceneRuns], notes: &mut Vec<String>) -> (Vec<String>, Vec<Vec<String>>) {
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
            let mut cells = vec![(*label).to_owned()];
            for (k, s) in measured.iter().enumerate() {
                let t = s.runs.first().and_then(Option::as_ref);
                let c =
                    |name| t.and_then(|t| counter(t, name)).map_or("–".into(), |v| si(v as f64));
                let st = |name| ms(t.and_then(|t| stage_ms(&t.stages, name)));
                cells.push(match row {
                    0 => si(s.triangles as f64),
                    1 => c("bsp_nodes"),
                    2 => c("bsp_nodes_visited"),
                    3 => c("nodes_occlusion_culled"),
                    4 => c("sampling_points_tested"),
                    5 => st(STAGE_TRANSFORMATION),
                    6 => st(STAGE_BSP),
                    7 => st(STAGE_RASTERIZATION),
                    _ => ms(t.map(|t| t.total_ms.median)),
                });
                cells.push(PAPER_TABLE1[row].get(k).map_or("–".into(), |v| (*v).to_owned()));
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

fn lecocq1(measured: &[SceneRuns], notes: &mut Vec<String>) -> (Vec<String>, Vec<Vec<String>>) {
    notes.push(
        "The paper's times include the shadow map and the scene's rendering; ours are the \
         method's own stages, with our scene rendering (the camera G-buffer) in its own column."
            .into(),
    );
    let header = [
        "scene (paper's model)",
        "triangles ours / paper",
        "G-buffer ms",
        "SM 1K ours / paper",
        "SM 2K ours / paper",
        "SPSM 1K ours / paper",
        "SPSM 2K ours / paper",
    ]
    .map(String::from)
    .to_vec();
    let rows = measured
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let paper = LECOCQ1.get(k);
            let mut cells = vec![
                format!("{} ({})", s.name, paper.map_or("–", |p| p.0)),
                format!("{} / {}", si(s.triangles as f64), paper.map_or("–", |p| p.1)),
                format!("{:.1}", s.gbuffer_ms),
            ];
            for (j, t) in s.runs.iter().enumerate() {
                let ours = ms(t.as_ref().map(|t| t.total_ms.median));
                cells.push(format!("{ours} / {}", paper.map_or("–", |p| p.2[j])));
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

fn lecocq2(measured: &[SceneRuns], notes: &mut Vec<String>) -> (Vec<String>, Vec<Vec<String>>) {
    notes.push(
        "Overhead = SPSM / SM - 1. The paper's times include rendering the scene, so its \
         overhead compares with ours including the G-buffer; without it, ours is the methods' \
         own."
            .into(),
    );
    let header = [
        "scene (paper's model)",
        "map",
        "SM ms ours / paper",
        "SPSM ms ours / paper",
        "overhead % (methods)",
        "overhead % (with G-buffer) / paper",
    ]
    .map(String::from)
    .to_vec();
    let mut rows = Vec::new();
    for s in measured {
        for (k, (res, sm_paper, spsm_paper, over_paper)) in LECOCQ2.iter().enumerate() {
            let t = |j: usize| s.runs.get(j).and_then(Option::as_ref).map(|t| t.total_ms.median);
            let (sm, spsm) = (t(2 * k), t(2 * k + 1));
            let over = |extra: f64| match (sm, spsm) {
                (Some(a), Some(b)) => format!("{:.0}", 100.0 * ((b + extra) / (a + extra) - 1.0)),
                _ => "–".into(),
            };
            rows.push(vec![
                format!("{} (YeahRight)", s.name),
                format!("{res}²"),
                format!("{} / {sm_paper}", ms(sm)),
                format!("{} / {spsm_paper}", ms(spsm)),
                over(0.0),
                format!("{} / {over_paper}", over(s.gbuffer_ms)),
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

fn pan1(measured: &[SceneRuns], notes: &mut Vec<String>) -> (Vec<String>, Vec<Vec<String>>) {
    use methods::pan09::TABLE1;
    notes.push(
        "pan09 in table mode with a 512x512 map, at the paper's rate for the scenes it lists \
         (our cage, plant and bunny-plane beside its Cage, Plant and Bunny) and 32 elsewhere. \
         The three times group our stages as methods::pan09::TABLE1 does (each the sum of its \
         stages' medians); the camera G-buffer and the per-scene edge adjacency are not in them."
            .into(),
    );
    let mut header = ["scene (paper's)", "triangles", "silhouette texels", "silhouette pixels"]
        .map(String::from)
        .to_vec();
    header.push("visibility evaluations".into());
    header.push("sample rate".into());
    header.extend(TABLE1.iter().map(|(name, _)| format!("{name} (ms)")));
    header.push("total (ms)".into());
    let rows = measured
        .iter()
        .map(|s| {
            let paper = PAN_TABLE1.iter().find(|(n, ..)| *n == s.name).and_then(|r| r.2);
            let beside = |ours: String, k: usize| match paper {
                Some(p) => format!("{ours} / {}", p[k]),
                None => ours,
            };
            let t = s.runs.first().and_then(Option::as_ref);
            let c = |name| t.and_then(|t| counter(t, name)).map_or("–".into(), |v| v.to_string());
            let groups: Vec<Option<f64>> = TABLE1
                .iter()
                .map(|(_, names)| {
                    t.map(|t| names.iter().filter_map(|n| stage_ms(&t.stages, n)).sum::<f64>())
                })
                .collect();
            let total = groups.iter().copied().sum::<Option<f64>>();
            let paper_total =
                paper.map(|p| p[6..9].iter().filter_map(|v| v.parse::<f64>().ok()).sum::<f64>());
            let mut cells = vec![
                format!("{} ({})", s.name, paper.map_or("–", |p| p[0])),
                beside(s.triangles.to_string(), 1),
                beside(c("silhouette_texels"), 2),
                beside(c("silhouette_pixels"), 3),
                beside(c("visibility_evaluations"), 4),
                beside(pan_rate(&s.name).to_string(), 5),
            ];
            for (k, g) in groups.iter().enumerate() {
                cells.push(beside(ms(*g), 6 + k));
            }
            cells.push(match paper_total {
                Some(p) => format!("{} / {p:.1}", ms(total)),
                None => ms(total),
            });
            cells
        })
        .collect();
    (header, rows)
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

/// The table as CSV (header row first).
pub fn csv(t: &Table) -> String {
    let quote = |c: &String| {
        if c.contains([',', '"', '\n']) {
            format!("\"{}\"", c.replace('"', "\"\""))
        } else {
            c.clone()
        }
    };
    std::iter::once(&t.header)
        .chain(&t.rows)
        .map(|r| r.iter().map(quote).collect::<Vec<_>>().join(",") + "\n")
        .collect()
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
    fn csv_quotes_cells_with_commas() {
        let t = Table {
            paper: PaperTable::LecocqTable2,
            title: "t".into(),
            paper_hardware: "h".into(),
            notes: vec![],
            header: vec!["a".into(), "b".into()],
            rows: vec![vec!["1, 2".into(), "x\"y".into()]],
        };
        assert_eq!(csv(&t), "a,b\n\"1, 2\",\"x\"\"y\"\n");
        let md = markdown(&t);
        assert!(md.contains("Paper's figures measured on: h."), "{md}");
        assert!(md.contains("| 1, 2 | x\"y |"), "{md}");
    }

    #[test]
    fn every_table_has_its_scenes_and_runs() {
        for p in [
            PaperTable::AilaLaineTable1,
            PaperTable::PanTable1,
            PaperTable::LecocqTable1,
            PaperTable::LecocqTable2,
        ] {
            let spec = TableSpec { paper: p, scenes: vec![], width: 0, height: 0 };
            let runs: usize = p.default_scenes().iter().map(|s| p.runs(s).len()).sum();
            assert_eq!(table_run_count(&spec) as usize, runs);
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
}
