//! Speed measured side by side with Intel Embree, in one process, on the same frame and the
//! same sample points, at the same thread count.
//!
//! The peer is Embree 3 (Debian's `libembree-dev`, 3.13) through the `embree` crate, behind
//! the `embree` cargo feature so that the workspace builds without it
//! (`scripts/install-embree` installs the library; `scripts/embree-bench` runs the benchmark).
//! What Embree is given is what a user would give it: the frame's triangles as `f32` in world
//! coordinates, one scene over every triangle for camera rays and, when some triangle casts no
//! shadow, a second one over the casters for shadow rays; the default build quality.
//!
//! The sample points ([`Samples`]) are the ones our methods use: sub-sample `s` of pixel
//! `(i, j)` of the shared [`methods::pattern::SamplePattern`] (at rate 1 the pixel centre), the
//! camera ray through it from `frame.camera`, and a shadow ray from the camera ray's hit point
//! towards the light (to the spot's position, or unbounded along a directional light), starting
//! at `afsm::shadow_offset`, as `raytrace` and `afsm` start theirs. Embree cannot leave out the
//! hit triangle itself as `raytrace` does, and works in `f32`: its shadow rays start at
//! [`embree_shadow_start`], 64 `f32` epsilons of the point's magnitude out, so that a surface
//! does not shadow itself; a caster nearer than that (a contact shadow) is missed.

#[cfg(feature = "embree")]
pub mod embree_tracer;

use glam::{DVec2, DVec3};
use methods::pattern::SamplePattern;
use methods::Frame;

/// The sub-sample points of a frame at one pattern.
#[derive(Debug, Clone)]
pub struct Samples {
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Sub-samples per pixel.
    pub rate: usize,
    /// Image-plane points, pixel by pixel in row order, each pixel's sub-samples in pattern
    /// order.
    pub points: Vec<DVec2>,
}

impl Samples {
    /// Every sub-sample of `pattern` over `frame`.
    pub fn new(frame: &Frame<'_>, pattern: &SamplePattern) -> Self {
        let (w, h) = (frame.width(), frame.height());
        let rate = pattern.rate() as usize;
        let mut points = Vec::with_capacity(w as usize * h as usize * rate);
        for j in 0..h {
            for i in 0..w {
                points.extend((0..rate).map(|s| pattern.point(i, j, s)));
            }
        }
        Self { width: w, height: h, rate, points }
    }
}

/// The shadow ray from `p` (a camera ray's hit, the camera ray starting at `eye`): its unit
/// direction towards the light, where it starts and where it ends (`None` when the point is at
/// the light or the direction is degenerate).
pub fn shadow_ray(frame: &Frame<'_>, eye: DVec3, p: DVec3) -> Option<(DVec3, f64, f64)> {
    let (dir, tmax) = match frame.scene.light {
        scenes::Light::Directional { direction } => {
            (scenes::direction::unit(-direction)?, f64::INFINITY)
        }
        scenes::Light::Spot { position, .. } => {
            (scenes::direction::unit(position - p)?, (position - p).length())
        }
    };
    let tmin = methods::afsm::shadow_offset(eye, p);
    (tmax > tmin).then_some((dir, tmin, tmax))
}

/// Where Embree's shadow ray from `p` (the camera ray starting at `eye`) starts: at
/// [`shadow_ray`]'s start, or 64 `f32` epsilons of the magnitude of the numbers that made `p`
/// when that is farther. Embree rounds `p` to `f32`, and `afsm`'s offset (1e-10 of that
/// magnitude) is far below `f32`'s precision: without this, a surface would shadow itself.
pub fn embree_shadow_start(eye: DVec3, p: DVec3, tmin: f64) -> f64 {
    let magnitude = eye.abs().max(p.abs()).max_element() + (p - eye).abs().max_element();
    tmin.max(64.0 * f64::from(f32::EPSILON) * magnitude)
}
