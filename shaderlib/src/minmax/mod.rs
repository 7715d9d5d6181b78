//! The `minmax` family (Chen et al. 2011): the askama views of `templates/minmax_build.wgsl`
//! and `templates/minmax_traverse.wgsl` and their rendering from a [`MinmaxVariant`]. The
//! family's first pass is the prefiltered family's `rectify`
//! ([`crate::KernelParams::minmax`] lists it with [`MinmaxVariant::prefiltered`]). CPU
//! mirrors: `reference/src/kernels/{minmax_build,minmax_traverse}.rs`. Host-side knobs, tree
//! layout and frame set-up: [`scatter_frame::minmax`] (re-exported here).

pub mod plan;

use askama::Template;

use crate::sampling::{SamplingView, camera_expr, unwarp_only};

pub use scatter_frame::minmax::{
    MinmaxVariant, level_count, level_offset, prepare_minmax, tree_levels, tree_width,
};

use crate::compose::template_path;
use crate::prefiltered::LightKind;
use crate::{Kernel, ShaderError};

/// Workgroup size of `minmax_build`: one workgroup of 128 invocations per rectified row
/// (`LANES` in the template).
pub const BUILD_WORKGROUP_SIZE: [u32; 3] = [BUILD_LANES, 1, 1];

/// Invocations of `minmax_build` per rectified row: the row is cut into this many blocks of
/// a power-of-two side.
pub const BUILD_LANES: u32 = 128;

/// Workgroup size of `minmax_traverse`: one invocation per pixel.
pub const MARCH_WORKGROUP_SIZE: [u32; 3] = [8, 8, 1];

/// Format of the min-max tree texture (r = min, g = max).
pub const TREE_FORMAT: &str = "rg32float";

/// `minmax_build`: the per-row trees (the same code for every variant).
#[derive(Template)]
#[template(path = "minmax_build.wgsl")]
struct BuildTemplate {}

/// `minmax_traverse`: the per-pixel hierarchical march.
#[derive(Template)]
#[template(path = "minmax_traverse.wgsl")]
struct TraverseTemplate {
    light_name: &'static str,
    spot: bool,
    cookie: bool,
    sampling: SamplingView,
}

/// `minmax_traverse_unwarp`: `minmax_traverse.wgsl` rendered as the epipolar unwarp.
#[derive(Template)]
#[template(path = "minmax_traverse_unwarp.wgsl")]
struct TraverseUnwarpTemplate {
    light_name: &'static str,
    spot: bool,
    cookie: bool,
    sampling: SamplingView,
}

/// `minmax_traverse_fallback`: `minmax_traverse.wgsl` rendered as the epipolar fallback.
#[derive(Template)]
#[template(path = "minmax_traverse_fallback.wgsl")]
struct TraverseFallbackTemplate {
    light_name: &'static str,
    spot: bool,
    cookie: bool,
    sampling: SamplingView,
}

/// The sampling view of `kernel` (`minmax_traverse`, its `_unwarp` or its `_fallback`) for
/// `variant`.
fn sampling_view(variant: &MinmaxVariant, kernel: Kernel) -> SamplingView {
    SamplingView::new(
        &variant.sampling_knobs(),
        kernel,
        Kernel::MinmaxTraverse,
        camera_expr("frame.axis.xyz"),
        6,
    )
}

fn validate(kernel: Kernel, variant: &MinmaxVariant) -> Result<(), ShaderError> {
    variant
        .validate()
        .map_err(|source| ShaderError::Variant { kernel, source })
}

/// Renders `templates/minmax_build.wgsl` (the same code for every variant).
pub(crate) fn render_build(variant: &MinmaxVariant) -> Result<String, ShaderError> {
    validate(Kernel::MinmaxBuild, variant)?;
    BuildTemplate {}
        .render()
        .map_err(|source| ShaderError::Render {
            kernel: Kernel::MinmaxBuild,
            template: template_path(Kernel::MinmaxBuild),
            source,
        })
}

/// Renders `templates/minmax_traverse.wgsl` for `variant` (only the light changes the code).
pub(crate) fn render_traverse(variant: &MinmaxVariant) -> Result<String, ShaderError> {
    validate(Kernel::MinmaxTraverse, variant)?;
    TraverseTemplate {
        light_name: variant.light.name(),
        spot: variant.light == LightKind::Spot,
        cookie: variant.cookie,
        sampling: sampling_view(variant, Kernel::MinmaxTraverse),
    }
    .render()
    .map_err(|source| ShaderError::Render {
        kernel: Kernel::MinmaxTraverse,
        template: template_path(Kernel::MinmaxTraverse),
        source,
    })
}

/// Renders `templates/minmax_traverse_unwarp.wgsl` for an `epipolar` variant (an error for
/// the others, which have no such pass).
pub(crate) fn render_traverse_unwarp(variant: &MinmaxVariant) -> Result<String, ShaderError> {
    validate(Kernel::MinmaxTraverseUnwarp, variant)?;
    unwarp_only(Kernel::MinmaxTraverseUnwarp, variant.sampling)?;
    TraverseUnwarpTemplate {
        light_name: variant.light.name(),
        spot: variant.light == LightKind::Spot,
        cookie: variant.cookie,
        sampling: sampling_view(variant, Kernel::MinmaxTraverseUnwarp),
    }
    .render()
    .map_err(|source| ShaderError::Render {
        kernel: Kernel::MinmaxTraverseUnwarp,
        template: template_path(Kernel::MinmaxTraverseUnwarp),
        source,
    })
}

/// Renders `templates/minmax_traverse_fallback.wgsl` for an `epipolar` variant (an error
/// for the others, which have no such pass).
pub(crate) fn render_traverse_fallback(variant: &MinmaxVariant) -> Result<String, ShaderError> {
    validate(Kernel::MinmaxTraverseFallback, variant)?;
    unwarp_only(Kernel::MinmaxTraverseFallback, variant.sampling)?;
    TraverseFallbackTemplate {
        light_name: variant.light.name(),
        spot: variant.light == LightKind::Spot,
        cookie: variant.cookie,
        sampling: sampling_view(variant, Kernel::MinmaxTraverseFallback),
    }
    .render()
    .map_err(|source| ShaderError::Render {
        kernel: Kernel::MinmaxTraverseFallback,
        template: template_path(Kernel::MinmaxTraverseFallback),
        source,
    })
}

impl crate::KernelParams {
    /// The kernels of a minmax-family variant, in pass order: the prefiltered family's
    /// `depth_columns`, `slice_fit` and `rectify` (of [`MinmaxVariant::prefiltered`]),
    /// `minmax_build`, `minmax_traverse`.
    pub fn minmax(variant: MinmaxVariant) -> [Self; 5] {
        [
            Self::DepthColumns(variant.prefiltered()),
            Self::SliceFit(variant.prefiltered()),
            Self::Rectify(variant.prefiltered()),
            Self::MinmaxBuild(variant),
            Self::MinmaxTraverse(variant),
        ]
    }
}

impl crate::family::KernelFamily for MinmaxVariant {
    fn kernel_params(&self) -> Vec<crate::KernelParams> {
        let mut out = crate::KernelParams::minmax(*self).to_vec();
        if self.sampling != crate::sampling::Sampling::Pixels {
            out.push(crate::KernelParams::MinmaxTraverseUnwarp(*self));
            out.push(crate::KernelParams::MinmaxTraverseFallback(*self));
        }
        out
    }

    fn plan(&self) -> crate::plan::Plan {
        plan::plan(self)
    }

    fn with_most_passes() -> Self {
        Self::default()
    }
}
