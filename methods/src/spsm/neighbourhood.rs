//! The 3x3 texel neighbourhood of a pixel's texel, as classification and silhouette recovery
//! both read it: the ring of 8 neighbours in cyclic order ([`RING`], bit `k` of a ring mask),
//! the centre's bit, and the offsets of a 9-bit pattern's bits ([`NEIGHBOURHOOD`]).
//! Classification tries the neighbours in ring order; recovery builds its patterns and
//! tangents on the same bits. The GPU kernels mirror these arrays (`gpu/spsm/lookup.wgsl`).

/// The 8 neighbours around the centre, in cyclic order (image coordinates, `y` down):
/// NW, N, NE, E, SE, S, SW, W. Bit `k` of a ring mask is `RING[k]`; bit 8 is the centre.
pub const RING: [(i64, i64); 8] =
    [(-1, -1), (0, -1), (1, -1), (1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0)];

/// Bit of the centre texel in a 9-bit pattern.
pub const CENTRE_BIT: u16 = 1 << 8;

/// The texel offsets of the bits of a 9-bit pattern: the ring, then the centre.
pub const NEIGHBOURHOOD: [(i64, i64); 9] =
    [(-1, -1), (0, -1), (1, -1), (1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (0, 0)];
