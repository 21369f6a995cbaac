//! `sm`: the standard shadow map (Williams 1978, "Casting curved shadows on curved surfaces",
//! as cited by every paper in `../shared/papers/`).
//!
//! Stages: **light depth map** (the nearest caster depth at each texel centre, see
//! [`crate::depth_map`]) and **depth test** (each pixel's surface point, taken at the pixel
//! centre from the G-buffer, is projected into the map; the texel it falls in is compared
//! once). Output is binary: 1 lit, 0 shadowed.
//!
//! Bias. A point is shadowed when `map depth < point depth - bias`, with
//! `bias = constant_bias * depth_range + slope_bias * slope`, where `depth_range` is the span of
//! light depths the scene occupies and `slope` is the receiver plane's depth change per texel
//! step, `max(|∂t/∂x|, |∂t/∂y|)`, computed exactly from the face normal and the light's
//! projection at the point (the ratio `|n·axis| / |n·ray|` clamped to `max_slope`).
//! Within one texel a plane's depth departs from its value at the texel centre by at most
//! `(|∂t/∂x| + |∂t/∂y|) / 2 <= slope` (exactly for orthographic lights, to first order for
//! spot lights), so `slope_bias >= 1` keeps a lit plane fully lit wherever its slope ratio is
//! below `max_slope`; that is the documented valid range. Smaller values show shadow acne.
//!
//! Choices where the classic method is vague: surfaces outside the map are lit; casters with
//! opacity < 1 are treated as opaque (the run record says so when the scene has transparency).

use crate::{
    frame::Frame,
    method::{MethodError, ShadowMethod, Visibility},
    raster::NO_TRIANGLE,
};
use glam::DVec3;
use instrumentation::{Counters, Recorder};
use rayon::prelude::*;
use scenes::projection::{ProjectionKind, Projector};

/// Name of the depth-test stage.
pub const STAGE_DEPTH_TEST: &str = "depth test";

/// Options of the standard shadow map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmOptions {
    /// Shadow map resolution `R` (the map is `R x R`). Default 1024.
    pub map_res: u32,
    /// Constant bias as a fraction of the scene's light depth range. Default `1e-5`.
    pub constant_bias: f64,
    /// Slope-scaled bias in units of the receiver's depth change per texel. Default 1.0;
    /// values >= 1 keep a lit plane free of acne (see the module doc).
    pub slope_bias: f64,
    /// Upper bound of the slope ratio `|n·axis| / |n·ray|` (about 84° from the light). Default 10.
    pub max_slope: f64,
}

impl Default for SmOptions {
    fn default() -> Self {
        Self { map_res: 1024, constant_bias: 1e-5, slope_bias: 1.0, max_slope: 10.0 }
    }
}

impl SmOptions {
    /// Checks the options; errors name the command-line flag.
    pub fn validate(&self) -> Result<(), MethodError> {
        if !(1..=16384).contains(&self.map_res) {
            return Err(MethodError::InvalidOption {
                option: "--map-res",
                message: format!("must be in 1..=16384, got {}", self.map_res),
            });
        }
        for (option, v) in [
            ("--constant-bias", self.constant_bias),
            ("--slope-bias", self.slope_bias),
            ("--max-slope", self.max_slope),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(MethodError::InvalidOption {
                    option,
                    message: format!("must be finite and >= 0, got {v}"),
                });
            }
        }
        Ok(())
    }
}

/// The standard shadow map.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StandardShadowMap {
    /// Options.
    pub options: SmOptions,
}

/// The receiver plane's depth change per texel step in x and y at light image point `xy`
/// with depth `t`, for unit normal `n`; the ratios are clamped to `max_slope`.
pub fn depth_slope(
    light: &Projector,
    n: DVec3,
    xy: glam::DVec2,
    t: f64,
    max_slope: f64,
) -> (f64, f64) {
    let dir = light.ray(xy).direction;
    let n_dir = n.dot(dir).abs();
    let ratio = |axis: DVec3| {
        let r = n.dot(axis).abs() / n_dir;
        if r.is_finite() {
            r.min(max_slope)
        } else {
            max_slope
        }
    };
    let (step_x, step_y) = match light.kind {
        ProjectionKind::Orthographic { half_width, half_height } => {
            (2.0 * half_width / light.width, 2.0 * half_height / light.height)
        }
        ProjectionKind::Perspective { tan_half_x, tan_half_y } => {
            (t * 2.0 * tan_half_x / light.width, t * 2.0 * tan_half_y / light.height)
        }
    };
    (ratio(light.right) * step_x, ratio(light.up) * step_y)
}

impl ShadowMethod for StandardShadowMap {
    fn name(&self) -> &'static str {
        "sm"
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let o = &self.options;
        let mut m = serde_json::Map::new();
        m.insert("map_res".into(), o.map_res.into());
        m.insert("constant_bias".into(), o.constant_bias.into());
        m.insert("slope_bias".into(), o.slope_bias.into());
        m.insert("max_slope".into(), o.max_slope.into());
        m
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        self.options.validate()?;
        if frame.effects.transparency {
            rec.notes.push("sm treats semi-transparent casters as opaque".into());
        }
        let map = frame.light_depth_map(self.options.map_res, rec);
        let depth_range = frame.light_depth_range(&map.projector);
        let o = self.options;
        let g = &frame.gbuffer;
        let (lit, counters) = rec.stages.time(STAGE_DEPTH_TEST, || {
            let lit: Vec<(f32, u64)> = (0..g.triangle.len())
                .into_par_iter()
                .map(|k| {
                    if g.triangle[k] == NO_TRIANGLE {
                        return (1.0, 0);
                    }
                    let Some((xy, t)) = map.projector.project(g.position[k]) else {
                        return (1.0, 0);
                    };
                    let Some(stored) = map.texel(xy.x.floor() as i64, xy.y.floor() as i64) else {
                        return (1.0, 0);
                    };
                    let (sx, sy) = depth_slope(&map.projector, g.normal[k], xy, t, o.max_slope);
                    let bias = o.constant_bias * depth_range + o.slope_bias * sx.max(sy);
                    (if stored < t - bias { 0.0 } else { 1.0 }, 1)
                })
                .collect();
            let lookups = lit.iter().map(|&(_, n)| n).sum();
            (lit.into_iter().map(|(v, _)| v).collect::<Vec<f32>>(), lookups)
        });
        rec.counters.merge(&Counters { shadow_map_lookups: counters, ..Default::default() });
        Ok(Visibility { width: frame.width(), height: frame.height(), lit, transmittance: None })
    }
}
