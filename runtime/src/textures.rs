//! Texture helpers for tools and tests that drive the passes directly (the bench): upload
//! an r32float image or a spot's cookie, read back an rgba16float one.

use scatter_shaderlib::Kernel;

use crate::error::{ErrorScopes, check_limit};
use crate::gpu::{DEPTH_FORMAT, Readback, decode_rgba};
use crate::{Context, RuntimeError};

/// The checks before an upload of `len` texels as a `size` texture named `label`: no zero
/// side, no side beyond the device's `max_texture_dimension_2d`, `len` texels exactly.
fn check_upload(
    ctx: &Context,
    kernel: Kernel,
    label: &str,
    size: [u32; 2],
    len: usize,
) -> Result<(), RuntimeError> {
    if size[0] == 0 || size[1] == 0 {
        return Err(RuntimeError::EmptyInput {
            kernel,
            size: format!("{label} {}x{}", size[0], size[1]),
        });
    }
    let max_2d = u64::from(ctx.device().limits().max_texture_dimension_2d);
    for (what, side) in [("texture width", size[0]), ("texture height", size[1])] {
        check_limit(
            kernel,
            what,
            side.into(),
            "max_texture_dimension_2d",
            max_2d,
        )?;
    }
    let expected = u64::from(size[0]) * u64::from(size[1]);
    if len as u64 != expected {
        return Err(RuntimeError::DataLength {
            kernel,
            size: format!("{label} {}x{}", size[0], size[1]),
            expected,
            actual: len as u64,
        });
    }
    Ok(())
}

/// Creates an r32float texture (`TEXTURE_BINDING | COPY_DST | COPY_SRC`) holding `data`
/// (`size[0] * size[1]` values, row-major from the top-left texel).
///
/// # Errors
///
/// [`RuntimeError::EmptyInput`] for a zero width or height;
/// [`RuntimeError::LimitExceeded`] for a side beyond the device's
/// `max_texture_dimension_2d`; [`RuntimeError::DataLength`] when `data` does not match
/// `size`; [`RuntimeError::Wgpu`] when wgpu rejects the texture. Nothing is created unless
/// the checks pass.
pub fn upload_r32float(
    ctx: &Context,
    kernel: Kernel,
    label: &str,
    size: [u32; 2],
    data: &[f32],
) -> Result<wgpu::Texture, RuntimeError> {
    check_upload(ctx, kernel, label, size, data.len())?;
    let scope = ErrorScopes::push(ctx.device());
    let extent = wgpu::Extent3d {
        width: size[0],
        height: size[1],
        depth_or_array_layers: 1,
    };
    let texture = ctx.device().create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: extent,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: DEPTH_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    ctx.queue().write_texture(
        texture.as_image_copy(),
        bytemuck::cast_slice(data),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(size[0] * 4),
            rows_per_image: Some(size[1]),
        },
        extent,
    );
    scope.pop(kernel, "uploading a texture")?;
    Ok(texture)
}

/// Reads back an rgba16float texture (one layer) as f32, row-major.
///
/// # Errors
///
/// [`RuntimeError::Poll`], [`RuntimeError::Readback`] or [`RuntimeError::Wgpu`].
pub fn read_rgba16float(
    ctx: &Context,
    kernel: Kernel,
    texture: &wgpu::Texture,
) -> Result<Vec<[f32; 4]>, RuntimeError> {
    let mut encoder = ctx
        .device()
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("read_rgba16float"),
        });
    let scope = ErrorScopes::push(ctx.device());
    let readback = Readback::encode(ctx.device(), &mut encoder, texture, 8, kernel)?;
    ctx.queue().submit([encoder.finish()]);
    scope.pop(kernel, "reading back a texture")?;
    Ok(readback
        .read(ctx, kernel)?
        .chunks_exact(8)
        .map(|t| decode_rgba(t, scatter_shaderlib::prefiltered::Storage::Rgba16float))
        .collect())
}

/// The formats a spot's `cookie` texture may have: the kernels load its texels and filter
/// them themselves, so any float format with RGB channels binds.
pub const COOKIE_FORMATS: [wgpu::TextureFormat; 4] = [
    wgpu::TextureFormat::Rgba16Float,
    wgpu::TextureFormat::Rgba8Unorm,
    wgpu::TextureFormat::Rgba8UnormSrgb,
    wgpu::TextureFormat::Rgba32Float,
];

/// Uploads a spot's cookie (`scatter_shaderlib::cookie`: linear RGB, row-major from the
/// top-left, alpha ignored) as the `rgba16float` texture the plans declare.
///
/// # Errors
///
/// [`RuntimeError::EmptyInput`] for a zero side, [`RuntimeError::LimitExceeded`] beyond the
/// device's texture size, [`RuntimeError::DataLength`] when `texels` does not hold
/// `size[0] * size[1]` values, [`RuntimeError::Wgpu`] when wgpu rejects it.
pub fn upload_cookie(
    ctx: &Context,
    kernel: Kernel,
    size: [u32; 2],
    texels: &[[f32; 4]],
) -> Result<wgpu::Texture, RuntimeError> {
    let label = "cookie";
    check_upload(ctx, kernel, label, size, texels.len())?;
    let halves: Vec<u16> = texels
        .iter()
        .flatten()
        .map(|c| half::f16::from_f32(*c).to_bits())
        .collect();
    let scope = ErrorScopes::push(ctx.device());
    let extent = wgpu::Extent3d {
        width: size[0],
        height: size[1],
        depth_or_array_layers: 1,
    };
    let texture = ctx.device().create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: extent,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba16Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    ctx.queue().write_texture(
        texture.as_image_copy(),
        bytemuck::cast_slice(&halves),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(size[0] * 8),
            rows_per_image: Some(size[1]),
        },
        extent,
    );
    scope.pop(kernel, "uploading the cookie")?;
    Ok(texture)
}

/// Checks an engine's cookie view: a 2D texture of one of [`COOKIE_FORMATS`] with
/// `TEXTURE_BINDING` usage.
///
/// # Errors
///
/// [`RuntimeError::InputMismatch`] naming what differs.
pub fn check_cookie(kernel: Kernel, view: &wgpu::TextureView) -> Result<(), RuntimeError> {
    let texture = view.texture();
    let mismatch = |what, expected: String, actual: String| {
        Err(RuntimeError::InputMismatch {
            kernel,
            what,
            expected,
            actual,
        })
    };
    if !COOKIE_FORMATS.contains(&texture.format()) {
        return mismatch(
            "cookie format",
            format!("one of {COOKIE_FORMATS:?}"),
            format!("{:?}", texture.format()),
        );
    }
    if texture.dimension() != wgpu::TextureDimension::D2 || texture.depth_or_array_layers() != 1 {
        return mismatch(
            "cookie dimension",
            "a 2D texture with one layer".into(),
            format!(
                "{:?} with {} layers",
                texture.dimension(),
                texture.depth_or_array_layers()
            ),
        );
    }
    if !texture
        .usage()
        .contains(wgpu::TextureUsages::TEXTURE_BINDING)
    {
        return mismatch(
            "cookie usage",
            "TEXTURE_BINDING".into(),
            format!("{:?}", texture.usage()),
        );
    }
    Ok(())
}
