//! The camera G-buffer: per pixel, the nearest triangle, its depth, the world position where
//! the pixel centre's ray meets it, and its face normal.
//!
//! Positions are computed as `ray(centre).at(depth)` with the depth from the ray-plane
//! intersection, so they reproject to their pixel centres up to `f64` rounding. Both the
//! positions and the normals (the plane the rasterizer intersects) are the rasterizer's own,
//! written with the depth where a triangle wins a pixel, on the ray that gave the depth.

use crate::raster::{rasterize_nearest_with_surface, NO_TRIANGLE};
use glam::DVec3;
use instrumentation::Counters;
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
    // Zeroed allocations (11 MB each at 800 x 600): the allocator's zero pages are first
    // touched where the raster writes a covered pixel, in its parallel bands. Filling them
    // with zeros first, even in parallel, took 2 of the G-buffer's 18 ms (bunny-plane, two
    // threads).
    let zeros = || bytemuck::zeroed_vec::<DVec3>(w * h);
    let (mut normal, mut position) = (zeros(), zeros());
    let nearest =
        rasterize_nearest_with_surface(geometry, camera, &mut normal, &mut position, counters);
    GBuffer {
        width: nearest.width,
        height: nearest.height,
        triangle: nearest.triangle,
        depth: nearest.depth,
        position,
        normal,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    /// Every covered pixel's position is the camera ray through its centre at its depth, bit
    /// for bit, and its normal its triangle's unit face normal; background pixels hold zeros.
    #[test]
    fn positions_lie_on_the_pixel_rays_at_their_depths() {
        let scene = scenes::load("bunny-plane").expect("built-in");
        let camera = scene.camera.projector(64, 48);
        let geometry = scene.geometry();
        let g = render_gbuffer(&geometry, &camera, &mut Counters::default());
        let mut covered = 0;
        for k in 0..g.triangle.len() {
            let t = g.triangle[k];
            if t == NO_TRIANGLE {
                assert_eq!((g.position[k], g.normal[k]), (DVec3::ZERO, DVec3::ZERO), "pixel {k}");
                continue;
            }
            covered += 1;
            let centre = DVec2::new((k % 64) as f64 + 0.5, (k / 64) as f64 + 0.5);
            assert_eq!(g.position[k], camera.ray(centre).at(g.depth[k]), "pixel {k}");
            let c = geometry.corners(t as usize);
            assert_eq!(g.normal[k], (c[1] - c[0]).cross(c[2] - c[0]).normalize(), "pixel {k}");
        }
        assert!(covered > 1000, "{covered} pixels covered");
    }
}
