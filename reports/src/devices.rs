//! CPU and GPU side by side: the runs of a suite that ran the same method with the same
//! parameters on both devices (`device = ["cpu", "gpu"]` in a `[[run]]`), paired.
//!
//! A CPU method's time leaves out the camera G-buffer (shared by every method of a scene and
//! listed per scene); a GPU method renders its own G-buffer as its first stage, so its time is
//! given both ways: with that stage, and without it (the figure to set against the CPU's).

use crate::model::Row;
use std::fmt::Write as _;

/// One method run on both devices.
#[derive(Debug, Clone, PartialEq)]
pub struct DevicePair<'a> {
    /// The CPU run.
    pub cpu: &'a Row,
    /// The GPU run.
    pub gpu: &'a Row,
}

impl DevicePair<'_> {
    /// The GPU run's median time without its G-buffer stage.
    pub fn gpu_ms_without_gbuffer(&self) -> f64 {
        let gbuffer: f64 = self
            .gpu
            .stages
            .iter()
            .filter(|s| s.name == methods::frame::STAGE_GPU_GBUFFER)
            .map(|s| s.ms.median)
            .sum();
        self.gpu.total_ms.median - gbuffer
    }

    /// CPU time over GPU time without its G-buffer (medians).
    pub fn speedup(&self) -> f64 {
        self.cpu.total_ms.median / self.gpu_ms_without_gbuffer()
    }
}

/// Whether a GPU adapter is a software rasterizer running on the CPU (Mesa's llvmpipe or
/// softpipe, lavapipe, its Vulkan driver, SwiftShader, or any adapter that says it is
/// software).
pub fn is_software_adapter(name: &str) -> bool {
    let n = name.to_lowercase();
    ["llvmpipe", "lavapipe", "softpipe", "swiftshader", "software"].iter().any(|k| n.contains(k))
}

/// The parameters without the device.
fn key(row: &Row) -> (String, String, String) {
    let mut p = row.params.clone();
    p.remove("device");
    (row.scene.clone(), row.method.clone(), serde_json::Value::Object(p).to_string())
}

/// Every GPU row with the CPU row of the same scene, method and parameters, in report order.
pub fn pairs(rows: &[Row]) -> Vec<DevicePair<'_>> {
    rows.iter()
        .filter(|r| r.on_gpu())
        .filter_map(|gpu| {
            let k = key(gpu);
            rows.iter().find(|r| !r.on_gpu() && key(r) == k).map(|cpu| DevicePair { cpu, gpu })
        })
        .collect()
}

/// The header of the side-by-side table.
pub const COLUMNS: [&str; 9] = [
    "scene",
    "method",
    "parameters",
    "CPU ms",
    "GPU ms",
    "GPU ms without its G-buffer",
    "CPU / GPU (without)",
    "CPU mean error",
    "GPU mean error",
];

/// The cells of one pair.
pub fn cells(p: &DevicePair<'_>) -> [String; 9] {
    let mut params = p.cpu.params.clone();
    params.remove("device");
    let params: Vec<String> = params.iter().map(|(k, v)| format!("{k}={v}")).collect();
    let ms = |r: &Row| {
        format!("{:.2} [{:.2}, {:.2}]", r.total_ms.median, r.total_ms.min, r.total_ms.max)
    };
    [
        p.cpu.scene.clone(),
        p.cpu.method.clone(),
        params.join(" "),
        ms(p.cpu),
        ms(p.gpu),
        format!("{:.2}", p.gpu_ms_without_gbuffer()),
        format!("{:.2}", p.speedup()),
        format!("{:.5}", p.cpu.metrics.mean_abs_error),
        format!("{:.5}", p.gpu.metrics.mean_abs_error),
    ]
}

/// The side-by-side table in Markdown, empty when no method ran on both devices.
pub fn markdown(rows: &[Row]) -> String {
    let pairs = pairs(rows);
    let mut s = String::new();
    if pairs.is_empty() {
        return s;
    }
    let _ = writeln!(s, "| {} |", COLUMNS.join(" | "));
    let _ = writeln!(s, "|{}", "---|".repeat(COLUMNS.len()));
    for p in &pairs {
        let _ = writeln!(s, "| {} |", cells(p).join(" | "));
    }
    s
}
