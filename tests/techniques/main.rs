//! Each technique end to end against its paper and the references, the shared kernels on
//! whole scenes, the two references against each other, the hard cases (scale, grazing light,
//! slivers, far objects) through every method, and the workspace's module graph (no import
//! cycles in any crate). One test binary, one module per concern.

#[path = "../common/mod.rs"]
mod common;

mod afsm;
mod esm;
mod far_objects;
mod frame;
mod ftizb;
mod ground_truth;
mod hard_cases;
mod light_fit;
mod modules;
mod motion;
mod msm;
mod pan09;
mod pcf;
mod planar;
mod shadow_maps;
mod spsm;
mod vsm;
mod warnings;
