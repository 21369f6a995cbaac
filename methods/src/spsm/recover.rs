//! Stage 5, per-pixel shadow silhouette recovery (Lecocq et al. 2014, section 4.2, Figs. 7,
//! 8 and 10), for the pixels the classification left uncertain.
//!
//! 1. **Depth-test pattern** (consistent depth tests). Each texel of the 3x3 neighbourhood
//!    is *occluded* when its stored triangle
//!    - spawns a depth in front of the point inside the texel: its consistent minimum depth
//!      (stage 4) is below the point's depth by more than the constant bias; and
//!    - passes in front of the receiver's own plane there (the plane through the point with
//!      the receiver's normal): checked exactly at the vertices of the triangle clipped to the
//!      texel. This replaces the slope-scaled bias of a depth map: the receiver's own plane
//!      and every surface behind it (the rest of a convex receiver, a farther object seen
//!      beside a steep receiver) never count, whatever the slope. Choice: the paper compares
//!      the consistent depth with the point's depth only, which leaves a steep receiver's own
//!      neighbours, and the surfaces behind them, as false occluders; and
//!    - does not hold the point itself (a triangle the point lies on cannot occlude it).
//!
//!    Comparisons allow for the packed texel's quantization: the triangle's error bound, but
//!    no more than the bound the receiver's own plane would have in that texel
//!    ([`SpsmMap::plane_error`]): a steep triangle's large derivative uncertainty would
//!    otherwise hide every silhouette triangle, while a triangle nearly coplanar with the
//!    receiver has the receiver's error. The clipped vertices' own uncertainty (the vertex
//!    step) is added as the distance it can move the comparison.
//! 2. **4-connectivity.** Conservative rasterization records every triangle touching a
//!    texel, so a shadow edge that reaches the centre texel cannot come from an occluded texel
//!    linked to the centre only through a corner: occluded texels not 4-connected to the
//!    centre (through occluded texels) are discarded (Fig. 7b, c). Look-up table
//!    [`connectivity_table`], 512 entries addressed by the 9-bit pattern.
//! 3. **Tangent estimate.** The filtered ring of 8 neighbours, as an 8-bit mask, addresses a
//!    256-entry table of predetermined patterns ([`pattern_table`], Fig. 8): a full ring is an
//!    occluder covering the area (shadowed, "all depth tests positive"); an empty ring leaves
//!    the centre's own triangle, which does not contain the point (lit); otherwise every
//!    maximal run of free texels around the ring is one side of the shadow, and gives one
//!    tangent estimate, the axis perpendicular to the mean direction from the centre to that
//!    run. Several runs (a thin occluder crossing the neighbourhood, Fig. 8 bottom right)
//!    give several tangents; the point is shadowed only if every one says so (the
//!    intersection of the results).
//! 4. **Silhouette function** (Fig. 10). Along a tangent axis `T` with normal `N` pointing
//!    into the shadow, a map point `q` has position `t(q) = (q - o)·T` and signed distance
//!    `d(q) = (q - o)·N` (`o` the centre texel's centre; the paper puts `o` at the
//!    neighbourhood's corner on the lit side, which only shifts every distance by the same
//!    amount). The boundary vertices are those of the occluding triangles' edges that face
//!    the axis (outward normal against `N`); linked along the axis they form the piecewise
//!    linear `φ`: at each `t`, the nearest facing edge that spans `t`; across a gap between
//!    edges, the segment linking the two endpoints that bound the gap; beyond the outermost
//!    vertices, no boundary (`+∞`). Vertices behind a facing edge never define `φ`. The point
//!    is shadowed when `d(q) > φ(t(q))`.
//!
//! **Receivers facing away from the light** (their face normal, as the G-buffer stores it,
//! points away from it) whose filtered pattern holds an occluded texel are shadowed, whatever
//! the tangents say: light reaches such a point only through the surface it lies on, so a
//! closed caster's back side is in the shadow of its own front (what the reference's shadow
//! ray finds, crossing the mesh, and what a shaded image shows). The silhouette function
//! misses that occluder near the light's silhouette, where the front side is nearly edge-on
//! and its recorded edges stop short of the receiver. Where no occluder is found around it
//! (an open, single-sided surface seen from behind), the pattern decides as usual.
//!
//! The recovered function is kept per pixel (its texel, occluder mask and tangents), so the
//! antialiasing stage evaluates the same function at the sub-samples.

use super::classify::{Lookup, MapPoint, UncertainPixel};
use super::depth::{clip_to_texel, consistent_min_depth, ConsistentDepths};
use super::neighbourhood::{CENTRE_BIT, NEIGHBOURHOOD, RING};
use super::texel::{SpsmMap, Tri};
use crate::depth_test::texel_at;
use crate::frame::Frame;
use glam::DVec2;
use instrumentation::Counters;
use rayon::prelude::*;
use std::sync::OnceLock;

/// Grid position `(column, row)` in `0..3` of pattern bit `k`.
fn cell(k: usize) -> (i64, i64) {
    (NEIGHBOURHOOD[k].0 + 1, NEIGHBOURHOOD[k].1 + 1)
}

/// The occluded texels of a 9-bit pattern that are 4-connected to the centre through
/// occluded texels (the centre is the seed whether or not it is occluded itself).
pub fn connected(mask: u16) -> u16 {
    let index = |(c, r): (i64, i64)| -> usize { (0..9).find(|&k| cell(k) == (c, r)).unwrap_or(8) };
    let mut keep = mask & CENTRE_BIT;
    let mut stack = vec![(1i64, 1i64)];
    let mut seen = 1u16 << 8;
    while let Some((c, r)) = stack.pop() {
        for (dc, dr) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
            let (nc, nr) = (c + dc, r + dr);
            if !(0..3).contains(&nc) || !(0..3).contains(&nr) {
                continue;
            }
            let k = index((nc, nr));
            let bit = 1u16 << k;
            if seen & bit != 0 || mask & bit == 0 {
                continue;
            }
            seen |= bit;
            keep |= bit;
            stack.push((nc, nr));
        }
    }
    keep
}

/// The 4-connectivity look-up table: 512 entries, the kept pattern of each 9-bit pattern.
pub fn connectivity_table() -> &'static [u16; 512] {
    static TABLE: OnceLock<[u16; 512]> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut t = [0u16; 512];
        for (m, e) in t.iter_mut().enumerate() {
            *e = connected(m as u16);
        }
        t
    })
}

/// What a ring pattern says.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Pattern {
    /// No occluded neighbour: lit.
    Lit,
    /// Every neighbour occluded: an occluder covers the area, shadowed.
    Shadowed,
    /// Recover the silhouette along each tangent: the unit normals `N` (pointing into the
    /// shadow) of the first `count` entries.
    Tangents {
        /// Number of tangent estimates (runs of free neighbours), 1 to 4.
        count: u8,
        /// Their normals.
        normals: [DVec2; 4],
    },
}

/// The tangent estimates of an 8-bit ring mask (bit set: occluded).
pub fn pattern(ring: u8) -> Pattern {
    match ring {
        0 => return Pattern::Lit,
        0xff => return Pattern::Shadowed,
        _ => {}
    }
    let occluded = |k: usize| ring & (1 << (k % 8)) != 0;
    // Start just after an occluded position so that no free run wraps around.
    let start = (0..8).find(|&k| occluded(k)).unwrap_or(0) + 1;
    let mut normals = [DVec2::ZERO; 4];
    let mut count = 0usize;
    let mut run = DVec2::ZERO;
    let mut in_run = false;
    for step in 0..=8 {
        let k = (start + step) % 8;
        if step < 8 && !occluded(k) {
            run += DVec2::new(RING[k].0 as f64, RING[k].1 as f64);
            in_run = true;
        } else if in_run {
            normals[count] = -run.normalize();
            count += 1;
            run = DVec2::ZERO;
            in_run = false;
        }
    }
    Pattern::Tangents { count: count as u8, normals }
}

/// The tangent look-up table: 256 entries addressed by the ring mask (Fig. 8).
pub fn pattern_table() -> &'static [Pattern; 256] {
    static TABLE: OnceLock<[Pattern; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut t = [Pattern::Lit; 256];
        for (m, e) in t.iter_mut().enumerate() {
            *e = pattern(m as u8);
        }
        t
    })
}

/// A recovered silhouette, as kept per uncertain pixel: where it is and what it used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Silhouette {
    /// Centre texel.
    pub texel: (u32, u32),
    /// The occluded texels kept (9-bit pattern after the connectivity filter).
    pub kept: u16,
    /// Whether the receiver faces away from the light and the pattern holds an occluded
    /// texel: shadowed whatever the tangents say.
    pub facing_away: bool,
}

impl Silhouette {
    /// The ring mask (8 bits) of the kept pattern.
    pub fn ring(&self) -> u8 {
        (self.kept & 0xff) as u8
    }

    /// What the pattern says; [`Pattern::Shadowed`] for a receiver facing away from the
    /// light with an occluded texel around it.
    pub fn pattern(&self) -> Pattern {
        if self.facing_away {
            return Pattern::Shadowed;
        }
        pattern_table()[self.ring() as usize]
    }
}

/// The occluding triangles of a silhouette, decoded once, and its tangents.
#[derive(Debug, Clone, Copy)]
pub struct Resolved {
    tris: [Tri; 9],
    n_tris: usize,
    pattern: Pattern,
    origin: DVec2,
}

impl Resolved {
    /// Decodes the kept occluders of `s` from `map` (a triangle stored in several texels
    /// counts once).
    pub fn new(map: &SpsmMap, s: &Silhouette) -> Self {
        let (x, y) = (i64::from(s.texel.0), i64::from(s.texel.1));
        let origin = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
        let empty = Tri {
            v: [DVec2::ZERO; 3],
            centre: origin,
            z: 0.0,
            dz: DVec2::ZERO,
            err_z: 0.0,
            err_dz: DVec2::ZERO,
            err_v: 0.0,
        };
        let mut tris = [empty; 9];
        let mut n_tris = 0;
        for (k, &(dx, dy)) in NEIGHBOURHOOD.iter().enumerate() {
            if s.kept & (1 << k) == 0 {
                continue;
            }
            let Some(t) = map.get(x + dx, y + dy) else { continue };
            if t.orientation() == 0.0 || tris[..n_tris].iter().any(|u| u.v == t.v) {
                continue;
            }
            tris[n_tris] = t;
            n_tris += 1;
        }
        Self { tris, n_tris, pattern: s.pattern(), origin }
    }

    /// Whether map point `q` is lit by the recovered silhouette.
    pub fn lit(&self, q: DVec2) -> bool {
        match self.pattern {
            Pattern::Lit => true,
            Pattern::Shadowed => false,
            Pattern::Tangents { count, normals } => {
                !normals[..count as usize].iter().all(|&n| self.shadowed_along(n, q))
            }
        }
    }

    /// Whether `q` lies beyond `φ` along the tangent with normal `n`.
    fn shadowed_along(&self, n: DVec2, q: DVec2) -> bool {
        let tangent = DVec2::new(-n.y, n.x);
        let proj = |p: DVec2| ((p - self.origin).dot(tangent), (p - self.origin).dot(n));
        let (tq, dq) = proj(q);
        let mut covered = f64::INFINITY;
        // Nearest endpoints left and right of tq: (t, d), larger t then smaller d wins on
        // the left, smaller t then smaller d on the right.
        let mut left: Option<(f64, f64)> = None;
        let mut right: Option<(f64, f64)> = None;
        for tri in &self.tris[..self.n_tris] {
            let sign = tri.orientation().signum();
            for e in 0..3 {
                let (a, b) = (tri.v[e], tri.v[(e + 1) % 3]);
                let d = b - a;
                let outward = DVec2::new(d.y, -d.x) * sign;
                if outward.dot(n) >= 0.0 {
                    continue;
                }
                let (pa, pb) = (proj(a), proj(b));
                let ((t0, d0), (t1, d1)) = if pa.0 <= pb.0 { (pa, pb) } else { (pb, pa) };
                if tq >= t0 && tq <= t1 {
                    let at =
                        if t1 > t0 { d0 + (d1 - d0) * (tq - t0) / (t1 - t0) } else { d0.min(d1) };
                    covered = covered.min(at);
                }
                for (te, de) in [(t0, d0), (t1, d1)] {
                    if te <= tq && left.is_none_or(|(lt, ld)| te > lt || (te == lt && de < ld)) {
                        left = Some((te, de));
                    }
                    if te >= tq && right.is_none_or(|(rt, rd)| te < rt || (te == rt && de < rd)) {
                        right = Some((te, de));
                    }
                }
            }
        }
        let phi = if covered.is_finite() {
            covered
        } else {
            match (left, right) {
                (Some((lt, ld)), Some((rt, rd))) if rt > lt => {
                    ld + (rd - ld) * (tq - lt) / (rt - lt)
                }
                _ => f64::INFINITY,
            }
        };
        dq > phi
    }

    /// Number of distinct occluding triangles used.
    pub fn occluders(&self) -> usize {
        self.n_tris
    }

    /// The occluding triangles, the pattern and the origin of the tangent frames (the centre
    /// texel's centre): what the GPU's antialiasing evaluates.
    pub fn parts(&self) -> (&[Tri], Pattern, DVec2) {
        (&self.tris[..self.n_tris], self.pattern, self.origin)
    }
}

/// What the depth-test pattern needs to know of the point: the point, its receiver plane's
/// gradient, and the quantization bound of that plane in a texel of this map.
#[derive(Debug, Clone, Copy)]
struct Receiver {
    p: MapPoint,
    grad: Option<DVec2>,
    error: (f64, DVec2),
}

/// Whether `tri`, stored in texel `(x, y)` with consistent minimum depth `cmin`, occludes the
/// neighbourhood of the point (see the module documentation).
fn occludes(tri: &Tri, (x, y): (i64, i64), cmin: f64, r: &Receiver) -> bool {
    let p = &r.p;
    // Quantization margin: the triangle's own error bound, but no more than the receiver's
    // own plane would suffer in this texel.
    let margin = |q: DVec2| tri.error_at(q).min(r.error.0 + (q - tri.centre).abs().dot(r.error.1));
    let stored = cmin.abs() * 0.5 * f64::from(f32::EPSILON);
    if cmin >= p.z - p.tol - margin(tri.centre + DVec2::splat(0.5)) - stored {
        return false;
    }
    if Lookup::lies_on_plane(tri, p, || r.grad.map(|_| r.error)) {
        return false;
    }
    let Some(g) = r.grad else { return true };
    // The clipped vertices are as uncertain as the stored ones.
    let moved = tri.err_v * std::f64::consts::SQRT_2 * (tri.dz - g).length();
    let (poly, n) = clip_to_texel(&tri.v, x as f64, y as f64);
    poly[..n].iter().any(|&q| tri.depth_at(q) < p.z + g.dot(q - p.xy) - p.tol - margin(q) - moved)
}

/// The depth-test pattern of `p` over its 3x3 neighbourhood, filtered by 4-connectivity;
/// `consistent` holds the neighbourhood's consistent minimum depths (stage 4; a texel it
/// lacks is computed here). `None` when `p` falls outside the map.
pub fn silhouette(
    lookup: &Lookup<'_>,
    consistent: &ConsistentDepths,
    p: &MapPoint,
) -> Option<Silhouette> {
    let (x, y) = texel_at(p.xy, lookup.map.res)?;
    let (x, y) = (x as i64, y as i64);
    let r = i64::from(lookup.map.res);
    let grad = lookup.gradient(p);
    let receiver =
        Receiver { p: *p, grad, error: lookup.map.plane_error(p.z, grad.unwrap_or(DVec2::ZERO)) };
    let mut mask = 0u16;
    for (k, &(dx, dy)) in NEIGHBOURHOOD.iter().enumerate() {
        let (nx, ny) = (x + dx, y + dy);
        let Some(tri) = lookup.map.get(nx, ny) else { continue };
        let cmin = consistent
            .get((ny * r + nx) as u32)
            .unwrap_or_else(|| consistent_min_depth(&tri, nx as usize, ny as usize).0);
        if occludes(&tri, (nx, ny), cmin, &receiver) {
            mask |= 1 << k;
        }
    }
    let kept = connectivity_table()[mask as usize];
    // A receiver facing away from the light, with an occluder found around it, is shadowed.
    let facing_away = !p.facing && kept != 0;
    Some(Silhouette { texel: (x as u32, y as u32), kept, facing_away })
}

/// The silhouette of one uncertain pixel and its lit value at the pixel's own map point;
/// `(None, true)` where the point falls outside the map.
pub fn recover_pixel(
    frame: &Frame<'_>,
    lookup: &Lookup<'_>,
    consistent: &ConsistentDepths,
    u: &UncertainPixel,
) -> (Option<Silhouette>, bool) {
    let g = &frame.gbuffer;
    let k = u.pixel as usize;
    let Some(p) = lookup.point(g.position[k], g.normal[k]) else {
        return (None, true);
    };
    match silhouette(lookup, consistent, &p) {
        Some(s) => {
            let lit = Resolved::new(lookup.map, &s).lit(p.xy);
            (Some(s), lit)
        }
        None => (None, true),
    }
}

/// Runs silhouette recovery for the uncertain pixels (indices into the frame), writing their
/// lit value (1 or 0) into `lit`. Returns each pixel's silhouette, in the order of
/// `uncertain`, and the counters ([`record`]).
pub fn recover_pixels(
    frame: &Frame<'_>,
    lookup: &Lookup<'_>,
    consistent: &ConsistentDepths,
    uncertain: &[UncertainPixel],
    lit: &mut [f32],
) -> (Vec<Option<Silhouette>>, Counters) {
    let out: Vec<(Option<Silhouette>, bool)> =
        uncertain.par_iter().map(|u| recover_pixel(frame, lookup, consistent, u)).collect();
    record(uncertain, out, lit)
}

/// Writes the recovered values `out` of the `uncertain` pixels (same order) into `lit`, and
/// counts `recovered_pixels` (pixels decided by a silhouette function rather than a full or
/// empty pattern) and `shadow_map_lookups` (9 per pixel with a silhouette).
pub fn record(
    uncertain: &[UncertainPixel],
    out: Vec<(Option<Silhouette>, bool)>,
    lit: &mut [f32],
) -> (Vec<Option<Silhouette>>, Counters) {
    let mut c = Counters::default();
    let mut silhouettes = Vec::with_capacity(out.len());
    for (u, (s, value)) in uncertain.iter().zip(out) {
        lit[u.pixel as usize] = if value { 1.0 } else { 0.0 };
        if let Some(s) = &s {
            c.shadow_map_lookups += 9;
            c.recovered_pixels += u64::from(matches!(s.pattern(), Pattern::Tangents { .. }));
        }
        silhouettes.push(s);
    }
    (silhouettes, c)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bits(ks: &[usize]) -> u16 {
        ks.iter().fold(0, |m, &k| m | (1 << k))
    }

    #[test]
    fn corners_reached_only_diagonally_are_discarded() {
        // NE alone (bit 2): not 4-connected to the centre.
        assert_eq!(connected(bits(&[2])), 0);
        // NE with N: kept through N.
        assert_eq!(connected(bits(&[1, 2])), bits(&[1, 2]));
        // NE with E and the centre occluded.
        assert_eq!(connected(bits(&[2, 3, 8])), bits(&[2, 3, 8]));
        // A corner touching the centre only diagonally, beside a kept edge on the other side.
        assert_eq!(connected(bits(&[0, 3, 8])), bits(&[3, 8]));
        // Everything connected stays.
        assert_eq!(connected(0x1ff), 0x1ff);
        let table = connectivity_table();
        for m in 0..512u16 {
            let k = table[m as usize];
            assert_eq!(k & !m, 0, "keeps only occluded texels");
            assert_eq!(table[k as usize], k, "idempotent");
        }
    }

    #[test]
    fn a_straight_edge_gives_one_tangent_along_it() {
        // Occluded top row (NW, N, NE): shadow above, the tangent is horizontal and the
        // normal points up (-y in image coordinates).
        match pattern(bits(&[0, 1, 2]) as u8) {
            Pattern::Tangents { count: 1, normals } => {
                assert!((normals[0] - DVec2::new(0.0, -1.0)).length() < 1e-12, "{normals:?}");
            }
            p => panic!("{p:?}"),
        }
        // Occluded W, SW, S: a diagonal edge, normal towards the lower left.
        match pattern(bits(&[5, 6, 7]) as u8) {
            Pattern::Tangents { count: 1, normals } => {
                let n = DVec2::new(-1.0, 1.0).normalize();
                assert!((normals[0] - n).length() < 1e-12, "{normals:?}");
            }
            p => panic!("{p:?}"),
        }
    }

    #[test]
    fn a_thin_strip_gives_two_tangents_and_full_or_empty_rings_decide() {
        // Occluded N and S only: a vertical strip through the centre; free runs E and W.
        match pattern(bits(&[1, 5]) as u8) {
            Pattern::Tangents { count: 2, normals } => {
                let mut xs: Vec<f64> = normals[..2].iter().map(|n| n.x).collect();
                xs.sort_by(f64::total_cmp);
                assert_eq!(xs, vec![-1.0, 1.0]);
                assert!(normals[..2].iter().all(|n| n.y.abs() < 1e-12));
            }
            p => panic!("{p:?}"),
        }
        assert_eq!(pattern(0), Pattern::Lit);
        assert_eq!(pattern(0xff), Pattern::Shadowed);
        let table = pattern_table();
        for (m, entry) in table.iter().enumerate().take(255).skip(1) {
            let Pattern::Tangents { count, normals } = *entry else { panic!("{m}") };
            assert!((1..=4).contains(&count), "{m}: {count}");
            for n in &normals[..count as usize] {
                assert!((n.length() - 1.0).abs() < 1e-12);
            }
        }
    }

    fn tri(v: [DVec2; 3]) -> Tri {
        Tri {
            v,
            centre: DVec2::ZERO,
            z: 0.0,
            dz: DVec2::ZERO,
            err_z: 0.0,
            err_dz: DVec2::ZERO,
            err_v: 0.0,
        }
    }

    fn resolved(tris: &[Tri], pattern: Pattern) -> Resolved {
        let mut r = Resolved {
            tris: [tri([DVec2::ZERO; 3]); 9],
            n_tris: tris.len(),
            pattern,
            origin: DVec2::new(0.5, 0.5),
        };
        r.tris[..tris.len()].copy_from_slice(tris);
        r
    }

    #[test]
    fn exact_the_gap_between_two_recorded_triangles_is_bridged() {
        // Two occluder triangles above y = 0 with their lower edges on y = 0, x in [-3, -0.5]
        // and [1.5, 4]; the missing triangle between them is recovered by the link.
        let a = tri([DVec2::new(-3.0, 0.0), DVec2::new(-0.5, 0.0), DVec2::new(-2.0, -2.0)]);
        let b = tri([DVec2::new(1.5, 0.0), DVec2::new(4.0, 0.0), DVec2::new(3.0, -2.0)]);
        let up = Pattern::Tangents { count: 1, normals: [DVec2::new(0.0, -1.0); 4] };
        let r = resolved(&[a, b], up);
        assert!(!r.lit(DVec2::new(0.5, -0.01)), "in the gap, above the link");
        assert!(r.lit(DVec2::new(0.5, 0.01)), "in the gap, below the link");
        assert!(!r.lit(DVec2::new(-1.0, -0.5)), "inside a recorded triangle");
        assert!(r.lit(DVec2::new(5.0, -0.5)), "beyond the outermost vertex");
    }

    #[test]
    fn exact_vertices_behind_a_facing_edge_do_not_define_the_boundary() {
        // A big triangle whose lower edge is y = 1, and a small one inside the shadow above
        // it with a lower edge at y = -1: the boundary stays at y = 1 where both span.
        let big = tri([DVec2::new(-4.0, 1.0), DVec2::new(4.0, 1.0), DVec2::new(0.0, -6.0)]);
        let small = tri([DVec2::new(-1.0, -1.0), DVec2::new(1.0, -1.0), DVec2::new(0.0, -3.0)]);
        let up = Pattern::Tangents { count: 1, normals: [DVec2::new(0.0, -1.0); 4] };
        let r = resolved(&[big, small], up);
        assert!(!r.lit(DVec2::new(0.0, 0.9)));
        assert!(r.lit(DVec2::new(0.0, 1.1)));
    }

    #[test]
    fn exact_two_tangents_intersect_their_shadows() {
        // A vertical strip x in [0, 1] made of two triangles; free on both sides.
        let s1 = tri([DVec2::new(0.0, -5.0), DVec2::new(1.0, -5.0), DVec2::new(0.0, 5.0)]);
        let s2 = tri([DVec2::new(1.0, -5.0), DVec2::new(1.0, 5.0), DVec2::new(0.0, 5.0)]);
        let strip = Pattern::Tangents {
            count: 2,
            normals: [DVec2::new(1.0, 0.0), DVec2::new(-1.0, 0.0), DVec2::ZERO, DVec2::ZERO],
        };
        let r = resolved(&[s1, s2], strip);
        assert!(!r.lit(DVec2::new(0.5, 0.3)));
        assert!(r.lit(DVec2::new(-0.2, 0.3)));
        assert!(r.lit(DVec2::new(1.2, 0.3)));
        assert_eq!(r.occluders(), 2);
    }
}
