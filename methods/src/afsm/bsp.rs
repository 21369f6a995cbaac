//! Stage "BSP construction" (Aila and Laine 2004, section 5.1): the axis-aligned 2D BSP of
//! the samples on the light's image plane.
//!
//! A node with at least `leaf_size` samples is split at the median of its samples along `x`
//! at even depths and `y` at odd depths (the root splits along `x`): quickselect
//! (`select_nth_unstable_by`) puts the `n / 2` smallest first, so the left child holds
//! `floor(n / 2)` samples and the right `ceil(n / 2)`, every left coordinate `<=` every right
//! one. Nodes with fewer than `leaf_size` samples are leaves (between `leaf_size / 2` and
//! `leaf_size - 1` samples, unless the whole set is smaller).
//!
//! Layout: the samples are permuted in place so that every node owns the contiguous range
//! `start..end`; nodes are stored in preorder (the left child follows its parent, the right
//! child lies `right` entries later), so every subtree is a contiguous run of nodes. Each
//! node keeps the exact bounding box of its samples (tighter than its split planes) and the
//! largest threshold depth among them (for max-depth culling).
//!
//! The split moves the 32-byte samples themselves, in place. Alternatives measured on `cage`'s
//! 325,840 samples at one thread: a bracket sampled around the median (Floyd and Rivest) with
//! two branch-free partitions, 15.6 ms (Lomuto) or 14.2 ms (Hoare) against quickselect's 14.0
//! (minimum of 15 builds); u32 indices selected by gathered keys, 36 ms. Records of 20 bytes
//! (image point and input index), each leaf gathering its samples and flat coordinates into
//! new vectors, made the stage slower, not faster: 23.5 and 32.9 ms of CPU time against 15.2
//! and 15.0 (24-byte records: 27.8 and 24.7 against 16.7 and 15.8; one pinned thread, load
//! 5 on 2 cores, alternating runs of 7 frames): the new vectors' first touch and the gather
//! cost more than the smaller records save. Writing the flat coordinates in each leaf while
//! its samples are in cache, instead of two passes after the build, made no difference
//! (`bunny-plane` and `cage`, one pinned thread, medians of 11 alternating runs of 5 frames:
//! 23.4 and 22.7 ms before, 23.4 and 22.9 after).

use super::samples::Sample;
use glam::DVec2;
use rayon::prelude::*;
use std::cmp::Ordering;

/// Subtrees with more samples than this are built on two threads.
const PARALLEL_SAMPLES: usize = 1 << 14;

/// A node of the 2D BSP.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Node {
    /// Lower corner of the exact bounding box of the node's samples (`+inf` when empty).
    pub lo: DVec2,
    /// Upper corner of that box (`-inf` when empty).
    pub hi: DVec2,
    /// Largest threshold depth [`Sample::zt`] among the node's samples (`-inf` when empty).
    pub max_zt: f64,
    /// First sample of the node.
    pub start: u32,
    /// One past its last sample.
    pub end: u32,
    /// Offset from this node to its right child (the left child is the next node); 0 for a
    /// leaf.
    pub right: u32,
}

impl Node {
    const EMPTY: Node = Node {
        lo: DVec2::splat(f64::INFINITY),
        hi: DVec2::splat(f64::NEG_INFINITY),
        max_zt: f64::NEG_INFINITY,
        start: 0,
        end: 0,
        right: 0,
    };

    /// Whether the node is a leaf.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.right == 0
    }

    /// Number of samples in the node.
    #[inline]
    pub fn len(&self) -> usize {
        (self.end - self.start) as usize
    }

    /// Whether the node holds no sample (only the root of an empty set).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.end == self.start
    }
}

/// The 2D BSP over the samples.
#[derive(Debug, Clone, PartialEq)]
pub struct Bsp {
    /// Nodes in preorder; the root is node 0.
    pub nodes: Vec<Node>,
    /// The samples, permuted so that each node's samples are contiguous.
    pub samples: Vec<Sample>,
    /// Their light image x, in the same order (for the leaves' vectorised box test).
    pub xs: Vec<f64>,
    /// Their light image y, in the same order.
    pub ys: Vec<f64>,
    /// The leaf size the tree was built with.
    pub leaf_size: usize,
}

/// Number of nodes of the tree over `n` samples, for every size that occurs in it: the sizes
/// at one depth are `floor(n / 2^d)` and `ceil(n / 2^d)`, at most two distinct values.
struct NodeCounts(Vec<(usize, usize)>);

impl NodeCounts {
    fn new(n: usize, leaf_size: usize) -> Self {
        let mut levels = vec![vec![n]];
        while let Some(sizes) = levels.last() {
            let mut next: Vec<usize> = sizes
                .iter()
                .filter(|&&m| m >= leaf_size)
                .flat_map(|&m| [m / 2, m - m / 2])
                .collect();
            next.sort_unstable();
            next.dedup();
            if next.is_empty() {
                break;
            }
            levels.push(next);
        }
        let mut counts: Vec<(usize, usize)> = Vec::new();
        for sizes in levels.iter().rev() {
            for &m in sizes {
                let c = if m < leaf_size {
                    1
                } else {
                    1 + Self::lookup(&counts, m / 2) + Self::lookup(&counts, m - m / 2)
                };
                counts.push((m, c));
            }
            counts.sort_unstable();
            counts.dedup();
        }
        Self(counts)
    }

    fn lookup(counts: &[(usize, usize)], m: usize) -> usize {
        counts.binary_search_by_key(&m, |&(size, _)| size).map_or(0, |i| counts[i].1)
    }

    fn get(&self, m: usize) -> usize {
        Self::lookup(&self.0, m)
    }
}

impl Bsp {
    /// Builds the BSP over `samples`; `leaf_size` must be at least 2.
    pub fn build(mut samples: Vec<Sample>, leaf_size: usize) -> Self {
        let leaf_size = leaf_size.max(2);
        let counts = NodeCounts::new(samples.len(), leaf_size);
        let mut nodes = vec![Node::EMPTY; counts.get(samples.len())];
        fill(&mut nodes, &mut samples, 0, 0, leaf_size, &counts);
        let xs = samples.par_iter().map(|s| s.x).collect();
        let ys = samples.par_iter().map(|s| s.y).collect();
        Self { nodes, samples, xs, ys, leaf_size }
    }

    /// The samples of `node`.
    #[inline]
    pub fn samples_of(&self, node: &Node) -> &[Sample] {
        &self.samples[node.start as usize..node.end as usize]
    }

    /// One past the last node of the subtree rooted at `g` (the end of its preorder run).
    pub fn subtree_end(&self, mut g: usize) -> usize {
        while !self.nodes[g].is_leaf() {
            g += self.nodes[g].right as usize;
        }
        g + 1
    }
}

/// The order of the median splits: numeric (`-0` equal to `0`), NaN after every number. One
/// comparison in the common case, where `f64::total_cmp` maps both bit patterns first: the
/// stage took 5-10 % less time on `bunny-plane` and `cage` at one thread (minima 22.7 -> 19.2
/// and 20.8 -> 19.1 ms, 11 alternating runs of 5 frames), with the same image and node visits.
#[inline(always)]
fn order(a: f64, b: f64) -> Ordering {
    a.partial_cmp(&b).unwrap_or_else(|| a.is_nan().cmp(&b.is_nan()))
}

/// Builds the subtree over `samples` (the global samples `first..first + samples.len()`)
/// into `nodes`, which has exactly the subtree's node count; `axis` 0 splits along x.
fn fill(
    nodes: &mut [Node],
    samples: &mut [Sample],
    first: usize,
    axis: usize,
    leaf_size: usize,
    counts: &NodeCounts,
) {
    let n = samples.len();
    let (start, end) = (first as u32, (first + n) as u32);
    if n < leaf_size {
        let mut node = Node { start, end, ..Node::EMPTY };
        for s in samples.iter() {
            let p = DVec2::new(s.x, s.y);
            node.lo = node.lo.min(p);
            node.hi = node.hi.max(p);
            node.max_zt = node.max_zt.max(s.zt);
        }
        nodes[0] = node;
        return;
    }
    let mid = n / 2;
    if axis == 0 {
        samples.select_nth_unstable_by(mid, |a, b| order(a.x, b.x));
    } else {
        samples.select_nth_unstable_by(mid, |a, b| order(a.y, b.y));
    }
    let (head, rest) = nodes.split_at_mut(1);
    let (left_nodes, right_nodes) = rest.split_at_mut(counts.get(mid));
    let (left, right) = samples.split_at_mut(mid);
    let next = 1 - axis;
    let mut build_left = || fill(left_nodes, left, first, next, leaf_size, counts);
    let mut build_right = || fill(right_nodes, right, first + mid, next, leaf_size, counts);
    if n > PARALLEL_SAMPLES {
        rayon::join(build_left, build_right);
    } else {
        build_left();
        build_right();
    }
    let (l, r) = (&left_nodes[0], &right_nodes[0]);
    head[0] = Node {
        lo: l.lo.min(r.lo),
        hi: l.hi.max(r.hi),
        max_zt: l.max_zt.max(r.max_zt),
        start,
        end,
        right: (1 + left_nodes.len()) as u32,
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn samples(points: &[(f64, f64)]) -> Vec<Sample> {
        points
            .iter()
            .enumerate()
            .map(|(i, &(x, y))| Sample { x, y, zt: (i % 7) as f64, id: i as u32, tri: 0 })
            .collect()
    }

    /// Checks every invariant of the module documentation; returns the leaf count.
    fn check(bsp: &Bsp, n: usize) -> usize {
        let mut owner = vec![0u32; n];
        let mut leaves = 0;
        check_node(bsp, 0, 0, &mut owner, &mut leaves);
        assert!(owner.iter().all(|&c| c == 1), "every sample in exactly one leaf");
        let mut ids: Vec<u32> = bsp.samples.iter().map(|s| s.id).collect();
        ids.sort_unstable();
        assert_eq!(ids, (0..n as u32).collect::<Vec<_>>(), "a permutation of the input");
        let flat: Vec<(f64, f64)> = bsp.samples.iter().map(|s| (s.x, s.y)).collect();
        let xy: Vec<(f64, f64)> = bsp.xs.iter().copied().zip(bsp.ys.iter().copied()).collect();
        assert_eq!(xy, flat, "flat coordinates in the samples' order");
        assert_eq!(bsp.subtree_end(0), bsp.nodes.len());
        assert_eq!(bsp.nodes.len(), 2 * leaves - 1);
        leaves
    }

    fn check_node(bsp: &Bsp, g: usize, depth: usize, owner: &mut [u32], leaves: &mut usize) {
        let node = bsp.nodes[g];
        let own = bsp.samples_of(&node);
        for s in own {
            assert!(node.lo.x <= s.x && s.x <= node.hi.x && node.lo.y <= s.y && s.y <= node.hi.y);
            assert!(s.zt <= node.max_zt);
        }
        if !own.is_empty() {
            assert!(own.iter().any(|s| s.zt == node.max_zt), "max depth is attained");
            assert!(own.iter().any(|s| s.x == node.lo.x) && own.iter().any(|s| s.y == node.hi.y));
        }
        if node.is_leaf() {
            assert!(node.len() < bsp.leaf_size);
            for k in node.start..node.end {
                owner[k as usize] += 1;
            }
            *leaves += 1;
            return;
        }
        assert!(node.len() >= bsp.leaf_size, "only nodes of at least leaf_size are split");
        let (l, r) = (bsp.nodes[g + 1], bsp.nodes[g + node.right as usize]);
        assert_eq!((l.start, l.end, r.start, r.end), (node.start, r.start, l.end, node.end));
        assert_eq!(l.len(), node.len() / 2, "median split");
        let coord = |s: &Sample| if depth.is_multiple_of(2) { s.x } else { s.y };
        let left_max = bsp.samples_of(&l).iter().map(coord).fold(f64::NEG_INFINITY, f64::max);
        let right_min = bsp.samples_of(&r).iter().map(coord).fold(f64::INFINITY, f64::min);
        assert!(left_max <= right_min, "depth {depth}: {left_max} > {right_min}");
        assert_eq!(g + node.right as usize, bsp.subtree_end(g + 1), "preorder layout");
        check_node(bsp, g + 1, depth + 1, owner, leaves);
        check_node(bsp, g + node.right as usize, depth + 1, owner, leaves);
    }

    #[test]
    fn leaves_hold_between_half_and_less_than_leaf_size() {
        // 100 000 points: eleven halvings give leaves of 48 or 49 points.
        let pts: Vec<(f64, f64)> = (0..100_000u64)
            .map(|i| (((i * 7919) % 1000) as f64 * 0.37, ((i * 104_729) % 997) as f64 * 0.11))
            .collect();
        let bsp = Bsp::build(samples(&pts), 64);
        let leaves = check(&bsp, pts.len());
        assert_eq!(leaves, 2048);
        for node in bsp.nodes.iter().filter(|n| n.is_leaf()) {
            assert!((32..64).contains(&node.len()), "{}", node.len());
        }
    }

    #[test]
    fn small_and_empty_sets_are_one_leaf() {
        for n in [0usize, 1, 5, 63] {
            let pts: Vec<(f64, f64)> = (0..n).map(|i| (i as f64, -(i as f64))).collect();
            let bsp = Bsp::build(samples(&pts), 64);
            assert_eq!(bsp.nodes.len(), 1);
            assert_eq!(bsp.nodes[0].len(), n);
            assert!(bsp.nodes[0].is_leaf());
        }
        let bsp = Bsp::build(Vec::new(), 64);
        assert!(bsp.nodes[0].is_empty() && bsp.nodes[0].lo.x == f64::INFINITY);
    }

    /// The splits' order is a total preorder over every `f64`, NaN of either sign included
    /// (a comparator that is not may make the selection panic), and numeric between numbers.
    #[test]
    fn the_split_order_is_total() {
        let values = [
            f64::NEG_INFINITY,
            -1.5,
            -0.0,
            0.0,
            f64::MIN_POSITIVE,
            2.0,
            f64::INFINITY,
            f64::NAN,
            -f64::NAN,
        ];
        for a in values {
            for b in values {
                assert_eq!(order(a, b), order(b, a).reverse(), "{a} {b}");
                if !a.is_nan() && !b.is_nan() {
                    assert_eq!(Some(order(a, b)), a.partial_cmp(&b), "{a} {b}");
                }
                for c in values {
                    if order(a, b).is_le() && order(b, c).is_le() {
                        assert!(order(a, c).is_le(), "{a} {b} {c}");
                    }
                }
            }
        }
        // NaN coordinates (which the transformation never makes) are split without panic.
        let pts: Vec<(f64, f64)> = (0..500)
            .map(|i| if i % 7 == 0 { (f64::NAN, 1.0) } else { (i as f64, -f64::NAN) })
            .collect();
        let bsp = Bsp::build(samples(&pts), 8);
        let mut ids: Vec<u32> = bsp.samples.iter().map(|s| s.id).collect();
        ids.sort_unstable();
        assert_eq!(ids, (0..500).collect::<Vec<_>>());
    }

    #[test]
    fn equal_coordinates_still_split_in_half() {
        let pts = vec![(1.0, 2.0); 1000];
        let bsp = Bsp::build(samples(&pts), 8);
        let leaves = check(&bsp, 1000);
        // Seven halvings leave 24 nodes of 7 samples (leaves) and 104 of 8, split once more.
        assert_eq!(leaves, 24 + 2 * 104);
    }

    proptest! {
        #[test]
        fn bsp_invariants_hold_for_any_points(
            pts in proptest::collection::vec((-1e3f64..1e3, -1e3f64..1e3), 0..3000),
            leaf_size in 2usize..100,
            snap in any::<bool>(),
        ) {
            // Snapped coordinates give many ties along both axes.
            let pts: Vec<(f64, f64)> = if snap {
                pts.iter().map(|&(x, y)| ((x / 100.0).round(), (y / 100.0).round())).collect()
            } else {
                pts
            };
            let bsp = Bsp::build(samples(&pts), leaf_size);
            check(&bsp, pts.len());
        }
    }
}
