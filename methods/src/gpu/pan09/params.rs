//! The run's constants as the kernels read them: one [`Params`], the WGSL struct `Params` of
//! `params.wgsl` field for field, bound as `params` (binding 0) by every stage that includes
//! that file. It holds the light and camera projectors ([`ProjectorData`]), the depth
//! tolerance, the shadow offset ratio (`afsm::SHADOW_OFFSET`, scaled per triangle by the
//! kernels), the light and eye models, the camera's screen basis and the light's planes seen by
//! it ([`PlaneData`]; computed on the CPU by the CPU's own code, per frame, as the projectors
//! are), the sizes, kinds and masks, and the sample pattern's offsets. The rate is at most
//! [`MAX_METHOD_RATE`], so the offsets are two fixed arrays of that many `f64` (x, y, relative
//! to the pixel's centre; zero past the rate) inside the block rather than a binding of their
//! own. Vectors are [`Xyz`] (`vec3<f64>` would be aligned to 32 bytes); masks four `u32`
//! words, lowest first.

use crate::{
    afsm::SHADOW_OFFSET,
    depth_test::DepthTester,
    frame::Frame,
    gpu::common::{ProjectorData, Xyz},
    pan09::{
        facets::LightPlanes,
        mask::Mask,
        screen::{CameraBasis, WorldPlane},
        silhouette::LightModel,
        Pan09Options, VisibilityMode,
    },
    pattern::{SamplePattern, MAX_METHOD_RATE},
};
use bytemuck::{Pod, Zeroable};
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

/// A plane seen by the camera ([`WorldPlane`]), the WGSL struct `PlaneData` of `params.wgsl`
/// field for field.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(super) struct PlaneData {
    n: Xyz,
    c: f64,
    n_ox: f64,
    n_oy: f64,
    n_dx: f64,
    n_dy: f64,
}

impl PlaneData {
    /// `p`, or the default plane (zero) where there is none.
    fn new(p: Option<&WorldPlane>) -> Self {
        let p = p.copied().unwrap_or_default();
        Self { n: p.n.into(), c: p.c, n_ox: p.n_ox, n_oy: p.n_oy, n_dx: p.n_dx, n_dy: p.n_dy }
    }
}

/// The sample pattern's offsets the block has room for (the largest rate of the methods).
const PATTERN: usize = MAX_METHOD_RATE as usize;

/// The run's constants, the WGSL struct `Params` of `params.wgsl` field for field (see the
/// module doc).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(super) struct Params {
    /// The light's projector (the depth map's).
    light: ProjectorData,
    /// The camera's projector.
    camera: ProjectorData,
    /// The depth tester's constant bias.
    constant: f64,
    /// The depth tester's slope bias.
    slope_bias: f64,
    /// The depth tester's largest slope.
    max_slope: f64,
    /// `afsm::SHADOW_OFFSET`; `visibility::occluder_offset` scales it per triangle.
    offset: f64,
    /// Infinity (WGSL has no literal for it).
    inf: f64,
    /// The light model's vector: the direction towards the light (`light_kind` 0) or its
    /// position (1).
    light_v: Xyz,
    /// The eye's, likewise (`eye_kind`).
    eye_v: Xyz,
    /// The camera's screen basis ([`CameraBasis`]).
    o0: Xyz,
    ox: Xyz,
    oy: Xyz,
    d0: Xyz,
    dx: Xyz,
    dy: Xyz,
    /// The light's planes seen by the camera ([`LightPlanes`]); `pw` and `pnear` zero where
    /// absent (`has_w`, `has_near`).
    px: PlaneData,
    py: PlaneData,
    pw: PlaneData,
    pnear: PlaneData,
    /// Depth map resolution.
    res: u32,
    /// Image width.
    width: u32,
    /// Image height.
    height: u32,
    /// Mask words per pixel ([`words`]).
    words: u32,
    /// Sub-samples per pixel.
    rate: u32,
    /// Visibility mode: 0 the lookup table, 1 exact.
    mode: u32,
    /// 1 with curved receivers.
    curved: u32,
    /// The light model's kind: 0 towards `light_v`, 1 at `light_v`.
    light_kind: u32,
    /// The eye's, likewise.
    eye_kind: u32,
    /// 1 where the camera is perspective.
    perspective: u32,
    /// 1 where `pw` is a plane.
    has_w: u32,
    /// 1 where `pnear` is a plane.
    has_near: u32,
    /// The mask of every sub-sample.
    all: [u32; 4],
    /// The mask of the centre sub-sample.
    centre: [u32; 4],
    /// The pattern's x offsets from the pixel's centre, `rate` of them, zero after.
    pattern_x: [f64; PATTERN],
    /// Their y offsets.
    pattern_y: [f64; PATTERN],
}

super::super::layout::wgsl_mirror!(
    PlaneData,
    "PlaneData",
    stage_source(),
    [n, c, n_ox, n_oy, n_dx, n_dy];
    Params,
    "Params",
    stage_source(),
    [
        light,
        camera,
        constant,
        slope_bias,
        max_slope,
        offset,
        inf,
        light_v,
        eye_v,
        o0,
        ox,
        oy,
        d0,
        dx,
        dy,
        px,
        py,
        pw,
        pnear,
        res,
        width,
        height,
        words,
        rate,
        mode,
        curved,
        light_kind,
        eye_kind,
        perspective,
        has_w,
        has_near,
        all,
        centre,
        pattern_x,
        pattern_y
    ];
);

/// A stage that reads the block, as its pipeline composes it: the depth test's.
#[cfg(test)]
fn stage_source() -> String {
    use crate::gpu::shader::{compose, Part};
    let own = Part::file("pan09/depth_test.wgsl", include_str!("depth_test.wgsl"));
    compose(&[&super::LIB, &super::PARAMS, &own])
}

impl Params {
    /// The constants of a run of `options` on `frame` with the light `light`.
    pub(super) fn new(
        frame: &Frame<'_>,
        light: &Projector,
        options: &Pan09Options,
        pattern: &SamplePattern,
    ) -> Self {
        let tester = DepthTester::new(&options.map, *light, frame.light_depth_range(light));
        let camera = CameraBasis::new(&frame.camera);
        let planes = LightPlanes::new(light, &camera);
        let (light_kind, light_v) = light_model(LightModel::of(light));
        let (eye_kind, eye_v) = light_model(LightModel::of(&frame.camera));
        let mut pattern_x = [0.0; PATTERN];
        let mut pattern_y = [0.0; PATTERN];
        for (i, o) in pattern.offsets().iter().enumerate() {
            pattern_x[i] = o.x - 0.5;
            pattern_y[i] = o.y - 0.5;
        }
        Self {
            light: ProjectorData::new(light),
            camera: ProjectorData::new(&frame.camera),
            constant: tester.constant,
            slope_bias: tester.slope_bias,
            max_slope: tester.max_slope,
            offset: SHADOW_OFFSET,
            inf: f64::INFINITY,
            light_v: light_v.into(),
            eye_v: eye_v.into(),
            o0: camera.o0.into(),
            ox: camera.ox.into(),
            oy: camera.oy.into(),
            d0: camera.d0.into(),
            dx: camera.dx.into(),
            dy: camera.dy.into(),
            px: PlaneData::new(Some(&planes.x)),
            py: PlaneData::new(Some(&planes.y)),
            pw: PlaneData::new(planes.w.as_ref()),
            pnear: PlaneData::new(planes.near.as_ref()),
            res: options.map.map_res,
            width: frame.width(),
            height: frame.height(),
            words: words(pattern.rate()),
            rate: pattern.rate(),
            mode: u32::from(options.visibility == VisibilityMode::Exact),
            curved: u32::from(frame.effects.curved_receivers),
            light_kind,
            eye_kind,
            perspective: u32::from(camera.perspective),
            has_w: u32::from(planes.w.is_some()),
            has_near: u32::from(planes.near.is_some()),
            all: to_words(<u128 as Mask>::first(pattern.rate())),
            centre: to_words(<u128 as Mask>::bit(pattern.centre_index())),
            pattern_x,
            pattern_y,
        }
    }
}
