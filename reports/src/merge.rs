//! A sharded report put back together (`report merge DIR... --out OUT`).
//!
//! A shard (`report --shard K/N`) writes its own items into its folder: first `shard.json`
//! ([`ShardStart`]), saying which shard started, then, when it has finished, its runs' images
//! and records and its `runs.json`, naming the shard and its items
//! ([`crate::model::ShardInfo`]); the pages and charts are left to the merge. The merge:
//!
//! - verifies every folder against its manifest (`crate::publish::verify`: each file the shard
//!   wrote present, with its size and SHA-256), so that a missing, truncated or edited file
//!   (a row deleted from `runs.json`, an EXR cut short) is refused naming it;
//! - reads every folder's `runs.json`, and refuses when a shard of `0..N` is missing or did
//!   not finish (naming each one and how to run only those again), when two folders hold the
//!   same shard, or when the shards are of different suites, shard counts or plans;
//! - refuses shards of different versions or commits of the workbench, naming both, unless
//!   `--allow-mixed` is given; the merged report's provenance then lists each shard's
//!   (`Provenance::mixed`);
//! - checks that each shard ran exactly its share of the plan ([`crate::plan::Shard::items`]),
//!   and each of its runs once: a run of another item or method than the plan's, a run twice,
//!   or more runs than the item plans are refused naming the run;
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
    /// A shard's files do not match its manifest (the source says which and how).
    #[error("{dir}")]
    Corrupt {
        /// The shard's folder.
        dir: PathBuf,
        /// Which file differs, how.
        source: crate::publish::PublishError,
    },
    /// Shards of different versions or commits.
    #[error(
        "{dir}: written by shadowbench {theirs}, but {first} by {ours}; shards of one report \
         come from one build (run them again with one build, or merge anyway with \
         --allow-mixed, which the report's provenance records)"
    )]
    Mixed {
        /// The shard that differs from the first.
        dir: PathBuf,
        /// Its version and commit.
        theirs: String,
        /// The first shard's folder.
        first: PathBuf,
        /// The first shard's version and commit.
        ours: String,
    },
    /// A shard's runs are not those its items plan.
    #[error("{dir}: {message}")]
    Unplanned {
        /// The shard's folder.
        dir: PathBuf,
        /// The run and why.
        message: String,
    },
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

/// A shard's build, as `0.1.0 abc123` (with `dirty` when its checkout had changes).
fn build_of(p: &Provenance) -> String {
    format!("{} {}{}", p.version, p.commit, if p.dirty { " dirty" } else { "" })
}

/// Reads `dir`'s `shard.json`: in the folder (a finished shard), or in its staging folder (a
/// shard that is running or was killed).
fn shard_start(dir: &Path) -> Result<ShardStart, String> {
    let staged = dir.join(crate::publish::STAGING).join(SHARD_START);
    let path = if staged.is_file() { staged } else { dir.join(SHARD_START) };
    std::fs::read_to_string(&path)
        .map_err(|e| e.to_string())
        .and_then(|t| serde_json::from_str::<ShardStart>(&t).map_err(|e| e.to_string()))
}

/// Checks that `f`'s runs are each a planned run of its items, once.
fn check_runs(f: &Finished, plan: &[crate::plan::WorkItem]) -> Result<(), MergeError> {
    use crate::plan::Work;
    let fail = |message: String| MergeError::Unplanned { dir: f.dir.clone(), message };
    let mut per_item: BTreeMap<usize, usize> = BTreeMap::new();
    let mut seen = std::collections::HashSet::new();
    for r in f.report.rows.iter().chain(&f.report.untimed).filter(|r| r.external) {
        let name = crate::model::row_stem(r);
        let planned = f.info.items.contains(&r.item).then(|| plan.get(r.item)).flatten();
        let Some(Work::External { name: planned, .. }) = planned.map(|i| &i.work) else {
            return Err(fail(format!(
                "outside result {name} is of item {}, which the shard does not plan as one",
                r.item
            )));
        };
        if *planned != r.method || !seen.insert(name.clone()) {
            return Err(fail(format!("outside result {name} is not planned once")));
        }
    }
    for r in f.report.rows.iter().filter(|r| !r.external) {
        let name = crate::model::row_stem(r);
        let Some(Work::Runs { method, runs, .. }) =
            f.info.items.contains(&r.item).then(|| plan.get(r.item).map(|i| &i.work)).flatten()
        else {
            return Err(fail(format!(
                "run {name} is of item {}, which the shard does not plan",
                r.item
            )));
        };
        if *method != r.method {
            return Err(fail(format!(
                "run {name} is of {}, but item {} plans {method}",
                r.method, r.item
            )));
        }
        if !seen.insert(name.clone()) {
            return Err(fail(format!("run {name} is in runs.json twice")));
        }
        let n = per_item.entry(r.item).or_default();
        *n += 1;
        if *n > runs.len() {
            return Err(fail(format!(
                "item {} plans {} runs, runs.json has more",
                r.item,
                runs.len()
            )));
        }
    }
    let mut tables = std::collections::HashSet::new();
    for t in &f.report.table_runs {
        let planned = match plan.get(t.item).map(|i| &i.work) {
            Some(Work::Table { table, runs, .. })
                if *table == t.table && f.info.items.contains(&t.item) =>
            {
                runs.len()
            }
            _ => {
                return Err(fail(format!(
                    "a run of table {} is of item {}, which the shard does not plan",
                    t.table, t.item
                )))
            }
        };
        if t.run >= planned || !tables.insert((t.item, t.run)) {
            return Err(fail(format!(
                "table run {} of item {} is not planned once",
                t.run, t.item
            )));
        }
    }
    Ok(())
}

/// Reads the shard folders and builds the merged report (see the module documentation);
/// shards of different builds are merged only with `allow_mixed`. Returns it with the
/// folders it came from, in shard order.
pub fn merge(dirs: &[PathBuf], allow_mixed: bool) -> Result<(Report, Vec<PathBuf>), MergeError> {
    if dirs.is_empty() {
        return Err(MergeError::Empty);
    }
    let mut finished: Vec<Finished> = Vec::new();
    let mut started: Vec<(ShardStart, PathBuf)> = Vec::new();
    for dir in dirs {
        let runs = dir.join("runs.json");
        if runs.is_file() {
            crate::publish::verify(dir)
                .map_err(|source| MergeError::Corrupt { dir: dir.clone(), source })?;
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
        match shard_start(dir) {
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
    let first = &finished[0];
    let ours = build_of(&first.info.provenance);
    let mut mixed = Vec::new();
    if let Some(other) = finished.iter().find(|f| build_of(&f.info.provenance) != ours) {
        if !allow_mixed {
            return Err(MergeError::Mixed {
                dir: other.dir.clone(),
                theirs: build_of(&other.info.provenance),
                first: first.dir.clone(),
                ours,
            });
        }
        mixed = finished
            .iter()
            .map(|f| format!("shard {}: {}", f.info.shard, build_of(&f.info.provenance)))
            .collect();
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
        check_runs(f, &plan)?;
    }
    let mut report = assemble(&suite, finished.iter().collect());
    report.provenance.mixed = mixed;
    Ok((report, finished.into_iter().map(|f| f.dir).collect()))
}

/// The merged report of finished shards that cover the plan.
fn assemble(suite: &crate::suite::Suite, shards: Vec<&Finished>) -> Report {
    let first = &shards[0];
    let mut machine = first.info.machine.clone();
    machine.gpu = shards.iter().find_map(|f| f.info.machine.gpu.clone());
    let mut rows = Vec::new();
    let mut untimed = Vec::new();
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
        untimed.extend(f.report.untimed.iter().cloned().map(|mut r| {
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
    untimed.sort_by_key(|r| r.item);
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
        untimed,
        grids,
        tables: crate::tables::build_all(&suite.tables, &table_runs),
        table_runs,
        cache,
        shards: shards.iter().map(|f| f.info.clone()).collect(),
    }
}

/// Copies the per-run and per-scene files of the shard folders `from` into `out`: the files
/// their manifests list under `visibility/`, `runs/` (but the pages), `scenes/` and `grids/`.
pub fn copy_shard_files(from: &[PathBuf], out: &Path) -> std::io::Result<()> {
    for dir in from {
        let manifest = crate::publish::read_manifest(dir)
            .map_err(|e| std::io::Error::other(e.to_string()))?
            .map(|m| m.files)
            .unwrap_or_default();
        for e in manifest {
            let Some((sub, _)) = e.path.split_once('/') else { continue };
            let page = Path::new(&e.path).extension().is_some_and(|x| x == "html");
            if !["visibility", "runs", "scenes", "grids"].contains(&sub) || page {
                continue;
            }
            let dst = out.join(&e.path);
            if let Some(parent) = dst.parent() {
                std::fs::create_dir_all(parent)?;
            }
            std::fs::copy(dir.join(&e.path), dst)?;
        }
    }
    Ok(())
}
