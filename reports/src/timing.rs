//! The timing protocol: untimed warm-up runs, then repeated timed runs summarised by median,
//! minimum and maximum, for the whole method and for each of its stages; and the machine the
//! times were taken on.
//!
//! The median comes with a 95 % confidence interval from a percentile bootstrap (Efron and
//! Tibshirani, *An Introduction to the Bootstrap*, Chapman & Hall 1993, section 13.3):
//! [`BOOTSTRAP_RESAMPLES`] resamples of the timed runs drawn with replacement, each resample's
//! median taken, and the interval's ends are the 2.5th and 97.5th percentiles of those
//! medians. The resamples are drawn from a generator with a fixed seed ([`BOOTSTRAP_SEED`]), so
//! the same times give the same interval and a report is reproducible from its times. The
//! interval never leaves [min, max]; with few timed runs (a suite's `repeats` below about 5)
//! it is wide and coarse, and with one run it is that run's time.

use instrumentation::Recorder;
use methods::{Frame, ShadowMethod, Visibility};
use serde::{Deserialize, Serialize};

/// Resamples of the bootstrap confidence interval of a median.
pub const BOOTSTRAP_RESAMPLES: usize = 1000;

/// Seed of the bootstrap's generator, fixed so that intervals are reproducible.
pub const BOOTSTRAP_SEED: u64 = 0x5eed_b007;

/// Median with its bootstrap 95 % confidence interval, minimum and maximum of repeated
/// measurements, in milliseconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Median (mean of the two middle values for an even count).
    pub median: f64,
    /// Lower end of the median's 95 % confidence interval (percentile bootstrap).
    pub ci_low: f64,
    /// Upper end of the median's 95 % confidence interval (percentile bootstrap).
    pub ci_high: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

/// Median of sorted values (mean of the two middle values for an even count); `v` not empty.
fn median_of_sorted(v: &[f64]) -> f64 {
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The 95 % percentile-bootstrap confidence interval of the median of `v` (not empty).
fn bootstrap_median_ci(v: &[f64]) -> (f64, f64) {
    let mut rng = fastrand::Rng::with_seed(BOOTSTRAP_SEED);
    let mut resample = vec![0.0; v.len()];
    let mut medians: Vec<f64> = (0..BOOTSTRAP_RESAMPLES)
        .map(|_| {
            for x in &mut resample {
                *x = v[rng.usize(..v.len())];
            }
            resample.sort_by(f64::total_cmp);
            median_of_sorted(&resample)
        })
        .collect();
    medians.sort_by(f64::total_cmp);
    let tail = BOOTSTRAP_RESAMPLES * 25 / 1000;
    (medians[tail], medians[BOOTSTRAP_RESAMPLES - 1 - tail])
}

impl Summary {
    /// Summarises the finite ones of `values`; `None` when there are none.
    pub fn of(values: &[f64]) -> Option<Self> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let (ci_low, ci_high) = bootstrap_median_ci(&v);
        Some(Self { median: median_of_sorted(&v), ci_low, ci_high, min: v[0], max: v[v.len() - 1] })
    }
}

/// One stage's times over the timed runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageTimes {
    /// Stage name.
    pub name: String,
    /// Its times.
    pub ms: Summary,
}

/// Per-stage summaries of repeated runs, stages in the order of the first run.
pub fn stage_summaries(runs: &[Vec<instrumentation::Stage>]) -> Vec<StageTimes> {
    let Some(first) = runs.first() else { return Vec::new() };
    first
        .iter()
        .filter_map(|stage| {
            let times: Vec<f64> = runs
                .iter()
                .filter_map(|r| r.iter().find(|s| s.name == stage.name).map(|s| s.ms))
                .collect();
            Summary::of(&times).map(|ms| StageTimes { name: stage.name.clone(), ms })
        })
        .collect()
}

/// What the timed runs of one method on one frame gave.
pub struct Timed {
    /// The last timed run's result (every method is deterministic for its parameters).
    pub visibility: Visibility,
    /// The last timed run's record: counters, notes, skipped stages.
    pub record: Recorder,
    /// Total of the method's stages.
    pub total_ms: Summary,
    /// Each stage.
    pub stages: Vec<StageTimes>,
}

/// Runs `method` on `frame` `warmup` times untimed, then `repeats` times timed (at least one).
/// The error is the method's own, as text.
pub fn time_method(
    method: &dyn ShadowMethod,
    frame: &Frame<'_>,
    warmup: u32,
    repeats: u32,
) -> Result<Timed, String> {
    let mut stage_runs = Vec::new();
    let mut totals = Vec::new();
    let mut last = None;
    for k in 0..warmup + repeats.max(1) {
        let mut rec = Recorder::default();
        let v = method.run(frame, &mut rec).map_err(|e| e.to_string())?;
        if k >= warmup {
            totals.push(rec.stages.total_ms());
            stage_runs.push(rec.stages.stages.clone());
            last = Some((v, rec));
        }
    }
    let (Some((visibility, record)), Some(total_ms)) = (last, Summary::of(&totals)) else {
        return Err("no timed run gave a finite time".into());
    };
    Ok(Timed { visibility, record, total_ms, stages: stage_summaries(&stage_runs) })
}

/// The machine the times were taken on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Machine {
    /// CPU model, from `/proc/cpuinfo` where available.
    pub cpu: String,
    /// Logical cores available to the process.
    pub cores: usize,
    /// Worker threads of the parallel runtime.
    pub threads: usize,
    /// GPU adapter, when a method ran on the GPU (`device = ["gpu"]`).
    pub gpu: Option<String>,
    /// Operating system and architecture.
    pub os: String,
}

impl Machine {
    /// Reads the current machine.
    pub fn current() -> Self {
        Self {
            cpu: instrumentation::cpu_model(),
            cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
            threads: rayon::current_num_threads(),
            gpu: None,
            os: format!("{} {}", std::env::consts::OS, std::env::consts::ARCH),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_min_max() {
        let s = Summary::of(&[3.0, 1.0, 2.0]).expect("values");
        assert_eq!((s.median, s.min, s.max), (2.0, 1.0, 3.0));
        let s = Summary::of(&[4.0, 1.0, 2.0, 3.0]).expect("values");
        assert_eq!(s.median, 2.5);
        assert_eq!(Summary::of(&[]), None);
    }

    #[test]
    fn the_median_interval_is_reproducible_and_within_the_range() {
        let times: Vec<f64> = (0..20).map(|k| 10.0 + ((k * 7) % 20) as f64).collect();
        let s = Summary::of(&times).expect("values");
        assert_eq!(Summary::of(&times), Some(s), "a fixed seed: the same interval");
        assert!(s.min <= s.ci_low && s.ci_low <= s.median, "{s:?}");
        assert!(s.median <= s.ci_high && s.ci_high <= s.max, "{s:?}");
        // 20 evenly spread values: the median's interval is narrower than the range.
        assert!(s.ci_high - s.ci_low < 0.6 * (s.max - s.min), "{s:?}");
        let one = Summary::of(&[4.0]).expect("a value");
        assert_eq!((one.ci_low, one.ci_high), (4.0, 4.0));
        let same = Summary::of(&[3.0; 9]).expect("values");
        assert_eq!((same.ci_low, same.ci_high), (3.0, 3.0));
    }

    #[test]
    fn stages_are_summarised_by_name() {
        let stage = |name: &str, ms| instrumentation::Stage { name: name.into(), ms };
        let runs = vec![
            vec![stage("a", 1.0), stage("b", 10.0)],
            vec![stage("a", 3.0), stage("b", 30.0)],
            vec![stage("a", 2.0), stage("b", 20.0)],
        ];
        let s = stage_summaries(&runs);
        assert_eq!(s.len(), 2);
        assert_eq!((s[0].name.as_str(), s[0].ms.median), ("a", 2.0));
        assert_eq!((s[1].ms.min, s[1].ms.max), (10.0, 30.0));
    }
}
