//! The sampling stage every family can use ([`scatter_frame::sampling`]): the askama view
//! the families' per-pixel kernels render their entry point with
//! (`templates/include/sampled_entry.wgsl`, `templates/include/sampled_bindings.wgsl`,
//! shared WGSL `templates/common/sampling.wgsl`), and the dispatch a family's plan gives its
//! per-pixel pass. CPU mirror: `reference/src/kernels/common_sampling.rs`.

pub use scatter_frame::sampling::{Sampling, SamplingKnobs};

use crate::Kernel;

/// What a family's per-pixel template needs of the sampling knobs (its field `sampling`).
#[derive(Clone, Debug)]
pub(crate) struct SamplingView {
    /// Whether the kernel is the lowres pass (`sampling = lowres`).
    pub lowres: bool,
    /// Block side S.
    pub scale: u32,
    /// The depth break as a WGSL f32 literal (a fraction of the nearer depth).
    pub depth_break: String,
    /// The light break as a WGSL f32 literal (a fraction of the brightest sample).
    pub light_break: String,
    /// The kernel's entry point; its per-pixel function is `<entry>_pixel`.
    pub entry: &'static str,
}

impl SamplingView {
    /// The view of `knobs` for kernel `kernel`.
    pub(crate) fn new(knobs: &SamplingKnobs, kernel: Kernel) -> Self {
        Self {
            lowres: knobs.sampling == Sampling::Lowres,
            scale: knobs.scale,
            depth_break: wgsl_f32(knobs.depth_break_fraction()),
            light_break: wgsl_f32(knobs.light_break_fraction()),
            entry: kernel.name(),
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

/// The invocations of a family's per-pixel pass: the screen for `pixels`; for `lowres`,
/// one workgroup of 8 x 8 invocations per 8 x 8 blocks of S x S pixels:
/// `8 * ceil(screen.width / (8 S))` by `8 * ceil(screen.height / (8 S))`.
pub fn sampling_invocations(knobs: &SamplingKnobs) -> [String; 3] {
    match knobs.sampling {
        Sampling::Pixels => ["screen.width".into(), "screen.height".into(), "1".into()],
        Sampling::Lowres => [
            format!("8 * ceil(screen.width / {})", 8 * knobs.scale),
            format!("8 * ceil(screen.height / {})", 8 * knobs.scale),
            "1".into(),
        ],
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
        for k in [SamplingKnobs::lowres(2), SamplingKnobs::lowres(4)] {
            for light in [
                crate::prefiltered::LightKind::Directional,
                crate::prefiltered::LightKind::Spot,
            ] {
                let variants: [crate::family::FamilyVariant; 3] = [
                    crate::prefiltered::PrefilteredVariant {
                        light,
                        ..Default::default()
                    }
                    .into(),
                    crate::raymarch::RaymarchVariant {
                        light,
                        ..Default::default()
                    }
                    .into(),
                    crate::minmax::MinmaxVariant {
                        light,
                        ..Default::default()
                    }
                    .into(),
                ];
                for v in variants {
                    for params in v.with_sampling(k).kernel_params() {
                        crate::build(&params).unwrap_or_else(|e| panic!("{e}"));
                    }
                }
            }
        }
    }
}
