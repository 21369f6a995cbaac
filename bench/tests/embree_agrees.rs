//! Embree and `raytrace` agree on small frames, sample by sample, except on exact ties.
//!
//! `raytrace` decides every hit in `f64` with a watertight test; Embree in `f32`. Where they
//! differ, the test checks that the sample is a tie: the ray passes within [`TIE`] (in
//! barycentric units, so relative to the triangle's size) of an edge of one of the triangles
//! involved, or meets two triangles at depths within [`TIE`] of each other, or (for shadow
//! rays) meets a caster between where our shadow ray starts and where Embree's does
//! ([`bench::embree_shadow_start`]: Embree works in `f32` and cannot leave out the surface the
//! ray leaves), or leaves its surface so nearly along it that where Embree starts it, it is
//! still within 8 `f32` epsilons of the point's magnitude of that surface (a grazing light,
//! where Embree's `f32` hit point may lie under the surface). Any other difference fails.

#![cfg(feature = "embree")]

use bench::embree_tracer::{trace, Api};
use bench::{embree_shadow_start, shadow_ray, Samples};
use glam::DVec3;
use instrumentation::Recorder;
use methods::pattern::{PatternKind, SamplePattern};
use methods::raster::NO_TRIANGLE;
use methods::Frame;

/// How close to an edge, a depth or a ray's start counts as a tie (barycentric, or relative).
const TIE: f64 = 1e-5;

/// Where the ray `o + t d` meets triangle `k`'s plane: `t` and the smallest barycentric
/// coordinate (negative outside); `None` for a ray parallel to the plane.
fn meet(frame: &Frame<'_>, k: usize, o: DVec3, d: DVec3) -> Option<(f64, f64)> {
    let g = &frame.geometry;
    let [a, b, c] = g.triangles[k].map(|i| g.positions[i as usize]);
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let s = o - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    Some((t, u.min(v).min(1.0 - u - v)))
}

/// Whether the camera ray through sample `xy` is a tie between hitting `ours` and `theirs`.
fn camera_tie(frame: &Frame<'_>, xy: glam::DVec2, ours: u32, theirs: u32) -> bool {
    let r = frame.camera.ray(xy);
    let hit = |k: u32| {
        (k != NO_TRIANGLE).then(|| meet(frame, k as usize, r.origin, r.direction)).flatten()
    };
    let grazes = |m: Option<(f64, f64)>| m.is_some_and(|(_, b)| b.abs() <= TIE);
    let (a, b) = (hit(ours), hit(theirs));
    let same_depth = match (a, b) {
        (Some((ta, _)), Some((tb, _))) => (ta - tb).abs() <= TIE * ta.abs().max(tb.abs()),
        _ => false,
    };
    grazes(a) || grazes(b) || same_depth
}

/// Whether the shadow ray from the camera's hit through sample `xy` on triangle `tri` is a
/// tie: it grazes a caster, or meets one within `TIE` of where it starts.
fn shadow_tie(frame: &Frame<'_>, xy: glam::DVec2, tri: u32) -> bool {
    let r = frame.camera.ray(xy);
    let Some((t, _)) = meet(frame, tri as usize, r.origin, r.direction) else { return true };
    let p = r.origin + t * r.direction;
    let Some((d, tmin, tmax)) = shadow_ray(frame, r.origin, p) else { return true };
    // A grazing light: where Embree starts the ray, it is still within f32 rounding of the
    // surface it leaves (Embree's hit point, in f32, may lie under that surface).
    let g = &frame.geometry;
    let [a, b, c] = g.triangles[tri as usize].map(|i| g.positions[i as usize]);
    let n = (b - a).cross(c - a).normalize_or_zero();
    let start = embree_shadow_start(r.origin, p, tmin);
    let magnitude = r.origin.abs().max(p.abs()).max_element() + (p - r.origin).abs().max_element();
    if d.dot(n).abs() * start <= 8.0 * f64::from(f32::EPSILON) * magnitude {
        return true;
    }
    (0..frame.geometry.len()).filter(|&k| frame.is_caster(k) && k != tri as usize).any(|k| {
        meet(frame, k, p, d).is_some_and(|(t, b)| {
            let along = t > tmin * (1.0 - TIE) && t < tmax;
            // Between our start and Embree's, or at either within TIE of the magnitude.
            let scale = TIE * p.abs().max_element().max(1.0);
            let near_start = t > tmin - scale && t < start + scale;
            (along && b.abs() <= TIE) || (near_start && b >= -TIE)
        })
    })
}

#[test]
fn embree_and_raytrace_agree_except_on_exact_ties() {
    let mut checked = 0;
    for name in ["plane-square", "cage", "spheres", "spot-spheres", "bunny-plane"] {
        let scene = match scenes::load(name) {
            Ok(s) => s,
            Err(e @ scenes::SceneError::ModelMissing { .. }) => {
                eprintln!("skipping {name}: {e}");
                continue;
            }
            Err(e) => panic!("{name}: {e}"),
        };
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        let pattern = SamplePattern::new(1, PatternKind::Grid).expect("rate 1");
        let rt = analysis::raytrace::RayTrace { pattern: pattern.clone() };
        let ours = rt.sample_image(&frame, &mut Recorder::default()).expect("traces");
        let samples = Samples::new(&frame, &pattern);
        for api in [Api::PerRay, Api::Stream16] {
            let theirs = trace(&frame, &samples, api);
            let (mut ties, mut shadowed) = (0, 0);
            for k in 0..samples.points.len() {
                let xy = samples.points[k];
                let (a, b) = (ours.triangle[k], theirs.triangle[k]);
                if a != b {
                    assert!(
                        camera_tie(&frame, xy, a, b),
                        "{name} {api:?}: sample {k} hits {a} here and {b} in Embree"
                    );
                    ties += 1;
                    continue;
                }
                shadowed += usize::from(ours.light[k] == 0.0);
                if ours.light[k] != theirs.light[k] {
                    assert!(
                        shadow_tie(&frame, xy, a),
                        "{name} {api:?}: sample {k} on triangle {a} has light {} here and {} in Embree",
                        ours.light[k],
                        theirs.light[k]
                    );
                    ties += 1;
                }
            }
            let n = samples.points.len();
            eprintln!("{name} {api:?}: {ties} ties of {n} samples, {shadowed} shadowed");
            assert!(shadowed > n / 100, "{name}: a frame with shadows ({shadowed} of {n})");
            assert!(ties <= n / 100, "{name} {api:?}: {ties} ties of {n} samples");
            checked += 1;
        }
    }
    assert!(checked >= 8, "the built-in scenes without models at least");
}
