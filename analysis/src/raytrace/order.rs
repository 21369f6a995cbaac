//! The order of a packet's shadow rays: where the camera rays' hits scatter in depth, the
//! shadow rays are put in Z order of their origins seen along the light, so that each group of
//! four rays (one SIMD test, [`super::packet`]) starts from one small patch of the light's
//! view instead of from anywhere in the packet's.
//!
//! Why: the camera rays of a packet are in Z order of the image, so a group of four is four
//! neighbouring sub-samples. Their shadow rays start where those camera rays hit, and on a
//! surface seen as a whole (bunny-plane, cage) neighbours in the image stay neighbours on the
//! surface. On random-1m (a million scattered triangles) the rays of a pixel hit triangles at
//! any depth, so a group's shadow rays start anywhere along the streak the pixel's view makes
//! across the light's view: every group then meets most of the boxes any ray of the packet
//! meets, and narrowing the packet to the groups that hit a box rules out few. The shadow
//! rays are two thirds of random-1m's tracing time at rate 64 (1,959 of 2,828 ms, one thread).
//!
//! When: sorting every packet (a key per ray, a sort of up to 256 keys) made bunny-plane's and
//! cage's tracing 20-30 % slower at rate 64, whose groups are already compact. So a packet is
//! sorted only when its groups are spread: when their boxes' half-perimeters (the sums of
//! their three extents) add up to more than [`SPREAD`] times the whole packet's. Groups tiling
//! the packet's box add up to a few times its half-perimeter (8 for 64 square tiles of a
//! square); groups each spanning the packet, to about 0.6 times their number (64). At rate 64
//! (320 x 240), 0.6 % of bunny-plane's shadow packets exceed 10, 7 % of cage's (pixels that
//! see bars at several depths) and 48 % of random-1m's. 6, 10 and 16 gave random-1m the same
//! time within the noise.
//!
//! The key: the two coordinates across the first ray's direction, each scaled to its own
//! extent (the packet's box across the light, at [`KEY_BITS`] bits each), but to no less than
//! a key's step of the other's extent, so that the rounding noise of a coordinate that does not
//! vary does not become a full key. One scale for both made random-1m's tracing 8 % slower
//! than per-coordinate scales.
//!
//! Measured (random-1m, 320 x 240, rate 64, alternating processes, 3 rounds of 2 runs each,
//! load 1.1-1.6): tracing 3,351 -> 2,969 ms at one thread (-11 %); bunny-plane and cage the
//! same within the noise. Images and counters are the same bit for bit on the built-in scenes
//! compared (ten at rate 1, five at rate 16, hairball's transparency among them).
//!
//! Nothing a ray finds depends on its place in the packet: its hits are decided by its own
//! tests ([`super::packet`]). Only the order in which a ray meets several semi-transparent
//! triangles can change, and with it the last bit of the product of their transmittances
//! (see the parent module).
//!
//! Hot path: the buffers are a band's, reused from packet to packet; the check of the groups
//! is one pass over the origins.

use super::packet::LANES as GROUP;
use super::ray::TraceRay;
use glam::DVec3;
use scenes::morton;

/// A packet is sorted when its groups' box half-perimeters add up to more than this many
/// times its own (see the module doc).
const SPREAD: f64 = 10.0;

/// Bits per axis of the Z-order key.
const KEY_BITS: u32 = 10;

/// Buffers for sorting a packet's shadow rays, reused from packet to packet.
#[derive(Default)]
pub(crate) struct Order {
    keys: Vec<(u32, u16)>,
    rays: Vec<TraceRay>,
    of: Vec<usize>,
    limits: Vec<(f64, f64)>,
    skip: Vec<u32>,
}

/// The half-perimeter of the box `(lo, hi)`: the sum of its extents.
#[inline]
fn half_perimeter(lo: DVec3, hi: DVec3) -> f64 {
    (hi - lo).element_sum()
}

/// Whether the groups of four of `rays` start from boxes whose half-perimeters add up to more
/// than [`SPREAD`] times that of the box of all their origins.
fn spread(rays: &[TraceRay]) -> bool {
    let (mut lo, mut hi, mut groups) = (DVec3::INFINITY, DVec3::NEG_INFINITY, 0.0);
    for group in rays.chunks(GROUP) {
        let (mut glo, mut ghi) = (group[0].origin, group[0].origin);
        for r in &group[1..] {
            (glo, ghi) = (glo.min(r.origin), ghi.max(r.origin));
        }
        groups += half_perimeter(glo, ghi);
        (lo, hi) = (lo.min(glo), hi.max(ghi));
    }
    groups > SPREAD * half_perimeter(lo, hi)
}

/// `x`, at least `lo` and at most `extent` above it, as an integer of [`KEY_BITS`] bits.
#[inline]
fn quantize(x: f64, lo: f64, extent: f64) -> u32 {
    let scale = f64::from((1u32 << KEY_BITS) - 1);
    let q = if extent > 0.0 { ((x - lo) / extent * scale) as u32 } else { 0 };
    q & ((1 << KEY_BITS) - 1)
}

impl Order {
    /// Puts the shadow rays `rays[..n]`, with their sub-samples `of`, ranges `limits` and the
    /// triangles they leave `skip` (each at least `n` long), in Z order of their origins
    /// projected along the first ray's direction when their groups are spread (see the
    /// module doc). Afterwards the first `n` entries of each are the packet, in its order.
    pub(crate) fn sort(
        &mut self,
        n: usize,
        rays: &mut Vec<TraceRay>,
        of: &mut Vec<usize>,
        limits: &mut Vec<(f64, f64)>,
        skip: &mut Vec<u32>,
    ) {
        if n <= GROUP || !spread(&rays[..n]) {
            return;
        }
        // Coordinates across the first ray's direction: for a directional light, the place of
        // each ray's line in the light's view.
        let d = rays[0].dir;
        let e1 = d.any_orthonormal_vector();
        let e2 = d.cross(e1);
        let across = |r: &TraceRay| (r.origin.dot(e1), r.origin.dot(e2));
        let (mut lo, mut hi) =
            ((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY));
        for r in &rays[..n] {
            let (u, v) = across(r);
            (lo, hi) = ((lo.0.min(u), lo.1.min(v)), (hi.0.max(u), hi.1.max(v)));
        }
        // Each coordinate scaled to its own extent, but to no less than a key's step of the
        // other's: a streak along one of them keeps its order, rather than the other's
        // rounding noise scaled up to a full key.
        let step = (hi.0 - lo.0).max(hi.1 - lo.1) / f64::from(1u32 << KEY_BITS);
        let (eu, ev) = ((hi.0 - lo.0).max(step), (hi.1 - lo.1).max(step));
        self.keys.clear();
        self.keys.extend(rays[..n].iter().enumerate().map(|(k, r)| {
            let (u, v) = across(r);
            (morton::code(quantize(u, lo.0, eu), quantize(v, lo.1, ev)), k as u16)
        }));
        self.keys.sort_unstable();
        let order = self.keys.iter().map(|&(_, k)| usize::from(k));
        self.rays.clear();
        self.rays.extend(order.clone().map(|k| rays[k]));
        self.of.clear();
        self.of.extend(order.clone().map(|k| of[k]));
        self.limits.clear();
        self.limits.extend(order.clone().map(|k| limits[k]));
        self.skip.clear();
        self.skip.extend(order.map(|k| skip[k]));
        std::mem::swap(rays, &mut self.rays);
        std::mem::swap(of, &mut self.of);
        std::mem::swap(limits, &mut self.limits);
        std::mem::swap(skip, &mut self.skip);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The light's direction in the tests: not along an axis.
    fn light() -> DVec3 {
        DVec3::new(0.3, -1.0, 0.2).normalize()
    }

    /// A packet's shadow rays and what goes with each.
    struct Packet {
        rays: Vec<TraceRay>,
        of: Vec<usize>,
        limits: Vec<(f64, f64)>,
        skip: Vec<u32>,
    }

    impl Packet {
        /// Rays toward the light from `origins`, each ray's sub-sample, range and left
        /// triangle made from its index.
        fn new(origins: &[DVec3]) -> Self {
            let rays =
                origins.iter().map(|&o| TraceRay::new(o, light()).expect("finite")).collect();
            let n = origins.len();
            let of = (0..n).map(|k| 1000 + k).collect();
            let limits = (0..n).map(|k| (k as f64, f64::INFINITY)).collect();
            let skip = (0..n).map(|k| 7 * k as u32).collect();
            Self { rays, of, limits, skip }
        }

        /// [`Order::sort`] of the first `n` rays.
        fn sort(&mut self, n: usize) {
            let Self { rays, of, limits, skip } = self;
            Order::default().sort(n, rays, of, limits, skip);
        }
    }

    /// A packet whose groups of four are 2 x 2 blocks of a 16 x 16 grid in Z order.
    fn tiled() -> Vec<DVec3> {
        (0..256u32)
            .map(morton::point)
            .map(|(x, z)| DVec3::new(f64::from(x), 0.0, f64::from(z)) * 0.01)
            .collect()
    }

    /// Points along a streak across the light's view, in a shuffled order, each moved along
    /// the light by a scattered depth (camera rays through one pixel hitting scattered
    /// triangles).
    fn streak() -> Vec<DVec3> {
        let mut state = 0x9E37_79B9u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let across = light().any_orthonormal_vector();
        let mut places: Vec<f64> = (0..256).map(f64::from).collect();
        for k in (1..places.len()).rev() {
            places.swap(k, (next() * (k + 1) as f64) as usize % (k + 1));
        }
        places.iter().map(|&s| across * s * 0.01 + light() * (next() * 50.0)).collect()
    }

    #[test]
    fn a_packet_whose_groups_tile_it_is_left_in_its_order() {
        let mut p = Packet::new(&tiled());
        assert!(!spread(&p.rays));
        p.sort(256);
        assert_eq!(p.of, (1000..1256).collect::<Vec<_>>());
    }

    #[test]
    fn scattered_rays_are_sorted_into_compact_groups_and_keep_their_entries() {
        let origins = streak();
        let mut p = Packet::new(&origins);
        assert!(spread(&p.rays));
        // Entries beyond the packet's `n` rays are left out (the camera rays' leftovers).
        let n = p.rays.len() - 3;
        // Seen along the light, the groups' extents add up to about 38 times the packet's
        // before and to about its extent after.
        let seen_along = |rays: &[TraceRay]| {
            let e1 = light().any_orthonormal_vector();
            let e2 = light().cross(e1);
            let flat = |r: &TraceRay| DVec3::new(r.origin.dot(e1), r.origin.dot(e2), 0.0);
            let extent = |g: &[TraceRay]| {
                let lo = g.iter().map(flat).fold(DVec3::INFINITY, DVec3::min);
                let hi = g.iter().map(flat).fold(DVec3::NEG_INFINITY, DVec3::max);
                half_perimeter(lo, hi)
            };
            rays.chunks(GROUP).map(extent).sum::<f64>() / extent(rays)
        };
        assert!(seen_along(&p.rays[..n]) > 20.0, "{}", seen_along(&p.rays[..n]));
        p.sort(n);
        assert!(seen_along(&p.rays[..n]) < 3.0, "{}", seen_along(&p.rays[..n]));
        let mut seen = vec![false; n];
        for k in 0..n {
            let was = p.of[k] - 1000;
            assert!(!std::mem::replace(&mut seen[was], true), "each ray once");
            assert_eq!(p.rays[k].origin, origins[was]);
            assert_eq!((p.limits[k], p.skip[k]), ((was as f64, f64::INFINITY), 7 * was as u32));
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn a_packet_of_one_group_or_of_one_origin_is_left_in_its_order() {
        for origins in [streak()[..4].to_vec(), vec![DVec3::ONE; 64]] {
            let mut p = Packet::new(&origins);
            p.sort(origins.len());
            assert_eq!(p.of, (1000..1000 + origins.len()).collect::<Vec<_>>());
        }
    }
}
