//! [`Engine`]: one variant of a scatter-gen directory on raw wgpu, built from the manifest
//! alone. [`Engine::load`] checks the parameters against their constraints, creates every
//! resource the manifest lists (textures, buffers, samplers, sized by the formulas), one bind
//! group layout per group from the reflected bindings, and one compute pipeline per pass
//! from the SPIR-V or WGSL file (its SHA-256 checked against the manifest first).
//! [`Engine::run`] uploads one frame's host data, picks each pass's bindings (honouring
//! `skip_when` and `alternative`), dispatches the formula's workgroup counts in pass order
//! and submits; [`Engine::read_texture`] reads a texture back.
//!
//! Nothing here knows the kernels: names of resources come from the manifest; only the
//! caller knows that `frame` holds the uniform block ([`crate::prefiltered`] is that
//! caller for the prefiltered family).

use std::borrow::Cow;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::mpsc;

use sha2::{Digest, Sha256};

use crate::EngineError;
use crate::condition::Condition;
use crate::formula::{Params, check_constraint, eval_u32};
use crate::manifest::{Binding, Manifest, Resource, SamplerDesc, VariantEntry};

/// Which emitted shaders the engine loads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// `.spv`, through naga's SPIR-V front-end inside wgpu.
    Spirv,
    /// `.wgsl`.
    Wgsl,
}

impl Target {
    /// The manifest's name for the target.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Spirv => "spirv",
            Self::Wgsl => "wgsl",
        }
    }
}

impl std::str::FromStr for Target {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "spirv" => Ok(Self::Spirv),
            "wgsl" => Ok(Self::Wgsl),
            other => Err(format!("unknown target {other:?} (allowed: spirv, wgsl)")),
        }
    }
}

impl std::fmt::Display for Target {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Host data for one frame, by resource name.
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameData<'a> {
    /// Bytes of the buffers the host writes every frame (resources with `copy_dst` usage:
    /// the uniform block, the slice table); each exactly the resource's `size_bytes`.
    pub buffers: &'a [(&'a str, &'a [u8])],
    /// Texels of the engine's textures (resources `provided_by: engine`), row-major from the
    /// top-left texel, layer after layer, every channel of a 32- or 16-bit float format (as
    /// f32; rounded to f16 for the latter).
    pub textures: &'a [(&'a str, &'a [f32])],
}

/// What [`Engine::run`] did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FrameRun {
    /// Kernels dispatched, in order, with their workgroup counts.
    pub dispatched: Vec<(String, [u32; 3])>,
    /// Kernels skipped by their `skip_when`.
    pub skipped: Vec<String>,
    /// `kernel binding -> resource` for every binding that took its alternative.
    pub alternatives: Vec<String>,
}

/// A created resource.
#[derive(Debug)]
enum Gpu {
    Texture {
        texture: wgpu::Texture,
        format: wgpu::TextureFormat,
    },
    Buffer {
        buffer: wgpu::Buffer,
        size: u64,
        host_written: bool,
    },
    Sampler(wgpu::Sampler),
}

/// What one binding binds this frame.
enum Bound<'a> {
    View(wgpu::TextureView),
    Buffer(&'a wgpu::Buffer),
    Sampler(&'a wgpu::Sampler),
}

/// One binding of a pass, ready to resolve per frame.
#[derive(Debug)]
struct BindingPlan {
    group: u32,
    binding: u32,
    view_dimension: Option<wgpu::TextureViewDimension>,
    resource: String,
    alternative: Option<(String, Condition)>,
}

/// One pass: pipeline, layouts, bindings, workgroup counts.
#[derive(Debug)]
struct PassPlan {
    kernel: String,
    pipeline: wgpu::ComputePipeline,
    layouts: Vec<wgpu::BindGroupLayout>,
    bindings: Vec<BindingPlan>,
    workgroups: [u32; 3],
    /// The buffer and byte offset of the workgroup counts of an indirect dispatch
    /// (`workgroups` is then their most).
    indirect: Option<(String, u64)>,
    skip_when: Option<Condition>,
}

/// One variant of a scatter-gen directory, ready to run frames.
#[derive(Debug)]
pub struct Engine {
    device: wgpu::Device,
    queue: wgpu::Queue,
    manifest: Manifest,
    variant: VariantEntry,
    target: Target,
    params: Params,
    resources: BTreeMap<String, (Resource, Gpu)>,
    passes: Vec<PassPlan>,
    /// Last bytes uploaded to each host-written buffer (conditions read them).
    uploaded: BTreeMap<String, Vec<u8>>,
    /// Engine textures supplied in the current frame.
    supplied: BTreeSet<String>,
}

/// Runs `f` inside validation and out-of-memory error scopes.
fn scoped<T>(
    device: &wgpu::Device,
    stage: impl Into<String>,
    f: impl FnOnce() -> T,
) -> Result<T, EngineError> {
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let value = f();
    let validation = pollster::block_on(validation.pop());
    let oom = pollster::block_on(oom.pop());
    match validation.or(oom) {
        None => Ok(value),
        Some(e) => Err(EngineError::Wgpu {
            stage: stage.into(),
            message: e.to_string(),
        }),
    }
}

/// A WebGPU texture format name.
pub fn texture_format(name: &str) -> Option<wgpu::TextureFormat> {
    use wgpu::TextureFormat as F;
    Some(match name {
        "r8unorm" => F::R8Unorm,
        "r16float" => F::R16Float,
        "r32float" => F::R32Float,
        "r32uint" => F::R32Uint,
        "r32sint" => F::R32Sint,
        "rg16float" => F::Rg16Float,
        "rg32float" => F::Rg32Float,
        "rgba8unorm" => F::Rgba8Unorm,
        "rgba8snorm" => F::Rgba8Snorm,
        "rgba16float" => F::Rgba16Float,
        "rgba32float" => F::Rgba32Float,
        "depth32float" => F::Depth32Float,
        _ => return None,
    })
}

/// How texels of a format decode to f32: channels, bytes per channel, encoding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    F32,
    F16,
    Unorm8,
    Snorm8,
    U32,
    I32,
}

fn encoding(format: wgpu::TextureFormat) -> Option<(usize, Encoding)> {
    use wgpu::TextureFormat as F;
    Some(match format {
        F::R32Float | F::Depth32Float => (1, Encoding::F32),
        F::Rg32Float => (2, Encoding::F32),
        F::Rgba32Float => (4, Encoding::F32),
        F::R16Float => (1, Encoding::F16),
        F::Rg16Float => (2, Encoding::F16),
        F::Rgba16Float => (4, Encoding::F16),
        F::R8Unorm => (1, Encoding::Unorm8),
        F::Rgba8Unorm => (4, Encoding::Unorm8),
        F::Rgba8Snorm => (4, Encoding::Snorm8),
        F::R32Uint => (1, Encoding::U32),
        F::R32Sint => (1, Encoding::I32),
        _ => return None,
    })
}

impl Encoding {
    const fn bytes(self) -> usize {
        match self {
            Self::F32 | Self::U32 | Self::I32 => 4,
            Self::F16 => 2,
            Self::Unorm8 | Self::Snorm8 => 1,
        }
    }

    fn decode(self, b: &[u8]) -> f32 {
        match self {
            Self::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            Self::F16 => half::f16::from_bits(u16::from_le_bytes([b[0], b[1]])).to_f32(),
            Self::Unorm8 => f32::from(b[0]) / 255.0,
            Self::Snorm8 => (f32::from(b[0] as i8) / 127.0).max(-1.0),
            Self::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
            Self::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        }
    }
}

fn view_dimension(name: &str) -> Option<wgpu::TextureViewDimension> {
    use wgpu::TextureViewDimension as D;
    Some(match name {
        "1d" => D::D1,
        "2d" => D::D2,
        "2d_array" => D::D2Array,
        "cube" => D::Cube,
        "cube_array" => D::CubeArray,
        "3d" => D::D3,
        _ => return None,
    })
}

fn filter(name: &str) -> Option<wgpu::FilterMode> {
    match name {
        "linear" => Some(wgpu::FilterMode::Linear),
        "nearest" => Some(wgpu::FilterMode::Nearest),
        _ => None,
    }
}

fn address_mode(name: &str) -> Option<wgpu::AddressMode> {
    match name {
        "clamp_to_edge" => Some(wgpu::AddressMode::ClampToEdge),
        "repeat" => Some(wgpu::AddressMode::Repeat),
        "mirror_repeat" => Some(wgpu::AddressMode::MirrorRepeat),
        _ => None,
    }
}

fn unsupported(context: impl Into<String>, what: &'static str, value: &str) -> EngineError {
    EngineError::Unsupported {
        context: context.into(),
        what,
        value: value.to_owned(),
    }
}

fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Reads a shader file the manifest lists and checks its hash against the pass's entry and
/// the directory's `files` list.
fn read_checked(
    dir: &Path,
    manifest: &Manifest,
    rel: &str,
    expected: &str,
) -> Result<(PathBuf, Vec<u8>), EngineError> {
    if rel.split(['/', '\\']).any(|c| c == ".." || c.is_empty()) || Path::new(rel).is_absolute() {
        return Err(EngineError::Inconsistent(format!(
            "shader path {rel:?} leaves the directory"
        )));
    }
    if let Some(entry) = manifest.files.iter().find(|f| f.path == rel)
        && entry.sha256 != expected
    {
        return Err(EngineError::Inconsistent(format!(
            "{rel}: the pass says sha256 {expected}, `files` says {}",
            entry.sha256
        )));
    }
    let path = dir.join(rel);
    let bytes = match std::fs::read(&path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(EngineError::MissingShader { path });
        }
        Err(source) => return Err(EngineError::Io { path, source }),
    };
    let actual = sha256_hex(&bytes);
    if actual != expected.to_ascii_lowercase() {
        return Err(EngineError::StaleShader {
            path,
            expected: expected.to_owned(),
            actual,
        });
    }
    Ok((path, bytes))
}

/// SPIR-V words of a `.spv` file (little- or big-endian, as the magic number says).
fn spirv_words(path: &Path, bytes: &[u8]) -> Result<Vec<u32>, EngineError> {
    const MAGIC: u32 = 0x0723_0203;
    let bad = |reason: String| EngineError::BadSpirv {
        path: path.to_path_buf(),
        reason,
    };
    if !bytes.len().is_multiple_of(4) || bytes.len() < 20 {
        return Err(bad(format!(
            "{} bytes: not a whole number of 32-bit words with a 5-word header",
            bytes.len()
        )));
    }
    let first = [bytes[0], bytes[1], bytes[2], bytes[3]];
    let big = if u32::from_le_bytes(first) == MAGIC {
        false
    } else if u32::from_be_bytes(first) == MAGIC {
        true
    } else {
        return Err(bad(format!(
            "magic number {:#010x}, expected {MAGIC:#010x}",
            u32::from_le_bytes(first)
        )));
    };
    Ok(bytes
        .chunks_exact(4)
        .map(|w| {
            let w = [w[0], w[1], w[2], w[3]];
            if big {
                u32::from_be_bytes(w)
            } else {
                u32::from_le_bytes(w)
            }
        })
        .collect())
}

impl Engine {
    /// Loads variant `variant_id` of the scatter-gen directory `dir` for `target` at the
    /// sizes in `params` (every parameter the variant lists must be set).
    ///
    /// # Errors
    ///
    /// Manifest errors ([`EngineError::MissingManifest`], [`EngineError::ManifestParse`],
    /// [`EngineError::UnknownVariant`], ...); [`EngineError::UnknownParameter`] or
    /// [`EngineError::Constraint`] for the sizes; [`EngineError::UnknownSymbol`] /
    /// [`EngineError::Formula`] for a formula; [`EngineError::Unsupported`] for a format,
    /// binding kind or sampler mode this engine does not implement;
    /// [`EngineError::TargetNotGenerated`], [`EngineError::MissingShader`],
    /// [`EngineError::StaleShader`], [`EngineError::BadSpirv`] for shader files;
    /// [`EngineError::Wgpu`] when wgpu rejects a shader, layout, pipeline or resource.
    pub fn load(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        dir: &Path,
        variant_id: &str,
        target: Target,
        params: &Params,
    ) -> Result<Self, EngineError> {
        let manifest = Manifest::load(dir)?;
        let variant = manifest.variant(variant_id)?.clone();
        let limits = device.limits();

        // Sizes: every parameter set, within its constraint; nothing else set.
        let mut effective = Params::default();
        for p in &variant.parameters {
            let value = params
                .get(&p.name)
                .ok_or_else(|| EngineError::UnknownParameter {
                    name: p.name.clone(),
                    known: params.names(),
                })?;
            check_constraint(&p.name, value, &p.constraint, &limits)?;
            effective.set(&p.name, value);
        }

        // Every shader file first: a stale or missing file fails before any GPU work.
        let mut shader_sources = Vec::new();
        for pass in &variant.passes {
            let file =
                pass.files
                    .get(target.name())
                    .ok_or_else(|| EngineError::TargetNotGenerated {
                        kernel: pass.kernel.clone(),
                        variant: variant.id.clone(),
                        target: target.name().to_owned(),
                    })?;
            let (path, bytes) = read_checked(dir, &manifest, &file.path, &file.sha256)?;
            let source = match target {
                Target::Spirv => wgpu::ShaderSource::SpirV(Cow::Owned(spirv_words(&path, &bytes)?)),
                Target::Wgsl => wgpu::ShaderSource::Wgsl(Cow::Owned(
                    String::from_utf8(bytes)
                        .map_err(|_| EngineError::BadWgsl { path: path.clone() })?,
                )),
            };

            shader_sources.push((file.entry_point.clone(), source));
        }
        let mut sources = shader_sources.into_iter();

        let mut resources = BTreeMap::new();
        for r in &variant.resources {
            let gpu = create_resource(device, r, &effective, &limits)?;
            resources.insert(r.name.clone(), (r.clone(), gpu));
        }

        let mut passes = Vec::new();
        for pass in &variant.passes {
            let context = |what: &str| format!("pass {} {what}", pass.kernel);
            let (entry_point, source) = sources.next().ok_or_else(|| {
                EngineError::Inconsistent("pass list changed while loading".to_owned())
            })?;

            // Bindings and their layouts.
            let mut plans = Vec::new();
            let mut entries: BTreeMap<u32, Vec<wgpu::BindGroupLayoutEntry>> = BTreeMap::new();
            for b in &pass.bindings {
                let ctx = context(&format!("binding {}.{} ({})", b.group, b.binding, b.name));
                let primary = lookup(&resources, &b.resource, &ctx)?;
                let alternative = match &b.alternative {
                    None => None,
                    Some(a) => {
                        let alt = lookup(&resources, &a.resource, &ctx)?;
                        if alt.0.kind != primary.0.kind {
                            return Err(EngineError::Inconsistent(format!(
                                "{ctx}: alternative {} is a {}, {} a {}",
                                a.resource, alt.0.kind, b.resource, primary.0.kind
                            )));
                        }
                        let cond = Condition::parse(&a.when, &manifest, &variant, &ctx)?;
                        if matches!(cond, Condition::Engine { .. }) && !primary.0.engine_provided()
                        {
                            return Err(EngineError::Condition {
                                condition: a.when.clone(),
                                context: ctx.clone(),
                                reason: format!(
                                    "not machine-readable, and {} is not an engine input whose absence could decide it",
                                    b.resource
                                ),
                            });
                        }
                        Some((a.resource.clone(), cond))
                    }
                };
                let samplers: Vec<&SamplerDesc> = std::iter::once(&b.resource)
                    .chain(b.alternative.as_ref().map(|a| &a.resource))
                    .filter_map(|n| resources.get(n).and_then(|(r, _)| r.sampler.as_ref()))
                    .collect();
                let entry = layout_entry(b, &samplers, &ctx)?;
                entries.entry(b.group).or_default().push(entry);
                plans.push(BindingPlan {
                    group: b.group,
                    binding: b.binding,
                    view_dimension: match &entry.ty {
                        wgpu::BindingType::Texture { view_dimension, .. }
                        | wgpu::BindingType::StorageTexture { view_dimension, .. } => {
                            Some(*view_dimension)
                        }
                        _ => None,
                    },
                    resource: b.resource.clone(),
                    alternative,
                });
            }
            let skip_when = pass
                .skip_when
                .as_deref()
                .map(|t| Condition::parse(t, &manifest, &variant, &context("skip_when")))
                .transpose()?;
            if let Some(c @ Condition::Engine { .. }) = &skip_when {
                return Err(EngineError::Condition {
                    condition: c.text().to_owned(),
                    context: context("skip_when"),
                    reason: "a skip condition must read a buffer".to_owned(),
                });
            }

            // Workgroup counts.
            if pass.dispatch.len() != 3 {
                return Err(EngineError::Inconsistent(format!(
                    "pass {} has {} dispatch dimensions, not 3",
                    pass.kernel,
                    pass.dispatch.len()
                )));
            }
            let mut workgroups = [1u32; 3];
            for (axis, (d, slot)) in pass.dispatch.iter().zip(&mut workgroups).enumerate() {
                let what = format!(
                    "workgroups of pass {} along {}",
                    pass.kernel,
                    ["x", "y", "z"][axis]
                );
                *slot = eval_u32(&d.workgroups, &effective, &what)?;
                check_constraint(
                    &what,
                    (*slot).into(),
                    "0..=max_compute_workgroups_per_dimension",
                    &limits,
                )?;
            }

            // An indirect dispatch reads a buffer of the manifest's at a 4-byte aligned offset.
            let indirect = match &pass.indirect {
                None => None,
                Some(i) => {
                    let buffer = variant
                        .resources
                        .iter()
                        .find(|r| r.name == i.buffer)
                        .and_then(|r| r.buffer.as_ref())
                        .ok_or_else(|| {
                            EngineError::Inconsistent(format!(
                                "pass {} is dispatched indirectly from `{}`, which is no buffer of the variant",
                                pass.kernel, i.buffer
                            ))
                        })?;
                    if !buffer.usage.iter().any(|u| u == "indirect") || i.offset_bytes % 4 != 0 {
                        return Err(EngineError::Inconsistent(format!(
                            "pass {} is dispatched indirectly from `{}` at byte {}: the buffer needs `indirect` usage and the offset a multiple of 4",
                            pass.kernel, i.buffer, i.offset_bytes
                        )));
                    }
                    Some((i.buffer.clone(), i.offset_bytes))
                }
            };

            let label = Some(pass.kernel.as_str());
            let max_group = entries.keys().next_back().copied().unwrap_or(0);
            let (pipeline, layouts) = scoped(device, context("pipeline creation"), || {
                let module =
                    device.create_shader_module(wgpu::ShaderModuleDescriptor { label, source });
                let layouts: Vec<wgpu::BindGroupLayout> = (0..=max_group)
                    .map(|g| {
                        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                            label,
                            entries: entries.get(&g).map_or(&[], Vec::as_slice),
                        })
                    })
                    .collect();
                let layout_refs: Vec<Option<&wgpu::BindGroupLayout>> =
                    layouts.iter().map(Some).collect();
                let pipeline_layout =
                    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                        label,
                        bind_group_layouts: &layout_refs,
                        immediate_size: 0,
                    });
                let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label,
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some(entry_point.as_str()),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    cache: None,
                });
                (pipeline, layouts)
            })?;
            passes.push(PassPlan {
                kernel: pass.kernel.clone(),
                pipeline,
                layouts,
                bindings: plans,
                workgroups,
                indirect,
                skip_when,
            });
        }
        Ok(Self {
            device: device.clone(),
            queue: queue.clone(),
            manifest,
            variant,
            target,
            params: effective,
            resources,
            passes,
            uploaded: BTreeMap::new(),
            supplied: BTreeSet::new(),
        })
    }

    /// Uploads `data`, resolves every pass's bindings for this frame and submits the passes
    /// that are not skipped, in the manifest's order (wgpu orders the compute passes and
    /// inserts the barriers and layout transitions the notes ask for).
    ///
    /// Engine textures not in `data.textures` count as absent this frame: a binding that
    /// needs one fails, an alternative whose condition is written for people (see
    /// [`crate::condition`]) replaces it.
    ///
    /// # Errors
    ///
    /// [`EngineError::NotAnInput`], [`EngineError::InputLength`] for bad data;
    /// [`EngineError::MissingInput`] when a pass needs a texture or buffer that was never
    /// supplied; [`EngineError::Condition`] when a condition reads a buffer never uploaded;
    /// [`EngineError::Wgpu`] when wgpu rejects a bind group or the submission.
    pub fn run(&mut self, data: &FrameData<'_>) -> Result<FrameRun, EngineError> {
        self.upload(data)?;
        let device = &self.device;
        let mut run = FrameRun::default();
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("foreign engine frame"),
        });
        for pass in &self.passes {
            if let Some(cond) = &pass.skip_when
                && cond.eval(|n| self.uploaded.get(n).map(Vec::as_slice))? == Some(true)
            {
                run.skipped.push(pass.kernel.clone());
                continue;
            }
            // Resolve each binding's resource.
            let mut chosen = Vec::with_capacity(pass.bindings.len());
            for b in &pass.bindings {
                let name = match &b.alternative {
                    Some((alt, cond)) => {
                        let take = match cond.eval(|n| self.uploaded.get(n).map(Vec::as_slice))? {
                            Some(v) => v,
                            // Written for people: the engine input it replaces is absent.
                            None => !self.supplied.contains(&b.resource),
                        };
                        if take {
                            run.alternatives
                                .push(format!("{} {} -> {alt}", pass.kernel, b.binding));
                            alt.as_str()
                        } else {
                            b.resource.as_str()
                        }
                    }
                    None => b.resource.as_str(),
                };
                let (res, gpu) = &self.resources[name];
                let missing = match gpu {
                    Gpu::Texture { .. } => res.engine_provided() && !self.supplied.contains(name),
                    Gpu::Buffer { host_written, .. } => {
                        *host_written && !self.uploaded.contains_key(name)
                    }
                    Gpu::Sampler(_) => false,
                };
                if missing {
                    return Err(EngineError::MissingInput {
                        kernel: pass.kernel.clone(),
                        resource: name.to_owned(),
                        contents: res.contents.clone(),
                    });
                }
                chosen.push((b, gpu));
            }
            let groups = scoped(
                device,
                format!("creating the bind groups of {}", pass.kernel),
                || {
                    let bound: Vec<(&BindingPlan, Bound<'_>)> = chosen
                        .iter()
                        .map(|&(b, gpu)| {
                            let bound = match gpu {
                                Gpu::Texture { texture, .. } => {
                                    Bound::View(texture.create_view(&wgpu::TextureViewDescriptor {
                                        dimension: b.view_dimension,
                                        ..wgpu::TextureViewDescriptor::default()
                                    }))
                                }
                                Gpu::Buffer { buffer, .. } => Bound::Buffer(buffer),
                                Gpu::Sampler(s) => Bound::Sampler(s),
                            };
                            (b, bound)
                        })
                        .collect();
                    pass.layouts
                        .iter()
                        .zip(0u32..)
                        .map(|(layout, group)| {
                            let entries: Vec<wgpu::BindGroupEntry<'_>> = bound
                                .iter()
                                .filter(|(b, _)| b.group == group)
                                .map(|(b, bound)| wgpu::BindGroupEntry {
                                    binding: b.binding,
                                    resource: match bound {
                                        Bound::View(view) => {
                                            wgpu::BindingResource::TextureView(view)
                                        }
                                        Bound::Buffer(buffer) => buffer.as_entire_binding(),
                                        Bound::Sampler(s) => wgpu::BindingResource::Sampler(s),
                                    },
                                })
                                .collect();
                            device.create_bind_group(&wgpu::BindGroupDescriptor {
                                label: Some(pass.kernel.as_str()),
                                layout,
                                entries: &entries,
                            })
                        })
                        .collect::<Vec<_>>()
                },
            )?;
            let mut cpass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(pass.kernel.as_str()),
                timestamp_writes: None,
            });
            cpass.set_pipeline(&pass.pipeline);
            for (group, bg) in (0u32..).zip(&groups) {
                cpass.set_bind_group(group, bg, &[]);
            }
            match &pass.indirect {
                Some((name, offset)) => match self.resources.get(name) {
                    Some((_, Gpu::Buffer { buffer, .. })) => {
                        cpass.dispatch_workgroups_indirect(buffer, *offset);
                    }
                    _ => {
                        return Err(EngineError::Inconsistent(format!(
                            "pass {} is dispatched indirectly from `{name}`, which was not created as a buffer",
                            pass.kernel
                        )));
                    }
                },
                None => {
                    let [x, y, z] = pass.workgroups;
                    cpass.dispatch_workgroups(x, y, z);
                }
            }
            drop(cpass);
            run.dispatched.push((pass.kernel.clone(), pass.workgroups));
        }
        scoped(device, "submitting the frame", || {
            self.queue.submit([encoder.finish()]);
        })?;
        Ok(run)
    }

    /// Writes the frame's buffers and engine textures.
    fn upload(&mut self, data: &FrameData<'_>) -> Result<(), EngineError> {
        self.supplied.clear();
        let not_input = |name: &str, reason: &str| EngineError::NotAnInput {
            resource: name.to_owned(),
            reason: reason.to_owned(),
        };
        let device = &self.device;
        for &(name, bytes) in data.buffers {
            let Some((_, gpu)) = self.resources.get(name) else {
                return Err(not_input(name, "the variant has no such resource"));
            };
            let Gpu::Buffer {
                buffer,
                size,
                host_written,
            } = gpu
            else {
                return Err(not_input(name, "not a buffer"));
            };
            if !host_written {
                return Err(not_input(name, "its usage lacks copy_dst"));
            }
            if bytes.len() as u64 != *size {
                return Err(EngineError::InputLength {
                    resource: name.to_owned(),
                    expected: *size,
                    actual: bytes.len() as u64,
                    unit: "bytes",
                });
            }
            scoped(device, format!("uploading {name}"), || {
                self.queue.write_buffer(buffer, 0, bytes);
            })?;
            self.uploaded.insert(name.to_owned(), bytes.to_vec());
        }
        for &(name, texels) in data.textures {
            let Some((res, gpu)) = self.resources.get(name) else {
                return Err(not_input(name, "the variant has no such resource"));
            };
            let Gpu::Texture { texture, format } = gpu else {
                return Err(not_input(name, "not a texture"));
            };
            if !res.engine_provided() {
                return Err(not_input(
                    name,
                    "scatter provides it (provided_by: scatter)",
                ));
            }
            let Some((channels, enc @ (Encoding::F32 | Encoding::F16))) = encoding(*format) else {
                return Err(unsupported(
                    format!("uploading engine texture {name}"),
                    "upload format (only 32- and 16-bit float formats)",
                    &format!("{format:?}"),
                ));
            };
            let size = texture.size();
            let expected = u64::from(size.width)
                * u64::from(size.height)
                * u64::from(size.depth_or_array_layers)
                * channels as u64;
            if texels.len() as u64 != expected {
                return Err(EngineError::InputLength {
                    resource: name.to_owned(),
                    expected,
                    actual: texels.len() as u64,
                    unit: "floats",
                });
            }
            // A 16-bit float texture (a spot's cookie) gets its texels rounded to f16.
            let halves: Vec<u16> = if enc == Encoding::F16 {
                texels
                    .iter()
                    .map(|t| half::f16::from_f32(*t).to_bits())
                    .collect()
            } else {
                Vec::new()
            };
            let bytes: &[u8] = if enc == Encoding::F16 {
                bytemuck::cast_slice(&halves)
            } else {
                bytemuck::cast_slice(texels)
            };
            scoped(device, format!("uploading {name}"), || {
                self.queue.write_texture(
                    texture.as_image_copy(),
                    bytes,
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(size.width * (enc.bytes() * channels) as u32),
                        rows_per_image: Some(size.height),
                    },
                    size,
                );
            })?;
            self.supplied.insert(name.to_owned());
        }
        Ok(())
    }

    /// Reads texture `name` back after the submitted work: every channel as f32, row-major
    /// from the top-left texel, layer after layer (channels per texel: the format's).
    ///
    /// # Errors
    ///
    /// [`EngineError::NotAnInput`] for a name that is not a texture;
    /// [`EngineError::Unsupported`] for a format it cannot decode;
    /// [`EngineError::Readback`] / [`EngineError::Wgpu`] when the copy or the mapping fails.
    pub fn read_texture(&self, name: &str) -> Result<(usize, Vec<f32>), EngineError> {
        let Some((_, Gpu::Texture { texture, format })) = self.resources.get(name) else {
            return Err(EngineError::NotAnInput {
                resource: name.to_owned(),
                reason: "not a texture of this variant".to_owned(),
            });
        };
        let (channels, enc) = encoding(*format).ok_or_else(|| {
            unsupported(
                format!("reading {name}"),
                "readback format",
                &format!("{format:?}"),
            )
        })?;
        let texel = channels * enc.bytes();
        let extent = texture.size();
        let row = extent.width as usize * texel;
        let padded = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT as usize);
        let device = &self.device;
        let buffer = scoped(device, format!("reading {name} back"), || {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("foreign engine readback"),
                size: (padded * extent.height as usize * extent.depth_or_array_layers as usize)
                    as u64,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("foreign engine readback"),
            });
            encoder.copy_texture_to_buffer(
                texture.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: &buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(padded as u32),
                        rows_per_image: Some(extent.height),
                    },
                },
                extent,
            );
            self.queue.submit([encoder.finish()]);
            buffer
        })?;
        let failed = |message: String| EngineError::Readback {
            resource: name.to_owned(),
            message,
        };
        let (sender, receiver) = mpsc::channel();
        buffer.map_async(wgpu::MapMode::Read, .., move |r| {
            // The receiver waits below; a failed send only means it gave up.
            let _ = sender.send(r);
        });
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| failed(format!("poll: {e}")))?;
        receiver
            .recv()
            .map_err(|e| failed(format!("map callback never ran: {e}")))?
            .map_err(|e| failed(format!("map_async: {e}")))?;
        let bytes = buffer
            .get_mapped_range(..)
            .map_err(|e| failed(format!("get_mapped_range: {e}")))?
            .to_vec();
        buffer.unmap();
        let mut out = Vec::with_capacity(bytes.len() / enc.bytes());
        for r in bytes.chunks_exact(padded) {
            out.extend(r[..row].chunks_exact(enc.bytes()).map(|c| enc.decode(c)));
        }
        Ok((channels, out))
    }

    /// The variant's manifest entry.
    pub fn variant(&self) -> &VariantEntry {
        &self.variant
    }

    /// The whole manifest.
    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    /// The target the pipelines were built from.
    pub fn target(&self) -> Target {
        self.target
    }

    /// The parameter values in effect.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// The device.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }
}

fn lookup<'a>(
    resources: &'a BTreeMap<String, (Resource, Gpu)>,
    name: &str,
    ctx: &str,
) -> Result<&'a (Resource, Gpu), EngineError> {
    resources
        .get(name)
        .ok_or_else(|| EngineError::Inconsistent(format!("{ctx} binds unknown resource {name:?}")))
}

/// Creates one resource from its manifest description.
fn create_resource(
    device: &wgpu::Device,
    r: &Resource,
    params: &Params,
    limits: &wgpu::Limits,
) -> Result<Gpu, EngineError> {
    let ctx = |what: &str| format!("resource {} {what}", r.name);
    let label = Some(r.name.as_str());
    match r.kind.as_str() {
        "texture" => {
            let t = r.texture.as_ref().ok_or_else(|| {
                EngineError::Inconsistent(format!("texture {} has no `texture` key", r.name))
            })?;
            let format = texture_format(&t.format)
                .ok_or_else(|| unsupported(ctx("format"), "texture format", &t.format))?;
            if t.dimension != "2d" {
                return Err(unsupported(
                    ctx("dimension"),
                    "texture dimension",
                    &t.dimension,
                ));
            }
            let width = eval_u32(&t.width, params, &ctx("width"))?;
            let height = eval_u32(&t.height, params, &ctx("height"))?;
            let layers = eval_u32(&t.layers, params, &ctx("layers"))?;
            // Sizes the formulas computed (not only the parameters) against the device,
            // before anything is created.
            for (what, value) in [("width", width), ("height", height)] {
                check_constraint(
                    &ctx(what),
                    value.into(),
                    "1..=max_texture_dimension_2d",
                    limits,
                )?;
            }
            check_constraint(
                &ctx("layers"),
                layers.into(),
                "1..=max_texture_array_layers",
                limits,
            )?;
            let mut usage = wgpu::TextureUsages::COPY_SRC;
            if r.engine_provided() {
                usage |= wgpu::TextureUsages::COPY_DST;
            }
            for u in &t.usage {
                usage |= match u.as_str() {
                    "texture_binding" => wgpu::TextureUsages::TEXTURE_BINDING,
                    "storage_binding" => wgpu::TextureUsages::STORAGE_BINDING,
                    "render_attachment" => wgpu::TextureUsages::RENDER_ATTACHMENT,
                    "copy_src" => wgpu::TextureUsages::COPY_SRC,
                    "copy_dst" => wgpu::TextureUsages::COPY_DST,
                    other => return Err(unsupported(ctx("usage"), "texture usage", other)),
                };
            }
            let texture = scoped(device, ctx("creation"), || {
                device.create_texture(&wgpu::TextureDescriptor {
                    label,
                    size: wgpu::Extent3d {
                        width,
                        height,
                        depth_or_array_layers: layers,
                    },
                    mip_level_count: t.mip_levels.max(1),
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                })
            })?;
            Ok(Gpu::Texture { texture, format })
        }
        "uniform_buffer" | "storage_buffer" => {
            let b = r.buffer.as_ref().ok_or_else(|| {
                EngineError::Inconsistent(format!("buffer {} has no `buffer` key", r.name))
            })?;
            let size = crate::formula::eval(&b.size_bytes, params, &ctx("size_bytes"))?;
            let mut usage = wgpu::BufferUsages::empty();
            for u in &b.usage {
                usage |= match u.as_str() {
                    "uniform" => wgpu::BufferUsages::UNIFORM,
                    "storage" => wgpu::BufferUsages::STORAGE,
                    "copy_dst" => wgpu::BufferUsages::COPY_DST,
                    "copy_src" => wgpu::BufferUsages::COPY_SRC,
                    "indirect" => wgpu::BufferUsages::INDIRECT,
                    other => return Err(unsupported(ctx("usage"), "buffer usage", other)),
                };
            }
            check_constraint(&ctx("size_bytes"), size, "1..=max_buffer_size", limits)?;
            for (flag, limit) in [
                (
                    wgpu::BufferUsages::UNIFORM,
                    "1..=max_uniform_buffer_binding_size",
                ),
                (
                    wgpu::BufferUsages::STORAGE,
                    "1..=max_storage_buffer_binding_size",
                ),
            ] {
                if usage.contains(flag) {
                    check_constraint(&ctx("size_bytes"), size, limit, limits)?;
                }
            }
            let buffer = scoped(device, ctx("creation"), || {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label,
                    size,
                    usage,
                    mapped_at_creation: false,
                })
            })?;
            Ok(Gpu::Buffer {
                buffer,
                size,
                host_written: usage.contains(wgpu::BufferUsages::COPY_DST),
            })
        }
        "sampler" => {
            let s = r.sampler.as_ref().ok_or_else(|| {
                EngineError::Inconsistent(format!("sampler {} has no `sampler` key", r.name))
            })?;
            let f = |v: &str, what: &str| {
                filter(v).ok_or_else(|| unsupported(ctx(what), "filter mode", v))
            };
            let a = |v: &str, what: &str| {
                address_mode(v).ok_or_else(|| unsupported(ctx(what), "address mode", v))
            };
            let mipmap_filter = match f(&s.mipmap_filter, "mipmap_filter")? {
                wgpu::FilterMode::Linear => wgpu::MipmapFilterMode::Linear,
                wgpu::FilterMode::Nearest => wgpu::MipmapFilterMode::Nearest,
            };
            let desc = wgpu::SamplerDescriptor {
                label,
                address_mode_u: a(&s.address_mode_u, "address_mode_u")?,
                address_mode_v: a(&s.address_mode_v, "address_mode_v")?,
                address_mode_w: a(&s.address_mode_w, "address_mode_w")?,
                mag_filter: f(&s.mag_filter, "mag_filter")?,
                min_filter: f(&s.min_filter, "min_filter")?,
                mipmap_filter,
                ..wgpu::SamplerDescriptor::default()
            };
            let sampler = scoped(device, ctx("creation"), || device.create_sampler(&desc))?;
            Ok(Gpu::Sampler(sampler))
        }
        other => Err(unsupported(ctx("kind"), "resource kind", other)),
    }
}

/// The bind group layout entry of one reflected binding; `samplers` are the descriptions of
/// the samplers it may bind (filtering or not).
fn layout_entry(
    b: &Binding,
    samplers: &[&SamplerDesc],
    ctx: &str,
) -> Result<wgpu::BindGroupLayoutEntry, EngineError> {
    let dim = || {
        let name = b.view_dimension.as_deref().unwrap_or("2d");
        view_dimension(name).ok_or_else(|| unsupported(ctx, "view dimension", name))
    };
    let ty = match b.kind.as_str() {
        "uniform_buffer" | "storage_buffer" => wgpu::BindingType::Buffer {
            ty: if b.kind == "uniform_buffer" {
                wgpu::BufferBindingType::Uniform
            } else {
                wgpu::BufferBindingType::Storage {
                    read_only: b.access == "read",
                }
            },
            has_dynamic_offset: false,
            min_binding_size: b.min_binding_size.and_then(wgpu::BufferSize::new),
        },
        "sampled_texture" | "depth_texture" => wgpu::BindingType::Texture {
            sample_type: match (b.kind.as_str(), b.sample_type.as_deref()) {
                ("depth_texture", _) | (_, Some("depth")) => wgpu::TextureSampleType::Depth,
                (_, Some("float") | None) => wgpu::TextureSampleType::Float {
                    filterable: b.filterable.unwrap_or(false),
                },
                (_, Some("sint")) => wgpu::TextureSampleType::Sint,
                (_, Some("uint")) => wgpu::TextureSampleType::Uint,
                (_, Some(other)) => return Err(unsupported(ctx, "sample type", other)),
            },
            view_dimension: dim()?,
            multisampled: b.multisampled.unwrap_or(false),
        },
        "storage_texture" => {
            let name = b.format.as_deref().unwrap_or_default();
            wgpu::BindingType::StorageTexture {
                access: match b.access.as_str() {
                    "write" => wgpu::StorageTextureAccess::WriteOnly,
                    "read" => wgpu::StorageTextureAccess::ReadOnly,
                    "read_write" => wgpu::StorageTextureAccess::ReadWrite,
                    other => return Err(unsupported(ctx, "storage access", other)),
                },
                format: texture_format(name)
                    .ok_or_else(|| unsupported(ctx, "storage texture format", name))?,
                view_dimension: dim()?,
            }
        }
        "sampler" => {
            let linear = samplers.iter().any(|s| {
                [&s.mag_filter, &s.min_filter, &s.mipmap_filter]
                    .iter()
                    .any(|f| f.as_str() == "linear")
            });
            wgpu::BindingType::Sampler(if linear {
                wgpu::SamplerBindingType::Filtering
            } else {
                wgpu::SamplerBindingType::NonFiltering
            })
        }
        "comparison_sampler" => wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
        other => return Err(unsupported(ctx, "binding kind", other)),
    };
    Ok(wgpu::BindGroupLayoutEntry {
        binding: b.binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty,
        count: None,
    })
}
