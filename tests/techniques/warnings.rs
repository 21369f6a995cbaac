//! Shadow maps that say when their light map makes them wrong (`methods::footprint`): a far
//! object that stretches a directional light's frustum, a camera whose field of view is
//! degenerate, a spot light inside the casters, and a 1 x 1 frame each give every shadow-map
//! method a warning naming the cause and what to change; the built-in scenes at their defaults
//! give none.

use crate::common::{self, MAP_METHODS};

use analysis::registry::technique;
use glam::DVec3;
use instrumentation::Recorder;
use methods::{Frame, MethodOptions, Visibility};
use scenes::{Camera, Light, Material, Mesh, Object, Scene};

const WIDTH: u32 = 32;
const HEIGHT: u32 = 24;

fn cage() -> Scene {
    common::load_builtin("cage").expect("cage needs no model")
}

/// Runs `name` with `options` on `scene` at `w x h`.
fn run_with(
    name: &str,
    options: &MethodOptions,
    scene: &Scene,
    w: u32,
    h: u32,
) -> (Visibility, Vec<String>) {
    let frame = Frame::new(scene, w, h, &mut Recorder::default());
    let mut rec = Recorder::default();
    let v = technique(name, options).expect("valid").run(&frame, &mut rec).expect("runs");
    (v, rec.warnings)
}

/// The warnings of `name` with default options on `scene` at the tests' frame size.
fn warnings(name: &str, scene: &Scene) -> Vec<String> {
    run_with(name, &MethodOptions::default(), scene, WIDTH, HEIGHT).1
}

/// Checks that every map method warns on `scene` with a warning holding every one of
/// `needed`.
fn every_method_warns(scene: &Scene, needed: &[&str]) {
    for &name in MAP_METHODS {
        let w = warnings(name, scene);
        assert!(
            w.iter().any(|w| w.starts_with(name) && needed.iter().all(|n| w.contains(n))),
            "{name} on {}: no warning with {needed:?} in {w:#?}",
            scene.name
        );
    }
}

#[test]
fn a_far_object_names_itself_as_what_stretches_the_light_frustum() {
    for d in [1e8, 1e10] {
        let mut scene = cage();
        scene.name = format!("cage with a triangle {d:e} away");
        let p = DVec3::new(d, 3.0, d);
        let mesh = Mesh::new(vec![p, p + DVec3::X, p + DVec3::new(0.0, 0.5, 1.0)], vec![[0, 1, 2]])
            .expect("valid mesh");
        scene.objects.push(Object {
            name: "far".into(),
            mesh,
            material: Material::default(),
            casts_shadows: true,
        });
        every_method_warns(
            &scene,
            &["wider than 16 pixels", "object 'far' stretches it", "move object 'far'"],
        );
    }
}

#[test]
fn a_degenerate_field_of_view_is_named_with_a_wider_one() {
    let mut scene = cage();
    scene.name = "cage seen through 1e-12 degrees".into();
    let Camera::Perspective { fov_y_deg, .. } = &mut scene.camera else {
        panic!("cage has a perspective camera")
    };
    *fov_y_deg = 1e-12;
    every_method_warns(
        &scene,
        &["fov_y_deg 1e-12) is degenerate", "a wider camera field of view", "no --map-res"],
    );
}

#[test]
fn the_map_resolution_a_warning_names_resolves_the_frame() {
    // A narrow view of the ground in the cage: texels about 20 pixels wide, which a finer map
    // resolves; the ground holds what the frame sees, so it is not named as stretching the
    // light's frustum.
    let mut scene = cage();
    let Camera::Perspective { fov_y_deg, .. } = &mut scene.camera else {
        panic!("cage has a perspective camera")
    };
    *fov_y_deg = 0.15;
    let w = run_with("sm", &MethodOptions::default(), &scene, 64, 48).1;
    let texel = w.iter().find(|w| w.contains("wider than 16 pixels")).expect("a texel warning");
    assert!(texel.contains("coarse for this frame") && !texel.contains("'ground'"), "{texel}");
    let res: u32 = texel
        .split("--map-res ")
        .nth(1)
        .and_then(|s| s.split(|c: char| !c.is_ascii_digit()).next())
        .and_then(|s| s.parse().ok())
        .expect("a --map-res in the warning");
    assert!(res > 1024 && res <= 16384, "{res}");
    let options = MethodOptions { map_res: Some(res), ..Default::default() };
    let (_, w) = run_with("sm", &options, &scene, 64, 48);
    assert!(w.iter().all(|w| !w.contains("wider than 16 pixels")), "{w:#?}");
}

#[test]
fn a_spot_light_inside_the_cage_warns_that_it_misses_what_surrounds_it() {
    let mut scene = cage();
    scene.name = "cage lit from inside".into();
    scene.light =
        Light::Spot { position: DVec3::new(0.0, 3.0, 0.0), target: DVec3::ZERO, fov_deg: 90.0 };
    every_method_warns(
        &scene,
        &["outside the light's frustum", "counts them lit", "lies inside the scene's bounds"],
    );
    // Outside the cone but only near casters that stay inside it: the guess is right, no
    // warning (the spot's pool of light on a ground, as in `spot-spheres`).
    let mut pool = common::lone_plane(Light::Spot {
        position: DVec3::new(0.0, 6.0, 0.0),
        target: DVec3::ZERO,
        fov_deg: 40.0,
    });
    let corners = [(-0.5, -0.5), (-0.5, 0.5), (0.5, 0.5), (0.5, -0.5)];
    let tile = Mesh::new(
        corners.iter().map(|&(x, z)| DVec3::new(x, 1.0, z)).collect(),
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .expect("valid mesh");
    pool.objects.push(Object {
        name: "tile".into(),
        mesh: tile,
        material: Material::default(),
        casts_shadows: true,
    });
    let w = warnings("sm", &pool);
    assert!(w.iter().all(|w| !w.contains("outside the light's frustum")), "{w:#?}");
}

#[test]
fn a_one_pixel_frame_is_decided_by_its_centre_and_says_so() {
    let scene = cage();
    let lit = |name: &str, options: &MethodOptions| {
        let (v, w) = run_with(name, options, &scene, 1, 1);
        (v.lit[0], w)
    };
    let defaults = MethodOptions::default();
    // Both references sample the pixel's centre at rate 1: it lies in a bar's shadow.
    assert_eq!(lit("raytrace", &defaults).0, 0.0);
    // sm's nearest texel there is lit: the centre lies within a texel of the bar's shadow
    // edge, which a finer map resolves.
    let (sm, w) = lit("sm", &defaults);
    assert_eq!(sm, 1.0);
    assert_eq!(lit("sm", &MethodOptions { map_res: Some(2048), ..defaults.clone() }).0, 0.0);
    // The pixel's own lit fraction is neither.
    let rate = MethodOptions { rate: Some(256), ..defaults.clone() };
    let area = lit("raytrace", &rate).0;
    assert!(area > 0.8 && area < 0.95, "{area}");
    assert!(
        w.iter()
            .any(|w| w.contains("wider than 64 texels") && w.contains("one point at its centre")),
        "{w:#?}"
    );
    // Methods that sample the pixel's area do not claim to decide it by its centre.
    for name in ["pcf-reeves", "pan09"] {
        let w = lit(name, &defaults).1;
        assert!(w.iter().all(|w| !w.contains("wider than 64 texels")), "{name}: {w:#?}");
    }
}

#[test]
fn built_in_scenes_at_their_defaults_do_not_warn() {
    for &(name, _) in scenes::BUILTINS {
        // The largest scenes cost more than this test should; their kind is covered by the
        // smaller random and sphere scenes.
        if ["random-100k", "random-1m", "bumpy"].contains(&name) {
            continue;
        }
        let Some(scene) = common::load_builtin(name) else { continue };
        for &m in MAP_METHODS {
            let w = warnings(m, &scene);
            assert!(w.is_empty(), "{m} on {name}: {w:#?}");
        }
    }
}
