//! The engine's own reader of `manifest.json` (schema version 1, `generator/MANIFEST.md`):
//! serde structs for the keys an engine needs to allocate, bind and dispatch, nothing from
//! the generator's crate. Unknown keys are ignored (the schema may grow within a version);
//! a missing key the engine needs is a parse error naming it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::EngineError;

/// The `schema` value of a scatter-gen manifest.
pub const SCHEMA: &str = "scatter-gen-manifest";
/// The schema version this engine reads.
pub const SCHEMA_VERSION: u64 = 1;
/// The manifest's file name in a shader directory.
pub const MANIFEST_FILE: &str = "manifest.json";

/// `manifest.json`.
#[derive(Clone, Debug, Deserialize)]
pub struct Manifest {
    /// Always [`SCHEMA`].
    pub schema: String,
    /// [`SCHEMA_VERSION`].
    pub schema_version: u64,
    /// `scatter-gen <version>`.
    #[serde(default)]
    pub generator: String,
    /// Every struct a buffer binding holds.
    pub structs: Vec<StructLayout>,
    /// One entry per variant.
    pub variants: Vec<VariantEntry>,
    /// Every file scatter-gen wrote besides the manifest.
    pub files: Vec<FileEntry>,
}

/// `structs[]`: a struct's layout.
#[derive(Clone, Debug, Deserialize)]
pub struct StructLayout {
    /// Family whose kernels use it.
    pub family: String,
    /// WGSL name (`Frame`).
    pub name: String,
    /// Size in bytes.
    pub size: u64,
    /// Fields in declaration order.
    pub fields: Vec<FieldLayout>,
}

/// `structs[].fields[]`.
#[derive(Clone, Debug, Deserialize)]
pub struct FieldLayout {
    /// Shader spelling (`e1_`, `anti_epipole`).
    pub name: String,
    /// WGSL type (`vec4<f32>`).
    #[serde(rename = "type")]
    pub ty: String,
    /// Byte offset.
    pub offset: u64,
    /// Byte size.
    pub size: u64,
}

/// `files[]`.
#[derive(Clone, Debug, Deserialize)]
pub struct FileEntry {
    /// Path relative to the directory.
    pub path: String,
    /// SHA-256, lower-case hex.
    pub sha256: String,
    /// Size in bytes.
    pub bytes: u64,
}

/// `variants[]`.
#[derive(Clone, Debug, Deserialize)]
pub struct VariantEntry {
    /// Family (`prefiltered`).
    pub family: String,
    /// PrefilteredVariant id (part of every file name).
    pub id: String,
    /// The knob values (family-specific object).
    #[serde(default)]
    pub knobs: serde_json::Value,
    /// The symbols formulas use.
    pub parameters: Vec<Parameter>,
    /// Textures, buffers and samplers.
    pub resources: Vec<Resource>,
    /// Kernels in the order they run.
    pub passes: Vec<Pass>,
}

/// `variants[].parameters[]`.
#[derive(Clone, Debug, Deserialize)]
pub struct Parameter {
    /// `screen.width`, ...
    pub name: String,
    /// Allowed range, `lo..=hi` (optionally after `<expression> = `).
    #[serde(default)]
    pub constraint: String,
}

/// `variants[].resources[]`.
#[derive(Clone, Debug, Deserialize)]
pub struct Resource {
    /// What bindings refer to.
    pub name: String,
    /// `texture`, `uniform_buffer`, `storage_buffer`, `sampler`.
    pub kind: String,
    /// `engine` or `scatter`.
    pub provided_by: String,
    /// What it holds.
    #[serde(default)]
    pub contents: String,
    /// Texture description.
    pub texture: Option<TextureDesc>,
    /// Buffer description.
    pub buffer: Option<BufferDesc>,
    /// Sampler description.
    pub sampler: Option<SamplerDesc>,
}

impl Resource {
    /// Whether the engine (not scatter) provides it: its depth buffer, shadow map, ...
    pub fn engine_provided(&self) -> bool {
        self.provided_by == "engine"
    }
}

/// `resources[].texture`.
#[derive(Clone, Debug, Deserialize)]
pub struct TextureDesc {
    /// WebGPU format name.
    pub format: String,
    /// `2d`.
    pub dimension: String,
    /// Formula.
    pub width: String,
    /// Formula.
    pub height: String,
    /// Formula.
    pub layers: String,
    /// Mip levels.
    pub mip_levels: u32,
    /// `texture_binding`, `storage_binding`.
    pub usage: Vec<String>,
}

/// `resources[].buffer`.
#[derive(Clone, Debug, Deserialize)]
pub struct BufferDesc {
    /// Formula.
    pub size_bytes: String,
    /// `uniform`, `storage`, `copy_dst`.
    pub usage: Vec<String>,
}

/// `resources[].sampler`.
#[derive(Clone, Debug, Deserialize)]
pub struct SamplerDesc {
    /// `linear` or `nearest`.
    pub mag_filter: String,
    /// `linear` or `nearest`.
    pub min_filter: String,
    /// `linear` or `nearest`.
    pub mipmap_filter: String,
    /// `clamp_to_edge`, `repeat`, `mirror_repeat`.
    pub address_mode_u: String,
    /// As `u`.
    pub address_mode_v: String,
    /// As `u`.
    pub address_mode_w: String,
}

/// `variants[].passes[]`.
#[derive(Clone, Debug, Deserialize)]
pub struct Pass {
    /// Kernel name.
    pub kernel: String,
    /// WGSL / SPIR-V entry point (per-target names in `files`).
    pub entry_point: String,
    /// From the IR.
    pub workgroup_size: [u32; 3],
    /// Per dimension.
    pub dispatch: Vec<Dispatch>,
    /// Per-frame condition under which the pass does not run.
    #[serde(default)]
    pub skip_when: Option<String>,
    /// Where the pass is dispatched indirectly (`dispatch` then gives the most).
    #[serde(default)]
    pub indirect: Option<Indirect>,
    /// Every binding the kernel uses.
    pub bindings: Vec<Binding>,
    /// Per target.
    pub files: BTreeMap<String, PassFile>,
}

/// `passes[].indirect`: three u32 workgroup counts an earlier pass wrote.
#[derive(Clone, Debug, Deserialize)]
pub struct Indirect {
    /// The buffer resource.
    pub buffer: String,
    /// Their byte offset in it.
    pub offset_bytes: u64,
}

/// `passes[].dispatch[]`.
#[derive(Clone, Debug, Deserialize)]
pub struct Dispatch {
    /// Formula: workgroups to dispatch along this dimension.
    pub workgroups: String,
}

/// `passes[].files.<target>`.
#[derive(Clone, Debug, Deserialize)]
pub struct PassFile {
    /// Path relative to the directory.
    pub path: String,
    /// Entry point in that file.
    pub entry_point: String,
    /// SHA-256 of the file.
    pub sha256: String,
}

/// `passes[].bindings[]`.
#[derive(Clone, Debug, Deserialize)]
pub struct Binding {
    /// `@group` / descriptor set.
    pub group: u32,
    /// `@binding`.
    pub binding: u32,
    /// The WGSL variable.
    #[serde(default)]
    pub name: String,
    /// `uniform_buffer`, `storage_buffer`, `sampled_texture`, `depth_texture`,
    /// `storage_texture`, `sampler`, `comparison_sampler`.
    pub kind: String,
    /// `read`, `write`, `read_write`.
    pub access: String,
    /// Buffers.
    #[serde(default)]
    pub min_binding_size: Option<u64>,
    /// Uniform buffers holding a struct.
    #[serde(default)]
    pub struct_name: Option<String>,
    /// Textures: `2d`, `2d_array`, ...
    #[serde(default)]
    pub view_dimension: Option<String>,
    /// Sampled textures: `float`, `sint`, `uint`, `depth`.
    #[serde(default)]
    pub sample_type: Option<String>,
    /// Sampled textures.
    #[serde(default)]
    pub multisampled: Option<bool>,
    /// Sampled textures: sampled through a sampler (needs a filterable format).
    #[serde(default)]
    pub filterable: Option<bool>,
    /// Storage textures.
    #[serde(default)]
    pub format: Option<String>,
    /// The resource bound.
    pub resource: String,
    /// Bind another resource when a per-frame condition holds.
    #[serde(default)]
    pub alternative: Option<Alternative>,
}

/// `bindings[].alternative`.
#[derive(Clone, Debug, Deserialize)]
pub struct Alternative {
    /// The resource bound instead.
    pub resource: String,
    /// The condition.
    pub when: String,
}

impl Manifest {
    /// Reads and checks `dir/manifest.json`.
    ///
    /// # Errors
    ///
    /// [`EngineError::MissingManifest`], [`EngineError::Io`],
    /// [`EngineError::ManifestParse`], [`EngineError::ForeignManifest`],
    /// [`EngineError::SchemaVersion`].
    pub fn load(dir: &Path) -> Result<Self, EngineError> {
        let path = dir.join(MANIFEST_FILE);
        let bytes = match std::fs::read(&path) {
            Ok(bytes) => bytes,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Err(EngineError::MissingManifest {
                    dir: dir.to_path_buf(),
                });
            }
            Err(source) => return Err(EngineError::Io { path, source }),
        };
        Self::parse(&bytes, &path)
    }

    /// Parses manifest bytes (`path` is for messages).
    ///
    /// # Errors
    ///
    /// As [`Self::load`], minus the I/O errors.
    pub fn parse(bytes: &[u8], path: &Path) -> Result<Self, EngineError> {
        // Check the header first, so a foreign file gets that message rather than a
        // complaint about some missing key.
        #[derive(Deserialize)]
        struct Header {
            schema: Option<String>,
            schema_version: Option<u64>,
        }
        let header: Header =
            serde_json::from_slice(bytes).map_err(|source| EngineError::ManifestParse {
                path: path.to_path_buf(),
                source,
            })?;
        let schema = header.schema.unwrap_or_default();
        if schema != SCHEMA {
            return Err(EngineError::ForeignManifest {
                path: path.to_path_buf(),
                schema,
            });
        }
        let found = header.schema_version.unwrap_or(0);
        if found != SCHEMA_VERSION {
            return Err(EngineError::SchemaVersion {
                path: path.to_path_buf(),
                found,
                supported: SCHEMA_VERSION,
            });
        }
        serde_json::from_slice(bytes).map_err(|source| EngineError::ManifestParse {
            path: PathBuf::from(path),
            source,
        })
    }

    /// The variant with id `id`.
    ///
    /// # Errors
    ///
    /// [`EngineError::UnknownVariant`] listing the ids the manifest has.
    pub fn variant(&self, id: &str) -> Result<&VariantEntry, EngineError> {
        self.variants
            .iter()
            .find(|v| v.id == id)
            .ok_or_else(|| EngineError::UnknownVariant {
                id: id.to_owned(),
                available: self
                    .variants
                    .iter()
                    .map(|v| v.id.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }

    /// The layout of struct `name` of `family`.
    pub fn struct_layout(&self, family: &str, name: &str) -> Option<&StructLayout> {
        self.structs
            .iter()
            .find(|s| s.family == family && s.name == name)
    }
}

impl VariantEntry {
    /// The resource called `name`.
    pub fn resource(&self, name: &str) -> Option<&Resource> {
        self.resources.iter().find(|r| r.name == name)
    }
}
