//! `manifest.json`: the schema (serde types) of what the generator tells an engine about
//! the files it wrote. Documented field by field in `generator/MANIFEST.md`; bump
//! [`SCHEMA_VERSION`] on any change that is not a pure addition.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::family::{Alternative, BufferDesc, Parameter, SamplerDesc, TextureDesc};
use crate::reflect::{Binding, StructLayout};

/// The value of [`Manifest::schema`]; also how the generator recognises its own manifests.
pub const SCHEMA: &str = "scatter-gen-manifest";
/// The schema version.
pub const SCHEMA_VERSION: u32 = 1;

/// The whole manifest.
#[derive(Clone, Debug, Serialize)]
pub struct Manifest {
    /// Always [`SCHEMA`].
    pub schema: &'static str,
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// `scatter-gen <version>`.
    pub generator: String,
    /// The targets emitted, in order.
    pub targets: Vec<TargetInfo>,
    /// Bounds-check policies every back-end used.
    pub bounds_checks: BTreeMap<&'static str, &'static str>,
    /// The host files with the uniform structs.
    pub host_files: HostFiles,
    /// Every struct a buffer binding holds, per family.
    pub structs: Vec<ManifestStruct>,
    /// The variants, sorted by family and id.
    pub variants: Vec<ManifestVariant>,
    /// Every file the generator wrote besides this manifest, sorted by path: the list of
    /// files it owns in the directory.
    pub files: Vec<FileEntry>,
}

/// One target.
#[derive(Clone, Debug, Serialize)]
pub struct TargetInfo {
    /// `wgsl`, `glsl`, `spirv`, `hlsl`, `msl`.
    pub name: &'static str,
    /// File extension.
    pub extension: &'static str,
    /// What it is and how bindings map.
    pub description: &'static str,
}

/// Names of the host files.
#[derive(Clone, Debug, Serialize)]
pub struct HostFiles {
    /// The C header.
    pub c_header: String,
    /// The Rust module.
    pub rust_module: String,
}

/// A struct layout with its host names.
#[derive(Clone, Debug, Serialize)]
pub struct ManifestStruct {
    /// The family whose kernels use it.
    pub family: &'static str,
    /// Name of the C typedef.
    pub c_type: String,
    /// Path of the Rust struct inside the module.
    pub rust_type: String,
    /// Name, offsets, sizes, alignment.
    #[serde(flatten)]
    pub layout: StructLayout,
}

/// One variant.
#[derive(Clone, Debug, Serialize)]
pub struct ManifestVariant {
    /// Family name.
    pub family: &'static str,
    /// PrefilteredVariant id (part of every file name).
    pub id: String,
    /// Knob values.
    pub knobs: Value,
    /// Symbols used by the size and dispatch formulas.
    pub parameters: Vec<Parameter>,
    /// Textures, buffers and samplers to create or provide.
    pub resources: Vec<ManifestResource>,
    /// The passes in the order they run.
    pub passes: Vec<ManifestPass>,
    /// What else the engine must do.
    pub notes: Vec<&'static str>,
}

/// A resource with its sizes resolved.
#[derive(Clone, Debug, Serialize)]
pub struct ManifestResource {
    /// Name the bindings refer to.
    pub name: &'static str,
    /// `texture`, `uniform_buffer`, `storage_buffer` or `sampler`.
    pub kind: &'static str,
    /// `engine` or `scatter`.
    pub provided_by: &'static str,
    /// What it holds.
    pub contents: &'static str,
    /// Texture allocation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub texture: Option<ManifestTexture>,
    /// Buffer allocation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub buffer: Option<ManifestBuffer>,
    /// Sampler state.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sampler: Option<SamplerDesc>,
    /// Passes that read it.
    pub read_by: Vec<&'static str>,
    /// Passes that write it.
    pub written_by: Vec<&'static str>,
}

/// A texture's allocation plus native format names.
#[derive(Clone, Debug, Serialize)]
pub struct ManifestTexture {
    /// Format, size, layers, usage.
    #[serde(flatten)]
    pub desc: TextureDesc,
    /// `VK_FORMAT_...`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vk_format: Option<&'static str>,
    /// OpenGL internal format.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gl_internal_format: Option<&'static str>,
}

/// A buffer's allocation with its byte size.
#[derive(Clone, Debug, Serialize)]
pub struct ManifestBuffer {
    /// Byte size (a formula).
    pub size_bytes: String,
    /// Elements and usage.
    #[serde(flatten)]
    pub desc: BufferDesc,
}

/// One pass (one kernel dispatch).
#[derive(Clone, Debug, Serialize)]
pub struct ManifestPass {
    /// Kernel name.
    pub kernel: &'static str,
    /// Entry point in WGSL and SPIR-V (per-target names in `files`).
    pub entry_point: &'static str,
    /// Workgroup size from the IR.
    pub workgroup_size: [u32; 3],
    /// Workgroups to dispatch along x, y, z.
    pub dispatch: Vec<DispatchDim>,
    /// A per-frame condition under which the pass does not run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skip_when: Option<&'static str>,
    /// Where the pass is dispatched indirectly: the buffer and byte offset of its three u32
    /// workgroup counts, written by an earlier pass (`dispatch` then gives the most they can
    /// be, for an engine that dispatches directly).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub indirect: Option<crate::family::Indirect>,
    /// Every binding the kernel uses.
    pub bindings: Vec<ManifestBinding>,
    /// The kernel's file per target.
    pub files: BTreeMap<&'static str, KernelFile>,
}

/// One dimension of a dispatch.
#[derive(Clone, Debug, Serialize)]
pub struct DispatchDim {
    /// Invocations needed (a formula).
    pub invocations: String,
    /// Workgroup size along this dimension.
    pub workgroup_size: u32,
    /// `ceil(invocations / workgroup_size)` as a formula (or a number).
    pub workgroups: String,
}

/// A binding with what is bound to it and where it lands in each target.
#[derive(Clone, Debug, Serialize)]
pub struct ManifestBinding {
    /// Group, binding, kind, format, access, ... from the IR.
    #[serde(flatten)]
    pub binding: Binding,
    /// The resource bound.
    pub resource: &'static str,
    /// Another resource bound under a per-frame condition.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alternative: Option<Alternative>,
    /// Textures: layers of the resource.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub array_layers: Option<String>,
    /// Per target: the binding in that language.
    pub targets: BTreeMap<&'static str, Value>,
}

/// One emitted kernel file.
#[derive(Clone, Debug, Serialize)]
pub struct KernelFile {
    /// Path relative to the manifest.
    pub path: String,
    /// Entry point name in this file.
    pub entry_point: String,
    /// sha256 of the file, lower-case hex.
    pub sha256: String,
    /// Target-wide binding facts (HLSL sampler heap, MSL sizes buffer).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bindings_extra: Option<Value>,
}

/// One file the generator owns.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct FileEntry {
    /// Path relative to the manifest, `/`-separated.
    pub path: String,
    /// sha256 of its bytes, lower-case hex.
    pub sha256: String,
    /// Its size.
    pub bytes: u64,
}

/// The part of an existing manifest the generator reads back: the files it owns.
#[derive(Clone, Debug, Deserialize)]
pub struct OwnedFiles {
    /// Must be [`SCHEMA`].
    pub schema: String,
    /// The files.
    pub files: Vec<FileEntry>,
}

/// sha256 of `bytes`, lower-case hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::Digest as _;
    sha2::Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}
