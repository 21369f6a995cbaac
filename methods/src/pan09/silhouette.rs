//! Stages "edge adjacency" and "silhouette edges" (section 3.2): "an edge is a silhouette if
//! one of its two adjacent faces is a front face with respect to the light source and the
//! other is a back face. Edges with only one adjacent face are also considered silhouette".
//!
//! Choices:
//! - **Welding.** Faces are adjacent when their edges join the same two *positions* (exact
//!   `f64` bits), so meshes stored with split vertices (per-face corners) keep their
//!   adjacency. Edges of zero length are dropped.
//! - **Front and back without winding.** Two faces `(a, b, c1)` and `(a, b, c2)` on edge
//!   `a b` face the light the same way when their third corners lie on opposite sides of the
//!   plane through the edge and the light (the plane holding the edge and the direction
//!   towards a directional light, or the spot light's position). For a consistently wound
//!   mesh this is exactly "one front, one back" negated, and it needs no winding, so leaves
//!   and other open or inconsistently wound surfaces get their folds right. A third corner
//!   within rounding of that plane (a face seen edge-on) makes the edge a silhouette.
//! - Edges with three or more faces (non-manifold) are silhouettes.
//! - Only shadow casters take part: receivers that cast no shadow have no silhouette that can
//!   bound a shadow.
//!
//! Adjacency depends only on the mesh, so a renderer computes it once per scene; it is its own
//! stage so that it can be left out of per-frame times (Table 1).

use glam::DVec3;
use rayon::prelude::*;
use scenes::Geometry;

/// The edges of the caster triangles, each with its adjacent faces' third corners.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeAdjacency {
    /// Endpoints of each edge (vertex indices).
    pub ends: Vec<[u32; 2]>,
    /// Number of adjacent faces of each edge.
    pub faces: Vec<u32>,
    /// Third corners (vertex indices) of the first two adjacent faces of each edge (the second
    /// repeats the first for boundary edges).
    pub opposite: Vec<[u32; 2]>,
}

impl EdgeAdjacency {
    /// The adjacency of the triangles `t` of `geometry` with `include(t)`.
    pub fn new(geometry: &Geometry, include: impl Fn(usize) -> bool + Sync) -> Self {
        let p = &geometry.positions;
        // Canonical vertex: the lowest index at the same position.
        let mut order: Vec<u32> = (0..p.len() as u32).collect();
        let key = |v: u32| p[v as usize].to_array().map(f64::to_bits);
        order.par_sort_unstable_by_key(|&v| (key(v), v));
        let mut canon = vec![0u32; p.len()];
        let mut first = 0usize;
        for i in 0..order.len() {
            if key(order[i]) != key(order[first]) {
                first = i;
            }
            canon[order[i] as usize] = order[first];
        }
        // Half-edges keyed by their canonical endpoints, sorted so that faces of an edge meet.
        let mut half: Vec<(u64, u32)> = (0..geometry.len())
            .into_par_iter()
            .filter(|&t| include(t))
            .flat_map_iter(|t| {
                let v = geometry.triangles[t].map(|i| canon[i as usize]);
                (0..3).filter_map(move |e| {
                    let (a, b, c) = (v[e], v[(e + 1) % 3], v[(e + 2) % 3]);
                    (a != b).then(|| ((u64::from(a.min(b)) << 32) | u64::from(a.max(b)), c))
                })
            })
            .collect();
        half.par_sort_unstable();
        let mut adjacency = Self { ends: Vec::new(), faces: Vec::new(), opposite: Vec::new() };
        let mut i = 0;
        while i < half.len() {
            let k = half[i].0;
            let mut j = i + 1;
            while j < half.len() && half[j].0 == k {
                j += 1;
            }
            adjacency.ends.push([(k >> 32) as u32, k as u32]);
            adjacency.faces.push((j - i) as u32);
            adjacency.opposite.push([half[i].1, half[(i + 1).min(j - 1)].1]);
            i = j;
        }
        adjacency
    }

    /// Number of edges.
    pub fn len(&self) -> usize {
        self.ends.len()
    }

    /// Whether there are no edges.
    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }
}

/// Where the light is, for the side tests of silhouettes and shadows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightModel {
    /// Unit direction towards a directional light.
    Towards(DVec3),
    /// Position of a spot light.
    At(DVec3),
}

impl LightModel {
    /// The light of a projector: orthographic projectors are directional lights looking along
    /// `forward`, perspective ones spot lights at `origin`.
    pub fn of(light: &scenes::Projector) -> Self {
        if light.is_perspective() {
            LightModel::At(light.origin)
        } else {
            LightModel::Towards(-light.forward)
        }
    }

    /// A vector from `p` towards the light (unit for directional lights).
    #[inline]
    pub fn towards(&self, p: DVec3) -> DVec3 {
        match *self {
            LightModel::Towards(w) => w,
            LightModel::At(q) => q - p,
        }
    }
}

/// The silhouette edges, as world-space endpoint pairs.
pub fn silhouette_edges(
    geometry: &Geometry,
    adjacency: &EdgeAdjacency,
    light: LightModel,
) -> Vec<[DVec3; 2]> {
    let p = &geometry.positions;
    (0..adjacency.len())
        .into_par_iter()
        .filter_map(|e| {
            let [a, b] = adjacency.ends[e].map(|v| p[v as usize]);
            let silhouette = match adjacency.faces[e] {
                2 => {
                    let [c1, c2] = adjacency.opposite[e].map(|v| p[v as usize]);
                    let n = (b - a).cross(light.towards(a));
                    let (s1, s2) = (n.dot(c1 - a), n.dot(c2 - a));
                    let tiny = |s: f64, c: DVec3| s.abs() <= 1e-12 * n.length() * (c - a).length();
                    let opposite = s1 * s2 < 0.0;
                    !opposite || tiny(s1, c1) || tiny(s2, c2)
                }
                _ => true,
            };
            silhouette.then_some([a, b])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube of 12 triangles with split vertices (each triangle its own corners).
    fn split_cube() -> Geometry {
        let c = |x: u32, y: u32, z: u32| DVec3::new(f64::from(x), f64::from(y), f64::from(z));
        let quads = [
            [c(0, 0, 0), c(1, 0, 0), c(1, 1, 0), c(0, 1, 0)],
            [c(0, 0, 1), c(0, 1, 1), c(1, 1, 1), c(1, 0, 1)],
            [c(0, 0, 0), c(0, 1, 0), c(0, 1, 1), c(0, 0, 1)],
            [c(1, 0, 0), c(1, 0, 1), c(1, 1, 1), c(1, 1, 0)],
            [c(0, 0, 0), c(0, 0, 1), c(1, 0, 1), c(1, 0, 0)],
            [c(0, 1, 0), c(1, 1, 0), c(1, 1, 1), c(0, 1, 1)],
        ];
        let mut g = Geometry::default();
        for q in quads {
            for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                let base = g.positions.len() as u32;
                g.positions.extend(t);
                g.triangles.push([base, base + 1, base + 2]);
                g.object.push(0);
            }
        }
        g
    }

    #[test]
    fn welded_cube_has_closed_edges_and_a_six_edge_outline() {
        let g = split_cube();
        let adj = EdgeAdjacency::new(&g, |_| true);
        assert_eq!(adj.len(), 18, "12 cube edges and 6 face diagonals");
        assert!(adj.faces.iter().all(|&f| f == 2));
        // Seen along the main diagonal, a cube's outline is a hexagon of six edges.
        let towards = DVec3::ONE.normalize();
        let sil = silhouette_edges(&g, &adj, LightModel::Towards(towards));
        assert_eq!(sil.len(), 6);
        // Seen along an axis, the side faces are edge-on: every edge they touch is a
        // silhouette (the top's and bottom's 8 edges, the 4 vertical ones, the 4 side
        // diagonals), only the top and bottom diagonals are not.
        let sil = silhouette_edges(&g, &adj, LightModel::Towards(DVec3::Y));
        assert_eq!(sil.len(), 16);
    }

    #[test]
    fn open_surfaces_have_boundary_silhouettes_and_folds_without_winding() {
        // Two triangles on edge (0,0,0)-(1,0,0), wound inconsistently, forming a flat strip
        // and then a fold that doubles back over itself.
        let mut g = Geometry {
            positions: vec![
                DVec3::ZERO,
                DVec3::X,
                DVec3::new(0.5, 0.0, 1.0),
                DVec3::new(0.5, 0.0, -1.0),
            ],
            triangles: vec![[0, 1, 2], [0, 1, 3]],
            object: vec![0, 0],
        };
        let light = LightModel::Towards(DVec3::Y);
        let adj = EdgeAdjacency::new(&g, |_| true);
        assert_eq!(adj.len(), 5);
        let sil = silhouette_edges(&g, &adj, light);
        assert_eq!(sil.len(), 4, "the boundary only: the shared edge is flat");
        g.positions[3] = DVec3::new(0.5, 0.5, 1.0); // folded back over the first triangle
        let adj = EdgeAdjacency::new(&g, |_| true);
        assert_eq!(silhouette_edges(&g, &adj, light).len(), 5);
        // Spot light right above the shared edge: the flat strip again has no fold.
        g.positions[3] = DVec3::new(0.5, 0.0, -1.0);
        let sil = silhouette_edges(&g, &adj, LightModel::At(DVec3::new(0.5, 3.0, 0.1)));
        assert_eq!(sil.len(), 4);
        // Excluded triangles take no part.
        assert_eq!(EdgeAdjacency::new(&g, |t| t == 0).len(), 3);
    }
}
