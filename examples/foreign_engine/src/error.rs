//! [`EngineError`]: everything that can go wrong between reading a scatter-gen directory and
//! reading back the output, each with a message that names the file, the key or the
//! resource involved. Bad files never panic.

use std::path::PathBuf;

/// Why the foreign engine cannot load a shader directory or run a frame.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// A file could not be read or written.
    #[error("cannot access {}: {}", line(.path.display()), line(.source))]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The directory has no `manifest.json`.
    #[error(
        "no manifest.json in {d}: generate the shaders first (cargo run -p scatter-gen -- --out {d} --target spirv,wgsl)",
        d = line(.dir.display())
    )]
    MissingManifest {
        /// The shader directory.
        dir: PathBuf,
    },
    /// `manifest.json` is not valid JSON or lacks a key the engine needs.
    #[error("{} is not a manifest this engine can read: {}", line(.path.display()), line(.source))]
    ManifestParse {
        /// The manifest.
        path: PathBuf,
        /// serde's message (names the key and the line).
        #[source]
        source: serde_json::Error,
    },
    /// `manifest.json` was not written by scatter-gen.
    #[error("{} has schema {schema:?}, not \"scatter-gen-manifest\"", line(.path.display()))]
    ForeignManifest {
        /// The manifest.
        path: PathBuf,
        /// Its `schema` value.
        schema: String,
    },
    /// The manifest's schema version is not the one this engine reads.
    #[error(
        "{} has schema_version {found}; this engine reads version {supported}",
        line(.path.display())
    )]
    SchemaVersion {
        /// The manifest.
        path: PathBuf,
        /// Its `schema_version`.
        found: u64,
        /// The version this engine reads.
        supported: u64,
    },
    /// No variant of the manifest has the requested id.
    #[error("the manifest has no variant {id:?}; it has: {}", line(.available))]
    UnknownVariant {
        /// The requested id.
        id: String,
        /// The ids it has, comma-separated.
        available: String,
    },
    /// The manifest has several variants and none was named.
    #[error(
        "the manifest has several variants; name one with --variant: {}",
        line(.available)
    )]
    VariantRequired {
        /// The ids it has, comma-separated.
        available: String,
    },
    /// A pass has no file for the requested target.
    #[error(
        "kernel {} of variant {} was not generated for target {t} (re-run scatter-gen with --target {t})",
        line(.kernel),
        line(.variant),
        t = line(.target)
    )]
    TargetNotGenerated {
        /// The kernel.
        kernel: String,
        /// The variant id.
        variant: String,
        /// The target (`spirv`, `wgsl`).
        target: String,
    },
    /// A shader file the manifest lists is not in the directory.
    #[error(
        "{} is listed in the manifest but missing (re-run scatter-gen)",
        line(.path.display())
    )]
    MissingShader {
        /// The shader file.
        path: PathBuf,
    },
    /// A shader file's SHA-256 differs from the manifest's: the directory was edited or
    /// only partly regenerated.
    #[error(
        "{} is stale: sha256 {actual}, the manifest says {} (re-run scatter-gen on the whole directory)",
        line(.path.display()),
        line(.expected)
    )]
    StaleShader {
        /// The shader file.
        path: PathBuf,
        /// The manifest's hash.
        expected: String,
        /// The file's hash.
        actual: String,
    },
    /// A `.spv` file is not a SPIR-V module.
    #[error("{} is not SPIR-V: {}", line(.path.display()), line(.reason))]
    BadSpirv {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A WGSL file is not UTF-8.
    #[error("{} is not UTF-8 text", line(.path.display()))]
    BadWgsl {
        /// The file.
        path: PathBuf,
    },
    /// A formula names a symbol that is not a parameter of the variant.
    #[error(
        "formula {formula:?} ({}) uses {symbol:?}, which is not a parameter (known: {})",
        line(.context),
        line(.known)
    )]
    UnknownSymbol {
        /// The formula.
        formula: String,
        /// Where it appears.
        context: String,
        /// The unknown symbol.
        symbol: String,
        /// The parameters, comma-separated.
        known: String,
    },
    /// A formula does not parse or cannot be evaluated.
    #[error("formula {formula:?} ({}): {}", line(.context), line(.reason))]
    Formula {
        /// The formula.
        formula: String,
        /// Where it appears.
        context: String,
        /// What is wrong.
        reason: String,
    },
    /// A per-frame condition (`skip_when`, `alternative.when`) is not one the engine can
    /// evaluate.
    #[error("condition {condition:?} ({}): {}", line(.context), line(.reason))]
    Condition {
        /// The condition.
        condition: String,
        /// Where it appears.
        context: String,
        /// What is wrong.
        reason: String,
    },
    /// The manifest names a parameter this engine does not know how to set.
    #[error(
        "the manifest's parameter {name:?} is unknown to this engine (it sets: {}); is the manifest newer than the engine?",
        line(.known)
    )]
    UnknownParameter {
        /// The parameter.
        name: String,
        /// What the engine sets, comma-separated.
        known: String,
    },
    /// A size is outside its allowed range: a parameter's constraint from the manifest, or
    /// a device limit on a size a formula computed.
    #[error(
        "{} = {value} violates the constraint {constraint:?} ({})",
        line(.name),
        line(.reason)
    )]
    Constraint {
        /// The parameter.
        name: String,
        /// Its value.
        value: u64,
        /// The constraint (`lo..=hi`, `hi` possibly a device limit's name).
        constraint: String,
        /// Which bound failed.
        reason: String,
    },
    /// The manifest uses something this engine does not implement (a texture format, a
    /// binding kind, a sampler mode).
    #[error("{}: unsupported {what} {value:?}", line(.context))]
    Unsupported {
        /// Where it appears.
        context: String,
        /// What kind of thing (`texture format`, `binding kind`, ...).
        what: &'static str,
        /// Its value.
        value: String,
    },
    /// The manifest is internally inconsistent (a binding names an unknown resource, a
    /// struct is missing, ...).
    #[error("inconsistent manifest: {}", line(.0))]
    Inconsistent(String),
    /// A resource the frame needs was not supplied.
    #[error(
        "{} needs {resource:?} this frame ({}) but it was not supplied",
        line(.kernel),
        line(.contents)
    )]
    MissingInput {
        /// The kernel that binds it.
        kernel: String,
        /// The resource.
        resource: String,
        /// The manifest's description of its contents.
        contents: String,
    },
    /// Supplied data has the wrong length.
    #[error("{resource:?} needs {expected} {unit}, got {actual}")]
    InputLength {
        /// The resource.
        resource: String,
        /// Expected count.
        expected: u64,
        /// Supplied count.
        actual: u64,
        /// `bytes` or `texels`.
        unit: &'static str,
    },
    /// Data was supplied for a resource that cannot take it (unknown, or not written by the
    /// host).
    #[error("{resource:?} cannot be written by the host: {}", line(.reason))]
    NotAnInput {
        /// The resource.
        resource: String,
        /// Why.
        reason: String,
    },
    /// wgpu rejected something (validation or out of memory).
    #[error("wgpu error while {}: {}", line(.stage), line(.message))]
    Wgpu {
        /// What the engine was doing.
        stage: String,
        /// wgpu's message.
        message: String,
    },
    /// Reading back a texture failed.
    #[error("readback of {resource:?} failed: {}", line(.message))]
    Readback {
        /// The resource.
        resource: String,
        /// What failed.
        message: String,
    },
    /// No adapter or device (binary only).
    #[error("no GPU device: {}", line(.0))]
    NoDevice(String),
    /// The frame set-up rejected the camera, light, medium or shadow map.
    #[error("frame set-up: {0}")]
    Frame(#[from] scatter_frame::frame::FrameError),
    /// An input file of the binary is malformed.
    #[error("{}: {}", line(.path.display()), line(.reason))]
    InputFile {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

/// `text` on one printable line: each line break, with the blanks around it, becomes one
/// space and other control characters are written as Rust escapes. The messages quote
/// manifest text, file paths and wgpu's multi-line reports through it.
fn line(text: impl std::fmt::Display) -> String {
    let text = text.to_string();
    let joined = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    scatter_frame::variant::printable(&joined).into_owned()
}

impl EngineError {
    /// An [`EngineError::Io`] for `path`.
    pub fn io(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.into();
        move |source| Self::Io { path, source }
    }
}
