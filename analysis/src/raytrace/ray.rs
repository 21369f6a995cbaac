//! The `f64` ray and its watertight triangle test: Woop, Benthin and Wald, "Watertight
//! Ray/Triangle Intersection", JCGT 2(1), 2013, double-sided, with a top-left rule where an
//! edge function is exactly zero (see the parent module's "Edges and vertices").

use glam::DVec3;

/// A ray in `f64` with the precomputed shear of Woop et al.'s watertight triangle test.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TraceRay {
    /// Where the ray starts (parameter 0).
    pub(crate) origin: DVec3,
    /// Its direction (parameter 1 is `origin + dir`), finite and non-zero.
    pub(crate) dir: DVec3,
    /// Axis indices: `kz` is the dominant axis of `dir`, `kx`, `ky` the other two (swapped
    /// when `dir[kz] < 0` to keep the winding).
    k: [usize; 3],
    /// `(dir[kx] / dir[kz], dir[ky] / dir[kz], 1 / dir[kz])`.
    shear: DVec3,
    /// `1 / dir`, component by component (infinite for zero components).
    pub(crate) inv: DVec3,
}

/// Whether the triangle owns its edge `p -> q` on which the ray's point lies exactly (edge
/// function 0), by the top-left rule on the edge's inward normal in the ray's projection
/// plane: `ccw` tells on which side of `p -> q` the triangle lies.
#[inline]
fn owns_edge(p: (f64, f64), q: (f64, f64), ccw: bool) -> bool {
    let (ex, ey) = (q.0 - p.0, q.1 - p.1);
    // Inward normal: the left perpendicular (-ey, ex) for a counter-clockwise triangle.
    let (nx, ny) = if ccw { (-ey, ex) } else { (ey, -ex) };
    ny > 0.0 || (ny == 0.0 && nx > 0.0)
}

impl TraceRay {
    /// The ray `origin + t * dir`; `None` unless both are finite and `dir` is non-zero.
    /// Inlined: its division's latency then overlaps with the neighbouring rays' set-up.
    #[inline(always)]
    pub(crate) fn new(origin: DVec3, dir: DVec3) -> Option<Self> {
        if !origin.is_finite() || !dir.is_finite() || dir == DVec3::ZERO {
            return None;
        }
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        // All three reciprocals in one vector division; `1 / dir[kz]` is the shear's.
        let inv = DVec3::ONE / dir;
        let sz = inv[kz];
        Some(Self {
            origin,
            dir,
            k: [kx, ky, kz],
            shear: DVec3::new(dir[kx] * sz, dir[ky] * sz, sz),
            inv,
        })
    }

    /// The ray with this direction from `origin` (`TraceRay::new(origin, self.dir)` without
    /// its division: parallel rays share their set-up); `None` unless `origin` is finite.
    #[inline]
    pub(crate) fn from(&self, origin: DVec3) -> Option<Self> {
        origin.is_finite().then_some(Self { origin, ..*self })
    }

    /// The point at parameter `t`.
    #[inline]
    pub(crate) fn at(&self, t: f64) -> DVec3 {
        self.origin + t * self.dir
    }

    /// Parameter where the ray meets the triangle (either side), or `None`. Watertight; a
    /// point exactly on an edge or vertex belongs to one triangle (top-left rule).
    #[inline]
    pub(crate) fn intersect(&self, tri: &[DVec3; 3]) -> Option<f64> {
        // One specialisation per axis order, so that the components are picked by constant
        // indices rather than by a branch per component (the same operations in each).
        match self.k {
            [1, 2, 0] => self.intersect_axes::<1, 2, 0>(tri),
            [2, 1, 0] => self.intersect_axes::<2, 1, 0>(tri),
            [2, 0, 1] => self.intersect_axes::<2, 0, 1>(tri),
            [0, 2, 1] => self.intersect_axes::<0, 2, 1>(tri),
            [0, 1, 2] => self.intersect_axes::<0, 1, 2>(tri),
            _ => self.intersect_axes::<1, 0, 2>(tri),
        }
    }

    /// [`TraceRay::intersect`] for the axes `[KX, KY, KZ] == self.k`.
    #[inline(always)]
    fn intersect_axes<const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        tri: &[DVec3; 3],
    ) -> Option<f64> {
        let (sx, sy, sz) = (self.shear.x, self.shear.y, self.shear.z);
        let a = (tri[0] - self.origin).to_array();
        let b = (tri[1] - self.origin).to_array();
        let c = (tri[2] - self.origin).to_array();
        let (ax, ay) = (a[KX] - sx * a[KZ], a[KY] - sy * a[KZ]);
        let (bx, by) = (b[KX] - sx * b[KZ], b[KY] - sy * b[KZ]);
        let (cx, cy) = (c[KX] - sx * c[KZ], c[KY] - sy * c[KZ]);
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        // Evaluated without short circuits: one branch, where the hit or miss is decided.
        let negative = (u < 0.0) | (v < 0.0) | (w < 0.0);
        let positive = (u > 0.0) | (v > 0.0) | (w > 0.0);
        if negative & positive {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        if u == 0.0 || v == 0.0 || w == 0.0 {
            // det = -2 * signed area of (A', B', C'), so the triangle is counter-clockwise in
            // the projection plane iff det < 0.
            let ccw = det < 0.0;
            let (pa, pb, pc) = ((ax, ay), (bx, by), (cx, cy));
            if (u == 0.0 && !owns_edge(pb, pc, ccw))
                || (v == 0.0 && !owns_edge(pc, pa, ccw))
                || (w == 0.0 && !owns_edge(pa, pb, ccw))
            {
                return None;
            }
        }
        let t = (u * (sz * a[KZ]) + v * (sz * b[KZ]) + w * (sz * c[KZ])) / det;
        t.is_finite().then_some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scenes::Geometry;

    fn geometry(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Geometry {
        let object = vec![0; triangles.len()];
        Geometry { positions, triangles, object }
    }

    /// A fan of `n` triangles around the origin in the plane z = 0, alternately wound.
    fn fan(n: u32) -> Geometry {
        let mut positions = vec![DVec3::ZERO];
        for k in 0..n {
            let a = std::f64::consts::TAU * f64::from(k) / f64::from(n);
            positions.push(DVec3::new(a.cos(), a.sin(), 0.0));
        }
        let triangles = (0..n)
            .map(|k| {
                let (p, q) = (1 + k, 1 + (k + 1) % n);
                if k % 2 == 0 {
                    [0, p, q]
                } else {
                    [q, 0, p]
                }
            })
            .collect();
        geometry(positions, triangles)
    }

    fn hits(g: &Geometry, ray: &TraceRay) -> usize {
        (0..g.len()).filter(|&t| ray.intersect(&g.corners(t)).is_some()).count()
    }

    #[test]
    fn rays_through_shared_vertices_and_edges_hit_exactly_one_triangle() {
        for n in [3, 4, 5, 6, 8, 12] {
            let g = fan(n);
            let mut targets = vec![DVec3::ZERO];
            for k in 0..n as usize {
                targets.push(0.5 * g.positions[1 + k]); // on an inner edge
                targets
                    .push(g.positions[1 + k] * 0.25 + g.positions[1 + (k + 1) % n as usize] * 0.25);
            }
            for target in targets {
                for origin in [
                    DVec3::new(0.0, 0.0, 3.0),
                    DVec3::new(0.3, -0.7, 2.0),
                    DVec3::new(-1.0, 0.5, -4.0),
                    DVec3::new(2.0, 2.0, 0.5),
                ] {
                    let ray = TraceRay::new(origin, target - origin).expect("finite");
                    assert_eq!(hits(&g, &ray), 1, "fan {n}, target {target}, origin {origin}");
                    let t = (0..g.len()).find_map(|t| ray.intersect(&g.corners(t)));
                    assert!((t.expect("hit") - 1.0).abs() < 1e-12);
                }
            }
        }
    }

    /// Exactly-zero edge functions: a 2 x 2 grid of unit quads (8 triangles, diagonals both
    /// ways) hit along dyadic directions through every vertex and edge midpoint, where the
    /// shear is exact and the ray's point lands exactly on the edges.
    #[test]
    fn exact_edge_and_vertex_hits_belong_to_one_triangle() {
        let positions: Vec<DVec3> =
            (0..9).map(|k| DVec3::new(f64::from(k % 3), f64::from(k / 3), 0.0)).collect();
        let mut triangles = Vec::new();
        for (qx, qy) in [(0u32, 0u32), (1, 0), (0, 1), (1, 1)] {
            let v = |dx: u32, dy: u32| (qy + dy) * 3 + qx + dx;
            if (qx + qy) % 2 == 0 {
                triangles.extend([[v(0, 0), v(1, 0), v(1, 1)], [v(0, 0), v(1, 1), v(0, 1)]]);
            } else {
                triangles.extend([[v(0, 0), v(1, 0), v(0, 1)], [v(1, 1), v(0, 1), v(1, 0)]]);
            }
        }
        let g = geometry(positions, triangles);
        for dir in [
            DVec3::NEG_Z,
            DVec3::new(0.5, 0.25, -1.0),
            DVec3::new(-0.25, 0.5, -1.0),
            DVec3::new(0.125, -0.375, 1.0),
        ] {
            for x2 in 1..4 {
                for y2 in 1..4 {
                    let target = DVec3::new(f64::from(x2) * 0.5, f64::from(y2) * 0.5, 0.0);
                    let ray = TraceRay::new(target - 4.0 * dir, dir).expect("finite");
                    assert_eq!(hits(&g, &ray), 1, "{dir} through {target}");
                }
            }
        }
    }

    #[test]
    fn degenerate_and_parallel_triangles_are_missed() {
        let ray = TraceRay::new(DVec3::new(0.1, 0.1, 5.0), DVec3::NEG_Z).expect("finite");
        let line = [DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0)];
        let point = [DVec3::ONE; 3];
        let edge_on = [DVec3::ZERO, DVec3::Z, DVec3::new(1.0, 1.0, 0.0)];
        for tri in [line, point, edge_on] {
            assert_eq!(ray.intersect(&tri), None);
        }
        assert!(TraceRay::new(DVec3::ZERO, DVec3::ZERO).is_none());
        assert!(TraceRay::new(DVec3::NAN, DVec3::X).is_none());
    }
}
