//! [`ShaderError`]: everything that can go wrong between a kernel choice and a validated
//! module, always naming the kernel.

use crate::Kernel;

/// Failure to render, compose or validate a kernel.
#[derive(Debug, thiserror::Error)]
pub enum ShaderError {
    /// A template parameter is outside its allowed range.
    #[error("kernel `{kernel}`: {knob} = {value} is invalid (allowed: {allowed})")]
    InvalidParameter {
        /// The kernel being built.
        kernel: Kernel,
        /// Name of the parameter.
        knob: &'static str,
        /// The rejected value.
        value: String,
        /// The allowed range, in words.
        allowed: &'static str,
    },
    /// A prefiltered-family [`PrefilteredVariant`](crate::prefiltered::PrefilteredVariant) knob is outside its
    /// allowed range (the message names the knob, the value and the range).
    #[error("kernel `{kernel}`: invalid variant: {source}")]
    Variant {
        /// The kernel being built.
        kernel: Kernel,
        /// Which knob, its value and the allowed range.
        #[source]
        source: crate::prefiltered::VariantError,
    },
    /// askama failed to render the template.
    #[error("kernel `{kernel}`: rendering template `{template}` failed: {source}")]
    Render {
        /// The kernel being built.
        kernel: Kernel,
        /// Template path relative to `shaderlib/templates`.
        template: &'static str,
        /// askama's error.
        #[source]
        source: askama::Error,
    },
    /// naga_oil failed to add a shared module or to compose the kernel.
    #[error("kernel `{kernel}`: composing `{file}` with naga_oil failed:\n{message}")]
    Compose {
        /// The kernel being built.
        kernel: Kernel,
        /// The file (template or shared module) that failed.
        file: &'static str,
        /// naga_oil's report, with source excerpts.
        message: String,
    },
    /// naga's validator rejected the composed module.
    #[error("kernel `{kernel}`: naga validation failed: {message}")]
    Validate {
        /// The kernel being built.
        kernel: Kernel,
        /// The validation error and its causes.
        message: String,
    },
    /// naga's WGSL back-end failed.
    #[error("kernel `{kernel}`: writing WGSL failed: {source}")]
    WriteWgsl {
        /// The kernel being built.
        kernel: Kernel,
        /// naga's error.
        #[source]
        source: naga::back::wgsl::Error,
    },
    /// The composed module lacks the kernel's entry point.
    #[error("kernel `{kernel}`: the composed module has no entry point `{entry_point}`")]
    MissingEntryPoint {
        /// The kernel being built.
        kernel: Kernel,
        /// The entry point looked for.
        entry_point: &'static str,
    },
}
