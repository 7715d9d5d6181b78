//! [`GenError`]: everything that stops a generator run, each a readable sentence, and the
//! process exit code it maps to (2 for bad input, 1 for everything else).

use std::path::PathBuf;

/// Why a generator run failed.
#[derive(Debug, thiserror::Error)]
pub enum GenError {
    /// A knob outside its allowed range; the message is the variant's own (`bases must be a
    /// multiple of 4 in 4..=128, got 30`).
    #[error("{0}")]
    Knob(#[from] scatter_shaderlib::prefiltered::VariantError),
    /// Any other bad input on the command line (unknown family, target, knob name).
    #[error("{0}")]
    Usage(String),
    /// The `--config` file is unreadable or wrong.
    #[error("{path}: {message}")]
    Config {
        /// The config file.
        path: PathBuf,
        /// What is wrong, naming the variant table and the knob where it applies.
        message: String,
    },
    /// A kernel failed to render, compose or validate.
    #[error("variant {variant}: {source}")]
    Shader {
        /// The variant id.
        variant: String,
        /// shaderlib's error (names the kernel).
        #[source]
        source: scatter_shaderlib::ShaderError,
    },
    /// A naga back-end failed, or its output failed naga's validation.
    #[error("variant {variant}, kernel `{kernel}`, target {target}: {message}")]
    Backend {
        /// The variant id.
        variant: String,
        /// The kernel.
        kernel: &'static str,
        /// The target (`glsl`, `spirv`, ...).
        target: &'static str,
        /// What failed.
        message: String,
    },
    /// The family's resource and pass description disagrees with a kernel's bindings (a
    /// template changed without the generator).
    #[error("variant {variant}, kernel `{kernel}`: {message}")]
    Plan {
        /// The variant id.
        variant: String,
        /// The kernel.
        kernel: &'static str,
        /// The disagreement.
        message: String,
    },
    /// A struct cannot be written as a C or Rust layout.
    #[error("struct `{name}`: {message}")]
    Layout {
        /// The struct (demangled).
        name: String,
        /// Why.
        message: String,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// A file in the output directory was not written by scatter-gen.
    #[error(
        "refusing to overwrite {}: {why}; move it away or pass --force",
        path.display()
    )]
    Foreign {
        /// The file.
        path: PathBuf,
        /// Why it is not ours.
        why: String,
    },
}

impl GenError {
    /// The process exit code: 2 for bad input (knobs, command line, config file), 1 for
    /// everything else.
    pub fn exit_code(&self) -> i32 {
        match self {
            Self::Knob(_) | Self::Usage(_) | Self::Config { .. } => 2,
            Self::Shader { .. }
            | Self::Backend { .. }
            | Self::Plan { .. }
            | Self::Layout { .. }
            | Self::Io { .. }
            | Self::Foreign { .. } => 1,
        }
    }

    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
}

impl From<scatter_shaderlib::family::UnknownFamily> for GenError {
    fn from(e: scatter_shaderlib::family::UnknownFamily) -> Self {
        Self::Usage(e.to_string())
    }
}
