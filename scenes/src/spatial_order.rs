//! The order a mesh file's triangles are kept in: near triangles at near ids.
//!
//! Every method walks the triangles by id: rasterizers bin and set them up in id order, the
//! exact reference gathers the corners of the triangles overlapping a pixel and of the casters
//! near a receiver, `afsm` copies its blockers into the BSP's nodes. When consecutive ids lie
//! far apart, each of those reads is a cache miss. A file's order is whatever the tool that
//! wrote it chose: the Stanford bunny (`bunny00.off`) has 56 % of 1,033 evenly spaced pairs of
//! consecutive triangles farther apart than four times their longest edge.
//!
//! So a mesh read from a file ([`spatially_ordered`]) with at least [`MIN_TRIANGLES`]
//! triangles, most of whose consecutive triangles lie apart ([`is_local`]), is stored with its
//! triangles in the Z order (Morton order) of their centroids over the mesh's bounding box,
//! ties kept in the file's order, and its vertices numbered in the order the triangles first
//! use them (those no triangle uses after them, in their own order). Each triangle keeps its
//! corners in their order, so its winding, and every edge its two triangles share keeps
//! being shared: the mesh is the same surface. After it, 1.8 % of the bunny's pairs lie apart.
//!
//! Measured on `bunny-plane` at 800 x 600 (one pinned thread, medians of 3 alternating runs of
//! 3 frames, load 0.2-1.0; a scene file naming the bunny in its file's order against one
//! naming it reordered so; ms): the camera G-buffer 37.8 -> 32.6, `exact` 422 -> 336 in all
//! (pixel classes 121 -> 95, surface shadows 160 -> 129), `afsm` 106 -> 89 (rasterization
//! of blockers 38.2 -> 29.9), `sm` at map 1024 83 -> 70 (light depth map 23.7 -> 18.7).
//! Renumbering the vertices gave 2-3 ms of that, ordering the triangles the rest. At two
//! threads (the built-in scene, 4 alternating runs of 3 frames): `exact` 212 -> 178 ms, `afsm`'s
//! stages 36.1 -> 30.7, `sm`'s 25.6 -> 23.2. The peer gains as much or more from the same
//! triangles: Embree's BVH build plus shadow rays on `bunny-plane`, one thread, 65.1 -> 50.6 ms
//! (`embree-side-by-side`, two runs half an hour apart).
//!
//! Generated meshes keep the order their generator gives them (a heightfield's rows, a
//! sphere's rings; the random triangles of `random-*` are random by design). A file already
//! in a local order keeps it, so a scene exported (`frame` writes `scene.glb`) and read again
//! keeps its ids.

use crate::mesh::Mesh;
use glam::DVec3;

/// Fewest triangles of a mesh that [`spatially_ordered`] reorders: a smaller one fits in the
/// caches whatever its order.
pub const MIN_TRIANGLES: usize = 1024;

/// Most pairs of consecutive triangles [`is_local`] looks at, evenly spaced.
pub const SAMPLED_PAIRS: usize = 1024;

/// How far apart, in longest edges, two consecutive triangles' centroids may lie for the pair
/// to count as near in [`is_local`].
pub const NEAR_EDGES: f64 = 4.0;

/// `mesh` in the order the module documentation gives: reordered when it has at least
/// [`MIN_TRIANGLES`] triangles and is not [`is_local`], else as it is.
pub fn spatially_ordered(mesh: Mesh) -> Mesh {
    if mesh.triangles.len() < MIN_TRIANGLES || is_local(&mesh) {
        return mesh;
    }
    let Some((lo, hi)) = mesh.bounds() else { return mesh };
    // Cells of 2^21 per axis: the Morton code of three axes fills 63 bits.
    const BITS: u32 = 21;
    let top = f64::from((1u32 << BITS) - 1);
    let extent = hi - lo;
    let scale = DVec3::select(extent.cmpgt(DVec3::ZERO), top / extent, DVec3::ZERO);
    let key = |t: usize| {
        let [a, b, c] = mesh.corners(t);
        let q = (((a + b + c) / 3.0 - lo) * scale).clamp(DVec3::ZERO, DVec3::splat(top));
        crate::morton::code3(q.x as u32, q.y as u32, q.z as u32)
    };
    let mut order: Vec<(u64, u32)> =
        (0..mesh.triangles.len()).map(|t| (key(t), t as u32)).collect();
    // The index breaks ties: the file's order among triangles of one cell.
    order.sort_unstable();
    let sorted = order.iter().map(|&(_, t)| mesh.triangles[t as usize]);
    let (triangles, used) = crate::mesh::numbered_by_first_use(sorted, mesh.positions.len());
    let mut positions: Vec<DVec3> = used.iter().map(|&v| mesh.positions[v as usize]).collect();
    if used.len() < mesh.positions.len() {
        // The vertices no triangle uses, after the used ones in their own order.
        let mut unused = vec![true; mesh.positions.len()];
        used.iter().for_each(|&v| unused[v as usize] = false);
        positions.extend(mesh.positions.iter().zip(&unused).filter(|(_, &u)| u).map(|(p, _)| *p));
    }
    Mesh { positions, triangles }
}

/// Whether the mesh's triangles are already in a local order: at most a quarter of up to
/// [`SAMPLED_PAIRS`] evenly spaced pairs of consecutive triangles have centroids farther
/// apart than [`NEAR_EDGES`] times the longer of the two triangles' longest edges.
pub fn is_local(mesh: &Mesh) -> bool {
    let n = mesh.triangles.len();
    if n < 2 {
        return true;
    }
    let step = ((n - 1) / SAMPLED_PAIRS).max(1);
    let centroid = |t: usize| {
        let [a, b, c] = mesh.corners(t);
        (a + b + c) / 3.0
    };
    let longest = |t: usize| {
        let [a, b, c] = mesh.corners(t);
        a.distance(b).max(b.distance(c)).max(c.distance(a))
    };
    let (mut pairs, mut apart) = (0usize, 0usize);
    for t in (0..n - 1).step_by(step) {
        pairs += 1;
        let reach = NEAR_EDGES * longest(t).max(longest(t + 1));
        if centroid(t).distance(centroid(t + 1)) > reach {
            apart += 1;
        }
    }
    4 * apart <= pairs
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `k x k` grid of quads in the plane `z = 0`, two triangles each, wound
    /// counter-clockwise seen from `+z`.
    fn grid(k: u32) -> Mesh {
        let mut positions = Vec::new();
        for j in 0..=k {
            for i in 0..=k {
                positions.push(DVec3::new(f64::from(i), f64::from(j), 0.0));
            }
        }
        let at = |i: u32, j: u32| j * (k + 1) + i;
        let mut triangles = Vec::new();
        for j in 0..k {
            for i in 0..k {
                triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        Mesh::new(positions, triangles).expect("valid grid")
    }

    /// The mesh's triangles shuffled by a fixed odd stride (coprime with the count).
    fn shuffled(mesh: &Mesh) -> Mesh {
        let n = mesh.triangles.len();
        let stride = (0..).map(|s| 7919 + 2 * s).find(|s| gcd(*s, n) == 1).expect("a stride");
        let triangles = (0..n).map(|i| mesh.triangles[(i * stride) % n]).collect();
        Mesh { positions: mesh.positions.clone(), triangles }
    }

    fn gcd(a: usize, b: usize) -> usize {
        if b == 0 {
            a
        } else {
            gcd(b, a % b)
        }
    }

    /// Every triangle as its corners' positions, in a canonical order of the triangles.
    fn surface(mesh: &Mesh) -> Vec<[[u64; 3]; 3]> {
        let mut all: Vec<_> = (0..mesh.triangles.len())
            .map(|t| mesh.corners(t).map(|p| p.to_array().map(f64::to_bits)))
            .collect();
        all.sort_unstable();
        all
    }

    #[test]
    fn a_shuffled_mesh_is_put_in_a_local_order_as_the_same_surface() {
        let mesh = shuffled(&grid(40));
        assert!(!is_local(&mesh), "the shuffle scatters the triangles");
        let ordered = spatially_ordered(mesh.clone());
        assert!(is_local(&ordered));
        // The same triangles, each with its corners in their order (so its winding).
        assert_eq!(surface(&ordered), surface(&mesh));
        assert_eq!(ordered.positions.len(), mesh.positions.len());
        assert!(ordered.validate().is_ok());
        // Vertices numbered by first use: the first triangle uses 0, 1 and 2.
        assert_eq!(ordered.triangles[0], [0, 1, 2]);
        // Twice is once: the order is local already.
        assert_eq!(spatially_ordered(ordered.clone()), ordered);
    }

    #[test]
    fn local_and_small_meshes_keep_their_order() {
        let local = grid(40);
        assert!(is_local(&local));
        assert_eq!(spatially_ordered(local.clone()), local);
        let small = shuffled(&grid(20));
        assert!(small.triangles.len() < MIN_TRIANGLES);
        assert_eq!(spatially_ordered(small.clone()), small);
    }

    /// Vertices no triangle uses keep their positions, after the used ones.
    #[test]
    fn unused_vertices_are_kept_after_the_used_ones() {
        let mut mesh = shuffled(&grid(40));
        let extra = DVec3::new(-5.0, 7.0, 1.0);
        mesh.positions.insert(0, extra);
        for t in &mut mesh.triangles {
            *t = t.map(|v| v + 1);
        }
        let ordered = spatially_ordered(mesh.clone());
        assert_eq!(surface(&ordered), surface(&mesh));
        assert_eq!(ordered.positions.last(), Some(&extra));
    }

    /// Flat, degenerate, far-flung and overflowing meshes are ordered without a panic, as the
    /// same surface.
    #[test]
    fn degenerate_meshes_are_ordered_as_the_same_surface() {
        let flat = shuffled(&grid(40));
        let mut far = flat.clone();
        for p in &mut far.positions {
            *p = *p * 1e300 + DVec3::new(1e306, -1e306, 0.0);
        }
        // A sliver from the largest `f64` to the smallest beside the grid: the box's extent
        // overflows, and so do the offsets of the centroids from its corner.
        let mut huge = flat.clone();
        let v = huge.positions.len() as u32;
        huge.positions.extend([DVec3::new(f64::MAX, 0.0, 0.0), DVec3::new(-f64::MAX, 0.0, 0.0)]);
        huge.triangles.push([v, v + 1, v]);
        assert!(huge.validate().is_ok(), "finite coordinates");
        assert!(!is_local(&huge), "ordered, not kept");
        // Every triangle collapsed to a point, the points scattered.
        let mut points = flat.clone();
        points.triangles = (0..flat.triangles.len() as u32).map(|t| [t, t, t]).collect();
        points.positions = (0..flat.triangles.len())
            .map(|t| DVec3::new(((t * 7919) % 1601) as f64, 0.0, 0.0))
            .collect();
        for mesh in [flat, far, huge, points] {
            let ordered = spatially_ordered(mesh.clone());
            assert_eq!(surface(&ordered), surface(&mesh));
        }
    }
}
