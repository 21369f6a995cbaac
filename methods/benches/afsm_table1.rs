//! Table 1 of Aila and Laine 2004 ("Alias-Free Shadow Maps", section 5.1): `afsm` on
//! `random-1k` .. `random-1m` at 1024 x 768, our numbers beside the paper's.
//!
//! Timing: each scene is measured by the workbench's one timing loop,
//! [`instrumentation::measure::measure`], under `Protocol::fixed(1, runs)`: one untimed
//! warm-up, then `SHADOWBENCH_BENCH_RUNS` timed runs (default 5). The times are wall-clock
//! medians from the engine's summaries: a stage's time is its median in `Measured::stages`,
//! the total the median of the per-run sums of the three stages (`Measured::wall_ms`). Beside the total,
//! the median CPU time of the process's threads over a run (`Measured::cpu_ms`, the rayon pool
//! included). The counters are the median run's; they do not depend on the run. The camera
//! G-buffer is rendered once per scene and is not part of the table (the paper starts from the
//! depth buffer too).
//!
//! `cargo bench -p shadowbench-methods --bench afsm_table1` prints the Markdown table.

mod common;

use instrumentation::{
    measure::{measure, Protocol},
    Counters, Recorder,
};
use methods::{
    afsm::{
        AfsmOptions, AliasFreeShadowMap, PAPER_TABLE1, STAGE_BSP, STAGE_RASTERIZATION,
        STAGE_TRANSFORMATION,
    },
    Frame, ShadowMethod,
};

const SCENES: [&str; 4] = ["random-1k", "random-10k", "random-100k", "random-1m"];
const WIDTH: u32 = 1024;
const HEIGHT: u32 = 768;

/// One cell of a table row, from a scene's measurements.
type Cell = fn(&Row) -> String;

/// One scene's column of the table.
struct Row {
    triangles: usize,
    samples: usize,
    counters: Counters,
    /// Wall-clock median ms of transformation, BSP construction, rasterization, and of their
    /// sum.
    ms: [f64; 4],
    /// Median CPU ms of a run, where the clock is available.
    cpu_ms: Option<f64>,
}

fn measure_scene(name: &str, protocol: &Protocol) -> Result<Row, String> {
    let scene = scenes::load(name).map_err(|e| e.to_string())?;
    let frame = Frame::new(&scene, WIDTH, HEIGHT, &mut Recorder::default());
    let method = AliasFreeShadowMap::pixel_centres(AfsmOptions::default());
    let m = measure(protocol, |rec: &mut Recorder| {
        method.run(&frame, rec).map(|_| ()).map_err(|e| e.to_string())
    })?;
    let stage = |n: &str| m.stages.iter().find(|s| s.name == n).map_or(0.0, |s| s.ms.median);
    let samples = frame.gbuffer.triangle.iter().filter(|&&t| t != methods::raster::NO_TRIANGLE);
    Ok(Row {
        triangles: scene.triangle_count(),
        samples: samples.count(),
        counters: m.record.counters,
        ms: [
            stage(STAGE_TRANSFORMATION),
            stage(STAGE_BSP),
            stage(STAGE_RASTERIZATION),
            m.wall_ms.median,
        ],
        cpu_ms: m.cpu_ms.map(|s| s.median),
    })
}

/// `1234567` as `1.23M`, `12345` as `12.3K`.
fn short(n: u64) -> String {
    let n = n as f64;
    let (v, unit) = if n >= 1e6 {
        (n / 1e6, "M")
    } else if n >= 1e3 {
        (n / 1e3, "K")
    } else {
        (n, "")
    };
    if v >= 100.0 || unit.is_empty() {
        format!("{v:.0}{unit}")
    } else if v >= 10.0 {
        format!("{v:.1}{unit}")
    } else {
        format!("{v:.2}{unit}")
    }
}

fn main() {
    let runs = common::runs(5);
    let protocol = common::protocol(runs);
    let mut measured = Vec::new();
    for name in SCENES {
        match measure_scene(name, &protocol) {
            Ok(m) => measured.push(m),
            Err(e) => {
                eprintln!("{name}: {e}");
                std::process::exit(1);
            }
        }
    }
    println!(
        "afsm, {WIDTH}x{HEIGHT}, {} on {} threads; wall-clock medians of {runs} runs after one \
         warm-up (instrumentation::measure); CPU time of the process's threads beside \
         (paper: 1.6 GHz Mobile Pentium 4). Times in ms.\n",
        instrumentation::cpu_model(),
        rayon::current_num_threads()
    );
    let mut header = String::from("| |");
    let mut rule = String::from("|---|");
    for name in SCENES {
        header.push_str(&format!(" {name} ours | paper |"));
        rule.push_str("---:|---:|");
    }
    println!("{header}\n{rule}");
    let rows: [(&str, Cell); 8] = [
        ("#Triangles (ground included)", |m| short(m.triangles as u64)),
        ("#2D BSP nodes (all; leaves)", |m| {
            let n = m.counters.bsp_nodes;
            format!("{}; {}", short(n), short(n.div_ceil(2)))
        }),
        ("#2D BSP nodes visited", |m| short(m.counters.bsp_nodes_visited)),
        ("#nodes occlusion culled", |m| short(m.counters.nodes_occlusion_culled)),
        ("#sampling points tested", |m| short(m.counters.sampling_points_tested)),
        ("Transformation of samples", |m| format!("{:.1}", m.ms[0])),
        ("BSP construction", |m| format!("{:.1}", m.ms[1])),
        ("Rasterization of blockers", |m| format!("{:.1}", m.ms[2])),
    ];
    for (row, (label, cell)) in rows.iter().enumerate() {
        let mut line = format!("| {label} |");
        for (m, paper) in measured.iter().zip(PAPER_TABLE1[row]) {
            line.push_str(&format!(" {} | {paper} |", cell(m)));
        }
        println!("{line}");
    }
    let mut line = String::from("| **Total time (ms)** |");
    for (m, paper) in measured.iter().zip(PAPER_TABLE1[8]) {
        line.push_str(&format!(" **{:.1}** | {paper} |", m.ms[3]));
    }
    println!("{line}");
    let mut line = String::from("| Total CPU time (ms, not in the paper) |");
    for m in &measured {
        line.push_str(&format!(" {} | – |", common::ms_or_dash(m.cpu_ms)));
    }
    println!("{line}");
    let mut line = String::from("| #nodes depth culled (not in the paper) |");
    for m in &measured {
        line.push_str(&format!(" {} | – |", short(m.counters.nodes_depth_culled)));
    }
    println!("{line}");
    let mut line = String::from("| visible samples (not in the paper) |");
    for m in &measured {
        line.push_str(&format!(" {} | – |", short(m.samples as u64)));
    }
    println!("{line}");
}
