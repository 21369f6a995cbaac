//! `shadowbench report`: a suite's tables and data, its pages in headless Chromium, a sweep in
//! shards merged back, the same on a real Slurm cluster, timing that holds under load, runs
//! over animated scenes, and today's techniques set against the seeds.

#[path = "../common/mod.rs"]
mod common;

mod motion;
mod report;
mod report_browser;
mod shard;
mod slurm;
mod sweeps;
mod timing;
mod today;
mod transactions;
