//! Stage "visibility evaluation" (section 3.4): every TT-pair's triangle against every pixel
//! of its texel's PT list, the occluded sub-samples ORed into the pixel's occlusion mask.
//!
//! A triangle is four world-space half-spaces ([`Occluder`]): three through its edges and the
//! light ("a triangle using three half-planes defined by its edges", seen from the light:
//! the plane through the edge and the light direction, or the spot light's position), and the
//! side of its plane away from the light ("the intersection line of the triangle and the
//! tangent plane"), shifted by the shadow offset. A facet point is occluded when it lies in
//! all four: the light's ray from it crosses the triangle at least the offset before reaching
//! it. Each half-space becomes a screen half-plane through the facet ([`FacetMap`]), each
//! half-plane a mask of sub-samples ([`Coverage`]: the lookup table or the exact test); the
//! masks are ANDed and the result ORed into the pixel's mask. Half-planes whose line misses
//! the pixel cost no lookup, and the depth half-plane goes first: a triangle wholly behind a
//! facet (or coplanar with it, like the receiver's own neighbours) is rejected after one
//! plane.
//!
//! **Shadow predicate.** Equivalent to `afsm`'s and the ray tracer's (see
//! [`crate::afsm`]): the pixel's own G-buffer triangle is excluded, and a triangle shadows a
//! point only when it crosses the point's light ray more than its [`occluder_offset`] before
//! the point ([`crate::afsm::SHADOW_OFFSET`] times the magnitude of the triangle's and the
//! camera's coordinates, the local scale of `afsm`'s offset: never the scene's size, so a
//! far-away object does not remove shadows), measured along the ray for directional lights
//! (exactly the ray tracer's rule) and perpendicular to the triangle's plane for spot lights
//! (the distance along the ray is not linear in the point; the two differ only for casters
//! within the offset of the receiver, i.e. in contact).
//!
//! Ties: a sub-sample exactly on an edge's line is covered (closed edges, so that a sample on
//! an edge shared by two triangles is covered by both and a shadow has no cracks); one exactly
//! at the offset depth is not.
//!
//! Parallel over TT-pairs (rayon, pairs sorted by PT-list length so that neighbouring tasks
//! do similar work); the masks are updated with atomic OR, so the result does not depend on
//! scheduling. On curved receivers the same pass notes the candidates of the validity mask,
//! as the paper integrates that mask into the evaluation ([`super::validity`]).

use super::coverage::Coverage;
use super::facets::Facet;
use super::mask::Mask;
use super::pairs::{TexelLists, TtPair};
use super::screen::{CameraBasis, Crossing, FacetMap, HalfPlane, WorldPlane};
use super::silhouette::LightModel;
use glam::DVec3;
use rayon::prelude::*;
use scenes::Geometry;

/// TT-pairs per parallel task.
const PAIRS_PER_TASK: usize = 8;

/// A caster triangle as four world half-spaces, the occluded side of each positive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Occluder {
    /// The three edge planes (inside `>= 0`), then the depth plane (occluding `> 0`).
    pub planes: [WorldPlane; 4],
}

impl Occluder {
    /// The occluder of the triangle `corners` under `light`, with shadow offset `offset`
    /// (world units); `None` when the triangle is degenerate or seen edge-on by the light
    /// (it covers nothing).
    pub fn new(
        corners: [DVec3; 3],
        light: LightModel,
        offset: f64,
        camera: &CameraBasis,
    ) -> Option<Self> {
        let [a, b, c] = corners;
        let normal = (b - a).cross(c - a);
        let mut planes = [WorldPlane::default(); 4];
        for e in 0..3 {
            let (p, q, r) = (corners[e], corners[(e + 1) % 3], corners[(e + 2) % 3]);
            let n = (q - p).cross(light.towards(p));
            let side = n.dot(r - p);
            if side == 0.0 || !side.is_finite() {
                return None;
            }
            let n = n * side.signum();
            planes[e] = WorldPlane::new(n, n.dot(p), camera);
        }
        let c0 = normal.dot(a);
        let (n, c) = match light {
            LightModel::Towards(w) => {
                // Hit of the ray X + u w with the plane: u = (c0 - N·X) / N·w > offset.
                let nw = normal.dot(w);
                if nw == 0.0 {
                    return None;
                }
                let s = nw.signum();
                (-s * normal, -s * (c0 - offset * nw))
            }
            LightModel::At(l) => {
                // X on the far side of the plane from the light, by more than the offset.
                let sl = normal.dot(l) - c0;
                if sl == 0.0 {
                    return None;
                }
                let s = sl.signum();
                (-s * normal, -s * c0 + offset * normal.length())
            }
        };
        if !(n.is_finite() && c.is_finite()) {
            return None;
        }
        planes[3] = WorldPlane::new(n, c, camera);
        Some(Self { planes })
    }

    /// The sub-samples of the facet seen through `map` that the triangle occludes.
    #[inline(always)]
    pub fn occlusion<M: Mask, C: Coverage<M>>(&self, map: &FacetMap, coverage: &C) -> M {
        self.occlusion_and_depth(map, coverage).0
    }

    /// [`Occluder::occlusion`], and the depth half-plane on the screen.
    #[inline(always)]
    pub fn occlusion_and_depth<M: Mask, C: Coverage<M>>(
        &self,
        map: &FacetMap,
        coverage: &C,
    ) -> (M, HalfPlane) {
        let depth = map.half_plane(&self.planes[3]);
        let mut m = coverage.open(&depth);
        for plane in &self.planes[..3] {
            if m == M::ZERO {
                break;
            }
            m &= coverage.closed(&map.half_plane(plane));
        }
        (m, depth)
    }
}

/// The shadow offset of the triangle `corners` seen from `eye`: [`crate::afsm::SHADOW_OFFSET`]
/// times the largest coordinate magnitude of `eye` and the corners plus the largest distance
/// (max norm) from `eye` to a corner, the scale of the rounding of the points it is compared
/// with (`afsm::shadow_offset` at the triangle instead of the sample).
pub fn occluder_offset(eye: DVec3, corners: [DVec3; 3]) -> f64 {
    let magnitude =
        corners.iter().map(|c| c.abs().max_element()).fold(eye.abs().max_element(), f64::max)
            + corners.iter().map(|&c| (c - eye).abs().max_element()).fold(0.0, f64::max);
    crate::afsm::SHADOW_OFFSET * magnitude
}

/// What the evaluation needs of the frame.
#[derive(Debug, Clone, Copy)]
pub struct Scene<'a> {
    /// All triangles.
    pub geometry: &'a Geometry,
    /// The light.
    pub light: LightModel,
    /// The camera's position (the projector's origin), the point the offsets are measured
    /// from.
    pub eye: DVec3,
    /// The camera's rays.
    pub camera: &'a CameraBasis,
}

/// The result of the visibility evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct Occlusion<M> {
    /// Occlusion mask per silhouette facet.
    pub masks: Vec<M>,
    /// Triangle-pixel evaluations made.
    pub evaluations: u64,
    /// `(facet, triangle)` pairs for the validity mask (when asked for): the triangle's plane
    /// cuts the pixel and lies nearer the light than the facet on the side away from the
    /// centre ([`super::validity`]).
    pub validity_candidates: Vec<(u32, u32)>,
}

/// The occlusion mask of every silhouette facet: every TT-pair's triangle against every pixel
/// of its texel's PT list (less the pixel's own triangle), in parallel over the pairs. With
/// `validity`, also the candidates of the validity mask.
pub fn occlusion_masks<M: Mask, C: Coverage<M>>(
    scene: &Scene<'_>,
    tt: &[TtPair],
    pt: &TexelLists,
    facets: &[Facet],
    coverage: &C,
    validity: bool,
) -> Occlusion<M> {
    let masks: Vec<M::Atomic> = (0..facets.len()).map(|_| M::atomic(M::ZERO)).collect();
    let (evaluations, validity_candidates) = tt
        .par_iter()
        .with_min_len(PAIRS_PER_TASK)
        .fold(
            || (0u64, Vec::new()),
            |(mut evaluations, mut candidates), pair| {
                let t = pair.triangle;
                let corners = scene.geometry.corners(t as usize);
                let offset = occluder_offset(scene.eye, corners);
                let Some(occluder) = Occluder::new(corners, scene.light, offset, scene.camera)
                else {
                    return (evaluations, candidates);
                };
                for &f in pt.of(pair.texel as usize) {
                    let facet = &facets[f as usize];
                    if facet.triangle == t {
                        continue;
                    }
                    evaluations += 1;
                    let (m, depth) = occluder.occlusion_and_depth(&facet.map, coverage);
                    if m != M::ZERO {
                        M::fetch_or(&masks[f as usize], m);
                    }
                    if validity && depth.g0 <= 0.0 && depth.crossing() == Crossing::Split {
                        candidates.push((f, t));
                    }
                }
                (evaluations, candidates)
            },
        )
        .reduce(
            || (0, Vec::new()),
            |(a, mut ca), (b, cb)| {
                ca.extend(cb);
                (a + b, ca)
            },
        );
    Occlusion { masks: masks.iter().map(M::load).collect(), evaluations, validity_candidates }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pan09::coverage::ExactCoverage;
    use crate::pattern::{PatternKind, SamplePattern};
    use glam::DVec2;
    use proptest::prelude::*;
    use scenes::projection::{look_basis, ProjectionKind, Projector};

    fn camera() -> Projector {
        let (right, up, forward) = look_basis(DVec3::new(0.1, -0.7, -1.0), DVec3::Y);
        Projector {
            origin: DVec3::new(0.0, 4.0, 5.0),
            right,
            up,
            forward,
            kind: ProjectionKind::Perspective { tan_half_x: 0.5, tan_half_y: 0.4 },
            near: 0.01,
            width: 40.0,
            height: 32.0,
        }
    }

    /// Whether the segment from `x` towards the light crosses the triangle beyond `offset`
    /// (brute force in world space, for comparison).
    fn occluded(x: DVec3, tri: [DVec3; 3], light: LightModel, offset: f64) -> bool {
        let [a, b, c] = tri;
        let n = (b - a).cross(c - a);
        let d = light.towards(x);
        let denom = n.dot(d);
        if denom == 0.0 {
            return false;
        }
        let u = (n.dot(a) - n.dot(x)) / denom;
        let limit = match light {
            LightModel::Towards(_) => f64::INFINITY,
            LightModel::At(_) => 1.0,
        };
        if !(u > 0.0 && u < limit) {
            return false;
        }
        let dist = match light {
            LightModel::Towards(_) => u,
            LightModel::At(_) => (n.dot(x) - n.dot(a)).abs() / n.length(),
        };
        if dist <= offset {
            return false;
        }
        let p = x + u * d;
        let inside = |p0: DVec3, p1: DVec3| n.dot((p1 - p0).cross(p - p0)) >= 0.0;
        inside(a, b) && inside(b, c) && inside(c, a)
    }

    proptest! {
        /// The screen masks of every sub-sample equal the world-space segment test at the
        /// sub-sample's facet point, away from the lines (rounding).
        #[test]
        fn masks_equal_the_world_segment_test(
            tri in proptest::collection::vec((-1.5f64..1.5, 0.05f64..1.5, -1.5f64..1.5), 3),
            px in 10u32..30, py in 10u32..22,
            spot in any::<bool>(),
            tilt in (-0.3f64..0.3, -0.3f64..0.3),
        ) {
            let cam = camera();
            let basis = CameraBasis::new(&cam);
            let light = if spot {
                LightModel::At(DVec3::new(1.0, 5.0, 0.5))
            } else {
                LightModel::Towards(DVec3::new(0.3, 1.0, 0.2).normalize())
            };
            let normal = DVec3::new(tilt.0, 1.0, tilt.1).normalize();
            let centre = DVec2::new(f64::from(px) + 0.5, f64::from(py) + 0.5);
            let ray = cam.ray(centre);
            let Some(t) = ray.intersect_plane(DVec3::Y, 0.0) else { return Ok(()) };
            let x0 = ray.at(t);
            let Some(map) = FacetMap::new(&basis, centre, normal, normal.dot(x0)) else {
                return Ok(());
            };
            let corners = [0, 1, 2].map(|i| DVec3::new(tri[i].0, tri[i].1, tri[i].2) + x0);
            let offset = 1e-6;
            let Some(occ) = Occluder::new(corners, light, offset, &basis) else { return Ok(()) };
            let pattern = SamplePattern::new(32, PatternKind::Grid).expect("valid");
            let cov = ExactCoverage::<u32>::new(&pattern);
            let m: u32 = occ.occlusion(&map, &cov);
            for (s, o) in pattern.offsets().iter().enumerate() {
                let u = *o - DVec2::splat(0.5);
                let x = map.point_at(&basis, u);
                // Skip samples within rounding of a plane.
                let near_line = occ.planes.iter().any(|p| {
                    let h = map.half_plane(p);
                    h.at(u).abs() <= 1e-9 * (h.g0.abs() + h.gx.abs() + h.gy.abs())
                });
                if near_line {
                    continue;
                }
                prop_assert_eq!(m >> s & 1 == 1, occluded(x, corners, light, offset), "sample {}", s);
            }
        }
    }
}
