//! [`RuntimeError`]: failures of a pass (bad input sizes, device limits, wgpu errors),
//! always naming the kernel.

use scatter_shaderlib::{Kernel, ShaderError};

/// Failure to build, encode or run a pass.
#[derive(Debug, thiserror::Error)]
pub enum RuntimeError {
    /// The kernel could not be built.
    #[error(transparent)]
    Shader(#[from] ShaderError),
    /// An input has a zero dimension.
    #[error("kernel `{kernel}`: input size {size} is empty; every dimension must be at least 1")]
    EmptyInput {
        /// The kernel.
        kernel: Kernel,
        /// The size given, `width x height x layers`.
        size: String,
    },
    /// A size exceeds a device limit.
    #[error("kernel `{kernel}`: {what} = {value} exceeds the device limit {limit} = {max}")]
    LimitExceeded {
        /// The kernel.
        kernel: Kernel,
        /// What was too large, e.g. `width` or `workgroups along x`.
        what: &'static str,
        /// The requested value.
        value: u64,
        /// Name of the `wgpu::Limits` field.
        limit: &'static str,
        /// The device's value of that limit.
        max: u64,
    },
    /// The data does not match the declared size.
    #[error("kernel `{kernel}`: {size} needs {expected} texels but {actual} were given")]
    DataLength {
        /// The kernel.
        kernel: Kernel,
        /// The declared size.
        size: String,
        /// Texels the size needs.
        expected: u64,
        /// Texels given.
        actual: u64,
    },
    /// wgpu reported an error (validation, out of memory) inside an error scope.
    #[error("kernel `{kernel}`: wgpu error during {stage}: {message}")]
    Wgpu {
        /// The kernel.
        kernel: Kernel,
        /// What was being done.
        stage: &'static str,
        /// wgpu's message.
        message: String,
    },
    /// Waiting for the device failed.
    #[error("kernel `{kernel}`: waiting for the GPU failed: {source}")]
    Poll {
        /// The kernel.
        kernel: Kernel,
        /// wgpu's error.
        #[source]
        source: wgpu::PollError,
    },
    /// Mapping a readback buffer failed.
    #[error("kernel `{kernel}`: reading results back failed: {message}")]
    Readback {
        /// The kernel.
        kernel: Kernel,
        /// What went wrong.
        message: String,
    },
}
