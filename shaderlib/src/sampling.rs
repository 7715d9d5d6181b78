//! The sampling stage every family can use ([`scatter_frame::sampling`]): the askama view
//! the families' per-pixel kernels render their entry point with
//! (`templates/include/sampled_entry.wgsl`, `templates/include/sampled_bindings.wgsl`), the
//! shared `lowres_upsample` kernel, and the plan pieces a family's plan adds for it. CPU
//! mirrors: `reference/src/kernels/{common_sampling,lowres_upsample}.rs`.

use askama::Template;

pub use scatter_frame::sampling::{Sampling, SamplingKnobs};

use crate::compose::template_path;
use crate::plan::{
    OUTPUT_FORMAT, PassPlan, Resource, STORAGE_AND_SAMPLED, bind, scatter_resource, texture_2d,
};
use crate::{Kernel, ShaderError};

/// What a family's per-pixel template needs of the sampling knobs (its field `sampling`).
#[derive(Clone, Debug)]
pub(crate) struct SamplingView {
    /// Whether the kernel is the sampling pass of `sampling = lowres`.
    pub lowres: bool,
    /// Block side S.
    pub scale: u32,
    /// The depth break as a WGSL f32 literal (a fraction of the nearer depth).
    pub depth_break: String,
    /// The kernel's entry point; its per-pixel function is `<entry>_pixel`.
    pub entry: &'static str,
    /// The binding of `samples` (the kernel's last binding plus one).
    pub samples_binding: u32,
}

impl SamplingView {
    /// The view of `knobs` for kernel `kernel`, whose `samples` binding is `samples_binding`.
    pub(crate) fn new(knobs: &SamplingKnobs, kernel: Kernel, samples_binding: u32) -> Self {
        Self {
            lowres: knobs.sampling == Sampling::Lowres,
            scale: knobs.scale,
            depth_break: wgsl_f32(knobs.depth_break_fraction()),
            entry: kernel.name(),
            samples_binding,
        }
    }
}

/// An f32 as a WGSL literal that parses back to the same value.
fn wgsl_f32(v: f32) -> String {
    let s = format!("{v:?}");
    if s.contains('.') || s.contains('e') {
        s
    } else {
        format!("{s}.0")
    }
}

/// `lowres_upsample`: the depth-aware upsample.
#[derive(Template)]
#[template(path = "lowres_upsample.wgsl")]
struct LowresUpsampleTemplate {
    scale: u32,
    depth_break: String,
}

/// Renders `templates/lowres_upsample.wgsl` for the sampling knobs (an error for
/// `sampling = pixels`, which has no upsample).
pub(crate) fn render_lowres_upsample(knobs: &SamplingKnobs) -> Result<String, ShaderError> {
    let kernel = Kernel::LowresUpsample;
    knobs
        .validate()
        .map_err(|source| ShaderError::Variant { kernel, source })?;
    if knobs.sampling != Sampling::Lowres {
        return Err(ShaderError::InvalidParameter {
            kernel,
            knob: "sampling",
            value: knobs.sampling.to_string(),
            allowed: "lowres (a variant with sampling = pixels has no upsample pass)",
        });
    }
    LowresUpsampleTemplate {
        scale: knobs.scale,
        depth_break: wgsl_f32(knobs.depth_break_fraction()),
    }
    .render()
    .map_err(|source| ShaderError::Render {
        kernel,
        template: template_path(kernel),
        source,
    })
}

/// The sample grid's size as formulas of the screen: `ceil(screen.width / S)`,
/// `ceil(screen.height / S)` (the screen itself for `pixels`).
pub fn grid_formulas(knobs: &SamplingKnobs) -> [String; 2] {
    match knobs.sampling {
        Sampling::Pixels => ["screen.width".into(), "screen.height".into()],
        Sampling::Lowres => [
            format!("ceil(screen.width / {})", knobs.scale),
            format!("ceil(screen.height / {})", knobs.scale),
        ],
    }
}

/// The invocations of a family's per-pixel pass: one per sample.
pub fn sampling_invocations(knobs: &SamplingKnobs) -> [String; 3] {
    let [w, h] = grid_formulas(knobs);
    [w, h, "1".into()]
}

/// The resources `sampling = lowres` adds to a family's plan: `samples` (none for `pixels`).
pub fn sampling_resources(knobs: &SamplingKnobs) -> Vec<Resource> {
    if !knobs.is_sampled() {
        return Vec::new();
    }
    let [w, h] = grid_formulas(knobs);
    vec![Resource {
        texture: Some(texture_2d(OUTPUT_FORMAT, &w, &h, "1", STORAGE_AND_SAMPLED)),
        ..scatter_resource(
            "samples",
            "in-scattered radiance at the low-resolution samples (written by the family's \
             per-pixel pass, read by lowres_upsample)",
        )
    }]
}

/// The bindings `sampling = lowres` adds to a family's per-pixel pass: `samples` at
/// `binding` (none for `pixels`).
pub fn sampling_bindings(knobs: &SamplingKnobs, binding: u32) -> Vec<crate::plan::BindingSource> {
    if knobs.is_sampled() {
        vec![bind(binding, "samples")]
    } else {
        Vec::new()
    }
}

/// The `lowres_upsample` pass (after the family's per-pixel pass), or `None` for `pixels`.
pub fn upsample_pass(knobs: &SamplingKnobs) -> Option<PassPlan> {
    knobs.is_sampled().then(|| PassPlan {
        kernel: Kernel::LowresUpsample,
        invocations: ["screen.width".into(), "screen.height".into(), "1".into()],
        skip_when: None,
        bindings: vec![bind(0, "depth"), bind(1, "samples"), bind(2, "output")],
    })
}

/// The kernels `sampling` adds after a family's own: `lowres_upsample` for `lowres`.
pub fn sampling_kernels(knobs: &SamplingKnobs) -> Vec<crate::KernelParams> {
    if knobs.is_sampled() {
        vec![crate::KernelParams::LowresUpsample(*knobs)]
    } else {
        Vec::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn literals_round_trip() {
        assert_eq!(wgsl_f32(0.05), "0.05");
        assert_eq!(wgsl_f32(1.0), "1.0");
        assert_eq!(wgsl_f32(0.5), "0.5");
    }

    #[test]
    fn every_family_builds_lowres() {
        use crate::family::KernelFamily;
        let knobs = [SamplingKnobs::lowres(2), SamplingKnobs::lowres(4)];
        for k in knobs {
            for light in [crate::prefiltered::LightKind::Directional, crate::prefiltered::LightKind::Spot] {
                let variants: [crate::family::FamilyVariant; 3] = [
                    crate::prefiltered::PrefilteredVariant { light, ..Default::default() }.into(),
                    crate::raymarch::RaymarchVariant { light, ..Default::default() }.into(),
                    crate::minmax::MinmaxVariant { light, ..Default::default() }.into(),
                ];
                let variants = variants.map(|v| v.with_sampling(k).kernel_params());
                for params in variants.into_iter().flatten() {
                    crate::build(&params).unwrap_or_else(|e| panic!("{e}"));
                }
            }
        }
    }

    #[test]
    fn upsample_renders_for_lowres_only() {
        assert!(render_lowres_upsample(&SamplingKnobs::lowres(2)).is_ok());
        assert!(render_lowres_upsample(&SamplingKnobs::default()).is_err());
        assert!(crate::build(&crate::KernelParams::LowresUpsample(SamplingKnobs::lowres(4))).is_ok());
    }
}
