//! The answer a report leads with, computed from its runs: per scene the runs on its Pareto
//! front (mean error against time on the report's clock, [`fronts`]), per method what the
//! runs say of it ([`verdicts`]: on how many scenes' fronts it is, where it is the most
//! accurate or the fastest, where it comes within twice the least error fastest), the machine
//! and the load the times were taken under ([`measured`]), and the best error of each method
//! within each time budget ([`budget_table`]).
//!
//! `index.html` shows the fronts, the verdicts and the machine on its first screen, and
//! `report.md` at its top. Every sentence is generated from the rows; none is written by hand.

use crate::figures::{best_within, clock_name, params_text, pareto_rows, BUDGETS_MS};
use crate::model::{row_stem, Report, Row};
use instrumentation::stats::Summary;
use serde::Serialize;

/// A time in milliseconds with as many decimals as it needs: `0.123`, `1.23`, `12.3`, `123`.
pub fn ms_text(v: f64) -> String {
    match v.abs() {
        a if a < 1.0 => format!("{v:.3}"),
        a if a < 10.0 => format!("{v:.2}"),
        a if a < 100.0 => format!("{v:.1}"),
        _ => format!("{v:.0}"),
    }
}

/// A mean error: four decimals from 0.001, three significant digits below, `0` for none.
pub fn error_text(e: f64) -> String {
    if e == 0.0 {
        "0".to_owned()
    } else if e.abs() >= 1e-3 {
        format!("{e:.4}")
    } else {
        format!("{e:.2e}")
    }
}

/// The median's confidence interval, `1.20–1.31`, or `no interval` with too few timed runs
/// for one (never the [min, max]).
pub fn interval_text(t: &Summary) -> String {
    match (t.ci_low, t.ci_high) {
        (Some(lo), Some(hi)) => format!("{}–{}", ms_text(lo), ms_text(hi)),
        _ => "no interval".to_owned(),
    }
}

/// A time on the report's clock as a table shows it: `1.23 (1.20–1.31)` or
/// `1.23 (no interval)`.
pub fn time_text(t: &Summary) -> String {
    format!("{} ({})", ms_text(t.median), interval_text(t))
}

/// A time in full: `1.23 (1.20–1.31) [1.10, 1.50]`, median, its interval (or `no interval`)
/// and [min, max].
pub fn full_time_text(t: &Summary) -> String {
    format!("{} [{}, {}]", time_text(t), ms_text(t.min), ms_text(t.max))
}

/// A run's swept parameters and device in few words: `map 512, 16x, grid, gpu` (other
/// parameters not at their method's default as `filter 5`).
pub fn short_params(r: &Row) -> String {
    let mut words = Vec::new();
    for (key, v) in [
        ("map_res", r.param("map_res")),
        ("rate", r.param("rate")),
        ("depth_bits", r.param("depth_bits")),
        ("pattern", r.param("pattern")),
    ] {
        if v.is_empty() {
            continue;
        }
        words.push(match key {
            "map_res" => format!("map {v}"),
            "rate" => format!("{v}x"),
            "depth_bits" => format!("{v} bits"),
            _ => v,
        });
    }
    for key in crate::model::other_params(r) {
        words.push(format!("{key} {}", r.param(key)));
    }
    if r.on_gpu() {
        words.push("gpu".into());
    }
    words.join(", ")
}

/// One run on a scene's Pareto front.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrontRun {
    /// Method.
    pub method: String,
    /// Its swept parameters and device (`map_res=512 rate=16`).
    pub params: String,
    /// The same in few words (`map 512, 16x`).
    pub short: String,
    /// Its page, relative to the report folder.
    pub page: String,
    /// Mean absolute error on the shadow-only pixels.
    pub error: f64,
    /// The same as text.
    pub error_text: String,
    /// Median time on the report's clock, as text.
    pub time_text: String,
    /// The median's confidence interval, or `no interval`.
    pub interval_text: String,
    /// Median wall time, as text.
    pub wall_text: String,
    /// Whether a timed run was contended (its wall time is not to be trusted).
    pub contended: bool,
}

/// A scene's Pareto front: the runs no other run of the scene beats in both error and time.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Front {
    /// Scene.
    pub scene: String,
    /// Its section's anchor in `index.html` (`scene-NAME`).
    pub anchor: String,
    /// Frame, `160x120`.
    pub frame: String,
    /// The reference the errors are taken against.
    pub reference: String,
    /// How many runs the scene has.
    pub runs_total: usize,
    /// The front's runs, fastest first.
    pub runs: Vec<FrontRun>,
}

/// The front's runs of `rows` on the report's clock, fastest first.
fn front_runs(report: &Report, rows: &[&Row]) -> Vec<FrontRun> {
    pareto_rows(rows, report.clock)
        .into_iter()
        .map(|r| {
            let t = r.time(report.clock);
            FrontRun {
                method: crate::model::method_label(r),
                params: params_text(r),
                short: short_params(r),
                page: format!("runs/{}.html", row_stem(r)),
                error: r.metrics.mean_abs_error,
                error_text: error_text(r.metrics.mean_abs_error),
                time_text: ms_text(t.median),
                interval_text: interval_text(t),
                wall_text: ms_text(r.total_ms.median),
                contended: r.contended,
            }
        })
        .collect()
}

/// Every scene's Pareto front, in report order (scenes without runs left out).
pub fn fronts(report: &Report) -> Vec<Front> {
    report
        .scenes
        .iter()
        .filter_map(|sc| {
            let rows = report.scene_rows(&sc.scene);
            (!rows.is_empty()).then(|| Front {
                scene: sc.scene.clone(),
                anchor: format!("scene-{}", crate::html::anchor(&sc.scene)),
                frame: format!("{}x{}", sc.width, sc.height),
                reference: sc.reference.clone(),
                runs_total: rows.len(),
                runs: front_runs(report, &rows),
            })
        })
        .collect()
}

/// What the runs say of one method.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verdict {
    /// Method.
    pub method: String,
    /// On how many scenes' fronts it has a run.
    pub fronts: usize,
    /// The sentences, each true of the rows (`on the Pareto front on 3 of 5 scenes (7 runs)`).
    pub sentences: Vec<String>,
}

/// Names as `a`, `a and b`, `a, b and c`.
fn and_list(names: &[String]) -> String {
    match names {
        [] => String::new(),
        [one] => one.clone(),
        [init @ .., last] => format!("{} and {last}", init.join(", ")),
    }
}

/// What each scene says of its methods: the most accurate, the fastest, and the fastest to
/// come within twice the least error when that is another method.
struct SceneFacts<'a> {
    scene: String,
    front: Vec<&'a Row>,
    most_accurate: Vec<String>,
    fastest: Vec<String>,
    /// The fastest run within twice the least error and the most accurate run, when their
    /// methods differ.
    near: Option<(&'a Row, &'a Row)>,
}

fn facts<'a>(report: &'a Report, scene: &str) -> Option<SceneFacts<'a>> {
    let rows = report.scene_rows(scene);
    let clock = report.clock;
    let least = rows.iter().map(|r| r.metrics.mean_abs_error).fold(f64::INFINITY, f64::min);
    let quickest = rows.iter().map(|r| r.time(clock).median).fold(f64::INFINITY, f64::min);
    if !least.is_finite() {
        return None;
    }
    let methods_where = |keep: &dyn Fn(&Row) -> bool| {
        let mut m: Vec<String> = Vec::new();
        for r in rows.iter().filter(|r| keep(r)) {
            if !m.contains(&r.method) {
                m.push(r.method.clone());
            }
        }
        m
    };
    let most_accurate = methods_where(&|r| r.metrics.mean_abs_error == least);
    let fastest = methods_where(&|r| r.time(clock).median == quickest);
    let by_time = |a: &&&Row, b: &&&Row| a.time(clock).median.total_cmp(&b.time(clock).median);
    let best = rows.iter().filter(|r| r.metrics.mean_abs_error == least).min_by(by_time);
    let near = rows.iter().filter(|r| r.metrics.mean_abs_error <= 2.0 * least).min_by(by_time);
    let near = match (near, best) {
        (Some(n), Some(b)) if least > 0.0 && !most_accurate.contains(&n.method) => Some((*n, *b)),
        _ => None,
    };
    Some(SceneFacts {
        scene: scene.to_owned(),
        front: pareto_rows(&rows, clock),
        most_accurate,
        fastest,
        near,
    })
}

/// What the runs say of each method that is on some scene's Pareto front or best somewhere,
/// those on the most fronts first (then in report order); the methods on no front and best
/// nowhere are the second list.
pub fn verdicts(report: &Report) -> (Vec<Verdict>, Vec<String>) {
    let clock = report.clock;
    let unit = format!("{} ms", clock_name(clock));
    let all: Vec<&Row> = report.rows.iter().collect();
    let methods = crate::figures::methods_in(&all);
    let scenes: Vec<SceneFacts<'_>> =
        report.scenes.iter().filter_map(|sc| facts(report, &sc.scene)).collect();
    let n = scenes.len();
    let mut out: Vec<Verdict> = Vec::new();
    let mut nowhere: Vec<String> = Vec::new();
    for m in methods {
        let on: Vec<String> = scenes
            .iter()
            .filter(|s| s.front.iter().any(|r| r.method == m))
            .map(|s| s.scene.clone())
            .collect();
        let runs: usize =
            scenes.iter().map(|s| s.front.iter().filter(|r| r.method == m).count()).sum();
        let mut sentences = Vec::new();
        let runs_text = if runs == 1 { "1 run".to_owned() } else { format!("{runs} runs") };
        if n == 1 && !on.is_empty() {
            sentences.push(format!("on the Pareto front ({runs_text})"));
        } else if on.len() == n && n > 0 {
            sentences.push(format!("on the Pareto front on all {n} scenes ({runs_text})"));
        } else if !on.is_empty() {
            sentences.push(format!(
                "on the Pareto front on {} of {n} scenes ({runs_text}: {})",
                on.len(),
                and_list(&on)
            ));
        }
        let listed = |pick: &dyn Fn(&SceneFacts<'_>) -> bool| -> Vec<String> {
            scenes.iter().filter(|s| pick(s)).map(|s| s.scene.clone()).collect()
        };
        let accurate = listed(&|s| s.most_accurate.contains(&m));
        if !accurate.is_empty() {
            sentences.push(if n == 1 {
                "the most accurate".to_owned()
            } else {
                format!("the most accurate on {}", and_list(&accurate))
            });
        }
        let fastest = listed(&|s| s.fastest.contains(&m));
        if !fastest.is_empty() {
            sentences.push(if n == 1 {
                "the fastest".to_owned()
            } else {
                format!("the fastest on {}", and_list(&fastest))
            });
        }
        for s in &scenes {
            if let Some((near, best)) = s.near.filter(|(r, _)| r.method == m) {
                let on = if n == 1 { String::new() } else { format!(" on {}", s.scene) };
                let what = [best.method.clone(), short_params(best)]
                    .into_iter()
                    .filter(|w| !w.is_empty())
                    .collect::<Vec<_>>()
                    .join(" ");
                sentences.push(format!(
                    "the fastest within twice the least error{on}: {} {unit}, against {} for the \
                     most accurate ({what})",
                    ms_text(near.time(clock).median),
                    ms_text(best.time(clock).median),
                ));
            }
        }
        if sentences.is_empty() {
            nowhere.push(m);
        } else {
            out.push(Verdict { method: m, fronts: on.len(), sentences });
        }
    }
    out.sort_by_key(|v| std::cmp::Reverse(v.fronts));
    (out, nowhere)
}

/// The machine and the conditions the times were taken under, as the first screen states
/// them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Measured {
    /// `report.machine.line()`: cores, CPU, threads, system, the load average over the sweep.
    pub machine: String,
    /// The GPU adapter, when a method ran on one.
    pub gpu: Option<String>,
    /// Whether that adapter is a software rasterizer.
    pub gpu_software: bool,
    /// The clock's name (`CPU`, `wall`).
    pub clock: String,
    /// How the clock's figures are taken.
    pub clock_means: String,
    /// The protocol: timed runs per run and warm-up.
    pub protocol: String,
    /// Runs with a contended timed run.
    pub contended: usize,
    /// Runs in all.
    pub runs: usize,
}

/// The machine, the clock and the load of `report`.
pub fn measured(report: &Report) -> Measured {
    let s = &report.suite;
    let max = s.protocol().max_repeats;
    let timed =
        if max > s.repeats { format!("{} to {max}", s.repeats) } else { s.repeats.to_string() };
    Measured {
        machine: report.machine.line(),
        gpu: report.machine.gpu.clone(),
        gpu_software: report
            .machine
            .gpu
            .as_deref()
            .is_some_and(crate::devices::is_software_adapter),
        clock: clock_name(report.clock).to_owned(),
        clock_means: report.clock.describe().to_owned(),
        protocol: format!(
            "median of {timed} timed {} after {} warm-up",
            if max == 1 { "run" } else { "runs" },
            s.warmup
        ),
        contended: report.rows.iter().filter(|r| r.contended).count(),
        runs: report.rows.len(),
    }
}

impl Measured {
    /// The whole statement in one paragraph of text.
    pub fn text(&self) -> String {
        let gpu = match &self.gpu {
            Some(g) if self.gpu_software => format!("; GPU: {g} (a software rasterizer)"),
            Some(g) => format!("; GPU: {g}"),
            None => String::new(),
        };
        format!(
            "Measured on {}{gpu}. Cost is {} time ({}), {}; wall time beside it. {}",
            self.machine,
            self.clock,
            self.clock_means,
            self.protocol,
            self.contended_text()
        )
    }

    /// How many runs were contended, and what that means.
    pub fn contended_text(&self) -> String {
        match self.contended {
            0 => format!("No run of {} was contended.", self.runs),
            k => format!(
                "{k} of {} runs contended: another process took the cores, so their wall \
                 times are not to be trusted.",
                self.runs
            ),
        }
    }
}

/// One scene and method of the budget table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BudgetRow {
    /// Scene.
    pub scene: String,
    /// Method.
    pub method: String,
    /// Per budget of [`BUDGETS_MS`], the least error of its runs that fit it.
    pub best: Vec<Option<f64>>,
    /// Per budget, whether that is the least error of the scene's methods within it.
    pub winner: Vec<bool>,
}

/// The best error of every method within each budget, per scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BudgetTable {
    /// The budgets' heads, `<= 10 CPU ms`.
    pub heads: Vec<String>,
    /// Every scene's methods, in report order.
    pub rows: Vec<BudgetRow>,
}

/// The budget table of `report`.
pub fn budget_table(report: &Report) -> BudgetTable {
    let clock = report.clock;
    let mut rows = Vec::new();
    for sc in &report.scenes {
        let mine = report.scene_rows(&sc.scene);
        let best: Vec<Vec<(String, Option<f64>)>> =
            BUDGETS_MS.iter().map(|&b| best_within(&mine, b, clock)).collect();
        let least: Vec<f64> = best
            .iter()
            .map(|per| per.iter().filter_map(|(_, e)| *e).fold(f64::INFINITY, f64::min))
            .collect();
        for (k, (m, _)) in best.first().into_iter().flatten().enumerate() {
            let errors: Vec<Option<f64>> = best.iter().map(|per| per[k].1).collect();
            rows.push(BudgetRow {
                scene: sc.scene.clone(),
                method: m.clone(),
                winner: errors.iter().zip(&least).map(|(e, l)| *e == Some(*l)).collect(),
                best: errors,
            });
        }
    }
    BudgetTable {
        heads: BUDGETS_MS.iter().map(|b| format!("<= {b} {} ms", clock_name(clock))).collect(),
        rows,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report() -> Report {
        crate::sweep::report_of(
            r#"
            name = "summary"
            width = 48
            height = 36
            warmup = 0
            repeats = 1
            scenes = ["plane-square", "cage"]
            [[run]]
            method = "sm"
            map_res = [64, 512]
            [[run]]
            method = "pcf-gems4"
            map_res = [256]
            "#,
        )
    }

    #[test]
    fn the_sentences_are_true_of_the_rows() {
        let mut report = report();
        let fronts = fronts(&report);
        assert_eq!(fronts.len(), 2);
        for f in &fronts {
            let rows = report.scene_rows(&f.scene);
            assert_eq!(f.runs_total, rows.len());
            // No run of the scene beats a front run in both error and time.
            for run in &f.runs {
                let r = rows
                    .iter()
                    .find(|r| format!("runs/{}.html", row_stem(r)) == run.page)
                    .expect("a run of the scene");
                let t = r.time(report.clock).median;
                assert!(!rows.iter().any(|o| o.time(report.clock).median < t
                    && o.metrics.mean_abs_error < r.metrics.mean_abs_error));
            }
        }
        let (verdicts, nowhere) = verdicts(&report);
        for v in &verdicts {
            let on = fronts.iter().filter(|f| f.runs.iter().any(|r| r.method == v.method)).count();
            assert_eq!(v.fronts, on, "{v:?}");
            if on == 2 {
                assert!(v.sentences[0].starts_with("on the Pareto front on all 2 scenes"), "{v:?}");
            }
        }
        // Every method is said something of, or listed as on no front.
        assert_eq!(verdicts.len() + nowhere.len(), 2);
        // The least error of each scene is named.
        for f in &fronts {
            let best = f.runs.last().expect("a front run");
            let v = verdicts.iter().find(|v| v.method == best.method).expect("a verdict");
            assert!(
                v.sentences
                    .iter()
                    .any(|s| s.starts_with("the most accurate") && s.contains(&f.scene)),
                "{v:?}"
            );
        }
        // The machine line names the clock and the contended runs.
        for r in &mut report.rows {
            r.contended = false;
        }
        report.rows[0].contended = true;
        let m = measured(&report);
        assert_eq!((m.contended, m.runs), (1, 6));
        let text = m.text();
        assert!(
            text.contains("Cost is CPU time") && text.contains("1 of 6 runs contended"),
            "{text}"
        );
        assert!(text.contains(&report.machine.line()), "{text}");
    }

    #[test]
    fn numbers_read_at_a_glance_and_no_interval_is_said() {
        assert_eq!(
            (ms_text(0.1234), ms_text(1.234), ms_text(12.34), ms_text(1234.0)),
            ("0.123".into(), "1.23".into(), "12.3".into(), "1234".into())
        );
        assert_eq!(error_text(0.012345), "0.0123");
        assert_eq!(error_text(1.5e-5), "1.50e-5");
        let few = Summary::of(&[1.0, 2.0, 3.0]).expect("times");
        assert_eq!(time_text(&few), "2.00 (no interval)");
        let many = Summary::of(&[1.0, 1.1, 1.2, 1.3, 1.4, 1.5, 1.6, 1.7]).expect("times");
        assert!(time_text(&many).contains('–'), "{}", time_text(&many));
    }

    #[test]
    fn the_budget_table_marks_the_least_error_within_each_budget() {
        let report = report();
        let t = budget_table(&report);
        assert_eq!(t.heads[0], "<= 10 CPU ms");
        assert_eq!(t.rows.len(), 4, "two methods on two scenes");
        for sc in ["plane-square", "cage"] {
            for k in 0..BUDGETS_MS.len() {
                let mine: Vec<&BudgetRow> = t.rows.iter().filter(|r| r.scene == sc).collect();
                let least = mine.iter().filter_map(|r| r.best[k]).fold(f64::INFINITY, f64::min);
                for r in mine {
                    assert_eq!(r.winner[k], r.best[k] == Some(least));
                }
            }
        }
    }
}
