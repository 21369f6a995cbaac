//! The headless wgpu device every GPU kernel runs on: adapter choice, buffers, compute
//! dispatch, read-back and stage timing.
//!
//! Adapter choice: `SHADOWBENCH_GPU_BACKEND` (`vulkan`, `gl`, `metal`, `dx12`; a comma list
//! is allowed) restricts the backends; otherwise every backend built in is asked. Among the
//! adapters that have 64-bit floats in shaders, a real GPU (discrete, then integrated, then
//! virtual) comes before a software rasterizer such as Mesa's llvmpipe (lavapipe), which is
//! taken only when there is nothing else. `SHADOWBENCH_GPU_ADAPTER` picks the first adapter
//! whose name contains the given text instead.
//!
//! Stage times: with `TIMESTAMP_QUERY` and `TIMESTAMP_QUERY_INSIDE_ENCODERS` a stage's time is
//! the difference of two timestamps written around its passes on the GPU; otherwise, and on
//! software adapters (whose timestamps do not wait for the compute work between them), it is
//! the wall-clock time from submission to completion. [`GpuContext::timing`] names which one
//! the run record gets. A stage submitted in parts is one entry, its parts' times summed
//! ([`instrumentation::Stages::add`]).
//!
//! Errors: what the device reports outside any call's result (validation errors, running out
//! of memory, a lost device) would make wgpu panic by default; here it is kept and returned as
//! [`GpuError::Device`] by the next wait ([`GpuContext::wait`], and so every stage and
//! read-back), an internal failure like any other device error.
//!
//! Runtime folder: Mesa's Vulkan driver prints `error: XDG_RUNTIME_DIR is invalid` when that
//! variable is unset or names no folder. Before the wgpu instance is made, such a value is
//! replaced, for this process only, by a private folder (`shadowbench-runtime-UID`, mode 0700)
//! under the system temp dir; a folder of that name that is not ours and private is not used.

use super::GpuError;
use bytemuck::Pod;
use instrumentation::Recorder;
use std::{
    sync::{Arc, Mutex, OnceLock},
    time::Instant,
};

/// Environment variable restricting the wgpu backends asked for an adapter.
pub const BACKEND_ENV: &str = "SHADOWBENCH_GPU_BACKEND";
/// Environment variable choosing an adapter by (part of) its name.
pub const ADAPTER_ENV: &str = "SHADOWBENCH_GPU_ADAPTER";

/// How stage times are taken on this adapter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Timing {
    /// GPU timestamps written before and after each stage's passes.
    TimestampQueries,
    /// Wall-clock time from submitting a stage to its completion.
    SubmitAndWait,
}

impl Timing {
    /// The name written into run records.
    pub fn name(self) -> &'static str {
        match self {
            Timing::TimestampQueries => "timestamp queries",
            Timing::SubmitAndWait => "submit and wait",
        }
    }
}

/// A wgpu device and queue with the workbench's helpers.
#[derive(Debug)]
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What the adapter says about itself.
    pub info: wgpu::AdapterInfo,
    /// How stage times are taken.
    pub timing: Timing,
    /// Timestamp ticks to nanoseconds.
    period_ns: f64,
    /// Query set of two timestamps, when [`Timing::TimestampQueries`].
    queries: Option<wgpu::QuerySet>,
    /// The first error the device reported outside a call's result (uncaptured error or
    /// device loss), not yet returned.
    fault: Arc<Mutex<Option<GpuError>>>,
}

/// The error an uncaptured wgpu error becomes: a validation error that says a size exceeds
/// one of the adapter's limits (a buffer, a binding, a dispatch) was caused by the input's
/// size, [`GpuError::Limit`]; everything else is a device failure.
fn classify(e: &wgpu::Error) -> GpuError {
    // wgpu's messages span several indented lines: one line reads better after a prefix.
    let text = e.to_string().split_whitespace().collect::<Vec<_>>().join(" ");
    match e {
        wgpu::Error::Validation { .. }
            if text.contains("limit") || text.contains("greater than the maximum") =>
        {
            GpuError::Limit(text)
        }
        _ => GpuError::Device(text),
    }
}

/// The variable Mesa's Vulkan driver checks for a runtime folder.
const RUNTIME_ENV: &str = "XDG_RUNTIME_DIR";

/// Points `XDG_RUNTIME_DIR` at a private folder when it is unset or not a folder, as the
/// module doc says; leaves it alone when no such folder can be had.
#[cfg(target_os = "linux")]
fn ensure_runtime_dir() {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt};
    if std::env::var_os(RUNTIME_ENV).is_some_and(|d| std::path::Path::new(&d).is_dir()) {
        return;
    }
    let Ok(uid) = std::fs::metadata("/proc/self").map(|m| m.uid()) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("shadowbench-runtime-{uid}"));
    // An existing folder is used only when it is ours and private (not made by someone else).
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    let usable = std::fs::symlink_metadata(&dir)
        .is_ok_and(|m| m.is_dir() && m.uid() == uid && m.mode() & 0o077 == 0);
    if usable {
        std::env::set_var(RUNTIME_ENV, &dir);
    }
}

/// No runtime folder is needed where there is no Mesa Vulkan driver to ask for one.
#[cfg(not(target_os = "linux"))]
fn ensure_runtime_dir() {}

/// Ranks an adapter: real GPUs first, software rasterizers last.
fn rank(info: &wgpu::AdapterInfo) -> u8 {
    match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// The backends `SHADOWBENCH_GPU_BACKEND` allows, or every backend built in.
fn backends() -> Result<wgpu::Backends, GpuError> {
    match std::env::var(BACKEND_ENV) {
        Ok(list) => {
            let b = wgpu::Backends::from_comma_list(&list);
            if b.is_empty() {
                return Err(GpuError::BadBackend(list));
            }
            Ok(b)
        }
        Err(_) => Ok(wgpu::Backends::all()),
    }
}

impl GpuContext {
    /// The process's shared context, created on first use.
    pub fn shared() -> Result<&'static GpuContext, GpuError> {
        static CONTEXT: OnceLock<Result<GpuContext, GpuError>> = OnceLock::new();
        CONTEXT.get_or_init(GpuContext::new).as_ref().map_err(Clone::clone)
    }

    /// Opens the adapter chosen as the module doc says.
    pub fn new() -> Result<Self, GpuError> {
        let backends = backends()?;
        ensure_runtime_dir();
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = backends;
        let instance = wgpu::Instance::new(desc);
        let adapters = pollster::block_on(instance.enumerate_adapters(backends));
        if adapters.is_empty() {
            return Err(GpuError::NoAdapter { backends: format!("{backends:?}") });
        }
        let names: Vec<String> = adapters
            .iter()
            .map(|a| {
                let i = a.get_info();
                format!("{} ({:?})", i.name, i.backend)
            })
            .collect();
        let mut usable = adapters;
        if let Some(want) = std::env::var_os(ADAPTER_ENV) {
            let want = want.to_string_lossy().into_owned();
            usable.retain(|a| a.get_info().name.contains(&want));
            if usable.is_empty() {
                return Err(GpuError::NoMatchingAdapter {
                    wanted: want,
                    adapters: names.join(", "),
                });
            }
        }
        usable.retain(|a| a.features().contains(wgpu::Features::SHADER_F64));
        usable.sort_by_key(|a| rank(&a.get_info()));
        let Some(adapter) = usable.into_iter().next() else {
            return Err(GpuError::NoF64Adapter { adapters: names.join(", ") });
        };
        let timestamps =
            wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        // lavapipe accepts timestamps inside encoders but writes them without waiting for the
        // compute work between them (measured: 0.04 ms around a 1.2 s dispatch), so software
        // adapters are timed by submit and wait.
        let software = adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        let has_timestamps = adapter.features().contains(timestamps) && !software;
        let mut required_features = wgpu::Features::SHADER_F64;
        if has_timestamps {
            required_features |= timestamps;
        }
        let alimits = adapter.limits();
        let required_limits = wgpu::Limits {
            max_storage_buffers_per_shader_stage: alimits.max_storage_buffers_per_shader_stage,
            max_storage_buffer_binding_size: alimits.max_storage_buffer_binding_size,
            max_buffer_size: alimits.max_buffer_size,
            max_compute_workgroups_per_dimension: alimits.max_compute_workgroups_per_dimension,
            ..wgpu::Limits::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("shadowbench"),
            required_features,
            required_limits,
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        let fault = Arc::new(Mutex::new(None));
        let keep = |fault: &Arc<Mutex<Option<GpuError>>>, e: GpuError| {
            if let Ok(mut f) = fault.lock() {
                f.get_or_insert(e);
            }
        };
        let f = Arc::clone(&fault);
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| keep(&f, classify(&e))));
        let f = Arc::clone(&fault);
        device.set_device_lost_callback(move |reason, message| {
            keep(&f, GpuError::Device(format!("device lost ({reason:?}): {message}")));
        });
        let queries = has_timestamps.then(|| {
            device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("stage timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            })
        });
        let timing = if has_timestamps { Timing::TimestampQueries } else { Timing::SubmitAndWait };
        let period_ns = f64::from(queue.get_timestamp_period());
        Ok(Self { device, queue, info: adapter.get_info(), timing, period_ns, queries, fault })
    }

    /// The adapter as the run record names it, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) via Vulkan`.
    pub fn adapter_name(&self) -> String {
        format!("{} via {:?}", self.info.name, self.info.backend)
    }

    /// Whether the adapter is a software rasterizer (no GPU).
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Writes the adapter and the timing method into a run's notes.
    pub fn describe(&self, rec: &mut Recorder) {
        rec.notes.push(format!(
            "GPU: {}; stage times by {}",
            self.adapter_name(),
            self.timing.name()
        ));
    }

    /// A compute pipeline from WGSL `source`, entry point `entry`, bind group 0 laid out from
    /// the shader.
    pub fn pipeline(&self, label: &str, source: &str, entry: &str) -> wgpu::ComputePipeline {
        let module = self.device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        self.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(label),
            layout: None,
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        })
    }

    /// A storage buffer holding `data`; an empty `data` gives one zeroed element (at least 4
    /// bytes), so that empty inputs bind (a binding holds at least one element of its array).
    pub fn upload<T: Pod>(&self, label: &str, data: &[T]) -> wgpu::Buffer {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let padded;
        let contents = if bytes.len() < 4 {
            padded = vec![0u8; std::mem::size_of::<T>().max(4)];
            &padded[..]
        } else {
            bytes
        };
        self.buffer_with(
            label,
            contents,
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        )
    }

    /// A uniform buffer holding `value`.
    pub fn uniform<T: Pod>(&self, label: &str, value: &T) -> wgpu::Buffer {
        self.buffer_with(
            label,
            bytemuck::bytes_of(value),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )
    }

    /// A buffer of `usage` holding `contents` (padded to a multiple of 4 bytes). A buffer the
    /// device refuses (larger than its limits, out of memory) comes back invalid, and the
    /// device's error is returned by the next wait; wgpu's own `create_buffer_init` panics
    /// there instead.
    fn buffer_with(&self, label: &str, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: (contents.len() as u64).next_multiple_of(4),
            usage,
            mapped_at_creation: true,
        });
        if let Ok(mut range) = buffer.get_mapped_range_mut(..) {
            range.slice(..contents.len()).copy_from_slice(contents);
        }
        buffer.unmap();
        buffer
    }

    /// A zeroed storage buffer of `len` elements of `T`, at least one (and 4 bytes), so that
    /// it binds when `len` is 0.
    pub fn zeroed<T: Pod>(&self, label: &str, len: usize) -> wgpu::Buffer {
        let size = (std::mem::size_of::<T>() * len.max(1)).max(4) as u64;
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: size.next_multiple_of(4),
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// A bind group for group 0 of `pipeline` with `buffers` at bindings 0, 1, 2, ...
    pub fn bind(
        &self,
        pipeline: &wgpu::ComputePipeline,
        buffers: &[&wgpu::Buffer],
    ) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry<'_>> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        })
    }

    /// Records one compute dispatch of `pipeline` over `groups` workgroups (x, y, z), split
    /// along y and z when x exceeds the adapter's per-dimension limit is the caller's concern.
    pub fn dispatch(
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        bind: &wgpu::BindGroup,
        groups: (u32, u32, u32),
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: None,
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bind, &[]);
        pass.dispatch_workgroups(groups.0, groups.1, groups.2);
    }

    /// Workgroups `(x, y, 1)` covering `n` invocations of a 1D kernel of `size` threads per
    /// group; kernels rebuild the index as `gid.x + gid.y * (groups.x * size)`.
    pub fn groups_1d(n: usize, size: u32) -> (u32, u32, u32) {
        let groups = (n as u64).div_ceil(u64::from(size)).max(1);
        const MAX: u64 = 65535;
        if groups <= MAX {
            (groups as u32, 1, 1)
        } else {
            (MAX as u32, groups.div_ceil(MAX) as u32, 1)
        }
    }

    /// Runs the stage `name`: `record` records its passes into one encoder, which is submitted
    /// and waited for; the stage's time goes into `rec` as the module doc says.
    pub fn stage<T>(
        &self,
        rec: &mut Recorder,
        name: &str,
        record: impl FnOnce(&mut wgpu::CommandEncoder) -> T,
    ) -> Result<T, GpuError> {
        let start = Instant::now();
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(name) });
        if let Some(q) = &self.queries {
            encoder.write_timestamp(q, 0);
        }
        let out = record(&mut encoder);
        let resolve = self.queries.as_ref().map(|q| {
            encoder.write_timestamp(q, 1);
            let buf = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            encoder.resolve_query_set(q, 0..2, &buf, 0);
            buf
        });
        self.queue.submit([encoder.finish()]);
        self.wait()?;
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
        let ms = match resolve {
            Some(buf) => {
                let t: Vec<u64> = self.read(&buf)?;
                (t[1].saturating_sub(t[0])) as f64 * self.period_ns * 1e-6
            }
            None => wall_ms,
        };
        rec.stages.add(name, ms);
        Ok(out)
    }

    /// Blocks until all submitted work is done; an error the device reported since the last
    /// wait (see the module doc) is returned here.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Device(e.to_string()))?;
        match self.fault.lock().map(|mut f| f.take()) {
            Ok(None) => Ok(()),
            Ok(Some(e)) => Err(e),
            Err(_) => Err(GpuError::Device("the device's error record is poisoned".into())),
        }
    }

    /// Copies `buffer` back to the CPU as elements of `T`.
    pub fn read<T: Pod>(&self, buffer: &wgpu::Buffer) -> Result<Vec<T>, GpuError> {
        let size = buffer.size();
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("read-back"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
        self.queue.submit([encoder.finish()]);
        let slice = staging.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        rx.recv()
            .map_err(|e| GpuError::Device(e.to_string()))?
            .map_err(|e| GpuError::Device(e.to_string()))?;
        let data = slice.get_mapped_range().map_err(|e| GpuError::Device(e.to_string()))?;
        let n = data.len() / std::mem::size_of::<T>();
        let out = bytemuck::cast_slice::<u8, T>(&data[..n * std::mem::size_of::<T>()]).to_vec();
        drop(data);
        staging.unmap();
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An error the device reports outside a call's result (here a buffer both readable and
    /// writable by mapping, which WebGPU forbids) comes back from the next wait as a device
    /// error, once, instead of wgpu's default panic.
    #[test]
    fn device_errors_come_back_from_the_next_wait() {
        let ctx = GpuContext::new().expect("a GPU adapter (scripts/install-gpu-driver)");
        ctx.wait().expect("no error yet");
        let _invalid = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("invalid"),
            size: 16,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::MAP_WRITE,
            mapped_at_creation: false,
        });
        let e = ctx.wait().expect_err("the error is returned");
        assert!(matches!(e, GpuError::Device(_)), "{e}");
        ctx.wait().expect("returned once");
    }

    /// A buffer larger than the device allows, uploaded from the CPU, is a limit error (bad
    /// input: the frame or map is too large for this adapter) from the next wait, not a panic.
    #[test]
    fn an_upload_beyond_the_device_limits_is_a_device_error() {
        let ctx = GpuContext::new().expect("a GPU adapter (scripts/install-gpu-driver)");
        let too_big = ctx.device.limits().max_buffer_size + 4;
        let Ok(len) = usize::try_from(too_big) else {
            return;
        };
        if len > 1 << 33 {
            eprintln!("skipped: the adapter allows buffers of {too_big} bytes");
            return;
        }
        let _buffer = ctx.upload("too big", &vec![0u8; len]);
        let e = ctx.wait().expect_err("the error is returned");
        assert!(matches!(e, GpuError::Limit(_)), "{e}");
    }
}
