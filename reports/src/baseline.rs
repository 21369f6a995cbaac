//! Comparison of a report with an earlier one (`report --baseline DIR`): per run present in
//! both, the change of the shadow-only error and the ratio of the median times with its
//! confidence interval; regressions flagged; a summary first.
//!
//! Runs are matched by scene, frame, method and parameters. The time ratio is
//! `median_now / median_before`, and its interval `[ci_low_now / ci_high_before,
//! ci_high_now / ci_low_before]` combines the two medians' 95 % bootstrap intervals
//! ([`crate::timing`]) conservatively: a run is flagged **slower** only when the whole interval
//! lies above `1 + time_tolerance` and the two intervals lie more than `min_change_ms` apart
//! (and **faster**, an improvement, only when the interval lies below `1 / (1 + time_tolerance)`
//! and the intervals lie as far apart the other way), so the noise of repeated timing flags
//! nothing at the defaults (see [`BaselineOptions`] for how they were chosen). Errors are
//! deterministic for a given commit and machine (seeded sampling), so a run is flagged **less
//! accurate** when its mean error grows by more than `error_tolerance`.

use crate::model::{Report, Row};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Thresholds of the comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaselineOptions {
    /// Relative slow-down the whole time-ratio interval must exceed to flag a run as slower.
    /// Default 0.5 (50 %): two reports of the `quick` suite taken one after the other on a
    /// shared 2-core machine had time-ratio intervals up to [1.30, 1.96] for unchanged code
    /// (3 timed runs each, so an interval is about the runs' [min, max]), while a real
    /// regression worth flagging in a sweep is a factor, not a few per cent. On a quiet machine
    /// with more repeats, lower it (`report --baseline-tolerance`).
    pub time_tolerance: f64,
    /// Milliseconds by which the run's time interval must lie above the baseline's (its
    /// lower bound over the baseline's upper bound) to flag it as slower. Default 5 ms: on a
    /// shared machine a run of a few milliseconds is delayed by a scheduler time slice or two
    /// whenever another process takes a core, whatever the method; in two `quick` reports one
    /// after the other, a `pcf-gems4` run of 3.4-3.6 ms took 5.6-7.4 ms in the second (a ratio
    /// interval of [1.58, 2.20], 2 ms apart), and no run with a real difference under 5 ms
    /// was seen. `report --baseline-min-ms 0` compares ratios alone.
    pub min_change_ms: f64,
    /// Growth of the mean error (lit fraction) that flags a run as less accurate. Default
    /// 1e-6.
    pub error_tolerance: f64,
}

impl Default for BaselineOptions {
    fn default() -> Self {
        Self { time_tolerance: 0.5, min_change_ms: 5.0, error_tolerance: 1e-6 }
    }
}

/// Why an earlier report could not be read.
#[derive(Debug, thiserror::Error)]
pub enum BaselineError {
    /// The folder has no readable `runs.json`.
    #[error("--baseline {dir}: cannot read {file}: {message}")]
    Read {
        /// The baseline folder.
        dir: PathBuf,
        /// The file.
        file: PathBuf,
        /// Why.
        message: String,
    },
}

/// What changed in one run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunChange {
    /// Scene.
    pub scene: String,
    /// Method.
    pub method: String,
    /// Parameters, as `map_res=1024 rate=16`.
    pub params: String,
    /// Mean error before and now.
    pub error: (f64, f64),
    /// Median time now over before.
    pub time_ratio: f64,
    /// The ratio's interval (see the module documentation).
    pub time_ratio_ci: (f64, f64),
    /// The run's time interval lies above the tolerance.
    pub slower: bool,
    /// The run's time interval lies below the tolerance.
    pub faster: bool,
    /// The run's error grew beyond the tolerance.
    pub less_accurate: bool,
}

/// A report set against its baseline.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// The baseline folder.
    pub dir: PathBuf,
    /// The baseline's commit, as its provenance gives it.
    pub commit: String,
    /// Runs present in both reports, in the current report's order.
    pub runs: Vec<RunChange>,
    /// Runs only in the current report.
    pub new_runs: usize,
    /// Runs only in the baseline.
    pub dropped_runs: usize,
}

impl Comparison {
    /// The runs flagged as regressions (slower or less accurate).
    pub fn regressions(&self) -> impl Iterator<Item = &RunChange> {
        self.runs.iter().filter(|r| r.slower || r.less_accurate)
    }
}

/// Reads the report in `dir` (its `runs.json`).
pub fn load(dir: &Path) -> Result<Report, BaselineError> {
    let file = dir.join("runs.json");
    let fail =
        |message: String| BaselineError::Read { dir: dir.to_owned(), file: file.clone(), message };
    let text = std::fs::read_to_string(&file).map_err(|e| fail(e.to_string()))?;
    serde_json::from_str(&text).map_err(|e| fail(format!("not a report's runs.json ({e})")))
}

/// The key a run is matched by.
fn key(r: &Row) -> (String, String, u32, u32, String) {
    let params = serde_json::Value::Object(r.params.clone()).to_string();
    (r.scene.clone(), r.method.clone(), r.width, r.height, params)
}

/// The parameters of a row, as `map_res=1024 rate=16`.
fn params(r: &Row) -> String {
    r.params
        .iter()
        .map(|(k, v)| format!("{k}={}", v.to_string().trim_matches('"')))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Sets `now` against `before` (the report read from `dir`).
pub fn compare(now: &Report, before: &Report, dir: &Path, options: BaselineOptions) -> Comparison {
    let mut runs = Vec::new();
    for r in &now.rows {
        let Some(b) = before.rows.iter().find(|b| key(b) == key(r)) else { continue };
        let (t, tb) = (&r.total_ms, &b.total_ms);
        let ratio = t.median / tb.median;
        let ci = (t.ci_low / tb.ci_high, t.ci_high / tb.ci_low);
        let (e0, e1) = (b.metrics.mean_abs_error, r.metrics.mean_abs_error);
        runs.push(RunChange {
            scene: r.scene.clone(),
            method: r.method.clone(),
            params: params(r),
            error: (e0, e1),
            time_ratio: ratio,
            time_ratio_ci: ci,
            slower: ci.0 > 1.0 + options.time_tolerance
                && t.ci_low - tb.ci_high > options.min_change_ms,
            faster: ci.1 < 1.0 / (1.0 + options.time_tolerance)
                && tb.ci_low - t.ci_high > options.min_change_ms,
            less_accurate: e1 - e0 > options.error_tolerance,
        });
    }
    let matched = runs.len();
    Comparison {
        dir: dir.to_owned(),
        commit: before.provenance.commit.clone(),
        runs,
        new_runs: now.rows.len() - matched,
        dropped_runs: before
            .rows
            .iter()
            .filter(|b| !now.rows.iter().any(|r| key(r) == key(b)))
            .count(),
    }
}

/// One sentence on the comparison: the baseline, the runs compared and the flags counted.
pub fn summary_line(c: &Comparison) -> String {
    let count = |f: fn(&RunChange) -> bool| c.runs.iter().filter(|r| f(r)).count();
    format!(
        "Against the baseline {} (commit {}): {} runs compared ({} new, {} dropped); {} slower, \
         {} less accurate, {} faster",
        c.dir.display(),
        c.commit,
        c.runs.len(),
        c.new_runs,
        c.dropped_runs,
        count(|r| r.slower),
        count(|r| r.less_accurate),
        count(|r| r.faster)
    )
}

/// The comparison as Markdown: the summary first (counts and every regression), then every
/// run.
pub fn markdown(c: &Comparison) -> String {
    let mut s = format!("{}.\n\n", summary_line(c));
    let regressions: Vec<&RunChange> = c.regressions().collect();
    if regressions.is_empty() {
        s.push_str("No regression.\n\n");
    } else {
        s.push_str("Regressions:\n\n");
        for r in &regressions {
            let _ = writeln!(
                s,
                "- **{}** {} on {}: {} ({})",
                r.method,
                r.params,
                r.scene,
                flags(r),
                describe(r)
            );
        }
        s.push('\n');
    }
    s.push_str("| scene | method | parameters | error before | error now | time ratio [95 % CI] | flag |\n");
    s.push_str("|---|---|---|---|---|---|---|\n");
    for r in &c.runs {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.6} | {:.6} | {:.2} [{:.2}, {:.2}] | {} |",
            r.scene,
            r.method,
            r.params,
            r.error.0,
            r.error.1,
            r.time_ratio,
            r.time_ratio_ci.0,
            r.time_ratio_ci.1,
            flags(r)
        );
    }
    s
}

/// The flags of a run, as words.
pub fn flags(r: &RunChange) -> String {
    [(r.slower, "slower"), (r.less_accurate, "less accurate"), (r.faster, "faster")]
        .iter()
        .filter(|(on, _)| *on)
        .map(|(_, w)| *w)
        .collect::<Vec<_>>()
        .join(", ")
}

/// One line on what changed in a run.
fn describe(r: &RunChange) -> String {
    format!(
        "time x{:.2} [{:.2}, {:.2}], error {:.6} -> {:.6}",
        r.time_ratio, r.time_ratio_ci.0, r.time_ratio_ci.1, r.error.0, r.error.1
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small_report() -> Report {
        let toml = r#"
            name = "baseline"
            width = 48
            height = 36
            warmup = 0
            repeats = 1
            scenes = ["plane-square"]
            [[run]]
            method = "sm"
            map_res = [256, 512]
            [[run]]
            method = "pcf-gems4"
            map_res = [256, 512]
        "#;
        crate::sweep::report_of(toml)
    }

    #[test]
    fn a_report_against_itself_flags_nothing_and_a_slowed_method_is_flagged() {
        // Times of a tiny frame are too short to compare: every run is given the same spread.
        let mut report = small_report();
        for r in &mut report.rows {
            r.total_ms = crate::timing::Summary {
                median: 10.0,
                ci_low: 9.0,
                ci_high: 11.0,
                min: 8.0,
                max: 12.0,
            };
        }
        let dir = Path::new("earlier");
        let same = compare(&report, &report, dir, BaselineOptions::default());
        assert_eq!(same.runs.len(), report.rows.len());
        assert_eq!((same.new_runs, same.dropped_runs), (0, 0));
        assert_eq!(same.regressions().count(), 0);
        assert!(markdown(&same).contains("No regression."));

        // `pcf-gems4` made three times slower, `sm` less accurate.
        let mut slowed = report.clone();
        for r in &mut slowed.rows {
            if r.method == "pcf-gems4" {
                let t = &mut r.total_ms;
                for v in [&mut t.median, &mut t.ci_low, &mut t.ci_high, &mut t.min, &mut t.max] {
                    *v *= 3.0;
                }
            } else {
                r.metrics.mean_abs_error += 1e-3;
            }
        }
        let c = compare(&slowed, &report, dir, BaselineOptions::default());
        for r in &c.runs {
            assert_eq!(r.slower, r.method == "pcf-gems4", "{r:?}");
            assert_eq!(r.less_accurate, r.method == "sm", "{r:?}");
            assert!(!r.faster);
        }
        let md = markdown(&c);
        assert!(md.contains("Regressions:") && md.contains("**pcf-gems4**"), "{md}");
        // And the other way round the slowed method got faster.
        let back = compare(&report, &slowed, dir, BaselineOptions::default());
        assert!(back.runs.iter().filter(|r| r.method == "pcf-gems4").all(|r| r.faster));
    }

    #[test]
    fn a_short_run_is_flagged_only_when_it_slows_by_more_than_the_time_slice_floor() {
        // A 3.5 ms run taking twice as long: a time slice of a shared machine at the default
        // floor, a regression when the floor is 0.
        let mut report = small_report();
        report.rows.truncate(1);
        let at = |ms: f64| crate::timing::Summary {
            median: ms,
            ci_low: ms - 0.1,
            ci_high: ms + 0.1,
            min: ms - 0.2,
            max: ms + 0.2,
        };
        report.rows[0].total_ms = at(3.5);
        let mut slowed = report.clone();
        slowed.rows[0].total_ms = at(7.0);
        let dir = Path::new("earlier");
        let default = compare(&slowed, &report, dir, BaselineOptions::default());
        assert!(!default.runs[0].slower, "{:?}", default.runs[0]);
        let strict = BaselineOptions { min_change_ms: 0.0, ..Default::default() };
        assert!(compare(&slowed, &report, dir, strict).runs[0].slower);
        // 3.5 ms to 14 ms is more than the floor.
        slowed.rows[0].total_ms = at(14.0);
        assert!(compare(&slowed, &report, dir, BaselineOptions::default()).runs[0].slower);
    }

    #[test]
    fn a_folder_without_a_report_is_refused_naming_the_file() {
        let dir = tempfile::tempdir().expect("tempdir");
        let err = load(dir.path()).expect_err("no runs.json");
        assert!(err.to_string().contains("runs.json"), "{err}");
        std::fs::write(dir.path().join("runs.json"), "{}").expect("writes");
        let err = load(dir.path()).expect_err("not a report");
        assert!(err.to_string().contains("not a report"), "{err}");
    }
}
