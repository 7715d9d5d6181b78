//! CPU mirror of `shaderlib/templates/pst_sweep_unwarp.wgsl`: the epipolar unwarp of the
//! `partial_sum_tree` family (`scatter_reference::kernels::common_sampling::epipolar_unwarp`):
//! every pixel gathered from the samples, or listed for `pst_sweep_fallback`.

use super::common_sampling::{EpipolarUnwarp, epipolar_unwarp};
use super::pst_sweep::PstInputs;
use super::texture::TexArray;
use scatter_shaderlib::partial_sum_tree::PartialSumTreeVariant;

/// Every pixel gathered from `samples` (what `pst_sweep` wrote to `epipolar_samples`), or
/// listed for `pst_sweep_fallback` where no sample stands for it.
pub fn pst_sweep_unwarp(
    variant: &PartialSumTreeVariant,
    inp: &PstInputs,
    samples: &TexArray,
) -> EpipolarUnwarp {
    epipolar_unwarp(
        &variant.sampling_knobs(),
        [inp.frame.sizes[0], inp.frame.sizes[1]],
        inp.depth,
        samples,
    )
}
