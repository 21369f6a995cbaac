//! Table 2 of Lecocq et al. 2014: `sm` and `spsm` time at map sizes 512 to 4096 on one scene
//! at 1920 x 1080, and the SPSM overhead.
//!
//! `cargo bench -p shadowbench-methods --bench spsm_table2 [-- SCENE [RUNS]]`; the scene
//! defaults to `bunny-plane` (75k triangles; the paper used YeahRight, 155k), or `spheres`
//! when the model is missing. Each configuration runs once to warm up, then `RUNS` times
//! (default `SHADOWBENCH_BENCH_RUNS`, else 5); the median of the method's own time (the sum
//! of its stages: for `sm` the light depth map and the depth test, for `spsm` all of its
//! stages) is reported. The camera
//! G-buffer, shared by both, is timed apart: the paper's times include scene rendering.

mod common;

use instrumentation::Recorder;
use methods::{method, Frame, MethodOptions};

/// The paper's Table 2 (YeahRight, GTX 580): map size, SM ms, SPSM ms, overhead %.
const PAPER: [(u32, f64, f64, f64); 4] = [
    (512, 5.5, 10.0, 81.0),
    (1024, 5.8, 9.1, 56.0),
    (2048, 7.4, 10.7, 44.0),
    (4096, 14.2, 18.1, 27.0),
];

fn main() {
    // `cargo bench` passes `--bench`; everything else is ours.
    let args: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    let requested = args.first().cloned();
    let runs: usize =
        args.get(1).and_then(|r| r.parse().ok()).unwrap_or_else(|| common::runs(5)).max(1);
    let scene = match requested.as_deref().map_or_else(|| scenes::load("bunny-plane"), scenes::load)
    {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}; using spheres");
            match scenes::load("spheres") {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("cannot load spheres: {e}");
                    return;
                }
            }
        }
    };
    let (w, h) = (1920, 1080);
    let mut gbuffer = Recorder::default();
    let frame = Frame::new(&scene, w, h, &mut gbuffer);
    println!(
        "Table 2: {} ({} triangles) at {w}x{h}; {}, {} threads; warm-up 1 run, median of {runs}",
        scene.name,
        scene.triangle_count(),
        instrumentation::cpu_model(),
        rayon::current_num_threads()
    );
    println!("camera G-buffer (shared, not included below): {:.1} ms", gbuffer.stages.total_ms());
    println!(
        "{:>6} {:>10} {:>10} {:>9} | {:>8} {:>8} {:>9} | spsm stages (median ms)",
        "map", "sm ms", "spsm ms", "overhead", "paper sm", "spsm", "overhead"
    );
    for (map_res, paper_sm, paper_spsm, paper_overhead) in PAPER {
        let options = MethodOptions { map_res: Some(map_res), ..Default::default() };
        let time = |name: &str| {
            let m = method(name, &options).expect("valid options");
            let mut totals = Vec::new();
            let mut stages: Vec<(String, Vec<f64>)> = Vec::new();
            let mut uncertain = 0;
            for run in 0..=runs {
                let mut rec = Recorder::default();
                m.run(&frame, &mut rec).expect("runs");
                if run == 0 {
                    continue;
                }
                totals.push(rec.stages.total_ms());
                uncertain = rec.counters.uncertain_pixels;
                for s in rec.stages.stages {
                    match stages.iter_mut().find(|(n, _)| *n == s.name) {
                        Some((_, v)) => v.push(s.ms),
                        None => stages.push((s.name, vec![s.ms])),
                    }
                }
            }
            let stages: Vec<String> =
                stages.into_iter().map(|(n, v)| format!("{n} {:.1}", common::median(v))).collect();
            (common::median(totals), stages.join(", "), uncertain)
        };
        let (sm, _, _) = time("sm");
        let (spsm, stages, uncertain) = time("spsm");
        println!(
            "{map_res:>6} {sm:>10.1} {spsm:>10.1} {:>8.0}% | {paper_sm:>8.1} {paper_spsm:>8.1} \
             {paper_overhead:>8.0}% | {stages}; uncertain pixels {uncertain}",
            100.0 * (spsm - sm) / sm,
        );
    }
}
