//! Why the GPU path could not run: [`GpuError`]. A module of its own that names nothing else
//! of the crate: [`crate::method::MethodError`] carries it, and the GPU path uses `method`
//! (every GPU method is a [`crate::method::ShadowMethod`]), so `method` depends on this
//! module only, not on the GPU path.

/// Why the GPU path could not run (no adapter, or an adapter that lacks what it needs).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GpuError {
    /// No adapter at all.
    #[error(
        "no GPU adapter found (backends asked: {backends}); install a GPU driver or Mesa's \
         software rasterizer (Debian: mesa-vulkan-drivers libvulkan1), or run with --device cpu"
    )]
    NoAdapter {
        /// The backends asked.
        backends: String,
    },
    /// Adapters exist, but none has 64-bit floats in shaders.
    #[error(
        "no GPU adapter with 64-bit floats in shaders (wgpu SHADER_F64), which the GPU kernels \
         need to match the CPU methods; adapters found: {adapters}. Try \
         SHADOWBENCH_GPU_BACKEND=vulkan, or run with --device cpu"
    )]
    NoF64Adapter {
        /// The adapters found.
        adapters: String,
    },
    /// `SHADOWBENCH_GPU_ADAPTER` is set, and no adapter's name contains it.
    #[error(
        "SHADOWBENCH_GPU_ADAPTER={wanted:?}: no adapter's name contains it; adapters found: \
         {adapters}"
    )]
    NoMatchingAdapter {
        /// The variable's value.
        wanted: String,
        /// The adapters found.
        adapters: String,
    },
    /// `SHADOWBENCH_GPU_BACKEND` names no backend.
    #[error("SHADOWBENCH_GPU_BACKEND={0:?} names no wgpu backend (vulkan, gl, metal, dx12)")]
    BadBackend(String),
    /// The input needs more than the adapter's limits allow (a buffer or binding larger than
    /// it takes): bad input for this device.
    #[error(
        "the input exceeds the GPU adapter's limits (lower --map-res, the frame size or --rate, \
         or run with --device cpu): {0}"
    )]
    Limit(String),
    /// The device failed (internal failure).
    #[error("GPU device: {0}")]
    Device(String),
}
