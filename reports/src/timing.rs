//! The machine a report's times were taken on, and its load over the sweep. How runs are
//! timed is the measurement engine's ([`instrumentation::measure`]); a suite gives its
//! protocol ([`crate::suite::Suite::protocol`]).

use serde::{Deserialize, Serialize};

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
    /// 1-minute load average when the sweep started (`/proc/loadavg`).
    #[serde(default)]
    pub load_start: Option<f64>,
    /// 1-minute load average when the sweep ended.
    #[serde(default)]
    pub load_end: Option<f64>,
}

impl Machine {
    /// Reads the current machine, with its load now as the start.
    pub fn current() -> Self {
        Self {
            cpu: instrumentation::cpu_model(),
            cores: instrumentation::clock::cores(),
            threads: rayon::current_num_threads(),
            gpu: None,
            os: format!("{} {}", std::env::consts::OS, std::env::consts::ARCH),
            load_start: instrumentation::clock::Load::now().map(|l| l.loadavg),
            load_end: None,
        }
    }

    /// The machine in one line, with the load it was measured under: `2 cores (Intel ...),
    /// 2 threads, load 0.4 -> 0.6`.
    pub fn line(&self) -> String {
        let load = match (self.load_start, self.load_end) {
            (Some(a), Some(b)) => format!(", load average {a:.1} -> {b:.1}"),
            (Some(a), None) => format!(", load average {a:.1} at the start"),
            _ => String::new(),
        };
        format!("{} cores ({}), {} threads, {}{load}", self.cores, self.cpu, self.threads, self.os)
    }
}
