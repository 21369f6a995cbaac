//! `spheres`: non-overlapping icospheres floating above the ground.
//!
//! Smooth curved casters (and, being closed, curved receivers of their own and each other's
//! shadows). `count` spheres with radii uniform in `[min_radius, max_radius]`, each inside the
//! 10 x 10 footprint centred on the origin, its lowest point at a height uniform in
//! `[min_height, max_height]`, placed by rejection sampling so that no two spheres overlap.
//! If a sphere finds no free spot in 10 000 tries (only with very crowded parameters), it is
//! lifted above all the spheres placed before it instead, so it still overlaps none.
//!
//! Invariants: each sphere is an icosphere (the icosahedron with every triangle split into
//! four `subdivisions` times, new vertices pushed onto the sphere): `20 * 4^subdivisions`
//! triangles and `10 * 4^subdivisions + 2` vertices, watertight, normals out, all vertices on
//! the true sphere (so inside it, and no two meshes intersect). Spheres are emitted one after
//! the other: `count * 20 * 4^subdivisions` triangles (10 240 at the defaults).

use super::rng::Rng;
use super::{
    at_least, count_at_least, non_negative, positive, triangle_budget, Generator, ParamError,
    FOOTPRINT,
};
use crate::mesh::Mesh;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// The finest allowed `subdivisions` (1.3 M triangles per sphere).
pub const MAX_SUBDIVISIONS: u32 = 8;

/// Placement tries per sphere before it is lifted above the others.
const TRIES: u32 = 10_000;

/// Parameters of the `spheres` generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpheresParams {
    /// Number of spheres. Default 8.
    pub count: u32,
    /// Smallest radius, in world units. Default 0.4.
    pub min_radius: f64,
    /// Largest radius, in world units (below 5, so that a sphere fits the 10 x 10 footprint).
    /// Default 1.2.
    pub max_radius: f64,
    /// Icosphere subdivision level, 0 (the icosahedron, 20 triangles) to 8; each level
    /// multiplies the triangles by 4. Default 3 (1280 triangles per sphere).
    pub subdivisions: u32,
    /// Lowest height of a sphere's lowest point above the ground, in world units. Default 0.5.
    pub min_height: f64,
    /// Highest height of a sphere's lowest point above the ground, in world units. Default 3.
    pub max_height: f64,
    /// Random seed. Default 1.
    pub seed: u64,
}

impl Default for SpheresParams {
    fn default() -> Self {
        Self {
            count: 8,
            min_radius: 0.4,
            max_radius: 1.2,
            subdivisions: 3,
            min_height: 0.5,
            max_height: 3.0,
            seed: 1,
        }
    }
}

impl SpheresParams {
    /// Triangles of one sphere: `20 * 4^subdivisions` (saturating).
    pub fn triangles_per_sphere(&self) -> u64 {
        4u64.checked_pow(self.subdivisions).map_or(u64::MAX, |p| p.saturating_mul(20))
    }
}

impl Generator for SpheresParams {
    /// The number of triangles [`Generator::generate`] builds.
    fn triangle_count(&self) -> u64 {
        u64::from(self.count).saturating_mul(self.triangles_per_sphere())
    }

    fn validate(&self) -> Result<(), ParamError> {
        count_at_least("count", self.count, 1)?;
        if self.subdivisions > MAX_SUBDIVISIONS {
            return Err(ParamError::new(
                "subdivisions",
                format!("must be at most {MAX_SUBDIVISIONS}, got {}", self.subdivisions),
            ));
        }
        triangle_budget("count", self.triangle_count())?;
        positive("min_radius", self.min_radius)?;
        at_least("max_radius", self.max_radius, self.min_radius, "min_radius")?;
        if self.max_radius >= 0.5 * FOOTPRINT {
            return Err(ParamError::new(
                "max_radius",
                format!(
                    "{} is too large for the 10 x 10 footprint (must be below 5)",
                    self.max_radius
                ),
            ));
        }
        // Keep rejection sampling easy: the spheres' largest possible shadows straight down
        // must cover at most half of the footprint.
        let covered = f64::from(self.count) * PI * self.max_radius * self.max_radius;
        if covered > 0.5 * FOOTPRINT * FOOTPRINT {
            return Err(ParamError::new(
                "count",
                format!(
                    "{} spheres of radius up to {} would crowd the 10 x 10 footprint \
                     (their discs cover {covered:.1} of at most 50 square units)",
                    self.count, self.max_radius
                ),
            ));
        }
        non_negative("min_height", self.min_height)?;
        at_least("max_height", self.max_height, self.min_height, "min_height")
    }

    fn generate(&self) -> Mesh {
        if self.validate().is_err() {
            return Mesh::default();
        }
        let unit = icosphere(self.subdivisions);
        let mut rng = Rng::new(self.seed);
        let mut placed: Vec<(DVec3, f64)> = Vec::with_capacity(self.count as usize);
        let half = 0.5 * FOOTPRINT;
        for _ in 0..self.count {
            let radius = rng.range(self.min_radius, self.max_radius);
            let mut centre = DVec3::ZERO;
            let mut free = false;
            for _ in 0..TRIES {
                centre = DVec3::new(
                    rng.range(-half + radius, half - radius),
                    radius + rng.range(self.min_height, self.max_height),
                    rng.range(-half + radius, half - radius),
                );
                free = placed.iter().all(|&(c, r)| (c - centre).length() > r + radius);
                if free {
                    break;
                }
            }
            if !free {
                let top = placed.iter().fold(0.0f64, |top, &(c, r)| top.max(c.y + r));
                centre.y = top + self.min_height + radius;
            }
            placed.push((centre, radius));
        }
        let mut mesh = Mesh {
            positions: Vec::with_capacity(placed.len() * unit.positions.len()),
            triangles: Vec::with_capacity(self.triangle_count() as usize),
        };
        for (centre, radius) in placed {
            let base = mesh.positions.len() as u32;
            mesh.positions.extend(unit.positions.iter().map(|&p| centre + radius * p));
            mesh.triangles.extend(unit.triangles.iter().map(|t| t.map(|v| v + base)));
        }
        mesh
    }
}

/// The unit icosphere: the icosahedron with each triangle split into four `level` times, new
/// vertices projected onto the sphere. Watertight, normals out.
pub(crate) fn icosphere(level: u32) -> Mesh {
    let t = 0.5 * (1.0 + 5.0f64.sqrt());
    let raw = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let mut positions: Vec<DVec3> = raw.iter().map(|&p| DVec3::from_array(p).normalize()).collect();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        // One midpoint per undirected edge, shared by the two triangles that use the edge.
        let mut midpoints: BTreeMap<(u32, u32), u32> = BTreeMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<DVec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let p = (positions[a as usize] + positions[b as usize]).normalize();
                positions.push(p);
                positions.len() as u32 - 1
            })
        };
        let mut finer = Vec::with_capacity(4 * triangles.len());
        for &[a, b, c] in &triangles {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            finer.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = finer;
    }
    Mesh { positions, triangles }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::{assert_watertight, bit_identical, signed_volume6};
    use super::*;

    #[test]
    fn icospheres_are_closed_outward_and_round() {
        for level in 0..4 {
            let mesh = icosphere(level);
            let n = mesh.triangle_count();
            assert_eq!(n, 20 * 4usize.pow(level));
            assert_eq!(mesh.positions.len(), 10 * 4usize.pow(level) + 2);
            assert_watertight(&mesh, 0..n);
            let volume = signed_volume6(&mesh, 0..n) / 6.0;
            assert!(volume > 0.6 * 4.0 / 3.0 * PI && volume < 4.0 / 3.0 * PI, "{level}: {volume}");
            assert!(mesh.positions.iter().all(|p| (p.length() - 1.0).abs() < 1e-12));
        }
    }

    #[test]
    fn spheres_do_not_overlap_and_stay_in_the_footprint() {
        let p = SpheresParams {
            count: 14,
            max_radius: 1.0,
            subdivisions: 1,
            seed: 3,
            ..Default::default()
        };
        let mesh = p.generate();
        let per = p.triangles_per_sphere() as usize;
        assert_eq!(mesh.triangle_count(), 14 * per);
        assert_watertight(&mesh, 0..mesh.triangle_count());
        let vertices = mesh.positions.len() / 14;
        let spheres: Vec<(DVec3, f64)> = mesh
            .positions
            .chunks_exact(vertices)
            .map(|s| {
                let (lo, hi) = s.iter().fold((s[0], s[0]), |(lo, hi), &q| (lo.min(q), hi.max(q)));
                (0.5 * (lo + hi), 0.5 * (hi.x - lo.x))
            })
            .collect();
        for (i, &(c, r)) in spheres.iter().enumerate() {
            assert!((0.4 - 1e-9..=1.0 + 1e-9).contains(&r), "radius {r}");
            assert!(c.x.abs() + r <= 5.0 + 1e-9 && c.z.abs() + r <= 5.0 + 1e-9);
            assert!(c.y - r >= 0.5 - 1e-9, "{c} {r}");
            for &(d, s) in &spheres[..i] {
                assert!((c - d).length() > r + s - 1e-9, "overlap");
            }
            let volume = signed_volume6(&mesh, i * per..(i + 1) * per);
            assert!(volume > 0.0);
        }
    }

    #[test]
    fn seeds_decide_the_placement() {
        let p = SpheresParams { subdivisions: 0, ..Default::default() };
        assert!(bit_identical(&p.generate(), &p.generate()));
        assert_ne!(p.generate(), SpheresParams { seed: 2, ..p.clone() }.generate());
    }

    #[test]
    fn validation_names_the_key() {
        let bad = |p: SpheresParams| p.validate().expect_err("invalid").key;
        let d = SpheresParams::default;
        assert_eq!(bad(SpheresParams { count: 0, ..d() }), "count");
        assert_eq!(bad(SpheresParams { count: 100, ..d() }), "count");
        assert_eq!(bad(SpheresParams { subdivisions: 9, ..d() }), "subdivisions");
        assert_eq!(bad(SpheresParams { subdivisions: u32::MAX, ..d() }), "subdivisions");
        assert_eq!(
            bad(SpheresParams { count: 100, max_radius: 0.5, subdivisions: 8, ..d() }),
            "count"
        );
        assert_eq!(bad(SpheresParams { min_radius: 0.0, ..d() }), "min_radius");
        assert_eq!(bad(SpheresParams { max_radius: 0.3, ..d() }), "max_radius");
        assert_eq!(bad(SpheresParams { min_radius: 5.0, max_radius: 5.0, ..d() }), "max_radius");
        assert_eq!(bad(SpheresParams { min_height: -1.0, ..d() }), "min_height");
        assert_eq!(bad(SpheresParams { max_height: f64::NAN, ..d() }), "max_height");
    }
}
