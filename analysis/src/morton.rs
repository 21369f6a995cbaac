//! The Z-order (Morton) curve on 16-bit coordinates: a point's code interleaves the bits of its
//! `x` (the even bits) and its `y` (the odd ones). Shared by the ray tracer (the pixels of a
//! tile, the shadow rays of a packet) and `exact`'s caster grid (the order of its triangles).
//!
//! Each direction is four shifts and masks, not a loop over the bits: it runs once per packet
//! ray and once per triangle.

/// The low 16 bits of `v`, each moved to an even bit (bit `b` to bit `2b`).
#[inline]
fn spread(v: u32) -> u32 {
    let v = v & 0xffff;
    let v = (v | (v << 8)) & 0x00ff_00ff;
    let v = (v | (v << 4)) & 0x0f0f_0f0f;
    let v = (v | (v << 2)) & 0x3333_3333;
    (v | (v << 1)) & 0x5555_5555
}

/// The even bits of `v`, gathered into the low 16 (bit `2b` to bit `b`): [`spread`] undone.
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
pub(crate) fn code(x: u32, y: u32) -> u32 {
    spread(x) | (spread(y) << 1)
}

/// The point `(x, y)` of `code`: [`code`] undone.
#[inline]
pub(crate) fn point(code: u32) -> (u32, u32) {
    (gather(code), gather(code >> 1))
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
}
