//! Shadow techniques and the shared kernels they use.
//!
//! Kernels: [`raster`] (exact CPU rasterizer), [`gbuffer`] (camera G-buffer), [`depth_map`]
//! (light depth map), [`frame`] (a scene at one resolution). Techniques, one module each:
//! [`sm`] (standard shadow map), [`afsm`] (alias-free shadow maps, `afsm` and `afsm-ss`). Every technique implements [`method::ShadowMethod`];
//! [`registry`] finds them by name.

pub mod afsm;
pub mod depth_map;
pub mod frame;
pub mod gbuffer;
pub mod method;
pub mod pattern;
pub mod raster;
pub mod registry;
pub mod sm;

pub use frame::Frame;
pub use method::{MethodError, ShadowMethod, Visibility};
pub use registry::{method, MethodOptions, METHODS};
