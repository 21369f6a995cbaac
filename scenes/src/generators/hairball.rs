//! `hairball`: thin hairs leaving the surface of a sphere.
//!
//! Stands for the self-shadowing hair ball of Aila & Laine 2004, Fig. 1 ("5000 hairs, each made
//! of 576 triangles ... semi-transparent shadow casters with opacity of 10%"). The opacity is
//! not geometry: the hairball is meant to be rendered with a material of opacity 0.1, which the
//! scene sets. The paper's ball is `strands = 5000, segments = 96, sides = 3` (576 triangles a
//! hair, 2.88 M in all); the default is a tenth of the hairs at a quarter of the segments.
//!
//! Each hair starts at a uniformly random point of the sphere of `radius` centred at
//! `(0, center_height, 0)` (the sphere itself is not part of the mesh), leaves it outward
//! (within about 27° of the surface normal), and follows a random curved path of total length
//! `length` in `segments` equal steps: it bends steadily towards a random side (0.3 to 1.5
//! radians over the hair) with a little random wiggle at every step.
//!
//! The hair's cross-section depends on `sides`:
//! - `sides >= 3`: an open tube (no end caps) of diameter `thickness` with `sides` sides:
//!   `2 * sides * segments` triangles a hair, normals out, vertices in rings of `sides`;
//! - `sides == 2`: a flat ribbon of width `thickness`: `2 * segments` triangles a hair.
//!
//! Invariants: `strands` times the triangles of a hair above (72 000 at the
//! defaults); hairs are emitted one after the other, each with the same vertex count; no vertex
//! is below the ground (validation requires `center_height >= radius + length`, and the few
//! vertices a tube's radius could push below y = 0 are clamped to it).

use super::rng::Rng;
use super::{
    at_least, count_at_least, polyline_tangents, positive, push_tube, transported_frames,
    triangle_budget, Generator, ParamError,
};
use crate::mesh::Mesh;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// The most sides a hair's cross-section may have.
pub const MAX_SIDES: u32 = 64;

/// Parameters of the `hairball` generator. Render it with opacity 0.1 (Aila & Laine 2004).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HairballParams {
    /// Number of hairs. Default 500.
    pub strands: u32,
    /// Segments along each hair. Default 24.
    pub segments: u32,
    /// Sides of a hair's cross-section: 2 for a flat ribbon, 3 to 64 for an open tube.
    /// Default 3.
    pub sides: u32,
    /// Radius of the sphere the hairs grow from, in world units. Default 1.5.
    pub radius: f64,
    /// Height of that sphere's centre above the ground, in world units (at least
    /// `radius + length`). Default 3.
    pub center_height: f64,
    /// Length of a hair along its path, in world units. Default 1.5.
    pub length: f64,
    /// Diameter of a hair (ribbon width when `sides = 2`), in world units. Default 0.01.
    pub thickness: f64,
    /// Random seed. Default 1.
    pub seed: u64,
}

impl Default for HairballParams {
    fn default() -> Self {
        Self {
            strands: 500,
            segments: 24,
            sides: 3,
            radius: 1.5,
            center_height: 3.0,
            length: 1.5,
            thickness: 0.01,
            seed: 1,
        }
    }
}

impl HairballParams {
    /// Triangles of one hair: `2 * segments * sides` for a tube, `2 * segments` for a ribbon.
    pub fn triangles_per_strand(&self) -> u64 {
        let around = if self.sides == 2 { 1 } else { u64::from(self.sides) };
        2 * u64::from(self.segments) * around
    }
}

impl Generator for HairballParams {
    /// The number of triangles [`Generator::generate`] builds.
    fn triangle_count(&self) -> u64 {
        u64::from(self.strands).saturating_mul(self.triangles_per_strand())
    }

    fn validate(&self) -> Result<(), ParamError> {
        count_at_least("strands", self.strands, 1)?;
        count_at_least("segments", self.segments, 1)?;
        if !(2..=MAX_SIDES).contains(&self.sides) {
            return Err(ParamError::new(
                "sides",
                format!("must be 2 (ribbon) or 3 to {MAX_SIDES} (tube), got {}", self.sides),
            ));
        }
        triangle_budget("strands", self.triangle_count())?;
        positive("radius", self.radius)?;
        positive("length", self.length)?;
        positive("thickness", self.thickness)?;
        at_least("center_height", self.center_height, self.radius + self.length, "radius + length")
    }

    fn generate(&self) -> Mesh {
        if self.validate().is_err() {
            return Mesh::default();
        }
        let mut rng = Rng::new(self.seed);
        let centre = DVec3::new(0.0, self.center_height, 0.0);
        let segments = self.segments as usize;
        let step = self.length / self.segments as f64;
        let wiggle = 0.15 / (self.segments as f64).sqrt();
        let per_strand_vertices =
            (segments + 1) * if self.sides == 2 { 2 } else { self.sides as usize };
        let mut mesh = Mesh {
            positions: Vec::with_capacity(self.strands as usize * per_strand_vertices),
            triangles: Vec::with_capacity(self.triangle_count() as usize),
        };
        let mut points = Vec::with_capacity(segments + 1);
        for _ in 0..self.strands {
            let normal = rng.unit_vector();
            let mut direction =
                (normal + 0.5 * rng.next_f64() * rng.unit_vector()).normalize_or(normal);
            if direction.dot(normal) <= 0.0 {
                direction = normal;
            }
            let towards = rng.unit_vector();
            let bend = rng.range(0.3, 1.5) / self.segments as f64;
            points.clear();
            points.push(centre + self.radius * normal);
            for _ in 0..segments {
                let last = points[points.len() - 1];
                points.push(last + step * direction);
                let side = (towards - towards.dot(direction) * direction).normalize_or_zero();
                let jitter = wiggle * rng.unit_vector();
                direction = (direction + bend * side + jitter).normalize_or(direction);
            }
            let tangents = polyline_tangents(&points);
            let start = mesh.positions.len();
            if self.sides == 2 {
                push_ribbon(&mut mesh, &points, &tangents, self.thickness);
            } else {
                push_tube(&mut mesh, &points, &tangents, 0.5 * self.thickness, self.sides, false);
            }
            for p in &mut mesh.positions[start..] {
                if p.y < 0.0 {
                    p.y = 0.0;
                }
            }
        }
        mesh
    }
}

/// Appends a flat ribbon of `width` along the curve: two vertices per point (along the
/// transported frame's normal), two triangles per segment.
fn push_ribbon(mesh: &mut Mesh, points: &[DVec3], tangents: &[DVec3], width: f64) {
    let base = mesh.positions.len() as u32;
    for (&p, (n, _)) in points.iter().zip(transported_frames(tangents)) {
        mesh.positions.push(p - 0.5 * width * n);
        mesh.positions.push(p + 0.5 * width * n);
    }
    for i in 0..points.len().saturating_sub(1) as u32 {
        let (a, b, c, d) = (base + 2 * i, base + 2 * i + 1, base + 2 * i + 3, base + 2 * i + 2);
        mesh.triangles.push([a, b, c]);
        mesh.triangles.push([a, c, d]);
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::bit_identical;
    use super::*;

    #[test]
    fn default_counts_and_extent() {
        let p = HairballParams::default();
        let mesh = p.generate();
        assert_eq!(mesh.triangle_count(), 72_000);
        assert_eq!(mesh.triangle_count() as u64, p.triangle_count());
        assert_eq!(mesh.positions.len(), 500 * 25 * 3);
        let (lo, hi) = mesh.bounds().expect("vertices");
        assert!(lo.y >= 0.0 && hi.y <= 6.0 + 0.01, "{lo} {hi}");
        assert!(lo.x >= -3.01 && hi.x <= 3.01 && lo.z >= -3.01 && hi.z <= 3.01);
    }

    #[test]
    fn hairs_start_on_the_sphere_and_have_their_length() {
        let p = HairballParams { strands: 20, sides: 4, thickness: 0.02, ..Default::default() };
        let mesh = p.generate();
        let centre = DVec3::new(0.0, 3.0, 0.0);
        for hair in mesh.positions.chunks_exact(25 * 4) {
            let rings: Vec<DVec3> =
                hair.chunks_exact(4).map(|r| r.iter().copied().sum::<DVec3>() / 4.0).collect();
            assert!(((rings[0] - centre).length() - 1.5).abs() < 1e-9);
            let length: f64 = rings.windows(2).map(|w| (w[1] - w[0]).length()).sum();
            assert!((length - 1.5).abs() < 1e-9, "{length}");
            assert!((rings[1] - centre).length() > 1.5, "the hair leaves the sphere");
            // Square cross-section: the diagonal is the thickness.
            assert!(((hair[0] - hair[2]).length() - 0.02).abs() < 1e-12);
        }
    }

    #[test]
    fn tubes_face_out_and_ribbons_are_flat() {
        let mesh = HairballParams { strands: 3, ..Default::default() }.generate();
        let per = 25 * 3;
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.corners(t);
            let hair = (mesh.triangles[t][0] as usize / per) * per;
            let ring = (mesh.triangles[t][0] as usize - hair) / 3 * 3 + hair;
            let axis =
                (mesh.positions[ring] + mesh.positions[ring + 1] + mesh.positions[ring + 2]) / 3.0;
            assert!((b - a).cross(c - a).dot(a - axis) > 0.0, "triangle {t} faces in");
        }
        let ribbon = HairballParams { strands: 4, segments: 10, sides: 2, ..Default::default() };
        let mesh = ribbon.generate();
        assert_eq!(mesh.triangle_count(), 4 * 2 * 10);
        for pair in mesh.positions.chunks_exact(2) {
            assert!(((pair[1] - pair[0]).length() - 0.01).abs() < 1e-12);
        }
    }

    #[test]
    fn seeds_decide_the_hairs() {
        let p = HairballParams { strands: 10, ..Default::default() };
        assert!(bit_identical(&p.generate(), &p.generate()));
        assert_ne!(p.generate(), HairballParams { seed: 2, ..p.clone() }.generate());
    }

    #[test]
    fn validation_names_the_key() {
        let bad = |p: HairballParams| p.validate().expect_err("invalid").key;
        let d = HairballParams::default;
        assert_eq!(bad(HairballParams { strands: 0, ..d() }), "strands");
        assert_eq!(bad(HairballParams { strands: 100_000, segments: 100, ..d() }), "strands");
        assert_eq!(bad(HairballParams { segments: 0, ..d() }), "segments");
        assert_eq!(bad(HairballParams { sides: 1, ..d() }), "sides");
        assert_eq!(bad(HairballParams { sides: 65, ..d() }), "sides");
        assert_eq!(bad(HairballParams { radius: 0.0, ..d() }), "radius");
        assert_eq!(bad(HairballParams { length: f64::INFINITY, ..d() }), "length");
        assert_eq!(bad(HairballParams { thickness: -0.01, ..d() }), "thickness");
        assert_eq!(bad(HairballParams { center_height: 2.9, ..d() }), "center_height");
    }
}
