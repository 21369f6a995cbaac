//! A page per run of a report, `runs/ID.html` (ID: the run's file stem,
//! [`crate::write::row_stem`]), beside the method's image `runs/ID.png` (the lit fraction as
//! 8-bit grey: black in shadow, white lit) and linked to its visibility buffer
//! `visibility/ID.exr`.
//!
//! A page shows the run's parameters, metrics, stage times and counters, and a comparison
//! view (plain JavaScript from `reports/assets/report.js`, nothing from the network): zoom
//! with the wheel or `+`/`-`, pan by dragging, `0` to fit; flip between this run's image and
//! those of the scene's other runs with the buttons, the list, the arrow keys or `n`/`p`, and
//! back to this run with `f`; `s` swipes between the two (this run left of the pointer, the
//! other right of it). Opened as `ID.html#selftest`, the page flips, zooms, pans and
//! swipes itself and writes what it found into `<pre id="selftest">`.

use crate::html::{anchor, escape, metric_cells, page_head, params_of, Cell, METRIC_COLUMNS};
use crate::output::OutputError;
use crate::sweep::{Produced, Report, Row};
use crate::write::{param_label, row_stem};
use methods::Visibility;
use std::fmt::Write as _;
use std::path::Path;

/// A run's lit fraction as 8-bit grey (0 in shadow, 255 lit).
pub fn lit_image(v: &Visibility) -> image::GrayImage {
    image::GrayImage::from_fn(v.width, v.height, |x, y| {
        let l = v.lit[(y * v.width + x) as usize];
        image::Luma([(l.clamp(0.0, 1.0) * 255.0).round() as u8])
    })
}

/// What a run is called on its page and in the list of views.
fn title(r: &Row) -> String {
    let params = param_label(r);
    if params.is_empty() {
        r.method.clone()
    } else {
        format!("{} {params}", r.method)
    }
}

/// A two-column table of names and cells.
fn key_value_table(rows: &[(String, Cell)]) -> String {
    let mut s = String::from("<table>\n");
    for (k, c) in rows {
        let _ = writeln!(s, "<tr><th class=\"text\">{}</th>{}</tr>", escape(k), c.td());
    }
    s.push_str("</table>\n");
    s
}

/// The page of `report.rows[row]`; `views` are the rows whose images the comparison view
/// flips between, this one first.
pub fn run_page(report: &Report, row: usize, views: &[usize]) -> String {
    let r = &report.rows[row];
    let stem = row_stem(r);
    let mut s = page_head(&format!("{} on {}", title(r), r.scene));
    let _ = writeln!(
        s,
        "<h1><code>{method}</code> on <code>{scene}</code></h1>\n<p>{params}</p>\n<p><a \
         href=\"../index.html#scene-{id}-runs\">back to the report</a> · files: <a \
         href=\"../visibility/{stem}.exr\">visibility buffer (EXR)</a>, <a \
         href=\"{stem}.png\">this image (PNG)</a>, <a href=\"../runs.json\">runs.json</a></p>",
        method = escape(&r.method),
        scene = escape(&r.scene),
        params = escape(&param_label(r)),
        id = anchor(&r.scene),
        stem = escape(&stem),
    );
    s.push_str(
        "<h2 id=\"compare\">Comparison</h2>\n<p>Lit fraction, black in shadow, white lit. Wheel \
         or <kbd>+</kbd>/<kbd>-</kbd> zoom, drag pans, <kbd>0</kbd> fits; <kbd>&larr;</kbd> \
         <kbd>&rarr;</kbd> (or <kbd>p</kbd> <kbd>n</kbd>) step through the scene's runs, \
         <kbd>f</kbd> flips between this run and the last one viewed, <kbd>s</kbd> swipes \
         between them (this run left of the pointer, the other right of it).</p>\n<div \
         class=\"controls\"><button id=\"prev\">&larr; previous</button><select \
         id=\"view-select\" aria-label=\"image shown\">",
    );
    for (k, &v) in views.iter().enumerate() {
        let mark = if k == 0 { " (this run)" } else { "" };
        let _ =
            write!(s, "<option value=\"{k}\">{}{mark}</option>", escape(&title(&report.rows[v])));
    }
    s.push_str(
        "</select><button id=\"next\">next &rarr;</button><button id=\"flip\">flip (f)</button>\
         <button id=\"swipe\">swipe (s)</button><button id=\"fit\">fit (0)</button> <span \
         id=\"view-label\"></span></div>\n<div \
         class=\"viewer\" id=\"viewer\" tabindex=\"0\"><div class=\"stage\">",
    );
    for (k, &v) in views.iter().enumerate() {
        let label =
            if k == 0 { format!("{} (this run)", title(r)) } else { title(&report.rows[v]) };
        let _ = write!(
            s,
            "<img class=\"view\" src=\"{}.png\" alt=\"{label}\" data-label=\"{label}\">",
            escape(&row_stem(&report.rows[v])),
            label = escape(&label),
        );
    }
    s.push_str("</div></div>\n");

    s.push_str("<h2 id=\"parameters\">Parameters</h2>\n");
    let mut params: Vec<(String, Cell)> =
        params_of(r).into_iter().map(|(k, v)| (k, Cell::text(v))).collect();
    params.push(("frame".into(), Cell::text(format!("{}x{}", r.width, r.height))));
    let reference = match r.ref_rate {
        Some(rate) => format!("{} at {rate} samples per pixel", r.reference),
        None => r.reference.clone(),
    };
    params.push(("reference".into(), Cell::text(reference)));
    s.push_str(&key_value_table(&params));

    s.push_str(
        "<h2 id=\"metrics\">Metrics</h2>\n<p>Over the reference's shadow-only pixels; see the \
         <a href=\"../index.html#glossary\">glossary</a>.</p>\n",
    );
    let mut metrics = vec![
        ("compared pixels".to_owned(), Cell::num(r.metrics.evaluated_pixels as f64, 0)),
        (
            "max abs error".to_owned(),
            if r.metrics.evaluated_pixels == 0 {
                Cell::na()
            } else {
                Cell::num(r.metrics.max_abs_error, 5)
            },
        ),
    ];
    metrics.extend(METRIC_COLUMNS.iter().map(|c| c.to_string()).zip(metric_cells(r)));
    s.push_str(&key_value_table(&metrics));

    let _ = writeln!(
        s,
        "<h2 id=\"times\">Stage times</h2>\n<p>Milliseconds, median of {} runs after {} warm-up, \
         with minimum and maximum.</p>\n<table><tr><th class=\"text\">stage</th><th>median</th>\
         <th>min</th><th>max</th></tr>",
        report.suite.repeats, report.suite.warmup
    );
    for st in &r.stages {
        let _ = writeln!(
            s,
            "<tr><td>{}</td>{}{}{}</tr>",
            escape(&st.name),
            Cell::num(st.ms.median, 3).td(),
            Cell::num(st.ms.min, 3).td(),
            Cell::num(st.ms.max, 3).td()
        );
    }
    let t = &r.total_ms;
    let _ = writeln!(
        s,
        "<tr><th class=\"text\">total</th>{}{}{}</tr></table>",
        Cell::num(t.median, 3).td(),
        Cell::num(t.min, 3).td(),
        Cell::num(t.max, 3).td()
    );
    if !r.skipped_stages.is_empty() {
        let _ = writeln!(
            s,
            "<p>Stages the scene did not call for: {}.</p>",
            escape(&r.skipped_stages.join(", "))
        );
    }
    let counters: Vec<(String, Cell)> = r
        .counters
        .entries()
        .into_iter()
        .filter(|(_, v)| *v != 0)
        .map(|(k, v)| (k.to_owned(), Cell::num(v as f64, 0)))
        .collect();
    if !counters.is_empty() {
        s.push_str("<h2 id=\"counters\">Counters</h2>\n<p>Of the last timed run; those at zero are left out.</p>\n");
        s.push_str(&key_value_table(&counters));
    }
    if !r.notes.is_empty() {
        s.push_str("<h2 id=\"notes\">Notes</h2>\n<ul>\n");
        for n in &r.notes {
            let _ = writeln!(s, "<li>{}</li>", escape(n));
        }
        s.push_str("</ul>\n");
    }
    s.push_str("</body></html>\n");
    s
}

/// Writes, for every produced run, `dir/runs/ID.png` (its lit fraction) and `dir/runs/ID.html`
/// (its page, flipping between the images of its scene's produced runs). Returns the pages'
/// paths relative to `dir`, in the order of `produced`.
pub fn write_run_pages(
    dir: &Path,
    report: &Report,
    produced: &[Produced],
) -> Result<Vec<String>, OutputError> {
    let err = |path: &Path, e: &dyn std::fmt::Display| OutputError::Write {
        path: path.to_owned(),
        message: e.to_string(),
    };
    let runs = dir.join("runs");
    std::fs::create_dir_all(&runs).map_err(|e| err(&runs, &e))?;
    for p in produced {
        let path = runs.join(format!("{}.png", row_stem(&report.rows[p.row])));
        lit_image(&p.visibility).save(&path).map_err(|e| err(&path, &e))?;
    }
    let mut pages = Vec::with_capacity(produced.len());
    for p in produced {
        let scene = &report.rows[p.row].scene;
        let views: Vec<usize> = std::iter::once(p.row)
            .chain(
                produced
                    .iter()
                    .map(|q| q.row)
                    .filter(|&q| q != p.row && report.rows[q].scene == *scene),
            )
            .collect();
        let name = format!("runs/{}.html", row_stem(&report.rows[p.row]));
        let path = dir.join(&name);
        std::fs::write(&path, run_page(report, p.row, &views)).map_err(|e| err(&path, &e))?;
        pages.push(name);
    }
    Ok(pages)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lit_fraction_is_grey() {
        let v = Visibility { width: 3, height: 1, lit: vec![0.0, 0.5, 1.0], transmittance: None };
        let g = lit_image(&v);
        assert_eq!(g.as_raw(), &[0, 128, 255]);
    }
}
