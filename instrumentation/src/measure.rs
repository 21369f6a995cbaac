//! The measurement engine: the one timing loop of the workbench. `render`, `compare`, a
//! report's sweep, the papers' tables, the benchmarks and the Embree side-by-side all time
//! their runs here, under one [`Protocol`].
//!
//! The protocol, for a set of subjects (the runs of one scene, or a single run):
//!
//! 1. **Warm-up**: each subject runs [`Protocol::warmup`] times untimed.
//! 2. **Rounds, interleaved**: each round runs every subject not yet done once, in turn, so
//!    that a drift of the machine (another job starting, the clock frequency falling) reaches
//!    every subject alike rather than the ones that happened to run late.
//! 3. **Each timed run** records the wall time of its stages (their sum, as `total_ms`
//!    always was) and their CPU time ([`clock::cpu_now`]: every thread, the rayon pool
//!    included; over the whole call where a stage came from a GPU's timestamps), the CPU share of its threads from the run queue
//!    ([`clock::Schedule`]) and the machine's load ([`clock::Load`]). A run whose share is
//!    below [`Protocol::min_share`] is **contended**: it is run once more in its place
//!    ([`Protocol::retry_contended`]), and kept marked contended when the retry is too.
//! 4. **Adaptive stop**: a subject is done after [`Protocol::max_repeats`] timed runs, or
//!    once it has [`Protocol::min_repeats`] and its median on [`Protocol::clock`] has a
//!    confidence interval ([`crate::stats`]) whose half-width is at most
//!    [`Protocol::target_half_width`] of the median, or once it has `min_repeats` and the
//!    rounds have taken longer than [`Protocol::time_cap`].
//!
//! A [`Measured`] keeps every timed run's figures ([`Sample`]), the summaries of both clocks,
//! per stage too, the record of the run of median time on the protocol's clock (its counters,
//! notes and warnings: every method is deterministic for its parameters) and the output of
//! the last run. A subject that fails is left out of later rounds; its error is its result.

use crate::clock::{self, Load, Schedule};
use crate::stats::Summary;
use crate::{Recorder, Stage};
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// Which clock a figure is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Clock {
    /// CPU time of the process's threads: what the work cost, little moved by other work on
    /// the machine.
    #[default]
    Cpu,
    /// Wall-clock time: what a user waits, moved by everything else the machine runs.
    Wall,
}

impl Clock {
    /// `cpu` or `wall`.
    pub fn name(self) -> &'static str {
        match self {
            Clock::Cpu => "cpu",
            Clock::Wall => "wall",
        }
    }

    /// How the clock's figures are taken, for a run record or a page.
    pub fn describe(self) -> &'static str {
        match self {
            Clock::Cpu => "CPU time of the process's threads (the rayon pool included)",
            Clock::Wall => "wall-clock time",
        }
    }
}

impl std::str::FromStr for Clock {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "cpu" => Ok(Clock::Cpu),
            "wall" => Ok(Clock::Wall),
            _ => Err(format!("`{s}` is not a clock; known: cpu, wall")),
        }
    }
}

/// How runs are timed (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Protocol {
    /// Untimed runs of each subject before the timed ones. Default 1.
    pub warmup: u32,
    /// Timed runs each subject has at least. Default 6, the fewest whose median has a 95 %
    /// interval ([`crate::stats::MIN_VALUES_FOR_INTERVAL`]).
    pub min_repeats: u32,
    /// Timed runs each subject has at most. Default 30.
    pub max_repeats: u32,
    /// The interval's half-width, relative to the median, at which a subject is done. Default
    /// 0.05.
    pub target_half_width: f64,
    /// The clock whose interval decides the stop. Default CPU time.
    pub clock: Clock,
    /// After this long in the timed rounds, subjects with `min_repeats` runs are done whatever
    /// their interval. Default 20 s.
    pub time_cap: Duration,
    /// The CPU share below which a run is contended. Default 0.55: in one run of the `quick`
    /// suite on an idle 2-core machine the lowest share of a run's timed runs was 0.87 at the
    /// median and 0.62 at the 5th percentile (the process competes with itself: the rayon
    /// pool's threads spin briefly beside the main thread after a parallel stage), and with
    /// one core kept busy by another process it was 0.46 at the median and 0.51 at the 95th
    /// percentile.
    pub min_share: f64,
    /// Whether a contended run is run once more in its place. Default true.
    pub retry_contended: bool,
}

impl Default for Protocol {
    fn default() -> Self {
        Self {
            warmup: 1,
            min_repeats: 6,
            max_repeats: 30,
            target_half_width: 0.05,
            clock: Clock::Cpu,
            time_cap: Duration::from_secs(20),
            min_share: 0.55,
            retry_contended: true,
        }
    }
}

impl Protocol {
    /// Exactly `repeats` timed runs (at least one) after `warmup` untimed ones, as a command
    /// line's `--repeat` asks; contended runs are still retried once.
    pub fn fixed(warmup: u32, repeats: u32) -> Self {
        let repeats = repeats.max(1);
        Self { warmup, min_repeats: repeats, max_repeats: repeats, ..Self::default() }
    }
}

/// One timed run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Wall-clock time of the run's stages, summed, milliseconds.
    pub wall_ms: f64,
    /// CPU time of the process's threads over the run's stages, milliseconds (over the whole
    /// run where a stage was timed on another clock, a GPU's timestamps); `None` where the
    /// clock is unavailable.
    pub cpu_ms: Option<f64>,
    /// The CPU share of the process's threads over the run ([`Schedule::share_since`]).
    pub share: Option<f64>,
    /// The share was below the protocol's threshold (after the retry, when there was one).
    pub contended: bool,
    /// The run is a retry of a contended one.
    pub retried: bool,
}

impl Sample {
    /// The run's time on `clock`, milliseconds (wall time where CPU time is unavailable).
    pub fn on(&self, clock: Clock) -> f64 {
        match clock {
            Clock::Cpu => self.cpu_ms.unwrap_or(self.wall_ms),
            Clock::Wall => self.wall_ms,
        }
    }
}

/// The machine's condition over a subject's timed runs.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Conditions {
    /// 1-minute load average before the first timed run.
    pub loadavg_before: Option<f64>,
    /// 1-minute load average after the last timed run.
    pub loadavg_after: Option<f64>,
    /// Share of the machine's cores other processes took during the timed runs (`/proc/stat`,
    /// 10 ms jiffies: coarse over short runs).
    pub others_share: Option<f64>,
    /// Share of the machine's cores the hypervisor took (steal) during the timed runs.
    pub steal_share: Option<f64>,
    /// The lowest CPU share of a kept run.
    pub min_share: Option<f64>,
    /// Logical cores of the machine.
    pub cores: usize,
}

/// One stage's times over the timed runs, on both clocks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageTimes {
    /// Stage name.
    pub name: String,
    /// Its wall-clock times.
    pub ms: Summary,
    /// Its CPU times, where every run timed it on the CPU.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpu_ms: Option<Summary>,
}

/// What the timed runs of one subject gave.
#[derive(Debug, Clone)]
pub struct Measured<T> {
    /// The last timed run's output.
    pub output: T,
    /// The record of the timed run of median time on the protocol's clock (the lower middle
    /// one for an even count): counters, stages, notes, warnings.
    pub record: Recorder,
    /// Wall-clock totals.
    pub wall_ms: Summary,
    /// CPU totals; `None` where the clock is unavailable.
    pub cpu_ms: Option<Summary>,
    /// Each stage, in the order of the first timed run.
    pub stages: Vec<StageTimes>,
    /// Every timed run kept, in order.
    pub samples: Vec<Sample>,
    /// The machine over the timed runs.
    pub conditions: Conditions,
    /// The protocol's clock, on which the record was chosen.
    pub clock: Clock,
    /// Index in `samples` of the run whose record is kept.
    pub chosen: usize,
}

/// How a run record's times were taken (`run.json`'s `timing`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    /// The clock on which the record's run was chosen as the median one.
    pub chosen_by: Clock,
    /// Untimed warm-up runs before the timed ones.
    pub warmup: u32,
    /// Wall-clock totals of the timed runs.
    pub wall_ms: Summary,
    /// CPU totals of the timed runs.
    pub cpu_ms: Option<Summary>,
    /// Whether a kept run was contended.
    pub contended: bool,
    /// Every timed run kept.
    pub samples: Vec<Sample>,
    /// The machine over the timed runs.
    pub conditions: Conditions,
}

impl<T> Measured<T> {
    /// The run record of the kept run for `who`, with its CPU time and how it was timed
    /// (`warmup`: the protocol's warm-up runs).
    pub fn run_record(&self, who: crate::RunIdentity, warmup: u32) -> crate::RunRecord {
        let mut record = self.record.clone().into_record(who);
        record.cpu_ms = self.samples[self.chosen].cpu_ms;
        record.timing = Some(Timing {
            chosen_by: self.clock,
            warmup,
            wall_ms: self.wall_ms,
            cpu_ms: self.cpu_ms,
            contended: self.contended(),
            samples: self.samples.clone(),
            conditions: self.conditions,
        });
        record
    }
}

impl<T> Measured<T> {
    /// Whether a kept run was contended (see [`Sample::contended`]).
    pub fn contended(&self) -> bool {
        self.samples.iter().any(|s| s.contended)
    }
}

/// One subject's progress through the rounds.
struct State<T, E> {
    failed: Option<E>,
    done: bool,
    /// Wall time of every call so far, warm-up runs and retries included.
    spent: Duration,
    samples: Vec<Sample>,
    records: Vec<Recorder>,
    output: Option<T>,
    loadavg_before: Option<f64>,
    loadavg_after: Option<f64>,
    others_s: f64,
    steal_s: f64,
    capacity_s: f64,
}

/// What one timed call gave: its output, record and figures, the machine's busy and stolen
/// core-seconds and capacity over it, and the load average before and after.
type Once<T> = (T, Recorder, Sample, (f64, f64, f64), Option<f64>, Option<f64>);

/// One timed call of `subject` ([`Once`]).
fn timed_once<T, E>(
    subject: &mut impl FnMut(&mut Recorder) -> Result<T, E>,
    min_share: f64,
    cores: usize,
) -> Result<Once<T>, E> {
    let load0 = Load::now();
    let sched0 = Schedule::now();
    let cpu0 = clock::cpu_now();
    let start = Instant::now();
    let mut rec = Recorder::default();
    let out = subject(&mut rec)?;
    let wall = start.elapsed();
    let cpu = cpu0.zip(clock::cpu_now()).map(|(a, b)| b.saturating_sub(a));
    let share = sched0.zip(Schedule::now()).and_then(|(a, b)| b.share_since(&a));
    let load1 = Load::now();
    let (mut others, mut steal) = (0.0, 0.0);
    if let (Some(a), Some(b)) = (load0, load1) {
        let capacity = wall.as_secs_f64() * cores as f64;
        others = b.others_since(&a, cpu.unwrap_or_default(), wall, cores).unwrap_or(0.0) * capacity;
        steal = b.steal_since(&a, wall, cores).unwrap_or(0.0) * capacity;
    }
    // Both clocks over the same span, the run's stages: their CPU times where every stage was
    // timed on the CPU, else (a stage from GPU timestamps) the process's over the whole call.
    let stage_cpu: Option<f64> = rec.stages.stages.iter().map(|s| s.cpu_ms).sum();
    let sample = Sample {
        wall_ms: rec.stages.total_ms(),
        cpu_ms: stage_cpu.or(cpu.map(|c| c.as_secs_f64() * 1e3)),
        share,
        contended: share.is_some_and(|s| s < min_share),
        retried: false,
    };
    let capacity = wall.as_secs_f64() * cores as f64;
    Ok((
        out,
        rec,
        sample,
        (others, steal, capacity),
        load0.map(|l| l.loadavg),
        load1.map(|l| l.loadavg),
    ))
}

/// Per-stage summaries of the records' stages, in the order of the first record's.
fn stage_times(records: &[Recorder]) -> Vec<StageTimes> {
    let Some(first) = records.first() else { return Vec::new() };
    first
        .stages
        .stages
        .iter()
        .filter_map(|stage| {
            let found: Vec<&Stage> = records
                .iter()
                .filter_map(|r| r.stages.stages.iter().find(|s| s.name == stage.name))
                .collect();
            let wall: Vec<f64> = found.iter().map(|s| s.ms).collect();
            let cpu: Option<Vec<f64>> = found.iter().map(|s| s.cpu_ms).collect();
            Summary::of(&wall).map(|ms| StageTimes {
                name: stage.name.clone(),
                ms,
                cpu_ms: cpu.and_then(|c| Summary::of(&c)),
            })
        })
        .collect()
}

/// Measures every subject under `protocol`, interleaved (see the module documentation);
/// `done(k, spent)` is called once subject `k` is measured or has failed, with the wall time
/// its calls took (warm-up runs and retries included), for estimates of the time left. Results
/// in the subjects'
/// order.
pub fn measure_all<T, E, F>(
    protocol: &Protocol,
    subjects: &mut [F],
    mut done: impl FnMut(usize, Duration),
) -> Vec<Result<Measured<T>, E>>
where
    F: FnMut(&mut Recorder) -> Result<T, E>,
{
    let cores = clock::cores();
    let mut states: Vec<State<T, E>> = subjects
        .iter()
        .map(|_| State {
            failed: None,
            done: false,
            spent: Duration::ZERO,
            samples: Vec::new(),
            records: Vec::new(),
            output: None,
            loadavg_before: None,
            loadavg_after: None,
            others_s: 0.0,
            steal_s: 0.0,
            capacity_s: 0.0,
        })
        .collect();
    for _ in 0..protocol.warmup {
        for (k, subject) in subjects.iter_mut().enumerate() {
            let state = &mut states[k];
            if state.failed.is_none() {
                let start = Instant::now();
                let result = subject(&mut Recorder::default());
                state.spent += start.elapsed();
                if let Err(e) = result {
                    state.failed = Some(e);
                    done(k, state.spent);
                }
            }
        }
    }
    let min = protocol.min_repeats.max(1) as usize;
    let max = (protocol.max_repeats.max(1) as usize).max(min);
    let start = Instant::now();
    loop {
        let mut any = false;
        for (k, subject) in subjects.iter_mut().enumerate() {
            let state = &mut states[k];
            if state.done || state.failed.is_some() {
                continue;
            }
            any = true;
            let start = Instant::now();
            let mut once = timed_once(subject, protocol.min_share, cores);
            if protocol.retry_contended && matches!(&once, Ok((_, _, s, ..)) if s.contended) {
                once = timed_once(subject, protocol.min_share, cores).map(|mut r| {
                    r.2.retried = true;
                    r
                });
            }
            state.spent += start.elapsed();
            match once {
                Ok((out, rec, sample, (others, steal, capacity), before, after)) => {
                    state.loadavg_before = state.loadavg_before.or(before);
                    state.loadavg_after = after.or(state.loadavg_after);
                    state.others_s += others;
                    state.steal_s += steal;
                    state.capacity_s += capacity;
                    state.output = Some(out);
                    state.records.push(rec);
                    state.samples.push(sample);
                }
                Err(e) => {
                    state.failed = Some(e);
                    done(k, state.spent);
                }
            }
        }
        if !any {
            break;
        }
        let capped = start.elapsed() > protocol.time_cap;
        for (k, state) in states.iter_mut().enumerate() {
            if state.done || state.failed.is_some() {
                continue;
            }
            let n = state.samples.len();
            let on_clock: Vec<f64> = state.samples.iter().map(|s| s.on(protocol.clock)).collect();
            let narrow = Summary::of(&on_clock)
                .and_then(|s| s.relative_half_width())
                .is_some_and(|w| w <= protocol.target_half_width);
            if n >= max || (n >= min && (narrow || capped)) {
                state.done = true;
                done(k, state.spent);
            }
        }
    }
    states.into_iter().map(|state| finish(state, protocol.clock, cores)).collect()
}

/// A subject's result from its state after the rounds.
fn finish<T, E>(state: State<T, E>, clock: Clock, cores: usize) -> Result<Measured<T>, E> {
    if let Some(e) = state.failed {
        return Err(e);
    }
    let State { samples, mut records, output, .. } = state;
    let wall: Vec<f64> = samples.iter().map(|s| s.wall_ms).collect();
    let cpu: Option<Vec<f64>> = samples.iter().map(|s| s.cpu_ms).collect();
    let (Some(output), Some(wall_ms)) = (output, Summary::of(&wall)) else {
        // Every subject runs at least one round unless it failed.
        unreachable!("a measured subject has at least one timed run")
    };
    let cpu_ms = cpu.as_deref().and_then(Summary::of);
    let stages = stage_times(&records);
    // The run of median time on the protocol's clock: its record is the one kept.
    let mut order: Vec<usize> = (0..samples.len()).collect();
    order.sort_by(|&a, &b| samples[a].on(clock).total_cmp(&samples[b].on(clock)));
    let chosen = order[(order.len() - 1) / 2];
    let record = records.swap_remove(chosen);
    let capacity = state.capacity_s;
    let conditions = Conditions {
        loadavg_before: state.loadavg_before,
        loadavg_after: state.loadavg_after,
        others_share: (capacity > 0.0).then(|| (state.others_s / capacity).clamp(0.0, 1.0)),
        steal_share: (capacity > 0.0).then(|| (state.steal_s / capacity).clamp(0.0, 1.0)),
        min_share: samples.iter().filter_map(|s| s.share).reduce(f64::min),
        cores,
    };
    Ok(Measured { output, record, wall_ms, cpu_ms, stages, samples, conditions, clock, chosen })
}

/// Measures one subject under `protocol`.
pub fn measure<T, E>(
    protocol: &Protocol,
    subject: impl FnMut(&mut Recorder) -> Result<T, E>,
) -> Result<Measured<T>, E> {
    let mut subjects = [subject];
    let mut results = measure_all(protocol, &mut subjects, |_, _| {});
    results.remove(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A subject whose runs take `ms` of busy work in one stage.
    fn busy(ms: f64) -> impl FnMut(&mut Recorder) -> Result<u32, String> {
        let mut calls = 0;
        move |rec: &mut Recorder| {
            calls += 1;
            rec.stages.time("work", || {
                let start = Instant::now();
                while start.elapsed().as_secs_f64() * 1e3 < ms {
                    std::hint::spin_loop();
                }
            });
            Ok(calls)
        }
    }

    #[test]
    fn a_fixed_protocol_times_exactly_its_repeats_after_the_warm_up() {
        let m = measure(&Protocol::fixed(2, 3), busy(1.0)).expect("measured");
        // Two warm-ups and three timed runs (plus any retries of contended ones).
        let retries = m.samples.iter().filter(|s| s.retried).count() as u32;
        assert_eq!(m.output, 5 + retries);
        assert_eq!((m.samples.len(), m.wall_ms.n), (3, 3));
        assert_eq!(m.wall_ms.ci_low, None, "three runs have no 95 % interval");
        assert_eq!(m.stages.len(), 1);
        assert_eq!(m.stages[0].name, "work");
        assert!(m.wall_ms.min >= 1.0, "{:?}", m.wall_ms);
        if let Some(cpu) = m.cpu_ms {
            assert!(cpu.median > 0.5, "1 ms of spinning: {cpu:?}");
            assert!(m.stages[0].cpu_ms.is_some());
        }
    }

    #[test]
    fn subjects_run_in_rounds_and_stop_at_their_interval_or_the_cap() {
        let order = std::cell::RefCell::new(Vec::new());
        let mut subjects: Vec<_> = (0..3)
            .map(|k| {
                let order = &order;
                move |rec: &mut Recorder| -> Result<(), String> {
                    order.borrow_mut().push(k);
                    rec.stages.add("work", 1.0 + k as f64);
                    Ok(())
                }
            })
            .collect();
        let protocol = Protocol {
            warmup: 0,
            min_repeats: 6,
            max_repeats: 10,
            clock: Clock::Wall,
            min_share: 0.0,
            ..Protocol::default()
        };
        let mut finished = Vec::new();
        let results = measure_all(&protocol, &mut subjects, |k, _| finished.push(k));
        // Constant times: the interval is a point after the sixth round, so all stop there.
        let order = order.into_inner();
        assert_eq!(order.len(), 18);
        assert_eq!(&order[..6], &[0, 1, 2, 0, 1, 2], "interleaved round-robin");
        assert_eq!(finished, [0, 1, 2]);
        for (k, r) in results.iter().enumerate() {
            let m = r.as_ref().expect("measured");
            assert_eq!(m.wall_ms.median, 1.0 + k as f64);
            assert_eq!(m.wall_ms.n, 6);
            assert_eq!(m.wall_ms.ci_low, Some(m.wall_ms.median));
        }
    }

    #[test]
    fn noisy_subjects_run_until_the_maximum_and_failures_leave_the_rounds() {
        let mut calls = [0u32; 2];
        type Subject<'a> = Box<dyn FnMut(&mut Recorder) -> Result<(), String> + 'a>;
        let mut subjects: Vec<Subject<'_>> = Vec::new();
        let (first, second) = calls.split_at_mut(1);
        subjects.push(Box::new(|rec: &mut Recorder| {
            first[0] += 1;
            // Alternating 1 and 3 ms: the interval stays [1, 3], never within 5 %.
            rec.stages.add("work", if first[0] % 2 == 0 { 1.0 } else { 3.0 });
            Ok(())
        }));
        subjects.push(Box::new(|_rec: &mut Recorder| {
            second[0] += 1;
            if second[0] > 2 {
                Err("broken".into())
            } else {
                Ok(())
            }
        }));
        let protocol = Protocol {
            warmup: 1,
            min_repeats: 6,
            max_repeats: 9,
            clock: Clock::Wall,
            min_share: 0.0,
            ..Protocol::default()
        };
        let results = measure_all(&protocol, &mut subjects, |_, _| {});
        drop(subjects);
        assert_eq!(results[0].as_ref().expect("measured").samples.len(), 9);
        assert_eq!(results[1].as_ref().err().map(String::as_str), Some("broken"));
        assert_eq!(calls, [10, 3], "a warm-up each, then the rounds; the failure stops at once");
    }

    #[test]
    fn the_record_kept_is_the_median_run() {
        let mut k = 0;
        let times = [5.0, 1.0, 4.0, 2.0, 3.0];
        let m = measure(
            &Protocol { clock: Clock::Wall, min_share: 0.0, ..Protocol::fixed(0, 5) },
            |rec: &mut Recorder| {
                rec.stages.add("work", times[k]);
                rec.counters.rays_traced = k as u64;
                k += 1;
                Ok::<_, String>(k)
            },
        )
        .expect("measured");
        assert_eq!(m.record.counters.rays_traced, 4, "the run of 3 ms, the median");
        assert_eq!(m.output, 5, "the last run's output");
        assert_eq!(m.wall_ms.median, 3.0);
    }

    #[test]
    fn clocks_parse_and_name_themselves() {
        assert_eq!("cpu".parse::<Clock>(), Ok(Clock::Cpu));
        assert_eq!("wall".parse::<Clock>(), Ok(Clock::Wall));
        assert!("gpu".parse::<Clock>().is_err());
        assert_eq!(serde_json::to_string(&Clock::Wall).expect("json"), "\"wall\"");
    }
}
