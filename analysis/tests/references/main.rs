//! The two references on their own: `exact` against analytic areas, point sampling and the
//! pixel classes beyond planar receivers, and `raytrace` end to end. One test binary.

mod exact;
mod grazing;
mod raytrace;
mod surfaces;
