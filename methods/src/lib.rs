//! Shadow techniques and the shared kernels they use.
//!
//! Kernels: [`raster`] (exact CPU rasterizer), [`bands`] (parallel binning into bands of rows),
//! [`gbuffer`] (camera G-buffer), [`depth_map`] (light depth map), [`depth_test`] (map lookups,
//! bias, depth quantization), [`footprint`] (whether a light map resolves the frame, and its
//! warnings), [`filtered_map`] (the box filter of the filtered shadow maps), [`pattern`] (sub-pixel
//! sample patterns), [`frame`] (a scene at one resolution), [`light_fit`] (the light frustum a map
//! is rendered through: the scene's bounds or the camera's view, `--frustum`). Techniques, one
//! module each: [`sm`] (standard shadow map), [`pcf_reeves`] (Reeves et al.'s stochastic PCF),
//! [`pcf_bs`] (Brabec and Seidel's packed PCF), [`pcf_gems`] (GPU Gems' 4x4-region PCF), [`afsm`]
//! (alias-free shadow maps, `afsm` and `afsm-ss`), [`pan09`] (Pan et al.'s fast sub-pixel
//! antialiased shadow maps), [`spsm`] (Lecocq et al.'s sub-pixel shadow maps). Every technique
//! implements [`method::ShadowMethod`]; [`registry`] finds them by name, in one table whose entries
//! declare their [`params`].

pub mod afsm;
pub mod bands;
pub mod closed;
pub mod depth_map;
pub mod depth_test;
pub mod filtered_map;
pub mod footprint;
pub mod frame;
pub mod ftizb;
pub mod gbuffer;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod light_fit;
pub mod method;
pub mod pan09;
pub mod parallel;
pub mod params;
pub mod pattern;
pub mod pcf_bs;
pub mod pcf_gems;
pub mod pcf_reeves;
pub mod raster;
pub mod registry;
#[cfg(feature = "slowdown")]
pub mod slowdown;
pub mod sm;
pub mod spsm;

pub use frame::Frame;
pub use light_fit::LightFit;
pub use method::{MethodError, ShadowMethod, Visibility};
pub use registry::{method, MethodOptions, METHODS};
