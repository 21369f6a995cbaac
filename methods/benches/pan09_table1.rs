//! Table 1 of Pan et al. 2009 ("Fast, Sub-pixel Antialiased Shadow Maps", section 5):
//! `pan09` on `cage`, `plant`, `spheres`, `bunny-plane` and `bumpy` at 800 x 600 with a
//! 512 x 512 map, our numbers beside the paper's where it has the scene.
//!
//! Sample rate: the paper's for the scenes it lists (128 for the cage, 32 for the plant and
//! the bunny), 32 elsewhere. Each scene: one warm-up run, then `SHADOWBENCH_BENCH_RUNS` runs
//! (default 5); the three times are medians of the per-run sums of their stages
//! (`methods::pan09::TABLE1`), the total the median of the per-run sums of the three. The
//! counters do not depend on the run. The camera G-buffer is rendered once per scene and is
//! not part of the table, nor is the per-scene edge adjacency. Scenes whose model is missing
//! (`scripts/fetch-models`) are skipped with a note. The last row is Fig. 9's statistic.
//!
//! `cargo bench -p shadowbench-methods --bench pan09_table1` prints the Markdown table.

mod common;

use instrumentation::{Counters, Recorder};
use methods::{
    pan09::{table1_times, Pan09, Pan09Options, PAPER_TABLE1, TABLE1},
    Frame, ShadowMethod,
};

const WIDTH: u32 = 800;
const HEIGHT: u32 = 600;

struct Measured {
    name: &'static str,
    triangles: usize,
    rate: u32,
    counters: Counters,
    /// Median ms of the three Table 1 times and of their sum.
    ms: [f64; 4],
}

fn measure(name: &'static str, rate: u32, runs: usize) -> Result<Option<Measured>, String> {
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
    let mut times: [Vec<f64>; 4] = Default::default();
    let mut counters = Counters::default();
    for run in 0..=runs {
        let mut rec = Recorder::default();
        method.run(&frame, &mut rec).map_err(|e| e.to_string())?;
        if run == 0 {
            continue; // warm-up
        }
        let ms = table1_times(&rec.stages);
        for (t, v) in times.iter_mut().zip(ms.iter().chain([&ms.iter().sum()])) {
            t.push(*v);
        }
        counters = rec.counters;
    }
    Ok(Some(Measured {
        name,
        triangles: scene.triangle_count(),
        rate,
        counters,
        ms: times.map(common::median),
    }))
}

fn main() {
    let runs = common::runs(5);
    let mut rows = Vec::new();
    for (name, rate, paper) in PAPER_TABLE1 {
        match measure(name, rate, runs) {
            Ok(Some(m)) => rows.push((m, paper, paper.map_or("–", |p| p[9]))),
            Ok(None) => {}
            Err(e) => {
                eprintln!("{name}: {e}");
                std::process::exit(1);
            }
        }
    }
    println!(
        "pan09 (table mode), {WIDTH}x{HEIGHT}, map 512x512, {} on {} threads; median of {runs} \
         runs after one warm-up. Paper: NVIDIA GTX 280 with a 3.0 GHz CPU (CUDA), its scenes \
         (Cage, Plant, Bunny) beside ours of the same kind. Times in ms.\n",
        instrumentation::cpu_model(),
        rayon::current_num_threads()
    );
    println!(
        "| Scene | Triangles | Silhouette texels | Silhouette pixels | Visibility evaluations \
         | Sample rate | {} | {} | {} | Total (ms) | FPS of the three |",
        TABLE1[0].0, TABLE1[1].0, TABLE1[2].0
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (m, paper, fps) in &rows {
        let c = &m.counters;
        println!(
            "| {} (ours) | {} | {} | {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} |",
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
            1000.0 / m.ms[3]
        );
        if let Some(p) = paper {
            let total: f64 = p[6..9].iter().filter_map(|v| v.parse::<f64>().ok()).sum();
            println!(
                "| {} (paper) | {} | {} | {} | {} | {} | {} | {} | {} | {total:.1} | {fps} (whole frame) |",
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
