//! The timing protocol: untimed warm-up runs, then repeated timed runs summarised by median,
//! minimum and maximum, for the whole method and for each of its stages; and the machine the
//! times were taken on.

use instrumentation::Recorder;
use methods::{Frame, ShadowMethod, Visibility};
use serde::{Deserialize, Serialize};

/// Median, minimum and maximum of repeated measurements, in milliseconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Median (mean of the two middle values for an even count).
    pub median: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

impl Summary {
    /// Summarises `values`; `None` when there are none.
    pub fn of(values: &[f64]) -> Option<Self> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let median = if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) };
        Some(Self { median, min: v[0], max: v[n - 1] })
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
