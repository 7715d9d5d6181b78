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
/// uniform array.
#[derive(Template)]
#[template(path = "ivsv_gather.wgsl")]
struct GatherTemplate {
    segments: u32,
    vpls: u32,
    interleave: u32,
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

/// Renders `templates/ivsv_gather.wgsl` for `variant`'s segments.
pub(crate) fn render_gather(variant: &AreaIvsvVariant) -> Result<String, ShaderError> {
    validate(Kernel::IvsvGather, variant)?;
    GatherTemplate {
        segments: variant.segments,
        vpls: variant.vpls,
        interleave: variant.interleave,
    }
    .render()
    .map_err(render_error(Kernel::IvsvGather))
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
    /// `ivsv_scan`, `ivsv_gather`, and `ivsv_interleave_sum` when interleaved.
    pub fn area_ivsv(variant: AreaIvsvVariant) -> Vec<Self> {
        let mut out = vec![
            Self::IvsvRectify(variant),
            Self::IvsvScan(variant),
            Self::IvsvGather(variant),
        ];
        if variant.interleave > 1 {
            out.push(Self::IvsvInterleaveSum(variant));
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
