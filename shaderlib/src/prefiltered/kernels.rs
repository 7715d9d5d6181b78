//! The askama views of the prefiltered family's templates (`templates/depth_columns.wgsl`,
//! `templates/slice_fit.wgsl`,
//! `templates/rectify.wgsl`, `templates/prefilter.wgsl`, `templates/scatter.wgsl`) and their
//! rendering from a [`PrefilteredVariant`]. CPU mirrors:
//! `reference/src/kernels/{depth_columns,slice_fit,rectify,prefilter,scatter}.rs`.
//!
//! Every value the templates print is computed here (plain numbers, booleans and names);
//! the templates do no arithmetic or string building.

use askama::Template;

use crate::sampling::{SamplingView, camera_expr, unwarp_only};

use super::variant::{
    Basis, LightKind, PrefilteredVariant, Rectification, Storage, VisibilityMode,
};
use crate::compose::template_path;
use crate::{Kernel, ShaderError};

/// Workgroup size of `depth_columns`: one workgroup per screen row.
pub const DEPTH_COLUMNS_WORKGROUP_SIZE: [u32; 3] = [64, 1, 1];
/// Workgroup size of `slice_fit`: its one workgroup (the dispatch is `(1, 1, 1)`).
pub const SLICE_FIT_WORKGROUP_SIZE: [u32; 3] = [256, 1, 1];
/// Workgroup size of `rectify`: one invocation per rectified texel.
pub const RECTIFY_WORKGROUP_SIZE: [u32; 3] = [8, 8, 1];
/// Workgroup size of `prefilter`: one invocation per (row, region, thread).
pub const PREFILTER_WORKGROUP_SIZE: [u32; 3] = [64, 1, 1];
/// Workgroup size of `scatter`: one invocation per screen pixel.
pub const SCATTER_WORKGROUP_SIZE: [u32; 3] = [8, 8, 1];

/// `depth_columns`: the deepest pixel of every screen row.
#[derive(Template)]
#[template(path = "depth_columns.wgsl")]
struct DepthColumnsTemplate {}

/// `slice_fit`: every row's column spacing fitted to the deepest pixel.
#[derive(Template)]
#[template(path = "slice_fit.wgsl")]
struct SliceFitTemplate {
    light_name: &'static str,
    spot: bool,
}

/// Rectified columns each `rectify` invocation stores (the plans' invocation count is
/// `ceil(rectified.width / RECTIFY_TEXELS)`): its row's constants once, and lavapipe's
/// per-invocation cost shared.
pub const RECTIFY_TEXELS: u32 = 8;

/// `rectify`: epipolar resampling of the standard shadow map.
#[derive(Template)]
#[template(path = "rectify.wgsl")]
struct RectifyTemplate {
    light_name: &'static str,
    spot: bool,
    texels: u32,
}

/// The WGSL element of the `filtered` storage buffer for a storage format: one layer of one
/// rectified texel, the bits of one texel of that format (`include/prefiltered_buffers.wgsl`).
pub const fn filtered_word(storage: Storage) -> &'static str {
    match storage {
        Storage::Rgba8unorm => "u32",
        Storage::Rgba16float => "vec2<u32>",
        Storage::Rgba32float => "vec4<f32>",
    }
}

/// Whether the `filtered` storage buffer holds each layer column-major (element
/// `(layer * Wr + x) * Hr + row`: 4- and 8-byte elements, `prefilter`'s lanes, one row each,
/// store side by side) or row-major (`(layer * Hr + row) * Wr + x`: rgba32float, whose
/// 16-byte elements `prefilter` stored twice as slowly column-major on lavapipe).
pub const fn filtered_column_major(storage: Storage) -> bool {
    !matches!(storage, Storage::Rgba32float)
}

/// Bytes of one layer of one rectified texel in the `filtered` storage buffer.
pub const fn filtered_word_bytes(storage: Storage) -> u32 {
    match storage {
        Storage::Rgba8unorm => 4,
        Storage::Rgba16float => 8,
        Storage::Rgba32float => 16,
    }
}

/// `prefilter`: basis transform (Fourier or power moments) and weighted running mean per row
/// and region.
#[derive(Template)]
#[template(path = "prefilter.wgsl")]
struct PrefilterTemplate {
    light_name: &'static str,
    visibility_name: &'static str,
    storage: &'static str,
    filtered_word: &'static str,
    spot: bool,
    weighted: bool,
    bases: u32,
    layers: u32,
    bases_per_thread: u32,
    layers_per_thread: u32,
    threads_per_row_region: u32,
    regions: u32,
    rectification_name: &'static str,
    projective: bool,
    moments: bool,
    moment_count: u32,
    cookie: bool,
    filtered_layers: u32,
    cbar_layer: u32,
    acc_layers: u32,
    stride: u32,
    resume: bool,
}

/// The askama views of `scatter.wgsl` and of the two epipolar passes that render it with
/// another sampling entry point (`scatter_unwarp.wgsl`, `scatter_fallback.wgsl`): the same
/// fields, one struct per template path.
macro_rules! scatter_templates {
    ($($(#[$doc:meta])* $name:ident($path:literal);)*) => {$(
        $(#[$doc])*
        #[derive(Template)]
        #[template(path = $path)]
        struct $name {
            light_name: &'static str,
            visibility_name: &'static str,
            storage: &'static str,
            filtered_word: &'static str,
            spot: bool,
            bases: u32,
            layers: u32,
            regions: u32,
            rectification_name: &'static str,
            projective: bool,
            moments: bool,
            moment_count: u32,
            cookie: bool,
            filtered_layers: u32,
            cbar_layer: u32,
            stride: u32,
            resume: bool,
            weighted: bool,
            sampling: SamplingView,
        }

        impl $name {
            /// The view of `variant` for `kernel` (`scatter` or one of its epipolar passes).
            fn of(variant: &PrefilteredVariant, kernel: Kernel) -> Self {
                Self {
                    light_name: variant.light.name(),
                    visibility_name: variant.visibility.name(),
                    storage: variant.storage.name(),
                    filtered_word: filtered_word(variant.storage),
                    spot: variant.light == LightKind::Spot,
                    bases: variant.bases,
                    layers: variant.layers(),
                    regions: variant.regions,
                    rectification_name: variant.rectification.name(),
                    projective: variant.rectification == Rectification::Projective,
                    moments: variant.basis == Basis::Moments,
                    moment_count: variant.moments,
                    cookie: variant.cookie,
                    filtered_layers: variant.filtered_layers(),
                    cbar_layer: 3 * variant.layers(),
                    stride: variant.filtered_stride,
                    resume: variant.resume,
                    weighted: variant.visibility == VisibilityMode::Weighted,
                    sampling: scatter_sampling_view(variant, kernel),
                }
            }
        }
    )*};
}

scatter_templates! {
    /// `scatter`: per-pixel prefiltered estimate plus the epipole ray march.
    ScatterTemplate("scatter.wgsl");
    /// `scatter_unwarp`: `scatter.wgsl` rendered as the epipolar unwarp.
    ScatterUnwarpTemplate("scatter_unwarp.wgsl");
    /// `scatter_fallback`: `scatter.wgsl` rendered as the epipolar fallback.
    ScatterFallbackTemplate("scatter_fallback.wgsl");
}

/// Checks `variant` on behalf of `kernel`.
fn validate(kernel: Kernel, variant: &PrefilteredVariant) -> Result<(), ShaderError> {
    variant
        .validate()
        .map_err(|source| ShaderError::Variant { kernel, source })
}

fn render_error(kernel: Kernel) -> impl FnOnce(askama::Error) -> ShaderError {
    move |source| ShaderError::Render {
        kernel,
        template: template_path(kernel),
        source,
    }
}

/// Renders `templates/depth_columns.wgsl` (the same for every variant).
pub(crate) fn render_depth_columns(variant: &PrefilteredVariant) -> Result<String, ShaderError> {
    validate(Kernel::DepthColumns, variant)?;
    DepthColumnsTemplate {}
        .render()
        .map_err(render_error(Kernel::DepthColumns))
}

/// Renders `templates/slice_fit.wgsl` for `variant` (only its light matters).
pub(crate) fn render_slice_fit(variant: &PrefilteredVariant) -> Result<String, ShaderError> {
    validate(Kernel::SliceFit, variant)?;
    SliceFitTemplate {
        light_name: variant.light.name(),
        spot: variant.light == LightKind::Spot,
    }
    .render()
    .map_err(render_error(Kernel::SliceFit))
}

/// Renders `templates/rectify.wgsl` for `variant` (only its light matters).
pub(crate) fn render_rectify(variant: &PrefilteredVariant) -> Result<String, ShaderError> {
    validate(Kernel::Rectify, variant)?;
    RectifyTemplate {
        light_name: variant.light.name(),
        spot: variant.light == LightKind::Spot,
        texels: RECTIFY_TEXELS,
    }
    .render()
    .map_err(render_error(Kernel::Rectify))
}

/// Renders `templates/prefilter.wgsl` for `variant`.
pub(crate) fn render_prefilter(variant: &PrefilteredVariant) -> Result<String, ShaderError> {
    validate(Kernel::Prefilter, variant)?;
    PrefilterTemplate {
        light_name: variant.light.name(),
        visibility_name: variant.visibility.name(),
        storage: variant.storage.name(),
        filtered_word: filtered_word(variant.storage),
        spot: variant.light == LightKind::Spot,
        weighted: variant.visibility == VisibilityMode::Weighted,
        bases: variant.bases,
        layers: variant.layers(),
        bases_per_thread: variant.per_thread(),
        layers_per_thread: variant.per_thread().div_ceil(4),
        threads_per_row_region: variant.threads_per_row_region(),
        regions: variant.regions,
        rectification_name: variant.rectification.name(),
        projective: variant.rectification == Rectification::Projective,
        moments: variant.basis == Basis::Moments,
        moment_count: variant.moments,
        cookie: variant.cookie,
        filtered_layers: variant.filtered_layers(),
        cbar_layer: 3 * variant.layers(),
        acc_layers: 3 * variant.per_thread().div_ceil(4),
        stride: variant.filtered_stride,
        resume: variant.resume,
    }
    .render()
    .map_err(render_error(Kernel::Prefilter))
}

/// Renders `templates/scatter.wgsl` for `variant` (`bases_per_thread` does not matter).
pub(crate) fn render_scatter(variant: &PrefilteredVariant) -> Result<String, ShaderError> {
    validate(Kernel::Scatter, variant)?;
    ScatterTemplate::of(variant, Kernel::Scatter)
        .render()
        .map_err(render_error(Kernel::Scatter))
}

/// The sampling view of `kernel` (`scatter`, `scatter_unwarp` or `scatter_fallback`) for
/// `variant`.
fn scatter_sampling_view(variant: &PrefilteredVariant, kernel: Kernel) -> SamplingView {
    SamplingView::new(
        &variant.sampling_knobs(),
        kernel,
        Kernel::Scatter,
        camera_expr("frame.axis.xyz"),
        7,
    )
}

/// Renders `templates/scatter_unwarp.wgsl` for an `epipolar` variant (an error for the
/// others, which have no such pass).
pub(crate) fn render_scatter_unwarp(variant: &PrefilteredVariant) -> Result<String, ShaderError> {
    validate(Kernel::ScatterUnwarp, variant)?;
    unwarp_only(Kernel::ScatterUnwarp, variant.sampling)?;
    ScatterUnwarpTemplate::of(variant, Kernel::ScatterUnwarp)
        .render()
        .map_err(render_error(Kernel::ScatterUnwarp))
}

/// Renders `templates/scatter_fallback.wgsl` for an `epipolar` variant (an error for the
/// others, which have no such pass).
pub(crate) fn render_scatter_fallback(variant: &PrefilteredVariant) -> Result<String, ShaderError> {
    validate(Kernel::ScatterFallback, variant)?;
    unwarp_only(Kernel::ScatterFallback, variant.sampling)?;
    ScatterFallbackTemplate::of(variant, Kernel::ScatterFallback)
        .render()
        .map_err(render_error(Kernel::ScatterFallback))
}
