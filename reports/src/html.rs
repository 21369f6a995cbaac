//! HTML for the report's pages (`index.html`, written by the `index` module, and a page per
//! run, by `run_pages`): escaping, the page head with the style and the script embedded
//! (`reports/assets/report.css` and `report.js`; no server, nothing from the network), table
//! cells that sort as numbers, the metric columns with `n/a` where a metric does not apply,
//! and the split of a table's parameters into those stated once above it, once per method,
//! or in a column of their own.
//!
//! Tables sort by clicking a header (numbers as numbers, `n/a` last) and filter by a text box.
//! The script marks every image `data-loaded="yes"` or `"no"` once a page has loaded; a page
//! opened as `PAGE.html#selftest` sorts and filters its first sortable table, drives its
//! comparison view if it has one, and writes what it found into `<pre id="selftest">`, for a
//! headless browser to check.

use crate::devices::is_software_adapter;
use crate::model::{params_of, Row};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// Escapes text for HTML.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// The pages' style sheet.
pub const STYLE: &str = include_str!("../assets/report.css");

/// The pages' script: sortable and filterable tables, the run pages' comparison view, and
/// the self-test.
pub const SCRIPT: &str = include_str!("../assets/report.js");

/// The start of a page, through `<body>`: title, style and script.
pub fn page_head(title: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\
         <style>{STYLE}</style><script>{SCRIPT}</script></head><body>\n",
        escape(title)
    )
}

/// An identifier usable as an HTML anchor: letters and digits kept, the rest `-`.
pub fn anchor(s: &str) -> String {
    s.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '-' }).collect()
}

/// The adapter's name as HTML, marked when it is a software rasterizer.
pub fn adapter_html(name: Option<&str>) -> String {
    match name {
        None => "none used".to_owned(),
        Some(n) if is_software_adapter(n) => format!(
            "{} <span class=\"software\">(a software rasterizer: its \"GPU\" runs on the CPU, \
             so its times say nothing of a hardware GPU's)</span>",
            escape(n)
        ),
        Some(n) => escape(n),
    }
}

/// One table cell: its text, and the number it sorts by (none for text and `n/a`).
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// What the cell shows.
    pub text: String,
    /// The value it sorts by.
    pub value: Option<f64>,
}

impl Cell {
    /// A text cell.
    pub fn text(s: impl Into<String>) -> Self {
        Self { text: s.into(), value: None }
    }

    /// A number shown with `decimals` decimals.
    pub fn num(v: f64, decimals: usize) -> Self {
        Self { text: format!("{v:.decimals$}"), value: Some(v) }
    }

    /// `n/a`: the quantity does not apply.
    pub fn na() -> Self {
        Self::text("n/a")
    }

    /// The cell as `<td>`, its text escaped.
    pub fn td(&self) -> String {
        match self.value {
            Some(v) if v.is_finite() => format!("<td data-v=\"{v}\">{}</td>", escape(&self.text)),
            _ => format!("<td class=\"text\">{}</td>", escape(&self.text)),
        }
    }
}

/// Heads of the metric columns, under [`metric_cells`].
pub const METRIC_COLUMNS: [&str; 10] = [
    "mean abs error",
    "RMSE",
    "boundary pixels",
    "boundary error",
    "boundary p50",
    "boundary p95",
    "boundary p99",
    "pixel match %",
    "pixel match (Lecocq) %",
    "FLIP",
];

/// A row's metrics under [`METRIC_COLUMNS`]: `n/a` where nothing was compared, and the
/// boundary statistics `n/a` where the reference has no boundary pixel.
pub fn metric_cells(r: &Row) -> Vec<Cell> {
    let m = &r.metrics;
    if m.evaluated_pixels == 0 {
        return vec![Cell::na(); METRIC_COLUMNS.len()];
    }
    let or_na = |v: Option<f64>| v.map_or_else(Cell::na, |v| Cell::num(v, 4));
    vec![
        Cell::num(m.mean_abs_error, 5),
        Cell::num(m.rmse, 5),
        Cell::num(m.boundary_pixels as f64, 0),
        or_na(m.boundary_mean()),
        or_na(m.boundary_p50_abs_error),
        or_na(m.boundary_p95_abs_error),
        or_na(m.boundary_p99_abs_error),
        Cell::num(100.0 * m.pixel_match, 2),
        r.pixel_match_lecocq.map_or_else(Cell::na, |v| Cell::num(100.0 * v, 2)),
        Cell::num(r.flip_mean, 4),
    ]
}

/// Parameters given a column of their own when they vary over a table (the ones suites sweep).
const COLUMN_KEYS: [&str; 5] = ["map_res", "rate", "depth_bits", "pattern", "device"];

/// Where each parameter of a table's rows is stated.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ParamSplit {
    /// Same in every row: stated once above the table.
    pub constant: BTreeMap<String, String>,
    /// Per method, the rest that is the same in all its rows: stated once per method.
    pub per_method: BTreeMap<String, BTreeMap<String, String>>,
    /// Swept parameters that vary: a column each.
    pub columns: Vec<&'static str>,
    /// Whether some row has a parameter left for the "other parameters" column.
    pub others: bool,
}

impl ParamSplit {
    /// Splits the parameters of `rows`.
    pub fn of(rows: &[&Row]) -> Self {
        let params: Vec<BTreeMap<String, String>> = rows.iter().map(|r| params_of(r)).collect();
        let same = |ps: &[&BTreeMap<String, String>], k: &str| -> Option<String> {
            let first = ps.first()?.get(k)?;
            ps.iter().all(|p| p.get(k) == Some(first)).then(|| first.clone())
        };
        let all: Vec<&BTreeMap<String, String>> = params.iter().collect();
        let keys: std::collections::BTreeSet<&String> =
            params.iter().flat_map(|p| p.keys()).collect();
        let constant: BTreeMap<String, String> =
            keys.iter().filter_map(|k| same(&all, k).map(|v| ((*k).clone(), v))).collect();
        let columns: Vec<&'static str> = COLUMN_KEYS
            .into_iter()
            .filter(|k| keys.contains(&k.to_string()) && !constant.contains_key(*k))
            .collect();
        let mut per_method = BTreeMap::new();
        for r in rows {
            if per_method.contains_key(&r.method) {
                continue;
            }
            let mine: Vec<&BTreeMap<String, String>> = rows
                .iter()
                .zip(&params)
                .filter(|(s, _)| s.method == r.method)
                .map(|x| x.1)
                .collect();
            let fixed: BTreeMap<String, String> = mine[0]
                .keys()
                .filter(|k| !constant.contains_key(*k) && !columns.contains(&k.as_str()))
                .filter_map(|k| same(&mine, k).map(|v| (k.clone(), v)))
                .collect();
            per_method.insert(r.method.clone(), fixed);
        }
        let mut split = Self { constant, per_method, columns, others: false };
        split.others = rows.iter().any(|r| !split.other_params(r).is_empty());
        split
    }

    /// The parameters of `r` stated neither above the table nor in a column.
    pub fn other_params(&self, r: &Row) -> String {
        let fixed = self.per_method.get(&r.method);
        params_of(r)
            .into_iter()
            .filter(|(k, _)| {
                !self.constant.contains_key(k)
                    && !self.columns.contains(&k.as_str())
                    && !fixed.is_some_and(|f| f.contains_key(k))
            })
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// The paragraph above the table: the constant parameters, then each method's.
    pub fn html(&self) -> String {
        let kv = |m: &BTreeMap<String, String>| {
            m.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(", ")
        };
        let mut s = String::new();
        if !self.constant.is_empty() {
            let _ = write!(s, "Every row: {}.", escape(&kv(&self.constant)));
        }
        for (method, fixed) in self.per_method.iter().filter(|(_, f)| !f.is_empty()) {
            let _ = write!(s, " <code>{}</code>: {}.", escape(method), escape(&kv(fixed)));
        }
        format!("<p class=\"constant\">{}</p>\n", s.trim())
    }
}

/// A section of its own holding a bulleted list of texts (escaped): `<h2 id=ID>TITLE</h2>`;
/// nothing when there is no item.
pub fn list_section(id: &str, title: &str, items: &[String]) -> String {
    if items.is_empty() {
        return String::new();
    }
    let mut s = format!("<h2 id=\"{id}\">{}</h2>\n<ul>\n", escape(title));
    for k in items {
        let _ = writeln!(s, "<li>{}</li>", escape(k));
    }
    s.push_str("</ul>\n");
    s
}

/// A sortable, filterable table: the filter box, the head and the body rows.
pub fn sortable_table(class: &str, heads: &[(String, bool)], rows: &[String]) -> String {
    let mut s = String::from(
        "<input type=\"search\" class=\"filter\" placeholder=\"filter rows (words)\" \
         aria-label=\"filter rows\">\n",
    );
    let _ = write!(s, "<table class=\"sortable {class}\"><thead><tr>");
    for (h, numeric) in heads {
        let _ =
            write!(s, "<th class=\"{}\">{}</th>", if *numeric { "num" } else { "text" }, escape(h));
    }
    s.push_str("</tr></thead><tbody>\n");
    for r in rows {
        let _ = writeln!(s, "<tr>{r}</tr>");
    }
    s.push_str("</tbody></table>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup() {
        assert_eq!(escape("<a href=\"x\">&</a>"), "&lt;a href=&quot;x&quot;&gt;&amp;&lt;/a&gt;");
    }

    #[test]
    fn software_adapters_are_marked() {
        for n in [
            "llvmpipe (LLVM 15.0.6, 256 bits) via Vulkan",
            "Lavapipe",
            "Microsoft Basic Render Driver (Software)",
        ] {
            assert!(is_software_adapter(n), "{n}");
            assert!(adapter_html(Some(n)).contains("software rasterizer"), "{n}");
        }
        assert!(!is_software_adapter("NVIDIA H200"));
        assert_eq!(adapter_html(Some("NVIDIA H200")), "NVIDIA H200");
    }
    fn row(method: &str, params: serde_json::Value) -> Row {
        let v =
            methods::Visibility { width: 10, height: 1, lit: vec![0.25; 10], transmittance: None };
        let metrics = analysis::Metrics::compare(&v, &[0.0; 10], &[true; 10]);
        Row {
            scene: "cage".into(),
            method: method.into(),
            params: params.as_object().expect("object").clone(),
            width: 10,
            height: 1,
            reference: "exact".into(),
            ref_rate: None,
            metrics,
            flip_mean: 0.01,
            pixel_match_lecocq: None,
            error_exceedance: Vec::new(),
            classes: None,
            item: 0,
            shard: None,
            total_ms: instrumentation::stats::Summary::of(&[1.0, 2.0, 3.0]).expect("times"),
            cpu_ms: None,
            contended: false,
            conditions: None,
            stages: Vec::new(),
            skipped_stages: Vec::new(),
            counters: Default::default(),
            notes: Vec::new(),
        }
    }

    #[test]
    fn parameters_are_stated_where_they_vary() {
        use serde_json::json;
        let rows = [
            row("sm", json!({"constant_bias": 1e-5, "map_res": 256, "slope_bias": 1.0})),
            row("sm", json!({"constant_bias": 1e-5, "map_res": 512, "slope_bias": 1.0})),
            row("spsm", json!({"constant_bias": 1e-5, "map_res": 256, "rate": 4, "texel": "f32"})),
            row(
                "spsm",
                json!({"constant_bias": 1e-5, "map_res": 256, "rate": 4, "texel": "packed"}),
            ),
        ];
        let refs: Vec<&Row> = rows.iter().collect();
        let split = ParamSplit::of(&refs);
        let constant: Vec<&str> = split.constant.keys().map(String::as_str).collect();
        assert_eq!(constant, ["constant_bias", "device"]);
        assert_eq!(split.columns, ["map_res", "rate"]);
        assert_eq!(split.per_method["sm"].keys().collect::<Vec<_>>(), ["slope_bias"]);
        assert!(split.per_method["spsm"].is_empty(), "texel varies within spsm");
        assert!(split.others);
        assert_eq!(split.other_params(&rows[0]), "");
        assert_eq!(split.other_params(&rows[2]), "texel=f32");
        let above = split.html();
        assert!(above.contains("Every row: constant_bias=0.00001, device=cpu."), "{above}");
        assert!(above.contains("<code>sm</code>: slope_bias=1.0."), "{above}");
    }

    #[test]
    fn metrics_that_do_not_apply_are_na() {
        let r = row("sm", serde_json::json!({}));
        let cells = metric_cells(&r);
        assert!(
            cells[3..7].iter().all(|c| *c == Cell::na()),
            "no boundary pixel: no boundary error"
        );
        assert_eq!(cells[0].value, Some(0.25));
        let none = Row { metrics: analysis::Metrics { evaluated_pixels: 0, ..r.metrics }, ..r };
        assert!(metric_cells(&none).iter().all(|c| c.text == "n/a"));
    }
}
