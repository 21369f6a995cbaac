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
//! lookup table built beforehand as the paper precomputes it.
//!
//! Timing: through the workbench's one timing loop, `instrumentation::measure::measure_all`,
//! under `Protocol::fixed(1, runs)`: one untimed warm-up each, then `SHADOWBENCH_BENCH_RUNS`
//! timed runs (default 5 for `pan09`, 3 for `afsm-ss`, whose runs take seconds). The rates of
//! one method are interleaved, round by round, on the frame: one `measure_all` over the seven
//! `pan09` configurations, then one over the seven `afsm-ss` ones. A method's time is the
//! wall-clock median of its per-run stage sums (`Measured::wall_ms`); beside it, the median CPU
//! time of the process's threads over a run (`Measured::cpu_ms`, the rayon pool included).
//!
//! Targets: `pan09` at 32 at least 10 times faster than `afsm-ss` at 32 (the paper's "an
//! order of magnitude"), and `pan09` at 128 at most 1.6 times its own time at 32.
//!
//! `cargo bench -p shadowbench-methods --bench pan09_fig10` prints the Markdown table.

mod common;

use instrumentation::{
    measure::{measure_all, Measured},
    Recorder,
};
use methods::{
    afsm::{AfsmOptions, AliasFreeShadowMap},
    pan09::{Pan09, Pan09Options},
    Frame, ShadowMethod,
};

const WIDTH: u32 = 800;
const HEIGHT: u32 = 600;
const RATES: [u32; 7] = [1, 4, 8, 16, 32, 64, 128];

/// Wall-clock and CPU medians (ms) of one configuration.
#[derive(Clone, Copy)]
struct Times {
    wall: f64,
    cpu: Option<f64>,
}

impl Times {
    fn of(m: &Measured<()>) -> Self {
        Self { wall: m.wall_ms.median, cpu: m.cpu_ms.map(|c| c.median) }
    }
}

/// `methods` on `frame`, interleaved under one warm-up and `runs` timed runs each.
fn time_all(
    what: &str,
    methods: &[Box<dyn ShadowMethod>],
    frame: &Frame<'_>,
    runs: usize,
) -> Result<Vec<Times>, String> {
    let mut subjects: Vec<_> = methods
        .iter()
        .map(|method| {
            move |rec: &mut Recorder| method.run(frame, rec).map(|_| ()).map_err(|e| e.to_string())
        })
        .collect();
    let results = measure_all(&common::protocol(runs), &mut subjects, |k, _| {
        eprintln!("{what} at rate {} measured", RATES[k]);
    });
    results.into_iter().map(|r| r.map(|m| Times::of(&m))).collect()
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
    let mut pans: Vec<Box<dyn ShadowMethod>> = Vec::new();
    let mut sss: Vec<Box<dyn ShadowMethod>> = Vec::new();
    for rate in RATES {
        let pan = Pan09::new(Pan09Options { rate, ..Pan09Options::default() })
            .map_err(|e| e.to_string())?;
        pans.push(Box::new(pan));
        let ss =
            AliasFreeShadowMap::supersampled(AfsmOptions { rate, ..AfsmOptions::supersampled() });
        sss.push(Box::new(ss));
    }
    let (pan_runs, ss_runs) = (common::runs(5), common::runs(3));
    let ours = time_all("pan09", &pans, &frame, pan_runs)?;
    let theirs = time_all("afsm-ss", &sss, &frame, ss_runs)?;
    let rows: Vec<(u32, Times, Times)> =
        RATES.iter().zip(ours.iter().zip(&theirs)).map(|(&r, (&o, &t))| (r, o, t)).collect();
    println!(
        "Fig. 10 on `{}` at {WIDTH}x{HEIGHT}: pan09 (map 512, table) and afsm-ss, {} on {} \
         threads; wall-clock medians of {pan_runs} (pan09) and {ss_runs} (afsm-ss) runs after one \
         warm-up (instrumentation::measure, each method's rates interleaved); CPU time of the \
         process's threads beside. Paper: pterosaur scene, NVIDIA GTX 280, ours vs GPU \
         alias-free shadow maps [SEA08] + supersampling (no 128x: framebuffer limit).\n",
        scene.name,
        instrumentation::cpu_model(),
        rayon::current_num_threads()
    );
    println!(
        "| Sub-samples | pan09 (ms) | afsm-ss (ms) | afsm-ss / pan09 | pan09 CPU (ms) \
         | afsm-ss CPU (ms) |"
    );
    println!("|---:|---:|---:|---:|---:|---:|");
    for (rate, ours, theirs) in &rows {
        println!(
            "| {rate} | {:.1} | {:.1} | {:.1} | {} | {} |",
            ours.wall,
            theirs.wall,
            theirs.wall / ours.wall,
            common::ms_or_dash(ours.cpu),
            common::ms_or_dash(theirs.cpu)
        );
    }
    let at = |r: u32| rows.iter().find(|row| row.0 == r).map_or(f64::NAN, |row| row.1.wall);
    let ss32 = rows.iter().find(|row| row.0 == 32).map_or(f64::NAN, |row| row.2.wall);
    println!(
        "\nafsm-ss / pan09 at 32: {:.1} (target >= 10; paper: \"an order of magnitude faster\"). \
         pan09 at 128 / pan09 at 32: {:.2} (target <= 1.6; paper: twice the samples only double \
         the bit depth of the masks).",
        ss32 / at(32),
        at(128) / at(32)
    );
    Ok(())
}
