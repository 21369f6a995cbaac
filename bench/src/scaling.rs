//! Cost against work: how each method's time grows with the scene's triangles (`random-1k` to
//! `random-1m` at 1024 x 768) and with the frame's pixels (`bunny-plane` from 320 x 240 to
//! 3840 x 2160), with the exponent of a power law fitted to each series.
//!
//! A method's time is its own stages (the camera G-buffer, shared by all, is the frame's and
//! timed apart as `gbuffer`); a reference's is its `evaluate`. The exponent is the slope of the
//! least-squares line through `(ln work, ln ms)`: 1 is linear, below 1 the fixed costs
//! dominate, above 1 the work grows faster than the input.

use instrumentation::Recorder;
use methods::{Frame, MethodOptions};

/// The methods measured, as `(label, name, options)`: a reference (`raytrace`, `exact`) or a
/// method of the registry.
pub fn methods() -> Vec<(&'static str, &'static str, MethodOptions)> {
    let rate = |r| MethodOptions { rate: Some(r), ..Default::default() };
    vec![
        ("afsm", "afsm", MethodOptions::default()),
        ("raytrace 1x", "raytrace", rate(1)),
        ("exact", "exact", MethodOptions::default()),
        ("sm", "sm", MethodOptions::default()),
        ("pan09 32x", "pan09", rate(32)),
        ("spsm", "spsm", MethodOptions::default()),
    ]
}

/// The median time, in milliseconds over `repeats` runs, of `name` with `options` on `frame`.
pub fn time(
    frame: &Frame<'_>,
    name: &str,
    options: &MethodOptions,
    repeats: usize,
) -> anyhow::Result<f64> {
    let mut times = Vec::with_capacity(repeats);
    for _ in 0..repeats.max(1) {
        let mut rec = Recorder::default();
        match name {
            "raytrace" | "exact" => {
                let r: Box<dyn analysis::Reference> = if name == "exact" {
                    Box::new(analysis::exact::ExactCoverage { edge: None })
                } else {
                    analysis::registry::reference(
                        name,
                        options.rate.unwrap_or(1),
                        Default::default(),
                    )?
                };
                r.evaluate(frame, &mut rec)?;
            }
            _ => {
                analysis::registry::technique(name, options)?.run(frame, &mut rec)?;
            }
        }
        times.push(rec.stages.total_ms());
    }
    Ok(crate::median(&mut times))
}

/// The exponent `b` of the power law `ms = a work^b` that fits `points` `(work, ms)` best in
/// the least-squares sense on logarithms; `None` for fewer than two distinct, positive works.
pub fn fit_exponent(points: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(w, t)| *w > 0.0 && *t > 0.0)
        .map(|(w, t)| (w.ln(), t.ln()))
        .collect();
    let n = logs.len() as f64;
    let (mx, my) = logs.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let sxx: f64 = logs.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    let sxy: f64 = logs.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    (logs.len() >= 2 && sxx > 0.0).then(|| sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_power_law_gives_its_exponent() {
        let pts: Vec<(f64, f64)> =
            [1e3, 1e4, 1e5, 1e6].iter().map(|&w: &f64| (w, 3.0 * w.powf(0.8))).collect();
        let b = fit_exponent(&pts).expect("fits");
        assert!((b - 0.8).abs() < 1e-12, "{b}");
        assert_eq!(fit_exponent(&pts[..1]), None);
        assert_eq!(fit_exponent(&[(1.0, 2.0), (1.0, 3.0)]), None, "one work only");
        // Noise around a line: the fit lies between the extremes' slopes.
        let noisy = [(1.0, 1.0), (10.0, 12.0), (100.0, 90.0), (1000.0, 1100.0)];
        let b = fit_exponent(&noisy).expect("fits");
        assert!((0.9..1.1).contains(&b), "{b}");
    }
}
