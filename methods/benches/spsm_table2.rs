//! Table 2 of Lecocq et al. 2014: `sm` and `spsm` time at map sizes 512 to 4096 on one scene
//! at 1920 x 1080, and the SPSM overhead.
//!
//! `cargo bench -p shadowbench-methods --bench spsm_table2 [-- SCENE [RUNS]]`; the scene
//! defaults to `bunny-plane` (75k triangles; the paper used YeahRight, 155k), or `spheres`
//! when the model is missing. A method's time is its own (the sum of its stages: for `sm` the
//! light depth map and the depth test, for `spsm` all of its stages). The camera G-buffer,
//! shared by both, is timed apart: the paper's times include scene rendering.
//!
//! Timing: the eight configurations (`sm` and `spsm` at each map size) are measured on the one
//! frame by the workbench's one timing loop, `instrumentation::measure::measure_all`,
//! interleaved round by round, under `Protocol::fixed(1, RUNS)`: one untimed warm-up each, then
//! `RUNS` timed runs (default `SHADOWBENCH_BENCH_RUNS`, else 5). Reported: the wall-clock median
//! of the per-run stage sums (`Measured::wall_ms`), the median CPU time of the process's
//! threads over a run beside it (`Measured::cpu_ms`, the rayon pool included), and each `spsm`
//! stage's wall-clock median (`Measured::stages`); the uncertain pixels are the median run's.

mod common;

use instrumentation::{
    measure::{measure_all, Measured},
    Recorder,
};
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
        "Table 2: {} ({} triangles) at {w}x{h}; {}, {} threads; warm-up 1 run, wall-clock \
         medians of {runs} (instrumentation::measure, the configurations interleaved); CPU time \
         of the process's threads beside",
        scene.name,
        scene.triangle_count(),
        instrumentation::cpu_model(),
        rayon::current_num_threads()
    );
    println!("camera G-buffer (shared, not included below): {:.1} ms", gbuffer.stages.total_ms());
    println!(
        "{:>6} {:>10} {:>10} {:>9} {:>8} {:>8} | {:>8} {:>8} {:>9} | spsm stages (median ms)",
        "map", "sm ms", "spsm ms", "overhead", "sm cpu", "spsm cpu", "paper sm", "spsm", "overhead"
    );
    let configs: Vec<(u32, &str)> =
        PAPER.iter().flat_map(|&(map_res, ..)| [(map_res, "sm"), (map_res, "spsm")]).collect();
    let built: Vec<_> = configs
        .iter()
        .map(|&(map_res, name)| {
            let options = MethodOptions { map_res: Some(map_res), ..Default::default() };
            method(name, &options).expect("valid options")
        })
        .collect();
    let mut subjects: Vec<_> = built
        .iter()
        .map(|m| {
            let frame = &frame;
            move |rec: &mut Recorder| m.run(frame, rec).map(|_| ())
        })
        .collect();
    let measured: Vec<Measured<()>> =
        measure_all(&common::protocol(runs), &mut subjects, |k, _| {
            eprintln!("{} at map {} measured", configs[k].1, configs[k].0);
        })
        .into_iter()
        .map(|r| r.expect("runs"))
        .collect();
    let cpu = |m: &Measured<()>| common::ms_or_dash(m.cpu_ms.map(|c| c.median));
    for ((map_res, paper_sm, paper_spsm, paper_overhead), pair) in
        PAPER.into_iter().zip(measured.chunks(2))
    {
        let [sm, spsm] = pair else { unreachable!("two configurations per map size") };
        let stages: Vec<String> =
            spsm.stages.iter().map(|s| format!("{} {:.1}", s.name, s.ms.median)).collect();
        let (sm_ms, spsm_ms) = (sm.wall_ms.median, spsm.wall_ms.median);
        println!(
            "{map_res:>6} {sm_ms:>10.1} {spsm_ms:>10.1} {:>8.0}% {:>8} {:>8} | {paper_sm:>8.1} \
             {paper_spsm:>8.1} {paper_overhead:>8.0}% | {}; uncertain pixels {}",
            100.0 * (spsm_ms - sm_ms) / sm_ms,
            cpu(sm),
            cpu(spsm),
            stages.join(", "),
            spsm.record.counters.uncertain_pixels,
        );
    }
}
