//! The clocks and load readings times are taken with: the process's CPU time, the time its
//! threads spent running and waiting for a core, and the machine's load.
//!
//! - **CPU time** ([`cpu_now`]): `clock_gettime(CLOCK_PROCESS_CPUTIME_ID)` through the
//!   `cpu-time` crate, the time every thread of the process (the rayon pool included) ran on a
//!   core, at nanosecond resolution. It moves far less than wall time when other work shares
//!   the cores, since a thread that waits for a core is not charged.
//! - **Run queue** ([`Schedule::now`]): per thread of the process, Linux's
//!   `/proc/self/task/TID/schedstat` gives the nanoseconds it ran and the nanoseconds it was
//!   runnable but waited for a core. Their sums over an interval give the run's **CPU share**,
//!   `ran / (ran + waited)`: 1 when every thread that wanted a core had one, lower the more
//!   the run was starved by other work ([`Schedule::share_since`]).
//! - **Load** ([`Load::now`]): the 1-minute load average of `/proc/loadavg`, and the
//!   machine's busy and stolen jiffies of `/proc/stat`'s `cpu` line, from which the share of
//!   the machine that other processes (or the hypervisor) took over an interval follows
//!   ([`Load::others_since`]). Jiffies are 10 ms, so that share is coarse over short
//!   intervals; the run queue is exact.
//!
//! Where these files do not exist (not Linux), the readings are `None` and no run is ever
//! called contended. The files are read by hand: each is one line of numbers in a fixed order
//! (proc(5)), which a crate such as `procfs` would parse through far more code.

use std::time::Duration;

/// The process's CPU time so far (every thread), or `None` where the clock is unavailable.
pub fn cpu_now() -> Option<Duration> {
    cpu_time::ProcessTime::try_now().ok().map(|t| t.as_duration())
}

/// The least time, in nanoseconds, the threads must have run or waited over an interval for
/// its CPU share to be judged: a few scheduler ticks (1-4 ms each).
pub const MIN_JUDGED_NS: u64 = 10_000_000;

/// What the process's threads did so far: nanoseconds on a core and waiting for one, summed
/// over the threads alive now.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Schedule {
    /// Nanoseconds the threads ran.
    pub ran_ns: u64,
    /// Nanoseconds the threads were runnable and waited for a core.
    pub waited_ns: u64,
}

impl Schedule {
    /// The sums over the process's threads now; `None` where `/proc/self/task` is not readable.
    pub fn now() -> Option<Self> {
        let mut sum = Schedule::default();
        for entry in std::fs::read_dir("/proc/self/task").ok()? {
            let Ok(entry) = entry else { continue };
            // A thread that ended since the listing has no file: it adds nothing.
            let Ok(text) = std::fs::read_to_string(entry.path().join("schedstat")) else {
                continue;
            };
            let mut fields = text.split_ascii_whitespace().map(str::parse::<u64>);
            if let (Some(Ok(ran)), Some(Ok(waited))) = (fields.next(), fields.next()) {
                sum.ran_ns += ran;
                sum.waited_ns += waited;
            }
        }
        Some(sum)
    }

    /// The CPU share since `before`: the time the threads ran over the time they ran or
    /// waited for a core; `None` when together they did so for less than [`MIN_JUDGED_NS`]
    /// (the kernel brings a running thread's figures up to date at its scheduler ticks, so
    /// shorter intervals are not to be judged by).
    pub fn share_since(&self, before: &Schedule) -> Option<f64> {
        let ran = self.ran_ns.saturating_sub(before.ran_ns) as f64;
        let waited = self.waited_ns.saturating_sub(before.waited_ns) as f64;
        (ran + waited >= MIN_JUDGED_NS as f64).then(|| ran / (ran + waited))
    }
}

/// The machine's load at one moment.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Load {
    /// The 1-minute load average.
    pub loadavg: f64,
    /// Jiffies every core spent busy (user, nice, system, irq, softirq, steal) so far.
    pub busy_jiffies: u64,
    /// Jiffies taken by the hypervisor (steal) so far.
    pub steal_jiffies: u64,
}

/// Clock ticks per second of `/proc/stat` (`USER_HZ`, 100 on every Linux architecture that
/// user space sees).
const JIFFIES_PER_S: f64 = 100.0;

impl Load {
    /// The load now; `None` where `/proc/loadavg` or `/proc/stat` is not readable.
    pub fn now() -> Option<Self> {
        let loadavg = std::fs::read_to_string("/proc/loadavg").ok()?;
        let loadavg = loadavg.split_ascii_whitespace().next()?.parse().ok()?;
        let stat = std::fs::read_to_string("/proc/stat").ok()?;
        let line = stat.lines().find(|l| l.starts_with("cpu "))?;
        // user nice system idle iowait irq softirq steal guest guest_nice (proc(5)); guest time
        // is already inside user and nice.
        let f: Vec<u64> =
            line.split_ascii_whitespace().skip(1).filter_map(|x| x.parse().ok()).collect();
        let at = |k: usize| f.get(k).copied().unwrap_or(0);
        let busy = at(0) + at(1) + at(2) + at(5) + at(6) + at(7);
        Some(Self { loadavg, busy_jiffies: busy, steal_jiffies: at(7) })
    }

    /// The share of the machine (`cores` over `wall`) that others took since `before`: busy
    /// time not the process's own (`own_cpu`), stolen time included; clamped to [0, 1]. `None`
    /// over no time.
    pub fn others_since(
        &self,
        before: &Load,
        own_cpu: Duration,
        wall: Duration,
        cores: usize,
    ) -> Option<f64> {
        let capacity = wall.as_secs_f64() * cores.max(1) as f64;
        if capacity <= 0.0 {
            return None;
        }
        let busy = self.busy_jiffies.saturating_sub(before.busy_jiffies) as f64 / JIFFIES_PER_S;
        Some(((busy - own_cpu.as_secs_f64()) / capacity).clamp(0.0, 1.0))
    }

    /// The share of the machine stolen by the hypervisor since `before`; `None` over no time.
    pub fn steal_since(&self, before: &Load, wall: Duration, cores: usize) -> Option<f64> {
        let capacity = wall.as_secs_f64() * cores.max(1) as f64;
        let steal = self.steal_jiffies.saturating_sub(before.steal_jiffies) as f64 / JIFFIES_PER_S;
        (capacity > 0.0).then(|| (steal / capacity).clamp(0.0, 1.0))
    }
}

/// Logical cores available to the process.
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}
