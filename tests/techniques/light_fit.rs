//! The light-frustum policies (`--frustum`, `methods::light_fit`) through the methods: `scene`
//! is what every map method did before, a view-fitted `sm` keeps every shadow of the scene fit
//! on what the camera sees and comes closer to the exact reference, every method that declares
//! the policy runs under each and records it, and a spot light's map is the same under all.

use analysis::{exact::ExactCoverage, Metrics, Reference};
use glam::{DVec2, DVec3};
use instrumentation::Recorder;
use methods::{method, params, Frame, LightFit, MethodOptions, Visibility, METHODS};
use scenes::{
    projection::{ProjectionKind, Projector},
    Camera, Scene,
};

fn run(name: &str, frame: &Frame<'_>, options: &MethodOptions) -> Visibility {
    method(name, options).expect("valid").run(frame, &mut Recorder::default()).expect("runs")
}

fn with(map_res: u32, fit: LightFit) -> MethodOptions {
    MethodOptions { map_res: Some(map_res), frustum: Some(fit), ..Default::default() }
}

/// `plane-square` seen from close, low over the square's shadow on the ground: the view holds
/// a small part of the ground alone, and the square casting the shadow lies above it.
fn close_plane_square() -> Scene {
    let mut scene = scenes::load("plane-square").expect("built-in");
    scene.camera = Camera::Perspective {
        eye: DVec3::new(-0.6, 1.2, 2.2),
        target: DVec3::new(-0.6, 0.0, -0.4),
        up: DVec3::Y,
        fov_y_deg: 35.0,
        near: 0.01,
    };
    scene
}

/// Whether the point `(u, v)` (light-space coordinates along the light's right and up axes)
/// lies inside the light-space projection of one of the triangles of `object` in `scene`.
fn under(scene: &Scene, object: usize, light: &Projector, u: f64, v: f64) -> bool {
    let mesh = &scene.objects[object].mesh;
    let at = |i: u32| {
        let p = mesh.positions[i as usize];
        (p.dot(light.right), p.dot(light.up))
    };
    mesh.triangles.iter().any(|t| {
        let [a, b, c] = t.map(at);
        let side = |(x0, y0): (f64, f64), (x1, y1): (f64, f64)| {
            (x1 - x0) * (v - y0) - (y1 - y0) * (u - x0)
        };
        let (s0, s1, s2) = (side(a, b), side(b, c), side(c, a));
        (s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0) || (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0)
    })
}

/// The pixels whose surface point lies on the ground in the square's shadow at least half a
/// `texel` (world units per axis) from its edge: every texel centre a nearest lookup can read
/// for them holds the square, whatever the map's grid.
fn deep_in_shadow(frame: &Frame<'_>, light: &Projector, texel: DVec2) -> Vec<usize> {
    let scene = frame.scene;
    let (square, ground) = (1, 0);
    let g = &frame.gbuffer;
    (0..g.triangle.len())
        .filter(|&k| {
            g.covered(k) && frame.geometry.object[g.triangle[k] as usize] as usize == ground && {
                let p = g.position[k];
                let (u, v) = (p.dot(light.right), p.dot(light.up));
                [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)].iter().all(|(su, sv)| {
                    under(scene, square, light, u + su * 0.5 * texel.x, v + sv * 0.5 * texel.y)
                })
            }
        })
        .collect()
}

/// World size of a texel of an orthographic `light`, per axis.
fn texel_size(light: &Projector) -> DVec2 {
    match light.kind {
        ProjectionKind::Orthographic { half_width, half_height } => {
            DVec2::new(2.0 * half_width / light.width, 2.0 * half_height / light.height)
        }
        ProjectionKind::Perspective { .. } => DVec2::NAN,
    }
}

/// On a view that sees part of the ground, `sm` through either view fit shadows every ground
/// pixel that lies in the square's shadow by more than half a texel of the scene fit (whose
/// texels are the larger) from its edge, as the scene fit's `sm` does: the square, above the
/// view, is in the map. And its mean error against `exact` is at most the scene fit's at the
/// same map resolution: its texels are smaller on what the camera sees.
#[test]
fn view_fits_keep_the_shadows_and_do_not_raise_the_error() {
    let scene = close_plane_square();
    assert_eq!(scene.objects[1].name, "square");
    let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
    let g = &frame.gbuffer;
    let object = |k: usize| frame.geometry.object[g.triangle[k] as usize];
    assert!((0..g.triangle.len()).all(|k| !g.covered(k) || object(k) == 0), "ground only");
    let exact =
        ExactCoverage::default().evaluate(&frame, &mut Recorder::default()).expect("planar");
    for map_res in [64, 256, 1024] {
        let light = frame.light_projector(map_res, LightFit::Scene);
        let deep = deep_in_shadow(&frame, &light, texel_size(&light));
        assert!(deep.len() > 500, "the view holds a shadow: {} pixels", deep.len());
        let scene_fit = run("sm", &frame, &with(map_res, LightFit::Scene));
        assert!(deep.iter().all(|&k| scene_fit.lit[k] == 0.0), "map {map_res}");
        let error = |v: &Visibility| Metrics::compare(v, &exact.lit, &exact.evaluated);
        let reference = error(&scene_fit);
        for fit in [LightFit::View, LightFit::ViewSnapped] {
            let view = frame.light_projector(map_res, fit);
            let (a, b) = (texel_size(&view), texel_size(&light));
            assert!(a.cmple(b).all(), "map {map_res} {}: texels {a} vs {b}", fit.as_str());
            let v = run("sm", &frame, &with(map_res, fit));
            let lost = deep.iter().filter(|&&k| v.lit[k] != 0.0).count();
            let m = error(&v);
            eprintln!(
                "map {map_res} {}: {} pixels deep in shadow, {lost} lost; mean error {:.5} \
                 (scene {:.5}), boundary {:.4} (scene {:.4})",
                fit.as_str(),
                deep.len(),
                m.mean_abs_error,
                reference.mean_abs_error,
                m.boundary_mean_abs_error,
                reference.boundary_mean_abs_error
            );
            assert_eq!(lost, 0, "map {map_res} {}", fit.as_str());
            assert!(
                m.mean_abs_error <= reference.mean_abs_error,
                "map {map_res} {}: {} > {}",
                fit.as_str(),
                m.mean_abs_error,
                reference.mean_abs_error
            );
        }
    }
}

/// Every method that declares `--frustum` runs under each policy, records it, and gives the
/// default's result, bit for bit, when `scene` is given; the light depth range (the unit of
/// the constant bias) is the scene fit's under every policy.
#[test]
fn every_map_method_runs_and_records_each_policy() {
    let scene = scenes::load("cage").expect("built-in");
    let frame = Frame::new(&scene, 64, 48, &mut Recorder::default());
    let declaring: Vec<&str> = METHODS
        .iter()
        .filter(|m| m.params.iter().any(|p| std::ptr::eq(*p, &params::FRUSTUM)))
        .map(|m| m.name)
        .collect();
    for name in [
        "sm",
        "pcf-reeves",
        "pcf-bs-2x2",
        "pcf-gems16",
        "spsm",
        "spsm-f32",
        "pan09",
        "vsm",
        "esm",
        "msm",
    ] {
        assert!(declaring.contains(&name), "{name} does not declare --frustum");
    }
    assert!(!declaring.contains(&"afsm") && !declaring.contains(&"afsm-ss"));
    for name in declaring {
        let default = MethodOptions { map_res: Some(256), ..Default::default() };
        let before = run(name, &frame, &default);
        for fit in LightFit::ALL {
            let options = with(256, fit);
            let m = method(name, &options).expect("valid");
            assert_eq!(m.params()["frustum"], fit.as_str(), "{name}");
            let v = run(name, &frame, &options);
            assert!(v.lit.iter().all(|l| (0.0..=1.0).contains(l)), "{name} {}", fit.as_str());
            if fit == LightFit::Scene {
                assert_eq!(v, before, "{name}: scene is the default");
            }
        }
    }
    let range = |fit| frame.light_depth_range(&frame.light_projector(256, fit));
    for fit in LightFit::ALL {
        let (got, want) = (range(fit), range(LightFit::Scene));
        assert!((got - want).abs() <= 1e-12 * want, "{}: {got} vs {want}", fit.as_str());
    }
}

/// A spot light's map is its cone under every policy: the same result.
#[test]
fn a_spot_lights_map_is_the_same_under_every_policy() {
    let scene = scenes::load("spot-spheres").expect("built-in");
    let frame = Frame::new(&scene, 64, 48, &mut Recorder::default());
    for name in ["sm", "pcf-gems4"] {
        let want = run(name, &frame, &with(256, LightFit::Scene));
        for fit in [LightFit::View, LightFit::ViewSnapped] {
            assert_eq!(run(name, &frame, &with(256, fit)), want, "{name} {}", fit.as_str());
        }
    }
}
