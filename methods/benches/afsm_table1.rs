//! Table 1 of Aila and Laine 2004 ("Alias-Free Shadow Maps", section 5.1): `afsm` on
//! `random-1k` .. `random-1m` at 1024 x 768, our numbers beside the paper's.
//!
//! Each scene: one warm-up run, then `SHADOWBENCH_BENCH_RUNS` runs (default 5); the stage
//! times are the medians over the runs, the total the median of the per-run sums of the three
//! stages. The counters do not depend on the run. The camera G-buffer is rendered once per
//! scene and is not part of the table (the paper starts from the depth buffer too).
//!
//! `cargo bench -p shadowbench-methods --bench afsm_table1` prints the Markdown table.

mod common;

use instrumentation::{Counters, Recorder};
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
type Cell = fn(&Measured) -> String;

struct Measured {
    triangles: usize,
    samples: usize,
    counters: Counters,
    /// Median ms of transformation, BSP construction, rasterization, and of their sum.
    ms: [f64; 4],
}

fn measure(name: &str, runs: usize) -> Result<Measured, String> {
    let scene = scenes::load(name).map_err(|e| e.to_string())?;
    let frame = Frame::new(&scene, WIDTH, HEIGHT, &mut Recorder::default());
    let method = AliasFreeShadowMap::pixel_centres(AfsmOptions::default());
    let mut times: [Vec<f64>; 4] = Default::default();
    let mut counters = Counters::default();
    for run in 0..=runs {
        let mut rec = Recorder::default();
        method.run(&frame, &mut rec).map_err(|e| e.to_string())?;
        if run == 0 {
            continue; // warm-up
        }
        let stage = |n: &str| rec.stages.stages.iter().find(|s| s.name == n).map_or(0.0, |s| s.ms);
        let ms = [stage(STAGE_TRANSFORMATION), stage(STAGE_BSP), stage(STAGE_RASTERIZATION)];
        for (t, v) in times.iter_mut().zip(ms.iter().chain([&ms.iter().sum()])) {
            t.push(*v);
        }
        counters = rec.counters;
    }
    let samples = frame.gbuffer.triangle.iter().filter(|&&t| t != methods::raster::NO_TRIANGLE);
    Ok(Measured {
        triangles: scene.triangle_count(),
        samples: samples.count(),
        counters,
        ms: times.map(common::median),
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
    let mut measured = Vec::new();
    for name in SCENES {
        match measure(name, runs) {
            Ok(m) => measured.push(m),
            Err(e) => {
                eprintln!("{name}: {e}");
                std::process::exit(1);
            }
        }
    }
    println!(
        "afsm, {WIDTH}x{HEIGHT}, {} on {} threads; median of {runs} runs after one warm-up \
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
