//! Table 1 of Pan et al. 2009 ("Fast, Sub-pixel Antialiased Shadow Maps", section 5):
//! `pan09` on `cage`, `plant`, `spheres`, `bunny-plane` and `bumpy` at 800 x 600 with a
//! 512 x 512 map, our numbers beside the paper's where it has the scene.
//!
//! Sample rate: the paper's for the scenes it lists (128 for the cage, 32 for the plant and
//! the bunny), 32 elsewhere. The counters do not depend on the run. The camera G-buffer is
//! rendered once per scene and is not part of the table, nor is the per-scene edge adjacency.
//! Scenes whose model is missing (`scripts/fetch-models`) are skipped with a note. The last row
//! is Fig. 9's statistic.
//!
//! Timing: each scene is measured by the workbench's one timing loop,
//! [`instrumentation::measure::measure`], under `Protocol::fixed(1, runs)`: one untimed
//! warm-up, then `SHADOWBENCH_BENCH_RUNS` timed runs (default 5). Each of the three times
//! groups our stages as `methods::pan09::TABLE1` does, each the sum of its stages' wall-clock
//! medians (`Measured::stages`), as the `papers` report's Table 1 does; the total is the sum of
//! the three. Beside it, the same sum on the CPU clock (CPU time of the process's threads, the
//! rayon pool included). The counters are those of the median run.
//!
//! `cargo bench -p shadowbench-methods --bench pan09_table1` prints the Markdown table.

mod common;

use instrumentation::{
    measure::{measure, Protocol, StageTimes},
    Counters, Recorder,
};
use methods::{
    pan09::{Pan09, Pan09Options, PAPER_TABLE1, TABLE1},
    Frame, ShadowMethod,
};

const WIDTH: u32 = 800;
const HEIGHT: u32 = 600;

/// One scene's row of the table.
struct Row {
    name: &'static str,
    triangles: usize,
    rate: u32,
    counters: Counters,
    /// Wall-clock ms of the three Table 1 times (sums of their stages' medians) and of their
    /// sum.
    ms: [f64; 4],
    /// The same sum of the three on the CPU clock, where every stage has a CPU time.
    cpu_ms: Option<f64>,
}

/// The sum over `names` of the stages' medians that `clock` picks; `None` when a stage that
/// ran has no figure on that clock.
fn group(
    stages: &[StageTimes],
    names: &[&str],
    clock: fn(&StageTimes) -> Option<f64>,
) -> Option<f64> {
    stages.iter().filter(|s| names.contains(&s.name.as_str())).map(clock).sum()
}

fn measure_scene(
    name: &'static str,
    rate: u32,
    protocol: &Protocol,
) -> Result<Option<Row>, String> {
    let scene = match scenes::load(name) {
        Ok(s) => s,
        Err(e @ scenes::SceneError::ModelMissing { .. }) => {
            eprintln!("skipping {name}: {e}");
            return Ok(None);
        }
        Err(e) => return Err(e.to_string()),
    };
    let frame = Frame::new(&scene, WIDTH, HEIGHT, &mut Recorder::default());
    let method =
        Pan09::new(Pan09Options { rate, ..Pan09Options::default() }).map_err(|e| e.to_string())?;
    let m = measure(protocol, |rec: &mut Recorder| {
        method.run(&frame, rec).map(|_| ()).map_err(|e| e.to_string())
    })?;
    let wall = |s: &StageTimes| Some(s.ms.median);
    let cpu = |s: &StageTimes| s.cpu_ms.map(|c| c.median);
    let times = TABLE1.map(|(_, names)| group(&m.stages, names, wall).unwrap_or(0.0));
    let cpu_ms: Option<f64> = TABLE1.iter().map(|(_, names)| group(&m.stages, names, cpu)).sum();
    Ok(Some(Row {
        name,
        triangles: scene.triangle_count(),
        rate,
        counters: m.record.counters,
        ms: [times[0], times[1], times[2], times.iter().sum()],
        cpu_ms,
    }))
}

fn main() {
    let runs = common::runs(5);
    let protocol = common::protocol(runs);
    let mut rows = Vec::new();
    for (name, rate, paper) in PAPER_TABLE1 {
        match measure_scene(name, rate, &protocol) {
            Ok(Some(m)) => rows.push((m, paper, paper.map_or("–", |p| p[9]))),
            Ok(None) => {}
            Err(e) => {
                eprintln!("{name}: {e}");
                std::process::exit(1);
            }
        }
    }
    println!(
        "pan09 (table mode), {WIDTH}x{HEIGHT}, map 512x512, {} on {} threads; wall-clock \
         medians of {runs} runs after one warm-up (instrumentation::measure), each time the sum \
         of its stages' medians; CPU time of the process's threads beside. Paper: NVIDIA GTX 280 with a 3.0 GHz CPU (CUDA), its scenes \
         (Cage, Plant, Bunny) beside ours of the same kind. Times in ms.\n",
        instrumentation::cpu_model(),
        rayon::current_num_threads()
    );
    println!(
        "| Scene | Triangles | Silhouette texels | Silhouette pixels | Visibility evaluations \
         | Sample rate | {} | {} | {} | Total (ms) | Total CPU (ms) | FPS of the three |",
        TABLE1[0].0, TABLE1[1].0, TABLE1[2].0
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (m, paper, fps) in &rows {
        let c = &m.counters;
        println!(
            "| {} (ours) | {} | {} | {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {} | {:.1} |",
            m.name,
            m.triangles,
            c.silhouette_texels,
            c.silhouette_pixels,
            c.visibility_evaluations,
            m.rate,
            m.ms[0],
            m.ms[1],
            m.ms[2],
            m.ms[3],
            common::ms_or_dash(m.cpu_ms),
            1000.0 / m.ms[3]
        );
        if let Some(p) = paper {
            let total: f64 = p[6..9].iter().filter_map(|v| v.parse::<f64>().ok()).sum();
            println!(
                "| {} (paper) | {} | {} | {} | {} | {} | {} | {} | {} | {total:.1} | – | {fps} (whole frame) |",
                p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8]
            );
        }
    }
    println!("\nFig. 9: mean valid sub-samples per boundary pixel (paper: 18.5 of 32 on its bumpy receiver)\n");
    println!("| Scene | Boundary pixels | Valid samples | Mean per boundary pixel |");
    println!("|---|---:|---:|---:|");
    for (m, _, _) in &rows {
        let c = &m.counters;
        let mean = if c.boundary_pixels > 0 && c.valid_samples > 0 {
            format!("{:.1} of {}", c.valid_samples as f64 / c.boundary_pixels as f64, m.rate)
        } else {
            "– (no validity mask: planar receivers)".into()
        };
        println!("| {} | {} | {} | {mean} |", m.name, c.boundary_pixels, c.valid_samples);
    }
}
