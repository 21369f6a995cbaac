//! Closed surfaces: whether a set of triangles has every edge used as often in one direction
//! as in the other (corners compared by vertex number, or else by position), so that it has no
//! boundary and a winding number around every point off it.
//!
//! What a closed caster allows is each user's argument: `exact` projects only the triangles of
//! a closed object facing the light onto a receiver plane below it, and `afsm` rasterizes only
//! those of a closed object seen from outside ([`crate::afsm::facing`]).
//!
//! Deciding it costs one parallel pass that sums an asymmetric hash of every directed edge
//! (a non-zero sum proves an edge unbalanced, so most open surfaces are ruled out there), then
//! for an object that may be closed a check of its edges, bucketed by their smaller corner (on
//! `random-1m`, a million separate triangles, sorting every object's edges took 500 ms)
//! ([`closed_objects`]).

use rayon::prelude::*;
use scenes::Geometry;
use std::sync::atomic::{AtomicU64, Ordering};

/// An asymmetric hash of a directed edge's ends.
#[inline]
fn mix(a: u64, b: u64) -> u64 {
    let h = a.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ b.rotate_left(29).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    h ^ (h >> 31)
}

/// Triangle `t`'s directed edges' hashes less those of the reversed edges, summed, its
/// corners standing for `key(v)` (their vertex numbers, or their positions' hashes).
#[inline]
fn edge_sum(g: &Geometry, t: usize, key: impl Fn(u32) -> u64) -> u64 {
    let k = g.triangles[t].map(key);
    let edge = |p: u64, q: u64| mix(p, q).wrapping_sub(mix(q, p));
    edge(k[0], k[1]).wrapping_add(edge(k[1], k[2])).wrapping_add(edge(k[2], k[0]))
}

/// A hash of vertex `v`'s position.
#[inline]
fn position_key(g: &Geometry, v: u32) -> u64 {
    let [x, y, z] = g.positions[v as usize].to_array().map(f64::to_bits);
    mix(mix(x, y), z)
}

/// Per object `o < objects` with `wanted(o)`, the sum of its triangles' [`edge_sum`]s.
fn sums(
    g: &Geometry,
    objects: usize,
    wanted: impl Fn(usize) -> bool + Sync,
    key: impl Fn(u32) -> u64 + Sync,
) -> Vec<u64> {
    per_object(
        g.len(),
        objects,
        0,
        |acc, t| {
            let o = g.object[t] as usize;
            if o < objects && wanted(o) {
                acc[o] = acc[o].wrapping_add(edge_sum(g, t, &key));
            }
        },
        u64::wrapping_add,
    )
}

/// One value per slot `k < slots`, gathered over the items `0..n`: each slot starts at `init`,
/// `step(acc, i)` updates the slots for item `i`, and the chunks' slots are joined by
/// `combine` (associative and commutative, so the result does not depend on the chunks).
///
/// Chunks of [`CHUNK`] items in parallel, each a plain loop into its own slots: rayon's
/// `fold` over the items, its accumulator moved through every step, cost about 8 ns an item
/// (3.7 ms against 0.3 ms over the bunny's 480,000 pixels at one thread).
pub fn per_object<A: Copy + Send + Sync>(
    n: usize,
    slots: usize,
    init: A,
    step: impl Fn(&mut [A], usize) + Sync,
    combine: impl Fn(A, A) -> A + Sync,
) -> Vec<A> {
    (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut acc = vec![init; slots];
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                step(&mut acc, i);
            }
            acc
        })
        .reduce(
            || vec![init; slots],
            |a, b| a.iter().zip(&b).map(|(&x, &y)| combine(x, y)).collect(),
        )
}

/// Items per task of [`per_object`].
const CHUNK: usize = 1 << 14;

/// How [`closed_objects`] compares corners.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Corners {
    /// By vertex number only: a mesh split for its normals (its corners repeated under
    /// several numbers) is open.
    ByNumber,
    /// By vertex number, or else by position.
    ByNumberOrPosition,
}

/// For each of `objects` objects of `g`: whether its triangles form a closed surface, each
/// edge used equally often in both directions, its corners compared as `corners` says, asked
/// only of the objects with `wanted(o)` (`false` for the others and for objects without
/// triangles).
///
/// An asymmetric hash of every directed edge less that of the reversed edge sums to zero over
/// a closed surface, so a non-zero sum proves an object open in one parallel pass; only an
/// object whose sum is zero has its edges sorted. Vertex numbers come first (no position is
/// read); positions only for the objects left, whose corners are repeated under several
/// numbers or which are open (a second pass, which reads every corner's position: 30 ms at
/// one thread on `random-1m`'s million separate triangles).
pub fn closed_objects(
    g: &Geometry,
    objects: usize,
    wanted: impl Fn(usize) -> bool + Sync,
    corners: Corners,
) -> Vec<bool> {
    let by_number = sums(g, objects, &wanted, u64::from);
    let may_be = |o: usize| wanted(o) && by_number[o] == 0;
    let listed = triangles_of(g, objects, may_be);
    let mut closed: Vec<bool> = (0..objects)
        .map(|o| may_be(o) && !listed[o].is_empty() && balanced(g, &listed[o], |v| v))
        .collect();
    let left: Vec<bool> = (0..objects).map(|o| wanted(o) && !closed[o]).collect();
    if corners == Corners::ByNumberOrPosition && left.contains(&true) {
        let by_position = sums(g, objects, |o| left[o], |v| position_key(g, v));
        let by_position_only = |o: usize| left[o] && by_position[o] == 0;
        // The objects not listed yet, in one more pass.
        let more = triangles_of(g, objects, |o| by_position_only(o) && !may_be(o));
        for o in (0..objects).filter(|&o| by_position_only(o)) {
            let tris = if may_be(o) { &listed[o] } else { &more[o] };
            closed[o] = !tris.is_empty() && balanced_by_position(g, tris);
        }
    }
    closed
}

/// The triangles of each object `o < objects` with `pick(o)` (none for the others), in one
/// pass over the triangles: one pass per object made a scene of many closed objects cost the
/// product of their number and the triangles'. With up to [`PARALLEL_LISTS`] objects picked,
/// the pass runs in parallel over parts of the triangles, each part's lists joined in part
/// order (in one thread, 0.5 ms of `exact` on `bunny-plane` at two threads, with the other
/// waiting); with more, a list per part and object would cost more memory than the pass time.
fn triangles_of(
    g: &Geometry,
    objects: usize,
    pick: impl Fn(usize) -> bool + Sync,
) -> Vec<Vec<u32>> {
    const PART: usize = 1 << 14;
    // Each picked object's place among the picked ones.
    let mut place = vec![u32::MAX; objects];
    let mut picked = 0;
    for o in (0..objects).filter(|&o| pick(o)) {
        place[o] = picked;
        picked += 1;
    }
    let mut lists = vec![Vec::new(); objects];
    if picked as usize > PARALLEL_LISTS {
        for (t, &o) in g.object.iter().enumerate() {
            if place.get(o as usize).is_some_and(|&p| p != u32::MAX) {
                lists[o as usize].push(t as u32);
            }
        }
        return lists;
    }
    let parts: Vec<Vec<Vec<u32>>> = g
        .object
        .par_chunks(PART)
        .enumerate()
        .map(|(p, part)| {
            let mut lists = vec![Vec::new(); picked as usize];
            for (t, &o) in part.iter().enumerate() {
                if let Some(&k) = place.get(o as usize).filter(|&&k| k != u32::MAX) {
                    lists[k as usize].push((p * PART + t) as u32);
                }
            }
            lists
        })
        .collect();
    for (o, list) in lists.iter_mut().enumerate().filter(|(o, _)| place[*o] != u32::MAX) {
        let k = place[o] as usize;
        let of_parts: Vec<&[u32]> = parts.iter().map(|part| &part[k][..]).collect();
        *list = crate::parallel::concat(&of_parts);
    }
    lists
}

/// Objects picked at most, for [`triangles_of`] to list them in parallel.
const PARALLEL_LISTS: usize = 64;

/// Whether the triangles `tris` of `g` have every edge used as often in both directions, their
/// corners compared by position: each vertex number stands for the smallest number at its
/// position.
fn balanced_by_position(g: &Geometry, tris: &[u32]) -> bool {
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
///
/// The edges are put in buckets by their smaller corner (a counting sort over the corners'
/// numbers, which are below `g.positions.len()`), then each bucket, a few edges around one
/// corner, is checked ([`bucket_balanced`]), in parallel over runs of [`BUCKET_RUN`] corners.
/// The counting sort runs in up to one part of the triangles per thread (at least
/// [`PART_MIN`] triangles each), each part counting its edges per corner and writing them into
/// its own slots of every bucket: done by one task, it was the check's serial half (on
/// `bunny-plane` at two threads the check took 2.8 ms with it, 2.3-2.4 in parts; medians of 9
/// frames in alternating runs). A least-significant-digit radix sort of every edge as one key
/// took as long as the buckets at one thread (3.1-3.5 ms against 3.3) and 3.0-3.2 at two.
/// A sort of all the edges at once took about twice as long as sorting each bucket on the
/// bunny's 226,000 at one thread; sorting each bucket took 3.4 ms there, counting each of its
/// edges' directions among the others ([`bucket_balanced`]) 2.6 ms.
fn balanced(g: &Geometry, tris: &[u32], number: impl Fn(u32) -> u32 + Sync) -> bool {
    let vertices = g.positions.len();
    // An edge in its bucket: its larger corner, then whether it runs from the larger.
    let edge = |p: u32, q: u32| (p.min(q), (u64::from(p.max(q)) << 1) | u64::from(p > q));
    let corners = |t: u32| g.triangles[t as usize].map(&number);
    // The counting sort in parts of the triangles, each counted and scattered by one task
    // into its own slots of every bucket (the order within a bucket does not matter).
    let tasks = rayon::current_num_threads().min(tris.len() / PART_MIN).clamp(1, MAX_PARTS);
    let parts: Vec<&[u32]> = tris.chunks(tris.len().div_ceil(tasks).max(1)).collect();
    let counts: Option<Vec<Vec<u32>>> = parts
        .par_iter()
        .map(|part| {
            let mut count = vec![0u32; vertices];
            for &t in *part {
                let [a, b, c] = corners(t);
                for (p, q) in [(a, b), (b, c), (c, a)] {
                    *count.get_mut(p.min(q) as usize)? += 1;
                }
            }
            Some(count)
        })
        .collect();
    let Some(mut fill) = counts else { return false };
    // `start[v]` is corner `v`'s first slot; each part's count becomes its first slot there.
    let mut start = vec![0u32; vertices + 1];
    let mut next = 0u32;
    for v in 0..vertices {
        start[v] = next;
        for part in &mut fill {
            (part[v], next) = (next, next + part[v]);
        }
    }
    start[vertices] = next;
    // Made in parallel: in one thread, with the others waiting, 0.8 ms of `afsm`'s
    // rasterization on `bunny-plane` at two threads.
    let slots: Vec<AtomicU64> = (0..next).into_par_iter().map(|_| AtomicU64::new(0)).collect();
    parts.par_iter().zip(&mut fill).for_each(|(part, fill)| {
        for &t in *part {
            let [a, b, c] = corners(t);
            for (p, q) in [(a, b), (b, c), (c, a)] {
                let (lo, key) = edge(p, q);
                slots[fill[lo as usize] as usize].store(key, Ordering::Relaxed);
                fill[lo as usize] += 1;
            }
        }
    });
    let mut keys: Vec<u64> = slots.into_iter().map(AtomicU64::into_inner).collect();
    // Runs of corners with their buckets, which are contiguous and disjoint.
    let run_of = |k: usize| k * BUCKET_RUN..((k + 1) * BUCKET_RUN).min(vertices);
    let runs = vertices.div_ceil(BUCKET_RUN);
    let lens = (0..runs).map(|k| (start[run_of(k).end] - start[run_of(k).start]) as usize);
    let runs = crate::parallel::cut(&mut keys, lens);
    runs.into_par_iter().enumerate().all(|(k, run)| {
        let corners = run_of(k);
        let base = start[corners.start] as usize;
        corners.into_iter().all(|v| {
            let bucket = &mut run[start[v] as usize - base..start[v + 1] as usize - base];
            bucket_balanced(v as u64, bucket)
        })
    })
}

/// Triangles per part of the counting sort, at least (so that small objects are one part).
const PART_MIN: usize = 1 << 14;

/// Parts of the counting sort, at most (each holds a count per corner).
const MAX_PARTS: usize = 8;

/// Corners whose buckets one task checks.
const BUCKET_RUN: usize = 1 << 12;

/// Buckets up to this size are checked by counting, larger ones sorted first.
const SMALL_BUCKET: usize = 8;

/// Whether the bucket of corner `v` (its edges' larger corners, shifted left by one, with bit
/// 0 set for an edge that runs from the larger corner) holds as many edges in one direction as
/// in the other toward each corner. An edge from `v` to itself (a degenerate triangle's) has
/// no direction. A small bucket counts, for each edge, the directions of the edges to the same
/// corner (no branch but the answer); a larger one is sorted, then its runs counted.
fn bucket_balanced(v: u64, bucket: &mut [u64]) -> bool {
    let direction = |e: u64| if e & 1 == 1 { 1i32 } else { -1 };
    if bucket.len() <= SMALL_BUCKET {
        // Padded to a fixed width by an edge to no corner, so that each count is one vector
        // comparison.
        let mut lanes = [u64::MAX; SMALL_BUCKET];
        lanes[..bucket.len()].copy_from_slice(bucket);
        return bucket.iter().all(|&e| {
            let w = e >> 1;
            let net: i32 = lanes.iter().map(|&f| if f >> 1 == w { direction(f) } else { 0 }).sum();
            net == 0 || w == v
        });
    }
    bucket.sort_unstable();
    bucket
        .chunk_by(|a, b| a >> 1 == b >> 1)
        .all(|run| run[0] >> 1 == v || run.iter().map(|&e| direction(e)).sum::<i32>() == 0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// The unit cube's corner `k`: x = bit 0, y = bit 1, z = bit 2.
    fn cube_corners() -> Vec<DVec3> {
        (0..8).map(|k| DVec3::new((k & 1) as f64, (k >> 1 & 1) as f64, (k >> 2) as f64)).collect()
    }

    /// Outward faces of the unit cube.
    const FACES: [[u32; 4]; 6] =
        [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];

    fn quads(faces: &[[u32; 4]]) -> Vec<[u32; 3]> {
        faces.iter().flat_map(|f| [[f[0], f[1], f[2]], [f[0], f[2], f[3]]]).collect()
    }

    fn geometry(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Geometry {
        Geometry { object: vec![0; triangles.len()], positions, triangles }
    }

    fn all(g: &Geometry) -> Vec<u32> {
        (0..g.len() as u32).collect()
    }

    /// Whether the triangles `tris` of `g` form a closed surface.
    fn closed(g: &Geometry, tris: &[u32]) -> bool {
        let mut one = g.clone();
        one.object = vec![1; g.len()];
        for &t in tris {
            one.object[t as usize] = 0;
        }
        closed_objects(&one, 1, |_| true, Corners::ByNumberOrPosition)[0]
    }

    /// A box is closed (also with its corners repeated per face, as a mesh split for its
    /// normals has them); without a face, or with a face turned, it is not.
    #[test]
    fn closed_boxes_qualify_and_open_ones_do_not() {
        let cube = geometry(cube_corners(), quads(&FACES));
        assert!(closed(&cube, &all(&cube)));
        let open = geometry(cube_corners(), quads(&FACES[1..]));
        assert!(!closed(&open, &all(&open)));
        let mut turned = FACES;
        turned[0].reverse();
        let turned = geometry(cube_corners(), quads(&turned));
        assert!(!closed(&turned, &all(&turned)));
        // Every face with corners of its own.
        let (mut positions, mut split) = (Vec::new(), Vec::new());
        for f in FACES {
            let base = positions.len() as u32;
            positions.extend(f.iter().map(|&k| cube_corners()[k as usize]));
            split.push([base, base + 1, base + 2, base + 3]);
        }
        let split = geometry(positions, quads(&split));
        assert!(closed(&split, &all(&split)));
        assert_eq!(closed_objects(&split, 1, |_| true, Corners::ByNumber), vec![false]);
        assert_eq!(closed_objects(&cube, 1, |_| true, Corners::ByNumber), vec![true]);
    }

    /// The check of the buckets agrees with a count of every directed edge, on small meshes
    /// with shared, repeated and degenerate edges, in buckets small and large (up to 80
    /// triangles on 6 corners): closed by construction (each triangle with
    /// a turned copy, in any order), then perhaps one triangle turned or dropped.
    #[test]
    fn buckets_agree_with_a_count_of_directed_edges() {
        use proptest::prelude::*;
        use std::collections::BTreeMap;
        let reference = |tris: &[[u32; 3]]| {
            let mut count: BTreeMap<(u32, u32), i64> = BTreeMap::new();
            for t in tris {
                for (p, q) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                    if p != q {
                        *count.entry((p.min(q), p.max(q))).or_default() +=
                            if p < q { 1 } else { -1 };
                    }
                }
            }
            count.values().all(|&n| n == 0)
        };
        let mesh = (
            proptest::collection::vec([0u32..6, 0u32..6, 0u32..6], 1..40),
            0usize..3,
            any::<proptest::sample::Index>(),
            any::<u64>(),
        );
        proptest!(|((half, change, at, shuffle) in mesh)| {
            let mut tris: Vec<[u32; 3]> =
                half.iter().flat_map(|&[a, b, c]| [[a, b, c], [c, b, a]]).collect();
            let k = at.index(tris.len());
            match change {
                1 => tris[k].reverse(),
                2 => {
                    tris.remove(k);
                }
                _ => {}
            }
            let n = tris.len();
            let key = |t: &[u32; 3]| t.iter().fold(0u64, |h, &v| h * 31 + u64::from(v));
            tris.sort_by_key(|t| key(t) ^ shuffle);
            let g = geometry(cube_corners()[..6].to_vec(), tris.clone());
            let all: Vec<u32> = (0..n as u32).collect();
            prop_assert_eq!(balanced(&g, &all, |v| v), reference(&tris));
            prop_assert_eq!(
                closed_objects(&g, 1, |_| true, Corners::ByNumber)[0],
                reference(&tris)
            );
        });
    }

    /// A closed grid torus of 144,000 triangles, counted in parts by four threads (and by
    /// one), is closed; with one triangle turned, or one dropped, it is not.
    #[test]
    fn a_large_closed_mesh_is_decided_in_parts() {
        let (n, m) = (300u32, 240u32);
        let at = |i: u32, j: u32| (i % n) * m + (j % m);
        let positions: Vec<DVec3> =
            (0..n * m).map(|k| DVec3::new(f64::from(k / m), f64::from(k % m), 0.0)).collect();
        let mut triangles = Vec::new();
        for i in 0..n {
            for j in 0..m {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                triangles.extend([[a, b, c], [a, c, d]]);
            }
        }
        let mut turned = triangles.clone();
        turned[12_345].reverse();
        let mut dropped = triangles.clone();
        dropped.remove(54_321);
        for threads in [4, 1] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build();
            let pool = pool.expect("a thread pool");
            for (tris, closed) in [(&triangles, true), (&turned, false), (&dropped, false)] {
                let g = geometry(positions.clone(), tris.clone());
                let got = pool.install(|| balanced(&g, &all(&g), |v| v));
                assert_eq!(got, closed, "{threads} threads");
            }
        }
    }

    /// Per object: a closed cube and an open one (a face missing) side by side; an object not
    /// asked about is not closed.
    #[test]
    fn objects_are_decided_apart() {
        let mut positions = cube_corners();
        positions.extend(cube_corners().iter().map(|&p| p + DVec3::X * 3.0));
        let mut triangles = quads(&FACES);
        let shifted: Vec<[u32; 4]> = FACES[1..].iter().map(|f| f.map(|k| k + 8)).collect();
        triangles.extend(quads(&shifted));
        let mut object = vec![0; 12];
        object.extend(vec![1; 10]);
        let g = Geometry { positions, triangles, object };
        let both = Corners::ByNumberOrPosition;
        assert_eq!(closed_objects(&g, 3, |_| true, both), vec![true, false, false]);
        assert_eq!(closed_objects(&g, 2, |o| o == 1, both), vec![false, false]);
    }

    /// Each picked object's triangles in ascending order, none for the others, over several
    /// parts of the triangles, whether few objects are picked (listed in parallel) or many
    /// (in one pass), objects numbered beyond `objects` among them.
    #[test]
    fn triangles_are_listed_by_object_in_order() {
        let n = 40_000;
        let object: Vec<u32> = (0..n as u32).map(|t| (t * 7919 + t / 3) % 150).collect();
        let g = Geometry { object, positions: Vec::new(), triangles: vec![[0, 0, 0]; n] };
        for pick in [|o: usize| o % 50 == 3, |o: usize| o.is_multiple_of(2)] {
            let lists = triangles_of(&g, 140, pick);
            assert_eq!(lists.len(), 140);
            for (o, list) in lists.iter().enumerate() {
                let want: Vec<u32> = (0..n as u32)
                    .filter(|&t| pick(o) && g.object[t as usize] as usize == o)
                    .collect();
                assert_eq!(list, &want, "object {o}");
            }
        }
    }
}
