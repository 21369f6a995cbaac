//! The Z-order (Morton) curve: a point's code interleaves the bits of its coordinates, `x`
//! lowest. In two dimensions on 16-bit coordinates ([`code`], [`point`]): the ray tracer's
//! tiles and packets and `exact`'s caster grid (the order of its triangles). In three on
//! 21-bit ones ([`code3`]): the order a mesh file's triangles are kept in
//! ([`spatial_order`](crate::spatial_order)).
//!
//! Each direction is a few shifts and masks, not a loop over the bits: it runs once per packet
//! ray and once per triangle.

/// The low 16 bits of `v`, each moved to an even bit (bit `b` to bit `2b`).
#[inline]
fn spread2(v: u32) -> u32 {
    let v = v & 0xffff;
    let v = (v | (v << 8)) & 0x00ff_00ff;
    let v = (v | (v << 4)) & 0x0f0f_0f0f;
    let v = (v | (v << 2)) & 0x3333_3333;
    (v | (v << 1)) & 0x5555_5555
}

/// The even bits of `v`, gathered into the low 16 (bit `2b` to bit `b`): [`spread2`] undone.
#[inline]
fn gather(v: u32) -> u32 {
    let v = v & 0x5555_5555;
    let v = (v | (v >> 1)) & 0x3333_3333;
    let v = (v | (v >> 2)) & 0x0f0f_0f0f;
    let v = (v | (v >> 4)) & 0x00ff_00ff;
    (v | (v >> 8)) & 0x0000_ffff
}

/// The code of point `(x, y)`, from the low 16 bits of each.
#[inline]
pub fn code(x: u32, y: u32) -> u32 {
    spread2(x) | (spread2(y) << 1)
}

/// The point `(x, y)` of `code`: [`code`] undone.
#[inline]
pub fn point(code: u32) -> (u32, u32) {
    (gather(code), gather(code >> 1))
}

/// The code of point `(x, y, z)`, from the low 21 bits of each: 63 bits.
#[inline]
pub fn code3(x: u32, y: u32, z: u32) -> u64 {
    spread3(x) | (spread3(y) << 1) | (spread3(z) << 2)
}

/// The low 21 bits of `v`, two zero bits after each (bit `b` to bit `3b`).
#[inline]
fn spread3(v: u32) -> u64 {
    let mut x = u64::from(v) & 0x1f_ffff;
    x = (x | (x << 32)) & 0x1f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x1f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_code_takes_x_from_the_even_bits_and_y_from_the_odd_ones() {
        for code in 0..1u32 << 16 {
            let (x, y) = point(code);
            let mut back = 0;
            for b in 0..16 {
                back |= ((x >> b) & 1) << (2 * b) | ((y >> b) & 1) << (2 * b + 1);
            }
            assert_eq!(back, code);
            assert!(x < 256 && y < 256);
        }
    }

    #[test]
    fn a_point_comes_back_from_its_code_and_only_its_low_16_bits_count() {
        for (x, y) in [(0, 0), (1, 0), (0, 1), (0xffff, 0), (0x1234, 0xfedc), (0xffff, 0xffff)] {
            assert_eq!(point(code(x, y)), (x, y));
            assert_eq!(code(x | 0x7_0000, y | 0xffff_0000), code(x, y));
        }
        assert_eq!(code(0b11, 0b01), 0b0111);
    }

    #[test]
    fn the_code_of_three_coordinates_interleaves_their_bits() {
        assert_eq!(code3(1, 0, 0), 1);
        assert_eq!(code3(0, 1, 0), 2);
        assert_eq!(code3(0, 0, 1), 4);
        assert_eq!(code3(3, 0, 0), 0b1001);
        let top = (1 << 21) - 1;
        assert_eq!(code3(top, top, top), (1u64 << 63) - 1);
    }
}
