//! The headless GPU context: adapter choice, device and queue.
//!
//! Adapter choice: every adapter of the enabled backends (`WGPU_BACKEND`,
//! default Vulkan/Metal/DX12) is listed; `WGPU_ADAPTER_NAME` keeps those whose
//! name contains it (case-insensitive); then a discrete GPU beats an integrated
//! one, which beats a virtual one, which beats a CPU (software) adapter such as
//! lavapipe. Optional features (timestamp queries, ray queries) are requested
//! only where the adapter has them, so that every method that needs neither
//! works on any adapter; `PENUMBRA_DISABLE_RAY_QUERY=1` leaves ray queries
//! off even where the adapter has them (to test the typed error of the
//! methods that need them, see [`RAY_QUERY_ENV`]).

use std::sync::{Arc, Mutex};

use crate::error::{Error, Result};

/// What was picked, for `penumbra.adapter_info()`.
#[derive(Debug, Clone, PartialEq)]
pub struct AdapterSummary {
    pub name: String,
    pub backend: String,
    pub device_type: String,
    pub driver: String,
    pub driver_info: String,
    pub timestamp_queries: bool,
    /// `EXPERIMENTAL_RAY_QUERY` (Vulkan `VK_KHR_ray_query`): the adapter has it
    /// and [`RAY_QUERY_ENV`] does not turn it off. Method `raytraced` needs it.
    pub ray_queries: bool,
    pub is_software: bool,
}

/// The environment variable that, set to anything but empty or `0`, keeps
/// ray queries off the device even where the adapter has them.
pub const RAY_QUERY_ENV: &str = "PENUMBRA_DISABLE_RAY_QUERY";

/// Whether [`RAY_QUERY_ENV`] turns ray queries off.
pub fn ray_queries_disabled() -> bool {
    std::env::var(RAY_QUERY_ENV).is_ok_and(|v| !v.is_empty() && v != "0")
}

pub struct GpuContext {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub summary: AdapterSummary,
    /// Errors raised outside any error scope, collected rather than panicking.
    uncaptured: Arc<Mutex<Vec<String>>>,
}

const DRIVER_HINT: &str = "install a Vulkan driver: on Debian or Ubuntu `apt-get install \
    mesa-vulkan-drivers libvulkan1` gives the software adapter (lavapipe); on a machine with a GPU, \
    install its vendor's driver. WGPU_BACKEND and WGPU_ADAPTER_NAME narrow the choice";

fn type_rank(t: wgpu::DeviceType) -> u8 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

fn backend_rank(b: wgpu::Backend) -> u8 {
    match b {
        wgpu::Backend::Vulkan | wgpu::Backend::Metal | wgpu::Backend::Dx12 => 0,
        wgpu::Backend::Gl => 1,
        _ => 2,
    }
}

fn instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::PRIMARY;
    wgpu::Instance::new(desc.with_env())
}

fn summarize(adapter: &wgpu::Adapter) -> AdapterSummary {
    let info = adapter.get_info();
    AdapterSummary {
        name: info.name.clone(),
        backend: format!("{:?}", info.backend).to_lowercase(),
        device_type: format!("{:?}", info.device_type),
        driver: info.driver.clone(),
        driver_info: info.driver_info.clone(),
        timestamp_queries: adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY),
        ray_queries: adapter.features().contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY) && !ray_queries_disabled(),
        is_software: info.device_type == wgpu::DeviceType::Cpu,
    }
}

/// Picks the adapter as the module documentation says.
pub fn select_adapter() -> Result<wgpu::Adapter> {
    let instance = instance();
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
    if adapters.is_empty() {
        return Err(Error::GpuUnavailable(format!("no GPU adapter found: {DRIVER_HINT}")));
    }
    let wanted = std::env::var("WGPU_ADAPTER_NAME").ok().filter(|s| !s.is_empty());
    let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
    let mut candidates: Vec<wgpu::Adapter> = adapters
        .into_iter()
        .filter(|a| match &wanted {
            Some(w) => a.get_info().name.to_lowercase().contains(&w.to_lowercase()),
            None => true,
        })
        .collect();
    if candidates.is_empty() {
        return Err(Error::GpuUnavailable(format!(
            "no adapter's name contains WGPU_ADAPTER_NAME={:?}; adapters found: {names:?}",
            wanted.unwrap_or_default()
        )));
    }
    candidates.sort_by_key(|a| {
        let info = a.get_info();
        (type_rank(info.device_type), backend_rank(info.backend))
    });
    Ok(candidates.swap_remove(0))
}

/// The summary of the adapter a renderer would pick, without creating a device.
pub fn adapter_summary() -> Result<AdapterSummary> {
    select_adapter().map(|a| summarize(&a))
}

/// The token wgpu asks for before it enables an `EXPERIMENTAL_` feature.
///
/// wgpu marks it `unsafe` because its experimental features may still hold
/// bugs: the one taken, ray queries, is used only by method `raytraced`
/// (acceleration-structure builds and `rayQuery*` in one compute shader), whose
/// tests compare it with the CPU ray casting of `penumbra.raycast` and with
/// Mitsuba. Every other method runs the same without it.
#[allow(unsafe_code)]
fn experimental() -> wgpu::ExperimentalFeatures {
    // SAFETY: see above; nothing else in the crate relies on experimental features.
    unsafe { wgpu::ExperimentalFeatures::enabled() }
}

impl GpuContext {
    pub fn new() -> Result<Self> {
        let adapter = select_adapter()?;
        let summary = summarize(&adapter);
        let mut required_features = wgpu::Features::empty();
        if summary.timestamp_queries {
            required_features |= wgpu::Features::TIMESTAMP_QUERY;
        }
        // The adapter's own limits: big shadow maps and images where the hardware allows.
        let required_limits = adapter.limits();
        let experimental_features = if summary.ray_queries {
            required_features |= wgpu::Features::EXPERIMENTAL_RAY_QUERY;
            experimental()
        } else {
            wgpu::ExperimentalFeatures::disabled()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("penumbra::device"),
            required_features,
            required_limits,
            experimental_features,
            memory_hints: wgpu::MemoryHints::MemoryUsage,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| {
            Error::GpuUnavailable(format!("adapter '{}' refused a device: {e}", summary.name))
        })?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut errors) = sink.lock() {
                errors.push(e.to_string());
            }
        }));
        Ok(Self { adapter, device, queue, summary, uncaptured })
    }

    pub fn has_ray_queries(&self) -> bool {
        self.device.features().contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY)
    }

    pub fn has_timestamps(&self) -> bool {
        self.device.features().contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// Runs `work` with validation and out-of-memory errors captured, turning
    /// any into [`Error::OutOfMemory`] or [`Error::Gpu`] instead of a panic. An
    /// out-of-memory error wins over the validation errors it causes (a
    /// texture that could not be allocated is invalid in every later call).
    pub fn scoped<T>(&self, work: impl FnOnce() -> Result<T>) -> Result<T> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let result = work();
        let validation_error = pollster::block_on(validation.pop());
        let oom_error = pollster::block_on(oom.pop());
        if let Some(e) = oom_error {
            return Err(Error::OutOfMemory(format!("out of GPU memory: {e}")));
        }
        if let Some(e) = validation_error {
            return Err(Error::Gpu(e.to_string()));
        }
        let stray = self.uncaptured.lock().map(|mut v| std::mem::take(&mut *v)).unwrap_or_default();
        if let Some(e) = stray.into_iter().next() {
            return Err(Error::Gpu(e));
        }
        result
    }

    /// Blocks until all submitted work is done.
    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| Error::Gpu(format!("waiting for the GPU failed: {e}")))
    }
}
