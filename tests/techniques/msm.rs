//! `msm`, moment shadow maps: with a one-texel filter the result is close to the standard
//! shadow map's (the moment bias softens it a little), at every precision with its default
//! bias; filtered results stay in [0, 1] and soften the edges; the light-bleeding reduction
//! darkens the light in shadowed regions.

use crate::common;
use instrumentation::Recorder;
use methods::{
    filtered_map::{BLEEDING_REDUCTION, FILTER, PRECISION},
    params,
    registry::msm,
    Frame, MethodOptions,
};

fn options(filter: u32, moment_bias: f64) -> MethodOptions {
    let mut o = MethodOptions { map_res: Some(256), ..Default::default() };
    o.set(&FILTER, params::Value::Count(filter));
    o.set(&msm::MOMENT_BIAS, params::Value::Real(moment_bias));
    o
}

/// `o` with the storage precision `name`.
fn at(mut o: MethodOptions, name: &str) -> MethodOptions {
    o.set(&PRECISION, PRECISION.parse(name).expect("a precision"));
    o
}

fn mean_abs_difference(a: &[f32], b: &[f32]) -> f64 {
    a.iter().zip(b).map(|(x, y)| f64::from((x - y).abs())).sum::<f64>() / a.len() as f64
}

fn lit(name: &str, frame: &Frame<'_>, o: &MethodOptions) -> Vec<f32> {
    let m = methods::method(name, o).expect("builds");
    m.run(frame, &mut Recorder::default()).expect("runs").lit
}

/// At one texel the reconstruction sees one depth per texel: `sm`'s lit pixels stay lit and
/// its shadowed ones are dark, within a small mean difference that shrinks with the bias. At
/// `f64` storage: a bias below what the rounding of `u16` or `f32` needs is meaningful only
/// without rounding (the next test takes each precision at its default bias).
#[test]
fn one_texel_is_close_to_the_standard_shadow_map() {
    for name in ["plane-square", "cage", "bumpy"] {
        let Some(scene) = common::load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
        let sm = lit("sm", &frame, &MethodOptions { map_res: Some(256), ..Default::default() });
        let mut last = f64::INFINITY;
        for bias in [1e-2, 3e-5, 1e-7] {
            let v = lit("msm", &frame, &at(options(1, bias), "f64"));
            assert!(v.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)), "{name}");
            let diff = mean_abs_difference(&v, &sm);
            assert!(
                diff <= last + 1e-9,
                "{name}: bias {bias} is farther from sm ({diff} > {last})"
            );
            last = diff;
        }
        assert!(last < 0.01, "{name}: {last} from sm at the smallest bias");
    }
}

/// Each precision at its default bias (the paper's 64-bit optimized quantization, `u16`, by
/// default; `f32`; `f64`) stays close to `sm` at one texel: few pixels `sm` lights are
/// darkened by more than 0.01 (at `f32` the paper's small bias leaves a few, a receiver close
/// behind its own caster's rounded moments), few flip, and the mean difference is small.
#[test]
fn one_texel_at_each_precision_is_close_to_the_standard_shadow_map() {
    for name in ["plane-square", "cage", "bumpy"] {
        let Some(scene) = common::load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 64, 48, &mut Recorder::default());
        let sm = lit("sm", &frame, &MethodOptions { map_res: Some(256), ..Default::default() });
        let mut o = MethodOptions { map_res: Some(256), ..Default::default() };
        o.set(&FILTER, params::Value::Count(1));
        for precision in [None, Some("u16"), Some("f32"), Some("f64")] {
            let o = precision.map_or_else(|| o.clone(), |p| at(o.clone(), p));
            let v = lit("msm", &frame, &o);
            let darkened = v.iter().zip(&sm).filter(|(l, s)| **s == 1.0 && **l < 0.99).count();
            let flips = v.iter().zip(&sm).filter(|(l, s)| (*l - *s).abs() > 0.5).count();
            let diff = mean_abs_difference(&v, &sm);
            eprintln!(
                "{name} {precision:?}: {darkened} lit pixels darkened, {flips} flips, mean \
                       difference {diff:e}"
            );
            assert!(darkened * 200 < sm.len(), "{name} {precision:?}: {darkened} darkened");
            assert!(flips * 200 < sm.len() && diff < 3e-3, "{name} {precision:?}: {diff}");
        }
    }
}

/// The light-bleeding reduction darkens the light wide filters let into `sm`'s shadows (by a
/// quarter at least at A = 0.3) and never brightens a pixel.
#[test]
fn bleeding_reduction_darkens_the_light_in_shadows() {
    for name in ["plane-square", "bumpy"] {
        let Some(scene) = common::load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 64, 48, &mut Recorder::default());
        let sm = lit("sm", &frame, &MethodOptions { map_res: Some(256), ..Default::default() });
        let mut o = MethodOptions { map_res: Some(256), ..Default::default() };
        o.set(&FILTER, params::Value::Count(9));
        let plain = lit("msm", &frame, &o);
        o.set(&BLEEDING_REDUCTION, params::Value::Real(0.3));
        let reduced = lit("msm", &frame, &o);
        let leak = |v: &[f32]| -> f64 {
            v.iter().zip(&sm).filter(|(_, s)| **s == 0.0).map(|(l, _)| f64::from(*l)).sum()
        };
        let (before, after) = (leak(&plain), leak(&reduced));
        eprintln!("{name}: light in sm's shadow {before:.2} without, {after:.2} with A = 0.3");
        assert!(after < 0.75 * before, "{name}: {after} of {before}");
        assert!(plain.iter().zip(&reduced).all(|(p, r)| r <= p), "{name}: brightened");
    }
}

/// Filtering makes penumbrae within [0, 1]; the shadow's interior stays dark.
#[test]
fn wider_filters_soften_the_edges_within_range() {
    let scene = common::load_builtin("plane-square").expect("built-in");
    let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
    let partial = |v: &[f32]| v.iter().filter(|&&x| x > 0.0 && x < 1.0).count();
    let sharp = lit("msm", &frame, &at(options(1, 1e-7), "f64"));
    let soft = lit("msm", &frame, &options(9, 3e-5));
    assert!(soft.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)));
    assert!(partial(&soft) > partial(&sharp), "{} <= {}", partial(&soft), partial(&sharp));
    assert!(soft.iter().any(|&x| x < 0.05), "no dark pixel left");
}
