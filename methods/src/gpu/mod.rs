//! The GPU path: the techniques as wgpu render and compute passes, each kernel checked against
//! its CPU twin (the CPU method of the same name, with the same stage names and counters).
//!
//! # Precision
//!
//! Every decision the CPU methods make in `f64` (where a point falls in a map, a depth
//! comparison against the bias, which side of an edge a sample lies on) is made by the kernels
//! in `f64` too, with the same operations in the same order, so that a kernel given the same
//! input as its twin gives the same answer bit for bit. The adapter must therefore have 64-bit
//! floats in shaders (wgpu's `SHADER_F64`: Vulkan and DX12 on desktop GPUs, Mesa's lavapipe);
//! [`GpuContext::new`] says so by name when it has not. Exact predicates the CPU evaluates
//! adaptively (orientation tests near zero) are filtered on the GPU with a forward error bound;
//! the few tests the filter cannot decide go back to the CPU twin, and a note of the run record
//! says how many.
//!
//! # Inputs
//!
//! A GPU run makes its own G-buffer and light depth map ([`raster`]: a hardware render pass of
//! triangle ids, resolved in `f64`), so it may differ from the CPU run where the hardware's
//! fixed-point coverage keeps another triangle than the CPU's exact rasterizer (at most 0.5 %
//! of samples on the built-in scenes, `tests/gpu/raster.rs`). The parity tests give each
//! kernel the CPU's own G-buffer and map ([`GpuFrame::upload`], [`GpuDepthMap::upload`]) and
//! require the twin's answer exactly.
//!
//! # What runs where
//!
//! `--device gpu` (see [`crate::registry`]) runs a technique's GPU kernels on the adapter
//! [`GpuContext`] chooses; `--device cpu` (the default) its CPU twin.

pub mod afsm;
pub mod afsm_ss;
pub mod common;
mod context;
mod error;
pub mod filtered;
pub mod frame;
pub mod ftizb;
mod layout;
pub mod pan09;
pub mod pcf;
pub mod raster;
mod scan;
mod shader;
pub mod sm;
pub mod spsm;

pub use context::{GpuContext, Timing, ADAPTER_ENV, BACKEND_ENV};
pub use error::GpuError;

use crate::method::ShadowMethod;

/// A GPU method's parameters: its CPU twin's, and `device = "gpu"`.
fn twin_params(twin: &dyn ShadowMethod) -> serde_json::Map<String, serde_json::Value> {
    let mut m = twin.params();
    m.insert("device".into(), "gpu".into());
    m
}
pub use frame::{GpuDepthMap, GpuFrame};

#[cfg(test)]
mod tests {
    use super::*;

    /// `a * b + c` in f64, on the GPU, must round twice as the CPU does: a fused multiply-add
    /// would break the bit-for-bit parity the kernels promise.
    #[test]
    fn f64_arithmetic_rounds_as_on_the_cpu() {
        let ctx = GpuContext::shared().expect("a GPU adapter (scripts/install-gpu-driver)");
        let src = r#"
@group(0) @binding(0) var<storage, read_write> v: array<f64>;
@compute @workgroup_size(1)
fn main() {
    let a = v[0]; let b = v[1]; let c = v[2];
    v[3] = a * b + c;
    v[4] = sqrt(a);
    v[5] = a / b;
    v[6] = floor(c * 1000.0lf);
}
"#;
        eprintln!("adapter: {}, timing: {}", ctx.adapter_name(), ctx.timing.name());
        let p = ctx.pipeline("probe", src, "main");
        let a = 1.0 + f64::EPSILON;
        let b = 1.0 - f64::EPSILON / 2.0;
        let c = -1.0;
        let buf = ctx.upload("v", &[a, b, c, 0.0, 0.0, 0.0, 0.0]);
        let bind = ctx.bind(&p, &[&buf]);
        let mut rec = instrumentation::Recorder::default();
        ctx.stage(&mut rec, "probe", |e| GpuContext::dispatch(e, &p, &bind, (1, 1, 1)))
            .expect("probe runs");
        let v: Vec<f64> = ctx.read(&buf).expect("read back");
        assert_eq!(v[3].to_bits(), (a * b + c).to_bits(), "fused: {:e} vs {:e}", v[3], a * b + c);
        assert_eq!(v[4].to_bits(), a.sqrt().to_bits());
        assert_eq!(v[5].to_bits(), (a / b).to_bits());
        assert_eq!(v[6], (c * 1000.0f64).floor());
        assert_eq!(rec.stages.stages.len(), 1);
    }
}
