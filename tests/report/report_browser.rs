//! A report's pages in headless Chromium, in a window of 1400 x 1000 pixels: index.html and a
//! run page open from the file system, every image loads, every local link names a file that
//! exists and every anchor a section, clicking a table header sorts the table (ascending,
//! then descending) and every other sortable table, today's techniques against the seeds
//! among them, the filter box hides rows, and the run page's comparison view flips
//! between images, zooms, pans and swipes. The index leads with the answer: its first screen
//! (the top 1000 pixels, nothing scrolled) holds the Pareto summary and the machine line, and
//! no table of runs is wider than the window, its time column in view.
//!
//! A run in motion (its temporal metrics, per-frame records and frames made by hand) has an
//! "In motion" section on the index and players on its page: the slider moves the three
//! players (method, reference, error map) to one frame, and playing advances them in step and
//! loops.
//!
//! The pages test themselves when opened with `#selftest` (`reports/assets/report.js`) and
//! write what they found into `<pre id="selftest">`, which `--dump-dom` prints. Chromium must
//! be installed (`scripts/install-chromium`); without it the test fails.

use reports::animation::FrameRecord;
use reports::model::MotionFrames;
use reports::{run_pages::write_run_pages, run_suite, write_report, Suite};
use std::path::{Path, PathBuf};
use std::process::Command;

const CHROMIUM: &str = "/usr/bin/chromium";

const SUITE: &str = r#"
name = "browser"
width = 96
height = 72
warmup = 1
repeats = 2
scenes = ["plane-square", "cage"]

[[run]]
method = "sm"
map_res = [64, 128]

[[run]]
method = "pcf-gems4"
map_res = [64]

[[run]]
method = "vsm"
map_res = [64]
"#;

/// The text of `<pre id="selftest">` in `page` opened with `#selftest`, one line per finding.
fn selftest(page: &Path) -> Vec<String> {
    assert!(
        Path::new(CHROMIUM).is_file(),
        "{CHROMIUM} is missing: run scripts/install-chromium (it installs Debian's chromium)"
    );
    let profile = tempfile::tempdir().expect("tempdir");
    let url = format!("file://{}#selftest", page.display());
    let o = Command::new(CHROMIUM)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            &format!("--user-data-dir={}", profile.path().display()),
            "--window-size=1400,1000",
            "--virtual-time-budget=5000",
            "--dump-dom",
            &url,
        ])
        .output()
        .expect("chromium runs");
    let dom = String::from_utf8_lossy(&o.stdout);
    // The last one: the script's comments name the element too.
    let text = dom
        .rsplit_once("<pre id=\"selftest\">")
        .and_then(|(_, t)| t.split("</pre>").next())
        .unwrap_or_else(|| {
            panic!(
                "{}: no self-test output; stderr: {}\n{dom}",
                page.display(),
                String::from_utf8_lossy(&o.stderr)
            )
        });
    text.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&amp;", "&")
        .lines()
        .map(str::to_owned)
        .collect()
}

/// The value of the line `key: value`.
fn finding<'a>(lines: &'a [String], key: &str) -> &'a str {
    let prefix = format!("{key}: ");
    lines
        .iter()
        .find_map(|l| l.strip_prefix(&prefix))
        .unwrap_or_else(|| panic!("no `{key}` in {lines:#?}"))
}

/// Checks the findings every page reports: its images (as many as the page has) all loaded,
/// and every local link it holds names a file beside it.
fn images_and_links(page: &Path, lines: &[String]) {
    let html = std::fs::read_to_string(page).expect("page");
    let n = html.matches("<img ").count();
    assert!(n > 0, "{}: no image", page.display());
    assert_eq!(finding(lines, "images"), format!("{n} of {n} loaded"), "{lines:#?}");
    let dir = page.parent().expect("folder");
    let links: Vec<PathBuf> =
        lines.iter().filter_map(|l| l.strip_prefix("link: ")).map(|l| dir.join(l)).collect();
    assert!(!links.is_empty(), "{lines:#?}");
    for l in links {
        assert!(l.is_file(), "{}: link to {} that does not exist", page.display(), l.display());
    }
    // Every anchor of the page is a section of it.
    for a in html.split("href=\"#").skip(1).filter_map(|s| s.split('"').next()) {
        assert!(html.contains(&format!("id=\"{a}\"")), "{}: #{a} leads nowhere", page.display());
    }
}

#[test]
fn index_and_run_pages_work_in_headless_chromium() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = Suite::parse(SUITE, Path::new("browser.toml")).expect("suite");
    let (report, images) = run_suite(&suite, |_| {});
    assert_eq!(report.rows.len(), 8, "{:?}", report.skipped);
    let out = dir.path();
    write_report(out, &report, &images, None).expect("report written");
    let pages = write_run_pages(out, &report).expect("run pages written");
    assert_eq!(pages.len(), 8);

    let index = out.join("index.html");
    let html = std::fs::read_to_string(&index).expect("index.html");
    // Parameters the same in every row are stated once, above each scene's runs table.
    assert_eq!(html.matches("constant_bias=").count(), 2, "{html}");
    for term in ["RMSE", "boundary pixels", "p50 / p95 / p99", "FLIP", "pixel match", "n/a"] {
        assert!(html.contains(&format!("<dt>{term}")), "glossary lacks {term}");
    }
    let lines = selftest(&index);
    images_and_links(&index, &lines);
    // The first screen leads with the answer, and the runs tables fit the window. On the
    // layout before the Pareto summary (a contents list first, runs tables of 17 columns) both
    // fail.
    assert!(finding(&lines, "viewport").starts_with("1400x"), "{lines:#?}");
    assert!(finding(&lines, "first screen").starts_with("ok"), "{lines:#?}");
    assert!(finding(&lines, "runs tables").starts_with("ok"), "{lines:#?}");
    assert!(finding(&lines, "sort").starts_with("ok"), "{lines:#?}");
    assert!(finding(&lines, "filter").starts_with("ok"), "{lines:#?}");
    // The other tables sort too: vsm, one of today's techniques, beside sm gives each scene
    // a table against the seeds.
    let tables = finding(&lines, "sort tables");
    assert!(tables.starts_with("ok"), "{lines:#?}");
    assert_eq!(tables.matches("today").count(), 2, "{tables}");
    for p in &pages {
        assert!(lines.iter().any(|l| l == &format!("link: {p}")), "index does not link {p}");
    }

    let run = out.join(&pages[0]);
    let lines = selftest(&run);
    images_and_links(&run, &lines);
    assert_eq!(
        finding(&lines, "views"),
        "7",
        "this run, the reference, its error map, the class map and the scene's three other runs"
    );
    // The first step and the flip go from the run to the reference and back.
    let flip = finding(&lines, "flip");
    assert!(flip.starts_with("ok"), "{lines:#?}");
    assert!(flip.contains("-> ../scenes/plane-square.reference.png ->"), "{flip}");
    let stem = Path::new(&pages[0]).file_stem().expect("stem").to_string_lossy().into_owned();
    for file in [
        format!("{stem}.error.png"),
        format!("{stem}.run.json"),
        format!("{stem}.metrics.json"),
        "../scenes/plane-square.reference.exr".to_owned(),
        "../scenes/plane-square.classes.png".to_owned(),
    ] {
        assert!(lines.contains(&format!("link: {file}")), "no link to {file}: {lines:#?}");
    }
    // The error map is the frame with its colour bar below; metrics.json is compare's, per
    // class.
    let runs = out.join("runs");
    let error = image::open(runs.join(format!("{stem}.error.png"))).expect("error map");
    assert_eq!(error.width(), 96);
    assert!(error.height() > 72, "no colour bar");
    let metrics: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(runs.join(format!("{stem}.metrics.json"))).expect("metrics"),
    )
    .expect("metrics.json parses");
    assert_eq!(metrics["reference"], "exact");
    assert_eq!(metrics["evaluated_pixels"], report.rows[0].metrics.evaluated_pixels);
    assert!(metrics["classes"]["planar"]["pixels"].as_u64().expect("planar") > 0);
    assert_eq!(finding(&lines, "zoom and pan"), "ok", "{lines:#?}");
    assert!(finding(&lines, "swipe").starts_with("ok"), "{lines:#?}");
    let exr = format!(
        "link: ../visibility/{}",
        Path::new(&pages[0]).with_extension("exr").file_name().expect("name").to_string_lossy()
    );
    assert!(lines.contains(&exr), "the page does not link its EXR: {lines:#?}");
}

/// Frames of the run in motion.
const FRAMES: u32 = 8;

/// How long each is shown, milliseconds.
const FRAME_MS: u16 = 50;

/// `img` as PNG bytes.
fn png(img: &image::RgbImage) -> Vec<u8> {
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).expect("encodes");
    bytes
}

/// A frame of `w x h`: grey `level` with a white bar at column `x` (a moving edge).
fn bar(w: u32, h: u32, level: u8, x: u32) -> image::RgbImage {
    image::RgbImage::from_fn(w, h, |i, _| {
        image::Rgb(if i == x % w { [255; 3] } else { [level; 3] })
    })
}

#[test]
fn a_run_in_motion_plays_its_three_players_in_step_in_headless_chromium() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = Suite::parse(
        "name = \"motion\"\nwidth = 48\nheight = 36\nwarmup = 0\nrepeats = 1\n\
         scenes = [\"plane-square\"]\n[[run]]\nmethod = \"sm\"\nmap_res = [64, 128]\n",
        Path::new("motion.toml"),
    )
    .expect("suite");
    let (mut report, mut images) = run_suite(&suite, |_| {});
    assert_eq!(report.rows.len(), 2, "{:?}", report.skipped);
    // The first run in motion, by hand: temporal error 0.01 on every pair of frames.
    let (w, h) = (report.rows[0].width, report.rows[0].height);
    let pairs = 100 * u64::from(FRAMES - 1);
    let class = analysis::temporal::ClassTemporal { pairs, mean: Some(0.01) };
    let row = &mut report.rows[0];
    row.temporal = Some(analysis::temporal::TemporalMetrics {
        frames: FRAMES,
        reprojected: false,
        pixel_pairs: pairs,
        mean: Some(0.01),
        p95: Some(0.02),
        boundary_pairs: pairs / 2,
        boundary_mean: Some(0.03),
        boundary_p95: Some(0.05),
        per_class: [("planar".to_owned(), class), ("surface".to_owned(), class)]
            .into_iter()
            .collect(),
        per_frame: vec![Some(0.01); FRAMES as usize - 1],
    });
    row.per_frame = (0..FRAMES)
        .map(|k| FrameRecord {
            frame: k,
            time: f64::from(k) / f64::from(FRAMES - 1),
            map_res: Some(64),
            mean_abs_error: Some(row.metrics.mean_abs_error),
            boundary_mean_abs_error: Some(0.1),
            boundary_p95_abs_error: Some(0.2),
            temporal_error: (k > 0).then_some(0.01),
            temporal_pairs: if k > 0 { 100 } else { 0 },
            method_ms: 1.0,
            method_cpu_ms: Some(1.0),
            reference_ms: 3.0,
            reference_cached: false,
        })
        .collect();
    let produced = images.runs.iter_mut().find(|p| p.row == 0).expect("the first run's");
    produced.motion = Some(MotionFrames {
        method: (0..FRAMES).map(|k| png(&bar(w, h, 40, 4 * k))).collect(),
        reference: (0..FRAMES).map(|k| png(&bar(w, h, 80, 4 * k + 1))).collect(),
        error: (0..FRAMES).map(|k| png(&bar(w, h + 10, 0, 4 * k))).collect(),
        frame_ms: FRAME_MS,
    });
    let out = dir.path();
    write_report(out, &report, &images, None).expect("report written");
    let stem = reports::model::row_stem(&report.rows[0]);

    // The index: the section with its charts, all loaded, its table within the window.
    let index = out.join("index.html");
    let html = std::fs::read_to_string(&index).expect("index.html");
    assert!(html.contains("id=\"scene-plane-square-motion\""), "{html}");
    let lines = selftest(&index);
    images_and_links(&index, &lines);
    assert!(finding(&lines, "runs tables").starts_with("ok"), "{lines:#?}");
    assert!(lines.contains(&format!("link: runs/{stem}.html")), "{lines:#?}");

    // The run page: the players start on frame 0, the slider moves all three, playing
    // advances them in step and loops back to the first frame.
    let page = out.join("runs").join(format!("{stem}.html"));
    let lines = selftest(&page);
    images_and_links(&page, &lines);
    for file in [
        format!("{stem}.animation.png"),
        format!("{stem}.frames.csv"),
        format!("{stem}.temporal.json"),
    ] {
        assert!(lines.contains(&format!("link: {file}")), "no link to {file}: {lines:#?}");
    }
    let players: Vec<&str> = lines.iter().filter_map(|l| l.strip_prefix("players: ")).collect();
    assert_eq!(players.len(), 3, "{lines:#?}");
    assert_eq!(players[0], "slider 3 -> 3 3 3 ok", "{lines:#?}");
    let play = players[1].strip_prefix("play advanced 0 -> ").expect("play");
    let (k, rest) = play.split_once(", ").expect("frame, then the rest");
    let k: u32 = k.parse().expect("a frame");
    assert!((1..FRAMES).contains(&k), "{play}");
    assert_eq!(rest, "in sync ok", "{lines:#?}");
    assert_eq!(players[2], format!("loop {} -> 0 ok", FRAMES - 1), "{lines:#?}");
    // The still run's page has no players.
    let still =
        out.join("runs").join(format!("{}.html", reports::model::row_stem(&report.rows[1])));
    let lines = selftest(&still);
    assert!(lines.iter().all(|l| !l.starts_with("players:")), "{lines:#?}");
}
