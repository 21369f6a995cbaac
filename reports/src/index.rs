//! `index.html`: the report as one page that opens in any browser from the file system (no
//! server, no script from elsewhere): a header with the machine, a contents list, the scenes,
//! per scene its charts and its table of runs (each run linked to its page, `runs/ID.html`,
//! [`crate::run_pages`]), CPU and GPU side by side, the papers' tables, a glossary of the
//! metrics, and what did not run. Images are files beside the page (`plots/*.png`, with the
//! SVG linked).
//!
//! The style and the script are embedded in the page (`reports/assets/report.css` and
//! `report.js`): tables sort by clicking a header (numbers as numbers, `n/a` last) and filter
//! by a text box; parameters that are the same over a whole table are stated once above it,
//! and a method's parameters that are the same over all its rows once per method. The script
//! marks every image `data-loaded="yes"` or `"no"` once the page has loaded, and the page
//! opened as `index.html#selftest` sorts and filters its first run table and writes what it
//! found into `<pre id="selftest">`, for a headless browser to check.

use crate::baseline::Comparison;
use crate::figures::PlotFile;
use crate::html::{
    adapter_html, anchor, escape, list_section, metric_cells, page_head, sortable_table, Cell,
    ParamSplit, METRIC_COLUMNS,
};
use crate::model::{params_of, row_stem, Report, Row};
use std::fmt::Write as _;

/// The table of one scene's runs.
fn runs_table(rows: &[&Row]) -> String {
    let split = ParamSplit::of(rows);
    let mut heads: Vec<(String, bool)> = vec![("method".into(), false)];
    heads
        .extend(split.columns.iter().map(|c| (c.to_string(), !matches!(*c, "pattern" | "device"))));
    if split.others {
        heads.push(("other parameters".into(), false));
    }
    heads.extend(METRIC_COLUMNS.iter().map(|c| (c.to_string(), true)));
    heads.extend(["time ms (median)", "min", "max"].iter().map(|c| (c.to_string(), true)));
    let body: Vec<String> = rows
        .iter()
        .map(|r| {
            let p = params_of(r);
            let mut s = format!(
                "<td><a href=\"runs/{}.html\">{}</a></td>",
                escape(&row_stem(r)),
                escape(&r.method)
            );
            for c in &split.columns {
                let v = p.get(*c).cloned().unwrap_or_default();
                let cell = match v.parse::<f64>() {
                    Ok(x) => Cell { text: v, value: Some(x) },
                    Err(_) => Cell::text(v),
                };
                s.push_str(&cell.td());
            }
            if split.others {
                s.push_str(&Cell::text(split.other_params(r)).td());
            }
            for c in metric_cells(r) {
                s.push_str(&c.td());
            }
            for t in [r.total_ms.median, r.total_ms.min, r.total_ms.max] {
                s.push_str(&Cell::num(t, 2).td());
            }
            s
        })
        .collect();
    split.html() + &sortable_table("runs", &heads, &body)
}

/// The glossary: what every quantity of the report means.
const GLOSSARY: &str = "<h2 id=\"glossary\">Glossary</h2>\n<dl class=\"glossary\">\n\
<dt>lit fraction</dt><dd>The fraction of a pixel's square that the light reaches, in [0, 1]: \
what every method computes and every reference gives exactly (<code>exact</code>) or by \
sampling (<code>raytrace</code>).</dd>\n\
<dt>pixel classes</dt><dd>What a pixel's square sees, decided exactly from the camera's view \
of the triangles: <b>planar</b>, the square sees one planar object and nothing else; \
<b>surface</b>, the square is tiled without gap or overlap by front-facing triangles of one \
continuous surface with nothing in front of them; <b>edge</b>, anything else (a silhouette, a \
depth discontinuity, several objects, background, a visible back face); <b>uncovered</b>, the \
square sees no geometry.</dd>\n\
<dt>shadow-only pixels</dt><dd>The pixels the metrics are taken over: the planar and surface \
pixels the reference evaluated (for <code>raytrace</code>, which has no classes of its own, \
by the classes of the camera's view of the triangles). On edge \
pixels the error is the camera's aliasing, not the shadow's, so they are left out.</dd>\n\
<dt>mean abs error</dt><dd>The mean of |method - reference| of the lit fraction over the \
shadow-only pixels.</dd>\n\
<dt>RMSE</dt><dd>The root mean square of method - reference over the same pixels: it weighs \
large errors more than the mean does.</dd>\n\
<dt>boundary pixels</dt><dd>Shadow-only pixels whose reference lit fraction is strictly \
between 0 and 1: the penumbra and the shadow's edges, where antialiasing matters.</dd>\n\
<dt>boundary error</dt><dd>The mean abs error over the boundary pixels only.</dd>\n\
<dt>p50 / p95 / p99 of the boundary error</dt><dd>The 50th, 95th and 99th percentiles of \
|method - reference| over the boundary pixels, by the nearest-rank definition (with the n \
errors sorted, the one of rank ceil(p n)): the typical and the worst errors at the shadow's \
edges.</dd>\n\
<dt>FLIP</dt><dd>NVIDIA's FLIP (Andersson et al., \"FLIP: A Difference Evaluator for \
Alternating Images\", HPG 2020): the perceived difference between the shaded method image and \
the shaded reference, per pixel in [0, 1], averaged over the frame; only shadow-only pixels \
may differ.</dd>\n\
<dt>pixel match</dt><dd>As reported here: the share of shadow-only pixels within half an \
8-bit step (0.5/255) of the reference. Against an exact reference an antialiased value hits \
a pixel's coverage only by luck, so this mostly measures how much of the frame is fully lit \
or fully shadowed. In Lecocq et al.'s sense (\"Sub-Pixel Shadow Mapping\", I3D 2014): the \
share of pixels whose binary lit/shadowed value equals that of <code>raytrace</code> at rate \
1 (one sample per pixel), for methods whose output is binary at that setting.</dd>\n\
<dt>error distribution</dt><dd>For the runs on a scene's Pareto front, the share of \
shadow-only pixels whose |method - reference| exceeds x, for x from 1e-4 to 0.9 (log-log). A \
curve ends where no pixel's error exceeds x. At x = 0.5/255 the share is one minus the pixel \
match; a curve that falls late has a tail of large errors that its mean hides.</dd>\n\
<dt>error map</dt><dd>On a run's page: |method - reference| on the shadow-only pixels in \
false colour (magma, black at 0, pale yellow at 0.1 and above), dark grey where nothing is \
compared, with its colour bar.</dd>\n\
<dt>n/a</dt><dd>The quantity does not apply: no pixel was compared, or (boundary error) the \
reference has no boundary pixel.</dd>\n\
<dt>time</dt><dd>The method's own stages, median of the timed runs after the warm-up, with \
their minimum and maximum; the camera G-buffer, shared by every method of a scene, is listed \
per scene.</dd>\n</dl>\n";

/// The page.
pub fn index_html(report: &Report, plots: &[PlotFile], baseline: Option<&Comparison>) -> String {
    let mut s = page_head(&format!("shadowbench report: {}", report.suite.name));
    let (m, p) = (&report.machine, &report.provenance);
    let _ = write!(
        s,
        "<header><h1>shadowbench report: suite <code>{name}</code></h1>\n<p>{desc}</p>\n\
         <p id=\"machine\">Machine: {cpu} ({cores} cores, {threads} threads, {os}); GPU: {gpu}. \
         Times: median of {rep} runs after {warm} warm-up, [min, max].</p>\n<p \
         id=\"provenance\">Produced by shadowbench {version}, commit <code>{commit}</code>{dirty}, \
         built with {rustc}, at {time}, by <code>{command}</code>. Everything as CSV: <a \
         href=\"runs.csv\">runs.csv</a>, as JSON: <a href=\"runs.json\">runs.json</a>.</p>\
         </header>\n",
        name = escape(&report.suite.name),
        desc = escape(&report.suite.description),
        cpu = escape(&m.cpu),
        cores = m.cores,
        threads = m.threads,
        os = escape(&m.os),
        gpu = adapter_html(m.gpu.as_deref()),
        rep = report.suite.repeats,
        warm = report.suite.warmup,
        version = escape(&p.version),
        commit = escape(&p.commit),
        dirty = if p.dirty { " (with local changes)" } else { "" },
        rustc = escape(&p.rustc),
        time = escape(&p.timestamp),
        command = escape(&p.command),
    );
    s.push_str(&contents(report, plots, baseline.is_some()));
    if let Some(c) = baseline {
        s.push_str(&baseline_section(c));
    }
    s.push_str("<h2 id=\"scenes\">Scenes</h2>\n");
    let heads: Vec<(String, bool)> = [
        ("scene", false),
        ("triangles", true),
        ("effects", false),
        ("frame", false),
        ("G-buffer ms", true),
        ("reference", false),
        ("reference ms", true),
    ]
    .iter()
    .map(|(h, n)| (h.to_string(), *n))
    .collect();
    let body: Vec<String> = report
        .scenes
        .iter()
        .map(|sc| {
            format!(
                "<td><a href=\"#scene-{id}\">{name}</a></td>{}{}{}{}{}{}",
                Cell::num(sc.triangles as f64, 0).td(),
                Cell::text(sc.effects.join(", ")).td(),
                Cell::text(format!("{}x{}", sc.width, sc.height)).td(),
                Cell::num(sc.gbuffer_ms, 1).td(),
                Cell::text(&sc.reference).td(),
                Cell::num(sc.reference_ms, 1).td(),
                id = anchor(&sc.scene),
                name = escape(&sc.scene),
            )
        })
        .collect();
    s.push_str(&sortable_table("scenes", &heads, &body));
    for (k, p) in plots.iter().filter(|p| p.scene.is_empty()).enumerate() {
        let _ = writeln!(
            s,
            "<figure id=\"summary-plot-{k}\"><img src=\"{png}\" alt=\"{t}\"><figcaption>{t} (<a \
             href=\"{svg}\">SVG</a>)</figcaption></figure>",
            png = escape(&p.png),
            svg = escape(&(p.png.trim_end_matches(".png").to_owned() + ".svg")),
            t = escape(&p.title)
        );
    }
    for sc in &report.scenes {
        let id = anchor(&sc.scene);
        let _ = writeln!(s, "<h2 id=\"scene-{id}\">{}</h2>", escape(&sc.scene));
        for (k, g) in report.grids.iter().filter(|g| g.scene == sc.scene).enumerate() {
            let _ = writeln!(
                s,
                "<figure id=\"scene-{id}-grid-{k}\"><img src=\"{png}\" alt=\"{t}\">\
                 <figcaption>{t}</figcaption></figure>",
                png = escape(&g.png),
                t = escape(&g.title)
            );
        }
        for (k, p) in plots.iter().filter(|p| p.scene == sc.scene).enumerate() {
            let svg = p.png.trim_end_matches(".png").to_owned() + ".svg";
            let _ = writeln!(
                s,
                "<div class=\"beside\"><figure id=\"scene-{id}-plot-{k}\"><img src=\"{png}\" \
                 alt=\"{t}\"><figcaption>{t} (<a href=\"{svg}\">SVG</a>)</figcaption></figure>{pareto}\
                 </div>",
                png = escape(&p.png),
                svg = escape(&svg),
                t = escape(&p.title),
                pareto = pareto_table(p),
            );
        }
        let rows: Vec<&Row> = report.rows.iter().filter(|r| r.scene == sc.scene).collect();
        let ref_rate = rows.first().and_then(|r| r.ref_rate);
        let _ = writeln!(
            s,
            "<h3 id=\"scene-{id}-runs\">Runs on {name}</h3>\n<p class=\"constant\">Frame {w}x{h}; \
             reference <code>{reference}</code>{rate}; metrics over the shadow-only pixels (see \
             the <a href=\"#glossary\">glossary</a>). Each method links to its run's page.</p>",
            name = escape(&sc.scene),
            w = sc.width,
            h = sc.height,
            reference = escape(&sc.reference),
            rate = ref_rate.map_or_else(String::new, |r| format!(" at {r} samples per pixel")),
        );
        if !rows.is_empty() {
            s.push_str(&runs_table(&rows));
        }
    }
    s.push_str(&devices_section(report));
    if !report.tables.is_empty() {
        s.push_str("<h2 id=\"tables\">The papers' tables</h2>\n");
        for t in &report.tables {
            let _ = writeln!(
                s,
                "<h3 id=\"table-{id}\">{}</h3>\n<p>Paper's figures measured on: {}. {} (<a \
                 href=\"tables/{}.csv\">CSV</a>)</p>\n<table><tr>{}</tr>",
                escape(&t.title),
                escape(&t.paper_hardware),
                escape(&t.notes.join(" ")),
                t.paper.name(),
                t.header.iter().map(|c| format!("<th>{}</th>", escape(c))).collect::<String>(),
                id = t.paper.name(),
            );
            for r in &t.rows {
                let cells: String = r.iter().map(|c| format!("<td>{}</td>", escape(c))).collect();
                let _ = writeln!(s, "<tr>{cells}</tr>");
            }
            s.push_str("</table>\n");
            if crate::tables::chart(t).is_some() {
                let _ = writeln!(
                    s,
                    "<figure id=\"table-{id}-chart\"><img src=\"plots/{id}.png\" alt=\"{t}\">\
                     <figcaption>{t}, log-log (<a href=\"plots/{id}.svg\">SVG</a>)</figcaption>\
                     </figure>",
                    id = t.paper.name(),
                    t = escape(&t.title),
                );
            }
        }
    }
    s.push_str(GLOSSARY);
    s.push_str(&list_section("skipped", "Not run", &report.skipped));
    s.push_str("</body></html>\n");
    s
}

/// The contents list: every section, and under each scene its figures and its table.
fn contents(report: &Report, plots: &[PlotFile], baseline: bool) -> String {
    let mut s = String::from("<nav class=\"contents\"><b>Contents</b><ul>\n");
    if baseline {
        s.push_str("<li><a href=\"#baseline\">Against the baseline</a></li>\n");
    }
    s.push_str("<li><a href=\"#scenes\">Scenes</a></li>\n");
    for (k, p) in plots.iter().filter(|p| p.scene.is_empty()).enumerate() {
        let _ = writeln!(s, "<li><a href=\"#summary-plot-{k}\">{}</a></li>", escape(&p.title));
    }
    for sc in &report.scenes {
        let id = anchor(&sc.scene);
        let _ = write!(s, "<li><a href=\"#scene-{id}\">{}</a><ul>", escape(&sc.scene));
        for (k, g) in report.grids.iter().filter(|g| g.scene == sc.scene).enumerate() {
            let _ = write!(s, "<li><a href=\"#scene-{id}-grid-{k}\">{}</a></li>", escape(&g.title));
        }
        for (k, p) in plots.iter().filter(|p| p.scene == sc.scene).enumerate() {
            let _ = write!(s, "<li><a href=\"#scene-{id}-plot-{k}\">{}</a></li>", escape(&p.title));
        }
        let _ = writeln!(s, "<li><a href=\"#scene-{id}-runs\">runs</a></li></ul></li>");
    }
    if !crate::devices::pairs(&report.rows).is_empty() {
        s.push_str("<li><a href=\"#devices\">CPU and GPU</a></li>\n");
    }
    if !report.tables.is_empty() {
        s.push_str("<li><a href=\"#tables\">The papers' tables</a><ul>");
        for t in &report.tables {
            let _ = write!(
                s,
                "<li><a href=\"#table-{}\">{}</a></li>",
                t.paper.name(),
                escape(&t.title)
            );
        }
        s.push_str("</ul></li>\n");
    }
    s.push_str("<li><a href=\"#glossary\">Glossary</a></li>\n");
    if !report.skipped.is_empty() {
        s.push_str("<li><a href=\"#skipped\">Not run</a></li>\n");
    }
    s.push_str("</ul></nav>\n");
    s
}

/// The runs on a chart's Pareto front as a table (empty for charts without one).
fn pareto_table(p: &PlotFile) -> String {
    if p.pareto.is_empty() {
        return String::new();
    }
    let mut s = String::from(
        "<table class=\"pareto\"><caption>Pareto front: no run is both faster and more \
         accurate</caption><tr><th>method</th><th>parameters</th><th>time ms</th><th>mean \
         error</th></tr>",
    );
    for e in &p.pareto {
        let _ = write!(
            s,
            "<tr><td>{}</td><td>{}</td><td>{:.1}</td><td>{:.6}</td></tr>",
            escape(&e.method),
            escape(&e.params),
            e.time_ms,
            e.error
        );
    }
    s.push_str("</table>");
    s
}

/// The comparison with an earlier report: counts, every regression, and a link to the whole
/// comparison (`baseline.md`).
fn baseline_section(c: &Comparison) -> String {
    let mut s = String::from("<section id=\"baseline\"><h2>Against the baseline</h2>\n");
    let _ = writeln!(
        s,
        "<p>{}. The whole comparison, run by run: <a href=\"baseline.md\">baseline.md</a>.</p>",
        escape(&crate::baseline::summary_line(c))
    );
    let regressions: Vec<_> = c.regressions().collect();
    if regressions.is_empty() {
        s.push_str("<p>No regression.</p>\n");
    } else {
        s.push_str("<ul class=\"regressions\">\n");
        for r in regressions {
            let _ = writeln!(
                s,
                "<li><b>{}</b> {} on {}: {} (time x{:.2} [{:.2}, {:.2}], error {:.6} -> {:.6})</li>",
                escape(&r.method),
                escape(&r.params),
                escape(&r.scene),
                escape(&crate::baseline::flags(r)),
                r.time_ratio,
                r.time_ratio_ci.0,
                r.time_ratio_ci.1,
                r.error.0,
                r.error.1
            );
        }
        s.push_str("</ul>\n");
    }
    s.push_str("</section>\n");
    s
}

/// CPU and GPU side by side, the parameters common to every pair stated once.
fn devices_section(report: &Report) -> String {
    let pairs = crate::devices::pairs(&report.rows);
    if pairs.is_empty() {
        return String::new();
    }
    let cpu_rows: Vec<&Row> = pairs.iter().map(|p| p.cpu).collect();
    let split = ParamSplit::of(&cpu_rows);
    let mut s = format!(
        "<h2 id=\"devices\">CPU and GPU</h2>\n<p>The same method and parameters on both devices; \
         GPU: {}.</p>\n",
        adapter_html(report.machine.gpu.as_deref())
    );
    if !split.constant.is_empty() {
        let kv: Vec<String> = split
            .constant
            .iter()
            .filter(|(k, _)| *k != "device")
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        let _ = writeln!(s, "<p class=\"constant\">Every pair: {}.</p>", escape(&kv.join(", ")));
    }
    let heads: Vec<(String, bool)> =
        crate::devices::COLUMNS.iter().enumerate().map(|(k, c)| (c.to_string(), k >= 3)).collect();
    let body: Vec<String> = pairs
        .iter()
        .map(|p| {
            let mut cells = crate::devices::cells(p);
            cells[2] = params_of(p.cpu)
                .into_iter()
                .filter(|(k, _)| k != "device" && !split.constant.contains_key(k))
                .map(|(k, v)| format!("{k}={v}"))
                .collect::<Vec<_>>()
                .join(" ");
            cells.iter().map(|c| format!("<td>{}</td>", escape(c))).collect()
        })
        .collect();
    s + &sortable_table("devices", &heads, &body)
}
