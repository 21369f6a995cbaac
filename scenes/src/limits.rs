//! The range of scene sizes and positions the workbench supports, in world units, and the
//! largest scene it builds.
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

/// The most triangles a whole scene may have (40 M), summed over its objects; a scene whose
/// triangle count may exceed it (by the upper bound of `registry::Described::triangles`,
/// computed from generator parameters and mesh file headers) is refused before any mesh is
/// built, naming the estimate and this limit.
///
/// Why 40 M: a triangle costs memory several times over before and while a method runs. The
/// scene holds it in its object's mesh (a triangle soup such as `random_triangles` has three
/// `f64` vertices of its own: 3 x 24 + 12 = 84 bytes), the frame copies every object into one
/// [`Geometry`](crate::Geometry) (88 bytes), and the methods and references add their own
/// structures. Measured as the growth of the peak resident memory of `render` at 64 x 48 from
/// 1 M to 4 M random triangles: 254 bytes a triangle with `sm`, 434 with `raytrace` (its BVH).
/// At 40 M that is 10 GB and 17 GB: within the project's 24 GB machines, with room for the
/// frame's buffers and the system, whereas the 190 M of ten 19 M-triangle objects (48 to
/// 82 GB) could only end in an allocation failure long after the run began. A single
/// generator stops at `generators::MAX_TRIANGLES` (20 M), so two objects at that limit still
/// fit. `exact` needs more (1.8 GB at 1 M random triangles, its shadow polygons); what a
/// particular method and frame need beyond the scene is for the command to check before it
/// builds anything.
pub const MAX_SCENE_TRIANGLES: u64 = 40_000_000;
