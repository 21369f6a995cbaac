//! The GPU targets beside the papers' figures, in one run (`scripts/gpu-bench`):
//!
//! - `pan09` at 32x on `bunny-plane` 800 x 600, map 512 (Pan et al. 2009, "Fast, Sub-pixel
//!   Antialiased Shadow Maps", Computer Graphics Forum 28(7), section 6: 22 ms on a GTX 280);
//! - `afsm` on `random-1m` 1024 x 768 (Aila and Laine 2004, Table 1: 8.6 s for the three
//!   stages on a 1.6 GHz Pentium 4);
//! - `spsm` against `sm` at maps 512 to 4096 on `bunny-plane` 1920 x 1080 (Lecocq et al.
//!   2014, "Sub-Pixel Shadow Mapping", I3D, Table 2: an overhead of 27-81 % on a GTX 580);
//! - `afsm-ss` at 32x against `pan09` at 32x on `bunny-plane` 800 x 600 (Pan et al.'s Fig. 10
//!   sets its method against brute-force supersampling).
//!
//! `cargo bench -p shadowbench-methods --bench gpu_bench [-- --quick]`. `--quick` divides
//! every frame side by 8 and uses `random-10k` for `random-1m`, to check the bench itself on a
//! software adapter. A software adapter is named as such in the header and in a warning: its
//! times say nothing of a GPU's.
//!
//! Timing: through the workbench's one timing loop, `instrumentation::measure::measure_all`,
//! the configurations of one frame interleaved round by round (`pan09` and `afsm-ss` on the
//! 800 x 600 frame; `sm` and `spsm` at the four map sizes on the 1920 x 1080 one), under
//! `Protocol::fixed(1, runs)` on the wall clock: one untimed warm-up each (pipelines compiled,
//! buffers first touched), then `SHADOWBENCH_BENCH_RUNS` timed runs (default 5). A GPU stage's
//! time comes from timestamp queries or from submitting and waiting (the header names which),
//! never from the CPU clock, so only wall (GPU) figures are printed. "With G-buffer" is the
//! median of the per-run stage sums (`Measured::wall_ms`); "ours" leaves out the median of the
//! GPU G-buffer stage (shared by every method), as `reports::devices` does.

mod common;

use instrumentation::{
    measure::{measure_all, Clock, Protocol},
    Recorder,
};
use methods::{
    frame::STAGE_GPU_GBUFFER, gpu::GpuContext, method, registry::Device, Frame, MethodOptions,
};
use scenes::Scene;

/// One timed configuration: median ms of the method's stages without and with the GPU
/// G-buffer, or why it did not run (an input beyond the adapter's limits, say).
type Timed = Result<(f64, f64), String>;

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let runs = common::runs(5);
    let ctx = match GpuContext::shared() {
        Ok(c) => c,
        Err(e) => {
            eprintln!("gpu-bench: {e}");
            std::process::exit(1);
        }
    };
    let software = ctx.is_software();
    println!(
        "GPU: {}{}; timing by {}; warm-up 1 run, medians of {runs} (instrumentation::measure, \
         the configurations of a frame interleaved){}",
        ctx.adapter_name(),
        if software { " (a SOFTWARE rasterizer: these times say nothing of a GPU)" } else { "" },
        ctx.timing.name(),
        if quick { "; --quick: frames / 8, random-10k for random-1m" } else { "" }
    );
    if software {
        eprintln!("gpu-bench: warning: only a software adapter was found ({})", ctx.adapter_name());
    }
    let side = |n: u32| if quick { (n / 8).max(8) } else { n };
    let bunny = load("bunny-plane");
    let random = load(if quick { "random-10k" } else { "random-1m" });

    println!("\n| target | ours (ms) | with G-buffer (ms) | paper / target |");
    println!("|---|---:|---:|---|");
    let pan_opts = MethodOptions { rate: Some(32), map_res: Some(512), ..gpu() };
    let ss_opts = MethodOptions { rate: Some(32), ..gpu() };
    let (w, h) = (side(800), side(600));
    let [pan, ss] = two(time_all(&bunny, w, h, &[("pan09", pan_opts), ("afsm-ss", ss_opts)], runs));
    row(
        &format!("pan09 32x, {} {w}x{h}, map 512", bunny.name),
        &pan,
        "Pan et al.: 22 ms (GTX 280); target < 2 ms",
    );
    let ratio = match (&ss, &pan) {
        (Ok((ss, _)), Ok((pan, _))) => format!("{:.1}x pan09 32x", ss / pan),
        _ => "n/a".to_owned(),
    };
    row(&format!("afsm-ss 32x, {} {w}x{h}", bunny.name), &ss, &ratio);
    let (w, h) = (side(1024), side(768));
    let afsm = time_all(&random, w, h, &[("afsm", gpu())], runs).remove(0);
    row(
        &format!("afsm, {} {w}x{h}", random.name),
        &afsm,
        "Aila & Laine: 8640 ms (P4 1.6 GHz); target < 10 ms",
    );

    let (w, h) = (side(1920), side(1080));
    println!("\nLecocq et al. Table 2 on {} {w}x{h} (paper: YeahRight, GTX 580)", bunny.name);
    println!("| map | sm (ms) | spsm (ms) | overhead | paper sm | paper spsm | paper overhead |");
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    let paper = [
        (512, 5.5, 10.0, 81.0),
        (1024, 5.8, 9.1, 56.0),
        (2048, 7.4, 10.7, 44.0),
        (4096, 14.2, 18.1, 27.0),
    ];
    let configs: Vec<(&str, MethodOptions)> = paper
        .iter()
        .flat_map(|&(map, ..)| {
            let o = MethodOptions { map_res: Some(map), ..gpu() };
            [("sm", o.clone()), ("spsm", o)]
        })
        .collect();
    let timed = time_all(&bunny, w, h, &configs, runs);
    let ms =
        |t: &Timed| t.as_ref().map_or_else(|e| format!("n/a ({e})"), |t| format!("{:.2}", t.0));
    for ((map, paper_sm, paper_spsm, paper_overhead), pair) in
        paper.into_iter().zip(timed.chunks(2))
    {
        let [sm, spsm] = pair else { unreachable!("two configurations per map size") };
        let overhead = match (sm, spsm) {
            (Ok((sm, _)), Ok((spsm, _))) => format!("{:.0} %", 100.0 * (spsm / sm - 1.0)),
            _ => "n/a".to_owned(),
        };
        println!(
            "| {map} | {} | {} | {overhead} | {paper_sm} | {paper_spsm} | {paper_overhead} % |",
            ms(sm),
            ms(spsm)
        );
    }
}

/// The shared options on the GPU.
fn gpu() -> MethodOptions {
    MethodOptions { device: Device::Gpu, ..MethodOptions::default() }
}

/// The built-in scene `name`, or the end of the bench with the reason.
fn load(name: &str) -> Scene {
    scenes::load(name).unwrap_or_else(|e| {
        eprintln!("gpu-bench: {name}: {e} (scripts/fetch-models fetches the models)");
        std::process::exit(1);
    })
}

/// The two results of a two-configuration measurement.
fn two(timed: Vec<Timed>) -> [Timed; 2] {
    timed.try_into().unwrap_or_else(|_| unreachable!("two configurations, two results"))
}

/// Each `(method, options)` of `configs` on one frame of `scene` at `w x h`, interleaved: one
/// warm-up, then `runs` timed runs each, on the wall clock (see the module documentation).
fn time_all(
    scene: &Scene,
    w: u32,
    h: u32,
    configs: &[(&str, MethodOptions)],
    runs: usize,
) -> Vec<Timed> {
    let frame = Frame::new(scene, w, h, &mut Recorder::default());
    let built: Vec<_> = configs
        .iter()
        .map(|(name, options)| method(name, options).map_err(|e| e.to_string()))
        .collect();
    let mut subjects: Vec<_> = built
        .iter()
        .map(|m| {
            let frame = &frame;
            move |rec: &mut Recorder| match m {
                Ok(m) => m.run(frame, rec).map(|_| ()).map_err(|e| e.to_string()),
                Err(e) => Err(e.clone()),
            }
        })
        .collect();
    let protocol = Protocol { clock: Clock::Wall, ..common::protocol(runs) };
    measure_all(&protocol, &mut subjects, |_, _| {})
        .into_iter()
        .map(|r| {
            r.map(|m| {
                let gbuffer: f64 = m
                    .stages
                    .iter()
                    .filter(|s| s.name == STAGE_GPU_GBUFFER)
                    .map(|s| s.ms.median)
                    .sum();
                (m.wall_ms.median - gbuffer, m.wall_ms.median)
            })
        })
        .collect()
}

/// One row of the targets' table.
fn row(what: &str, t: &Timed, paper: &str) {
    match t {
        Ok((own, with)) => println!("| {what} | {own:.2} | {with:.2} | {paper} |"),
        Err(e) => println!("| {what} | n/a ({e}) | | {paper} |"),
    }
}
