//! Stage 3, pixel classification (Lecocq et al. 2014, section 4.1, Algorithm 1).
//!
//! Every pixel's surface point `p` (the G-buffer position at the pixel centre) is projected
//! into the map, and the texel it falls in is decoded:
//!
//! - **lit by one lookup**: `p` lies on the stored triangle's plane, `|p_z̃ - p_z| <= tol`,
//!   with `p_z̃` the stored depth extrapolated to `p` (equation 1); conservative
//!   rasterization kept the nearest triangle touching the texel, so nothing lies in front. An
//!   empty texel (no caster touches it) is lit by one lookup too. Choice: the error bounds of
//!   a packed texel make "`p_z̃ ≈ p_z`" vacuous for a steep triangle far from the texel
//!   centre, so `p` must also lie inside the triangle (allowing for the vertex quantization,
//!   [`Tri::may_contain`]), or the triangle's plane must be known at `p` as well as the
//!   receiver's own plane would be ([`Lookup::lies_on`]: a coplanar neighbour).
//! - **shadowed by one lookup**: the stored triangle passes in front of `p` (`p_z̃ < p_z -
//!   tol`, Algorithm 1's early rejection) and `p` lies inside its 2D projection whatever the
//!   vertex quantization ([`Tri::surely_contains`], exact predicates).
//! - **shadowed by the neighbourhood**: the same test succeeds for a triangle stored in one
//!   of the 8 neighbouring texels (they are tried in [`super::neighbourhood::RING`] order and
//!   the first hit ends the search).
//! - **uncertain** otherwise: left to silhouette recovery.
//!
//! Tolerance: the constant term of the shared bias rule ([`crate::depth_test`]), converted to
//! map-depth units, plus the decoded triangle's own error bound at `p`
//! ([`super::texel::Tri::error_at`]). No slope-scaled term: equation 1 evaluates the stored
//! plane at `p` itself, so a receiver's own triangle matches it to rounding at any slope
//! (the paper's point against slope-scaled bias, Fig. 6). Adjacent faces of a curved mesh
//! differ from it by their curvature and are sent to recovery.
//!
//! Counters: `lit_by_one_lookup`, `shadowed_by_one_lookup`, `shadowed_by_neighbourhood`,
//! `uncertain_pixels`, and `shadow_map_lookups` (texels decoded: 1 to 9 per pixel).

use super::neighbourhood::RING;
use super::texel::{LightSpace, SpsmMap, Tri};
use crate::depth_test::{texel_at, DepthTester};
use crate::frame::Frame;
use glam::{DVec2, DVec3};
use instrumentation::Counters;
use rayon::prelude::*;

/// The class of a pixel (Fig. 14).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum PixelClass {
    /// No surface, or a surface outside the light's map: lit, no lookup.
    #[default]
    Unmapped,
    /// Lit by a single lookup.
    LitOneLookup,
    /// Shadowed by the triangle of its own texel.
    ShadowedOneLookup,
    /// Shadowed by a triangle of the 3x3 neighbourhood (green in Fig. 14).
    ShadowedNeighbourhood,
    /// Uncertain: decided by silhouette recovery (red in Fig. 14).
    Uncertain,
}

impl PixelClass {
    /// The colour Fig. 14 marks the class with: green for the 3x3 neighbourhood, red for
    /// silhouette recovery, none for single lookups and unmapped pixels.
    pub fn fig14_colour(self) -> Option<[u8; 3]> {
        match self {
            PixelClass::ShadowedNeighbourhood => Some([0, 200, 0]),
            PixelClass::Uncertain => Some([220, 0, 0]),
            _ => None,
        }
    }
}

/// A surface point as the map sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapPoint {
    /// Position in the map, texels.
    pub xy: DVec2,
    /// Light depth.
    pub depth: f64,
    /// Map depth `z̃`.
    pub z: f64,
    /// Tolerance of depth comparisons, map-depth units (the constant bias).
    pub tol: f64,
    /// Whether the surface faces the light.
    pub facing: bool,
    /// World position of the surface point.
    pub position: DVec3,
    /// Unit normal of the surface.
    pub normal: DVec3,
}

/// Lookups into one SPSM: the map, the bias rule and the map's depth space.
#[derive(Debug, Clone, Copy)]
pub struct Lookup<'a> {
    /// The map.
    pub map: &'a SpsmMap,
    /// The shared bias rule.
    pub tester: DepthTester,
    /// The map's depth space.
    pub space: LightSpace,
}

impl Lookup<'_> {
    /// The map point of the surface point `position` with unit normal `normal`; `None` where
    /// it does not project (behind a spot light).
    #[inline]
    pub fn point(&self, position: DVec3, normal: DVec3) -> Option<MapPoint> {
        let (xy, depth) = self.tester.projector.project(position)?;
        let tol = self.space.z_tolerance(self.tester.constant, depth);
        let facing = normal.dot(self.tester.projector.direction_to(position)) > 0.0;
        Some(MapPoint { xy, depth, z: self.space.z(depth), tol, facing, position, normal })
    }

    /// The map-depth gradient per texel of the receiver's plane at `p`, from two points of
    /// the plane a texel away; `None` where the plane is seen edge-on.
    pub fn gradient(&self, p: &MapPoint) -> Option<DVec2> {
        let (position, normal) = (p.position, p.normal);
        let (t1, t2) = normal.any_orthonormal_pair();
        let size = self.space.texel_world_size(p.depth).max_element();
        let proj = &self.tester.projector;
        let (q1, d1) = proj.project(position + t1 * size)?;
        let (q2, d2) = proj.project(position + t2 * size)?;
        let (a, b) = (q1 - p.xy, q2 - p.xy);
        let (z1, z2) = (self.space.z(d1) - p.z, self.space.z(d2) - p.z);
        let det = a.x * b.y - a.y * b.x;
        let g = DVec2::new((z1 * b.y - z2 * a.y) / det, (a.x * z2 - b.x * z1) / det);
        g.is_finite().then_some(g)
    }

    /// Algorithm 1: whether `tri` passes in front of `p` there.
    #[inline]
    pub fn intersects(tri: &Tri, p: &MapPoint) -> bool {
        tri.depth_at(p.xy) < p.z - p.tol - tri.error_at(p.xy) && tri.surely_contains(p.xy)
    }

    /// Whether `p` lies on `tri`: on its plane, and inside its 2D projection (allowing for
    /// the vertex quantization) or, outside it, with the plane known at `p` as well as the
    /// receiver's own plane would be in that texel (a coplanar neighbour, as across the
    /// diagonal of a quad; a steep triangle's plane, uncertain far from its centre, does not
    /// light `p`).
    pub fn lies_on(&self, tri: &Tri, p: &MapPoint) -> bool {
        Self::lies_on_plane(tri, p, || self.gradient(p).map(|g| self.map.plane_error(p.z, g)))
    }

    /// [`Self::lies_on`] with the quantization bound of the receiver's plane in this map
    /// ([`SpsmMap::plane_error`] at its gradient; `None` where the plane has none) given by
    /// `receiver_error`, called only when needed: silhouette recovery tests nine texels
    /// against one receiver.
    pub fn lies_on_plane(
        tri: &Tri,
        p: &MapPoint,
        receiver_error: impl FnOnce() -> Option<(f64, DVec2)>,
    ) -> bool {
        let err = tri.error_at(p.xy);
        if (tri.depth_at(p.xy) - p.z).abs() > p.tol + err {
            return false;
        }
        tri.may_contain(p.xy)
            || receiver_error().is_some_and(|(at_centre, per_texel)| {
                err <= p.tol + at_centre + (p.xy - tri.centre).abs().dot(per_texel)
            })
    }

    /// Classifies `p`; returns the class and the texels decoded.
    pub fn classify(&self, p: &MapPoint) -> (PixelClass, u64) {
        let Some((x, y)) = texel_at(p.xy, self.map.res) else {
            return (PixelClass::Unmapped, 0);
        };
        let (x, y) = (x as i64, y as i64);
        let Some(tri) = self.map.get(x, y) else {
            return (PixelClass::LitOneLookup, 1);
        };
        if self.lies_on(&tri, p) {
            return (PixelClass::LitOneLookup, 1);
        }
        if Self::intersects(&tri, p) {
            return (PixelClass::ShadowedOneLookup, 1);
        }
        let mut lookups = 1;
        for (dx, dy) in RING {
            lookups += 1;
            if let Some(t) = self.map.get(x + dx, y + dy) {
                if Self::intersects(&t, p) {
                    return (PixelClass::ShadowedNeighbourhood, lookups);
                }
            }
        }
        (PixelClass::Uncertain, lookups)
    }
}

/// An uncertain pixel and the texel its point falls in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UncertainPixel {
    /// Pixel index, row by row.
    pub pixel: u32,
    /// Texel index, row by row.
    pub texel: u32,
}

/// Classifies every pixel of the frame in parallel: the class, the lit value (1 or 0; 0 for
/// uncertain pixels until recovery decides), the uncertain pixels and the counters.
pub fn classify_pixels(
    frame: &Frame<'_>,
    lookup: &Lookup<'_>,
) -> (Vec<PixelClass>, Vec<f32>, Vec<UncertainPixel>, Counters) {
    let g = &frame.gbuffer;
    let res = lookup.map.res;
    let out: Vec<(PixelClass, u64, u32)> = (0..g.triangle.len())
        .into_par_iter()
        .map(|k| {
            if !g.covered(k) {
                return (PixelClass::Unmapped, 0, 0);
            }
            match lookup.point(g.position[k], g.normal[k]) {
                Some(p) => {
                    let (class, lookups) = lookup.classify(&p);
                    let texel =
                        texel_at(p.xy, res).map_or(0, |(x, y)| (y * res as usize + x) as u32);
                    (class, lookups, texel)
                }
                None => (PixelClass::Unmapped, 0, 0),
            }
        })
        .collect();
    let mut c = Counters::default();
    let mut uncertain = Vec::new();
    let mut lit = Vec::with_capacity(out.len());
    for (k, &(class, lookups, texel)) in out.iter().enumerate() {
        c.shadow_map_lookups += lookups;
        let value = match class {
            PixelClass::Unmapped => 1.0,
            PixelClass::LitOneLookup => {
                c.lit_by_one_lookup += 1;
                1.0
            }
            PixelClass::ShadowedOneLookup => {
                c.shadowed_by_one_lookup += 1;
                0.0
            }
            PixelClass::ShadowedNeighbourhood => {
                c.shadowed_by_neighbourhood += 1;
                0.0
            }
            PixelClass::Uncertain => {
                c.uncertain_pixels += 1;
                uncertain.push(UncertainPixel { pixel: k as u32, texel });
                0.0
            }
        };
        lit.push(value);
    }
    (out.into_iter().map(|o| o.0).collect(), lit, uncertain, c)
}
