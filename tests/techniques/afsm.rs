//! Alias-free shadow maps (`afsm`, `afsm-ss`) against the ray-traced reference at the same
//! sample points, semi-transparent casters, the two culling tests, determinism and options.

use crate::common::load_builtin;
use analysis::{
    raytrace::{RayTrace, SampleImage},
    Reference, ReferenceImage,
};
use glam::{DVec2, DVec3};
use instrumentation::Recorder;
use methods::{
    afsm::{self, AfsmOptions, AliasFreeShadowMap},
    method, MethodError, MethodOptions, ShadowMethod, Visibility,
};
use methods::{
    pattern::{PatternKind, SamplePattern},
    raster::NO_TRIANGLE,
    Frame, LightFit,
};
use robust::{orient2d, Coord};
use scenes::registry::BUILTINS;

fn run(m: &AliasFreeShadowMap, frame: &Frame<'_>) -> (Visibility, Recorder) {
    let mut rec = Recorder::default();
    let v = m.run(frame, &mut rec).expect("afsm runs");
    assert_eq!(v.lit.len(), frame.gbuffer.triangle.len());
    assert!(v.lit.iter().all(|l| l.is_finite() && (0.0..=1.0).contains(l)));
    (v, rec)
}

fn raytrace(frame: &Frame<'_>, rate: u32, kind: PatternKind) -> ReferenceImage {
    let pattern = SamplePattern::new(rate, kind).expect("valid rate");
    RayTrace { pattern }.evaluate(frame, &mut Recorder::default()).expect("raytrace applies")
}

fn xy(p: DVec2) -> Coord<f64> {
    Coord { x: p.x, y: p.y }
}

/// Whether the surface point of pixel `k` (rate 1) projects exactly onto an edge that two
/// caster triangles share, inside the closed projection of one of them: the only place
/// where `afsm` and `raytrace` may break a tie differently.
fn on_shared_caster_edge(frame: &Frame<'_>, k: usize) -> bool {
    let light = frame.light_projector(afsm::LIGHT_IMAGE_RES, LightFit::Scene);
    let own = frame.gbuffer.triangle[k];
    let Some((p, _)) = light.project(frame.gbuffer.position[k]) else { return false };
    let g = &frame.geometry;
    let key = |a: DVec3, b: DVec3| {
        let (a, b) = (a.to_array().map(f64::to_bits), b.to_array().map(f64::to_bits));
        if a < b {
            (a, b)
        } else {
            (b, a)
        }
    };
    let mut edges = std::collections::HashMap::new();
    for t in (0..g.len()).filter(|&t| frame.is_caster(t)) {
        let c = g.corners(t);
        for e in 0..3 {
            *edges.entry(key(c[e], c[(e + 1) % 3])).or_insert(0u32) += 1;
        }
    }
    (0..g.len()).filter(|&t| frame.is_caster(t) && t as u32 != own).any(|t| {
        let c = g.corners(t);
        let q = c.map(|v| light.project_unclipped(v).0);
        let area = orient2d(xy(q[0]), xy(q[1]), xy(q[2]));
        let side: Vec<f64> =
            (0..3).map(|e| orient2d(xy(q[e]), xy(q[(e + 1) % 3]), xy(p)) * area.signum()).collect();
        side.iter().all(|&s| s >= 0.0)
            && (0..3).any(|e| side[e] == 0.0 && edges[&key(c[e], c[(e + 1) % 3])] >= 2)
    })
}

/// How many sub-samples of pixel `k` (whose hits `image` holds) lie on the edge of a caster
/// triangle's projection in the light image to within `f64` rounding (an edge through the
/// sample): where `afsm-ss`, deciding in the light image, and `raytrace`, deciding along the
/// ray, may break the tie differently.
fn subsamples_on_caster_edges(
    frame: &Frame<'_>,
    pattern: &SamplePattern,
    image: &SampleImage,
    k: usize,
) -> usize {
    let light = afsm::light_projector(frame);
    let (i, j) = ((k % image.width as usize) as u32, (k / image.width as usize) as u32);
    let g = &frame.geometry;
    (0..image.rate as usize)
        .filter(|&s| {
            let own = image.triangle[k * image.rate as usize + s];
            if own == NO_TRIANGLE {
                return false;
            }
            let r = frame.camera.ray(pattern.point(i, j, s));
            let c = g.corners(own as usize);
            let n = (c[1] - c[0]).cross(c[2] - c[0]);
            let p = r.origin + n.dot(c[0] - r.origin) / n.dot(r.direction) * r.direction;
            let q = light.project_unclipped(p).0;
            (0..g.len()).filter(|&t| frame.is_caster(t) && t as u32 != own).any(|t| {
                let v = g.corners(t).map(|v| light.project_unclipped(v).0);
                (0..3).any(|e| {
                    let (a, b) = (v[e], v[(e + 1) % 3]);
                    let len = (b - a).length();
                    let along = (q - a).dot(b - a) / (len * len);
                    let off = orient2d(xy(a), xy(b), xy(q)).abs() / len;
                    (0.0..=1.0).contains(&along) && off <= 1e-9 * (len + q.abs().max_element())
                })
            })
        })
        .count()
}

/// Pixels where the two results differ.
fn differing(v: &Visibility, r: &ReferenceImage) -> Vec<usize> {
    (0..v.lit.len()).filter(|&k| f64::from(v.lit[k]) != r.lit[k]).collect()
}

#[test]
fn afsm_equals_raytrace_at_pixel_centres_on_every_opaque_builtin() {
    let m = AliasFreeShadowMap::pixel_centres(AfsmOptions::default());
    let mut compared = 0;
    for (name, _) in BUILTINS {
        let Some(scene) = load_builtin(name) else { continue };
        if scene.effects().transparency {
            eprintln!("{name}: has transparency, compared by the transmittance test");
            continue;
        }
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        let (v, _) = run(&m, &frame);
        let r = raytrace(&frame, 1, PatternKind::Grid);
        let diff = differing(&v, &r);
        let shadowed = v.lit.iter().filter(|&&l| l == 0.0).count();
        eprintln!(
            "{name}: {} differing pixels, {shadowed} shadowed of {}",
            diff.len(),
            v.lit.len()
        );
        assert!(shadowed > 0, "{name}: no shadow at all");
        for &k in &diff {
            assert!(
                on_shared_caster_edge(&frame, k),
                "{name}: pixel ({}, {}) differs: afsm {} raytrace {}",
                k % 160,
                k / 160,
                v.lit[k],
                r.lit[k]
            );
        }
        compared += 1;
    }
    assert!(compared >= 10, "{compared} scenes compared");
}

#[test]
fn afsm_ss_equals_raytrace_at_rate_32_on_cage_and_plant() {
    for name in ["cage", "plant"] {
        let scene = scenes::load(name).expect("built-in");
        let frame = Frame::new(&scene, 64, 48, &mut Recorder::default());
        for kind in [PatternKind::Grid, PatternKind::Rotated] {
            let m = AliasFreeShadowMap::supersampled(AfsmOptions {
                pattern: kind,
                ..AfsmOptions::supersampled()
            });
            let (v, rec) = run(&m, &frame);
            let r = raytrace(&frame, 32, kind);
            let diff = differing(&v, &r);
            let partial = v.lit.iter().filter(|&&l| l > 0.0 && l < 1.0).count();
            eprintln!("{name} {kind}: {} differing pixels, {partial} partly lit", diff.len());
            // Only sub-samples on a caster's edge (to within rounding) may differ.
            assert!(diff.len() <= 2, "{name} {kind}: pixels {diff:?} differ");
            if !diff.is_empty() {
                let pattern = SamplePattern::new(32, kind).expect("valid rate");
                let image = RayTrace { pattern: pattern.clone() }
                    .sample_image(&frame, &mut Recorder::default())
                    .expect("raytrace applies");
                for &k in &diff {
                    let gap = ((f64::from(v.lit[k]) - r.lit[k]).abs() * 32.0).round() as usize;
                    let ties = subsamples_on_caster_edges(&frame, &pattern, &image, k);
                    assert!(
                        gap <= ties,
                        "{name}: pixel {k}: {gap} sub-samples differ, {ties} ties"
                    );
                }
            }
            assert!(partial > 20, "{name} {kind}: {partial} partly lit pixels");
            let gbuffers = rec
                .stages
                .stages
                .iter()
                .filter(|s| s.name.starts_with("camera G-buffer ("))
                .count();
            assert_eq!(gbuffers, 31, "one G-buffer stage per non-centre sub-sample");
        }
    }
}

#[test]
fn afsm_transmittance_matches_raytrace_on_hairball() {
    let scene = scenes::load("hairball").expect("built-in");
    assert!(scene.effects().transparency);
    let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
    let (v, _) = run(&AliasFreeShadowMap::pixel_centres(AfsmOptions::default()), &frame);
    let r = raytrace(&frame, 1, PatternKind::Grid);
    let (mine, theirs) = (
        v.transmittance.as_ref().expect("afsm carries transmittance"),
        r.transmittance.as_ref().expect("raytrace carries transmittance"),
    );
    let mut worst = 0.0f64;
    for (a, b) in mine.iter().zip(theirs) {
        for c in 0..3 {
            assert!((0.0..=1.0).contains(&a[c]));
            worst = worst.max((f64::from(a[c]) - b[c]).abs());
        }
    }
    let attenuated = mine.iter().filter(|t| t[0] > 0.0 && t[0] < 0.95).count();
    eprintln!("hairball: max channel difference {worst:.2e}, {attenuated} attenuated pixels");
    assert!(worst <= 1e-5, "{worst}");
    assert!(attenuated > 100, "{attenuated}");
    for (l, t) in v.lit.iter().zip(mine) {
        assert!((f64::from(*l) - f64::from(t[0])).abs() <= 1e-6);
    }
}

/// Runs `afsm` with `options` and with `off` applied to them; the pixels must be equal.
fn with_and_without(
    frame: &Frame<'_>,
    mut options: AfsmOptions,
    off: impl Fn(&mut AfsmOptions),
) -> (instrumentation::Counters, instrumentation::Counters) {
    let (on, rec_on) = run(&AliasFreeShadowMap::pixel_centres(options), frame);
    off(&mut options);
    let (without, rec_off) = run(&AliasFreeShadowMap::pixel_centres(options), frame);
    assert_eq!(on, without, "culling changed a pixel");
    (rec_on.counters, rec_off.counters)
}

/// The paper's algorithm: every caster rasterized (the options' defaults, without facing
/// culling, which is not the paper's), so that the paper's two cullings are measured alone.
fn paper() -> AfsmOptions {
    AfsmOptions { facing_culling: false, ..AfsmOptions::default() }
}

#[test]
fn occlusion_culling_skips_work_without_changing_a_pixel() {
    for name in ["grazing", "spot-spheres"] {
        let scene = scenes::load(name).expect("built-in");
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        let (on, off) = with_and_without(&frame, paper(), |o| o.occlusion_culling = false);
        eprintln!(
            "{name}: occlusion culled {}, points tested {} vs {}, nodes visited {} vs {}",
            on.nodes_occlusion_culled,
            on.sampling_points_tested,
            off.sampling_points_tested,
            on.bsp_nodes_visited,
            off.bsp_nodes_visited
        );
        assert!(on.nodes_occlusion_culled > 0, "{name}");
        assert_eq!(off.nodes_occlusion_culled, 0, "{name}");
        assert!(on.sampling_points_tested < off.sampling_points_tested, "{name}");
        // Culled leaves save point tests; culled inner nodes also save visits below them.
        assert!(on.bsp_nodes_visited <= off.bsp_nodes_visited, "{name}");
    }
}

#[test]
fn depth_culling_skips_work_without_changing_a_pixel() {
    for name in ["spheres", "city", "spot-spheres"] {
        let scene = scenes::load(name).expect("built-in");
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        let (on, off) = with_and_without(&frame, paper(), |o| o.depth_culling = false);
        eprintln!(
            "{name}: depth culled {}, points tested {} vs {}, nodes visited {} vs {}",
            on.nodes_depth_culled,
            on.sampling_points_tested,
            off.sampling_points_tested,
            on.bsp_nodes_visited,
            off.bsp_nodes_visited
        );
        assert!(on.nodes_depth_culled > 0, "{name}");
        assert_eq!(off.nodes_depth_culled, 0, "{name}");
        assert!(on.sampling_points_tested < off.sampling_points_tested, "{name}");
        assert!(on.bsp_nodes_visited < off.bsp_nodes_visited, "{name}");
    }
}

/// Of a closed caster seen from outside only the triangles facing the light are rasterized:
/// the same pixels, fewer nodes visited, and the run says so.
#[test]
fn facing_culling_skips_work_without_changing_a_pixel() {
    for name in ["bunny-plane", "cage", "spheres", "spot-spheres", "city"] {
        let Some(scene) = load_builtin(name) else { continue };
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        let (on, off) = with_and_without(&frame, AfsmOptions::default(), |o| {
            o.facing_culling = false;
        });
        eprintln!(
            "{name}: nodes visited {} vs {}, points tested {} vs {}",
            on.bsp_nodes_visited,
            off.bsp_nodes_visited,
            on.sampling_points_tested,
            off.sampling_points_tested
        );
        assert!(on.bsp_nodes_visited < off.bsp_nodes_visited, "{name}");
        let (_, rec) = run(&AliasFreeShadowMap::pixel_centres(AfsmOptions::default()), &frame);
        assert!(rec.notes.iter().any(|n| n.contains("facing the light")), "{name}");
    }
}

/// Whether facing culling left every triangle in: the counters equal those of a run without
/// it, and the pixels too. Asked at one sub-sample per pixel (the check reads the G-buffer)
/// and at four (it reads the samples), which must agree.
fn keeps_every_triangle(scene: &scenes::Scene) -> bool {
    let frame = Frame::new(scene, 120, 90, &mut Recorder::default());
    let (on, off) = with_and_without(&frame, AfsmOptions::default(), |o| {
        o.facing_culling = false;
    });
    let four = |facing_culling| {
        let options = AfsmOptions { rate: 4, facing_culling, ..AfsmOptions::supersampled() };
        run(&AliasFreeShadowMap::supersampled(options), &frame)
    };
    let ((lit_on, rec_on), (lit_off, rec_off)) = (four(true), four(false));
    assert_eq!(lit_on, lit_off, "culling changed a pixel at 4 sub-samples");
    assert_eq!(on == off, rec_on.counters == rec_off.counters, "1 and 4 sub-samples disagree");
    on == off
}

/// A closed mesh seen from the back of its triangles (wound inward) keeps every triangle:
/// were only those facing the light by their winding kept, the spheres' sides toward the
/// light would lose their shadows.
#[test]
fn a_closed_mesh_wound_inward_keeps_every_triangle() {
    let mut scene = scenes::load("spheres").expect("built-in");
    assert!(!keeps_every_triangle(&scene), "the spheres wound outward are culled");
    for o in &mut scene.objects {
        for t in &mut o.mesh.triangles {
            t.swap(1, 2);
        }
    }
    assert!(keeps_every_triangle(&scene));
}

/// A camera inside a closed room wound inward sees its walls from the front, but from inside:
/// every triangle is kept (the floor is in the shadow of the ceiling, which faces away from
/// the light by its winding and would be left out).
#[test]
fn a_camera_inside_a_closed_room_keeps_every_triangle() {
    let mut scene = scenes::load("plane-square").expect("built-in");
    let corners: Vec<DVec3> = (0..8)
        .map(|k| DVec3::new((k & 1) as f64, (k >> 1 & 1) as f64, (k >> 2) as f64) * 8.0 - 4.0)
        .collect();
    // Faces of the cube wound inward (their normals into the room).
    let faces: [[u32; 4]; 6] =
        [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
    let triangles = faces.iter().flat_map(|f| [[f[0], f[1], f[2]], [f[0], f[2], f[3]]]).collect();
    let room = scenes::Mesh { positions: corners, triangles };
    let mut object = scene.objects[0].clone();
    object.mesh = room;
    scene.objects = vec![object];
    scene.camera = scenes::Camera::Perspective {
        eye: DVec3::new(0.5, 1.0, 3.0),
        target: DVec3::new(0.0, -2.0, 0.0),
        up: DVec3::Y,
        fov_y_deg: 60.0,
        near: 0.01,
    };
    let frame = Frame::new(&scene, 120, 90, &mut Recorder::default());
    let (v, _) = run(&AliasFreeShadowMap::pixel_centres(AfsmOptions::default()), &frame);
    let seen = frame.gbuffer.triangle.iter().filter(|&&t| t != NO_TRIANGLE).count();
    assert!(seen > 1000, "the room is seen");
    let dark = v.lit.iter().filter(|&&l| l == 0.0).count();
    assert!(dark > 1000, "the floor is in the room's shadow: {dark} dark pixels");
    assert!(keeps_every_triangle(&scene));
}

#[test]
fn results_and_counters_do_not_depend_on_the_thread_count() {
    for name in ["random-10k", "hairball"] {
        let scene = scenes::load(name).expect("built-in");
        let frame = Frame::new(&scene, 160, 120, &mut Recorder::default());
        let m = AliasFreeShadowMap::supersampled(AfsmOptions { rate: 4, ..Default::default() });
        let (many, rec_many) = run(&m, &frame);
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a pool");
        let (single, rec_single) = one.install(|| run(&m, &frame));
        assert_eq!(many, single, "{name}");
        assert_eq!(rec_many.counters, rec_single.counters, "{name}");
    }
}

#[test]
fn stages_and_counters_are_recorded() {
    let scene = scenes::load("plane-square").expect("built-in");
    let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
    let (_, rec) = run(&AliasFreeShadowMap::pixel_centres(AfsmOptions::default()), &frame);
    let names: Vec<&str> = rec.stages.stages.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, [afsm::STAGE_TRANSFORMATION, afsm::STAGE_BSP, afsm::STAGE_RASTERIZATION]);
    assert_eq!(
        [afsm::STAGE_TRANSFORMATION, afsm::STAGE_BSP, afsm::STAGE_RASTERIZATION],
        ["transformation of samples", "BSP construction", "rasterization of blockers"]
    );
    let c = rec.counters;
    let visible = frame.gbuffer.triangle.iter().filter(|&&t| t != NO_TRIANGLE).count() as u64;
    fn leaves(n: u64) -> u64 {
        if n < 64 {
            1
        } else {
            leaves(n / 2) + leaves(n - n / 2)
        }
    }
    assert!(visible > 64 * 32);
    assert_eq!(c.bsp_nodes, 2 * leaves(visible) - 1);
    assert!(c.bsp_nodes_visited > 0 && c.sampling_points_tested >= visible);
    assert_eq!(c.shadow_map_lookups + c.rays_traced, 0);
}

#[test]
fn afsm_ss_at_rate_1_is_afsm() {
    let scene = scenes::load("spot-spheres").expect("built-in");
    let frame = Frame::new(&scene, 96, 72, &mut Recorder::default());
    let (a, _) = run(&AliasFreeShadowMap::pixel_centres(AfsmOptions::default()), &frame);
    let (b, rec) = run(
        &AliasFreeShadowMap::supersampled(AfsmOptions { rate: 1, ..AfsmOptions::default() }),
        &frame,
    );
    assert_eq!(a, b);
    assert_eq!(rec.stages.stages.len(), 3, "no extra G-buffer at rate 1");
}

#[test]
fn registry_builds_both_and_rejects_bad_options() {
    for name in ["afsm", "afsm-ss"] {
        assert!(methods::METHODS.iter().any(|m| m.name == name));
        assert_eq!(method(name, &MethodOptions::default()).expect("valid").name(), name);
    }
    let ss = method("afsm-ss", &MethodOptions::default()).expect("valid");
    assert_eq!(ss.params()["rate"], 32);
    assert_eq!(ss.params()["pattern"], "grid");
    let bad_rate =
        |name, rate| method(name, &MethodOptions { rate: Some(rate), ..Default::default() }).err();
    for rate in [0, 3, 256, 1024] {
        assert!(matches!(
            bad_rate("afsm-ss", rate),
            Some(MethodError::InvalidOption { option: "--rate", .. })
        ));
    }
    for leaf_size in [0, 1] {
        let m = AliasFreeShadowMap::pixel_centres(AfsmOptions { leaf_size, ..Default::default() });
        assert!(matches!(
            m.validate(),
            Err(MethodError::InvalidOption { option: "--leaf-size", .. })
        ));
    }
    let m = AliasFreeShadowMap::pixel_centres(AfsmOptions { rate: 4, ..Default::default() });
    assert!(matches!(m.validate(), Err(MethodError::InvalidOption { option: "--rate", .. })));
}
