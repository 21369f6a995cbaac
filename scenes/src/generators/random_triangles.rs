//! `random_triangles`: a cloud of disconnected random triangles of constant total area.
//!
//! Stands for the scalability scenes of Aila & Laine 2004, Table 1 (1K–1M random triangles):
//! "the sizes of the triangles were adjusted so that their total area is approximately
//! constant in all the scenes". Here the total is exact up to rounding: the triangles are
//! built at unit scale, then all scaled by one factor so that their areas sum to `total_area`.
//!
//! Invariants:
//! - exactly `count` triangles and `3 * count` vertices (no shared vertices; open triangles);
//! - the areas sum to `total_area` (relative error about 1e-12 even at 1M triangles);
//! - no slivers: each triangle's shortest altitude is at least a tenth of its longest edge
//!   (corners at angles 120° apart, each jittered by up to ±20°, at radii in [0.6, 1] of the
//!   triangle's size), sizes vary by a factor of 2 in area, orientations are uniform on the
//!   sphere (so the front face is random);
//! - each triangle lies inside the box of size `extent` centred on the origin in x and z whose
//!   bottom is at `min_height`, whenever it fits in that box (its position is uniform among
//!   the positions where it fits); a triangle larger than the box is centred in x and z and
//!   rests on the box's bottom, so no vertex is ever below `min_height`.

use super::rng::{sin_cos, Rng};
use super::{count_at_least, non_negative, positive, triangle_budget, Generator, ParamError};
use crate::mesh::Mesh;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Parameters of the `random_triangles` generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RandomTrianglesParams {
    /// Number of triangles. Default 1000.
    pub count: u32,
    /// Sum of the triangles' areas, in square world units, whatever `count`. Default 40.
    pub total_area: f64,
    /// Size `[x, y, z]` of the box the triangles are placed in, in world units. Default
    /// `[8, 3, 8]`.
    #[serde(deserialize_with = "crate::arrays::exact")]
    pub extent: [f64; 3],
    /// Height of the box's bottom above the ground, in world units. Default 1.
    pub min_height: f64,
    /// Random seed. Default 1.
    pub seed: u64,
}

impl Default for RandomTrianglesParams {
    fn default() -> Self {
        Self { count: 1000, total_area: 40.0, extent: [8.0, 3.0, 8.0], min_height: 1.0, seed: 1 }
    }
}

impl Generator for RandomTrianglesParams {
    /// The number of triangles [`Generator::generate`] builds: `count`.
    fn triangle_count(&self) -> u64 {
        u64::from(self.count)
    }

    fn validate(&self) -> Result<(), ParamError> {
        count_at_least("count", self.count, 1)?;
        triangle_budget("count", self.triangle_count())?;
        positive("total_area", self.total_area)?;
        for e in self.extent {
            positive("extent", e)?;
        }
        non_negative("min_height", self.min_height)
    }

    fn generate(&self) -> Mesh {
        if self.validate().is_err() {
            return Mesh::default();
        }
        let n = self.count as usize;
        let mut rng = Rng::new(self.seed);
        let mut positions = Vec::with_capacity(3 * n);
        // Pass 1: every triangle at unit scale around the origin, and the sum of their areas
        // (Neumaier-compensated so that the total stays exact to ~1 ulp at 1M triangles).
        let (mut sum, mut compensation) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let normal = rng.unit_vector();
            let (u, v) = normal.any_orthonormal_pair();
            let phase = rng.range(0.0, TAU);
            // Linear size in [0.7, 1]: areas vary by a factor of about 2.
            let size = rng.range(0.7, 1.0);
            let mut corners = [DVec3::ZERO; 3];
            for (k, corner) in corners.iter_mut().enumerate() {
                let angle = phase + TAU * k as f64 / 3.0 + rng.range(-0.35, 0.35);
                let radius = size * rng.range(0.6, 1.0);
                let (s, c) = sin_cos(angle);
                *corner = radius * (c * u + s * v);
            }
            let area = 0.5 * (corners[1] - corners[0]).cross(corners[2] - corners[0]).length();
            let t = sum + area;
            compensation += if sum.abs() >= area { (sum - t) + area } else { (area - t) + sum };
            sum = t;
            positions.extend_from_slice(&corners);
        }
        let scale = (self.total_area / (sum + compensation)).sqrt();
        // Pass 2: scale, then place each triangle uniformly where it fits in the box.
        let [ex, ey, ez] = self.extent;
        let box_min = DVec3::new(-0.5 * ex, self.min_height, -0.5 * ez);
        let box_max = DVec3::new(0.5 * ex, self.min_height + ey, 0.5 * ez);
        for corners in positions.chunks_exact_mut(3) {
            for p in corners.iter_mut() {
                *p *= scale;
            }
            // Bounds by plain comparisons (`f64::min` may pick either zero of ±0 on some
            // platforms; comparisons are the same everywhere).
            let (mut lo, mut hi) = (corners[0], corners[0]);
            for p in &corners[1..] {
                for axis in 0..3 {
                    if p[axis] < lo[axis] {
                        lo[axis] = p[axis];
                    }
                    if p[axis] > hi[axis] {
                        hi[axis] = p[axis];
                    }
                }
            }
            let mut offset = [0.0; 3];
            for (axis, o) in offset.iter_mut().enumerate() {
                let u = rng.next_f64();
                let (from, to) = (box_min[axis] - lo[axis], box_max[axis] - hi[axis]);
                *o = if from <= to {
                    from + (to - from) * u
                } else if axis == 1 {
                    from
                } else {
                    0.5 * (box_min[axis] + box_max[axis]) - 0.5 * (lo[axis] + hi[axis])
                };
            }
            let offset = DVec3::from_array(offset);
            for p in corners.iter_mut() {
                *p += offset;
                // Rounding must not put a vertex an ulp below the box (or the ground).
                if p.y < box_min.y {
                    p.y = box_min.y;
                }
            }
        }
        let triangles = (0..n as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        Mesh { positions, triangles }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::bit_identical;
    use super::*;

    #[test]
    fn count_and_total_area_are_exact() {
        for count in [1, 2, 10, 1000] {
            let p = RandomTrianglesParams { count, ..Default::default() };
            let mesh = p.generate();
            assert_eq!(mesh.triangle_count(), count as usize);
            assert_eq!(mesh.positions.len(), 3 * count as usize);
            let area = mesh.area();
            assert!((area - 40.0).abs() <= 1e-12 * 40.0, "{count}: {area}");
        }
    }

    #[test]
    fn triangles_stay_in_the_box_and_are_not_slivers() {
        let p = RandomTrianglesParams { count: 5000, seed: 9, ..Default::default() };
        let mesh = p.generate();
        let (lo, hi) = mesh.bounds().expect("vertices");
        assert!(lo.cmpge(DVec3::new(-4.0 - 1e-12, 1.0, -4.0 - 1e-12)).all(), "{lo}");
        assert!(hi.cmple(DVec3::splat(4.0 + 1e-12)).all(), "{hi}");
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.corners(t);
            let twice_area = (b - a).cross(c - a).length();
            let longest = (b - a).length().max((c - b).length()).max((a - c).length());
            // Shortest altitude = 2 * area / longest edge.
            assert!(twice_area / longest >= 0.1 * longest, "sliver {t}");
        }
    }

    #[test]
    fn a_triangle_bigger_than_the_box_rests_on_its_bottom() {
        let p = RandomTrianglesParams { count: 1, extent: [0.1, 0.1, 0.1], ..Default::default() };
        let mesh = p.generate();
        let (lo, _) = mesh.bounds().expect("vertices");
        assert!(lo.y >= 1.0 && lo.y - 1.0 < 1e-12, "{lo}");
    }

    #[test]
    fn seeds_decide_the_mesh() {
        let p = RandomTrianglesParams { count: 100, ..Default::default() };
        assert!(bit_identical(&p.generate(), &p.generate()));
        assert_ne!(p.generate(), RandomTrianglesParams { seed: 2, ..p.clone() }.generate());
    }

    #[test]
    fn validation_names_the_key() {
        let bad = |p: RandomTrianglesParams| p.validate().expect_err("invalid").key;
        let d = RandomTrianglesParams::default;
        assert_eq!(bad(RandomTrianglesParams { count: 0, ..d() }), "count");
        assert_eq!(bad(RandomTrianglesParams { count: 20_000_001, ..d() }), "count");
        assert_eq!(bad(RandomTrianglesParams { total_area: -1.0, ..d() }), "total_area");
        assert_eq!(bad(RandomTrianglesParams { extent: [1.0, f64::NAN, 1.0], ..d() }), "extent");
        assert_eq!(bad(RandomTrianglesParams { min_height: -0.1, ..d() }), "min_height");
    }
}
