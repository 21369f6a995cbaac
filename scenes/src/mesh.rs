//! Indexed triangle meshes.
//!
//! Positions are stored in `f64` (`DVec3`): every later stage (projection, depth, exact
//! coverage) works in `f64`, and loaders convert once on input. A mesh may hold degenerate
//! triangles (zero area); consumers must tolerate them, and [`Mesh::validate`] rejects only what
//! no consumer can use: non-finite positions and out-of-range indices.

use glam::{DMat4, DVec3};

/// An indexed triangle mesh in `f64`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Triangles as indices into `positions`, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
}

/// Why a mesh is unusable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {index} has a non-finite coordinate")]
    NonFinite {
        /// Index of the vertex.
        index: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {vertex}, but the mesh has {count} vertices")]
    IndexOutOfRange {
        /// Index of the triangle.
        triangle: usize,
        /// The bad vertex index.
        vertex: u32,
        /// Number of vertices.
        count: usize,
    },
    /// The mesh has no triangles.
    #[error("the mesh has no triangles")]
    Empty,
}

impl Mesh {
    /// A mesh from positions and triangles, validated.
    pub fn new(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        let mesh = Self { positions, triangles };
        mesh.validate()?;
        Ok(mesh)
    }

    /// Checks that every position is finite, every index in range and the mesh not empty.
    pub fn validate(&self) -> Result<(), MeshError> {
        if self.triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        if let Some(index) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(MeshError::NonFinite { index });
        }
        let count = self.positions.len();
        for (triangle, t) in self.triangles.iter().enumerate() {
            if let Some(&vertex) = t.iter().find(|&&v| v as usize >= count) {
                return Err(MeshError::IndexOutOfRange { triangle, vertex, count });
            }
        }
        Ok(())
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The three corners of triangle `t`.
    #[inline]
    pub fn corners(&self, t: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[t];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    /// Appends `other`, offsetting its indices.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.triangles
            .extend(other.triangles.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
    }

    /// Applies an affine transform to every position. A transform that mirrors (negative
    /// determinant) also flips the winding, so that fronts stay fronts.
    pub fn transform(&mut self, m: &DMat4) {
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        if m.determinant() < 0.0 {
            for t in &mut self.triangles {
                t.swap(1, 2);
            }
        }
    }

    /// Axis-aligned bounds `(min, max)`, or `None` for a mesh without vertices.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        let first = *self.positions.first()?;
        Some(self.positions.iter().fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))))
    }

    /// Total area of all triangles.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    /// The plane (unit normal `n`, offset `d` with `n·p = d`) that holds every vertex, within a
    /// tolerance relative to the mesh's size; `None` when the mesh is not planar or has no
    /// triangle of non-zero area.
    pub fn plane(&self) -> Option<(DVec3, f64)> {
        let (lo, hi) = self.bounds()?;
        let extent = (hi - lo).length().max(f64::MIN_POSITIVE);
        // The normal of the largest triangle is the best-conditioned estimate.
        let (mut best, mut best_area) = (DVec3::ZERO, 0.0);
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.corners(t);
            let n = (b - a).cross(c - a);
            let area = n.length();
            if area > best_area {
                best = n;
                best_area = area;
            }
        }
        if best_area <= 0.0 {
            return None;
        }
        let n = best / best_area;
        let d = n.dot(self.positions[self.triangles[0][0] as usize]);
        let tolerance = 1e-9 * extent;
        let planar = self
            .triangles
            .iter()
            .flatten()
            .all(|&v| (n.dot(self.positions[v as usize]) - d).abs() <= tolerance);
        planar.then_some((n, d))
    }
}

/// `triangles` with their corners renumbered in the order the triangles first use them, and
/// for each new number the old one. Every corner is below `vertices`; a vertex no triangle
/// uses gets no new number.
pub(crate) fn numbered_by_first_use(
    triangles: impl IntoIterator<Item = [u32; 3]>,
    vertices: usize,
) -> (Vec<[u32; 3]>, Vec<u32>) {
    let mut renumbered = vec![u32::MAX; vertices];
    let mut used = Vec::new();
    let triangles = triangles
        .into_iter()
        .map(|t| {
            t.map(|v| {
                let slot = &mut renumbered[v as usize];
                if *slot == u32::MAX {
                    *slot = used.len() as u32;
                    used.push(v);
                }
                *slot
            })
        })
        .collect();
    (triangles, used)
}

/// The eight corners of the axis-aligned box `(lo, hi)`: corner `i` takes `hi` on axis `k`
/// where bit `k` of `i` is set (x, y, z), `lo` elsewhere.
pub fn box_corners(lo: DVec3, hi: DVec3) -> [DVec3; 8] {
    std::array::from_fn(|i| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Mesh {
        Mesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 0.0, 1.0), DVec3::Z],
            vec![[0, 2, 1], [0, 3, 2]],
        )
        .expect("valid quad")
    }

    #[test]
    fn quad_is_planar_with_unit_area() {
        let q = quad();
        assert!((q.area() - 1.0).abs() < 1e-15);
        let (n, d) = q.plane().expect("planar");
        assert!((n.abs() - DVec3::Y).length() < 1e-15);
        assert_eq!(d, 0.0);
    }

    #[test]
    fn bent_mesh_is_not_planar() {
        let mut q = quad();
        q.positions[3].y = 0.1;
        assert!(q.plane().is_none());
    }

    #[test]
    fn validation_rejects_bad_meshes() {
        assert_eq!(Mesh::new(vec![DVec3::ZERO], vec![]), Err(MeshError::Empty));
        assert_eq!(
            Mesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 3]]),
            Err(MeshError::IndexOutOfRange { triangle: 0, vertex: 3, count: 3 })
        );
        assert_eq!(
            Mesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::splat(f64::NAN)], vec![[0, 1, 2]]),
            Err(MeshError::NonFinite { index: 2 })
        );
    }

    #[test]
    fn mirroring_keeps_fronts() {
        let mut q = quad();
        let before = q.triangles.clone();
        q.transform(&DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)));
        assert_ne!(q.triangles, before);
        assert_eq!(q.triangles[0], [0, 1, 2]);
    }
}
