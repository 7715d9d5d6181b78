//! The `area_ivsv` family (Wyman & Dai 2013): the askama views of
//! `templates/ivsv_rectify.wgsl`, `templates/ivsv_scan.wgsl` and `templates/ivsv_gather.wgsl`
//! and their rendering from an [`AreaIvsvVariant`]. CPU mirrors:
//! `reference/src/kernels/{ivsv_rectify,ivsv_scan,ivsv_gather}.rs`. Host-side knobs and frame
//! set-up: [`scatter_frame::area_ivsv`] (re-exported here).
//! The family renders area lights only (`light = area`, [`scatter_frame::area_light`]); its
//! frame's standard shadow map is the template of its VPLs' maps.

pub mod plan;

use askama::Template;

pub use scatter_frame::area_ivsv::{
    AreaIvsvFrame, AreaIvsvVariant, IvsvUniforms, MAX_SEGMENTS, MAX_VPLS, PHI_BITS, VplGrid,
    VplInput, VplRecord, fit_grid, prepare_area_ivsv, prepare_area_light,
};
pub use scatter_frame::area_light::{AreaLightDesc, AreaShapeDesc, halton, light_basis};

use crate::compose::template_path;
use crate::sampling::{EPIPOLAR_SAMPLES_FORMAT, Sampling, SamplingView, camera_expr, unwarp_only};
use crate::{Kernel, ShaderError};

/// Workgroup size of `ivsv_rectify` (x: phi bits) and `ivsv_scan` (x: row words).
pub const LINE_WORKGROUP_SIZE: [u32; 3] = [64, 1, 1];

/// Workgroup size of `ivsv_gather`: one invocation per pixel.
pub const GATHER_WORKGROUP_SIZE: [u32; 3] = [8, 8, 1];

/// `ivsv_rectify`: the VPL records are a uniform array of the variant's length.
#[derive(Template)]
#[template(path = "ivsv_rectify.wgsl")]
struct RectifyTemplate {
    vpls: u32,
}

/// `ivsv_scan`.
#[derive(Template)]
#[template(path = "ivsv_scan.wgsl")]
struct ScanTemplate;

/// `ivsv_gather`: the pieces of the integrand are a constant loop count, the VPL records a
/// uniform array; the sampling stage's entry points.
#[derive(Template)]
#[template(path = "ivsv_gather.wgsl")]
struct GatherTemplate {
    segments: u32,
    vpls: u32,
    interleave: u32,
    output_format: &'static str,
    sampling: SamplingView,
}

/// `ivsv_gather_unwarp`: `ivsv_gather` with the unwarp entry point.
#[derive(Template)]
#[template(path = "ivsv_gather_unwarp.wgsl")]
struct GatherUnwarpTemplate {
    segments: u32,
    vpls: u32,
    interleave: u32,
    output_format: &'static str,
    sampling: SamplingView,
}

/// `ivsv_gather_fallback`: `ivsv_gather` with the fallback entry point.
#[derive(Template)]
#[template(path = "ivsv_gather_fallback.wgsl")]
struct GatherFallbackTemplate {
    segments: u32,
    vpls: u32,
    interleave: u32,
    output_format: &'static str,
    sampling: SamplingView,
}

/// The sampling view of `kernel` (`ivsv_gather` or its unwarp or fallback): epipolar
/// slices radiate from the VPLs' centroid (`frame.centre`); the first free binding is 5.
fn sampling_view(variant: &AreaIvsvVariant, kernel: Kernel) -> SamplingView {
    SamplingView::new(
        &variant.sampling_knobs(),
        kernel,
        Kernel::IvsvGather,
        camera_expr("frame.centre.xyz - frame.eye.xyz"),
        5,
    )
}

/// `ivsv_interleave_sum`: the window side.
#[derive(Template)]
#[template(path = "ivsv_interleave_sum.wgsl")]
struct InterleaveSumTemplate {
    interleave: u32,
}

fn validate(kernel: Kernel, variant: &AreaIvsvVariant) -> Result<(), ShaderError> {
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

/// Renders `templates/ivsv_rectify.wgsl`.
pub(crate) fn render_rectify(variant: &AreaIvsvVariant) -> Result<String, ShaderError> {
    validate(Kernel::IvsvRectify, variant)?;
    RectifyTemplate { vpls: variant.vpls }
        .render()
        .map_err(render_error(Kernel::IvsvRectify))
}

/// Renders `templates/ivsv_scan.wgsl`.
pub(crate) fn render_scan(variant: &AreaIvsvVariant) -> Result<String, ShaderError> {
    validate(Kernel::IvsvScan, variant)?;
    ScanTemplate
        .render()
        .map_err(render_error(Kernel::IvsvScan))
}

/// Renders `templates/ivsv_gather.wgsl` for `variant`'s segments and sampling.
pub(crate) fn render_gather(variant: &AreaIvsvVariant) -> Result<String, ShaderError> {
    validate(Kernel::IvsvGather, variant)?;
    GatherTemplate {
        segments: variant.segments,
        vpls: variant.vpls,
        interleave: variant.interleave,
        output_format: if variant.interleave > 1 {
            "rgba32float"
        } else if variant.sampling != Sampling::Pixels {
            EPIPOLAR_SAMPLES_FORMAT
        } else {
            "rgba16float"
        },
        sampling: sampling_view(variant, Kernel::IvsvGather),
    }
    .render()
    .map_err(render_error(Kernel::IvsvGather))
}

/// Renders `templates/ivsv_gather_unwarp.wgsl` (`sampling = epipolar` only).
pub(crate) fn render_gather_unwarp(variant: &AreaIvsvVariant) -> Result<String, ShaderError> {
    let kernel = Kernel::IvsvGatherUnwarp;
    validate(kernel, variant)?;
    unwarp_only(kernel, variant.sampling)?;
    GatherUnwarpTemplate {
        segments: variant.segments,
        vpls: variant.vpls,
        interleave: variant.interleave,
        output_format: "rgba16float",
        sampling: sampling_view(variant, kernel),
    }
    .render()
    .map_err(render_error(kernel))
}

/// Renders `templates/ivsv_gather_fallback.wgsl` (`sampling = epipolar` only).
pub(crate) fn render_gather_fallback(variant: &AreaIvsvVariant) -> Result<String, ShaderError> {
    let kernel = Kernel::IvsvGatherFallback;
    validate(kernel, variant)?;
    unwarp_only(kernel, variant.sampling)?;
    GatherFallbackTemplate {
        segments: variant.segments,
        vpls: variant.vpls,
        interleave: variant.interleave,
        output_format: "rgba16float",
        sampling: sampling_view(variant, kernel),
    }
    .render()
    .map_err(render_error(kernel))
}

/// Renders `templates/ivsv_interleave_sum.wgsl` for an interleaved variant (an error for
/// `interleave = 1`, which has no such pass).
pub(crate) fn render_interleave_sum(variant: &AreaIvsvVariant) -> Result<String, ShaderError> {
    let kernel = Kernel::IvsvInterleaveSum;
    validate(kernel, variant)?;
    if variant.interleave < 2 {
        return Err(ShaderError::Variant {
            kernel,
            source: scatter_frame::variant::VariantError {
                knob: "interleave",
                value: variant.interleave.to_string(),
                allowed: "2 or 4 (ivsv_interleave_sum is the interleaved gather's pass)".into(),
            },
        });
    }
    InterleaveSumTemplate {
        interleave: variant.interleave,
    }
    .render()
    .map_err(render_error(kernel))
}

impl crate::KernelParams {
    /// The kernels of an area_ivsv-family variant, in pass order: `ivsv_rectify`,
    /// `ivsv_scan`, `ivsv_gather`, then `ivsv_interleave_sum` when interleaved, or
    /// `ivsv_gather_unwarp` and `ivsv_gather_fallback` with `sampling = epipolar`.
    pub fn area_ivsv(variant: AreaIvsvVariant) -> Vec<Self> {
        let mut out = vec![
            Self::IvsvRectify(variant),
            Self::IvsvScan(variant),
            Self::IvsvGather(variant),
        ];
        if variant.interleave > 1 {
            out.push(Self::IvsvInterleaveSum(variant));
        }
        if variant.sampling != Sampling::Pixels {
            out.push(Self::IvsvGatherUnwarp(variant));
            out.push(Self::IvsvGatherFallback(variant));
        }
        out
    }
}

impl crate::family::KernelFamily for AreaIvsvVariant {
    fn kernel_params(&self) -> Vec<crate::KernelParams> {
        crate::KernelParams::area_ivsv(*self)
    }

    fn plan(&self) -> crate::plan::Plan {
        plan::plan(self)
    }

    /// Interleaved (the `ivsv_interleave_sum` pass).
    fn with_most_passes() -> Self {
        Self {
            interleave: 2,
            ..Self::default()
        }
    }
}
