//! CPU mirror of `shaderlib/templates/minmax_traverse_fallback.wgsl`: the epipolar fallback of the
//! minmax_traverse family (`scatter_reference::kernels::common_sampling::epipolar_fallback` with
//! minmax_traverse's per-pixel body).

use super::common_sampling::{EpipolarUnwarp, SampledOutput, epipolar_fallback};
use super::minmax_traverse::{TraverseInputs, minmax_traverse_main};
use scatter_shaderlib::minmax::MinmaxVariant;

/// The pixels `minmax_traverse_unwarp` listed, traversed themselves into its output.
pub fn minmax_traverse_fallback(
    variant: &MinmaxVariant,
    inp: &TraverseInputs,
    unwarped: EpipolarUnwarp,
) -> SampledOutput {
    epipolar_fallback(unwarped, &|x, y| {
        let c = minmax_traverse_main([x, y, 0], variant, inp).map_or([0.0; 4], |(c, _)| c);
        [c[0], c[1], c[2]]
    })
}
