//! What the benchmarks share: the number of timed runs, and the protocol they are timed under.
//!
//! Every bench times through the workbench's one timing loop,
//! [`instrumentation::measure::measure`] (or `measure_all`, its configurations of one frame
//! interleaved round by round), under [`protocol`]: one untimed warm-up, then exactly
//! `SHADOWBENCH_BENCH_RUNS` timed runs (a contended run retried once in its place). Its
//! medians are the engine's ([`instrumentation::stats::Summary`]).

use instrumentation::measure::Protocol;

/// Timed runs per configuration: `SHADOWBENCH_BENCH_RUNS` when it is a positive number, else
/// `default`.
pub fn runs(default: usize) -> usize {
    std::env::var("SHADOWBENCH_BENCH_RUNS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .filter(|&r| r > 0)
        .unwrap_or(default)
}

/// One warm-up run, then exactly `runs` timed runs.
pub fn protocol(runs: usize) -> Protocol {
    Protocol::fixed(1, u32::try_from(runs).unwrap_or(u32::MAX))
}

/// `ms` with one decimal, or `–` where the clock gave none.
#[allow(dead_code)] // Not every bench prints a CPU time.
pub fn ms_or_dash(ms: Option<f64>) -> String {
    ms.map_or_else(|| "–".to_owned(), |ms| format!("{ms:.1}"))
}
