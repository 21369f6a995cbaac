//! `vsm`, the method added through the registry's table alone: it reduces to the standard
//! shadow map without filtering, its filtered results stay in [0, 1] and soften the edges, and
//! no file but its module and the table names it.

use crate::common;
use instrumentation::Recorder;
use methods::{filtered_map::FILTER, params, registry::vsm, Frame, MethodOptions};

fn options(filter: u32, min_variance: f64) -> MethodOptions {
    let mut o = MethodOptions::default();
    o.set(&FILTER, params::Value::Count(filter));
    o.set(&vsm::MIN_VARIANCE, params::Value::Real(min_variance));
    o
}

fn lit(name: &str, frame: &Frame<'_>, o: &MethodOptions) -> Vec<f32> {
    let m = methods::method(name, o).expect("builds");
    m.run(frame, &mut Recorder::default()).expect("runs").lit
}

/// With a one-texel filter and no minimum variance, the Chebyshev bound is 1 where the
/// receiver is no deeper than the stored depth and 0 where it is: `sm`'s test, pixel for
/// pixel, at every map size.
#[test]
fn one_texel_without_minimum_variance_is_the_standard_shadow_map() {
    for name in ["cage", "bumpy", "plane-square"] {
        let Some(scene) = common::load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
        for map_res in [64, 256] {
            let mut o = options(1, 0.0);
            o.map_res = Some(map_res);
            let sm =
                lit("sm", &frame, &MethodOptions { map_res: Some(map_res), ..Default::default() });
            assert_eq!(lit("vsm", &frame, &o), sm, "{name} at map {map_res}");
        }
    }
}

/// Filtering makes penumbrae: more pixels strictly between 0 and 1 as the filter widens, every
/// value finite and in [0, 1], and the shadow's interior stays dark.
#[test]
fn wider_filters_soften_the_edges_within_range() {
    let scene = common::load_builtin("plane-square").expect("built-in");
    let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
    let partial = |v: &[f32]| v.iter().filter(|&&x| x > 0.0 && x < 1.0).count();
    let mut last = 0;
    for filter in [1, 5, 15] {
        let mut o = options(filter, 1e-6);
        o.map_res = Some(256);
        let v = lit("vsm", &frame, &o);
        assert!(v.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)), "filter {filter}");
        let p = partial(&v);
        assert!(p >= last, "filter {filter}: {p} partial pixels, fewer than {last}");
        last = p;
        assert!(v.iter().any(|&x| x < 0.05), "filter {filter}: no dark pixel left");
    }
    assert!(last > 0, "a 15-texel filter leaves no penumbra");
}

/// The example of `docs/adding-a-method.md` is a module and a table entry: no other source
/// file of the workspace names it (tests and documents aside).
#[test]
fn the_example_method_touches_only_its_module_and_the_table() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut naming = Vec::new();
    let mut stack: Vec<std::path::PathBuf> =
        ["src", "scenes/src", "instrumentation/src", "methods/src", "analysis/src", "reports/src"]
            .iter()
            .map(|d| root.join(d))
            .collect();
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).expect("reads the sources").flatten() {
            let path = e.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|x| x == "rs" || x == "wgsl" || x == "toml") {
                let text = std::fs::read_to_string(&path).expect("reads a source");
                if text.contains("vsm") {
                    naming.push(path.strip_prefix(root).expect("inside").to_owned());
                }
            }
        }
    }
    naming.sort();
    let mut expected: Vec<std::path::PathBuf> =
        ["methods/src/registry.rs", "methods/src/registry/vsm.rs"].iter().map(Into::into).collect();
    expected.sort();
    assert_eq!(naming, expected);
    assert!(root.join("docs/adding-a-method.md").exists());
}
