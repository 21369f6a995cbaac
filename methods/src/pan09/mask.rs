//! Sub-sample bitmasks: bit `s` stands for sub-sample `s` of the shared
//! [`SamplePattern`](crate::pattern::SamplePattern). The width follows the rate, as in the
//! paper ("to accommodate twice the number of samples, our algorithm only need to double the
//! bit depth of the masks", section 5.1): `u32` up to rate 32, `u64` at 64, `u128` at 128.
//! Masks are accumulated from parallel tasks through atomic OR and AND, as the paper's CUDA
//! implementation does with atomic instructions (section 4); both are commutative, so the
//! result does not depend on scheduling.

use std::fmt::Debug;
use std::ops::{BitAnd, BitAndAssign, BitOr, BitOrAssign, Not};
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

/// A bitmask of sub-samples with atomic storage.
pub trait Mask:
    Copy
    + Eq
    + Debug
    + Default
    + Send
    + Sync
    + 'static
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + Not<Output = Self>
    + BitAndAssign
    + BitOrAssign
{
    /// Bits of the mask.
    const BITS: u32;
    /// No sample.
    const ZERO: Self;
    /// Atomic storage of one mask.
    type Atomic: Send + Sync;

    /// The mask of sub-sample `s` alone (`s < BITS`).
    fn bit(s: usize) -> Self;
    /// The mask of sub-samples `0..n` (`n <= BITS`).
    fn first(n: u32) -> Self;
    /// Number of sub-samples in the mask.
    fn count(self) -> u32;
    /// The mask widened to 128 bits.
    fn to_u128(self) -> u128;
    /// Atomic storage holding `v`.
    fn atomic(v: Self) -> Self::Atomic;
    /// `*a |= v`.
    fn fetch_or(a: &Self::Atomic, v: Self);
    /// `*a &= v`.
    fn fetch_and(a: &Self::Atomic, v: Self);
    /// The value held.
    fn load(a: &Self::Atomic) -> Self;
}

macro_rules! native_mask {
    ($t:ty, $atomic:ty) => {
        impl Mask for $t {
            const BITS: u32 = <$t>::BITS;
            const ZERO: Self = 0;
            type Atomic = $atomic;

            #[inline(always)]
            fn bit(s: usize) -> Self {
                1 << s
            }

            #[inline]
            fn first(n: u32) -> Self {
                if n >= Self::BITS {
                    <$t>::MAX
                } else {
                    (1 << n) - 1
                }
            }

            #[inline(always)]
            fn count(self) -> u32 {
                self.count_ones()
            }

            #[inline(always)]
            fn to_u128(self) -> u128 {
                u128::from(self)
            }

            fn atomic(v: Self) -> Self::Atomic {
                <$atomic>::new(v)
            }

            #[inline(always)]
            fn fetch_or(a: &Self::Atomic, v: Self) {
                a.fetch_or(v, Ordering::Relaxed);
            }

            #[inline(always)]
            fn fetch_and(a: &Self::Atomic, v: Self) {
                a.fetch_and(v, Ordering::Relaxed);
            }

            #[inline(always)]
            fn load(a: &Self::Atomic) -> Self {
                a.load(Ordering::Relaxed)
            }
        }
    };
}

native_mask!(u32, AtomicU32);
native_mask!(u64, AtomicU64);

/// 128-bit masks are stored as two 64-bit atomics (low, high); each half is updated
/// atomically, which is all OR and AND need.
impl Mask for u128 {
    const BITS: u32 = 128;
    const ZERO: Self = 0;
    type Atomic = [AtomicU64; 2];

    #[inline(always)]
    fn bit(s: usize) -> Self {
        1 << s
    }

    #[inline]
    fn first(n: u32) -> Self {
        if n >= 128 {
            u128::MAX
        } else {
            (1 << n) - 1
        }
    }

    #[inline(always)]
    fn count(self) -> u32 {
        self.count_ones()
    }

    #[inline(always)]
    fn to_u128(self) -> u128 {
        self
    }

    fn atomic(v: Self) -> Self::Atomic {
        [AtomicU64::new(v as u64), AtomicU64::new((v >> 64) as u64)]
    }

    #[inline(always)]
    fn fetch_or(a: &Self::Atomic, v: Self) {
        let (lo, hi) = (v as u64, (v >> 64) as u64);
        if lo != 0 {
            a[0].fetch_or(lo, Ordering::Relaxed);
        }
        if hi != 0 {
            a[1].fetch_or(hi, Ordering::Relaxed);
        }
    }

    #[inline(always)]
    fn fetch_and(a: &Self::Atomic, v: Self) {
        let (lo, hi) = (v as u64, (v >> 64) as u64);
        if lo != u64::MAX {
            a[0].fetch_and(lo, Ordering::Relaxed);
        }
        if hi != u64::MAX {
            a[1].fetch_and(hi, Ordering::Relaxed);
        }
    }

    #[inline(always)]
    fn load(a: &Self::Atomic) -> Self {
        u128::from(a[0].load(Ordering::Relaxed)) | (u128::from(a[1].load(Ordering::Relaxed)) << 64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    fn roundtrip<M: Mask>() {
        assert_eq!(M::first(0), M::ZERO);
        assert_eq!(M::first(M::BITS).count(), M::BITS);
        assert_eq!(M::first(5).count(), 5);
        assert_eq!((M::bit(3) | M::bit(M::BITS as usize - 1)).count(), 2);
        let a = M::atomic(M::first(M::BITS));
        M::fetch_and(&a, !M::bit(0));
        M::fetch_or(&a, M::ZERO);
        assert_eq!(M::load(&a).count(), M::BITS - 1);
        // Concurrent ORs of every bit from many tasks give every bit.
        let b = M::atomic(M::ZERO);
        (0..M::BITS as usize * 8)
            .into_par_iter()
            .for_each(|s| M::fetch_or(&b, M::bit(s % M::BITS as usize)));
        assert_eq!(M::load(&b), M::first(M::BITS));
        assert_eq!(M::load(&b).to_u128().count_ones(), M::BITS);
    }

    #[test]
    fn every_width_sets_counts_and_accumulates_atomically() {
        roundtrip::<u32>();
        roundtrip::<u64>();
        roundtrip::<u128>();
    }
}
