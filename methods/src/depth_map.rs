//! The light depth map: the depth of the nearest shadow caster at every texel centre of an
//! `R x R` map seen from the light (Williams 1978).

use crate::raster::rasterize_nearest_at;
use glam::DVec2;
use instrumentation::Counters;
use scenes::{Geometry, Projector};

/// Nearest caster depth per texel.
#[derive(Debug, Clone, PartialEq)]
pub struct LightDepthMap {
    /// The light's projector onto the map.
    pub projector: Projector,
    /// Map resolution (the map is `res x res`).
    pub res: u32,
    /// Where the samples lie: texel `(i, j)` holds the depth at image point
    /// `(i + 0.5 + shift.x, j + 0.5 + shift.y)`; zero for the texel centres.
    pub shift: DVec2,
    /// Depth of the nearest caster at each texel's sample point; `f64::INFINITY` where none.
    pub depth: Vec<f64>,
    /// Id of that caster triangle, [`crate::raster::NO_TRIANGLE`] where none.
    pub triangle: Vec<u32>,
}

impl LightDepthMap {
    /// Rasterizes the triangles `is_caster` selects from the light's projector, sampling at the
    /// texel centres moved by `shift` (a jittered image plane; zero for the plain map).
    pub fn render(
        geometry: &Geometry,
        is_caster: impl Fn(usize) -> bool + Sync,
        projector: &Projector,
        shift: DVec2,
        counters: &mut Counters,
    ) -> Self {
        let nearest = rasterize_nearest_at(geometry, is_caster, projector, shift, counters);
        Self {
            projector: *projector,
            shift,
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

    /// A map holding `depth` (row by row, `res x res`) under a unit orthographic light looking
    /// down `-z`, for unit tests of the filters.
    #[cfg(test)]
    pub(crate) fn from_depths(depth: Vec<f64>, res: u32) -> Self {
        use scenes::projection::{look_basis, ProjectionKind};
        let (right, up, forward) = look_basis(-glam::DVec3::Z, glam::DVec3::Y);
        let projector = Projector {
            origin: glam::DVec3::ZERO,
            right,
            up,
            forward,
            kind: ProjectionKind::Orthographic { half_width: 1.0, half_height: 1.0 },
            near: f64::NEG_INFINITY,
            width: f64::from(res),
            height: f64::from(res),
        };
        let triangle = vec![crate::raster::NO_TRIANGLE; depth.len()];
        Self { projector, res, shift: DVec2::ZERO, depth, triangle }
    }
}
