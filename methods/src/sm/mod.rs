//! `sm`: the standard shadow map (Williams 1978, "Casting curved shadows on curved surfaces",
//! SIGGRAPH 1978, as cited by every paper the other methods follow).
//!
//! Stages: **light depth map** (the nearest caster depth at each texel centre, see
//! [`crate::depth_map`]) and **depth test** (each pixel's surface point, taken at the pixel
//! centre from the G-buffer, is projected into the map; the texel it falls in is compared
//! once). Output is binary: 1 lit, 0 shadowed.
//!
//! Bias ([`crate::depth_test`]): a point is shadowed when `map depth < point depth - tolerance`,
//! with the reach of one nearest-texel lookup, `(0.5, 0.5)` texels:
//! `tolerance = constant_bias * depth_range + slope_bias * (|∂t/∂x| + |∂t/∂y|) / 2`.
//! `slope_bias >= 1` keeps a lit plane fully lit wherever its slope ratio is below
//! `max_slope`; that is the documented valid range. Smaller values show shadow acne.
//!
//! Choices where the classic method is vague: surfaces outside the map are lit; casters with
//! opacity < 1 are treated as opaque (the run record says so when the scene has transparency).
//! A run says when its map makes it wrong ([`crate::footprint`]): texels wider than 16 pixels on
//! the visible receivers, visible surfaces outside a spot's frustum that a caster may shadow,
//! or pixels so wide that one centre decides many texels' worth of receiver.

use crate::{
    depth_map::LightDepthMap,
    depth_test::{filter_pixels, texel_at, DepthTester, MapOptions, PixelResult, Receiver},
    footprint::Sampling,
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
};
use glam::DVec2;
use instrumentation::Recorder;

/// Name of the depth-test stage.
pub const STAGE_DEPTH_TEST: &str = "depth test";

/// Reach of one nearest-texel lookup: the texel centre is at most half a texel away per axis.
pub const NEAREST_REACH: DVec2 = DVec2::splat(0.5);

/// The standard depth test of one surface point: the texel the point falls in is compared
/// once, shadowed when `map depth < point depth - tolerance` with the reach of one
/// nearest-texel lookup; points outside the map are lit. (`pan09` runs the same test on its
/// non-silhouette pixels.)
#[inline]
pub fn depth_test(map: &LightDepthMap, tester: &DepthTester, r: &Receiver) -> PixelResult {
    let Some((x, y)) = texel_at(r.xy, map.res) else {
        return PixelResult { lit: 1.0, ..Default::default() };
    };
    let stored = map.depth[y * map.res as usize + x];
    let shadowed = stored < r.depth - tester.tolerance(r, NEAREST_REACH);
    PixelResult { lit: if shadowed { 0.0 } else { 1.0 }, compares: 1, bilinear_lookups: 0 }
}

/// The standard shadow map.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StandardShadowMap {
    /// Options.
    pub options: MapOptions,
}

impl ShadowMethod for StandardShadowMap {
    fn name(&self) -> &'static str {
        "sm"
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        self.options.params()
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        self.options.validate()?;
        if frame.effects.transparency {
            rec.notes.push("sm treats semi-transparent casters as opaque".into());
        }
        let map = frame.light_depth_map(self.options.map_res, self.options.frustum, rec);
        let tester =
            DepthTester::new(&self.options, map.projector, frame.light_depth_range(&map.projector));
        rec.warnings.extend(tester.warnings(self.name(), frame, Sampling::PixelCentre));
        let (lit, counters) = rec.stages.time(STAGE_DEPTH_TEST, || {
            filter_pixels(frame, &tester, |_, _, r| depth_test(&map, &tester, r))
        });
        rec.counters.merge(&counters);
        Ok(Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None })
    }
}
