//! [`RuntimeError`]: failures of a pass (bad input sizes, device limits, wgpu errors),
//! always naming the kernel or the family; plus the helpers every pass shares to produce
//! them (limit checks, wgpu error scopes).

use scatter_shaderlib::prefiltered::{FrameError, VariantError};
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
    /// A `prefiltered` variant has a knob outside its range.
    #[error("prefiltered variant `{variant}`: {source}")]
    InvalidVariant {
        /// The variant's id.
        variant: String,
        /// Which knob, its value and the allowed range.
        #[source]
        source: VariantError,
    },
    /// The per-frame parameters cannot be set up (NaN or degenerate camera, light or
    /// medium, wrong light type, bad sizes).
    #[error("frame set-up failed: {0}")]
    Frame(#[from] FrameError),
    /// The shadow map of a frame differs in size from the one the pipelines were made for.
    #[error(
        "the shadow map is {actual}x{actual} texels but the pass was created for \
         {expected}x{expected}; create a new pass (`Prefiltered`, `Raymarch`) for the new size"
    )]
    ShadowMapSize {
        /// The size given at creation.
        expected: u32,
        /// The size of this frame's shadow map.
        actual: u32,
    },
    /// Too few rectified columns for the variant's prefix regions (the sun's regions split a
    /// row quadratically, so the first has `width / regions^2` columns).
    #[error(
        "kernel `{kernel}`: regions = {regions} with filtered_stride = {stride} needs a \
         rectified width of at least {min} columns (filtered_stride x regions^2, so that every \
         region has a stored column), got {width}"
    )]
    TooFewColumns {
        /// The kernel.
        kernel: Kernel,
        /// Regions of the variant.
        regions: u32,
        /// The variant's `filtered_stride`.
        stride: u32,
        /// Rectified width.
        width: u32,
        /// Smallest allowed width.
        min: u32,
    },
    /// A rectified width that the variant's `filtered_stride` does not divide.
    #[error(
        "kernel `{kernel}`: the rectified width must be a multiple of filtered_stride = \
         {stride} (prefilter stores one column in {stride}), got {width}"
    )]
    StrideMismatch {
        /// The kernel.
        kernel: Kernel,
        /// The variant's `filtered_stride`.
        stride: u32,
        /// Rectified width.
        width: u32,
    },
    /// A texture handed to a pass has the wrong format or size.
    #[error("kernel `{kernel}`: {what} must be {expected}, got {actual}")]
    InputMismatch {
        /// The kernel.
        kernel: Kernel,
        /// Which input property, e.g. `shadow map format`.
        what: &'static str,
        /// What the pass needs.
        expected: String,
        /// What was given.
        actual: String,
    },
    /// A cookie was given to a variant that does not read one.
    #[error(
        "variant {variant} reads no cookie: only a variant with cookie = true and light = \
         spot takes one"
    )]
    NoCookie {
        /// The variant's id.
        variant: String,
    },
    /// A raymarch-family variant knob is out of range.
    #[error("raymarch variant {variant}: {source}")]
    InvalidRaymarchVariant {
        /// The variant's id.
        variant: String,
        /// Which knob and why.
        #[source]
        source: VariantError,
    },
    /// A texture the frame's rectification needs was not given.
    #[error("kernel `{kernel}`: missing input: {what}")]
    MissingInput {
        /// The kernel that reads it.
        kernel: Kernel,
        /// What is missing and why it is needed.
        what: &'static str,
    },
    /// A pass was encoded before its per-frame parameters were uploaded.
    #[error("kernel `{kernel}`: encode called before prepare; upload a frame first")]
    NotPrepared {
        /// The first kernel of the family.
        kernel: Kernel,
    },
    /// A family's plan and its compiled kernels disagree (a binding the plan does not
    /// describe, a formula symbol with no value): a defect of the family, not of the input.
    #[error("kernel `{kernel}`: the plan and the kernel disagree: {message}")]
    Plan {
        /// The kernel.
        kernel: Kernel,
        /// What disagrees.
        message: String,
    },
}

/// Fails with [`RuntimeError::LimitExceeded`] when `value > max`.
pub(crate) fn check_limit(
    kernel: Kernel,
    what: &'static str,
    value: u64,
    limit: &'static str,
    max: u64,
) -> Result<(), RuntimeError> {
    if value > max {
        return Err(RuntimeError::LimitExceeded {
            kernel,
            what,
            value,
            limit,
            max,
        });
    }
    Ok(())
}

/// Validation and out-of-memory error scopes around a group of wgpu calls, turned into a
/// [`RuntimeError::Wgpu`] instead of wgpu's default panic.
pub(crate) struct ErrorScopes {
    validation: wgpu::ErrorScopeGuard,
    out_of_memory: wgpu::ErrorScopeGuard,
}

impl ErrorScopes {
    pub(crate) fn push(device: &wgpu::Device) -> Self {
        let out_of_memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
        Self {
            validation,
            out_of_memory,
        }
    }

    pub(crate) fn pop(self, kernel: Kernel, stage: &'static str) -> Result<(), RuntimeError> {
        let validation = pollster::block_on(self.validation.pop());
        let out_of_memory = pollster::block_on(self.out_of_memory.pop());
        match validation.or(out_of_memory) {
            None => Ok(()),
            Some(e) => Err(RuntimeError::Wgpu {
                kernel,
                stage,
                // wgpu's reports span several lines ("Validation Error", "Caused by:",
                // ...): one line, as every error of this crate.
                message: e
                    .to_string()
                    .lines()
                    .map(str::trim)
                    .filter(|l| !l.is_empty())
                    .collect::<Vec<_>>()
                    .join(" "),
            }),
        }
    }
}
