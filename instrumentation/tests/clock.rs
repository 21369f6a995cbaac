//! The clocks against real work, in a process of its own: the run queue sums every thread of
//! the process, so other tests' threads ending beside it would move them.

use instrumentation::clock::{cpu_now, Load, Schedule, MIN_JUDGED_NS};
use std::time::Duration;

/// Busy work on this thread until it has run `ms` of CPU time.
fn spin(ms: u64) -> u64 {
    let start = cpu_time::ThreadTime::now();
    let mut x = 1u64;
    while start.elapsed() < Duration::from_millis(ms) {
        x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    }
    x
}

#[test]
fn cpu_time_the_run_queue_and_the_load_advance_with_work() {
    let (Some(c0), Some(s0)) = (cpu_now(), Schedule::now()) else {
        // Not Linux: nothing to read, and nothing is ever called contended.
        return;
    };
    std::hint::black_box(spin(40));
    let (c1, s1) = (cpu_now().expect("clock"), Schedule::now().expect("schedstat"));
    let cpu = (c1 - c0).as_secs_f64() * 1e3;
    assert!(cpu >= 40.0, "40 ms of spinning gave {cpu} ms of CPU time");
    // The run queue's figures lag by at most a scheduler tick or so.
    let ran = (s1.ran_ns - s0.ran_ns) as f64 / 1e6;
    assert!(ran >= 25.0, "ran {ran} ms: {s0:?} {s1:?}");
    let share = s1.share_since(&s0).expect("a share");
    assert!((0.0..=1.0).contains(&share), "{share}");
    assert_eq!(s1.share_since(&s1), None, "no time, no share");
    let short = Schedule { ran_ns: s0.ran_ns + MIN_JUDGED_NS / 2, ..s0 };
    assert_eq!(short.share_since(&s0), None, "too short to judge");
    let l = Load::now().expect("/proc/loadavg and /proc/stat");
    assert!(l.loadavg >= 0.0 && l.busy_jiffies > 0, "{l:?}");
    assert_eq!(l.others_since(&l, Duration::ZERO, Duration::from_secs(1), 2), Some(0.0));
    assert_eq!(l.others_since(&l, Duration::ZERO, Duration::ZERO, 2), None);
}
