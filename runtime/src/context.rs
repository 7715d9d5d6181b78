//! Adapter and device selection: the [`Context`] every pass runs on, the `SCATTER_GPU`
//! policy ([`GpuPolicy`]) and the [`AdapterReport`] that says which adapter was chosen.

use std::fmt;

/// Whether a GPU (any wgpu adapter, lavapipe included) is required, optional or unwanted.
///
/// Read from the environment by [`GpuPolicy::from_env`]: `SCATTER_GPU=required|auto|off`; when
/// `SCATTER_GPU` is unset or empty, a non-empty `CI` means `required` and anything else
/// `auto`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GpuPolicy {
    /// No adapter is an error.
    Required,
    /// No adapter means GPU work is skipped, with a loud reason on stderr.
    Auto,
    /// Do not touch wgpu at all.
    Off,
}

impl GpuPolicy {
    /// Name of the environment variable that selects the policy.
    pub const ENV: &'static str = "SCATTER_GPU";

    /// Reads `SCATTER_GPU` and `CI`.
    ///
    /// # Errors
    ///
    /// [`ContextError::InvalidPolicy`] when `SCATTER_GPU` holds anything but `required`,
    /// `auto` or `off` (case-insensitive, surrounding blanks ignored).
    pub fn from_env() -> Result<Self, ContextError> {
        let scatter_gpu = std::env::var_os(Self::ENV).map(|v| v.to_string_lossy().into_owned());
        let ci = std::env::var_os("CI").map(|v| v.to_string_lossy().into_owned());
        Self::from_values(scatter_gpu.as_deref(), ci.as_deref())
    }

    /// The policy for given values of `SCATTER_GPU` and `CI` (`None` = unset).
    ///
    /// # Errors
    ///
    /// [`ContextError::InvalidPolicy`] for an unknown `SCATTER_GPU` value.
    pub fn from_values(scatter_gpu: Option<&str>, ci: Option<&str>) -> Result<Self, ContextError> {
        match scatter_gpu.map(str::trim).filter(|v| !v.is_empty()) {
            Some(value) => match value.to_ascii_lowercase().as_str() {
                "required" => Ok(Self::Required),
                "auto" => Ok(Self::Auto),
                "off" => Ok(Self::Off),
                _ => Err(ContextError::InvalidPolicy {
                    value: value.to_owned(),
                }),
            },
            None if ci.is_some_and(|v| !v.trim().is_empty()) => Ok(Self::Required),
            None => Ok(Self::Auto),
        }
    }

    /// The policy's name as written in `SCATTER_GPU`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Required => "required",
            Self::Auto => "auto",
            Self::Off => "off",
        }
    }
}

impl fmt::Display for GpuPolicy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Failure to create a [`Context`].
#[derive(Debug, thiserror::Error)]
pub enum ContextError {
    /// `SCATTER_GPU` holds an unknown value.
    #[error("SCATTER_GPU={value:?} is invalid (allowed: required, auto, off)")]
    InvalidPolicy {
        /// The rejected value.
        value: String,
    },
    /// wgpu found no adapter on the enabled backends.
    #[error(
        "no GPU adapter found on backends {backends} (GL is not built in; for a software \
         adapter install lavapipe, Debian package mesa-vulkan-drivers, and set WGPU_BACKEND=vulkan)"
    )]
    NoAdapter {
        /// The backends that were searched.
        backends: String,
    },
    /// `WGPU_ADAPTER_NAME` matches none of the adapters found.
    #[error("WGPU_ADAPTER_NAME={wanted:?} matches no adapter (found: {found})")]
    NoMatchingAdapter {
        /// The requested name.
        wanted: String,
        /// The adapters that were found, comma separated.
        found: String,
    },
    /// The adapter refused to create a device.
    #[error("adapter {adapter:?} refused to create a device: {source}")]
    RequestDevice {
        /// The adapter's name.
        adapter: String,
        /// wgpu's error.
        #[source]
        source: wgpu::RequestDeviceError,
    },
}

/// Which adapter a [`Context`] runs on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterReport {
    /// Adapter name, e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`.
    pub name: String,
    /// Graphics API backend.
    pub backend: wgpu::Backend,
    /// Discrete, integrated, virtual, CPU or other.
    pub device_type: wgpu::DeviceType,
    /// Driver name.
    pub driver: String,
    /// Driver version and details.
    pub driver_info: String,
    /// Whether GPU timestamps (`TIMESTAMP_QUERY`) are enabled on the device.
    pub timestamps: bool,
}

impl AdapterReport {
    fn new(info: &wgpu::AdapterInfo, timestamps: bool) -> Self {
        Self {
            name: info.name.clone(),
            backend: info.backend,
            device_type: info.device_type,
            driver: info.driver.clone(),
            driver_info: info.driver_info.clone(),
            timestamps,
        }
    }

    /// True for a software adapter (lavapipe, WARP, SwiftShader): timings there say nothing
    /// about real GPUs.
    pub fn is_cpu(&self) -> bool {
        self.device_type == wgpu::DeviceType::Cpu
    }
}

impl fmt::Display for AdapterReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} ({:?}, {:?}, driver {} {}, timestamps {})",
            self.name,
            self.backend,
            self.device_type,
            self.driver,
            self.driver_info,
            if self.timestamps { "on" } else { "off" }
        )
    }
}

/// A wgpu device and queue on the chosen adapter.
#[derive(Debug)]
pub struct Context {
    adapter: wgpu::Adapter,
    device: wgpu::Device,
    queue: wgpu::Queue,
    report: AdapterReport,
}

impl Context {
    /// Creates a context on the best adapter, or fails.
    ///
    /// Backends come from `WGPU_BACKEND` when set (Vulkan, Metal and DX12 are built in);
    /// among the adapters found, discrete GPUs are preferred to integrated, virtual, other
    /// and finally CPU adapters. `WGPU_ADAPTER_NAME`, when set, keeps only adapters whose
    /// name contains it (case-insensitive). The device gets the adapter's limits and, where
    /// the adapter has them, `TIMESTAMP_QUERY` (+ inside encoders). No kernel needs an
    /// optional feature (the prefiltered bases are filtered by hand, so rgba32float needs no
    /// `FLOAT32_FILTERABLE`).
    ///
    /// # Errors
    ///
    /// [`ContextError`] when no adapter fits or the device cannot be created.
    pub fn new() -> Result<Self, ContextError> {
        let desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        // Only the backends both requested (WGPU_BACKEND) and built in can yield adapters.
        let backends = desc.backends & wgpu::Instance::enabled_backend_features();
        let instance = wgpu::Instance::new(desc);
        let adapters = pollster::block_on(instance.enumerate_adapters(backends));
        let infos: Vec<_> = adapters.iter().map(wgpu::Adapter::get_info).collect();
        let wanted = std::env::var("WGPU_ADAPTER_NAME")
            .ok()
            .filter(|w| !w.trim().is_empty());
        let chosen = adapters
            .into_iter()
            .zip(&infos)
            .filter(|(_, info)| {
                wanted
                    .as_deref()
                    .is_none_or(|w| info.name.to_lowercase().contains(&w.trim().to_lowercase()))
            })
            .min_by_key(|(_, info)| device_type_rank(info.device_type));
        let Some((adapter, info)) = chosen else {
            return Err(match wanted {
                Some(wanted) if !infos.is_empty() => ContextError::NoMatchingAdapter {
                    wanted,
                    found: infos
                        .iter()
                        .map(|i| format!("{} ({:?})", i.name, i.backend))
                        .collect::<Vec<_>>()
                        .join(", "),
                },
                _ => ContextError::NoAdapter {
                    backends: format!("{backends:?}"),
                },
            });
        };
        // Timestamps for the pass times; depth-clip control for an engine that rasterises
        // the projective rectified map on this device (the README's contract: depth
        // clamping on; `scatter_examples::raster`). Each only where the adapter has it.
        let wanted_features = wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
            | wgpu::Features::DEPTH_CLIP_CONTROL;
        let required_features = adapter.features() & wanted_features;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("scatter"),
            required_features,
            required_limits: adapter.limits(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|source| ContextError::RequestDevice {
            adapter: info.name.clone(),
            source,
        })?;
        let report = AdapterReport::new(
            info,
            required_features.contains(wgpu::Features::TIMESTAMP_QUERY),
        );
        tracing::info!(adapter = %report, "scatter: GPU context created");
        Ok(Self {
            adapter,
            device,
            queue,
            report,
        })
    }

    /// Wraps a device and queue that the engine created itself on `adapter`, with its own
    /// features and limits. Every pass checks its sizes against `device.limits()`, so a
    /// device created with lower limits than the adapter's gets errors naming those limits;
    /// GPU timestamps are recorded only when the device has `TIMESTAMP_QUERY`.
    pub fn from_device(adapter: wgpu::Adapter, device: wgpu::Device, queue: wgpu::Queue) -> Self {
        let report = AdapterReport::new(
            &adapter.get_info(),
            device.features().contains(wgpu::Features::TIMESTAMP_QUERY),
        );
        Self {
            adapter,
            device,
            queue,
            report,
        }
    }

    /// Creates a context as the `SCATTER_GPU` / `CI` policy says (see [`GpuPolicy`]).
    ///
    /// # Errors
    ///
    /// An invalid `SCATTER_GPU`, or no usable adapter under [`GpuPolicy::Required`].
    pub fn from_env() -> Result<Option<Self>, ContextError> {
        Self::with_policy(GpuPolicy::from_env()?)
    }

    /// Creates a context under an explicit policy: `Ok(None)` means "skip GPU work"; under
    /// [`GpuPolicy::Auto`] the reason is printed to stderr and logged.
    ///
    /// # Errors
    ///
    /// Under [`GpuPolicy::Required`], whatever [`Context::new`] fails with.
    pub fn with_policy(policy: GpuPolicy) -> Result<Option<Self>, ContextError> {
        match policy {
            GpuPolicy::Off => Ok(None),
            GpuPolicy::Required => Self::new().map(Some),
            GpuPolicy::Auto => match Self::new() {
                Ok(ctx) => Ok(Some(ctx)),
                Err(e) => {
                    eprintln!(
                        "scatter: SKIPPING GPU work: {e}. Set SCATTER_GPU=required to make this an \
                         error (it is whenever CI is set), or SCATTER_GPU=off to silence it."
                    );
                    tracing::warn!(error = %e, "scatter: no GPU context, GPU work skipped");
                    Ok(None)
                }
            },
        }
    }

    /// The chosen adapter.
    pub fn adapter(&self) -> &wgpu::Adapter {
        &self.adapter
    }

    /// The device.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The queue.
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// Which adapter this is.
    pub fn report(&self) -> &AdapterReport {
        &self.report
    }

    /// Whether passes can record GPU timestamps.
    pub fn has_timestamps(&self) -> bool {
        self.report.timestamps
    }
}

/// Preference order of device types: lower is better.
const fn device_type_rank(t: wgpu::DeviceType) -> u8 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn policy_from_values() {
        use GpuPolicy::*;
        let p = |gpu, ci| GpuPolicy::from_values(gpu, ci).expect("valid");
        assert_eq!(p(None, None), Auto);
        assert_eq!(p(None, Some("")), Auto);
        assert_eq!(p(None, Some("true")), Required);
        assert_eq!(p(Some(""), Some("1")), Required);
        assert_eq!(p(Some("auto"), Some("true")), Auto);
        assert_eq!(p(Some("off"), Some("true")), Off);
        assert_eq!(p(Some(" Required "), None), Required);
    }

    #[test]
    fn invalid_policy_names_the_variable() {
        let e = GpuPolicy::from_values(Some("maybe"), None).expect_err("invalid");
        let text = e.to_string();
        assert!(
            text.contains("SCATTER_GPU") && text.contains("maybe"),
            "{text}"
        );
    }

    #[test]
    fn off_never_touches_wgpu() {
        assert!(Context::with_policy(GpuPolicy::Off).expect("ok").is_none());
    }

    #[test]
    fn discrete_beats_cpu() {
        assert!(
            device_type_rank(wgpu::DeviceType::DiscreteGpu)
                < device_type_rank(wgpu::DeviceType::Cpu)
        );
    }
}
