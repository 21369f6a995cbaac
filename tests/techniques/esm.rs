//! `esm`, exponential shadow maps: with a one-texel filter the result tends to the standard
//! shadow map's as the exponent grows; filtered results stay in [0, 1] and soften the edges.

use crate::common;
use instrumentation::Recorder;
use methods::{filtered_map::FILTER, params, registry::esm, Frame, MethodOptions};

fn options(filter: u32, exponent: f64) -> MethodOptions {
    let mut o = MethodOptions { map_res: Some(256), ..Default::default() };
    o.set(&FILTER, params::Value::Count(filter));
    o.set(&esm::EXPONENT, params::Value::Real(exponent));
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
/// shrinks with `c`, and never comes from a pixel `sm` lights.
#[test]
fn one_texel_tends_to_the_standard_shadow_map_as_the_exponent_grows() {
    for name in ["plane-square", "cage"] {
        let Some(scene) = common::load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
        let sm = lit("sm", &frame, &MethodOptions { map_res: Some(256), ..Default::default() });
        let mut last = f64::INFINITY;
        for c in [10.0, 80.0, 700.0] {
            let v = lit("esm", &frame, &options(1, c));
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

/// Filtering makes penumbrae within [0, 1]; the shadow's interior stays dark at the paper's
/// exponent.
#[test]
fn wider_filters_soften_the_edges_within_range() {
    let scene = common::load_builtin("plane-square").expect("built-in");
    let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
    let partial = |v: &[f32]| v.iter().filter(|&&x| x > 0.0 && x < 1.0).count();
    let sharp = lit("esm", &frame, &options(1, 700.0));
    let soft = lit("esm", &frame, &options(9, 80.0));
    assert!(soft.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)));
    assert!(partial(&soft) > partial(&sharp), "{} <= {}", partial(&soft), partial(&sharp));
    assert!(soft.iter().any(|&x| x < 0.05), "no dark pixel left");
}
