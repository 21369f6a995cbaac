//! Whether a light depth map resolves the frame it shadows: the footprint of one map texel on
//! the visible receivers, in pixels' footprints, and the visible surface points the light's
//! frustum misses. Every shadow-map method (`sm`, `pcf-*`, `pan09`, CPU and GPU) measures it
//! once per run, outside its timed stages, through [`crate::depth_test::DepthTester::warnings`].
//!
//! # The measure
//!
//! For every visible G-buffer sample (surface point `p`, unit face normal `n`), in one parallel
//! pass, the areas on the receiver's tangent plane of
//!
//! - the pixel: a perspective camera (eye `e`, forward `f`, pixel area `a = (2 tan_x / W)
//!   (2 tan_y / H)` on the image plane at unit depth) covers `a d³ / |n·(p - e)|` there, with
//!   `d = (p - e)·f` (the pixel's solid angle times the squared distance, over the cosine
//!   between the ray and the normal); an orthographic one `(2 hw / W) (2 hh / H) / |n·f|`;
//! - the texel: the same with the light's projector onto its `R x R` map.
//!
//! Their ratio's square root, `r`, is the texel's width in pixels on the receiver (the
//! geometric mean of its two axes: a proxy that needs no per-pixel derivatives and does not
//! depend on how either footprint is turned on the plane). Both cosines are floored at
//! [`COS_FLOOR`] (89.94°, the bias rule's default bound), so that a surface edge-on to the
//! camera or the light counts as stretched a thousandfold, not infinitely. The pass keeps a
//! histogram of `log2 r` (a quarter octave per bin, a fixed array per worker, nothing per pixel),
//! from which the warnings read quantiles.
//!
//! # The warnings
//!
//! - **Texels wider than pixels' footprints**: when more than [`FOOTPRINT_SHARE`] of the
//!   visible samples inside the light's frustum have `r >` [`TEXEL_PIXELS`] (a texel wider than
//!   16 pixels), the map cannot resolve what the frame shows: shadows there come out as blocks,
//!   or vanish, or stand where the texel's centre puts them. The warning gives the share, the
//!   largest and median `r`, the cause, and what to change: the `--map-res` that brings the
//!   share under the limit (texel widths scale as `1 / R`), if one up to 16384 does. The cause
//!   is the first of:
//!   1. *a far object*: a directional light's frustum fitted to the scene's bounds (`--frustum
//!      scene`, [`crate::light_fit`]) is stretched by one object far from the rest; named when
//!      the map is so fitted, the object lies apart from what the frame sees (its bounds miss
//!      the visible samples' bounds) and the frustum fitted without it would have texels
//!      narrow enough (its removal alone brings the share under the limit);
//!   2. *a degenerate camera*: the median texel is wider than the whole frame (the camera sees
//!      less than one texel of the scene), as with a field of view of 1e-12 degrees; the fix is
//!      the field of view (or orthographic height) that brings the share under the limit;
//!   3. *a spot light inside the scene's bounds*, among the casters, seeing the visible
//!      surfaces at extreme angles;
//!   4. otherwise, a map that is coarse for the frame.
//! - **Samples the frustum misses**: when more than [`FOOTPRINT_SHARE`] of the visible samples
//!   lie outside the light's frustum (a spot light's cone, or behind it), the methods count
//!   them lit, which is a guess: the references light a spot in every direction. The warning
//!   names the count, those behind the light, and the `fov_deg` that would take them in where
//!   none lies behind it.
//! - **Pixels wider than many texels** (methods that decide a pixel by its centre alone,
//!   [`Sampling::PixelCentre`]): when more than half of the visible samples have
//!   `r < 1 /` [`PIXEL_TEXELS`], every such pixel's binary answer is the depth test of one
//!   point, not the lit fraction of the area it covers, and a centre within a texel of a shadow
//!   edge or a thin caster's shadow can fall on either side. This is what a 1 x 1 frame of
//!   `cage` shows: its one centre lies at the edge of a bar's shadow (a bar 0.03 wide, about
//!   1.4 texels of the default map), where `sm` reads the lit texel next to it and answers 1
//!   while both references, sampling that same point at rate 1, answer 0, and the pixel's lit
//!   fraction (`raytrace` at 256 samples) is 0.91. The answer is the method's own (the same
//!   centre in a 161 x 121 frame gives the same 1; `--map-res 2048` gives 0), so the run
//!   warns instead of changing it.

use crate::{frame::Frame, light_fit::LightFit};
use glam::DVec3;
use rayon::prelude::*;
use scenes::projection::{ProjectionKind, Projector};
use scenes::{Camera, Light};

/// The texel width, in pixels on the receiver, beyond which a sample counts as unresolved.
pub const TEXEL_PIXELS: f64 = 16.0;

/// The pixel width, in texels on the receiver, beyond which a centre-sampled pixel counts as
/// covering many texels.
pub const PIXEL_TEXELS: f64 = 64.0;

/// Share of the visible samples above which an unresolved or missed part warns.
pub const FOOTPRINT_SHARE: f64 = 0.01;

/// Floor of the cosines between a surface's normal and the camera's or the light's ray.
pub const COS_FLOOR: f64 = 1e-3;

/// The largest map resolution a run accepts (`--map-res`).
const MAX_MAP_RES: f64 = 16384.0;

const BINS_PER_OCTAVE: f64 = 4.0;
const LOW_OCTAVE: f64 = -64.0;
const BINS: usize = 512;

/// How a method decides a pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sampling {
    /// By the one point at its centre (`sm`; `pcf-gems*` and `pcf-bs-*`, whose filters cover
    /// a fixed region of texels around it).
    PixelCentre,
    /// By samples over its area (`pcf-reeves`, `pan09`).
    PixelArea,
}

/// The footprint area of one image cell of `p` on the plane through `pos` with unit normal
/// `n`; infinite or NaN where `pos` does not lie in front of a perspective projector.
fn cell_area(p: &Projector, pos: DVec3, n: DVec3) -> f64 {
    match p.kind {
        ProjectionKind::Perspective { tan_half_x, tan_half_y } => {
            let v = pos - p.origin;
            let d = v.dot(p.forward);
            let len = v.length();
            let cos = (n.dot(v) / len).abs().max(COS_FLOOR);
            let a = 4.0 * tan_half_x * tan_half_y / (p.width * p.height);
            a * d * (d / len) * (d / cos)
        }
        ProjectionKind::Orthographic { half_width, half_height } => {
            let cos = n.dot(p.forward).abs().max(COS_FLOOR);
            4.0 * half_width * half_height / (p.width * p.height) / cos
        }
    }
}

/// The histogram bin of ratio `r` (clamped to the first and last bins).
fn bin(r: f64) -> usize {
    let b = ((r.log2() - LOW_OCTAVE) * BINS_PER_OCTAVE).floor();
    if b.is_nan() || b < 0.0 {
        0
    } else {
        (b as usize).min(BINS - 1)
    }
}

/// The upper edge of bin `i`.
fn bin_top(i: usize) -> f64 {
    (LOW_OCTAVE + (i + 1) as f64 / BINS_PER_OCTAVE).exp2()
}

/// Per-worker tally of the pass.
#[derive(Debug, Clone)]
struct Tally {
    covered: u64,
    outside: u64,
    at_risk: u64,
    behind: u64,
    measured: u64,
    over: u64,
    under: u64,
    max_ratio: f64,
    max_light_angle_over: f64,
    max_off_axis_tan: f64,
    lo: DVec3,
    hi: DVec3,
    bins: Box<[u64; BINS]>,
}

impl Tally {
    fn new() -> Self {
        Self {
            covered: 0,
            outside: 0,
            at_risk: 0,
            behind: 0,
            measured: 0,
            over: 0,
            under: 0,
            max_ratio: 0.0,
            max_light_angle_over: 0.0,
            max_off_axis_tan: 0.0,
            lo: DVec3::splat(f64::INFINITY),
            hi: DVec3::splat(f64::NEG_INFINITY),
            bins: Box::new([0; BINS]),
        }
    }

    fn merge(mut self, o: Self) -> Self {
        self.covered += o.covered;
        self.outside += o.outside;
        self.at_risk += o.at_risk;
        self.behind += o.behind;
        self.measured += o.measured;
        self.over += o.over;
        self.under += o.under;
        self.max_ratio = self.max_ratio.max(o.max_ratio);
        self.max_light_angle_over = self.max_light_angle_over.max(o.max_light_angle_over);
        self.max_off_axis_tan = self.max_off_axis_tan.max(o.max_off_axis_tan);
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
        for (a, b) in self.bins.iter_mut().zip(o.bins.iter()) {
            *a += b;
        }
        self
    }
}

/// The frame's visible samples against one light map (see the module doc).
#[derive(Debug, Clone)]
pub struct Footprint {
    /// Map resolution.
    pub map_res: u32,
    /// Visible samples (pixels whose centre sees a surface).
    pub covered: u64,
    /// Those outside the light's frustum (behind a spot light included).
    pub outside: u64,
    /// Those of them that a caster reaching outside the frustum may shadow.
    pub at_risk: u64,
    /// Those behind a spot light.
    pub behind: u64,
    /// Those inside the frustum, whose ratio was measured.
    pub measured: u64,
    /// Measured samples whose texel is wider than [`TEXEL_PIXELS`] pixels.
    pub over: u64,
    /// Measured samples whose pixel is wider than [`PIXEL_TEXELS`] texels.
    pub under: u64,
    /// The largest ratio `r` (texel width in pixels).
    pub max_ratio: f64,
    /// The largest angle between the light's ray and the normal among the `over` samples,
    /// degrees.
    pub max_light_angle_over_deg: f64,
    /// A spot light's largest `tan` of the angle off its axis, per image axis, among the
    /// visible samples in front of it (0 for a directional light).
    pub max_off_axis_tan: f64,
    /// Bounds of the visible samples.
    pub visible_bounds: (DVec3, DVec3),
    /// Whether the light's projector is fitted to the scene's bounds (`--frustum scene`), so
    /// that an object far from the rest stretches a directional light's texels.
    pub scene_fitted: bool,
    bins: Box<[u64; BINS]>,
}

impl Footprint {
    /// Measures the frame's visible samples against the light `projector` onto an
    /// `map_res x map_res` map.
    pub fn measure(projector: &Projector, map_res: u32, frame: &Frame<'_>) -> Self {
        let g = &frame.gbuffer;
        let camera = &frame.camera;
        let light = projector;
        let perspective = light.is_perspective();
        let risky = RiskyCasters::new(light, frame);
        let t = (0..g.triangle.len())
            .into_par_iter()
            .fold(Tally::new, |mut t, k| {
                if !g.covered(k) {
                    return t;
                }
                let (p, n) = (g.position[k], g.normal[k]);
                t.covered += 1;
                t.lo = t.lo.min(p);
                t.hi = t.hi.max(p);
                let v = p - light.origin;
                let depth = v.dot(light.forward);
                let object = frame.geometry.object[g.triangle[k] as usize] as usize;
                if perspective {
                    if depth.is_nan() || depth <= 0.0 {
                        t.behind += 1;
                        t.outside += 1;
                        t.at_risk += u64::from(risky.may_shadow(object));
                        return t;
                    }
                    let off = v.dot(light.right).abs().max(v.dot(light.up).abs()) / depth;
                    t.max_off_axis_tan = t.max_off_axis_tan.max(off);
                }
                let inside = light.project(p).is_some_and(|(xy, _)| {
                    xy.x >= 0.0 && xy.y >= 0.0 && xy.x <= light.width && xy.y <= light.height
                });
                if !inside {
                    t.outside += 1;
                    t.at_risk += u64::from(risky.may_shadow(object));
                    return t;
                }
                let r = (cell_area(light, p, n) / cell_area(camera, p, n)).sqrt();
                if r.is_nan() {
                    return t;
                }
                t.measured += 1;
                t.bins[bin(r)] += 1;
                t.max_ratio = t.max_ratio.max(r);
                if r > TEXEL_PIXELS {
                    t.over += 1;
                    let ray = if perspective { v } else { light.forward };
                    let cos = (n.dot(ray) / ray.length()).abs().min(1.0);
                    t.max_light_angle_over = t.max_light_angle_over.max(cos.acos().to_degrees());
                }
                if r < 1.0 / PIXEL_TEXELS {
                    t.under += 1;
                }
                t
            })
            .reduce(Tally::new, Tally::merge);
        Self {
            map_res,
            covered: t.covered,
            outside: t.outside,
            at_risk: t.at_risk,
            behind: t.behind,
            measured: t.measured,
            over: t.over,
            under: t.under,
            max_ratio: t.max_ratio,
            max_light_angle_over_deg: t.max_light_angle_over,
            max_off_axis_tan: t.max_off_axis_tan,
            visible_bounds: (t.lo, t.hi),
            scene_fitted: *projector == frame.light_projector(map_res, LightFit::Scene),
            bins: t.bins,
        }
    }

    /// A ratio that at most `share` of the measured samples exceed (the upper edge of the
    /// histogram bin where that share is reached; the largest ratio in the last bin).
    pub fn ratio_exceeded_by(&self, share: f64) -> f64 {
        let allowed = share * self.measured as f64;
        let mut above = 0u64;
        for i in (0..BINS).rev() {
            if (above + self.bins[i]) as f64 > allowed {
                return if i == BINS - 1 { self.max_ratio } else { bin_top(i).min(self.max_ratio) };
            }
            above += self.bins[i];
        }
        0.0
    }

    /// Whether more than [`FOOTPRINT_SHARE`] of the measured samples are unresolved.
    pub fn unresolved(&self) -> bool {
        self.over > 0 && self.over as f64 > FOOTPRINT_SHARE * self.measured as f64
    }

    /// The warnings a run of `method` records (see the module doc).
    pub fn warnings(&self, method: &str, frame: &Frame<'_>, sampling: Sampling) -> Vec<String> {
        let mut w = Vec::new();
        if self.unresolved() {
            w.push(self.texel_warning(method, frame));
        }
        if self.at_risk > 0 && self.at_risk as f64 > FOOTPRINT_SHARE * self.covered as f64 {
            w.push(self.outside_warning(method, frame));
        }
        if sampling == Sampling::PixelCentre && self.under as f64 > 0.5 * self.measured as f64 {
            w.push(self.coarse_warning(method, frame));
        }
        w
    }

    /// The factor by which texels must narrow to bring the unresolved share under the limit.
    fn needed_factor(&self) -> f64 {
        self.ratio_exceeded_by(FOOTPRINT_SHARE) / TEXEL_PIXELS
    }

    fn texel_warning(&self, method: &str, frame: &Frame<'_>) -> String {
        let factor = self.needed_factor();
        let median = self.ratio_exceeded_by(0.5);
        let (w, h) = (frame.width(), frame.height());
        let mut fixes = Vec::new();
        let cause = if let Some((name, narrower)) = self
            .scene_fitted
            .then(|| stretching_object(frame, self.map_res, self.visible_bounds))
            .flatten()
            .filter(|(_, f)| *f >= factor)
        {
            fixes.push(format!("move object '{name}' nearer the rest or remove it"));
            let (lo, hi) = frame.scene.bounds();
            let (vlo, vhi) = self.visible_bounds;
            format!(
                "the light frustum is fitted to the scene's bounds, {} to {}, while the visible \
                 samples lie within {} to {}: object '{name}' stretches it (without it the \
                 texels would be {narrower:.3e} times narrower)",
                v3(lo),
                v3(hi),
                v3(vlo),
                v3(vhi)
            )
        } else if median > f64::from(w.max(h)) {
            let (vlo, vhi) = self.visible_bounds;
            let view = match frame.scene.camera {
                Camera::Perspective { fov_y_deg, .. } => {
                    let wider = (fov_y_deg.to_radians() * 0.5).tan() * factor;
                    let wider = 2.0 * wider.atan().to_degrees();
                    if wider < 179.0 {
                        fixes.push(format!("a wider camera field of view (fov_y_deg {wider:.3e})"));
                    }
                    format!("field of view (fov_y_deg {fov_y_deg:e})")
                }
                Camera::Orthographic { height, .. } => {
                    fixes.push(format!("a larger camera height ({:.3e})", height * factor));
                    format!("view height ({height:e})")
                }
            };
            format!(
                "the camera's {view} is degenerate: the whole {w}x{h} frame sees {:.3e} world \
                 units of the scene, less than one texel (a median texel is {median:.3e} pixels \
                 wide)",
                (vhi - vlo).length()
            )
        } else if let Light::Spot { position, .. } = frame.scene.light {
            let (lo, hi) = frame.scene.bounds();
            if position.cmpge(lo).all() && position.cmple(hi).all() {
                fixes.push("move the spot light out of the casters, farther from them".into());
                format!(
                    "the spot light at {} lies inside the scene's bounds, among the casters, and \
                     sees the visible surfaces at up to {:.2}° from their normals",
                    v3(position),
                    self.max_light_angle_over_deg
                )
            } else {
                self.coarse_map_cause()
            }
        } else {
            self.coarse_map_cause()
        };
        let res = (f64::from(self.map_res) * factor).ceil();
        let map_res = if res <= MAX_MAP_RES {
            fixes.push(format!("--map-res {res}"));
            String::new()
        } else {
            format!(" (no --map-res up to {MAX_MAP_RES} suffices: it would need {res:.3e})")
        };
        format!(
            "{method}: {} of {} visible surface pixels inside the light's frustum lie where one \
             shadow-map texel is wider than {TEXEL_PIXELS} pixels (up to {:.3e}, median \
             {median:.3e}): the map cannot resolve what the frame shows, so shadows there are \
             blocks, missing or misplaced; cause: {cause}; to change: {}{map_res}",
            self.over,
            self.measured,
            self.max_ratio,
            fixes.join(", or ")
        )
    }

    fn coarse_map_cause(&self) -> String {
        format!("the {0} x {0} shadow map is coarse for this frame's pixels", self.map_res)
    }

    fn outside_warning(&self, method: &str, frame: &Frame<'_>) -> String {
        let fix = match frame.scene.light {
            Light::Spot { fov_deg, .. } => {
                let wide = 2.0 * self.max_off_axis_tan.atan().to_degrees();
                if self.behind == 0 && wide <= 170.0 {
                    format!("a spot fov_deg of {:.2} (given {fov_deg}) would take them in", wide)
                } else {
                    "no spot fov_deg takes them in: aim the spot light at them or move it out, \
                     beyond them"
                        .to_owned()
                }
            }
            Light::Directional { .. } => "the light's frustum misses them".to_owned(),
        };
        let cause = match frame.scene.light {
            Light::Spot { position, .. } => {
                let (lo, hi) = frame.scene.bounds();
                if position.cmpge(lo).all() && position.cmple(hi).all() {
                    format!(
                        "; the spot light at {} lies inside the scene's bounds, among the \
                         casters, where no cone takes in what surrounds it",
                        v3(position)
                    )
                } else {
                    String::new()
                }
            }
            Light::Directional { .. } => String::new(),
        };
        format!(
            "{method}: {} of {} visible surface pixels lie outside the light's frustum ({} of \
             them behind the light), where casters reaching outside it may shadow them: the \
             method counts them lit, which is a guess (the references light them from the \
             light's position in every direction){cause}; {fix}",
            self.at_risk, self.covered, self.behind
        )
    }

    fn coarse_warning(&self, method: &str, frame: &Frame<'_>) -> String {
        let median = self.ratio_exceeded_by(0.5);
        format!(
            "{method}: {} of {} visible surface pixels of the {}x{} frame are each wider than \
             {PIXEL_TEXELS} texels of the {} x {} shadow map (a median pixel is {:.1} texels \
             wide): the method decides a pixel by the one point at its centre, so its value is \
             not the lit fraction of the area it covers, and a centre within a texel of a shadow \
             edge or of a thin caster's shadow may fall on either side; a larger frame \
             (--width, --height) or a method that samples the pixel's area measures it",
            self.under,
            self.measured,
            frame.width(),
            frame.height(),
            self.map_res,
            self.map_res,
            1.0 / median.max(f64::MIN_POSITIVE)
        )
    }
}

/// The casters that reach outside a spot light's frustum: only they can shadow a point outside
/// it, since the segment from the light to such a point runs outside the frustum (a pyramid
/// from the light, convex) all the way. An object whose vertices all lie inside the frustum
/// lies inside it whole. A planar object cannot shadow points of its own plane, so
/// a sample on a planar object is at risk only from the other casters. A directional light's
/// frustum holds the whole scene: nothing lies outside it but by rounding, and any caster may
/// shadow such a point.
struct RiskyCasters {
    /// Per object: whether it reaches outside the frustum and casts shadows.
    reaching: Vec<bool>,
    /// Per object: whether it is planar (only computed for reaching objects).
    planar: Vec<bool>,
    count: usize,
}

impl RiskyCasters {
    fn new(light: &Projector, frame: &Frame<'_>) -> Self {
        let objects = &frame.scene.objects;
        let reaching: Vec<bool> = objects
            .iter()
            .enumerate()
            .map(|(i, o)| {
                frame.object_casts_shadows(i)
                    && (!light.is_perspective()
                        || o.mesh.positions.par_iter().any(|&c| {
                            light.project(c).is_none_or(|(xy, _)| {
                                !(xy.x >= 0.0
                                    && xy.y >= 0.0
                                    && xy.x <= light.width
                                    && xy.y <= light.height)
                            })
                        }))
            })
            .collect();
        let planar = objects
            .iter()
            .zip(&reaching)
            .map(|(o, &r)| r && light.is_perspective() && o.mesh.plane().is_some())
            .collect();
        let count = reaching.iter().filter(|&&r| r).count();
        Self { reaching, planar, count }
    }

    /// Whether a caster reaching outside the frustum may shadow a point of object `o`.
    fn may_shadow(&self, o: usize) -> bool {
        let own = usize::from(self.reaching[o] && self.planar[o]);
        self.count > own
    }
}

/// A point as `[x, y, z]` with short numbers.
fn v3(p: DVec3) -> String {
    format!("[{:.3e}, {:.3e}, {:.3e}]", p.x, p.y, p.z)
}

/// Among the objects apart from what the frame sees (bounds disjoint from `visible`, the
/// visible samples' bounds), the one whose removal from the scene's bounds narrows a
/// directional light's texels the most, with that factor (texel width, geometric mean of its
/// axes); `None` for a spot light (its texels do not depend on the bounds) or where no such
/// object is left out with another remaining.
fn stretching_object(
    frame: &Frame<'_>,
    map_res: u32,
    visible: (DVec3, DVec3),
) -> Option<(String, f64)> {
    let light = &frame.scene.light;
    if !matches!(light, Light::Directional { .. }) {
        return None;
    }
    let area = |p: &Projector| match p.kind {
        ProjectionKind::Orthographic { half_width, half_height } => half_width * half_height,
        ProjectionKind::Perspective { .. } => f64::NAN,
    };
    let empty = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let join = |a: (DVec3, DVec3), b: (DVec3, DVec3)| (a.0.min(b.0), a.1.max(b.1));
    let objects = &frame.scene.objects;
    let bounds: Vec<_> = objects.iter().map(|o| o.mesh.bounds().unwrap_or(empty)).collect();
    let mut before = vec![empty; bounds.len() + 1];
    for (i, b) in bounds.iter().enumerate() {
        before[i + 1] = join(before[i], *b);
    }
    let full = area(&light.projector(before[bounds.len()], map_res));
    let mut after = empty;
    let mut best: Option<(usize, f64)> = None;
    for i in (0..bounds.len()).rev() {
        let others = join(before[i], after);
        after = join(after, bounds[i]);
        let (lo, hi) = bounds[i];
        let apart = lo.cmpgt(visible.1).any() || hi.cmplt(visible.0).any();
        if !(apart && others.0.cmple(others.1).all()) {
            continue;
        }
        let narrower = (full / area(&light.projector(others, map_res))).sqrt();
        if narrower.is_finite() && best.is_none_or(|(_, f)| narrower > f) {
            best = Some((i, narrower));
        }
    }
    best.map(|(i, f)| (objects[i].name.clone(), f))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_cover_ratios_from_tiny_to_huge_and_clamp_the_rest() {
        assert_eq!(bin(0.0), 0);
        assert_eq!(bin(f64::NAN), 0);
        assert_eq!(bin(f64::INFINITY), BINS - 1);
        for r in [1e-15, 0.3, 1.0, 16.0, 1e12] {
            let i = bin(r);
            assert!(bin_top(i) > r && r >= bin_top(i) / 2f64.powf(0.25) * 0.999_999, "{r}");
        }
    }
}
