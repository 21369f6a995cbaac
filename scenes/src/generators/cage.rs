//! `cage`: a box-shaped cage of thin square bars.
//!
//! Stands for the cage scene of Pan et al. 2009, Fig. 11, whose thin bars cast shadows that
//! shadow maps miss at low sample rates. The cage's outer bounds are exactly the box
//! `size` (x, y, z), centred on the origin in x and z, with its bottom at
//! `height_above_ground`. Each of its six faces carries a square grid of `bars_per_side` bars
//! in each direction, the two outermost being the box's edges; a bar spans the cage's full
//! length, so bars cross (overlap) at the joints.
//!
//! Invariants:
//! - every bar is a separate closed box of square cross-section `bar_width`: 8 vertices and 12
//!   triangles, watertight, normals out (the bars overlap at joints but share no vertices);
//! - bars on the surface of an n-bar grid: `4 (n - 1)` bars along each axis, `12 (n - 1)` in
//!   all, `144 (n - 1)` triangles (1584 at the defaults);
//! - neighbouring parallel bars never touch (validation requires
//!   `bar_width < min(size) / bars_per_side`), so light passes between them.

use super::{
    count_at_least, non_negative, positive, push_box, triangle_budget, Generator, ParamError,
};
use crate::mesh::Mesh;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Parameters of the `cage` generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CageParams {
    /// Outer size `[x, y, z]` of the cage, in world units. Default `[4, 4, 4]`.
    #[serde(deserialize_with = "crate::arrays::exact")]
    pub size: [f64; 3],
    /// Bars across each face in each direction, counting the two edge bars (at least 2).
    /// Default 12.
    pub bars_per_side: u32,
    /// Side of a bar's square cross-section, in world units. Default 0.03.
    pub bar_width: f64,
    /// Height of the cage's bottom above the ground, in world units. Default 1.
    pub height_above_ground: f64,
}

impl Default for CageParams {
    fn default() -> Self {
        Self { size: [4.0, 4.0, 4.0], bars_per_side: 12, bar_width: 0.03, height_above_ground: 1.0 }
    }
}

impl CageParams {
    /// The number of bars: `12 * (bars_per_side - 1)`.
    pub fn bar_count(&self) -> u64 {
        12 * u64::from(self.bars_per_side.saturating_sub(1))
    }
}

impl Generator for CageParams {
    /// The number of triangles [`Generator::generate`] builds: 12 per bar.
    fn triangle_count(&self) -> u64 {
        12 * self.bar_count()
    }

    fn validate(&self) -> Result<(), ParamError> {
        for s in self.size {
            positive("size", s)?;
        }
        count_at_least("bars_per_side", self.bars_per_side, 2)?;
        triangle_budget("bars_per_side", self.triangle_count())?;
        positive("bar_width", self.bar_width)?;
        let smallest = self.size.iter().fold(f64::INFINITY, |m, &s| m.min(s));
        let widest = smallest / f64::from(self.bars_per_side);
        if self.bar_width >= widest {
            return Err(ParamError::new(
                "bar_width",
                format!(
                    "{} would make neighbouring bars touch; it must be below \
                     min(size) / bars_per_side = {widest}",
                    self.bar_width
                ),
            ));
        }
        non_negative("height_above_ground", self.height_above_ground)
    }

    fn generate(&self) -> Mesh {
        if self.validate().is_err() {
            return Mesh::default();
        }
        let n = self.bars_per_side;
        let w = self.bar_width;
        let lo = DVec3::new(-0.5 * self.size[0], self.height_above_ground, -0.5 * self.size[2]);
        let hi = lo + DVec3::from_array(self.size);
        // Centre of grid line `k` along `axis`: the outermost lines are inset by half a bar.
        let line = |axis: usize, k: u32| {
            lo[axis] + 0.5 * w + (hi[axis] - lo[axis] - w) * f64::from(k) / f64::from(n - 1)
        };
        let mut mesh = Mesh {
            positions: Vec::with_capacity(8 * self.bar_count() as usize),
            triangles: Vec::with_capacity(self.triangle_count() as usize),
        };
        for along in 0..3 {
            let (a, b) = ((along + 1) % 3, (along + 2) % 3);
            for j in 0..n {
                for k in 0..n {
                    let on_surface = j == 0 || j == n - 1 || k == 0 || k == n - 1;
                    if !on_surface {
                        continue;
                    }
                    let (mut min, mut max) = (lo, hi);
                    let (ca, cb) = (line(a, j), line(b, k));
                    min[a] = ca - 0.5 * w;
                    max[a] = ca + 0.5 * w;
                    min[b] = cb - 0.5 * w;
                    max[b] = cb + 0.5 * w;
                    push_box(&mut mesh, min, max);
                }
            }
        }
        mesh
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::{assert_watertight, signed_volume6};
    use super::*;

    #[test]
    fn default_cage_has_the_documented_bars() {
        let p = CageParams::default();
        let mesh = p.generate();
        assert_eq!(p.bar_count(), 132);
        assert_eq!(mesh.triangle_count(), 1584);
        assert_eq!(mesh.triangle_count() as u64, p.triangle_count());
        let (lo, hi) = mesh.bounds().expect("vertices");
        assert!((lo - DVec3::new(-2.0, 1.0, -2.0)).abs().max_element() < 1e-12, "{lo}");
        assert!((hi - DVec3::new(2.0, 5.0, 2.0)).abs().max_element() < 1e-12, "{hi}");
    }

    #[test]
    fn every_bar_is_a_closed_outward_box() {
        let p = CageParams { size: [2.0, 3.0, 1.0], bars_per_side: 4, ..Default::default() };
        let mesh = p.generate();
        assert_eq!(mesh.triangle_count(), 12 * 12 * 3);
        assert_watertight(&mesh, 0..mesh.triangle_count());
        for bar in 0..p.bar_count() as usize {
            let volume = signed_volume6(&mesh, 12 * bar..12 * bar + 12) / 6.0;
            let [a, b, c] = [0.03f64, 0.03, 1.0];
            assert!(volume > 0.0 && volume <= a * b * c * 3.0 + 1e-12, "bar {bar}: {volume}");
        }
    }

    #[test]
    fn the_smallest_cage_is_its_twelve_edges() {
        let mesh = CageParams { bars_per_side: 2, ..Default::default() }.generate();
        assert_eq!(mesh.triangle_count(), 12 * 12);
    }

    #[test]
    fn validation_names_the_key() {
        let bad = |p: CageParams| p.validate().expect_err("invalid").key;
        let d = CageParams::default;
        assert_eq!(bad(CageParams { size: [4.0, 0.0, 4.0], ..d() }), "size");
        assert_eq!(bad(CageParams { bars_per_side: 1, ..d() }), "bars_per_side");
        assert_eq!(bad(CageParams { bars_per_side: 10_000_000, ..d() }), "bars_per_side");
        assert_eq!(bad(CageParams { bar_width: 0.0, ..d() }), "bar_width");
        assert_eq!(bad(CageParams { bar_width: 0.4, ..d() }), "bar_width");
        assert_eq!(bad(CageParams { height_above_ground: f64::NAN, ..d() }), "height_above_ground");
    }
}
