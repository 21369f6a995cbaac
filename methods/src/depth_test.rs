//! The depth comparison against a light depth map, shared by `sm` and the percentage-closer
//! filtering methods: where a pixel's surface point falls in the map, how much depth bias it
//! gets, and (for Brabec & Seidel's depth-as-colour maps) how depths are quantized.
//!
//! # Bias
//!
//! A comparison of the point's light depth `t` against a depth stored at a texel centre
//! `c` shadows the point when `stored < t - tolerance`, with
//!
//! `tolerance = constant_bias * depth_range + slope_bias * (reach.x * |∂t/∂x| + reach.y * |∂t/∂y|)`
//!
//! where `depth_range` is the span of light depths the scene occupies, `∂t/∂x`, `∂t/∂y` are the
//! receiver plane's depth changes per texel step ([`depth_slope`], exact from the face normal
//! and the light's projection, the ratio `|n·axis| / |n·ray|` clamped to `max_slope`), and
//! `reach` is the largest distance, in texels along each axis, from the point to the centre of
//! any texel the method compares it against: `(0.5, 0.5)` for one nearest-texel lookup, more
//! for filters. A plane's depth at such a centre departs from `t` by at most
//! `reach.x |∂t/∂x| + reach.y |∂t/∂y|` (exactly for orthographic lights, to first order for
//! spot lights), so **`slope_bias >= 1` keeps a lit plane fully lit for every method**, wherever
//! its slope ratio is below `max_slope`: the documented valid range. Smaller values show
//! shadow acne, larger ones move shadows away from their casters ("Peter Panning"), more so the
//! wider the filter, as the papers' users know.
//!
//! # Grazing light: the valid range and its warning
//!
//! The slope ratio of a plane whose normal makes the angle `θ` with the light's ray is at most
//! `tan θ` per axis, so the slope term is the part of the rule that adapts to the
//! light-receiver angle: it grows with `tan θ` as the plane turns towards the light's horizon.
//! The bound `max_slope` only exists so that surfaces parallel to the light (ratio infinite)
//! keep a finite tolerance. Its default, [`DEFAULT_MAX_SLOPE`] = 1000, puts the edge of the
//! valid range at `atan(1000)` = 89.94°: with default options a lit ground stays lit for every
//! light up to 89.9° from its normal. (The earlier default, 10, ended the range at 84.3°; the
//! ground then showed acne over its whole lit part, mean error 0.06 at 85° and 0.41 at 89°.)
//! The cost of the larger bound is confined to the surfaces it newly covers: a plane at
//! `θ` gets `tan θ` times the depth change of one texel step, which is the depth span of the
//! footprint its own texel already has on it, so shadows move by at most that footprint.
//!
//! Beyond the range acne is possible, so every method that uses the rule checks the frame's
//! visible surface points ([`DepthTester::range_warning`]): when more than
//! [`WARNING_SHARE`] of them lie where `slope_bias * min(ratio, max_slope) < ratio` on some
//! axis (the tolerance falls short of the plane's own depth change), the run records a
//! warning naming the largest light-receiver angle met, the flags `--slope-bias` and
//! `--max-slope` with their values, the valid range, and the `--max-slope` that would cover
//! those points. A few pixels on triangles that happen to lie almost parallel to the light
//! (random triangles, tessellated spheres at the terminator) stay below the share and do not
//! warn; a ground under a grazing light, or a `--slope-bias` below 1 on sloped surfaces, does.
//!
//! # Quantized depth
//!
//! Brabec and Seidel store depth as colour through a linear ramp texture (section 2), so both
//! the map and the camera pass see depth quantized to `bits` bits over the light's depth span
//! ([`DepthCode`]). Comparisons then happen between integer codes, with the tolerance converted
//! to code units; a rounding step can hide up to one code of depth, so with quantization the
//! valid range also needs `constant_bias >= 2^(1 - bits)` (two codes' worth of margin against
//! the one code rounding can take).

use crate::{
    footprint::{Footprint, Sampling},
    frame::Frame,
    light_fit::LightFit,
    method::MethodError,
};
use glam::{DVec2, DVec3};
use instrumentation::Counters;
use rayon::prelude::*;
use scenes::projection::{ProjectionKind, Projector};

/// Options every shadow-map method shares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapOptions {
    /// Shadow map resolution `R` (the map is `R x R`). Default 1024.
    pub map_res: u32,
    /// Constant bias as a fraction of the scene's light depth range. Default `1e-5`.
    pub constant_bias: f64,
    /// Slope-scaled bias in units of the receiver's depth change over the method's reach
    /// (see the module doc). Default 1.0; values >= 1 keep a lit plane free of acne.
    pub slope_bias: f64,
    /// Upper bound of the slope ratio `|n·axis| / |n·ray|`. Default [`DEFAULT_MAX_SLOPE`]
    /// (1000: planes up to 89.94° from the light's ray).
    pub max_slope: f64,
    /// The light frustum the map is rendered through ([`crate::light_fit`]). Default
    /// [`LightFit::Scene`], fitted to the scene's bounds.
    pub frustum: LightFit,
}

impl Default for MapOptions {
    fn default() -> Self {
        Self {
            map_res: 1024,
            constant_bias: 1e-5,
            slope_bias: 1.0,
            max_slope: DEFAULT_MAX_SLOPE,
            frustum: LightFit::Scene,
        }
    }
}

/// Default bound of the slope ratio: `tan` of 89.94°, so that the valid range of the bias rule
/// reaches a light 89.9° from a plane's normal (see the module doc).
pub const DEFAULT_MAX_SLOPE: f64 = 1000.0;

/// Share of a frame's visible surface points beyond the bias rule's valid range above which a
/// run records a warning.
pub const WARNING_SHARE: f64 = 0.01;

impl MapOptions {
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

    /// The options as run-record parameters.
    pub fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = serde_json::Map::new();
        m.insert("map_res".into(), self.map_res.into());
        m.insert("constant_bias".into(), self.constant_bias.into());
        m.insert("slope_bias".into(), self.slope_bias.into());
        m.insert("max_slope".into(), self.max_slope.into());
        m.insert("frustum".into(), self.frustum.as_str().into());
        m
    }
}

/// The receiver plane's depth change per texel step in x and y at light image point `xy`
/// with depth `t`, for unit normal `n`; the ratios are clamped to `max_slope`.
pub fn depth_slope(light: &Projector, n: DVec3, xy: DVec2, t: f64, max_slope: f64) -> DVec2 {
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
    DVec2::new(ratio(light.right) * step_x, ratio(light.up) * step_y)
}

/// A surface point seen from the light: where it falls in the map and how its plane slopes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Receiver {
    /// Light image point, in texels from the map's top-left corner.
    pub xy: DVec2,
    /// Light depth.
    pub depth: f64,
    /// `(|∂t/∂x|, |∂t/∂y|)`: depth change of the receiver plane per texel step.
    pub slope: DVec2,
}

/// Builds [`Receiver`]s and their tolerances for one map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthTester {
    /// The light's projector onto the map.
    pub projector: Projector,
    /// `constant_bias * depth_range`, in depth units.
    pub constant: f64,
    /// Slope-scaled bias factor.
    pub slope_bias: f64,
    /// Bound of the slope ratio.
    pub max_slope: f64,
}

impl DepthTester {
    /// The tester for a map seen through `projector`, in a scene whose light depths span
    /// `depth_range`.
    pub fn new(options: &MapOptions, projector: Projector, depth_range: f64) -> Self {
        Self {
            projector,
            constant: options.constant_bias * depth_range,
            slope_bias: options.slope_bias,
            max_slope: options.max_slope,
        }
    }

    /// The surface point `position` with unit normal `normal` as seen from the light, or
    /// `None` where it does not project (behind a spot light).
    #[inline]
    pub fn receiver(&self, position: DVec3, normal: DVec3) -> Option<Receiver> {
        let (xy, depth) = self.projector.project(position)?;
        let slope = depth_slope(&self.projector, normal, xy, depth, self.max_slope);
        Some(Receiver { xy, depth, slope })
    }

    /// The depth tolerance of comparisons that reach up to `reach` texels from the point.
    #[inline]
    pub fn tolerance(&self, r: &Receiver, reach: DVec2) -> f64 {
        self.constant + self.slope_bias * reach.dot(r.slope)
    }

    /// Where the frame's visible surface points stand against the rule's valid range.
    pub fn range(&self, frame: &Frame<'_>) -> BiasRange {
        let g = &frame.gbuffer;
        let per_pixel = |k: usize| -> Option<(f64, f64)> {
            if !g.covered(k) {
                return None;
            }
            let n = g.normal[k];
            let (xy, _) = self.projector.project(g.position[k])?;
            let dir = scenes::direction::unit(self.projector.ray(xy).direction)?;
            let n_dir = n.dot(dir).abs();
            let ratio = (n.dot(self.projector.right).abs() / n_dir)
                .max(n.dot(self.projector.up).abs() / n_dir);
            let ratio = if ratio.is_nan() { 0.0 } else { ratio };
            let angle = n_dir.clamp(0.0, 1.0).acos().to_degrees();
            Some((ratio, angle))
        };
        let (covered, beyond, max_angle, max_ratio) = (0..g.triangle.len())
            .into_par_iter()
            .filter_map(per_pixel)
            .map(|(ratio, angle)| {
                let ok = self.slope_bias * ratio.min(self.max_slope) >= ratio;
                if ok {
                    (1usize, 0usize, 0.0f64, 0.0f64)
                } else {
                    (1, 1, angle, ratio)
                }
            })
            .reduce(|| (0, 0, 0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1, a.2.max(b.2), a.3.max(b.3)));
        BiasRange { covered, beyond, max_angle_deg: max_angle, max_ratio }
    }

    /// Every warning a run of `method`, which decides pixels as `sampling` says, records about
    /// its map on `frame`: the bias rule's range ([`Self::range_warning`]) and whether the map
    /// resolves the frame ([`Footprint`]). One parallel pass over the G-buffer each, run
    /// outside the method's timed stages.
    pub fn warnings(&self, method: &str, frame: &Frame<'_>, sampling: Sampling) -> Vec<String> {
        let mut w: Vec<String> = self.range_warning(method, frame).into_iter().collect();
        let res = self.projector.width.round() as u32;
        w.extend(Footprint::measure(&self.projector, res, frame).warnings(method, frame, sampling));
        w
    }

    /// The warning a run of `method` records when more than [`WARNING_SHARE`] of the frame's
    /// visible surface points lie beyond the rule's valid range (see the module doc).
    pub fn range_warning(&self, method: &str, frame: &Frame<'_>) -> Option<String> {
        let r = self.range(frame);
        if r.beyond == 0 || (r.beyond as f64) <= WARNING_SHARE * r.covered as f64 {
            return None;
        }
        let bound_deg = self.max_slope.atan().to_degrees();
        let mut fixes = Vec::new();
        if self.slope_bias < 1.0 {
            fixes.push("--slope-bias 1".to_owned());
        }
        if r.max_ratio > self.max_slope && r.max_ratio.is_finite() {
            fixes.push(format!("--max-slope {:.4}", r.max_ratio));
        }
        let fix = if r.max_ratio.is_finite() {
            format!("{} would cover them", fixes.join(" and "))
        } else {
            "surfaces parallel to the light cannot be covered".to_owned()
        };
        Some(format!(
            "{method}: {} of {} visible surface pixels see the light up to {:.2}° from their \
             normal, beyond the depth bias rule's valid range (--slope-bias >= 1 and a slope \
             ratio up to --max-slope, {:.2}° from the normal; given --slope-bias {}, \
             --max-slope {}): they may show shadow acne; {fix}",
            r.beyond, r.covered, r.max_angle_deg, bound_deg, self.slope_bias, self.max_slope
        ))
    }
}

/// The visible surface points of a frame against the bias rule's valid range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasRange {
    /// Pixels whose surface point projects into the light's view.
    pub covered: usize,
    /// Those whose tolerance falls short of their plane's depth change on some axis.
    pub beyond: usize,
    /// The largest angle between the light's ray and a surface normal among them, degrees.
    pub max_angle_deg: f64,
    /// The largest slope ratio among them (infinite for surfaces parallel to the light).
    pub max_ratio: f64,
}

/// What a filter computed for one pixel: its lit fraction and the work it did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PixelResult {
    /// Lit fraction in `[0, 1]`.
    pub lit: f32,
    /// Depth compares made.
    pub compares: u64,
    /// Bilinear PCF lookups made.
    pub bilinear_lookups: u64,
}

/// Runs `filter` on every pixel whose surface point projects into the light's view, in
/// parallel; pixels without a surface, or behind a spot light, are lit. `filter` gets the
/// pixel's `(column, row)`, its index and its [`Receiver`]. Returns the lit fractions and the
/// summed counters.
pub fn filter_pixels(
    frame: &Frame<'_>,
    tester: &DepthTester,
    filter: impl Fn((u32, u32), usize, &Receiver) -> PixelResult + Sync,
) -> (Vec<f32>, Counters) {
    let g = &frame.gbuffer;
    let w = g.width as usize;
    let out: Vec<PixelResult> = (0..g.triangle.len())
        .into_par_iter()
        .map(|k| {
            if !g.covered(k) {
                return PixelResult { lit: 1.0, ..Default::default() };
            }
            match tester.receiver(g.position[k], g.normal[k]) {
                Some(r) => filter(((k % w) as u32, (k / w) as u32), k, &r),
                None => PixelResult { lit: 1.0, ..Default::default() },
            }
        })
        .collect();
    let counters = Counters {
        shadow_map_lookups: out.iter().map(|o| o.compares).sum(),
        bilinear_lookups: out.iter().map(|o| o.bilinear_lookups).sum(),
        ..Default::default()
    };
    (out.into_iter().map(|o| o.lit).collect(), counters)
}

/// Whether a nearest-texel lookup at `xy` of an `res x res` map is inside it, and the texel.
#[inline]
pub fn texel_at(xy: DVec2, res: u32) -> Option<(usize, usize)> {
    let (x, y) = (xy.x.floor(), xy.y.floor());
    let r = f64::from(res);
    (x >= 0.0 && y >= 0.0 && x < r && y < r).then_some((x as usize, y as usize))
}

/// Linear depth quantization over the light's depth span (Brabec and Seidel's depth-as-colour
/// ramp): depth `t` maps to the integer code `round(clamp((t - near) / span, 0, 1) * (2^bits - 1))`,
/// and "no caster" to the far code `2^bits - 1`, as a cleared depth buffer holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthCode {
    /// Bits per depth value.
    pub bits: u32,
    near: f64,
    span: f64,
    max_code: f64,
}

/// Depth precisions the depth-as-colour maps accept (`--depth-bits`).
pub const DEPTH_BITS: &[u32] = &[8, 12, 24, 32];

impl DepthCode {
    /// Quantization to `bits` bits over light depths `near ..= near + span`.
    pub fn new(bits: u32, near: f64, span: f64) -> Result<Self, MethodError> {
        if !DEPTH_BITS.contains(&bits) {
            return Err(MethodError::InvalidOption {
                option: "--depth-bits",
                message: format!("must be one of 8, 12, 24, 32, got {bits}"),
            });
        }
        let max_code = (2.0f64).powi(bits as i32) - 1.0;
        Ok(Self { bits, near, span: span.max(f64::MIN_POSITIVE), max_code })
    }

    /// The largest code (the far plane).
    pub fn max_code(&self) -> u32 {
        self.max_code as u32
    }

    /// The code of depth `t` (`f64::INFINITY`, no caster, gives the far code).
    #[inline]
    pub fn encode(&self, t: f64) -> u32 {
        let n = ((t - self.near) / self.span).clamp(0.0, 1.0);
        if n.is_nan() {
            return self.max_code();
        }
        (n * self.max_code).round() as u32
    }

    /// A depth tolerance in code units.
    #[inline]
    pub fn tolerance(&self, depth_tolerance: f64) -> f64 {
        depth_tolerance / self.span * self.max_code
    }

    /// The documented smallest valid constant bias at this precision: `2^(1 - bits)` (for
    /// any `bits`: beyond 1075 it is 0, the value of every smaller power of two in `f64`).
    pub fn min_constant_bias(bits: u32) -> f64 {
        (2.0f64).powi(1 - bits.min(1100) as i32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_span_the_range_and_round_to_nearest() {
        let c = DepthCode::new(8, 10.0, 2.0).expect("valid");
        assert_eq!(c.encode(10.0), 0);
        assert_eq!(c.encode(12.0), 255);
        assert_eq!(c.encode(f64::INFINITY), 255);
        assert_eq!(c.encode(-5.0), 0);
        assert_eq!(c.encode(10.0 + 2.0 * 100.4 / 255.0), 100);
        assert_eq!(c.encode(10.0 + 2.0 * 100.6 / 255.0), 101);
        let c = DepthCode::new(32, 0.0, 1.0).expect("valid");
        assert_eq!(c.encode(1.0), u32::MAX);
        assert!(matches!(
            DepthCode::new(16, 0.0, 1.0),
            Err(MethodError::InvalidOption { option: "--depth-bits", .. })
        ));
    }

    #[test]
    fn min_constant_bias_covers_one_rounding_step() {
        for &bits in DEPTH_BITS {
            let c = DepthCode::new(bits, 0.0, 1.0).expect("valid");
            assert!(c.tolerance(DepthCode::min_constant_bias(bits)) >= 1.0);
        }
        for bits in [1100, 1 << 31, u32::MAX] {
            assert_eq!(DepthCode::min_constant_bias(bits), 0.0, "{bits}");
        }
    }

    /// A 10 x 10 ground alone under a directional light `angle_deg` from its normal, seen
    /// from above at 32 x 24.
    fn grazing_ground(angle_deg: f64) -> scenes::Scene {
        let s = 5.0;
        let corners = [
            DVec3::new(-s, 0.0, -s),
            DVec3::new(-s, 0.0, s),
            DVec3::new(s, 0.0, s),
            DVec3::new(s, 0.0, -s),
        ];
        let mesh =
            scenes::Mesh::new(corners.to_vec(), vec![[0, 1, 2], [0, 2, 3]]).expect("valid mesh");
        let (sin, cos) = angle_deg.to_radians().sin_cos();
        scenes::Scene {
            name: "ground".into(),
            width: 32,
            height: 24,
            camera: scenes::Camera::Perspective {
                eye: DVec3::new(0.0, 6.0, 8.0),
                target: DVec3::ZERO,
                up: DVec3::Y,
                fov_y_deg: 45.0,
                near: 0.01,
            },
            light: scenes::Light::Directional {
                direction: DVec3::new(-0.8 * sin, -cos, -0.6 * sin),
            },
            objects: vec![scenes::Object {
                name: "ground".into(),
                mesh,
                material: Default::default(),
                casts_shadows: true,
            }],
            switches: Default::default(),
            animation: Default::default(),
        }
    }

    /// The bias warning of `sm` with `options` on `scene`.
    fn warning(scene: &scenes::Scene, options: &MapOptions) -> Option<String> {
        let frame = Frame::new(scene, 32, 24, &mut instrumentation::Recorder::default());
        let light = frame.light_projector(options.map_res, options.frustum);
        let tester = DepthTester::new(options, light, frame.light_depth_range(&light));
        tester.range_warning("sm", &frame)
    }

    #[test]
    fn grazing_light_is_in_range_by_default_and_warns_beyond_the_bound() {
        let defaults = MapOptions::default();
        for angle in [45.0, 85.0, 89.9] {
            assert_eq!(warning(&grazing_ground(angle), &defaults), None, "{angle}°");
        }
        let bound_10 = MapOptions { max_slope: 10.0, ..defaults };
        assert_eq!(warning(&grazing_ground(80.0), &bound_10), None);
        let w = warning(&grazing_ground(89.0), &bound_10).expect("a warning at 89°");
        assert!(w.contains("89.00°") && w.contains("--max-slope 10)"), "{w}");
        assert!(w.contains("--max-slope 57.2"), "{w}");
        assert!(!w.contains("--slope-bias 1 "), "{w}");
    }

    #[test]
    fn a_slope_bias_below_one_warns_without_asking_for_a_smaller_bound() {
        let o = MapOptions { slope_bias: 0.5, ..MapOptions::default() };
        let w = warning(&grazing_ground(60.0), &o).expect("a warning");
        assert!(w.contains("--slope-bias 1 would cover them"), "{w}");
        assert!(!w.contains("--max-slope 1."), "{w}");
    }

    #[test]
    fn texel_lookup_rejects_points_outside_the_map() {
        assert_eq!(texel_at(DVec2::new(0.0, 3.999), 4), Some((0, 3)));
        assert_eq!(texel_at(DVec2::new(-1e-12, 1.0), 4), None);
        assert_eq!(texel_at(DVec2::new(4.0, 1.0), 4), None);
        assert_eq!(texel_at(DVec2::new(f64::NAN, 1.0), 4), None);
    }
}
