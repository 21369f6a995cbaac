//! `plane`: a square ground receiver.
//!
//! A square of side `size` at y = 0, centred on the origin, normal +y, split into
//! `subdivisions` x `subdivisions` quads of two triangles each: `2 * subdivisions²` triangles
//! and `(subdivisions + 1)²` shared vertices. Open (a single-sided sheet), planar.

use super::{count_at_least, positive, triangle_budget, Generator, ParamError};
use crate::mesh::Mesh;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Parameters of the `plane` generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlaneParams {
    /// Side of the square, in world units. Default 20.
    pub size: f64,
    /// Quads along each side (two triangles each). Default 1.
    pub subdivisions: u32,
}

impl Default for PlaneParams {
    fn default() -> Self {
        Self { size: 20.0, subdivisions: 1 }
    }
}

impl Generator for PlaneParams {
    /// The number of triangles [`Generator::generate`] builds: `2 * subdivisions²` (saturating).
    fn triangle_count(&self) -> u64 {
        (u64::from(self.subdivisions) * u64::from(self.subdivisions)).saturating_mul(2)
    }

    fn validate(&self) -> Result<(), ParamError> {
        positive("size", self.size)?;
        count_at_least("subdivisions", self.subdivisions, 1)?;
        triangle_budget("subdivisions", self.triangle_count())
    }

    fn generate(&self) -> Mesh {
        if self.validate().is_err() {
            return Mesh::default();
        }
        grid(self.size, self.subdivisions, |_, _| 0.0)
    }
}

/// A `size` x `size` square centred on the origin in x and z, `n` x `n` quads, with height
/// `height(x, z)` at each vertex; every triangle counter-clockwise seen from +y (so its normal
/// has a positive y component whatever the heights). Vertex `(i, j)` (i along x, j along z) is
/// `positions[j * (n + 1) + i]`.
pub(crate) fn grid(size: f64, n: u32, height: impl Fn(f64, f64) -> f64) -> Mesh {
    let row = n as usize + 1;
    let coordinate = |i: u32| size * (f64::from(i) / f64::from(n) - 0.5);
    let mut mesh = Mesh {
        positions: Vec::with_capacity(row * row),
        triangles: Vec::with_capacity(2 * (row - 1) * (row - 1)),
    };
    for j in 0..=n {
        let z = coordinate(j);
        for i in 0..=n {
            let x = coordinate(i);
            mesh.positions.push(DVec3::new(x, height(x, z), z));
        }
    }
    let vertex = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            let (a, b) = (vertex(i, j), vertex(i + 1, j));
            let (c, d) = (vertex(i + 1, j + 1), vertex(i, j + 1));
            mesh.triangles.push([a, d, c]);
            mesh.triangles.push([a, c, b]);
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_two_triangles_facing_up() {
        let mesh = PlaneParams::default().generate();
        assert_eq!(mesh.triangle_count(), 2);
        assert_eq!(mesh.positions.len(), 4);
        assert!((mesh.area() - 400.0).abs() < 1e-9);
        let (n, d) = mesh.plane().expect("planar");
        assert_eq!((n, d), (DVec3::Y, 0.0));
        let (lo, hi) = mesh.bounds().expect("vertices");
        assert_eq!((lo, hi), (DVec3::new(-10.0, 0.0, -10.0), DVec3::new(10.0, 0.0, 10.0)));
    }

    #[test]
    fn subdivisions_give_two_triangles_per_quad() {
        let p = PlaneParams { size: 3.0, subdivisions: 7 };
        let mesh = p.generate();
        assert_eq!(mesh.triangle_count(), 2 * 7 * 7);
        assert_eq!(mesh.triangle_count() as u64, p.triangle_count());
        assert_eq!(mesh.positions.len(), 64);
        assert!((mesh.area() - 9.0).abs() < 1e-12);
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.corners(t);
            let n = (b - a).cross(c - a);
            assert!(n.y > 0.0 && n.x == 0.0 && n.z == 0.0);
        }
    }

    #[test]
    fn validation_names_the_key() {
        let bad = |p: PlaneParams| p.validate().expect_err("invalid").key;
        assert_eq!(bad(PlaneParams { size: 0.0, ..Default::default() }), "size");
        assert_eq!(bad(PlaneParams { size: f64::INFINITY, ..Default::default() }), "size");
        assert_eq!(bad(PlaneParams { subdivisions: 0, ..Default::default() }), "subdivisions");
        assert_eq!(
            bad(PlaneParams { subdivisions: 100_000, ..Default::default() }),
            "subdivisions"
        );
        assert!(PlaneParams { subdivisions: 0, ..Default::default() }
            .generate()
            .triangles
            .is_empty());
    }
}
