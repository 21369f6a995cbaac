//! The ray tracer's memory: its own large buffers allocated fallibly (`Vec::try_reserve_exact`),
//! a typed error naming what could not be had and what the whole run needs, and the estimate of
//! that need ([`memory_estimate`]).
//!
//! obvhs allocates inside its BVH build (bytemuck's `zeroed_vec`, which panics when the
//! allocation fails, and plain `Vec`s, which abort), where it cannot be made fallible. Before
//! each build the tracer therefore reserves, and releases at once, a block of the size obvhs
//! will need ([`OBVHS_BYTES_PER_TRIANGLE`] per triangle, measured): an allocator or an address
//! space limit that cannot give that much is refused with the typed error. Memory taken by
//! something else between that probe and the build can still make obvhs fail.
//!
//! The two largest buffers a run keeps (the slots' corners and the BVH's nodes) are handed from
//! run to run ([`Spare`]).

use std::sync::Mutex;

/// Bytes per triangle the BVH build allocates at its peak, from its arrays' sizes: obvhs 0.4's
/// PLOC holds two node arrays, the Morton codes (32 bytes each) and the binary BVH (two 32-byte
/// nodes per triangle), 164 bytes; while it is converted to the tracer's nodes the binary BVH
/// (two 48-byte nodes per triangle) is held, 96. 200 bounds both, as it bounded obvhs' wide
/// BVH conversion before.
pub(crate) const OBVHS_BYTES_PER_TRIANGLE: u64 = 200;

/// Bytes per triangle of the tracer's own arrays kept beside the BVH: the `f64` corners (72),
/// the triangle id (4) and the light it lets through (8) per slot, the tracer's nodes (at most
/// one of 64 bytes per triangle, allocated before the parts are built and converted into it)
/// and each slot's box (4), plus the build's temporary triangle list, medians and placed `f32`
/// boxes (4 + 8 + 28).
const OWN_BYTES_PER_TRIANGLE: u64 = 192;

/// Bytes per sub-sample of the per-sample buffers: [`super::RayTrace::sample_image`] keeps a
/// triangle id and a light value (12 bytes) per sub-sample twice (the rows and the image);
/// `evaluate` keeps at most 42 bytes per pixel (lit value, evaluated flag, RGB transmittance,
/// rows and image), less than this at any rate.
const BYTES_PER_SAMPLE: u64 = 48;

/// The ray tracer's peak memory beyond the frame, in bytes, for `triangles` triangles in its
/// BVHs (the scene's, plus its casters again when some triangle casts no shadow, which gets a
/// BVH of its own) and `samples` sub-samples (pixels times rate): the BVH build and the tracer's
/// copies of the triangles, then the per-sample buffers. It counts what is allocated, an upper
/// bound of what is touched (the per-sample term is what `sample_image` keeps; `evaluate`
/// keeps per-pixel values only). Peak RSS of a release build at 320 x 240: `render --method
/// raytrace` on random-1m peaked 343 MB at rates 1 and 16, 65 MB above `render --method sm`
/// on the same frame (estimate 396 and 451 MB; the ray tracer's peak comes when the scene's
/// own buffers are partly gone); on random-100k it stays below `sm`'s peak.
pub fn memory_estimate(triangles: u64, samples: u64) -> u64 {
    triangles
        .saturating_mul(OBVHS_BYTES_PER_TRIANGLE + OWN_BYTES_PER_TRIANGLE)
        .saturating_add(samples.saturating_mul(BYTES_PER_SAMPLE))
}

/// Memory the ray tracer could not allocate.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "raytrace: could not allocate {bytes} bytes for {what}; the ray tracer needs about \
     {estimate} bytes for this frame's triangles and sub-samples: lower the triangle count, \
     the frame size or the rate"
)]
pub struct AllocationError {
    /// The buffer that could not be allocated.
    pub what: &'static str,
    /// Its size in bytes.
    pub bytes: u64,
    /// What the whole run needs ([`memory_estimate`]).
    pub estimate: u64,
}

/// Allocates the tracer's buffers fallibly, naming the run's estimate when one fails.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Allocator {
    /// The run's [`memory_estimate`].
    pub(crate) estimate: u64,
}

impl Allocator {
    /// The error for `count` items of `T` named `what`.
    fn error<T>(&self, what: &'static str, count: usize) -> AllocationError {
        let bytes = (count as u64).saturating_mul(std::mem::size_of::<T>() as u64);
        AllocationError { what, bytes, estimate: self.estimate }
    }

    /// An empty vector with room for `count` items, or the error naming `what`.
    pub(crate) fn vec<T>(
        &self,
        count: usize,
        what: &'static str,
    ) -> Result<Vec<T>, AllocationError> {
        let mut v = Vec::new();
        v.try_reserve_exact(count).map_err(|_| self.error::<T>(what, count))?;
        Ok(v)
    }

    /// A vector of `count` zeroed items, or the error naming `what`. The allocator's zeroed
    /// pages are first touched where the items are written, in parallel, not in a fill of its
    /// own; pages never written are never touched.
    pub(crate) fn zeroed<T: bytemuck::Zeroable>(
        &self,
        count: usize,
        what: &'static str,
    ) -> Result<Vec<T>, AllocationError> {
        bytemuck::allocation::try_zeroed_vec(count).map_err(|()| self.error::<T>(what, count))
    }

    /// Whether a block of obvhs' build size for `triangles` triangles can be had: reserves it
    /// and releases it at once (see the module's doc).
    pub(crate) fn probe_bvh_build(&self, triangles: usize) -> Result<(), AllocationError> {
        let bytes = (triangles as u64).saturating_mul(OBVHS_BYTES_PER_TRIANGLE);
        let count = usize::try_from(bytes).unwrap_or(usize::MAX);
        self.vec::<u8>(count, "the BVH build").map(drop)
    }
}

/// The one buffer of a kind that a finished run left for the next run to reuse
/// ([`Spare::take`], [`Spare::give`]).
///
/// Why: glibc's `malloc` takes a buffer above 32 MiB straight from the kernel and gives it back
/// when it is freed, so each run's largest buffers came to it as fresh pages, each touched
/// first (a page fault and the kernel zeroing it) inside the timed build. On random-1m (a
/// million triangles, 1024 x 768, rate 1) the slots' corners (72 MB) and the BVH's nodes (up
/// to 64 MB) took about 29,000 such faults a run (37 ms of system time at one thread).
/// Reusing them made the BVH build 14 % faster at one thread (346 -> 297 ms) and 19 % at two
/// (211 -> 171 ms), the tracing the same (5 and 3 alternating processes of 4 runs each, load
/// 1.1-1.4). Smaller buffers are reused by `malloc` itself after the first run.
///
/// What it costs: after the run, the process keeps the largest buffer of each kind given back
/// (for random-1m, 136 MB in all). A run that takes it uses it in place of a buffer that
/// [`memory_estimate`] counts. Runs on several threads at once each take the spare or, when
/// another holds it, allocate their own; the larger one given back is kept.
pub(crate) struct Spare<T> {
    held: Mutex<Vec<T>>,
}

impl<T> Spare<T> {
    /// No buffer held.
    pub(crate) const fn new() -> Self {
        Self { held: Mutex::new(Vec::new()) }
    }

    /// An empty vector with room for `count` items: the spare when it has that room (taken
    /// out, so that no other run uses it meanwhile), else a new one from `alloc`.
    pub(crate) fn take(
        &self,
        alloc: &Allocator,
        count: usize,
        what: &'static str,
    ) -> Result<Vec<T>, AllocationError> {
        let spare = std::mem::take(&mut *self.lock());
        if spare.capacity() >= count {
            return Ok(spare);
        }
        // Freed before the new one is had, so that the two are never held together.
        drop(spare);
        alloc.vec(count, what)
    }

    /// Keeps `buffer`, emptied, for the next [`Spare::take`] when it holds more than the
    /// spare held now.
    pub(crate) fn give(&self, mut buffer: Vec<T>) {
        buffer.clear();
        let mut held = self.lock();
        if buffer.capacity() > held.capacity() {
            *held = buffer;
        }
    }

    /// The held buffer; a run that panicked while holding the lock left a vector, which is
    /// still one.
    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<T>> {
        self.held.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_estimate_grows_with_triangles_and_samples_and_saturates() {
        let base = memory_estimate(100_000, 76_800);
        assert!(memory_estimate(1_000_000, 76_800) > base);
        assert!(memory_estimate(100_000, 16 * 76_800) > base);
        assert_eq!(memory_estimate(u64::MAX, u64::MAX), u64::MAX);
        // Measured: random-1m (1,000,002 triangles) at 320 x 240, rate 16, peaked 242,088 KiB
        // above the same frame's `sm` run (release build); the estimate covers it.
        let measured = 242_088 * 1024;
        let estimate = memory_estimate(1_000_002, 16 * 320 * 240);
        assert!(estimate >= measured && estimate < 2 * measured, "{estimate}");
    }

    #[test]
    fn a_buffer_that_cannot_be_had_is_an_error_naming_its_size_and_the_estimate() {
        let alloc = Allocator { estimate: memory_estimate(1 << 40, 0) };
        let e = alloc
            .vec::<[f64; 9]>(usize::MAX / 8, "the triangles' corners")
            .expect_err("more than the address space");
        assert_eq!(e.what, "the triangles' corners");
        assert_eq!(e.bytes, u64::MAX);
        assert_eq!(e.estimate, memory_estimate(1 << 40, 0));
        let message = e.to_string();
        assert!(
            message.contains("the triangles' corners") && message.contains("rate"),
            "{message}"
        );
        assert!(alloc.probe_bvh_build(usize::MAX).is_err());
        assert!(alloc.probe_bvh_build(1000).is_ok());
    }

    #[test]
    fn a_spare_buffer_is_reused_when_it_has_room_and_the_larger_one_is_kept() {
        let (spare, alloc) = (Spare::<u64>::new(), Allocator { estimate: 0 });
        let mut first = spare.take(&alloc, 1000, "test").expect("small");
        first.extend(0..1000);
        let at = first.as_ptr();
        spare.give(first);
        spare.give(Vec::with_capacity(10));
        let again = spare.take(&alloc, 500, "test").expect("small");
        assert_eq!((again.as_ptr(), again.len()), (at, 0), "the larger buffer, emptied");
        // Taken out: a second run meanwhile gets a buffer of its own.
        let other = spare.take(&alloc, 500, "test").expect("small");
        assert_ne!(other.as_ptr(), at);
        spare.give(again);
        let larger = spare.take(&alloc, 2000, "test").expect("small");
        assert!(larger.capacity() >= 2000 && larger.is_empty());
        let too_much = spare.take(&alloc, usize::MAX / 8, "the test's buffer");
        assert_eq!(too_much.expect_err("more than the address space").what, "the test's buffer");
    }
}
