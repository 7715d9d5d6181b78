//! The runtime's GPU toolkit that belongs to no family: compute pipelines from built kernels,
//! workgroup counts and device-limit checks of a dispatch, checks of the engine's texture
//! views, texel decoding and texture readback.

use std::borrow::Cow;

use scatter_shaderlib::prefiltered::Storage;
use scatter_shaderlib::{BuiltKernel, Kernel};

use crate::error::{ErrorScopes, check_limit};
use crate::timer::read_buffer;
use crate::{Context, RuntimeError};

/// Format of the depth buffer, the standard shadow map and the rectified map.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
/// Format of every family's output (in-scattered radiance, rgb; alpha 1).
pub const OUTPUT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// One compute pipeline with its bind group layout and workgroup size.
#[derive(Debug)]
pub(crate) struct Pipeline {
    pub(crate) layout: wgpu::BindGroupLayout,
    pub(crate) pipeline: wgpu::ComputePipeline,
}

/// Workgroup counts `ceil(n / size)` of one dispatch.
pub(crate) fn groups(n: [u32; 3], size: [u32; 3]) -> [u32; 3] {
    [0, 1, 2].map(|i| n[i].div_ceil(size[i].max(1)))
}

/// Names of the properties of one engine-provided texture, for [`check_view`].
pub(crate) struct ViewNames {
    format: &'static str,
    size: &'static str,
    usage: &'static str,
}

pub(crate) const DEPTH_NAMES: ViewNames = ViewNames {
    format: "depth buffer format",
    size: "depth buffer size",
    usage: "depth buffer usage",
};

pub(crate) const RECTIFIED_NAMES: ViewNames = ViewNames {
    format: "rasterised rectified map format",
    size: "rasterised rectified map size",
    usage: "rasterised rectified map usage",
};

pub(crate) const SHADOW_NAMES: ViewNames = ViewNames {
    format: "shadow map format",
    size: "shadow map size",
    usage: "shadow map usage",
};

/// Checks an engine-provided r32float texture view: format, size, sampling usage.
pub(crate) fn check_view(
    kernel: Kernel,
    names: &ViewNames,
    view: &wgpu::TextureView,
    size: [u32; 2],
) -> Result<(), RuntimeError> {
    let texture = view.texture();
    let mismatch = |what, expected: String, actual: String| {
        Err(RuntimeError::InputMismatch {
            kernel,
            what,
            expected,
            actual,
        })
    };
    if texture.format() != DEPTH_FORMAT {
        return mismatch(
            names.format,
            format!("{DEPTH_FORMAT:?}"),
            format!("{:?}", texture.format()),
        );
    }
    let extent = texture.size();
    if [extent.width, extent.height] != size {
        return mismatch(
            names.size,
            format!("{}x{}", size[0], size[1]),
            format!("{}x{}", extent.width, extent.height),
        );
    }
    if !texture
        .usage()
        .contains(wgpu::TextureUsages::TEXTURE_BINDING)
    {
        return mismatch(
            names.usage,
            "TEXTURE_BINDING".to_owned(),
            format!("{:?}", texture.usage()),
        );
    }
    Ok(())
}

/// Checks a kernel's workgroup size, and the workgroup counts of a dispatch covering
/// `invocations`, against the device limits.
pub(crate) fn check_dispatch(
    limits: &wgpu::Limits,
    built: &BuiltKernel,
    invocations: [u32; 3],
) -> Result<(), RuntimeError> {
    check_workgroup(limits, built)?;
    let counts = groups(invocations, built.workgroup_size);
    for (count, what) in counts.into_iter().zip([
        "workgroups along x",
        "workgroups along y",
        "workgroups along z",
    ]) {
        check_limit(
            built.kernel,
            what,
            count.into(),
            "max_compute_workgroups_per_dimension",
            limits.max_compute_workgroups_per_dimension.into(),
        )?;
    }
    Ok(())
}

/// Checks a kernel's workgroup size against the device limits.
fn check_workgroup(limits: &wgpu::Limits, built: &BuiltKernel) -> Result<(), RuntimeError> {
    let [x, y, z] = built.workgroup_size;
    let kernel = built.kernel;
    check_limit(
        kernel,
        "workgroup invocations",
        u64::from(x) * u64::from(y) * u64::from(z),
        "max_compute_invocations_per_workgroup",
        limits.max_compute_invocations_per_workgroup.into(),
    )?;
    check_limit(
        kernel,
        "workgroup size x",
        x.into(),
        "max_compute_workgroup_size_x",
        limits.max_compute_workgroup_size_x.into(),
    )?;
    check_limit(
        kernel,
        "workgroup size y",
        y.into(),
        "max_compute_workgroup_size_y",
        limits.max_compute_workgroup_size_y.into(),
    )?;
    check_limit(
        kernel,
        "workgroup size z",
        z.into(),
        "max_compute_workgroup_size_z",
        limits.max_compute_workgroup_size_z.into(),
    )
}

/// Creates a kernel's bind group layout and compute pipeline inside an error scope.
pub(crate) fn create_pipeline(
    device: &wgpu::Device,
    built: BuiltKernel,
    entries: &[wgpu::BindGroupLayoutEntry],
) -> Result<Pipeline, RuntimeError> {
    let kernel = built.kernel;
    let scope = ErrorScopes::push(device);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(kernel.name()),
        source: wgpu::ShaderSource::Naga(Cow::Owned(built.module)),
    });
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(kernel.name()),
        entries,
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(kernel.name()),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(kernel.name()),
        layout: Some(&pipeline_layout),
        module: &module,
        entry_point: Some(built.entry_point),
        compilation_options: wgpu::PipelineCompilationOptions::default(),
        cache: None,
    });
    scope.pop(kernel, "pipeline creation")?;
    Ok(Pipeline { layout, pipeline })
}

/// Decodes one rgba texel of a storage format to f32.
pub(crate) fn decode_rgba(texel: &[u8], storage: Storage) -> [f32; 4] {
    match storage {
        Storage::Rgba8unorm => [0, 1, 2, 3].map(|c| f32::from(texel[c]) / 255.0),
        Storage::Rgba16float => [0, 1, 2, 3].map(|c| {
            half::f16::from_bits(u16::from_le_bytes([texel[2 * c], texel[2 * c + 1]])).to_f32()
        }),
        Storage::Rgba32float => [0, 1, 2, 3].map(|c| {
            f32::from_le_bytes([
                texel[4 * c],
                texel[4 * c + 1],
                texel[4 * c + 2],
                texel[4 * c + 3],
            ])
        }),
    }
}

/// A texture copied into a mappable buffer (rows padded to 256 bytes).
pub(crate) struct Readback {
    buffer: wgpu::Buffer,
    extent: wgpu::Extent3d,
    texel_bytes: u32,
    padded_row: u32,
}

impl Readback {
    /// Records the copy of every layer of `texture` (`texel_bytes` per texel).
    ///
    /// # Errors
    ///
    /// [`RuntimeError::LimitExceeded`] (for `kernel`) when the readback buffer would exceed
    /// the device's `max_buffer_size`; nothing is created then.
    pub(crate) fn encode(
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        texture: &wgpu::Texture,
        texel_bytes: u32,
        kernel: Kernel,
    ) -> Result<Self, RuntimeError> {
        let extent = texture.size();
        let padded_row =
            (extent.width * texel_bytes).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let size = u64::from(padded_row)
            * u64::from(extent.height)
            * u64::from(extent.depth_or_array_layers);
        check_limit(
            kernel,
            "readback buffer bytes",
            size,
            "max_buffer_size",
            device.limits().max_buffer_size,
        )?;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("prefiltered readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded_row),
                    rows_per_image: Some(extent.height),
                },
            },
            extent,
        );
        Ok(Self {
            buffer,
            extent,
            texel_bytes,
            padded_row,
        })
    }

    /// Maps the buffer and returns the texels' bytes without row padding, layer by layer,
    /// row by row.
    pub(crate) fn read(self, ctx: &Context, kernel: Kernel) -> Result<Vec<u8>, RuntimeError> {
        let bytes = read_buffer(ctx, kernel, &self.buffer)?;
        let row_bytes = (self.extent.width * self.texel_bytes) as usize;
        let mut packed = Vec::with_capacity(
            row_bytes * self.extent.height as usize * self.extent.depth_or_array_layers as usize,
        );
        for row in bytes.chunks_exact(self.padded_row as usize) {
            packed.extend_from_slice(&row[..row_bytes]);
        }
        Ok(packed)
    }
}

/// Records the copy of the whole of `buffer` (which needs `COPY_SRC`) into a new mappable
/// buffer; read it with [`crate::timer::read_buffer`] after submitting.
pub(crate) fn encode_buffer_readback(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    buffer: &wgpu::Buffer,
) -> wgpu::Buffer {
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("buffer readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    staging
}

/// The slice table read back after `slice_fit` (16 bytes per row).
pub(crate) fn read_slices(
    ctx: &Context,
    kernel: Kernel,
    staging: &wgpu::Buffer,
) -> Result<Vec<scatter_shaderlib::prefiltered::SliceParams>, RuntimeError> {
    Ok(bytemuck::pod_collect_to_vec(&read_buffer(
        ctx, kernel, staging,
    )?))
}

/// Fails with [`RuntimeError::EmptyInput`] for the first size with a zero dimension; each
/// entry names the kernel to blame and what the size is (`screen`, `shadow map`, ...).
pub(crate) fn check_nonempty(sizes: &[(Kernel, &str, [u32; 2])]) -> Result<(), RuntimeError> {
    for &(kernel, what, [w, h]) in sizes {
        if w == 0 || h == 0 {
            return Err(RuntimeError::EmptyInput {
                kernel,
                size: format!("{what} {w}x{h}"),
            });
        }
    }
    Ok(())
}

/// Checks CPU textures against their sizes and uploads them as r32float textures (test
/// conveniences): one `(texture, view)` per entry `(kernel to blame, what, size, texels)`.
///
/// # Errors
///
/// [`RuntimeError::DataLength`] naming the texture whose length does not match; upload
/// errors.
pub(crate) fn upload_inputs(
    ctx: &Context,
    inputs: &[(Kernel, &str, [u32; 2], &[f32])],
) -> Result<Vec<(wgpu::Texture, wgpu::TextureView)>, RuntimeError> {
    for &(kernel, what, [w, h], data) in inputs {
        let expected = u64::from(w) * u64::from(h);
        if data.len() as u64 != expected {
            return Err(RuntimeError::DataLength {
                kernel,
                size: format!("{what} {w}x{h}"),
                expected,
                actual: data.len() as u64,
            });
        }
    }
    inputs
        .iter()
        .map(|&(kernel, what, size, data)| {
            let texture = crate::textures::upload_r32float(ctx, kernel, what, size, data)?;
            let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
            Ok((texture, view))
        })
        .collect()
}

/// Fails with [`RuntimeError::LimitExceeded`] for the first texture side beyond the device's
/// `max_texture_dimension_2d`; each entry names the kernel to blame and the side.
pub(crate) fn check_texture_sides(
    limits: &wgpu::Limits,
    sides: &[(Kernel, &'static str, u32)],
) -> Result<(), RuntimeError> {
    for &(kernel, what, value) in sides {
        check_limit(
            kernel,
            what,
            value.into(),
            "max_texture_dimension_2d",
            limits.max_texture_dimension_2d.into(),
        )?;
    }
    Ok(())
}
