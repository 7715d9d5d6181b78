//! The `hybrid_volume` family (Wyman & Ramsey 2008): the askama views of
//! `templates/volume_bounds.wgsl` and `templates/volume_march.wgsl` and their rendering from a
//! [`HybridVolumeVariant`]. The family's first passes are the prefiltered family's
//! `depth_columns`, `slice_fit` and `rectify` ([`crate::KernelParams::hybrid_volume`] lists
//! them with [`HybridVolumeVariant::prefiltered`]). CPU mirrors:
//! `reference/src/kernels/{volume_bounds,volume_march}.rs`. Host-side knobs and frame set-up:
//! [`scatter_frame::hybrid_volume`] (re-exported here).

pub mod plan;

use askama::Template;

use crate::sampling::{SamplingView, camera_expr, unwarp_only};

pub use scatter_frame::hybrid_volume::{
    DEFAULT_BINS, DEFAULT_SAMPLES, HybridVolumeVariant, MAX_BINS, MAX_PAD, MAX_SAMPLES, NO_EDGE,
    prepare_hybrid_volume,
};

use crate::compose::template_path;
use crate::prefiltered::LightKind;
use crate::{Kernel, ShaderError};

/// Workgroup size of `volume_bounds`: one workgroup of 64 per rectified row.
pub const BOUNDS_WORKGROUP_SIZE: [u32; 3] = [64, 1, 1];

/// Workgroup size of `volume_march`: one invocation per pixel.
pub const MARCH_WORKGROUP_SIZE: [u32; 3] = [8, 8, 1];

/// `volume_bounds`: the per-row bins of boundary crossings.
#[derive(Template)]
#[template(path = "volume_bounds.wgsl")]
struct BoundsTemplate {
    bins: u32,
}

/// `volume_march` and its epipolar passes: the per-pixel march of the interval.
#[derive(Template)]
#[template(path = "volume_march.wgsl")]
struct MarchTemplate {
    light_name: &'static str,
    spot: bool,
    cookie: bool,
    samples: u32,
    bins: u32,
    pad: u32,
    sampling: SamplingView,
}

/// `volume_march_unwarp`: `volume_march.wgsl` rendered as the epipolar unwarp.
#[derive(Template)]
#[template(path = "volume_march_unwarp.wgsl")]
struct MarchUnwarpTemplate {
    light_name: &'static str,
    spot: bool,
    cookie: bool,
    samples: u32,
    bins: u32,
    pad: u32,
    sampling: SamplingView,
}

/// `volume_march_fallback`: `volume_march.wgsl` rendered as the epipolar fallback.
#[derive(Template)]
#[template(path = "volume_march_fallback.wgsl")]
struct MarchFallbackTemplate {
    light_name: &'static str,
    spot: bool,
    cookie: bool,
    samples: u32,
    bins: u32,
    pad: u32,
    sampling: SamplingView,
}

/// The sampling view of `kernel` (`volume_march`, its `_unwarp` or its `_fallback`).
fn sampling_view(variant: &HybridVolumeVariant, kernel: Kernel) -> SamplingView {
    SamplingView::new(
        &variant.sampling_knobs(),
        kernel,
        Kernel::VolumeMarch,
        camera_expr("frame.axis.xyz"),
        7,
    )
}

fn validate(kernel: Kernel, variant: &HybridVolumeVariant) -> Result<(), ShaderError> {
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

/// Renders `templates/volume_bounds.wgsl` (only the bins change the code).
pub(crate) fn render_bounds(variant: &HybridVolumeVariant) -> Result<String, ShaderError> {
    validate(Kernel::VolumeBounds, variant)?;
    BoundsTemplate { bins: variant.bins }
        .render()
        .map_err(render_error(Kernel::VolumeBounds))
}

/// Renders `templates/volume_march.wgsl` for `variant`.
pub(crate) fn render_march(variant: &HybridVolumeVariant) -> Result<String, ShaderError> {
    let kernel = Kernel::VolumeMarch;
    validate(kernel, variant)?;
    MarchTemplate {
        light_name: variant.light.name(),
        spot: variant.light == LightKind::Spot,
        cookie: variant.cookie,
        samples: variant.samples,
        bins: variant.bins,
        pad: variant.pad,
        sampling: sampling_view(variant, kernel),
    }
    .render()
    .map_err(render_error(kernel))
}

/// Renders `templates/volume_march_unwarp.wgsl` for an `epipolar` variant (an error for the
/// others, which have no such pass).
pub(crate) fn render_march_unwarp(variant: &HybridVolumeVariant) -> Result<String, ShaderError> {
    let kernel = Kernel::VolumeMarchUnwarp;
    validate(kernel, variant)?;
    unwarp_only(kernel, variant.sampling)?;
    MarchUnwarpTemplate {
        light_name: variant.light.name(),
        spot: variant.light == LightKind::Spot,
        cookie: variant.cookie,
        samples: variant.samples,
        bins: variant.bins,
        pad: variant.pad,
        sampling: sampling_view(variant, kernel),
    }
    .render()
    .map_err(render_error(kernel))
}

/// Renders `templates/volume_march_fallback.wgsl` for an `epipolar` variant (an error for
/// the others, which have no such pass).
pub(crate) fn render_march_fallback(variant: &HybridVolumeVariant) -> Result<String, ShaderError> {
    let kernel = Kernel::VolumeMarchFallback;
    validate(kernel, variant)?;
    unwarp_only(kernel, variant.sampling)?;
    MarchFallbackTemplate {
        light_name: variant.light.name(),
        spot: variant.light == LightKind::Spot,
        cookie: variant.cookie,
        samples: variant.samples,
        bins: variant.bins,
        pad: variant.pad,
        sampling: sampling_view(variant, kernel),
    }
    .render()
    .map_err(render_error(kernel))
}

impl crate::KernelParams {
    /// The kernels of a hybrid_volume-family variant, in pass order: the prefiltered
    /// family's `depth_columns`, `slice_fit` and `rectify` (of
    /// [`HybridVolumeVariant::prefiltered`]), `volume_bounds`, `volume_march`.
    pub fn hybrid_volume(variant: HybridVolumeVariant) -> [Self; 5] {
        [
            Self::DepthColumns(variant.prefiltered()),
            Self::SliceFit(variant.prefiltered()),
            Self::Rectify(variant.prefiltered()),
            Self::VolumeBounds(variant),
            Self::VolumeMarch(variant),
        ]
    }
}

impl crate::family::KernelFamily for HybridVolumeVariant {
    fn kernel_params(&self) -> Vec<crate::KernelParams> {
        let mut out = crate::KernelParams::hybrid_volume(*self).to_vec();
        if self.sampling != crate::sampling::Sampling::Pixels {
            out.push(crate::KernelParams::VolumeMarchUnwarp(*self));
            out.push(crate::KernelParams::VolumeMarchFallback(*self));
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
