//! The light depth map: the depth of the nearest shadow caster at every texel centre of an
//! `R x R` map seen from the light (Williams 1978).

use crate::raster::rasterize_nearest;
use instrumentation::Counters;
use scenes::{Geometry, Projector};

/// Nearest caster depth per texel.
#[derive(Debug, Clone, PartialEq)]
pub struct LightDepthMap {
    /// The light's projector onto the map.
    pub projector: Projector,
    /// Map resolution (the map is `res x res`).
    pub res: u32,
    /// Depth of the nearest caster at each texel centre; `f64::INFINITY` where none.
    pub depth: Vec<f64>,
    /// Id of that caster triangle, [`crate::raster::NO_TRIANGLE`] where none.
    pub triangle: Vec<u32>,
}

impl LightDepthMap {
    /// Rasterizes the triangles `is_caster` selects from the light's projector.
    pub fn render(
        geometry: &Geometry,
        is_caster: impl Fn(usize) -> bool + Sync,
        projector: &Projector,
        counters: &mut Counters,
    ) -> Self {
        let nearest = rasterize_nearest(geometry, is_caster, projector, counters);
        Self {
            projector: *projector,
            res: nearest.width,
            depth: nearest.depth,
            triangle: nearest.triangle,
        }
    }

    /// Depth stored at texel `(x, y)`, or `None` outside the map.
    #[inline]
    pub fn texel(&self, x: i64, y: i64) -> Option<f64> {
        let r = i64::from(self.res);
        (x >= 0 && y >= 0 && x < r && y < r).then(|| self.depth[(y * r + x) as usize])
    }
}
