//! Fig. 10 of Pan et al. 2009 (section 5.1, "Scalability"): the time of `pan09` and of
//! alias-free shadow maps with supersampling (`afsm-ss`) at 1, 4, 8, 16, 32, 64 and 128
//! sub-samples per pixel, measured side by side in one run on one scene at 800 x 600.
//!
//! The paper's scene is its pterosaur (10 000 triangles), which the workbench does not have;
//! we use `bunny-plane` (one scanned model over a plane, like the paper's), or `cage` when the
//! bunny's model is missing (`scripts/fetch-models`). Both methods run on the same frame
//! (the camera G-buffer is rendered once and not timed); a method's time is the sum of its
//! stages, `afsm-ss`'s including the G-buffers of its extra sub-samples (part of
//! supersampling). `pan09` runs with its defaults (512 map, lookup table, grid pattern), the
//! lookup table built beforehand as the paper precomputes it. One warm-up run each, then the
//! median of `SHADOWBENCH_BENCH_RUNS` runs (default 5 for `pan09`, 3 for `afsm-ss`, whose
//! runs take seconds).
//!
//! Targets: `pan09` at 32 at least 10 times faster than `afsm-ss` at 32 (the paper's "an
//! order of magnitude"), and `pan09` at 128 at most 1.6 times its own time at 32.
//!
//! `cargo bench -p shadowbench-methods --bench pan09_fig10` prints the Markdown table.

mod common;

use instrumentation::Recorder;
use methods::{
    afsm::{AfsmOptions, AliasFreeShadowMap},
    pan09::{Pan09, Pan09Options},
    Frame, ShadowMethod,
};

const WIDTH: u32 = 800;
const HEIGHT: u32 = 600;
const RATES: [u32; 7] = [1, 4, 8, 16, 32, 64, 128];

/// Median total stage time of `runs` runs after one warm-up.
fn time(method: &dyn ShadowMethod, frame: &Frame<'_>, runs: usize) -> Result<f64, String> {
    let mut ms = Vec::new();
    for run in 0..=runs {
        let mut rec = Recorder::default();
        method.run(frame, &mut rec).map_err(|e| e.to_string())?;
        if run > 0 {
            ms.push(rec.stages.total_ms());
        }
    }
    Ok(common::median(ms))
}

fn main() -> Result<(), String> {
    let scene = match scenes::load("bunny-plane") {
        Ok(s) => s,
        Err(e) => {
            eprintln!("bunny-plane unavailable ({e}); using cage");
            scenes::load("cage").map_err(|e| e.to_string())?
        }
    };
    let frame = Frame::new(&scene, WIDTH, HEIGHT, &mut Recorder::default());
    let mut rows = Vec::new();
    for rate in RATES {
        let pan = Pan09::new(Pan09Options { rate, ..Pan09Options::default() })
            .map_err(|e| e.to_string())?;
        let ours = time(&pan, &frame, common::runs(5))?;
        let ss =
            AliasFreeShadowMap::supersampled(AfsmOptions { rate, ..AfsmOptions::supersampled() });
        let theirs = time(&ss, &frame, common::runs(3))?;
        eprintln!("rate {rate}: pan09 {ours:.1} ms, afsm-ss {theirs:.1} ms");
        rows.push((rate, ours, theirs));
    }
    println!(
        "Fig. 10 on `{}` at {WIDTH}x{HEIGHT}: pan09 (map 512, table) and afsm-ss, {} on {} \
         threads; medians after one warm-up. Paper: pterosaur scene, NVIDIA GTX 280, ours vs \
         GPU alias-free shadow maps [SEA08] + supersampling (no 128x: framebuffer limit).\n",
        scene.name,
        instrumentation::cpu_model(),
        rayon::current_num_threads()
    );
    println!("| Sub-samples | pan09 (ms) | afsm-ss (ms) | afsm-ss / pan09 |");
    println!("|---:|---:|---:|---:|");
    for (rate, ours, theirs) in &rows {
        println!("| {rate} | {ours:.1} | {theirs:.1} | {:.1} |", theirs / ours);
    }
    let at = |r: u32| rows.iter().find(|row| row.0 == r).map_or(f64::NAN, |row| row.1);
    let ss32 = rows.iter().find(|row| row.0 == 32).map_or(f64::NAN, |row| row.2);
    println!(
        "\nafsm-ss / pan09 at 32: {:.1} (target >= 10; paper: \"an order of magnitude faster\"). \
         pan09 at 128 / pan09 at 32: {:.2} (target <= 1.6; paper: twice the samples only double \
         the bit depth of the masks).",
        ss32 / at(32),
        at(128) / at(32)
    );
    Ok(())
}
