//! What runs and reports write. A single run: the visibility buffer as EXR, a shaded PNG for
//! looking, and the run record as JSON ([`output`]). A report: a [`suite`] of scenes, methods
//! and parameters, planned as items by [`plan`] (and split into shards there), run by [`sweep`]
//! under the timing protocol of [`timing`] with references from the [`cache`], held in the
//! [`model`], written by [`write`] as JSON, CSV, Markdown, EXR images and HTML pages
//! ([`index`], [`run_pages`], rendered from [`templates`]), leading with the answer that
//! [`summary`] computes (Pareto fronts, what the runs say of each method, the machine and its
//! load), with the charts chosen by [`figures`] and drawn by [`plots`];
//! the papers' tables and the cost-against-work tables are measured by [`tables`]; shards are
//! put back together by [`merge`].

pub mod baseline;
pub mod cache;
pub mod devices;
pub mod figures;
pub mod grids;
pub mod html;
pub mod index;
pub mod merge;
pub mod model;
pub mod output;
pub mod plan;
pub mod plots;
pub mod run_pages;
pub mod suite;
pub mod summary;
pub mod sweep;
pub mod tables;
pub mod templates;
pub mod timing;
pub mod write;

pub use figures::write_plots;
pub use model::{Images, Report, Row};
pub use output::{
    shade, write_class_pngs, write_run_json, write_shadow_png, write_visibility_exr, MetricsRecord,
    OutputError,
};
pub use suite::{Suite, SuiteError, BUILTIN_SUITES};
pub use sweep::run_suite;
pub use write::write_report;

#[cfg(test)]
mod tests {
    use std::collections::{BTreeMap, BTreeSet};

    /// The modules of this crate with the modules each one's code names (`crate::NAME`),
    /// comment lines included.
    fn module_graph() -> BTreeMap<String, BTreeSet<String>> {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let sources: BTreeMap<String, String> = std::fs::read_dir(&dir)
            .expect("src/")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_some_and(|x| x == "rs") && !p.ends_with("lib.rs"))
            .map(|p| {
                let name = p.file_stem().expect("stem").to_string_lossy().into_owned();
                (name, std::fs::read_to_string(&p).expect("source"))
            })
            .collect();
        sources
            .iter()
            .map(|(m, text)| {
                let named = text
                    .split("crate::")
                    .skip(1)
                    .map(|s| s.chars().take_while(|c| c.is_ascii_lowercase() || *c == '_'))
                    .map(String::from_iter)
                    .filter(|t| t != m && sources.contains_key(t))
                    .collect();
                (m.clone(), named)
            })
            .collect()
    }

    /// No two modules need each other, directly or through others: shared parts live in a
    /// module of their own (`model`, `output`, `timing`).
    #[test]
    fn modules_form_no_cycle() {
        let graph = module_graph();
        assert!(graph.len() >= 10 && graph["sweep"].contains("model"), "{graph:?}");
        // Depth-first search from every module; a module met again on the path is a cycle.
        fn visit<'a>(
            m: &'a str,
            graph: &'a BTreeMap<String, BTreeSet<String>>,
            path: &mut Vec<&'a str>,
        ) {
            if let Some(k) = path.iter().position(|p| *p == m) {
                panic!("import cycle: {} -> {m}", path[k..].join(" -> "));
            }
            path.push(m);
            for n in &graph[m] {
                visit(n, graph, path);
            }
            path.pop();
        }
        for m in graph.keys() {
            visit(m, &graph, &mut Vec::new());
        }
    }
}
