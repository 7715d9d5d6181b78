//! The `row_prefix` pass: pipeline, size checks against device limits, encoding, and a
//! one-call upload-dispatch-readback helper ([`row_prefix`]) for tests and tools.

use std::fmt;
use std::time::{Duration, Instant};

use scatter_shaderlib::{Kernel, KernelParams, RowPrefixParams, reflect};

use crate::error::ErrorScopes;
use crate::executor::layout_entry;
use crate::gpu::{Pipeline, create_pipeline};
use crate::timer::read_buffer;
use crate::{Context, GpuTimer, RuntimeError};

const KERNEL: Kernel = Kernel::RowPrefix;
/// Bytes per rgba32float texel.
const TEXEL_BYTES: u32 = 16;
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// Size of a texture array: `width` texels per row, `height` rows, `layers` layers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ArraySize {
    /// Texels per row.
    pub width: u32,
    /// Rows per layer.
    pub height: u32,
    /// Layers.
    pub layers: u32,
}

impl ArraySize {
    /// A size.
    pub const fn new(width: u32, height: u32, layers: u32) -> Self {
        Self {
            width,
            height,
            layers,
        }
    }

    /// Number of texels, `width * height * layers`.
    pub const fn texel_count(&self) -> u64 {
        self.width as u64 * self.height as u64 * self.layers as u64
    }

    /// Row-major index of texel (x, row, layer) in a flat array of [`Self::texel_count`].
    pub const fn index(&self, x: u32, row: u32, layer: u32) -> usize {
        ((layer as usize * self.height as usize) + row as usize) * self.width as usize + x as usize
    }

    fn extent(&self) -> wgpu::Extent3d {
        wgpu::Extent3d {
            width: self.width,
            height: self.height,
            depth_or_array_layers: self.layers,
        }
    }
}

impl fmt::Display for ArraySize {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}x{}", self.width, self.height, self.layers)
    }
}

/// Result of [`row_prefix`].
#[derive(Clone, Debug)]
pub struct RowPrefixOutput {
    /// Output texels, laid out as [`ArraySize::index`].
    pub texels: Vec<[f32; 4]>,
    /// Time between the GPU timestamps at the start and end of the compute pass, when the
    /// device supports timestamps.
    pub gpu_time: Option<Duration>,
    /// Wall time from submission until the results were mapped (includes the copy back).
    pub wall_time: Duration,
}

/// The `row_prefix` compute pipeline for one parameter set.
#[derive(Debug)]
pub struct RowPrefixPass {
    params: RowPrefixParams,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    /// The reflected binding of `input`.
    input_binding: u32,
    /// The reflected binding of `output`.
    output_binding: u32,
}

impl RowPrefixPass {
    /// Builds the kernel with `scatter-shaderlib` and creates its pipeline.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::Shader`] when the kernel does not build,
    /// [`RuntimeError::LimitExceeded`] when the workgroup is larger than the device allows,
    /// [`RuntimeError::Wgpu`] when wgpu rejects the pipeline.
    pub fn new(ctx: &Context, params: RowPrefixParams) -> Result<Self, RuntimeError> {
        let built = scatter_shaderlib::build(&KernelParams::RowPrefix(params))?;
        let limits = ctx.device().limits();
        let [wg_x, _, _] = built.workgroup_size;
        check_limit(
            "workgroup size",
            wg_x.into(),
            "max_compute_invocations_per_workgroup",
            limits.max_compute_invocations_per_workgroup.into(),
        )?;
        check_limit(
            "workgroup size",
            wg_x.into(),
            "max_compute_workgroup_size_x",
            limits.max_compute_workgroup_size_x.into(),
        )?;

        // The bind group layout from the bindings reflected out of the compiled kernel, as
        // the executor builds every family's (no hand-written layout).
        let reflection =
            reflect::reflect(&built.module, &built.info, built.entry_point).map_err(|m| {
                RuntimeError::Plan {
                    kernel: KERNEL,
                    message: format!("reflection failed: {m}"),
                }
            })?;
        let binding_of = |name: &str| {
            reflection
                .bindings
                .iter()
                .find(|b| b.name == name)
                .map(|b| b.binding)
                .ok_or_else(|| RuntimeError::Plan {
                    kernel: KERNEL,
                    message: format!("the kernel has no binding named `{name}`"),
                })
        };
        let input_binding = binding_of("input")?;
        let output_binding = binding_of("output")?;
        let entries = reflection
            .bindings
            .iter()
            .map(|b| layout_entry(KERNEL, b, |_| false))
            .collect::<Result<Vec<_>, _>>()?;
        let Pipeline { layout, pipeline } = create_pipeline(ctx.device(), built, &entries)?;
        Ok(Self {
            params,
            layout,
            pipeline,
            input_binding,
            output_binding,
        })
    }

    /// The parameters the pipeline was built with.
    pub fn params(&self) -> &RowPrefixParams {
        &self.params
    }

    /// Checks a texture array size against the kernel's needs and the device limits.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::EmptyInput`] or [`RuntimeError::LimitExceeded`] naming the limit.
    pub fn check_size(&self, ctx: &Context, size: ArraySize) -> Result<(), RuntimeError> {
        if size.texel_count() == 0 {
            return Err(RuntimeError::EmptyInput {
                kernel: KERNEL,
                size: size.to_string(),
            });
        }
        let limits = ctx.device().limits();
        let max_2d = limits.max_texture_dimension_2d.into();
        check_limit(
            "width",
            size.width.into(),
            "max_texture_dimension_2d",
            max_2d,
        )?;
        check_limit(
            "height",
            size.height.into(),
            "max_texture_dimension_2d",
            max_2d,
        )?;
        check_limit(
            "layers",
            size.layers.into(),
            "max_texture_array_layers",
            limits.max_texture_array_layers.into(),
        )?;
        let [groups_x, groups_y, _] = self.params.dispatch_size(size.height, size.layers);
        let max_groups = limits.max_compute_workgroups_per_dimension.into();
        check_limit(
            "workgroups along x (rows)",
            groups_x.into(),
            "max_compute_workgroups_per_dimension",
            max_groups,
        )?;
        check_limit(
            "workgroups along y (layers)",
            groups_y.into(),
            "max_compute_workgroups_per_dimension",
            max_groups,
        )?;
        check_limit(
            "readback buffer bytes",
            readback_bytes(size),
            "max_buffer_size",
            limits.max_buffer_size,
        )
    }

    /// A bind group for an input view (`texture_2d_array<f32>`, rgba, non-filterable) and an
    /// output view (`rgba32float` storage, `D2Array`) of the same size.
    pub fn bind_group(
        &self,
        ctx: &Context,
        input: &wgpu::TextureView,
        output: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("row_prefix"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: self.input_binding,
                    resource: wgpu::BindingResource::TextureView(input),
                },
                wgpu::BindGroupEntry {
                    binding: self.output_binding,
                    resource: wgpu::BindingResource::TextureView(output),
                },
            ],
        })
    }

    /// Records the pass for an array of `size` (checked with [`Self::check_size`] first).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        bind_group: &wgpu::BindGroup,
        size: ArraySize,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("row_prefix"),
            timestamp_writes,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        let [x, y, z] = self.params.dispatch_size(size.height, size.layers);
        pass.dispatch_workgroups(x, y, z);
    }
}

/// Uploads `input` (texels laid out as [`ArraySize::index`]) as an rgba32float array of
/// `size`, runs `row_prefix` with `params`, and reads the result back.
///
/// # Errors
///
/// Any [`RuntimeError`]: a bad size or data length, a device limit, a wgpu error.
pub fn row_prefix(
    ctx: &Context,
    params: RowPrefixParams,
    size: ArraySize,
    input: &[[f32; 4]],
) -> Result<RowPrefixOutput, RuntimeError> {
    let pass = RowPrefixPass::new(ctx, params)?;
    pass.check_size(ctx, size)?;
    let given = input.len() as u64;
    if given != size.texel_count() {
        return Err(RuntimeError::DataLength {
            kernel: KERNEL,
            size: size.to_string(),
            expected: size.texel_count(),
            actual: given,
        });
    }

    let device = ctx.device();
    let queue = ctx.queue();
    let scope = ErrorScopes::push(device);
    let texture = |label, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: size.extent(),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage,
            view_formats: &[],
        })
    };
    let input_texture = texture(
        "row_prefix input",
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    );
    let output_texture = texture(
        "row_prefix output",
        wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
    );
    // A one-layer texture defaults to a D2 view: ask for D2Array explicitly.
    let array_view = |t: &wgpu::Texture| {
        t.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..wgpu::TextureViewDescriptor::default()
        })
    };
    queue.write_texture(
        input_texture.as_image_copy(),
        bytemuck::cast_slice(input),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(size.width * TEXEL_BYTES),
            rows_per_image: Some(size.height),
        },
        size.extent(),
    );
    let bind_group = pass.bind_group(
        ctx,
        &array_view(&input_texture),
        &array_view(&output_texture),
    );
    let padded_row = padded_row_bytes(size.width);
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("row_prefix readback"),
        size: readback_bytes(size),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let timer = GpuTimer::new(ctx);

    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("row_prefix"),
    });
    pass.encode(
        &mut encoder,
        &bind_group,
        size,
        timer.as_ref().map(GpuTimer::compute_pass_writes),
    );
    encoder.copy_texture_to_buffer(
        output_texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row),
                rows_per_image: Some(size.height),
            },
        },
        size.extent(),
    );
    if let Some(timer) = &timer {
        timer.resolve(&mut encoder);
    }
    let start = Instant::now();
    queue.submit([encoder.finish()]);
    scope.pop(KERNEL, "dispatch")?;

    let bytes = read_buffer(ctx, KERNEL, &readback)?;
    let wall_time = start.elapsed();
    let gpu_time = timer.map(|t| t.read(ctx, KERNEL)).transpose()?;

    let row_bytes = (size.width * TEXEL_BYTES) as usize;
    let mut texels = Vec::with_capacity(input.len());
    for row in bytes.chunks_exact(padded_row as usize) {
        texels.extend(
            row[..row_bytes]
                .chunks_exact(TEXEL_BYTES as usize)
                .map(bytemuck::pod_read_unaligned::<[f32; 4]>),
        );
    }
    Ok(RowPrefixOutput {
        texels,
        gpu_time,
        wall_time,
    })
}

/// Bytes per row of a buffer that a texture row is copied into (256-byte aligned).
const fn padded_row_bytes(width: u32) -> u32 {
    (width * TEXEL_BYTES).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
}

/// Bytes of the readback buffer for a whole array.
fn readback_bytes(size: ArraySize) -> u64 {
    u64::from(padded_row_bytes(size.width)) * u64::from(size.height) * u64::from(size.layers)
}

fn check_limit(
    what: &'static str,
    value: u64,
    limit: &'static str,
    max: u64,
) -> Result<(), RuntimeError> {
    crate::error::check_limit(KERNEL, what, value, limit, max)
}
