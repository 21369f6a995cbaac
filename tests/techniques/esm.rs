//! `esm`, exponential shadow maps: with a one-texel filter the result tends to the standard
//! shadow map's as the exponent grows (at `f64` storage; at the paper's `f32` and exponent the
//! same as at `f64` to within rounding); filtered results stay in [0, 1] and soften the edges.

use crate::common;
use instrumentation::Recorder;
use methods::{
    filtered_map::{FILTER, PRECISION},
    params,
    registry::esm,
    Frame, MethodOptions,
};

fn options(filter: u32, exponent: f64) -> MethodOptions {
    let mut o = MethodOptions { map_res: Some(256), ..Default::default() };
    o.set(&FILTER, params::Value::Count(filter));
    o.set(&esm::EXPONENT, params::Value::Real(exponent));
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

/// At one texel, a lit pixel of `sm` is lit (`d <= z`: the test is at least 1) and a shadowed
/// one is `exp(-c (d - z))`, which falls to 0 as `c` grows: the mean difference from `sm`
/// shrinks with `c`, and never comes from a pixel `sm` lights. At `f64` storage: at `f32`,
/// `c = 700` rounds the stored values of casters nearer than 0.85 of the depth range to 0
/// (the run warns), which shadows everything in their texels.
#[test]
fn one_texel_tends_to_the_standard_shadow_map_as_the_exponent_grows() {
    for name in ["plane-square", "cage"] {
        let Some(scene) = common::load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
        let sm = lit("sm", &frame, &MethodOptions { map_res: Some(256), ..Default::default() });
        let mut last = f64::INFINITY;
        for c in [10.0, 80.0, 700.0] {
            let v = lit("esm", &frame, &at(options(1, c), "f64"));
            for (e, s) in v.iter().zip(&sm) {
                assert!((0.0..=1.0).contains(e), "{name} c {c}: {e}");
                if *s == 1.0 {
                    assert_eq!(*e, 1.0, "{name} c {c}: a pixel sm lights is shadowed");
                }
            }
            let diff = mean_abs_difference(&v, &sm);
            assert!(diff <= last, "{name}: c {c} is farther from sm ({diff}) than before ({last})");
            last = diff;
        }
        assert!(last < 1e-3, "{name}: at c 700, {last} from sm");
    }
}

/// At the default precision (the paper's `f32`) and exponent every value is the `f64` map's
/// to within 1e-5, one texel or nine; at `f16` the paper's exponent rounds near casters' values
/// to 0, and the run says so.
#[test]
fn the_papers_precision_and_exponent_agree_with_f64() {
    let scene = common::load_builtin("cage").expect("built-in");
    let frame = Frame::new(&scene, 64, 48, &mut Recorder::default());
    for filter in [1, 9] {
        let o = options(filter, esm::DEFAULT_EXPONENT);
        let (single, double) = (lit("esm", &frame, &o), lit("esm", &frame, &at(o.clone(), "f64")));
        let worst = single.iter().zip(&double).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
        assert!(worst < 1e-5, "filter {filter}: {worst}");
        let m = methods::method("esm", &at(o, "f16")).expect("builds");
        let mut rec = Recorder::default();
        m.run(&frame, &mut rec).expect("runs");
        assert!(rec.warnings.iter().any(|w| w.contains("rounds to 0")), "{:?}", rec.warnings);
    }
}

/// Filtering makes penumbrae within [0, 1]; the shadow's interior stays dark at the paper's
/// exponent.
#[test]
fn wider_filters_soften_the_edges_within_range() {
    let scene = common::load_builtin("plane-square").expect("built-in");
    let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
    let partial = |v: &[f32]| v.iter().filter(|&&x| x > 0.0 && x < 1.0).count();
    let sharp = lit("esm", &frame, &at(options(1, 700.0), "f64"));
    let soft = lit("esm", &frame, &options(9, 80.0));
    assert!(soft.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)));
    assert!(partial(&soft) > partial(&sharp), "{} <= {}", partial(&soft), partial(&sharp));
    assert!(soft.iter().any(|&x| x < 0.05), "no dark pixel left");
}
