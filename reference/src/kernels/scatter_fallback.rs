//! CPU mirror of `shaderlib/templates/scatter_fallback.wgsl`: the epipolar fallback of the
//! scatter family (`scatter_reference::kernels::common_sampling::epipolar_fallback` with
//! scatter's per-pixel body).

use super::common_sampling::{EpipolarUnwarp, SampledOutput, epipolar_fallback};
use super::scatter::{ScatterInputs, scatter_main};
use scatter_shaderlib::prefiltered::PrefilteredVariant;

/// The pixels `scatter_unwarp` listed, evaluated themselves into its output.
pub fn scatter_fallback(
    variant: &PrefilteredVariant,
    inp: &ScatterInputs,
    unwarped: EpipolarUnwarp,
) -> SampledOutput {
    epipolar_fallback(unwarped, &|x, y| {
        let c = scatter_main([x, y, 0], variant, inp).unwrap_or([0.0; 4]);
        [c[0], c[1], c[2]]
    })
}
