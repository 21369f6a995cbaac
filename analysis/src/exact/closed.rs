//! A closed mesh's shadow on a receiver plane is the shadow of its triangles facing the light.
//!
//! A plane point `p` is in the shadow of a mesh when the segment from `p` to the light meets
//! one of its triangles. Let the mesh be closed: every edge is used as often in one
//! direction as in the other by its triangles (corners compared by position), so the mesh
//! has no boundary and a winding number `w(x)` around every point off it, constant between
//! its triangles and changed by one, up or down with the triangle's orientation, where a
//! path crosses a triangle (up where it crosses against the triangle's normal).
//!
//! Let every corner lie on the light's side of the plane or in it, and, for a spot light,
//! below the plane through the light ([`Setup::toward_light`]). A ray from the light away
//! from the plane then meets no triangle (for a directional light, the light is at
//! infinity), so `w(light) = 0`. A plane point `p` off the mesh has `w(p) = 0` (a ray from it
//! away from the light meets nothing). Along the segment from `p` to the light the
//! crossings' signed count is `w(light) - w(p) = 0`: a segment that crosses the mesh crosses
//! it both ways, so it crosses a triangle facing the light ([`Setup::faces_light`]), whose
//! normal the segment runs along when it leaves the closed surface. A plane point on a
//! triangle lying in the plane (a base the mesh stands on) is one more case: let no such
//! triangle face the light; just above `p`, `w` is then at least 1 (each triangle of the
//! plane there is crossed against its normal by a path going up), so the segment leaves the
//! surface through a triangle facing the light again. Only the segments through an edge, a
//! corner or along a triangle's plane escape these counts, and they cover no area of the
//! plane. So the union of the shadows of the triangles facing the light is the union of all
//! the mesh's shadows, up to the rounding of their projections; no other property of the
//! mesh (one sheet, no self-intersection, outward normals) is needed.
//!
//! On `bunny-plane` at 800 x 600 the ground's shadow polygons go from 75,408 to 35,672 and
//! the cuts of their union from 138,872 to 67,974 (stage `pixel unions` 30 -> 18 ms); on
//! `cage` from 1,584 to 792 polygons. Whether an object qualifies is decided per frame, in
//! the stage that projects the polygons: one parallel pass sums a hash of its directed edges
//! (non-zero proves it open), then only an object that may be closed has its edges sorted,
//! by their corners' vertex numbers or, when a corner is repeated under several numbers, by
//! their positions.

use super::shadow::Setup;
use super::ScreenPolygons;
use methods::Frame;
use rayon::prelude::*;

/// The shadow polygons of the casters of `frame` on the plane of `setup`, that of object
/// `receiver` ([`Setup::shadow_polygons`]): of a closed object toward the light, those of its
/// triangles facing the light only ([`facing_suffices`]).
pub(crate) fn shadow_polygons(frame: &Frame<'_>, setup: &Setup, receiver: usize) -> ScreenPolygons {
    let casters: Vec<bool> = (0..frame.scene.objects.len())
        .map(|o| o != receiver && frame.object_casts_shadows(o))
        .collect();
    setup.shadow_polygons(frame, receiver, &facing_suffices(frame, setup, &casters))
}

/// For each object of `frame`: whether its shadow on the plane of `setup` is that of its
/// triangles facing the light alone. It must be one of the `casters` (others are not looked
/// at), closed, with every corner toward the light from the plane, and no triangle lying in
/// the plane facing the light.
pub(crate) fn facing_suffices(frame: &Frame<'_>, setup: &Setup, casters: &[bool]) -> Vec<bool> {
    let g = &frame.geometry;
    let objects = casters.len();
    // One parallel pass over the triangles: per object, whether every triangle lies toward
    // the light (none in the plane facing it), and its edges' hash sums.
    let start = (true, (0u64, 0u64));
    let per_object = (0..g.len())
        .into_par_iter()
        .fold(
            || vec![start; objects],
            |mut acc, t| {
                let o = g.object[t] as usize;
                if casters.get(o).copied().unwrap_or(false) && acc[o].0 {
                    let c = g.corners(t);
                    let in_plane = c.iter().all(|&p| setup.light_height(p) == 0.0);
                    let toward = c.iter().all(|&p| setup.toward_light(p));
                    acc[o] = (
                        toward && !(in_plane && setup.faces_light(&c)),
                        add(acc[o].1, edge_sums(g, t as u32)),
                    );
                }
                acc
            },
        )
        .reduce(
            || vec![start; objects],
            |a, b| a.iter().zip(&b).map(|(x, y)| (x.0 && y.0, add(x.1, y.1))).collect(),
        );
    let mut triangles: Vec<Vec<u32>> = vec![Vec::new(); objects];
    let sorted = |o: usize| casters[o] && per_object[o].0 && closed_may_be(per_object[o].1);
    for (t, &o) in g.object.iter().enumerate() {
        if casters.get(o as usize).copied().unwrap_or(false) && sorted(o as usize) {
            triangles[o as usize].push(t as u32);
        }
    }
    (0..objects)
        .map(|o| {
            sorted(o) && !triangles[o].is_empty() && closed_given(g, &triangles[o], per_object[o].1)
        })
        .collect()
}

/// An asymmetric hash of a directed edge's ends.
#[inline]
fn mix(a: u64, b: u64) -> u64 {
    let h = a.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ b.rotate_left(29).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    h ^ (h >> 31)
}

/// Two hash sums added.
#[inline]
fn add(a: (u64, u64), b: (u64, u64)) -> (u64, u64) {
    (a.0.wrapping_add(b.0), a.1.wrapping_add(b.1))
}

/// Triangle `t`'s directed edges' hashes less those of the reversed edges, summed: its
/// corners taken by vertex number, and by position.
#[inline]
fn edge_sums(g: &scenes::Geometry, t: u32) -> (u64, u64) {
    let position = |v: u32| {
        let [x, y, z] = g.positions[v as usize].to_array().map(f64::to_bits);
        mix(mix(x, y), z)
    };
    let edge = |p: u64, q: u64| mix(p, q).wrapping_sub(mix(q, p));
    let v = g.triangles[t as usize];
    let (n, p) = (v.map(u64::from), v.map(position));
    [(0, 1), (1, 2), (2, 0)]
        .iter()
        .fold((0, 0), |s, &(a, b)| add(s, (edge(n[a], n[b]), edge(p[a], p[b]))))
}

/// Whether a surface with these hash sums may be closed: a closed surface sums to zero by
/// vertex number or by position; a non-zero sum proves an edge unbalanced.
fn closed_may_be((by_number, by_position): (u64, u64)) -> bool {
    by_number == 0 || by_position == 0
}

/// Whether the triangles `tris` of `g` form a closed surface ([`closed_given`]).
#[cfg(test)]
fn closed(g: &scenes::Geometry, tris: &[u32]) -> bool {
    let sums = tris.par_iter().map(|&t| edge_sums(g, t)).reduce(|| (0, 0), add);
    closed_may_be(sums) && closed_given(g, tris, sums)
}

/// Whether the triangles `tris` of `g`, whose hash sums ([`edge_sums`]) are given, form a
/// closed surface: each edge used equally often in both directions, by vertex number, or else
/// by position. A closed surface's sums are zero, and a non-zero sum proves an edge
/// unbalanced, so most open surfaces are ruled out in the pass that sums the hashes, before
/// their edges are sorted (on `random-1m`, a million separate triangles, the sorts took 500
/// ms).
fn closed_given(g: &scenes::Geometry, tris: &[u32], (by_number, by_position): (u64, u64)) -> bool {
    if by_number == 0 && balanced(g, tris, |v| v) {
        return true;
    }
    if by_position != 0 {
        return false;
    }
    // The same corner under several numbers (a mesh split for its normals): each number
    // stands for the smallest number at its position.
    let mut numbers: Vec<u32> = tris.iter().flat_map(|&t| g.triangles[t as usize]).collect();
    numbers.par_sort_unstable();
    numbers.dedup();
    let key = |v: u32| g.positions[v as usize].to_array().map(f64::to_bits);
    let mut by_position = numbers.clone();
    by_position.par_sort_unstable_by_key(|&v| (key(v), v));
    let mut first = vec![0u32; by_position.len()];
    for k in 0..by_position.len() {
        let same = k > 0 && key(by_position[k]) == key(by_position[k - 1]);
        first[k] = if same { first[k - 1] } else { by_position[k] };
    }
    // `canonical[numbers.binary_search(v)]`: the number standing for `v`.
    let mut canonical = vec![0u32; numbers.len()];
    for (k, &v) in by_position.iter().enumerate() {
        let at = numbers.binary_search(&v).unwrap_or(0);
        canonical[at] = first[k];
    }
    balanced(g, tris, |v| canonical[numbers.binary_search(&v).unwrap_or(0)])
}

/// Whether every edge of the triangles `tris`, its corners numbered by `number`, is used as
/// often from its first corner to its second as back.
fn balanced(g: &scenes::Geometry, tris: &[u32], number: impl Fn(u32) -> u32 + Sync) -> bool {
    // An edge's key: its smaller and larger corner, then whether it runs from the larger.
    let mut edges: Vec<u64> = tris
        .par_iter()
        .flat_map_iter(|&t| {
            let [a, b, c] = g.triangles[t as usize].map(&number);
            [(a, b), (b, c), (c, a)].map(|(p, q)| {
                let (lo, hi) = (p.min(q), p.max(q));
                (u64::from(lo) << 33) | (u64::from(hi) << 1) | u64::from(p > q)
            })
        })
        .collect();
    edges.par_sort_unstable();
    edges.chunk_by(|a, b| a >> 1 == b >> 1).all(|run| {
        // An edge from a corner to itself (a degenerate triangle's) has no direction.
        let (lo, hi) = (run[0] >> 33, (run[0] >> 1) & u64::from(u32::MAX));
        lo == hi || 2 * run.iter().filter(|&&e| e & 1 == 1).count() == run.len()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact::coverage;
    use glam::DVec3;
    use instrumentation::Recorder;

    /// On bunny-plane, cage and spheres the ground's shadow polygons of the closed casters'
    /// triangles facing the light cover, in every pixel, what those of all their triangles
    /// cover, to 1e-12; and they are fewer.
    #[test]
    fn the_triangles_facing_the_light_cast_the_whole_shadow() {
        for name in ["bunny-plane", "cage", "spheres"] {
            let Ok(scene) = scenes::load(name) else {
                eprintln!("{name}: model not available, skipped");
                continue;
            };
            let frame = Frame::new(&scene, 200, 150, &mut Recorder::default());
            let (receiver, setup) = Setup::main_receiver(&frame).expect("planar receiver");
            let facing = shadow_polygons(&frame, &setup, receiver);
            let g = &frame.geometry;
            let mut all = crate::exact::ScreenPolygons::default();
            for t in (0..g.len()).filter(|&t| g.object[t] as usize != receiver) {
                if let Some(p) = setup.caster(g.corners(t)).filter(|_| frame.is_caster(t)) {
                    all.push(p.points());
                }
            }
            assert!(facing.len() < all.len(), "{name}: {} of {}", facing.len(), all.len());
            let (a, _) = coverage::union_area(&facing, 200, 150, |_| true);
            let (b, _) = coverage::union_area(&all, 200, 150, |_| true);
            let worst = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
            assert!(worst <= 1e-12, "{name}: {worst}");
            assert!(b.iter().filter(|&&v| v > 0.5).count() > 100, "{name}: a shadow");
        }
    }

    /// A box is closed (also with its corners repeated per face, as a mesh split for its
    /// normals has them); without a face, or with a face turned, it is not; a box on the
    /// light's side of the plane qualifies, one reaching through the plane does not.
    #[test]
    fn closed_boxes_qualify_and_open_or_crossing_ones_do_not() {
        let corners = |lift: f64| -> Vec<DVec3> {
            (0..8)
                .map(|k| DVec3::new((k & 1) as f64, (k >> 1 & 1) as f64 + lift, (k >> 2) as f64))
                .collect()
        };
        // Outward faces of the unit cube (corner k: x = bit 0, y = bit 1, z = bit 2).
        let faces: [[u32; 4]; 6] =
            [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let quads = |faces: &[[u32; 4]]| -> Vec<[u32; 3]> {
            faces.iter().flat_map(|f| [[f[0], f[1], f[2]], [f[0], f[2], f[3]]]).collect()
        };
        let geometry = |positions: Vec<DVec3>, triangles: Vec<[u32; 3]>| scenes::Geometry {
            object: vec![0; triangles.len()],
            positions,
            triangles,
        };
        let all = |g: &scenes::Geometry| (0..g.len() as u32).collect::<Vec<_>>();
        let cube = geometry(corners(0.5), quads(&faces));
        assert!(closed(&cube, &all(&cube)));
        let open = geometry(corners(0.5), quads(&faces[1..]));
        assert!(!closed(&open, &all(&open)));
        let mut turned = faces;
        turned[0].reverse();
        let turned = geometry(corners(0.5), quads(&turned));
        assert!(!closed(&turned, &all(&turned)));
        // Every face with corners of its own.
        let (mut positions, mut split) = (Vec::new(), Vec::new());
        for f in faces {
            let base = positions.len() as u32;
            positions.extend(f.iter().map(|&k| corners(0.5)[k as usize]));
            split.push([base, base + 1, base + 2, base + 3]);
        }
        let split = geometry(positions, quads(&split));
        assert!(closed(&split, &all(&split)));

        // On the ground of plane-square's frame, under its light.
        let scene = scenes::load("plane-square").expect("built-in");
        let frame = Frame::new(&scene, 40, 30, &mut Recorder::default());
        let (_, setup) = Setup::main_receiver(&frame).expect("planar receiver");
        let above = cube.positions.iter().all(|&p| setup.toward_light(p));
        let lowered = corners(-0.5);
        let through = lowered.iter().all(|&p| setup.toward_light(p));
        assert!(above && !through, "the cube above the ground qualifies, through it not");
    }
}
