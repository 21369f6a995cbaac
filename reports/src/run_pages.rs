//! A page per run of a report, `runs/ID.html` (ID: the run's file stem,
//! [`crate::model::row_stem`]), with the run's files beside it:
//!
//! - `runs/ID.png`: the method's lit fraction as 8-bit grey (black in shadow, white lit);
//! - `runs/ID.error.png`: `|method - reference|` on the compared pixels in false colour
//!   (magma, 0 to [`analysis::error_map::DEFAULT_MAX_ERROR`], with its colour bar; dark grey
//!   where nothing is compared), as `compare` writes `error.png`;
//! - `runs/ID.run.json`: the run record of its last timed run, as `render` writes `run.json`;
//! - `runs/ID.metrics.json`: its comparison with the reference, per pixel class, as `compare`
//!   writes `metrics.json`;
//! - `visibility/ID.exr`: its visibility buffer;
//!
//! and its scene's, shared by the scene's runs ([`scene_files`]): the reference's lit
//! fraction (`scenes/SCENE.reference.png`, and `.exr`) and the pixel classes
//! (`scenes/SCENE.classes.png`).
//!
//! A page shows the run's parameters, metrics (the headline and each pixel class), stage
//! times and counters, and a comparison view (plain JavaScript from
//! `reports/assets/report.js`, nothing from the network) over the run's image, the reference,
//! the error map, the class map and the images of the scene's other runs: zoom with the wheel
//! or `+`/`-`, pan by dragging, `0` to fit; step through the views with the buttons, the list,
//! the arrow keys or `n`/`p`; `f` flips between this run and the last other view (the
//! reference at first); `s` swipes between the two (this run left of the pointer, the other
//! right of it). `ID.html#view=N` opens the page on view N (1 the reference, 2 the error
//! map, 3 the class map). Opened as `ID.html#selftest`, the page flips, zooms, pans and swipes itself
//! and writes what it found into `<pre id="selftest">`.

use crate::html::{anchor, escape, list_section, metric_cells, page_head, Cell, METRIC_COLUMNS};
use crate::model::{param_label, params_of, row_stem, scene_stem, Images, Report, Row};
use crate::output::{write_run_json, write_visibility_exr, OutputError};
use analysis::metrics::PerClass;
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

/// One image of the comparison view.
#[derive(Debug, Clone, PartialEq)]
pub struct View {
    /// The image, relative to the page.
    pub src: String,
    /// What it is.
    pub label: String,
}

/// The views of the run `report.rows[row]`: its image, the reference, its error map, the
/// class map, then the images of the scene's other runs (same scene and frame) in report
/// order.
pub fn views(report: &Report, row: usize) -> Vec<View> {
    let r = &report.rows[row];
    let stem = row_stem(r);
    let scene = scene_stem(&r.scene);
    let mut v = vec![
        View { src: format!("{stem}.png"), label: format!("{} (this run)", title(r)) },
        View {
            src: format!("../scenes/{scene}.reference.png"),
            label: format!("reference ({})", reference_text(r)),
        },
        View {
            src: format!("{stem}.error.png"),
            label: format!(
                "|error| of this run, 0 to {} (magma)",
                analysis::error_map::DEFAULT_MAX_ERROR
            ),
        },
        View {
            src: format!("../scenes/{scene}.classes.png"),
            label: "pixel classes (blue planar, green surface, red edge, black uncovered)".into(),
        },
    ];
    let same = |o: &Row| o.scene == r.scene && (o.width, o.height) == (r.width, r.height);
    v.extend(
        report
            .rows
            .iter()
            .enumerate()
            .filter(|(k, o)| *k != row && same(o))
            .map(|(_, o)| View { src: format!("{}.png", row_stem(o)), label: title(o) }),
    );
    v
}

/// The reference a row was measured against, in words.
fn reference_text(r: &Row) -> String {
    match r.ref_rate {
        Some(rate) => format!("{} at {rate} samples per pixel", r.reference),
        None => r.reference.clone(),
    }
}

/// The page of the run `report.rows[row]`.
pub fn run_page(report: &Report, row: usize) -> String {
    let r = &report.rows[row];
    let stem = row_stem(r);
    let scene = scene_stem(&r.scene);
    let mut s = page_head(&format!("{} on {}", title(r), r.scene));
    let _ = writeln!(
        s,
        "<h1><code>{method}</code> on <code>{scene_name}</code></h1>\n<p>{params}</p>\n<p><a \
         href=\"../index.html#scene-{id}-runs\">back to the report</a></p>\n<p>This run: <a \
         href=\"../visibility/{stem}.exr\">visibility buffer (EXR)</a>, <a \
         href=\"{stem}.png\">image (PNG)</a>, <a href=\"{stem}.error.png\">error map (PNG)</a>, \
         <a href=\"{stem}.run.json\">run.json</a>, <a \
         href=\"{stem}.metrics.json\">metrics.json</a>. The scene: <a \
         href=\"../scenes/{scene}.reference.exr\">reference (EXR)</a>, <a \
         href=\"../scenes/{scene}.reference.png\">reference (PNG)</a>, <a \
         href=\"../scenes/{scene}.classes.png\">pixel classes (PNG)</a>. All runs: <a \
         href=\"../runs.json\">runs.json</a>, <a href=\"../runs.csv\">runs.csv</a>.</p>",
        method = escape(&r.method),
        scene_name = escape(&r.scene),
        params = escape(&param_label(r)),
        id = anchor(&r.scene),
        stem = escape(&stem),
        scene = escape(&scene),
    );
    let views = views(report, row);
    s.push_str(
        "<h2 id=\"compare\">Comparison</h2>\n<p>Lit fraction in grey, black in shadow, white \
         lit; the error map in magma from black (no error) to pale yellow (0.1 or more), dark \
         grey where nothing is compared, with its colour bar below it. Wheel or \
         <kbd>+</kbd>/<kbd>-</kbd> zoom, drag pans, <kbd>0</kbd> fits; <kbd>&larr;</kbd> \
         <kbd>&rarr;</kbd> (or <kbd>p</kbd> <kbd>n</kbd>) step through the views, <kbd>f</kbd> \
         flips between this run and the last other view (the reference at first), <kbd>s</kbd> \
         swipes between them (this run left of the pointer, the other right of it).</p>\n<div \
         class=\"controls\"><button id=\"prev\">&larr; previous</button><select \
         id=\"view-select\" aria-label=\"image shown\">",
    );
    for (k, v) in views.iter().enumerate() {
        let _ = write!(s, "<option value=\"{k}\">{}</option>", escape(&v.label));
    }
    s.push_str(
        "</select><button id=\"next\">next &rarr;</button><button id=\"flip\">flip (f)</button>\
         <button id=\"swipe\">swipe (s)</button><button id=\"fit\">fit (0)</button> <span \
         id=\"view-label\"></span></div>\n<div \
         class=\"viewer\" id=\"viewer\" tabindex=\"0\"><div class=\"stage\">",
    );
    for v in &views {
        let _ = write!(
            s,
            "<img class=\"view\" src=\"{}\" alt=\"{label}\" data-label=\"{label}\">",
            escape(&v.src),
            label = escape(&v.label),
        );
    }
    s.push_str("</div></div>\n");

    s.push_str("<h2 id=\"parameters\">Parameters</h2>\n");
    let mut params: Vec<(String, Cell)> =
        params_of(r).into_iter().map(|(k, v)| (k, Cell::text(v))).collect();
    params.push(("frame".into(), Cell::text(format!("{}x{}", r.width, r.height))));
    params.push(("reference".into(), Cell::text(reference_text(r))));
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
    if let Some(classes) = &r.classes {
        s.push_str(&class_table(classes));
    }

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
    s.push_str(&list_section("notes", "Notes", &r.notes));
    s.push_str("</body></html>\n");
    s
}

/// Each pixel class's metrics (`metrics.json`'s `classes`), `n/a` where a class has no
/// compared pixel.
fn class_table(classes: &PerClass) -> String {
    let mut s = String::from(
        "<h3 id=\"classes\">By pixel class</h3>\n<p>Pixels the reference evaluated, by class; \
         the headline above is planar and surface together. Edge pixels are not referenced in \
         a report (their error is the camera's aliasing), so their row is n/a.</p>\n<table><tr>\
         <th class=\"text\">class</th><th>pixels</th><th>mean abs error</th><th>RMSE</th>\
         <th>max</th><th>p95</th><th>boundary pixels</th><th>boundary error</th>\
         <th>boundary p95</th></tr>\n",
    );
    for (name, m) in
        [("planar", &classes.planar), ("surface", &classes.surface), ("edge", &classes.edge)]
    {
        let or_na = |v: Option<f64>| v.map_or_else(Cell::na, |v| Cell::num(v, 5));
        let cells = [
            Cell::num(m.pixels as f64, 0),
            or_na(m.mean_abs_error),
            or_na(m.rmse),
            or_na(m.max_abs_error),
            or_na(m.p95_abs_error),
            Cell::num(m.boundary_pixels as f64, 0),
            or_na(m.boundary_mean_abs_error),
            or_na(m.boundary_p95_abs_error),
        ];
        let _ = write!(s, "<tr><td>{name}</td>");
        for cell in cells {
            s.push_str(&cell.td());
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</table>\n");
    s
}

/// Writes every scene's shared images into `dir/scenes/`: `SCENE.reference.png` (the
/// reference's lit fraction in grey), `SCENE.reference.exr` (the same in 32-bit float) and
/// `SCENE.classes.png` (the pixel classes, coloured as `render --method exact` colours them).
pub fn scene_files(dir: &Path, report: &Report, images: &Images) -> Result<(), OutputError> {
    let scenes = dir.join("scenes");
    std::fs::create_dir_all(&scenes).map_err(|e| write_err(&scenes, &e))?;
    for sc in &images.scenes {
        let stem = scene_stem(&report.scenes[sc.scene].scene);
        let lit = sc.reference.to_visibility();
        let path = scenes.join(format!("{stem}.reference.png"));
        lit_image(&lit).save(&path).map_err(|e| write_err(&path, &e))?;
        write_visibility_exr(&scenes.join(format!("{stem}.reference.exr")), &lit)?;
        let (w, h) = (sc.reference.width, sc.reference.height);
        let path = scenes.join(format!("{stem}.classes.png"));
        image::RgbImage::from_fn(w, h, |x, y| {
            image::Rgb(sc.classes[(y * w + x) as usize].colour())
        })
        .save(&path)
        .map_err(|e| write_err(&path, &e))?;
    }
    Ok(())
}

/// Writes, for every produced run, into `dir/runs/`: `ID.png` (its lit fraction),
/// `ID.error.png` (its error map), `ID.run.json` and `ID.metrics.json`.
pub fn run_files(dir: &Path, report: &Report, images: &Images) -> Result<(), OutputError> {
    let runs = dir.join("runs");
    std::fs::create_dir_all(&runs).map_err(|e| write_err(&runs, &e))?;
    for p in &images.runs {
        let stem = row_stem(&report.rows[p.row]);
        let sc = &images.scenes[p.scene];
        let path = runs.join(format!("{stem}.png"));
        lit_image(&p.visibility).save(&path).map_err(|e| write_err(&path, &e))?;
        let path = runs.join(format!("{stem}.error.png"));
        let max = analysis::error_map::DEFAULT_MAX_ERROR;
        analysis::error_map::error_map(&p.visibility, &sc.reference.lit, &sc.compared, max)
            .map_err(|e| write_err(&path, &e))?
            .save(&path)
            .map_err(|e| write_err(&path, &e))?;
        write_run_json(&runs.join(format!("{stem}.run.json")), &p.record)?;
        let path = runs.join(format!("{stem}.metrics.json"));
        let text = serde_json::to_string_pretty(&p.metrics).map_err(|e| write_err(&path, &e))?;
        std::fs::write(&path, text + "\n").map_err(|e| write_err(&path, &e))?;
    }
    Ok(())
}

/// Writes every run's page, `dir/runs/ID.html` (its files are to be there or to follow:
/// [`run_files`]). Returns the pages' paths relative to `dir`, in report order.
pub fn write_run_pages(dir: &Path, report: &Report) -> Result<Vec<String>, OutputError> {
    let runs = dir.join("runs");
    std::fs::create_dir_all(&runs).map_err(|e| write_err(&runs, &e))?;
    let mut pages = Vec::with_capacity(report.rows.len());
    for row in 0..report.rows.len() {
        let name = format!("runs/{}.html", row_stem(&report.rows[row]));
        let path = dir.join(&name);
        std::fs::write(&path, run_page(report, row)).map_err(|e| write_err(&path, &e))?;
        pages.push(name);
    }
    Ok(pages)
}

/// A failure to write `path`.
fn write_err(path: &Path, e: &dyn std::fmt::Display) -> OutputError {
    OutputError::Write { path: path.to_owned(), message: e.to_string() }
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
