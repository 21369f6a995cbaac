//! What the benchmarks share: the median of their runs and the number of runs.

/// Median of `v` (mean of the two middle values for an even count); NaN when empty.
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Timed runs per configuration: `SHADOWBENCH_BENCH_RUNS` when it is a positive number, else
/// `default`.
pub fn runs(default: usize) -> usize {
    std::env::var("SHADOWBENCH_BENCH_RUNS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .filter(|&r| r > 0)
        .unwrap_or(default)
}
