//! The camera G-buffer: per pixel, the nearest triangle, its depth, the world position where
//! the pixel centre's ray meets it, and its face normal.
//!
//! Positions are computed as `ray(centre).at(depth)` with the depth from the ray-plane
//! intersection, so they reproject to their pixel centres up to `f64` rounding. Normals are
//! the rasterizer's own (the plane it intersects), written where a triangle wins a pixel.

use crate::raster::{rasterize_nearest_with_normals, NO_TRIANGLE};
use glam::{DVec2, DVec3};
use instrumentation::Counters;
use rayon::prelude::*;
use scenes::{Geometry, Projector};

/// Per-pixel surface data seen by the camera.
#[derive(Debug, Clone, PartialEq)]
pub struct GBuffer {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Nearest triangle per pixel, [`NO_TRIANGLE`] for background.
    pub triangle: Vec<u32>,
    /// Depth along the camera's forward axis (`f64::INFINITY` for background).
    pub depth: Vec<f64>,
    /// World position at the pixel centre (zero for background).
    pub position: Vec<DVec3>,
    /// Unit face normal of the triangle as wound (zero for background).
    pub normal: Vec<DVec3>,
}

impl GBuffer {
    /// Whether pixel `k` sees a surface.
    #[inline]
    pub fn covered(&self, k: usize) -> bool {
        self.triangle[k] != NO_TRIANGLE
    }
}

/// Renders the G-buffer of all triangles of `geometry` through the camera projector.
pub fn render_gbuffer(geometry: &Geometry, camera: &Projector, counters: &mut Counters) -> GBuffer {
    let (w, h) = (camera.width as usize, camera.height as usize);
    // Filled in parallel: 11 MB at 800 x 600.
    let mut normal = Vec::with_capacity(w * h);
    normal.par_extend(rayon::iter::repeat_n(DVec3::ZERO, w * h));
    let nearest = rasterize_nearest_with_normals(geometry, camera, &mut normal, counters);
    let position = nearest
        .triangle
        .par_iter()
        .zip(&nearest.depth)
        .enumerate()
        .map(|(k, (&t, &d))| {
            if t == NO_TRIANGLE {
                return DVec3::ZERO;
            }
            let centre = DVec2::new((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
            camera.ray(centre).at(d)
        })
        .collect();
    GBuffer {
        width: nearest.width,
        height: nearest.height,
        triangle: nearest.triangle,
        depth: nearest.depth,
        position,
        normal,
    }
}
