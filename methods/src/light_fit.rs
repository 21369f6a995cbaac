//! The light frustum a shadow map is rendered through, chosen per run (`--frustum`,
//! [`LightFit`]): fitted to the scene's bounds, or re-fitted each frame to what the camera
//! sees. Lecocq et al. ("Sub-Pixel Shadow Mapping", ACM I3D 2014, section 2) tell the flicker
//! of maps whose parameters are "constantly updated" to follow the view (as Lauritzen et al.'s
//! sample distribution shadow maps, 2011, fit them to the view samples in light space) apart
//! from the sampling flicker of a fixed map; these policies let a run render either, and its
//! record says which.
//!
//! - **`scene`** (the default): [`scenes::Light::projector`] over the scene's bounds, the map
//!   every shadow-map method rendered before the policy existed, bit for bit.
//! - **`view`**: for a directional light, the orthographic image rectangle is the tightest one
//!   around the light-space `x`/`y` (along the light's right and up axes) of every covered
//!   G-buffer position (the camera's visible samples at pixel centres), padded on every side by
//!   [`FIT_MARGIN`] of the rectangle's diagonal, as the scene fit pads the scene's box by that
//!   share of its diagonal, and never wider on either axis than the scene fit's rectangle (which
//!   holds every visible sample already). The depth range stays the scene fit's: the origin
//!   moves across the light's rays only, so every caster between the light and a visible sample
//!   is in the map, and light depths (the unit of the constant bias,
//!   [`crate::frame::Frame::light_depth_range`]) keep their values up to rounding. A caster
//!   that shadows a visible sample lies on the light ray through that sample, so it projects
//!   onto the sample's own image point, inside the rectangle: at the visible pixel centres the
//!   view fit loses no shadow the scene fit finds, and its texels are smaller. Lookups beyond
//!   the pixel centre (a filter's neighbouring texels, the sub-samples of a pixel's area) may
//!   reach past the margin at the rectangle's border, where the map holds no caster and they
//!   count lit, as at the border of any map.
//! - **`view-snapped`**: `view` stabilised the usual way. Each half size is rounded up to the
//!   scene fit's half size times a power of two (`2^k`, `k` any integer), so the texel size
//!   takes discrete values, and large enough that the view rectangle stays inside after the
//!   centre moves by half a texel; the centre is then snapped to whole texels of that size
//!   along the light's right and up axes, in a light-space frame anchored at the world origin
//!   (not at the scene's box, which would move the grid with the box). While the light does
//!   not turn and the texel size is unchanged, a camera motion moves the map by whole texels
//!   only: texel centres stay where they were on the region both frames cover. A one-texel map
//!   cannot keep the view inside once its centre is snapped; it is the scene fit's.
//! - **Spot lights**: the map is the spot's cone, the light's own perspective frustum, under
//!   every policy (re-fitting the rectangle is a directional-light practice); the run record
//!   still says the policy.
//! - **No covered pixel**: `view` and `view-snapped` fall back to `scene`.
//!
//! The fit reads the frame's CPU G-buffer (every run has one), so CPU and GPU runs of a method
//! render the same map; it is computed where a method builds its light projector.

use crate::gbuffer::GBuffer;
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use scenes::{
    light::FIT_MARGIN,
    projection::{ProjectionKind, Projector},
    Scene,
};

/// The light frustum a shadow map is rendered through (`--frustum`; see the module doc).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum LightFit {
    /// Fitted to the scene's bounds (default).
    #[default]
    Scene,
    /// Fitted each frame to the camera's visible samples.
    View,
    /// Fitted to the visible samples, its texel size on powers of two of the scene fit's and
    /// its texels on a grid anchored at the world origin.
    ViewSnapped,
}

/// A frustum policy's name that is not one of [`LightFit::ALL`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("--frustum: `{0}` is not one of scene, view, view-snapped")]
pub struct UnknownLightFit(pub String);

impl LightFit {
    /// Every policy, in the order `--help` lists them.
    pub const ALL: [LightFit; 3] = [LightFit::Scene, LightFit::View, LightFit::ViewSnapped];

    /// The name, as on the command line and in run records.
    pub fn as_str(self) -> &'static str {
        match self {
            LightFit::Scene => "scene",
            LightFit::View => "view",
            LightFit::ViewSnapped => "view-snapped",
        }
    }
}

impl std::str::FromStr for LightFit {
    type Err = UnknownLightFit;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL.into_iter().find(|f| f.as_str() == s).ok_or_else(|| UnknownLightFit(s.into()))
    }
}

/// The least share of the scene fit's half size a view fit's half size keeps, so that one
/// visible sample, or samples on one light ray, give a finite projection.
pub const LEAST_SHARE: f64 = 1e-6;

/// The light's projector onto a `res x res` map of `scene`, whose camera G-buffer is
/// `gbuffer`, under `policy` (see the module doc).
pub fn fit(scene: &Scene, gbuffer: &GBuffer, res: u32, policy: LightFit) -> Projector {
    let fitted = scene.light.projector(scene.bounds(), res);
    let ProjectionKind::Orthographic { half_width, half_height } = fitted.kind else {
        return fitted;
    };
    let snapped = match policy {
        LightFit::Scene => return fitted,
        LightFit::View => false,
        LightFit::ViewSnapped if res < 2 => return fitted,
        LightFit::ViewSnapped => true,
    };
    let Some((lo, hi)) = visible_extent(&fitted, gbuffer) else {
        return fitted;
    };
    let scene_half = DVec2::new(half_width, half_height);
    let pad = (hi - lo).length() * FIT_MARGIN;
    // Padded, within the scene fit's rectangle (widened only to hold a sample outside it).
    let lo = (lo - DVec2::splat(pad)).max(-scene_half).min(lo);
    let hi = (hi + DVec2::splat(pad)).min(scene_half).max(hi);
    let mut centre = 0.5 * (lo + hi);
    let mut half = (0.5 * (hi - lo)).max(scene_half * LEAST_SHARE);
    if snapped {
        let r = f64::from(res);
        half = DVec2::new(
            power_of_two_multiple(half.x * r / (r - 1.0), scene_half.x),
            power_of_two_multiple(half.y * r / (r - 1.0), scene_half.y),
        );
        // The centre in the world-anchored frame, snapped to whole texels there.
        let anchor = DVec2::new(fitted.origin.dot(fitted.right), fitted.origin.dot(fitted.up));
        let texel = 2.0 * half / r;
        centre = ((anchor + centre) / texel).round() * texel - anchor;
    }
    Projector {
        origin: fitted.origin + fitted.right * centre.x + fitted.up * centre.y,
        kind: ProjectionKind::Orthographic { half_width: half.x, half_height: half.y },
        ..fitted
    }
}

/// The bounding rectangle of the covered G-buffer positions along `light`'s right and up axes,
/// relative to its origin; `None` without a covered pixel (or a finite position).
fn visible_extent(light: &Projector, g: &GBuffer) -> Option<(DVec2, DVec2)> {
    let empty = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    let (lo, hi) = (0..g.triangle.len())
        .into_par_iter()
        .filter(|&k| g.covered(k))
        .map(|k| {
            let v: DVec3 = g.position[k] - light.origin;
            DVec2::new(v.dot(light.right), v.dot(light.up))
        })
        .filter(|p| p.is_finite())
        .fold(|| empty, |(lo, hi), p| (lo.min(p), hi.max(p)))
        .reduce(|| empty, |a, b| (a.0.min(b.0), a.1.max(b.1)));
    lo.cmple(hi).all().then_some((lo, hi))
}

/// The least `unit * 2^k` (`k` an integer) at least `need`, for positive finite `need` and
/// `unit`; scaling by a power of two is exact, so the texel sizes it gives are exactly
/// `unit`'s times powers of two.
fn power_of_two_multiple(need: f64, unit: f64) -> f64 {
    let k = (need / unit).log2().ceil().clamp(-1000.0, 1000.0) as i32;
    let mut h = unit * 2f64.powi(k);
    if h < need {
        h *= 2.0;
    } else if h * 0.5 >= need {
        h *= 0.5;
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gbuffer::render_gbuffer;
    use instrumentation::Counters;
    use scenes::{Camera, Light};

    fn gbuffer(scene: &Scene, w: u32, h: u32) -> GBuffer {
        render_gbuffer(&scene.geometry(), &scene.camera.projector(w, h), &mut Counters::default())
    }

    fn half_sizes(p: &Projector) -> DVec2 {
        match p.kind {
            ProjectionKind::Orthographic { half_width, half_height } => {
                DVec2::new(half_width, half_height)
            }
            ProjectionKind::Perspective { .. } => DVec2::NAN,
        }
    }

    /// `cage` seen from close above its centre: the view sees part of the ground only.
    fn close_cage() -> Scene {
        let mut scene = scenes::load("cage").expect("built-in");
        scene.camera = Camera::Perspective {
            eye: DVec3::new(0.3, 4.0, 3.0),
            target: DVec3::new(0.0, 0.5, 0.0),
            up: DVec3::Y,
            fov_y_deg: 40.0,
            near: 0.01,
        };
        scene
    }

    #[test]
    fn names_parse_back() {
        for f in LightFit::ALL {
            assert_eq!(f.as_str().parse::<LightFit>(), Ok(f));
        }
        assert_eq!(LightFit::default(), LightFit::Scene);
        let e = "tight".parse::<LightFit>().expect_err("unknown");
        assert!(e.to_string().starts_with("--frustum: `tight`"), "{e}");
    }

    /// `scene` is the scene fit as the light computes it, bit for bit, on every scene kind.
    #[test]
    fn scene_is_the_light_fitted_to_the_bounds() {
        for name in ["plane-square", "cage", "spot-spheres"] {
            let scene = scenes::load(name).expect("built-in");
            let g = gbuffer(&scene, 64, 48);
            for res in [1, 256, 1024] {
                let want = scene.light.projector(scene.bounds(), res);
                assert_eq!(fit(&scene, &g, res, LightFit::Scene), want, "{name} at {res}");
            }
        }
    }

    /// `view` holds every covered sample's projection inside the map, with texels no larger
    /// than the scene fit's (strictly smaller where the view sees part of the scene), and the
    /// same depths.
    #[test]
    fn view_holds_every_visible_sample_with_smaller_texels() {
        for scene in [scenes::load("cage").expect("built-in"), close_cage()] {
            let g = gbuffer(&scene, 96, 72);
            let res = 512;
            let whole = fit(&scene, &g, res, LightFit::Scene);
            for policy in [LightFit::View, LightFit::ViewSnapped] {
                let view = fit(&scene, &g, res, policy);
                for k in (0..g.triangle.len()).filter(|&k| g.covered(k)) {
                    let (xy, depth) = view.project(g.position[k]).expect("projects");
                    let r = f64::from(res);
                    assert!(xy.cmpge(DVec2::ZERO).all() && xy.cmple(DVec2::splat(r)).all(), "{xy}");
                    let want = whole.depth_of(g.position[k]);
                    assert!((depth - want).abs() <= 1e-12 * want.abs().max(1.0), "{depth} {want}");
                }
                if policy == LightFit::View {
                    let (v, s) = (half_sizes(&view), half_sizes(&whole));
                    assert!(v.cmple(s).all(), "{v} vs {s}");
                }
            }
        }
        let scene = close_cage();
        let g = gbuffer(&scene, 96, 72);
        let (v, s) = (
            half_sizes(&fit(&scene, &g, 512, LightFit::View)),
            half_sizes(&fit(&scene, &g, 512, LightFit::Scene)),
        );
        eprintln!("close cage: view half sizes {v}, scene {s}");
        assert!(v.x < 0.5 * s.x && v.y < 0.5 * s.y, "{v} vs {s}");
    }

    /// Two cameras a fraction of a texel apart: the snapped maps have equal texels whose
    /// centres coincide (origins a whole number of texels apart), where the plain view fit's
    /// do not.
    #[test]
    fn snapped_maps_move_by_whole_texels() {
        let a = close_cage();
        let res = 256;
        let first = fit(&a, &gbuffer(&a, 96, 72), res, LightFit::ViewSnapped);
        let texel = 2.0 * half_sizes(&first) / f64::from(res);
        let mut plain_moved_by_a_fraction = false;
        for shift in [0.31, 0.5, 1.37, 7.77] {
            let mut b = a.clone();
            let Camera::Perspective { eye, target, .. } = &mut b.camera else { unreachable!() };
            let step = first.right * (shift * texel.x) + first.up * (0.6 * shift * texel.y);
            *eye += step;
            *target += step;
            let second = fit(&b, &gbuffer(&b, 96, 72), res, LightFit::ViewSnapped);
            assert_eq!(half_sizes(&second), half_sizes(&first), "shift {shift}");
            let moved = second.origin - first.origin;
            let texels = DVec2::new(moved.dot(first.right), moved.dot(first.up)) / texel;
            eprintln!("shift {shift}: the snapped map moved by {texels} texels");
            assert!((texels - texels.round()).abs().max_element() < 1e-6, "{shift}: {texels}");
            // A point both maps hold lands at the same place within its texel.
            let p = first.ray(DVec2::splat(0.5 * f64::from(res))).at(3.0);
            let (x, y) = (first.project(p).expect("in").0, second.project(p).expect("in").0);
            assert!(((x - y) - (x - y).round()).abs().max_element() < 1e-6, "{x} {y}");
            let (pa, pb) = (
                fit(&a, &gbuffer(&a, 96, 72), res, LightFit::View),
                fit(&b, &gbuffer(&b, 96, 72), res, LightFit::View),
            );
            let moved = (pb.origin - pa.origin).dot(pa.right) / texel.x;
            plain_moved_by_a_fraction |= (moved - moved.round()).abs() > 0.05;
        }
        assert!(plain_moved_by_a_fraction, "the unsnapped fit moved by whole texels as well");
        // The texel size is the scene fit's times a power of two.
        let whole = half_sizes(&fit(&a, &gbuffer(&a, 96, 72), res, LightFit::Scene));
        for ratio in (half_sizes(&first) / whole).to_array() {
            assert_eq!(ratio.log2().fract(), 0.0, "{ratio}");
        }
    }

    #[test]
    fn spot_lights_keep_their_own_frustum() {
        let scene = scenes::load("spot-spheres").expect("built-in");
        assert!(matches!(scene.light, Light::Spot { .. }));
        let g = gbuffer(&scene, 64, 48);
        let want = fit(&scene, &g, 512, LightFit::Scene);
        for policy in LightFit::ALL {
            assert_eq!(fit(&scene, &g, 512, policy), want, "{}", policy.as_str());
        }
    }

    /// A camera that sees nothing, and a one-texel snapped map, give the scene fit.
    #[test]
    fn without_a_visible_sample_the_view_fits_fall_back_to_the_scene() {
        let mut scene = scenes::load("plane-square").expect("built-in");
        scene.camera = Camera::Perspective {
            eye: DVec3::new(0.0, 5.0, 0.0),
            target: DVec3::new(0.0, 10.0, 0.0),
            up: DVec3::Z,
            fov_y_deg: 30.0,
            near: 0.01,
        };
        let g = gbuffer(&scene, 32, 24);
        assert!((0..g.triangle.len()).all(|k| !g.covered(k)));
        let want = fit(&scene, &g, 256, LightFit::Scene);
        for policy in LightFit::ALL {
            assert_eq!(fit(&scene, &g, 256, policy), want, "{}", policy.as_str());
        }
        let seen = gbuffer(&close_cage(), 32, 24);
        let cage = close_cage();
        assert_eq!(
            fit(&cage, &seen, 1, LightFit::ViewSnapped),
            fit(&cage, &seen, 1, LightFit::Scene)
        );
        assert_ne!(fit(&cage, &seen, 1, LightFit::View), fit(&cage, &seen, 1, LightFit::Scene));
    }

    #[test]
    fn powers_of_two_cover_what_is_needed() {
        for (need, unit, want) in
            [(1.0, 1.0, 1.0), (1.1, 1.0, 2.0), (0.3, 1.0, 0.5), (0.25, 1.0, 0.25), (3.0, 0.75, 3.0)]
        {
            assert_eq!(power_of_two_multiple(need, unit), want, "{need} {unit}");
        }
    }
}
