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
        let canon = canonical_vertices(&geometry.positions);
        // Half-edges keyed by their canonical endpoints, sorted so that faces of an edge meet.
        // Three slots per triangle, in place (an indexed collect, nothing moved afterwards);
        // a slot without a half-edge (a zero-length edge, a triangle not included) holds
        // `NONE`, which sorts after every edge (its low half is no vertex a < b can give).
        const NONE: (u64, u32) = (u64::MAX, u32::MAX);
        let mut half: Vec<(u64, u32)> = (0..geometry.len() * 3)
            .into_par_iter()
            .with_min_len(4096)
            .map(|slot| {
                let (t, e) = (slot / 3, slot % 3);
                if !include(t) {
                    return NONE;
                }
                let v = geometry.triangles[t];
                let [a, b, c] = [v[e], v[(e + 1) % 3], v[(e + 2) % 3]].map(|i| canon[i as usize]);
                if a == b {
                    return NONE;
                }
                ((u64::from(a.min(b)) << 32) | u64::from(a.max(b)), c)
            })
            .collect();
        half.par_sort_unstable();
        half.truncate(half.partition_point(|h| *h != NONE));
        // One edge per run of equal keys, the runs found and read in parallel.
        let starts: Vec<usize> = (0..half.len())
            .into_par_iter()
            .with_min_len(4096)
            .filter(|&i| i == 0 || half[i - 1].0 != half[i].0)
            .collect();
        let (ends, (faces, opposite)) = (0..starts.len())
            .into_par_iter()
            .map(|r| {
                let (i, j) = (starts[r], starts.get(r + 1).copied().unwrap_or(half.len()));
                let k = half[i].0;
                let opposite = [half[i].1, half[(i + 1).min(j - 1)].1];
                ([(k >> 32) as u32, k as u32], ((j - i) as u32, opposite))
            })
            .unzip();
        Self { ends, faces, opposite }
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

/// For each vertex, the lowest index of a vertex at the same position (exact `f64` bits).
///
/// The vertices are sorted by a 64-bit hash of their position's bits with their index
/// (16-byte entries: sorting the 24-byte positions themselves took twice as long), and a
/// run of equal hashes is split by exact comparison: each vertex takes the first of the run
/// at its position. Hash collisions cost comparisons, never a wrong weld.
fn canonical_vertices(p: &[DVec3]) -> Vec<u32> {
    weld(p, position_hash)
}

/// SplitMix64's finalizer over the three coordinates' bits.
fn position_hash(q: &DVec3) -> u64 {
    let mix = |mut z: u64| {
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let [x, y, z] = q.to_array().map(f64::to_bits);
    mix(mix(mix(x) ^ y) ^ z)
}

/// [`canonical_vertices`] with the hash given (tests pass one that collides).
fn weld(p: &[DVec3], hash: impl Fn(&DVec3) -> u64 + Sync) -> Vec<u32> {
    let mut order: Vec<(u64, u32)> =
        p.par_iter().enumerate().map(|(v, q)| (hash(q), v as u32)).collect();
    order.par_sort_unstable();
    let same = |a: u32, b: u32| {
        p[a as usize].to_array().map(f64::to_bits) == p[b as usize].to_array().map(f64::to_bits)
    };
    let mut canon = vec![0u32; p.len()];
    // The distinct positions of the current run of equal hashes, by their first vertex.
    let mut firsts: Vec<u32> = Vec::new();
    for (i, &(h, v)) in order.iter().enumerate() {
        if i == 0 || order[i - 1].0 != h {
            firsts.clear();
        }
        // Within a run the indices increase: the first vertex met at a position is its
        // lowest.
        let first = match firsts.iter().find(|&&f| same(f, v)) {
            Some(&f) => f,
            None => {
                firsts.push(v);
                v
            }
        };
        canon[v as usize] = first;
    }
    canon
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
///
/// The silhouettes' edge numbers are collected first (4 bytes each), then their endpoints
/// written in place: collecting the 48-byte endpoint pairs directly would assemble them in
/// pieces and move every one (on `random-1m`, 3 M silhouettes, 144 MB).
pub fn silhouette_edges(
    geometry: &Geometry,
    adjacency: &EdgeAdjacency,
    light: LightModel,
) -> Vec<[DVec3; 2]> {
    let p = &geometry.positions;
    let is_silhouette = |e: usize| match adjacency.faces[e] {
        2 => {
            let [a, b] = adjacency.ends[e].map(|v| p[v as usize]);
            let [c1, c2] = adjacency.opposite[e].map(|v| p[v as usize]);
            let n = (b - a).cross(light.towards(a));
            let (s1, s2) = (n.dot(c1 - a), n.dot(c2 - a));
            let tiny = |s: f64, c: DVec3| s.abs() <= 1e-12 * n.length() * (c - a).length();
            let opposite = s1 * s2 < 0.0;
            !opposite || tiny(s1, c1) || tiny(s2, c2)
        }
        _ => true,
    };
    let chosen: Vec<u32> = (0..adjacency.len())
        .into_par_iter()
        .with_min_len(4096)
        .filter(|&e| is_silhouette(e))
        .map(|e| e as u32)
        .collect();
    chosen.par_iter().map(|&e| adjacency.ends[e as usize].map(|v| p[v as usize])).collect()
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
    fn welding_takes_the_lowest_index_at_each_position_whatever_the_hash() {
        // Positions on a small grid, many repeated, with -0.0 and 0.0 kept apart (their bits
        // differ) and a NaN, equal to itself by bits.
        let mut p = Vec::new();
        for k in 0u32..2000 {
            let c = |m: u32| f64::from((k * m) % 5) - 2.0;
            p.push(DVec3::new(c(7), c(11), c(13)));
        }
        p.extend([DVec3::new(-0.0, 0.0, 0.0), DVec3::ZERO, DVec3::splat(f64::NAN)]);
        p.extend([DVec3::new(-0.0, 0.0, 0.0), DVec3::ZERO, DVec3::splat(f64::NAN)]);
        let mut lowest = std::collections::BTreeMap::new();
        let want: Vec<u32> = p
            .iter()
            .enumerate()
            .map(|(v, q)| *lowest.entry(q.to_array().map(f64::to_bits)).or_insert(v as u32))
            .collect();
        assert_eq!(canonical_vertices(&p), want);
        // Every position colliding, or two hashes for all: runs split by exact comparison.
        assert_eq!(weld(&p, |_| 7), want);
        assert_eq!(weld(&p, |q| u64::from(q.x > 0.0)), want);
        assert!(canonical_vertices(&[]).is_empty());
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
