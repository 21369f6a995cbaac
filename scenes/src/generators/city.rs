//! `city`: a grid of closed boxes of random heights, separated by streets.
//!
//! A `blocks` x `blocks` grid over the 10 x 10 footprint centred on the origin: each cell of
//! side `10 / blocks` holds one box standing on the ground (y from 0 to a height uniform in
//! `[min_height, max_height]`), inset by half a `street_width` on every side, so neighbouring
//! boxes are `street_width` apart. Long, straight shadow edges over flat streets: the case of
//! grazing light and of shadow-edge staircase artefacts.
//!
//! Invariants: `blocks²` boxes, each a separate closed box (bottom face included) of 8
//! vertices and 12 triangles, watertight, normals out: `12 * blocks²` triangles (768 at the
//! defaults). Boxes are emitted row by row (z, then x).

use super::rng::Rng;
use super::{
    at_least, count_at_least, non_negative, positive, push_box, triangle_budget, Generator,
    ParamError, FOOTPRINT,
};
use crate::mesh::Mesh;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Parameters of the `city` generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CityParams {
    /// Boxes along each side of the 10 x 10 footprint. Default 8.
    pub blocks: u32,
    /// Lowest box height, in world units. Default 0.5.
    pub min_height: f64,
    /// Highest box height, in world units. Default 4.
    pub max_height: f64,
    /// Gap between neighbouring boxes, in world units (0 makes them touch). Default 0.4.
    pub street_width: f64,
    /// Random seed. Default 1.
    pub seed: u64,
}

impl Default for CityParams {
    fn default() -> Self {
        Self { blocks: 8, min_height: 0.5, max_height: 4.0, street_width: 0.4, seed: 1 }
    }
}

impl Generator for CityParams {
    /// The number of triangles [`Generator::generate`] builds: `12 * blocks²` (saturating).
    fn triangle_count(&self) -> u64 {
        (u64::from(self.blocks) * u64::from(self.blocks)).saturating_mul(12)
    }

    fn validate(&self) -> Result<(), ParamError> {
        count_at_least("blocks", self.blocks, 1)?;
        triangle_budget("blocks", self.triangle_count())?;
        positive("min_height", self.min_height)?;
        at_least("max_height", self.max_height, self.min_height, "min_height")?;
        non_negative("street_width", self.street_width)?;
        let pitch = FOOTPRINT / f64::from(self.blocks);
        if self.street_width >= pitch {
            return Err(ParamError::new(
                "street_width",
                format!(
                    "{} leaves no room for the boxes; it must be below 10 / blocks = {pitch}",
                    self.street_width
                ),
            ));
        }
        Ok(())
    }

    fn generate(&self) -> Mesh {
        if self.validate().is_err() {
            return Mesh::default();
        }
        let n = self.blocks;
        let mut rng = Rng::new(self.seed);
        let edge = |i: u32| FOOTPRINT * (f64::from(i) / f64::from(n) - 0.5);
        let half_street = 0.5 * self.street_width;
        let mut mesh = Mesh {
            positions: Vec::with_capacity(8 * (n * n) as usize),
            triangles: Vec::with_capacity(self.triangle_count() as usize),
        };
        for j in 0..n {
            for i in 0..n {
                let height = rng.range(self.min_height, self.max_height);
                let min = DVec3::new(edge(i) + half_street, 0.0, edge(j) + half_street);
                let max = DVec3::new(edge(i + 1) - half_street, height, edge(j + 1) - half_street);
                push_box(&mut mesh, min, max);
            }
        }
        mesh
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::{assert_watertight, bit_identical, signed_volume6};
    use super::*;

    #[test]
    fn boxes_are_closed_outward_and_in_range() {
        let p = CityParams::default();
        let mesh = p.generate();
        assert_eq!(mesh.triangle_count(), 768);
        assert_eq!(mesh.triangle_count() as u64, p.triangle_count());
        assert_watertight(&mesh, 0..768);
        let footprint = (1.25 - 0.4) * (1.25 - 0.4);
        for b in 0..64 {
            let volume = signed_volume6(&mesh, 12 * b..12 * b + 12) / 6.0;
            let height = volume / footprint;
            assert!((0.5 - 1e-9..=4.0 + 1e-9).contains(&height), "box {b}: {height}");
        }
        let (lo, hi) = mesh.bounds().expect("vertices");
        assert_eq!(lo.y, 0.0);
        assert!(lo.x >= -5.0 && hi.x <= 5.0 && lo.z >= -5.0 && hi.z <= 5.0 && hi.y <= 4.0);
    }

    #[test]
    fn seeds_decide_the_heights() {
        let p = CityParams { blocks: 3, ..Default::default() };
        assert!(bit_identical(&p.generate(), &p.generate()));
        assert_ne!(p.generate(), CityParams { seed: 5, ..p.clone() }.generate());
    }

    #[test]
    fn validation_names_the_key() {
        let bad = |p: CityParams| p.validate().expect_err("invalid").key;
        let d = CityParams::default;
        assert_eq!(bad(CityParams { blocks: 0, ..d() }), "blocks");
        assert_eq!(bad(CityParams { blocks: 5000, ..d() }), "blocks");
        assert_eq!(bad(CityParams { min_height: 0.0, ..d() }), "min_height");
        assert_eq!(bad(CityParams { max_height: 0.2, ..d() }), "max_height");
        assert_eq!(bad(CityParams { street_width: -0.1, ..d() }), "street_width");
        assert_eq!(bad(CityParams { street_width: 1.25, ..d() }), "street_width");
        assert!(CityParams { street_width: 0.0, ..d() }.validate().is_ok());
    }
}
