//! `index.html`: the report as one page that opens in any browser from the file system (no
//! server, no script from elsewhere): the machine, the scenes, and per scene its charts and
//! its table of runs. Images are files beside the page (`plots/*.png`, with the SVG linked).
//!
//! A small inline script marks, once the page has loaded, every image with
//! `data-loaded="yes"` or `"no"`, so that a headless browser can check that nothing is broken.

use crate::figures::PlotFile;
use crate::sweep::Report;
use crate::write::{run_cells, RUN_COLUMNS};
use std::fmt::Write as _;

/// Escapes text for HTML.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

const STYLE: &str = "body{font-family:sans-serif;margin:2em;max-width:1100px}\
table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;\
text-align:right}td:first-child,th:first-child{text-align:left}img{max-width:100%;\
border:1px solid #ddd}figure{margin:1em 0}";

const CHECK: &str = "window.addEventListener('load',function(){for(const i of document.images)\
{i.setAttribute('data-loaded',i.complete&&i.naturalWidth>0?'yes':'no');}\
document.body.setAttribute('data-checked','yes');});";

/// The page.
pub fn index_html(report: &Report, plots: &[PlotFile]) -> String {
    let mut s = String::new();
    let m = &report.machine;
    let _ = write!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>shadowbench \
         report: {name}</title><style>{STYLE}</style><script>{CHECK}</script></head><body>\n\
         <h1>shadowbench report: suite <code>{name}</code></h1>\n<p>{desc}</p>\n<p>Machine: {cpu} \
         ({cores} cores, {threads} threads, {os}); GPU: {gpu}. Times: median of {rep} runs after \
         {warm} warm-up, [min, max]; a method's time is its own stages (the camera G-buffer is \
         shared and listed per scene). Tables as CSV: <a href=\"runs.csv\">runs.csv</a>, \
         everything as JSON: <a href=\"runs.json\">runs.json</a>.</p>\n",
        name = escape(&report.suite.name),
        desc = escape(&report.suite.description),
        cpu = escape(&m.cpu),
        cores = m.cores,
        threads = m.threads,
        os = escape(&m.os),
        gpu = escape(m.gpu.as_deref().unwrap_or("none used")),
        rep = report.suite.repeats,
        warm = report.suite.warmup,
    );
    s.push_str(
        "<h2>Scenes</h2>\n<table><tr><th>scene</th><th>triangles</th><th>effects</th>\
         <th>frame</th><th>G-buffer ms</th><th>reference</th><th>reference ms</th></tr>\n",
    );
    for sc in &report.scenes {
        let _ = writeln!(
            s,
            "<tr><td><a href=\"#{id}\">{name}</a></td><td>{}</td><td>{}</td><td>{}x{}</td>\
             <td>{:.1}</td><td>{}</td><td>{:.1}</td></tr>",
            sc.triangles,
            escape(&sc.effects.join(", ")),
            sc.width,
            sc.height,
            sc.gbuffer_ms,
            escape(&sc.reference),
            sc.reference_ms,
            id = escape(&sc.scene),
            name = escape(&sc.scene),
        );
    }
    s.push_str("</table>\n");
    for sc in &report.scenes {
        let _ = writeln!(s, "<h2 id=\"{0}\">{0}</h2>", escape(&sc.scene));
        for g in report.grids.iter().filter(|g| g.scene == sc.scene) {
            let _ = writeln!(
                s,
                "<figure><img src=\"{png}\" alt=\"{t}\"><figcaption>{t}</figcaption></figure>",
                png = escape(&g.png),
                t = escape(&g.title)
            );
        }
        for p in plots.iter().filter(|p| p.scene == sc.scene) {
            let svg = p.png.trim_end_matches(".png").to_owned() + ".svg";
            let _ = writeln!(
                s,
                "<figure><img src=\"{png}\" alt=\"{t}\"><figcaption>{t} (<a href=\"{svg}\">SVG</a>)\
                 </figcaption></figure>",
                png = escape(&p.png),
                svg = escape(&svg),
                t = escape(&p.title)
            );
        }
        let head: Vec<String> =
            RUN_COLUMNS.iter().map(|c| format!("<th>{}</th>", escape(c))).collect();
        let _ = writeln!(s, "<table><tr>{}</tr>", head.concat());
        for r in report.rows.iter().filter(|r| r.scene == sc.scene) {
            let cells: Vec<String> =
                run_cells(r).iter().map(|c| format!("<td>{}</td>", escape(c))).collect();
            let _ = writeln!(s, "<tr>{}</tr>", cells.concat());
        }
        s.push_str("</table>\n");
    }
    let pairs = crate::devices::pairs(&report.rows);
    if !pairs.is_empty() {
        let _ = writeln!(
            s,
            "<h2 id=\"devices\">CPU and GPU</h2>\n<p>The same method and parameters on both \
             devices; GPU: {}.</p>",
            escape(report.machine.gpu.as_deref().unwrap_or("none"))
        );
        let head: Vec<String> =
            crate::devices::COLUMNS.iter().map(|c| format!("<th>{}</th>", escape(c))).collect();
        let _ = writeln!(s, "<table><tr>{}</tr>", head.concat());
        for p in &pairs {
            let cells: Vec<String> = crate::devices::cells(p)
                .iter()
                .map(|c| format!("<td>{}</td>", escape(c)))
                .collect();
            let _ = writeln!(s, "<tr>{}</tr>", cells.concat());
        }
        s.push_str("</table>\n");
    }
    if !report.tables.is_empty() {
        s.push_str("<h2 id=\"tables\">The papers' tables</h2>\n");
        for t in &report.tables {
            let _ = writeln!(
                s,
                "<h3>{}</h3>\n<p>Paper's figures measured on: {}. {} (<a href=\"tables/{}.csv\">CSV\
                 </a>)</p>\n<table><tr>{}</tr>",
                escape(&t.title),
                escape(&t.paper_hardware),
                escape(&t.notes.join(" ")),
                t.paper.name(),
                t.header.iter().map(|c| format!("<th>{}</th>", escape(c))).collect::<String>()
            );
            for r in &t.rows {
                let cells: String = r.iter().map(|c| format!("<td>{}</td>", escape(c))).collect();
                let _ = writeln!(s, "<tr>{cells}</tr>");
            }
            s.push_str("</table>\n");
        }
    }
    if !report.skipped.is_empty() {
        s.push_str("<h2>Not run</h2>\n<ul>\n");
        for k in &report.skipped {
            let _ = writeln!(s, "<li>{}</li>", escape(k));
        }
        s.push_str("</ul>\n");
    }
    s.push_str("</body></html>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup() {
        assert_eq!(escape("<a href=\"x\">&</a>"), "&lt;a href=&quot;x&quot;&gt;&amp;&lt;/a&gt;");
    }
}
