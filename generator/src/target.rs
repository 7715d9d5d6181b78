//! The back-ends: one validated kernel module in, the bytes of one target out, with every
//! option set explicitly (so debug and release builds emit the same bytes) and the binding
//! each resource gets in that target, for the manifest.
//!
//! | target | file | naga back-end and options |
//! |---|---|---|
//! | `wgsl` | `.wgsl` | shaderlib's WGSL (naga's WGSL writer), re-parsed and re-validated by naga |
//! | `glsl` | `.comp` | GLSL 450 core (OpenGL flavour: `layout(binding = N)` from an explicit binding map, no `set`) |
//! | `spirv` | `.spv` | SPIR-V 1.0, no debug names, descriptor set = group, binding = binding |
//! | `hlsl` | `.hlsl` | shader model 5.1, register = binding, space = group; samplers through naga's sampler heap |
//! | `msl` | `.metal` | MSL 2.0, buffer / texture / sampler indices in binding order, a sizes buffer for runtime arrays |
//!
//! Every back-end runs on the module after `process_overrides` (which naga re-validates);
//! bounds checks are wgpu's for a device without robust buffer or image access: `Restrict`
//! for indices, buffers and image loads.

use std::collections::BTreeMap;
use std::fmt;

use naga::back::{glsl, hlsl, msl, spv};
use naga::proc::{BoundsCheckPolicies, BoundsCheckPolicy};
use naga::valid::{ModuleInfo, ValidationFlags, Validator};
use naga::{Module, ResourceBinding, ShaderStage};
use serde_json::{Value, json};

use crate::GenError;
use crate::reflect::{Binding, BindingKind};

/// An output language.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Target {
    /// WGSL (`.wgsl`).
    Wgsl,
    /// GLSL 450 core, OpenGL flavour (`.comp`).
    Glsl,
    /// SPIR-V 1.0 binary (`.spv`).
    Spirv,
    /// HLSL, shader model 5.1 (`.hlsl`).
    Hlsl,
    /// Metal Shading Language 2.0 (`.metal`).
    Msl,
}

impl Target {
    /// Every target, in manifest order.
    pub const ALL: &'static [Target] = &[
        Target::Wgsl,
        Target::Glsl,
        Target::Spirv,
        Target::Hlsl,
        Target::Msl,
    ];

    /// The targets emitted when `--target` is not given.
    pub const DEFAULT: &'static [Target] = &[Target::Wgsl, Target::Glsl, Target::Spirv];

    /// The target's name (`--target`).
    pub const fn name(self) -> &'static str {
        match self {
            Self::Wgsl => "wgsl",
            Self::Glsl => "glsl",
            Self::Spirv => "spirv",
            Self::Hlsl => "hlsl",
            Self::Msl => "msl",
        }
    }

    /// File extension without the dot.
    pub const fn extension(self) -> &'static str {
        match self {
            Self::Wgsl => "wgsl",
            Self::Glsl => "comp",
            Self::Spirv => "spv",
            Self::Hlsl => "hlsl",
            Self::Msl => "metal",
        }
    }

    /// One line for `list` and the manifest.
    pub const fn description(self) -> &'static str {
        match self {
            Self::Wgsl => "WGSL (WebGPU)",
            Self::Glsl => {
                "GLSL 450 core, OpenGL flavour: layout(binding) from the manifest's binding map, no set"
            }
            Self::Spirv => "SPIR-V 1.0 for Vulkan: descriptor set = group, binding = binding",
            Self::Hlsl => {
                "HLSL shader model 5.1: register = binding, space = group, samplers through naga's sampler heap"
            }
            Self::Msl => {
                "Metal Shading Language 2.0: buffer, texture and sampler indices from the manifest"
            }
        }
    }

    /// Parses a comma-separated list (or several), sorted in [`Target::ALL`] order.
    ///
    /// # Errors
    ///
    /// [`GenError::Usage`] naming the unknown target and the allowed ones, or the target
    /// named twice (`wgsl,wgsl` is a slip, not a request).
    pub fn parse_list<S: AsRef<str>>(names: &[S]) -> Result<Vec<Target>, GenError> {
        let mut out = Vec::new();
        for name in names {
            for part in name.as_ref().split(',') {
                let part = part.trim();
                let t = Self::ALL
                    .iter()
                    .copied()
                    .find(|t| t.name() == part)
                    .ok_or_else(|| {
                        let all: Vec<_> = Self::ALL.iter().map(|t| t.name()).collect();
                        GenError::Usage(format!(
                            "target must be {}, got {}",
                            all.join(" | "),
                            scatter_shaderlib::prefiltered::variant::printable(part)
                        ))
                    })?;
                if out.contains(&t) {
                    return Err(GenError::Usage(format!(
                        "target {t} is named twice: name each target once"
                    )));
                }
                out.push(t);
            }
        }
        out.sort();
        Ok(out)
    }
}

impl fmt::Display for Target {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One emitted file and what the manifest says about it.
#[derive(Clone, Debug)]
pub struct Output {
    /// The file's bytes.
    pub bytes: Vec<u8>,
    /// The entry point's name in this target (`main` in GLSL).
    pub entry_point: String,
    /// Per binding `(group, binding)`: where the resource goes in this target.
    pub bindings: BTreeMap<(u32, u32), Value>,
    /// Target-wide binding facts (HLSL sampler heap, MSL sizes buffer).
    pub extra: Option<Value>,
}

/// A kernel ready for the back-ends.
pub struct Input<'a> {
    /// The validated module, overrides processed.
    pub module: &'a Module,
    /// Its validation info.
    pub info: &'a ModuleInfo,
    /// shaderlib's WGSL text of the module.
    pub wgsl: &'a str,
    /// The compute entry point.
    pub entry_point: &'a str,
    /// The reflected bindings.
    pub bindings: &'a [Binding],
    /// Comment lines (without comment markers) put at the top of text outputs.
    pub banner: &'a [String],
}

/// Bounds-check policies for every back-end: wgpu's on a device without robust access.
pub const BOUNDS_CHECKS: BoundsCheckPolicies = BoundsCheckPolicies {
    index: BoundsCheckPolicy::Restrict,
    buffer: BoundsCheckPolicy::Restrict,
    image_load: BoundsCheckPolicy::Restrict,
    binding_array: BoundsCheckPolicy::Unchecked,
};

fn comment(banner: &[String], prefix: &str) -> String {
    banner.iter().map(|l| format!("{prefix}{l}\n")).collect()
}

/// Validates a module with every check naga has, errors as one line.
///
/// # Errors
///
/// naga's validation error and its causes.
pub fn validate(module: &Module) -> Result<ModuleInfo, String> {
    Validator::new(ValidationFlags::all(), scatter_shaderlib::capabilities())
        .validate(module)
        .map_err(|e| {
            let mut message = e.as_inner().to_string();
            let mut cause = std::error::Error::source(e.as_inner());
            while let Some(c) = cause {
                message.push_str(": ");
                message.push_str(&c.to_string());
                cause = c.source();
            }
            message
        })
}

/// Emits one target.
///
/// # Errors
///
/// The back-end's error, or naga's validation error of re-parsed WGSL, as one message.
pub fn emit(target: Target, input: &Input<'_>) -> Result<Output, String> {
    match target {
        Target::Wgsl => wgsl(input),
        Target::Glsl => glsl(input),
        Target::Spirv => spirv(input),
        Target::Hlsl => hlsl(input),
        Target::Msl => msl(input),
    }
}

fn wgsl(input: &Input<'_>) -> Result<Output, String> {
    let text = format!("{}{}", comment(input.banner, "// "), input.wgsl);
    let reparsed = naga::front::wgsl::parse_str(&text)
        .map_err(|e| format!("emitted WGSL does not parse: {}", e.emit_to_string(&text)))?;
    validate(&reparsed).map_err(|e| format!("emitted WGSL does not validate: {e}"))?;
    if !reparsed
        .entry_points
        .iter()
        .any(|ep| ep.name == input.entry_point)
    {
        return Err(format!(
            "emitted WGSL lacks entry point `{}`",
            input.entry_point
        ));
    }
    let bindings = input
        .bindings
        .iter()
        .map(|b| {
            (
                (b.group, b.binding),
                json!({ "group": b.group, "binding": b.binding }),
            )
        })
        .collect();
    Ok(Output {
        bytes: text.into_bytes(),
        entry_point: input.entry_point.to_owned(),
        bindings,
        extra: None,
    })
}

/// The GLSL binding number of a WGSL binding: the binding itself in group 0, `16 * group +
/// binding` in later groups.
pub fn glsl_binding(group: u32, binding: u32) -> Result<u8, String> {
    let n = if group == 0 {
        binding
    } else {
        16 * group + binding
    };
    if group > 0 && binding >= 16 {
        return Err(format!(
            "binding {binding} of group {group} does not fit the GLSL binding map (16 per group)"
        ));
    }
    u8::try_from(n).map_err(|_| format!("GLSL binding {n} (group {group}) exceeds 255"))
}

fn global_of(module: &Module, b: &Binding) -> Option<naga::Handle<naga::GlobalVariable>> {
    module.global_variables.iter().find_map(|(h, v)| {
        v.binding
            .as_ref()
            .filter(|rb| rb.group == b.group && rb.binding == b.binding)
            .map(|_| h)
    })
}

fn glsl(input: &Input<'_>) -> Result<Output, String> {
    let mut binding_map = glsl::BindingMap::default();
    for b in input.bindings {
        binding_map.insert(
            ResourceBinding {
                group: b.group,
                binding: b.binding,
            },
            glsl_binding(b.group, b.binding)?,
        );
    }
    let options = glsl::Options {
        version: glsl::Version::Desktop(450),
        writer_flags: glsl::WriterFlags::empty(),
        binding_map,
        zero_initialize_workgroup_memory: true,
    };
    let pipeline = glsl::PipelineOptions {
        shader_stage: ShaderStage::Compute,
        entry_point: input.entry_point.to_owned(),
        multiview: None,
    };
    let mut body = String::new();
    let reflection = glsl::Writer::new(
        &mut body,
        input.module,
        input.info,
        &options,
        &pipeline,
        BOUNDS_CHECKS,
    )
    .and_then(|mut w| w.write())
    .map_err(|e| e.to_string())?;
    // `#version` must come first; the banner follows it.
    let (version, rest) = body.split_once('\n').unwrap_or((body.as_str(), ""));
    let text = format!("{version}\n{}{rest}", comment(input.banner, "// "));

    let mut bindings = BTreeMap::new();
    for b in input.bindings {
        let handle = global_of(input.module, b);
        let unit = glsl_binding(b.group, b.binding)?;
        let mut entry = serde_json::Map::new();
        match b.kind {
            BindingKind::Sampler | BindingKind::ComparisonSampler => {
                // GLSL has no separate samplers: naga folds each into the texture it samples.
                let textures: Vec<_> = reflection
                    .texture_mapping
                    .iter()
                    .filter(|(_, m)| m.sampler.is_some() && m.sampler == handle)
                    .filter_map(|(_, m)| {
                        input
                            .bindings
                            .iter()
                            .find(|t| global_of(input.module, t) == Some(m.texture))
                    })
                    .map(|t| json!(glsl_binding(t.group, t.binding).unwrap_or(0)))
                    .collect();
                entry.insert("binding".into(), Value::Null);
                entry.insert(
                    "combined_into_texture_binding".into(),
                    Value::Array(textures),
                );
            }
            _ => {
                entry.insert("binding".into(), json!(unit));
                let namespace = match b.kind {
                    BindingKind::UniformBuffer => "uniform block (std140)",
                    BindingKind::StorageBuffer => "shader storage block (std430)",
                    BindingKind::StorageTexture => "image unit",
                    _ => "texture unit",
                };
                entry.insert("namespace".into(), json!(namespace));
                let mut names: Vec<_> = reflection
                    .texture_mapping
                    .iter()
                    .filter(|(_, m)| Some(m.texture) == handle)
                    .collect();
                names.sort_by(|a, b| a.0.cmp(b.0));
                if let Some((name, m)) = names.first() {
                    entry.insert("name".into(), json!(name));
                    let sampler = m.sampler.and_then(|s| {
                        input
                            .bindings
                            .iter()
                            .find(|t| global_of(input.module, t) == Some(s))
                    });
                    if let Some(sb) = sampler {
                        entry.insert(
                            "combined_with_sampler".into(),
                            json!({ "group": sb.group, "binding": sb.binding }),
                        );
                    }
                } else if let Some(name) = handle.and_then(|h| reflection.uniforms.get(&h)) {
                    entry.insert("name".into(), json!(name));
                }
            }
        }
        bindings.insert((b.group, b.binding), Value::Object(entry));
    }
    Ok(Output {
        bytes: text.into_bytes(),
        entry_point: "main".into(),
        bindings,
        extra: None,
    })
}

fn spirv(input: &Input<'_>) -> Result<Output, String> {
    let mut binding_map = spv::BindingMap::default();
    for b in input.bindings {
        binding_map.insert(
            ResourceBinding {
                group: b.group,
                binding: b.binding,
            },
            spv::BindingInfo {
                descriptor_set: b.group,
                binding: b.binding,
                binding_array_size: None,
            },
        );
    }
    let options = spv::Options {
        lang_version: (1, 0),
        // No DEBUG: naga adds it in debug builds only, which would make debug and release
        // output differ. The other flags only touch vertex and fragment stages.
        flags: spv::WriterFlags::empty(),
        fake_missing_bindings: false,
        binding_map,
        capabilities: None,
        bounds_check_policies: BOUNDS_CHECKS,
        zero_initialize_workgroup_memory: spv::ZeroInitializeWorkgroupMemoryMode::Polyfill,
        force_loop_bounding: true,
        ray_query_initialization_tracking: true,
        trace_ray_argument_validation: true,
        use_storage_input_output_16: true,
        debug_info: None,
        task_dispatch_limits: None,
        mesh_shader_primitive_indices_clamp: true,
        emit_int_div_checks: true,
    };
    let pipeline = spv::PipelineOptions {
        shader_stage: ShaderStage::Compute,
        entry_point: input.entry_point.to_owned(),
    };
    let words = spv::write_vec(input.module, input.info, &options, Some(&pipeline))
        .map_err(|e| e.to_string())?;
    // naga builds the `Restrict` clamp of unsigned texel coordinates from signed constants:
    // retype them, or SPIR-V consumers (naga's own front-end, the Vulkan validation layers)
    // reject the module.
    let (words, _) = crate::spirv_fixup::fix_constant_composite_signedness(&words)?;
    // naga's SPIR-V front-end reads an arrayed image's size without its layer count: give
    // the clamp of `texture_2d_array` loads a size it can read (see spirv_fixup).
    let (words, _) = crate::spirv_fixup::fix_arrayed_load_clamps(&words)?;
    let bytes = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let bindings = input
        .bindings
        .iter()
        .map(|b| {
            (
                (b.group, b.binding),
                json!({ "set": b.group, "binding": b.binding }),
            )
        })
        .collect();
    Ok(Output {
        bytes,
        entry_point: input.entry_point.to_owned(),
        bindings,
        extra: None,
    })
}

fn space(group: u32) -> Result<u8, String> {
    u8::try_from(group).map_err(|_| format!("group {group} exceeds HLSL's 255 register spaces"))
}

fn hlsl(input: &Input<'_>) -> Result<Output, String> {
    let mut options = hlsl::Options {
        shader_model: hlsl::ShaderModel::V5_1,
        restrict_indexing: true,
        force_loop_bounding: true,
        zero_initialize_workgroup_memory: true,
        fake_missing_bindings: false,
        ..hlsl::Options::default()
    };
    let mut bindings = BTreeMap::new();
    let mut samplers_per_group: BTreeMap<u32, u32> = BTreeMap::new();
    let mut last_binding: BTreeMap<u32, u32> = BTreeMap::new();
    for b in input.bindings {
        let s = space(b.group)?;
        let last = last_binding.entry(b.group).or_default();
        *last = (*last).max(b.binding);
        let (register, value) = match b.kind {
            BindingKind::Sampler | BindingKind::ComparisonSampler => {
                let index = samplers_per_group.entry(b.group).or_default();
                let r = *index;
                *index += 1;
                (
                    r,
                    json!({ "sampler_index": r, "space": s, "heap": if b.kind == BindingKind::Sampler { "standard" } else { "comparison" } }),
                )
            }
            _ => {
                let letter = match (&b.kind, b.access) {
                    (BindingKind::UniformBuffer, _) => "b",
                    (BindingKind::StorageBuffer | BindingKind::StorageTexture, "read") => "t",
                    (BindingKind::StorageBuffer | BindingKind::StorageTexture, _) => "u",
                    _ => "t",
                };
                (
                    b.binding,
                    json!({ "register": format!("{letter}{}", b.binding), "space": s }),
                )
            }
        };
        options.binding_map.insert(
            ResourceBinding {
                group: b.group,
                binding: b.binding,
            },
            hlsl::BindTarget {
                space: s,
                register,
                binding_array_size: None,
                dynamic_storage_buffer_offsets_index: None,
                restrict_indexing: true,
            },
        );
        bindings.insert((b.group, b.binding), value);
    }
    let mut index_buffers = Vec::new();
    for &group in samplers_per_group.keys() {
        let register = last_binding.get(&group).copied().unwrap_or(0) + 1;
        let s = space(group)?;
        options.sampler_buffer_binding_map.insert(
            hlsl::SamplerIndexBufferKey { group },
            hlsl::BindTarget {
                space: s,
                register,
                binding_array_size: None,
                dynamic_storage_buffer_offsets_index: None,
                restrict_indexing: false,
            },
        );
        index_buffers.push(json!({
            "group": group,
            "register": format!("t{register}"),
            "space": s,
            "contents": "StructuredBuffer<uint>: per sampler binding of the group (sampler_index), its slot in the sampler heap",
        }));
    }
    let heap = &options.sampler_heap_target;
    let extra = (!index_buffers.is_empty()).then(|| {
        json!({
            "sampler_heap": { "register": format!("s{}", heap.standard_samplers.register), "space": heap.standard_samplers.space, "size": 2048 },
            "comparison_sampler_heap": { "register": format!("s{}", heap.comparison_samplers.register), "space": heap.comparison_samplers.space, "size": 2048 },
            "sampler_index_buffers": index_buffers,
        })
    });
    let pipeline = hlsl::PipelineOptions {
        entry_point: Some((ShaderStage::Compute, input.entry_point.to_owned())),
    };
    let mut body = String::new();
    let reflection = hlsl::Writer::new(&mut body, &options, &pipeline)
        .write(input.module, input.info, None)
        .map_err(|e| e.to_string())?;
    let entry_point = reflection
        .entry_point_names
        .into_iter()
        .next()
        .ok_or("no entry point written")?
        .map_err(|e| e.to_string())?;
    Ok(Output {
        bytes: format!("{}{body}", comment(input.banner, "// ")).into_bytes(),
        entry_point,
        bindings,
        extra,
    })
}

fn msl(input: &Input<'_>) -> Result<Output, String> {
    let mut resources = msl::BindingMap::default();
    let mut bindings = BTreeMap::new();
    let (mut buffers, mut textures, mut samplers) = (0u8, 0u8, 0u8);
    let next = |n: &mut u8| -> Result<u8, String> {
        let slot = *n;
        *n = n
            .checked_add(1)
            .ok_or("more than 255 Metal argument slots of one kind")?;
        Ok(slot)
    };
    let mut runtime_arrays = Vec::new();
    for b in input.bindings {
        let mut target = msl::BindTarget {
            mutable: b.access != "read",
            ..msl::BindTarget::default()
        };
        let value = match b.kind {
            BindingKind::UniformBuffer | BindingKind::StorageBuffer => {
                let slot = next(&mut buffers)?;
                target.buffer = Some(slot);
                if b.array_stride.is_some() {
                    runtime_arrays.push(json!({ "group": b.group, "binding": b.binding }));
                }
                json!({ "buffer": slot })
            }
            BindingKind::Sampler | BindingKind::ComparisonSampler => {
                let slot = next(&mut samplers)?;
                target.sampler = Some(msl::BindSamplerTarget::Resource(slot));
                json!({ "sampler": slot })
            }
            _ => {
                let slot = next(&mut textures)?;
                target.texture = Some(slot);
                json!({ "texture": slot })
            }
        };
        resources.insert(
            ResourceBinding {
                group: b.group,
                binding: b.binding,
            },
            target,
        );
        bindings.insert((b.group, b.binding), value);
    }
    let sizes_buffer = next(&mut buffers)?;
    let mut per_entry_point_map = msl::EntryPointResourceMap::default();
    per_entry_point_map.insert(
        input.entry_point.to_owned(),
        msl::EntryPointResources {
            resources,
            immediates_buffer: None,
            sizes_buffer: Some(sizes_buffer),
        },
    );
    let options = msl::Options {
        lang_version: (2, 0),
        per_entry_point_map,
        inline_samplers: Vec::new(),
        spirv_cross_compatibility: false,
        fake_missing_bindings: false,
        bounds_check_policies: BOUNDS_CHECKS,
        zero_initialize_workgroup_memory: true,
        force_loop_bounding: true,
        task_dispatch_limits: None,
        mesh_shader_primitive_indices_clamp: true,
        emit_int_div_checks: true,
        ray_query_initialization_tracking: true,
    };
    let pipeline = msl::PipelineOptions {
        entry_point: Some((ShaderStage::Compute, input.entry_point.to_owned())),
        ..msl::PipelineOptions::default()
    };
    let (body, info) = msl::write_string(input.module, input.info, &options, &pipeline)
        .map_err(|e| e.to_string())?;
    let entry_point = info
        .entry_point_names
        .into_iter()
        .next()
        .ok_or("no entry point written")?
        .map_err(|e| e.to_string())?;
    let extra = (!runtime_arrays.is_empty()).then(|| {
        json!({
            "sizes_buffer": {
                "buffer": sizes_buffer,
                "contents": "uint32 array: byte size of each bound buffer that holds a runtime-sized array, in this order",
                "bindings": runtime_arrays,
            }
        })
    });
    Ok(Output {
        bytes: format!("{}{body}", comment(input.banner, "// ")).into_bytes(),
        entry_point,
        bindings,
        extra,
    })
}
