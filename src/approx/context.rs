//! The GPU context (docs/design.md §4): adapter selection, device and queue, and wgpu's errors turned
//! into `PgtError::Gpu` instead of panics.
//!
//! wgpu's default handler for errors outside an error scope panics; pgt installs its own, which
//! records the message, and wraps every fallible step in an error scope that is popped and
//! reported. No adapter at all is a clear message and exit code 2 (docs/design.md §4).

use crate::error::{PgtError, Result};
use std::sync::{Arc, Mutex};

/// The message docs/design.md §4 asks for when no adapter exists.
pub const NO_ADAPTER: &str =
    "no GPU adapter found: install mesa-vulkan-drivers and libvulkan1 (lavapipe, Vulkan on the CPU) or a GPU driver";

/// One adapter as the user can name it with `--adapter`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AdapterDescription {
    /// The driver's name, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
    pub name: String,
    pub backend: String,
    pub device_type: String,
    /// A CPU implementation (lavapipe): its loop limit shapes how pgt splits work.
    pub is_cpu: bool,
}

impl std::fmt::Display for AdapterDescription {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({}, {})", self.name, self.backend, self.device_type)
    }
}

/// An open device on a chosen adapter.
///
/// The device has the adapter's own limits (docs/design.md §4 "Buffer limits"), not wgpu's
/// defaults: the largest storage buffer bounds the scene size, and every buffer pgt creates
/// is checked against it first ([`GpuContext::check_buffers`]).
pub struct GpuContext {
    /// The adapter that runs everything (named in every summary).
    pub adapter: AdapterDescription,
    /// The device, opened with every limit the adapter offers (or with a smaller storage
    /// buffer: [`GpuContext::with_storage_limit`]).
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// Whether compute passes can carry timestamp queries (`TIMESTAMP_QUERY`).
    pub timestamps: bool,
    /// Whether the device was opened with f64 in shaders (`SHADER_F64`; only
    /// [`GpuContext::with_f64`] asks for it).
    pub f64: bool,
    /// Errors that reached the uncaptured-error handler, oldest first.
    uncaptured: Arc<Mutex<Vec<String>>>,
}

impl std::fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuContext")
            .field("adapter", &self.adapter)
            .field("timestamps", &self.timestamps)
            .finish_non_exhaustive()
    }
}

/// Keeps the Vulkan loader's device-selection layer from printing
/// `error: XDG_RUNTIME_DIR is invalid or not set in the environment.` on every GPU command.
///
/// Mesa's implicit layer `VK_LAYER_MESA_device_select` looks for a Wayland compositor's GPU
/// (`wl_display_connect`) whenever the instance enables `VK_KHR_wayland_surface`, which wgpu
/// always does; libwayland prints that line (twice: the layer enumerates twice) when
/// `XDG_RUNTIME_DIR` is unset. Without `XDG_RUNTIME_DIR` there is no Wayland session whose GPU
/// the layer could find, and pgt chooses its adapter itself (`--adapter`, else the first
/// hardware adapter), so the layer is switched off with its own variable, `NODEVICE_SELECT=1`.
/// A user who configures the layer (`NODEVICE_SELECT`, `MESA_VK_DEVICE_SELECT`, `DRI_PRIME`)
/// keeps it as configured. Nothing else is hidden: no output of the loader or driver is filtered.
///
/// Changes the process environment: call it before any thread starts (`main` does).
pub fn quiet_device_select_probe() {
    let unset = |name: &str| std::env::var_os(name).is_none_or(|v| v.is_empty());
    if unset("XDG_RUNTIME_DIR")
        && unset("NODEVICE_SELECT")
        && unset("MESA_VK_DEVICE_SELECT")
        && unset("DRI_PRIME")
    {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
}

/// The refusal of an adapter (`described` by [`describe`]) whose `features` lack f64 in
/// shaders, which the GPU reference needs (docs/design.md §12).
fn require_f64(features: wgpu::Features, described: &str) -> Result<()> {
    if features.contains(wgpu::Features::SHADER_F64) {
        return Ok(());
    }
    Err(PgtError::Gpu(format!(
        "the GPU reference needs f64 in shaders (Vulkan shaderFloat64, wgpu SHADER_F64), which {described} does not offer; render on the CPU (pgt render without --gpu) or choose another adapter with --adapter"
    )))
}

fn describe(info: &wgpu::AdapterInfo) -> AdapterDescription {
    AdapterDescription {
        name: info.name.clone(),
        backend: format!("{:?}", info.backend),
        device_type: format!("{:?}", info.device_type),
        is_cpu: info.device_type == wgpu::DeviceType::Cpu,
    }
}

fn instance() -> wgpu::Instance {
    // WGPU_BACKEND and friends still apply (with_env), so a user can pick a backend.
    wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle().with_env())
}

/// Every adapter wgpu can see.
pub fn list_adapters() -> Vec<AdapterDescription> {
    let instance = instance();
    pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()))
        .iter()
        .map(|a| describe(&a.get_info()))
        .collect()
}

impl GpuContext {
    /// Opens a device. `adapter_filter`: a case-insensitive substring of the adapter's name
    /// (`--adapter`); without one, the first hardware adapter, else the first of any kind
    /// (lavapipe is a `Cpu` adapter).
    pub fn new(adapter_filter: Option<&str>) -> Result<GpuContext> {
        GpuContext::open(adapter_filter, false, None)
    }

    /// [`GpuContext::new`] with f64 in shaders (`SHADER_F64`, Vulkan's `shaderFloat64`), as the
    /// GPU reference needs (docs/design.md §12); an adapter without it is refused by name.
    pub fn with_f64(adapter_filter: Option<&str>) -> Result<GpuContext> {
        GpuContext::open(adapter_filter, true, None)
    }

    /// [`GpuContext::new`] (`f64` false) or [`GpuContext::with_f64`] (`f64` true) on a device
    /// whose storage buffers bind at most `bytes` (wgpu's `max_storage_buffer_binding_size`,
    /// where the adapter allows more): an adapter of a smaller limit, which wgpu then
    /// enforces, so that the tests of the limits run on small scenes.
    pub fn with_storage_limit(
        adapter_filter: Option<&str>,
        f64: bool,
        bytes: u64,
    ) -> Result<GpuContext> {
        GpuContext::open(adapter_filter, f64, Some(bytes))
    }

    fn open(
        adapter_filter: Option<&str>,
        f64: bool,
        storage_cap: Option<u64>,
    ) -> Result<GpuContext> {
        let instance = instance();
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
        if adapters.is_empty() {
            return Err(PgtError::Gpu(NO_ADAPTER.into()));
        }
        let adapter = match adapter_filter {
            Some(filter) => {
                let needle = filter.to_lowercase();
                adapters
                    .iter()
                    .find(|a| a.get_info().name.to_lowercase().contains(&needle))
                    .ok_or_else(|| {
                        let names: Vec<String> = adapters
                            .iter()
                            .map(|a| describe(&a.get_info()).to_string())
                            .collect();
                        PgtError::Gpu(format!(
                            "no GPU adapter matches --adapter '{filter}'; available: {}",
                            names.join("; ")
                        ))
                    })?
            }
            None => adapters
                .iter()
                .find(|a| {
                    matches!(
                        a.get_info().device_type,
                        wgpu::DeviceType::DiscreteGpu | wgpu::DeviceType::IntegratedGpu
                    )
                })
                .unwrap_or(&adapters[0]),
        };
        let info = adapter.get_info();
        let storage = super::contract::BINDINGS
            .iter()
            .filter(|b| b.kind != super::contract::BindingKind::Uniform)
            .count() as u32;
        let allowed = adapter.limits().max_storage_buffers_per_shader_stage;
        if allowed < storage {
            return Err(PgtError::Gpu(format!(
                "{} allows {allowed} storage buffers per shader stage; pgt's programs bind {storage} (docs/user-shaders.md)",
                info.name
            )));
        }
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let mut required_features = if timestamps {
            wgpu::Features::TIMESTAMP_QUERY
        } else {
            wgpu::Features::empty()
        };
        if f64 {
            require_f64(adapter.features(), &describe(&info).to_string())?;
            required_features |= wgpu::Features::SHADER_F64;
        }
        // Ask for everything the adapter offers, not wgpu's defaults (128 MiB a storage
        // buffer): the storage-buffer limits bound the scene size.
        let mut required_limits = adapter.limits();
        if let Some(bytes) = storage_cap {
            required_limits.max_storage_buffer_binding_size =
                bytes.min(required_limits.max_storage_buffer_binding_size);
        }
        let desc = wgpu::DeviceDescriptor {
            label: Some("pgt"),
            required_features,
            required_limits,
            ..Default::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&desc))
            .map_err(|e| PgtError::Gpu(format!("cannot open a device on {}: {e}", info.name)))?;
        let uncaptured: Arc<Mutex<Vec<String>>> = Arc::default();
        let sink = Arc::clone(&uncaptured);
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        Ok(GpuContext {
            adapter: describe(&info),
            device,
            queue,
            timestamps,
            f64,
            uncaptured,
        })
    }

    /// The largest storage buffer the device binds and allocates (bytes): the smaller of
    /// wgpu's `max_storage_buffer_binding_size` and `max_buffer_size` as the device has them.
    pub fn storage_limit(&self) -> u64 {
        storage_limit(&self.device.limits())
    }

    /// Refuses the first of `buffers` (a name for messages and a size in bytes) that exceeds
    /// [`GpuContext::storage_limit`], naming the buffer, its size, the limit and the adapter;
    /// `advice` says what the user can do instead. Called before the buffers are made, so a
    /// scene too large for the adapter is an error (exit code 2), never wgpu's validation
    /// error or an image rendered from part of the scene (docs/design.md §4 "Buffer limits").
    pub fn check_buffers(&self, buffers: &[(&str, u64)], advice: &str) -> Result<()> {
        self.check_buffers_under(u64::MAX, buffers, advice)
    }

    /// [`GpuContext::check_buffers`] as if the adapter bound at most `limit` bytes per storage
    /// buffer (never more than it does): the approximations' forced bands
    /// (`dispatch::run_with_limit`).
    pub(crate) fn check_buffers_under(
        &self,
        limit: u64,
        buffers: &[(&str, u64)],
        advice: &str,
    ) -> Result<()> {
        let mut limits = self.device.limits();
        limits.max_storage_buffer_binding_size = limits.max_storage_buffer_binding_size.min(limit);
        check_sizes(&limits, &self.adapter.to_string(), buffers, advice)
    }

    /// Runs `f` inside validation and out-of-memory error scopes; an error caught by either, or
    /// one that reached the uncaptured handler meanwhile, becomes `PgtError::Gpu` naming `what`.
    pub fn checked<T>(&self, what: &str, f: impl FnOnce() -> T) -> Result<T> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = f();
        let v = pollster::block_on(validation.pop());
        let o = pollster::block_on(oom.pop());
        if let Some(e) = v.or(o) {
            return Err(PgtError::Gpu(format!("{what}: {e}")));
        }
        self.check_uncaptured(what)?;
        Ok(value)
    }

    /// Reports an error that wgpu raised outside any scope.
    pub fn check_uncaptured(&self, what: &str) -> Result<()> {
        let mut v = self
            .uncaptured
            .lock()
            .map_err(|_| PgtError::Gpu(format!("{what}: GPU error handler poisoned")))?;
        if v.is_empty() {
            return Ok(());
        }
        let all = v.drain(..).collect::<Vec<_>>().join("; ");
        Err(PgtError::Gpu(format!("{what}: {all}")))
    }
}

/// See [`GpuContext::storage_limit`].
fn storage_limit(limits: &wgpu::Limits) -> u64 {
    limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size)
}

/// [`GpuContext::check_buffers`] for a device of `limits` on the adapter `described`.
fn check_sizes(
    limits: &wgpu::Limits,
    described: &str,
    buffers: &[(&str, u64)],
    advice: &str,
) -> Result<()> {
    let limit = storage_limit(limits);
    match buffers.iter().find(|&&(_, size)| size > limit) {
        None => Ok(()),
        Some(&(name, size)) => Err(PgtError::Gpu(format!(
            "this scene is too large for {described}: its {name} buffer needs {}, \
             the adapter allows {} per storage buffer (wgpu max_storage_buffer_binding_size {}, \
             max_buffer_size {}); {advice}",
            exact_bytes(size),
            exact_bytes(limit),
            limits.max_storage_buffer_binding_size,
            limits.max_buffer_size,
        ))),
    }
}

/// `320 bytes`, `1.5 KiB`, `128.0 MiB`, `2.0 GiB`.
pub fn human_bytes(bytes: u64) -> String {
    const KIB: u64 = 1 << 10;
    const MIB: u64 = 1 << 20;
    const GIB: u64 = 1 << 30;
    match bytes {
        0..KIB => format!("{bytes} bytes"),
        KIB..MIB => format!("{:.1} KiB", bytes as f64 / KIB as f64),
        MIB..GIB => format!("{:.1} MiB", bytes as f64 / MIB as f64),
        _ => format!("{:.1} GiB", bytes as f64 / GIB as f64),
    }
}

/// [`human_bytes`] with the exact count from 1 KiB up: `320 bytes`, `4.0 KiB (4097 bytes)`.
fn exact_bytes(bytes: u64) -> String {
    if bytes < 1024 {
        human_bytes(bytes)
    } else {
        format!("{} ({bytes} bytes)", human_bytes(bytes))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An adapter without f64 is refused by name with the flag it lacks and what to do; one
    /// with it passes (lavapipe offers f64, so the GPU tests cannot reach the refusal).
    #[test]
    fn an_adapter_without_f64_is_refused_by_name() {
        let err = require_f64(
            wgpu::Features::TIMESTAMP_QUERY,
            "SomeGPU (Vulkan, DiscreteGpu)",
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("SomeGPU (Vulkan, DiscreteGpu) does not offer")
                && err.contains("SHADER_F64")
                && err.contains("--adapter"),
            "{err}"
        );
        assert!(require_f64(wgpu::Features::SHADER_F64, "lavapipe").is_ok());
    }

    /// A buffer over the smaller of the two wgpu limits is refused with its name, its size,
    /// the limit, both wgpu limits and the adapter; one at the limit passes (the limit is the
    /// largest size allowed). Small fake limits: nothing is allocated.
    #[test]
    fn a_buffer_over_the_storage_limit_is_refused_by_name() {
        let limits = wgpu::Limits {
            max_storage_buffer_binding_size: 4096,
            max_buffer_size: 8192,
            ..wgpu::Limits::default()
        };
        let check = |buffers: &[(&str, u64)]| {
            check_sizes(&limits, "SomeGPU (Vulkan, Cpu)", buffers, "render fewer")
        };
        assert!(check(&[("particle", 4096), ("BVH node", 0)]).is_ok());
        let err = check(&[("particle", 4096), ("BVH node", 4097), ("x", 1 << 40)])
            .unwrap_err()
            .to_string();
        for part in [
            "too large for SomeGPU (Vulkan, Cpu)",
            "its BVH node buffer needs 4.0 KiB (4097 bytes)",
            "allows 4.0 KiB (4096 bytes) per storage buffer",
            "max_storage_buffer_binding_size 4096",
            "max_buffer_size 8192",
            "; render fewer",
        ] {
            assert!(err.contains(part), "{part:?} missing from: {err}");
        }
        // max_buffer_size the smaller: it is the limit.
        let limits = wgpu::Limits {
            max_storage_buffer_binding_size: 8192,
            max_buffer_size: 1000,
            ..wgpu::Limits::default()
        };
        assert!(check_sizes(&limits, "A", &[("p", 1000)], "").is_ok());
        let err = check_sizes(&limits, "A", &[("p", 1001)], "").unwrap_err();
        assert!(
            err.to_string().contains("allows 1000 bytes per storage"),
            "{err}"
        );
        assert_eq!(human_bytes(3 << 30), "3.0 GiB");
    }
}
