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
//! `cargo bench -p shadowbench-methods --bench gpu_bench [-- --quick]`. Each configuration
//! runs once to warm up (pipelines compiled, buffers first touched), then `RUNS` times
//! (`SHADOWBENCH_BENCH_RUNS`, default 5); the median of the method's own stages is reported,
//! the GPU G-buffer (shared by every method) apart. `--quick` divides every frame side by 8 and
//! uses `random-10k` for `random-1m`, to check the bench itself on a software adapter. A
//! software adapter is named as such in the header and in a warning: its times say nothing of
//! a GPU's.

mod common;

use instrumentation::Recorder;
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
        "GPU: {}{}; timing by {}; warm-up 1 run, median of {runs}{}",
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
    let (w, h) = (side(800), side(600));
    let pan = time(&bunny, w, h, "pan09", &pan_opts, runs);
    row(
        &format!("pan09 32x, {} {w}x{h}, map 512", bunny.name),
        &pan,
        "Pan et al.: 22 ms (GTX 280); target < 2 ms",
    );
    let ss = time(&bunny, w, h, "afsm-ss", &MethodOptions { rate: Some(32), ..gpu() }, runs);
    let ratio = match (&ss, &pan) {
        (Ok((ss, _)), Ok((pan, _))) => format!("{:.1}x pan09 32x", ss / pan),
        _ => "n/a".to_owned(),
    };
    row(&format!("afsm-ss 32x, {} {w}x{h}", bunny.name), &ss, &ratio);
    let (w, h) = (side(1024), side(768));
    let afsm = time(&random, w, h, "afsm", &gpu(), runs);
    row(
        &format!("afsm, {} {w}x{h}", random.name),
        &afsm,
        "Aila & Laine: 8640 ms (P4 1.6 GHz); target < 10 ms",
    );

    let (w, h) = (side(1920), side(1080));
    println!("\nLecocq et al. Table 2 on {} {w}x{h} (paper: YeahRight, GTX 580)", bunny.name);
    println!("| map | sm (ms) | spsm (ms) | overhead | paper sm | paper spsm | paper overhead |");
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    for (map, paper_sm, paper_spsm, paper_overhead) in [
        (512, 5.5, 10.0, 81.0),
        (1024, 5.8, 9.1, 56.0),
        (2048, 7.4, 10.7, 44.0),
        (4096, 14.2, 18.1, 27.0),
    ] {
        let o = MethodOptions { map_res: Some(map), ..gpu() };
        let ms =
            |t: &Timed| t.as_ref().map_or_else(|e| format!("n/a ({e})"), |t| format!("{:.2}", t.0));
        let sm = time(&bunny, w, h, "sm", &o, runs);
        let spsm = time(&bunny, w, h, "spsm", &o, runs);
        let overhead = match (&sm, &spsm) {
            (Ok((sm, _)), Ok((spsm, _))) => format!("{:.0} %", 100.0 * (spsm / sm - 1.0)),
            _ => "n/a".to_owned(),
        };
        println!(
            "| {map} | {} | {} | {overhead} | {paper_sm} | {paper_spsm} | {paper_overhead} % |",
            ms(&sm),
            ms(&spsm)
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

/// `name` with `options` on `scene` at `w x h`: one warm-up, then the median of `runs`.
fn time(scene: &Scene, w: u32, h: u32, name: &str, options: &MethodOptions, runs: usize) -> Timed {
    let frame = Frame::new(scene, w, h, &mut Recorder::default());
    let m = method(name, options).map_err(|e| e.to_string())?;
    let mut own = Vec::with_capacity(runs);
    let mut with = Vec::with_capacity(runs);
    for run in 0..=runs {
        let mut rec = Recorder::default();
        m.run(&frame, &mut rec).map_err(|e| e.to_string())?;
        if run > 0 {
            let total = rec.stages.total_ms();
            let g: f64 = rec
                .stages
                .stages
                .iter()
                .filter(|s| s.name == STAGE_GPU_GBUFFER)
                .map(|s| s.ms)
                .sum();
            own.push(total - g);
            with.push(total);
        }
    }
    Ok((common::median(own), common::median(with)))
}

/// One row of the targets' table.
fn row(what: &str, t: &Timed, paper: &str) {
    match t {
        Ok((own, with)) => println!("| {what} | {own:.2} | {with:.2} | {paper} |"),
        Err(e) => println!("| {what} | n/a ({e}) | | {paper} |"),
    }
}
