//! `msm`, moment shadow maps: with a one-texel filter the result is close to the standard
//! shadow map's (the moment bias softens it a little); filtered results stay in [0, 1] and
//! soften the edges.

use crate::common;
use instrumentation::Recorder;
use methods::{filtered_map::FILTER, params, registry::msm, Frame, MethodOptions};

fn options(filter: u32, moment_bias: f64) -> MethodOptions {
    let mut o = MethodOptions { map_res: Some(256), ..Default::default() };
    o.set(&FILTER, params::Value::Count(filter));
    o.set(&msm::MOMENT_BIAS, params::Value::Real(moment_bias));
    o
}

fn lit(name: &str, frame: &Frame<'_>, o: &MethodOptions) -> Vec<f32> {
    let m = methods::method(name, o).expect("builds");
    m.run(frame, &mut Recorder::default()).expect("runs").lit
}

/// At one texel the reconstruction sees one depth per texel: `sm`'s lit pixels stay lit and
/// its shadowed ones are dark, within a small mean difference that shrinks with the bias.
#[test]
fn one_texel_is_close_to_the_standard_shadow_map() {
    for name in ["plane-square", "cage", "bumpy"] {
        let Some(scene) = common::load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
        let sm = lit("sm", &frame, &MethodOptions { map_res: Some(256), ..Default::default() });
        let mut last = f64::INFINITY;
        for bias in [1e-2, 3e-5, 1e-7] {
            let v = lit("msm", &frame, &options(1, bias));
            assert!(v.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)), "{name}");
            let diff: f64 = v.iter().zip(&sm).map(|(a, b)| f64::from((a - b).abs())).sum::<f64>()
                / v.len() as f64;
            assert!(
                diff <= last + 1e-9,
                "{name}: bias {bias} is farther from sm ({diff} > {last})"
            );
            last = diff;
        }
        assert!(last < 0.01, "{name}: {last} from sm at the smallest bias");
    }
}

/// Filtering makes penumbrae within [0, 1]; the shadow's interior stays dark.
#[test]
fn wider_filters_soften_the_edges_within_range() {
    let scene = common::load_builtin("plane-square").expect("built-in");
    let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
    let partial = |v: &[f32]| v.iter().filter(|&&x| x > 0.0 && x < 1.0).count();
    let sharp = lit("msm", &frame, &options(1, 1e-7));
    let soft = lit("msm", &frame, &options(9, 3e-5));
    assert!(soft.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)));
    assert!(partial(&soft) > partial(&sharp), "{} <= {}", partial(&soft), partial(&sharp));
    assert!(soft.iter().any(|&x| x < 0.05), "no dark pixel left");
}
