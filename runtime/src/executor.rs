//! The one plan-driven GPU executor every family runs on.
//!
//! A family's passes are described once, as data: the [`Plan`] of its variant
//! (`scatter_shaderlib::<family>::plan`, the same plan `scatter-gen` writes into
//! `manifest.json`). [`Executor::new`] builds everything from it: each pass's bind group
//! layout from the bindings reflected out of the compiled kernel (never written by hand),
//! its pipeline, its workgroup counts from the plan's invocation formulas, and every resource
//! the plan says scatter allocates (textures, buffers sized from the reflected struct or
//! array stride, samplers). [`Executor::encode`] binds, per frame, each binding's resource by
//! name (the engine's textures are passed by name too) and dispatches the passes in order,
//! honouring the plan's per-frame conditions (a pass skipped, an alternative resource bound).
//!
//! What a family keeps for itself: its input checks, its per-frame upload (uniform blocks,
//! slice tables) and its frame report.

use scatter_shaderlib::plan::{self, PassPlan, Plan, Resource};
use scatter_shaderlib::reflect::{self, Binding, BindingKind};
use scatter_shaderlib::{BuiltKernel, Kernel};

use crate::error::{ErrorScopes, check_limit};
use crate::gpu::{Pipeline, check_dispatch, create_pipeline, groups};
use crate::{Context, GpuTimer, RuntimeError};

/// One pass: its plan, pipeline, reflected bindings and workgroup counts.
#[derive(Debug)]
struct ExecPass {
    plan: PassPlan,
    pipeline: Pipeline,
    bindings: Vec<Binding>,
    workgroups: [u32; 3],
}

/// A resource the executor allocated (the plan's `provided_by: scatter`).
#[derive(Debug)]
enum Owned {
    Texture {
        texture: wgpu::Texture,
        /// One view per view dimension the passes bind it with, the first one the default.
        views: Vec<(wgpu::TextureViewDimension, wgpu::TextureView)>,
    },
    Buffer(wgpu::Buffer),
    Sampler(wgpu::Sampler),
}

/// The plan of one variant, built: pipelines, resources, workgroup counts, timestamps.
#[derive(Debug)]
pub(crate) struct Executor {
    plan: Plan,
    passes: Vec<ExecPass>,
    owned: Vec<(&'static str, Owned)>,
    timer: Option<GpuTimer>,
}

fn plan_error(kernel: Kernel, message: String) -> RuntimeError {
    RuntimeError::Plan { kernel, message }
}

/// The wgpu format of a WebGPU format name the plans use.
fn texture_format(name: &str) -> Option<wgpu::TextureFormat> {
    use wgpu::TextureFormat as F;
    Some(match name {
        "r32float" => F::R32Float,
        "rg32float" => F::Rg32Float,
        "rgba8unorm" => F::Rgba8Unorm,
        "rgba16float" => F::Rgba16Float,
        "rgba32float" => F::Rgba32Float,
        "r32uint" => F::R32Uint,
        "rg32uint" => F::Rg32Uint,
        "rgba32uint" => F::Rgba32Uint,
        _ => return None,
    })
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

fn address_mode(name: &str) -> Option<wgpu::AddressMode> {
    Some(match name {
        "clamp_to_edge" => wgpu::AddressMode::ClampToEdge,
        "repeat" => wgpu::AddressMode::Repeat,
        "mirror_repeat" => wgpu::AddressMode::MirrorRepeat,
        _ => return None,
    })
}

fn filter_mode(name: &str) -> Option<wgpu::FilterMode> {
    Some(match name {
        "linear" => wgpu::FilterMode::Linear,
        "nearest" => wgpu::FilterMode::Nearest,
        _ => return None,
    })
}

fn mipmap_filter_mode(name: &str) -> Option<wgpu::MipmapFilterMode> {
    Some(match name {
        "linear" => wgpu::MipmapFilterMode::Linear,
        "nearest" => wgpu::MipmapFilterMode::Nearest,
        _ => return None,
    })
}

/// Every resource name a binding of `pass` may get (its default and its alternative).
fn sources<'p>(pass: &'p PassPlan, binding: u32) -> impl Iterator<Item = &'static str> + 'p {
    pass.bindings
        .iter()
        .filter(move |s| s.binding == binding)
        .flat_map(|s| std::iter::once(s.resource).chain(s.alternative.as_ref().map(|a| a.resource)))
}

/// The bind group layout entry of a reflected binding. A sampler is filtering when
/// `filtering(binding)` says so (in a plan: when any sampler the plan binds there filters
/// linearly).
pub(crate) fn layout_entry(
    kernel: Kernel,
    b: &Binding,
    filtering: impl Fn(u32) -> bool,
) -> Result<wgpu::BindGroupLayoutEntry, RuntimeError> {
    let dimension = || {
        b.view_dimension.and_then(view_dimension).ok_or_else(|| {
            plan_error(
                kernel,
                format!("binding {} has no view dimension", b.binding),
            )
        })
    };
    let ty = match b.kind {
        BindingKind::UniformBuffer | BindingKind::StorageBuffer => wgpu::BindingType::Buffer {
            ty: if b.kind == BindingKind::UniformBuffer {
                wgpu::BufferBindingType::Uniform
            } else {
                wgpu::BufferBindingType::Storage {
                    read_only: b.access == "read",
                }
            },
            has_dynamic_offset: false,
            min_binding_size: b
                .min_binding_size
                .and_then(|s| wgpu::BufferSize::new(s.into())),
        },
        BindingKind::SampledTexture => wgpu::BindingType::Texture {
            sample_type: match b.sample_type {
                Some("uint") => wgpu::TextureSampleType::Uint,
                Some("sint") => wgpu::TextureSampleType::Sint,
                _ => wgpu::TextureSampleType::Float {
                    filterable: b.filterable.unwrap_or(false),
                },
            },
            view_dimension: dimension()?,
            multisampled: b.multisampled.unwrap_or(false),
        },
        BindingKind::DepthTexture => wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Depth,
            view_dimension: dimension()?,
            multisampled: b.multisampled.unwrap_or(false),
        },
        BindingKind::StorageTexture => wgpu::BindingType::StorageTexture {
            access: match b.access {
                "read" => wgpu::StorageTextureAccess::ReadOnly,
                "read_write" => wgpu::StorageTextureAccess::ReadWrite,
                _ => wgpu::StorageTextureAccess::WriteOnly,
            },
            format: b
                .format
                .as_deref()
                .and_then(texture_format)
                .ok_or_else(|| {
                    plan_error(
                        kernel,
                        format!(
                            "binding {} has storage format {:?}, which the runtime does not map",
                            b.binding, b.format
                        ),
                    )
                })?,
            view_dimension: dimension()?,
        },
        BindingKind::Sampler => wgpu::BindingType::Sampler(if filtering(b.binding) {
            wgpu::SamplerBindingType::Filtering
        } else {
            wgpu::SamplerBindingType::NonFiltering
        }),
        BindingKind::ComparisonSampler => {
            wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison)
        }
    };
    Ok(wgpu::BindGroupLayoutEntry {
        binding: b.binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty,
        count: None,
    })
}

impl Executor {
    /// Builds the plan: reflects each pass's kernel, checks its dispatch against the device
    /// limits, creates its pipeline, then allocates every resource scatter provides.
    /// `built` holds the plan's kernels (any order); `params` the values of the plan's
    /// formula symbols (`screen.width`, ...).
    ///
    /// # Errors
    ///
    /// [`RuntimeError::LimitExceeded`] for a dispatch or texture beyond the device's limits
    /// (checked before anything is created); [`RuntimeError::Plan`] when the plan and a
    /// kernel disagree (a binding the plan does not describe, an unknown symbol);
    /// [`RuntimeError::Wgpu`] when wgpu rejects a pipeline or resource.
    pub(crate) fn new(
        ctx: &Context,
        plan: Plan,
        built: Vec<BuiltKernel>,
        params: &[(&str, u64)],
    ) -> Result<Self, RuntimeError> {
        let device = ctx.device();
        let limits = device.limits();
        let first = plan.passes.first().map_or(Kernel::RowPrefix, |p| p.kernel);
        let eval32 = |kernel: Kernel, formula: &str| -> Result<u32, RuntimeError> {
            let v = plan::eval(formula, params).map_err(|m| plan_error(kernel, m))?;
            u32::try_from(v).map_err(|_| {
                plan_error(kernel, format!("formula `{formula}` = {v} exceeds 32 bits"))
            })
        };

        // Checks first: reflection, dispatch limits, texture limits. Nothing is created yet.
        let mut staged = Vec::with_capacity(plan.passes.len());
        let mut built = built;
        for pass in &plan.passes {
            let kernel = pass.kernel;
            let index = built
                .iter()
                .position(|b| b.kernel == kernel)
                .ok_or_else(|| {
                    plan_error(
                        kernel,
                        "the plan has a pass but no kernel was built for it".into(),
                    )
                })?;
            let b = built.swap_remove(index);
            let reflection = reflect::reflect(&b.module, &b.info, b.entry_point)
                .map_err(|m| plan_error(kernel, format!("reflection failed: {m}")))?;
            for binding in &reflection.bindings {
                if binding.group != 0 {
                    return Err(plan_error(
                        kernel,
                        format!(
                            "binding {} is in group {}; plans bind group 0 only",
                            binding.binding, binding.group
                        ),
                    ));
                }
                if sources(pass, binding.binding).next().is_none() {
                    return Err(plan_error(
                        kernel,
                        format!(
                            "the kernel uses binding {} ({}), which the plan does not bind",
                            binding.binding, binding.name
                        ),
                    ));
                }
            }
            let invocations = [
                eval32(kernel, &pass.invocations[0])?,
                eval32(kernel, &pass.invocations[1])?,
                eval32(kernel, &pass.invocations[2])?,
            ];
            check_dispatch(&limits, &b, invocations)?;
            let workgroups = groups(invocations, b.workgroup_size);
            staged.push((b, reflection.bindings, workgroups));
        }
        let mut sizes = Vec::new();
        for r in plan.resources.iter().filter(|r| r.provided_by == "scatter") {
            if let Some(t) = &r.texture {
                let size = [
                    eval32(first, &t.width)?,
                    eval32(first, &t.height)?,
                    eval32(first, &t.layers)?,
                ];
                for (what, value, limit, max) in [
                    (
                        "texture width",
                        size[0],
                        "max_texture_dimension_2d",
                        limits.max_texture_dimension_2d,
                    ),
                    (
                        "texture height",
                        size[1],
                        "max_texture_dimension_2d",
                        limits.max_texture_dimension_2d,
                    ),
                    (
                        "texture layers",
                        size[2],
                        "max_texture_array_layers",
                        limits.max_texture_array_layers,
                    ),
                ] {
                    check_limit(first, what, value.into(), limit, max.into())?;
                }
                sizes.push(size);
            }
        }

        // Pipelines, layouts from the reflected bindings.
        let mut passes = Vec::with_capacity(staged.len());
        for (pass, (b, bindings, workgroups)) in plan.passes.iter().zip(staged) {
            let entries = bindings
                .iter()
                .map(|binding| {
                    layout_entry(pass.kernel, binding, |at| {
                        sources(pass, at)
                            .filter_map(|name| plan.resource(name).and_then(|r| r.sampler.as_ref()))
                            .any(|s| s.mag_filter == "linear" || s.min_filter == "linear")
                    })
                })
                .collect::<Result<Vec<_>, _>>()?;
            let pipeline = create_pipeline(device, b, &entries)?;
            passes.push(ExecPass {
                plan: pass.clone(),
                pipeline,
                bindings,
                workgroups,
            });
        }

        // Resources.
        let scope = ErrorScopes::push(device);
        let mut owned = Vec::new();
        let mut sizes = sizes.into_iter();
        for r in plan.resources.iter().filter(|r| r.provided_by == "scatter") {
            let made = Self::allocate(device, params, &passes, r, &mut sizes)?;
            owned.push((r.name, made));
        }
        scope.pop(first, "creating textures and buffers")?;
        let timer = GpuTimer::with_passes(ctx, passes.len() as u32);
        Ok(Self {
            plan,
            passes,
            owned,
            timer,
        })
    }

    fn allocate(
        device: &wgpu::Device,
        params: &[(&str, u64)],
        passes: &[ExecPass],
        r: &Resource,
        sizes: &mut impl Iterator<Item = [u32; 3]>,
    ) -> Result<Owned, RuntimeError> {
        let first = passes.first().map_or(Kernel::RowPrefix, |p| p.plan.kernel);
        let label = Some(r.name);
        // The reflected bindings that get this resource, with their pass.
        let uses = || {
            passes.iter().flat_map(move |p| {
                p.bindings
                    .iter()
                    .filter(move |b| sources(&p.plan, b.binding).any(|n| n == r.name))
            })
        };
        if let Some(t) = &r.texture {
            let [width, height, layers] = sizes
                .next()
                .ok_or_else(|| plan_error(first, format!("no size for texture `{}`", r.name)))?;
            let format = texture_format(&t.format).ok_or_else(|| {
                plan_error(
                    first,
                    format!(
                        "texture `{}` has format `{}`, which the runtime does not map",
                        r.name, t.format
                    ),
                )
            })?;
            // COPY_SRC beyond the plan's usages: the runtime reads outputs back.
            let mut usage = wgpu::TextureUsages::COPY_SRC;
            for u in &t.usage {
                usage |= match *u {
                    "texture_binding" => wgpu::TextureUsages::TEXTURE_BINDING,
                    "storage_binding" => wgpu::TextureUsages::STORAGE_BINDING,
                    "copy_dst" => wgpu::TextureUsages::COPY_DST,
                    "copy_src" => wgpu::TextureUsages::COPY_SRC,
                    "render_attachment" => wgpu::TextureUsages::RENDER_ATTACHMENT,
                    other => {
                        return Err(plan_error(
                            first,
                            format!("texture `{}` has usage `{other}`", r.name),
                        ));
                    }
                };
            }
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label,
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: layers,
                },
                mip_level_count: t.mip_levels,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            });
            let mut views: Vec<(wgpu::TextureViewDimension, wgpu::TextureView)> = Vec::new();
            for b in uses() {
                let Some(dim) = b.view_dimension.and_then(view_dimension) else {
                    continue;
                };
                if !views.iter().any(|(d, _)| *d == dim) {
                    // A one-layer texture defaults to a D2 view: name the dimension.
                    let view = texture.create_view(&wgpu::TextureViewDescriptor {
                        label,
                        dimension: Some(dim),
                        ..wgpu::TextureViewDescriptor::default()
                    });
                    views.push((dim, view));
                }
            }
            if views.is_empty() {
                let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
                views.push((wgpu::TextureViewDimension::D2, view));
            }
            return Ok(Owned::Texture { texture, views });
        }
        if let Some(buf) = &r.buffer {
            let reflected = uses().next().ok_or_else(|| {
                plan_error(
                    first,
                    format!(
                        "buffer `{}` is bound by no pass, so its size is unknown",
                        r.name
                    ),
                )
            })?;
            let size = match (&buf.elements, reflected.array_stride) {
                (Some(elements), Some(stride)) => plan::eval(elements, params)
                    .map_err(|m| plan_error(first, m))?
                    .checked_mul(stride.into())
                    .ok_or_else(|| plan_error(first, format!("buffer `{}` overflows", r.name)))?,
                _ => reflected.min_binding_size.map_or(0, u64::from),
            };
            let mut usage = wgpu::BufferUsages::empty();
            for u in &buf.usage {
                usage |= match *u {
                    "uniform" => wgpu::BufferUsages::UNIFORM,
                    "storage" => wgpu::BufferUsages::STORAGE,
                    "copy_dst" => wgpu::BufferUsages::COPY_DST,
                    "copy_src" => wgpu::BufferUsages::COPY_SRC,
                    "indirect" => wgpu::BufferUsages::INDIRECT,
                    other => {
                        return Err(plan_error(
                            first,
                            format!("buffer `{}` has usage `{other}`", r.name),
                        ));
                    }
                };
            }
            return Ok(Owned::Buffer(device.create_buffer(
                &wgpu::BufferDescriptor {
                    label,
                    size,
                    usage,
                    mapped_at_creation: false,
                },
            )));
        }
        if let Some(s) = &r.sampler {
            let bad = |what: &str| plan_error(first, format!("sampler `{}` has {what}", r.name));
            let address = |name: &str| address_mode(name).ok_or_else(|| bad(name));
            let filter = |name: &str| filter_mode(name).ok_or_else(|| bad(name));
            return Ok(Owned::Sampler(device.create_sampler(
                &wgpu::SamplerDescriptor {
                    label,
                    address_mode_u: address(s.address_mode_u)?,
                    address_mode_v: address(s.address_mode_v)?,
                    address_mode_w: address(s.address_mode_w)?,
                    mag_filter: filter(s.mag_filter)?,
                    min_filter: filter(s.min_filter)?,
                    mipmap_filter:
                        mipmap_filter_mode(s.mipmap_filter).ok_or_else(|| bad(s.mipmap_filter))?,
                    ..wgpu::SamplerDescriptor::default()
                },
            )));
        }
        Err(plan_error(
            first,
            format!(
                "resource `{}` is neither a texture, a buffer nor a sampler",
                r.name
            ),
        ))
    }

    /// The GPU timer (one slot per pass, in plan order), when the device has timestamps.
    pub(crate) fn timer(&self) -> Option<&GpuTimer> {
        self.timer.as_ref()
    }

    fn owned(&self, name: &str) -> Option<&Owned> {
        self.owned.iter().find(|(n, _)| *n == name).map(|(_, o)| o)
    }

    /// An allocated buffer, or `None` when the plan allocates none of that name.
    pub(crate) fn buffer_if_any(&self, name: &str) -> Option<&wgpu::Buffer> {
        match self.owned(name) {
            Some(Owned::Buffer(b)) => Some(b),
            _ => None,
        }
    }

    /// An allocated buffer.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::Plan`] when the plan allocates no buffer of that name.
    pub(crate) fn buffer(&self, name: &str) -> Result<&wgpu::Buffer, RuntimeError> {
        match self.owned(name) {
            Some(Owned::Buffer(b)) => Ok(b),
            _ => Err(self.missing(name, "buffer")),
        }
    }

    /// An allocated texture and its default view (the dimension the passes bind it with).
    ///
    /// # Errors
    ///
    /// [`RuntimeError::Plan`] when the plan allocates no texture of that name.
    pub(crate) fn texture(
        &self,
        name: &str,
    ) -> Result<(&wgpu::Texture, &wgpu::TextureView), RuntimeError> {
        match self.owned(name) {
            Some(Owned::Texture { texture, views }) => views
                .first()
                .map(|(_, v)| (texture, v))
                .ok_or_else(|| self.missing(name, "texture view")),
            _ => Err(self.missing(name, "texture")),
        }
    }

    fn missing(&self, name: &str, what: &str) -> RuntimeError {
        let kernel = self
            .passes
            .first()
            .map_or(Kernel::RowPrefix, |p| p.plan.kernel);
        plan_error(kernel, format!("the plan allocates no {what} `{name}`"))
    }

    /// Records the passes in plan order: every pass, or only `only`'s. `engine` gives the
    /// engine's textures by resource name; `conditions` the plan conditions that hold this
    /// frame (a pass whose `skip_when` holds does not run; a binding whose alternative's
    /// `when` holds gets the alternative). With `timestamps` (and a device that has them)
    /// each pass writes its timestamps into its slot of [`Self::timer`], resolved at the end.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::MissingInput`] when an engine texture a pass binds is not in
    /// `engine`; [`RuntimeError::Wgpu`] when wgpu rejects a bind group.
    pub(crate) fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        engine: &[(&str, &wgpu::TextureView)],
        conditions: &[&str],
        only: Option<Kernel>,
    ) -> Result<(), RuntimeError> {
        let timestamps = only.is_none();
        for (index, pass) in (0u32..).zip(&self.passes) {
            let kernel = pass.plan.kernel;
            if pass.plan.skip_when.is_some_and(|c| conditions.contains(&c))
                || only.is_some_and(|k| k != kernel)
            {
                continue;
            }
            let mut entries = Vec::with_capacity(pass.bindings.len());
            for b in &pass.bindings {
                let source = pass
                    .plan
                    .bindings
                    .iter()
                    .find(|s| s.binding == b.binding)
                    .ok_or_else(|| {
                        plan_error(kernel, format!("binding {} is not in the plan", b.binding))
                    })?;
                let name = source.resource_for(conditions);
                let resource = match self.owned(name) {
                    Some(Owned::Buffer(buffer)) => buffer.as_entire_binding(),
                    Some(Owned::Sampler(sampler)) => wgpu::BindingResource::Sampler(sampler),
                    Some(Owned::Texture { views, .. }) => {
                        let dim = b.view_dimension.and_then(view_dimension);
                        let view = views
                            .iter()
                            .find(|(d, _)| Some(*d) == dim)
                            .or(views.first())
                            .map(|(_, v)| v)
                            .ok_or_else(|| self.missing(name, "texture view"))?;
                        wgpu::BindingResource::TextureView(view)
                    }
                    None => {
                        let view = engine
                            .iter()
                            .find(|(n, _)| *n == name)
                            .map(|(_, v)| *v)
                            .ok_or_else(|| RuntimeError::MissingInput {
                                kernel,
                                what: self
                                    .plan
                                    .resource(name)
                                    .map_or("a texture the plan does not describe", |r| r.contents),
                            })?;
                        wgpu::BindingResource::TextureView(view)
                    }
                };
                entries.push(wgpu::BindGroupEntry {
                    binding: b.binding,
                    resource,
                });
            }
            let scope = ErrorScopes::push(device);
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(kernel.name()),
                layout: &pass.pipeline.layout,
                entries: &entries,
            });
            scope.pop(kernel, "creating the bind group")?;
            let writes = if timestamps {
                self.timer.as_ref().and_then(|t| t.pass_writes(index))
            } else {
                None
            };
            let mut cpass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(kernel.name()),
                timestamp_writes: writes,
            });
            cpass.set_pipeline(&pass.pipeline.pipeline);
            cpass.set_bind_group(0, &group, &[]);
            if let Some(indirect) = pass.plan.indirect {
                // Workgroup counts an earlier pass wrote (`pass.workgroups` is their most).
                match self.owned(indirect.buffer) {
                    Some(Owned::Buffer(buffer)) => {
                        cpass.dispatch_workgroups_indirect(buffer, indirect.offset_bytes);
                    }
                    _ => return Err(self.missing(indirect.buffer, "indirect dispatch buffer")),
                }
            } else {
                let [x, y, z] = pass.workgroups;
                cpass.dispatch_workgroups(x, y, z);
            }
        }
        if let Some(timer) = self.timer.as_ref().filter(|_| timestamps) {
            timer.resolve(encoder);
        }
        Ok(())
    }
}
