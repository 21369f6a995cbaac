//! Hard cases: a generated family of scenes that stresses every method and both references.
//!
//! The base scene is a 10 x 10 ground plane with a floating box and a free triangle above it
//! and a triangle hidden just under it, seen at 64 x 48, under a directional or a spot light.
//! The family transforms it as a whole (positions, camera eye, target and near distance, spot
//! position and target) over scale (1e-6 .. 1e6) and translation (up to 1e7), adds one
//! triangle far away (1e8 .. 1e12), turns the light towards the horizon (up to 89.9 degrees
//! from the ground's normal), and adds slivers (aspect 1e-6), degenerate and duplicated
//! triangles, casters lying in and touching the ground, and a camera that sees the ground
//! edge-on.
//!
//! On every scene, every method of `methods::registry` (CPU) and both references must run
//! without panicking and give finite values in `[0, 1]`. On the scaled, translated and
//! far-object variants, `exact` must evaluate the same pixels as on the base scene, and
//! `raytrace` (rate 1 and 16) and `afsm` must agree with it as well as they do on the base
//! scene: the mean absolute error over `exact`'s evaluated pixels within `1e-4` of the base
//! scene's. Every other method must do the same on the scaled and translated variants (with a
//! far object the light frustum, fitted to the scene's bounds, no longer resolves the scene
//! near the origin, and the constant depth bias, a fraction of the light's depth range, grows
//! past the scene under a spot light too, so shadow maps are not held to it there). Scenes beyond `scenes::limits`
//! must be refused as bad input naming the supported range. Near the horizon, the shadow-map
//! methods with default options must keep the lit ground lit, or say in the run's warnings
//! that the bias is out of range.
//! Where a GPU adapter exists (Mesa's lavapipe will do), `afsm`'s GPU kernels must equal the
//! CPU's pixel for pixel on the base, scaled, translated and far-object scenes.

use crate::common;

use analysis::{registry::technique, ReferenceImage};
use glam::DVec3;
use instrumentation::Recorder;
use methods::{pattern::PatternKind, Frame, MethodOptions, Visibility};
use scenes::{Camera, Light, Material, Mesh, Object, Scene};
use std::panic::{catch_unwind, AssertUnwindSafe};

const WIDTH: u32 = 64;
const HEIGHT: u32 = 48;

/// A mesh of separate triangles.
fn triangles(tris: &[[DVec3; 3]]) -> Mesh {
    let positions = tris.iter().flatten().copied().collect();
    let indices = (0..tris.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    Mesh::new(positions, indices).expect("valid mesh")
}

/// An axis-aligned box between `lo` and `hi`, counter-clockwise seen from outside.
fn box_mesh(lo: DVec3, hi: DVec3) -> Mesh {
    let corners = scenes::mesh::box_corners(lo, hi);
    let c = |i: usize| corners[i];
    let centre = 0.5 * (lo + hi);
    let quads =
        [[0, 1, 3, 2], [4, 5, 7, 6], [0, 1, 5, 4], [2, 3, 7, 6], [0, 2, 6, 4], [1, 3, 7, 5]];
    let mut tris = Vec::new();
    for q in quads {
        let [a, b, cc, d] = q.map(c);
        for mut t in [[a, b, cc], [a, cc, d]] {
            let outward = (t[0] + t[1] + t[2]) / 3.0 - centre;
            if (t[1] - t[0]).cross(t[2] - t[0]).dot(outward) < 0.0 {
                t.swap(1, 2);
            }
            tris.push(t);
        }
    }
    triangles(&tris)
}

fn object(name: &str, mesh: Mesh) -> Object {
    Object { name: name.into(), mesh, material: Material::default(), casts_shadows: true }
}

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// The ground: a 10 x 10 square at y = 0, facing up.
fn ground() -> Object {
    let s = 5.0;
    object(
        "ground",
        triangles(&[
            [v(-s, 0.0, -s), v(-s, 0.0, s), v(s, 0.0, s)],
            [v(-s, 0.0, -s), v(s, 0.0, s), v(s, 0.0, -s)],
        ]),
    )
}

/// A free triangle above the ground, facing up.
const FREE_TRIANGLE: [[f64; 3]; 3] = [[0.5, 1.2, -1.2], [0.9, 0.9, 1.3], [2.2, 1.4, 0.4]];

fn free_triangle() -> [DVec3; 3] {
    FREE_TRIANGLE.map(DVec3::from)
}

/// The light's direction `angle_deg` from the ground's normal, from an azimuth that is
/// parallel to no face of the box.
fn directional_at(angle_deg: f64) -> Light {
    let (s, c) = angle_deg.to_radians().sin_cos();
    Light::Directional { direction: v(-0.8 * s, -c, -0.6 * s) }
}

fn spot() -> Light {
    Light::Spot { position: v(-3.0, 8.0, 2.0), target: DVec3::ZERO, fov_deg: 90.0 }
}

/// The base scene: the ground, a floating box, a free triangle, and a triangle just under the
/// ground.
fn base(light: Light) -> Scene {
    Scene {
        name: "hard-base".into(),
        width: WIDTH,
        height: HEIGHT,
        camera: Camera::Perspective {
            eye: v(0.0, 6.0, 8.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_deg: 45.0,
            near: 0.01,
        },
        light,
        objects: vec![
            ground(),
            object("box", box_mesh(v(-2.0, 0.6, -1.0), v(-0.8, 1.6, 0.2))),
            object("triangle", triangles(&[free_triangle()])),
            // Hidden under the ground: it must not cost `exact` any evaluated pixel.
            object(
                "under",
                triangles(&[[v(-3.0, -1e-3, 1.0), v(3.0, -1e-3, 1.0), v(0.0, -1e-3, -3.0)]]),
            ),
        ],
        switches: Default::default(),
        animation: Default::default(),
    }
}

/// `scene` with every position mapped by `p -> p * scale + offset`: geometry, camera (eye,
/// target, near distance) and spot light (position, target).
fn transformed(scene: &Scene, scale: f64, offset: DVec3) -> Scene {
    let f = |p: DVec3| p * scale + offset;
    let mut s = scene.clone();
    for o in &mut s.objects {
        for p in &mut o.mesh.positions {
            *p = f(*p);
        }
    }
    s.camera = match s.camera {
        Camera::Perspective { eye, target, up, fov_y_deg, near } => Camera::Perspective {
            eye: f(eye),
            target: f(target),
            up,
            fov_y_deg,
            near: near * scale,
        },
        Camera::Orthographic { eye, target, up, height } => {
            Camera::Orthographic { eye: f(eye), target: f(target), up, height: height * scale }
        }
    };
    if let Light::Spot { position, target, fov_deg } = s.light {
        s.light = Light::Spot { position: f(position), target: f(target), fov_deg };
    }
    s
}

/// One member of the family.
struct Case {
    name: String,
    scene: Scene,
    /// Whether the case is the base scene moved, scaled or extended by a far object, whose
    /// references must agree with `exact` as on the base scene (index into the bases).
    base: Option<usize>,
    /// Whether the case adds a far object (the shadow maps' light frustum, fitted to the
    /// scene's bounds, then no longer resolves the scene near the origin).
    far: bool,
}

fn case(name: impl Into<String>, scene: Scene, base: Option<usize>) -> Case {
    Case { name: name.into(), scene, base, far: false }
}

/// The two base scenes: directional (index 0) and spot light (index 1).
fn bases() -> [Scene; 2] {
    [base(directional_at(35.0)), base(spot())]
}

/// The whole family.
fn family() -> Vec<Case> {
    let bases = bases();
    let mut cases = Vec::new();
    for (k, b) in bases.iter().enumerate() {
        let light = if k == 0 { "directional" } else { "spot" };
        cases.push(case(format!("base {light}"), b.clone(), None));
        for scale in [1e-6, 1e-3, 1e3, 1e6] {
            cases.push(case(
                format!("scale {scale:e} {light}"),
                transformed(b, scale, DVec3::ZERO),
                Some(k),
            ));
        }
        for t in [1e3, 1e5, 1e7] {
            cases.push(case(
                format!("translate {t:e} {light}"),
                transformed(b, 1.0, v(1.0, 0.5, -0.7) * t),
                Some(k),
            ));
        }
        for d in [1e8, 1e10, 1e12] {
            // Behind the camera and away from the light's path: it shadows nothing in view.
            let mut s = b.clone();
            let p = v(0.6 * d, 3.0, 0.8 * d);
            s.objects
                .push(object("far", triangles(&[[p, p + v(1.0, 0.0, 0.0), p + v(0.0, 0.5, 1.0)]])));
            cases.push(Case { far: true, ..case(format!("far object {d:e} {light}"), s, Some(k)) });
        }
    }
    for angle in [45.0, 80.0, 85.0, 89.0, 89.9] {
        cases.push(case(format!("light {angle} deg"), base(directional_at(angle)), None));
    }
    let with = |name: &str, extra: Object| {
        let mut s = base(directional_at(35.0));
        s.objects.push(extra);
        case(name, s, None)
    };
    cases.push(with(
        "slivers",
        object(
            "slivers",
            triangles(&[
                [v(-3.0, 2.0, 1.0), v(3.0, 2.0, 1.0 + 6e-6), v(3.0, 2.0, 1.0)],
                [v(1.0, 0.5, -3.0), v(1.0 + 4e-6, 2.5, 2.0), v(1.0, 2.5, 2.0)],
                [v(-1.0, 1.0, 2.0), v(2.0, 1.0 + 3e-6, 2.0), v(-1.0, 1.0, 2.0 + 3e-6)],
            ]),
        ),
    ));
    let t = free_triangle();
    cases.push(with(
        "degenerate",
        object(
            "degenerate",
            Mesh::new(
                vec![t[0], t[1], t[2], 0.5 * (t[0] + t[1]), v(1.0, 2.0, 1.0)],
                vec![[0, 1, 3], [0, 0, 2], [4, 4, 4], [1, 1, 1], [0, 3, 1]],
            )
            .expect("valid indices"),
        ),
    ));
    cases.push(with("duplicated", object("duplicated", triangles(&[t, t, t, [t[0], t[2], t[1]]]))));
    cases.push(with(
        "caster in the ground plane",
        object("flat", triangles(&[[v(-1.0, 0.0, 2.0), v(0.0, 0.0, 3.0), v(1.0, 0.0, 1.5)]])),
    ));
    cases.push(with(
        "caster touching the ground",
        object("standing", box_mesh(v(1.5, 0.0, 1.0), v(2.5, 1.0, 2.0))),
    ));
    for (name, eye) in
        [("ground edge-on", v(0.0, 0.0, 9.0)), ("ground nearly edge-on", v(0.0, 1e-4, 9.0))]
    {
        let mut s = base(directional_at(35.0));
        s.camera = Camera::Perspective {
            eye,
            target: v(0.0, eye.y, 0.0),
            up: DVec3::Y,
            fov_y_deg: 45.0,
            near: 0.01,
        };
        cases.push(case(name, s, None));
    }
    cases
}

/// Every technique name: every method of the registry and both references.
fn techniques() -> Vec<&'static str> {
    let mut names: Vec<&str> = methods::METHODS.iter().map(|m| m.name).collect();
    names.extend(analysis::registry::REFERENCES.iter().map(|(n, _)| *n));
    names
}

/// Runs `name` (default options, `rate` if given) on `frame`, catching panics.
fn run(name: &str, rate: Option<u32>, frame: &Frame<'_>) -> Result<(Visibility, Recorder), String> {
    run_with(name, &MethodOptions { rate, ..Default::default() }, frame)
}

/// Runs `name` with `options` on `frame`, catching panics.
fn run_with(
    name: &str,
    options: &MethodOptions,
    frame: &Frame<'_>,
) -> Result<(Visibility, Recorder), String> {
    let t = technique(name, options).map_err(|e| format!("not built: {e}"))?;
    catch_unwind(AssertUnwindSafe(|| {
        let mut rec = Recorder::default();
        t.run(frame, &mut rec).map(|v| (v, rec))
    }))
    .map_err(|p| {
        let msg = p
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| p.downcast_ref::<&str>().map(|s| (*s).to_owned()))
            .unwrap_or_default();
        format!("panicked: {msg}")
    })?
    .map_err(|e| format!("refused: {e}"))
}

/// The first pixel whose value is not finite or lies outside `[0, 1]`.
fn bad_pixel(v: &Visibility) -> Option<(usize, f32)> {
    let bad = |x: f32| !(x.is_finite() && (0.0..=1.0).contains(&x));
    v.lit.iter().copied().enumerate().find(|&(_, x)| bad(x)).or_else(|| {
        v.transmittance.iter().flatten().flatten().copied().enumerate().find(|&(_, x)| bad(x))
    })
}

fn exact(frame: &Frame<'_>) -> Option<ReferenceImage> {
    analysis::registry::reference("exact", 1, PatternKind::Grid)
        .expect("exists")
        .evaluate(frame, &mut Recorder::default())
        .ok()
}

/// Mean absolute error of `v` against `reference` over its evaluated pixels, and their count.
fn mean_error(v: &Visibility, reference: &ReferenceImage) -> (f64, usize) {
    let (mut sum, mut n) = (0.0, 0usize);
    for ((&x, &r), &e) in v.lit.iter().zip(&reference.lit).zip(&reference.evaluated) {
        if e {
            sum += (f64::from(x) - r).abs();
            n += 1;
        }
    }
    (if n == 0 { 0.0 } else { sum / n as f64 }, n)
}

#[test]
fn every_technique_gives_finite_values_in_range_on_every_hard_case() {
    let mut failures = Vec::new();
    for c in family() {
        let frame = match catch_unwind(AssertUnwindSafe(|| {
            Frame::new(&c.scene, WIDTH, HEIGHT, &mut Recorder::default())
        })) {
            Ok(f) => f,
            Err(_) => {
                failures.push(format!("{}: the frame panicked", c.name));
                continue;
            }
        };
        for name in techniques() {
            match run(name, None, &frame) {
                Ok((v, _)) => {
                    if let Some((k, x)) = bad_pixel(&v) {
                        failures.push(format!("{}: {name}: pixel {k} is {x}", c.name));
                    }
                }
                Err(e) => failures.push(format!("{}: {name}: {e}", c.name)),
            }
        }
    }
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn every_technique_agrees_with_exact_at_every_scale_and_position_as_at_scale_1() {
    // (technique, rate, also with a far object): the shadow-map methods only where their
    // light depth map still resolves the scene, scaled and translated.
    let mut checks: Vec<(&str, Option<u32>, bool)> =
        vec![("raytrace", Some(1), true), ("raytrace", Some(16), true), ("afsm", None, true)];
    checks.extend(
        methods::METHODS.iter().filter(|m| m.name != "afsm").map(|m| (m.name, None, false)),
    );
    let errors = |scene: &Scene| -> Vec<Result<(f64, usize), String>> {
        let frame = Frame::new(scene, WIDTH, HEIGHT, &mut Recorder::default());
        let Some(reference) = exact(&frame) else {
            return vec![Err("exact does not apply".into()); checks.len()];
        };
        checks
            .iter()
            .map(|&(name, rate, _)| {
                run(name, rate, &frame).map(|(v, _)| mean_error(&v, &reference))
            })
            .collect()
    };
    let base_errors: Vec<Vec<(f64, usize)>> = bases()
        .iter()
        .map(|b| errors(b).into_iter().map(|e| e.expect("the base scene runs")).collect())
        .collect();
    let mut failures = Vec::new();
    for c in family() {
        let Some(k) = c.base else { continue };
        for ((got, want), (name, rate, with_far)) in
            errors(&c.scene).into_iter().zip(&base_errors[k]).zip(checks.iter().copied())
        {
            if c.far && !with_far {
                continue;
            }
            let rate = rate.map_or("default".to_owned(), |r| r.to_string());
            let label = format!("{}: {name} rate {rate}", c.name);
            match got {
                Ok((e, n)) => {
                    eprintln!(
                        "{label}: mean error {e:.3e} over {n} px (base {:.3e} over {})",
                        want.0, want.1
                    );
                    if n != want.1 || (e - want.0).abs() > 1e-4 {
                        failures.push(format!(
                            "{label}: mean error {e:.3e} over {n} px, base {:.3e} over {} px",
                            want.0, want.1
                        ));
                    }
                }
                Err(e) => failures.push(format!("{label}: {e}")),
            }
        }
    }
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

/// Mean absolute error of `v` on the lit ground: the pixels `exact` evaluates and finds fully
/// lit, where any shadow is acne.
fn lit_ground_error(v: &Visibility, reference: &ReferenceImage) -> f64 {
    let errors: Vec<f64> = v
        .lit
        .iter()
        .zip(&reference.lit)
        .zip(&reference.evaluated)
        .filter(|((_, &r), &e)| e && r == 1.0)
        .map(|((&x, _), _)| 1.0 - f64::from(x))
        .collect();
    assert!(errors.len() > 200, "{} lit ground pixels", errors.len());
    errors.iter().sum::<f64>() / errors.len() as f64
}

#[test]
fn grazing_light_keeps_the_lit_ground_lit_or_warns() {
    let angles = [45.0, 80.0, 85.0, 89.0, 89.9];
    let mut failures = Vec::new();
    eprintln!("mean error on the lit ground; `*` marks a run with a bias warning");
    eprintln!(
        "{:<11} {:<12} {}",
        "method",
        "max slope",
        angles.map(|a| format!("{a:>9}")).join("")
    );
    for name in ["sm", "pcf-reeves", "pan09"] {
        // `None`: the default; `Some(10.0)`: the bound the default had before.
        for max_slope in [None, Some(10.0)] {
            let options = MethodOptions { max_slope, ..Default::default() };
            let mut row = Vec::new();
            for angle in angles {
                let scene = base(directional_at(angle));
                let frame = Frame::new(&scene, WIDTH, HEIGHT, &mut Recorder::default());
                let reference = exact(&frame).expect("exact applies");
                let (v, rec) = run_with(name, &options, &frame).expect("runs");
                row.push((angle, lit_ground_error(&v, &reference), rec.warnings));
            }
            let label = max_slope.map_or("default".to_owned(), |m| m.to_string());
            let cells: Vec<String> = row
                .iter()
                .map(|(_, e, w)| format!("{e:>8.4}{}", if w.is_empty() { " " } else { "*" }))
                .collect();
            eprintln!("{name:<11} {label:<12} {}", cells.join(""));
            let at_45 = row[0].1;
            for (angle, e, warnings) in &row {
                let acne = *e > 2.0 * at_45 + 5e-3;
                if acne && warnings.is_empty() {
                    failures.push(format!(
                        "{name} (max slope {label}) at {angle}°: lit ground error {e:.4} \
                         (at 45°: {at_45:.4}) and no warning"
                    ));
                }
                if max_slope.is_none() && [85.0, 89.0].contains(angle) && acne {
                    failures.push(format!(
                        "{name} at {angle}° with default options: lit ground error {e:.4}"
                    ));
                }
                if *angle == 45.0 && !warnings.is_empty() {
                    failures.push(format!("{name} (max slope {label}) at 45°: {warnings:?}"));
                }
                for w in warnings {
                    for needed in ["--slope-bias", "--max-slope", "°"] {
                        if !w.contains(needed) {
                            failures.push(format!("{name}: warning without `{needed}`: {w}"));
                        }
                    }
                }
            }
            if max_slope.is_some() && row[3].2.is_empty() {
                failures.push(format!("{name} with --max-slope 10 at 89°: no warning"));
            }
        }
    }
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

/// A scene file of a ground plane whose transform is `transform`, seen from a camera at
/// `eye` looking at `target`.
fn scene_file(transform: &str, eye: [f64; 3], target: [f64; 3]) -> String {
    format!(
        "resolution = [64, 48]\n[camera.perspective]\neye = {eye:?}\ntarget = {target:?}\n\
         fov_y_deg = 45.0\n[light.directional]\ndirection = [-0.3, -1.0, -0.2]\n[[object]]\n\
         shape.plane = {{ size = 10.0 }}\ntransform = {transform}\n"
    )
}

#[test]
fn scenes_beyond_the_supported_range_are_refused_naming_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let cases = [
        ("far.toml", "{ translate = [1e16, 0.0, 0.0] }", [1e16, 6.0, 8.0], [1e16, 0.0, 0.0]),
        ("huge.toml", "{ scale = [1e23, 1e23, 1e23] }", [0.0, 6e23, 8e23], [0.0, 0.0, 0.0]),
        ("tiny.toml", "{ scale = [1e-12, 1e-12, 1e-12] }", [0.0, 6e-12, 8e-12], [0.0, 0.0, 0.0]),
    ];
    let mut failures = Vec::new();
    for (file, transform, eye, target) in cases {
        let path = common::write(dir.path(), file, &scene_file(transform, eye, target));
        let o = common::shadowbench(&[
            "render",
            "--scene",
            &path,
            "--method",
            "raytrace",
            "--out",
            out.to_str().expect("utf-8"),
        ]);
        let err = common::stderr(&o);
        let names_range =
            ["1e15", "1e-9", "1000000000000000", "0.000000001"].iter().any(|r| err.contains(r));
        if o.status.code() != Some(2) || !err.contains(file) || !names_range {
            failures.push(format!("{file}: exit {:?}: {err}", o.status.code()));
        }
    }
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

#[cfg(feature = "gpu")]
#[test]
fn gpu_afsm_equals_the_cpu_on_every_scale_position_and_far_object() {
    use methods::{
        afsm::{AfsmOptions, AliasFreeShadowMap},
        gpu::{afsm as gpu_afsm, GpuContext, GpuFrame},
        ShadowMethod,
    };
    let ctx = match GpuContext::shared() {
        Ok(ctx) => ctx,
        Err(e) => {
            eprintln!("skipped: no GPU adapter ({e})");
            return;
        }
    };
    let cpu = AliasFreeShadowMap::pixel_centres(AfsmOptions::default());
    let mut failures = Vec::new();
    for c in family().into_iter().filter(|c| c.base.is_some() || c.name.starts_with("base")) {
        let frame = Frame::new(&c.scene, WIDTH, HEIGHT, &mut Recorder::default());
        let want = cpu.run(&frame, &mut Recorder::default()).expect("CPU afsm runs");
        let gpu = GpuFrame::upload(ctx, &frame, &frame.gbuffer);
        match gpu_afsm::shade(ctx, &gpu, &frame, &mut Recorder::default()) {
            Ok(out) => {
                let differing = out.lit.iter().zip(&want.lit).filter(|(g, c)| g != c).count();
                if differing > 0 {
                    failures.push(format!("{}: {differing} pixels differ", c.name));
                }
            }
            Err(e) => failures.push(format!("{}: {e}", c.name)),
        }
    }
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}
