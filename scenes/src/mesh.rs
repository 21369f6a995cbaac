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
    ///
    /// A mesh that four of its corners prove not planar (see [`Mesh::surely_not_planar`]) is
    /// answered without the passes over every triangle. Every frame asks it of every object
    /// (the scene's effects, `exact`'s pixel classes); on `bumpy`'s 530,688 triangles the
    /// passes took about 3 ms a call, 1.4 % of a one-thread profile of `exact`, and now 0.2 %.
    pub fn plane(&self) -> Option<(DVec3, f64)> {
        let (lo, hi) = self.bounds()?;
        let extent = (hi - lo).length().max(f64::MIN_POSITIVE);
        let tolerance = 1e-9 * extent;
        if self.surely_not_planar(lo, hi, extent, tolerance) {
            return None;
        }
        self.plane_by_passes(tolerance)
    }

    /// [`Mesh::plane`] by its passes over every triangle: the normal of the largest triangle,
    /// then every corner within `tolerance` of its plane.
    fn plane_by_passes(&self, tolerance: f64) -> Option<(DVec3, f64)> {
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
        let planar = self
            .triangles
            .iter()
            .flatten()
            .all(|&v| (n.dot(self.positions[v as usize]) - d).abs() <= tolerance);
        planar.then_some((n, d))
    }

    /// Whether four corners of the triangles, taken from [`PLANARITY_SAMPLES`] triangles
    /// evenly spaced through the list, span a tetrahedron too thick for any slab that
    /// [`Mesh::plane`] would accept: then `plane` is `None` whatever normal it would find.
    ///
    /// The bound: where `plane` accepts, every corner lies within `w = tolerance + 16 ε M` of a
    /// plane with unit normal (`M` the largest coordinate magnitude of the bounds, `16 ε M` the
    /// rounding of `n·p - d`; the normal's own rounding is in the factor `1 + 4 ε`). The
    /// differences of four such corners are at most `extent` long, and their components
    /// along that normal at most `2 w`; their triple product is a sum of three terms each
    /// holding one such component (the term of none vanishes, being the volume spanned by three
    /// vectors in one plane; terms of two or three vanish, holding `n × n`), so it is at most
    /// `6 w extent²`. Computed in `f64`, the differences and the product add at most
    /// `16 ε extent³`. A computed product beyond twice their sum, and finite, proves the mesh
    /// not planar; anything else (a planar mesh, a sample too small to show relief, overflow)
    /// leaves the answer to the passes.
    fn surely_not_planar(&self, lo: DVec3, hi: DVec3, extent: f64, tolerance: f64) -> bool {
        let step = (self.triangles.len() / PLANARITY_SAMPLES).max(1);
        let sample =
            || self.triangles.iter().step_by(step).flatten().map(|&v| self.positions[v as usize]);
        let Some(p0) = sample().next() else { return false };
        let farthest = |measure: &dyn Fn(DVec3) -> f64| {
            sample().map(|p| (measure(p), p)).fold((0.0, p0), |a, b| if b.0 > a.0 { b } else { a })
        };
        let (_, p1) = farthest(&|p| (p - p0).length_squared());
        let (_, p2) = farthest(&|p| (p - p0).cross(p1 - p0).length_squared());
        let normal = (p1 - p0).cross(p2 - p0);
        let (volume, _) = farthest(&|p| normal.dot(p - p0).abs());
        let eps = f64::EPSILON;
        let magnitude = lo.abs().max(hi.abs()).max_element();
        let slab = (tolerance + 16.0 * eps * magnitude) * (1.0 + 4.0 * eps);
        let bound = 2.0 * (6.0 * slab * extent * extent + 16.0 * eps * extent.powi(3));
        volume.is_finite() && bound.is_finite() && volume > bound
    }
}

/// Triangles whose corners [`Mesh::surely_not_planar`] looks at.
const PLANARITY_SAMPLES: usize = 64;

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

    /// A grid of `n` x `n` corners at `offset`, `scale` across, whose heights are
    /// `relief * scale` times a fixed pattern of signs and sizes.
    fn relief_grid(n: u32, offset: DVec3, scale: f64, relief: f64) -> Mesh {
        let mut positions = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let bump = ((i * 7 + j * 13) % 5) as f64 - 2.0;
                let p = DVec3::new(i as f64, relief * bump, j as f64) * scale / (n - 1) as f64;
                positions.push(offset + p);
            }
        }
        let mut triangles = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let v = j * n + i;
                triangles.extend([[v, v + n, v + 1], [v + 1, v + n, v + n + 1]]);
            }
        }
        Mesh::new(positions, triangles).expect("valid grid")
    }

    /// The answer of [`Mesh::plane`]'s passes alone.
    fn by_passes(m: &Mesh) -> Option<(DVec3, f64)> {
        let (lo, hi) = m.bounds().expect("vertices");
        let extent = (hi - lo).length().max(f64::MIN_POSITIVE);
        m.plane_by_passes(1e-9 * extent)
    }

    #[test]
    fn the_early_answer_is_the_passes_answer_around_the_tolerance() {
        for offset in [0.0, 1e-6, 1.0, 1e3, 1e6] {
            for scale in [1e-6, 1e-3, 1.0, 1e3, 1e6] {
                for relief in [0.0, 1e-14, 1e-12, 1e-10, 3e-10, 1e-9, 3e-9, 1e-8, 1e-6, 1e-2, 1.0] {
                    let m = relief_grid(9, DVec3::splat(offset), scale, relief);
                    let (lo, hi) = m.bounds().expect("vertices");
                    let extent = (hi - lo).length().max(f64::MIN_POSITIVE);
                    let early = m.surely_not_planar(lo, hi, extent, 1e-9 * extent);
                    assert_eq!(m.plane(), by_passes(&m), "{offset} {scale} {relief}");
                    // Relief of a thousand tolerances is proved, unless the offset's rounding
                    // outweighs it.
                    if relief >= 1e-6 && offset <= 1e3 * scale {
                        assert!(early, "{offset} {scale} {relief}: answered by the passes");
                    }
                }
            }
        }
    }

    proptest::proptest! {
        /// Any mesh of a few corners, flat, bent a little or a lot, degenerate or not, gets
        /// the answer the passes give.
        #[test]
        fn plane_is_the_passes_answer(
            corners in proptest::collection::vec(
                (-1e3f64..1e3, -1e3f64..1e3, -1e3f64..1e3), 3..12),
            flatten in proptest::bool::ANY,
            triangles in proptest::collection::vec((0u32..12, 0u32..12, 0u32..12), 1..16),
        ) {
            let n = corners.len() as u32;
            let positions = corners
                .iter()
                .map(|&(x, y, z)| DVec3::new(x, if flatten { y * 1e-12 } else { y }, z))
                .collect();
            let triangles = triangles.iter().map(|&(a, b, c)| [a % n, b % n, c % n]).collect();
            let m = Mesh::new(positions, triangles).expect("valid");
            proptest::prop_assert_eq!(m.plane(), by_passes(&m));
        }
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
