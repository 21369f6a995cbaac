//! The run's constants as the kernels read them (`params.wgsl`): `P` (`f64`) holds the light
//! and camera projectors, the depth tolerance, the shadow offset ratio (`afsm::SHADOW_OFFSET`,
//! scaled per triangle by the kernels), the light and eye models,
//! the camera's screen basis and the light's planes seen by it (computed on the CPU by the
//! CPU's own code, per frame, as the projectors are), then the pattern's offsets; `U` (`u32`)
//! the sizes, kinds and masks.

use crate::{
    afsm::SHADOW_OFFSET,
    depth_test::DepthTester,
    frame::Frame,
    gpu::frame::ProjectorData,
    pan09::{
        facets::LightPlanes,
        mask::Mask,
        screen::{CameraBasis, WorldPlane},
        silhouette::LightModel,
        Pan09Options, VisibilityMode,
    },
    pattern::SamplePattern,
};
use glam::DVec3;
use scenes::Projector;

/// Counter slots of the kernels' counters buffer (`pan09.wgsl`).
pub(super) mod slot {
    /// Silhouette edges found.
    pub const EDGES: usize = 0;
    /// Marked texels of the mask map.
    pub const SILHOUETTE_TEXELS: usize = 1;
    /// Silhouette facets.
    pub const SILHOUETTE_PIXELS: usize = 2;
    /// Depth tests.
    pub const LOOKUPS: usize = 3;
    /// PT-pairs kept.
    pub const PT_PAIRS: usize = 4;
    /// TT-pairs kept.
    pub const TT_PAIRS: usize = 5;
    /// Triangle-pixel evaluations.
    pub const EVALUATIONS: usize = 6;
    /// Validity candidates noted.
    pub const CANDIDATES: usize = 7;
    /// Valid sub-samples of boundary pixels.
    pub const VALID_SAMPLES: usize = 8;
    /// Boundary pixels.
    pub const BOUNDARY: usize = 9;
    /// The TT-pairs' PT-list lengths summed (a bound on the evaluations).
    pub const EVALUATION_BOUND: usize = 10;
    /// Slots in all.
    pub const COUNT: usize = 11;
}

/// Mask words per pixel at `rate` sub-samples (32 per word, 1, 2 or 4).
pub(super) fn words(rate: u32) -> u32 {
    rate.div_ceil(32).next_power_of_two()
}

/// `m` as four `u32` words, lowest first.
pub(super) fn to_words(m: u128) -> [u32; 4] {
    [m as u32, (m >> 32) as u32, (m >> 64) as u32, (m >> 96) as u32]
}

fn light_model(l: LightModel) -> (u32, DVec3) {
    match l {
        LightModel::Towards(w) => (0, w),
        LightModel::At(p) => (1, p),
    }
}

/// The projector of `p` as `load_proj` in `params.wgsl` reads it: 18 `f64`, the kind as 0 or 1.
fn projector(out: &mut Vec<f64>, p: &Projector) {
    let d = ProjectorData::new(p);
    for v in [d.origin, d.right, d.up, d.forward] {
        out.extend_from_slice(&[v.x, v.y, v.z]);
    }
    out.extend_from_slice(&[f64::from(d.kind), d.a, d.b, d.near, d.width, d.height]);
}

fn plane(out: &mut Vec<f64>, p: Option<&WorldPlane>) {
    let p = p.copied().unwrap_or_default();
    out.extend_from_slice(&[p.n.x, p.n.y, p.n.z, p.c, p.n_ox, p.n_oy, p.n_dx, p.n_dy]);
}

/// `P` and `U` for a run of `options` on `frame` with the light `light`.
pub(super) fn params(
    frame: &Frame<'_>,
    light: &Projector,
    options: &Pan09Options,
    pattern: &SamplePattern,
) -> (Vec<f64>, Vec<u32>) {
    let tester = DepthTester::new(&options.map, *light, frame.light_depth_range(light));
    let camera = CameraBasis::new(&frame.camera);
    let planes = LightPlanes::new(light, &camera);
    let (light_kind, light_v) = light_model(LightModel::of(light));
    let (eye_kind, eye_v) = light_model(LightModel::of(&frame.camera));
    let mut p = Vec::with_capacity(97 + 2 * pattern.rate() as usize);
    projector(&mut p, light);
    projector(&mut p, &frame.camera);
    p.extend_from_slice(&[
        tester.constant,
        tester.slope_bias,
        tester.max_slope,
        SHADOW_OFFSET,
        f64::INFINITY,
    ]);
    p.extend_from_slice(&light_v.to_array());
    p.extend_from_slice(&eye_v.to_array());
    for v in [camera.o0, camera.ox, camera.oy, camera.d0, camera.dx, camera.dy] {
        p.extend_from_slice(&v.to_array());
    }
    plane(&mut p, Some(&planes.x));
    plane(&mut p, Some(&planes.y));
    plane(&mut p, planes.w.as_ref());
    plane(&mut p, planes.near.as_ref());
    debug_assert_eq!(p.len(), 97);
    p.extend(pattern.offsets().iter().map(|o| o.x - 0.5));
    p.extend(pattern.offsets().iter().map(|o| o.y - 0.5));

    let all = to_words(<u128 as Mask>::first(pattern.rate()));
    let centre = to_words(<u128 as Mask>::bit(pattern.centre_index()));
    let mut u = vec![
        options.map.map_res,
        frame.width(),
        frame.height(),
        words(pattern.rate()),
        pattern.rate(),
        u32::from(options.visibility == VisibilityMode::Exact),
        u32::from(frame.effects.curved_receivers),
        light_kind,
        eye_kind,
        u32::from(camera.perspective),
        u32::from(planes.w.is_some()),
        u32::from(planes.near.is_some()),
    ];
    u.extend_from_slice(&all);
    u.extend_from_slice(&centre);
    (p, u)
}
