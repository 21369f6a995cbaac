//! Procedural generators: seeded, deterministic meshes for the benchmark scenes.
//!
//! Each generator is a parameter struct (serde, `deny_unknown_fields`, every field defaulted)
//! that implements [`Generator`]. Scene files name them with `kind = "..."`.
//!
//! | generator | builds | stands for | triangles at defaults |
//! |---|---|---|---|
//! | [`plane`] | a subdivided square at y = 0, normal +y | ground receiver | 2 |
//! | [`random_triangles`] | disconnected random triangles of constant total area | Aila & Laine 2004, Table 1 | 1 000 |
//! | [`cage`] | a box-shaped cage of thin square bars (closed boxes) | Pan et al. 2009, Fig. 11 | 1 584 |
//! | [`spheres`] | non-overlapping floating icospheres | smooth curved casters | 10 240 |
//! | [`city`] | a grid of closed boxes of random heights | grazing light, long shadows | 768 |
//! | [`plant`] | thin folded leaves around thin stems | Pan et al. 2009, Fig. 12(c) | 1 960 |
//! | [`heightfield`] | a densely tessellated bumpy receiver | Pan et al. 2009, Fig. 9 | 131 072 |
//! | [`hairball`] | thin open tubes leaving a sphere (render with opacity 0.1) | Aila & Laine 2004, Fig. 1 | 72 000 |
//!
//! Conventions shared by all generators:
//!
//! - World y-up, right-handed; the ground is y = 0. `plane` and `heightfield` are receivers
//!   centred on the origin; every other generator builds casters only (no ground), centred on
//!   the origin in x and z, with no vertex below y = 0, and fitting a 10 x 10 footprint at
//!   their defaults.
//! - Triangles are counter-clockwise seen from the front; closed parts (boxes, spheres, bars,
//!   stems) are watertight (shared vertices, every edge used by exactly two triangles in
//!   opposite directions) with normals pointing out.
//! - Determinism: the same parameters (seed included) give the bit-identical mesh on every
//!   platform: randomness comes from [`rng::Rng`], trigonometry from [`rng::sin_cos`], and all
//!   loops run in a fixed order.
//! - [`Generator::validate`] names the bad key; [`Generator::generate`] on invalid parameters
//!   returns an empty mesh (it never panics, and never tries to allocate an absurd mesh).
//!   No generator builds more than [`MAX_TRIANGLES`] triangles, and each knows how many it
//!   builds before building them ([`Generator::triangle_count`], exact on valid parameters).

use crate::mesh::Mesh;
use glam::DVec3;

pub mod cage;
pub mod city;
pub mod hairball;
pub mod heightfield;
pub mod plane;
pub mod plant;
pub mod random_triangles;
pub mod rng;
pub mod spheres;

pub use cage::CageParams;
pub use city::CityParams;
pub use hairball::HairballParams;
pub use heightfield::HeightfieldParams;
pub use plane::PlaneParams;
pub use plant::PlantParams;
pub use random_triangles::RandomTrianglesParams;
pub use spheres::SpheresParams;

/// The most triangles any generator may build (20 M); larger requests fail validation.
pub const MAX_TRIANGLES: u64 = 20_000_000;

/// The largest length (or area) any parameter may take, 1e9 world units: far beyond any
/// scene, and small enough that no sum or product of parameters overflows.
pub const MAX_LENGTH: f64 = 1e9;

/// The smallest length (or area) a parameter that must be positive may take, 1e-9 world units:
/// far below any scene, and large enough that no ratio of parameters overflows.
pub const MIN_LENGTH: f64 = 1e-9;

/// The side of the square footprint, centred on the origin, that casters fill at their
/// defaults (`spheres` and `city` fill exactly this square).
pub const FOOTPRINT: f64 = 10.0;

/// A procedural mesh generator: a parameter struct that can check itself, say how many
/// triangles it builds, and build its mesh.
pub trait Generator {
    /// The number of triangles [`Generator::generate`] builds on valid parameters, computed
    /// from the parameters alone (nothing is generated; saturating, so that absurd parameters
    /// give a huge count rather than an overflow). Scenes sum these to refuse, before building
    /// anything, a scene beyond [`crate::limits::MAX_SCENE_TRIANGLES`].
    fn triangle_count(&self) -> u64;
    /// Checks the parameters; the error names the bad key.
    fn validate(&self) -> Result<(), ParamError>;
    /// Builds the mesh (call validate first; generate on invalid params may return a degenerate
    /// mesh but must not panic). The generators here return an empty mesh on invalid params.
    fn generate(&self) -> Mesh;
}

/// A generator parameter that is out of range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{key}`: {message}")]
pub struct ParamError {
    /// The parameter's key, as written in scene files.
    pub key: &'static str,
    /// What is wrong with it.
    pub message: String,
}

impl ParamError {
    /// An error for `key`.
    pub fn new(key: &'static str, message: impl Into<String>) -> Self {
        Self { key, message: message.into() }
    }
}

/// `value` must be positive: in `[MIN_LENGTH, MAX_LENGTH]`.
pub(crate) fn positive(key: &'static str, value: f64) -> Result<(), ParamError> {
    if (MIN_LENGTH..=MAX_LENGTH).contains(&value) {
        Ok(())
    } else {
        Err(ParamError::new(
            key,
            format!("must be a positive number in [{MIN_LENGTH:e}, {MAX_LENGTH:e}], got {value}"),
        ))
    }
}

/// `value` must be in `[0, MAX_LENGTH]`.
pub(crate) fn non_negative(key: &'static str, value: f64) -> Result<(), ParamError> {
    if (0.0..=MAX_LENGTH).contains(&value) {
        Ok(())
    } else {
        Err(ParamError::new(key, format!("must be a number in [0, {MAX_LENGTH:e}], got {value}")))
    }
}

/// `value` must be in `[min, MAX_LENGTH]`, `min` being another parameter (named in the
/// message).
pub(crate) fn at_least(
    key: &'static str,
    value: f64,
    min: f64,
    min_name: &str,
) -> Result<(), ParamError> {
    if value >= min && value <= MAX_LENGTH {
        Ok(())
    } else {
        Err(ParamError::new(
            key,
            format!("must be at least {min_name} ({min}) and at most {MAX_LENGTH:e}, got {value}"),
        ))
    }
}

/// A count must be at least `min`.
pub(crate) fn count_at_least(key: &'static str, value: u32, min: u32) -> Result<(), ParamError> {
    if value >= min {
        Ok(())
    } else {
        Err(ParamError::new(key, format!("must be at least {min}, got {value}")))
    }
}

/// The mesh would have `triangles` triangles; blames `key` when that exceeds [`MAX_TRIANGLES`].
pub(crate) fn triangle_budget(key: &'static str, triangles: u64) -> Result<(), ParamError> {
    if triangles <= MAX_TRIANGLES {
        Ok(())
    } else {
        Err(ParamError::new(
            key,
            format!("would build {triangles} triangles, more than the limit of {MAX_TRIANGLES}"),
        ))
    }
}

/// Appends the closed box `[min, max]`: 8 vertices, 12 triangles, normals out.
pub(crate) fn push_box(mesh: &mut Mesh, min: DVec3, max: DVec3) {
    let base = mesh.positions.len() as u32;
    // Vertex v has x from bit 0, y from bit 1, z from bit 2 (0 = min, 1 = max).
    for v in 0..8u32 {
        let pick = |bit: u32, lo: f64, hi: f64| if v & bit == 0 { lo } else { hi };
        mesh.positions.push(DVec3::new(
            pick(1, min.x, max.x),
            pick(2, min.y, max.y),
            pick(4, min.z, max.z),
        ));
    }
    const FACES: [[u32; 3]; 12] = [
        [0, 4, 6], // -x
        [0, 6, 2],
        [1, 3, 7], // +x
        [1, 7, 5],
        [0, 1, 5], // -y
        [0, 5, 4],
        [2, 6, 7], // +y
        [2, 7, 3],
        [0, 2, 3], // -z
        [0, 3, 1],
        [4, 5, 7], // +z
        [4, 7, 6],
    ];
    mesh.triangles.extend(FACES.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
}

/// Unit tangents of a polyline: the direction of the first and last segments at the ends, the
/// normalised sum of the two adjacent segment directions inside. Zero-length segments fall back
/// to the previous tangent (or +y).
pub(crate) fn polyline_tangents(points: &[DVec3]) -> Vec<DVec3> {
    let n = points.len();
    let mut tangents = Vec::with_capacity(n);
    let mut last = DVec3::Y;
    for i in 0..n {
        let prev =
            if i > 0 { (points[i] - points[i - 1]).normalize_or_zero() } else { DVec3::ZERO };
        let next =
            if i + 1 < n { (points[i + 1] - points[i]).normalize_or_zero() } else { DVec3::ZERO };
        last = (prev + next).normalize_or(last);
        tangents.push(last);
    }
    tangents
}

/// Parallel-transported frames `(normal, binormal)` along a curve with unit `tangents`: each
/// normal is the previous one with its tangential part removed, so the frame twists as little as
/// possible. `tangent × normal = binormal`.
pub(crate) fn transported_frames(tangents: &[DVec3]) -> Vec<(DVec3, DVec3)> {
    let mut frames = Vec::with_capacity(tangents.len());
    let Some(&first) = tangents.first() else {
        return frames;
    };
    let mut normal = first.any_orthonormal_pair().0;
    for &t in tangents {
        let projected = normal - normal.dot(t) * t;
        normal = projected.normalize_or(t.any_orthonormal_pair().0);
        frames.push((normal, t.cross(normal)));
    }
    frames
}

/// Appends a tube of `sides` (>= 3) around the curve `points` with unit `tangents` (same
/// length): a ring of `sides` vertices per point and two triangles per side and segment, normals
/// out. With `capped`, each end is closed by a fan around a centre vertex, which makes the tube
/// watertight. Triangles: `2 * sides * (points - 1)`, plus `2 * sides` when capped.
pub(crate) fn push_tube(
    mesh: &mut Mesh,
    points: &[DVec3],
    tangents: &[DVec3],
    radius: f64,
    sides: u32,
    capped: bool,
) {
    if points.len() < 2 || tangents.len() != points.len() || sides < 3 {
        return;
    }
    let base = mesh.positions.len() as u32;
    let ring: Vec<(f64, f64)> = (0..sides)
        .map(|j| rng::sin_cos(std::f64::consts::TAU * f64::from(j) / f64::from(sides)))
        .collect();
    for (&p, (n, b)) in points.iter().zip(transported_frames(tangents)) {
        for &(s, c) in &ring {
            mesh.positions.push(p + radius * (c * n + s * b));
        }
    }
    let vertex = |i: usize, j: u32| base + i as u32 * sides + j % sides;
    for i in 0..points.len() - 1 {
        for j in 0..sides {
            let (a, b) = (vertex(i, j), vertex(i, j + 1));
            let (c, d) = (vertex(i + 1, j + 1), vertex(i + 1, j));
            mesh.triangles.push([a, b, c]);
            mesh.triangles.push([a, c, d]);
        }
    }
    if capped {
        let last = points.len() - 1;
        let start = mesh.positions.len() as u32;
        mesh.positions.push(points[0]);
        mesh.positions.push(points[last]);
        for j in 0..sides {
            mesh.triangles.push([start, vertex(0, j + 1), vertex(0, j)]);
            mesh.triangles.push([start + 1, vertex(last, j), vertex(last, j + 1)]);
        }
    }
}

#[cfg(test)]
pub(crate) mod testutil {
    //! Mesh checks shared by the generators' unit tests.

    use crate::mesh::Mesh;
    use std::collections::BTreeMap;

    /// Every undirected edge of `triangles` is used exactly twice, once in each direction.
    pub fn assert_watertight(mesh: &Mesh, triangles: std::ops::Range<usize>) {
        let mut edges: BTreeMap<(u32, u32), i32> = BTreeMap::new();
        for t in &mesh.triangles[triangles] {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                assert_ne!(a, b, "degenerate triangle {t:?}");
                *edges.entry((a.min(b), a.max(b))).or_default() += if a < b { 1 } else { 100 };
            }
        }
        for (edge, uses) in edges {
            assert_eq!(uses, 101, "edge {edge:?} is not shared by two opposite half-edges");
        }
    }

    /// Six times the signed volume enclosed by `triangles` (positive when normals point out).
    pub fn signed_volume6(mesh: &Mesh, triangles: std::ops::Range<usize>) -> f64 {
        triangles
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                a.dot(b.cross(c))
            })
            .sum()
    }

    /// Bitwise equality of two meshes (`-0.0` and `0.0` differ, NaNs with equal bits agree).
    pub fn bit_identical(a: &Mesh, b: &Mesh) -> bool {
        a.triangles == b.triangles
            && a.positions.len() == b.positions.len()
            && a.positions
                .iter()
                .zip(&b.positions)
                .all(|(p, q)| p.to_array().map(f64::to_bits) == q.to_array().map(f64::to_bits))
    }
}

#[cfg(test)]
mod tests {
    use super::testutil::*;
    use super::*;

    #[test]
    fn a_box_is_closed_and_outward() {
        let mut mesh = Mesh::default();
        push_box(&mut mesh, DVec3::new(-1.0, 0.0, 2.0), DVec3::new(1.0, 3.0, 2.5));
        assert_eq!(mesh.triangle_count(), 12);
        assert_watertight(&mesh, 0..12);
        assert!((signed_volume6(&mesh, 0..12) / 6.0 - 2.0 * 3.0 * 0.5).abs() < 1e-12);
        assert!((mesh.area() - 2.0 * (6.0 + 1.0 + 1.5)).abs() < 1e-12);
    }

    #[test]
    fn a_capped_tube_is_closed_and_outward() {
        let points: Vec<DVec3> =
            (0..6).map(|i| DVec3::new(0.3 * f64::from(i), f64::from(i), 0.1)).collect();
        let tangents = polyline_tangents(&points);
        let mut mesh = Mesh::default();
        push_tube(&mut mesh, &points, &tangents, 0.05, 5, true);
        let n = mesh.triangle_count();
        assert_eq!(n, 2 * 5 * 5 + 2 * 5);
        assert_watertight(&mesh, 0..n);
        assert!(signed_volume6(&mesh, 0..n) > 0.0);
    }

    #[test]
    fn frames_are_orthonormal_along_a_bend() {
        let points: Vec<DVec3> = (0..20)
            .map(|i| {
                let (s, c) = rng::sin_cos(0.2 * f64::from(i));
                DVec3::new(c, s, 0.05 * f64::from(i))
            })
            .collect();
        let tangents = polyline_tangents(&points);
        for (t, (n, b)) in tangents.iter().zip(transported_frames(&tangents)) {
            assert!((t.length() - 1.0).abs() < 1e-12 && (n.length() - 1.0).abs() < 1e-12);
            assert!(t.dot(n).abs() < 1e-12 && (b.length() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn every_generator_counts_its_triangles_before_building_them() {
        type Pair = (Box<dyn Generator>, Box<dyn Generator>);
        let generators: [(&str, Pair); 8] = [
            (
                "plane",
                (
                    Box::new(PlaneParams::default()),
                    Box::new(PlaneParams { subdivisions: 9, ..Default::default() }),
                ),
            ),
            (
                "random_triangles",
                (
                    Box::new(RandomTrianglesParams::default()),
                    Box::new(RandomTrianglesParams { count: 17, ..Default::default() }),
                ),
            ),
            (
                "cage",
                (
                    Box::new(CageParams::default()),
                    Box::new(CageParams { bars_per_side: 3, ..Default::default() }),
                ),
            ),
            (
                "spheres",
                (
                    Box::new(SpheresParams::default()),
                    Box::new(SpheresParams { count: 3, subdivisions: 1, ..Default::default() }),
                ),
            ),
            (
                "city",
                (
                    Box::new(CityParams::default()),
                    Box::new(CityParams { blocks: 3, ..Default::default() }),
                ),
            ),
            (
                "plant",
                (
                    Box::new(PlantParams::default()),
                    Box::new(PlantParams { leaves: 7, stems: 2, ..Default::default() }),
                ),
            ),
            (
                "heightfield",
                (
                    Box::new(HeightfieldParams::default()),
                    Box::new(HeightfieldParams { resolution: 5, ..Default::default() }),
                ),
            ),
            (
                "hairball",
                (
                    Box::new(HairballParams::default()),
                    Box::new(HairballParams { strands: 4, sides: 2, ..Default::default() }),
                ),
            ),
        ];
        for (name, (default, other)) in &generators {
            for g in [default, other] {
                assert!(g.validate().is_ok(), "{name}");
                assert_eq!(g.triangle_count(), g.generate().triangle_count() as u64, "{name}");
            }
        }
    }

    #[test]
    fn errors_name_the_key() {
        let e = positive("size", f64::NAN).expect_err("NaN");
        assert_eq!(e.key, "size");
        assert!(e.to_string().starts_with("`size`: "), "{e}");
        assert!(non_negative("h", -1.0).is_err() && non_negative("h", 0.0).is_ok());
        assert!(count_at_least("n", 0, 1).is_err() && count_at_least("n", 1, 1).is_ok());
        assert!(triangle_budget("n", MAX_TRIANGLES + 1).is_err());
        assert!(at_least("max", 1.0, 2.0, "min").is_err());
    }
}
