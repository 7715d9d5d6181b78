//! CPU mirror of `shaderlib/templates/minmax_traverse_unwarp.wgsl`: the epipolar unwarp of
//! the minmax family (`scatter_reference::kernels::common_sampling::epipolar_unwarp` with
//! [`minmax_traverse_main`] as the body of the pixels no sample stands for).

use super::common_sampling::{EpipolarCamera, SampledOutput, epipolar_unwarp};
use super::minmax_traverse::{TraverseInputs, minmax_traverse_main};
use super::texture::TexArray;
use scatter_shaderlib::minmax::MinmaxVariant;

/// Every pixel of an `epipolar` variant gathered from `samples` (what `minmax_traverse`
/// wrote to `epipolar_samples`), or traversed itself.
pub fn minmax_traverse_unwarp(
    variant: &MinmaxVariant,
    inp: &TraverseInputs,
    samples: &TexArray,
) -> SampledOutput {
    epipolar_unwarp(
        &variant.sampling_knobs(),
        [inp.frame.sizes[0], inp.frame.sizes[1]],
        inp.depth,
        &EpipolarCamera::of_frame(inp.frame),
        samples,
        &|x, y| {
            let c = minmax_traverse_main([x, y, 0], variant, inp).map_or([0.0; 4], |(c, _)| c);
            [c[0], c[1], c[2]]
        },
    )
}
