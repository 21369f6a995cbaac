//! The section "Against today's techniques": a suite with `sm` (a seed) and `vsm` and `esm`
//! (today's techniques, by their entries in the methods' table) on one scene at 64 x 48 gives
//! the section in `index.html` and `report.md`, with its chart drawn and a table whose rows
//! are the scene's runs, each with its family and whether it is on the Pareto front, which is
//! checked against the runs' own times and errors. A suite without any of today's techniques
//! gives no section, and neither do today's techniques alone.

use reports::index::index_page;
use reports::today::{family_of, Family, FRONT_HEAD};
use reports::{run_suite, write_report, Report, Row, Suite};
use std::path::Path;

/// One quick scene, a seed at two map sizes and two of today's techniques.
const SUITE: &str = r#"
name = "today"
width = 64
height = 48
warmup = 0
repeats = 1
scenes = ["plane-square"]

[[run]]
method = "sm"
map_res = [64, 128]

[[run]]
method = "vsm"
map_res = [64, 128]

[[run]]
method = "esm"
map_res = [64]
"#;

/// The same scene with seeds only.
const SEEDS: &str = r#"
name = "seeds"
width = 64
height = 48
warmup = 0
repeats = 1
scenes = ["plane-square"]

[[run]]
method = "sm"
map_res = [64, 128]

[[run]]
method = "pcf-gems4"
map_res = [64]
"#;

/// The chart's stem for the scene.
const CHART: &str = "plots/today-vs-seeds-plane-square";

/// The report of `suite`, written into `out`.
fn report_into(suite: &str, out: &Path) -> Report {
    let suite = Suite::parse(suite, Path::new("today.toml")).expect("a valid suite");
    let (report, images) = run_suite(&suite, |_| {});
    assert!(report.skipped.is_empty(), "{:?}", report.skipped);
    write_report(out, &report, &images, None).expect("written");
    report
}

/// Whether `r` is on the Pareto front of `rows` by their own numbers: no other run at least
/// as fast on the report's clock and as accurate, and better in one of the two.
fn undominated(report: &Report, rows: &[Row], r: &Row) -> bool {
    let at = |r: &Row| (r.time(report.clock).median, r.metrics.mean_abs_error);
    let (t, e) = at(r);
    !rows.iter().map(at).any(|(u, f)| u <= t && f <= e && (u < t || f < e))
}

/// The cells of each body row of the first `<table class="sortable CLASS">` of `html`, as
/// text without their tags.
fn table_cells(html: &str, class: &str) -> Vec<Vec<String>> {
    let start = html.find(&format!("<table class=\"sortable {class}\">")).expect("the table");
    let table = &html[start..];
    let body = &table[..table.find("</table>").expect("its end")];
    let body = body.split("<tbody>").nth(1).expect("a body");
    body.split("<tr>")
        .skip(1)
        .map(|row| {
            row.split("<td")
                .skip(1)
                .map(|cell| {
                    let inner = cell.split_once('>').map_or("", |(_, rest)| rest);
                    let inner = inner.split("</td>").next().unwrap_or_default();
                    // Without the link around the method.
                    let text = inner
                        .split('>')
                        .nth(1)
                        .map_or(inner, |t| t.split('<').next().unwrap_or_default());
                    text.to_owned()
                })
                .collect()
        })
        .collect()
}

#[test]
fn todays_techniques_against_a_seed_give_the_section_with_its_chart_and_front() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path();
    let report = report_into(SUITE, out);
    let methods: Vec<&str> = report.rows.iter().map(|r| r.method.as_str()).collect();
    assert_eq!(methods, ["sm", "sm", "vsm", "vsm", "esm"]);
    let families: Vec<Option<Family>> = report.rows.iter().map(family_of).collect();
    assert_eq!(families[..2], [Some(Family::Seed); 2]);
    assert_eq!(families[2..], [Some(Family::Today); 3]);

    // The chart, as PNG and SVG, shown in the section once.
    for ext in ["png", "svg"] {
        assert!(out.join(format!("{CHART}.{ext}")).is_file(), "{CHART}.{ext}");
    }
    let html = std::fs::read_to_string(out.join("index.html")).expect("index.html");
    assert_eq!(html.matches("<section id=\"today\">").count(), 1);
    assert!(html.contains("href=\"#today\"") && html.contains("href=\"#today-plane-square\""));
    assert_eq!(html.matches(&format!("src=\"{CHART}.png\"")).count(), 1, "{html}");
    assert!(html.contains("<dt>today's techniques, seeds</dt>"), "in the glossary");

    // The table: a row per run, in report order, its family and front flag; the flags are
    // the runs' own front.
    let page = index_page(&report, &[], None);
    let section = page.today.expect("the section");
    let [scene] = &section.scenes[..] else { panic!("{:?}", section.scenes) };
    let heads: Vec<&str> = scene.table.heads.iter().map(|h| h.text.as_str()).collect();
    let family = heads.iter().position(|h| *h == "family").expect("a family column");
    let front = heads.iter().position(|h| *h == FRONT_HEAD).expect("a front column");
    assert_eq!(scene.table.rows.len(), report.rows.len());
    let cells = table_cells(&html, "today");
    assert_eq!(cells.len(), report.rows.len(), "the page's table: {cells:?}");
    let mut on = 0;
    for ((row, model), shown) in report.rows.iter().zip(&scene.table.rows).zip(&cells) {
        let flag = if undominated(&report, &report.rows, row) { "yes" } else { "no" };
        on += usize::from(flag == "yes");
        assert_eq!(model[0].text, row.method);
        assert_eq!(
            model[family].text,
            if row.method == "sm" { "seed (2001-2014)" } else { "today" }
        );
        assert_eq!(model[front].text, flag, "{} {:?}", row.method, row.params);
        assert_eq!(shown[0], row.method, "{shown:?}");
        assert_eq!(shown[front], flag, "{shown:?}");
    }
    assert!(on >= 1, "the fastest run is on the front");
    assert!(scene.about.contains(&format!("{on} of its 5 runs on the Pareto front")));
    // The time column reads the report's clock.
    assert!(heads.contains(&"CPU ms (95 % interval)"), "{heads:?}");

    // report.md: the same table under the section's heading, and the chart.
    let md = std::fs::read_to_string(out.join("report.md")).expect("report.md");
    let part = md.split("## Against today's techniques").nth(1).expect("the section");
    assert!(part.contains("### plane-square: today's techniques against the seeds"), "{md}");
    assert!(part.contains(&format!("]({CHART}.png)")), "{md}");
    let head = format!("| {} |", heads.join(" | "));
    let table = part.split(&head).nth(1).expect("the table's head");
    let lines: Vec<&str> = table.lines().skip(2).take_while(|l| l.starts_with("| ")).collect();
    assert_eq!(lines.len(), report.rows.len(), "{table}");
    for (line, row) in lines.iter().zip(&scene.table.rows) {
        let expected: Vec<&str> = row.iter().map(|c| c.text.as_str()).collect();
        assert_eq!(*line, format!("| {} |", expected.join(" | ")));
    }

    // Today's techniques alone: no section.
    let mut alone = report.clone();
    alone.rows.retain(|r| family_of(r) == Some(Family::Today));
    assert!(index_page(&alone, &[], None).today.is_none());
}

#[test]
fn seeds_alone_give_no_section() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path();
    let report = report_into(SEEDS, out);
    assert_eq!(report.rows.len(), 3);
    let html = std::fs::read_to_string(out.join("index.html")).expect("index.html");
    assert!(!html.contains("id=\"today\"") && !html.contains("href=\"#today"), "{html}");
    assert!(!out.join(format!("{CHART}.png")).exists());
    let md = std::fs::read_to_string(out.join("report.md")).expect("report.md");
    assert!(!md.contains("today's techniques"), "{md}");
    assert!(index_page(&report, &[], None).today.is_none());
}
