//! Reflection of a validated kernel module: its bindings (group, binding, resource kind,
//! texture format, view dimension, sample type, access) and the byte layout of the structs
//! its buffers hold, all read from the naga IR and naga's layouter, never written twice by
//! hand.

use naga::proc::Layouter;
use naga::{
    AddressSpace, ArraySize, Handle, ImageClass, ImageDimension, Module, Scalar, ScalarKind,
    StorageAccess, StorageFormat, Type, TypeInner, VectorSize,
};
use serde::Serialize;

/// naga_oil's decoration around the encoded module path of an imported name.
const NAGA_OIL_PRE: &str = "X_naga_oil_mod_X";

/// A name without naga_oil's `X_naga_oil_mod_X<module>X` suffix.
pub fn demangle(name: &str) -> &str {
    name.find(NAGA_OIL_PRE).map_or(name, |i| &name[..i])
}

/// The WGSL module path naga_oil encoded into a mangled name (`scatter::prefiltered`).
pub fn mangled_module(name: &str) -> Option<String> {
    let start = name.find(NAGA_OIL_PRE)? + NAGA_OIL_PRE.len();
    let encoded = name[start..].strip_suffix('X')?;
    base32_decode(encoded).and_then(|b| String::from_utf8(b).ok())
}

/// RFC 4648 base32 without padding (naga_oil's encoding of module paths).
fn base32_decode(s: &str) -> Option<Vec<u8>> {
    let mut out = Vec::new();
    let (mut buffer, mut bits) = (0u64, 0u32);
    for c in s.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'2'..=b'7' => c - b'2' + 26,
            _ => return None,
        };
        buffer = (buffer << 5) | u64::from(v);
        bits += 5;
        if bits >= 8 {
            bits -= 8;
            out.push(((buffer >> bits) & 0xff) as u8);
        }
    }
    Some(out)
}

/// What kind of resource a binding is.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BindingKind {
    /// `var<uniform>`.
    UniformBuffer,
    /// `var<storage, ...>`.
    StorageBuffer,
    /// A sampled texture (`texture_2d<f32>`, ...).
    SampledTexture,
    /// A depth texture.
    DepthTexture,
    /// A storage texture.
    StorageTexture,
    /// A filtering or non-filtering sampler.
    Sampler,
    /// A comparison sampler.
    ComparisonSampler,
}

/// One binding of a kernel, read from the IR.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Binding {
    /// Bind group (descriptor set).
    pub group: u32,
    /// Binding number.
    pub binding: u32,
    /// The WGSL variable's name.
    pub name: String,
    /// The resource kind.
    pub kind: BindingKind,
    /// `read`, `write`, `read_write` (storage buffers and textures), `read` otherwise.
    pub access: &'static str,
    /// WGSL type, demangled (`Frame`, `array<vec4<f32>>`, `texture_2d<f32>`).
    #[serde(rename = "type")]
    pub ty: String,
    /// Buffers: smallest byte size that may be bound (the struct size, or one element of a
    /// runtime-sized array).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_binding_size: Option<u32>,
    /// Runtime-sized arrays: bytes per element.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub array_stride: Option<u32>,
    /// Textures: `2d`, `2d_array`, `cube`, `cube_array`, `3d`, `1d`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub view_dimension: Option<&'static str>,
    /// Sampled textures: `float`, `uint`, `sint`; depth textures: `depth`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sample_type: Option<&'static str>,
    /// Sampled textures: whether the kernel samples it through a sampler (so the format
    /// must be filterable with the family's linear samplers), or only loads texels.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub filterable: Option<bool>,
    /// Sampled textures: multisampled.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub multisampled: Option<bool>,
    /// Storage textures: WebGPU format name.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub format: Option<String>,
    /// The struct this buffer holds, demangled (see the manifest's `structs`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub struct_name: Option<String>,
}

/// One member of a struct.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Field {
    /// The member's name as the emitted shaders spell it.
    pub name: String,
    /// WGSL type, demangled.
    #[serde(rename = "type")]
    pub ty: String,
    /// Byte offset from the start of the struct.
    pub offset: u32,
    /// Byte size.
    pub size: u32,
    /// Byte alignment.
    pub alignment: u32,
    /// The field's shape for C and Rust.
    #[serde(skip)]
    pub shape: Shape,
}

/// The host-side shape of a field.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Shape {
    /// A scalar (`f32`, `u32`, `i32`).
    Scalar(&'static str),
    /// `count` scalars (a vector).
    Vector(&'static str, u32),
    /// `columns` columns of `rows` scalars, each column `column_stride` bytes.
    Matrix {
        /// Scalar.
        scalar: &'static str,
        /// Columns.
        columns: u32,
        /// Rows.
        rows: u32,
        /// Bytes per column.
        column_stride: u32,
    },
    /// A fixed-size array of `len` elements, `stride` bytes apart.
    Array {
        /// Element.
        element: Box<Shape>,
        /// Element size in bytes.
        element_size: u32,
        /// Elements.
        len: u32,
        /// Bytes per element.
        stride: u32,
    },
    /// A nested struct (demangled name).
    Struct(String),
    /// Anything C and Rust cannot express here (runtime arrays, bool).
    Unsupported(String),
}

/// A struct's layout.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct StructLayout {
    /// Demangled name, e.g. `Frame`.
    pub name: String,
    /// The name in the composed module (naga_oil-mangled when imported).
    pub mangled_name: String,
    /// The WGSL module that declares it (`scatter::prefiltered`), when imported.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub module: Option<String>,
    /// Byte size (the struct's span).
    pub size: u32,
    /// Byte alignment.
    pub alignment: u32,
    /// Members in order.
    pub fields: Vec<Field>,
}

/// Bindings and struct layouts of one kernel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Reflection {
    /// Bindings used by the entry point, sorted by group and binding.
    pub bindings: Vec<Binding>,
    /// Every struct a buffer binding holds, nested ones first, sorted by first use.
    pub structs: Vec<StructLayout>,
}

/// Reflects the bindings the entry point `entry` of a validated module uses.
///
/// # Errors
///
/// A readable message when naga's layouter fails or the entry point is missing.
pub fn reflect(
    module: &Module,
    info: &naga::valid::ModuleInfo,
    entry: &str,
) -> Result<Reflection, String> {
    let mut layouter = Layouter::default();
    layouter
        .update(module.to_ctx())
        .map_err(|e| format!("layout failed: {e}"))?;
    let index = module
        .entry_points
        .iter()
        .position(|ep| ep.name == entry)
        .ok_or_else(|| format!("no entry point `{entry}`"))?;
    let ep_info = info.get_entry_point(index);
    let sampled: Vec<Handle<naga::GlobalVariable>> =
        ep_info.sampling_set.iter().map(|key| key.image).collect();
    let cx = Cx {
        module,
        layouter: &layouter,
    };
    let mut bindings = Vec::new();
    let mut structs: Vec<StructLayout> = Vec::new();
    for (handle, var) in module.global_variables.iter() {
        let Some(rb) = &var.binding else { continue };
        if ep_info[handle].is_empty() {
            continue;
        }
        let inner = &module.types[var.ty].inner;
        let mut b = Binding {
            group: rb.group,
            binding: rb.binding,
            name: var.name.clone().unwrap_or_default(),
            kind: BindingKind::UniformBuffer,
            access: "read",
            ty: cx.type_name(var.ty),
            min_binding_size: None,
            array_stride: None,
            view_dimension: None,
            sample_type: None,
            filterable: None,
            multisampled: None,
            format: None,
            struct_name: None,
        };
        match var.space {
            AddressSpace::Uniform | AddressSpace::Storage { .. } => {
                if let AddressSpace::Storage { access } = var.space {
                    b.kind = BindingKind::StorageBuffer;
                    b.access = storage_access(access);
                }
                match inner {
                    TypeInner::Array {
                        base,
                        size: ArraySize::Dynamic,
                        stride,
                    } => {
                        b.array_stride = Some(*stride);
                        b.min_binding_size = Some(*stride);
                        cx.collect_structs(*base, &mut structs);
                    }
                    TypeInner::Array { stride, .. } => {
                        b.array_stride = Some(*stride);
                        b.min_binding_size = Some(layouter[var.ty].size);
                        cx.collect_structs(var.ty, &mut structs);
                    }
                    _ => {
                        b.min_binding_size = Some(layouter[var.ty].size);
                        cx.collect_structs(var.ty, &mut structs);
                    }
                }
                match inner {
                    TypeInner::Struct { .. } => {
                        b.struct_name = Some(demangle(&b.ty).to_owned());
                    }
                    // An array of structs (a slice table, VPL records): its element's.
                    TypeInner::Array { base, .. }
                        if matches!(module.types[*base].inner, TypeInner::Struct { .. }) =>
                    {
                        b.struct_name = Some(demangle(&cx.type_name(*base)).to_owned());
                    }
                    _ => {}
                }
            }
            AddressSpace::Handle => match inner {
                TypeInner::Image {
                    dim,
                    arrayed,
                    class,
                } => {
                    b.view_dimension = Some(view_dimension(*dim, *arrayed));
                    match class {
                        ImageClass::Sampled { kind, multi } => {
                            b.kind = BindingKind::SampledTexture;
                            b.sample_type = Some(match kind {
                                ScalarKind::Sint => "sint",
                                ScalarKind::Uint => "uint",
                                _ => "float",
                            });
                            b.multisampled = Some(*multi);
                            b.filterable = Some(sampled.contains(&handle));
                        }
                        ImageClass::Depth { multi } => {
                            b.kind = BindingKind::DepthTexture;
                            b.sample_type = Some("depth");
                            b.multisampled = Some(*multi);
                        }
                        ImageClass::Storage { format, access } => {
                            b.kind = BindingKind::StorageTexture;
                            b.access = storage_access(*access);
                            b.format = Some(format_name(*format));
                        }
                        ImageClass::External => {
                            b.kind = BindingKind::SampledTexture;
                        }
                    }
                }
                TypeInner::Sampler { comparison } => {
                    b.kind = if *comparison {
                        BindingKind::ComparisonSampler
                    } else {
                        BindingKind::Sampler
                    };
                }
                other => return Err(format!("unsupported handle type {other:?}")),
            },
            other => return Err(format!("unsupported address space {other:?}")),
        }
        bindings.push(b);
    }
    bindings.sort_by_key(|b| (b.group, b.binding));
    Ok(Reflection { bindings, structs })
}

fn storage_access(access: StorageAccess) -> &'static str {
    let load = access.contains(StorageAccess::LOAD);
    let store = access.contains(StorageAccess::STORE);
    match (load, store) {
        (true, true) => "read_write",
        (false, true) => "write",
        _ => "read",
    }
}

fn view_dimension(dim: ImageDimension, arrayed: bool) -> &'static str {
    match (dim, arrayed) {
        (ImageDimension::D1, _) => "1d",
        (ImageDimension::D2, false) => "2d",
        (ImageDimension::D2, true) => "2d_array",
        (ImageDimension::D3, _) => "3d",
        (ImageDimension::Cube, false) => "cube",
        (ImageDimension::Cube, true) => "cube_array",
    }
}

/// WebGPU name of a storage format (`rgba8unorm`).
pub fn format_name(format: StorageFormat) -> String {
    match format {
        StorageFormat::R32Float => "r32float".into(),
        StorageFormat::R32Uint => "r32uint".into(),
        StorageFormat::R32Sint => "r32sint".into(),
        StorageFormat::Rgba8Unorm => "rgba8unorm".into(),
        StorageFormat::Rgba16Float => "rgba16float".into(),
        StorageFormat::Rgba32Float => "rgba32float".into(),
        StorageFormat::Rgba32Uint => "rgba32uint".into(),
        StorageFormat::Rgba16Uint => "rgba16uint".into(),
        StorageFormat::Rg32Float => "rg32float".into(),
        other => format!("{other:?}").to_lowercase(),
    }
}

/// Vulkan and OpenGL names of a WebGPU texture format, for the manifest.
pub fn native_format(format: &str) -> Option<(&'static str, &'static str)> {
    Some(match format {
        "r32float" => ("VK_FORMAT_R32_SFLOAT", "GL_R32F"),
        "rgba8unorm" => ("VK_FORMAT_R8G8B8A8_UNORM", "GL_RGBA8"),
        "rgba16float" => ("VK_FORMAT_R16G16B16A16_SFLOAT", "GL_RGBA16F"),
        "rgba32float" => ("VK_FORMAT_R32G32B32A32_SFLOAT", "GL_RGBA32F"),
        _ => return None,
    })
}

struct Cx<'a> {
    module: &'a Module,
    layouter: &'a Layouter,
}

fn scalar_name(s: Scalar) -> &'static str {
    match (s.kind, s.width) {
        (ScalarKind::Float, 2) => "f16",
        (ScalarKind::Float, 8) => "f64",
        (ScalarKind::Float, _) => "f32",
        (ScalarKind::Uint, 8) => "u64",
        (ScalarKind::Uint, _) => "u32",
        (ScalarKind::Sint, 8) => "i64",
        (ScalarKind::Sint, _) => "i32",
        (ScalarKind::Bool, _) => "bool",
        (ScalarKind::AbstractInt, _) => "abstract-int",
        (ScalarKind::AbstractFloat, _) => "abstract-float",
    }
}

fn vector_len(size: VectorSize) -> u32 {
    size as u32
}

impl Cx<'_> {
    /// The WGSL spelling of a type, struct names demangled.
    fn type_name(&self, ty: Handle<Type>) -> String {
        let t = &self.module.types[ty];
        match &t.inner {
            TypeInner::Scalar(s) => scalar_name(*s).into(),
            TypeInner::Vector { size, scalar } => {
                format!("vec{}<{}>", vector_len(*size), scalar_name(*scalar))
            }
            TypeInner::Matrix {
                columns,
                rows,
                scalar,
            } => format!(
                "mat{}x{}<{}>",
                vector_len(*columns),
                vector_len(*rows),
                scalar_name(*scalar)
            ),
            TypeInner::Atomic(s) => format!("atomic<{}>", scalar_name(*s)),
            TypeInner::Array { base, size, .. } => match size {
                ArraySize::Constant(n) => format!("array<{}, {n}>", self.type_name(*base)),
                _ => format!("array<{}>", self.type_name(*base)),
            },
            TypeInner::Struct { .. } => demangle(t.name.as_deref().unwrap_or("?")).to_owned(),
            TypeInner::Image {
                dim,
                arrayed,
                class,
            } => {
                let d = view_dimension(*dim, *arrayed);
                match class {
                    ImageClass::Sampled { kind, multi } => format!(
                        "texture_{}{d}<{}>",
                        if *multi { "multisampled_" } else { "" },
                        match kind {
                            ScalarKind::Sint => "i32",
                            ScalarKind::Uint => "u32",
                            _ => "f32",
                        }
                    ),
                    ImageClass::Depth { .. } => format!("texture_depth_{d}"),
                    ImageClass::Storage { format, access } => format!(
                        "texture_storage_{d}<{}, {}>",
                        format_name(*format),
                        storage_access(*access)
                    ),
                    ImageClass::External => "texture_external".into(),
                }
            }
            TypeInner::Sampler { comparison } => {
                if *comparison {
                    "sampler_comparison".into()
                } else {
                    "sampler".into()
                }
            }
            other => format!("{other:?}"),
        }
    }

    fn shape(&self, ty: Handle<Type>) -> Shape {
        let t = &self.module.types[ty];
        match &t.inner {
            TypeInner::Scalar(s) if s.kind != ScalarKind::Bool => Shape::Scalar(scalar_name(*s)),
            // The host sees an atomic as its scalar (same size and alignment).
            TypeInner::Atomic(s) => Shape::Scalar(scalar_name(*s)),
            TypeInner::Vector { size, scalar } if scalar.kind != ScalarKind::Bool => {
                Shape::Vector(scalar_name(*scalar), vector_len(*size))
            }
            TypeInner::Matrix {
                columns,
                rows,
                scalar,
            } => Shape::Matrix {
                scalar: scalar_name(*scalar),
                columns: vector_len(*columns),
                rows: vector_len(*rows),
                column_stride: naga::proc::Alignment::from(*rows)
                    .round_up(vector_len(*rows) * u32::from(scalar.width)),
            },
            TypeInner::Array {
                base,
                size: ArraySize::Constant(n),
                stride,
            } => Shape::Array {
                element: Box::new(self.shape(*base)),
                element_size: self.layouter[*base].size,
                len: n.get(),
                stride: *stride,
            },
            TypeInner::Struct { .. } => {
                Shape::Struct(demangle(t.name.as_deref().unwrap_or("?")).to_owned())
            }
            _ => Shape::Unsupported(self.type_name(ty)),
        }
    }

    /// Adds the layout of every struct reachable from `ty` (nested ones first).
    fn collect_structs(&self, ty: Handle<Type>, out: &mut Vec<StructLayout>) {
        let t = &self.module.types[ty];
        match &t.inner {
            TypeInner::Array { base, .. } => self.collect_structs(*base, out),
            TypeInner::Struct { members, span } => {
                for m in members {
                    self.collect_structs(m.ty, out);
                }
                let mangled = t.name.clone().unwrap_or_default();
                if out.iter().any(|s| s.mangled_name == mangled) {
                    return;
                }
                let fields = members
                    .iter()
                    .map(|m| Field {
                        name: m.name.clone().unwrap_or_default(),
                        ty: self.type_name(m.ty),
                        offset: m.offset,
                        size: self.layouter[m.ty].size,
                        alignment: self.layouter[m.ty].alignment.round_up(1),
                        shape: self.shape(m.ty),
                    })
                    .collect();
                out.push(StructLayout {
                    name: demangle(&mangled).to_owned(),
                    module: mangled_module(&mangled),
                    mangled_name: mangled,
                    size: *span,
                    alignment: self.layouter[ty].alignment.round_up(1),
                    fields,
                });
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn demangles_naga_oil_names() {
        let name = "FrameX_naga_oil_mod_XONRWC5DUMVZDUOTQOJSWM2LMORSXEZLEX";
        assert_eq!(demangle(name), "Frame");
        assert_eq!(
            mangled_module(name).as_deref(),
            Some("scatter::prefiltered")
        );
        assert_eq!(demangle("eye"), "eye");
        assert_eq!(mangled_module("eye"), None);
    }
}
