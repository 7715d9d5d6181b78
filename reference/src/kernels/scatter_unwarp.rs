//! CPU mirror of `shaderlib/templates/scatter_unwarp.wgsl`: the epipolar unwarp of the
//! scatter family (`scatter_reference::kernels::common_sampling::epipolar_unwarp`): every pixel
//! gathered from the samples, or listed for `scatter_fallback`.

use super::common_sampling::{EpipolarUnwarp, epipolar_unwarp};
use super::scatter::ScatterInputs;
use super::texture::TexArray;
use scatter_shaderlib::prefiltered::PrefilteredVariant;

/// Every pixel of an `epipolar` variant gathered from `samples` (what `scatter` wrote to
/// `epipolar_samples`), or listed for `scatter_fallback` where no sample stands for it.
pub fn scatter_unwarp(
    variant: &PrefilteredVariant,
    inp: &ScatterInputs,
    samples: &TexArray,
) -> EpipolarUnwarp {
    epipolar_unwarp(
        &variant.sampling_knobs(),
        [inp.frame.sizes[0], inp.frame.sizes[1]],
        inp.depth,
        samples,
    )
}
