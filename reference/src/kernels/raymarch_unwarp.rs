//! CPU mirror of `shaderlib/templates/raymarch_unwarp.wgsl`: the epipolar unwarp of the
//! raymarch family (`scatter_reference::kernels::common_sampling::epipolar_unwarp` with
//! [`raymarch_main`] as the body of the pixels no sample stands for).

use super::common_sampling::{EpipolarCamera, SampledOutput, epipolar_unwarp};
use super::raymarch::raymarch_main;
use super::texture::{Tex, TexArray};
use scatter_shaderlib::raymarch::{RaymarchUniforms, RaymarchVariant};

/// Every pixel of an `epipolar` variant gathered from `samples` (what `raymarch` wrote to
/// `epipolar_samples`), or marched itself.
pub fn raymarch_unwarp(
    variant: &RaymarchVariant,
    m: &RaymarchUniforms,
    depth: &Tex,
    shadow_map: &Tex,
    samples: &TexArray,
) -> SampledOutput {
    epipolar_unwarp(
        &variant.sampling_knobs(),
        [m.sizes[0], m.sizes[1]],
        depth,
        &EpipolarCamera::of_raymarch(m, variant.light),
        samples,
        &|x, y| {
            let c = raymarch_main([x, y, 0], variant, m, depth, shadow_map).unwrap_or([0.0; 4]);
            [c[0], c[1], c[2]]
        },
    )
}
