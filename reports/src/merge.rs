//! A sharded report put back together (`report merge DIR... --out OUT`).
//!
//! A shard (`report --shard K/N`) writes its own items into its folder: first `shard.json`
//! ([`ShardStart`]), saying which shard started, then, when it has finished, its runs' images
//! and records and its `runs.json`, naming the shard and its items
//! ([`crate::model::ShardInfo`]); the pages and charts are left to the merge. The merge:
//!
//! - reads every folder's `runs.json`, and refuses when a shard of `0..N` is missing or did
//!   not finish (naming each one and how to run only those again), when two folders hold the
//!   same shard, or when the shards are of different suites, shard counts or plans;
//! - checks that each shard ran exactly its share of the plan ([`crate::plan::Shard::items`]);
//! - puts the scenes, runs, grids and the tables' runs in the order an unsharded report has
//!   them (the plan's order), each run marked with its shard, and builds the papers' tables
//!   from every shard's table runs (`crate::tables::build`); skipped runs are listed once;
//! - copies the shards' per-run and per-scene files (`visibility/`, `runs/`, `scenes/`,
//!   `grids/`) and writes everything made from the report alone (`crate::write::write_summary`):
//!   runs.json, runs.csv, report.md, index.html, plots, tables, the run pages.
//!
//! Metrics are the shards' own, computed where the runs ran, so they equal an unsharded
//! report's. Times and machines are each shard's; the merged report's `machine` is the first
//! shard's (with a GPU adapter if any shard used one), every shard's provenance, machine,
//! cache counts and wall time are in `shards`, and its `provenance` is the merge's.

use crate::model::{Report, ShardInfo};
use crate::plan::Shard;
use instrumentation::Provenance;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What a shard writes into its folder before it starts (`shard.json`), so that a shard that
/// did not finish can be named.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShardStart {
    /// The suite's name.
    pub suite: String,
    /// The shard.
    pub shard: Shard,
    /// When it started, RFC 3339 in UTC.
    pub started: String,
}

/// The file a shard writes first.
pub const SHARD_START: &str = "shard.json";

/// Why shards could not be merged.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// A folder is neither a shard nor a shard that started.
    #[error("{dir}: not a shard's folder ({message})")]
    NotAShard {
        /// The folder.
        dir: PathBuf,
        /// Why.
        message: String,
    },
    /// Shards disagree on the suite, the shard count or the plan.
    #[error("{dir}: {message}")]
    Mismatch {
        /// The folder that disagrees with the first.
        dir: PathBuf,
        /// On what.
        message: String,
    },
    /// Shards of the plan are missing or unfinished.
    #[error("{}", missing_text(.missing, .unfinished, *.count))]
    Missing {
        /// The shards missing, unfinished included.
        missing: Vec<u32>,
        /// Shards whose folder is there but has no report (started, not finished), with it.
        unfinished: Vec<(u32, PathBuf)>,
        /// The shard count.
        count: u32,
    },
    /// No folder was given.
    #[error("no shard folder given")]
    Empty,
}

/// The message of [`MergeError::Missing`]: the shards, the unfinished ones' folders, and how
/// to run only those again.
fn missing_text(missing: &[u32], unfinished: &[(u32, PathBuf)], count: u32) -> String {
    let names: Vec<String> = missing.iter().map(|k| format!("shard {k}")).collect();
    let plain: Vec<String> = missing.iter().map(u32::to_string).collect();
    let (verb, them) = if missing.len() == 1 { ("is", "it") } else { ("are", "them") };
    let mut s = format!("{} of {count} {verb} missing", names.join(", "));
    for (k, d) in unfinished {
        s += &format!(" (shard {k} started in {} but did not finish)", d.display());
    }
    s += &format!(
        ": run {them} again (`scripts/slurm/submit --only {}` with the same suite and `--shards \
         {count}`, or `report --suite SUITE --shard K/{count}` for each K), then merge again",
        plain.join(",")
    );
    s
}

/// One finished shard.
struct Finished {
    dir: PathBuf,
    report: Report,
    info: ShardInfo,
}

/// Reads the shard folders and builds the merged report (see the module documentation).
/// Returns it with the folders it came from, in shard order.
pub fn merge(dirs: &[PathBuf]) -> Result<(Report, Vec<PathBuf>), MergeError> {
    if dirs.is_empty() {
        return Err(MergeError::Empty);
    }
    let mut finished: Vec<Finished> = Vec::new();
    let mut started: Vec<(ShardStart, PathBuf)> = Vec::new();
    for dir in dirs {
        let runs = dir.join("runs.json");
        if runs.is_file() {
            let report = crate::baseline::load(dir)
                .map_err(|e| MergeError::NotAShard { dir: dir.clone(), message: e.to_string() })?;
            let [info] = report.shards.as_slice() else {
                return Err(MergeError::NotAShard {
                    dir: dir.clone(),
                    message: "its runs.json is not a shard's (run with `report --shard K/N`)"
                        .into(),
                });
            };
            let info = info.clone();
            finished.push(Finished { dir: dir.clone(), report, info });
            continue;
        }
        let start = std::fs::read_to_string(dir.join(SHARD_START))
            .map_err(|e| e.to_string())
            .and_then(|t| serde_json::from_str::<ShardStart>(&t).map_err(|e| e.to_string()));
        match start {
            Ok(s) => started.push((s, dir.clone())),
            Err(message) => {
                return Err(MergeError::NotAShard {
                    dir: dir.clone(),
                    message: format!("no runs.json, and no readable {SHARD_START}: {message}"),
                })
            }
        }
    }
    finished.sort_by_key(|f| f.info.shard.index);
    let count = finished
        .first()
        .map(|f| f.info.shard.count)
        .or_else(|| started.first().map(|s| s.0.shard.count))
        .unwrap_or(1);
    if let Some(first) = finished.first() {
        for f in &finished[1..] {
            if f.report.suite != first.report.suite {
                return Err(MergeError::Mismatch {
                    dir: f.dir.clone(),
                    message: format!("a shard of another suite than {}", first.dir.display()),
                });
            }
        }
    }
    for f in &finished {
        if f.info.shard.count != count {
            return Err(MergeError::Mismatch {
                dir: f.dir.clone(),
                message: format!("shard {} is of {count} shards in the first folder", f.info.shard),
            });
        }
    }
    for w in finished.windows(2) {
        if w[0].info.shard.index == w[1].info.shard.index {
            return Err(MergeError::Mismatch {
                dir: w[1].dir.clone(),
                message: format!("shard {} is also in {}", w[1].info.shard, w[0].dir.display()),
            });
        }
    }
    let have: Vec<u32> = finished.iter().map(|f| f.info.shard.index).collect();
    let missing: Vec<u32> = (0..count).filter(|k| !have.contains(k)).collect();
    if !missing.is_empty() {
        let unfinished = started
            .iter()
            .filter(|(s, _)| missing.contains(&s.shard.index))
            .map(|(s, d)| (s.shard.index, d.clone()))
            .collect();
        return Err(MergeError::Missing { missing, unfinished, count });
    }
    let suite = finished[0].report.suite.clone();
    let plan = crate::plan::plan(&suite);
    for f in &finished {
        if f.info.items != f.info.shard.items(&plan) {
            return Err(MergeError::Mismatch {
                dir: f.dir.clone(),
                message: format!(
                    "shard {} ran items {:?}, but its share of the plan is {:?} (a suite or \
                     scene changed between shards?)",
                    f.info.shard,
                    f.info.items,
                    f.info.shard.items(&plan)
                ),
            });
        }
    }
    Ok((assemble(&suite, finished.iter().collect()), finished.into_iter().map(|f| f.dir).collect()))
}

/// The merged report of finished shards that cover the plan.
fn assemble(suite: &crate::suite::Suite, shards: Vec<&Finished>) -> Report {
    let first = &shards[0];
    let mut machine = first.info.machine.clone();
    machine.gpu = shards.iter().find_map(|f| f.info.machine.gpu.clone());
    let mut rows = Vec::new();
    let mut grids = Vec::new();
    let mut scenes = BTreeMap::new();
    let mut table_runs = Vec::new();
    let mut skipped = Vec::new();
    for f in &shards {
        let k = f.info.shard.index;
        rows.extend(f.report.rows.iter().cloned().map(|mut r| {
            r.shard = Some(k);
            r
        }));
        grids.extend(f.report.grids.iter().cloned());
        for s in &f.report.scenes {
            let at = suite.scenes.iter().position(|n| *n == s.scene).unwrap_or(usize::MAX);
            scenes.entry((at, s.scene.clone())).or_insert_with(|| s.clone());
        }
        table_runs.extend(f.report.table_runs.iter().cloned().map(|mut r| {
            r.shard = Some(k);
            r
        }));
        skipped.extend(f.report.skipped.iter().cloned());
    }
    // Stable sorts keep each item's runs in the order they ran.
    rows.sort_by_key(|r| r.item);
    table_runs.sort_by_key(|r| r.item);
    grids.sort_by_key(|g| g.item);
    let mut seen = std::collections::HashSet::new();
    skipped.retain(|s| seen.insert(s.clone()));
    let cache = shards.iter().filter_map(|f| f.info.cache).reduce(|a, b| a + b);
    let mut provenance = Provenance::capture(Provenance::command_line(), None);
    provenance.adapter = machine.gpu.clone();
    Report {
        suite: suite.clone(),
        provenance,
        machine,
        clock: suite.clock,
        scenes: scenes.into_values().collect(),
        rows,
        skipped,
        grids,
        tables: crate::tables::build_all(&suite.tables, &table_runs),
        table_runs,
        cache,
        shards: shards.iter().map(|f| f.info.clone()).collect(),
    }
}

/// Copies the per-run and per-scene files of the shard folders `from` into `out`
/// (`visibility/`, `runs/` but the pages, `scenes/`, `grids/`).
pub fn copy_shard_files(from: &[PathBuf], out: &Path) -> std::io::Result<()> {
    for dir in from {
        for sub in ["visibility", "runs", "scenes", "grids"] {
            let src = dir.join(sub);
            let Ok(entries) = std::fs::read_dir(&src) else { continue };
            let dst = out.join(sub);
            std::fs::create_dir_all(&dst)?;
            for e in entries {
                let e = e?;
                let name = e.file_name();
                let page = Path::new(&name).extension().is_some_and(|x| x == "html");
                if e.file_type()?.is_file() && !page {
                    std::fs::copy(e.path(), dst.join(&name))?;
                }
            }
        }
    }
    Ok(())
}
