//! Large vectors made and joined in parallel.
//!
//! A frame's per-pixel and per-triangle buffers are megabytes each, made anew every frame.
//! Made by one thread (`vec![0.0; n]`, or a copy of parts one after the other), they keep the
//! other threads waiting: the allocator clears memory it kept from an earlier frame, or the
//! kernel gives fresh pages one fault at a time, in the one thread. Here each thread writes,
//! and so first touches, its own part.
//!
//! On `bunny-plane` at 800 x 600 and two threads, `exact` ran 19 ms of its 148 in the calling
//! thread alone, most of it making and joining such buffers (`perf` samples of that thread);
//! made here, and with the other serial passes that sampling found spread over the threads,
//! 3.6 ms.

use rayon::prelude::*;

/// Below this many elements a vector is made in the calling thread: handing it to the others
/// costs more than it saves.
const SERIAL_BELOW: usize = 1 << 14;

/// `n` copies of `value`, written in parallel.
pub fn filled<T: Copy + Send + Sync>(n: usize, value: T) -> Vec<T> {
    if n < SERIAL_BELOW {
        return vec![value; n];
    }
    (0..n).into_par_iter().map(|_| value).collect()
}

/// The parts one after the other in one vector, each copied into its own place in parallel.
pub fn concat<T: Copy + Default + Send + Sync>(parts: &[&[T]]) -> Vec<T> {
    if parts.iter().map(|p| p.len()).sum::<usize>() < SERIAL_BELOW {
        return parts.concat();
    }
    let mut all = filled(parts.iter().map(|p| p.len()).sum(), T::default());
    let places = cut(&mut all, parts.iter().map(|p| p.len()));
    places.into_par_iter().zip(parts).for_each(|(place, part)| place.copy_from_slice(part));
    all
}

/// `slice` cut into consecutive parts of the lengths `lens`, in order, so that each part can
/// be given to a thread of its own. The lengths must add up to at most `slice`'s.
pub fn cut<T>(mut slice: &mut [T], lens: impl IntoIterator<Item = usize>) -> Vec<&mut [T]> {
    let lens = lens.into_iter();
    let mut parts = Vec::with_capacity(lens.size_hint().0);
    for len in lens {
        let (part, tail) = std::mem::take(&mut slice).split_at_mut(len);
        parts.push(part);
        slice = tail;
    }
    parts
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The parts are joined in order, empty ones included.
    #[test]
    fn parts_are_joined_in_order() {
        let parts: Vec<Vec<u32>> =
            (0..40u32).map(|p| (0..p % 7 * 100).map(|k| p * 1000 + k).collect()).collect();
        let slices: Vec<&[u32]> = parts.iter().map(|p| &p[..]).collect();
        assert_eq!(concat(&slices), parts.concat());
        assert!(concat::<u32>(&[]).is_empty());
        let long: Vec<Vec<u32>> = (0..3u32).map(|p| vec![p; SERIAL_BELOW]).collect();
        let slices: Vec<&[u32]> = long.iter().map(|p| &p[..]).collect();
        assert_eq!(concat(&slices), long.concat(), "in parallel");
        assert_eq!(filled(5, 1.5), vec![1.5; 5]);
        let mut ten: Vec<u32> = (0..10).collect();
        let parts = cut(&mut ten, [3, 0, 4]);
        assert_eq!(parts, [&[0, 1, 2][..], &[], &[3, 4, 5, 6]], "the rest left out");
        assert_eq!(filled(SERIAL_BELOW + 3, 2u8), vec![2u8; SERIAL_BELOW + 3]);
    }
}
