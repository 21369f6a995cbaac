//! `vsm`, the method added through the registry's table alone: it reduces to the standard
//! shadow map without filtering (exactly at `f64` storage, closely at the paper's `f32`), its
//! filtered results stay in [0, 1] and soften the edges, its light-bleeding reduction darkens
//! the light in shadowed regions, and no file but its module and the table names it.

use crate::common;
use instrumentation::Recorder;
use methods::{
    filtered_map::{BLEEDING_REDUCTION, FILTER, PRECISION},
    params,
    registry::vsm,
    Frame, MethodOptions,
};

fn options(filter: u32, min_variance: f64) -> MethodOptions {
    let mut o = MethodOptions::default();
    o.set(&FILTER, params::Value::Count(filter));
    o.set(&vsm::MIN_VARIANCE, params::Value::Real(min_variance));
    o
}

/// `o` with the storage precision `name`.
fn at(mut o: MethodOptions, name: &str) -> MethodOptions {
    o.set(&PRECISION, PRECISION.parse(name).expect("a precision"));
    o
}

fn lit(name: &str, frame: &Frame<'_>, o: &MethodOptions) -> Vec<f32> {
    let m = methods::method(name, o).expect("builds");
    m.run(frame, &mut Recorder::default()).expect("runs").lit
}

fn mean_abs_difference(a: &[f32], b: &[f32]) -> f64 {
    a.iter().zip(b).map(|(x, y)| f64::from((x - y).abs())).sum::<f64>() / a.len() as f64
}

/// With a one-texel filter, no minimum variance and `f64` storage, the Chebyshev bound is 1
/// where the receiver is no deeper than the stored depth and 0 where it is: `sm`'s test, pixel
/// for pixel, at every map size. (At `f32` the rounding of `M2` leaves a variance of rounding
/// size behind a caster, so the bound there is small but not 0: the next test.)
#[test]
fn one_texel_without_minimum_variance_is_the_standard_shadow_map() {
    for name in ["cage", "bumpy", "plane-square"] {
        let Some(scene) = common::load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
        for map_res in [64, 256] {
            let mut o = at(options(1, 0.0), "f64");
            o.map_res = Some(map_res);
            let sm =
                lit("sm", &frame, &MethodOptions { map_res: Some(map_res), ..Default::default() });
            assert_eq!(lit("vsm", &frame, &o), sm, "{name} at map {map_res}");
        }
    }
}

/// At the default precision (the paper's `f32`) and minimum variance, a one-texel filter
/// stays close to `sm`: no pixel `sm` lights is darkened, few flip, and the mean difference is
/// the `f64` map's to within 1e-4; `f16` departs further.
#[test]
fn one_texel_at_the_default_precision_is_close_to_the_standard_shadow_map() {
    for name in ["cage", "bumpy", "plane-square"] {
        let Some(scene) = common::load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 64, 48, &mut Recorder::default());
        let sm = lit("sm", &frame, &MethodOptions { map_res: Some(256), ..Default::default() });
        let mut o = options(1, vsm::DEFAULT_MIN_VARIANCE);
        o.map_res = Some(256);
        let default = lit("vsm", &frame, &o);
        let exact = lit("vsm", &frame, &at(o.clone(), "f64"));
        let half = lit("vsm", &frame, &at(o, "f16"));
        for (v, s) in default.iter().zip(&sm) {
            assert!(*s == 0.0 || *v == 1.0, "{name}: a pixel sm lights is darkened ({v})");
        }
        let flips = default.iter().zip(&sm).filter(|(v, s)| (*v - *s).abs() > 0.5).count();
        assert!(flips * 200 < sm.len(), "{name}: {flips} pixels flip");
        let (d32, d64) = (mean_abs_difference(&default, &sm), mean_abs_difference(&exact, &sm));
        let d16 = mean_abs_difference(&half, &sm);
        eprintln!("{name}: mean difference from sm {d32:e} at f32, {d64:e} at f64, {d16:e} at f16");
        assert!((d32 - d64).abs() < 1e-4 && d32 < 2e-3, "{name}: {d32} at f32, {d64} at f64");
        assert!(d16 >= d32, "{name}: f16 {d16} closer than f32 {d32}");
    }
}

/// The light-bleeding reduction darkens the light wide filters let into `sm`'s shadows (by a
/// quarter at least at A = 0.3) and keeps every pixel `vsm` lights fully lit.
#[test]
fn bleeding_reduction_darkens_the_light_in_shadows() {
    for name in ["plane-square", "bumpy"] {
        let Some(scene) = common::load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 64, 48, &mut Recorder::default());
        let sm = lit("sm", &frame, &MethodOptions { map_res: Some(256), ..Default::default() });
        let mut o = options(9, vsm::DEFAULT_MIN_VARIANCE);
        o.map_res = Some(256);
        let plain = lit("vsm", &frame, &o);
        o.set(&BLEEDING_REDUCTION, params::Value::Real(0.3));
        let reduced = lit("vsm", &frame, &o);
        let leak = |v: &[f32]| -> f64 {
            v.iter().zip(&sm).filter(|(_, s)| **s == 0.0).map(|(l, _)| f64::from(*l)).sum()
        };
        let (before, after) = (leak(&plain), leak(&reduced));
        eprintln!("{name}: light in sm's shadow {before:.2} without, {after:.2} with A = 0.3");
        assert!(after < 0.75 * before, "{name}: {after} of {before}");
        for (p, r) in plain.iter().zip(&reduced) {
            assert!(*p < 1.0 || *r == 1.0, "{name}: a lit pixel darkened");
            assert!(r <= p, "{name}: the reduction brightened a pixel");
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

/// The example of `docs/adding-a-method.md` is a module (its Rust and, for its GPU kernels'
/// `store` and `test`, its WGSL) and a table entry: no other source file of the workspace names
/// it (tests and documents aside).
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
    // Its module is a Rust file and the WGSL of its GPU twin beside it.
    let mut expected: Vec<std::path::PathBuf> =
        ["methods/src/registry.rs", "methods/src/registry/vsm.rs", "methods/src/registry/vsm.wgsl"]
            .iter()
            .map(Into::into)
            .collect();
    expected.sort();
    assert_eq!(naming, expected);
    assert!(root.join("docs/adding-a-method.md").exists());
}
