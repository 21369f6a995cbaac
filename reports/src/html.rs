//! The parts of the report's pages (`index.html`, built by the `index` module, and a page per
//! run, by `run_pages`) that the templates (`reports/templates/`, rendered by `templates`)
//! are given: the style and the script embedded in each page (`reports/assets/report.css`
//! and `report.js`; no server, nothing from the network), table cells that sort as numbers
//! ([`Cell`]), tables whose columns that read the same in every row are stated once above
//! them ([`TableView::state_constant_columns`]), the metric columns with `n/a` where a metric
//! does not apply, and the split of a table's parameters into those stated once above it,
//! once per method, or in a column of their own ([`ParamSplit`]).
//!
//! Tables sort by clicking a header (numbers as numbers, `n/a` last) and filter by a text box.
//! The script marks every image `data-loaded="yes"` or `"no"` once a page has loaded; a page
//! opened as `PAGE.html#selftest` checks its layout, sorts and filters its first sortable
//! table, sorts every other, drives its comparison view if it has one, and writes what it
//! found into `<pre id="selftest">`, for a headless browser to check.

use crate::model::{params_of, Row};
use serde::Serialize;
use std::collections::BTreeMap;

/// The pages' style sheet.
pub const STYLE: &str = include_str!("../assets/report.css");

/// The pages' script: sortable and filterable tables, the run pages' comparison view, and
/// the self-test.
pub const SCRIPT: &str = include_str!("../assets/report.js");

/// An identifier usable as an HTML anchor: letters and digits kept, the rest `-`.
pub fn anchor(s: &str) -> String {
    s.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '-' }).collect()
}

/// One table cell: its text, the number it sorts by (none for text and `n/a`), and where it
/// links to.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// What the cell shows.
    pub text: String,
    /// The value it sorts by.
    pub value: Option<f64>,
    /// The page it links to, relative to the page it is on.
    pub href: Option<String>,
}

impl Cell {
    /// A text cell.
    pub fn text(s: impl Into<String>) -> Self {
        Self { text: s.into(), value: None, href: None }
    }

    /// A number shown with `decimals` decimals.
    pub fn num(v: f64, decimals: usize) -> Self {
        Self { text: format!("{v:.decimals$}"), value: Some(v), href: None }
    }

    /// A text that sorts by `v`.
    pub fn sorted(text: impl Into<String>, v: f64) -> Self {
        Self { text: text.into(), value: Some(v), href: None }
    }

    /// `n/a`: the quantity does not apply.
    pub fn na() -> Self {
        Self::text("n/a")
    }

    /// The cell as a link to `href`.
    pub fn link(mut self, href: impl Into<String>) -> Self {
        self.href = Some(href.into());
        self
    }

    /// A text cell that sorts by the number it reads as, when it reads as one.
    pub fn parsed(s: String) -> Self {
        match s.parse::<f64>() {
            Ok(x) => Self::sorted(s, x),
            Err(_) => Self::text(s),
        }
    }
}

impl Serialize for Cell {
    /// As the templates read it: `text`, `sort` (the number as text, absent for text and
    /// `n/a`) and `href`.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct View<'a> {
            text: &'a str,
            sort: Option<String>,
            href: Option<&'a str>,
        }
        View {
            text: &self.text,
            sort: self.value.filter(|v| v.is_finite()).map(|v| v.to_string()),
            href: self.href.as_deref(),
        }
        .serialize(s)
    }
}

/// A column head.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Head {
    /// What it says.
    pub text: String,
    /// Whether its cells are numbers (right-aligned, sorted as numbers).
    pub numeric: bool,
}

impl Head {
    /// A head of text cells.
    pub fn text(s: impl Into<String>) -> Self {
        Self { text: s.into(), numeric: false }
    }

    /// A head of numbers.
    pub fn num(s: impl Into<String>) -> Self {
        Self { text: s.into(), numeric: true }
    }
}

/// A line stated above a table: what holds for all its rows, or for one method's rows
/// (`code`, the method).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Note {
    /// The method it is about, shown as code; `None` for every row.
    pub code: Option<String>,
    /// What holds.
    pub text: String,
}

/// A sortable, filterable table as the templates draw it (`macros.html`'s `table`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TableView {
    /// Its class beside `sortable` (`runs`, `scenes`, `devices`).
    pub class: String,
    /// Lines stated once above it.
    pub notes: Vec<Note>,
    /// Column heads.
    pub heads: Vec<Head>,
    /// Rows of cells, one per head.
    pub rows: Vec<Vec<Cell>>,
}

impl TableView {
    /// A table of class `class` without notes.
    pub fn new(class: &str, heads: Vec<Head>, rows: Vec<Vec<Cell>>) -> Self {
        Self { class: class.to_owned(), notes: Vec::new(), heads, rows }
    }

    /// Moves each column among `candidates` (by head) whose cells read the same in every row
    /// of a table of two rows or more out of the table, into one note above it (`boundary
    /// pixels: 1234; contended: no`): the table keeps the columns that tell its rows apart.
    pub fn state_constant_columns(&mut self, candidates: &[&str]) {
        if self.rows.len() < 2 {
            return;
        }
        let constant: Vec<usize> = (0..self.heads.len())
            .filter(|&k| candidates.contains(&self.heads[k].text.as_str()))
            .filter(|&k| self.rows.iter().all(|r| r[k].text == self.rows[0][k].text))
            .collect();
        if constant.is_empty() {
            return;
        }
        let stated: Vec<String> = constant
            .iter()
            .map(|&k| format!("{}: {}", self.heads[k].text, self.rows[0][k].text))
            .collect();
        self.notes.push(Note { code: None, text: format!("Every run: {}.", stated.join("; ")) });
        for &k in constant.iter().rev() {
            self.heads.remove(k);
            for r in &mut self.rows {
                r.remove(k);
            }
        }
    }
}

/// The head of a time column on `clock` (`CPU`, `wall`): the median with its 95 % interval.
pub fn time_head(clock: &str) -> String {
    format!("{clock} ms (95 % interval)")
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

/// The metric columns of the index's runs tables (the others are on the runs' pages), as
/// indices into [`METRIC_COLUMNS`]: the mean, the boundary pixels (stated above the table,
/// being the reference's), the boundary error and its 95th percentile, both pixel matches and
/// FLIP.
pub const RUN_TABLE_METRICS: [usize; 7] = [0, 2, 3, 5, 7, 8, 9];

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

/// Parameters given a column of their own when they vary over a table (the ones suites sweep,
/// the filtered maps' filter width, and the light-frustum policy of the shadow-map methods).
const COLUMN_KEYS: [&str; 7] =
    ["map_res", "rate", "depth_bits", "pattern", "filter", "device", "frustum"];

/// Where each parameter of a table's rows is stated.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ParamSplit {
    /// Same in every row: stated once above the table.
    pub constant: BTreeMap<String, String>,
    /// Per method, the rest that is the same in all its rows: stated once per method.
    pub per_method: BTreeMap<String, BTreeMap<String, String>>,
    /// Swept parameters that vary within some method's rows: a column each.
    pub columns: Vec<&'static str>,
    /// Whether some row has a parameter left for the "other" column (those that vary within
    /// a method and have no column of their own).
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
        // A column for a swept parameter that varies within some method's rows; one that only
        // tells methods apart is stated once per method.
        let varies_within = |k: &str| {
            rows.iter().zip(&params).any(|(r, p)| {
                rows.iter().zip(&params).any(|(o, q)| o.method == r.method && q.get(k) != p.get(k))
            })
        };
        let columns: Vec<&'static str> = COLUMN_KEYS
            .into_iter()
            .filter(|k| keys.contains(&k.to_string()) && !constant.contains_key(*k))
            .filter(|k| varies_within(k))
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

    /// The heads of the parameter columns a table has after its method's: one per varying
    /// key ([`ParamSplit::columns`]; text for names, numbers otherwise), then `other` when
    /// some row has parameters left for it.
    pub fn heads(&self) -> Vec<Head> {
        let mut heads: Vec<Head> = self
            .columns
            .iter()
            .map(|c| {
                if matches!(*c, "pattern" | "device" | "frustum") {
                    Head::text(*c)
                } else {
                    Head::num(*c)
                }
            })
            .collect();
        if self.others {
            heads.push(Head::text("other"));
        }
        heads
    }

    /// Row `r`'s cells under [`ParamSplit::heads`].
    pub fn cells(&self, r: &Row) -> Vec<Cell> {
        let p = params_of(r);
        let mut cells: Vec<Cell> = self
            .columns
            .iter()
            .map(|c| Cell::parsed(p.get(*c).cloned().unwrap_or_default()))
            .collect();
        if self.others {
            cells.push(Cell::text(self.other_params(r)));
        }
        cells
    }

    /// The lines above the table: the constant parameters, then each method's.
    pub fn notes(&self) -> Vec<Note> {
        let kv = |m: &BTreeMap<String, String>| {
            m.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(", ")
        };
        let mut notes = Vec::new();
        if !self.constant.is_empty() {
            notes.push(Note { code: None, text: format!("Every row: {}.", kv(&self.constant)) });
        }
        for (method, fixed) in self.per_method.iter().filter(|(_, f)| !f.is_empty()) {
            notes.push(Note { code: Some(method.clone()), text: format!("{}.", kv(fixed)) });
        }
        notes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_the_same_in_every_row_are_stated_once() {
        let heads = vec![Head::text("method"), Head::num("boundary pixels"), Head::num("FLIP")];
        let rows = vec![
            vec![Cell::text("sm"), Cell::num(12.0, 0), Cell::num(0.1, 2)],
            vec![Cell::text("afsm"), Cell::num(12.0, 0), Cell::num(0.2, 2)],
        ];
        let mut t = TableView::new("runs", heads, rows);
        t.state_constant_columns(&["boundary pixels", "FLIP"]);
        assert_eq!(t.heads.iter().map(|h| h.text.as_str()).collect::<Vec<_>>(), ["method", "FLIP"]);
        assert!(t.rows.iter().all(|r| r.len() == 2));
        assert_eq!(t.notes[0].text, "Every run: boundary pixels: 12.");
        let json = serde_json::to_value(&t.rows[0][1]).expect("serialises");
        assert_eq!(json["sort"], "0.1");
        assert_eq!(
            serde_json::to_value(Cell::na()).expect("serialises")["sort"],
            serde_json::Value::Null
        );
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
            external: false,
            temporal: None,
            per_frame: Vec::new(),
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
        assert_eq!(split.columns, ["map_res"], "rate only tells spsm from sm");
        assert_eq!(split.per_method["sm"].keys().collect::<Vec<_>>(), ["slope_bias"]);
        assert_eq!(
            split.per_method["spsm"].keys().collect::<Vec<_>>(),
            ["rate"],
            "texel varies within spsm"
        );
        assert!(split.others);
        assert_eq!(split.other_params(&rows[0]), "");
        assert_eq!(split.other_params(&rows[2]), "texel=f32");
        let notes = split.notes();
        assert_eq!(notes[0].text, "Every row: constant_bias=0.00001, device=cpu.");
        assert_eq!(
            (notes[1].code.as_deref(), notes[1].text.as_str()),
            (Some("sm"), "slope_bias=1.0.")
        );
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
