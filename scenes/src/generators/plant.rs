//! `plant`: many thin, folded leaves around thin stems.
//!
//! Stands for the plant of Pan et al. 2009, Fig. 12(c): the "many thin features" case, where
//! most shadow detail is narrower than a shadow-map texel. `stems` thin stems grow from the
//! ground near the origin, curving gently outward; the first reaches exactly `height`, the
//! others 60–100 % of it. `leaves` leaves hang off random points of the stems (from a fifth of
//! a stem's height up) with random azimuth, elevation (-30° to +50°), droop and roll.
//!
//! A leaf is a strip of two quads along its midrib (base, middle, tip), folded at the middle
//! by the droop: 6 vertices and 4 triangles, open, its front facing up when unrolled. Its
//! widest part (the middle) is `leaf_width`; the base is 40 % and the tip 20 % of that. A
//! stem is a closed square tube of 8 segments with capped ends: watertight, normals out,
//! 72 triangles, its bottom cap on the ground.
//!
//! Layout and invariants: the stems come first (`72 * stems` triangles), then the leaves
//! (`4 * leaves` triangles): 1960 triangles at the defaults. No vertex is below the ground
//! (a leaf that would dip below it is rebuilt pointing up).

use super::rng::{sin_cos, Rng};
use super::{count_at_least, positive, push_tube, triangle_budget, Generator, ParamError};
use crate::mesh::Mesh;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Segments along a stem.
const STEM_SEGMENTS: u32 = 8;
/// Sides of a stem's cross-section.
const STEM_SIDES: u32 = 4;
/// Triangles of one stem: the tube and its two capping fans.
pub const TRIANGLES_PER_STEM: u64 = 2 * (STEM_SIDES * STEM_SEGMENTS + STEM_SIDES) as u64;
/// Triangles of one leaf.
pub const TRIANGLES_PER_LEAF: u64 = 4;

/// Parameters of the `plant` generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlantParams {
    /// Number of leaves. Default 400.
    pub leaves: u32,
    /// Length of a leaf from base to tip, in world units. Default 0.8.
    pub leaf_length: f64,
    /// Width of a leaf at its widest (the middle), in world units. Default 0.08.
    pub leaf_width: f64,
    /// Height of the tallest stem, in world units. Default 4.
    pub height: f64,
    /// Number of stems. Default 5.
    pub stems: u32,
    /// Side of a stem's square cross-section, in world units. Default 0.04.
    pub stem_width: f64,
    /// Random seed. Default 1.
    pub seed: u64,
}

impl Default for PlantParams {
    fn default() -> Self {
        Self {
            leaves: 400,
            leaf_length: 0.8,
            leaf_width: 0.08,
            height: 4.0,
            stems: 5,
            stem_width: 0.04,
            seed: 1,
        }
    }
}

/// A stem: `point(t) = base + height * (t * up + t² * lean)` for t in [0, 1].
struct Stem {
    base: DVec3,
    height: f64,
    lean: DVec3,
}

impl Stem {
    fn point(&self, t: f64) -> DVec3 {
        self.base + self.height * (t * DVec3::Y + t * t * self.lean)
    }

    fn tangent(&self, t: f64) -> DVec3 {
        (DVec3::Y + 2.0 * t * self.lean).normalize()
    }
}

impl Generator for PlantParams {
    /// The number of triangles [`Generator::generate`] builds: `72 * stems + 4 * leaves`.
    fn triangle_count(&self) -> u64 {
        TRIANGLES_PER_STEM * u64::from(self.stems) + TRIANGLES_PER_LEAF * u64::from(self.leaves)
    }

    fn validate(&self) -> Result<(), ParamError> {
        count_at_least("leaves", self.leaves, 1)?;
        triangle_budget("leaves", self.triangle_count())?;
        positive("leaf_length", self.leaf_length)?;
        positive("leaf_width", self.leaf_width)?;
        positive("height", self.height)?;
        count_at_least("stems", self.stems, 1)?;
        positive("stem_width", self.stem_width)?;
        if self.stem_width >= self.height {
            return Err(ParamError::new(
                "stem_width",
                format!("{} must be below height ({})", self.stem_width, self.height),
            ));
        }
        Ok(())
    }

    fn generate(&self) -> Mesh {
        if self.validate().is_err() {
            return Mesh::default();
        }
        let mut rng = Rng::new(self.seed);
        let stems: Vec<Stem> = (0..self.stems)
            .map(|i| {
                let azimuth = TAU * (f64::from(i) + rng.range(-0.3, 0.3)) / f64::from(self.stems);
                let (s, c) = sin_cos(azimuth);
                let outward = DVec3::new(c, 0.0, s);
                let spread = if self.stems == 1 { 0.0 } else { rng.range(0.03, 0.12) };
                let tall = if i == 0 { 1.0 } else { rng.range(0.6, 1.0) };
                Stem {
                    base: spread * self.height * outward,
                    height: tall * self.height,
                    lean: rng.range(0.05, 0.35) * outward,
                }
            })
            .collect();
        let mut mesh = Mesh {
            positions: Vec::with_capacity(
                self.stems as usize * (STEM_SIDES * (STEM_SEGMENTS + 1) + 2) as usize
                    + 6 * self.leaves as usize,
            ),
            triangles: Vec::with_capacity(self.triangle_count() as usize),
        };
        // A square of side w has circumradius w / √2.
        let tube_radius = self.stem_width * std::f64::consts::FRAC_1_SQRT_2;
        for stem in &stems {
            let ts: Vec<f64> =
                (0..=STEM_SEGMENTS).map(|k| f64::from(k) / f64::from(STEM_SEGMENTS)).collect();
            let points: Vec<DVec3> = ts.iter().map(|&t| stem.point(t)).collect();
            let tangents: Vec<DVec3> = ts.iter().map(|&t| stem.tangent(t)).collect();
            push_tube(&mut mesh, &points, &tangents, tube_radius, STEM_SIDES, true);
        }
        for _ in 0..self.leaves {
            let stem = &stems[rng.below(self.stems) as usize];
            let base = stem.point(rng.range(0.2, 1.0));
            let leaf = Leaf {
                azimuth: rng.range(0.0, TAU),
                elevation: rng.range(-0.52, 0.87),
                droop: rng.range(0.0, 0.5),
                roll: rng.range(-0.6, 0.6),
            };
            let mut corners = leaf.corners(base, self.leaf_length, self.leaf_width);
            if corners.iter().any(|p| p.y < 0.0) {
                let up = Leaf { elevation: leaf.elevation.abs(), droop: 0.0, roll: 0.0, ..leaf };
                corners = up.corners(base, self.leaf_length, self.leaf_width);
            }
            let v = mesh.positions.len() as u32;
            mesh.positions.extend_from_slice(&corners);
            // Corners: base -, base +, middle -, middle +, tip -, tip +.
            mesh.triangles.extend_from_slice(&[
                [v, v + 1, v + 3],
                [v, v + 3, v + 2],
                [v + 2, v + 3, v + 5],
                [v + 2, v + 5, v + 4],
            ]);
        }
        mesh
    }
}

/// A leaf's orientation (radians).
#[derive(Clone, Copy)]
struct Leaf {
    azimuth: f64,
    elevation: f64,
    droop: f64,
    roll: f64,
}

impl Leaf {
    /// The six corners: base, middle and tip rows, each `-` then `+` side.
    fn corners(&self, base: DVec3, length: f64, width: f64) -> [DVec3; 6] {
        let (sa, ca) = sin_cos(self.azimuth);
        let direction = |elevation: f64| {
            let (se, ce) = sin_cos(elevation);
            DVec3::new(ce * ca, se, ce * sa)
        };
        let first = direction(self.elevation);
        let second = direction(self.elevation - self.droop);
        // Horizontal side direction, then rolled about the first half's midrib.
        let flat = DVec3::new(-sa, 0.0, ca);
        let (sr, cr) = sin_cos(self.roll);
        let side = cr * flat + sr * first.cross(flat);
        let middle = base + 0.5 * length * first;
        let tip = middle + 0.5 * length * second;
        let row = |p: DVec3, fraction: f64| {
            let half = 0.5 * fraction * width * side;
            [p - half, p + half]
        };
        let [b0, b1] = row(base, 0.4);
        let [m0, m1] = row(middle, 1.0);
        let [t0, t1] = row(tip, 0.2);
        [b0, b1, m0, m1, t0, t1]
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::{assert_watertight, bit_identical, signed_volume6};
    use super::*;

    #[test]
    fn counts_and_layout_are_as_documented() {
        let p = PlantParams::default();
        let mesh = p.generate();
        assert_eq!(TRIANGLES_PER_STEM, 72);
        assert_eq!(mesh.triangle_count(), 1960);
        assert_eq!(mesh.triangle_count() as u64, p.triangle_count());
        let stems = 72 * 5;
        assert_watertight(&mesh, 0..stems);
        for s in 0..5 {
            assert!(signed_volume6(&mesh, 72 * s..72 * (s + 1)) > 0.0);
        }
        let (lo, hi) = mesh.bounds().expect("vertices");
        assert!(lo.y >= 0.0 && hi.y < 4.0 + 0.8, "{lo} {hi}");
        assert!(lo.x > -5.0 && lo.z > -5.0 && hi.x < 5.0 && hi.z < 5.0, "{lo} {hi}");
    }

    #[test]
    fn leaves_are_thin_and_face_up_when_flat() {
        let leaf = Leaf { azimuth: 0.3, elevation: 0.0, droop: 0.0, roll: 0.0 };
        let c = leaf.corners(DVec3::new(0.0, 1.0, 0.0), 0.8, 0.08);
        assert!(c.iter().all(|p| (p.y - 1.0).abs() < 1e-15));
        assert!(((c[3] - c[2]).length() - 0.08).abs() < 1e-15);
        assert!((c[1] - c[0]).cross(c[3] - c[0]).y > 0.0);
        let mesh = PlantParams { leaves: 50, stems: 2, ..Default::default() }.generate();
        let leaves =
            Mesh { positions: mesh.positions.clone(), triangles: mesh.triangles[144..].to_vec() };
        let area = leaves.area();
        // Each leaf is about (0.4 + 2 * 1 + 0.2) / 4 * 0.08 * 0.8 = 0.0416 square units.
        assert!((area / 50.0 - 0.0416).abs() < 0.002, "{area}");
    }

    #[test]
    fn seeds_decide_the_plant() {
        let p = PlantParams { leaves: 30, ..Default::default() };
        assert!(bit_identical(&p.generate(), &p.generate()));
        assert_ne!(p.generate(), PlantParams { seed: 2, ..p.clone() }.generate());
    }

    #[test]
    fn validation_names_the_key() {
        let bad = |p: PlantParams| p.validate().expect_err("invalid").key;
        let d = PlantParams::default;
        assert_eq!(bad(PlantParams { leaves: 0, ..d() }), "leaves");
        assert_eq!(bad(PlantParams { leaves: u32::MAX, ..d() }), "leaves");
        assert_eq!(bad(PlantParams { leaf_length: 0.0, ..d() }), "leaf_length");
        assert_eq!(bad(PlantParams { leaf_width: f64::NAN, ..d() }), "leaf_width");
        assert_eq!(bad(PlantParams { height: -4.0, ..d() }), "height");
        assert_eq!(bad(PlantParams { stems: 0, ..d() }), "stems");
        assert_eq!(bad(PlantParams { stem_width: 5.0, ..d() }), "stem_width");
    }
}
