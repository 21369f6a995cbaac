//! The range of scene sizes and positions the workbench supports, in world units.
//!
//! Every pipeline computes in `f64`, and products of up to a few coordinates (areas, plane
//! equations, homogeneous projections, squared lengths) must neither overflow nor underflow;
//! the ray tracer's BVH stores `f32` boxes in a frame centred on the geometry and scaled to its
//! typical triangle. Within these bounds every method and both references stay finite and
//! scale-free (tested from scale 1e-6 to 1e6, translations to 1e7 and objects 1e12 away in
//! `tests/techniques/hard_cases.rs`); a scene beyond them is refused with the range named.

/// Largest magnitude of any world-space coordinate of a scene's geometry, camera or light.
pub const MAX_COORDINATE: f64 = 1e15;

/// Smallest bounding-box diagonal of a scene's geometry.
pub const MIN_EXTENT: f64 = 1e-9;
