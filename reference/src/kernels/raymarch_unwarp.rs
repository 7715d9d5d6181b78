//! CPU mirror of `shaderlib/templates/raymarch_unwarp.wgsl`: the epipolar unwarp of the
//! raymarch family (`scatter_reference::kernels::common_sampling::epipolar_unwarp`): every pixel
//! gathered from the samples, or listed for `raymarch_fallback`.

use super::common_sampling::{EpipolarUnwarp, epipolar_unwarp};
use super::texture::{Tex, TexArray};
use scatter_shaderlib::raymarch::{RaymarchUniforms, RaymarchVariant};

/// Every pixel of an `epipolar` variant gathered from `samples` (what `raymarch` wrote to
/// `epipolar_samples`), or listed for `raymarch_fallback` where no sample stands for it.
pub fn raymarch_unwarp(
    variant: &RaymarchVariant,
    m: &RaymarchUniforms,
    depth: &Tex,
    samples: &TexArray,
) -> EpipolarUnwarp {
    epipolar_unwarp(
        &variant.sampling_knobs(),
        [m.sizes[0], m.sizes[1]],
        depth,
        samples,
    )
}
