//! The range of scene sizes and positions the workbench supports, in world units, and the
//! largest scene it builds.
//!
//! Every pipeline computes in `f64`, and products of up to a few coordinates (areas, plane
//! equations, homogeneous projections, squared lengths) must neither overflow nor underflow;
//! the ray tracer's BVH stores `f32` boxes in a frame centred on the geometry and scaled to its
//! typical triangle. Within these bounds every method and both references stay finite and
//! scale-free (tested from scale 1e-6 to 1e6, translations to 1e7 and objects 1e12 away in
//! `tests/techniques/hard_cases.rs`); a scene beyond them is refused with the range named. The
//! messages that name a value beside its bound are written here, once for every kind of scene.

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

/// `x` for a message that sets it against `bound`: in scientific notation with at most 3
/// significant digits when those differ from the bound (`3.2e20`), else with every digit it
/// takes (`1.0000000000000001e15`), so that a value just beyond a bound never reads as the
/// bound itself.
pub(crate) fn apart(x: f64, bound: f64) -> String {
    let text = format!("{x:.2e}");
    let short = match text.split_once('e') {
        Some((mantissa, exponent)) => {
            let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
            format!("{mantissa}e{exponent}")
        }
        None => text,
    };
    if short.parse::<f64>().is_ok_and(|s| (s > bound) == (x > bound) && s != bound) {
        short
    } else {
        format!("{x:e}")
    }
}

/// Why a largest coordinate magnitude `m` is beyond [`MAX_COORDINATE`] (or not finite), if it is.
pub(crate) fn beyond_range(m: f64) -> Option<String> {
    let beyond = format!("beyond the supported range |x| <= {MAX_COORDINATE:e}");
    if m.is_finite() {
        (m > MAX_COORDINATE)
            .then(|| format!("coordinates reach {}, {beyond}", apart(m, MAX_COORDINATE)))
    } else {
        Some(format!("coordinates overflow, {beyond}"))
    }
}

/// Why a bounding-box diagonal is below [`MIN_EXTENT`], if it is.
pub(crate) fn below_extent(diagonal: f64) -> Option<String> {
    (diagonal < MIN_EXTENT).then(|| {
        format!(
            "the geometry's bounding box has a diagonal of {}, below the supported minimum \
             {MIN_EXTENT:e}",
            apart(diagonal, MIN_EXTENT)
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_value_beside_its_bound_is_printed_apart_from_it() {
        assert_eq!(apart(3.2e20, MAX_COORDINATE), "3.2e20");
        assert_eq!(apart(1.5e15, MAX_COORDINATE), "1.5e15");
        assert_eq!(apart(1e15 + 1.0, MAX_COORDINATE), "1.000000000000001e15");
        assert_eq!(apart(MAX_COORDINATE.next_up(), MAX_COORDINATE), "1.0000000000000001e15");
        assert_eq!(apart(MIN_EXTENT.next_down(), MIN_EXTENT), "9.999999999999999e-10");
        assert_eq!(apart(4e-10, MIN_EXTENT), "4e-10");
        let message = beyond_range(MAX_COORDINATE.next_up()).expect("beyond");
        assert_eq!(
            message,
            "coordinates reach 1.0000000000000001e15, beyond the supported range |x| <= 1e15"
        );
    }
}
