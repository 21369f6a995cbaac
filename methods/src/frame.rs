//! A frame: a scene prepared at one resolution, with its camera G-buffer. Methods read the
//! frame; the light depth map is rendered only when a method asks for it.

use crate::{
    depth_map::LightDepthMap,
    gbuffer::{render_gbuffer, GBuffer},
    light_fit::{self, LightFit},
};
use glam::DVec2;
use instrumentation::Recorder;
use scenes::{Effects, Geometry, Projector, Scene};

/// Name of the stage that renders the camera G-buffer.
pub const STAGE_GBUFFER: &str = "camera G-buffer";
/// Name of the stage that renders the light depth map.
pub const STAGE_LIGHT_DEPTH_MAP: &str = "light depth map";
/// Name of the stage in which a GPU run renders its own camera G-buffer.
pub const STAGE_GPU_GBUFFER: &str = "G-buffer (GPU)";

/// A scene at one resolution, with everything the methods share.
#[derive(Debug, Clone)]
pub struct Frame<'s> {
    /// The scene.
    pub scene: &'s Scene,
    /// All triangles; triangle ids index into it.
    pub geometry: Geometry,
    /// Effects the scene calls for.
    pub effects: Effects,
    /// Camera projector at this resolution.
    pub camera: Projector,
    /// The camera G-buffer.
    pub gbuffer: GBuffer,
    casters: Vec<bool>,
}

impl<'s> Frame<'s> {
    /// Prepares `scene` at `width x height`, timing the G-buffer as a stage of `rec`.
    pub fn new(scene: &'s Scene, width: u32, height: u32, rec: &mut Recorder) -> Self {
        let geometry = scene.geometry();
        let camera = scene.camera.projector(width, height);
        let gbuffer = rec
            .stages
            .time(STAGE_GBUFFER, || render_gbuffer(&geometry, &camera, &mut rec.counters));
        let casters =
            scene.objects.iter().map(|o| o.casts_shadows && o.material.opacity > 0.0).collect();
        Self { scene, geometry, effects: scene.effects(), camera, gbuffer, casters }
    }

    /// Image width.
    pub fn width(&self) -> u32 {
        self.gbuffer.width
    }

    /// Image height.
    pub fn height(&self) -> u32 {
        self.gbuffer.height
    }

    /// Whether triangle `t` casts shadows.
    #[inline]
    pub fn is_caster(&self, t: usize) -> bool {
        self.object_casts_shadows(self.geometry.object[t] as usize)
    }

    /// Whether object `o` casts shadows.
    #[inline]
    pub fn object_casts_shadows(&self, o: usize) -> bool {
        self.casters[o]
    }

    /// The light's projector onto a `res x res` map, its frustum fitted as `fit` says
    /// ([`crate::light_fit`]: to the scene's bounds, or to this frame's visible samples).
    pub fn light_projector(&self, res: u32, fit: LightFit) -> Projector {
        light_fit::fit(self.scene, &self.gbuffer, res, fit)
    }

    /// The span of light-space depths the scene occupies (far minus near of the fitted
    /// frustum), the unit of constant depth biases. Every [`LightFit`] keeps the scene fit's
    /// depths (the view fits move the origin across the light's rays only), so a bias means the
    /// same under every policy (up to rounding).
    pub fn light_depth_range(&self, light: &Projector) -> f64 {
        let (near, far) = self.light_depth_bounds(light);
        (far - near).max(f64::MIN_POSITIVE)
    }

    /// The nearest and farthest light depth of the scene's bounding box corners.
    pub fn light_depth_bounds(&self, light: &Projector) -> (f64, f64) {
        let (lo, hi) = self.scene.bounds();
        let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
        for c in scenes::mesh::box_corners(lo, hi) {
            let d = light.depth_of(c);
            a = a.min(d);
            b = b.max(d);
        }
        (a, b)
    }

    /// Renders the light depth map of the casters at `res x res` through the frustum `fit`
    /// gives, as a timed stage.
    pub fn light_depth_map(&self, res: u32, fit: LightFit, rec: &mut Recorder) -> LightDepthMap {
        self.jittered_light_depth_map(res, fit, DVec2::ZERO, STAGE_LIGHT_DEPTH_MAP, rec)
    }

    /// Renders the light depth map of the casters at `res x res` through the frustum `fit`
    /// gives, with its sample points moved by `shift` texels (a jittered image plane), as a
    /// stage timed under `stage`; the frustum's fitting is part of the stage.
    pub fn jittered_light_depth_map(
        &self,
        res: u32,
        fit: LightFit,
        shift: DVec2,
        stage: &str,
        rec: &mut Recorder,
    ) -> LightDepthMap {
        // The frustum is fitted inside the stage: a view fit reads every pixel of the frame.
        rec.stages.time(stage, || {
            let projector = self.light_projector(res, fit);
            LightDepthMap::render(
                &self.geometry,
                |t| self.is_caster(t),
                &projector,
                shift,
                &mut rec.counters,
            )
        })
    }
}
