//! How far a sweep has come and how long it has left, for the progress bar and the log.
//!
//! The estimate starts from the plan's cost model ([`crate::plan`]: pixels times samples,
//! map texels and triangles per run) and is corrected as runs finish, per method and device:
//! each finished run's wall time (warm-up runs and retries included, as the measurement engine
//! reports it) over its estimated cost gives that method's seconds per unit of cost, which
//! prices the runs of the same method still to come; a method none of whose runs has finished
//! takes the mean of those finished so far. The sum is scaled by the share of the elapsed time
//! the runs themselves took, so that the frames' shared work (G-buffers, references, grids) is
//! counted as it has been so far. A GPU method on a software rasterizer, or a method much
//! slower on this machine than its cost says, is thus priced by its own runs, not by the
//! suite's mean.

use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// How far a sweep has come.
#[derive(Debug, Clone, Copy)]
pub struct Progress<'a> {
    /// What just finished (`cage pcf-gems16`).
    pub label: &'a str,
    /// Runs done (measured, failed or not run).
    pub runs_done: u64,
    /// Runs of the sweep.
    pub runs_total: u64,
    /// The time left ([`Estimate::time_left`]); `None` before any run has finished.
    pub time_left: Option<Duration>,
}

/// The key runs are priced by: the method, and `gpu` for its GPU kernels.
pub fn run_key(method: &str, gpu: bool) -> String {
    if gpu {
        format!("{method} gpu")
    } else {
        method.to_owned()
    }
}

/// One method's runs: estimated cost left and done, and the wall time the done ones took.
#[derive(Debug, Clone, Copy, Default)]
struct Priced {
    left: f64,
    done: f64,
    secs: f64,
}

/// The estimate of the time a sweep has left (see the module documentation).
#[derive(Debug, Clone)]
pub struct Estimate {
    start: Instant,
    runs_total: u64,
    runs_done: u64,
    by_key: BTreeMap<String, Priced>,
}

impl Estimate {
    /// An estimate of the runs `planned` (each its [`run_key`] and estimated cost), starting
    /// now.
    pub fn new(planned: impl IntoIterator<Item = (String, f64)>) -> Self {
        let mut by_key: BTreeMap<String, Priced> = BTreeMap::new();
        let mut runs_total = 0;
        for (key, cost) in planned {
            by_key.entry(key).or_default().left += cost.max(0.0);
            runs_total += 1;
        }
        Self { start: Instant::now(), runs_total, runs_done: 0, by_key }
    }

    /// Runs done and runs planned.
    pub fn runs(&self) -> (u64, u64) {
        (self.runs_done, self.runs_total)
    }

    /// A run of `key` and estimated `cost` is done; `spent` is the wall time it took, `None`
    /// for one that did not run (its cost leaves the estimate, its time teaches nothing).
    pub fn done(&mut self, key: &str, cost: f64, spent: Option<Duration>) {
        self.runs_done += 1;
        let p = self.by_key.entry(key.to_owned()).or_default();
        let cost = cost.max(0.0);
        p.left = (p.left - cost).max(0.0);
        if let Some(spent) = spent {
            p.done += cost;
            p.secs += spent.as_secs_f64();
        }
    }

    /// The time left after `elapsed` since the start (see the module documentation); `None`
    /// before any run has taken time.
    pub fn time_left_after(&self, elapsed: Duration) -> Option<Duration> {
        let (cost, secs) =
            self.by_key.values().fold((0.0, 0.0), |(c, s), p| (c + p.done, s + p.secs));
        if secs <= 0.0 || cost <= 0.0 {
            return None;
        }
        let mean = secs / cost;
        let left: f64 = self
            .by_key
            .values()
            .map(|p| p.left * if p.done > 0.0 { p.secs / p.done } else { mean })
            .sum();
        let overhead = (elapsed.as_secs_f64() / secs).max(1.0);
        Some(Duration::from_secs_f64(left * overhead))
    }

    /// The time left now.
    pub fn time_left(&self) -> Option<Duration> {
        self.time_left_after(self.start.elapsed())
    }

    /// The time since the start.
    pub fn elapsed(&self) -> Duration {
        self.start.elapsed()
    }
}

/// `d` as `1h02m03s`, `2m03s` or `3s`.
pub fn hms(d: Duration) -> String {
    let s = d.as_secs();
    match (s / 3600, s / 60 % 60, s % 60) {
        (0, 0, s) => format!("{s}s"),
        (0, m, s) => format!("{m}m{s:02}s"),
        (h, m, s) => format!("{h}h{m:02}m{s:02}s"),
    }
}

/// Progress lines of a sweep for a log: what starts, the runs done of the total, the time
/// elapsed and the time left. Printed only when standard error is not a terminal (on a
/// terminal the caller's progress bar shows the same).
pub struct ProgressLog {
    enabled: bool,
}

impl ProgressLog {
    /// A log that prints when standard error is not a terminal.
    pub fn new() -> Self {
        Self { enabled: !std::io::stderr().is_terminal() }
    }

    /// The line for `what` (e.g. `frame 2/5 cage 320x240`) after `done` of `total` runs in
    /// `elapsed`, with `left` to go.
    pub fn line(
        what: &str,
        (done, total): (u64, u64),
        elapsed: Duration,
        left: Option<Duration>,
    ) -> String {
        let left =
            left.map_or("time left unknown".to_owned(), |l| format!("about {} left", hms(l)));
        format!("{what}: {done}/{total} runs done, {} elapsed, {left}", hms(elapsed))
    }

    /// Prints the line for `what` at the estimate's state, when enabled.
    pub fn print(&self, what: &str, estimate: &Estimate) {
        if self.enabled {
            let line = Self::line(what, estimate.runs(), estimate.elapsed(), estimate.time_left());
            eprintln!("{line}");
        }
    }
}

impl Default for ProgressLog {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_say_the_runs_the_time_and_what_is_left() {
        let line = ProgressLog::line(
            "frame 2/5 cage 320x240",
            (100, 120),
            Duration::from_secs(72),
            Some(Duration::from_secs(144)),
        );
        assert_eq!(
            line,
            "frame 2/5 cage 320x240: 100/120 runs done, 1m12s elapsed, about 2m24s left"
        );
        let first = ProgressLog::line("frame 1/5 cage 320x240", (0, 120), Duration::ZERO, None);
        assert_eq!(first, "frame 1/5 cage 320x240: 0/120 runs done, 0s elapsed, time left unknown");
        assert_eq!(hms(Duration::from_secs(3723)), "1h02m03s");
    }

    /// Four `sm` runs and four slow `afsm gpu` runs of the same estimated cost: after one of
    /// each, the GPU runs are priced by their own time, not by the mean.
    #[test]
    fn each_method_is_priced_by_its_own_runs() {
        let planned = (0..4).flat_map(|_| [("sm".to_owned(), 10.0), (run_key("afsm", true), 10.0)]);
        let mut e = Estimate::new(planned);
        assert_eq!(e.runs(), (0, 8));
        assert_eq!(e.time_left_after(Duration::from_secs(1)), None, "nothing done yet");
        e.done("sm", 10.0, Some(Duration::from_secs(1)));
        // Only sm has run: the GPU runs take the mean, 0.1 s a unit: 3 + 4 s.
        assert_eq!(e.time_left_after(Duration::from_secs(1)), Some(Duration::from_secs(7)));
        e.done("afsm gpu", 10.0, Some(Duration::from_secs(9)));
        // 3 sm at 1 s and 3 GPU runs at 9 s; the 10 s elapsed were all runs.
        assert_eq!(e.time_left_after(Duration::from_secs(10)), Some(Duration::from_secs(30)));
        // Twice as long elapsed as the runs took: the frames' own work doubles the estimate.
        assert_eq!(e.time_left_after(Duration::from_secs(20)), Some(Duration::from_secs(60)));
        // A run that did not run leaves the estimate without teaching it anything.
        e.done("sm", 10.0, None);
        assert_eq!(e.time_left_after(Duration::from_secs(10)), Some(Duration::from_secs(29)));
        assert_eq!(e.runs(), (3, 8));
    }
}
