//! Comparison of a report with an earlier one (`report --baseline DIR`): per run present in
//! both, the change of the shadow-only error and the ratio of the median times with its
//! interval; regressions flagged; a summary first.
//!
//! Runs are matched by scene, frame, method and parameters. Times are compared on the
//! report's clock ([`Report::clock`], CPU time by default: the time the work took on the
//! cores, which another process on the machine moves little), on both reports' figures of
//! that clock (wall time for a run either report has no CPU time for, said per run). The ratio
//! is `median_now / median_before`, and its interval `[low_now / high_before, high_now /
//! low_before]` combines the two medians' confidence intervals ([`instrumentation::stats`])
//! conservatively, or their ranges where a run had too few timed runs for an interval (said
//! per run). A run is flagged **slower** only when the whole interval lies above `1 +
//! time_tolerance` and the two intervals lie more than `min_change_ms` apart (and **faster**,
//! an improvement, only when the interval lies below `1 / (1 + time_tolerance)` and the
//! intervals lie as far apart the other way). Wall-time ratios are given beside, and only for
//! runs contended in neither report: a contended run's wall time measures the other work.
//! Errors are deterministic for a given commit and machine (seeded sampling), so a run is
//! flagged **less accurate** when its mean error grows by more than `error_tolerance`.

use crate::model::{Report, Row};
use instrumentation::measure::Clock;
use instrumentation::stats::Summary;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Thresholds of the comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaselineOptions {
    /// Relative slow-down the whole time-ratio interval must exceed to flag a run as slower.
    /// Default 0.2 (20 %): CPU times of unchanged code, one report on a quiet 2-core machine
    /// and one with a core taken by another process, had ratio intervals within it (see the
    /// README's timing protocol), and a method made 1.5 times slower is flagged.
    pub time_tolerance: f64,
    /// Milliseconds by which the run's time interval must lie above the baseline's (its
    /// lower bound over the baseline's upper bound) to flag it as slower. Default 1 ms: a
    /// run of a few milliseconds moves by a fraction of a millisecond of CPU time with the
    /// caches another process shares; `report --baseline-min-ms 0` compares ratios alone.
    pub min_change_ms: f64,
    /// Growth of the mean error (lit fraction) that flags a run as less accurate. Default
    /// 1e-6.
    pub error_tolerance: f64,
}

impl Default for BaselineOptions {
    fn default() -> Self {
        Self { time_tolerance: 0.2, min_change_ms: 1.0, error_tolerance: 1e-6 }
    }
}

/// Why an earlier report could not be read.
#[derive(Debug, thiserror::Error)]
pub enum BaselineError {
    /// The folder's `runs.json` cannot be compared with ([`validate`]).
    #[error("--baseline {dir}: {file}: {source}")]
    Invalid {
        /// The baseline folder.
        dir: PathBuf,
        /// The file.
        file: PathBuf,
        /// What is wrong.
        source: BaselineInvalid,
    },
    /// A file of the folder differs from what its manifest says was written (the source
    /// says which and how).
    #[error("--baseline {dir}")]
    Changed {
        /// The baseline folder.
        dir: PathBuf,
        /// Which file, how.
        source: crate::publish::PublishError,
    },
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

/// A baseline's `runs.json` that reads but cannot be compared with.
#[derive(Debug, thiserror::Error)]
pub enum BaselineInvalid {
    /// Written by a later version of the workbench, whose fields may mean other things.
    #[error("written by shadowbench {found}, later than this {ours}")]
    Version {
        /// The baseline's version.
        found: String,
        /// This workbench's.
        ours: String,
    },
    /// A run's time is not a time to compare with.
    #[error("run {run}: {field} {message}")]
    Time {
        /// The run, as `scene method parameters`.
        run: String,
        /// The field, as `total_ms.ci_low`.
        field: String,
        /// What is wrong.
        message: String,
    },
}

/// `a.b.c` as numbers; parts that are not numbers count as 0.
fn version_parts(v: &str) -> Vec<u64> {
    v.split(['.', '-', '+']).take(3).map(|p| p.parse().unwrap_or(0)).collect()
}

/// Checks that `report` can be compared with: a version no later than this one, and every
/// run's times finite, not negative, a positive median, and ordered (`min <= ci_low <= median
/// <= ci_high <= max`).
pub fn validate(report: &Report) -> Result<(), BaselineInvalid> {
    let ours = env!("CARGO_PKG_VERSION");
    let found = &report.provenance.version;
    if version_parts(found) > version_parts(ours) {
        return Err(BaselineInvalid::Version { found: found.clone(), ours: ours.to_owned() });
    }
    for r in &report.rows {
        let run = format!("{} {} {}", r.scene, r.method, params(r));
        let clocks = [("total_ms", Some(&r.total_ms)), ("cpu_ms", r.cpu_ms.as_ref())];
        for (name, summary) in clocks {
            let Some(t) = summary else { continue };
            let bad = |field: &str, message: String| BaselineInvalid::Time {
                run: run.clone(),
                field: format!("{name}.{field}"),
                message,
            };
            let values = [("min", Some(t.min)), ("ci_low", t.ci_low), ("median", Some(t.median))]
                .into_iter()
                .chain([("ci_high", t.ci_high), ("max", Some(t.max))]);
            let mut last: Option<(&str, f64)> = None;
            for (field, v) in values {
                let Some(v) = v else { continue };
                if !(v.is_finite() && v >= 0.0) {
                    return Err(bad(field, format!("is {v}, not a finite time >= 0")));
                }
                if let Some((before, u)) = last {
                    if v < u {
                        return Err(bad(field, format!("is {v}, below {before} {u}")));
                    }
                }
                last = Some((field, v));
            }
            if t.median <= 0.0 {
                return Err(bad("median", "is 0: no time to compare with".to_owned()));
            }
        }
    }
    Ok(())
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
    /// The clock the times were compared on.
    pub clock: Clock,
    /// Whether both runs had confidence intervals (else their ranges bound the ratio).
    pub intervals: bool,
    /// Median time now over before.
    pub time_ratio: f64,
    /// The ratio's interval (see the module documentation).
    pub time_ratio_ci: (f64, f64),
    /// The wall-time ratio and its interval, where neither run was contended.
    pub wall_ratio: Option<(f64, (f64, f64))>,
    /// The ratio of the wall-time medians, contended or not (for the distribution of what
    /// the machine's load did to wall times, [`ratio_summary`]).
    pub wall_median_ratio: f64,
    /// Whether either run was contended.
    pub contended: bool,
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

/// Reads the report in `dir` as a baseline: verified against its manifest where it has one
/// (`crate::publish::verify`), then [`load`] and [`validate`].
pub fn load_baseline(dir: &Path) -> Result<Report, BaselineError> {
    // A report written with a manifest is read only as it was written.
    if dir.join(crate::publish::MANIFEST).is_file() {
        crate::publish::verify(dir)
            .map_err(|source| BaselineError::Changed { dir: dir.to_owned(), source })?;
    }
    let report = load(dir)?;
    validate(&report).map_err(|source| BaselineError::Invalid {
        dir: dir.to_owned(),
        file: dir.join("runs.json"),
        source,
    })?;
    Ok(report)
}

/// The key a run is matched by: its scene, method, frame and the parameters its label names
/// (`crate::model::param_label`: the labelled ones and every other one not at its method's
/// default), so that a run recorded before a parameter was added (which its method then took
/// at its default) matches the same run recorded after.
fn key(r: &Row) -> (String, String, u32, u32, String) {
    (r.scene.clone(), r.method.clone(), r.width, r.height, crate::model::param_label(r))
}

/// The parameters of a row, as `map_res=1024 rate=16`.
fn params(r: &Row) -> String {
    r.params
        .iter()
        .map(|(k, v)| format!("{k}={}", v.to_string().trim_matches('"')))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The ratio of two summaries' medians and its interval, and whether both bounds were
/// confidence intervals.
fn ratio(now: &Summary, before: &Summary) -> (f64, (f64, f64), bool) {
    let ((lo, hi), a) = now.bounds();
    let ((lo_b, hi_b), b) = before.bounds();
    (now.median / before.median, (lo / hi_b, hi / lo_b), a && b)
}

/// Sets `now` against `before` (the report read from `dir`).
pub fn compare(now: &Report, before: &Report, dir: &Path, options: BaselineOptions) -> Comparison {
    let mut runs = Vec::new();
    for r in &now.rows {
        let Some(b) = before.rows.iter().find(|b| key(b) == key(r)) else { continue };
        // A clock both runs have: the report's, or wall time where either lacks CPU time.
        let clock = match (now.clock, &r.cpu_ms, &b.cpu_ms) {
            (Clock::Cpu, Some(_), Some(_)) => Clock::Cpu,
            _ => Clock::Wall,
        };
        let (t, tb) = (r.time(clock), b.time(clock));
        let (time_ratio, ci, intervals) = ratio(t, tb);
        let ((lo, hi), _) = t.bounds();
        let ((lo_b, hi_b), _) = tb.bounds();
        let contended = r.contended || b.contended;
        let wall = (!contended).then(|| {
            let (q, ci, _) = ratio(&r.total_ms, &b.total_ms);
            (q, ci)
        });
        let (e0, e1) = (b.metrics.mean_abs_error, r.metrics.mean_abs_error);
        runs.push(RunChange {
            scene: r.scene.clone(),
            method: r.method.clone(),
            params: params(r),
            error: (e0, e1),
            clock,
            intervals,
            time_ratio,
            time_ratio_ci: ci,
            wall_ratio: wall,
            wall_median_ratio: r.total_ms.median / b.total_ms.median,
            contended,
            slower: ci.0 > 1.0 + options.time_tolerance && lo - hi_b > options.min_change_ms,
            faster: ci.1 < 1.0 / (1.0 + options.time_tolerance)
                && lo_b - hi > options.min_change_ms,
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

/// The distribution of the runs' time ratios, now over before: the median and the 95th
/// percentile (nearest rank) on each run's clock, and of the wall-time medians' ratios of
/// every run, contended ones included; `None` without runs.
pub fn ratio_summary(c: &Comparison) -> Option<String> {
    let spread = |mut v: Vec<f64>| {
        v.retain(|x| x.is_finite());
        let p50 = analysis::metrics::nearest_rank(&mut v, 50)?;
        let p95 = analysis::metrics::nearest_rank(&mut v, 95)?;
        Some(format!("median {p50:.2}, p95 {p95:.2}"))
    };
    let clocks: Vec<&str> = {
        let mut v: Vec<&str> = c.runs.iter().map(|r| r.clock.name()).collect();
        v.dedup();
        v
    };
    let on_clock = spread(c.runs.iter().map(|r| r.time_ratio).collect())?;
    let wall = spread(c.runs.iter().map(|r| r.wall_median_ratio).collect())?;
    let contended = c.runs.iter().filter(|r| r.contended).count();
    Some(format!(
        "Time ratios ({} time) over {} runs: {on_clock}; wall-time ratios: {wall} ({contended} \
         runs contended in either report)",
        clocks.join(" and "),
        c.runs.len()
    ))
}

/// The comparison as Markdown: the summary first (counts and every regression), then every
/// run.
pub fn markdown(c: &Comparison) -> String {
    let mut s = format!("{}.\n\n", summary_line(c));
    if let Some(ratios) = ratio_summary(c) {
        let _ = writeln!(s, "{ratios}.\n");
    }
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
    s.push_str(
        "Time ratios are now over before, on the clock named per run; the interval combines \
         both medians' 95 % confidence intervals, or their ranges (`range`) where a run had \
         too few timed runs for one. Wall ratios only where neither run was contended.\n\n",
    );
    s.push_str(
        "| scene | method | parameters | error before | error now | time ratio [interval] | \
         wall ratio | flag |\n",
    );
    s.push_str("|---|---|---|---|---|---|---|---|\n");
    for r in &c.runs {
        let wall = r.wall_ratio.map_or_else(
            || "contended".to_owned(),
            |(q, (lo, hi))| format!("{q:.2} [{lo:.2}, {hi:.2}]"),
        );
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.6} | {:.6} | {} | {wall} | {} |",
            r.scene,
            r.method,
            r.params,
            r.error.0,
            r.error.1,
            time_text(r),
            flags(r)
        );
    }
    s
}

/// A run's time ratio on its clock with its interval, as `cpu 1.02 [0.95, 1.10]`.
fn time_text(r: &RunChange) -> String {
    let range = if r.intervals { "" } else { " range" };
    format!(
        "{} {:.2} [{:.2}, {:.2}]{range}",
        r.clock.name(),
        r.time_ratio,
        r.time_ratio_ci.0,
        r.time_ratio_ci.1
    )
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
    format!("time {}, error {:.6} -> {:.6}", time_text(r), r.error.0, r.error.1)
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

    /// A summary of nine timed runs around `ms`, with its interval.
    fn around(ms: f64) -> Summary {
        Summary::of(&[0.9, 0.95, 0.97, 0.99, 1.0, 1.01, 1.03, 1.05, 1.1].map(|f| f * ms))
            .expect("values")
    }

    #[test]
    fn a_report_against_itself_flags_nothing_and_a_slowed_method_is_flagged() {
        // Times of a tiny frame are too short to compare: every run is given the same spread.
        let mut report = small_report();
        for r in &mut report.rows {
            r.total_ms = around(10.0);
            r.cpu_ms = Some(around(15.0));
            r.contended = false;
        }
        let dir = Path::new("earlier");
        let same = compare(&report, &report, dir, BaselineOptions::default());
        assert_eq!(same.runs.len(), report.rows.len());
        assert_eq!((same.new_runs, same.dropped_runs), (0, 0));
        assert_eq!(same.regressions().count(), 0);
        assert!(same.runs.iter().all(|r| r.clock == Clock::Cpu && r.intervals));
        assert!(markdown(&same).contains("No regression."));

        // `pcf-gems4` made 1.5 times slower in CPU time, `sm` less accurate; every wall time
        // doubled, as on a loaded machine, which the CPU clock does not see.
        let mut slowed = report.clone();
        for r in &mut slowed.rows {
            r.total_ms = around(20.0);
            if r.method == "pcf-gems4" {
                r.cpu_ms = Some(around(22.5));
            } else {
                r.metrics.mean_abs_error += 1e-3;
            }
        }
        let c = compare(&slowed, &report, dir, BaselineOptions::default());
        for r in &c.runs {
            assert_eq!(r.slower, r.method == "pcf-gems4", "{r:?}");
            assert_eq!(r.less_accurate, r.method == "sm", "{r:?}");
            assert!(!r.faster);
            assert_eq!(r.wall_ratio.map(|w| w.0), Some(2.0));
        }
        let md = markdown(&c);
        assert!(md.contains("Regressions:") && md.contains("**pcf-gems4**"), "{md}");
        assert!(md.contains("cpu 1.50 ["), "{md}");
        // Two runs of four at 1.5 in CPU time, every wall time doubled.
        let ratios = ratio_summary(&c).expect("runs");
        assert!(ratios.contains("(cpu time) over 4 runs: median 1.00, p95 1.50"), "{ratios}");
        assert!(ratios.contains("wall-time ratios: median 2.00, p95 2.00"), "{ratios}");
        // And the other way round the slowed method got faster.
        let back = compare(&report, &slowed, dir, BaselineOptions::default());
        assert!(back.runs.iter().filter(|r| r.method == "pcf-gems4").all(|r| r.faster));

        // On the wall clock the doubled times are flagged; a contended run has no wall ratio.
        let wall = Report { clock: Clock::Wall, ..slowed.clone() };
        assert!(compare(&wall, &report, dir, BaselineOptions::default())
            .runs
            .iter()
            .all(|r| r.slower));
        slowed.rows[0].contended = true;
        let c = compare(&slowed, &report, dir, BaselineOptions::default());
        assert_eq!((c.runs[0].wall_ratio, c.runs[0].contended), (None, true));
        assert!(markdown(&c).contains("| contended |"));
    }

    #[test]
    fn a_run_recorded_before_a_parameter_existed_matches_the_same_run_at_its_default() {
        let report = small_report();
        let mut earlier = report.clone();
        for r in &mut earlier.rows {
            assert_eq!(r.params.remove("frustum"), Some("scene".into()), "{}", r.method);
        }
        let c = compare(&report, &earlier, Path::new("earlier"), BaselineOptions::default());
        assert_eq!((c.runs.len(), c.new_runs, c.dropped_runs), (report.rows.len(), 0, 0));
        // A value other than the default is another run.
        let mut other = report.clone();
        other.rows[0].params.insert("frustum".into(), "view".into());
        let c = compare(&other, &report, Path::new("earlier"), BaselineOptions::default());
        assert_eq!((c.new_runs, c.dropped_runs), (1, 1));
    }

    #[test]
    fn a_short_run_is_flagged_only_when_it_slows_by_more_than_the_floor() {
        // A 0.5 ms run taking twice as long: within the default floor, a regression when the
        // floor is 0.
        let mut report = small_report();
        report.rows.truncate(1);
        report.rows[0].cpu_ms = Some(around(0.5));
        let mut slowed = report.clone();
        slowed.rows[0].cpu_ms = Some(around(1.0));
        let dir = Path::new("earlier");
        let default = compare(&slowed, &report, dir, BaselineOptions::default());
        assert!(!default.runs[0].slower, "{:?}", default.runs[0]);
        let strict = BaselineOptions { min_change_ms: 0.0, ..Default::default() };
        assert!(compare(&slowed, &report, dir, strict).runs[0].slower);
        // 0.5 ms to 4 ms is more than the floor.
        slowed.rows[0].cpu_ms = Some(around(4.0));
        assert!(compare(&slowed, &report, dir, BaselineOptions::default()).runs[0].slower);
    }

    #[test]
    fn without_intervals_the_ranges_bound_the_ratio_and_a_missing_clock_falls_back_to_wall() {
        let mut report = small_report();
        report.rows.truncate(1);
        report.rows[0].cpu_ms = Summary::of(&[9.0, 10.0, 11.0]);
        let mut now = report.clone();
        now.rows[0].cpu_ms = Summary::of(&[13.0, 14.0, 15.0]);
        let dir = Path::new("earlier");
        let c = compare(&now, &report, dir, BaselineOptions::default());
        assert!(!c.runs[0].intervals);
        assert_eq!(c.runs[0].time_ratio_ci, (13.0 / 11.0, 15.0 / 9.0));
        assert!(!c.runs[0].slower, "13/11 is within 20 %");
        assert!(markdown(&c).contains("] range |"), "{}", markdown(&c));
        // A baseline of a version without CPU times is compared on wall time.
        report.rows[0].cpu_ms = None;
        assert_eq!(
            compare(&now, &report, dir, BaselineOptions::default()).runs[0].clock,
            Clock::Wall
        );
    }

    #[test]
    fn baselines_with_times_that_are_not_times_or_a_later_version_are_refused() {
        let mut report = small_report();
        report.rows.truncate(1);
        report.rows[0].total_ms = around(10.0);
        report.rows[0].cpu_ms = Some(around(12.0));
        assert!(validate(&report).is_ok());
        let refused = |edit: &dyn Fn(&mut Report)| {
            let mut r = report.clone();
            edit(&mut r);
            validate(&r).expect_err("refused").to_string()
        };
        let e = refused(&|r| r.rows[0].total_ms.median = -1.0);
        assert!(e.contains("total_ms.median") && e.contains("plane-square sm"), "{e}");
        let e = refused(&|r| r.rows[0].total_ms = Summary::of(&[0.0]).expect("a value"));
        assert!(e.contains("total_ms.median is 0"), "{e}");
        let e = refused(&|r| r.rows[0].total_ms.max = f64::INFINITY);
        assert!(e.contains("total_ms.max") && e.contains("inf"), "{e}");
        // An interval whose low end is above its high end.
        let e = refused(&|r| {
            let t = r.rows[0].cpu_ms.as_mut().expect("cpu");
            (t.ci_low, t.ci_high) = (t.ci_high, t.ci_low);
        });
        assert!(e.contains("cpu_ms.median") || e.contains("cpu_ms.ci_high"), "{e}");
        let e = refused(&|r| r.provenance.version = "99.0.0".into());
        assert!(e.contains("99.0.0") && e.contains("later"), "{e}");
        // An earlier version is compared with.
        let mut older = report.clone();
        older.provenance.version = "0.0.1".into();
        assert!(validate(&older).is_ok());
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
