//! The `raymarch` family (Tóth & Umenhoffer 2009): the askama views of
//! `templates/raymarch.wgsl` and `templates/interleave_sum.wgsl` and their rendering from a
//! [`RaymarchVariant`]. CPU mirrors: `reference/src/kernels/{raymarch,interleave_sum}.rs`.
//! Host-side knobs and uniforms: [`scatter_frame::raymarch`] (re-exported here).

pub mod plan;

use askama::Template;

pub use scatter_frame::raymarch::{RaymarchUniforms, RaymarchVariant, prepare_raymarch};

use crate::compose::template_path;
use crate::prefiltered::LightKind;
use crate::sampling::{EPIPOLAR_SAMPLES_FORMAT, Sampling, SamplingView, camera_expr, unwarp_only};
use crate::{Kernel, ShaderError};

/// Workgroup size of `raymarch` and `interleave_sum`: one invocation per pixel.
pub const RAYMARCH_WORKGROUP_SIZE: [u32; 3] = [8, 8, 1];

/// Format of the partial sums `raymarch` stores for `interleave_sum` (interleaved variants).
pub const PARTIAL_FORMAT: &str = "rgba32float";

/// `raymarch`: per-pixel march, full or one interleaving class.
#[derive(Template)]
#[template(path = "raymarch.wgsl")]
struct RaymarchTemplate {
    light_name: &'static str,
    spot: bool,
    interleaved: bool,
    cookie: bool,
    output_format: &'static str,
    sampling: SamplingView,
}

/// `raymarch_unwarp`: `raymarch.wgsl` rendered as the epipolar unwarp.
#[derive(Template)]
#[template(path = "raymarch_unwarp.wgsl")]
struct RaymarchUnwarpTemplate {
    light_name: &'static str,
    spot: bool,
    interleaved: bool,
    cookie: bool,
    output_format: &'static str,
    sampling: SamplingView,
}

/// `raymarch_fallback`: `raymarch.wgsl` rendered as the epipolar fallback.
#[derive(Template)]
#[template(path = "raymarch_fallback.wgsl")]
struct RaymarchFallbackTemplate {
    light_name: &'static str,
    spot: bool,
    interleaved: bool,
    cookie: bool,
    output_format: &'static str,
    sampling: SamplingView,
}

/// `interleave_sum`: the separable window sum.
#[derive(Template)]
#[template(path = "interleave_sum.wgsl")]
struct InterleaveSumTemplate {}

fn validate(kernel: Kernel, variant: &RaymarchVariant) -> Result<(), ShaderError> {
    variant
        .validate()
        .map_err(|source| ShaderError::Variant { kernel, source })
}

/// The sampling view of `kernel` (`raymarch`, `raymarch_unwarp` or `raymarch_fallback`)
/// for `variant`.
fn sampling_view(variant: &RaymarchVariant, kernel: Kernel) -> SamplingView {
    let toward = match variant.light {
        LightKind::Directional => "-frame.light_dir.xyz",
        // `Area` is refused by `validate` before any template renders.
        LightKind::Spot | LightKind::Area => "frame.light_pos.xyz - frame.eye.xyz",
    };
    SamplingView::new(
        &variant.sampling_knobs(),
        kernel,
        Kernel::Raymarch,
        camera_expr(toward),
        4,
    )
}

/// Renders `templates/raymarch.wgsl` for `variant` (`samples` is a uniform, not compiled
/// in: only the light and whether the variant interleaves change the code).
pub(crate) fn render_raymarch(variant: &RaymarchVariant) -> Result<String, ShaderError> {
    validate(Kernel::Raymarch, variant)?;
    RaymarchTemplate {
        light_name: variant.light.name(),
        spot: variant.light == LightKind::Spot,
        interleaved: variant.interleaved(),
        cookie: variant.cookie,
        output_format: if variant.interleaved() {
            PARTIAL_FORMAT
        } else if variant.sampling != Sampling::Pixels {
            EPIPOLAR_SAMPLES_FORMAT
        } else {
            "rgba16float"
        },
        sampling: sampling_view(variant, Kernel::Raymarch),
    }
    .render()
    .map_err(|source| ShaderError::Render {
        kernel: Kernel::Raymarch,
        template: template_path(Kernel::Raymarch),
        source,
    })
}

/// Renders `templates/raymarch_unwarp.wgsl` for an `epipolar` variant (an error for the
/// others, which have no such pass).
pub(crate) fn render_raymarch_unwarp(variant: &RaymarchVariant) -> Result<String, ShaderError> {
    validate(Kernel::RaymarchUnwarp, variant)?;
    unwarp_only(Kernel::RaymarchUnwarp, variant.sampling)?;
    RaymarchUnwarpTemplate {
        light_name: variant.light.name(),
        spot: variant.light == LightKind::Spot,
        interleaved: false,
        cookie: variant.cookie,
        output_format: "rgba16float",
        sampling: sampling_view(variant, Kernel::RaymarchUnwarp),
    }
    .render()
    .map_err(|source| ShaderError::Render {
        kernel: Kernel::RaymarchUnwarp,
        template: template_path(Kernel::RaymarchUnwarp),
        source,
    })
}

/// Renders `templates/raymarch_fallback.wgsl` for an `epipolar` variant (an error for the
/// others, which have no such pass).
pub(crate) fn render_raymarch_fallback(variant: &RaymarchVariant) -> Result<String, ShaderError> {
    validate(Kernel::RaymarchFallback, variant)?;
    unwarp_only(Kernel::RaymarchFallback, variant.sampling)?;
    RaymarchFallbackTemplate {
        light_name: variant.light.name(),
        spot: variant.light == LightKind::Spot,
        interleaved: false,
        cookie: variant.cookie,
        output_format: "rgba16float",
        sampling: sampling_view(variant, Kernel::RaymarchFallback),
    }
    .render()
    .map_err(|source| ShaderError::Render {
        kernel: Kernel::RaymarchFallback,
        template: template_path(Kernel::RaymarchFallback),
        source,
    })
}

/// Renders `templates/interleave_sum.wgsl` (the same code for every interleaved variant;
/// an error for a variant without interleaving, which has no such pass).
pub(crate) fn render_interleave_sum(variant: &RaymarchVariant) -> Result<String, ShaderError> {
    validate(Kernel::InterleaveSum, variant)?;
    if !variant.interleaved() {
        return Err(ShaderError::InvalidParameter {
            kernel: Kernel::InterleaveSum,
            knob: "interleave",
            value: variant.interleave.to_string(),
            allowed: "2..=8 (a variant with interleave = 1 has no interleave_sum pass)",
        });
    }
    InterleaveSumTemplate {}
        .render()
        .map_err(|source| ShaderError::Render {
            kernel: Kernel::InterleaveSum,
            template: template_path(Kernel::InterleaveSum),
            source,
        })
}

impl crate::KernelParams {
    /// The kernels of a raymarch-family variant, in pass order: `raymarch`, then
    /// `interleave_sum` when it interleaves, or `raymarch_unwarp` and `raymarch_fallback`
    /// with epipolar sampling.
    pub fn raymarch(variant: RaymarchVariant) -> Vec<Self> {
        let mut out = vec![Self::Raymarch(variant)];
        if variant.interleaved() {
            out.push(Self::InterleaveSum(variant));
        }
        if variant.sampling != Sampling::Pixels {
            out.push(Self::RaymarchUnwarp(variant));
            out.push(Self::RaymarchFallback(variant));
        }
        out
    }
}

impl crate::family::KernelFamily for RaymarchVariant {
    fn kernel_params(&self) -> Vec<crate::KernelParams> {
        crate::KernelParams::raymarch(*self)
    }

    fn plan(&self) -> crate::plan::Plan {
        plan::plan(self)
    }

    /// An interleaved variant: `raymarch` and `interleave_sum`.
    fn with_most_passes() -> Self {
        Self {
            interleave: 2,
            ..Self::default()
        }
    }
}
