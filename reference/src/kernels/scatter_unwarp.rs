//! CPU mirror of `shaderlib/templates/scatter_unwarp.wgsl`: the epipolar unwarp of the
//! prefiltered family (`scatter_reference::kernels::common_sampling::epipolar_unwarp` with
//! [`scatter_main`] as the body of the pixels no sample stands for).

use super::common_sampling::{EpipolarCamera, SampledOutput, epipolar_unwarp};
use super::scatter::{ScatterInputs, scatter_main};
use super::texture::TexArray;
use scatter_shaderlib::prefiltered::PrefilteredVariant;

/// Every pixel of an `epipolar` variant gathered from `samples` (what `scatter` wrote to
/// `epipolar_samples`), or evaluated itself.
pub fn scatter_unwarp(
    variant: &PrefilteredVariant,
    inp: &ScatterInputs,
    samples: &TexArray,
) -> SampledOutput {
    epipolar_unwarp(
        &variant.sampling_knobs(),
        [inp.frame.sizes[0], inp.frame.sizes[1]],
        inp.depth,
        &EpipolarCamera::of_frame(inp.frame),
        samples,
        &|x, y| {
            let c = scatter_main([x, y, 0], variant, inp).unwrap_or([0.0; 4]);
            [c[0], c[1], c[2]]
        },
    )
}
