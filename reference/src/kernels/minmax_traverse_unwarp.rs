//! CPU mirror of `shaderlib/templates/minmax_traverse_unwarp.wgsl`: the epipolar unwarp of the
//! minmax_traverse family (`scatter_reference::kernels::common_sampling::epipolar_unwarp`): every pixel
//! gathered from the samples, or listed for `minmax_traverse_fallback`.

use super::common_sampling::{EpipolarUnwarp, epipolar_unwarp};
use super::minmax_traverse::TraverseInputs;
use super::texture::TexArray;
use scatter_shaderlib::minmax::MinmaxVariant;

/// Every pixel of an `epipolar` variant gathered from `samples` (what `minmax_traverse` wrote to
/// `epipolar_samples`), or listed for `minmax_traverse_fallback` where no sample stands for it.
pub fn minmax_traverse_unwarp(
    variant: &MinmaxVariant,
    inp: &TraverseInputs,
    samples: &TexArray,
) -> EpipolarUnwarp {
    epipolar_unwarp(
        &variant.sampling_knobs(),
        [inp.frame.sizes[0], inp.frame.sizes[1]],
        inp.depth,
        samples,
    )
}
